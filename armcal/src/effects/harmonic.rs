//! `encoder_harmonic`: an error of a joint's encoder periodic in its reading,
//! e(θ) = s·sin(hθ) + c·cos(hθ) (rad), added to the joint's angle. Order 1 is the disc's
//! eccentricity, order 2 its ellipticity. Two unknowns per term: s (0) and c (1).

use super::figure::{Figure, Legend, Patterns};
use super::{
    parse_periodic, periodic_entry, periodic_vocabulary, Describe, Draw, Effect, Family, Simulate,
    Term, TermsError, TipPoint,
};
use crate::data::Dataset;
use crate::rng::SimRng;
use nalgebra::Vector3;
use quatarm::table::limits::HARMONIC_SUM;
use quatarm_params::{Link, Param};
use quatarm_ref::arm::{Arm, Harmonic as Entry};
use rand::Rng;
use serde_json::Value;

/// The spec's key.
pub const KEY: &str = "encoder_harmonic";

/// Highest harmonic order a diagnosis tries by default (`diagnose --max-order`). Each order
/// adds two unknowns per joint to every selection step, so the cap bounds the run time; the
/// data may resolve less ([`resolvable_order`]), which then sets the limit.
pub const DIAGNOSIS_MAX_ORDER: u32 = 8;

/// Highest order the vocabulary holds: what the firmware's table can apply.
pub const VOCABULARY_MAX_ORDER: u32 = quatarm::table::MAX_HARMONIC_ORDER as u32;

/// Fewest distinct readings per order of a wave: each order is two unknowns, and a fit of
/// 2H unknowns wants several readings per unknown to tell a wave from noise.
pub const READINGS_PER_ORDER: usize = 8;

/// The highest order of a wave in joint `k`'s reading (0-based) that `data` resolve: the
/// smallest of
/// - ⌊π / g⌋ − 1 with g the widest gap between consecutive distinct readings (rad): a wave of
///   order h has a half period of π / h, and a half period with no reading in it hides a
///   whole crest (the Nyquist argument on irregular samples: one reading per half period at
///   least, with one order of margin);
/// - n / [`READINGS_PER_ORDER`] with n the distinct readings (two unknowns per order);
/// - [`VOCABULARY_MAX_ORDER`].
///
/// 0 when the joint has fewer than 2 [`READINGS_PER_ORDER`] distinct readings.
pub fn resolvable_order(data: &Dataset, k: usize) -> u32 {
    let mut v: Vec<f64> = data
        .rows
        .iter()
        .filter_map(|r| r.theta.get(k).copied())
        .filter(|t| t.is_finite())
        .collect();
    v.sort_by(f64::total_cmp);
    v.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    if v.len() < 2 * READINGS_PER_ORDER {
        return 0;
    }
    let gap = v.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
    let by_gap = if gap > 0.0 {
        ((std::f64::consts::PI / gap).floor() - 1.0).max(0.0)
    } else {
        0.0
    };
    let by_count = (v.len() / READINGS_PER_ORDER) as f64;
    by_gap.min(by_count).min(f64::from(VOCABULARY_MAX_ORDER)) as u32
}

/// The family of encoder harmonics.
pub struct Harmonics;

/// Its registration.
pub static FAMILY: Harmonics = Harmonics;

/// Joint `joint`'s (0-based) harmonic of order `order`.
#[derive(Clone, Copy, Debug)]
pub struct Harmonic {
    /// Joint, 0-based.
    pub joint: usize,
    /// Order h ≥ 1.
    pub order: u32,
}

impl Family for Harmonics {
    fn key(&self) -> &'static str {
        KEY
    }

    fn usage(&self) -> &'static str {
        "+encoder_harmonic:J:H"
    }

    fn parse(&self, item: &str, args: &[&str], dof: usize) -> Result<Vec<Effect>, TermsError> {
        parse_periodic(item, KEY, args, dof, |joint, order| Effect::Harmonic {
            joint,
            order,
        })
    }

    fn vocabulary(&self, dof: usize, _thermal: bool) -> Vec<Effect> {
        periodic_vocabulary(dof, VOCABULARY_MAX_ORDER, |joint, order| Effect::Harmonic {
            joint,
            order,
        })
    }

    fn beyond_table(&self, arm: &Arm, at: Link) -> Vec<String> {
        let Link::Joint(k) = at else {
            return Vec::new();
        };
        let j = &arm.joints[k];
        let mut out = Vec::new();
        let n = j
            .harmonics
            .iter()
            .filter(|h| h.sin != 0.0 || h.cos != 0.0)
            .count();
        if n > quatarm::table::MAX_HARMONICS {
            out.push(format!(
                "joint {} has {n} harmonic terms; the table holds {}",
                k + 1,
                quatarm::table::MAX_HARMONICS
            ));
        }
        let sum: f64 = j.harmonics.iter().map(|h| h.sin.abs() + h.cos.abs()).sum();
        if sum > HARMONIC_SUM {
            out.push(format!(
                "joint {} harmonics: Σ|coefficients| = {sum:.3e} rad; the table holds {HARMONIC_SUM:e} rad",
                k + 1
            ));
        }
        out
    }

    fn clear(&self, arm: &mut Arm) {
        for h in arm.joints.iter_mut().flat_map(|j| &mut j.harmonics) {
            h.sin = 0.0;
            h.cos = 0.0;
        }
    }
}

