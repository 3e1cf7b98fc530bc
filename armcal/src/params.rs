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

use quatarm_ref::arm::{Arm, Harmonic};
use std::fmt;

/// A link that can expand with temperature: one of the joints' links, or the probe.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Link {
    /// The link after joint i (0-based).
    Joint(usize),
    /// The probe vector.
    Probe,
}

/// One unknown of a calibration. Joint indices are 0-based here; names and reports say
/// joint numbers 1-based as the spec does.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Param {
    /// Δθ_i (rad).
    ZeroOffset(usize),
    /// δα_i (component 0) or δβ_i (component 1) of `tilt` (rad).
    Tilt(usize, usize),
    /// Component c of Δv_i (mm).
    LinkError(usize, usize),
    /// Component c of Δv_p (mm).
    ProbeError(usize),
    /// One coefficient of an `encoder_harmonic` term (rad): of sin(hθ) or of cos(hθ).
    Harmonic {
        /// Joint (0-based).
        joint: usize,
        /// Order h ≥ 1.
        order: u32,
        /// `true` for the cos coefficient, `false` for sin.
        cos: bool,
    },
    /// `gravity_compliance` g_i (rad/mm).
    Gravity(usize),
    /// `thermal_expansion` κ (1/°C) of a link or the probe.
    Thermal(Link),
    /// Instrument frame: a small rotation about the arm's base axis c, before the frame's
    /// current transform (rad).
    FrameRotation(usize),
    /// Instrument frame: a small translation along the arm's base axis c, before the frame's
    /// current transform (mm).
    FrameTranslation(usize),
}

const XYZ: [&str; 3] = ["x", "y", "z"];

impl Param {
    /// Whether the parameter belongs to the instrument frame rather than the arm.
    pub fn is_frame(self) -> bool {
        matches!(self, Param::FrameRotation(_) | Param::FrameTranslation(_))
    }

    /// Whether the parameter is one of the geometric model's (`spec/arm-model.md`).
    pub fn is_geometric(self) -> bool {
        matches!(
            self,
            Param::ZeroOffset(_) | Param::Tilt(..) | Param::LinkError(..) | Param::ProbeError(_)
        )
    }

    /// The calibration-file key it adjusts, e.g. `joint[2].zero_offset`, `joint[3].tilt[0]`
    /// (joints 1-based, array elements 0-based as in the file reader's messages).
    pub fn key(self) -> String {
        match self {
            Param::ZeroOffset(j) => format!("joint[{}].zero_offset", j + 1),
            Param::Tilt(j, c) => format!("joint[{}].tilt[{c}]", j + 1),
            Param::LinkError(j, c) => format!("joint[{}].link_error[{c}]", j + 1),
            Param::ProbeError(c) => format!("probe.error[{c}]"),
            Param::Harmonic { joint, order, cos } => format!(
                "joint[{}].harmonics(order={order}).{}",
                joint + 1,
                if cos { "cos" } else { "sin" }
            ),
            Param::Gravity(j) => format!("joint[{}].gravity", j + 1),
            Param::Thermal(Link::Joint(j)) => format!("joint[{}].thermal", j + 1),
            Param::Thermal(Link::Probe) => "probe.thermal".into(),
            Param::FrameRotation(c) => format!("reference_frame.rotation_{}", XYZ[c]),
            Param::FrameTranslation(c) => format!("reference_frame.translation[{c}]"),
        }
    }

    /// The parameter in words, for reports.
    pub fn describe(self, arm: &Arm) -> String {
        match self {
            Param::ZeroOffset(j) => format!("joint {} zero offset Δθ", j + 1),
            Param::Tilt(j, c) => {
                let (e1, e2) = arm.joints[j].axis.perpendicular();
                let (sym, ax) = if c == 0 { ("δα", e1) } else { ("δβ", e2) };
                format!("joint {} tilt {sym} (about its {})", j + 1, ax.name())
            }
            Param::LinkError(j, c) => format!("link {} error along {}", j + 1, XYZ[c]),
            Param::ProbeError(c) => format!("probe error along {}", XYZ[c]),
            Param::Harmonic { joint, order, cos } => format!(
                "joint {} encoder harmonic order {order} ({})",
                joint + 1,
                if cos { "cos" } else { "sin" }
            ),
            Param::Gravity(j) => format!("joint {} gravity compliance", j + 1),
            Param::Thermal(Link::Joint(j)) => format!("link {} thermal expansion", j + 1),
            Param::Thermal(Link::Probe) => "probe thermal expansion".into(),
            Param::FrameRotation(c) => {
                format!("instrument frame rotation about the base {} axis", XYZ[c])
            }
            Param::FrameTranslation(c) => {
                format!(
                    "instrument frame translation along the base {} axis",
                    XYZ[c]
                )
            }
        }
    }

