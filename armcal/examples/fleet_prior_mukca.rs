//! The MUKCa protocol (panda_2, fit on `front_center` only, score the other sessions but
//! `high`) with a fleet prior from the other Panda units, against the same fit without it.
//!
//! Each fleet unit is calibrated on all its own sessions with the default options (least
//! squares); panda_2's arm (panda_1,
//! panda_1_with_sensor, panda_left are recordings of it, `data/mukca/README.md`) is never in
//! the fleet, and none of panda_2's sessions but `front_center` is fitted. The fleet is tried
//! with every other Panda unit, and with one recording per physical arm (panda_3_bis and
//! panda_right are panda_3's arm, so they count it three times).
//!
//! Also, as a check that does not look at panda_2: each other physical arm fitted one session
//! at a time with the fleet of the remaining arms, scored on its other sessions.
//!
//!     cargo run --release -p armcal --example fleet_prior_mukca

use armcal::fit::fleet_prior::{self, FleetPrior};
use armcal::fit::options::Options;
use armcal::fit::priors::{Prior, Ridge};
use armcal::mukca::{self, Unit};
use quatarm_ref::arm::Arm;

/// The MUKCa options with the fleet's Gaussians, the rest left to `ridge` (or least squares).
fn with_fleet(fleet: Option<&FleetPrior>, ridge: Option<Ridge>) -> Options {
    let mut o = mukca::options(ridge);
    if let Some(f) = fleet {
        o.prior = Some(Prior {
            unknowns: f.gaussians(),
            ..Prior::default()
        });
    }
    o
}

/// The same without the prior-data conflict test (every fleet Gaussian kept).
fn without_conflict_test(mut o: Options) -> Options {
    if let Some(p) = &mut o.prior {
        p.conflict_sigmas = Some(f64::INFINITY);
    }
    o
}

/// The protocol's fit itself (to say which priors it dropped).
fn trial_fit(p2: &Unit, opts: &Options) -> (mukca::Trial, armcal::fit::finish::Fit) {
    let train = p2.group("front_center").expect("front_center");
    let high = p2.group("high").expect("high");
    let test: Vec<i64> = p2
        .groups()
        .into_iter()
        .filter(|g| *g != train && *g != high)
        .collect();
    mukca::trial(p2, &[train], &test, opts).expect("trial")
}

/// A unit calibrated on all its sessions with the default options (least squares; all
/// sessions together are not a degenerate pose set).
fn calibrated(unit: &Unit) -> Arm {
    armcal::fit::calib::calibrate(&unit.arm, &unit.data, &Options::default())
        .unwrap_or_else(|e| panic!("{}: {e}", unit.name))
        .arm
}

fn fleet_of(nominal: &Arm, units: &[(String, Arm)], names: &[&str]) -> FleetPrior {
    let chosen: Vec<(String, Arm)> = units
        .iter()
        .filter(|(n, _)| names.contains(&n.as_str()))
        .cloned()
        .collect();
    fleet_prior::from_arms(nominal, &chosen).expect("fleet prior")
}

/// One session at a time: fit each session, score the unit's other sessions; the mean.
fn one_session(unit: &Unit, opts: &Options) -> f64 {
    let groups = unit.groups();
    let mut sum = 0.0;
    for &g in &groups {
        let test: Vec<i64> = groups.iter().copied().filter(|x| *x != g).collect();
        let (t, _) = mukca::trial(unit, &[g], &test, opts)
            .unwrap_or_else(|e| panic!("{} session {g}: {e}", unit.name));
        sum += t.test_after;
    }
    sum / groups.len() as f64
}