impl Draw for Harmonics {
    fn figure(&self, at: &Patterns) -> Option<Figure> {
        let (data, geo) = (at.data, &at.geo);
        let mut skipped = Vec::new();
        let mut panels = Vec::new();
        for k in 0..data.dof {
            let Some(cut) = at.cut_of(k) else {
                skipped.push(k + 1);
                continue;
            };
            let kind = match (at.plain, at.arm().is_hinge(k)) {
                (false, _) => String::new(),
                (true, true) => " (hinge)".to_string(),
                (true, false) => " (swivel)".to_string(),
            };
            let harmonic = (1..=VOCABULARY_MAX_ORDER)
                .map(|order| Effect::Harmonic { joint: k, order })
                .find(|e| at.named(*e));
            panels.push(at.panel(
                format!("joint {}{kind}", k + 1),
                format!("joint {} reading θ{} (deg)", k + 1, k + 1),
                "apparent angle error (µrad)".into(),
                harmonic,
                &|i, m| {
                    let t = geo[i].turn[k];
                    let t2 = t.norm_squared();
                    (t2.sqrt() >= cut && t2 > 0.0)
                        .then(|| (data.rows[i].theta[k].to_degrees(), 1e6 * t.dot(m) / t2))
                },
            ));
        }
        let mut caption =
            "An encoder harmonic shows as a wave of its order (cycles per turn)".to_string();
        if !skipped.is_empty() {
            caption += &format!(
                "; no panel for joint {}: the ball passes too close to its axis to show its angle",
                skipped
                    .iter()
                    .map(|k| k.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
        Some(Figure {
            legend: Legend::Models,
            file: "residuals_vs_joint_angle.png".into(),
            title:
                "What the model misses, as each joint's angle error, against the joint's reading"
                    .into(),
            caption,
            panels,
        })
    }
}

impl Term for Harmonic {
    fn family(&self) -> &'static dyn Family {
        &FAMILY
    }

    fn coefficients(&self) -> usize {
        2
    }

    fn param(&self, c: usize) -> Param {
        Param::Harmonic {
            joint: self.joint,
            order: self.order,
            cos: c == 1,
        }
    }

    fn unit(&self) -> &'static str {
        "rad"
    }

    fn plausible(&self) -> f64 {
        0.01
    }

    fn priority(&self) -> u32 {
        5
    }

    fn value(&self, arm: &Arm, c: usize) -> f64 {
        arm.joints[self.joint]
            .harmonics
            .iter()
            .filter(|h| h.order == self.order)
            .map(|h| if c == 1 { h.cos } else { h.sin })
            .sum()
    }

    fn add_to(&self, arm: &mut Arm, c: usize, dx: f64) {
        let order = self.order;
        let h = periodic_entry(
            &mut arm.joints[self.joint].harmonics,
            order,
            |h| h.order,
            || Entry {
                order,
                sin: 0.0,
                cos: 0.0,
            },
        );
        if c == 1 {
            h.cos += dx;
        } else {
            h.sin += dx;
        }
    }

    fn add_entry(&self, arm: &mut Arm) {
        self.add_to(arm, 0, 0.0);
    }

    fn column(&self, c: usize, at: &TipPoint) -> Vector3<f64> {
        let a = f64::from(self.order) * at.theta[self.joint];
        at.turn(self.joint) * if c == 1 { a.cos() } else { a.sin() }
    }
}

impl Describe for Harmonic {
    fn spec(&self) -> String {
        format!("+{KEY}:{}:{}", self.joint + 1, self.order)
    }

    fn describe(&self) -> String {
        format!(
            "joint {} encoder harmonic of order {}",
            self.joint + 1,
            self.order
        )
    }

    fn physical(&self) -> &'static str {
        match self.order {
            1 => " (encoder disc eccentricity)",
            2 => " (encoder disc ellipticity)",
            _ => "",
        }
    }

    fn location(&self) -> Value {
        Value::from(self.joint + 1)
    }

    fn order(&self) -> Option<u32> {
        Some(self.order)
    }

    fn describe_param(&self, c: usize) -> String {
        format!(
            "joint {} encoder harmonic order {} ({})",
            self.joint + 1,
            self.order,
            sin_cos(c)
        )
    }

    fn magnitude(&self, values: &[(f64, f64)], rho: f64) -> (f64, f64) {
        let ((s, us), (co, uc)) = (values[0], values[1]);
        let a = s.hypot(co);
        let var = (s * s * us * us + co * co * uc * uc + 2.0 * s * co * rho * us * uc)
            / (a * a).max(1e-300);
        (a, var.max(0.0).sqrt())
    }

    fn phasor(&self, values: &[f64]) -> Option<(f64, f64)> {
        Some((values[0], values[1]))
    }
}

impl Simulate for Harmonic {
    fn set_typical(&self, arm: &mut Arm, rng: &mut SimRng) {
        let amp = rng.gen_range(25e-6..120e-6);
        let phase = rng.gen_range(0.0..std::f64::consts::TAU);
        arm.joints[self.joint].harmonics.push(Entry {
            order: self.order,
            sin: amp * phase.cos(),
            cos: amp * phase.sin(),
        });
    }
}

fn sin_cos(c: usize) -> &'static str {
    if c == 1 {
        "cos"
    } else {
        "sin"
    }
}
