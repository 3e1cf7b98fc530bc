//! Complete test sets: every row an acceptance test of `spec/acceptance-tests.md` needs, made
//! by the virtual arm in one file, as a metrologist would record them on the day.
//!
//! `iso10360-12` follows ISO 10360-12 and ASME B89.4.22 where a simulation can:
//! - P_Size and P_Form: two positions of the test sphere, 25 points each (groups 1–2);
//! - L_Dia: one position, five articulations of five points (group 3);
//! - E_Uni: ball-bar lengths of 20 %, 40 % and 60 % of the arm's reach, each in five positions
//!   and directions through the volume (groups 11–25, five rows a ball);
//! - SPAT: three cones of ten poses each (groups 31–33).
//!
//! Positions are drawn where the arm reaches (a random pose's ball, as every simulated group),
//! not at the standards' named locations (near, mid and far reach, several heights): the
//! arm's own random poses spread them through its volume. Every row carries the virtual arm's
//! noise (`Options::noise_mm`, the probing) and quantisation.

use super::{reach, simulate, Options, SimError, SimRng, Simulated};
use crate::data::{Dataset, Kind};
use quatarm_ref::arm::Arm;

/// The test set of ISO 10360-12 (with B89.4.22's SPAT), from `base`'s noise and temperatures.
pub fn iso_10360_12(truth: &Arm, base: &Options, rng: &mut SimRng) -> Result<Simulated, SimError> {
    let mut rows = Vec::new();
    let mut add = |opts: Options, first_group: i64, rng: &mut SimRng| -> Result<(), SimError> {
        let s = simulate(truth, &opts, rng)?;
        rows.extend(s.data.rows.into_iter().map(|mut r| {
            r.group += first_group - 1;
            r
        }));
        Ok(())
    };
    let with = |kind: Kind, count: usize| Options {
        kind,
        count,
        group_size: match kind {
            Kind::Sphere => 25,
            Kind::Length => 10,
            _ => 10,
        },
        ..base.clone()
    };
    add(with(Kind::Sphere, 50), 1, rng)?;
    add(
        Options {
            articulations: Some(5),
            ..with(Kind::Sphere, 25)
        },
        3,
        rng,
    )?;
    let r = reach(truth);
    for (i, share) in [0.2, 0.4, 0.6].into_iter().enumerate() {
        add(
            Options {
                bar_mm: Some(share * r),
                ..with(Kind::Length, 50)
            },
            11 + 5 * i as i64,
            rng,
        )?;
    }
    add(with(Kind::Spat, 30), 31, rng)?;
    let data = Dataset::from_rows(rows, truth.dof(), base.temp.is_some(), "(simulated)")?;
    Ok(Simulated {
        data,
        frame: quatarm_ref::arm::Frame {
            rotation: [1.0, 0.0, 0.0, 0.0],
            translation: [0.0; 3],
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::rng;

    #[test]
    fn has_every_test_of_the_standard() {
        let arm = Arm::default6();
        let s = iso_10360_12(&arm, &Options::new(Kind::Point, 1), &mut rng(3)).unwrap();
        let l = s.data.layout();
        assert_eq!(l.sphere.len(), 3);
        assert!(l.sphere.iter().all(|g| g.rows.len() == 25));
        assert_eq!(l.length.len(), 15);
        assert_eq!(l.spat.len(), 3);
        assert!(l.points.is_empty());
        let bars: std::collections::BTreeSet<i64> = l
            .length
            .iter()
            .map(|g| g.length_mm.round() as i64)
            .collect();
        assert_eq!(bars.len(), 3, "three bar lengths");
    }
}
