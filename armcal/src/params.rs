//! The unknowns of a calibration and how they map onto an [`Arm`].
//!
//! A calibration adjusts the error keys of the calibration file and nothing else: the nominal
//! `link` and probe `vector` never change, and `tilt` (which holds nominal and error together)
//! only moves by the identified error. A parameter vector is therefore a list of *increments*
//! to the start arm's keys, so that x = 0 is the start arm whatever it already contains (a
//! nominal arm, or an earlier calibration being refined).
//!
//! The same list names the instrument frame's six unknowns, so that identifiability can speak
//! of "joint 1's zero offset against the frame's rotation about z" in one vocabulary.
//!
//! The unknowns themselves, [`Param`] and [`Link`], are the workspace's one vocabulary of
//! parameters (crate `quatarm-params`, joints 0-based, named by the calibration file's keys),
//! which the reference's budget lists and the table builder writes columns for; [`ParamExt`]
//! adds what only armcal knows of them.

pub use crate::effects::Effect;
use crate::effects::{self, TermsError};
use quatarm_params::XYZ;
pub use quatarm_params::{Link, Param};
use quatarm_ref::arm::Arm;

/// The unknowns' answers that need armcal: words, units, plausible sizes, and the arm's
/// keys they read and move. An extension of [`Param`], which is the workspace's one
/// vocabulary (`quatarm-params`): the name of a parameter is its `Display`, the calibration
/// file's key (`joint[2].zero_offset`).
pub trait ParamExt: Copy {
    /// The effect an unknown belongs to and its number within it (`None`: a geometric or
    /// frame unknown).
    fn effect(self) -> Option<(Effect, usize)>;
    /// The parameter in words, for reports.
    fn describe(self, arm: &Arm) -> String;
    /// Unit of the parameter's value.
    fn unit(self) -> &'static str;
    /// A size beyond which a value is not physically plausible for the term. Identifiability
    /// uses it to call a direction the data cannot pin down better than this "not
    /// identified".
    fn plausible(self) -> f64;
    /// Which parameter to keep when the data cannot separate two: lower keeps first. The
    /// frame is kept (it must absorb whatever the data cannot tell from it), then the
    /// encoder's zero offsets, the probe, the links, the tilts, and the extended effects last.
    fn priority(self) -> u32;
    /// The parameter's current value in an arm (the whole key: nominal and error for `tilt`).
    /// Frame parameters are local increments and read 0.
    fn value(self, arm: &Arm) -> f64;
    /// Adds `dx` to the parameter's key in `arm` (frame parameters: nothing).
    fn add_to(self, arm: &mut Arm, dx: f64);
}

/// The extended effects' unknowns, which their effect answers for ([`effects::Term`]).
macro_rules! effect_params {
    () => {
        Param::Harmonic { .. } | Param::Wobble { .. } | Param::Gravity(_) | Param::Thermal(_)
    };
}

/// Asks the term an effect unknown belongs to, with the unknown's number within it.
fn term<R>(p: Param, f: impl FnOnce(&dyn effects::Term, usize) -> R) -> R {
    let Some((e, c)) = effects::effect_of(p) else {
        unreachable!("{p} is not an effect's unknown")
    };
    e.with(|t| f(t, c))
}

// Every match here names every kind of parameter (no catch-all): a new kind makes the
// compiler stop at each answer it must give.
impl ParamExt for Param {
    fn effect(self) -> Option<(Effect, usize)> {
        effects::effect_of(self)
    }

    fn describe(self, arm: &Arm) -> String {
        match self {
            Param::ZeroOffset(j) => format!("joint {} zero offset Δθ", j + 1),
            Param::Tilt(j, c) => {
                let (e1, e2) = arm.joints[j].axis.perpendicular();
                let (sym, ax) = if c == 0 { ("δα", e1) } else { ("δβ", e2) };
                format!("joint {} tilt {sym} (about its {})", j + 1, ax.name())
            }
            Param::LinkError(j, c) => format!("link {} error along {}", j + 1, XYZ[c]),
            Param::ProbeError(k, c) => match arm.probe_at(k) {
                Some(p) if arm.probe_count() > 1 => {
                    format!("probe {} error along {}", p.id, XYZ[c])
                }
                _ => format!("probe error along {}", XYZ[c]),
            },
            Param::FrameRotation(c) => {
                format!("instrument frame rotation about the base {} axis", XYZ[c])
            }
            Param::FrameTranslation(c) => {
                format!(
                    "instrument frame translation along the base {} axis",
                    XYZ[c]
                )
            }
            effect_params!() => term(self, |t, c| t.describe_param(c)),
        }
    }

