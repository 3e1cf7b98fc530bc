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

/// The hub's Σ_p of the reading's own terms (its chain differenced, in f32 and in fixed
/// point) against the host's first order (analytic J_θ, f64) on the shipped budget, at
/// random readings: U95 within 1 %.
#[test]
fn hub_own_terms_agree_with_the_host() {
    use armcal::uncertainty::{propagate, Budget};
    use quatarm::uncertainty::Uncertainty;
    use quatarm::{Chain, Fixed, F32};
    let text = include_str!("../../data/default-6-full.toml");
    let parsed = quatarm_ref::calfile::parse(text).unwrap();
    let (arm, u) = (&parsed.arm, parsed.uncertainty.as_ref().unwrap());
    let bytes = armcal::tablebuild::build_with(arm, Some(u)).unwrap();
    let table = quatarm::Table::parse(&bytes).unwrap();
    let mut host = Budget::from_file(u, arm);
    host.params.clear();
    host.cov = nalgebra::DMatrix::zeros(0, 0);
    let hub = Uncertainty::new(&table).expect("the table has its budget");
    let (c32, cfx) = (
        Chain::<F32>::new(&table).unwrap(),
        Chain::<Fixed>::new(&table).unwrap(),
    );
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let mut worst: f64 = 0.0;
    for _ in 0..200 {
        let counts: Vec<u32> = arm
            .joints
            .iter()
            .map(|j| rng.gen_range(0..j.encoder_counts))
            .collect();
        let temp_mc: i32 = rng.gen_range(16_000..28_000);
        let (_, s) = propagate::point(
            arm,
            &host,
            &arm.counts_to_rad(&counts),
            f64::from(temp_mc) / 1000.0,
        );
        let want_nm = u95(&s) * 1e6;
        let p32 = c32.eval(&counts, temp_mc).unwrap();
        let pfx = cfx.eval(&counts, temp_mc).unwrap();
        for got in [
            hub.covariance(&c32, &counts, temp_mc, &p32)
                .unwrap()
                .u95_nm(),
            hub.covariance(&cfx, &counts, temp_mc, &pfx)
                .unwrap()
                .u95_nm(),
        ] {
            worst = worst.max((f64::from(got) / want_nm - 1.0).abs());
        }
    }
    println!("worst hub own-terms U95 error {worst:.2e}");
    assert!(worst < 1e-2, "{worst}");
}
