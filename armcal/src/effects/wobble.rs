//! `axis_wobble`: a joint's bearing tilts as it turns, so its tilt varies periodically with its
//! reading: δα(θ) = δα + a·sin(hθ) + b·cos(hθ), δβ(θ) = δβ + c·sin(hθ) + d·cos(hθ) (rad,
//! `spec/arm-model.md`). Order 1 is a race inclined to the axis of rotation (the axis traces
//! a cone once a turn), order 2 an oval race, order 3 a tri-lobed one. Four unknowns per term:
//! a, b (δα's sin and cos), c, d (δβ's).

use super::figure::{Figure, Legend, Patterns};
use super::{
    parse_periodic, periodic_entry, periodic_vocabulary, Describe, Draw, Effect, Family, Simulate,
    Term, TermsError, TipPoint,
};
use crate::rng::SimRng;
use nalgebra::Vector3;
use quatarm_params::{Link, Param};
use quatarm_ref::arm::{Arm, Wobble as Entry};
use rand::Rng;
use serde_json::Value;

/// The spec's key.
pub const KEY: &str = "axis_wobble";

/// Highest order the diagnosis's vocabulary holds (each order is four unknowns per joint in
/// every selection step). Orders 1–3 are the mechanisms a rolling bearing has (an inclined,
/// an oval, a tri-lobed race); a wobble of a higher order still shows, as structure against
/// the joint's reading, in the report's `unexplained`.
pub const VOCABULARY_MAX_ORDER: u32 = 3;

/// The family of axis wobbles.
pub struct Wobbles;

/// Its registration.
pub static FAMILY: Wobbles = Wobbles;

/// Joint `joint`'s (0-based) axis wobble of order `order`.
#[derive(Clone, Copy, Debug)]
pub struct Wobble {
    /// Joint, 0-based.
    pub joint: usize,
    /// Order h ≥ 1.
    pub order: u32,
}

/// The tilt component (0: δα, 1: δβ) and the sinusoid (0: sin, 1: cos) of unknown `c`.
fn split(c: usize) -> (usize, usize) {
    (c / 2, c % 2)
}

const SYMBOL: [&str; 2] = ["δα", "δβ"];
const WAVE: [&str; 2] = ["sin", "cos"];

impl Family for Wobbles {
    fn key(&self) -> &'static str {
        KEY
    }

    fn usage(&self) -> &'static str {
        "+axis_wobble:J:H"
    }

    fn parse(&self, item: &str, args: &[&str], dof: usize) -> Result<Vec<Effect>, TermsError> {
        parse_periodic(item, KEY, args, dof, |joint, order| Effect::Wobble {
            joint,
            order,
        })
    }

    fn vocabulary(&self, dof: usize, _thermal: bool) -> Vec<Effect> {
        periodic_vocabulary(dof, VOCABULARY_MAX_ORDER, |joint, order| Effect::Wobble {
            joint,
            order,
        })
    }

    fn beyond_table(&self, arm: &Arm, at: Link) -> Vec<String> {
        let Link::Joint(k) = at else {
            return Vec::new();
        };
        let terms: Vec<_> = arm.joints[k]
            .wobble
            .iter()
            .filter(|w| w.alpha.iter().chain(&w.beta).any(|x| *x != 0.0))
            .collect();
        let (most, highest) = (
            quatarm::table::wobble::MAX_TERMS,
            quatarm::table::MAX_HARMONIC_ORDER,
        );
        let mut out = Vec::new();
        if terms.len() > most {
            out.push(format!(
                "joint {} has {} axis wobble terms; the table holds {most}",
                k + 1,
                terms.len()
            ));
        }
        if let Some(w) = terms.iter().find(|w| w.order > u32::from(highest)) {
            out.push(format!(
                "joint {} axis wobble of order {}; the table holds orders up to {highest}",
                k + 1,
                w.order
            ));
        }
        let sum: f64 = terms
            .iter()
            .flat_map(|w| w.alpha.iter().chain(&w.beta))
            .map(|x| x.abs())
            .sum();
        let limit = quatarm::table::limits::HARMONIC_SUM;
        if sum > limit {
            out.push(format!(
                "joint {} axis wobble: Σ|coefficients| = {sum:.3e} rad; the table holds {limit:e} rad",
                k + 1
            ));
        }
        out
    }

    fn clear(&self, arm: &mut Arm) {
        for w in arm.joints.iter_mut().flat_map(|j| &mut j.wobble) {
            w.alpha = [0.0; 2];
            w.beta = [0.0; 2];
        }
    }
}

