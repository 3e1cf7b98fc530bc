//! The hub's U95 (`quatarm::uncertainty::radius`, f32, a grid and micromath) against the
//! host's exact radius (`armcal::uncertainty::u95`, f64 quadrature).

use armcal::uncertainty::u95::{shape_factor as shape_factor_exact, u95};
use nalgebra::{Matrix3, Vector3};
use quatarm::uncertainty::radius::{shape_factor, u95 as hub_u95};
use quatarm::uncertainty::Covariance;
use rand::{Rng, SeedableRng};

/// The committed grid is the host's function at its nodes (as `--example u95_grid` prints).
#[test]
fn u95_grid_is_current() {
    for i in 0..17 {
        for j in 0..17 {
            let (a, b) = (i as f64 / 16.0, j as f64 / 16.0);
            let (want, got) = (
                shape_factor_exact(a, b),
                f64::from(shape_factor(a as f32, b as f32)),
            );
            assert!(
                (got / want - 1.0).abs() < 2e-7,
                "G({a}, {b}): grid {got}, host {want}: regenerate src/uncertainty/grid.rs"
            );
        }
    }
}

/// Between the nodes, bilinear interpolation stays within 0.1 % of the exact shape factor.
#[test]
fn interpolation_is_within_a_permille() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let mut worst: f64 = 0.0;
    for _ in 0..400 {
        let (a, b) = (rng.gen::<f64>(), rng.gen::<f64>());
        let e = f64::from(shape_factor(a as f32, b as f32)) / shape_factor_exact(a, b) - 1.0;
        worst = worst.max(e.abs());
    }
    println!("worst interpolation error {:.2e}", worst);
    assert!(worst < 1e-3, "{worst}");
}

/// On random covariances of every shape (rotated, one direction up to 100× the others,
/// entries from nm² to mm²), the hub's U95 is within 0.1 % of the host's.
#[test]
fn hub_u95_agrees_with_the_host() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let mut worst: f64 = 0.0;
    for _ in 0..500 {
        let scale = 10f64.powf(rng.gen_range(0.0..12.0));
        let l = Vector3::new(
            scale,
            scale * 10f64.powf(rng.gen_range(-4.0..0.0)),
            scale * 10f64.powf(rng.gen_range(-4.0..0.0)),
        );
        let axis = Vector3::new(
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
        );
        let r = nalgebra::Rotation3::new(axis * 3.0);
        let s = r.matrix() * Matrix3::from_diagonal(&l) * r.matrix().transpose();
        // The hub's order is the host's output order.
        let c = Covariance(armcal::uncertainty::propagate::entries(&s).map(|x| x as f32));
        let e = f64::from(hub_u95(&c)) / u95(&s) - 1.0;
        worst = worst.max(e.abs());
    }
    println!("worst hub U95 error {:.2e}", worst);
    assert!(worst < 1e-3, "{worst}");
}

/// The hub's U95 (`quatarm::uncertainty::Uncertainty`: the reading's own terms and the table's
/// parameter block, every column analytic on the matrix chain's frames) against the
/// host's first order (analytic Jacobians, f64) at random readings, in f32 and in fixed point;
/// returns the worst relative error and the parameter part's largest share of the variance.
fn hub_against_host(
    arm: &quatarm_ref::Arm,
    u: &quatarm_ref::uncertainty::Uncertainty,
    seed: u64,
) -> (f64, f64) {
    hub_against_host_with_probe(arm, u, 0, seed)
}

