//! The least-squares problem a calibration solves ([`Problem`], the state it moves,
//! [`State`]): the residuals and their Jacobian, block by block, and the instrument frame it
//! starts from ([`start_frame`]). What is fitted, held or pulled by a prior is decided
//! elsewhere in the fit; this file only evaluates.
//!
//! # The residuals
//! - `point`: R_T p + t_T − x, with the instrument frame (R_T, t_T) estimated alongside.
//! - `spat`: the fixed point of a group is never an unknown of the solver. For any arm, the
//!   point that fits a group best is the mean of its ball centres, so each row's residual is
//!   its ball centre minus the group mean (variable projection: exact, and the solver's size
//!   does not grow with the number of groups).
//! - `length`: the two ball centres a, b with |a − b| = L. Each end's rows are centred on the
//!   end's mean (m_a, m_b) as for `spat`; the best constrained centres then move along the
//!   bar by the length discrepancy, which adds exactly √(n_a n_b / (n_a + n_b)) · (|m_a − m_b| − L)
//!   as one more residual. The reduced problem has the same minimum as the one with the
//!   centres as unknowns.
//! - `sphere`: each row's distance from the group's sphere centre c minus the known radius
//!   R = (diameter + ball diameter)/2, one scalar per row. The centre is the best one for the
//!   arm (a small fit with R known, as L_Dia takes it), and its three unknowns are projected
//!   out of the Jacobian: J ← J − A (AᵀA)⁻¹ Aᵀ J with A's rows −u_iᵀ, the derivatives of the
//!   residuals by the centre (Kaufman's variable projection, exact in the gradient at the
//!   best centre; the covariance from it is marginal over the centre). A sphere of known
//!   diameter is a spat cone with a known radius: it fixes the scale, not the placement.
//!
//! All residuals are millimetres of ball position, so one noise level weighs them all.

use crate::data::{Dataset, Layout, LengthGroup};
use crate::fit::ident::RFactor;
use crate::fit::jacobian::tip_jacobian;
use crate::fit::lm::{self, Normal};
use crate::fit::residuals::{best_rigid, Rigid};
use crate::params::{apply, Param};
use nalgebra::{DMatrix, DVector, Rotation3, Vector3};
use quatarm_ref::arm::Arm;

/// The state the solver moves: increments of the arm unknowns and the instrument frame.
#[derive(Clone, Debug)]
pub struct State {
    /// Increments of every unknown (aligned with the unknowns; frame entries stay 0).
    pub x: Vec<f64>,
    /// Instrument frame.
    pub frame: Rigid,
}

/// Row-block evaluation of the residuals and Jacobian for a set of unknowns.
pub struct Problem<'a> {
    data: &'a Dataset,
    layout: &'a Layout,
    base: &'a Arm,
    all: &'a [Param],
    /// Positions (in `all`) of the unknowns solved for, in solver order.
    kept: Vec<usize>,
    arm_params: Vec<Param>,
    arm_cols: Vec<usize>,
    frame_cols: Vec<(Param, usize)>,
    /// Prior weight and centre per kept unknown: the residual w·(x − m) joins the cost
    /// (w = 0: no prior).
    prior: Vec<(f64, f64)>,
}

/// Evaluates the rows `idx` of one fixed point (a spat group, a bar's end) through `eval` and
/// appends them centred on their mean to `br` (residuals) and, with `jac`, their Jacobian rows
/// (each 3 × `n`) centred on their mean to `bj`; returns the mean centre and leaves the mean
/// Jacobian in `mj`. The fixed point's unknown position drops out this way.
fn centred(
    eval: &mut dyn FnMut(usize, &mut [f64]) -> Vector3<f64>,
    jac: bool,
    n: usize,
    idx: &[usize],
    br: &mut Vec<f64>,
    bj: &mut Vec<f64>,
    mj: &mut [f64],
) -> Vector3<f64> {
    let r0 = br.len();
    let j0 = bj.len();
    let mut m = Vector3::zeros();
    for &i in idx {
        bj.resize(bj.len() + if jac { 3 * n } else { 0 }, 0.0);
        let len = bj.len();
        let q = eval(i, if jac { &mut bj[len - 3 * n..] } else { &mut [] });
        br.extend_from_slice(&[q.x, q.y, q.z]);
        m += q;
    }
    let k = idx.len() as f64;
    m /= k;
    for row in br[r0..].chunks_mut(3) {
        for c in 0..3 {
            row[c] -= m[c];
        }
    }
    if jac {
        mj.iter_mut().for_each(|v| *v = 0.0);
        for block in bj[j0..].chunks(3 * n) {
            for (a, b) in mj.iter_mut().zip(block) {
                *a += b;
            }
        }
        mj.iter_mut().for_each(|v| *v /= k);
        for block in bj[j0..].chunks_mut(3 * n) {
            for (a, b) in block.iter_mut().zip(mj.iter()) {
                *a -= b;
            }
        }
    }
    m
}