fn main() {
    let dir = mukca::default_dir();
    let names = [
        "panda_3",
        "panda_3_bis",
        "panda_right",
        "panda_4",
        "panda_6",
        "panda_7",
    ];
    let units: Vec<Unit> = names
        .iter()
        .map(|n| mukca::load(&dir, n).expect("unit"))
        .collect();
    let cals: Vec<(String, Arm)> = units
        .iter()
        .map(|u| (u.name.clone(), calibrated(u)))
        .collect();
    let p2 = mukca::load(&dir, "panda_2").expect("panda_2");

    let variants: [(&str, Vec<&str>); 2] = [
        ("every other Panda unit (6)", names.to_vec()),
        (
            "one per physical arm: panda_3, panda_4, panda_6, panda_7",
            vec!["panda_3", "panda_4", "panda_6", "panda_7"],
        ),
    ];
    println!(
        "panda_2, fit front_center, score 7 test sessions (mean distance, mm); published 0.347"
    );
    for (label, rule) in [
        ("least squares", None),
        ("ridge λ = 1e-4", Some(Ridge::MUKCA)),
    ] {
        let t = mukca::authors_protocol(&dir, &with_fleet(None, rule)).expect("protocol");
        println!(
            "  without fleet prior, {label:<16} train {:.4}  test {:.4}",
            t.train_after, t.test_after
        );
    }
    for (vlabel, members) in &variants {
        let fleet = fleet_of(&p2.arm, &cals, members);
        let used = fleet.gaussians().len();
        let few = fleet
            .fallbacks()
            .filter(|e| e.fallback == Some(fleet_prior::Fallback::TooFewUnits))
            .count();
        let flat = fleet.fallbacks().count() - few;
        println!(
            "  fleet: {vlabel}: {used} unknowns with a fleet Gaussian, {few} left to the rule \
             (fewer than 3 units), {flat} (no spread)"
        );
        let back: Vec<String> = fleet
            .fallbacks()
            .map(|e| format!("{} ({} units)", e.key, e.units))
            .collect();
        println!("    left to the rule: {}", back.join(", "));
        for (label, rule) in [
            ("rest least squares", None),
            ("rest ridge 1e-4", Some(Ridge::MUKCA)),
        ] {
            let t =
                mukca::authors_protocol(&dir, &with_fleet(Some(&fleet), rule)).expect("protocol");
            let per: Vec<String> = t
                .per_session
                .iter()
                .map(|(n, _, a)| format!("{n} {a:.3}"))
                .collect();
            println!(
                "    with fleet prior, {label:<20} train {:.4}  test {:.4}   ({})",
                t.train_after,
                t.test_after,
                per.join(", ")
            );
            let (raw, _) = trial_fit(&p2, &without_conflict_test(with_fleet(Some(&fleet), rule)));
            println!(
                "      the same, no prior dropped (conflict test off): train {:.4}  test {:.4}",
                raw.train_after, raw.test_after
            );
            let (_, fit) = trial_fit(&p2, &with_fleet(Some(&fleet), rule));
            for c in &fit.prior_conflicts {
                println!(
                    "      prior dropped, contradicted by front_center: {} data {:+.4e} ± {:.1e}, \
                     fleet {:+.4e} ± {:.1e} ({:.1} σ)",
                    fit.params[c.index],
                    c.data,
                    c.data_sd,
                    c.prior.mean,
                    c.prior.sd,
                    c.sigmas()
                );
            }
        }
    }

    // The check on the other arms: each fitted one session at a time, with the fleet of the
    // remaining physical arms (one recording each), against least squares and the ridge.
    println!("\nother arms, one session at a time, fleet of the remaining arms (mm)");
    println!("  unit      least squares  ridge 1e-4  fleet+LS  fleet+ridge  fleet+LS, test off");
    let arms = ["panda_3", "panda_4", "panda_6", "panda_7"];
    let mut ratio = [0.0; 4];
    for name in arms {
        let unit = units.iter().find(|u| u.name == name).expect("unit");
        let rest: Vec<&str> = arms.iter().copied().filter(|n| *n != name).collect();
        let fleet = fleet_of(&unit.arm, &cals, &rest);
        let ls = one_session(unit, &with_fleet(None, None));
        let ridge = one_session(unit, &with_fleet(None, Some(Ridge::MUKCA)));
        let fl = one_session(unit, &with_fleet(Some(&fleet), None));
        let fr = one_session(unit, &with_fleet(Some(&fleet), Some(Ridge::MUKCA)));
        let raw = one_session(unit, &without_conflict_test(with_fleet(Some(&fleet), None)));
        for (r, v) in ratio.iter_mut().zip([ridge, fl, fr, raw]) {
            *r += v / ls / arms.len() as f64;
        }
        println!("  {name:<9} {ls:>13.4} {ridge:>11.4} {fl:>9.4} {fr:>12.4} {raw:>19.4}");
    }
    println!(
        "  mean ratio to least squares: ridge {:.4}, fleet+LS {:.4}, fleet+ridge {:.4}, \
         fleet+LS without the conflict test {:.4}",
        ratio[0], ratio[1], ratio[2], ratio[3]
    );
}
