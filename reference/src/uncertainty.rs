//! The `[uncertainty]` section of the calibration file (`spec/uncertainty.md`): the budget a
//! calibration leaves for every later point.
//!
//! The parameters are the workspace's one vocabulary, [`Param`] (`quatarm-params`); this
//! module owns the budget's text grammar for them (`joint.K.tilt.0`,
//! `joint.K.harmonics.H.sin`, …: [`parse_name`], [`name`]) and checks every name against the
//! arm it belongs to, so a name pointing at a joint or harmonic the file does not have is
//! refused with its key, like any other bad value. The text names a periodic term by its
//! place H in the joint's list; the [`Param`] by its order, which the arm translates.

use crate::arm::Arm;
use crate::calfile::{CalFileError, Limits};
use nalgebra::{DMatrix, SymmetricEigen};
pub use quatarm_params::{Link, Param};
use toml::{Table, Value};

/// Parses a budget's parameter name and checks that `arm` has what it points at.
pub fn parse_name(name: &str, arm: &Arm) -> Result<Param, String> {
    let parts: Vec<&str> = name.split('.').collect();
    let comp = |s: &str, n: usize| -> Result<usize, String> {
        s.parse::<usize>()
            .ok()
            .filter(|c| *c < n)
            .ok_or_else(|| format!("`{s}` is not a component: 0 to {}", n - 1))
    };
    let key = |p: Param| p.file_key();
    match parts.as_slice() {
        ["probe", k, c] if *k == key(Param::ProbeError(0, 0)) => {
            Ok(Param::ProbeError(0, comp(c, 3)?))
        }
        ["probe", k] if *k == key(Param::Thermal(Link::Probe)) => Ok(Param::Thermal(Link::Probe)),
        ["probe", id, k, c] if *k == key(Param::ProbeError(0, 0)) => {
            let k = id
                .parse::<u8>()
                .ok()
                .and_then(|id| arm.probe_index(id))
                .ok_or_else(|| {
                    let ids: Vec<String> = arm.probes().map(|p| p.id.to_string()).collect();
                    format!("`{id}` is not a probe of this arm: {}", ids.join(", "))
                })?;
            Ok(Param::ProbeError(k, comp(c, 3)?))
        }
        ["joint", k, rest @ ..] => {
            let j = one_based(k, arm.dof(), || {
                format!("`{k}` is not a joint of this arm: 1 to {}", arm.dof())
            })?;
            let joint = &arm.joints[j];
            match rest {
                [k] if *k == key(Param::ZeroOffset(j)) => Ok(Param::ZeroOffset(j)),
                [k, c] if *k == key(Param::Tilt(j, 0)) => Ok(Param::Tilt(j, comp(c, 2)?)),
                [k, c] if *k == key(Param::LinkError(j, 0)) => Ok(Param::LinkError(j, comp(c, 3)?)),
                [k] if *k == key(Param::Gravity(j)) => Ok(Param::Gravity(j)),
                [k] if *k == key(Param::Thermal(Link::Joint(j))) => {
                    Ok(Param::Thermal(Link::Joint(j)))
                }
                [k, h, sc] if *k == joint_key(PeriodicKey::Harmonics) => {
                    let n = joint.harmonics.len();
                    let index = one_based(h, n, || {
                        format!("joint {} has {n} harmonics; `{h}` is not one", j + 1)
                    })?;
                    let cos = quatarm_params::SIN_COS
                        .iter()
                        .position(|s| s == sc)
                        .ok_or_else(|| unknown_name(name))?;
                    Ok(Param::Harmonic {
                        joint: j,
                        order: joint.harmonics[index].order,
                        cos: cos == 1,
                    })
                }
                [k, w, ab, c] if *k == joint_key(PeriodicKey::Wobble) => {
                    let n = joint.wobble.len();
                    let index = one_based(w, n, || {
                        format!("joint {} has {n} wobble terms; `{w}` is not one", j + 1)
                    })?;
                    let t = quatarm_params::WOBBLE_COMPONENT
                        .iter()
                        .position(|s| s == ab)
                        .ok_or_else(|| unknown_name(name))?;
                    Ok(Param::Wobble {
                        joint: j,
                        order: joint.wobble[index].order,
                        coef: (2 * t + comp(c, 2)?) as u8,
                    })
                }
                _ => Err(unknown_name(name)),
            }
        }
        _ => Err(unknown_name(name)),
    }
}

