//! First-order propagation (GUM, JCGM 100 §5): the spec's
//!
//!   Σ_p = J_π C J_πᵀ + J_θ diag(σ_θ²) J_θᵀ + J_T σ_T² J_Tᵀ + (σ_probe² + σ_model²) I₃.
//!
//! With the budget's pose part kept apart ([`super::PoseSplit`], issue 27) the parameters'
//! term of a reading is J C Jᵀ + (max(1, ℓ, ℓJ) − 1) J P Jᵀ, ℓ = tr(J C_fit Jᵀ)/mean of the
//! same over the calibration's rows, ℓJ the joint angles' leverage when the budget has one
//! ([`Leverage`], [`widening`]): every reading's variance goes through [`point`] or
//! [`group_deviations`], so the factor is applied here once.
//!
//! J_π is [`tip_jacobian`]'s analytic columns for the budget's parameters. J_θ is analytic too:
//! a reading error moves the tip as a zero offset of the same joint does, a_k × (p − o_k)
//! (the same column; the harmonic and gravity terms change that slope by their own size,
//! ~1e-4 relative, which is neglected). J_T is a central difference of the f64 reference
//! over ±1 °C: the thermal model is linear in the temperature, so the difference is exact to
//! rounding.

use super::Budget;
use crate::fit::jacobian::tip_jacobian;
use crate::params::Param;
use nalgebra::{DMatrix, Matrix3, Vector3};
use quatarm_ref::arm::Arm;
use quatarm_ref::forward;

/// A reading's tip and its Jacobians.
#[derive(Clone, Debug)]
pub struct Jacobians {
    /// The tip (mm).
    pub p: Vector3<f64>,
    /// ∂p/∂π for each budget parameter.
    pub pi: Vec<Vector3<f64>>,
    /// ∂p/∂θ_k for each joint (mm/rad).
    pub theta: Vec<Vector3<f64>>,
    /// ∂p/∂T (mm/°C).
    pub temp: Vector3<f64>,
    /// The reading's joint angles (rad), for its joint leverage ℓJ.
    pub theta_rad: Vec<f64>,
}

/// The Jacobians at a reading (θ rad, T °C) taken with the arm's probe at index `probe`
/// (`quatarm_ref::Arm::probes` order).
pub fn jacobians(
    arm: &Arm,
    probe: usize,
    budget: &Budget,
    theta: &[f64],
    temp_c: f64,
) -> Jacobians {
    let n = arm.dof();
    let mut params: Vec<Param> = budget.params.clone();
    params.extend((0..n).map(Param::ZeroOffset));
    let mut cols = vec![Vector3::zeros(); params.len()];
    let mounted = arm
        .for_probe(probe)
        .expect("a reading's probe is one of the arm's");
    let arm = mounted.as_ref();
    let p = tip_jacobian(arm, probe, &params, theta, temp_c, &mut cols);
    let theta_cols = cols.split_off(budget.params.len());
    let h = 1.0;
    let temp = (forward::forward(arm, theta, temp_c + h).p
        - forward::forward(arm, theta, temp_c - h).p)
        / (2.0 * h);
    Jacobians {
        p,
        pi: cols,
        theta: theta_cols,
        temp,
        theta_rad: theta.to_vec(),
    }
}

/// J C Jᵀ for columns `a` and `b` (the cross-covariance of two readings when they differ).
fn sandwich(a: &[Vector3<f64>], c: &DMatrix<f64>, b: &[Vector3<f64>]) -> Matrix3<f64> {
    let mut out = Matrix3::zeros();
    for (i, ai) in a.iter().enumerate() {
        for (j, bj) in b.iter().enumerate() {
            let cij = c[(i, j)];
            if cij != 0.0 {
                out += ai * bj.transpose() * cij;
            }
        }
    }
    out
}

