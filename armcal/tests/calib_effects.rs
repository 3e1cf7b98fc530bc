//! Every extended effect of the spec is fittable: hidden in simulated data, fitted with the
//! right terms, it is recovered within its uncertainty and the model predicts the truth.

use armcal::data::Kind;
use armcal::fit::calib::calibrate;
use armcal::fit::design::poses::{limits, random_pose};
use armcal::fit::ident::Why;
use armcal::fit::options::Options;
use armcal::params::{Link, Param, Terms};
use armcal::rng::rng;
use armcal::sim::{self, perturb, simulate};
use quatarm_ref::arm::{Arm, Harmonic, Wobble};
use quatarm_ref::forward;

fn truth() -> Arm {
    let mut t = perturb(&Arm::default6(), 3e-4, 0.3, &mut rng(31));
    t.joints[1].harmonics.push(Harmonic {
        order: 1,
        sin: 6e-5,
        cos: -4e-5,
    });
    t.joints[4].harmonics.push(Harmonic {
        order: 2,
        sin: -3e-5,
        cos: 5e-5,
    });
    t.joints[3].gravity = 3e-8;
    t.joints[2].thermal = 2e-5;
    t.probe.thermal = 1.5e-5;
    t
}

#[test]
fn hidden_effects_are_recovered() {
    let t = truth();
    let mut o = sim::Options::new(Kind::Point, 600);
    o.temp = Some((16.0, 28.0));
    let data = simulate(&t, &o, &mut rng(32)).unwrap().data;
    let terms = Terms::parse(
        "+encoder_harmonic:2:1,+encoder_harmonic:5:2,+gravity_compliance:4,+thermal_expansion:3,+thermal_expansion:probe",
        6,
    )
    .unwrap();
    let opts = Options {
        terms,
        ..Options::default()
    };
    let fit = calibrate(&Arm::default6(), &data, &opts).unwrap();
    let geometric = calibrate(&Arm::default6(), &data, &Options::default()).unwrap();
    println!(
        "sigma: extended {:.2} µm, geometric {:.2} µm",
        fit.sigma_mm * 1e3,
        geometric.sigma_mm * 1e3
    );
    assert!(fit.sigma_mm < 0.0056, "{}", fit.sigma_mm);
    assert!(
        geometric.sigma_mm > 0.008,
        "the effects are visible: {}",
        geometric.sigma_mm
    );
    // Each effect's value against the truth, within 4 standard uncertainties.
    let check = |p: Param, want: f64| {
        let k = fit.params.iter().position(|q| *q == p).unwrap();
        let u = fit.uncertainty[k].unwrap_or_else(|| panic!("{p} not fitted"));
        println!("{p}: {:.4e} ± {:.1e} (truth {want:.4e})", fit.values[k], u);
        assert!((fit.values[k] - want).abs() < 4.0 * u, "{p}");
    };
    check(
        Param::Harmonic {
            joint: 1,
            order: 1,
            cos: false,
        },
        6e-5,
    );
    check(
        Param::Harmonic {
            joint: 1,
            order: 1,
            cos: true,
        },
        -4e-5,
    );
    check(
        Param::Harmonic {
            joint: 4,
            order: 2,
            cos: false,
        },
        -3e-5,
    );
    check(
        Param::Harmonic {
            joint: 4,
            order: 2,
            cos: true,
        },
        5e-5,
    );
    check(Param::Gravity(3), 3e-8);
    check(Param::Thermal(Link::Joint(2)), 2e-5);
    check(Param::Thermal(Link::Probe), 1.5e-5);
    // The calibrated model predicts fresh poses at any temperature.
    let lim = limits(&t);
    let mut r = rng(33);
    let poses: Vec<(Vec<f64>, f64)> = (0..3000)
        .map(|k| (random_pose(&lim, &mut r), 16.0 + 12.0 * (k as f64 / 3000.0)))
        .collect();
    let after = armcal::fit::residuals::compare_aligned(&fit.arm, &t, &poses);
    println!("fresh poses: {after:?}");
    assert!(after.rms_um < 3.0, "{after:?}");
    // The written file carries every term.
    let back = quatarm_ref::calfile::parse(&quatarm_ref::calfile::write(&fit.arm, &[]))
        .unwrap()
        .arm;
    for (th, tc) in poses.iter().take(20) {
        let d = forward::forward(&back, th, *tc).p - forward::forward(&fit.arm, th, *tc).p;
        assert!(d.norm() < 1e-9);
    }
}