impl Draw for Wobbles {
    fn figure(&self, at: &Patterns) -> Option<Figure> {
        let (data, geo) = (at.data, &at.geo);
        let mut panels = Vec::new();
        for k in 0..data.dof {
            let Some(cut) = at.cut_of(k) else { continue };
            let wobble = (1..=VOCABULARY_MAX_ORDER)
                .map(|order| Effect::Wobble { joint: k, order })
                .find(|e| at.named(*e));
            for (c, symbol) in SYMBOL.iter().enumerate() {
                panels.push(at.panel(
                    format!("joint {} {symbol}", k + 1),
                    format!("joint {} reading θ{} (deg)", k + 1, k + 1),
                    format!("apparent tilt {symbol} (µrad)"),
                    wobble,
                    &|i, m| {
                        let t = geo[i].tilt[k][c];
                        let t2 = t.norm_squared();
                        (t2.sqrt() >= cut && t2 > 0.0)
                            .then(|| (data.rows[i].theta[k].to_degrees(), 1e6 * t.dot(m) / t2))
                    },
                ));
            }
        }
        (!panels.is_empty()).then(|| Figure {
            legend: Legend::Models,
            file: "residuals_vs_joint_tilt.png".into(),
            title: "What the model misses, as each joint's tilt, against the joint's reading"
                .into(),
            caption: "An axis wobble shows as a wave of its order (cycles per turn) in δα, δβ \
                      or both; an encoder harmonic shows in the angle figure instead"
                .into(),
            panels,
        })
    }
}

impl Term for Wobble {
    fn family(&self) -> &'static dyn Family {
        &FAMILY
    }

    fn coefficients(&self) -> usize {
        4
    }

    fn param(&self, c: usize) -> Param {
        Param::Wobble {
            joint: self.joint,
            order: self.order,
            coef: c as u8,
        }
    }

    fn unit(&self) -> &'static str {
        "rad"
    }

    fn plausible(&self) -> f64 {
        0.01
    }

    /// After the fixed tilts it trades with (4) and the harmonics (5), which a data set of
    /// one pose per reading tells from it only by direction.
    fn priority(&self) -> u32 {
        7
    }

    fn value(&self, arm: &Arm, c: usize) -> f64 {
        let (t, w) = split(c);
        arm.joints[self.joint]
            .wobble
            .iter()
            .filter(|e| e.order == self.order)
            .map(|e| [e.alpha, e.beta][t][w])
            .sum()
    }

    fn add_to(&self, arm: &mut Arm, c: usize, dx: f64) {
        let order = self.order;
        let e = periodic_entry(
            &mut arm.joints[self.joint].wobble,
            order,
            |e| e.order,
            || Entry {
                order,
                alpha: [0.0; 2],
                beta: [0.0; 2],
            },
        );
        let (t, w) = split(c);
        [&mut e.alpha, &mut e.beta][t][w] += dx;
    }

    fn add_entry(&self, arm: &mut Arm) {
        self.add_to(arm, 0, 0.0);
    }

    /// The tilt's column at the reading's tilt ([`TipPoint::tilt_turn`]) times sin or cos of
    /// hθ: the wobble is the tilt, varied.
    fn column(&self, c: usize, at: &TipPoint) -> Vector3<f64> {
        let (t, w) = split(c);
        let a = f64::from(self.order) * at.theta[self.joint];
        at.tilt_turn(self.joint, t) * if w == 1 { a.cos() } else { a.sin() }
    }
}

