//! `thermal_expansion`: a link (or the probe) lengthens by κ (1/°C) per degree from the
//! reference temperature. One unknown per link: κ.

use super::figure::{Figure, Legend, Patterns};
use super::{joint_args, Describe, Draw, Effect, Family, Simulate, Term, TermsError, TipPoint};
use crate::rng::SimRng;
use nalgebra::Vector3;
use quatarm::table::limits::THERMAL;
use quatarm_params::{Link, Param};
use quatarm_ref::arm::Arm;
use quatarm_ref::forward::REFERENCE_TEMP_C;
use rand::Rng;
use serde_json::Value;

/// The spec's key.
pub const KEY: &str = "thermal_expansion";

/// The family of thermal expansions.
pub struct Expansions;

/// Its registration.
pub static FAMILY: Expansions = Expansions;

/// The thermal expansion of one link or the probe.
#[derive(Clone, Copy, Debug)]
pub struct Thermal {
    /// The link.
    pub link: Link,
}

impl Family for Expansions {
    fn key(&self) -> &'static str {
        KEY
    }

    fn usage(&self) -> &'static str {
        "+thermal_expansion:J|probe"
    }

    fn parse(&self, item: &str, args: &[&str], dof: usize) -> Result<Vec<Effect>, TermsError> {
        let links = joint_args(item, KEY, args.first(), dof, true)?;
        Ok(links.into_iter().map(Effect::Thermal).collect())
    }

    fn vocabulary(&self, dof: usize, thermal: bool) -> Vec<Effect> {
        if !thermal {
            return Vec::new();
        }
        (0..dof)
            .map(Link::Joint)
            .chain([Link::Probe])
            .map(Effect::Thermal)
            .collect()
    }

    fn beyond_table(&self, arm: &Arm, at: Link) -> Vec<String> {
        let (kappa, name) = match at {
            Link::Joint(k) => (arm.joints[k].thermal, format!("link {}", k + 1)),
            Link::Probe => (arm.probe.thermal, "probe".to_string()),
        };
        if kappa.abs() > THERMAL {
            vec![format!(
                "{name} thermal expansion κ = {kappa:.3e} /°C; the table holds |κ| ≤ {THERMAL:e} /°C"
            )]
        } else {
            Vec::new()
        }
    }

    fn clear(&self, arm: &mut Arm) {
        for j in &mut arm.joints {
            j.thermal = 0.0;
        }
        arm.probe.thermal = 0.0;
    }
}

impl Draw for Expansions {
    fn figure(&self, at: &Patterns) -> Option<Figure> {
        if !at.thermal {
            return None;
        }
        let (data, geo, n) = (at.data, &at.geo, at.data.dof);
        let mut panels = Vec::new();
        for l in 0..=n {
            if geo.iter().all(|g| g.links[l].is_none()) {
                continue;
            }
            let (name, link) = if l == n {
                ("probe".to_string(), Link::Probe)
            } else {
                (format!("link {}", l + 1), Link::Joint(l))
            };
            let cause = at
                .causes
                .iter()
                .find(|c| {
                    c.effect == Effect::Thermal(link)
                        || c.indistinguishable.contains(&Effect::Thermal(link))
                })
                .map(|c| c.effect);
            panels.push(at.panel(
                name.clone(),
                "temperature (°C)".into(),
                format!("apparent {name} elongation (µm)"),
                cause,
                &|i, m| geo[i].links[l].map(|dir| (data.rows[i].temp_c, 1e3 * dir.dot(m))),
            ));
        }
        Some(Figure {
            legend: Legend::Models,
            file: "residuals_vs_temperature.png".into(),
            title: "What the model misses, as each link's elongation, against temperature".into(),
            caption: "A thermal expansion shows as a line rising with temperature (slope κ·L)"
                .into(),
            panels,
        })
    }
}

impl Term for Thermal {
    fn family(&self) -> &'static dyn Family {
        &FAMILY
    }

    fn coefficients(&self) -> usize {
        1
    }

    fn param(&self, _c: usize) -> Param {
        Param::Thermal(self.link)
    }

    fn unit(&self) -> &'static str {
        "1/°C"
    }

    fn plausible(&self) -> f64 {
        1e-3
    }

    fn priority(&self) -> u32 {
        7
    }

    fn value(&self, arm: &Arm, _c: usize) -> f64 {
        match self.link {
            Link::Joint(j) => arm.joints[j].thermal,
            Link::Probe => arm.probe.thermal,
        }
    }

    fn add_to(&self, arm: &mut Arm, _c: usize, dx: f64) {
        match self.link {
            Link::Joint(j) => arm.joints[j].thermal += dx,
            Link::Probe => arm.probe.thermal += dx,
        }
    }

    fn add_entry(&self, _arm: &mut Arm) {}

    fn column(&self, _c: usize, at: &TipPoint) -> Vector3<f64> {
        let dt = at.temp_c - REFERENCE_TEMP_C;
        match self.link {
            Link::Joint(j) => at.after(j) * Vector3::from(at.arm.joints[j].actual_link()) * dt,
            // The first probe's expansion; a reading taken with another moves none with it.
            Link::Probe if at.probe != 0 => Vector3::zeros(),
            Link::Probe => at.after(at.arm.dof() - 1) * Vector3::from(at.arm.probe.actual()) * dt,
        }
    }
}

impl Describe for Thermal {
    fn spec(&self) -> String {
        match self.link {
            Link::Joint(j) => format!("+{KEY}:{}", j + 1),
            Link::Probe => format!("+{KEY}:probe"),
        }
    }

    fn describe(&self) -> String {
        match self.link {
            Link::Joint(j) => format!("link {} thermal expansion", j + 1),
            Link::Probe => "probe thermal expansion".into(),
        }
    }

    fn physical(&self) -> &'static str {
        " (the link lengthens with temperature)"
    }

    fn location(&self) -> Value {
        match self.link {
            Link::Joint(j) => Value::from(j + 1),
            Link::Probe => Value::from("probe"),
        }
    }

    fn describe_param(&self, _c: usize) -> String {
        self.describe()
    }

    fn no_effect_reason(&self, arm: &Arm, thermal: bool) -> Option<String> {
        if !thermal {
            return Some("the data have no temperature spread".into());
        }
        match self.link {
            Link::Joint(j) if arm.joints[j].actual_link().iter().all(|c| c.abs() < 1e-9) => {
                Some(format!("link {} has no length: nothing to expand", j + 1))
            }
            _ => None,
        }
    }
}

impl Simulate for Thermal {
    fn set_typical(&self, arm: &mut Arm, rng: &mut SimRng) {
        let kappa = rng.gen_range(1.5e-5..2.5e-5);
        match self.link {
            Link::Joint(j) => arm.joints[j].thermal = kappa,
            Link::Probe => arm.probe.thermal = kappa,
        }
    }
}
