//! What each kind of data can fix, and what it cannot, said in words before any fit.
//!
//! The structural analysis of `ident` finds exact dependencies of the Jacobian at the arm's
//! skeleton. Some blind spots of the data's kinds are not such dependencies and it cannot find
//! them:
//!
//! - **Scale** (`spat` alone). Every row of a spat group probes one unknown point, and
//!   scaling the whole arm (each link and the probe by 1 + ε) scales every residual by 1 + ε:
//!   the cost falls towards zero as the arm shrinks, and at ε = −1 (every length gone) it is
//!   zero. At the skeleton the scale column is the model's own misfit, small but not a
//!   dependency, so the fit walks down it and collapses the arm (links −600 mm, residuals
//!   0.00 µm). Only a known length fixes the scale: a bar (`length`), a test sphere's
//!   diameter (`sphere`) or an instrument (`point`). Without one the calibration is refused whenever the unknowns can express the
//!   scale (every link and probe error fitted); a fit of effects alone (`--terms only,…`) on a
//!   given geometry is not affected.
//! - **Placement** (`spat`, `length`, `sphere`). Residuals are centred on each group's point, which is
//!   unknown: moving or turning the whole arm changes none of them. Such unknowns are held
//!   (the frame's rotations stand for the turn; a translation has no effect at all).
//! - **Instrument frame** (`point`). The instrument's frame is unknown and fitted alongside;
//!   what moves the arm as a whole (joint 1's zero offset, the base's offsets) is carried by
//!   the frame and held.

use crate::data::Layout;
use crate::params::Param;
use quatarm_ref::arm::Arm;

/// A blind spot that no fit can get around: the calibration is refused.
#[derive(Clone, Debug, PartialEq)]
pub struct Refusal {
    /// What the data cannot fix.
    pub what: String,
    /// Why, and what to record instead.
    pub why: String,
}

/// Whether the unknowns `fitted` (indices into `params`) can express a scaling of the arm:
/// every link and probe component that is not zero has its error among them.
pub(crate) fn can_scale(arm: &Arm, params: &[Param], fitted: &[usize]) -> bool {
    let mut need: Vec<Param> = Vec::new();
    for (j, joint) in arm.joints.iter().enumerate() {
        for (c, v) in joint.actual_link().iter().enumerate() {
            if *v != 0.0 {
                need.push(Param::LinkError(j, c));
            }
        }
    }
    // The first probe always; another only where the data used it (it has unknowns then: a
    // probe no row was taken with takes no part in the data's scale).
    let used = |k: usize| {
        k == 0
            || params
                .iter()
                .any(|p| matches!(p, Param::ProbeError(q, _) if *q == k))
    };
    for (k, probe) in arm.probes().enumerate().filter(|(k, _)| used(*k)) {
        for (c, v) in probe.actual().iter().enumerate() {
            if *v != 0.0 {
                need.push(Param::ProbeError(k, c));
            }
        }
    }
    need.iter().all(|q| fitted.iter().any(|&i| params[i] == *q))
}

/// The refusal for data whose kinds cannot fix what the unknowns `fitted` would change.
pub fn check(layout: &Layout, arm: &Arm, params: &[Param], fitted: &[usize]) -> Option<Refusal> {
    let has_length = !layout.length.is_empty() || !layout.sphere.is_empty();
    let has_points = !layout.points.is_empty();
    if !has_length && !has_points && can_scale(arm, params, fitted) {
        return Some(Refusal {
            what: "the arm's scale".into(),
            why: "spat rows alone probe unknown points, and an arm scaled by any factor (every link and the probe together) fits \
                  them as well, down to an arm shrunk to nothing with no residual at all. A \
                  known length is needed: add ball-bar rows (`length`), test-sphere rows \
                  (`sphere`) or instrument rows (`point`), or fit extended effects alone on the given geometry \
                  (`--terms only,+…`)"
                .into(),
        });
    }
    None
}

/// What the data's kinds leave to the start arm or to the instrument frame, in words, for the
/// report (empty when nothing is worth saying).
pub fn notes(layout: &Layout) -> Vec<String> {
    let has_length = !layout.length.is_empty();
    let has_sphere = !layout.sphere.is_empty();
    let has_spat = !layout.spat.is_empty();
    let has_points = !layout.points.is_empty();
    let mut v = Vec::new();
    if (has_spat || has_length || has_sphere) && !has_points {
        v.push(
            "spat, length and sphere data do not fix where the arm stands: moving or turning \
             the whole arm leaves every residual unchanged, so its placement is that of the \
             start arm"
                .into(),
        );
    }
    if has_points {
        v.push(
            "point data are in the instrument's own frame, fitted alongside: what moves the \
             arm as a whole is carried by that frame"
                .into(),
        );
    }
    match (has_length, has_sphere, has_points) {
        (true, false, false) => v.push("the scale comes from the bar lengths alone".into()),
        (false, true, false) => v.push(
            "the scale comes from the test spheres' diameters alone, with the stylus ball's \
             diameter as the calibration file gives it (not fitted)"
                .into(),
        ),
        (true, true, false) => v.push(
            "the scale comes from the bar lengths and the test spheres' diameters (with the \
             stylus ball's diameter as the calibration file gives it, not fitted)"
                .into(),
        ),
        _ => {}
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::{LengthGroup, SpatGroup};
    use crate::params::Terms;

    fn spat_only() -> Layout {
        Layout {
            points: vec![],
            spat: vec![SpatGroup {
                group: 1,
                rows: vec![0, 1],
            }],
            length: vec![],
            sphere: vec![],
        }
    }

    #[test]
    fn spat_alone_cannot_fix_the_scale() {
        let arm = Arm::default6();
        let params = Terms::geometric().params(6);
        let all: Vec<usize> = (0..params.len()).collect();
        let r = check(&spat_only(), &arm, &params, &all).expect("refused");
        assert_eq!(r.what, "the arm's scale");
        // A bar fixes it.
        let mut with_bar = spat_only();
        with_bar.length.push(LengthGroup {
            group: 2,
            a: vec![2],
            b: vec![3],
            length_mm: 500.0,
        });
        assert!(check(&with_bar, &arm, &params, &all).is_none());
        // Effects alone on a given geometry cannot scale the arm.
        let gravity: Vec<Param> = (0..6).map(Param::Gravity).collect();
        let g: Vec<usize> = (0..gravity.len()).collect();
        assert!(check(&spat_only(), &arm, &gravity, &g).is_none());
        // Holding one link error that is part of the scale is enough too.
        let held = params
            .iter()
            .position(|p| *p == Param::LinkError(1, 2))
            .unwrap();
        let some: Vec<usize> = all.iter().copied().filter(|&i| i != held).collect();
        assert!(check(&spat_only(), &arm, &params, &some).is_none());
    }

    #[test]
    fn a_test_sphere_fixes_the_scale() {
        let arm = Arm::default6();
        let params = Terms::geometric().params(6);
        let all: Vec<usize> = (0..params.len()).collect();
        let mut with_sphere = spat_only();
        with_sphere.sphere.push(crate::data::SphereGroup {
            group: 3,
            rows: vec![4, 5, 6, 7],
            diameter_mm: 25.0,
        });
        assert!(check(&with_sphere, &arm, &params, &all).is_none());
        let notes = notes(&with_sphere);
        assert!(notes
            .iter()
            .any(|n| n.contains("test spheres' diameters alone")));
    }
}