/// The two periodic kinds, whose keys a name matches before it knows the order.
enum PeriodicKey {
    Harmonics,
    Wobble,
}

/// The file key of a periodic kind: [`Param::file_key`] of any of its parameters.
fn joint_key(k: PeriodicKey) -> &'static str {
    match k {
        PeriodicKey::Harmonics => Param::Harmonic {
            joint: 0,
            order: 1,
            cos: false,
        },
        PeriodicKey::Wobble => Param::Wobble {
            joint: 0,
            order: 1,
            coef: 0,
        },
    }
    .file_key()
}

/// The name a budget writes for `p`, for `arm` (a probe other than the first is named by its
/// id, a periodic term by its place in the joint's list). `None` where the budget cannot
/// list it: the instrument frame's unknowns, a periodic term of an order the arm has no entry
/// for, a probe the arm does not have.
pub fn name(p: Param, arm: &Arm) -> Option<String> {
    let key = p.file_key();
    // The 1-based place of the entry of `order` in a joint's list.
    fn place(mut orders: impl Iterator<Item = u32>, order: u32) -> Option<usize> {
        orders.position(|o| o == order).map(|i| i + 1)
    }
    Some(match p {
        Param::ZeroOffset(j) | Param::Gravity(j) | Param::Thermal(Link::Joint(j)) => {
            format!("joint.{}.{key}", j + 1)
        }
        Param::Tilt(j, c) | Param::LinkError(j, c) => format!("joint.{}.{key}.{c}", j + 1),
        Param::ProbeError(0, c) => format!("probe.{key}.{c}"),
        Param::ProbeError(k, c) => format!("probe.{}.{key}.{c}", arm.probe_at(k)?.id),
        Param::Thermal(Link::Probe) => format!("probe.{key}"),
        Param::Harmonic { joint, order, cos } => {
            let h = arm.joints.get(joint)?;
            let index = place(h.harmonics.iter().map(|e| e.order), order)?;
            let sc = quatarm_params::SIN_COS[usize::from(cos)];
            format!("joint.{}.{key}.{index}.{sc}", joint + 1)
        }
        Param::Wobble { joint, order, coef } => {
            let w = arm.joints.get(joint)?;
            let index = place(w.wobble.iter().map(|e| e.order), order)?;
            let ab = quatarm_params::WOBBLE_COMPONENT[usize::from(coef / 2) % 2];
            format!("joint.{}.{key}.{index}.{ab}.{}", joint + 1, coef % 2)
        }
        Param::FrameRotation(_) | Param::FrameTranslation(_) => return None,
    })
}

/// The 0-based position a name's 1-based number `s` (1 to `n`) points at, or `refuse`'s message.
fn one_based(s: &str, n: usize, refuse: impl FnOnce() -> String) -> Result<usize, String> {
    s.parse::<usize>()
        .ok()
        .filter(|k| (1..=n).contains(k))
        .map(|k| k - 1)
        .ok_or_else(refuse)
}

fn unknown_name(name: &str) -> String {
    format!(
        "`{name}` is not a parameter: joint.K.zero_offset, joint.K.tilt.C, \
         joint.K.link_error.C, joint.K.harmonics.H.sin|cos, joint.K.wobble.W.alpha|beta.C, \
         joint.K.gravity, joint.K.thermal, \
         probe.error.C, probe.ID.error.C, probe.thermal"
    )
}

/// The budget. Every term absent in the file is 0.
#[derive(Clone, Debug, PartialEq)]
pub struct Uncertainty {
    /// The identified parameters, in the covariance's order.
    pub parameters: Vec<Param>,
    /// Their covariance, row-major, `parameters.len()²` values (units²).
    pub covariance: Vec<f64>,
    /// Standard uncertainty of each joint's reading (counts), one per joint.
    pub encoder_counts: Vec<f64>,
    /// Standard uncertainty of the probing, per axis (mm).
    pub probing_mm: f64,
    /// Standard uncertainty of the temperature reading (°C).
    pub temperature_c: f64,
    /// What the model leaves unexplained, per axis (mm).
    pub model_mm: f64,
    /// The pose part of `covariance` kept apart, for the leverage-scaled pose term; `None`
    /// when the file has none (the budget then reads as `covariance` alone).
    pub pose: Option<PoseLeverage>,
}

