//! `gravity_compliance`: a hinge bends under the weight beyond it, by g (rad/mm) times its
//! gravity lever a · ((p − o) × ẑ). One unknown per joint: g.

use super::figure::{Figure, Legend, Patterns};
use super::{
    joint_args, joints_of, Describe, Draw, Effect, Family, Simulate, Term, TermsError, TipPoint,
};
use crate::rng::SimRng;
use nalgebra::Vector3;
use quatarm::table::limits::GRAVITY;
use quatarm_params::{Link, Param};
use quatarm_ref::arm::Arm;
use rand::Rng;
use serde_json::Value;

/// The spec's key.
pub const KEY: &str = "gravity_compliance";

/// The family of gravity compliances.
pub struct Compliances;

/// Its registration.
pub static FAMILY: Compliances = Compliances;

/// Joint `joint`'s (0-based) gravity compliance.
#[derive(Clone, Copy, Debug)]
pub struct Gravity {
    /// Joint, 0-based.
    pub joint: usize,
}

impl Family for Compliances {
    fn key(&self) -> &'static str {
        KEY
    }

    fn usage(&self) -> &'static str {
        "+gravity_compliance:J"
    }

    fn parse(&self, item: &str, args: &[&str], dof: usize) -> Result<Vec<Effect>, TermsError> {
        let links = joint_args(item, KEY, args.first(), dof, false)?;
        Ok(joints_of(links).map(Effect::Gravity).collect())
    }

    fn vocabulary(&self, dof: usize, _thermal: bool) -> Vec<Effect> {
        (0..dof).map(Effect::Gravity).collect()
    }

    fn beyond_table(&self, arm: &Arm, at: Link) -> Vec<String> {
        let Link::Joint(k) = at else {
            return Vec::new();
        };
        let g = arm.joints[k].gravity;
        if g.abs() > GRAVITY {
            vec![format!(
                "joint {} gravity compliance g = {g:.3e} rad/mm; the table holds |g| ≤ {GRAVITY:e} rad/mm",
                k + 1
            )]
        } else {
            Vec::new()
        }
    }

    fn clear(&self, arm: &mut Arm) {
        for j in &mut arm.joints {
            j.gravity = 0.0;
        }
    }
}

impl Draw for Compliances {
    fn figure(&self, at: &Patterns) -> Option<Figure> {
        let geo = &at.geo;
        let mut panels = Vec::new();
        for k in 0..at.data.dof {
            let span = geo.iter().map(|g| g.lever[k].abs()).fold(0.0, f64::max);
            if span < 1.0 {
                continue;
            }
            let Some(cut) = at.cut_of(k) else { continue };
            panels.push(at.panel(
                format!("joint {}", k + 1),
                format!("joint {} gravity lever a·((p − o) × z) (mm)", k + 1),
                "apparent angle error (µrad)".into(),
                Some(Effect::Gravity(k)).filter(|e| at.named(*e)),
                &|i, m| {
                    let t = geo[i].turn[k];
                    let t2 = t.norm_squared();
                    (t2.sqrt() >= cut && t2 > 0.0).then(|| (geo[i].lever[k], 1e6 * t.dot(m) / t2))
                },
            ));
        }
        Some(Figure {
            legend: Legend::Models,
            file: "residuals_vs_gravity_lever.png".into(),
            title: "What the model misses, as each joint's angle error, against its gravity lever"
                .into(),
            caption: "A gravity compliance shows as a straight line through 0 (slope g in µrad/mm)"
                .into(),
            panels,
        })
    }
}

impl Term for Gravity {
    fn family(&self) -> &'static dyn Family {
        &FAMILY
    }

    fn coefficients(&self) -> usize {
        1
    }

    fn param(&self, _c: usize) -> Param {
        Param::Gravity(self.joint)
    }

    fn unit(&self) -> &'static str {
        "rad/mm"
    }

    fn plausible(&self) -> f64 {
        1e-5
    }

    fn priority(&self) -> u32 {
        6
    }

    fn value(&self, arm: &Arm, _c: usize) -> f64 {
        arm.joints[self.joint].gravity
    }

    fn add_to(&self, arm: &mut Arm, _c: usize, dx: f64) {
        arm.joints[self.joint].gravity += dx;
    }

    fn add_entry(&self, _arm: &mut Arm) {}

    /// The first-order lever e_k = a_k · ((p − o_k) × ẑ) of the spec (see [`crate::fit::jacobian`]).
    fn column(&self, _c: usize, at: &TipPoint) -> Vector3<f64> {
        let c = at.chain;
        let j = self.joint;
        let lever = c.axes[j].dot(&(c.p - c.origins[j]).cross(&Vector3::z()));
        at.turn(j) * lever
    }
}

impl Describe for Gravity {
    fn spec(&self) -> String {
        format!("+{KEY}:{}", self.joint + 1)
    }

    fn describe(&self) -> String {
        format!("joint {} gravity compliance", self.joint + 1)
    }

    fn physical(&self) -> &'static str {
        " (the joint bends under the weight beyond it)"
    }

    fn location(&self) -> Value {
        Value::from(self.joint + 1)
    }

    fn describe_param(&self, _c: usize) -> String {
        self.describe()
    }

    fn no_effect_reason(&self, _arm: &Arm, _thermal: bool) -> Option<String> {
        Some(format!(
            "joint {} has no gravity lever on these poses (its axis stays vertical, so \
             a · ((p − o) × ẑ) = 0)",
            self.joint + 1
        ))
    }
}

impl Simulate for Gravity {
    fn set_typical(&self, arm: &mut Arm, rng: &mut SimRng) {
        arm.joints[self.joint].gravity = rng.gen_range(2e-8..4e-8);
    }
}
