//! The calibration's uncertainty budget as the hub carries it: the reading's own terms
//! (`quatarm::table::budget`) and the parameter covariance (`quatarm::table::parameters`:
//! each parameter as the way it moves the tip, and C's Cholesky factor), with the budget's
//! pose part after it where the budget has one (`quatarm::table::pose`), and the joint
//! leverage after that where the pose part has one (`quatarm::table::joint_leverage`).

use nalgebra::DMatrix;
use quatarm::table::budget::BudgetData;
use quatarm::table::joint_leverage::{self, JointLeverageData};
use quatarm::table::parameters::{Column, Kind, ParameterData, LIMIT, MAX_PARAMETERS};
use quatarm::table::pose::{PoseData, MAX_FACTORS};
use quatarm::table::MAX_JOINTS;
use quatarm_ref::forward::tilt_axis;
use quatarm_ref::uncertainty::{JointLeverage, Link, Param, PoseLeverage, Uncertainty};
use quatarm_ref::Arm;

// The file's cap on the pose part's columns (what `armcal` estimates and `quatarm_ref`
// reads) is the table's: the two crates cannot see each other, so the one crate that sees
// both holds them equal at compile time.
const _: () = assert!(quatarm_ref::uncertainty::POSE_RANK_MAX == MAX_FACTORS);
// The same for the limit on a joint's mean angle.
const _: () =
    assert!(quatarm_ref::uncertainty::JOINT_MEAN_LIMIT == joint_leverage::MEAN_LIMIT as f64);

/// The table's budget of a calibration file's `[uncertainty]` section.
pub fn budget_data(u: &Uncertainty) -> BudgetData {
    let mut encoder_counts = [0.0; MAX_JOINTS];
    for (e, c) in encoder_counts.iter_mut().zip(&u.encoder_counts) {
        *e = *c;
    }
    BudgetData {
        encoder_counts,
        probing_mm: u.probing_mm,
        model_mm: u.model_mm,
        temperature_c: u.temperature_c,
    }
}

/// A budget's parameter block, owned: what [`ParameterData`] borrows.
#[derive(Clone, Debug, PartialEq)]
pub struct Block {
    /// One column record per listed parameter.
    pub columns: Vec<Column>,
    /// C's lower Cholesky factor, row by row.
    pub factor: Vec<f32>,
    /// The budget's pose part, where it has one.
    pub pose: Option<PoseBlock>,
}

/// A budget's pose part, owned, as the table holds it (`quatarm::table::pose`).
#[derive(Clone, Debug, PartialEq)]
pub struct PoseBlock {
    /// D row by parameter: row i holds D_i0 … D_i(r−1).
    pub factor: Vec<f32>,
    /// r, D's columns.
    pub count: usize,
    /// b.
    pub shrink: f32,
    /// m (mm²).
    pub leverage_mean: f32,
    /// The joint leverage, where the budget has one.
    pub joints: Option<JointBlock>,
}

/// A budget's joint leverage, owned, as the table holds it
/// (`quatarm::table::joint_leverage`).
#[derive(Clone, Debug, PartialEq)]
pub struct JointBlock {
    /// μ, one angle a joint (rad).
    pub mean: Vec<f32>,
    /// W's upper triangle, row by row (1/rad²).
    pub weight: Vec<f32>,
}

impl Block {
    /// The block as the table encoder takes it.
    pub fn data(&self) -> ParameterData<'_> {
        ParameterData {
            columns: &self.columns,
            factor: &self.factor,
            pose: self.pose.as_ref().map(|p| PoseData {
                factor: &p.factor,
                count: p.count,
                shrink: p.shrink,
                leverage_mean: p.leverage_mean,
                joints: p.joints.as_ref().map(|j| JointLeverageData {
                    mean: &j.mean,
                    weight: &j.weight,
                }),
            }),
        }
    }
}