/// The pose part of the budget's covariance, kept apart so that a reading at a placement the
/// calibration did not see can widen it (issue 27; keys `pose_factor`, `pose_shrink` and
/// `pose_leverage_mean` of `[uncertainty]`, proposed in `docs/spec-reading.md`).
///
/// The pose part is P = D Dᵀ + b · C_fit, where D's columns are `factor` (the between-group
/// spread of the parameters, low rank: one column per held-out group at most), b is
/// `shrink`, and C_fit = (`covariance` − D Dᵀ)/(1 + b) is the fit's own covariance, so that
/// `covariance` = C_fit + P is the budget read without these keys. A reading whose Jacobian
/// is J has the leverage ratio ℓ = tr(J C_fit Jᵀ) / `leverage_mean` and the variance
/// J `covariance` Jᵀ + (max(1, ℓ) − 1) · J P Jᵀ beside the reading's own terms: the pose part
/// grows where the calibration's design gave the parameters little hold.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseLeverage {
    /// D's columns, each one value per parameter in `parameters`' order (units).
    pub factor: Vec<Vec<f64>>,
    /// b ≥ 0: the weight of the fit's own covariance in the pose part.
    pub shrink: f64,
    /// The calibration rows' mean of tr(J C_fit Jᵀ) (mm²), > 0.
    pub leverage_mean: f64,
    /// The joint-space leverage (keys `pose_joint_mean`, `pose_joint_weight`); `None` when
    /// the file has none (the factor is then max(1, ℓ)).
    pub joints: Option<JointLeverage>,
}

/// The joint-space leverage ratio ℓJ of a reading (issue 27, keys `pose_joint_mean` and
/// `pose_joint_weight` of `[uncertainty]`, proposed in `docs/spec-reading.md`).
///
/// The tip's ℓ (above) measures how little hold the calibration's design gave the parameters
/// *at the reading's tip*; on real arms the model's misfit also grows where the arm's *joint
/// configuration* is one the calibration did not see (a raised artefact bends shoulder and
/// elbow otherwise: MUKCa kuka_14 `raised_left`, panda_1 `back-high`), whatever the tip's ℓ.
/// ℓJ = dᵀ W d, d = θ − μ taken to [−π, π) ([`wrap`]), with θ the reading's joint angles as
/// the measured-data file gives them (rad), μ the calibration rows' (circular) mean and W their inverse covariance scaled so that
/// ℓJ's mean over the calibration rows is 1 (W = Σ⁻¹ · n / (k (n − 1)) for n rows and k
/// joints that moved; rows and columns of joints that did not move are 0). With it the
/// factor on the pose part is max(1, ℓ, ℓJ).
#[derive(Clone, Debug, PartialEq)]
pub struct JointLeverage {
    /// μ: one value per joint (rad).
    pub mean: Vec<f64>,
    /// W: joints² values, row-major, symmetric positive semi-definite (1/rad²).
    pub weight: Vec<f64>,
}

impl JointLeverage {
    /// ℓJ of joint angles `theta` (rad): dᵀ W d with d = θ − μ taken to [−π, π) (a joint
    /// angle and the same angle a turn on are one configuration: a data file's (−π, π] and
    /// a hub's counts' [0, 2π) give the same ℓJ), ≥ 0. Angles beyond the joints the file
    /// gives are ignored; missing ones count as at the mean.
    pub fn ratio(&self, theta: &[f64]) -> f64 {
        let k = self.mean.len();
        let d: Vec<f64> = (0..k)
            .map(|j| theta.get(j).map_or(0.0, |t| wrap(t - self.mean[j])))
            .collect();
        let q: f64 = (0..k)
            .map(|i| d[i] * (0..k).map(|j| self.weight[i * k + j] * d[j]).sum::<f64>())
            .sum();
        q.max(0.0)
    }
}

/// An angle difference `x` (rad) taken to [−π, π): the nearest turn's.
pub fn wrap(x: f64) -> f64 {
    let tau = std::f64::consts::TAU;
    let w = x - (x / tau).round() * tau;
    if w >= std::f64::consts::PI {
        w - tau
    } else {
        w
    }
}

