//! Prints how closely published D–H arms, evaluated with 4×4 matrices, agree with their
//! conversion into the spec model evaluated by `quatarm_ref::forward` — the figures of
//! `docs/results/dh.md`.
//!
//! ```text
//! cargo run --release -p quatarm-ref --example dh_agreement [POSES]   # default 1000000
//! ```
//!
//! Poses are uniform in [−π, π) on every joint from a fixed seed, so the output is reproducible.

use nalgebra::Vector3;
use quatarm_ref::dh::{agreement, tables, to_spec_arm, DhArm};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;

fn main() {
    let poses: usize = match std::env::args().nth(1) {
        None => 1_000_000,
        Some(s) => match s.parse() {
            Ok(n) if n > 0 => n,
            _ => {
                eprintln!("usage: dh_agreement [POSES]  (a positive integer, default 1000000)");
                std::process::exit(2);
            }
        },
    };
    let arms: Vec<(DhArm, &str)> = vec![
        (tables::ur5(Vector3::new(0.0, 0.0, 120.0)), "6 classic"),
        (
            tables::kinova_gen3(Vector3::new(3.0, -2.0, 120.0)),
            "7 classic, base Rot_x(π), θ offsets π",
        ),
        (tables::iiwa14(Vector3::new(0.0, 0.0, 40.0)), "7 modified"),
        (tables::panda(Vector3::new(0.0, 0.0, 103.4)), "7 modified"),
    ];
    println!("poses per arm: {poses} (uniform in [-pi, pi) per joint, seed 2024)");
    println!(
        "{:<14} {:<40} {:>14} {:>14} {:>14}",
        "arm", "table", "max |dp| mm", "rms |dp| mm", "max |dn|"
    );
    let mut worst: f64 = 0.0;
    for (dh, what) in &arms {
        let arm = match to_spec_arm(dh) {
            Ok(a) => a,
            Err(e) => {
                eprintln!("{}: conversion refused: {e}", dh.name);
                std::process::exit(1);
            }
        };
        let mut rng = ChaCha8Rng::seed_from_u64(2024);
        let dof = dh.dof();
        // Generated lazily, so that 10^6 poses need no 10^6-row buffer.
        let random = (0..poses).map(|_| {
            (0..dof)
                .map(|_| rng.gen_range(-PI..PI))
                .collect::<Vec<f64>>()
        });
        let s = match agreement(dh, &arm, random) {
            Ok(a) => a,
            Err(e) => {
                eprintln!("{}: {e}", dh.name);
                std::process::exit(1);
            }
        };
        worst = worst.max(s.max_position_mm);
        println!(
            "{:<14} {:<40} {:>14.3e} {:>14.3e} {:>14.3e}",
            dh.name, what, s.max_position_mm, s.rms_position_mm, s.max_direction
        );
    }
    println!("worst over all arms: {worst:.3e} mm (bound held by the tests: 1e-9 mm)");
}
