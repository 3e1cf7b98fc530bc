//! The calibration file (`spec/calibration-file.md`): TOML in, TOML out.
//!
//! Reading walks the TOML tree by hand rather than through `serde` so that every refusal names
//! the key path (`joint[3].tilt[1]`) and every unknown key is reported, as the spec asks.
//! Writing emits every key, zeros included, so that a file read back gives the same arm and a
//! person sees at a glance which terms exist — except `wobble`, written only where a joint has
//! an entry, so that a file written before the key existed is written again byte for byte.

use crate::arm::{
    Arm, Axis, Frame, Harmonic, Joint, Probe, Wobble, DEFAULT_COUNTS, JOINT_COUNTS, MAX_PROBES,
};
pub use crate::uncertainty::{Param, Uncertainty};
use std::fmt::Write as _;
use toml::{Table, Value};

/// The highest `harmonics[].order` a file holds.
pub const MAX_HARMONIC_ORDER: u32 = u16::MAX as u32;

/// A calibration file that cannot be used, with the key path at fault.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{path}: {message}")]
pub struct CalFileError {
    /// Key path, for example `joint[2].axis`; `(file)` for TOML syntax errors.
    pub path: String,
    /// Why it was refused.
    pub message: String,
}

/// An arm read from a file, with the unknown keys it ignored.
#[derive(Debug, Clone)]
pub struct Parsed {
    /// The arm.
    pub arm: Arm,
    /// Key paths that the spec does not know; they were ignored.
    pub unknown_keys: Vec<String>,
    /// The `[uncertainty]` budget, when the file has one.
    pub uncertainty: Option<Uncertainty>,
    /// `[calibration]`: its number, date and due date (number 0, no dates, without it).
    pub release: crate::release::Release,
}

/// Physical bounds on a file's values, beyond the format's own checks (numbers finite, counts
/// in range). The reference has no opinion on them: a tool passes the bounds its evaluators
/// and its hardware set (`armcal::limits::CALFILE`, from the firmware table's limits), so
/// that a value such as `link = [0, 0, 1e300]` is refused on reading, with its key, instead of
/// turning into inf and NaN in every later computation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// |component| of `link`, `link_error`, their sum, and of the probe's `vector`, `error`
    /// and their sum (mm).
    pub length_mm: f64,
    /// |`zero_offset`| and |`tilt` component| (rad).
    pub angle_rad: f64,
    /// |`sin`| and |`cos`| of a harmonic (rad).
    pub harmonic_rad: f64,
    /// |`alpha`| and |`beta`| components of an axis wobble term (rad).
    pub wobble_rad: f64,
    /// |`gravity`| (rad/mm).
    pub gravity: f64,
    /// |`thermal`| of a link or the probe (1/°C).
    pub thermal: f64,
    /// |component| of `reference_frame.translation` (mm).
    pub translation_mm: f64,
    /// `[uncertainty]`'s `encoder_counts` (counts).
    pub budget_counts: f64,
    /// `[uncertainty]`'s `probing_mm` and `model_mm` (mm).
    pub budget_mm: f64,
    /// `[uncertainty]`'s `temperature_c` (°C).
    pub budget_temperature_c: f64,
}

impl Limits {
    /// No bounds beyond the format's: every finite number passes.
    pub const NONE: Limits = Limits {
        length_mm: f64::MAX,
        angle_rad: f64::MAX,
        harmonic_rad: f64::MAX,
        wobble_rad: f64::MAX,
        gravity: f64::MAX,
        thermal: f64::MAX,
        translation_mm: f64::MAX,
        budget_counts: f64::MAX,
        budget_mm: f64::MAX,
        budget_temperature_c: f64::MAX,
    };
}

fn err(path: impl Into<String>, message: impl Into<String>) -> CalFileError {
    CalFileError {
        path: path.into(),
        message: message.into(),
    }
}

/// Reads a calibration file from its text, with the format's checks only ([`Limits::NONE`]).
pub fn parse(text: &str) -> Result<Parsed, CalFileError> {
    parse_with(text, &Limits::NONE)
}

/// Reads a calibration file from its text, refusing values beyond `limits` (with their key).
pub fn parse_with(text: &str, limits: &Limits) -> Result<Parsed, CalFileError> {
    let root: Table = text
        .parse()
        .map_err(|e: toml::de::Error| syntax(text, &e))?;
    let mut unknown = Vec::new();
    for key in root.keys() {
        if !matches!(
            key.as_str(),
            "name"
                | "serial"
                | "encoder_counts"
                | "joint"
                | "probe"
                | "reference_frame"
                | "uncertainty"
                | "calibration"
        ) {
            unknown.push(key.clone());
        }
    }
    let name = opt_string(&root, "name", "name")?;
    let serial = opt_string(&root, "serial", "serial")?;
    if let Some(at) = serial
        .as_deref()
        .and_then(|s| s.bytes().position(|b| b == 0))
    {
        return Err(err(
            "serial",
            format!(
                "has a NUL character (byte {}): a serial is printable text",
                at + 1
            ),
        ));
    }

    let joint_values = match root.get("joint") {
        Some(Value::Array(a)) => a,
        Some(_) => return Err(err("joint", "must be an array of tables ([[joint]])")),
        None => return Err(err("joint", "missing: the arm needs its [[joint]] tables")),
    };
    let n = joint_values.len();
    if !JOINT_COUNTS.contains(&n) {
        return Err(err(
            "joint",
            format!(
                "{n} joints; the arm model takes {} or {}",
                JOINT_COUNTS.start(),
                JOINT_COUNTS.end()
            ),
        ));
    }
    let counts = encoder_counts(root.get("encoder_counts"), n)?;
    let mut joints = Vec::with_capacity(n);
    for (i, v) in joint_values.iter().enumerate() {
        let path = format!("joint[{}]", i + 1);
        let t = v.as_table().ok_or_else(|| err(&path, "must be a table"))?;
        joints.push(joint(t, &path, counts[i], &mut unknown, limits)?);
    }
    let (probe, more_probes) = match root.get("probe") {
        Some(Value::Table(t)) => (probe(t, "probe", &mut unknown, limits)?, Vec::new()),
        Some(Value::Array(a)) => probes(a, &mut unknown, limits)?,
        Some(_) => {
            return Err(err(
                "probe",
                "must be a table ([probe]) or an array of tables ([[probe]], one per probe)",
            ))
        }
        None => return Err(err("probe", "missing: the [probe] table with its vector")),
    };
    let reference_frame = match root.get("reference_frame") {
        Some(Value::Table(t)) => Some(frame(t, &mut unknown, limits)?),
        Some(_) => return Err(err("reference_frame", "must be a table")),
        None => None,
    };
    let arm = Arm {
        name,
        serial,
        joints,
        probe,
        more_probes,
        reference_frame,
    };
    let uncertainty = match root.get("uncertainty") {
        Some(Value::Table(t)) => Some(crate::uncertainty::parse(t, &arm, limits, &mut unknown)?),
        Some(_) => return Err(err("uncertainty", "must be a table")),
        None => None,
    };
    let release = crate::release::parse(root.get("calibration"), &mut unknown)?;
    Ok(Parsed {
        arm,
        unknown_keys: unknown,
        uncertainty,
        release,
    })
}

/// Reads a calibration file from disk ([`Limits::NONE`]); errors carry the file name in front
/// of the key path.
pub fn read(path: &std::path::Path) -> Result<Parsed, CalFileError> {
    read_with(path, &Limits::NONE)
}