/// The most columns `pose_factor` may have: D's rank r. The host's estimate gives one
/// column per direction in which the held-out groups' fits differed (at most G − 1 for G
/// groups) and folds any beyond the cap into `pose_shrink` (bounded, so the widening stays
/// on the safe side); 16 holds a calibration of up to 17 sessions or placements whole (the
/// largest MUKCa unit has 9), and costs a reading 16 × n multiply-adds per axis for J D, a
/// quarter of the n² of J C Jᵀ at the table's 64 parameters. The hub's table uses the same
/// constant (the lead unifies it with the hub's copy).
pub const POSE_RANK_MAX: usize = 16;

impl PoseLeverage {
    /// D as a matrix: n rows (the parameters), r columns.
    pub fn factor_matrix(&self, n: usize) -> DMatrix<f64> {
        DMatrix::from_fn(n, self.factor.len(), |i, k| self.factor[k][i])
    }
}

impl Uncertainty {
    /// The same budget without its parameters: the reading's own terms only (a table for
    /// the fixed-point hubs, which refuse the parameter block). The pose part, a part of the
    /// parameters' covariance, goes with it.
    pub fn without_covariance(&self) -> Uncertainty {
        Uncertainty {
            parameters: Vec::new(),
            covariance: Vec::new(),
            pose: None,
            ..self.clone()
        }
    }

    /// The covariance as a matrix.
    pub fn matrix(&self) -> DMatrix<f64> {
        let n = self.parameters.len();
        DMatrix::from_row_slice(n, n, &self.covariance)
    }
}

const KEYS: &[&str] = &[
    "parameters",
    "covariance",
    "encoder_counts",
    "probing_mm",
    "temperature_c",
    "model_mm",
    "pose_factor",
    "pose_shrink",
    "pose_leverage_mean",
    "pose_joint_mean",
    "pose_joint_weight",
];

/// The pose part's keys: all three or none.
const POSE_KEYS: [&str; 3] = ["pose_factor", "pose_shrink", "pose_leverage_mean"];

/// The joint leverage's keys: both or none, and only with [`POSE_KEYS`].
const JOINT_KEYS: [&str; 2] = ["pose_joint_mean", "pose_joint_weight"];

/// The largest |μ| a joint's mean angle may have (rad): a few turns, far beyond any joint's
/// range, so that a misplaced unit (degrees, counts) is refused where it is read.
pub const JOINT_MEAN_LIMIT: f64 = 64.0;

fn err(path: impl Into<String>, message: impl Into<String>) -> CalFileError {
    CalFileError {
        path: path.into(),
        message: message.into(),
    }
}

/// A standard uncertainty: a finite number in [0, `limit`] (the limit the tool reading the
/// file applies: `armcal` takes the binary table's, so a budget the hub would refuse is
/// refused on the host too, where it is read).
fn non_negative(v: &Value, path: &str, limit: f64) -> Result<f64, CalFileError> {
    let x = match v {
        Value::Float(f) => *f,
        Value::Integer(i) => *i as f64,
        _ => return Err(err(path, "must be a number")),
    };
    if !x.is_finite() || x < 0.0 {
        return Err(err(
            path,
            format!("{x} is not a standard uncertainty (finite, ≥ 0)"),
        ));
    }
    if x > limit {
        return Err(err(
            path,
            format!("{x:e} is beyond the limit of {limit} for this standard uncertainty"),
        ));
    }
    Ok(x)
}

/// The largest |value| `limits` allow for what `p` names: a standard uncertainty larger
/// than every value the parameter may take is no budget. The instrument frame, which no
/// budget lists, has no limit.
pub fn limit(p: Param, limits: &Limits) -> f64 {
    match p {
        Param::ZeroOffset(_) | Param::Tilt(..) => limits.angle_rad,
        Param::LinkError(..) | Param::ProbeError(..) => limits.length_mm,
        Param::Harmonic { .. } => limits.harmonic_rad,
        Param::Wobble { .. } => limits.wobble_rad,
        Param::Gravity(_) => limits.gravity,
        Param::Thermal(_) => limits.thermal,
        Param::FrameRotation(_) | Param::FrameTranslation(_) => f64::INFINITY,
    }
}

