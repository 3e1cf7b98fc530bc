//! Round 4 of issue 27: forms of the pose term's per-reading factor, measured nested on
//! MUKCa towards every unit in 88–99 % (`coverage` bench, `mukca-variants`, block "round
//! 4"; `docs/results/uncertainty.md`, "Round 4: panda_1 and dinova_2").
//!
//! Each training set of a unit (a pair of consecutive sessions, or all sessions but one) is
//! calibrated and validated by session once, and what every variant needs is kept per row
//! ([`Trained`]): for the training set's own held-out rows (which set κ and the isotropic
//! term τ) and for the probings of every session it did not see (which are scored). A
//! variant is then arithmetic on those rows ([`Variant`]), so dozens are compared on the same
//! fits — and the choice among them is itself scored by leaving units out
//! ([`leave_one_unit_out`]): a variant picked by looking at the per-unit table is a
//! selection on the scored sessions.
//!
//! The variants are all of the form the table could carry: a reading's covariance is
//! S_rest + m τ² g I + κ² f J P Jᵀ, with P the pose part at κ = 1, f and g factors ≥ 0 from
//! scalar leverage ratios ℓ = q/q̄ (q a trace the hub computes from the reading's Jacobian,
//! q̄ its mean over the calibration's probings, one scalar the table would carry per
//! metric).

use super::super::estimate::{self, Settings};
use super::super::misfit::{self, RowCov};
use super::super::{pose, propagate, u95, Budget};
use crate::data::Dataset;
use crate::fit::holdout::FoldFit;
use crate::mukca::{self, Unit};
use nalgebra::{DMatrix, Matrix3};
use std::collections::{BTreeMap, HashMap};

/// The leverage metrics kept per row, in this order in [`Row::q`].
pub const METRICS: [&str; 4] = [
    "C dev (tr (J−J̄) C (J−J̄)ᵀ)",
    "P dev (tr (J−J̄) P (J−J̄)ᵀ)",
    "C tip (tr J C Jᵀ)",
    "joints (Mahalanobis d² of θ in the training joint angles)",
];

/// How many metrics: the length of [`Row::q`].
pub const NQ: usize = METRICS.len();

/// One row (a probing) as every variant needs it.
#[derive(Clone, Debug)]
pub struct Row {
    /// Its session.
    pub session: i64,
    /// |r|: its distance from its socket's centre (held-out fit or the training set's fit).
    pub d: f64,
    /// What the rest of the budget predicts for it (parameters, reading, probing; no model).
    pub s: Matrix3<f64>,
    /// The factor of an isotropic term's variance in it (1 − 1/n for one of n probings).
    pub m: f64,
    /// The pose part at κ = 1.
    pub p: Matrix3<f64>,
    /// tr of the parameters' part of `s` (the rest of `s` is the reading's own terms).
    pub c_part: f64,
    /// The raw leverage traces of [`METRICS`].
    pub q: [f64; NQ],
}

impl Row {
    /// The row's leverage ratios against the normalisers `norm`.
    pub fn ratios(&self, norm: &[f64; NQ]) -> [f64; NQ] {
        std::array::from_fn(|k| ratio(self.q[k], norm[k]))
    }
}

/// q/q̄, 1 when q̄ is not a positive number (no spread to compare with).
pub fn ratio(q: f64, mean: f64) -> f64 {
    if mean > 0.0 && mean.is_finite() && q.is_finite() {
        q / mean
    } else {
        1.0
    }
}

/// One training set's fit, its own held-out rows and the rows it scores.
#[derive(Clone, Debug)]
pub struct Trained {
    /// The training sessions.
    pub sessions: Vec<i64>,
    /// Sessions whose leave-one-out fits gave the pose part.
    pub groups: usize,
    /// Its own held-out rows (each against the spread of the other training sessions when
    /// ≥ 3, else of both, as [`pose::estimate`]).
    pub inner: Vec<Row>,
    /// The normalisers of the inner rows' ratios: each metric's mean over them.
    pub inner_norm: [f64; NQ],
    /// The probings of the sessions it did not train on.
    pub scored: Vec<Row>,
    /// The normalisers of the scored rows' ratios: each metric's mean over the training
    /// probings (what the table would carry).
    pub norm: [f64; NQ],
}

/// A unit's training sets: every pair of consecutive sessions (cyclic; the regime where κ
/// is borrowed from the fleet) and every leave-one-session-out set (the outer folds).
#[derive(Clone, Debug)]
pub struct UnitRows {
    /// The unit.
    pub name: String,
    /// Its sessions' names.
    pub sessions: BTreeMap<i64, String>,
    /// The pair-trained sets.
    pub pairs: Vec<Trained>,
    /// The outer folds, one per held-out session.
    pub outer: Vec<Trained>,
}

