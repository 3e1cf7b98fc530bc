//! `armcal eval`: joint readings (CSV) through one evaluator to XYZ and probe direction (CSV).
//!
//! Input columns `j1..jN` (radians) or `c1..cN` (encoder counts, 0 ≤ c < counts per
//! revolution), optional `temp_c` (20 °C where absent or empty) and `probe` (the id of the
//! probe the reading was taken with; the arm's first where absent or empty); other columns
//! are ignored.
//! `f64` runs the reference; `f32` and `fixed` run the `quatarm` quaternion chain on the binary
//! table a board would load, with radians rounded to the nearest count and the temperature to
//! the nearest milli-degree — the firmware's inputs — and print the firmware's integer outputs
//! (nm, 1e-9) scaled, so they compare bit for bit with a board's stream. The whole input is
//! evaluated before anything is written: a bad row gives an error and no partial output.

use crate::data::{
    count_cell, joint_columns, number_cell, unique_columns, without_comments, Bound, HeaderProblem,
    Lines,
};
use crate::limits::shown;
use anyhow::Context as _;
use quatarm::{Chain, Fixed, Table, F32};
use quatarm_ref::Arm;
use std::fmt::Write as _;

/// The evaluator.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Evaluator {
    /// The f64 reference (exact gravity).
    F64,
    /// The firmware's f32 quaternion chain.
    F32,
    /// The firmware's fixed-point quaternion chain.
    Fixed,
}

/// A refused input, with its place.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("line {line}, column {column}: {message}")]
pub struct RowError {
    /// 1-based line of the input (the header is line 1).
    pub line: u64,
    /// The column's name (`(header)`, `(row)` for the whole).
    pub column: String,
    /// Why.
    pub message: String,
}

/// One parsed input row.
#[derive(Clone, Debug, PartialEq)]
pub enum Reading {
    /// Radians.
    Radians(Vec<f64>),
    /// Counts.
    Counts(Vec<u32>),
}

impl Reading {
    /// The reading's angles (rad), as the f64 reference evaluates it.
    pub fn radians(&self, arm: &Arm) -> Vec<f64> {
        match self {
            Reading::Radians(v) => v.clone(),
            Reading::Counts(c) => arm.counts_to_rad(c),
        }
    }
}

/// One input row.
#[derive(Clone, Debug, PartialEq)]
pub struct Input {
    /// The joint reading.
    pub reading: Reading,
    /// Its temperature (°C).
    pub temp_c: f64,
    /// The index (`quatarm_ref::Arm::probes` order) of the probe it was taken with.
    pub probe: usize,
}

/// Parsed input, in input order.
pub type Rows = Vec<Input>;

/// Reads the CSV input for an arm. The header follows the measured data's rule
/// ([`crate::data::unique_columns`], [`crate::data::joint_columns`]): every name once, the
/// joint columns exactly the arm's; numbers within the same bounds ([`Bound`]).
pub fn read_rows(arm: &Arm, mut input: impl std::io::Read) -> Result<Rows, RowError> {
    let mut text = String::new();
    input.read_to_string(&mut text).map_err(|e| RowError {
        line: 0,
        column: "(input)".into(),
        message: format!("cannot read: {e}"),
    })?;
    // A spreadsheet's UTF-8 byte order mark would glue itself to the first column's name.
    let text = without_comments(text.strip_prefix('\u{feff}').unwrap_or(&text));
    let lines = Lines::new(&text);
    let mut rdr = csv::ReaderBuilder::new()
        .delimiter(crate::data::separator(&text))
        .has_headers(true)
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let header = Header::read(&mut rdr, arm.dof())?;
    let mut rows = Vec::new();
    for rec in rdr.records() {
        let rec = rec.map_err(|e| RowError {
            line: lines.of_error(&e) as u64,
            column: "(row)".into(),
            message: e.to_string(),
        })?;
        let line = lines.of_record(&rec) as u64;
        rows.push(header.input(arm, &Record { rec: &rec, line })?);
    }
    Ok(rows)
}

/// The input's header: which columns hold the joints (radians or counts), the temperature
/// and the probe.
struct Header {
    /// The column names, as written.
    names: Vec<String>,
    /// The joint columns, in joint order.
    joints: Vec<usize>,
    /// Whether the joints are in radians (`j1..jN`), else counts (`c1..cN`).
    radians: bool,
    /// The `temp_c` column, if any.
    temp: Option<usize>,
    /// The `probe` column, if any.
    probe: Option<usize>,
}