/// 3 × r: the columns `a` (one per parameter) times D.
fn times_factor(a: &[Vector3<f64>], d: &DMatrix<f64>) -> nalgebra::Matrix3xX<f64> {
    let mut out = nalgebra::Matrix3xX::zeros(d.ncols());
    for (i, ai) in a.iter().enumerate() {
        for k in 0..d.ncols() {
            let x = d[(i, k)];
            if x != 0.0 {
                let mut c = out.column_mut(k);
                c += ai * x;
            }
        }
    }
    out
}

/// A reading's leverage ratio ℓ = tr(J C_fit Jᵀ)/`leverage_mean` from its tip columns `tip`
/// and J cov Jᵀ `tip_cov`: C_fit = (cov − D Dᵀ)/(1 + b), so tr J C_fit Jᵀ =
/// (tr J cov Jᵀ − |J D|²)/(1 + b) and no n × n product is needed. `None` without a pose part.
pub fn leverage(budget: &Budget, tip: &[Vector3<f64>], tip_cov: &Matrix3<f64>) -> Option<f64> {
    let p = budget.pose.as_ref()?;
    let jd = times_factor(tip, &p.factor);
    let fit = (tip_cov.trace() - jd.norm_squared()).max(0.0) / (1.0 + p.shrink);
    Some(fit / p.leverage_mean)
}

/// A reading's two leverage ratios: the tip's ℓ ([`leverage`]) and the joints' ℓJ
/// ([`joint_leverage`]); each `None` where the budget has no such part.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Leverage {
    /// ℓ = tr(J C_fit Jᵀ)/mean: `None` without a pose part.
    pub tip: Option<f64>,
    /// ℓJ = (θ − μ)ᵀ W (θ − μ): `None` without the budget's joint leverage.
    pub joints: Option<f64>,
}

impl Leverage {
    /// The ratio the pose part's factor takes: max(ℓ, ℓJ) (the factor is then
    /// max(1, ℓ, ℓJ), [`super::pose::leverage_factor`]); `None` without a pose part.
    pub fn ratio(&self) -> Option<f64> {
        let l = self.tip?;
        Some(
            self.joints
                .map_or(l, |j| if j.is_finite() { l.max(j) } else { l }),
        )
    }
}

/// A reading's joint leverage ℓJ at joint angles `theta` (rad): `None` unless the budget's
/// pose part carries a [`quatarm_ref::uncertainty::JointLeverage`].
pub fn joint_leverage(budget: &Budget, theta: &[f64]) -> Option<f64> {
    let j = budget.pose.as_ref()?.joints.as_ref()?;
    Some(j.ratio(theta))
}

/// What the pose part adds to the parameters' term G cov Gᵀ = `gcg` at a reading of
/// leverage ratio `l`: (max(1, l) − 1) G P Gᵀ, with G P Gᵀ = (G D (G D)ᵀ + b G cov Gᵀ)/(1 + b).
/// G is the reading's tip columns or, for a deviation from a group's mean, J_i − J̄; `l` is
/// always the reading's own [`Leverage::ratio`], max(ℓ, ℓJ) (the tip's ℓ alone without a
/// joint leverage), the quantities the hub computes for a reading. Zero without a pose part
/// or at l ≤ 1.
pub fn widening(
    budget: &Budget,
    l: Option<f64>,
    g: &[Vector3<f64>],
    gcg: &Matrix3<f64>,
) -> Matrix3<f64> {
    let (Some(p), Some(l)) = (budget.pose.as_ref(), l) else {
        return Matrix3::zeros();
    };
    let f = super::pose::leverage_factor(l) - 1.0;
    if f <= 0.0 {
        return Matrix3::zeros();
    }
    let gd = times_factor(g, &p.factor);
    (&gd * gd.transpose() + gcg * p.shrink) * (f / (1.0 + p.shrink))
}