/// Reads a calibration file from disk, refusing values beyond `limits`.
pub fn read_with(path: &std::path::Path, limits: &Limits) -> Result<Parsed, CalFileError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| err(path.display().to_string(), format!("cannot read: {e}")))?;
    parse_with(&text, limits).map_err(|e| err(format!("{}: {}", path.display(), e.path), e.message))
}

/// A TOML syntax error with its line and column (1-based), and for an error inside an array
/// of tables (a duplicate key in the third `[[joint]]`) which table it is in: the parser's own
/// message names the key but not the table's index.
fn syntax(text: &str, e: &toml::de::Error) -> CalFileError {
    let message = e.message().trim_end();
    let Some(at) = e.span().map(|s| s.start.min(text.len())) else {
        return err("(file)", format!("not valid TOML: {message}"));
    };
    let before = &text[..at];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    let table = enclosing_table(before)
        .map(|t| format!(" (in {t})"))
        .unwrap_or_default();
    err(
        format!("line {line}, column {column}"),
        format!("not valid TOML: {message}{table}"),
    )
}

/// The table a position of the text is in, from the headers before it: `joint[3]` for the
/// third `[[joint]]`, `probe` for `[probe]`; `None` at the top level.
fn enclosing_table(before: &str) -> Option<String> {
    let mut current: Option<String> = None;
    let mut counts: std::collections::BTreeMap<String, usize> = Default::default();
    for line in before.lines() {
        let l = line.split('#').next().unwrap_or("").trim();
        if let Some(name) = l.strip_prefix("[[").and_then(|r| r.strip_suffix("]]")) {
            let name = name.trim().to_string();
            let k = counts.entry(name.clone()).or_insert(0);
            *k += 1;
            current = Some(format!("{name}[{k}]"));
        } else if let Some(name) = l.strip_prefix('[').and_then(|r| r.strip_suffix(']')) {
            current = Some(name.trim().to_string());
        }
    }
    current
}

/// Refuses |x| > `limit` at `path`, saying what the bound is for.
fn bounded(x: f64, limit: f64, path: &str, what: &str) -> Result<f64, CalFileError> {
    if x.abs() > limit {
        return Err(err(
            path,
            format!("{} is beyond the {what} limit of ±{limit}", short(x)),
        ));
    }
    Ok(x)
}