/// The ends (bar ends) of a dataset: the groups whose probings share a centre.
fn ends(d: &Dataset) -> Vec<Vec<usize>> {
    d.layout().length_ends().cloned().collect()
}

/// Per row of `rows` of `data`: (row, tr of the deviation under `b`) for every end.
fn dev_traces(arm: &quatarm_ref::arm::Arm, b: &Budget, data: &Dataset) -> HashMap<usize, f64> {
    ends(data)
        .iter()
        .flat_map(|e| propagate::group_deviations(arm, b, data, e))
        .map(|(i, s)| (i, s.trace()))
        .collect()
}

/// Per row of `data`: tr J C Jᵀ at its own tip under `c_only`.
fn tip_traces(arm: &quatarm_ref::arm::Arm, c_only: &Budget, data: &Dataset) -> Vec<f64> {
    data.rows
        .iter()
        .map(|r| {
            let probe = crate::fit::probes::index(arm, r);
            propagate::point(arm, probe, c_only, &r.theta, r.temp_c)
                .1
                .trace()
        })
        .collect()
}

/// The normalisers of `rows`: each metric's mean over them, but the joints' (already a
/// ratio to its own training rows, [`joint_ratio`]) 1.
fn means(rows: &[Row]) -> [f64; NQ] {
    let n = rows.len().max(1) as f64;
    let mut m: [f64; NQ] = std::array::from_fn(|k| rows.iter().map(|r| r.q[k]).sum::<f64>() / n);
    m[3] = 1.0;
    m
}

/// The joints' leverage ratio ℓJ against the training rows `train` (the budget's
/// [`quatarm_ref::uncertainty::JointLeverage`], estimated by
/// [`super::super::extrapolation::joint_leverage`]: its mean over them is 1). A placement
/// whose joint configuration the training did not see (a raised artefact bends shoulder and
/// elbow otherwise) has a large ratio whatever its tip's leverage. `None` when the training
/// joints have no spread to measure with.
pub fn joint_ratio(train: &Dataset) -> Option<impl Fn(&[f64]) -> f64> {
    let l = super::super::extrapolation::joint_leverage(train)?;
    Some(move |theta: &[f64]| l.ratio(theta))
}

/// A [`joint_ratio`] kept per group.
type JointRatio = Box<dyn Fn(&[f64]) -> f64>;

/// Calibrates `unit` on `train` and keeps what every variant needs (see [`Trained`]).
/// `None` when the fit or its validation by session fails.
pub fn train(unit: &Unit, train: &[i64]) -> Option<Trained> {
    let data = unit.sessions_data(train);
    let opts = mukca::options(None);
    let fit = crate::fit::calib::calibrate(&unit.arm, &data, &opts).ok()?;
    let h = crate::fit::holdout::validate(
        &unit.arm,
        &data,
        &opts,
        &crate::fit::holdout::by_group(&data),
    );
    if h.fits.len() < 2 {
        return None;
    }
    let no_model = Settings {
        model_mm: Some(0.0),
        ..Settings::default()
    };
    // The nested budget without its model term: C inflated by the held-out excess, as
    // `calibrate --by-group` writes it before the pose part is added.
    let rest = estimate::from_fit(&fit, &data, Some(&h), 0.0, &no_model)
        .ok()?
        .budget;
    let (params, c) = (&rest.params, &rest.cov);
    let arm = &fit.arm;
    let all: Vec<&FoldFit> = h.fits.iter().collect();
    let g = all.len();
    let gf = g as f64;
    let p_all = pose::between(params, &all, g, c) * (1.0 + 1.0 / gf);
    let c_only = Budget::of_parameters(params, c.clone(), data.dof);
    let p_only = Budget::of_parameters(params, p_all.clone(), data.dof);
    // Normalisers over the training probings, each row against the training fit.
    let (tc, tp, tt) = (
        dev_traces(arm, &c_only, &data),
        dev_traces(arm, &p_only, &data),
        tip_traces(arm, &c_only, &data),
    );
    let nt = tc.len().max(1) as f64;
    let norm = [
        tc.values().sum::<f64>() / nt,
        tp.values().sum::<f64>() / nt,
        tc.keys().map(|&i| tt[i]).sum::<f64>() / nt,
        1.0,
    ];
    let jr = joint_ratio(&data);
    let inner = inner_rows(arm, params, c, &data, &h, &all, &rest);
    let inner_norm = means(&inner);
    let mut scored = Vec::new();
    for s in unit.groups().into_iter().filter(|s| !train.contains(s)) {
        let test = unit.sessions_data(&[s]);
        let res = crate::fit::residuals::residuals(arm, &test, None);
        let tip = tip_traces(arm, &c_only, &test);
        for e in ends(&test) {
            let m = 1.0 - 1.0 / e.len() as f64;
            let r = propagate::group_deviations(arm, &rest, &test, &e);
            let p = propagate::group_deviations(arm, &p_only, &test, &e);
            let cc = propagate::group_deviations(arm, &c_only, &test, &e);
            for ((i, s_i), ((_, p_i), (_, c_i))) in r.into_iter().zip(p.into_iter().zip(cc)) {
                scored.push(Row {
                    session: s,
                    d: res.rows[i].norm(),
                    s: s_i,
                    m,
                    p: p_i,
                    c_part: c_i.trace(),
                    q: [
                        c_i.trace(),
                        p_i.trace(),
                        tip[i],
                        jr.as_ref().map_or(1.0, |f| f(&test.rows[i].theta)),
                    ],
                });
            }
        }
    }
    Some(Trained {
        sessions: train.to_vec(),
        groups: g,
        inner,
        inner_norm,
        scored,
        norm,
    })
}