/// The table's pose part of a budget over `p` parameters (`quatarm_ref::uncertainty::
/// PoseLeverage`: D's columns, b, m). `Err` names the key and says why the hub could not
/// take it: more columns than [`MAX_FACTORS`] (the cap the host's estimate keeps to), a
/// column of another length than the parameters', a value that is not finite or not within
/// the table's limits (b ≥ 0, m > 0, each within `quatarm::table::parameters::LIMIT`) — or
/// that f32 rounds to 0 (m) or out of range — and its joint leverage ([`joint_data`]) for
/// an arm of `dof` joints.
pub fn pose_data(pose: &PoseLeverage, p: usize, dof: usize) -> Result<PoseBlock, String> {
    let r = pose.factor.len();
    if !(1..=MAX_FACTORS).contains(&r) {
        return Err(format!(
            "pose_factor: {r} columns; a table carries 1 to {MAX_FACTORS} (the hub's J·D \
             costs 3 · P multiply-adds a column)"
        ));
    }
    if let Some((j, c)) = pose.factor.iter().enumerate().find(|(_, c)| c.len() != p) {
        return Err(format!(
            "pose_factor[{j}]: {} values for {p} parameters",
            c.len()
        ));
    }
    let limit = f64::from(LIMIT);
    let within = |x: f64| x.is_finite() && x.abs() <= limit;
    if let Some((j, i)) = (0..r)
        .flat_map(|j| (0..p).map(move |i| (j, i)))
        .find(|&(j, i)| !within(pose.factor[j][i]))
    {
        return Err(format!(
            "pose_factor[{j}][{i}]: {} is not finite or beyond {limit:e}",
            pose.factor[j][i]
        ));
    }
    if !(within(pose.shrink) && pose.shrink >= 0.0) {
        return Err(format!(
            "pose_shrink: {} is not a shrink (finite, 0 to {limit:e})",
            pose.shrink
        ));
    }
    let m = pose.leverage_mean as f32;
    if !(within(pose.leverage_mean) && m > 0.0) {
        return Err(format!(
            "pose_leverage_mean: {} mm² is not a mean leverage (finite, > 0 in f32, up to \
             {limit:e})",
            pose.leverage_mean
        ));
    }
    Ok(PoseBlock {
        factor: (0..p)
            .flat_map(|i| pose.factor.iter().map(move |c| c[i] as f32))
            .collect(),
        count: r,
        shrink: pose.shrink as f32,
        leverage_mean: m,
        joints: pose
            .joints
            .as_ref()
            .map(|j| joint_data(j, dof))
            .transpose()?,
    })
}

/// The table's joint leverage of a budget for an arm of `dof` joints
/// (`quatarm_ref::uncertainty::JointLeverage`: μ, W). `Err` names the key and says why the
/// hub could not take it: lengths other than the arm's joints', a mean that is not finite or
/// beyond `joint_leverage::MEAN_LIMIT`, a weight that is not finite, beyond
/// `joint_leverage::WEIGHT_LIMIT` in f32 or not symmetric to f32's rounding, or a negative
/// diagonal (a budget that the hub would misread is never written without its joints).
pub fn joint_data(joints: &JointLeverage, dof: usize) -> Result<JointBlock, String> {
    let k = joints.mean.len();
    if k != dof || !(quatarm::table::MIN_JOINTS..=MAX_JOINTS).contains(&k) {
        return Err(format!(
            "pose_joint_mean: {k} values; the table's arm has {dof} joints"
        ));
    }
    if joints.weight.len() != k * k {
        return Err(format!(
            "pose_joint_weight: {} values; {k} joints need {}",
            joints.weight.len(),
            k * k
        ));
    }
    let mean_limit = f64::from(joint_leverage::MEAN_LIMIT);
    if let Some((i, x)) = joints
        .mean
        .iter()
        .enumerate()
        .find(|(_, x)| !(x.is_finite() && x.abs() <= mean_limit))
    {
        return Err(format!(
            "pose_joint_mean[{i}]: {x:e} rad is not finite or beyond {mean_limit} rad"
        ));
    }
    let limit = f64::from(joint_leverage::WEIGHT_LIMIT);
    let w = |i: usize, j: usize| joints.weight[i * k + j];
    let mut weight = Vec::with_capacity(joint_leverage::weight_len(k));
    for i in 0..k {
        for j in i..k {
            let (x, y) = (w(i, j), w(j, i));
            let at = i * k + j;
            if !(x.is_finite() && x.abs() <= limit) {
                return Err(format!(
                    "pose_joint_weight[{at}]: {x:e} is not finite or beyond {limit:e} 1/rad²"
                ));
            }
            if i == j && x < 0.0 {
                return Err(format!(
                    "pose_joint_weight[{at}]: {x:e} is a negative diagonal entry"
                ));
            }
            // The table keeps the upper triangle: the lower one must be the same number.
            if (x - y).abs() > 1e-6 * x.abs().max(y.abs()) {
                return Err(format!(
                    "pose_joint_weight[{at}]: {x:e} differs from its transpose [{}] ({y:e})",
                    j * k + i
                ));
            }
            weight.push(x as f32);
        }
    }
    Ok(JointBlock {
        mean: joints.mean.iter().map(|&x| x as f32).collect(),
        weight,
    })
}