#[test]
fn an_axis_wobble_is_recovered() {
    // Joint 3 (a hinge) wobbles twice a turn, joint 2 cones once a turn; 600 point readings.
    let mut t = perturb(&Arm::default6(), 3e-4, 0.3, &mut rng(41));
    t.joints[2].wobble.push(Wobble {
        order: 2,
        alpha: [5e-5, -3e-5],
        beta: [2e-5, 4e-5],
    });
    // Counter-rotating (a = d, b = −c): the coning, which the geometry cannot carry.
    t.joints[1].wobble.push(Wobble {
        order: 1,
        alpha: [4e-5, 2e-5],
        beta: [-2e-5, 4e-5],
    });
    let data = simulate(&t, &sim::Options::new(Kind::Point, 600), &mut rng(42))
        .unwrap()
        .data;
    let opts = Options {
        terms: Terms::parse("+axis_wobble:3:2,+axis_wobble:2:1", 6).unwrap(),
        ..Options::default()
    };
    let fit = calibrate(&Arm::default6(), &data, &opts).unwrap();
    let geometric = calibrate(&Arm::default6(), &data, &Options::default()).unwrap();
    println!(
        "sigma: with wobble {:.2} µm, geometric {:.2} µm",
        fit.sigma_mm * 1e3,
        geometric.sigma_mm * 1e3
    );
    assert!(fit.sigma_mm < 0.0056, "{}", fit.sigma_mm);
    assert!(geometric.sigma_mm > 0.008, "{}", geometric.sigma_mm);
    let at = |p: Param| {
        let k = fit.params.iter().position(|q| *q == p).unwrap();
        (fit.values[k], fit.uncertainty[k])
    };
    let w = |joint, order, coef| Param::Wobble { joint, order, coef };
    for (coef, want) in [5e-5, -3e-5, 2e-5, 4e-5].into_iter().enumerate() {
        let (v, u) = at(w(2, 2, coef as u8));
        let u = u.expect("order 2 is fitted whole");
        println!("joint 3 order 2 [{coef}]: {v:.4e} ± {u:.1e} (truth {want:.4e})");
        assert!((v - want).abs() < 4.0 * u, "coefficient {coef}");
    }
    // Order 1: two of the four are held (the co-rotating half is geometry); the coning part
    // p = (a + d) / 2, q = (b − c) / 2 is what the data determine.
    let order1: Vec<(f64, Option<f64>)> = (0..4).map(|c| at(w(1, 1, c))).collect();
    assert_eq!(order1.iter().filter(|(_, u)| u.is_none()).count(), 2);
    let u = order1.iter().filter_map(|(_, u)| *u).fold(0.0, f64::max);
    let p = (order1[0].0 + order1[3].0) / 2.0;
    let q = (order1[1].0 - order1[2].0) / 2.0;
    println!("joint 2 order 1 coning: p {p:.4e}, q {q:.4e} (truth 4e-5, 2e-5) ± {u:.1e}");
    assert!((p - 4e-5).abs() < 4.0 * u && (q - 2e-5).abs() < 4.0 * u);
    let lim = limits(&t);
    let mut r = rng(43);
    let poses: Vec<(Vec<f64>, f64)> = (0..2000)
        .map(|_| (random_pose(&lim, &mut r), 20.0))
        .collect();
    let after = armcal::fit::residuals::compare_aligned(&fit.arm, &t, &poses);
    println!("fresh poses: {after:?}");
    assert!(after.rms_um < 3.0, "{after:?}");
    // The written file carries the wobble, and reads back to the same arm.
    let back = quatarm_ref::calfile::parse(&quatarm_ref::calfile::write(&fit.arm, &[]))
        .unwrap()
        .arm;
    assert_eq!(back.joints[2].wobble, fit.arm.joints[2].wobble);
}

#[test]
fn collinear_links_expand_indistinguishably() {
    // Links 2 and 3 of default-6 lie on one line: their thermal expansions look alike.
    let t = truth();
    let mut o = sim::Options::new(Kind::Point, 300);
    o.temp = Some((16.0, 28.0));
    let data = simulate(&t, &o, &mut rng(34)).unwrap().data;
    let opts = Options {
        terms: Terms::parse("+thermal_expansion:2,+thermal_expansion:3", 6).unwrap(),
        ..Options::default()
    };
    let fit = calibrate(&Arm::default6(), &data, &opts).unwrap();
    let held: Vec<_> = fit
        .ident
        .fixed
        .iter()
        .filter(|f| matches!(fit.params[f.index], Param::Thermal(_)))
        .collect();
    assert_eq!(held.len(), 1, "one of the pair is held");
    let f = held[0];
    assert_eq!(f.why, Why::Inseparable);
    assert_eq!(fit.params[f.index], Param::Thermal(Link::Joint(2)));
    assert_eq!(
        fit.params[f.absorbed_by[0].0],
        Param::Thermal(Link::Joint(1))
    );
    assert!(
        (f.absorbed_by[0].1 - 1.0).abs() < 1e-6,
        "{:?}",
        f.absorbed_by
    );
}

#[test]
fn thermal_terms_without_a_temperature_spread_have_no_effect() {
    let t = Arm::default6();
    let data = simulate(&t, &sim::Options::new(Kind::Point, 200), &mut rng(35))
        .unwrap()
        .data;
    let opts = Options {
        terms: Terms::parse("+thermal_expansion:4", 6).unwrap(),
        ..Options::default()
    };
    let fit = calibrate(&Arm::default6(), &data, &opts).unwrap();
    let k = fit
        .params
        .iter()
        .position(|p| *p == Param::Thermal(Link::Joint(3)))
        .unwrap();
    assert!(fit
        .ident
        .fixed
        .iter()
        .any(|f| f.index == k && f.why == Why::NoEffect));
}