/// 1e300 rather than its 301 digits.
fn short(x: f64) -> String {
    if x == 0.0 || (1e-4..1e7).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

fn bounded_all(xs: &[f64], limit: f64, path: &str, what: &str) -> Result<(), CalFileError> {
    for (k, &x) in xs.iter().enumerate() {
        bounded(x, limit, &format!("{path}[{k}]"), what)?;
    }
    Ok(())
}

/// Reads joint table `t` (key path `path`, for messages), its keys noted where unknown,
/// then checks every value against `limits` ([`joint_in_limits`]).
fn joint(
    t: &Table,
    path: &str,
    counts: u32,
    unknown: &mut Vec<String>,
    limits: &Limits,
) -> Result<Joint, CalFileError> {
    const KEYS: &[&str] = &[
        "axis",
        "link",
        "zero_offset",
        "tilt",
        "link_error",
        "harmonics",
        "wobble",
        "gravity",
        "thermal",
    ];
    note_unknown(t, KEYS, path, unknown);
    let axis = axis(t, path)?;
    let link = match t.get("link") {
        None => return Err(err(format!("{path}.link"), "missing")),
        Some(v) => array::<3>(v, &format!("{path}.link"))?,
    };
    let harmonics = terms(
        t,
        "harmonics",
        "{ order, sin, cos }",
        path,
        unknown,
        harmonic,
    )?;
    let wobble = terms(t, "wobble", "{ order, alpha, beta }", path, unknown, wobble)?;
    let j = Joint {
        axis,
        link,
        zero_offset: opt_number(t, "zero_offset", path)?,
        tilt: opt_array::<2>(t, "tilt", path)?,
        link_error: opt_array::<3>(t, "link_error", path)?,
        harmonics,
        wobble,
        gravity: opt_number(t, "gravity", path)?,
        thermal: opt_number(t, "thermal", path)?,
        encoder_counts: counts,
    };
    joint_in_limits(&j, path, limits)?;
    Ok(j)
}

/// A joint's required `axis`: `"x"`, `"y"` or `"z"`.
fn axis(t: &Table, path: &str) -> Result<Axis, CalFileError> {
    match t.get("axis") {
        None => Err(err(format!("{path}.axis"), "missing")),
        Some(Value::String(s)) => match s.as_str() {
            "x" => Ok(Axis::X),
            "y" => Ok(Axis::Y),
            "z" => Ok(Axis::Z),
            other => Err(err(
                format!("{path}.axis"),
                format!("\"{other}\" is not an axis: x, y or z"),
            )),
        },
        Some(_) => Err(err(format!("{path}.axis"), "must be a string: x, y or z")),
    }
}

/// Every value of joint `j` within `limits` (the link with its error too), the first one
/// outside named by its key path: a typo in units (metres, degrees) is refused here, not
/// fitted from.
fn joint_in_limits(j: &Joint, path: &str, limits: &Limits) -> Result<(), CalFileError> {
    let length = "link length";
    bounded_all(&j.link, limits.length_mm, &format!("{path}.link"), length)?;
    bounded_all(
        &j.link_error,
        limits.length_mm,
        &format!("{path}.link_error"),
        length,
    )?;
    bounded_all(
        &j.actual_link(),
        limits.length_mm,
        &format!("{path}.link + link_error"),
        length,
    )?;
    bounded(
        j.zero_offset,
        limits.angle_rad,
        &format!("{path}.zero_offset"),
        "angle",
    )?;
    bounded_all(&j.tilt, limits.angle_rad, &format!("{path}.tilt"), "angle")?;
    for (k, h) in j.harmonics.iter().enumerate() {
        let hp = format!("{path}.harmonics[{}]", k + 1);
        bounded(h.sin, limits.harmonic_rad, &format!("{hp}.sin"), "harmonic")?;
        bounded(h.cos, limits.harmonic_rad, &format!("{hp}.cos"), "harmonic")?;
    }
    for (k, w) in j.wobble.iter().enumerate() {
        let wp = format!("{path}.wobble[{}]", k + 1);
        bounded_all(
            &w.alpha,
            limits.wobble_rad,
            &format!("{wp}.alpha"),
            "wobble",
        )?;
        bounded_all(&w.beta, limits.wobble_rad, &format!("{wp}.beta"), "wobble")?;
    }
    bounded(
        j.gravity,
        limits.gravity,
        &format!("{path}.gravity"),
        "gravity compliance",
    )?;
    bounded(
        j.thermal,
        limits.thermal,
        &format!("{path}.thermal"),
        "thermal expansion",
    )?;
    Ok(())
}

/// A joint's list of periodic terms under `key` (absent: none), each read by `read` with its
/// key path (`joint[K].KEY[W]`, 1-based); `shape` names the tables, for the message.
fn terms<T>(
    t: &Table,
    key: &str,
    shape: &str,
    path: &str,
    unknown: &mut Vec<String>,
    read: fn(&Value, &str, &mut Vec<String>) -> Result<T, CalFileError>,
) -> Result<Vec<T>, CalFileError> {
    match t.get(key) {
        None => Ok(Vec::new()),
        Some(Value::Array(a)) => a
            .iter()
            .enumerate()
            .map(|(k, v)| read(v, &format!("{path}.{key}[{}]", k + 1), unknown))
            .collect(),
        Some(_) => Err(err(
            format!("{path}.{key}"),
            format!("must be an array of {shape} tables"),
        )),
    }
}

fn harmonic(v: &Value, path: &str, unknown: &mut Vec<String>) -> Result<Harmonic, CalFileError> {
    let t = v
        .as_table()
        .ok_or_else(|| err(path, "must be a table { order, sin, cos }"))?;
    note_unknown(t, &["order", "sin", "cos"], path, unknown);
    Ok(Harmonic {
        order: order(t, path)?,
        sin: opt_number(t, "sin", path)?,
        cos: opt_number(t, "cos", path)?,
    })
}

fn wobble(v: &Value, path: &str, unknown: &mut Vec<String>) -> Result<Wobble, CalFileError> {
    let t = v
        .as_table()
        .ok_or_else(|| err(path, "must be a table { order, alpha, beta }"))?;
    note_unknown(t, &["order", "alpha", "beta"], path, unknown);
    Ok(Wobble {
        order: order(t, path)?,
        alpha: opt_array::<2>(t, "alpha", path)?,
        beta: opt_array::<2>(t, "beta", path)?,
    })
}

/// A periodic term's `order`: an integer from 1 to [`MAX_HARMONIC_ORDER`].
fn order(t: &Table, path: &str) -> Result<u32, CalFileError> {
    Ok(match t.get("order") {
        None => return Err(err(format!("{path}.order"), "missing")),
        Some(Value::Integer(h)) if (1..=i64::from(MAX_HARMONIC_ORDER)).contains(h) => *h as u32,
        Some(Value::Integer(h)) => {
            return Err(err(
                format!("{path}.order"),
                format!("{h} is not an order: an integer from 1 to {MAX_HARMONIC_ORDER}"),
            ))
        }
        Some(_) => return Err(err(format!("{path}.order"), "must be an integer ≥ 1")),
    })
}

/// Several probes (`[[probe]]`): each entry as a `[probe]` table, with its `id` (required
/// where there is more than one), ids distinct, at most [`MAX_PROBES`]. The first is the
/// arm's `probe`, the rest its `more_probes`.
fn probes(
    entries: &[Value],
    unknown: &mut Vec<String>,
    limits: &Limits,
) -> Result<(Probe, Vec<Probe>), CalFileError> {
    if entries.is_empty() || entries.len() > MAX_PROBES {
        return Err(err(
            "probe",
            format!("{} probes; an arm carries 1 to {MAX_PROBES}", entries.len()),
        ));
    }
    let mut all: Vec<Probe> = Vec::with_capacity(entries.len());
    for (k, v) in entries.iter().enumerate() {
        let path = format!("probe[{}]", k + 1);
        let t = v.as_table().ok_or_else(|| err(&path, "must be a table"))?;
        if entries.len() > 1 && !t.contains_key("id") {
            return Err(err(
                format!("{path}.id"),
                "missing: with several probes each names its id",
            ));
        }
        let p = probe(t, &path, unknown, limits)?;
        if let Some(first) = all.iter().position(|q| q.id == p.id) {
            return Err(err(
                format!("{path}.id"),
                format!(
                    "{} is probe[{}]'s id too: ids are distinct",
                    p.id,
                    first + 1
                ),
            ));
        }
        all.push(p);
    }
    let first = all.remove(0);
    Ok((first, all))
}

/// One probe's table at `path` (`probe`, or `probe[K]` in an array).
fn probe(
    t: &Table,
    path: &str,
    unknown: &mut Vec<String>,
    limits: &Limits,
) -> Result<Probe, CalFileError> {
    note_unknown(
        t,
        &["id", "vector", "error", "thermal", "ball_diameter"],
        path,
        unknown,
    );
    let key = |k: &str| format!("{path}.{k}");
    let id = match t.get("id") {
        None => 0,
        Some(Value::Integer(i)) if (0..=255).contains(i) => *i as u8,
        Some(_) => return Err(err(key("id"), "must be an integer from 0 to 255")),
    };
    let vector = match t.get("vector") {
        None => return Err(err(key("vector"), "missing")),
        Some(v) => array::<3>(v, &key("vector"))?,
    };
    let p = Probe {
        id,
        vector,
        error: opt_array::<3>(t, "error", path)?,
        thermal: opt_number(t, "thermal", path)?,
        ball_diameter: opt_number(t, "ball_diameter", path)?,
    };
    if !(0.0..=limits.length_mm).contains(&p.ball_diameter) {
        return Err(err(
            key("ball_diameter"),
            format!(
                "{} mm is not a ball diameter: 0 to {} mm",
                p.ball_diameter, limits.length_mm
            ),
        ));
    }
    let length = "probe length";
    bounded_all(&p.vector, limits.length_mm, &key("vector"), length)?;
    bounded_all(&p.error, limits.length_mm, &key("error"), length)?;
    bounded_all(
        &p.actual(),
        limits.length_mm,
        &key("vector + error"),
        length,
    )?;
    bounded(
        p.thermal,
        limits.thermal,
        &key("thermal"),
        "thermal expansion",
    )?;
    let a = p.actual();
    if a.iter().all(|c| *c == 0.0) {
        return Err(err(
            key("vector"),
            "vector + error is zero: the probe direction is undefined",
        ));
    }
    Ok(p)
}

fn frame(t: &Table, unknown: &mut Vec<String>, limits: &Limits) -> Result<Frame, CalFileError> {
    note_unknown(t, &["rotation", "translation"], "reference_frame", unknown);
    let rotation = match t.get("rotation") {
        None => [1.0, 0.0, 0.0, 0.0],
        Some(v) => array::<4>(v, "reference_frame.rotation")?,
    };
    let norm = rotation.iter().map(|c| c * c).sum::<f64>().sqrt();
    if (norm - 1.0).abs() > 1e-6 {
        return Err(err(
            "reference_frame.rotation",
            format!("not a unit quaternion (norm {norm})"),
        ));
    }
    let translation = opt_array::<3>(t, "translation", "reference_frame")?;
    bounded_all(
        &translation,
        limits.translation_mm,
        "reference_frame.translation",
        "instrument distance",
    )?;
    Ok(Frame {
        rotation: rotation.map(|c| c / norm),
        translation,
    })
}

fn encoder_counts(v: Option<&Value>, n: usize) -> Result<Vec<u32>, CalFileError> {
    fn one(v: &Value, path: &str) -> Result<u32, CalFileError> {
        let c = match v {
            Value::Integer(i) => *i,
            Value::Float(f) if f.fract() == 0.0 && f.is_finite() => *f as i64,
            _ => return Err(err(path, "must be a positive integer")),
        };
        if !(2..=i64::from(i32::MAX)).contains(&c) {
            return Err(err(path, format!("{c} is out of range 2 ..= 2^31-1")));
        }
        Ok(c as u32)
    }
    match v {
        None => Ok(vec![DEFAULT_COUNTS; n]),
        Some(Value::Array(a)) => {
            if a.len() != n {
                return Err(err(
                    "encoder_counts",
                    format!("{} values for {n} joints", a.len()),
                ));
            }
            a.iter()
                .enumerate()
                .map(|(i, v)| one(v, &format!("encoder_counts[{}]", i + 1)))
                .collect()
        }
        Some(v) => Ok(vec![one(v, "encoder_counts")?; n]),
    }
}

fn note_unknown(t: &Table, known: &[&str], path: &str, unknown: &mut Vec<String>) {
    for k in t.keys() {
        if !known.contains(&k.as_str()) {
            unknown.push(format!("{path}.{k}"));
        }
    }
}

fn number(v: &Value, path: &str) -> Result<f64, CalFileError> {
    let x = match v {
        Value::Float(f) => *f,
        Value::Integer(i) => *i as f64,
        _ => return Err(err(path, "must be a number")),
    };
    if !x.is_finite() {
        return Err(err(path, format!("{x} is not a finite number")));
    }
    Ok(x)
}

fn array<const K: usize>(v: &Value, path: &str) -> Result<[f64; K], CalFileError> {
    let a = v
        .as_array()
        .ok_or_else(|| err(path, format!("must be an array of {K} numbers")))?;
    if a.len() != K {
        return Err(err(path, format!("has {} values, must have {K}", a.len())));
    }
    let mut out = [0.0; K];
    for (k, x) in a.iter().enumerate() {
        out[k] = number(x, &format!("{path}[{k}]"))?;
    }
    Ok(out)
}

fn opt_number(t: &Table, key: &str, path: &str) -> Result<f64, CalFileError> {
    t.get(key)
        .map_or(Ok(0.0), |v| number(v, &format!("{path}.{key}")))
}

fn opt_array<const K: usize>(t: &Table, key: &str, path: &str) -> Result<[f64; K], CalFileError> {
    t.get(key)
        .map_or(Ok([0.0; K]), |v| array::<K>(v, &format!("{path}.{key}")))
}

fn opt_string(t: &Table, key: &str, path: &str) -> Result<Option<String>, CalFileError> {
    match t.get(key) {
        None => Ok(None),
        Some(Value::String(s)) => Ok(Some(s.clone())),
        Some(_) => Err(err(path, "must be a string")),
    }
}

/// Writes an arm as a calibration file. `header` lines become `#` comments at the top.
///
/// Numbers are written with Rust's shortest round-trip formatting, so reading the file back
/// gives the same f64 values bit for bit.
pub fn write(arm: &Arm, header: &[&str]) -> String {
    write_with(arm, None, header)
}

/// Writes an arm and, when given, its `[uncertainty]` budget.
pub fn write_with(arm: &Arm, uncertainty: Option<&Uncertainty>, header: &[&str]) -> String {
    let mut s = String::new();
    for line in header {
        let _ = writeln!(s, "# {line}");
    }
    if let Some(name) = &arm.name {
        let _ = writeln!(s, "name = {}", quote(name));
    }
    if let Some(serial) = &arm.serial {
        let _ = writeln!(s, "serial = {}", quote(serial));
    }
    let counts: Vec<u32> = arm.joints.iter().map(|j| j.encoder_counts).collect();
    if counts.iter().all(|c| *c == counts[0]) {
        let _ = writeln!(s, "encoder_counts = {}", counts[0]);
    } else {
        let list: Vec<String> = counts.iter().map(u32::to_string).collect();
        let _ = writeln!(s, "encoder_counts = [{}]", list.join(", "));
    }
    for j in &arm.joints {
        let _ = writeln!(s, "\n[[joint]]");
        let _ = writeln!(s, "axis = \"{}\"", j.axis.name());
        let _ = writeln!(s, "link = {}", arr(&j.link));
        let _ = writeln!(s, "zero_offset = {}", num(j.zero_offset));
        let _ = writeln!(s, "tilt = {}", arr(&j.tilt));
        let _ = writeln!(s, "link_error = {}", arr(&j.link_error));
        let hs: Vec<String> = j
            .harmonics
            .iter()
            .map(|h| {
                format!(
                    "{{ order = {}, sin = {}, cos = {} }}",
                    h.order,
                    num(h.sin),
                    num(h.cos)
                )
            })
            .collect();
        let _ = writeln!(s, "harmonics = [{}]", hs.join(", "));
        if !j.wobble.is_empty() {
            let ws: Vec<String> = j
                .wobble
                .iter()
                .map(|w| {
                    format!(
                        "{{ order = {}, alpha = {}, beta = {} }}",
                        w.order,
                        arr(&w.alpha),
                        arr(&w.beta)
                    )
                })
                .collect();
            let _ = writeln!(s, "wobble = [{}]", ws.join(", "));
        }
        let _ = writeln!(s, "gravity = {}", num(j.gravity));
        let _ = writeln!(s, "thermal = {}", num(j.thermal));
    }
    // One probe of id 0 is written as `[probe]`, as every file before several probes were
    // possible; otherwise one `[[probe]]` each, with its id.
    let one = arm.more_probes.is_empty() && arm.probe.id == 0;
    for p in arm.probes() {
        if one {
            let _ = writeln!(s, "\n[probe]");
        } else {
            let _ = writeln!(s, "\n[[probe]]");
            let _ = writeln!(s, "id = {}", p.id);
        }
        let _ = writeln!(s, "vector = {}", arr(&p.vector));
        let _ = writeln!(s, "error = {}", arr(&p.error));
        let _ = writeln!(s, "thermal = {}", num(p.thermal));
        if p.ball_diameter != 0.0 {
            let _ = writeln!(s, "ball_diameter = {}", num(p.ball_diameter));
        }
    }
    if let Some(f) = &arm.reference_frame {
        let _ = writeln!(s, "\n[reference_frame]");
        let _ = writeln!(s, "rotation = {}", arr(&f.rotation));
        let _ = writeln!(s, "translation = {}", arr(&f.translation));
    }
    if let Some(u) = uncertainty {
        crate::uncertainty::write(u, arm, &mut s);
    }
    s
}

fn num(x: f64) -> String {
    // `{:?}` is the shortest text that reads back to the same f64, and it always carries a
    // `.` or an exponent, so TOML reads it as a float.
    format!("{x:?}")
}

fn arr(a: &[f64]) -> String {
    let parts: Vec<String> = a.iter().map(|x| num(*x)).collect();
    format!("[{}]", parts.join(", "))
}

fn quote(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    const FULL: &str = r#"
name = "t"
serial = "SN-7"
encoder_counts = 1048576
[[joint]]
axis = "z"
link = [0.0, 0.0, 200.0]
zero_offset = 1e-3
tilt = [2e-4, -3e-4]
link_error = [0.1, -0.2, 0.3]
harmonics = [ { order = 1, sin = 5e-5, cos = -2e-5 }, { order = 3, sin = 1e-6, cos = 0.0 } ]
wobble = [ { order = 2, alpha = [3e-5, -1e-5], beta = [0.0, 2e-5] } ]
gravity = 3e-8
thermal = 2.3e-5
[[joint]]
axis = "x"
link = [0, 0, 300]
[[joint]]
axis = "z"
link = [0, 0, 300]
[[joint]]
axis = "x"
link = [0, 0, 250]
[[joint]]
axis = "z"
link = [0, 0, 250]
[[joint]]
axis = "x"
link = [0, 0, 80]
bogus = 1
[probe]
vector = [0.0, 0.0, 120.0]
error = [0.01, 0.0, -0.02]
thermal = 1e-5
[reference_frame]
rotation = [1.0, 0.0, 0.0, 0.0]
translation = [10.0, 20.0, 30.0]
"#;

    #[test]
    fn reads_every_key() {
        let p = parse(FULL).unwrap();
        let a = &p.arm;
        assert_eq!(a.dof(), 6);
        assert_eq!(a.serial.as_deref(), Some("SN-7"));
        assert_eq!(a.joints[0].harmonics.len(), 2);
        assert_eq!(a.joints[0].harmonics[1].order, 3);
        assert_eq!(a.joints[0].tilt, [2e-4, -3e-4]);
        assert_eq!(a.joints[0].wobble[0].order, 2);
        assert_eq!(a.joints[0].wobble[0].alpha, [3e-5, -1e-5]);
        assert_eq!(a.joints[0].wobble[0].beta, [0.0, 2e-5]);
        assert_eq!(a.joints[1].link, [0.0, 0.0, 300.0]);
        assert_eq!(a.joints[1].gravity, 0.0);
        assert_eq!(a.probe.thermal, 1e-5);
        assert_eq!(p.unknown_keys, vec!["joint[6].bogus".to_string()]);
    }

    #[test]
    fn round_trips_bit_for_bit() {
        let a = parse(FULL).unwrap().arm;
        let text = write(&a, &["round trip"]);
        let b = parse(&text).unwrap();
        assert_eq!(a, b.arm);
        assert!(b.unknown_keys.is_empty());
    }

    #[test]
    fn refusals_name_the_key() {
        let cases = [
            (
                FULL.replace(
                    "axis = \"x\"\nlink = [0, 0, 300]",
                    "axis = \"w\"\nlink = [0, 0, 300]",
                ),
                "joint[2].axis",
            ),
            (FULL.replace("link = [0, 0, 80]", ""), "joint[6].link"),
            (
                FULL.replace("gravity = 3e-8", "gravity = nan"),
                "joint[1].gravity",
            ),
            (
                FULL.replace("tilt = [2e-4, -3e-4]", "tilt = [2e-4]"),
                "joint[1].tilt",
            ),
            (
                FULL.replace("zero_offset = 1e-3", "zero_offset = \"a\""),
                "joint[1].zero_offset",
            ),
            (
                FULL.replace("vector = [0.0, 0.0, 120.0]", "vector = [0.0, inf, 120.0]"),
                "probe.vector[1]",
            ),
            (
                FULL.replace("order = 3", "order = 0"),
                "joint[1].harmonics[2].order",
            ),
            (
                FULL.replace("order = 2, alpha", "order = -2, alpha"),
                "joint[1].wobble[1].order",
            ),
            (
                FULL.replace("beta = [0.0, 2e-5]", "beta = [0.0]"),
                "joint[1].wobble[1].beta",
            ),
            ("name = ".to_string(), "line 1, column 8"),
        ];
        for (text, path) in cases {
            let e = parse(&text).unwrap_err();
            assert_eq!(e.path, path, "{e}");
        }
    }

    #[test]
    fn defaults_apply() {
        let text = FULL.replace("encoder_counts = 1048576\n", "");
        let a = parse(&text).unwrap().arm;
        assert!(a.joints.iter().all(|j| j.encoder_counts == DEFAULT_COUNTS));
        let per_joint = FULL.replace(
            "encoder_counts = 1048576",
            "encoder_counts = [1, 2, 3, 4, 5, 6]",
        );
        assert_eq!(parse(&per_joint).unwrap_err().path, "encoder_counts[1]");
        let per_joint = FULL.replace(
            "encoder_counts = 1048576",
            "encoder_counts = [4096, 8192, 4096, 8192, 4096, 65536]",
        );
        let a = parse(&per_joint).unwrap().arm;
        assert_eq!(a.joints[5].encoder_counts, 65536);
    }

    #[test]
    fn syntax_errors_have_a_line_and_a_table() {
        let e = parse("name = \"a\"\nserial = \n").unwrap_err();
        assert_eq!(e.path, "line 2, column 10", "{e}");
        // A duplicate key: the parser names the key, the reader adds which joint.
        let text = FULL.replace("link = [0, 0, 250]", "link = [0, 0, 250]\nlink = [0, 0, 1]");
        let e = parse(&text).unwrap_err();
        assert!(e.path.starts_with("line "), "{e}");
        assert!(e.message.contains("duplicate key"), "{e}");
        assert!(e.message.contains("(in joint[4])"), "{e}");
    }

    #[test]
    fn a_serial_with_a_nul_is_refused() {
        let e = parse(&FULL.replace("\"SN-7\"", "\"SN\\u0000\"")).unwrap_err();
        assert_eq!(e.path, "serial");
        assert!(e.message.contains("NUL"), "{e}");
    }

    #[test]
    fn limits_refuse_absurd_values_with_their_key() {
        let l = Limits {
            length_mm: 5000.0,
            angle_rad: 7.0,
            harmonic_rad: 0.1,
            wobble_rad: 0.1,
            gravity: 1e-4,
            thermal: 4e-4,
            translation_mm: 1e5,
            budget_counts: 1e4,
            budget_mm: 10.0,
            budget_temperature_c: 50.0,
        };
        let cases = [
            (
                "link = [0, 0, 300]",
                "link = [0, 0, 1e300]",
                "joint[2].link[2]",
            ),
            (
                "link_error = [0.1, -0.2, 0.3]",
                "link_error = [0.1, -0.2, 1e308]",
                "joint[1].link_error[2]",
            ),
            (
                "link = [0, 0, 250]",
                "link = [0, 0, 250]\nlink_error = [0, 0, 4900]",
                "joint[4].link + link_error[2]",
            ),
            (
                "zero_offset = 1e-3",
                "zero_offset = 1e300",
                "joint[1].zero_offset",
            ),
            (
                "tilt = [2e-4, -3e-4]",
                "tilt = [2e-4, 30]",
                "joint[1].tilt[1]",
            ),
            ("sin = 5e-5", "sin = 2", "joint[1].harmonics[1].sin"),
            ("gravity = 3e-8", "gravity = 1", "joint[1].gravity"),
            ("thermal = 2.3e-5", "thermal = 1e300", "joint[1].thermal"),
            (
                "vector = [0.0, 0.0, 120.0]",
                "vector = [1e308, 1e308, 1e308]",
                "probe.vector[0]",
            ),
            (
                "error = [0.01, 0.0, -0.02]",
                "error = [1e308, 0.0, 0.0]",
                "probe.error[0]",
            ),
            (
                "translation = [10.0, 20.0, 30.0]",
                "translation = [1e300, 20.0, 30.0]",
                "reference_frame.translation[0]",
            ),
        ];
        for (from, to, path) in cases {
            let text = FULL.replace(from, to);
            assert_ne!(text, FULL, "{from}");
            assert!(parse(&text).is_ok(), "the format alone accepts {to}");
            let e = parse_with(&text, &l).unwrap_err();
            assert_eq!(e.path, path, "{e}");
            assert!(e.message.contains("limit"), "{e}");
        }
        assert!(parse_with(FULL, &l).is_ok());
    }

    const BUDGET: &str = r#"
[uncertainty]
parameters = ["joint.1.tilt.0", "joint.1.wobble.1.beta.1", "probe.error.2", "joint.1.harmonics.2.sin"]
covariance = [4e-10, 1e-11, 0.0, 0.0,
              1e-11, 9e-10, 0.0, 0.0,
              0.0, 0.0, 1e-6, 0.0,
              0.0, 0.0, 0.0, 1e-12]
encoder_counts = 0.29
probing_mm = 0.002
temperature_c = 0.2
"#;

    #[test]
    fn reads_and_round_trips_the_budget() {
        let p = parse(&format!("{FULL}{BUDGET}")).unwrap();
        let u = p.uncertainty.clone().unwrap();
        assert_eq!(
            u.parameters,
            vec![
                Param::Tilt(0, 0),
                // `wobble.1`: the first entry, of order 2; β's cos coefficient.
                Param::Wobble {
                    joint: 0,
                    order: 2,
                    coef: 3
                },
                Param::ProbeError(0, 2),
                // `harmonics.2`: the second entry, of order 3.
                Param::Harmonic {
                    joint: 0,
                    order: 3,
                    cos: false
                }
            ]
        );
        assert_eq!(u.encoder_counts, vec![0.29; 6]);
        assert_eq!(u.model_mm, 0.0);
        assert_eq!(u.matrix()[(1, 0)], 1e-11);
        let text = write_with(&p.arm, Some(&u), &[]);
        let back = parse(&text).unwrap();
        assert_eq!(back.uncertainty, Some(u));
        assert!(parse(FULL).unwrap().uncertainty.is_none());
    }

    #[test]
    fn budget_refusals_name_the_key() {
        let cases = [
            (
                "\"joint.1.tilt.0\"",
                "\"joint.7.tilt.0\"",
                "uncertainty.parameters[0]",
            ),
            (
                "\"joint.1.tilt.0\"",
                "\"joint.1.tilt.2\"",
                "uncertainty.parameters[0]",
            ),
            (
                "\"joint.1.harmonics.2.sin\"",
                "\"joint.1.harmonics.3.sin\"",
                "uncertainty.parameters[3]",
            ),
            (
                "\"probe.error.2\"",
                "\"joint.1.tilt.0\"",
                "uncertainty.parameters[2]",
            ),
            (
                "\"probe.error.2\"",
                "\"link.1\"",
                "uncertainty.parameters[2]",
            ),
            (
                "\"joint.1.wobble.1.beta.1\"",
                "\"joint.1.wobble.2.beta.1\"",
                "uncertainty.parameters[1]",
            ),
            (
                "\"joint.1.wobble.1.beta.1\"",
                "\"joint.1.wobble.1.gamma.1\"",
                "uncertainty.parameters[1]",
            ),
            (
                "0.0, 0.0, 0.0, 1e-12]",
                "0.0, 0.0, 0.0]",
                "uncertainty.covariance",
            ),
            (
                "0.0, 0.0, 0.0, 1e-12]",
                "0.0, 0.0, 0.0, -1e-12]",
                "uncertainty.covariance[15]",
            ),
            ("1e-11, 9e-10", "2e-11, 9e-10", "uncertainty.covariance[4]"),
            (
                "probing_mm = 0.002",
                "probing_mm = -0.002",
                "uncertainty.probing_mm",
            ),
            (
                "encoder_counts = 0.29",
                "encoder_counts = [0.29]",
                "uncertainty.encoder_counts",
            ),
        ];
        for (from, to, path) in cases {
            let text = format!("{FULL}{}", BUDGET.replacen(from, to, 1));
            let e = parse(&text).unwrap_err();
            assert_eq!(e.path, path, "{to}: {e}");
        }
        // The one counterexample of the PSD check is symmetric and within its diagonal bound
        // element by element, but not as a whole.
        let e = parse(&format!(
            "{FULL}{}",
            BUDGET.replacen("4e-10, 1e-11", "4e-10, 1e-9", 1).replacen(
                "1e-11, 9e-10",
                "1e-9, 9e-10",
                1
            )
        ))
        .unwrap_err();
        assert!(e.message.contains("positive semi-definite"), "{e}");
    }

    /// The pose part of [`BUDGET`]'s covariance: D of rank 2, b, the leverage mean.
    const POSE: &str = r#"pose_factor = [
  [1e-5, 0.0, 0.0, 0.0],
  [0.0, 2e-5, 3e-4, 0.0],
]
pose_shrink = 0.25
pose_leverage_mean = 3.5e-5
"#;

    /// Issue 27: the three pose keys read, and write back bit for bit; a file without them
    /// reads as before (no pose part, `model_mm` as it was).
    #[test]
    fn the_pose_keys_round_trip() {
        let text = format!("{FULL}{BUDGET}model_mm = 0.004\n{POSE}");
        let p = parse(&text).unwrap();
        let u = p.uncertainty.clone().unwrap();
        let pose = u.pose.clone().unwrap();
        assert_eq!(pose.factor[1], vec![0.0, 2e-5, 3e-4, 0.0]);
        assert_eq!((pose.shrink, pose.leverage_mean), (0.25, 3.5e-5));
        assert_eq!(u.model_mm, 0.004);
        assert!(
            !p.unknown_keys.iter().any(|k| k.starts_with("uncertainty")),
            "{:?}",
            p.unknown_keys
        );
        // Values no decimal text holds exactly, to test the bits.
        let mut odd = u.clone();
        odd.pose.as_mut().unwrap().factor[0][0] = 1.0e-5 / 3.0;
        odd.pose.as_mut().unwrap().shrink = 1.0 / 7.0;
        odd.pose.as_mut().unwrap().leverage_mean = std::f64::consts::PI * 1e-5;
        for u in [u, odd] {
            let back = parse(&write_with(&p.arm, Some(&u), &[])).unwrap();
            let b = back.uncertainty.unwrap();
            let (x, y) = (b.pose.as_ref().unwrap(), u.pose.as_ref().unwrap());
            assert_eq!(x.shrink.to_bits(), y.shrink.to_bits());
            assert_eq!(x.leverage_mean.to_bits(), y.leverage_mean.to_bits());
            for (a, c) in x.factor.iter().flatten().zip(y.factor.iter().flatten()) {
                assert_eq!(a.to_bits(), c.to_bits());
            }
            assert_eq!(b, u);
        }
        let without = parse(&format!("{FULL}{BUDGET}model_mm = 0.004\n")).unwrap();
        let u = without.uncertainty.unwrap();
        assert_eq!((u.pose, u.model_mm), (None, 0.004));
        // No parameters, no pose part.
        let u = p.uncertainty.unwrap().without_covariance();
        assert!(u.pose.is_none());
    }

    /// Issue 27: a pose part that is not one is refused with its key and index.
    #[test]
    fn pose_refusals_name_the_key() {
        let many = format!(
            "pose_factor = [\n{}]\n",
            "  [0.0, 0.0, 0.0, 0.0],\n".repeat(crate::uncertainty::POSE_RANK_MAX + 1)
        );
        let cases = [
            (
                "pose_shrink = 0.25\n",
                "",
                "uncertainty.pose_shrink",
                "missing",
            ),
            (
                "pose_leverage_mean = 3.5e-5\n",
                "",
                "uncertainty.pose_leverage_mean",
                "missing",
            ),
            (
                "pose_factor = [\n  [1e-5, 0.0, 0.0, 0.0],\n  [0.0, 2e-5, 3e-4, 0.0],\n]\n",
                "",
                "uncertainty.pose_factor",
                "missing",
            ),
            (
                "pose_factor = [\n  [1e-5, 0.0, 0.0, 0.0],\n  [0.0, 2e-5, 3e-4, 0.0],\n]\n",
                &many,
                "uncertainty.pose_factor",
                "at most 16",
            ),
            (
                "[0.0, 2e-5, 3e-4, 0.0]",
                "[0.0, 2e-5, 3e-4]",
                "uncertainty.pose_factor[1]",
                "3 values",
            ),
            (
                "[1e-5, 0.0",
                "[nan, 0.0",
                "uncertainty.pose_factor[0][0]",
                "finite",
            ),
            (
                "[0.0, 2e-5, 3e-4, 0.0]",
                "[0.0, 2e-5, 3e-4, \"x\"]",
                "uncertainty.pose_factor[1][3]",
                "finite",
            ),
            (
                "pose_shrink = 0.25",
                "pose_shrink = -0.25",
                "uncertainty.pose_shrink",
                "standard uncertainty",
            ),
            (
                "pose_shrink = 0.25",
                "pose_shrink = inf",
                "uncertainty.pose_shrink",
                "finite",
            ),
            (
                "pose_leverage_mean = 3.5e-5",
                "pose_leverage_mean = 0.0",
                "uncertainty.pose_leverage_mean",
                "> 0",
            ),
            // D Dᵀ larger than the covariance: 9e-10 against 4e-10 on the first diagonal.
            (
                "[1e-5, 0.0",
                "[3e-5, 0.0",
                "uncertainty.pose_factor",
                "positive semi-definite",
            ),
            // A correlation the covariance does not have: the 2×2 minor of (1, 2) negative.
            (
                "[0.0, 2e-5, 3e-4, 0.0]",
                "[0.0, 2.9e-5, 9.9e-4, 0.0]",
                "uncertainty.pose_factor",
                "positive semi-definite",
            ),
        ];
        for (from, to, path, says) in cases {
            let pose = POSE.replacen(from, to, 1);
            assert_ne!(pose, POSE, "{from}");
            let e = parse(&format!("{FULL}{BUDGET}{pose}")).unwrap_err();
            assert_eq!(e.path, path, "{to}: {e}");
            assert!(e.message.contains(says), "{to}: {e}");
        }
        // Beyond the parameter's own limit (joint.1.tilt.0, rad); the semi-definite check
        // would refuse it too, but later and without the index.
        let l = Limits {
            angle_rad: 10.0,
            ..Limits::NONE
        };
        let e = parse_with(
            &format!("{FULL}{BUDGET}{}", POSE.replacen("[1e-5", "[50.0", 1)),
            &l,
        )
        .unwrap_err();
        assert_eq!(e.path, "uncertainty.pose_factor[0][0]", "{e}");
        assert!(e.message.contains("limit"), "{e}");
    }

    /// The joint leverage of a six-joint arm: μ and a diagonal-plus-one W.
    const JOINTS: &str = r#"pose_joint_mean = [0.1, -0.5, 1.0, 0.0, 0.25, 0.0]
pose_joint_weight = [
  2.0, 0.5, 0.0, 0.0, 0.0, 0.0,
  0.5, 1.0, 0.0, 0.0, 0.0, 0.0,
  0.0, 0.0, 1.5, 0.0, 0.0, 0.0,
  0.0, 0.0, 0.0, 0.8, 0.0, 0.0,
  0.0, 0.0, 0.0, 0.0, 0.7, 0.0,
  0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
]
"#;

    /// Issue 27: the joint leverage's keys read, give ℓJ = (θ − μ)ᵀ W (θ − μ), and write
    /// back bit for bit.
    #[test]
    fn the_joint_leverage_round_trips_and_is_its_formula() {
        let p = parse(&format!("{FULL}{BUDGET}{POSE}{JOINTS}")).unwrap();
        let u = p.uncertainty.clone().unwrap();
        let j = u.pose.as_ref().unwrap().joints.clone().unwrap();
        assert_eq!(j.mean[1], -0.5);
        assert_eq!(j.ratio(&j.mean), 0.0);
        // θ − μ = (1, 1, 0, 0, 0, 5): 2 + 2·0.5 + 1 = 4; joint 6 did not move (W row 0).
        let mut theta = j.mean.clone();
        theta[0] += 1.0;
        theta[1] += 1.0;
        theta[5] += 5.0;
        assert!((j.ratio(&theta) - 4.0).abs() < 1e-12, "{}", j.ratio(&theta));
        assert!(
            !p.unknown_keys.iter().any(|k| k.starts_with("uncertainty")),
            "{:?}",
            p.unknown_keys
        );
        let mut odd = u.clone();
        odd.pose.as_mut().unwrap().joints.as_mut().unwrap().mean[0] = 1.0 / 3.0;
        for u in [u, odd] {
            let back = parse(&write_with(&p.arm, Some(&u), &[])).unwrap();
            assert_eq!(back.uncertainty.unwrap(), u);
        }
    }

    /// Issue 27: a joint leverage that is not one is refused with its key and index.
    #[test]
    fn joint_leverage_refusals_name_the_key() {
        let cases = [
            (
                "pose_joint_weight = [",
                "pose_joint_wait = [",
                "uncertainty.pose_joint_weight",
                "missing",
            ),
            (
                "pose_joint_mean = [",
                "pose_joint_man = [",
                "uncertainty.pose_joint_mean",
                "missing",
            ),
            (
                "[0.1, -0.5, 1.0, 0.0, 0.25, 0.0]",
                "[0.1, -0.5, 1.0, 0.0, 0.25]",
                "uncertainty.pose_joint_mean",
                "5 values",
            ),
            (
                "[0.1, -0.5,",
                "[0.1, -500.0,",
                "uncertainty.pose_joint_mean[1]",
                "beyond",
            ),
            (
                "[0.1, -0.5,",
                "[0.1, nan,",
                "uncertainty.pose_joint_mean[1]",
                "finite",
            ),
            (
                "  0.5, 1.0, 0.0",
                "  0.4, 1.0, 0.0",
                "uncertainty.pose_joint_weight[6]",
                "symmetric",
            ),
            (
                "  2.0, 0.5,",
                "  -2.0, 0.5,",
                "uncertainty.pose_joint_weight",
                "semi-definite",
            ),
            (
                "  0.0, 0.0, 0.0, 0.0, 0.0, 0.0,\n]",
                "]",
                "uncertainty.pose_joint_weight",
                "30 values",
            ),
        ];
        for (from, to, path, says) in cases {
            let joints = JOINTS.replacen(from, to, 1);
            assert_ne!(joints, JOINTS, "{from}");
            let e = parse(&format!("{FULL}{BUDGET}{POSE}{joints}")).unwrap_err();
            assert_eq!(e.path, path, "{to}: {e}");
            assert!(e.message.contains(says), "{to}: {e}");
        }
        // Without the pose part the joint keys have nothing to widen.
        let e = parse(&format!("{FULL}{BUDGET}{JOINTS}")).unwrap_err();
        assert_eq!(e.path, "uncertainty.pose_joint_mean", "{e}");
    }

    /// Issue 27, F1: a zero variance beside a non-zero covariance (eigenvalue −0.6e-6) passed
    /// the correlation matrix's check, which cannot see a zero variance; refused at the entry.
    #[test]
    fn a_zero_variance_beside_a_covariance_is_refused() {
        let text = format!("{FULL}{}", BUDGET.replacen("4e-10, 1e-11", "0.0, 1e-11", 1));
        let e = parse(&text).unwrap_err();
        assert_eq!(e.path, "uncertainty.covariance[1]", "{e}");
        assert!(e.message.contains("positive semi-definite"), "{e}");
        // A zero variance with zero covariances is a parameter known exactly: read.
        let exact = BUDGET.replacen("0.0, 0.0, 1e-6, 0.0", "0.0, 0.0, 0.0, 0.0", 1);
        assert!(parse(&format!("{FULL}{exact}")).is_ok());
    }

    /// Issue 27, F2: every term of the budget within the limits the tool reads with, refused
    /// with its key beyond them (`probing_mm = 1e200` gave a U95 of 0).
    #[test]
    fn budget_terms_beyond_the_limits_are_refused_with_their_key() {
        let l = Limits {
            budget_counts: 1e4,
            budget_mm: 10.0,
            budget_temperature_c: 50.0,
            ..Limits::NONE
        };
        let l = Limits {
            angle_rad: 7.0,
            length_mm: 5000.0,
            ..l
        };
        let cases = [
            (
                "probing_mm = 0.002",
                "probing_mm = 1e200",
                "uncertainty.probing_mm",
            ),
            (
                "probing_mm = 0.002",
                "probing_mm = 0.002\nmodel_mm = 11",
                "uncertainty.model_mm",
            ),
            (
                "encoder_counts = 0.29",
                "encoder_counts = 1e300",
                "uncertainty.encoder_counts",
            ),
            (
                "temperature_c = 0.2",
                "temperature_c = 60",
                "uncertainty.temperature_c",
            ),
            ("4e-10, 1e-11", "64.0, 1e-11", "uncertainty.covariance[0]"),
        ];
        for (from, to, path) in cases {
            let text = format!("{FULL}{}", BUDGET.replacen(from, to, 1));
            assert!(parse(&text).is_ok(), "{to}: without limits");
            let e = parse_with(&text, &l).unwrap_err();
            assert_eq!(e.path, path, "{to}: {e}");
            assert!(e.message.contains("limit"), "{e}");
        }
        assert!(parse_with(&format!("{FULL}{BUDGET}"), &l).is_ok());
    }

    /// `FULL` with its `[probe]` replaced by `probes`.
    fn with_probes(probes: &str) -> String {
        let start = FULL.find("[probe]").unwrap();
        let end = FULL.find("[reference_frame]").unwrap();
        format!("{}{probes}{}", &FULL[..start], &FULL[end..])
    }

    const THREE_PROBES: &str = r#"[[probe]]
id = 4
vector = [0.0, 0.0, 120.0]
error = [0.01, 0.0, -0.02]
thermal = 1e-5
ball_diameter = 6.0
[[probe]]
id = 0
vector = [0.0, 0.0, 250.5]
ball_diameter = 3.0
[[probe]]
id = 17
vector = [40.0, 0.0, 90.0]
error = [0.0, 0.1, 0.0]
"#;

    /// Several probes: read in file order (the first is `probe`), their ids, a round trip
    /// bit for bit, and each one's evaluation through `for_probe`.
    #[test]
    fn several_probes_are_read_written_and_evaluated() {
        let a = parse(&with_probes(THREE_PROBES)).unwrap().arm;
        assert_eq!(a.probe_count(), 3);
        let ids: Vec<u8> = a.probes().map(|p| p.id).collect();
        assert_eq!(ids, [4, 0, 17]);
        assert_eq!(a.probe_index(17), Some(2));
        assert_eq!(a.probe_index(5), None);
        assert_eq!(a.more_probes[0].ball_diameter, 3.0);
        let text = write(&a, &[]);
        assert!(text.contains("[[probe]]\nid = 17\n"), "{text}");
        assert_eq!(parse(&text).unwrap().arm, a);
        // Each probe is evaluated as the arm with it mounted: two probes' ball centres differ
        // by the difference of their vectors, turned by the last joint (same length; without
        // gravity, whose deflection depends on where the ball is).
        let theta = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6];
        let mut rigid = a.clone();
        rigid.joints.iter_mut().for_each(|j| j.gravity = 0.0);
        let tip = |k: usize| crate::forward::forward(&rigid.for_probe(k).unwrap(), &theta, 20.0).p;
        let v = |k: usize| nalgebra::Vector3::from(a.probe_at(k).unwrap().actual());
        for k in 1..3 {
            let d = tip(k) - tip(0);
            assert!((d.norm() - (v(k) - v(0)).norm()).abs() < 1e-9, "{d}");
        }
        assert!(a.for_probe(3).is_none());
        // One probe of id 0 is still written as `[probe]`, as before.
        let one = parse(FULL).unwrap().arm;
        assert!(write(&one, &[]).contains("\n[probe]\n"));
    }

    #[test]
    fn bad_probe_lists_are_refused_with_their_key() {
        let cases = [
            (THREE_PROBES.replacen("id = 0\n", "", 1), "probe[2].id"),
            (THREE_PROBES.replacen("id = 17", "id = 4", 1), "probe[3].id"),
            (
                THREE_PROBES.replacen("id = 17", "id = 256", 1),
                "probe[3].id",
            ),
            (
                THREE_PROBES.replacen("id = 17", "id = \"a\"", 1),
                "probe[3].id",
            ),
            (
                THREE_PROBES.replacen("vector = [0.0, 0.0, 250.5]", "", 1),
                "probe[2].vector",
            ),
            (
                THREE_PROBES.replacen("ball_diameter = 3.0", "ball_diameter = -3.0", 1),
                "probe[2].ball_diameter",
            ),
        ];
        for (probes, path) in cases {
            let e = parse(&with_probes(&probes)).unwrap_err();
            assert_eq!(e.path, path, "{e}");
        }
        let nine: String = (0..9)
            .map(|id| format!("[[probe]]\nid = {id}\nvector = [0.0, 0.0, 100.0]\n"))
            .collect();
        let e = parse(&with_probes(&nine)).unwrap_err();
        assert_eq!(e.path, "probe", "{e}");
        // A single `[[probe]]` needs no id (0), as `[probe]`.
        let single = "[[probe]]\nvector = [0.0, 0.0, 100.0]\n";
        assert_eq!(parse(&with_probes(single)).unwrap().arm.probe.id, 0);
    }

    /// `probe.ID.error.C` names another probe's error; an id the arm lacks is refused.
    #[test]
    fn another_probes_error_has_a_budget_name() {
        use crate::uncertainty::name;
        let a = parse(&with_probes(THREE_PROBES)).unwrap().arm;
        assert_eq!(
            crate::uncertainty::parse_name("probe.17.error.1", &a),
            Ok(Param::ProbeError(2, 1))
        );
        assert_eq!(
            name(Param::ProbeError(2, 1), &a).as_deref(),
            Some("probe.17.error.1")
        );
        assert_eq!(
            name(Param::ProbeError(0, 1), &a).as_deref(),
            Some("probe.error.1")
        );
        assert_eq!(name(Param::ProbeError(3, 1), &a), None);
        assert_eq!(
            crate::uncertainty::parse_name("probe.4.error.0", &a),
            Ok(Param::ProbeError(0, 0))
        );
        let e = crate::uncertainty::parse_name("probe.5.error.0", &a).unwrap_err();
        assert!(e.contains("4, 0, 17"), "{e}");
    }
}
