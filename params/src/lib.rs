//! The one vocabulary of an arm's calibration parameters: which unknown a fit adjusts, which
//! entry a budget's covariance lists, which column the table builder writes.
//!
//! # Why a crate of its own
//!
//! The parameter's identity was spelt five times (armcal's `Param`, the reference's
//! `ParamKey` with the conversions `key_of`/`param_of` between them, and the table builder's
//! own match), each with its own conventions (a harmonic by its order or by its place in the
//! joint's list, a probe's expansion as `Link::Probe` or `None`). One enum needs one home
//! that every user can depend on:
//!
//! - not the reference (`quatarm-ref`): it is f64 and `std`, and the firmware must never
//!   depend on it;
//! - not the firmware (`quatarm`): the hub does not know parameters, only the motions of the
//!   table's column records (`quatarm::table::parameters::Kind`: a turn, a tilt, a shift),
//!   into which several parameters fall (a link error, a probe error and a thermal expansion
//!   are all shifts). Putting the host's vocabulary there would make the reference and
//!   armcal depend on the firmware for a name, and grow the firmware's surface for nothing it
//!   runs;
//! - so a crate of its own, `no_std`, with no dependency: the reference (the calibration
//!   file's grammar), `quatarm-wire` (the table builder, which matches it exhaustively) and
//!   armcal (the fit indexes it) all use it, and the firmware may too without cost.
//!
//! # Conventions
//!
//! - **Indices are 0-based in the enum** (joints, vector components, probes in
//!   `Arm::probes` order, the instrument frame's axes). Text written for people and files
//!   says joints 1-based, as the spec does; components stay 0-based in text.
//! - **A periodic term is named by its order** h, not by its place in the joint's list: the
//!   order is what the term is, the place is an accident of the file (the budget's text
//!   names the place, `joint.K.harmonics.H`, and the reference translates).
//! - **Names**: each kind's spelling is the calibration file's key (`spec/calibration-file.md`):
//!   `zero_offset`, `tilt`, `link_error`, `error` (of a probe), `harmonics`, `wobble`,
//!   `gravity`, `thermal` ([`Param::file_key`]). The effects' names in `--terms` and reports
//!   (`encoder_harmonic`, `gravity_compliance`, `thermal_expansion`, `axis_wobble`) are the
//!   spec's names of the *effects* (`spec/arm-model.md`), a grouping of these parameters,
//!   not a second name of one.

#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

use core::fmt;

/// A link that can expand with temperature: one of the joints' links, or the probe.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Link {
    /// The link after joint i (0-based).
    Joint(usize),
    /// The probe vector.
    Probe,
}

/// One unknown of a calibration, of the arm or of the instrument frame a fit carries along.
///
/// Every `match` on it outside this crate is meant to be exhaustive (no `_` arm), so that a
/// new variant makes the compiler point at every place that must learn it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Param {
    /// Δθ_i, the zero offset of joint i (rad). File key `zero_offset`.
    ZeroOffset(usize),
    /// δα_i (component 0) or δβ_i (component 1) of joint i's `tilt` (rad).
    Tilt(usize, usize),
    /// Component c (the second field) of Δv_i, joint i's `link_error` (mm).
    LinkError(usize, usize),
    /// Component c (the second field) of Δv_p, the `error` of the arm's probe at index k (the
    /// first field; `Arm::probes` order, 0 the first probe) (mm).
    ProbeError(usize, usize),
    /// One coefficient of an encoder harmonic of the joint's `harmonics` (rad): of sin(hθ)
    /// or of cos(hθ).
    Harmonic {
        /// Joint (0-based).
        joint: usize,
        /// Order h ≥ 1.
        order: u32,
        /// `true` for the cos coefficient, `false` for sin.
        cos: bool,
    },
    /// One coefficient of an axis wobble of the joint's `wobble` (rad): `coef` 0 and 1 are
    /// δα's sin(hθ) and cos(hθ) coefficients, 2 and 3 δβ's.
    Wobble {
        /// Joint (0-based).
        joint: usize,
        /// Order h ≥ 1.
        order: u32,
        /// 0..4: α sin, α cos, β sin, β cos.
        coef: u8,
    },
    /// The gravity compliance g_i of joint i, its `gravity` (rad/mm).
    Gravity(usize),
    /// The thermal expansion κ, `thermal`, of a link or of the probe (1/°C).
    Thermal(Link),
    /// Instrument frame: a small rotation about the arm's base axis c, before the frame's
    /// current transform (rad). Not a key of the calibration file.
    FrameRotation(usize),
    /// Instrument frame: a small translation along the arm's base axis c, before the frame's
    /// current transform (mm). Not a key of the calibration file.
    FrameTranslation(usize),
}

/// The names of the axes of a vector's components.
pub const XYZ: [&str; 3] = ["x", "y", "z"];
/// The names of a wobble's two tilt components, in `coef / 2` order.
pub const WOBBLE_COMPONENT: [&str; 2] = ["alpha", "beta"];
/// The names of a periodic term's two coefficients, in `cos as usize` (or `coef % 2`) order.
pub const SIN_COS: [&str; 2] = ["sin", "cos"];

