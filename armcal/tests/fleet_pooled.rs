//! Partial pooling as a candidate of the fleet diagnosis ([`armcal::diagnose::fleet_pooled`]):
//! a shoulder compliance spread ±50 % over eight arms, too small for each arm's own estimate,
//! is named for every arm by the pooled model, with a held-out gain per arm; a fleet with
//! nothing hidden gets nothing named.

mod common;

use armcal::data::{Dataset, Kind};
use armcal::diagnose::candidates;
use armcal::diagnose::fleet::{self, UnitData};
use armcal::diagnose::fleet_pooled::{pool_arms, PooledFleet};
use armcal::params::Effect;
use armcal::sim;
use quatarm_ref::arm::Arm;

/// A `default-6` arm with its own geometric errors and a shoulder compliance `g` (rad/mm):
/// 120 tracker points in 4 sessions (the fleet of `examples/pooling_fleet.rs`).
fn arm_data(seed: u64, g: f64) -> Dataset {
    let mut rng = armcal::rng::rng(seed);
    let mut truth = sim::perturb(&Arm::default6(), 3e-4, 0.3, &mut rng);
    truth.joints[1].gravity = g;
    let d = sim::simulate(&truth, &sim::Options::new(Kind::Point, 120), &mut rng)
        .unwrap()
        .data;
    common::in_sessions(d, 4, "(simulated arm)")
}

/// The pooled stage over eight arms of compliances `gs`, each arm its own recording.
fn pooled(gs: &[f64], seed: u64) -> PooledFleet {
    let units: Vec<UnitData> = gs
        .iter()
        .enumerate()
        .map(|(k, &g)| UnitData {
            name: format!("arm_{k}"),
            file: format!("arm_{k}.csv"),
            data: arm_data(seed + k as u64, g),
        })
        .collect();
    let arms: Vec<(String, Vec<usize>)> = units
        .iter()
        .enumerate()
        .map(|(k, u)| (u.name.clone(), vec![k]))
        .collect();
    let start = Arm::default6();
    let testable: Vec<Vec<Effect>> = units
        .iter()
        .map(|u| {
            candidates::candidates_up_to(&start, &u.data, 1)
                .testable
                .iter()
                .map(|c| c.effect)
                .collect()
        })
        .collect();
    pool_arms(&start, &units, &arms, &testable, &fleet::Options::default()).unwrap()
}

#[test]
fn a_spread_effect_too_small_for_each_arm_is_named_for_every_arm_pooled() {
    // 1.25…3.75e-9 rad/mm: each arm's own estimate is within ~2 of its jackknife errors.
    let gs: Vec<f64> = (0..8).map(|k| 2.5e-9 * (0.5 + k as f64 / 7.0)).collect();
    let p = pooled(&gs, 500);
    let g = p
        .effects
        .iter()
        .find(|e| e.effect == Effect::Gravity(1))
        .unwrap_or_else(|| panic!("shoulder compliance not pooled: {p:#?}"));
    assert!(g.named, "{:?}", g.design);
    assert_eq!(g.design.arms, 8);
    let [lo, hi] = g.design.mean_interval;
    assert!(lo > 0.0 && lo < 2.5e-9 && 2.5e-9 < hi, "{:?}", g.design);
    assert!(
        g.arms.iter().filter(|a| a.value.named_alone).count() < 8,
        "every arm alone already names it: the fleet is too easy to show pooling's power"
    );
    // Every arm named, each with its nested held-out gain. At 1.25…3.75e-9 rad/mm the effect
    // moves the ball by about a micrometre against 5 µm of noise: the pooled value helps the
    // fleet's held-out sessions as a whole, not every arm's four.
    let (mut before, mut after, mut better) = (0.0, 0.0, 0);
    for a in &g.arms {
        assert!(a.value.named_pooled, "{}: {:?}", a.arm, a.value);
        let h = a.holdout.as_ref().expect("held-out gain of a named arm");
        assert_eq!(h.sessions, 4);
        before += h.rms_um[0].powi(2);
        after += h.rms_um[1].powi(2);
        better += h.sessions_better;
    }
    assert!(after < before, "{before} → {after}");
    assert!(better > 16, "better on {better} of 32 sessions");
    // Nothing else is named: the other joints' compliances are not in the data.
    for e in p.effects.iter().filter(|e| e.effect != Effect::Gravity(1)) {
        assert!(!e.named, "{} named: {:?}", e.term, e.design);
    }
    let mut text = String::new();
    p.write_text(&mut text);
    assert!(
        text.contains("+gravity_compliance:2") && text.contains("named for the design"),
        "{text}"
    );
}

#[test]
fn a_fleet_with_nothing_hidden_gets_nothing_named() {
    for seed in [10_000, 10_100] {
        let p = pooled(&[0.0; 8], seed);
        assert!(!p.effects.is_empty());
        for e in &p.effects {
            assert!(!e.named, "seed {seed}: {} named: {:?}", e.term, e.design);
            assert!(e
                .arms
                .iter()
                .all(|a| !a.value.named_pooled && a.holdout.is_none()));
        }
    }
}
