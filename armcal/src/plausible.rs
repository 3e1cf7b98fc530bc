//! Plausibility before any fit or decision: data and limits that look like a unit mistake
//! are refused with what looks wrong and the flag that accepts them deliberately.
//!
//! Every mistake here passes every syntactic check and gives a confident wrong answer: point
//! data in metres calibrate a shrunken arm to a "perfect" fit, joint angles in degrees move
//! every point, `P_Size = 20` meant in µm is 20 mm and passes everything, another arm's
//! calibration fails `check` by hundreds of mm with no hint why. Each check compares the
//! input with what the arm's own nominal model says it must be, so the thresholds are ratios
//! (a unit mistake is a factor of 25.4, 57.3 or 1000), not tuned numbers. The flags that
//! accept a refused input all read `--accept-…` ([`Accept`]).

use crate::acceptance::mpe::{Limit, Mpe};
use crate::acceptance::statistics::Test;
use crate::data::Dataset;
use crate::fit::probes::Mounted;
use quatarm_ref::arm::{Arm, Joint};

/// What the user accepts deliberately (`--accept-units`, `--accept-temperature`,
/// `--accept-mpe`, `--accept-misfit`, `--accept-duplicates`, `--accept-order`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Accept {
    /// Lengths or angles that look like another unit.
    pub units: bool,
    /// Temperatures outside what a CMM is used at.
    pub temperature: bool,
    /// MPE values no articulated arm has.
    pub mpe: bool,
    /// A calibration that does not fit the data it is checked with.
    pub misfit: bool,
    /// Rows that repeat an earlier row's joint readings exactly.
    pub duplicates: bool,
    /// Joint columns that a reordering fits far better than their order as given.
    pub order: bool,
}

/// The largest joint reading (rad) of an arm that does not turn a joint past a full turn
/// either way: beyond it, the readings look like degrees.
pub const TURN_RAD: f64 = 2.0 * std::f64::consts::PI + 0.1;
/// A joint reading (rad) beyond which it is no angle in degrees either (three turns of
/// degrees): encoder counts in a radian column.
pub const COUNTS_RAD: f64 = 3.0 * 360.0;
/// How far the data's size may be from the model's (a ratio) before it looks like another
/// unit: inches are 25.4 mm, metres 1000, and a real arm's errors are far below a factor 2.
pub const SIZE_RATIO: f64 = 2.0;
/// Temperatures (°C) a CMM arm is used at; outside, the readings look like °F or a sensor
/// fault.
pub const TEMP_C: std::ops::RangeInclusive<f64> = 0.0..=45.0;
/// MPE values (mm) articulated arms have: from 0.5 µm (nothing smaller is measurable with a
/// touch probe) to 1 mm (a 4 m arm's E_Uni is about 0.1 mm).
pub const MPE_MM: std::ops::RangeInclusive<f64> = 0.0005..=1.0;
/// A test value (µm) no calibration of this arm can give on its own data: 5 mm.
pub const MISFIT_UM: f64 = 5000.0;

/// Why an input was refused as implausible: the message names the file, what looks wrong,
/// the values, and the flag that accepts it.
#[derive(Debug, thiserror::Error)]
#[error("{file}: {what}; {hint} (or `--accept-{flag}` if it is right as it is)")]
pub struct Implausible {
    /// The file concerned.
    pub file: String,
    /// What looks wrong, with the values.
    pub what: String,
    /// What the likely mistake is and how to mend it.
    pub hint: String,
    /// The flag's name after `--accept-`.
    pub flag: &'static str,
}