impl Header {
    /// Reads and checks the header of an input for an arm of `n` joints (every problem on
    /// line 1, naming its column).
    fn read<R: std::io::Read>(rdr: &mut csv::Reader<R>, n: usize) -> Result<Header, RowError> {
        let header_err = |column: String, message: String| RowError {
            line: 1,
            column,
            message,
        };
        let names: Vec<String> = rdr
            .headers()
            .map_err(|e| header_err("(header)".into(), format!("cannot read the header: {e}")))?
            .iter()
            .map(str::to_string)
            .collect();
        let problem = |p: HeaderProblem| header_err(p.column, p.message);
        let seen = unique_columns(&names).map_err(problem)?;
        let j = joint_columns(&names, "j", n).map_err(problem)?;
        let c = joint_columns(&names, "c", n).map_err(problem)?;
        let (joints, radians) = match (j, c) {
            (Some(j), None) => (j, true),
            (None, Some(c)) => (c, false),
            _ => {
                return Err(header_err(
                    "(header)".into(),
                    format!("need columns j1..j{n} (radians) or c1..c{n} (counts), not both"),
                ))
            }
        };
        Ok(Header {
            temp: seen.get("temp_c").copied(),
            probe: seen.get("probe").copied(),
            names,
            joints,
            radians,
        })
    }

    /// One data row as an input: its reading, its temperature and its probe, in that order
    /// of checking.
    fn input(&self, arm: &Arm, r: &Record) -> Result<Input, RowError> {
        Ok(Input {
            reading: self.reading(arm, r)?,
            temp_c: self.temperature(r)?,
            probe: self.probe(arm, r)?,
        })
    }

    /// The cell of column `col` (a short row misses it).
    fn field<'r>(&self, r: &Record<'r>, col: usize) -> Result<&'r str, RowError> {
        r.rec
            .get(col)
            .ok_or_else(|| self.bad(r, col, "missing field".into()))
    }

    /// A refusal of the cell of column `col`, naming the line and the column.
    fn bad(&self, r: &Record, col: usize, message: String) -> RowError {
        RowError {
            line: r.line,
            column: shown(&self.names[col]),
            message,
        }
    }

    /// The joint cells, radians within [`Bound::joint`] or counts below each joint's counts
    /// per revolution.
    fn reading(&self, arm: &Arm, r: &Record) -> Result<Reading, RowError> {
        let cell = |col: usize| self.field(r, col);
        if self.radians {
            let mut v = Vec::with_capacity(self.joints.len());
            for &col in &self.joints {
                v.push(
                    number_cell(cell(col)?, &Bound::joint())
                        .map_err(|m| self.bad(r, col, m.to_string()))?,
                );
            }
            Ok(Reading::Radians(v))
        } else {
            let mut v = Vec::with_capacity(self.joints.len());
            for (k, &col) in self.joints.iter().enumerate() {
                let per_rev = arm.joints[k].encoder_counts;
                v.push(
                    count_cell(cell(col)?, per_rev).map_err(|m| self.bad(r, col, m.to_string()))?,
                );
            }
            Ok(Reading::Counts(v))
        }
    }

    /// The temperature (°C): the reference temperature where there is no column or the cell
    /// is empty.
    fn temperature(&self, r: &Record) -> Result<f64, RowError> {
        Ok(match self.temp {
            Some(col) if !self.field(r, col)?.is_empty() => {
                number_cell(self.field(r, col)?, &Bound::temperature())
                    .map_err(|m| self.bad(r, col, m.to_string()))?
            }
            _ => quatarm_ref::forward::REFERENCE_TEMP_C,
        })
    }

    /// The index of the row's probe: the arm's first where there is no column or the cell is
    /// empty; an id the arm does not have is refused, listing the ids it has.
    fn probe(&self, arm: &Arm, r: &Record) -> Result<usize, RowError> {
        let col = match self.probe {
            Some(col) if !self.field(r, col)?.is_empty() => col,
            _ => return Ok(0),
        };
        let s = self.field(r, col)?;
        s.parse::<u8>()
            .ok()
            .and_then(|id| arm.probe_index(id))
            .ok_or_else(|| {
                let ids: Vec<String> = arm.probes().map(|p| p.id.to_string()).collect();
                self.bad(
                    r,
                    col,
                    format!(
                        "`{}` is not a probe of the arm (its probes: {})",
                        shown(s),
                        ids.join(", ")
                    ),
                )
            })
    }
}

/// A data record and its line in the input, for messages that name the cell.
struct Record<'a> {
    rec: &'a csv::StringRecord,
    line: u64,
}
/// The count nearest to an angle (rad), in 0..counts.
pub fn nearest_count(theta: f64, counts: u32) -> u32 {
    let c = (theta / std::f64::consts::TAU * f64::from(counts)).round() as i64;
    c.rem_euclid(i64::from(counts)) as u32
}