/// Reads the `[uncertainty]` table for `arm`, every term within `limits`.
pub fn parse(
    t: &Table,
    arm: &Arm,
    limits: &Limits,
    unknown: &mut Vec<String>,
) -> Result<Uncertainty, CalFileError> {
    for k in t.keys() {
        if !KEYS.contains(&k.as_str()) {
            unknown.push(format!("uncertainty.{k}"));
        }
    }
    let parameters = parameters(t.get("parameters"), arm)?;
    let covariance = covariance(t.get("covariance"), &parameters, limits)?;
    let pose = pose(t, &parameters, &covariance, limits, arm.dof())?;
    let opt = |key: &str, limit: f64| -> Result<f64, CalFileError> {
        t.get(key).map_or(Ok(0.0), |v| {
            non_negative(v, &format!("uncertainty.{key}"), limit)
        })
    };
    let counts = limits.budget_counts;
    let n = arm.dof();
    let encoder_counts = match t.get("encoder_counts") {
        None => vec![0.0; n],
        Some(Value::Array(a)) if a.len() == n => a
            .iter()
            .enumerate()
            .map(|(k, v)| {
                non_negative(v, &format!("uncertainty.encoder_counts[{}]", k + 1), counts)
            })
            .collect::<Result<_, _>>()?,
        Some(Value::Array(a)) => {
            return Err(err(
                "uncertainty.encoder_counts",
                format!("{} values for {n} joints", a.len()),
            ))
        }
        Some(v) => vec![non_negative(v, "uncertainty.encoder_counts", counts)?; n],
    };
    Ok(Uncertainty {
        parameters,
        covariance,
        encoder_counts,
        probing_mm: opt("probing_mm", limits.budget_mm)?,
        temperature_c: opt("temperature_c", limits.budget_temperature_c)?,
        model_mm: opt("model_mm", limits.budget_mm)?,
        pose,
    })
}

/// The pose part (`pose_factor`, `pose_shrink`, `pose_leverage_mean`): all three or none;
/// D's entries finite and within their parameter's limit (a column of D is a standard
/// deviation of the parameters, like the square root of the covariance's diagonal), at most
/// [`POSE_RANK_MAX`] columns of n values; b finite and ≥ 0; the leverage mean finite and
/// positive; and `covariance` − D Dᵀ positive semi-definite with the covariance's own tolerance
/// (C_fit (1 + b) is what is left, and a covariance cannot be negative).
fn pose(
    t: &Table,
    parameters: &[Param],
    covariance: &[f64],
    limits: &Limits,
    dof: usize,
) -> Result<Option<PoseLeverage>, CalFileError> {
    if !all_or_none(t, &POSE_KEYS, "the pose part")? {
        if let Some(k) = JOINT_KEYS.iter().find(|k| t.contains_key(**k)) {
            return Err(err(
                format!("uncertainty.{k}"),
                "the joint leverage widens the pose part: it needs pose_factor, pose_shrink \
                 and pose_leverage_mean",
            ));
        }
        return Ok(None);
    }
    let n = parameters.len();
    const FACTOR: &str = "uncertainty.pose_factor";
    let cols = t["pose_factor"]
        .as_array()
        .ok_or_else(|| err(FACTOR, "must be an array of columns (arrays of numbers)"))?;
    if cols.len() > POSE_RANK_MAX {
        return Err(err(
            FACTOR,
            format!(
                "{} columns; at most {POSE_RANK_MAX} (the pose part's rank)",
                cols.len()
            ),
        ));
    }
    let mut factor = Vec::with_capacity(cols.len());
    for (k, col) in cols.iter().enumerate() {
        let path = format!("{FACTOR}[{k}]");
        let a = col
            .as_array()
            .ok_or_else(|| err(&path, "must be an array of numbers, one per parameter"))?;
        if a.len() != n {
            return Err(err(
                &path,
                format!("{} values; {n} parameters need {n}", a.len()),
            ));
        }
        let mut v = Vec::with_capacity(n);
        for (i, x) in a.iter().enumerate() {
            let path = format!("{FACTOR}[{k}][{i}]");
            let x = finite(x, &path)?;
            let limit = limit(parameters[i], limits);
            if x.abs() > limit {
                return Err(err(
                    path,
                    format!("{x:e} is beyond the parameter's limit of {limit}"),
                ));
            }
            v.push(x);
        }
        factor.push(v);
    }
    let shrink = non_negative(&t["pose_shrink"], "uncertainty.pose_shrink", f64::MAX)?;
    const MEAN: &str = "uncertainty.pose_leverage_mean";
    let leverage_mean = non_negative(&t["pose_leverage_mean"], MEAN, f64::MAX)?;
    if leverage_mean <= 0.0 {
        return Err(err(
            MEAN,
            "must be > 0: a mean of tr(J C Jᵀ) over the calibration's rows",
        ));
    }
    let p = PoseLeverage {
        factor,
        shrink,
        leverage_mean,
        joints: joints(t, dof)?,
    };
    // covariance − D Dᵀ, judged on the covariance's correlation scale (its own diagonal):
    // what rounding leaves of a zero C_fit is then a rounding-sized eigenvalue, not a NaN.
    let d = p.factor_matrix(n);
    let rest = DMatrix::from_row_slice(n, n, covariance) - &d * d.transpose();
    let scale: Vec<f64> = (0..n).map(|i| covariance[i * n + i].sqrt()).collect();
    // A parameter known exactly (zero variance, so zero covariances: checked above) has no
    // pose part either.
    if let Some((i, k)) = (0..n)
        .filter(|&i| scale[i] == 0.0)
        .find_map(|i| (0..d.ncols()).find(|&k| d[(i, k)] != 0.0).map(|k| (i, k)))
    {
        return Err(err(
            format!("{FACTOR}[{k}][{i}]"),
            "non-zero where the parameter's variance is zero: covariance − D Dᵀ is not \
             positive semi-definite",
        ));
    }
    let r = DMatrix::from_fn(n, n, |i, j| {
        if scale[i] == 0.0 || scale[j] == 0.0 {
            f64::from(u8::from(i == j))
        } else {
            rest[(i, j)] / (scale[i] * scale[j])
        }
    });
    if n > 0 {
        let min = SymmetricEigen::new(r).eigenvalues.min();
        if min < -SEMI_DEFINITE_TOLERANCE {
            return Err(err(
                FACTOR,
                format!(
                    "covariance − D Dᵀ is not positive semi-definite (correlation-scale \
                     eigenvalue {min:e}): the pose part is larger than the covariance it is a \
                     part of"
                ),
            ));
        }
    }
    Ok(Some(p))
}

