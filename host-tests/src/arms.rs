//! Arms anywhere inside the binary table's limits, checked against the f64 reference: the
//! generator behind the `chain_accuracy` property test and the `chain_arm_accuracy` fuzz
//! target (one implementation, fed by proptest's bytes or by libFuzzer's).
//!
//! Every value is drawn over the whole range the table admits ([`quatarm::table::limits`]):
//! any axis, any counts per revolution, any fixed rotation (tilts and zero offsets of any
//! size, D–H twists included), links and probe up to the table's 5 m, harmonics and axis
//! wobble of any order up to their summed limits, gravity compliance and thermal expansion up to their limits, and
//! readings anywhere in the encoders' turn at any accepted temperature. Values favour the
//! edges (zero, the limit, powers of ten below it) as well as the interior, and the arm is
//! often scaled so that its reach lies just inside an evaluator's limit, where rounding and
//! the gravity terms are largest.
//!
//! [`check`] then asks of every arm: either a table refuses it (the host's builder, the
//! table's validation or `Chain::new`, each with a named error), or every chain — the
//! quaternion chains of the firmware and the matrix chains they are compared with, f32 and
//! fixed point — meets the firmware's bounds on every reading (the f32 matrix chain's tip,
//! [`MATRIX_F32_TIP_UM`], twice them).

use arbitrary::{Result as ArbResult, Unstructured};
use quatarm::table::limits;
use quatarm::{Arithmetic, Chain, ChainError, Evaluator, Fixed, MatrixChain, Point, Table, F32};
use quatarm_ref::arm::Wobble;
use quatarm_ref::{Arm, Axis, Harmonic, Joint, Probe};
use std::f64::consts::PI;

/// The firmware's accuracy bounds (issue 2): tip (µm) and direction, f32 and fixed point.
pub const F32_TIP_UM: f64 = 1.0;
/// Fixed point's tip bound (µm).
pub const FIXED_TIP_UM: f64 = 0.1;
/// f32's direction bound.
pub const F32_DIR: f64 = 1e-6;
/// Fixed point's direction bound.
pub const FIXED_DIR: f64 = 1e-7;
/// The f32 *matrix* chain's tip bound (µm): it is a comparison, not a firmware path, and its
/// f32 rounding (each link turned by the composed matrix, partial sums up to 2147 mm with an
/// ulp of 0.24 µm) reaches the firmware's 1 µm on the longest arms (the fuzz target found
/// 1.04 µm). Twice the bound still catches any error of method, which costs micrometres.
pub const MATRIX_F32_TIP_UM: f64 = 2.0;

/// One generated case: an arm and readings of it (raw counts, temperature in m°C).
#[derive(Clone, Debug)]
pub struct Case {
    /// The arm.
    pub arm: Arm,
    /// Readings: counts (each below its joint's counts per revolution) and temperature.
    pub readings: Vec<(Vec<u32>, i32)>,
}

/// A number in [0, 1) from four bytes.
fn unit(u: &mut Unstructured) -> ArbResult<f64> {
    Ok(f64::from(u.arbitrary::<u32>()?) / 4_294_967_296.0)
}

/// A value in (−limit, limit): zero, (just inside) the limit, a power-of-ten fraction of it,
/// or uniform, with a random sign.
fn value(u: &mut Unstructured, limit: f64) -> ArbResult<f64> {
    let sign = if u.arbitrary::<bool>()? { -1.0 } else { 1.0 };
    let x = match u.int_in_range(0u8..=5)? {
        0 => 0.0,
        1 => limit * (1.0 - 1e-9),
        2 => limit * 10f64.powi(-i32::from(u.int_in_range(1u8..=9)?)),
        3 => limit * 10f64.powf(-9.0 * unit(u)?),
        _ => limit * unit(u)?,
    };
    Ok(sign * x)
}

/// An angle anywhere in (−π, π], or a multiple of π/2 (D–H twists), or small.
fn angle(u: &mut Unstructured) -> ArbResult<f64> {
    Ok(match u.int_in_range(0u8..=3)? {
        0 => value(u, 5e-3)?,
        1 => f64::from(u.int_in_range(-1i8..=2)?) * PI / 2.0 + value(u, 1e-2)?,
        _ => PI * (2.0 * unit(u)? - 1.0),
    })
}

