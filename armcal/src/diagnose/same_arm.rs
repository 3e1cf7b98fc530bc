//! Which recordings of a fleet are of one physical arm, so that the fleet test
//! ([`super::fleet`]) counts arms and not files.
//!
//! A fleet's random-effects pooling treats its units as independent draws from the design. Two
//! recordings of one arm (MUKCa's panda_3 recorded again as panda_3_bis and as
//! panda_right) are not: they share the arm's geometry and its single-unit causes, so counting
//! them twice lets one arm's effect pass for the design's, and shrinks the between-unit spread
//! τ² it should inflate.
//!
//! **What the data say.** Each recording's geometric model is fitted on its own sessions
//! ([`super::fleet::geometric`], the fit the fleet makes anyway), and its identified unknowns
//! come with their covariance C, σ̂² (JᵀJ)⁻¹ marginal over the instrument frame and the `spat`
//! points, inflated by the held-out excess when the recording has two sessions or more
//! ([`crate::uncertainty::estimate::parameters`], the calibration's own budget). Two
//! recordings of one arm estimate the same geometric errors from independent readings, so
//! their difference d has mean 0 and covariance C_A + C_B, and
//!
//! χ² = dᵀ (C_A + C_B)⁻¹ d  ~  χ²_k   (k the unknowns compared)
//!
//! if the covariances were honest. They are not quite: the rows of one session share the
//! unmodelled part of the arm's error (MUKCa's Pandas leave 0.2–0.5 mm), so σ̂² (JᵀJ)⁻¹
//! understates the scatter of a recording's estimate. That excess is measured on the data,
//! with no recording's identity assumed: every recording of two sessions or more is split
//! into two halves (alternate sessions, [`halves`]), two readings of one arm as mounted, and
//! their χ² pooled over the recordings gives φ̂ = Σ χ² / Σ k on D = Σ k degrees of freedom
//! (2.5 on 163 on MUKCa's Pandas). The pair's statistic is then
//!
//! F = (χ² / k) / φ̂  ~  F(k, D)   under "one arm",
//!
//! the ratio of two independent scaled χ²: the quasi-likelihood test with an estimated
//! dispersion. A pair is called one arm when P(F(k, D) > F) ≥ `alpha` ([`ALPHA`], 10⁻⁶).
//! The level is strict because recordings of one arm made on other days (the arm remounted,
//! another bench) scatter by more than one recording's halves: on MUKCa, F = 1.5 to 3.4 (p
//! down to 1.2e-5) for the pairs the dataset's notes call one arm, against F ≥ 64 for every
//! other pair (units of one design differ by tenths of a millimetre and of a milliradian).
//! Any level between the two, 10⁻⁵ to 10⁻⁶⁰, gives the same groups; the gap decides.
//! Without a recording of two sessions there is no φ̂ and the test is χ²_k itself.
//!
//! The probe (the ball's offset from the last joint) is not compared: it belongs to the tool
//! mounted for the recording, not to the arm (MUKCa's panda_1_with_sensor carries a 38 mm
//! force sensor), and a remounted tool moves it by more than the arm's own errors.
//!
//! **Gauge.** Only what both recordings identify is compared. The unknowns the data cannot see
//! (the base's place and turn for `length` and `spat` data, a rotation about the first axis)
//! are held by the identifiability analysis ([`crate::fit::ident`]) at their start values, and a kept
//! unknown then stands for itself plus the held ones it absorbs ([`crate::fit::finish::Fit::combination`]).
//! So a kept unknown is compared only when it is kept by both recordings and absorbs, in
//! either, no unknown that the other one fits: otherwise the two numbers are estimates of
//! different combinations. The frame is marginalised, never compared: each recording has its
//! own. Directions of C_A + C_B below 10⁻⁹ of its largest (unit-diagonal scaling) are dropped
//! from the quadratic form and from k.
//!
//! **Groups.** The pairwise decisions are closed transitively (A ~ B and B ~ C put A, B, C in
//! one arm); every within-arm pair is reported with its statistic, so a chain held by one
//! link shows. An arm is named by its first recording in file order.

use super::fleet::{self, FleetError, UnitData};
use crate::data::Dataset;
use crate::fit::finish::Fit;
use crate::fit::holdout::Holdout;
use crate::params::Param;
use crate::progress::{Observer, Silent};
use crate::stats::{chi2_tail, f_tail};
use nalgebra::{DMatrix, DVector, SymmetricEigen};
use quatarm_ref::arm::Arm;
use std::collections::BTreeMap;

/// Default level of the same-arm test: a pair is one arm unless P(F(k, D) > F) < this (module
/// text: why so strict).
pub const ALPHA: f64 = 1e-6;

