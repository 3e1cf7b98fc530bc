//! The parts of the diagnosis: which candidates the data can test, and the linearised
//! held-out validation the selection ranks them by, against real refits.

use armcal::data::Kind;
use armcal::diagnose::candidates::{candidates, vocabulary};
use armcal::diagnose::linear::{Linearisation, Set};
use armcal::diagnose::scenario;
use armcal::diagnose::select::unit_errors;
use armcal::fit::calib::calibrate;
use armcal::fit::holdout;
use armcal::fit::options::Options;
use armcal::params::{Effect, Link, Terms};
use armcal::sim;
use quatarm_ref::arm::Arm;

#[test]
fn candidates_of_default6_with_and_without_temperatures() {
    let s = scenario::with_families(1, &[]);
    let data = scenario::points(&s, 200);
    let c = candidates(&Arm::default6(), &data);
    assert!(c.thermal);
    // Harmonics of orders 1–64 in the vocabulary, 1–8 tried (200 readings per joint resolve
    // more), 6 gravity, 7 thermal, 6 × 3 axis wobbles, of which: gravity 1 has no lever
    // (vertical axis), links 3, 5 and the probe are collinear with 2, 4 and 6.
    assert_eq!(vocabulary(6, true).len(), 6 * 64 + 6 + 7 + 6 * 3);
    let untestable: Vec<Effect> = c.untestable.iter().map(|u| u.effect).collect();
    assert_eq!(
        untestable,
        vec![
            Effect::Gravity(0),
            Effect::Thermal(Link::Joint(2)),
            Effect::Thermal(Link::Joint(4)),
            Effect::Thermal(Link::Probe)
        ]
    );
    assert_eq!(c.testable.len(), 6 * 8 + 5 + 4 + 6 * 3);
    // Axis wobbles: the co-rotating half of order 1 is the next link's frame turned, so two
    // of its four unknowns are geometry and held; joint 6's order 2 loses two as well (the
    // ball 200 mm along its axis: a twice-a-turn tilt there equals joint 5's angle and joint
    // 6's fixed tilt). Every other order is tested with all four.
    for t in &c.testable {
        if let Effect::Wobble { joint, order } = t.effect {
            let want = if order == 1 || (joint, order) == (5, 2) {
                2
            } else {
                4
            };
            assert_eq!(t.fitted.len(), want, "{}", t.effect);
        } else {
            assert_eq!(t.fitted, t.effect.params(), "{}", t.effect);
        }
    }
    let pair = |l: usize| {
        c.testable
            .iter()
            .find(|t| t.effect == Effect::Thermal(Link::Joint(l)))
            .unwrap()
            .indistinguishable
            .clone()
    };
    assert_eq!(pair(1), vec![Effect::Thermal(Link::Joint(2))]);
    assert_eq!(pair(3), vec![Effect::Thermal(Link::Joint(4))]);
    assert_eq!(pair(5), vec![Effect::Thermal(Link::Probe)]);
    assert!(pair(0).is_empty());

    // Without a temperature column, no thermal candidate at all.
    let plain = sim::simulate(
        &s.truth,
        &sim::Options::new(Kind::Point, 200),
        &mut armcal::rng::rng(5),
    )
    .unwrap()
    .data;
    let c = candidates(&Arm::default6(), &plain);
    assert!(!c.thermal);
    assert_eq!(c.testable.len(), 6 * 8 + 5 + 6 * 3);
    assert!(c
        .testable
        .iter()
        .all(|t| !matches!(t.effect, Effect::Thermal(_))));
}

#[test]
fn candidates_of_a_panda_session() {
    let dir = armcal::mukca::default_dir();
    let unit = armcal::mukca::load(&dir, "panda_2").unwrap();
    let c = candidates(&unit.arm, &unit.data);
    // Joint 1 of the Panda turns about the vertical: no gravity lever.
    assert!(c
        .untestable
        .iter()
        .any(|u| u.effect == Effect::Gravity(0) && u.reason.contains("no gravity lever")));
    assert!(!c.thermal);
    assert_eq!(c.testable.len(), 7 * 8 + 6 + 7 * 3);
}

#[test]
fn the_highest_harmonic_order_follows_the_readings() {
    // 101 readings of joint 1: the widest gap and the count set the order (⌊π / g⌋ − 1 and
    // n / 8), and orders beyond it are not tried.
    let s = scenario::with_families(1, &[]);
    let mut data = scenario::points(&s, 101);
    for (i, r) in data.rows.iter_mut().enumerate() {
        r.theta[0] = 0.5 * i as f64;
    }
    assert_eq!(armcal::effects::harmonic::resolvable_order(&data, 0), 5);
    let c = armcal::diagnose::candidates::candidates_up_to(&Arm::default6(), &data, 8);
    let tried = |order| {
        c.testable
            .iter()
            .any(|t| t.effect == Effect::Harmonic { joint: 0, order })
    };
    assert!(tried(5) && !tried(6));
    assert!(c
        .untestable
        .iter()
        .any(|u| u.effect == Effect::Harmonic { joint: 0, order: 6 }
            && u.reason.contains("up to order 5")));
    for (i, r) in data.rows.iter_mut().enumerate() {
        r.theta[0] = 0.01 * i as f64;
    }
    // The gap allows ⌊π / 0.01⌋ − 1 = 313; 101 readings allow 12.
    assert_eq!(armcal::effects::harmonic::resolvable_order(&data, 0), 12);
    // Other joints: random readings, far beyond the default cap.
    assert!(armcal::effects::harmonic::resolvable_order(&data, 1) >= 8);
}

#[test]
fn linearised_holdout_matches_real_refits() {
    // A hidden harmonic; the geometric fit linearised with the harmonic's columns predicts the
    // held-out error of every unit as real refits of each fold give it.
    let mut s = scenario::with_families(7, &[]);
    s.truth.joints[2]
        .harmonics
        .push(quatarm_ref::arm::Harmonic {
            order: 2,
            sin: 6e-5,
            cos: 2e-5,
        });
    let data = scenario::points(&s, 400);
    let folds = holdout::kfold(&data, 5, 9);
    let opts = Options::default();
    let fit = calibrate(&Arm::default6(), &data, &opts).unwrap();
    let effect = Effect::Harmonic { joint: 2, order: 2 };
    let lin = Linearisation::at(&fit, &data, &effect.params(), &folds);
    let model = lin.model();
    let mut with = model.clone();
    with.extend(lin.positions(&effect.params()));
    let held = lin.heldout(&data, &[Set::of(model), Set::of(with)]);
    for (k, terms) in [Terms::geometric(), Terms::with(&[effect])]
        .into_iter()
        .enumerate()
    {
        let real = holdout::validate(
            &Arm::default6(),
            &data,
            &Options {
                terms,
                ..opts.clone()
            },
            &folds,
        );
        let real: Vec<f64> = unit_errors(&data, &real)
            .into_iter()
            .map(Option::unwrap)
            .collect();
        assert_eq!(real.len(), held[k].len());
        let (a, b): (f64, f64) = (real.iter().sum(), held[k].iter().sum());
        println!("model {k}: held-out SS real {a:.6} mm², linearised {b:.6} mm²");
        assert!((a - b).abs() < 1e-3 * a, "{a} vs {b}");
        let worst = real
            .iter()
            .zip(&held[k])
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-6, "a unit differs by {worst} mm²");
    }
}
