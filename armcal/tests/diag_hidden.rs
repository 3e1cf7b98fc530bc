//! The diagnosis finds hidden effects: each case draws, from its seed, a `default-6` arm with
//! random geometric errors and one or two extended effects of random family and joint
//! (`armcal::diagnose::scenario`), simulates 600 `point` readings (5 µm noise per axis,
//! 16–28 °C), and requires the exact causes named (a collinear thermal pair as one cause with
//! its partner), the held-out RMS cut to the noise floor, and the extended model predicting
//! fresh poses of the true arm to 3 µm RMS after one rigid alignment. A null case names
//! nothing; `spat` + `length` data name the same causes.

use armcal::data::Dataset;
use armcal::diagnose::scenario::{self, Family, Scenario};
use armcal::diagnose::{self, Diagnosis};
use armcal::fit::design::poses::{limits, random_pose};
use armcal::fit::residuals::{compare_aligned, residuals, summarise};
use armcal::params::{Effect, Link};
use nalgebra::Vector3;
use quatarm_ref::arm::{Arm, Harmonic, Wobble};

/// The RMS of the truth's own residuals on the data: the noise floor no model can beat.
fn floor_um(truth: &Arm, data: &Dataset) -> f64 {
    summarise(&residuals(truth, data, None), data).all.rms_um
}

fn names(d: &Diagnosis) -> Vec<(Effect, Vec<Effect>)> {
    let mut v: Vec<_> = d
        .causes
        .iter()
        .map(|c| (c.effect, c.indistinguishable.clone()))
        .collect();
    v.sort();
    v
}

/// The truth's value of what a named cause measures (a pair's partner carried by the named
/// link in proportion to their lengths).
fn true_magnitude(truth: &Arm, e: Effect, partners: &[Effect]) -> f64 {
    let len = |l: Link| match l {
        Link::Joint(j) => Vector3::from(truth.joints[j].actual_link()).norm(),
        Link::Probe => Vector3::from(truth.probe.actual()).norm(),
    };
    let kappa = |l: Link| match l {
        Link::Joint(j) => truth.joints[j].thermal,
        Link::Probe => truth.probe.thermal,
    };
    match e {
        Effect::Harmonic { joint, order } => {
            let hs: Vec<&Harmonic> = truth.joints[joint]
                .harmonics
                .iter()
                .filter(|h| h.order == order)
                .collect();
            let s: f64 = hs.iter().map(|h| h.sin).sum();
            let c: f64 = hs.iter().map(|h| h.cos).sum();
            s.hypot(c)
        }
        Effect::Wobble { joint, order } => {
            let sum = |f: &dyn Fn(&Wobble) -> f64| -> f64 {
                truth.joints[joint]
                    .wobble
                    .iter()
                    .filter(|w| w.order == order)
                    .map(f)
                    .sum()
            };
            let c = [
                sum(&|w| w.alpha[0]),
                sum(&|w| w.alpha[1]),
                sum(&|w| w.beta[0]),
                sum(&|w| w.beta[1]),
            ];
            if order == 1 {
                // Its counter-rotating part: the rest is geometry (`effects::wobble`).
                let (p, q) = ((c[0] + c[3]) / 2.0, (c[1] - c[2]) / 2.0);
                (2.0 * (p * p + q * q)).sqrt()
            } else {
                c.iter().map(|x| x * x).sum::<f64>().sqrt()
            }
        }
        Effect::Gravity(j) => truth.joints[j].gravity,
        Effect::Thermal(l) => {
            kappa(l)
                + partners
                    .iter()
                    .map(|p| match p {
                        Effect::Thermal(m) => kappa(*m) * len(*m) / len(l),
                        _ => 0.0,
                    })
                    .sum::<f64>()
        }
    }
}