/// The least eigenvalue a covariance's correlation matrix may have: rounding, not a
/// negative variance.
const SEMI_DEFINITE_TOLERANCE: f64 = 1e-8;

/// Whether the keys `keys` of `what` are in `t`: all (true) or none (false); some without
/// the others is an error naming the first missing one and those present.
fn all_or_none(t: &Table, keys: &[&str], what: &str) -> Result<bool, CalFileError> {
    let present: Vec<&str> = keys
        .iter()
        .copied()
        .filter(|k| t.contains_key(*k))
        .collect();
    if present.is_empty() {
        return Ok(false);
    }
    match keys.iter().find(|k| !t.contains_key(**k)) {
        None => Ok(true),
        Some(missing) => {
            let (last, rest) = keys.split_last().unwrap_or((&"", &[]));
            let needs = if rest.is_empty() {
                last.to_string()
            } else {
                format!("{} and {last}", rest.join(", "))
            };
            Err(err(
                format!("uncertainty.{missing}"),
                format!(
                    "missing: {what} needs {needs} together (the file has {})",
                    present.join(", ")
                ),
            ))
        }
    }
}

/// A finite number at `path`.
fn finite(x: &Value, path: &str) -> Result<f64, CalFileError> {
    match x {
        Value::Float(f) if f.is_finite() => Ok(*f),
        Value::Integer(i) => Ok(*i as f64),
        _ => Err(err(path, "must be a finite number")),
    }
}