fn axis(u: &mut Unstructured) -> ArbResult<Axis> {
    Ok(match u.int_in_range(0u8..=2)? {
        0 => Axis::X,
        1 => Axis::Y,
        _ => Axis::Z,
    })
}

fn counts(u: &mut Unstructured) -> ArbResult<u32> {
    Ok(match u.int_in_range(0u8..=3)? {
        0 => 1 << 20,
        1 => 1 << u.int_in_range(1u32..=30)?,
        2 => i32::MAX as u32,
        _ => u.int_in_range(2u32..=i32::MAX as u32)?,
    })
}

fn vector(u: &mut Unstructured, limit: f64) -> ArbResult<[f64; 3]> {
    Ok([value(u, limit)?, value(u, limit)?, value(u, limit)?])
}

fn harmonics(u: &mut Unstructured) -> ArbResult<Vec<Harmonic>> {
    let count = u.int_in_range(0usize..=quatarm::table::MAX_HARMONICS)?;
    let mut h = Vec::with_capacity(count);
    for _ in 0..count {
        h.push(Harmonic {
            order: u32::from(u.int_in_range(1u16..=quatarm::table::MAX_HARMONIC_ORDER)?),
            sin: value(u, limits::HARMONIC_SUM)?,
            cos: value(u, limits::HARMONIC_SUM)?,
        });
    }
    // Scale into the summed limit (an arm beyond it is the builder's to refuse, tested
    // elsewhere; here the interest is the chain on what the table takes).
    let sum: f64 = h.iter().map(|t| t.sin.abs() + t.cos.abs()).sum();
    if sum > limits::HARMONIC_SUM {
        let k = limits::HARMONIC_SUM * (1.0 - 1e-9) / sum;
        for t in &mut h {
            t.sin *= k;
            t.cos *= k;
        }
    }
    Ok(h)
}

/// Up to four axis wobble terms of any order, their sum within the table's limit (half the
/// time none; none once the bytes run out, so that the inputs found before the wobble, drawn
/// last, keep their arms).
fn wobble(u: &mut Unstructured) -> ArbResult<Vec<Wobble>> {
    let count = if u.arbitrary::<bool>()? {
        u.int_in_range(1usize..=quatarm::table::wobble::MAX_TERMS)?
    } else {
        0
    };
    let mut w = Vec::with_capacity(count);
    for _ in 0..count {
        let limit = limits::HARMONIC_SUM;
        w.push(Wobble {
            order: u32::from(u.int_in_range(1u16..=quatarm::table::MAX_HARMONIC_ORDER)?),
            alpha: [value(u, limit)?, value(u, limit)?],
            beta: [value(u, limit)?, value(u, limit)?],
        });
    }
    let sum: f64 = w
        .iter()
        .flat_map(|t| t.alpha.iter().chain(&t.beta))
        .map(|x| x.abs())
        .sum();
    if sum > limits::HARMONIC_SUM {
        let k = limits::HARMONIC_SUM * (1.0 - 1e-9) / sum;
        for t in &mut w {
            t.alpha = t.alpha.map(|x| x * k);
            t.beta = t.beta.map(|x| x * k);
        }
    }
    Ok(w)
}

fn joint(u: &mut Unstructured) -> ArbResult<Joint> {
    let error_limit = if u.arbitrary::<bool>()? { 1.0 } else { 100.0 };
    Ok(Joint {
        axis: axis(u)?,
        link: vector(u, limits::LENGTH_MM)?,
        zero_offset: angle(u)?,
        tilt: [angle(u)?, angle(u)?],
        link_error: vector(u, error_limit)?,
        harmonics: harmonics(u)?,
        wobble: Vec::new(),
        gravity: value(u, limits::GRAVITY)?,
        thermal: value(u, limits::THERMAL)?,
        encoder_counts: counts(u)?,
    })
}