/// A sphere group's radial rows u_iᵀ J_i (`us` the unit directions from the centre, `bj` the
/// rows' 3 × `n` Jacobian blocks), with the centre's three unknowns projected out (the
/// centre is fitted for every state, so the solver must not move along it).
fn radial_rows(us: &[Vector3<f64>], bj: &[f64], n: usize) -> DMatrix<f64> {
    let mut radial = DMatrix::zeros(us.len(), n);
    for (k, u) in us.iter().enumerate() {
        let block = &bj[k * 3 * n..(k + 1) * 3 * n];
        for col in 0..n {
            radial[(k, col)] = (0..3).map(|c| u[c] * block[c * n + col]).sum();
        }
    }
    let a = DMatrix::from_fn(us.len(), 3, |k, c| -us[k][c]);
    let ata = a.transpose() * &a;
    if let Some(inv) = ata.try_inverse() {
        radial -= &a * (inv * (a.transpose() * &radial));
    }
    radial
}

/// One state's ball centres through the instrument frame, q = R_T p + t_T, with (when `jac`)
/// their Jacobian rows: what every residual block of [`Problem::visit`] is made of.
struct Balls<'a> {
    problem: &'a Problem<'a>,
    mounted: crate::fit::probes::Mounted<'a>,
    frame: &'a Rigid,
    jac: bool,
    /// The arm unknowns' derivatives of the tip (scratch, one per arm unknown).
    cols: Vec<Vector3<f64>>,
}

impl Balls<'_> {
    /// The ball centre of row `i` through the frame, and its 3 × n Jacobian rows into `j`
    /// (row-major, one column per kept unknown; untouched without `jac`).
    fn at(&mut self, i: usize, j: &mut [f64]) -> Vector3<f64> {
        let p = self.problem;
        let n = p.kept.len();
        let rot = self.frame.rot;
        let row = &p.data.rows[i];
        if !self.jac {
            return rot * self.mounted.tip(row) + self.frame.trans;
        }
        let (probe, with) = self.mounted.of(row);
        let tip = tip_jacobian(
            with,
            probe,
            &p.arm_params,
            &row.theta,
            row.temp_c,
            &mut self.cols,
        );
        j.iter_mut().for_each(|v| *v = 0.0);
        for (k, &col) in p.arm_cols.iter().enumerate() {
            let v = rot * self.cols[k];
            for c in 0..3 {
                j[c * n + col] = v[c];
            }
        }
        // Frame unknowns are small motions in the arm's base frame, before R_T: rotation
        // ω gives R_T (ω × p), translation τ gives R_T τ.
        for &(param, col) in &p.frame_cols {
            let v = match param {
                Param::FrameRotation(a) => rot * Vector3::ith(a, 1.0).cross(&tip),
                Param::FrameTranslation(a) => rot.column(a).into_owned(),
                _ => Vector3::zeros(),
            };
            for c in 0..3 {
                j[c * n + col] = v[c];
            }
        }
        rot * tip + self.frame.trans
    }
}

/// A bar's rows: each end's rows centred on the end's mean ([`centred`]), then the bar's own
/// residual √(n_a n_b / (n_a + n_b)) (|m_a − m_b| − L), appended to `br` (and, with `jac`, the
/// Jacobian rows to `bj`); `mja` and `mj` are scratch for the ends' mean Jacobians.
fn bar_rows(
    eval: &mut dyn FnMut(usize, &mut [f64]) -> Vector3<f64>,
    jac: bool,
    n: usize,
    g: &LengthGroup,
    (br, bj): (&mut Vec<f64>, &mut Vec<f64>),
    (mja, mj): (&mut [f64], &mut [f64]),
) {
    let ma = centred(eval, jac, n, &g.a, br, bj, mja);
    let mb = centred(eval, jac, n, &g.b, br, bj, mj);
    let w = ((g.a.len() * g.b.len()) as f64 / (g.a.len() + g.b.len()) as f64).sqrt();
    let d = ma - mb;
    let dist = d.norm();
    br.push(w * (dist - g.length_mm));
    if jac {
        let u = if dist > 0.0 {
            d / dist
        } else {
            Vector3::zeros()
        };
        for col in 0..n {
            let v = (0..3)
                .map(|c| u[c] * (mja[c * n + col] - mj[c * n + col]))
                .sum::<f64>();
            bj.push(w * v);
        }
    }
}