/// The training set's own held-out rows as [`pose::estimate`] scores them: the rest of the
/// budget with C × F/(F − 1), each row's pose part from the spread of the other groups
/// (G ≥ 3) or of both (G = 2) times 1 + 1/(G − 1).
fn inner_rows(
    arm: &quatarm_ref::arm::Arm,
    params: &[crate::params::Param],
    c: &DMatrix<f64>,
    data: &Dataset,
    h: &crate::fit::holdout::Holdout,
    all: &[&FoldFit],
    rest: &Budget,
) -> Vec<Row> {
    let g = all.len();
    let mut b = rest.clone();
    let f = h.folds as f64;
    if f > 1.0 {
        b.cov *= f / (f - 1.0);
    }
    let rows = misfit::row_covariances(arm, &b, data, &h.judged, 0.0);
    let res = misfit::without_frame(data, h);
    let sb = pose::between(params, all, g, c);
    let mut extra: HashMap<usize, Matrix3<f64>> = HashMap::new();
    for (k, fit) in all.iter().enumerate() {
        let cov = if g >= 3 {
            let others: Vec<&FoldFit> = (0..g).filter(|&o| o != k).map(|o| all[o]).collect();
            pose::between(params, &others, g, c)
        } else {
            sb.clone()
        } * (1.0 + 1.0 / (g as f64 - 1.0));
        let Some(group) = fit.rows.first().map(|&i| data.rows[i].group) else {
            continue;
        };
        let po = Budget::of_parameters(params, cov, data.dof);
        for e in ends(data)
            .into_iter()
            .filter(|e| e.first().is_some_and(|&i| data.rows[i].group == group))
        {
            extra.extend(propagate::group_deviations(arm, &po, data, &e));
        }
    }
    let c_only = Budget::of_parameters(params, c.clone(), data.dof);
    let cdev = dev_traces(arm, &c_only, data);
    let tip = tip_traces(arm, &c_only, data);
    // The joints' ratio of a held-out row against the *other* groups' joint angles: what a
    // fit without its group saw.
    let mut joints: HashMap<i64, Option<JointRatio>> = HashMap::new();
    rows.into_iter()
        .map(|r| {
            let group = data.rows[r.row].group;
            let jr = joints.entry(group).or_insert_with(|| {
                super::super::extrapolation::joint_leverage_without(data, group)
                    .map(|l| Box::new(move |t: &[f64]| l.ratio(t)) as JointRatio)
            });
            let lj = jr.as_ref().map_or(1.0, |f| f(&data.rows[r.row].theta));
            let p = extra.get(&r.row).copied().unwrap_or_else(Matrix3::zeros);
            let cp = cdev.get(&r.row).copied().unwrap_or(0.0);
            Row {
                session: data.rows[r.row].group,
                d: res[r.row].norm(),
                s: r.s,
                m: r.m,
                p,
                c_part: cp,
                q: [cp, p.trace(), tip[r.row], lj],
            }
        })
        .collect()
}

/// Every training set of a unit with ≥ 3 sessions (a 3-session unit's pairs are its outer
/// folds: fitted once). `None` with fewer sessions.
pub fn unit_rows(unit: &Unit) -> Option<UnitRows> {
    let groups = unit.groups();
    let n = groups.len();
    if n < 3 {
        return None;
    }
    let mut memo: BTreeMap<Vec<i64>, Option<Trained>> = BTreeMap::new();
    let mut get = |mut set: Vec<i64>| {
        set.sort_unstable();
        memo.entry(set.clone())
            .or_insert_with(|| train(unit, &set))
            .clone()
    };
    let pairs = (0..n)
        .filter_map(|k| get(vec![groups[k], groups[(k + 1) % n]]))
        .collect();
    let outer = groups
        .iter()
        .filter_map(|&g| get(groups.iter().copied().filter(|&x| x != g).collect()))
        .collect();
    Some(UnitRows {
        name: unit.name.clone(),
        sessions: unit.sessions.clone(),
        pairs,
        outer,
    })
}