/// The data against the arm's nominal model: joint readings in radians, point and length
/// data in mm at the arm's size, temperatures in °C.
pub fn data(arm: &Arm, data: &Dataset, accept: Accept) -> Result<(), Implausible> {
    let refuse = |what: String, hint: &str, flag| Implausible {
        file: data.source.clone(),
        what,
        hint: hint.to_string(),
        flag,
    };
    let placed: Vec<Reading> = data
        .rows
        .iter()
        .map(|r| Reading {
            theta: &r.theta,
            temp_c: data.has_temperature.then_some(r.temp_c),
            place: format!("line {}", r.line),
        })
        .collect();
    readings(&data.source, &placed, accept)?;
    if !accept.duplicates {
        duplicates(std::slice::from_ref(data))?;
    }
    if !accept.order {
        order(arm, data)?;
    }
    if !accept.units {
        if let Some(ratio) = point_size_ratio(arm, data) {
            if !(1.0 / SIZE_RATIO..=SIZE_RATIO).contains(&ratio) {
                return Err(refuse(
                    format!(
                        "the measured points spread {} the arm's nominal model at the same joint \
                         readings (a factor {ratio:.3})",
                        if ratio > 1.0 {
                            "less than"
                        } else {
                            "more than"
                        }
                    ),
                    unit_hint(ratio),
                    "units",
                ));
            }
        }
        if let Some((ratio, g, length)) = length_ratio(arm, data) {
            if !(1.0 / SIZE_RATIO..=SIZE_RATIO).contains(&ratio) {
                return Err(refuse(
                    format!(
                        "length group {g}: length_mm = {length} while the arm's nominal model puts \
                         the bar's ends {:.1} mm apart (a factor {ratio:.3})",
                        length * ratio
                    ),
                    unit_hint(ratio),
                    "units",
                ));
            }
        }
        if let Some((ratio, g, line, diameter)) = sphere_ratio(arm, data) {
            if !(1.0 / SIZE_RATIO..=SIZE_RATIO).contains(&ratio) {
                return Err(refuse(
                    format!(
                        "sphere group {g} (line {line}): diameter_mm = {diameter} while the arm's \
                         nominal model puts the ball centres on a test sphere of about {:.1} mm \
                         (a factor {ratio:.3})",
                        diameter * ratio,
                    ),
                    unit_hint(ratio),
                    "units",
                ));
            }
        }
    }
    Ok(())
}

/// A joint reading with its temperature (where the input has one) and its place in the
/// input for messages (`line 5`, `row 3`).
pub struct Reading<'a> {
    /// Joint angles (rad).
    pub theta: &'a [f64],
    /// Temperature (°C), where the input records one.
    pub temp_c: Option<f64>,
    /// Where it is.
    pub place: String,
}

/// Joint readings in radians (no joint past a turn: [`TURN_RAD`]) and temperatures in °C
/// where arms are used ([`TEMP_C`]): the measured data's rule and `eval`'s input's.
pub fn readings(file: &str, rows: &[Reading], accept: Accept) -> Result<(), Implausible> {
    let refuse = |what: String, hint: &str, flag| Implausible {
        file: file.to_string(),
        what,
        hint: hint.to_string(),
        flag,
    };
    if !accept.units {
        let dof = rows.iter().map(|r| r.theta.len()).max().unwrap_or(0);
        for j in 0..dof {
            let worst = rows
                .iter()
                .filter_map(|r| r.theta.get(j).map(|t| (t.abs(), r)))
                .fold(None, |a: Option<(f64, &Reading)>, b| match a {
                    Some(a) if a.0 >= b.0 => Some(a),
                    _ => Some(b),
                });
            if let Some((t, r)) = worst.filter(|w| w.0 > TURN_RAD) {
                return Err(refuse(
                    format!(
                        "joint {} reads {t:.4} rad on {} (more than a turn, {:.1} turns)",
                        j + 1,
                        r.place,
                        t / std::f64::consts::TAU
                    ),
                    if t > COUNTS_RAD {
                        "joint readings are in radians: encoder counts? name the columns c1..cN \
                         (the calibration's encoder_counts convert them)"
                    } else {
                        "joint readings are in radians: in degrees? multiply by π/180"
                    },
                    "units",
                ));
            }
        }
    }
    if !accept.temperature {
        let outside = rows
            .iter()
            .find_map(|r| r.temp_c.filter(|t| !TEMP_C.contains(t)).map(|t| (t, r)));
        if let Some((t, r)) = outside {
            return Err(refuse(
                format!(
                    "temp_c = {t} °C on {}, outside {}..{} °C where arms are used",
                    r.place,
                    TEMP_C.start(),
                    TEMP_C.end()
                ),
                "temperatures are in °C: in °F? (°C = (°F − 32) / 1.8)",
                "temperature",
            ));
        }
    }
    Ok(())
}

