//! `armcal eval --uncertainty`: the columns `cxx,cyy,czz,cxy,cxz,cyz,U95` of every row, by
//! first-order propagation or by Monte Carlo (GUM Supplement 1) of the same budget.

use super::{montecarlo, propagate, u95, Budget};
use crate::eval::Rows;
use nalgebra::Matrix3;
use quatarm_ref::arm::Arm;

/// How Σ_p is obtained.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Method {
    /// The spec's first-order formula.
    FirstOrder,
    /// Monte Carlo draws of every input (GUM Supplement 1).
    MonteCarlo,
}

/// The header the columns add.
pub const HEADER: &str = "cxx,cyy,czz,cxy,cxz,cyz,U95";

fn line(s: &Matrix3<f64>, u: f64) -> String {
    let e = propagate::entries(s);
    format!(
        "{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.9}",
        e[0], e[1], e[2], e[3], e[4], e[5], u
    )
}

/// One line of columns per row (no leading comma). Monte Carlo: `draws` per row, the
/// generator seeded once with `seed` (the same input gives the same output).
pub fn columns(
    arm: &Arm,
    budget: &Budget,
    rows: &Rows,
    method: Method,
    draws: usize,
    seed: u64,
) -> Vec<String> {
    columns_observed(arm, budget, rows, method, draws, seed, &mut || {})
}

/// As [`columns`], calling `done` after each row (a progress counter).
pub fn columns_observed(
    arm: &Arm,
    budget: &Budget,
    rows: &Rows,
    method: Method,
    draws: usize,
    seed: u64,
    done: &mut dyn FnMut(),
) -> Vec<String> {
    let root = montecarlo::sqrt_cov(&budget.cov);
    let mut rng = crate::rng::rng(seed);
    rows.iter()
        .map(|r| {
            let th = r.reading.radians(arm);
            let (t, probe) = (r.temp_c, r.probe);
            let out = match method {
                Method::FirstOrder => {
                    let (_, s) = propagate::point(arm, probe, budget, &th, t);
                    line(&s, u95::u95(&s))
                }
                Method::MonteCarlo => {
                    let o = montecarlo::point(arm, probe, budget, &root, &th, t, draws, &mut rng);
                    line(&o.cov, o.u95)
                }
            };
            done();
            out
        })
        .collect()
}