/// How a reading's leverage ratios ℓ = [C dev, P dev, C tip, joints] (see [`METRICS`])
/// become the factor of the pose part.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Factor {
    /// 1: the product's budget today.
    One,
    /// max(1, ℓ_k): one metric, floored (only widens).
    Floored(usize),
    /// max(1, √(ℓ_a ℓ_b)): the geometric mean of two metrics, floored.
    Mix(usize, usize),
    /// max(1, ℓ_a, ℓ_b): the larger of two, floored.
    Larger(usize, usize),
    /// ℓ_k itself: also narrows the term at placements the calibration saw well.
    Raw(usize),
    /// max(1, √ℓ_k): a distance's ratio rather than a squared one.
    Root(usize),
}

impl Factor {
    /// The factor at ratios `l`; 1 where it is not a finite non-negative number.
    pub fn at(&self, l: &[f64; NQ]) -> f64 {
        let f = match *self {
            Factor::One => 1.0,
            Factor::Floored(k) => l[k].max(1.0),
            Factor::Mix(a, b) => (l[a] * l[b]).max(0.0).sqrt().max(1.0),
            Factor::Larger(a, b) => l[a].max(l[b]).max(1.0),
            Factor::Raw(k) => l[k],
            Factor::Root(k) => l[k].max(0.0).sqrt().max(1.0),
        };
        if f.is_finite() && f >= 0.0 {
            f
        } else {
            1.0
        }
    }

    /// Its name in the tables.
    pub fn name(&self) -> String {
        let m = |k: usize| ["ℓC", "ℓP", "ℓT", "ℓJ"][k];
        match *self {
            Factor::One => "1 (product)".into(),
            Factor::Floored(k) => format!("max(1, {})", m(k)),
            Factor::Mix(a, b) => format!("max(1, √({}·{}))", m(a), m(b)),
            Factor::Larger(a, b) => format!("max(1, {}, {})", m(a), m(b)),
            Factor::Raw(k) => format!("{} (unfloored)", m(k)),
            Factor::Root(k) => format!("max(1, √{})", m(k)),
        }
    }
}

/// Student's t at 97.5 % for ν = 1…8 degrees of freedom.
const T975: [f64; 8] = [12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306];

/// The few-groups correction of a κ validated with G training groups: the validation scored
/// each group against a spread of G − 1 groups (ν = G − 2), the budget's spread has G
/// (ν = G − 1); a Student-t factor on σ shrinks by t(ν = G − 1)/t(ν = G − 2). 1 where κ
/// was not validated (G < 3) or ν is beyond the table (t within 1 % of its limit).
pub fn t_ratio(groups: usize) -> f64 {
    if groups < 3 {
        return 1.0;
    }
    match (T975.get(groups - 2), T975.get(groups - 3)) {
        (Some(a), Some(b)) => a / b,
        _ => 1.0,
    }
}

/// A variant of the nested budget.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Variant {
    /// The pose part's factor per reading.
    pub factor: Factor,
    /// The isotropic term τ² scaled by the same factor (set on the scaled scores).
    pub iso_scaled: bool,
    /// A validated κ times [`t_ratio`].
    pub t_corrected: bool,
}

impl Variant {
    /// Its name in the tables.
    pub fn name(&self) -> String {
        format!(
            "{}{}{}",
            self.factor.name(),
            if self.iso_scaled { ", τ² × f" } else { "" },
            if self.t_corrected {
                ", κ × t-ratio"
            } else {
                ""
            }
        )
    }
}

/// Each row's least covering κ with the pose part times its factor (rest of the budget
/// without model term).
fn least(rows: &[Row], norm: &[f64; NQ], factor: Factor) -> Vec<f64> {
    let rc: Vec<RowCov> = rows
        .iter()
        .map(|r| RowCov {
            row: 0,
            s: r.s,
            m: r.m,
        })
        .collect();
    let extra: Vec<Matrix3<f64>> = rows
        .iter()
        .map(|r| r.p * factor.at(&r.ratios(norm)))
        .collect();
    let d: Vec<f64> = rows.iter().map(|r| r.d).collect();
    pose::least_scales(&rc, &extra, &d)
}

/// A unit's two-session κ under a factor: the conformal κ of its pair-trained scores.
pub fn two_session_kappa(u: &UnitRows, factor: Factor) -> f64 {
    let t: Vec<f64> = u
        .pairs
        .iter()
        .flat_map(|p| least(&p.scored, &p.norm, factor))
        .collect();
    pose::conformal_scale(t)
}