/// A sphere group's rows `idx`: each ball centre's distance from the group's best centre for
/// this arm minus `radius`, appended to `br`, and (with `jac`) their radial Jacobian rows with
/// the centre projected out ([`radial_rows`]) to `bj`.
fn sphere_rows(
    eval: &mut dyn FnMut(usize, &mut [f64]) -> Vector3<f64>,
    jac: bool,
    n: usize,
    idx: &[usize],
    radius: f64,
    br: &mut Vec<f64>,
    bj: &mut Vec<f64>,
) {
    let mut qs = Vec::with_capacity(idx.len());
    for &i in idx {
        bj.resize(bj.len() + if jac { 3 * n } else { 0 }, 0.0);
        let len = bj.len();
        qs.push(eval(i, if jac { &mut bj[len - 3 * n..] } else { &mut [] }));
    }
    // Validated before any fit (`check_sphere_groups`); a group whose centre is lost
    // on the way keeps its mean, which the solver sees as a large residual.
    let c = crate::geometry::sphere::centre_of(&qs, radius)
        .unwrap_or_else(|_| qs.iter().sum::<Vector3<f64>>() / qs.len() as f64);
    let us: Vec<Vector3<f64>> = qs
        .iter()
        .map(|q| (q - c).try_normalize(0.0).unwrap_or_else(Vector3::z))
        .collect();
    br.extend(qs.iter().map(|q| (q - c).norm() - radius));
    if jac {
        let radial = radial_rows(&us, bj, n);
        bj.clear();
        bj.extend(radial.transpose().iter());
    }
}

impl<'a> Problem<'a> {
    /// A problem over the unknowns `kept` (positions in `all`).
    pub fn new(
        data: &'a Dataset,
        layout: &'a Layout,
        base: &'a Arm,
        all: &'a [Param],
        kept: &[usize],
    ) -> Problem<'a> {
        let mut arm_params = Vec::new();
        let mut arm_cols = Vec::new();
        let mut frame_cols = Vec::new();
        for (col, &i) in kept.iter().enumerate() {
            if all[i].is_frame() {
                frame_cols.push((all[i], col));
            } else {
                arm_params.push(all[i]);
                arm_cols.push(col);
            }
        }
        Problem {
            data,
            layout,
            base,
            all,
            kept: kept.to_vec(),
            arm_params,
            arm_cols,
            frame_cols,
            prior: vec![(0.0, 0.0); kept.len()],
        }
    }

    /// The same problem with a Gaussian prior: unknown k (solver order) adds the residual
    /// w_k · (x_k − m_k) for `terms[k]` = (w_k, m_k), i.e. w_k = σ/s_k for a prior standard
    /// deviation s_k against a noise σ, m_k the prior's mean (0: the start arm).
    pub fn with_prior(mut self, terms: Vec<(f64, f64)>) -> Self {
        assert_eq!(terms.len(), self.kept.len());
        self.prior = terms;
        self
    }

    fn prior_cost(&self, s: &State) -> f64 {
        self.kept
            .iter()
            .zip(&self.prior)
            .map(|(&i, (w, m))| (w * (s.x[i] - m)).powi(2))
            .sum()
    }

    /// ½‖r‖² of the data alone (without the prior's residuals).
    pub fn data_cost(&self, s: &State) -> f64 {
        let mut c = 0.0;
        self.visit(s, false, &mut |r, _| {
            c += r.iter().map(|v| v * v).sum::<f64>()
        });
        0.5 * c
    }

    /// The arm at a state.
    pub fn arm(&self, s: &State) -> Arm {
        apply(self.base, self.all, &s.x)
    }

    /// Evaluates every residual block, with its Jacobian rows (row-major, one row per
    /// residual, one column per kept unknown) when `jac`.
    ///
    /// Every ball centre goes through the frame, q = R_T p + t_T. For `point` rows that is the
    /// instrument; for `spat` and `length` rows, whose residuals are centred, it changes no
    /// residual's length, but it gives the frame's rotation unknowns a column there too:
    /// a rotation of the whole arm about its base, the symmetry such data cannot see.
    pub fn visit(&self, s: &State, jac: bool, sink: &mut dyn FnMut(&[f64], &[f64])) {
        let arm = self.arm(s);
        let n = self.kept.len();
        let mut balls = Balls {
            problem: self,
            mounted: crate::fit::probes::Mounted::new(&arm),
            frame: &s.frame,
            jac,
            cols: vec![Vector3::zeros(); self.arm_params.len()],
        };
        let mut eval = |i: usize, j: &mut [f64]| balls.at(i, j);
        let mut j = vec![0.0; 3 * n];
        for &i in &self.layout.points {
            let q = eval(i, &mut j);
            let x = self.data.rows[i].xyz.unwrap_or([0.0; 3]);
            let r = [q.x - x[0], q.y - x[1], q.z - x[2]];
            sink(&r, &j);
        }
        // Groups: ball centres and Jacobians, centred on the mean of their fixed point.
        let mut br: Vec<f64> = Vec::new();
        let mut bj: Vec<f64> = Vec::new();
        let mut mj = vec![0.0; 3 * n];
        for g in &self.layout.spat {
            br.clear();
            bj.clear();
            centred(&mut eval, jac, n, &g.rows, &mut br, &mut bj, &mut mj);
            sink(&br, &bj);
        }
        let mut mja = vec![0.0; 3 * n];
        for g in &self.layout.length {
            br.clear();
            bj.clear();
            bar_rows(
                &mut eval,
                jac,
                n,
                g,
                (&mut br, &mut bj),
                (&mut mja, &mut mj),
            );
            sink(&br, &bj);
        }
        for g in &self.layout.sphere {
            br.clear();
            bj.clear();
            let radius = crate::fit::probes::sphere_radius(&arm, self.data, g);
            sphere_rows(&mut eval, jac, n, &g.rows, radius, &mut br, &mut bj);
            sink(&br, &bj);
        }
    }

    /// The R factor of the Jacobian at a state.
    pub fn r_factor(&self, s: &State) -> DMatrix<f64> {
        let mut f = RFactor::new(self.kept.len());
        self.visit(s, true, &mut |_, j| f.push(j));
        f.finish()
    }
}