/// [`hub_against_host`] with the arm's probe at index `probe` mounted on the hub (its chains
/// and its uncertainty, as `ToDevice::SelectProbe` does) and on the host.
fn hub_against_host_with_probe(
    arm: &quatarm_ref::Arm,
    u: &quatarm_ref::uncertainty::Uncertainty,
    probe: usize,
    seed: u64,
) -> (f64, f64) {
    use armcal::uncertainty::{propagate, Budget};
    use quatarm::uncertainty::Uncertainty;
    use quatarm::{Chain, Fixed, F32};
    let bytes = armcal::tablebuild::build_with(arm, Some(u)).unwrap();
    let table = quatarm::Table::parse(&bytes).unwrap();
    let host = Budget::from_file(u);
    let mut own_only = host.clone();
    own_only.params.clear();
    own_only.cov = nalgebra::DMatrix::zeros(0, 0);
    let mut h32 = Uncertainty::<F32>::new(&table)
        .unwrap()
        .expect("the table has its budget");
    let mut hfx = Uncertainty::<Fixed>::new(&table)
        .unwrap()
        .expect("the table has its budget");
    assert_eq!(h32.has_parameters(), !u.parameters.is_empty());
    let (mut c32, mut cfx) = (
        Chain::<F32>::new(&table).unwrap(),
        Chain::<Fixed>::new(&table).unwrap(),
    );
    if probe != 0 {
        c32.mount(&table, probe).unwrap();
        cfx.mount(&table, probe).unwrap();
        h32.mount(&table, probe).unwrap();
        hfx.mount(&table, probe).unwrap();
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let (mut worst, mut share): (f64, f64) = (0.0, 0.0);
    for _ in 0..200 {
        let counts: Vec<u32> = arm
            .joints
            .iter()
            .map(|j| rng.gen_range(0..j.encoder_counts))
            .collect();
        let temp_mc: i32 = rng.gen_range(16_000..28_000);
        let (theta, t) = (arm.counts_to_rad(&counts), f64::from(temp_mc) / 1000.0);
        let (_, s) = propagate::point(arm, probe, &host, &theta, t);
        let (_, own) = propagate::point(arm, probe, &own_only, &theta, t);
        share = share.max(1.0 - own.trace() / s.trace());
        let want_nm = u95(&s) * 1e6;
        // The hub's chain takes every reading the uncertainty is asked for.
        c32.eval(&counts, temp_mc).unwrap();
        cfx.eval(&counts, temp_mc).unwrap();
        for got in [
            h32.covariance(&counts, temp_mc).unwrap().u95_nm(),
            hfx.covariance(&counts, temp_mc).unwrap().u95_nm(),
        ] {
            worst = worst.max((f64::from(got) / want_nm - 1.0).abs());
        }
    }
    (worst, share)
}

/// The shipped 52-parameter budget (every kind of parameter but the probe's thermal
/// expansion): the hub's U95 within 0.1 % of the host's.
#[test]
fn hub_u95_agrees_with_the_host_on_the_shipped_budget() {
    let text = include_str!("../../data/default-6-full.toml");
    let parsed = quatarm_ref::calfile::parse(text).unwrap();
    let (worst, share) = hub_against_host(&parsed.arm, parsed.uncertainty.as_ref().unwrap(), 3);
    println!(
        "default-6-full: worst hub U95 error {worst:.2e} (parameter part up to {:.1} % of the variance)",
        100.0 * share
    );
    assert!(
        share > 0.1,
        "the parameter part must matter for this test to test it: {share}"
    );
    assert!(worst < 1e-3, "{worst}");
}

/// The Raspberry Pi Pico's profile (issue 32): the fixed-point hub with the axis wobble and
/// the parameter block, its U95 in f32 (software floating point on the M0+, the same code
/// compiled here) from the fixed-point matrix chain's frames, against `armcal eval
/// --uncertainty`'s first order, on the arm whose every joint wobbles
/// (`data/default-6-wobble.toml`) with the shipped 52-parameter budget: within 0.1 %.
#[test]
fn pico_profile_u95_agrees_with_the_host_on_a_wobbling_arm() {
    let wobbling =
        quatarm_ref::calfile::parse(include_str!("../../data/default-6-wobble.toml")).unwrap();
    let full = quatarm_ref::calfile::parse(include_str!("../../data/default-6-full.toml")).unwrap();
    let budget = full.uncertainty.as_ref().unwrap();
    let bytes = armcal::tablebuild::build_with(&wobbling.arm, Some(budget)).unwrap();
    let table = quatarm::Table::parse(&bytes).unwrap();
    assert!(table.wobble().is_some() && table.parameters().is_some());
    let (worst, share) = hub_against_host(&wobbling.arm, budget, 17);
    println!(
        "Pico profile, default-6-wobble with the 52-parameter budget: worst hub U95 error \
         {worst:.2e} (parameter part up to {:.1} % of the variance)",
        100.0 * share
    );
    assert!(share > 0.1, "{share}");
    assert!(worst < 1e-3, "{worst}");
}

/// Without its parameters the same budget still agrees: the reading's own terms alone.
#[test]
fn hub_own_terms_agree_with_the_host() {
    let text = include_str!("../../data/default-6-full.toml");
    let parsed = quatarm_ref::calfile::parse(text).unwrap();
    let u = parsed.uncertainty.as_ref().unwrap().without_covariance();
    let (worst, _) = hub_against_host(&parsed.arm, &u, 5);
    println!("own terms: worst hub U95 error {worst:.2e}");
    assert!(worst < 1e-3, "{worst}");
}

/// A 7-axis robot with D–H twists of ±π/2 in its fixed rotations (MUKCa's Panda), with a
/// budget over every geometric parameter, its probe's thermal expansion and random
/// correlations: the frames' relabelling and every column kind against the host.
#[test]
fn hub_u95_agrees_with_the_host_on_a_twisted_7_axis_arm() {
    use quatarm_ref::uncertainty::{Link, Param};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../data/mukca/mukca-panda-panda_2-repo-calibrated.toml");
    let mut arm = quatarm_ref::calfile::read(&path).unwrap().arm;
    for (k, j) in arm.joints.iter_mut().enumerate() {
        j.thermal = 1.1e-5;
        j.tilt = [3e-4, -2e-4 * k as f64];
        j.harmonics.push(quatarm_ref::arm::Harmonic {
            order: 1 + k as u32,
            sin: 2e-5,
            cos: -1e-5,
        });
    }
    arm.probe.thermal = 2.3e-5;
    let n = arm.dof();
    let mut keys = Vec::new();
    for j in 0..n {
        keys.extend(geometry_keys(j));
        keys.push(Param::Harmonic {
            joint: j,
            order: 1 + j as u32,
            cos: j % 2 == 1,
        });
    }
    keys.extend((0..3).map(|c| Param::ProbeError(0, c)));
    keys.extend([Param::Thermal(Link::Joint(2)), Param::Thermal(Link::Probe)]);
    let p = keys.len();
    let u = random_budget(keys, 17, n);
    let (worst, share) = hub_against_host(&arm, &u, 9);
    println!(
        "panda_2, {p} parameters: worst hub U95 error {worst:.2e} (parameter part up to {:.1} %)",
        100.0 * share
    );
    assert!(share > 0.5, "{share}");
    assert!(worst < 1e-3, "{worst}");
}

/// An arm of three probes whose budget holds every probe's error (kind 8 on the hub: a shift
/// counted only while its probe is mounted) and the first probe's expansion: with each probe
/// mounted, the hub's U95 is within 0.1 % of the host's for that probe.
#[test]
fn hub_u95_agrees_with_the_host_for_each_mounted_probe() {
    use quatarm_ref::arm::Probe;
    use quatarm_ref::uncertainty::{Link, Param};
    let mut arm = quatarm_ref::Arm::default6();
    arm.probe.thermal = 2.3e-5;
    let probe = |id, vector| Probe {
        id,
        vector,
        error: [0.01, -0.02, 0.03],
        thermal: 1.2e-5,
        ball_diameter: 2.0,
    };
    // f32 serves a reach of 1,650 mm: a 200 mm extension on the 1,380 mm arm.
    arm.more_probes = vec![probe(3, [0.0, 0.0, 200.0]), probe(7, [60.0, 0.0, 100.0])];
    for (k, j) in arm.joints.iter_mut().enumerate() {
        j.thermal = 1.1e-5;
        j.tilt = [3e-4, -2e-4 * k as f64];
    }
    let n = arm.dof();
    let mut keys = Vec::new();
    for j in 0..n {
        keys.extend(geometry_keys(j));
    }
    for k in 0..3 {
        keys.extend((0..3).map(|c| Param::ProbeError(k, c)));
    }
    keys.push(Param::Thermal(Link::Probe));
    let p = keys.len();
    let u = random_budget(keys, 23, n);
    for k in 0..3 {
        let (worst, share) = hub_against_host_with_probe(&arm, &u, k, 31 + k as u64);
        println!(
            "probe index {k}, {p} parameters: worst hub U95 error {worst:.2e} (parameter part up to {:.1} %)",
            100.0 * share
        );
        assert!(share > 0.3, "{share}");
        assert!(worst < 1e-3, "probe index {k}: {worst}");
    }
}

/// A budget over `keys` whose covariance is C = A Aᵀ with A random (seeded), each parameter at
/// its own scale (rad ~1e-5, mm ~3e-3, 1/°C ~1e-6), so that every correlation is exercised,
/// with the encoder, probing and temperature terms of a typical arm of `n` joints.
fn random_budget(
    keys: Vec<quatarm_ref::uncertainty::Param>,
    seed: u64,
    n: usize,
) -> quatarm_ref::uncertainty::Uncertainty {
    use quatarm_ref::uncertainty::Param;
    let p = keys.len();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let scale: Vec<f64> = keys
        .iter()
        .map(|k| match k {
            Param::LinkError(..) | Param::ProbeError(..) => 3e-3,
            Param::Thermal(_) => 1e-6,
            _ => 1e-5,
        })
        .collect();
    let a = nalgebra::DMatrix::from_fn(p, p, |i, _| {
        scale[i] * rng.gen_range(-1.0..1.0) / (p as f64).sqrt()
    });
    let c = &a * a.transpose();
    quatarm_ref::uncertainty::Uncertainty {
        parameters: keys,
        covariance: c.transpose().as_slice().to_vec(),
        encoder_counts: vec![0.29; n],
        probing_mm: 0.002,
        temperature_c: 0.2,
        model_mm: 0.0,
        pose: None,
    }
}

/// Joint `j`'s geometric parameters: its zero offset, its two tilts and its link's three errors.
fn geometry_keys(j: usize) -> [quatarm_ref::uncertainty::Param; 6] {
    use quatarm_ref::uncertainty::Param;
    [
        Param::ZeroOffset(j),
        Param::Tilt(j, 0),
        Param::Tilt(j, 1),
        Param::LinkError(j, 0),
        Param::LinkError(j, 1),
        Param::LinkError(j, 2),
    ]
}

/// A pose part for the budget `u` (issue 27, `quatarm_ref::uncertainty::PoseLeverage`): D =
/// S W with C = S Sᵀ and W's r columns orthogonal, of norms 0.3 to 0.9 (so that C − D Dᵀ
/// stays positive semidefinite, as the host's estimate makes it), b from `shrink`, and m
/// `mean`; seeded.
fn pose_for(
    u: &quatarm_ref::uncertainty::Uncertainty,
    r: usize,
    shrink: f64,
    mean: f64,
    seed: u64,
) -> quatarm_ref::uncertainty::PoseLeverage {
    let p = u.parameters.len();
    let c = u.matrix();
    let eig = ((&c + c.transpose()) * 0.5).symmetric_eigen();
    let mut s = eig.eigenvectors.clone();
    for (k, lambda) in eig.eigenvalues.iter().enumerate() {
        s.column_mut(k).scale_mut(lambda.max(0.0).sqrt());
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let q = nalgebra::DMatrix::from_fn(p, r, |_, _| rng.gen_range(-1.0..1.0))
        .qr()
        .q();
    let w = nalgebra::DMatrix::from_fn(p, r, |i, j| q[(i, j)] * (0.3 + 0.6 * j as f64 / r as f64));
    let d = s * w;
    quatarm_ref::uncertainty::PoseLeverage {
        factor: (0..r)
            .map(|j| d.column(j).iter().copied().collect())
            .collect(),
        shrink,
        leverage_mean: mean,
        joints: None,
    }
}

/// What the hub is compared with: the reading's Σ_p from the formula of
/// `quatarm_ref::uncertainty::PoseLeverage`, written here in f64 from the host's analytic
/// Jacobian J over the budget's parameters: own terms + J C Jᵀ + (max(1, ℓ, ℓJ) − 1) J P Jᵀ,
/// P = D Dᵀ + b C_fit, C_fit = (C − D Dᵀ)/(1 + b), ℓ = tr(J C_fit Jᵀ)/m, and ℓJ =
/// (θ − μ)ᵀ W (θ − μ) where the part has the joint leverage (else 0). Returns Σ_p (mm²),
/// ℓ, and Σ_p without the pose part (the plain J C Jᵀ); [`joint_ratio`] gives ℓJ.
fn host_with_pose(
    arm: &quatarm_ref::Arm,
    u: &quatarm_ref::uncertainty::Uncertainty,
    theta: &[f64],
    temp_c: f64,
) -> (Matrix3<f64>, f64, Matrix3<f64>) {
    use armcal::uncertainty::{propagate, Budget};
    let pose = u.pose.as_ref().expect("a budget with a pose part");
    let host = Budget::from_file(u);
    let jac = propagate::jacobians(arm, 0, &host, theta, temp_c);
    let own = propagate::own_terms(&host, &host.sigma_theta(arm), &jac);
    let p = u.parameters.len();
    let j = nalgebra::DMatrix::from_fn(3, p, |a, i| jac.pi[i][a]);
    let c = u.matrix();
    let d = nalgebra::DMatrix::from_fn(p, pose.factor.len(), |i, k| pose.factor[k][i]);
    let ddt = &d * d.transpose();
    let c_fit = (&c - &ddt) / (1.0 + pose.shrink);
    let pp = &ddt + &c_fit * pose.shrink;
    let sandwich = |m: &nalgebra::DMatrix<f64>| -> Matrix3<f64> {
        let s = &j * m * j.transpose();
        Matrix3::from_fn(|a, b| s[(a, b)])
    };
    let leverage = sandwich(&c_fit).trace() / pose.leverage_mean;
    let factor = leverage.max(joint_ratio(u, theta)).max(1.0);
    let plain = own + sandwich(&c);
    (plain + sandwich(&pp) * (factor - 1.0), leverage, plain)
}

/// ℓJ = dᵀ W d, d = θ − μ to the nearest turn, of the budget's joint leverage at joint angles
/// `theta` (rad, as `Arm::counts_to_rad` gives them), written out in f64; 0 without one.
fn joint_ratio(u: &quatarm_ref::uncertainty::Uncertainty, theta: &[f64]) -> f64 {
    let Some(j) = u.pose.as_ref().and_then(|p| p.joints.as_ref()) else {
        return 0.0;
    };
    let k = j.mean.len();
    let d = nalgebra::DVector::from_fn(k, |i, _| {
        let x = theta[i] - j.mean[i];
        x - (x / std::f64::consts::TAU).round() * std::f64::consts::TAU
    });
    let w = nalgebra::DMatrix::from_row_slice(k, k, &j.weight);
    (d.transpose() * w * d)[(0, 0)]
}

/// A joint leverage for `arm`: μ at mid-turn (π, the mean of the readings [0, 2π) the tests
/// draw) but for joint 1 at 1 rad, and W = s · A Aᵀ / (k · π²/3) with A = I + a random
/// coupling (seeded), so that ℓJ of uniform readings is about `s` on average and W has every
/// off-diagonal entry.
fn joints_for(
    arm: &quatarm_ref::Arm,
    s: f64,
    seed: u64,
) -> quatarm_ref::uncertainty::JointLeverage {
    let k = arm.joints.len();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let a = nalgebra::DMatrix::from_fn(k, k, |i, j| {
        f64::from(u8::from(i == j)) + 0.3 * rng.gen_range(-1.0..1.0)
    });
    let w = &a * a.transpose() * (s / (k as f64 * std::f64::consts::PI.powi(2) / 3.0));
    let w = (&w + w.transpose()) * 0.5;
    quatarm_ref::uncertainty::JointLeverage {
        mean: (0..k)
            .map(|i| if i == 1 { 1.0 } else { std::f64::consts::PI })
            .collect(),
        weight: w.transpose().as_slice().to_vec(),
    }
}

/// What [`hub_against_pose_formula`] saw: the worst relative error of the hub's U95, the
/// leverages ℓ and ℓJ (smallest, largest), the largest change the part makes to the host's
/// U95, and the readings at which ℓJ was below 1, the largest of max(1, ℓ, ℓJ), and above 10.
#[derive(Debug, Default)]
struct PoseSeen {
    worst: f64,
    leverage: (f64, f64),
    joint: (f64, f64),
    change: f64,
    joint_below_1: usize,
    joint_largest: usize,
    joint_above_10: usize,
}

/// The hub's U95 with the budget's pose part (issue 27) against [`host_with_pose`] at 200
/// random readings, with the f32 and the fixed-point chains' frames. `None` where the hub's
/// build does not take the part (the Pico's profile, `--features quatarm/fixed-u95`: the
/// table is refused by the block's flag).
fn hub_against_pose_formula(
    arm: &quatarm_ref::Arm,
    u: &quatarm_ref::uncertainty::Uncertainty,
    seed: u64,
) -> Option<PoseSeen> {
    use quatarm::uncertainty::Uncertainty;
    use quatarm::{Fixed, F32};
    let bytes = match armcal::tablebuild::build_with(arm, Some(u)) {
        Ok(b) => b,
        Err(e) if e.to_string().contains("invalid flags") => {
            println!("this build refuses the pose part by its flag: {e}");
            return None;
        }
        Err(e) => panic!("{e}"),
    };
    let table = quatarm::Table::parse(&bytes).unwrap();
    let r = u.pose.as_ref().unwrap().factor.len();
    let pose = table.parameters().unwrap().pose();
    assert_eq!(pose.map(|p| p.count()), Some(r));
    let has_joints = u.pose.as_ref().unwrap().joints.is_some();
    // A budget with the joint leverage never builds a table without it.
    assert_eq!(pose.and_then(|p| p.joints()).is_some(), has_joints);
    let h32 = Uncertainty::<F32>::new(&table).unwrap().unwrap();
    let hfx = Uncertainty::<Fixed>::new(&table).unwrap().unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut seen = PoseSeen {
        leverage: (f64::INFINITY, 0.0),
        joint: (f64::INFINITY, 0.0),
        ..PoseSeen::default()
    };
    for _ in 0..200 {
        let counts: Vec<u32> = arm
            .joints
            .iter()
            .map(|j| rng.gen_range(0..j.encoder_counts))
            .collect();
        let temp_mc: i32 = rng.gen_range(16_000..28_000);
        let (theta, t) = (arm.counts_to_rad(&counts), f64::from(temp_mc) / 1000.0);
        let (s, l, plain) = host_with_pose(arm, u, &theta, t);
        seen.leverage = (seen.leverage.0.min(l), seen.leverage.1.max(l));
        if has_joints {
            let lj = joint_ratio(u, &theta);
            seen.joint = (seen.joint.0.min(lj), seen.joint.1.max(lj));
            seen.joint_below_1 += usize::from(lj < 1.0);
            seen.joint_largest += usize::from(lj > l.max(1.0));
            seen.joint_above_10 += usize::from(lj > 10.0);
        }
        let want_nm = u95(&s) * 1e6;
        seen.change = seen.change.max(want_nm / (u95(&plain) * 1e6) - 1.0);
        for got in [
            h32.covariance(&counts, temp_mc).unwrap().u95_nm(),
            hfx.covariance(&counts, temp_mc).unwrap().u95_nm(),
        ] {
            seen.worst = seen.worst.max((f64::from(got) / want_nm - 1.0).abs());
        }
    }
    Some(seen)
}

/// The mean of tr(J C_fit Jᵀ) (mm²) over 50 random readings of `arm` for the budget `u` with
/// its pose part: the scale that puts the readings' leverage about 1.
fn mean_fit_trace(arm: &quatarm_ref::Arm, u: &quatarm_ref::uncertainty::Uncertainty) -> f64 {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(99);
    let mut sum = 0.0;
    for _ in 0..50 {
        let counts: Vec<u32> = arm
            .joints
            .iter()
            .map(|j| rng.gen_range(0..j.encoder_counts))
            .collect();
        let (_, l, _) = host_with_pose(arm, u, &arm.counts_to_rad(&counts), 20.0);
        sum += l * u.pose.as_ref().unwrap().leverage_mean;
    }
    sum / 50.0
}

/// Issue 27: the hub streams the same U95 as the host's formula for the same table, within
/// 0.1 %, with the budget's pose part: the shipped 52-parameter budget with r = 1, 8 and 16
/// columns of D, b = 0 and b > 0, m at the readings' mean (ℓ on both sides of 1) and at a
/// twentieth of it (ℓ ≫ 1). The part must widen U95 (by 2–100 % here) for the test to test it.
#[test]
fn hub_u95_with_the_pose_part_agrees_with_the_formula() {
    let full = quatarm_ref::calfile::parse(include_str!("../../data/default-6-full.toml")).unwrap();
    let shipped = full.uncertainty.clone().unwrap();
    let mut cases = Vec::new();
    for (r, shrink, seed) in [(1usize, 0.0, 41u64), (8, 0.5, 42), (16, 0.2, 43)] {
        let mut u = shipped.clone();
        u.pose = Some(pose_for(&u, r, shrink, 1.0, seed));
        let mean = mean_fit_trace(&full.arm, &u);
        for (what, m) in [("m the mean", mean), ("m a twentieth", mean / 20.0)] {
            u.pose.as_mut().unwrap().leverage_mean = m;
            cases.push((
                format!("default-6-full, 52 parameters, r = {r}, b = {shrink}, {what}"),
                full.arm.clone(),
                u.clone(),
            ));
        }
    }
    let seen = cases.len();
    let (mut extremes, mut widest) = ((f64::INFINITY, 0.0f64), 0.0f64);
    for (k, (what, arm, u)) in cases.into_iter().enumerate() {
        let Some(PoseSeen {
            worst,
            leverage: (lo, hi),
            change,
            ..
        }) = hub_against_pose_formula(&arm, &u, 60 + k as u64)
        else {
            return;
        };
        println!(
            "{what}: worst hub U95 error {worst:.2e}, ℓ from {lo:.2} to {hi:.1}, the part widens \
             U95 by up to {:.1} %",
            100.0 * change
        );
        extremes = (extremes.0.min(lo), extremes.1.max(hi));
        widest = widest.max(change);
        assert!(worst < 1e-3, "{what}: {worst}");
        // And against what `armcal eval --uncertainty` computes for the same file (its
        // propagation of the budget with the pose part, `propagate::point`): the hub streams
        // eval's U95.
        let (eval_worst, _) = hub_against_host(&arm, &u, 80 + k as u64);
        println!("{what}: worst hub U95 error against eval's {eval_worst:.2e}");
        assert!(eval_worst < 1e-3, "{what}, against eval: {eval_worst}");
    }
    assert_eq!(seen, 6);
    assert!(widest > 0.3, "the part hardly widens U95: {widest}");
    // Both sides of ℓ = 1 were met, and leverages far above it.
    assert!(
        extremes.0 < 1.0 && extremes.1 > 10.0,
        "ℓ from {} to {}",
        extremes.0,
        extremes.1
    );
}

/// Issue 27: the hub streams the same U95 as the host's formula within 0.1 % with the
/// budget's joint leverage too, the factor max(1, ℓ, ℓJ): the shipped 52-parameter budget with
/// r = 8 and 16, W scaled so that ℓJ of the readings is about 1 (ℓJ on both sides of 1, the
/// largest of the three at some readings and not at others) and about 30 (ℓJ ≫ 1). The joint
/// leverage must change U95 against the same table without it, for the test to test it.
#[test]
fn hub_u95_with_the_joint_leverage_agrees_with_the_formula() {
    let full = quatarm_ref::calfile::parse(include_str!("../../data/default-6-full.toml")).unwrap();
    let shipped = full.uncertainty.clone().unwrap();
    let mut totals = PoseSeen::default();
    let (mut extremes, mut cases) = ((f64::INFINITY, 0.0f64), 0);
    for (r, shrink, scale, seed) in [(8usize, 0.5, 1.0, 44u64), (16, 0.2, 30.0, 45)] {
        let mut u = shipped.clone();
        u.pose = Some(pose_for(&u, r, shrink, 1.0, seed));
        let mean = mean_fit_trace(&full.arm, &u);
        u.pose.as_mut().unwrap().leverage_mean = mean;
        let without = u.clone();
        u.pose.as_mut().unwrap().joints = Some(joints_for(&full.arm, scale, seed));
        let what = format!("default-6-full, r = {r}, b = {shrink}, ℓJ about {scale}");
        let Some(seen) = hub_against_pose_formula(&full.arm, &u, 70 + seed) else {
            return;
        };
        let Some(plain) = hub_against_pose_formula(&full.arm, &without, 70 + seed) else {
            return;
        };
        println!(
            "{what}: worst hub U95 error {:.2e}, ℓ from {:.2} to {:.1}, ℓJ from {:.2} to {:.1} \
             (below 1 at {}, the largest at {}, above 10 at {} of 200 readings); the pose part \
             widens U95 by up to {:.1} % with ℓJ, {:.1} % without",
            seen.worst,
            seen.leverage.0,
            seen.leverage.1,
            seen.joint.0,
            seen.joint.1,
            seen.joint_below_1,
            seen.joint_largest,
            seen.joint_above_10,
            100.0 * seen.change,
            100.0 * plain.change
        );
        assert!(seen.worst < 1e-3, "{what}: {}", seen.worst);
        // And against eval's own propagation of the same budget (`propagate::point`, which
        // applies max(1, ℓ, ℓJ) through `propagate::Leverage`): the hub streams eval's U95.
        let (eval_worst, _) = hub_against_host(&full.arm, &u, 90 + seed);
        println!("{what}: worst hub U95 error against eval's {eval_worst:.2e}");
        assert!(eval_worst < 1e-3, "{what}: against eval {eval_worst}");
        assert!(
            seen.change > plain.change * 1.1,
            "{what}: ℓJ hardly changes U95 ({} against {})",
            seen.change,
            plain.change
        );
        extremes = (extremes.0.min(seen.joint.0), extremes.1.max(seen.joint.1));
        totals.joint_below_1 += seen.joint_below_1;
        totals.joint_largest += seen.joint_largest;
        totals.joint_above_10 += seen.joint_above_10;
        cases += 1;
    }
    assert_eq!(cases, 2);
    assert!(
        extremes.0 < 1.0 && extremes.1 > 10.0,
        "ℓJ from {extremes:?}"
    );
    // ℓJ below 1, the largest of the three, and not the largest, each at some readings.
    assert!(totals.joint_below_1 > 0, "{totals:?}");
    assert!(totals.joint_largest > 0, "{totals:?}");
    assert!(totals.joint_largest < 400, "{totals:?}");
    assert!(totals.joint_above_10 > 0, "{totals:?}");
}