/// What a factor gives before κ is corrected or τ set, for every unit: its two-session κ
/// (for the fleet) and, per outer fold, the κ validated on its training sessions (0 where
/// they are 2: not validated). The expensive part (a bisection per row), shared by the
/// variants with the same factor.
#[derive(Clone, Debug)]
pub struct FactorKappas {
    /// The factor.
    pub factor: Factor,
    /// Per unit, its two-session κ.
    pub two_session: Vec<f64>,
    /// Per unit, per outer fold, the validated κ.
    pub validated: Vec<Vec<f64>>,
}

impl FactorKappas {
    /// The κ of `units` under `factor`.
    pub fn of(units: &[UnitRows], factor: Factor) -> FactorKappas {
        FactorKappas {
            factor,
            two_session: units.iter().map(|u| two_session_kappa(u, factor)).collect(),
            validated: units
                .iter()
                .map(|u| {
                    u.outer
                        .iter()
                        .map(|t| {
                            if t.groups >= 3 {
                                pose::conformal_scale(least(&t.inner, &t.inner_norm, factor))
                            } else {
                                0.0
                            }
                        })
                        .collect()
                })
                .collect(),
        }
    }

    /// Unit k's fleet κ: the median of the other units' two-session κ.
    pub fn fleet(&self, k: usize) -> f64 {
        let others: Vec<f64> = self
            .two_session
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != k)
            .map(|(_, x)| *x)
            .collect();
        super::fleet_scale(&others)
    }
}

/// What one outer fold gave: (κ, τ, per scored row (covered, U95, its covariance's traces
/// [parameters, own terms, pose, isotropic])).
#[derive(Clone, Debug)]
pub struct Judged {
    /// The held-out session.
    pub session: i64,
    /// κ used.
    pub kappa: f64,
    /// Whether κ was validated on the training sessions (else the fleet's).
    pub validated: bool,
    /// The isotropic term (mm per axis).
    pub tau: f64,
    /// Per scored probing: (covered, U95 mm, [tr parameters, tr own, tr pose, tr isotropic]).
    pub rows: Vec<(bool, f64, [f64; 4])>,
}

/// One outer fold judged under `v`: `own` the κ validated on its training sessions (used
/// with ≥ 3 of them), `fleet` the κ where two training sessions cannot set it (the median of
/// the other units' [`two_session_kappa`] under the same factor).
pub fn judge(t: &Trained, v: &Variant, own: f64, fleet: f64) -> Judged {
    let validated = t.groups >= 3;
    let kappa = if validated {
        own * if v.t_corrected {
            t_ratio(t.groups)
        } else {
            1.0
        }
    } else {
        fleet
    };
    let k2 = kappa * kappa;
    // τ: split conformal on the inner rows with the scaled pose part at κ.
    let scores: Vec<misfit::Score> = t
        .inner
        .iter()
        .map(|r| {
            let f = v.factor.at(&r.ratios(&t.inner_norm));
            misfit::Score {
                deviation: r.d,
                lambda: u95::eigenvalues(&(r.s + r.p * (k2 * f))),
                m: r.m * if v.iso_scaled { f } else { 1.0 },
            }
        })
        .collect();
    let tau = misfit::conformal(&scores, u95::LEVEL).map_or(0.0, |c| c.0);
    let rows = t
        .scored
        .iter()
        .map(|r| {
            let f = v.factor.at(&r.ratios(&t.norm));
            let iso = r.m * tau * tau * if v.iso_scaled { f } else { 1.0 };
            let pose = r.p * (k2 * f);
            let u = u95::u95(&(r.s + pose + Matrix3::identity() * iso));
            let traces = [r.c_part, r.s.trace() - r.c_part, pose.trace(), 3.0 * iso];
            (r.d <= u, u, traces)
        })
        .collect();
    Judged {
        session: t.scored.first().map_or(-1, |r| r.session),
        kappa,
        validated,
        tau,
        rows,
    }
}

/// A unit's nested figures under one variant.
#[derive(Clone, Debug)]
pub struct UnitResult {
    /// Coverage over its scored probings.
    pub covered: f64,
    /// Probings scored.
    pub probings: usize,
    /// Median U95 (mm).
    pub median_u95: f64,
    /// The folds.
    pub folds: Vec<Judged>,
}

/// Every unit under `v`, whose factor's κ are `fk` ([`FactorKappas::of`] with `v.factor`).
pub fn nested(units: &[UnitRows], v: &Variant, fk: &FactorKappas) -> Vec<UnitResult> {
    units
        .iter()
        .enumerate()
        .map(|(k, u)| {
            let fleet = fk.fleet(k);
            let folds: Vec<Judged> = u
                .outer
                .iter()
                .zip(&fk.validated[k])
                .map(|(t, own)| judge(t, v, *own, fleet))
                .collect();
            let all: Vec<&(bool, f64, [f64; 4])> = folds.iter().flat_map(|j| &j.rows).collect();
            let mut us: Vec<f64> = all.iter().map(|r| r.1).collect();
            us.sort_by(f64::total_cmp);
            UnitResult {
                covered: all.iter().filter(|r| r.0).count() as f64 / all.len().max(1) as f64,
                probings: all.len(),
                median_u95: us.get(us.len() / 2).copied().unwrap_or(f64::NAN),
                folds,
            }
        })
        .collect()
}

