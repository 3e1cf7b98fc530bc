//! `armcal eval --uncertainty`: the columns `cxx,cyy,czz,cxy,cxz,cyz,U95` of every row, by
//! first-order propagation or by Monte Carlo (GUM Supplement 1) of the same budget. A budget
//! with a leverage-scaled pose part (issue 27) adds a column `leverage`, each reading's
//! ℓ ([`super::propagate::leverage`]), and one with a joint leverage a last column
//! `joint_leverage`, its ℓJ ([`super::propagate::joint_leverage`]): its pose part was
//! multiplied by max(1, ℓ, ℓJ) (max(1, ℓ) without the joint leverage).

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

/// The column a budget with a pose part adds after [`HEADER`].
pub const LEVERAGE: &str = "leverage";

/// The column a budget with a joint leverage adds after [`LEVERAGE`].
pub const JOINT_LEVERAGE: &str = "joint_leverage";

/// The columns of every row, and each row's leverage ratio (`None` without a pose part).
#[derive(Clone, Debug)]
pub struct Columns {
    /// The header's columns, then `leverage` where the budget has a pose part and
    /// `joint_leverage` where it has a joint leverage.
    pub header: String,
    /// One line per row (no leading comma).
    pub lines: Vec<String>,
    /// ℓ and ℓJ per row.
    pub leverage: Vec<propagate::Leverage>,
}

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
    columns_observed(arm, budget, rows, method, draws, seed, &mut || {}).lines
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
) -> Columns {
    let root = montecarlo::sqrt_cov(&budget.cov);
    let mut rng = crate::rng::rng(seed);
    let mut leverage = Vec::with_capacity(rows.len());
    let lines = rows
        .iter()
        .map(|r| {
            let th = r.reading.radians(arm);
            let (t, probe) = (r.temp_c, r.probe);
            let (mut out, l) = match method {
                Method::FirstOrder => {
                    let (_, s, l) = propagate::point_with_leverage(arm, probe, budget, &th, t);
                    (line(&s, u95::u95(&s)), l)
                }
                Method::MonteCarlo => {
                    let o = montecarlo::point(arm, probe, budget, &root, &th, t, draws, &mut rng);
                    let l = match budget.pose {
                        Some(_) => propagate::leverages_at(
                            budget,
                            &propagate::jacobians(arm, probe, budget, &th, t),
                        ),
                        None => propagate::Leverage::default(),
                    };
                    (line(&o.cov, o.u95), l)
                }
            };
            if let Some(x) = l.tip {
                out.push_str(&format!(",{x:.4}"));
                if let Some(j) = l.joints {
                    out.push_str(&format!(",{j:.4}"));
                }
            }
            leverage.push(l);
            done();
            out
        })
        .collect();
    let header = match &budget.pose {
        Some(p) if p.joints.is_some() => format!("{HEADER},{LEVERAGE},{JOINT_LEVERAGE}"),
        Some(_) => format!("{HEADER},{LEVERAGE}"),
        None => HEADER.to_string(),
    };
    Columns {
        header,
        lines,
        leverage,
    }
}