/// The joint leverage: `pose_joint_mean` (one angle a joint, |μ| ≤ [`JOINT_MEAN_LIMIT`])
/// and `pose_joint_weight` (joints² numbers, row-major, symmetric and positive
/// semi-definite to rounding), both or neither.
fn joints(t: &Table, dof: usize) -> Result<Option<JointLeverage>, CalFileError> {
    if !all_or_none(t, &JOINT_KEYS, "the joint leverage")? {
        return Ok(None);
    }
    let numbers = |key: &str, len: usize, what: &str| -> Result<Vec<f64>, CalFileError> {
        let path = format!("uncertainty.{key}");
        let a = t[key]
            .as_array()
            .ok_or_else(|| err(&path, format!("must be an array of {what}")))?;
        if a.len() != len {
            return Err(err(
                &path,
                format!(
                    "{} values; this arm's {dof} joints need {len} ({what})",
                    a.len()
                ),
            ));
        }
        a.iter()
            .enumerate()
            .map(|(i, x)| finite(x, &format!("{path}[{i}]")))
            .collect()
    };
    let mean = numbers("pose_joint_mean", dof, "angles in rad, one a joint")?;
    if let Some((i, x)) = mean
        .iter()
        .enumerate()
        .find(|(_, x)| x.abs() > JOINT_MEAN_LIMIT)
    {
        return Err(err(
            format!("uncertainty.pose_joint_mean[{i}]"),
            format!("{x:e} rad is beyond {JOINT_MEAN_LIMIT} rad: not a joint's mean angle"),
        ));
    }
    const WEIGHT: &str = "uncertainty.pose_joint_weight";
    let weight = numbers("pose_joint_weight", dof * dof, "joints² numbers, row-major")?;
    let w = DMatrix::from_row_slice(dof, dof, &weight);
    let scale = w.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    for i in 0..dof {
        for j in 0..i {
            if (w[(i, j)] - w[(j, i)]).abs() > 1e-9 * scale {
                return Err(err(
                    format!("{WEIGHT}[{}]", i * dof + j),
                    format!(
                        "{:e} differs from its transpose [{}] ({:e}): the weight must be \
                         symmetric",
                        w[(i, j)],
                        j * dof + i,
                        w[(j, i)]
                    ),
                ));
            }
        }
    }
    if dof > 0 && scale > 0.0 {
        let min = SymmetricEigen::new(&w / scale).eigenvalues.min();
        if min < -SEMI_DEFINITE_TOLERANCE {
            return Err(err(
                WEIGHT,
                format!(
                    "not positive semi-definite (relative eigenvalue {min:e}): a joint \
                     configuration would get a negative leverage"
                ),
            ));
        }
    }
    Ok(Some(JointLeverage { mean, weight }))
}

fn parameters(v: Option<&Value>, arm: &Arm) -> Result<Vec<Param>, CalFileError> {
    let Some(v) = v else {
        return Ok(Vec::new());
    };
    let a = v
        .as_array()
        .ok_or_else(|| err("uncertainty.parameters", "must be an array of names"))?;
    let mut out: Vec<Param> = Vec::with_capacity(a.len());
    for (k, v) in a.iter().enumerate() {
        let path = format!("uncertainty.parameters[{k}]");
        let s = v.as_str().ok_or_else(|| err(&path, "must be a string"))?;
        let p = parse_name(s, arm).map_err(|m| err(&path, m))?;
        if out.contains(&p) {
            return Err(err(&path, format!("`{s}` is listed twice")));
        }
        out.push(p);
    }
    Ok(out)
}