/// The terms of Σ_p that are the reading's own (angles, temperature, probing, model): those
/// two readings do not share.
pub fn own_terms(budget: &Budget, sigma_theta: &[f64], j: &Jacobians) -> Matrix3<f64> {
    let mut s = Matrix3::identity() * (budget.probing_mm.powi(2) + budget.model_mm.powi(2));
    for (col, sd) in j.theta.iter().zip(sigma_theta) {
        s += col * col.transpose() * (sd * sd);
    }
    s + j.temp * j.temp.transpose() * budget.temperature_c.powi(2)
}

/// Σ_p of a reading taken with the arm's probe at index `probe`, with its tip.
pub fn point(
    arm: &Arm,
    probe: usize,
    budget: &Budget,
    theta: &[f64],
    temp_c: f64,
) -> (Vector3<f64>, Matrix3<f64>) {
    let (p, s, _) = point_with_leverage(arm, probe, budget, theta, temp_c);
    (p, s)
}

/// [`point`] with the reading's leverage ratios (the tip's ℓ, `None` without a pose part;
/// the joints' ℓJ, `None` without a joint leverage): the tip, Σ_p, the ratios.
pub fn point_with_leverage(
    arm: &Arm,
    probe: usize,
    budget: &Budget,
    theta: &[f64],
    temp_c: f64,
) -> (Vector3<f64>, Matrix3<f64>, Leverage) {
    let j = jacobians(arm, probe, budget, theta, temp_c);
    let jcj = sandwich(&j.pi, &budget.cov, &j.pi);
    let l = Leverage {
        tip: leverage(budget, &j.pi, &jcj),
        joints: joint_leverage(budget, theta),
    };
    let s = jcj
        + widening(budget, l.ratio(), &j.pi, &jcj)
        + own_terms(budget, &budget.sigma_theta(arm), &j);
    (j.p, s, l)
}

/// A reading's tip leverage ratio ℓ from its Jacobians ([`leverage`]).
pub fn leverage_at(budget: &Budget, j: &Jacobians) -> Option<f64> {
    budget.pose.as_ref()?;
    leverage(budget, &j.pi, &sandwich(&j.pi, &budget.cov, &j.pi))
}

/// A reading's two leverage ratios from its Jacobians.
pub fn leverages_at(budget: &Budget, j: &Jacobians) -> Leverage {
    Leverage {
        tip: leverage_at(budget, j),
        joints: joint_leverage(budget, &j.theta_rad),
    }
}

/// The distance between two readings and its standard uncertainty: gauge-free, the
/// parameters' part through the difference of the two Jacobians (what a rigid motion of the
/// base does to both cancels), the readings' own terms independent. Both readings are of the
/// first probe (a ball bar is measured with one).
pub fn distance(arm: &Arm, budget: &Budget, a: (&[f64], f64), b: (&[f64], f64)) -> (f64, f64) {
    let ja = jacobians(arm, 0, budget, a.0, a.1);
    let jb = jacobians(arm, 0, budget, b.0, b.1);
    let d = ja.p - jb.p;
    let len = d.norm();
    let u = if len > 0.0 { d / len } else { Vector3::zeros() };
    let g: Vec<f64> = ja
        .pi
        .iter()
        .zip(&jb.pi)
        .map(|(x, y)| u.dot(&(x - y)))
        .collect();
    let gv = nalgebra::DVector::from_vec(g);
    let params = (gv.transpose() * &budget.cov * &gv)[(0, 0)];
    let st = budget.sigma_theta(arm);
    let own = own_terms(budget, &st, &ja) + own_terms(budget, &st, &jb);
    (
        len,
        (params + (u.transpose() * own * u)[(0, 0)]).max(0.0).sqrt(),
    )
}

