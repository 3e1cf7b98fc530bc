//! The diagnosis on real robots (`data/mukca/`, sessions held out whole): a cause it names
//! must hold on sessions it did not fit — by the authors' own score, leaving each session out,
//! and on separate recordings of the same arm — and where nothing holds it says none.

use armcal::diagnose::{self, FoldChoice};
use armcal::fit::options::Options;
use armcal::mukca;
use armcal::params::Terms;

fn by_session() -> diagnose::Options {
    diagnose::Options {
        folds: FoldChoice::ByGroup,
        ..diagnose::Options::default()
    }
}

#[test]
fn named_causes_hold_on_sessions_not_fitted() {
    let dir = mukca::default_dir();
    let mut named_units = Vec::new();
    for (name, _) in mukca::unit_names(&dir).unwrap() {
        let unit = mukca::load(&dir, &name).unwrap();
        let sessions = unit.groups().len();
        let d = diagnose::diagnose(&unit.arm, &unit.data, &by_session());
        if sessions < 2 {
            let e = d.expect_err("one session cannot be held out");
            assert!(e.to_string().contains("held-out"), "{name}: {e}");
            continue;
        }
        let d = d.unwrap_or_else(|e| panic!("{name}: {e}"));
        let causes: Vec<String> = d.causes.iter().map(|c| c.effect.spec()).collect();
        println!(
            "{name}: {sessions} sessions, named {causes:?}; held-out RMS {:.1} → {:.1} µm",
            d.baseline.holdout.summary.all.rms_um, d.extended.holdout.summary.all.rms_um
        );
        if sessions < 3 {
            // Two sessions cannot show that a gain holds (the spread of two gains says
            // nothing): nothing is named.
            assert!(
                causes.is_empty(),
                "{name}: named {causes:?} from two sessions"
            );
            continue;
        }
        if causes.is_empty() {
            assert_eq!(d.gain_percent(), 0.0);
            continue;
        }
        // The authors' score, each session left out of the fit in turn: the extended model
        // must do better than the geometric one on average.
        let loso = |terms: Terms| {
            mukca::loso(
                &unit,
                &Options {
                    terms,
                    ..Options::default()
                },
            )
        };
        let geo = loso(Terms::geometric());
        let ext = loso(Terms::with(&d.extended.effects));
        let v = geo.versus(&ext);
        println!(
            "  MUKCa score leaving each session out: {:.3} → {:.3} mm, better on {}/{} sessions (p = {:.1e})",
            geo.mean_after, ext.mean_after, v.better, v.sessions, v.p
        );
        assert!(
            ext.mean_after < geo.mean_after,
            "{name}: {causes:?} do not hold by the authors' score ({:.3} → {:.3} mm)",
            geo.mean_after,
            ext.mean_after
        );
        named_units.push((name, d.extended.effects.clone()));
    }
    // panda_3 names causes; panda_3_bis and panda_right are separate recordings of the same
    // arm (data/mukca/README.md says on what evidence). With panda_3's probe kept, the model
    // extended on panda_3 predicts every one of their sessions better than the geometric
    // model fitted on the same data. That is what this asserts, and no more: with the probe
    // refitted per recording the gain holds on 3 of 4 sessions and its interval spans 0
    // (docs/results/claims.md §7, example `same_arm_probe_mukca`), so the README does not
    // claim that the causes carry over to the other recordings.
    let (_, effects) = named_units
        .iter()
        .find(|(n, _)| n == "panda_3")
        .expect("panda_3 names a cause");
    let p3 = mukca::load(&dir, "panda_3").unwrap();
    let fit = |terms: Terms| {
        armcal::fit::calib::calibrate(
            &p3.arm,
            &p3.data,
            &Options {
                terms,
                ..Options::default()
            },
        )
        .unwrap()
        .arm
    };
    let geo = fit(Terms::geometric());
    let ext = fit(Terms::with(effects));
    for other in ["panda_3_bis", "panda_right"] {
        let u = mukca::load(&dir, other).unwrap();
        for g in u.groups() {
            let s = u.sessions_data(&[g]);
            let (a, b) = (
                mukca::session_score(&geo, &s),
                mukca::session_score(&ext, &s),
            );
            println!("  {other} session {}: {a:.3} → {b:.3} mm", u.sessions[&g]);
            assert!(b < a, "{other} {}: {a:.3} → {b:.3}", u.sessions[&g]);
        }
    }
}