/// No row repeats an earlier row's kind and joint readings exactly, in one file or across
/// the files of one recording (`parts`, in the order given). Encoders of 2^20 counts a turn
/// never read the same six angles in two probings, so an exact repeat is a copy: a row
/// pasted twice, or a file given twice under two names.
pub fn duplicates(parts: &[Dataset]) -> Result<(), Implausible> {
    let mut seen: std::collections::HashMap<(crate::data::Kind, Vec<u64>), (usize, usize)> =
        std::collections::HashMap::new();
    for (f, part) in parts.iter().enumerate() {
        for r in &part.rows {
            let key = (
                r.kind,
                r.theta.iter().map(|t| t.to_bits()).collect::<Vec<_>>(),
            );
            if let Some(&(ff, line)) = seen.get(&key) {
                let earlier = if ff == f {
                    format!("line {line}")
                } else {
                    format!("line {line} of {}", parts[ff].source)
                };
                return Err(Implausible {
                    file: part.source.clone(),
                    what: format!(
                        "line {} repeats {earlier} (the same kind and the same joint readings \
                         to the last digit, which two probings never give)",
                        r.line
                    ),
                    hint: "a row pasted twice, or one recording given twice?".into(),
                    flag: "duplicates",
                });
            }
            seen.insert(key, (f, r.line));
        }
    }
    Ok(())
}

/// The nominal model's misfit (RMS, mm) beyond which the data look like joint columns out of
/// order, where a reordering fits: a calibration corrects link errors of a millimetre and
/// angle errors of a few mrad (a few mm at a metre's reach), never 20 mm RMS.
pub const ORDER_MM: f64 = 20.0;
/// How much better a reordering must fit than the columns as given to be named: a factor 5.
pub const ORDER_GAIN: f64 = 5.0;

/// The joint columns in the order the arm's joints come: where the nominal model misfits the
/// data by more than [`ORDER_MM`] and a swap of two columns (or all of them reversed) fits
/// within it, [`ORDER_GAIN`] times better, the data are refused with the reordering named.
/// The misfit is the residuals' RMS of the nominal model (`point` rows after the best rigid
/// placement, `spat` and bar ends about their group's mean, `sphere` rows from their sphere,
/// each bar's length error), so it needs no fit of the arm.
pub fn order(arm: &Arm, data: &Dataset) -> Result<(), Implausible> {
    let as_given = nominal_misfit(arm, data, &(0..data.dof).collect::<Vec<_>>());
    if as_given.is_nan() || as_given <= ORDER_MM {
        return Ok(());
    }
    let n = data.dof;
    // (the reordering, how to mend the file, the model's joint k from the file's column p[k])
    let mut orders: Vec<(String, String, Vec<usize>)> = Vec::new();
    for i in 0..n {
        for j in i + 1..n {
            let mut p: Vec<usize> = (0..n).collect();
            p.swap(i, j);
            orders.push((
                format!("j{} and j{} swapped", i + 1, j + 1),
                format!(
                    "exchange the columns j{0} and j{1} (the file's j{0} is the arm's joint {1})",
                    i + 1,
                    j + 1
                ),
                p,
            ));
        }
    }
    if n > 3 {
        orders.push((
            format!("j1..j{n} reversed"),
            format!("reverse the joint columns (the file's j1 is the arm's joint {n})"),
            (0..n).rev().collect(),
        ));
    }
    let best = orders
        .into_iter()
        .map(|(name, mend, p)| (nominal_misfit(arm, data, &p), name, mend))
        .filter(|(m, _, _)| m.is_finite())
        .min_by(|a, b| a.0.total_cmp(&b.0));
    match best {
        Some((m, name, mend)) if m <= ORDER_MM && m * ORDER_GAIN <= as_given => Err(Implausible {
            file: data.source.clone(),
            what: format!(
                "the joint columns look out of order: the arm's model misfits the data \
                 by {as_given:.1} mm RMS as the columns are, by {m:.2} mm with {name} (a \
                 calibration corrects a few mm, never {ORDER_MM} mm)"
            ),
            hint: mend,
            flag: "order",
        }),
        _ => Ok(()),
    }
}