/// Σ |components| of the links (with errors) and the probe: the reach the chains check.
pub fn reach_mm(arm: &Arm) -> f64 {
    let links: f64 = arm
        .joints
        .iter()
        .map(|j| j.actual_link().iter().map(|x| x.abs()).sum::<f64>())
        .sum();
    links + arm.probe.actual().iter().map(|x| x.abs()).sum::<f64>()
}

/// Scales every link and the probe (with their errors) by `k`.
fn scale(arm: &mut Arm, k: f64) {
    for j in &mut arm.joints {
        j.link = j.link.map(|x| x * k);
        j.link_error = j.link_error.map(|x| x * k);
    }
    arm.probe.vector = arm.probe.vector.map(|x| x * k);
    arm.probe.error = arm.probe.error.map(|x| x * k);
}

/// An arm inside the table's limits and readings of it, from arbitrary bytes.
pub fn case(u: &mut Unstructured) -> ArbResult<Case> {
    let n = if u.arbitrary::<bool>()? { 6 } else { 7 };
    let mut joints = Vec::with_capacity(n);
    for _ in 0..n {
        joints.push(joint(u)?);
    }
    let mut probe = Probe {
        id: 0,
        vector: vector(u, limits::LENGTH_MM)?,
        error: vector(u, 1.0)?,
        thermal: value(u, limits::THERMAL)?,
        ball_diameter: 0.0,
    };
    if probe.actual().iter().all(|&x| x == 0.0) {
        probe.vector = [0.0, 0.0, 100.0];
    }
    let mut arm = Arm {
        name: Some("generated".into()),
        serial: None,
        joints,
        probe,
        more_probes: Vec::new(),
        reference_frame: None,
    };
    // Most arms drawn at 5 m a component reach far beyond what an evaluator holds: scale
    // many of them to just inside a limit (f32's and fixed point's `MAX_REACH_MM` with the
    // thermal margin, the table's 2064 mm, or anywhere below), where the chain is hardest
    // pressed.
    let reach = reach_mm(&arm);
    if reach > 0.0 {
        let target = match u.int_in_range(0u8..=4)? {
            0 => None,
            1 => Some(Fixed::MAX_REACH_MM / 1.04 * (1.0 - 1e-6)),
            2 if u.arbitrary::<bool>()? => Some(F32::MAX_REACH_MM / 1.04 * (1.0 - 1e-6)),
            2 => Some(2064.0 * (1.0 - 1e-9)),
            _ => Some(2147.0 / 1.04 * unit(u)?),
        };
        if let Some(t) = target {
            scale(&mut arm, t / reach);
        }
    }
    let count = u.int_in_range(1usize..=24)?;
    let mut readings = Vec::with_capacity(count);
    for _ in 0..count {
        let mut c = Vec::with_capacity(n);
        for j in &arm.joints {
            c.push(u.int_in_range(0..=j.encoder_counts - 1)?);
        }
        let t = match u.int_in_range(0u8..=2)? {
            0 => -80_000,
            1 => 120_000,
            _ => u.int_in_range(-80_000..=120_000)?,
        };
        readings.push((c, t));
    }
    // Last: the wobble changes neither the reach nor the readings' ranges.
    for j in &mut arm.joints {
        j.wobble = wobble(u)?;
    }
    Ok(Case { arm, readings })
}

/// What [`check`] found for an arm that passed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Refused by the host's table builder or the table's validation.
    RefusedTable,
    /// The table was valid; `Chain::new` refused it for one evaluator or both (the chains
    /// that accepted it met their bounds).
    RefusedChain {
        /// The f32 chain's refusal, if any.
        f32: Option<ChainError>,
        /// The fixed-point chain's refusal, if any.
        fixed: Option<ChainError>,
    },
    /// Both chains accepted it and met their bounds on every reading.
    Accurate,
}

/// The largest errors of one chain over a case's readings.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Worst {
    /// Tip (µm).
    pub tip_um: f64,
    /// Direction.
    pub dir: f64,
}