    /// Unit of the parameter's value.
    pub fn unit(self) -> &'static str {
        match self {
            Param::ZeroOffset(_)
            | Param::Tilt(..)
            | Param::Harmonic { .. }
            | Param::FrameRotation(_) => "rad",
            Param::LinkError(..) | Param::ProbeError(_) | Param::FrameTranslation(_) => "mm",
            Param::Gravity(_) => "rad/mm",
            Param::Thermal(_) => "1/°C",
        }
    }

    /// A size beyond which a value is not physically plausible for the term. Identifiability
    /// uses it to call a direction the data cannot pin down better than this "not identified".
    pub fn plausible(self) -> f64 {
        match self {
            Param::ZeroOffset(_) | Param::Tilt(..) => 0.05,
            Param::LinkError(..) | Param::ProbeError(_) => 20.0,
            Param::Harmonic { .. } => 0.01,
            Param::Gravity(_) => 1e-5,
            Param::Thermal(_) => 1e-3,
            Param::FrameRotation(_) => 10.0,
            Param::FrameTranslation(_) => 1e6,
        }
    }

    /// Which parameter to keep when the data cannot separate two: lower keeps first. The frame
    /// is kept (it must absorb whatever the data cannot tell from it), then the encoder's zero
    /// offsets, the probe, the links, the tilts, and the extended effects last.
    pub fn priority(self) -> u32 {
        match self {
            Param::FrameRotation(_) | Param::FrameTranslation(_) => 0,
            Param::ZeroOffset(_) => 1,
            Param::ProbeError(_) => 2,
            Param::LinkError(..) => 3,
            Param::Tilt(..) => 4,
            Param::Harmonic { .. } => 5,
            Param::Gravity(_) => 6,
            Param::Thermal(_) => 7,
        }
    }

    /// The parameter's current value in an arm (the whole key: nominal and error for `tilt`).
    /// Frame parameters are local increments and read 0.
    pub fn value(self, arm: &Arm) -> f64 {
        match self {
            Param::ZeroOffset(j) => arm.joints[j].zero_offset,
            Param::Tilt(j, c) => arm.joints[j].tilt[c],
            Param::LinkError(j, c) => arm.joints[j].link_error[c],
            Param::ProbeError(c) => arm.probe.error[c],
            Param::Harmonic { joint, order, cos } => arm.joints[joint]
                .harmonics
                .iter()
                .filter(|h| h.order == order)
                .map(|h| if cos { h.cos } else { h.sin })
                .sum(),
            Param::Gravity(j) => arm.joints[j].gravity,
            Param::Thermal(Link::Joint(j)) => arm.joints[j].thermal,
            Param::Thermal(Link::Probe) => arm.probe.thermal,
            Param::FrameRotation(_) | Param::FrameTranslation(_) => 0.0,
        }
    }

    /// Adds `dx` to the parameter's key in `arm` (frame parameters: nothing).
    pub fn add_to(self, arm: &mut Arm, dx: f64) {
        match self {
            Param::ZeroOffset(j) => arm.joints[j].zero_offset += dx,
            Param::Tilt(j, c) => arm.joints[j].tilt[c] += dx,
            Param::LinkError(j, c) => arm.joints[j].link_error[c] += dx,
            Param::ProbeError(c) => arm.probe.error[c] += dx,
            Param::Harmonic { joint, order, cos } => {
                let hs = &mut arm.joints[joint].harmonics;
                let h = match hs.iter().position(|h| h.order == order) {
                    Some(i) => &mut hs[i],
                    None => {
                        hs.push(Harmonic {
                            order,
                            sin: 0.0,
                            cos: 0.0,
                        });
                        hs.last_mut().expect("just pushed")
                    }
                };
                if cos {
                    h.cos += dx;
                } else {
                    h.sin += dx;
                }
            }
            Param::Gravity(j) => arm.joints[j].gravity += dx,
            Param::Thermal(Link::Joint(j)) => arm.joints[j].thermal += dx,
            Param::Thermal(Link::Probe) => arm.probe.thermal += dx,
            Param::FrameRotation(_) | Param::FrameTranslation(_) => {}
        }
    }
}

impl fmt::Display for Param {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.key())
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

/// An extended effect of the spec's vocabulary, as `--terms` names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Effect {
    /// `encoder_harmonic` of a joint (0-based) and order: two coefficients (sin, cos).
    Harmonic {
        /// Joint, 0-based.
        joint: usize,
        /// Order h ≥ 1.
        order: u32,
    },
    /// `gravity_compliance` of a joint (0-based).
    Gravity(usize),
    /// `thermal_expansion` of a link or the probe.
    Thermal(Link),
}

impl Effect {
    /// The unknowns the effect adds.
    pub fn params(self) -> Vec<Param> {
        match self {
            Effect::Harmonic { joint, order } => vec![
                Param::Harmonic {
                    joint,
                    order,
                    cos: false,
                },
                Param::Harmonic {
                    joint,
                    order,
                    cos: true,
                },
            ],
            Effect::Gravity(j) => vec![Param::Gravity(j)],
            Effect::Thermal(l) => vec![Param::Thermal(l)],
        }
    }