/// The RMS (mm) of the nominal model's residuals on `data` with each row's joint readings
/// taken in the order `perm` (reading k of the model is the file's column `perm[k]`).
fn nominal_misfit(arm: &Arm, data: &Dataset, perm: &[usize]) -> f64 {
    let mut d = data.clone();
    for r in &mut d.rows {
        let theta: Vec<f64> = perm.iter().map(|&k| r.theta[k]).collect();
        r.theta = theta;
    }
    let res = crate::fit::residuals::residuals(arm, &d, None);
    let sum: f64 = res.rows.iter().map(|v| v.norm_squared()).sum::<f64>()
        + res.lengths.iter().map(|(_, e)| e * e).sum::<f64>();
    let count = res.rows.len() + res.lengths.len();
    (sum / count.max(1) as f64).sqrt()
}

/// The likely unit of data `ratio` times smaller than the model.
fn unit_hint(ratio: f64) -> &'static str {
    let near = |f: f64| (ratio / f).ln().abs() < 0.3;
    if near(1000.0) {
        "lengths are in mm: in metres? multiply by 1000"
    } else if near(25.4) {
        "lengths are in mm: in inches? multiply by 25.4"
    } else if near(1e-3) {
        "lengths are in mm: in µm? divide by 1000"
    } else {
        "lengths are in mm: are these data of this arm (its model or calibration), in mm?"
    }
}

/// The model's spread of the point rows' ball centres over the data's (RMS distance from
/// their centroid; a rigid instrument frame keeps it): 1 for data in mm, 1000 in metres.
/// `None` under 3 points or where the model's points do not spread.
fn point_size_ratio(arm: &Arm, data: &Dataset) -> Option<f64> {
    let m = Mounted::new(arm);
    let (mut model, mut meas) = (Vec::new(), Vec::new());
    for r in &data.rows {
        if let Some(p) = r.xyz {
            model.push(m.tip(r));
            meas.push(nalgebra::Vector3::from(p));
        }
    }
    let spread = |v: &[nalgebra::Vector3<f64>]| {
        let c = v.iter().sum::<nalgebra::Vector3<f64>>() / v.len() as f64;
        (v.iter().map(|p| (p - c).norm_squared()).sum::<f64>() / v.len() as f64).sqrt()
    };
    if model.len() < 3 {
        return None;
    }
    let (a, b) = (spread(&model), spread(&meas));
    (a > 1.0).then(|| if b > 0.0 { a / b } else { f64::INFINITY })
}

/// The worst length group: the model's mean distance between the bar's ends over the
/// stated length, with the group and its length.
fn length_ratio(arm: &Arm, data: &Dataset) -> Option<(f64, i64, f64)> {
    let m = Mounted::new(arm);
    let mean = |rows: &[usize]| {
        rows.iter()
            .map(|&i| m.tip(&data.rows[i]))
            .sum::<nalgebra::Vector3<f64>>()
            / rows.len().max(1) as f64
    };
    data.layout()
        .length
        .iter()
        .filter(|g| !g.a.is_empty() && !g.b.is_empty() && g.length_mm > 0.0)
        .map(|g| {
            let d = (mean(&g.a) - mean(&g.b)).norm();
            (d / g.length_mm, g.group, g.length_mm)
        })
        .max_by(|x, y| x.0.ln().abs().total_cmp(&y.0.ln().abs()))
}

/// The sphere group whose stated diameter is farthest from what the nominal model's ball
/// centres span (their largest distance apart, less the stylus ball: the diameter of a test
/// sphere probed over a hemisphere or more), as (span over stated, group, line of its first
/// row, stated diameter). `None` without sphere groups.
fn sphere_ratio(arm: &Arm, data: &Dataset) -> Option<(f64, i64, usize, f64)> {
    let m = Mounted::new(arm);
    data.layout()
        .sphere
        .iter()
        .filter(|g| g.rows.len() >= 4 && g.diameter_mm > 0.0)
        .map(|g| {
            let q: Vec<nalgebra::Vector3<f64>> =
                g.rows.iter().map(|&i| m.tip(&data.rows[i])).collect();
            let span = q
                .iter()
                .flat_map(|a| q.iter().map(move |b| (a - b).norm()))
                .fold(0.0, f64::max);
            let ball = crate::fit::probes::sphere_ball_diameter(arm, data, g);
            let ratio = (span - ball).max(0.0) / g.diameter_mm;
            (ratio, g.group, data.rows[g.rows[0]].line, g.diameter_mm)
        })
        .max_by(|x, y| x.0.ln().abs().total_cmp(&y.0.ln().abs()))
}