    fn unit(self) -> &'static str {
        match self {
            Param::ZeroOffset(_) | Param::Tilt(..) | Param::FrameRotation(_) => "rad",
            Param::LinkError(..) | Param::ProbeError(..) | Param::FrameTranslation(_) => "mm",
            effect_params!() => term(self, |t, _| t.unit()),
        }
    }

    fn plausible(self) -> f64 {
        match self {
            Param::ZeroOffset(_) | Param::Tilt(..) => 0.05,
            Param::FrameRotation(_) => 10.0,
            Param::FrameTranslation(_) => 1e6,
            Param::LinkError(..) | Param::ProbeError(..) => 20.0,
            effect_params!() => term(self, |t, _| t.plausible()),
        }
    }

    fn priority(self) -> u32 {
        match self {
            Param::FrameRotation(_) | Param::FrameTranslation(_) => 0,
            Param::ZeroOffset(_) => 1,
            Param::ProbeError(..) => 2,
            Param::LinkError(..) => 3,
            Param::Tilt(..) => 4,
            effect_params!() => term(self, |t, _| t.priority()),
        }
    }

    fn value(self, arm: &Arm) -> f64 {
        match self {
            Param::ZeroOffset(j) => arm.joints[j].zero_offset,
            Param::Tilt(j, c) => arm.joints[j].tilt[c],
            Param::LinkError(j, c) => arm.joints[j].link_error[c],
            Param::ProbeError(k, c) => arm.probe_at(k).map_or(0.0, |p| p.error[c]),
            Param::FrameRotation(_) | Param::FrameTranslation(_) => 0.0,
            effect_params!() => term(self, |t, c| t.value(arm, c)),
        }
    }

    fn add_to(self, arm: &mut Arm, dx: f64) {
        match self {
            Param::ZeroOffset(j) => arm.joints[j].zero_offset += dx,
            Param::Tilt(j, c) => arm.joints[j].tilt[c] += dx,
            Param::LinkError(j, c) => arm.joints[j].link_error[c] += dx,
            Param::ProbeError(k, c) => {
                if let Some(p) = arm.probe_at_mut(k) {
                    p.error[c] += dx;
                }
            }
            Param::FrameRotation(_) | Param::FrameTranslation(_) => {}
            effect_params!() => term(self, |t, c| t.add_to(arm, c, dx)),
        }
    }
}

/// The arm with `x` added to the keys of `params` (frame parameters skipped).
pub fn apply(base: &Arm, params: &[Param], x: &[f64]) -> Arm {
    let mut arm = base.clone();
    for (p, v) in params.iter().zip(x) {
        if *v != 0.0 {
            p.add_to(&mut arm, *v);
        }
    }
    arm
}

/// The highest harmonic order a calibration file holds (`harmonics[].order`).
pub const MAX_ORDER: u32 = quatarm_ref::calfile::MAX_HARMONIC_ORDER;

/// What a calibration fits: the geometric model (or not) and any extended effects.
///
/// Text form (`--terms`): comma-separated items. `geometric` is the 6N + 3 geometric
/// parameters and is implied unless `only` appears; `+KEY:ARGS` adds the terms of an effect
/// (each module of [`effects`] says its arguments: the 1-based joint or `*` for every joint,
/// and what else it needs); `only` fits just the listed effects (and the instrument frame) on
/// top of the start arm.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Terms {
    /// Fit the geometric parameters.
    pub geometric: bool,
    /// Extended effects to fit, without repeats, in the order given.
    pub effects: Vec<Effect>,
}

impl Default for Terms {
    fn default() -> Terms {
        Terms::geometric()
    }
}

impl Terms {
    /// The geometric model alone.
    pub fn geometric() -> Terms {
        Terms {
            geometric: true,
            effects: Vec::new(),
        }
    }

    /// The geometric model plus `effects`.
    pub fn with(effects: &[Effect]) -> Terms {
        let mut t = Terms::geometric();
        for e in effects {
            t.add(*e);
        }
        t
    }

    /// Adds an effect unless it is already there.
    pub fn add(&mut self, e: Effect) {
        if !self.effects.contains(&e) {
            self.effects.push(e);
        }
    }

    /// Parses the `--terms` text for an arm with `dof` joints.
    pub fn parse(text: &str, dof: usize) -> Result<Terms, TermsError> {
        let mut t = Terms::geometric();
        let mut only = false;
        for item in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            if item == "geometric" {
                continue;
            }
            if item == "only" {
                only = true;
                continue;
            }
            let body = item.strip_prefix('+').unwrap_or(item);
            let mut parts = body.split(':');
            let name = parts.next().unwrap_or("");
            let args: Vec<&str> = parts.collect();
            let Some(family) = effects::family(name) else {
                return Err(TermsError(format!(
                    "unknown term `{item}`: geometric, only, {}",
                    effects::usages()
                )));
            };
            for e in family.parse(item, &args, dof)? {
                t.add(e);
            }
        }
        if only {
            if t.effects.is_empty() {
                return Err(TermsError(nothing_to_fit()));
            }
            t.geometric = false;
        }
        Ok(t)
    }

    /// The arm unknowns, geometric first (per joint: zero offset, tilts, link error; then the
    /// probe), then the effects in order.
    pub fn params(&self, dof: usize) -> Vec<Param> {
        let mut v = Vec::new();
        if self.geometric {
            v.extend(geometric_params(dof));
        }
        for e in &self.effects {
            for p in e.params() {
                if !v.contains(&p) {
                    v.push(p);
                }
            }
        }
        v
    }

    /// The text form.
    pub fn spec(&self) -> String {
        let mut items = Vec::new();
        if self.geometric {
            items.push("geometric".to_string());
        } else {
            items.push("only".to_string());
        }
        items.extend(self.effects.iter().map(|e| e.spec()));
        items.join(",")
    }
}