/// Runs a scenario on `data`; returns what failed (empty: all good) and a line to print.
fn check(s: &Scenario, data: &Dataset, label: &str) -> (Vec<String>, String) {
    let d = diagnose::diagnose(&Arm::default6(), data, &diagnose::Options::default())
        .unwrap_or_else(|e| panic!("seed {} ({label}): {e}", s.seed));
    let mut fails = Vec::new();
    let mut want = s.expected.clone();
    want.sort();
    let got = names(&d);
    if got != want {
        fails.push(format!("named {got:?}, hidden {want:?}"));
    }
    let floor = floor_um(&s.truth, data);
    let base = d.baseline.holdout.summary.all.rms_um;
    let ext = d.extended.holdout.summary.all.rms_um;
    // Near the floor: the held-out error of a right model exceeds the truth's own residuals
    // only by the fitted parameters' share (≈ 1 + p / 2n) and quantisation.
    if ext > 1.05 * floor {
        fails.push(format!(
            "held-out RMS {ext:.2} µm, noise floor {floor:.2} µm"
        ));
    }
    let poses = scenario::fresh_poses(s.seed, 2000);
    let fresh_geo = compare_aligned(&d.baseline.fit.arm, &s.truth, &poses).rms_um;
    let fresh = compare_aligned(&d.extended.fit.arm, &s.truth, &poses).rms_um;
    if fresh > 3.0 {
        fails.push(format!("fresh poses {fresh:.2} µm RMS"));
    }
    for c in &d.causes {
        let truth = true_magnitude(&s.truth, c.effect, &c.indistinguishable);
        let err = (c.magnitude - truth).abs();
        if err > 5.0 * c.magnitude_uncertainty + 0.02 * truth.abs() {
            fails.push(format!(
                "{}: magnitude {:.4e} ± {:.1e}, truth {truth:.4e}",
                c.effect.spec(),
                c.magnitude,
                c.magnitude_uncertainty
            ));
        }
    }
    let line = format!(
        "seed {:>3} {label}: hidden {:?} → named {}; held-out {base:.2} → {ext:.2} µm (floor \
         {floor:.2}); fresh poses {fresh_geo:.2} → {fresh:.2} µm",
        s.seed,
        s.hidden.iter().map(|e| e.spec()).collect::<Vec<_>>(),
        if got.is_empty() {
            "none".to_string()
        } else {
            got.iter()
                .map(|(e, _)| e.spec())
                .collect::<Vec<_>>()
                .join(" ")
        },
    );
    (
        fails
            .into_iter()
            .map(|f| format!("seed {} ({label}): {f}", s.seed))
            .collect(),
        line,
    )
}

fn run(cases: &[(Scenario, Dataset, &str)]) {
    let mut fails = Vec::new();
    for (s, data, label) in cases {
        let (f, line) = check(s, data, label);
        println!("{line}");
        fails.extend(f);
    }
    assert!(fails.is_empty(), "{}", fails.join("\n"));
}

fn family(e: Effect) -> Family {
    match e {
        Effect::Harmonic { .. } => Family::Harmonic,
        Effect::Gravity(_) => Family::Gravity,
        Effect::Thermal(_) => Family::Thermal,
        Effect::Wobble { .. } => Family::Wobble,
    }
}

#[test]
fn hidden_effects_are_named_from_point_data() {
    let seeds = 1..=24u64;
    let cases: Vec<(Scenario, Dataset, &str)> = seeds
        .map(|seed| {
            let s = scenario::draw(seed);
            let data = scenario::points(&s, 600);
            (s, data, "600 point")
        })
        .collect();
    // The seeds cover every family, one and two effects at once.
    for f in [Family::Harmonic, Family::Gravity, Family::Thermal] {
        let n = cases
            .iter()
            .filter(|c| c.0.hidden.iter().any(|e| family(*e) == f))
            .count();
        assert!(n >= 4, "{f:?} hidden in only {n} cases");
    }
    assert!(cases.iter().any(|c| c.0.hidden.len() == 2));
    assert!(cases.iter().any(|c| c.0.hidden.len() == 1));
    run(&cases);
}