/// The MPE file's values against what articulated arms have ([`MPE_MM`]).
pub fn mpe(mpe: &Mpe, file: &str, accept: Accept) -> Result<(), Implausible> {
    if accept.mpe {
        return Ok(());
    }
    for t in Test::ALL {
        let values: Vec<(String, f64)> = match mpe.limit(t) {
            None => continue,
            Some(Limit::Constant(c)) => vec![(t.key().to_string(), c)],
            Some(Limit::Linear { a, per_m }) => vec![
                (format!("{}.a", t.key()), a),
                (format!("{}.per_m", t.key()), per_m),
            ],
        };
        for (key, v) in values {
            // Zero is zero in every unit: a deliberately strict limit, no unit mistake.
            if v == 0.0 {
                continue;
            }
            if !MPE_MM.contains(&v) {
                return Err(Implausible {
                    file: file.to_string(),
                    what: format!(
                        "{key} = {v} mm ({} µm), outside {}..{} mm, the MPEs articulated arms have",
                        v * 1000.0,
                        MPE_MM.start(),
                        MPE_MM.end()
                    ),
                    hint: if v > *MPE_MM.end() {
                        format!("MPE values are in mm: for {v} µm write {}", v / 1000.0)
                    } else {
                        "MPE values are in mm: in metres? multiply by 1000".to_string()
                    },
                    flag: "mpe",
                });
            }
        }
    }
    Ok(())
}

/// The acceptance tests' values (µm, by test key) against what a calibration of this arm can
/// give ([`MISFIT_UM`]): beyond, the calibration is not this arm's (or not of this data).
pub fn misfit<'a>(
    results: impl IntoIterator<Item = (&'a str, f64)>,
    data_file: &str,
    calib_file: &str,
    accept: Accept,
) -> Result<(), Implausible> {
    if accept.misfit {
        return Ok(());
    }
    for (key, v) in results {
        if !v.is_finite() || v.abs() > MISFIT_UM {
            return Err(Implausible {
                file: data_file.to_string(),
                what: format!(
                    "{key} = {v:.1} µm with the calibration {calib_file}: beyond {} mm, more than \
                     any calibration of the arm that measured the data can be wrong",
                    MISFIT_UM / 1000.0
                ),
                hint: "is it this arm's calibration (its serial), and this arm's data?".into(),
                flag: "misfit",
            });
        }
    }
    Ok(())
}

/// How far (rad) a calibration file's `zero_offset` or `tilt` component may be from the
/// nearest quarter turn: a tilt holds a Denavit–Hartenberg twist (0, ±π/2, ±π) and an error
/// of a few mrad, a zero offset a quarter-turn offset of the model and an error of a few mrad
/// (the largest in the project's real arms: 14 mrad), so 50 mrad (2.9°) off every quarter
/// turn is an angle written in degrees (`tilt = [0.13, 0.14]` for errors of 2.3 mrad,
/// `[90, 0]` for a quarter turn).
pub const TWIST_OFF_RAD: f64 = 0.05;
/// The largest harmonic or wobble coefficient (rad) that looks like radians: 5 mrad (0.29°) of
/// encoder error or bearing wobble, 40 times the largest the project's arms and simulations
/// have (25–120 µrad), while 0.005 written in degrees is 87 µrad.
pub const PERIODIC_RAD: f64 = 0.005;
/// Stylus ball diameters (mm) probes have: 0.3 mm (the finest ruby ball) to 50 mm (a
/// large ball probe); outside, a diameter looks like µm or metres.
pub const BALL_MM: std::ops::RangeInclusive<f64> = 0.3..=50.0;