/// The covariance of each probing's deviation from its group's centre, for the probings
/// `rows` of `data` (one `spat` point, one bar end): r_i = p_i − (1/n) Σ_j p_j. The parameters'
/// part goes through J_i − J̄ (what all the group's probings share cancels), the readings' own
/// parts as (1 − 2/n) Σ_i + (1/n²) Σ_j Σ_j. How MUKCa's authors judge a session, and what a
/// held-out group's residuals are. With a pose part, each probing's pose part is scaled by
/// its own leverage factor max(1, ℓ, ℓJ) (a variance per probing, as [`point`] gives it).
pub fn group_deviations(
    arm: &Arm,
    b: &Budget,
    data: &crate::data::Dataset,
    rows: &[usize],
) -> Vec<(usize, Matrix3<f64>)> {
    let n = rows.len() as f64;
    let st = b.sigma_theta(arm);
    let js: Vec<Jacobians> = rows
        .iter()
        .map(|&i| {
            let r = &data.rows[i];
            jacobians(
                arm,
                crate::fit::probes::index(arm, r),
                b,
                &r.theta,
                r.temp_c,
            )
        })
        .collect();
    let own: Vec<Matrix3<f64>> = js.iter().map(|j| own_terms(b, &st, j)).collect();
    let own_mean = own.iter().sum::<Matrix3<f64>>() / (n * n);
    let k = b.params.len();
    let mean_j: Vec<Vector3<f64>> = (0..k)
        .map(|c| js.iter().map(|j| j.pi[c]).sum::<Vector3<f64>>() / n)
        .collect();
    rows.iter()
        .zip(js.iter().zip(&own))
        .map(|(&i, (j, o))| {
            let g: Vec<Vector3<f64>> = j.pi.iter().zip(&mean_j).map(|(a, m)| a - m).collect();
            let gcg = sandwich(&g, &b.cov, &g);
            let widen = widening(b, leverages_at(b, j).ratio(), &g, &gcg);
            (i, o * (1.0 - 2.0 / n) + own_mean + gcg + widen)
        })
        .collect()
}