#[test]
fn axis_wobbles_are_named_exactly() {
    // One wobble of order 1, 2 or 3 on one joint, 20–100 µrad, random direction and phase
    // (`scenario::Family::Wobble`); then wobbles on the shoulder with a harmonic of the same
    // order on the same joint, which turns the joint rather than tilting it.
    let mut cases: Vec<(Scenario, Dataset, &str)> = (501..=509u64)
        .map(|seed| {
            let s = scenario::with_families(seed, &[Family::Wobble]);
            let data = scenario::points(&s, 600);
            (s, data, "600 point")
        })
        .collect();
    for order in 1..=3 {
        let seen = cases
            .iter()
            .any(|c| matches!(c.0.hidden[0], Effect::Wobble { order: o, .. } if o == order));
        assert!(seen, "no seed draws a wobble of order {order}");
    }
    let mut s = scenario::with_families(510, &[]);
    s.truth.joints[1].wobble.push(Wobble {
        order: 1,
        alpha: [4e-5, -2e-5],
        beta: [1e-5, 3e-5],
    });
    s.truth.joints[1].harmonics.push(Harmonic {
        order: 1,
        sin: 3e-5,
        cos: 4e-5,
    });
    s.hidden = vec![
        Effect::Wobble { joint: 1, order: 1 },
        Effect::Harmonic { joint: 1, order: 1 },
    ];
    s.expected = s
        .hidden
        .iter()
        .map(|e| scenario::expected_cause(*e))
        .collect();
    let data = scenario::points(&s, 600);
    cases.push((s, data, "600 point"));
    run(&cases);
}

#[test]
fn null_case_names_none() {
    let mut fails = Vec::new();
    for seed in 101..=106u64 {
        let s = scenario::with_families(seed, &[]);
        let data = scenario::points(&s, 600);
        let d = diagnose::diagnose(&Arm::default6(), &data, &diagnose::Options::default()).unwrap();
        println!(
            "seed {seed}: named {:?}; held-out {:.2} µm (floor {:.2})",
            names(&d),
            d.baseline.holdout.summary.all.rms_um,
            floor_um(&s.truth, &data)
        );
        if !d.causes.is_empty() {
            fails.push(format!("seed {seed}: named {:?} in pure noise", names(&d)));
        }
        assert_eq!(d.gain_percent(), 0.0);
        assert!(d.extended.effects.is_empty());
    }
    assert!(fails.is_empty(), "{}", fails.join("\n"));
}

#[test]
fn the_same_causes_are_named_from_spat_and_length_data() {
    let cases: Vec<(Scenario, Dataset, &str)> = (1..=8u64)
        .map(|seed| {
            let s = scenario::draw(seed);
            let data = scenario::spat_length(&s, 400, 200);
            (s, data, "400 spat + 200 length")
        })
        .collect();
    run(&cases);
}

#[test]
fn collinear_thermal_links_are_one_cause() {
    // The expansion of link 5 or of the probe is named on the lower link of its pair.
    let mut cases = Vec::new();
    for (seed, link) in [
        (201u64, Link::Joint(4)),
        (202, Link::Probe),
        (203, Link::Joint(2)),
    ] {
        let mut s = scenario::with_families(seed, &[]);
        match link {
            Link::Joint(j) => s.truth.joints[j].thermal = 2e-5,
            Link::Probe => s.truth.probe.thermal = 2e-5,
        }
        s.hidden = vec![Effect::Thermal(link)];
        s.expected = vec![scenario::expected_cause(Effect::Thermal(link))];
        let data = scenario::points(&s, 600);
        cases.push((s, data, "600 point"));
    }
    assert_eq!(
        cases[1].0.expected,
        vec![(
            Effect::Thermal(Link::Joint(5)),
            vec![Effect::Thermal(Link::Probe)]
        )]
    );
    run(&cases);
}

#[test]
fn near_aliases_on_one_joint_are_told_apart() {
    // A gravity compliance of the shoulder against an eccentricity of its encoder (both turn
    // the joint by amounts that vary with the pose), alone and together.
    let mut cases = Vec::new();
    let set = |s: &mut Scenario, effects: &[Effect]| {
        for e in effects {
            match *e {
                Effect::Gravity(j) => s.truth.joints[j].gravity = 3e-8,
                Effect::Harmonic { joint, order } => {
                    s.truth.joints[joint].harmonics.push(Harmonic {
                        order,
                        sin: 4e-5,
                        cos: -3e-5,
                    })
                }
                Effect::Thermal(_) | Effect::Wobble { .. } => unreachable!(),
            }
        }
        s.hidden = effects.to_vec();
        s.expected = effects
            .iter()
            .map(|e| scenario::expected_cause(*e))
            .collect();
    };
    let g2 = Effect::Gravity(1);
    let h21 = Effect::Harmonic { joint: 1, order: 1 };
    let g4 = Effect::Gravity(3);
    let h41 = Effect::Harmonic { joint: 3, order: 1 };
    for (seed, effects) in [
        (301u64, vec![g2]),
        (302, vec![h21]),
        (303, vec![g2, h21]),
        (304, vec![g4, h41]),
    ] {
        let mut s = scenario::with_families(seed, &[]);
        set(&mut s, &effects);
        let data = scenario::points(&s, 600);
        cases.push((s, data, "600 point"));
    }
    run(&cases);
}