/// A calibration file's angles in radians and its stylus balls in mm, read from its text
/// (`file` names it): a `zero_offset` or `tilt` far from every quarter turn
/// ([`TWIST_OFF_RAD`]), a harmonic or wobble coefficient of [`PERIODIC_RAD`] or more, or a ball diameter
/// outside [`BALL_MM`] is refused with its key and line. A text the format refuses passes
/// here: the loader names its fault (with its key) next.
pub fn calibration_text(text: &str, file: &str, accept: Accept) -> Result<(), Implausible> {
    if accept.units {
        return Ok(());
    }
    // Wide bounds so that degrees (up to a turn, 360) and a ball in µm reach the checks below
    // rather than the loader's limits, whose messages cannot name the likely unit.
    let wide = quatarm_ref::calfile::Limits {
        length_mm: f64::MAX,
        angle_rad: 1.0e4,
        harmonic_rad: 1.0e4,
        wobble_rad: 1.0e4,
        ..crate::limits::CALFILE
    };
    let Ok(parsed) = quatarm_ref::calfile::parse_with(text, &wide) else {
        return Ok(());
    };
    let place = CalPlace { text, file };
    for (i, j) in parsed.arm.joints.iter().enumerate() {
        angles_in_radians(&place, i + 1, j)?;
        periodic_in_radians(&place, i + 1, j)?;
    }
    balls_in_mm(&place, &parsed.arm)
}

/// A calibration file's text and name, for a refusal that names the key's line.
struct CalPlace<'a> {
    text: &'a str,
    file: &'a str,
}

/// The hint of an angle that looks like degrees.
const DEGREES: &str = "angles are in radians: in degrees? multiply by π/180";

impl CalPlace<'_> {
    /// The refusal of `key` (found on its line by `line_key` in `joint`'s table, or in the
    /// whole file), `what` said of its value, with the `--accept-units` flag.
    fn refuse(
        &self,
        joint: Option<usize>,
        key: String,
        line_key: &str,
        what: String,
        hint: &str,
    ) -> Implausible {
        let line = key_line(self.text, joint, line_key)
            .map(|l| format!("line {l}, "))
            .unwrap_or_default();
        Implausible {
            file: self.file.to_string(),
            what: format!("{line}{key} {what}"),
            hint: hint.to_string(),
            flag: "units",
        }
    }
}

/// Joint `k`'s (1-based) `zero_offset` and `tilt`: each within [`TWIST_OFF_RAD`] of a
/// quarter turn and of magnitude at most π (plus that), as angles in radians are.
fn angles_in_radians(place: &CalPlace, k: usize, j: &Joint) -> Result<(), Implausible> {
    let quarter = std::f64::consts::FRAC_PI_2;
    let angles = std::iter::once(("zero_offset".to_string(), "zero_offset", j.zero_offset)).chain(
        j.tilt
            .iter()
            .enumerate()
            .map(|(c, &t)| (format!("tilt[{c}]"), "tilt", t)),
    );
    for (key, line_key, t) in angles {
        let off = (t - (t / quarter).round() * quarter).abs();
        if off > TWIST_OFF_RAD || t.abs() > std::f64::consts::PI + TWIST_OFF_RAD {
            return Err(place.refuse(
                Some(k),
                format!("joint[{k}].{key}"),
                line_key,
                format!(
                    "= {t} rad ({:.1}°), {off:.3} rad off the nearest quarter turn, where it \
                     holds 0, ±π/2 or ±π and an error of a few mrad (read as degrees: \
                     {:.5} rad)",
                    t.to_degrees(),
                    t.to_radians()
                ),
                DEGREES,
            ));
        }
    }
    Ok(())
}