/// The target band of each unit's coverage.
pub const BAND: (f64, f64) = (0.88, 0.99);

/// How a variant's per-unit coverages rank when chosen: (units in the band, −|pooled −
/// 0.95|), larger is better. Pooled weights units by probings.
pub fn merit(cov: &[(f64, usize)]) -> (usize, f64) {
    let inside = cov
        .iter()
        .filter(|(c, _)| (BAND.0..=BAND.1).contains(c))
        .count();
    let n: usize = cov.iter().map(|c| c.1).sum();
    let pooled = cov.iter().map(|(c, p)| c * *p as f64).sum::<f64>() / n.max(1) as f64;
    (inside, -(pooled - 0.95).abs())
}

/// The choice among variants scored by leaving units out: for each unit k, the variant
/// with the best [`merit`] on the *other* units (`table[v][u]` = (coverage, probings) of
/// unit u under variant v; ties to the earlier variant), and unit k's coverage under it.
pub fn leave_one_unit_out(table: &[Vec<(f64, usize)>]) -> Vec<(usize, f64)> {
    let units = table.first().map_or(0, Vec::len);
    (0..units)
        .map(|k| {
            let best = (0..table.len())
                .map(|v| {
                    let others: Vec<(f64, usize)> = table[v]
                        .iter()
                        .enumerate()
                        .filter(|(j, _)| *j != k)
                        .map(|(_, c)| *c)
                        .collect();
                    (v, merit(&others))
                })
                .fold(None::<(usize, (usize, f64))>, |acc, (v, m)| match acc {
                    Some((_, b)) if b.0 > m.0 || (b.0 == m.0 && b.1 >= m.1) => acc,
                    _ => Some((v, m)),
                })
                .map_or(0, |b| b.0);
            (best, table[best][k].0)
        })
        .collect()
}

/// The 95 % Wilson score interval of `k` covered of `n`, as if the probings were
/// independent. They are not (a session's probings share its placement), so this is the
/// narrowest honest reading of a unit's figure; [`session_bootstrap`] is the pooled one's.
pub fn wilson(k: usize, n: usize) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let (z, nf) = (1.959_963_985, n as f64);
    let p = k as f64 / nf;
    let d = 1.0 + z * z / nf;
    let c = (p + z * z / (2.0 * nf)) / d;
    let h = z * (p * (1.0 - p) / nf + z * z / (4.0 * nf * nf)).sqrt() / d;
    ((c - h).max(0.0), (c + h).min(1.0))
}

/// A 95 % interval of a pooled coverage with whole sessions resampled (percentile bootstrap,
/// `draws` resamples from `seed`): `sessions` are (covered, probings) per session, the unit
/// that is exchangeable. (0, 1) without sessions.
pub fn session_bootstrap(sessions: &[(usize, usize)], draws: usize, seed: u64) -> (f64, f64) {
    if sessions.is_empty() || draws == 0 {
        return (0.0, 1.0);
    }
    let mut rng = crate::rng::rng(seed);
    let mut v: Vec<f64> = (0..draws)
        .map(|_| drawn_coverage(&mut rng, sessions, sessions.len()))
        .collect();
    v.sort_by(f64::total_cmp);
    let at = |q: f64| v[((q * draws as f64) as usize).min(draws - 1)];
    (at(0.025), at(0.975))
}

/// The pooled coverage of `count` sessions drawn with replacement from `pool` (covered,
/// probings): one draw of [`session_bootstrap`] and [`band_chance`]. `pool` not empty.
fn drawn_coverage(rng: &mut crate::rng::SimRng, pool: &[(usize, usize)], count: usize) -> f64 {
    use rand::Rng;
    let (mut k, mut n) = (0usize, 0usize);
    for _ in 0..count {
        let s = pool[rng.gen_range(0..pool.len())];
        k += s.0;
        n += s.1;
    }
    k as f64 / n.max(1) as f64
}

/// How often units with a unit's few sessions land in a coverage band by the sessions they
/// happen to have, if each unit's held-out sessions were like the fleet's
/// ([`band_chance`]).
#[derive(Clone, Debug, PartialEq)]
pub struct BandChance {
    /// Per unit, the share of draws whose coverage is in the band.
    pub per_unit: Vec<f64>,
    /// The mean number of units in the band per draw.
    pub mean_in_band: f64,
    /// The share of draws with every unit in the band.
    pub all_in_band: f64,
    /// The share of draws with at most `observed` units in the band.
    pub at_most_observed: f64,
}