/// One recording's identified geometry.
#[derive(Clone, Debug)]
pub struct Geometry {
    /// The identified arm unknowns (no frame).
    pub params: Vec<Param>,
    /// Their fitted increments over the common start arm.
    pub values: Vec<f64>,
    /// Their covariance (inflated by `inflation`).
    pub cov: DMatrix<f64>,
    /// The factor the held-out check multiplied σ̂² (JᵀJ)⁻¹ by (1: none or no check).
    pub inflation: f64,
    /// For each of `params`, the held unknowns whose effect it absorbs.
    absorbs: Vec<Vec<Param>>,
}

/// The identified geometry of a recording's fit (`None` without a covariance).
pub fn geometry(fit: &Fit, data: &Dataset, baseline: Option<&Holdout>) -> Option<Geometry> {
    let in_sample = crate::fit::residuals::summarise(
        &crate::fit::residuals::residuals(&fit.arm, data, fit.frame),
        data,
    );
    let (params, cov, inflation) =
        crate::uncertainty::estimate::parameters(fit, baseline, in_sample.all.rms_um).ok()?;
    let index = |p: &Param| fit.params.iter().position(|q| q == p);
    let values = params
        .iter()
        .map(|p| index(p).map_or(0.0, |i| fit.values[i]))
        .collect();
    let absorbs = params
        .iter()
        .map(|p| {
            let i = index(p);
            fit.ident
                .fixed
                .iter()
                .filter(|f| f.absorbed_by.iter().any(|(by, _)| Some(*by) == i))
                .map(|f| fit.params[f.index])
                .collect()
        })
        .collect();
    Some(Geometry {
        params,
        values,
        cov,
        inflation,
        absorbs,
    })
}

/// The same-arm statistic of two recordings.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Pair {
    /// One recording (index among the files).
    #[serde(skip)]
    pub a: usize,
    /// The other.
    #[serde(skip)]
    pub b: usize,
    /// dᵀ (C_A + C_B)⁻¹ d.
    pub chi2: f64,
    /// Unknowns compared (directions kept).
    pub dof: usize,
    /// (χ² / dof) / φ̂: the difference against what one recording's halves scatter by.
    pub f: f64,
    /// P(F_{dof, D} > f), D the halves' pooled degrees of freedom (P(χ²_dof > χ²) when no
    /// recording has two sessions).
    pub p_value: f64,
    /// Whether the test calls them one arm (p ≥ alpha).
    pub same: bool,
    /// How far their predicted balls are apart over both recordings' poses, probe and frame
    /// out (RMS, µm; [`super::gauge_free::tip_difference`]): the difference in what the two
    /// calibrations predict, which does not depend on their gauge.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tip_rms_um: Option<f64>,
}

/// The two recordings' calibrations compared by their predicted balls over both recordings'
/// poses, probe and frame out ([`super::gauge_free`]).
fn tip_rms_um(a: &Option<Fit>, b: &Option<Fit>, da: &Dataset, db: &Dataset) -> Option<f64> {
    let (a, b) = (a.as_ref()?, b.as_ref()?);
    let mut poses = super::gauge_free::poses(da);
    poses.extend(super::gauge_free::poses(db));
    Some(super::gauge_free::tip_difference(&a.arm, &b.arm, &poses).rms_um)
}

/// χ² of the difference of two recordings' geometries on what both identify alike (module
/// text); `None` when nothing can be compared.
pub fn chi2(a: &Geometry, b: &Geometry) -> Option<(f64, usize)> {
    let pos = |g: &Geometry, p: &Param| g.params.iter().position(|q| q == p);
    let common: Vec<(usize, usize)> = a
        .params
        .iter()
        .enumerate()
        .filter(|(_, p)| !matches!(p, Param::ProbeError(..)))
        .filter_map(|(i, p)| {
            let j = pos(b, p)?;
            let alike = a.absorbs[i].iter().all(|q| pos(b, q).is_none())
                && b.absorbs[j].iter().all(|q| pos(a, q).is_none());
            alike.then_some((i, j))
        })
        .collect();
    let k = common.len();
    if k == 0 {
        return None;
    }
    let c = DMatrix::from_fn(k, k, |r, s| {
        let (ir, jr) = common[r];
        let (is, js) = common[s];
        a.cov[(ir, is)] + b.cov[(jr, js)]
    });
    let scale: Vec<f64> = (0..k).map(|r| c[(r, r)].max(1e-300).sqrt()).collect();
    let d = DVector::from_fn(k, |r, _| {
        (a.values[common[r].0] - b.values[common[r].1]) / scale[r]
    });
    let eig = SymmetricEigen::new(DMatrix::from_fn(k, k, |r, s| {
        c[(r, s)] / (scale[r] * scale[s])
    }));
    let max = eig.eigenvalues.max();
    let mut q = 0.0;
    let mut dof = 0;
    for (l, v) in eig.eigenvalues.iter().zip(eig.eigenvectors.column_iter()) {
        if *l > 1e-9 * max {
            q += v.dot(&d).powi(2) / l;
            dof += 1;
        }
    }
    (dof > 0).then_some((q, dof))
}

