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
use quatarm_ref::arm::Arm;

/// What the user accepts deliberately (`--accept-units`, `--accept-temperature`,
/// `--accept-mpe`, `--accept-misfit`).
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
}

/// The largest joint reading (rad) of an arm that does not turn a joint past a full turn
/// either way: beyond it, the readings look like degrees.
pub const TURN_RAD: f64 = 2.0 * std::f64::consts::PI + 0.1;
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
                    "joint readings are in radians: in degrees? multiply by π/180",
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
