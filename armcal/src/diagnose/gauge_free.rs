//! Comparing calibrations by what they predict, not by their parameter values.
//!
//! A calibration's parameter values depend on its gauge: which unknowns the data could not
//! separate, which of them were held, the instrument frame, the probe. Two calibrations of one
//! arm can differ by a millimetre in a link and a probe error and predict the same ball
//! positions; "the extended model is closer to the other recording's" can be a probe offset of
//! 0.1–0.5 mm (issue 30). So calibrations are compared here by their **predicted ball
//! positions over a reference pose set** (a held-out session's joint readings), with
//! - the **frame out**: the best rigid alignment of one prediction onto the other
//!   ([`crate::fit::residuals::compare_aligned`]);
//! - the **probe out**: both evaluated with one probe (the first one's), so that a probe
//!   offset between recordings is not counted as a difference of the arms;
//!
//! and a calibration scored on **another recording** of the same arm gets its probe refitted
//! on that recording first ([`refit_probe`]: every other unknown held at the calibration's
//! value), since a recording's tool is its own.

use crate::data::Dataset;
use crate::fit::calib::{self};
use crate::fit::error::CalibError;
use crate::fit::finish::Fit;
use crate::fit::residuals::{compare_aligned, Spread};
use crate::params::Param;
use quatarm_ref::arm::Arm;

/// The reference poses of `data`: each row's joint readings and temperature.
pub fn poses(data: &Dataset) -> Vec<(Vec<f64>, f64)> {
    data.rows
        .iter()
        .map(|r| (r.theta.clone(), r.temp_c))
        .collect()
}

/// How far `b`'s predicted ball is from `a`'s over `poses`, frame and probe out: `b` is given
/// `a`'s probe (vector and error), then aligned rigidly onto `a`.
pub fn tip_difference(a: &Arm, b: &Arm, poses: &[(Vec<f64>, f64)]) -> Spread {
    let mut b = b.clone();
    b.probe = a.probe.clone();
    compare_aligned(&b, a, poses)
}

/// `arm` with only its tool refitted to `data` (and the instrument frame, when `data` have
/// `point` rows): how a calibration of one recording is scored on another recording of the
/// same arm, whose tool is its own. The tool is the probe's offset and the last joint's zero
/// offset and tilt: an offset across the last axis is indistinguishable from that joint's zero
/// offset, which identifiability keeps in its place, so holding the joint would leave part of
/// a new tool unfitted.
pub fn refit_probe(
    arm: &Arm,
    data: &Dataset,
    opts: &crate::fit::options::Options,
) -> Result<Fit, CalibError> {
    let o = crate::fit::options::Options {
        terms: crate::params::Terms::geometric(),
        ..opts.clone()
    };
    let last = arm.dof().saturating_sub(1);
    let mut hold: Vec<Param> = crate::fit::structure::unknowns(arm, &o.terms, data)
        .into_iter()
        .filter(|p| match p {
            Param::ProbeError(..) | Param::FrameRotation(_) | Param::FrameTranslation(_) => false,
            Param::ZeroOffset(j) | Param::Tilt(j, _) => *j != last,
            _ => true,
        })
        .collect();
    hold.extend(o.hold.iter().copied());
    calib::calibrate(arm, data, &crate::fit::options::Options { hold, ..o })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::Kind;

    fn poses_of(arm: &Arm) -> Vec<(Vec<f64>, f64)> {
        let mut rng = crate::rng::rng(3);
        let d = crate::sim::simulate(arm, &crate::sim::Options::new(Kind::Point, 40), &mut rng)
            .unwrap()
            .data;
        poses(&d)
    }

    #[test]
    fn a_probe_offset_is_no_difference_and_a_link_error_is() {
        let a = Arm::default6();
        let p = poses_of(&a);
        let mut b = a.clone();
        b.probe.error = [0.3, -0.2, 0.4];
        assert!(tip_difference(&a, &b, &p).rms_um < 1e-6);
        // Compared by parameter values the two differ by half a millimetre; by what they
        // predict, not at all. A link error is a real difference.
        b.joints[2].link_error = [0.0, 0.0, 0.2];
        let s = tip_difference(&a, &b, &p);
        assert!(s.rms_um > 10.0, "{s:?}");
    }

    #[test]
    fn a_refit_of_the_probe_takes_another_recordings_tool_and_nothing_else() {
        // The same arm measured with a tool 0.4 mm off: its calibration (the truth, here)
        // scored on that recording with its probe refitted fits it to the noise, and keeps
        // every other unknown.
        let truth = Arm::default6();
        let mut other_tool = truth.clone();
        other_tool.probe.error = [0.4, -0.3, 0.2];
        let mut rng = crate::rng::rng(5);
        let d = crate::sim::simulate(
            &other_tool,
            &crate::sim::Options::new(Kind::Point, 60),
            &mut rng,
        )
        .unwrap()
        .data;
        let opts = crate::fit::options::Options {
            design_check: false,
            allow_degenerate: true,
            ..crate::fit::options::Options::default()
        };
        let fit = refit_probe(&truth, &d, &opts).unwrap();
        // The arm before its last joint is kept; the new tool is taken whole (the part of it
        // across the last axis by that joint's zero offset: the same prediction).
        assert_eq!(fit.arm.joints[..5], truth.joints[..5]);
        let [x, _, z] = fit.arm.probe.error;
        assert!(
            (x - 0.4).abs() < 0.01 && (z - 0.2).abs() < 0.01,
            "{:?}",
            fit.arm.probe
        );
        assert!(fit.rms_after_mm < 0.02, "{}", fit.rms_after_mm);
    }
}