/// The firmware's temperature input: milli-degrees, rounded.
pub fn temp_mc(temp_c: f64) -> i32 {
    (temp_c * 1000.0).round() as i32
}

/// Integer units printed with `decimals` digits after the point, exactly.
pub fn fixed_decimal(v: i32, decimals: u32) -> String {
    let scale = 10i64.pow(decimals);
    let v = i64::from(v);
    let sign = if v < 0 { "-" } else { "" };
    let a = v.abs();
    format!(
        "{sign}{}.{:0width$}",
        a / scale,
        a % scale,
        width = decimals as usize
    )
}

fn counts_of(arm: &Arm, r: &Reading) -> Vec<u32> {
    match r {
        Reading::Counts(c) => c.clone(),
        Reading::Radians(v) => v
            .iter()
            .zip(&arm.joints)
            .map(|(&t, j)| nearest_count(t, j.encoder_counts))
            .collect(),
    }
}

/// The firmware path `P` on the table a board would load: ONE table holding all the arm's
/// probes, as a hub loads it, with each row's probe mounted on it ([`Chain::mount`], a hub
/// with that probe selected). The chain's model takes its reach, levers and second-order
/// gravity from the table's longest probe, so a table per probe would not compute what the
/// hub does. `calib` names the calibration in errors about it (a table it cannot become, an
/// arm the evaluator cannot hold).
fn firmware<P: quatarm::Evaluator>(
    arm: &Arm,
    rows: &Rows,
    calib: &str,
    out: &mut String,
) -> anyhow::Result<()> {
    let no_evaluator = || format!("{calib}: no {} evaluator for this arm", P::NAME);
    let bytes = crate::tablebuild::build(arm)
        .map_err(anyhow::Error::from)
        .with_context(no_evaluator)?;
    let table = Table::parse(&bytes)
        .map_err(anyhow::Error::from)
        .with_context(no_evaluator)?;
    let chain = |k: usize| -> anyhow::Result<Chain<P>> {
        let mut chain = Chain::<P>::new(&table)
            .map_err(anyhow::Error::from)
            .with_context(no_evaluator)?;
        chain
            .mount(&table, k)
            .map_err(anyhow::Error::from)
            .with_context(|| format!("{calib}: probe {k} cannot be mounted"))?;
        Ok(chain)
    };
    let mut chains: Vec<Option<Chain<P>>> = (0..arm.probe_count()).map(|_| None).collect();
    for r in rows {
        if chains[r.probe].is_none() {
            chains[r.probe] = Some(chain(r.probe)?);
        }
        let chain = chains[r.probe].as_ref().context("built above")?;
        let counts = counts_of(arm, &r.reading);
        let pt = chain.eval(&counts, temp_mc(r.temp_c))?;
        let [x, y, z] = pt.xyz_nm();
        let [nx, ny, nz] = pt.dir_e9();
        let _ = writeln!(
            out,
            "{},{},{},{},{},{}",
            fixed_decimal(x, 6),
            fixed_decimal(y, 6),
            fixed_decimal(z, 6),
            fixed_decimal(nx, 9),
            fixed_decimal(ny, 9),
            fixed_decimal(nz, 9)
        );
    }
    Ok(())
}

/// Evaluates every row; returns the whole output CSV. `calib` names the calibration in
/// errors about the arm itself.
pub fn evaluate(
    arm: &Arm,
    rows: &Rows,
    evaluator: Evaluator,
    calib: &str,
) -> anyhow::Result<String> {
    let mut out = String::from("x,y,z,nx,ny,nz\n");
    match evaluator {
        Evaluator::F64 => {
            let mounted: Vec<_> = (0..arm.probe_count())
                .filter_map(|k| arm.for_probe(k))
                .collect();
            for r in rows {
                let with = mounted
                    .get(r.probe)
                    .context("a row's probe is one of the arm's")?;
                let pose = quatarm_ref::forward::forward(with, &r.reading.radians(arm), r.temp_c);
                let _ = writeln!(
                    out,
                    "{:.9},{:.9},{:.9},{:.12},{:.12},{:.12}",
                    pose.p.x, pose.p.y, pose.p.z, pose.n.x, pose.n.y, pose.n.z
                );
            }
        }
        Evaluator::F32 => firmware::<F32>(arm, rows, calib, &mut out)?,
        Evaluator::Fixed => firmware::<Fixed>(arm, rows, calib, &mut out)?,
    }
    Ok(out)
}