/// The six covariance entries in the output's order: cxx, cyy, czz, cxy, cxz, cyz.
pub fn entries(s: &Matrix3<f64>) -> [f64; 6] {
    [
        s[(0, 0)],
        s[(1, 1)],
        s[(2, 2)],
        s[(0, 1)],
        s[(0, 2)],
        s[(1, 2)],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::{Effect, Link, Terms};
    use quatarm_ref::arm::Harmonic;

    fn arm() -> Arm {
        let mut a = Arm::default6();
        for (k, j) in a.joints.iter_mut().enumerate() {
            j.zero_offset = 1e-3 * k as f64;
            j.tilt = [2e-4, -1e-4];
            j.thermal = 1.2e-5;
        }
        a.joints[2].harmonics.push(Harmonic {
            order: 2,
            sin: 3e-5,
            cos: 0.0,
        });
        a.probe.thermal = 2e-5;
        a
    }

    #[test]
    fn reading_and_temperature_columns_match_finite_differences() {
        let a = arm();
        let b = Budget::zero(6);
        let th = [0.3, -0.7, 1.1, 0.9, -2.0, 0.4];
        let j = jacobians(&a, 0, &b, &th, 27.0);
        for k in 0..6 {
            let h = 1e-6;
            let mut plus = th;
            let mut minus = th;
            plus[k] += h;
            minus[k] -= h;
            let fd = (forward::forward(&a, &plus, 27.0).p - forward::forward(&a, &minus, 27.0).p)
                / (2.0 * h);
            // The harmonic of joint 3 changes its slope by 2·3e-5 relative: neglected.
            assert!(
                (fd - j.theta[k]).norm() <= 1e-4 * fd.norm() + 1e-6,
                "joint {k}"
            );
        }
        let fd = (forward::forward(&a, &th, 27.5).p - forward::forward(&a, &th, 26.5).p) / 1.0;
        assert!((fd - j.temp).norm() < 1e-9);
        assert!(j.temp.norm() > 1e-3, "the thermal terms move the tip");
    }

    #[test]
    fn sigma_is_the_sum_of_the_spec_terms() {
        let a = arm();
        let params = Terms::with(&[Effect::Thermal(Link::Probe)]).params(6);
        let k = params.len();
        let mut b = Budget::zero(6);
        b.params = params;
        b.cov = DMatrix::from_fn(k, k, |i, j| if i == j { 1e-8 } else { 0.0 });
        b.encoder_counts = vec![0.3; 6];
        b.temperature_c = 0.2;
        b.probing_mm = 0.002;
        b.model_mm = 0.001;
        let th = [0.3, -0.7, 1.1, 0.9, -2.0, 0.4];
        let (_, s) = point(&a, 0, &b, &th, 25.0);
        let j = jacobians(&a, 0, &b, &th, 25.0);
        let st = b.sigma_theta(&a);
        let mut want = Matrix3::identity() * (0.002f64.powi(2) + 0.001f64.powi(2));
        want += j.temp * j.temp.transpose() * 0.04;
        for (col, sd) in j.theta.iter().zip(&st) {
            want += col * col.transpose() * (sd * sd);
        }
        for c in &j.pi {
            want += c * c.transpose() * 1e-8;
        }
        assert!((s - want).norm() < 1e-15, "{s} {want}");
        // The distance from a point to itself has only the two readings' own parts.
        let (d, ud) = distance(&a, &b, (&th, 25.0), (&th, 25.0));
        assert_eq!(d, 0.0);
        assert!(ud == 0.0);
    }

    /// Issue 27: a budget whose pose part is kept apart gives the same Σ_p (and U95) as the
    /// same covariance without it at a reading of ℓ ≤ 1, a larger one at ℓ > 1, and both
    /// match the n × n formula J cov Jᵀ + (max(1, ℓ) − 1) J P Jᵀ, ℓ = tr(J C_fit Jᵀ)/mean.
    #[test]
    fn the_pose_part_widens_only_above_the_mean_leverage() {
        use super::super::{u95, PoseSplit};
        let a = arm();
        let params = Terms::with(&[Effect::Thermal(Link::Probe)]).params(6);
        let n = params.len();
        let c_fit = DMatrix::from_fn(n, n, |i, j| {
            if i == j {
                1e-8 * (1.0 + i as f64 / n as f64)
            } else {
                2e-10
            }
        });
        let d = DMatrix::from_fn(n, 3, |i, k| 1e-5 * ((i * 7 + k * 3) % 5) as f64 - 2e-5);
        let shrink = 0.4;
        let cov = &c_fit * (1.0 + shrink) + &d * d.transpose();
        let mut plain = Budget::zero(6);
        plain.params = params;
        plain.cov = cov.clone();
        plain.encoder_counts = vec![0.3; 6];
        plain.probing_mm = 0.002;
        plain.model_mm = 0.001;
        let th = [0.3, -0.7, 1.1, 0.9, -2.0, 0.4];
        let (_, s_plain) = point(&a, 0, &plain, &th, 25.0);
        let j = jacobians(&a, 0, &plain, &th, 25.0);
        let jm = nalgebra::Matrix3xX::from_columns(&j.pi);
        let tr_fit = (&jm * &c_fit * jm.transpose()).trace();
        let split = |mean: f64| PoseSplit {
            factor: d.clone(),
            shrink,
            leverage_mean: mean,
            joints: None,
        };
        let direct = |b: &Budget| {
            let p = b.pose.as_ref().unwrap();
            assert!((p.fit_covariance(&cov) - &c_fit).norm() < 1e-12 * c_fit.norm());
            let l = tr_fit / p.leverage_mean;
            let jpj = &jm * p.matrix(&cov) * jm.transpose();
            let jcj = &jm * &cov * jm.transpose();
            let m = jcj + jpj * (l.max(1.0) - 1.0);
            let own = own_terms(b, &b.sigma_theta(&a), &j);
            (Matrix3::from_iterator(m.iter().copied()) + own, l)
        };
        for (mean, widened) in [
            (2.0 * tr_fit, false),
            (tr_fit * (1.0 + 1e-9), false),
            (tr_fit / 3.0, true),
        ] {
            let b = Budget {
                pose: Some(split(mean)),
                ..plain.clone()
            };
            let (_, s, l) = point_with_leverage(&a, 0, &b, &th, 25.0);
            let (want, l_want) = direct(&b);
            assert!(
                (l.tip.unwrap() - l_want).abs() <= 1e-12 * l_want,
                "{l:?} {l_want}"
            );
            assert!((s - want).norm() <= 1e-12 * want.norm(), "{s} {want}");
            let (u, u_plain) = (u95::u95(&s), u95::u95(&s_plain));
            if widened {
                assert!(u > u_plain * 1.01, "{u} {u_plain}");
            } else {
                assert_eq!(s, s_plain);
                assert_eq!(u, u_plain);
            }
        }
        // With a joint leverage the factor is max(1, ℓ, ℓJ): ℓJ below both leaves Σ_p as the
        // tip's ℓ made it, above them it sets the factor alone.
        let lo = tr_fit * 2.0;
        let l_tip = tr_fit / lo;
        for lj_want in [0.2, 0.4, 7.5] {
            // W = w I on the six joints, μ = 0: ℓJ = w |θ|².
            let w = lj_want / th.iter().map(|x| x * x).sum::<f64>();
            let joints = quatarm_ref::uncertainty::JointLeverage {
                mean: vec![0.0; 6],
                weight: (0..36).map(|k| if k % 7 == 0 { w } else { 0.0 }).collect(),
            };
            let b = Budget {
                pose: Some(PoseSplit {
                    joints: Some(joints),
                    ..split(lo)
                }),
                ..plain.clone()
            };
            let (_, s, l) = point_with_leverage(&a, 0, &b, &th, 25.0);
            assert!((l.joints.unwrap() - lj_want).abs() < 1e-12 * lj_want);
            assert!((l.tip.unwrap() - l_tip).abs() < 1e-12);
            assert!((l.ratio().unwrap() - lj_want.max(l_tip)).abs() < 1e-12 * lj_want);
            let jpj = &jm * PoseSplit::matrix(b.pose.as_ref().unwrap(), &cov) * jm.transpose();
            let jcj = &jm * &cov * jm.transpose();
            let m = jcj + jpj * (lj_want.max(l_tip).max(1.0) - 1.0);
            let want =
                Matrix3::from_iterator(m.iter().copied()) + own_terms(&b, &b.sigma_theta(&a), &j);
            assert!(
                (s - want).norm() <= 1e-12 * want.norm(),
                "{lj_want}: {s} {want}"
            );
            if lj_want < 1.0 {
                assert_eq!(s, s_plain, "ℓ, ℓJ ≤ 1: the budget read without the keys");
            } else {
                assert!(u95::u95(&s) > u95::u95(&s_plain) * 1.01);
            }
            // Monte Carlo's extra pose draw takes the same factor.
            let mc = crate::uncertainty::montecarlo::pose_scale_at(&b, &j);
            assert!((mc - (lj_want.max(l_tip).max(1.0) - 1.0).sqrt()).abs() < 1e-12);
        }
        // A deviation from a group's mean: its pose part scaled by its own tip's factor.
        let b = Budget {
            pose: Some(split(tr_fit / 3.0)),
            ..plain.clone()
        };
        let rows = (0..3)
            .map(|k| {
                let mut t = th.to_vec();
                t[4] += 0.2 * f64::from(k);
                crate::data::Row::point(0, t, [0.0; 3], 25.0, None)
            })
            .collect();
        let data = crate::data::Dataset::from_rows(rows, 6, true, "test").unwrap();
        let wide = group_deviations(&a, &b, &data, &[0, 1, 2]);
        let narrow = group_deviations(&a, &plain, &data, &[0, 1, 2]);
        for ((_, w), (_, n)) in wide.iter().zip(&narrow) {
            assert!(w.trace() > n.trace(), "{w} {n}");
        }
    }
}