/// The parameter block of a budget: one column record per listed parameter and C's lower
/// Cholesky factor (row by row, f32). `Ok(None)` where the budget lists no parameter; `Err`
/// says why the block cannot be written.
pub fn parameter_data(u: &Uncertainty, arm: &Arm) -> Result<Option<Block>, String> {
    let p = u.parameters.len();
    if p == 0 {
        return Ok(None);
    }
    if p > MAX_PARAMETERS {
        return Err(format!(
            "{p} parameters; a table carries the covariance of at most {MAX_PARAMETERS}"
        ));
    }
    Ok(Some(Block {
        columns: u
            .parameters
            .iter()
            .map(|p| column(*p, arm))
            .collect::<Result<_, _>>()?,
        factor: factor(&u.matrix())?,
        pose: u
            .pose
            .as_ref()
            .map(|pose| pose_data(pose, p, arm.joints.len()))
            .transpose()?,
    }))
}

/// How parameter `p` moves the tip (`quatarm::table::parameters`, its table of kinds):
/// the host's analytic Jacobian (`armcal::jacobian`) written as the hub evaluates it. The
/// match over [`Param`] is exhaustive, without a catch-all: a new kind of parameter fails to
/// compile here until it says its column. `Err` for the instrument frame's unknowns, which no
/// budget lists (the reader refuses them).
///
/// A probe's error and expansion are a shift of the last joint's frame (kind 5) on an arm of
/// one probe, as they always were; on an arm of several, a shift of that probe (kind 8, its
/// id in `order`), which the hub counts only while that probe is mounted.
fn column(p: Param, arm: &Arm) -> Result<Column, String> {
    let n = arm.dof();
    let shift = |joint: usize, vector: [f64; 3], w0: f64, w1: f64| Column {
        vector: vector.map(|x| x as f32),
        w0: w0 as f32,
        w1: w1 as f32,
        ..Column::new(Kind::Shift, joint as u8)
    };
    let probe_shift = |k: usize, vector: [f64; 3], w0: f64, w1: f64| {
        let c = shift(n - 1, vector, w0, w1);
        match arm.probe_at(k) {
            Some(p) if arm.probe_count() > 1 => Column {
                kind: Kind::ProbeShift,
                order: u16::from(p.id),
                ..c
            },
            _ => c,
        }
    };
    let unit = |c: usize| {
        let mut e = [0.0; 3];
        e[c] = 1.0;
        e
    };
    Ok(match p {
        Param::ZeroOffset(j) => Column::new(Kind::Turn, j as u8),
        Param::Tilt(j, c) => {
            let joint = &arm.joints[j];
            let w = tilt_axis(joint.axis, joint.tilt, c);
            Column {
                vector: [w.x as f32, w.y as f32, w.z as f32],
                ..Column::new(Kind::Tilt, j as u8)
            }
        }
        Param::LinkError(j, c) => shift(j, unit(c), 1.0, arm.joints[j].thermal),
        Param::ProbeError(k, c) => {
            let thermal = arm.probe_at(k).map_or(0.0, |p| p.thermal);
            probe_shift(k, unit(c), 1.0, thermal)
        }
        Param::Harmonic { joint, order, cos } => Column {
            order: order as u16,
            ..Column::new(if cos { Kind::TurnCos } else { Kind::TurnSin }, joint as u8)
        },
        Param::Gravity(j) => Column::new(Kind::Gravity, j as u8),
        Param::Thermal(Link::Joint(j)) => shift(j, arm.joints[j].actual_link(), 0.0, 1.0),
        Param::Thermal(Link::Probe) => probe_shift(0, arm.probe.actual(), 0.0, 1.0),
        Param::Wobble { joint, order, coef } => {
            // The tilt's column at the fixed tilt, weighed by sin or cos hθ (the wobble moves
            // the axis by ~1e-4 of itself: far below U95's 1e-3).
            let j = &arm.joints[joint];
            let w = tilt_axis(j.axis, j.tilt, usize::from(coef / 2));
            let kind = if coef % 2 == 0 {
                Kind::TiltSin
            } else {
                Kind::TiltCos
            };
            Column {
                vector: [w.x as f32, w.y as f32, w.z as f32],
                order: order as u16,
                ..Column::new(kind, joint as u8)
            }
        }
        Param::FrameRotation(_) | Param::FrameTranslation(_) => {
            return Err(format!(
                "{p} belongs to the instrument frame, not the arm: a table has no column for it"
            ))
        }
    })
}