/// Evaluates every reading with one chain (its `eval`) against the reference.
pub fn worst<P: Arithmetic>(
    eval: impl Fn(&[u32], i32) -> Result<Point<P>, ChainError>,
    case: &Case,
) -> Result<Worst, String> {
    let mut w = Worst::default();
    for (counts, temp_mc) in &case.readings {
        let theta = case.arm.counts_to_rad(counts);
        let r = quatarm_ref::forward::forward(&case.arm, &theta, f64::from(*temp_mc) / 1000.0);
        let p: Point<P> = eval(counts, *temp_mc)
            .map_err(|e| format!("{}: a valid reading refused: {e}", P::NAME))?;
        let x = p.xyz_f64();
        let d = p.dir_f64();
        let tip = (0..3).map(|k| (x[k] - r.p[k]).powi(2)).sum::<f64>().sqrt() * 1000.0;
        let dir = (0..3).map(|k| (d[k] - r.n[k]).powi(2)).sum::<f64>().sqrt();
        if !(tip.is_finite() && dir.is_finite()) {
            return Err(format!("{}: non-finite output", P::NAME));
        }
        // The streamed integers must be the exact rounding of the value (no clip).
        let nm = p.xyz_nm();
        for k in 0..3 {
            if (f64::from(nm[k]) - x[k] * 1e6).abs() > 1.0 {
                return Err(format!(
                    "{}: xyz {} mm streamed as {} nm",
                    P::NAME,
                    x[k],
                    nm[k]
                ));
            }
        }
        w.tip_um = w.tip_um.max(tip);
        w.dir = w.dir.max(dir);
    }
    Ok(w)
}

/// Whether a chain refusal names its cause (a value, the reach or the levers that do not
/// fit).
fn named(e: &ChainError) -> bool {
    matches!(
        e,
        ChainError::Range { .. } | ChainError::Reach { .. } | ChainError::Levers { .. }
    )
}

/// One precision's chains (quaternion and matrix) on a table: a named refusal, or both
/// within the bounds.
fn check_precision<P: Evaluator>(
    table: &Table,
    case: &Case,
    (tip_um, dir): (f64, f64),
    matrix_tip_um: f64,
) -> Result<Option<ChainError>, String> {
    let (quat, matrix) = match (Chain::<P>::new(table), MatrixChain::<P>::new(table)) {
        (Ok(q), Ok(m)) => (q, m),
        (Err(e), Err(f)) if e == f && named(&e) => return Ok(Some(e)),
        (q, m) => {
            return Err(format!(
                "{}: refused without a named limit, or by one chain only: {:?} {:?}",
                P::NAME,
                q.err(),
                m.err()
            ))
        }
    };
    for (name, w, tip_um) in [
        ("quaternion", worst(|c, t| quat.eval(c, t), case)?, tip_um),
        (
            "matrix",
            worst(|c, t| matrix.eval(c, t), case)?,
            matrix_tip_um,
        ),
    ] {
        if w.tip_um > tip_um || w.dir > dir {
            return Err(format!("{} {name}: {w:?}", P::NAME));
        }
    }
    Ok(None)
}

/// Checks a case: a named refusal, or every chain (quaternion and matrix, f32 and fixed
/// point) within its bounds. `Err` describes the failure.
pub fn check(case: &Case) -> Result<Verdict, String> {
    let Ok(bytes) = quatarm_wire::tablebuild::build(&case.arm) else {
        return Ok(Verdict::RefusedTable);
    };
    let Ok(table) = Table::parse(&bytes) else {
        return Ok(Verdict::RefusedTable);
    };
    let refused = (
        check_precision::<F32>(&table, case, (F32_TIP_UM, F32_DIR), MATRIX_F32_TIP_UM)?,
        check_precision::<Fixed>(&table, case, (FIXED_TIP_UM, FIXED_DIR), FIXED_TIP_UM)?,
    );
    Ok(match refused {
        (None, None) => Verdict::Accurate,
        (f32, fixed) => Verdict::RefusedChain { f32, fixed },
    })
}

/// [`case`] and [`check`] on raw bytes (the fuzz target's and the property test's entry).
/// Bytes too short for a case count as nothing to check.
pub fn check_bytes(data: &[u8]) -> Result<Option<Verdict>, String> {
    let mut u = Unstructured::new(data);
    match case(&mut u) {
        Ok(c) => check(&c).map(Some),
        Err(_) => Ok(None),
    }
}