/// Why `only` without an effect fits nothing, with an example that would.
pub fn nothing_to_fit() -> String {
    format!(
        "`only` fits the listed effects alone, and none is listed: nothing to fit (e.g. \
         `only,+{}:*`)",
        effects::gravity::KEY
    )
}

/// The 6N + 3 geometric parameters of `spec/arm-model.md` (the first probe's error; an arm
/// with several probes adds [`probe_params`] for the others).
pub fn geometric_params(dof: usize) -> Vec<Param> {
    let mut v = Vec::with_capacity(6 * dof + 3);
    for j in 0..dof {
        v.push(Param::ZeroOffset(j));
        v.push(Param::Tilt(j, 0));
        v.push(Param::Tilt(j, 1));
        for c in 0..3 {
            v.push(Param::LinkError(j, c));
        }
    }
    v.extend(probe_params(0));
    v
}

/// The error Δv_p of the probe at index `k` (`quatarm_ref::Arm::probes` order).
pub fn probe_params(k: usize) -> impl Iterator<Item = Param> {
    (0..3).map(move |c| Param::ProbeError(k, c))
}

/// The instrument frame's six unknowns.
pub fn frame_params() -> Vec<Param> {
    (0..3)
        .map(Param::FrameRotation)
        .chain((0..3).map(Param::FrameTranslation))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_terms() {
        let t = Terms::parse(
            &format!(
                "geometric,+{}:2:1,+{}:4,+{}:probe",
                effects::harmonic::KEY,
                effects::gravity::KEY,
                effects::thermal::KEY
            ),
            6,
        )
        .unwrap();
        assert!(t.geometric);
        assert_eq!(
            t.effects,
            vec![
                Effect::Harmonic { joint: 1, order: 1 },
                Effect::Gravity(3),
                Effect::Thermal(Link::Probe)
            ]
        );
        assert_eq!(t.params(6).len(), 39 + 4);
        assert_eq!(Terms::parse(&t.spec(), 6).unwrap(), t);
        let all = Terms::parse(&format!("+{}:*", effects::thermal::KEY), 6).unwrap();
        assert_eq!(all.effects.len(), 7);
        assert!(Terms::parse(&format!("+{}:7", effects::gravity::KEY), 6).is_err());
        assert!(Terms::parse(&format!("+{}:2", effects::harmonic::KEY), 6).is_err());
        assert!(Terms::parse("+wobble:2", 6).is_err());
        let w = Terms::parse(&format!("+{}:3:2", effects::wobble::KEY), 6).unwrap();
        assert_eq!(w.effects, vec![Effect::Wobble { joint: 2, order: 2 }]);
        assert_eq!(w.params(6).len(), 39 + 4);
        assert_eq!(Terms::parse(&w.spec(), 6).unwrap(), w);
        assert!(Terms::parse(&format!("+{}:3", effects::wobble::KEY), 6).is_err());
        let only = Terms::parse(&format!("only,+{}:2", effects::gravity::KEY), 7).unwrap();
        assert_eq!(only.params(7), vec![Param::Gravity(1)]);
    }

    #[test]
    fn apply_touches_error_keys_only() {
        let base = Arm::default6();
        let params = Terms::with(&[
            Effect::Harmonic { joint: 2, order: 2 },
            Effect::Thermal(Link::Probe),
        ])
        .params(6);
        let x: Vec<f64> = (0..params.len()).map(|i| 1e-3 * (i as f64 + 1.0)).collect();
        let arm = apply(&base, &params, &x);
        for (a, b) in arm.joints.iter().zip(&base.joints) {
            assert_eq!(a.link, b.link);
            assert_eq!(a.axis, b.axis);
        }
        assert_eq!(arm.probe.vector, base.probe.vector);
        for (p, v) in params.iter().zip(&x) {
            assert!((p.value(&arm) - p.value(&base) - v).abs() < 1e-15, "{p}");
        }
        assert_eq!(arm.joints[2].harmonics.len(), 1);
    }
}