/// The covariance: n² finite numbers, symmetric, positive semi-definite to rounding, each
/// standard deviation within its parameter's limit.
fn covariance(
    v: Option<&Value>,
    parameters: &[Param],
    limits: &Limits,
) -> Result<Vec<f64>, CalFileError> {
    let n = parameters.len();
    const PATH: &str = "uncertainty.covariance";
    let c: Vec<f64> = match v {
        None if n == 0 => return Ok(Vec::new()),
        None => {
            return Err(err(
                PATH,
                format!("missing: {n} parameters need {n}² values"),
            ))
        }
        Some(Value::Array(a)) => a
            .iter()
            .enumerate()
            .map(|(k, v)| finite(v, &format!("{PATH}[{k}]")))
            .collect::<Result<_, _>>()?,
        Some(_) => return Err(err(PATH, "must be an array of numbers")),
    };
    if c.len() != n * n {
        return Err(err(
            PATH,
            format!("{} values; {n} parameters need {}", c.len(), n * n),
        ));
    }
    for i in 0..n {
        if c[i * n + i] < 0.0 {
            return Err(err(
                format!("{PATH}[{}]", i * n + i),
                "a variance (diagonal) is negative",
            ));
        }
        let limit = limit(parameters[i], limits);
        if c[i * n + i].sqrt() > limit {
            return Err(err(
                format!("{PATH}[{}]", i * n + i),
                format!(
                    "a standard deviation of {:e} is beyond the parameter's limit of {limit}",
                    c[i * n + i].sqrt()
                ),
            ));
        }
        for j in 0..i {
            let (a, b) = (c[i * n + j], c[j * n + i]);
            let scale = (c[i * n + i] * c[j * n + j]).sqrt();
            if (a - b).abs() > 1e-9 * scale.max(f64::MIN_POSITIVE) {
                return Err(err(
                    format!("{PATH}[{}]", i * n + j),
                    format!(
                        "{a:e} differs from its mirror [{}] = {b:e}: not symmetric",
                        j * n + i
                    ),
                ));
            }
        }
    }
    // A zero variance beside a non-zero covariance: not semi-definite at any tolerance (the
    // 2×2 minor is −c²), and the correlation matrix below cannot see it.
    for i in 0..n {
        for j in 0..n {
            if i != j && c[i * n + i] == 0.0 && c[i * n + j] != 0.0 {
                return Err(err(
                    format!("{PATH}[{}]", i * n + j),
                    format!(
                        "{:e} beside a zero variance [{}]: not positive semi-definite",
                        c[i * n + j],
                        i * n + i
                    ),
                ));
            }
        }
    }
    // Positive semi-definite, judged on the correlation matrix so units do not matter.
    let d: Vec<f64> = (0..n).map(|i| c[i * n + i].sqrt()).collect();
    let r = DMatrix::from_fn(n, n, |i, j| {
        if d[i] == 0.0 || d[j] == 0.0 {
            f64::from(u8::from(i == j))
        } else {
            c[i * n + j] / (d[i] * d[j])
        }
    });
    if n > 0 {
        let min = SymmetricEigen::new(r).eigenvalues.min();
        if min < -SEMI_DEFINITE_TOLERANCE {
            return Err(err(
                PATH,
                format!("not positive semi-definite (correlation eigenvalue {min:e})"),
            ));
        }
    }
    Ok(c)
}

/// Appends the section to a calibration file's text.
pub fn write(u: &Uncertainty, arm: &Arm, s: &mut String) {
    use std::fmt::Write as _;
    let num = |x: f64| format!("{x:?}");
    let _ = writeln!(s, "\n[uncertainty]");
    let names: Vec<String> = u
        .parameters
        .iter()
        .map(|p| format!("\"{}\"", name(*p, arm).unwrap_or_else(|| p.to_string())))
        .collect();
    let _ = writeln!(s, "parameters = [{}]", names.join(", "));
    let n = u.parameters.len();
    let _ = writeln!(s, "covariance = [");
    for row in u.covariance.chunks(n.max(1)) {
        let vals: Vec<String> = row.iter().map(|x| num(*x)).collect();
        let _ = writeln!(s, "  {},", vals.join(", "));
    }
    let _ = writeln!(s, "]");
    let e = &u.encoder_counts;
    if e.iter().all(|x| Some(x) == e.first()) && !e.is_empty() {
        let _ = writeln!(s, "encoder_counts = {}", num(e[0]));
    } else {
        let vals: Vec<String> = e.iter().map(|x| num(*x)).collect();
        let _ = writeln!(s, "encoder_counts = [{}]", vals.join(", "));
    }
    let _ = writeln!(s, "probing_mm = {}", num(u.probing_mm));
    let _ = writeln!(s, "temperature_c = {}", num(u.temperature_c));
    let _ = writeln!(s, "model_mm = {}", num(u.model_mm));
    if let Some(p) = &u.pose {
        let _ = writeln!(s, "pose_factor = [");
        for col in &p.factor {
            let vals: Vec<String> = col.iter().map(|x| num(*x)).collect();
            let _ = writeln!(s, "  [{}],", vals.join(", "));
        }
        let _ = writeln!(s, "]");
        let _ = writeln!(s, "pose_shrink = {}", num(p.shrink));
        let _ = writeln!(s, "pose_leverage_mean = {}", num(p.leverage_mean));
        if let Some(j) = &p.joints {
            let vals: Vec<String> = j.mean.iter().map(|x| num(*x)).collect();
            let _ = writeln!(s, "pose_joint_mean = [{}]", vals.join(", "));
            let _ = writeln!(s, "pose_joint_weight = [");
            for row in j.weight.chunks(j.mean.len().max(1)) {
                let vals: Vec<String> = row.iter().map(|x| num(*x)).collect();
                let _ = writeln!(s, "  {},", vals.join(", "));
            }
            let _ = writeln!(s, "]");
        }
    }
}