/// A recording's sessions in two halves (alternate sessions in group order): two
/// recordings of one arm with its tool as mounted, read on different sessions. `None` with
/// fewer than two sessions.
pub fn halves(data: &Dataset) -> Option<(Dataset, Dataset)> {
    let groups: Vec<i64> = crate::fit::holdout::by_group(data)
        .iter()
        .map(|f| data.rows[f[0]].group)
        .collect();
    if groups.len() < 2 {
        return None;
    }
    let half = |odd: bool| {
        let rows = data
            .rows
            .iter()
            .filter(|r| (groups.iter().position(|g| *g == r.group).unwrap_or(0) % 2 == 1) == odd)
            .cloned()
            .collect();
        Dataset::from_rows(rows, data.dof, data.has_temperature, &data.source).ok()
    };
    Some((half(false)?, half(true)?))
}

/// How the fleet's recordings are grouped into arms.
#[derive(Clone, Debug, PartialEq)]
pub enum Grouping {
    /// From the data: the same-arm test at this level, closed transitively.
    Detect {
        /// The test's level.
        alpha: f64,
    },
    /// Given by hand (`--same-arm ARM=REC,REC,…`): each entry's recordings are one arm of that
    /// name, every other recording an arm of its own; nothing is detected.
    ByHand(Vec<(String, Vec<String>)>),
    /// Every file is an arm of its own (as before this test).
    EachFile,
}

impl Grouping {
    /// The rule in words, for the report.
    pub fn rule(&self) -> String {
        match self {
            Grouping::Detect { alpha } => format!(
                "detected: two recordings are one arm when their identified geometric errors \
                 (probe excluded) agree, P(F(k, D) > dᵀ(C_A + C_B)⁻¹d / (k φ̂)) ≥ {alpha}, \
                 φ̂ from each recording's two halves, closed transitively"
            ),
            Grouping::ByHand(_) => {
                "by hand (--same-arm); every other recording an arm of its own".into()
            }
            Grouping::EachFile => "each file an arm of its own (--each-file-an-arm)".into(),
        }
    }
}

/// Parses one `--same-arm ARM=REC,REC,…`.
pub fn parse_same_arm(s: &str) -> Result<(String, Vec<String>), String> {
    let (arm, recs) = s
        .split_once('=')
        .ok_or_else(|| format!("--same-arm {s}: expected ARM=RECORDING,RECORDING,…"))?;
    let arm = arm.trim();
    let recs: Vec<String> = recs.split(',').map(|r| r.trim().to_string()).collect();
    if arm.is_empty() || recs.iter().any(String::is_empty) {
        return Err(format!(
            "--same-arm {s}: an empty arm or recording name (expected ARM=RECORDING,RECORDING,…)"
        ));
    }
    Ok((arm.to_string(), recs))
}

/// The statistic of one recording's two halves.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Split {
    /// The recording (index among the files).
    #[serde(skip)]
    pub recording: usize,
    /// χ² of the halves' difference.
    pub chi2: f64,
    /// Unknowns compared.
    pub dof: usize,
}

/// One physical arm.
#[derive(Clone, Debug)]
pub struct ArmGroup {
    /// Its name.
    pub arm: String,
    /// Its recordings (indices among the files, file order).
    pub recordings: Vec<usize>,
}

/// The grouping of a fleet's recordings.
#[derive(Clone, Debug)]
pub struct Arms {
    /// The arms, in the order of their first recording.
    pub groups: Vec<ArmGroup>,
    /// Every pair's statistic (empty with [`Grouping::EachFile`]); a recording without a
    /// geometry (its fit failed or has no covariance) is in none.
    pub pairs: Vec<Pair>,
    /// Each recording's halves compared ([`halves`]).
    pub splits: Vec<Split>,
    /// φ̂ = Σ χ² / Σ k over `splits`, and Σ k (`None` without splits).
    pub overdispersion: Option<(f64, usize)>,
    /// The rule that made the groups.
    pub rule: String,
    /// Recordings whose geometry could not be compared, with why.
    pub uncompared: Vec<(usize, String)>,
}