    /// The `--terms` spelling, e.g. `+encoder_harmonic:2:1` (joint 1-based).
    pub fn spec(self) -> String {
        match self {
            Effect::Harmonic { joint, order } => format!("+encoder_harmonic:{}:{order}", joint + 1),
            Effect::Gravity(j) => format!("+gravity_compliance:{}", j + 1),
            Effect::Thermal(Link::Joint(j)) => format!("+thermal_expansion:{}", j + 1),
            Effect::Thermal(Link::Probe) => "+thermal_expansion:probe".into(),
        }
    }
}

/// The highest harmonic order a calibration file holds (`harmonics[].order`).
pub const MAX_ORDER: u32 = quatarm_ref::calfile::MAX_HARMONIC_ORDER;

/// What a calibration fits: the geometric model (or not) and any extended effects.
///
/// Text form (`--terms`): comma-separated items. `geometric` is the 6N + 3 geometric
/// parameters and is implied unless `only` appears; `+encoder_harmonic:J:H`,
/// `+gravity_compliance:J` and `+thermal_expansion:J` / `+thermal_expansion:probe` add an
/// effect, J the 1-based joint or `*` for every joint (every link and the probe for thermal);
/// `only` fits just the listed effects (and the instrument frame) on top of the start arm.
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
    pub fn parse(text: &str, dof: usize) -> Result<Terms, String> {
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
            let joints = |s: Option<&&str>, probe_ok: bool| -> Result<Vec<Link>, String> {
                match s.copied() {
                    None => Err(format!(
                        "`{item}`: which joint? e.g. `{name}:2` or `{name}:*`"
                    )),
                    Some("*") => {
                        let mut v: Vec<Link> = (0..dof).map(Link::Joint).collect();
                        if probe_ok {
                            v.push(Link::Probe);
                        }
                        Ok(v)
                    }
                    Some("probe") if probe_ok => Ok(vec![Link::Probe]),
                    Some(j) => match j.parse::<usize>() {
                        Ok(k) if (1..=dof).contains(&k) => Ok(vec![Link::Joint(k - 1)]),
                        _ => Err(format!(
                            "`{item}`: `{j}` is not a joint of this arm (1..={dof}{})",
                            if probe_ok { ", probe or *" } else { " or *" }
                        )),
                    },
                }
            };
            let joint_of = |l: Link| match l {
                Link::Joint(j) => j,
                Link::Probe => 0,
            };
            match name {
                "encoder_harmonic" => {
                    let order = match args.get(1).map(|s| s.parse::<u32>()) {
                        Some(Ok(h)) if (1..=MAX_ORDER).contains(&h) => h,
                        Some(Ok(h)) => {
                            return Err(format!(
                                "`{item}`: order {h} is beyond {MAX_ORDER}, the highest a \
                                 calibration file holds"
                            ))
                        }
                        _ => {
                            return Err(format!(
                                "`{item}`: give the order, e.g. `+encoder_harmonic:2:1` (joint 2, order 1)"
                            ))
                        }
                    };
                    for l in joints(args.first(), false)? {
                        t.add(Effect::Harmonic {
                            joint: joint_of(l),
                            order,
                        });
                    }
                }
                "gravity_compliance" => {
                    for l in joints(args.first(), false)? {
                        t.add(Effect::Gravity(joint_of(l)));
                    }
                }
                "thermal_expansion" => {
                    for l in joints(args.first(), true)? {
                        t.add(Effect::Thermal(l));
                    }
                }
                _ => {
                    return Err(format!(
                        "unknown term `{item}`: geometric, only, +encoder_harmonic:J:H, \
                         +gravity_compliance:J, +thermal_expansion:J|probe"
                    ))
                }
            }
        }
        if only {
            if t.effects.is_empty() {
                return Err(
                    "`only` fits the listed effects alone, and none is listed: nothing to fit \
                     (e.g. `only,+gravity_compliance:*`)"
                        .into(),
                );
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

/// The 6N + 3 geometric parameters of `spec/arm-model.md`.
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
    v.extend((0..3).map(Param::ProbeError));
    v
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
            "geometric,+encoder_harmonic:2:1,+gravity_compliance:4,+thermal_expansion:probe",
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
        let all = Terms::parse("+thermal_expansion:*", 6).unwrap();
        assert_eq!(all.effects.len(), 7);
        assert!(Terms::parse("+gravity_compliance:7", 6).is_err());
        assert!(Terms::parse("+encoder_harmonic:2", 6).is_err());
        assert!(Terms::parse("+wobble:2", 6).is_err());
        let only = Terms::parse("only,+gravity_compliance:2", 7).unwrap();
        assert_eq!(only.params(7), vec![Param::Gravity(1)]);
    }

    #[test]
    fn apply_touches_error_keys_only() {
        let base = Arm::default6();
        let params = Terms::parse("+encoder_harmonic:3:2,+thermal_expansion:probe", 6)
            .unwrap()
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