#[test]
fn a_wrist_compliance_below_the_noise_is_not_misnamed() {
    // Hinge 6 carries only the 200 mm from its axis to the ball: 4e-8 rad/mm moves the ball by
    // at most 1.6 µm, under the 5 µm noise. The data cannot name it; whatever is named must not
    // be something else, and the model must still predict the arm to 3 µm.
    let mut s = scenario::with_families(401, &[]);
    s.truth.joints[5].gravity = 4e-8;
    let data = scenario::points(&s, 600);
    let d = diagnose::diagnose(&Arm::default6(), &data, &diagnose::Options::default()).unwrap();
    let got = names(&d);
    println!("named {got:?}");
    assert!(
        got.iter().all(|(e, _)| *e == Effect::Gravity(5)),
        "named {got:?}"
    );
    let fresh = compare_aligned(
        &d.extended.fit.arm,
        &s.truth,
        &scenario::fresh_poses(401, 2000),
    );
    assert!(fresh.rms_um < 3.0, "{fresh:?}");
}

#[test]
fn a_seven_axis_arm_is_diagnosed_too() {
    // The MUKCa Panda's nominal model (D–H twists in `tilt`) with random geometric errors and
    // three hidden effects, 600 point readings at 16–28 °C.
    let dir = armcal::mukca::default_dir();
    let nominal = quatarm_ref::calfile::read(&dir.join("mukca-panda-panda_2.toml"))
        .unwrap()
        .arm;
    let mut truth = armcal::sim::perturb(&nominal, 3e-4, 0.3, &mut armcal::rng::rng(5));
    truth.joints[3].harmonics.push(Harmonic {
        order: 2,
        sin: 5e-5,
        cos: 3e-5,
    });
    truth.joints[1].gravity = 3e-8;
    truth.joints[4].thermal = 2e-5;
    let mut o = armcal::sim::Options::new(armcal::data::Kind::Point, 600);
    o.temp = Some((16.0, 28.0));
    let data = armcal::sim::simulate(&truth, &o, &mut armcal::rng::rng(6))
        .unwrap()
        .data;
    let d = diagnose::diagnose(&nominal, &data, &diagnose::Options::default()).unwrap();
    let mut want = vec![
        (Effect::Harmonic { joint: 3, order: 2 }, vec![]),
        (Effect::Gravity(1), vec![]),
        (Effect::Thermal(Link::Joint(4)), vec![]),
    ];
    want.sort();
    assert_eq!(names(&d), want);
    // Links of zero length (2 and 7 of the Panda) have nothing to expand.
    let zero: Vec<Effect> = d.candidates.untestable.iter().map(|u| u.effect).collect();
    assert!(zero.contains(&Effect::Thermal(Link::Joint(1))), "{zero:?}");
    assert!(zero.contains(&Effect::Thermal(Link::Joint(6))), "{zero:?}");
    let lim = limits(&nominal);
    let mut rng = armcal::rng::rng(7);
    let poses: Vec<(Vec<f64>, f64)> = (0..2000)
        .map(|k| {
            (
                random_pose(&lim, &mut rng),
                16.0 + 12.0 * (k as f64 / 2000.0),
            )
        })
        .collect();
    let geo = compare_aligned(&d.baseline.fit.arm, &truth, &poses).rms_um;
    let ext = compare_aligned(&d.extended.fit.arm, &truth, &poses).rms_um;
    println!("fresh poses: geometric {geo:.2} µm, extended {ext:.2} µm");
    assert!(ext < 3.0, "{ext}");
    assert!(geo > 10.0, "{geo}");
}