/// Joint `k`'s (1-based) harmonic and wobble coefficients: each below [`PERIODIC_RAD`].
fn periodic_in_radians(place: &CalPlace, k: usize, j: &Joint) -> Result<(), Implausible> {
    let periodic = j
        .harmonics
        .iter()
        .enumerate()
        .flat_map(|(h, t)| {
            [
                (format!("harmonics[{}].sin", h + 1), t.sin),
                (format!("harmonics[{}].cos", h + 1), t.cos),
            ]
        })
        .chain(j.wobble.iter().enumerate().flat_map(|(h, w)| {
            (0..2).flat_map(move |c| {
                [
                    (format!("wobble[{}].alpha[{c}]", h + 1), w.alpha[c]),
                    (format!("wobble[{}].beta[{c}]", h + 1), w.beta[c]),
                ]
            })
        }));
    for (key, v) in periodic {
        if v.abs() >= PERIODIC_RAD {
            let line_key = key.split('[').next().unwrap_or("").to_string();
            return Err(place.refuse(
                Some(k),
                format!("joint[{k}].{key}"),
                &line_key,
                format!(
                    "= {v} rad ({:.2}°), where an encoder's or a bearing's periodic error \
                     is below {PERIODIC_RAD} rad (read as degrees: {:.2e} rad)",
                    v.to_degrees(),
                    v.to_radians()
                ),
                DEGREES,
            ));
        }
    }
    Ok(())
}

/// Every probe's stylus ball diameter (0: not given) within [`BALL_MM`], the hint saying
/// which unit it looks like.
fn balls_in_mm(place: &CalPlace, arm: &Arm) -> Result<(), Implausible> {
    for p in arm.probes() {
        let d = p.ball_diameter;
        if d != 0.0 && !BALL_MM.contains(&d) {
            return Err(place.refuse(
                None,
                format!("probe (id {}) ball_diameter", p.id),
                "ball_diameter",
                format!(
                    "= {d} mm, outside {}..{} mm, the stylus balls probes have",
                    BALL_MM.start(),
                    BALL_MM.end()
                ),
                if d > *BALL_MM.end() {
                    "lengths are in mm: in µm? divide by 1000"
                } else {
                    "lengths are in mm: in metres? multiply by 1000"
                },
            ));
        }
    }
    Ok(())
}

/// [`calibration_text`] of the file at `path` (a file that cannot be read passes: the loader
/// says why next, naming it once).
pub fn calibration(path: &std::path::Path, accept: Accept) -> Result<(), Implausible> {
    match std::fs::read_to_string(path) {
        Ok(text) => calibration_text(&text, &path.display().to_string(), accept),
        Err(_) => Ok(()),
    }
}

/// The 1-based line of `key = …` in the `joint`-th `[[joint]]` table (1-based), or anywhere
/// for `None` (the first such line): where a person looks for the key in the file.
fn key_line(text: &str, joint: Option<usize>, key: &str) -> Option<usize> {
    let (mut current, mut in_joint) = (0, false);
    for (i, line) in text.lines().enumerate() {
        let l = line.split('#').next().unwrap_or("").trim();
        if l.starts_with("[[joint]]") {
            current += 1;
            in_joint = true;
            continue;
        }
        if l.starts_with('[') {
            // Another table: no longer inside a joint.
            in_joint = false;
            continue;
        }
        let here = joint.is_none_or(|k| in_joint && k == current);
        let is_key = l
            .strip_prefix(key)
            .is_some_and(|rest| rest.trim_start().starts_with('='));
        if here && is_key {
            return Some(i + 1);
        }
    }
    None
}

/// What a hub must announce to be running a calibration's table: the calibration file, its
/// joint count and the CRCs of the tables `armcal table build` makes from it (with and
/// without the covariance).
#[derive(Clone, Debug, PartialEq)]
pub struct HubTable {
    /// The calibration file.
    pub file: String,
    /// Its arm's joint count.
    pub joints: usize,
    /// The CRC of each table built from it.
    pub crcs: Vec<u32>,
}