/// Each unit's coverage if its sessions were drawn from the *other* units' held-out
/// sessions: per draw, unit u gets as many sessions as it has (`units[u]`, each (covered,
/// probings)), drawn with replacement from every other unit's, and is in the band where its
/// pooled coverage is within `band` (inclusive). `draws` draws from `seed`; `observed` the
/// units in the band on the data. It asks what the per-unit band can show with 3–4 sessions a
/// unit when sessions are covered nearly whole or not at all: a unit's figure is then mostly
/// which sessions it happened to have. A unit whose others have no sessions is never in the
/// band.
pub fn band_chance(
    units: &[Vec<(usize, usize)>],
    band: (f64, f64),
    observed: usize,
    draws: usize,
    seed: u64,
) -> BandChance {
    let mut rng = crate::rng::rng(seed);
    let mut hits = vec![0usize; units.len()];
    let (mut total, mut all, mut at_most) = (0usize, 0usize, 0usize);
    let pools: Vec<Vec<(usize, usize)>> = (0..units.len())
        .map(|u| {
            units
                .iter()
                .enumerate()
                .filter(|(o, _)| *o != u)
                .flat_map(|(_, s)| s.iter().copied())
                .collect()
        })
        .collect();
    for _ in 0..draws {
        let mut inside = 0usize;
        for (u, own) in units.iter().enumerate() {
            let pool = &pools[u];
            if pool.is_empty() || own.is_empty() {
                continue;
            }
            let f = drawn_coverage(&mut rng, pool, own.len());
            if f >= band.0 && f <= band.1 {
                hits[u] += 1;
                inside += 1;
            }
        }
        total += inside;
        all += usize::from(inside == units.len());
        at_most += usize::from(inside <= observed);
    }
    let share = |c: usize| c as f64 / draws.max(1) as f64;
    BandChance {
        per_unit: hits.into_iter().map(share).collect(),
        mean_in_band: share(total),
        all_in_band: share(all),
        at_most_observed: share(at_most),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each factor as its formula; a ratio that is not a number leaves the term as it is.
    #[test]
    fn the_factors_are_their_formulas() {
        let l = [4.0, 0.25, 9.0, 16.0];
        assert_eq!(Factor::One.at(&l), 1.0);
        assert_eq!(Factor::Floored(0).at(&l), 4.0);
        assert_eq!(Factor::Floored(1).at(&l), 1.0);
        assert_eq!(Factor::Mix(0, 1).at(&l), 1.0);
        assert_eq!(Factor::Mix(0, 2).at(&l), 6.0);
        assert_eq!(Factor::Larger(1, 2).at(&l), 9.0);
        assert_eq!(Factor::Raw(1).at(&l), 0.25);
        assert_eq!(Factor::Root(3).at(&l), 4.0);
        // Round 4's candidate: the larger of the C leverage and the joints' ratio.
        assert_eq!(Factor::Larger(0, 3).at(&l), 16.0);
        assert_eq!(Factor::Larger(0, 3).at(&[4.0, 1.0, 1.0, 0.5]), 4.0);
        assert_eq!(Factor::Larger(0, 3).at(&[0.2, 1.0, 1.0, 0.5]), 1.0);
        assert_eq!(Factor::Root(1).at(&l), 1.0);
        assert_eq!(Factor::Raw(0).at(&[f64::NAN, 1.0, 1.0, 1.0]), 1.0);
        assert_eq!(ratio(2.0, 0.0), 1.0);
        assert_eq!(ratio(2.0, 4.0), 0.5);
    }

    /// The joints' ratio is 1 on average over the training rows and grows with a
    /// configuration they did not see; none without spread.
    #[test]
    fn the_joint_ratio_is_one_on_the_training_rows_on_average() {
        let row = |a: f64, b: f64| crate::data::Row::point(0, vec![a, b], [0.0; 3], 20.0, None);
        let rows: Vec<crate::data::Row> = (0..20)
            .map(|k| {
                let t = f64::from(k) * 0.3;
                row(t.sin() * 0.2, (2.0 * t).cos() * 0.1)
            })
            .collect();
        let data = Dataset {
            rows,
            dof: 2,
            has_temperature: false,
            warnings: vec![],
            source: "test".into(),
        };
        let f = joint_ratio(&data).expect("spread");
        let mean = data.rows.iter().map(|r| f(&r.theta)).sum::<f64>() / 20.0;
        assert!((mean - 1.0).abs() < 1e-9, "{mean}");
        // Its normaliser is k (n − 1)/n for k moving joints and n rows (the sample
        // covariance's identity): a table needs n, not another mean.
        let sup = crate::uncertainty::extrapolation::JointSupport::of(&data).expect("spread");
        let th = [0.3, -0.2];
        let d2 = sup.distance(&th).powi(2);
        assert!((f(&th) - d2 * 20.0 / (2.0 * 19.0)).abs() < 1e-9 * f(&th));
        assert!(f(&[1.0, 1.0]) > 10.0);
        let still = Dataset {
            rows: vec![row(0.1, 0.2); 5],
            ..data.clone()
        };
        assert!(joint_ratio(&still).is_none());
    }

    /// The intervals hold their point and widen with fewer probings or sessions.
    #[test]
    fn the_intervals_hold_the_figure_and_widen_with_less_data() {
        let (lo, hi) = wilson(90, 100);
        assert!(lo < 0.9 && hi > 0.9 && lo > 0.8 && hi < 0.96, "{lo} {hi}");
        let (a, b) = wilson(900, 1000);
        assert!(b - a < hi - lo);
        assert_eq!(wilson(0, 0), (0.0, 1.0));
        let same = [(50, 60); 8];
        assert_eq!(session_bootstrap(&same, 200, 1), (50.0 / 60.0, 50.0 / 60.0));
        let mixed = [(60, 60), (60, 60), (30, 60), (58, 60)];
        let (lo, hi) = session_bootstrap(&mixed, 2000, 1);
        assert!(
            lo < 208.0 / 240.0 && hi > 208.0 / 240.0 && hi <= 1.0,
            "{lo} {hi}"
        );
    }

    /// Sessions covered at 95 % put every unit in the band; sessions covered whole or not at
    /// all never put a 3-session unit there (its coverage is 0, ⅓, ⅔ or 1).
    #[test]
    fn the_band_chance_follows_the_sessions_spread() {
        let even = vec![vec![(57, 60); 3]; 4];
        let c = band_chance(&even, (0.88, 0.99), 4, 500, 3);
        assert_eq!(c.per_unit, vec![1.0; 4]);
        assert_eq!(
            (c.mean_in_band, c.all_in_band, c.at_most_observed),
            (4.0, 1.0, 1.0)
        );
        let whole = vec![vec![(60, 60), (60, 60), (0, 60)]; 4];
        let c = band_chance(&whole, (0.88, 0.99), 0, 500, 3);
        assert_eq!(
            (c.mean_in_band, c.all_in_band, c.at_most_observed),
            (0.0, 0.0, 1.0)
        );
        // Mixed: the others' 57/60 sessions put a unit in the band unless it draws a 0/60.
        let mixed = vec![
            vec![(57, 60), (57, 60), (57, 60), (0, 60)],
            vec![(57, 60); 4],
        ];
        let c = band_chance(&mixed, (0.88, 0.99), 1, 4000, 5);
        assert_eq!(c.per_unit[0], 1.0);
        // Unit 1 draws from unit 0's: all four from the three 57s, (3/4)^4 = 0.316.
        assert!((c.per_unit[1] - 0.316).abs() < 0.03, "{:?}", c.per_unit);
        assert!((c.all_in_band - c.per_unit[1]).abs() < 1e-12);
    }

    /// The t-ratio shrinks a κ validated on spreads with one group fewer, most with few
    /// groups, and leaves an unvalidated κ alone.
    #[test]
    fn the_t_ratio_is_one_group_more_over_the_validations() {
        assert_eq!(t_ratio(2), 1.0);
        assert!((t_ratio(3) - 4.303 / 12.706).abs() < 1e-12);
        assert!((t_ratio(4) - 3.182 / 4.303).abs() < 1e-12);
        assert!(t_ratio(5) > t_ratio(4) && t_ratio(9) < 1.0 && t_ratio(9) > 0.97);
        assert_eq!(t_ratio(11), 1.0);
    }

    /// A variant chosen on the other units: unit 0 is judged by the choice the others make,
    /// not by its own best.
    #[test]
    fn the_choice_is_made_without_the_unit_it_scores() {
        // Variant 0 puts units 1, 2 in the band and unit 0 out; variant 1 unit 0 only.
        let table = vec![
            vec![(0.80, 100), (0.95, 100), (0.95, 100)],
            vec![(0.95, 100), (0.80, 100), (0.999, 100)],
        ];
        let c = leave_one_unit_out(&table);
        assert_eq!(c[0], (0, 0.80));
        // Without unit 1: variant 0 has unit 2 in (1), variant 1 unit 0 (1); pooled 0.875
        // vs 0.9745: variant 1.
        assert_eq!(c[1], (1, 0.80));
        assert_eq!(merit(&[(0.9, 1), (1.0, 1)]).0, 1);
    }
}