impl lm::Problem for Problem<'_> {
    type State = State;

    fn dim(&self) -> usize {
        self.kept.len()
    }

    fn cost(&self, s: &State) -> f64 {
        self.data_cost(s) + 0.5 * self.prior_cost(s)
    }

    fn normal(&self, s: &State) -> Normal {
        let n = self.kept.len();
        let mut jtj = vec![0.0; n * n];
        let mut jtr = vec![0.0; n];
        let mut cost = 0.0;
        let mut count = 0;
        self.visit(s, true, &mut |r, j| {
            for (row, rv) in r.iter().enumerate() {
                let jr = &j[row * n..(row + 1) * n];
                cost += rv * rv;
                count += 1;
                for a in 0..n {
                    let ja = jr[a];
                    if ja == 0.0 {
                        continue;
                    }
                    jtr[a] += ja * rv;
                    let dst = &mut jtj[a * n..(a + 1) * n];
                    for b in a..n {
                        dst[b] += ja * jr[b];
                    }
                }
            }
        });
        for (k, (&i, (w, m))) in self.kept.iter().zip(&self.prior).enumerate() {
            jtj[k * n + k] += w * w;
            jtr[k] += w * w * (s.x[i] - m);
        }
        let m = DMatrix::from_fn(n, n, |a, b| {
            if a <= b {
                jtj[a * n + b]
            } else {
                jtj[b * n + a]
            }
        });
        Normal {
            cost: 0.5 * (cost + self.prior_cost(s)),
            jtj: m,
            jtr: DVector::from_vec(jtr),
            residuals: count,
        }
    }

    fn step(&self, s: &State, dx: &[f64]) -> State {
        let mut t = s.clone();
        let mut w = Vector3::zeros();
        let mut tau = Vector3::zeros();
        for (col, &i) in self.kept.iter().enumerate() {
            match self.all[i] {
                Param::FrameRotation(a) => w[a] = dx[col],
                Param::FrameTranslation(a) => tau[a] = dx[col],
                _ => t.x[i] += dx[col],
            }
        }
        // x = R_T (exp(ω) p + τ) + t_T.
        t.frame.trans += s.frame.rot * tau;
        if w != Vector3::zeros() {
            t.frame.rot = s.frame.rot * Rotation3::new(w).into_inner();
        }
        t
    }
}

/// The instrument frame that best maps an arm's ball centres onto the `point` rows.
pub fn start_frame(arm: &Arm, data: &Dataset, layout: &Layout) -> Rigid {
    if layout.points.is_empty() {
        return Rigid::identity();
    }
    let mounted = crate::fit::probes::Mounted::new(arm);
    let ps: Vec<Vector3<f64>> = layout
        .points
        .iter()
        .map(|&i| mounted.tip(&data.rows[i]))
        .collect();
    let xs: Vec<Vector3<f64>> = layout
        .points
        .iter()
        .map(|&i| Vector3::from(data.rows[i].xyz.unwrap_or([0.0; 3])))
        .collect();
    best_rigid(&ps, &xs)
}