/// L with C = L Lᵀ, lower triangular, row by row. C is a covariance, positive semidefinite
/// but possibly singular (a parameter the data does not see), where Cholesky fails: so
/// C = S Sᵀ with S = V √Λ from its eigenvectors (negative rounding clamped to 0), and the QR
/// decomposition Sᵀ = Q R gives C = Rᵀ R, L = Rᵀ.
fn factor(c: &DMatrix<f64>) -> Result<Vec<f32>, String> {
    let p = c.nrows();
    if c.iter().any(|x| !x.is_finite()) {
        return Err("the covariance has a value that is not finite".into());
    }
    let sym = (c + c.transpose()) * 0.5;
    let eig = sym.symmetric_eigen();
    let mut s = eig.eigenvectors.clone();
    for (k, lambda) in eig.eigenvalues.iter().enumerate() {
        let root = lambda.max(0.0).sqrt();
        s.column_mut(k).scale_mut(root);
    }
    let r = s.transpose().qr().r();
    let mut out = Vec::with_capacity(p * (p + 1) / 2);
    for i in 0..p {
        for k in 0..=i {
            out.push(r[(k, i)] as f32);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A probe's error and expansion: a shift of the last frame on an arm of one probe (its
    /// tables as before), a shift of that probe, by id, on an arm of several; and the table
    /// takes the block.
    #[test]
    fn a_probes_parameters_name_their_probe_on_an_arm_of_several() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/default-6-probes.toml");
        let arm = quatarm_ref::calfile::read(&path).unwrap().arm;
        let keys = [
            Param::ProbeError(0, 0),
            Param::ProbeError(2, 1),
            Param::Thermal(Link::Probe),
            Param::LinkError(5, 2),
        ];
        let budget = Uncertainty {
            parameters: keys.to_vec(),
            covariance: (0..16)
                .map(|k| if k % 5 == 0 { 1e-6 } else { 0.0 })
                .collect(),
            encoder_counts: vec![0.3; 6],
            probing_mm: 0.002,
            temperature_c: 0.2,
            model_mm: 0.0,
            pose: None,
        };
        let kinds = |arm: &Arm| -> Vec<(Kind, u16, u8)> {
            let b = parameter_data(&budget, arm).unwrap().unwrap();
            b.columns
                .iter()
                .map(|c| (c.kind, c.order, c.joint))
                .collect()
        };
        assert_eq!(
            kinds(&arm),
            [
                (Kind::ProbeShift, 1, 5),
                (Kind::ProbeShift, 5, 5),
                (Kind::ProbeShift, 1, 5),
                (Kind::Shift, 0, 5)
            ]
        );
        let table = crate::tablebuild::build_with(&arm, Some(&budget)).unwrap();
        let t = quatarm::Table::parse(&table).unwrap();
        assert_eq!(t.parameters().unwrap().count(), 4);
        assert_eq!(t.probe_count(), 3);
        // One probe: shifts, as before there were several.
        let mut one = arm.clone();
        one.more_probes.clear();
        let mut single = budget.clone();
        single.parameters[1] = Param::ProbeError(0, 1);
        let b = parameter_data(&single, &one).unwrap().unwrap();
        assert!(b.columns[..3]
            .iter()
            .all(|c| c.kind == Kind::Shift && c.order == 0));
    }

    /// The shipped six-joint arm and a budget over its six zero offsets (a diagonal C) whose
    /// pose part has D's columns `factor`, b = 0.4, m = 3e-6 and the joint leverage `joints`:
    /// the pose part's tests vary only those.
    fn arm_with_pose(
        factor: Vec<Vec<f64>>,
        joints: Option<JointLeverage>,
    ) -> (quatarm_ref::arm::Arm, Uncertainty) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/default-6.toml");
        let arm = quatarm_ref::calfile::read(&path).unwrap().arm;
        let budget = Uncertainty {
            parameters: (0..6).map(Param::ZeroOffset).collect(),
            covariance: (0..36)
                .map(|k| if k % 7 == 0 { 1e-10 } else { 0.0 })
                .collect(),
            encoder_counts: vec![0.3; 6],
            probing_mm: 0.002,
            temperature_c: 0.2,
            model_mm: 0.0,
            pose: Some(PoseLeverage {
                factor,
                shrink: 0.4,
                leverage_mean: 3e-6,
                joints,
            }),
        };
        (arm, budget)
    }

    /// The budget's pose part reaches the table: D's columns as the rows' entries, b and m;
    /// a budget without one writes the block as before; a malformed one is refused naming
    /// its key, and so is one that would make the table longer than a hub holds.
    #[test]
    fn the_pose_part_reaches_the_table_or_is_refused_by_key() {
        let factor = vec![
            (0..6).map(|i| 1e-6 * i as f64).collect::<Vec<_>>(),
            (0..6).map(|i| -2e-6 * i as f64 + 1e-7).collect(),
        ];
        let (arm, mut budget) = arm_with_pose(factor.clone(), None);
        let table = crate::tablebuild::build_with(&arm, Some(&budget)).unwrap();
        let t = quatarm::Table::parse(&table).unwrap();
        let pose = t.parameters().unwrap().pose().unwrap();
        assert_eq!(
            (pose.count(), pose.shrink(), pose.leverage_mean()),
            (2, 0.4, 3e-6)
        );
        for (j, column) in factor.iter().enumerate() {
            for (i, x) in column.iter().enumerate() {
                assert_eq!(pose.entry(i, j), Some(*x as f32));
            }
        }
        let without = Uncertainty {
            pose: None,
            ..budget.clone()
        };
        let plain = crate::tablebuild::build_with(&arm, Some(&without)).unwrap();
        assert_eq!(plain.len(), table.len() - quatarm::table::pose::len(6, 2));
        assert!(quatarm::Table::parse(&plain)
            .unwrap()
            .parameters()
            .unwrap()
            .pose()
            .is_none());
        let bad = |f: &dyn Fn(&mut PoseLeverage)| {
            let mut u = budget.clone();
            f(u.pose.as_mut().unwrap());
            crate::tablebuild::build_with(&arm, Some(&u))
                .unwrap_err()
                .to_string()
        };
        for (msg, key) in [
            (bad(&|p| p.factor.clear()), "pose_factor: 0 columns"),
            (
                bad(&|p| p.factor = vec![vec![0.0; 6]; 17]),
                "pose_factor: 17 columns",
            ),
            (
                bad(&|p| p.factor[1].pop().map(drop).unwrap()),
                "pose_factor[1]: 5 values",
            ),
            (bad(&|p| p.factor[0][3] = f64::NAN), "pose_factor[0][3]"),
            (bad(&|p| p.shrink = -0.1), "pose_shrink"),
            (bad(&|p| p.leverage_mean = 0.0), "pose_leverage_mean"),
            (bad(&|p| p.leverage_mean = 1e-50), "pose_leverage_mean"),
        ] {
            assert!(msg.contains(key), "{msg}");
        }
        // 64 parameters with 16 columns: 4,108 bytes more than a hub holds with them.
        let keys: Vec<Param> = (0..6)
            .flat_map(|j| {
                [Param::ZeroOffset(j), Param::Tilt(j, 0), Param::Tilt(j, 1)]
                    .into_iter()
                    .chain((0..3).map(move |c| Param::LinkError(j, c)))
            })
            .chain((0..28).map(|k| Param::Harmonic {
                joint: k % 6,
                order: 1 + (k / 6) as u32,
                cos: false,
            }))
            .collect();
        let p = keys.len();
        assert_eq!(p, 64);
        budget.parameters = keys;
        budget.covariance = (0..p * p)
            .map(|k| if k % (p + 1) == 0 { 1e-10 } else { 0.0 })
            .collect();
        budget.pose = Some(PoseLeverage {
            factor: vec![vec![1e-6; p]; 16],
            shrink: 0.0,
            leverage_mean: 1e-6,
            joints: None,
        });
        let msg = crate::tablebuild::build_with(&arm, Some(&budget))
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("pose_factor") && msg.contains("a hub holds at most"),
            "{msg}"
        );
    }

    /// The budget's joint leverage reaches the table (μ, W's upper triangle) whenever the
    /// budget has it — a budget with joints never builds a table without them — and a
    /// malformed one is refused naming its key.
    #[test]
    fn the_joint_leverage_reaches_the_table_or_is_refused_by_key() {
        let mean = vec![0.5, 1.0, 3.0, 6.0, -0.1, 2.0];
        // W symmetric: 1 + i on the diagonal, 0.1 · (i + j) off it.
        let weight: Vec<f64> = (0..36)
            .map(|x| {
                let (i, j) = (x / 6, x % 6);
                if i == j {
                    1.0 + i as f64
                } else {
                    0.1 * (i + j) as f64
                }
            })
            .collect();
        let (arm, budget) = arm_with_pose(
            vec![(0..6).map(|i| 1e-6 * i as f64).collect()],
            Some(JointLeverage {
                mean: mean.clone(),
                weight: weight.clone(),
            }),
        );
        let table = crate::tablebuild::build_with(&arm, Some(&budget)).unwrap();
        let t = quatarm::Table::parse(&table).unwrap();
        let j = t.parameters().unwrap().pose().unwrap().joints().unwrap();
        assert_eq!(j.count(), 6);
        for i in 0..6 {
            assert_eq!(j.mean(i), Some(mean[i] as f32));
            for k in 0..6 {
                assert_eq!(j.weight(i, k), Some(weight[i * 6 + k] as f32), "({i}, {k})");
            }
        }
        let mut without = budget.clone();
        without.pose.as_mut().unwrap().joints = None;
        let plain = crate::tablebuild::build_with(&arm, Some(&without)).unwrap();
        assert_eq!(plain.len(), table.len() - joint_leverage::len(6));
        let bad = |f: &dyn Fn(&mut JointLeverage)| {
            let mut u = budget.clone();
            f(u.pose.as_mut().unwrap().joints.as_mut().unwrap());
            crate::tablebuild::build_with(&arm, Some(&u))
                .unwrap_err()
                .to_string()
        };
        for (msg, key) in [
            (
                bad(&|j| j.mean.truncate(5)),
                "pose_joint_mean: 5 values; the table's arm has 6",
            ),
            (
                bad(&|j| j.weight.truncate(35)),
                "pose_joint_weight: 35 values",
            ),
            (bad(&|j| j.mean[2] = f64::NAN), "pose_joint_mean[2]"),
            (bad(&|j| j.mean[4] = -64.5), "pose_joint_mean[4]"),
            (bad(&|j| j.weight[7] = 2e12), "pose_joint_weight[7]"),
            (bad(&|j| j.weight[14] = -1e-3), "pose_joint_weight[14]"),
            (
                bad(&|j| j.weight[3] = 5.0),
                "pose_joint_weight[3]: 5e0 differs",
            ),
        ] {
            assert!(msg.contains(key), "{key}: {msg}");
        }
    }

    /// L Lᵀ gives C back, also for a singular C (one parameter a copy of another).
    #[test]
    fn the_factor_gives_the_covariance_back() {
        let a = DMatrix::from_row_slice(3, 3, &[4.0, 2.0, 0.6, 1.0, 3.0, -0.5, 0.2, 0.1, 1.5]);
        let mut c = &a * a.transpose() * 1e-6;
        // Make parameter 2 a copy of parameter 0: C singular.
        for k in 0..3 {
            c[(2, k)] = c[(0, k)];
        }
        for k in 0..3 {
            c[(k, 2)] = c[(k, 0)];
        }
        c[(2, 2)] = c[(0, 0)];
        let l = factor(&c).unwrap();
        let mut lm = DMatrix::zeros(3, 3);
        let mut at = 0;
        for i in 0..3 {
            for k in 0..=i {
                lm[(i, k)] = f64::from(l[at]);
                at += 1;
            }
        }
        let back = &lm * lm.transpose();
        let err = (back - &c).abs().max();
        assert!(err < 1e-6 * c.abs().max(), "{err:e}");
    }
}