/// Groups the recordings `files` into arms by `grouping`; the pairwise statistics are
/// computed unless `grouping` is [`Grouping::EachFile`] (with a hand grouping they show what
/// the data say of it). Errors name the option and the recording.
pub fn group(
    start: &Arm,
    files: &[UnitData],
    opts: &fleet::Options,
    grouping: &Grouping,
) -> Result<Arms, FleetError> {
    group_observed(start, files, opts, grouping, &mut Silent)
}

/// [`group`], telling `obs` each recording's fits (its two halves, then the whole) as a
/// counted step, so that a command can show the count and the time left.
pub fn group_observed(
    start: &Arm,
    files: &[UnitData],
    opts: &fleet::Options,
    grouping: &Grouping,
    obs: &mut dyn Observer,
) -> Result<Arms, FleetError> {
    let n = files.len();
    // A hand grouping is checked before any fit.
    let hand = match grouping {
        Grouping::ByHand(hand) => Some(by_hand(files, hand)?),
        _ => None,
    };
    let mut pairs = Vec::new();
    let mut uncompared = Vec::new();
    let mut splits = Vec::new();
    let mut overdispersion = None;
    if *grouping != Grouping::EachFile {
        let alpha = match grouping {
            Grouping::Detect { alpha } => *alpha,
            _ => ALPHA,
        };
        let inner = fleet::geometric_options(opts);
        let fit_of = |d: &Dataset| {
            let g = fleet::geometric(start, d, &inner);
            let geo = g
                .fit
                .as_ref()
                .and_then(|f| geometry(f, d, g.baseline.as_ref()));
            (g.fit, geo)
        };
        let geo_of = |d: &Dataset| fit_of(d).1;
        (splits, overdispersion) = split_each(files, &geo_of, obs);
        let (fits, geos): (Vec<Option<Fit>>, Vec<Option<Geometry>>) = files
            .iter()
            .enumerate()
            .map(|(i, u)| {
                obs.step("same-arm test: fit of recording", i, n);
                let (fit, geo) = fit_of(&u.data);
                if geo.is_none() {
                    uncompared.push((
                        i,
                        "its geometric model has no covariance (fit failed or singular)".into(),
                    ));
                }
                (fit, geo)
            })
            .unzip();
        pairs = compare_pairs(&geos, overdispersion, alpha, &|a, b| {
            tip_rms_um(&fits[a], &fits[b], &files[a].data, &files[b].data)
        });
    }
    let of: Vec<usize> = match grouping {
        Grouping::Detect { .. } => joined_by_same(n, &pairs),
        Grouping::EachFile => (0..n).collect(),
        Grouping::ByHand(_) => hand.expect("checked above"),
    };
    Ok(Arms {
        groups: arm_groups(files, &of, grouping),
        pairs,
        splits,
        overdispersion,
        rule: grouping.rule(),
        uncompared,
    })
}

/// Each recording's halves compared ([`halves`], [`chi2`]), and the overdispersion φ̂ they
/// estimate together (`None` without a split).
fn split_each(
    files: &[UnitData],
    geo_of: &dyn Fn(&Dataset) -> Option<Geometry>,
    obs: &mut dyn Observer,
) -> (Vec<Split>, Option<(f64, usize)>) {
    let mut splits = Vec::new();
    let (mut q_split, mut k_split) = (0.0, 0usize);
    for (i, u) in files.iter().enumerate() {
        obs.step("same-arm test: halves of recording", i, files.len());
        let Some((x, y)) = halves(&u.data) else {
            continue;
        };
        if let (Some(gx), Some(gy)) = (geo_of(&x), geo_of(&y)) {
            if let Some((q, k)) = chi2(&gx, &gy) {
                splits.push(Split {
                    recording: i,
                    chi2: q,
                    dof: k,
                });
                q_split += q;
                k_split += k;
            }
        }
    }
    let overdispersion = (k_split > 0).then(|| (q_split / k_split as f64, k_split));
    (splits, overdispersion)
}