impl Describe for Wobble {
    fn spec(&self) -> String {
        format!("+{KEY}:{}:{}", self.joint + 1, self.order)
    }

    fn describe(&self) -> String {
        format!(
            "joint {} axis wobble of order {}",
            self.joint + 1,
            self.order
        )
    }

    fn physical(&self) -> &'static str {
        match self.order {
            1 => " (the bearing's axis cones once a turn: an inclined race)",
            2 => " (the bearing's axis wobbles twice a turn: an oval race)",
            3 => " (the bearing's axis wobbles three times a turn: a tri-lobed race)",
            _ => " (the bearing's axis wobbles as it turns)",
        }
    }

    fn location(&self) -> Value {
        Value::from(self.joint + 1)
    }

    fn order(&self) -> Option<u32> {
        Some(self.order)
    }

    fn describe_param(&self, c: usize) -> String {
        let (t, w) = split(c);
        format!(
            "joint {} axis wobble order {} ({} {})",
            self.joint + 1,
            self.order,
            SYMBOL[t],
            WAVE[w]
        )
    }

    /// The quadrature sum of the δα and δβ amplitudes, √(a² + b² + c² + d²): √2 times the RMS
    /// of the axis's excursion over a turn. Order 1 counts only its counter-rotating part
    /// (a = d, b = −c: the axis cones in the frame before the joint): the co-rotating part
    /// (a = −d, b = c) is a tilt fixed in the turning part, which is the next link's frame
    /// turned, so the geometric model carries it and a calibration holds some of the four
    /// unknowns — the magnitude must not depend on which. Uncertainty by first-order
    /// propagation, the four unknowns taken as uncorrelated (the report's `rho` is for two); a
    /// held unknown (no uncertainty) counts as exact.
    fn magnitude(&self, values: &[(f64, f64)], _rho: f64) -> (f64, f64) {
        let u = |k: usize| {
            let u = values[k].1;
            if u.is_finite() {
                u
            } else {
                0.0
            }
        };
        let v = |k: usize| values[k].0;
        // The wave's parts and their variances.
        let (parts, vars): (Vec<f64>, Vec<f64>) = if self.order == 1 {
            let p = (v(0) + v(3)) / 2.0;
            let q = (v(1) - v(2)) / 2.0;
            let (vp, vq) = (
                (u(0).powi(2) + u(3).powi(2)) / 4.0,
                (u(1).powi(2) + u(2).powi(2)) / 4.0,
            );
            // Counter-rotating (p, q, −q, p): its sum of squares is 2(p² + q²).
            (vec![p, q, -q, p], vec![vp, vq, vq, vp])
        } else {
            (
                (0..4).map(v).collect(),
                (0..4).map(|k| u(k).powi(2)).collect(),
            )
        };
        let a2: f64 = parts.iter().map(|x| x * x).sum();
        let var: f64 = parts
            .iter()
            .zip(&vars)
            .map(|(x, s2)| x * x * s2)
            .sum::<f64>()
            / a2.max(1e-300);
        (a2.sqrt(), var.max(0.0).sqrt())
    }
}

impl Simulate for Wobble {
    /// 20–100 µrad of tilt variation, in a random direction and phase: what a hub-class
    /// arm's angular-contact bearings show.
    fn set_typical(&self, arm: &mut Arm, rng: &mut SimRng) {
        let amp = rng.gen_range(20e-6..100e-6);
        let dir = rng.gen_range(0.0..std::f64::consts::TAU);
        let phase = rng.gen_range(0.0..std::f64::consts::TAU);
        let (s, c) = phase.sin_cos();
        let (a, b) = (amp * dir.cos(), amp * dir.sin());
        arm.joints[self.joint].wobble.push(Entry {
            order: self.order,
            alpha: [a * c, a * s],
            beta: [b * c, b * s],
        });
    }
}