impl Param {
    /// The calibration file's key of the parameter's kind (`spec/calibration-file.md`): the
    /// one spelling of the kind, which the file's reader and every name written for it use.
    /// The instrument frame is not in the file: `reference_frame`, the name reports use.
    pub fn file_key(self) -> &'static str {
        match self {
            Param::ZeroOffset(_) => "zero_offset",
            Param::Tilt(..) => "tilt",
            Param::LinkError(..) => "link_error",
            Param::ProbeError(..) => "error",
            Param::Harmonic { .. } => "harmonics",
            Param::Wobble { .. } => "wobble",
            Param::Gravity(_) => "gravity",
            Param::Thermal(_) => "thermal",
            Param::FrameRotation(_) | Param::FrameTranslation(_) => "reference_frame",
        }
    }

    /// The joint the parameter belongs to (0-based); `None` for the probe's and the frame's.
    pub fn joint(self) -> Option<usize> {
        match self {
            Param::ZeroOffset(j)
            | Param::Tilt(j, _)
            | Param::LinkError(j, _)
            | Param::Gravity(j)
            | Param::Thermal(Link::Joint(j))
            | Param::Harmonic { joint: j, .. }
            | Param::Wobble { joint: j, .. } => Some(j),
            Param::ProbeError(..)
            | Param::Thermal(Link::Probe)
            | Param::FrameRotation(_)
            | Param::FrameTranslation(_) => None,
        }
    }

    /// Whether the parameter belongs to the instrument frame rather than the arm.
    pub fn is_frame(self) -> bool {
        matches!(self, Param::FrameRotation(_) | Param::FrameTranslation(_))
    }

    /// Whether the parameter is one of the geometric model's (`spec/arm-model.md`).
    pub fn is_geometric(self) -> bool {
        matches!(
            self,
            Param::ZeroOffset(_) | Param::Tilt(..) | Param::LinkError(..) | Param::ProbeError(..)
        )
    }
}

/// The key the parameter adjusts, as a calibration file's reader names it in its messages:
/// `joint[2].zero_offset`, `joint[3].tilt[0]`, `joint[2].harmonics(order=1).sin`,
/// `joint[3].wobble(order=2).beta[1]`, `probe.error[2]`, `probe[2].error[0]` (joints and
/// probes 1-based, array elements 0-based), `reference_frame.rotation_z`.
impl fmt::Display for Param {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let key = self.file_key();
        match *self {
            Param::ZeroOffset(j) | Param::Gravity(j) | Param::Thermal(Link::Joint(j)) => {
                write!(f, "joint[{}].{key}", j + 1)
            }
            Param::Tilt(j, c) | Param::LinkError(j, c) => write!(f, "joint[{}].{key}[{c}]", j + 1),
            Param::ProbeError(0, c) => write!(f, "probe.{key}[{c}]"),
            Param::ProbeError(k, c) => write!(f, "probe[{}].{key}[{c}]", k + 1),
            Param::Thermal(Link::Probe) => write!(f, "probe.{key}"),
            Param::Harmonic { joint, order, cos } => write!(
                f,
                "joint[{}].{key}(order={order}).{}",
                joint + 1,
                SIN_COS[usize::from(cos)]
            ),
            Param::Wobble { joint, order, coef } => write!(
                f,
                "joint[{}].{key}(order={order}).{}[{}]",
                joint + 1,
                WOBBLE_COMPONENT[usize::from(coef / 2) % 2],
                coef % 2
            ),
            Param::FrameRotation(c) => write!(f, "{key}.rotation_{}", XYZ[c % 3]),
            Param::FrameTranslation(c) => write!(f, "{key}.translation[{c}]"),
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::string::ToString;

    #[test]
    fn names_are_the_file_keys_joints_one_based() {
        let cases = [
            (Param::ZeroOffset(1), "joint[2].zero_offset"),
            (Param::Tilt(2, 0), "joint[3].tilt[0]"),
            (Param::LinkError(0, 2), "joint[1].link_error[2]"),
            (Param::ProbeError(0, 1), "probe.error[1]"),
            (Param::ProbeError(1, 0), "probe[2].error[0]"),
            (
                Param::Harmonic {
                    joint: 1,
                    order: 1,
                    cos: false,
                },
                "joint[2].harmonics(order=1).sin",
            ),
            (
                Param::Wobble {
                    joint: 2,
                    order: 2,
                    coef: 3,
                },
                "joint[3].wobble(order=2).beta[1]",
            ),
            (Param::Gravity(3), "joint[4].gravity"),
            (Param::Thermal(Link::Joint(0)), "joint[1].thermal"),
            (Param::Thermal(Link::Probe), "probe.thermal"),
            (Param::FrameRotation(2), "reference_frame.rotation_z"),
            (Param::FrameTranslation(1), "reference_frame.translation[1]"),
        ];
        for (p, name) in cases {
            assert_eq!(p.to_string(), name);
        }
    }

    #[test]
    fn joints_and_groups() {
        assert_eq!(Param::Gravity(3).joint(), Some(3));
        assert_eq!(Param::Thermal(Link::Probe).joint(), None);
        assert!(Param::FrameRotation(0).is_frame() && !Param::FrameRotation(0).is_geometric());
        assert!(Param::ProbeError(1, 2).is_geometric());
        assert!(!Param::Gravity(0).is_geometric() && !Param::Gravity(0).is_frame());
    }
}