/// Every pair of recordings with a geometry compared: χ² scaled by the overdispersion, its
/// p-value (F with the splits' degrees of freedom, else χ²), and whether the pair is the same
/// arm at level `alpha`.
fn compare_pairs(
    geos: &[Option<Geometry>],
    overdispersion: Option<(f64, usize)>,
    alpha: f64,
    tip_rms_um: &dyn Fn(usize, usize) -> Option<f64>,
) -> Vec<Pair> {
    let (phi, d2) = overdispersion.map_or((1.0, f64::INFINITY), |(p, k)| (p, k as f64));
    let mut pairs = Vec::new();
    for a in 0..geos.len() {
        for b in a + 1..geos.len() {
            let (Some(ga), Some(gb)) = (&geos[a], &geos[b]) else {
                continue;
            };
            if let Some((q, dof)) = chi2(ga, gb) {
                let f = q / dof as f64 / phi;
                let p = if d2.is_finite() {
                    f_tail(f, dof as f64, d2)
                } else {
                    chi2_tail(q, dof)
                };
                pairs.push(Pair {
                    a,
                    b,
                    chi2: q,
                    dof,
                    f,
                    p_value: p,
                    same: p >= alpha,
                    tip_rms_um: tip_rms_um(a, b),
                });
            }
        }
    }
    pairs
}

/// Each of `n` recordings' representative when the "same" pairs join them: union–find, the
/// root the lowest index.
fn joined_by_same(n: usize, pairs: &[Pair]) -> Vec<usize> {
    let mut root: Vec<usize> = (0..n).collect();
    fn find(r: &mut [usize], i: usize) -> usize {
        let mut i = i;
        while r[i] != i {
            r[i] = r[r[i]];
            i = r[i];
        }
        i
    }
    for p in pairs.iter().filter(|p| p.same) {
        let (x, y) = (find(&mut root, p.a), find(&mut root, p.b));
        root[x.max(y)] = x.min(y);
    }
    (0..n).map(|i| find(&mut root, i)).collect()
}

/// The arms from each recording's representative `of`, in the order of their first
/// recording, named by hand where `grouping` gives names, else by their first recording.
fn arm_groups(files: &[UnitData], of: &[usize], grouping: &Grouping) -> Vec<ArmGroup> {
    let mut groups: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for (i, r) in of.iter().enumerate() {
        groups.entry(*r).or_default().push(i);
    }
    let names: BTreeMap<usize, String> = match grouping {
        Grouping::ByHand(hand) => hand
            .iter()
            .map(|(arm, recs)| {
                let first = files.iter().position(|u| u.name == recs[0]).unwrap_or(0);
                (of[first], arm.clone())
            })
            .collect(),
        _ => BTreeMap::new(),
    };
    let mut groups: Vec<ArmGroup> = groups
        .into_iter()
        .map(|(r, recordings)| ArmGroup {
            arm: names
                .get(&r)
                .cloned()
                .unwrap_or_else(|| files[r].name.clone()),
            recordings,
        })
        .collect();
    groups.sort_by_key(|g| g.recordings[0]);
    groups
}

/// Each recording's representative (the first of its hand-given arm, or itself).
fn by_hand(files: &[UnitData], hand: &[(String, Vec<String>)]) -> Result<Vec<usize>, FleetError> {
    let bad = |m: String| Err(FleetError::Grouping(m));
    let mut of: Vec<usize> = (0..files.len()).collect();
    let mut claimed: BTreeMap<usize, &str> = BTreeMap::new();
    let known = || {
        files
            .iter()
            .map(|u| u.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    };
    for (arm, recs) in hand {
        let mut first = None;
        for r in recs {
            let Some(i) = files.iter().position(|u| &u.name == r) else {
                return bad(format!(
                    "--same-arm {arm}=…: no recording `{r}` among the fleet's files (their \
                     names: {})",
                    known()
                ));
            };
            if let Some(other) = claimed.insert(i, arm) {
                return bad(format!(
                    "--same-arm: recording `{r}` ({}) is given to both arm `{other}` and arm \
                     `{arm}`",
                    files[i].file
                ));
            }
            let f = *first.get_or_insert(i);
            of[i] = f;
        }
    }
    // An arm name may not be another recording's, unless that recording is in the arm.
    for (arm, recs) in hand {
        if let Some(u) = files
            .iter()
            .find(|u| &u.name == arm && !recs.contains(&u.name))
        {
            return bad(format!(
                "--same-arm {arm}=…: `{arm}` is the name of recording {}, which the option \
                 does not list; name the arm otherwise or list it",
                u.file
            ));
        }
    }
    let mut names: BTreeMap<&str, &str> = BTreeMap::new();
    for (arm, _) in hand {
        if names.insert(arm, arm).is_some() {
            return bad(format!("--same-arm: arm `{arm}` is given twice"));
        }
    }
    Ok(of)
}

impl Arms {
    /// The arms as [`fleet::diagnose_arms`] takes them: (name, recordings).
    pub fn list(&self) -> Vec<(String, Vec<usize>)> {
        self.groups
            .iter()
            .map(|g| (g.arm.clone(), g.recordings.clone()))
            .collect()
    }
}