/// A hub's announced table (`joints`, and the live table's CRC where it has one) against the
/// calibration the user says it runs: another joint count is another arm's table; another
/// CRC is another calibration's (an older one of this arm, or another arm's), so the hub's
/// coordinates are not this calibration's.
pub fn hub(
    expected: &HubTable,
    source: &str,
    joints: u8,
    crc: Option<u32>,
    accept: Accept,
) -> Result<(), Implausible> {
    // Without a valid table (0 joints) the hub sends no coordinates to mistrust.
    if accept.misfit || joints == 0 {
        return Ok(());
    }
    let refuse = |what: String| Implausible {
        file: source.to_string(),
        what,
        hint: format!(
            "send the table built from {} (`armcal table build`, `armcal table send`), or give \
             the calibration the hub runs",
            expected.file
        ),
        flag: "misfit",
    };
    if usize::from(joints) != expected.joints {
        return Err(refuse(format!(
            "the hub announces a table of {joints} joints, the calibration {} is of an arm of {} \
             joints: the hub runs another arm's table",
            expected.file, expected.joints
        )));
    }
    if let Some(crc) = crc.filter(|c| !expected.crcs.contains(c)) {
        let built: Vec<String> = expected.crcs.iter().map(|c| format!("{c:08x}")).collect();
        return Err(refuse(format!(
            "the hub's live table has CRC {crc:08x}, the tables built from {} have CRC {}: the \
             hub runs another calibration (an older one of this arm, or another arm's)",
            expected.file,
            built.join(" or ")
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn data_dir() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../data")
    }

    /// Every calibration file the project ships (nominal models of real arms, calibrated
    /// ones, default-6 with every term) reads as radians and mm.
    #[test]
    fn the_shipped_calibration_files_pass() {
        let mut n = 0;
        for dir in [data_dir(), data_dir().join("mukca")] {
            for e in std::fs::read_dir(dir).unwrap() {
                let p = e.unwrap().path();
                if p.extension().is_some_and(|x| x == "toml") && !p.ends_with("mpe-example.toml") {
                    calibration(&p, Accept::default())
                        .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
                    n += 1;
                }
            }
        }
        assert!(n >= 20, "{n} files");
    }

    /// The line of a key in the k-th `[[joint]]`, not in another table or joint.
    #[test]
    fn key_lines_are_those_of_the_joint() {
        let text = "name = \"a\"\n[[joint]]\naxis = \"z\"\ntilt = [0, 0]\n[[joint]]\n\
                    axis = \"x\"\ntilt = [1, 0]\n[probe]\nball_diameter = 6\n";
        assert_eq!(key_line(text, Some(1), "tilt"), Some(4));
        assert_eq!(key_line(text, Some(2), "tilt"), Some(7));
        assert_eq!(key_line(text, Some(3), "tilt"), None);
        assert_eq!(key_line(text, None, "ball_diameter"), Some(9));
        assert_eq!(key_line(text, Some(2), "ball_diameter"), None);
    }

    /// MUKCa's 13 real recordings with their nominal models pass the order check; three of
    /// them (one per arm type) misfit by less than half [`ORDER_MM`], and the same rows with
    /// two joint columns swapped are refused, the swap named.
    #[test]
    fn real_recordings_pass_the_order_check_and_a_swap_is_named() {
        let dir = data_dir().join("mukca");
        let mut n = 0;
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            let cal = p.with_extension("toml");
            if p.extension().is_none_or(|x| x != "csv") || !cal.exists() {
                continue;
            }
            let arm = crate::load::arm(&cal).unwrap();
            let data = crate::data::read(&p, arm.dof()).unwrap();
            let m = nominal_misfit(&arm, &data, &(0..arm.dof()).collect::<Vec<_>>());
            eprintln!(
                "{}: the nominal model misfits by {m:.2} mm RMS",
                p.display()
            );
            order(&arm, &data).unwrap_or_else(|e| panic!("{e}"));
            n += 1;
        }
        assert_eq!(n, 13);
        for name in [
            "mukca-panda-panda_2",
            "mukca-gen3lite-dinova_1",
            "mukca-iiwa14-kuka_14",
        ] {
            let arm = crate::load::arm(&dir.join(format!("{name}.toml"))).unwrap();
            let data = crate::data::read(&dir.join(format!("{name}.csv")), arm.dof()).unwrap();
            let n = arm.dof();
            let m = nominal_misfit(&arm, &data, &(0..n).collect::<Vec<_>>());
            eprintln!("{name}: the nominal model misfits by {m:.2} mm RMS");
            assert!(m < ORDER_MM / 2.0, "{name}: {m} mm");
            order(&arm, &data).unwrap();
            let mut swapped = data.clone();
            for r in &mut swapped.rows {
                r.theta.swap(1, 2);
            }
            let e = order(&arm, &swapped).unwrap_err().to_string();
            assert!(e.contains("with j2 and j3 swapped"), "{name}: {e}");
        }
    }
}
