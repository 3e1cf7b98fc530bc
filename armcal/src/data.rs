//! Measured data (`spec/measured-data.md`): the CSV an arm's owner records, read into rows.
//!
//! Reading is all-or-nothing: the first problem found is returned with the file, the line and
//! the column at fault, and no rows are returned with it, so a tool can never fit half a file.
//! Rows keep their line number so that later stages (calibration, diagnosis) can point back
//! into the file too.

use crate::limits::{number, shown};
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// What the ball was resting on (`kind`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Kind {
    /// The ball centre was measured by a reference instrument (`x`, `y`, `z`).
    Point,
    /// Single-point articulation: every row of the group probes one fixed, unknown point.
    Spat,
    /// A ball bar: rows probe ball `a` or `b`, whose centres are `length_mm` apart.
    Length,
    /// The ball touches a calibrated test sphere of `diameter_mm` (acceptance tests).
    Sphere,
}

impl Kind {
    /// The file's spelling.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Point => "point",
            Kind::Spat => "spat",
            Kind::Length => "length",
            Kind::Sphere => "sphere",
        }
    }
}

/// Which ball of a bar a `length` row probes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum End {
    /// Ball `a`.
    A,
    /// Ball `b`.
    B,
}

/// One probing: the arm in one pose with its ball resting on something.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// The row's kind.
    pub kind: Kind,
    /// Rows that belong together (one artefact position) share it.
    pub group: i64,
    /// Raw encoder readings (rad), one per joint.
    pub theta: Vec<f64>,
    /// `point` rows: the reference coordinates of the ball centre (mm, instrument frame).
    pub xyz: Option<[f64; 3]>,
    /// `length` rows: which ball.
    pub end: Option<End>,
    /// `length` rows: the calibrated distance between the two ball centres (mm).
    pub length_mm: Option<f64>,
    /// `sphere` rows: the test sphere touched.
    pub sphere: Option<Touch>,
    /// Arm temperature at the reading (°C); 20 where the file records none.
    pub temp_c: f64,
    /// The id of the probe the row was taken with (the `probe` column); `None` for the arm's
    /// first probe (no column, or an empty cell).
    pub probe: Option<u8>,
    /// 1-based line of the row in its file (0 for rows made in memory).
    pub line: usize,
    /// The file the row was read from, where a dataset merges several files ([`read_all`]),
    /// so that a message raised after the merge names the row's own file with its line
    /// ([`Dataset::file_of`]); `None`: the dataset's [`Dataset::source`].
    pub file: Option<std::sync::Arc<str>>,
}

impl Row {
    /// A `point` row made in memory (simulated or designed): the ball at `xyz` in the
    /// instrument frame, no line or file of its own.
    pub fn point(
        group: i64,
        theta: Vec<f64>,
        xyz: [f64; 3],
        temp_c: f64,
        probe: Option<u8>,
    ) -> Row {
        Row {
            kind: Kind::Point,
            group,
            theta,
            xyz: Some(xyz),
            end: None,
            length_mm: None,
            sphere: None,
            temp_c,
            probe,
            line: 0,
            file: None,
        }
    }
}

/// What a `sphere` row touches.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Touch {
    /// The test sphere's calibrated diameter D (mm).
    pub diameter_mm: f64,
    /// Which articulation of an L_Dia test the row belongs to, where the file says.
    pub articulation: Option<i64>,
}

/// A `sphere` group: one position of a test sphere.
#[derive(Clone, Debug, PartialEq)]
pub struct SphereGroup {
    /// The group number of the file.
    pub group: i64,
    /// Indices into [`Dataset::rows`].
    pub rows: Vec<usize>,
    /// The sphere's diameter D (mm).
    pub diameter_mm: f64,
}

/// A `spat` group: the rows that probe one fixed, unknown point.
#[derive(Clone, Debug, PartialEq)]
pub struct SpatGroup {
    /// The group number of the file.
    pub group: i64,
    /// Indices into [`Dataset::rows`].
    pub rows: Vec<usize>,
}

/// A `length` group: one position of a ball bar.
#[derive(Clone, Debug, PartialEq)]
pub struct LengthGroup {
    /// The group number of the file.
    pub group: i64,
    /// Rows probing ball `a` (indices into [`Dataset::rows`]).
    pub a: Vec<usize>,
    /// Rows probing ball `b`.
    pub b: Vec<usize>,
    /// Distance between the ball centres (mm).
    pub length_mm: f64,
}

/// The rows of a file sorted by what ties them together.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Layout {
    /// `point` rows (indices into [`Dataset::rows`]); they share one instrument frame.
    pub points: Vec<usize>,
    /// `spat` groups, by group number.
    pub spat: Vec<SpatGroup>,
    /// `length` groups, by group number.
    pub length: Vec<LengthGroup>,
    /// `sphere` groups, by group number.
    pub sphere: Vec<SphereGroup>,
}

/// One unit of evidence: what a held-out check leaves out and judges whole, and what the
/// calibration's residuals come in blocks of (a `point` row alone; a `spat`, `length` or
/// `sphere` group whole, since its fixed point, bar or centre is estimated from its own rows).
#[derive(Clone, Debug, PartialEq)]
pub struct Unit {
    /// Indices into [`Dataset::rows`].
    pub rows: Vec<usize>,
    /// The group number of a `length` unit, whose bar error belongs to it too.
    pub bar: Option<i64>,
}

impl Layout {
    /// Each `length` group's two ends (the rows probing ball `a`, then those probing `b`): the
    /// rows that share one centre, which a held-out check judges by their deviations from it.
    pub fn length_ends(&self) -> impl Iterator<Item = &Vec<usize>> {
        self.length.iter().flat_map(|l| [&l.a, &l.b])
    }

    /// The units, in the order the calibration visits its residual blocks: `point` rows one
    /// by one, then `spat`, `length` (ball `a`'s rows, then `b`'s) and `sphere` groups.
    pub fn units(&self) -> Vec<Unit> {
        let whole = |rows: &[usize]| Unit {
            rows: rows.to_vec(),
            bar: None,
        };
        let mut v: Vec<Unit> = self.points.iter().map(|&i| whole(&[i])).collect();
        v.extend(self.spat.iter().map(|g| whole(&g.rows)));
        v.extend(self.length.iter().map(|g| Unit {
            rows: g.a.iter().chain(&g.b).copied().collect(),
            bar: Some(g.group),
        }));
        v.extend(self.sphere.iter().map(|g| whole(&g.rows)));
        v
    }
}

/// A whole data file.
#[derive(Clone, Debug, PartialEq)]
pub struct Dataset {
    /// The rows, in file order.
    pub rows: Vec<Row>,
    /// Joint count N of every row.
    pub dof: usize,
    /// Whether the file has a `temp_c` column.
    pub has_temperature: bool,
    /// Things the reader ignored (unknown columns).
    pub warnings: Vec<String>,
    /// Where the rows came from, for messages.
    pub source: String,
}

/// Bad input: the file, line and column at fault, and why.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{file}: {}{message}", place(*.line, .column))]
pub struct DataError {
    /// The file.
    pub file: String,
    /// 1-based line (the header is line 1 unless comments precede it).
    pub line: usize,
    /// Column name (or `(row)` for a row as a whole).
    pub column: String,
    /// What is wrong.
    pub message: String,
}

/// "line L, column C: ", or nothing for the file as a whole (line 0: it cannot be read).
fn place(line: usize, column: &str) -> String {
    if line == 0 {
        String::new()
    } else {
        format!("line {line}, column {column}: ")
    }
}

/// The separator of a CSV text, from its header (the first line that is not a comment): the
/// one of `,`, `;` and tab it holds most (a spreadsheet in a comma-decimal locale writes `;`),
/// `,` when it holds none (a one-column header; the column check then names what is missing).
pub fn separator(text: &str) -> u8 {
    let header = text
        .lines()
        .find(|l| {
            let t = l.trim();
            !t.is_empty() && !t.starts_with('#')
        })
        .unwrap_or("");
    let count = |c: char| header.matches(c).count();
    [b',', b';', b'\t']
        .into_iter()
        .max_by_key(|&c| (count(char::from(c)), c == b','))
        .unwrap_or(b',')
}

/// The separator's name in messages.
pub fn separator_name(sep: u8) -> &'static str {
    match sep {
        b';' => "`;`",
        b'\t' => "tab",
        _ => "`,`",
    }
}

/// Reads a data file for an arm with `dof` joints (joint columns `j1..jN` in radians; count
/// columns need the arm's encoders: [`read_all`]).
pub fn read(path: &std::path::Path, dof: usize) -> Result<Dataset, DataError> {
    let file = path.display().to_string();
    parse_with(&read_text(path)?, &file, Joints::Radians(dof))
}

/// A file's text, or the error naming it.
fn read_text(path: &std::path::Path) -> Result<String, DataError> {
    std::fs::read_to_string(path).map_err(|e| DataError {
        file: path.display().to_string(),
        line: 0,
        column: "(file)".into(),
        message: format!("cannot read: {e}"),
    })
}

/// How a file's joint readings are read: radians only, or radians (`j1..jN`) or encoder
/// counts (`c1..cN`, converted with the arm's counts per revolution).
#[derive(Clone, Copy)]
enum Joints<'a> {
    Radians(usize),
    RadiansOrCounts(&'a quatarm_ref::Arm),
}

impl Joints<'_> {
    fn dof(&self) -> usize {
        match self {
            Joints::Radians(n) => *n,
            Joints::RadiansOrCounts(arm) => arm.dof(),
        }
    }
}

/// Several data files read as one dataset for `arm`, as a recording comes (`simulate` writes
/// one kind per file; a session may be saved in parts). Each file is read and checked on its
/// own first (its errors name it); joint readings may be radians (`j1..jN`) or encoder counts
/// (`c1..cN`), file by file. Each file's groups stay apart: a group number a file shares with
/// an earlier file is renumbered (every group of that file moved by the same multiple of
/// 1000), and the returned notes say so. `point` rows come from one file only: they share one
/// instrument frame, which two recordings need not.
pub fn read_all(paths: &[std::path::PathBuf], arm: &quatarm_ref::Arm) -> Result<Files, DataError> {
    let mut notes = Vec::new();
    let mut parts = Vec::new();
    let mut merged: Option<Dataset> = None;
    let mut point_file: Option<String> = None;
    let mut seen: Vec<(std::path::PathBuf, String)> = Vec::new();
    for path in paths {
        let file = path.display().to_string();
        refuse_twice(&mut seen, path, &file)?;
        let mut part = parse_with(&read_text(path)?, &file, Joints::RadiansOrCounts(arm))?;
        if paths.len() > 1 {
            let name: std::sync::Arc<str> = file.as_str().into();
            for r in &mut part.rows {
                r.file = Some(name.clone());
            }
        }
        parts.push(part.clone());
        one_point_file(&mut point_file, &part, &file)?;
        match merged.as_mut() {
            None => merged = Some(part),
            Some(all) => merge_file(all, part, &file, &mut notes),
        }
    }
    let data = merged.ok_or_else(|| DataError {
        file: "(no file)".into(),
        line: 0,
        column: "(file)".into(),
        message: "no data file given".into(),
    })?;
    check_groups(&data)?;
    Ok(Files { data, notes, parts })
}

/// Refuses a file given twice (by any path to it): the same recording twice would count every
/// row twice and look twice as certain. `seen` holds the files read so far.
fn refuse_twice(
    seen: &mut Vec<(std::path::PathBuf, String)>,
    path: &std::path::Path,
    file: &str,
) -> Result<(), DataError> {
    let Ok(real) = std::fs::canonicalize(path) else {
        return Ok(());
    };
    if let Some((_, earlier)) = seen.iter().find(|(p, _)| *p == real) {
        return Err(DataError {
            file: file.to_string(),
            line: 0,
            column: "(file)".into(),
            message: format!("given twice (also as {earlier}): each file is read once"),
        });
    }
    seen.push((real, file.to_string()));
    Ok(())
}

/// Refuses `point` rows in a second file: point rows share one instrument frame, which two
/// recordings need not. `point_file` is the file that brought the first ones.
fn one_point_file(
    point_file: &mut Option<String>,
    part: &Dataset,
    file: &str,
) -> Result<(), DataError> {
    let Some(first) = part.rows.iter().find(|r| r.kind == Kind::Point) else {
        return Ok(());
    };
    match point_file {
        Some(earlier) => Err(DataError {
            file: file.to_string(),
            line: first.line,
            column: "kind".into(),
            message: format!(
                "`point` rows here and in {earlier}: point rows share one \
                 instrument frame; put them in one file"
            ),
        }),
        None => {
            *point_file = Some(file.to_string());
            Ok(())
        }
    }
}

/// Appends a later file's rows to the files read so far, its groups renumbered where they
/// clash and a note where the files disagree on temperature.
fn merge_file(all: &mut Dataset, mut part: Dataset, file: &str, notes: &mut Vec<String>) {
    notes.extend(renumber_clashing_groups(all, &mut part, file));
    if all.has_temperature != part.has_temperature {
        notes.push(format!(
            "{file}: {} a temp_c column, an earlier file {}: rows without one are taken \
             at 20 °C",
            if part.has_temperature {
                "has"
            } else {
                "has no"
            },
            if part.has_temperature {
                "has none"
            } else {
                "has one"
            },
        ));
    }
    all.rows.append(&mut part.rows);
    all.warnings.append(&mut part.warnings);
    all.has_temperature |= part.has_temperature;
    all.source = format!("{} + {file}", all.source);
}

/// Moves every group of `part` by the same multiple of 1000 past the groups of `all` when
/// any of its numbers is taken, so that two files' groups never merge; the note says so.
fn renumber_clashing_groups(all: &Dataset, part: &mut Dataset, file: &str) -> Option<String> {
    let taken = groups(all);
    let mine = groups(part);
    let clash: Vec<String> = mine.intersection(&taken).map(i64::to_string).collect();
    if clash.is_empty() {
        return None;
    }
    let (lo, hi) = (mine.first().copied(), taken.last().copied());
    let shift = match (lo, hi) {
        (Some(lo), Some(hi)) => ((hi - lo) / 1000 + 1) * 1000,
        _ => 1000,
    };
    for r in &mut part.rows {
        if r.kind != Kind::Point {
            r.group += shift;
        }
    }
    Some(format!(
        "{file}: group{} {} also in an earlier file: every group of this file is \
         renumbered + {shift} (group g is read as g + {shift}), so that no two files' \
         groups merge",
        if clash.len() == 1 { "" } else { "s" },
        if clash.len() > 6 {
            format!("{}, … ({} in all) are", clash[..6].join(", "), clash.len())
        } else {
            format!(
                "{} {}",
                clash.join(", "),
                if clash.len() == 1 { "is" } else { "are" }
            )
        }
    ))
}

/// Several files read as one ([`read_all`]).
pub struct Files {
    /// Every file's rows, groups renumbered where two files share a number.
    pub data: Dataset,
    /// What was renumbered, for the user.
    pub notes: Vec<String>,
    /// Each file as read, its own groups and lines, for checks whose messages name a row's
    /// file and line.
    pub parts: Vec<Dataset>,
}

/// The group numbers of a dataset's `spat`, `length` and `sphere` rows.
fn groups(data: &Dataset) -> std::collections::BTreeSet<i64> {
    data.rows
        .iter()
        .filter(|r| r.kind != Kind::Point)
        .map(|r| r.group)
        .collect()
}

/// Column positions found in the header.
struct Columns {
    kind: usize,
    group: usize,
    joints: Vec<usize>,
    /// The arm whose encoders convert them where the joint columns are counts (`c1..cN`).
    counts_of: Option<quatarm_ref::Arm>,
    xyz: Option<[usize; 3]>,
    end: Option<usize>,
    length: Option<usize>,
    diameter: Option<usize>,
    articulation: Option<usize>,
    temp: Option<usize>,
    probe: Option<usize>,
}

/// Reads data from text; `file` names it in errors.
pub fn parse(text: &str, file: &str, dof: usize) -> Result<Dataset, DataError> {
    parse_with(text, file, Joints::Radians(dof))
}

/// Reads one file's text, its joint readings as `joints_as` allows: the header, the columns
/// it names, the rows, and the groups' rules, each a step below; the first error stops it.
fn parse_with(text: &str, file: &str, joints_as: Joints) -> Result<Dataset, DataError> {
    let dof = joints_as.dof();
    // A spreadsheet's UTF-8 byte order mark would glue itself to the first column's name.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let err = |line: usize, column: &str, message: String| DataError {
        file: file.to_string(),
        line,
        column: column.to_string(),
        message,
    };
    let cleaned = without_comments(text);
    let lines = Lines::new(&cleaned);
    let mut reader = csv::ReaderBuilder::new()
        .delimiter(separator(&cleaned))
        .trim(csv::Trim::All)
        .flexible(true)
        .from_reader(cleaned.as_bytes());
    let hline = first_content_line(text).unwrap_or(1);
    let names = header_names(&mut reader, &cleaned, &lines, hline, &err)?;
    let seen = unique_columns(&names).map_err(|h| err(hline, &h.column, h.message))?;
    let warnings = unknown_columns(&names, joints_as, file, hline);
    let columns = columns_of(&names, &seen, joints_as, hline, &err)?;
    let rows = read_rows(&mut reader, &lines, &names, &columns, hline, &err)?;
    let data = Dataset {
        rows,
        dof,
        has_temperature: columns.temp.is_some(),
        warnings,
        source: file.to_string(),
    };
    check_groups(&data)?;
    Ok(data)
}

/// The header's column names, refused when the file is empty, has no header, or its header
/// is one column (the wrong separator: the message names the one it read with). `hline` is
/// the header's line, for the messages.
fn header_names(
    reader: &mut csv::Reader<&[u8]>,
    cleaned: &str,
    lines: &Lines,
    hline: usize,
    err: &dyn Fn(usize, &str, String) -> DataError,
) -> Result<Vec<String>, DataError> {
    let header_line = reader
        .headers()
        .map_err(|e| err(lines.of_error(&e), "(header)", format!("not CSV: {e}")))?
        .clone();
    if cleaned.trim().is_empty() {
        return Err(err(
            0,
            "(file)",
            "empty: no header and no rows (was it saved?)".into(),
        ));
    }
    if header_line.is_empty() || header_line.iter().all(str::is_empty) {
        return Err(err(1, "(header)", "no header row".into()));
    }
    let names: Vec<String> = header_line.iter().map(|s| s.to_string()).collect();
    if let [one] = names.as_slice() {
        return Err(err(
            hline,
            "(header)",
            format!(
                "the header is one column, `{one}`: columns are separated by `,`, `;` or tab \
                 (read with {})",
                separator_name(separator(cleaned))
            ),
        ));
    }
    Ok(names)
}

/// A warning for each column the reader does not know (read on, ignored): a typo in an
/// optional column's name would otherwise drop it silently.
fn unknown_columns(names: &[String], joints_as: Joints, file: &str, hline: usize) -> Vec<String> {
    let counts = matches!(joints_as, Joints::RadiansOrCounts(_));
    names
        .iter()
        .filter(|n| {
            let known = matches!(
                n.as_str(),
                "kind"
                    | "group"
                    | "x"
                    | "y"
                    | "z"
                    | "end"
                    | "length_mm"
                    | "diameter_mm"
                    | "articulation"
                    | "session"
                    | "temp_c"
                    | "probe"
            );
            !known && joint_index(n, "j").is_none() && !(counts && joint_index(n, "c").is_some())
        })
        .map(|n| {
            format!(
                "{file}: line {hline}: unknown column `{}` ignored",
                shown(n)
            )
        })
        .collect()
}

/// The positions of the columns a row is read from: the joints (radians or, where
/// `joints_as` allows, counts; one of the two), `kind` and `group` required, the rest where
/// present.
fn columns_of(
    names: &[String],
    seen: &BTreeMap<&str, usize>,
    joints_as: Joints,
    hline: usize,
    err: &dyn Fn(usize, &str, String) -> DataError,
) -> Result<Columns, DataError> {
    let dof = joints_as.dof();
    // Another joint count than the arm's: whose arm it is, so that another arm's calibration
    // given with the data is named as such.
    let joints_err = |h: HeaderProblem| match joints_as {
        Joints::RadiansOrCounts(arm) if h.message.contains(" joints") => err(
            hline,
            &h.column,
            format!("{}; {}", h.message, whose_arm(arm)),
        ),
        _ => err(hline, &h.column, h.message),
    };
    let need = |name: &str| -> Result<usize, DataError> {
        seen.get(name)
            .copied()
            .ok_or_else(|| err(hline, name, "missing column".into()))
    };
    let counts = match joints_as {
        Joints::RadiansOrCounts(_) => joint_columns(names, "c", dof).map_err(joints_err)?,
        Joints::Radians(_) => None,
    };
    let (joints, counts_of) = match (
        joint_columns(names, "j", dof).map_err(joints_err)?,
        counts,
        joints_as,
    ) {
        (Some(j), None, _) => (j, None),
        (None, Some(c), Joints::RadiansOrCounts(arm)) => (c, Some(arm.clone())),
        (Some(_), Some(_), _) => {
            return Err(err(
                hline,
                "c1",
                format!(
                    "both j1..j{dof} (radians) and c1..c{dof} (counts): give one reading per joint"
                ),
            ))
        }
        _ => {
            return Err(joints_err(HeaderProblem {
                column: "j1".into(),
                message: missing_joint(1, 0, dof),
            }))
        }
    };
    Ok(Columns {
        kind: need("kind")?,
        group: need("group")?,
        joints,
        counts_of,
        xyz: match (seen.get("x"), seen.get("y"), seen.get("z")) {
            (Some(&x), Some(&y), Some(&z)) => Some([x, y, z]),
            _ => None,
        },
        end: seen.get("end").copied(),
        length: seen.get("length_mm").copied(),
        diameter: seen.get("diameter_mm").copied(),
        articulation: seen.get("articulation").copied(),
        temp: seen.get("temp_c").copied(),
        probe: seen.get("probe").copied(),
    })
}

/// Every data row, blank rows skipped; a row with another field count than the header, or
/// none at all, is refused.
fn read_rows(
    reader: &mut csv::Reader<&[u8]>,
    lines: &Lines,
    names: &[String],
    columns: &Columns,
    hline: usize,
    err: &dyn Fn(usize, &str, String) -> DataError,
) -> Result<Vec<Row>, DataError> {
    let mut rows = Vec::new();
    for record in reader.records() {
        let record =
            record.map_err(|e| err(lines.of_error(&e), "(row)", format!("not CSV: {e}")))?;
        let line = lines.of_record(&record);
        if record.iter().all(str::is_empty) {
            continue;
        }
        if record.len() != names.len() {
            return Err(err(
                line,
                "(row)",
                format!("{} fields, the header has {}", record.len(), names.len()),
            ));
        }
        rows.push(parse_row(&record, line, names, columns, err)?);
    }
    if rows.is_empty() {
        return Err(err(hline, "(file)", "no data rows".into()));
    }
    Ok(rows)
}

/// A header that breaks the column rules, with the column at fault.
#[derive(Clone, Debug, PartialEq)]
pub struct HeaderProblem {
    /// The column (as the message shows it).
    pub column: String,
    /// What is wrong.
    pub message: String,
}

/// Every column name once: positions by name, or the first name that appears twice. Every CSV
/// reader of armcal applies this rule (measured data, `eval`'s readings): a second `j1` is
/// refused, never read in place of the first.
pub fn unique_columns(names: &[String]) -> Result<BTreeMap<&str, usize>, HeaderProblem> {
    let mut seen = BTreeMap::new();
    for (i, n) in names.iter().enumerate() {
        if seen.insert(n.as_str(), i).is_some() {
            return Err(HeaderProblem {
                column: shown(n),
                message: "column appears twice".into(),
            });
        }
    }
    Ok(seen)
}

/// Positions of the joint columns `{prefix}1..{prefix}N` for an arm of `dof` joints, `None`
/// when the header has no column of that prefix. Refused: a gap (`j1, j3`), a joint the arm
/// does not have (`j7` for six joints), too few. The same rule for measured data (`j`) and
/// for `eval` (`j` radians, `c` counts).
pub fn joint_columns(
    names: &[String],
    prefix: &str,
    dof: usize,
) -> Result<Option<Vec<usize>>, HeaderProblem> {
    let cols: BTreeMap<usize, usize> = names
        .iter()
        .enumerate()
        .filter_map(|(i, n)| joint_index(n, prefix).map(|k| (k, i)))
        .collect();
    let Some(&file_dof) = cols.keys().next_back() else {
        return Ok(None);
    };
    let problem = |k: usize, message: String| HeaderProblem {
        column: format!("{prefix}{k}"),
        message,
    };
    for k in 1..=file_dof.max(dof) {
        if !cols.contains_key(&k) {
            return Err(problem(k, missing_joint(k, file_dof, dof)));
        }
    }
    if file_dof != dof {
        return Err(problem(
            file_dof,
            format!("the data has {file_dof} joint columns, the arm has {dof} joints"),
        ));
    }
    Ok(Some((1..=dof).map(|k| cols[&k]).collect()))
}

/// Where the csv reader's records are, as a person sees them in an editor.
///
/// The csv reader gives a record the position where it stopped after the record before: the
/// blank lines it skipped in between, and the comment lines, are not counted (a bad value
/// after a mid-file comment was reported one line early). So comments are emptied first
/// ([`without_comments`], which keeps every newline), and a record's line is counted here
/// from the first byte after the newlines that follow that position.
pub struct Lines<'a> {
    text: &'a [u8],
    starts: Vec<u64>,
}

impl<'a> Lines<'a> {
    /// The lines of `text` (comments already emptied).
    pub fn new(text: &'a str) -> Lines<'a> {
        let starts = std::iter::once(0)
            .chain(
                text.bytes()
                    .enumerate()
                    .filter(|(_, b)| *b == b'\n')
                    .map(|(i, _)| i as u64 + 1),
            )
            .collect();
        Lines {
            text: text.as_bytes(),
            starts,
        }
    }

    /// The 1-based line of what starts at byte `at`, blank lines skipped.
    pub fn of(&self, at: u64) -> usize {
        let mut i = at as usize;
        while i < self.text.len() && matches!(self.text[i], b'\n' | b'\r') {
            i += 1;
        }
        self.starts.partition_point(|&s| s <= i as u64).max(1)
    }

    /// The line of a record.
    pub fn of_record(&self, r: &csv::StringRecord) -> usize {
        r.position().map_or(0, |p| self.of(p.byte()))
    }

    /// The line of a csv error (0 where it has none).
    pub fn of_error(&self, e: &csv::Error) -> usize {
        e.position().map_or(0, |p| self.of(p.byte()))
    }
}

/// The text with every comment line (`#` first, after any blanks) emptied, its newline kept,
/// so that the csv reader skips it as a blank line and line numbers stay those of the file.
pub fn without_comments(text: &str) -> std::borrow::Cow<'_, str> {
    let is_comment = |l: &str| l.trim_start().starts_with('#');
    if !text.lines().any(is_comment) {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len());
    for piece in text.split_inclusive('\n') {
        if is_comment(piece) {
            if piece.ends_with('\n') {
                out.push('\n');
            }
        } else {
            out.push_str(piece);
        }
    }
    std::borrow::Cow::Owned(out)
}

/// What a numeric cell must hold.
#[derive(Clone, Debug)]
pub enum Bound {
    /// |x| ≤ the value; the text names the quantity and its unit, e.g. "mm (a coordinate)".
    Abs(f64, &'static str),
    /// x within the range; the text names the quantity and its unit.
    Within(std::ops::RangeInclusive<f64>, &'static str),
}

impl Bound {
    /// A joint reading (rad).
    pub fn joint() -> Bound {
        Bound::Abs(
            crate::limits::JOINT_RAD,
            "rad (a joint reading: a thousand turns; encoder counts? name the columns c1..cN)",
        )
    }

    /// A coordinate or a distance of the world (mm).
    pub fn coordinate() -> Bound {
        Bound::Abs(
            crate::limits::COORDINATE_MM,
            "mm (any coordinate or length)",
        )
    }

    /// The arm's temperature (°C).
    pub fn temperature() -> Bound {
        Bound::Within(
            crate::limits::temp_range_c(),
            "°C (the temperatures the firmware accepts)",
        )
    }
}

/// Why a numeric cell was refused (the caller adds the file, line and column).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CellError {
    /// Parsed, but infinite or NaN.
    #[error("`{0}` is not a finite number")]
    NotFinite(String),
    /// Nothing in the cell.
    #[error("empty: a number is needed")]
    Empty,
    /// Not a number at all.
    #[error("`{0}` is not a number")]
    NotNumber(String),
    /// A number written with a decimal comma (`0,5`): a spreadsheet of a comma-decimal locale.
    #[error("`{0}` is not a number: a decimal comma? numbers are written with a point (`{1}`)")]
    DecimalComma(String, String),
    /// Not an encoder count.
    #[error("`{0}` is not a count (an integer ≥ 0)")]
    NotCount(String),
    /// A count of a turn or more.
    #[error("count {count} is not below the joint's {per_rev} counts per revolution")]
    CountBeyond {
        /// The count read.
        count: u32,
        /// The joint's counts per revolution.
        per_rev: u32,
    },
    /// Beyond a symmetric bound.
    #[error("{value} is beyond ±{limit} {what}")]
    Beyond {
        /// The value as written.
        value: String,
        /// The bound.
        limit: f64,
        /// The bound's unit and what it bounds.
        what: &'static str,
    },
    /// Outside a range.
    #[error("{value} is outside {lo}..{hi} {what}")]
    Outside {
        /// The value as written.
        value: String,
        /// The range's lower end.
        lo: f64,
        /// The range's upper end.
        hi: f64,
        /// The range's unit and what it bounds.
        what: &'static str,
    },
}

/// A numeric cell: a finite number within `bound`, or why not.
pub fn number_cell(s: &str, bound: &Bound) -> Result<f64, CellError> {
    let x = match s.parse::<f64>() {
        Ok(x) if x.is_finite() => x,
        Ok(_) => return Err(CellError::NotFinite(shown(s))),
        Err(_) if s.is_empty() => return Err(CellError::Empty),
        Err(_) => {
            let pointed = s.replacen(',', ".", 1);
            return Err(
                if s.matches(',').count() == 1 && pointed.parse::<f64>().is_ok() {
                    CellError::DecimalComma(shown(s), shown(&pointed))
                } else {
                    CellError::NotNumber(shown(s))
                },
            );
        }
    };
    match bound {
        Bound::Abs(limit, what) if x.abs() > *limit => Err(CellError::Beyond {
            value: number(x),
            limit: *limit,
            what,
        }),
        Bound::Within(range, what) if !range.contains(&x) => Err(CellError::Outside {
            value: number(x),
            lo: *range.start(),
            hi: *range.end(),
            what,
        }),
        _ => Ok(x),
    }
}

/// An encoder count cell: an integer from 0 to below `per_rev`, the joint's counts per
/// revolution. The one reading of count columns (`c1..cN`), for measured data and `eval`;
/// the counts become radians through `quatarm_ref::Arm::counts_to_rad`.
pub fn count_cell(s: &str, per_rev: u32) -> Result<u32, CellError> {
    let count: u32 = s.parse().map_err(|_| CellError::NotCount(shown(s)))?;
    if count >= per_rev {
        return Err(CellError::CountBeyond { count, per_rev });
    }
    Ok(count)
}

fn missing_joint(k: usize, file_dof: usize, dof: usize) -> String {
    if k > file_dof {
        format!("missing column: the arm has {dof} joints, the data has {file_dof} joint columns")
    } else {
        "missing column: joint columns must run j1, j2, … without a gap".into()
    }
}

/// The arm the data are read for, as a message names it: its name, serial and joint count,
/// and the question a joint count other than the data's raises.
pub fn whose_arm(arm: &quatarm_ref::Arm) -> String {
    format!(
        "the calibration's arm is {} ({}{} joints): is it the arm these data were measured with?",
        arm.name
            .as_deref()
            .map_or_else(|| "unnamed".to_string(), |n| format!("`{}`", shown(n))),
        arm.serial
            .as_deref()
            .map_or_else(String::new, |s| format!("serial {}, ", shown(s))),
        arm.dof()
    )
}

/// The line of the first non-comment, non-blank line (the header).
fn first_content_line(text: &str) -> Option<usize> {
    text.lines()
        .position(|l| {
            let t = l.trim();
            !t.is_empty() && !t.starts_with('#')
        })
        .map(|i| i + 1)
}

fn joint_index(name: &str, prefix: &str) -> Option<usize> {
    let digits = name.strip_prefix(prefix)?;
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    digits.parse().ok().filter(|k| *k >= 1)
}

/// One record's cells, with what turns a bad one into an error naming its line and column.
struct Cells<'a> {
    record: &'a csv::StringRecord,
    line: usize,
    names: &'a [String],
    err: &'a dyn Fn(usize, &str, String) -> DataError,
}

impl Cells<'_> {
    fn text(&self, i: usize) -> &str {
        self.record.get(i).unwrap_or("")
    }

    fn fail(&self, column: &str, message: String) -> DataError {
        (self.err)(self.line, column, message)
    }

    fn number(&self, i: usize, bound: Bound) -> Result<f64, DataError> {
        number_cell(self.text(i), &bound)
            .map_err(|m| self.fail(&shown(&self.names[i]), m.to_string()))
    }

    fn positive(&self, i: usize, column: &str, what: &str) -> Result<f64, DataError> {
        let x = self.number(i, Bound::coordinate())?;
        if x <= 0.0 {
            return Err(self.fail(column, format!("{x} is not a positive {what}")));
        }
        Ok(x)
    }

    fn integer(&self, i: usize, column: &str) -> Result<i64, DataError> {
        let s = self.text(i);
        if s.is_empty() {
            return Err(self.fail(column, "empty: every row needs a whole number here".into()));
        }
        match s.parse::<i64>() {
            Ok(g) => Ok(g),
            Err(_) => match s.parse::<f64>() {
                Ok(f) if f.is_finite() && f.fract() == 0.0 && f.abs() < 9e15 => Ok(f as i64),
                _ => Err(self.fail(column, format!("`{}` is not an integer", shown(s)))),
            },
        }
    }

    /// The column a kind's rows need, or the error saying so.
    fn needed(&self, col: Option<usize>, column: &str, kind: &str) -> Result<usize, DataError> {
        col.ok_or_else(|| self.fail(column, format!("missing column: `{kind}` rows need it")))
    }
}

fn parse_row(
    record: &csv::StringRecord,
    line: usize,
    names: &[String],
    c: &Columns,
    err: &dyn Fn(usize, &str, String) -> DataError,
) -> Result<Row, DataError> {
    let cells = Cells {
        record,
        line,
        names,
        err,
    };
    let kind = match cells.text(c.kind) {
        "point" => Kind::Point,
        "spat" => Kind::Spat,
        "length" => Kind::Length,
        "sphere" => Kind::Sphere,
        other => {
            return Err(cells.fail(
                "kind",
                format!(
                    "unknown kind `{}`: point, spat, length or sphere",
                    shown(other)
                ),
            ))
        }
    };
    let group = cells.integer(c.group, "group")?;
    let theta = match &c.counts_of {
        None => c
            .joints
            .iter()
            .map(|&i| cells.number(i, Bound::joint()))
            .collect::<Result<Vec<_>, _>>()?,
        Some(arm) => {
            let mut counts = Vec::with_capacity(c.joints.len());
            for (&i, j) in c.joints.iter().zip(&arm.joints) {
                counts.push(
                    count_cell(cells.text(i), j.encoder_counts)
                        .map_err(|m| cells.fail(&shown(&cells.names[i]), m.to_string()))?,
                );
            }
            // The one conversion of counts, `eval`'s too.
            arm.counts_to_rad(&counts)
        }
    };
    let xyz = match kind {
        Kind::Point => Some(point_cells(&cells, c)?),
        _ => None,
    };
    let (end, length_mm) = match kind {
        Kind::Length => {
            let (end, l) = bar_cells(&cells, c)?;
            (Some(end), Some(l))
        }
        _ => (None, None),
    };
    let sphere = match kind {
        Kind::Sphere => Some(sphere_cells(&cells, c)?),
        _ => None,
    };
    let temp_c = match c.temp {
        Some(i) if !cells.text(i).is_empty() => cells.number(i, Bound::temperature())?,
        _ => quatarm_ref::forward::REFERENCE_TEMP_C,
    };
    let probe = match c.probe {
        Some(i) if !cells.text(i).is_empty() => Some(probe_cell(&cells, i)?),
        _ => None,
    };
    Ok(Row {
        kind,
        group,
        theta,
        xyz,
        end,
        length_mm,
        sphere,
        temp_c,
        probe,
        line,
        file: None,
    })
}

/// A `probe` cell: a probe id, an integer from 0 to 255 (the calibration file's `id`).
fn probe_cell(cells: &Cells, i: usize) -> Result<u8, DataError> {
    let id = cells.integer(i, "probe")?;
    u8::try_from(id).map_err(|_| cells.fail("probe", format!("{id} is not a probe id: 0 to 255")))
}

/// A `point` row's reference coordinates.
fn point_cells(cells: &Cells, c: &Columns) -> Result<[f64; 3], DataError> {
    let Some(cols) = c.xyz else {
        let missing = ["x", "y", "z"]
            .into_iter()
            .find(|n| !cells.names.iter().any(|m| m == n))
            .unwrap_or("x");
        return Err(cells.fail(
            missing,
            "missing column: `point` rows need x, y and z".into(),
        ));
    };
    Ok([
        cells.number(cols[0], Bound::coordinate())?,
        cells.number(cols[1], Bound::coordinate())?,
        cells.number(cols[2], Bound::coordinate())?,
    ])
}

/// A `length` row's ball and bar length.
fn bar_cells(cells: &Cells, c: &Columns) -> Result<(End, f64), DataError> {
    let ce = cells.needed(c.end, "end", "length")?;
    let cl = cells.needed(c.length, "length_mm", "length")?;
    let end = match cells.text(ce) {
        "a" | "A" => End::A,
        "b" | "B" => End::B,
        other => return Err(cells.fail("end", format!("`{}` is not an end: a or b", shown(other)))),
    };
    Ok((end, cells.positive(cl, "length_mm", "length")?))
}

/// A `sphere` row's test sphere.
fn sphere_cells(cells: &Cells, c: &Columns) -> Result<Touch, DataError> {
    let cd = cells.needed(c.diameter, "diameter_mm", "sphere")?;
    let diameter_mm = cells.positive(cd, "diameter_mm", "diameter")?;
    let articulation = match c.articulation {
        Some(i) if !cells.text(i).is_empty() => Some(cells.integer(i, "articulation")?),
        _ => None,
    };
    Ok(Touch {
        diameter_mm,
        articulation,
    })
}

/// Checks what ties rows together: spat groups of two rows or more, length groups with both
/// ends and one length, sphere groups of one diameter, probe and articulation, no group
/// number shared by rows of two kinds. The first broken rule is the error, on its row.
fn check_groups(data: &Dataset) -> Result<(), DataError> {
    one_kind_per_group(data)?;
    let layout = data.layout();
    for g in &layout.spat {
        spat_group(data, g)?;
    }
    for g in &layout.sphere {
        sphere_group(data, g)?;
    }
    for g in &layout.length {
        length_group(data, g)?;
    }
    Ok(())
}

/// The error of a group rule on `row`, named by its file and line.
fn group_error(data: &Dataset, row: &Row, column: &str, message: String) -> DataError {
    DataError {
        file: data.file_of(row).to_string(),
        line: row.line,
        column: column.to_string(),
        message,
    }
}

/// A group number is one kind of rows (`point` rows have no group): a `spat` and a `length`
/// group of the same number would be read as one.
fn one_kind_per_group(data: &Dataset) -> Result<(), DataError> {
    let mut kinds: BTreeMap<i64, (Kind, usize)> = BTreeMap::new();
    for (i, r) in data.rows.iter().enumerate() {
        if r.kind == Kind::Point {
            continue;
        }
        match kinds.get(&r.group) {
            Some(&(k, first)) if k != r.kind => {
                return Err(group_error(
                    data,
                    r,
                    "group",
                    format!(
                        "group {} mixes {} rows (first on line {}) and {} rows",
                        r.group,
                        k.name(),
                        data.rows[first].line,
                        r.kind.name()
                    ),
                ))
            }
            Some(_) => {}
            None => {
                kinds.insert(r.group, (r.kind, i));
            }
        }
    }
    Ok(())
}

/// A fixed point needs two poses or more: one row says nothing about the arm.
fn spat_group(data: &Dataset, g: &SpatGroup) -> Result<(), DataError> {
    if g.rows.len() < 2 {
        let r = &data.rows[g.rows[0]];
        return Err(group_error(
            data,
            r,
            "group",
            format!(
                "spat group {} has one row: a fixed point needs two poses or more",
                g.group
            ),
        ));
    }
    Ok(())
}

/// A sphere group is one test: one diameter, one stylus ball, articulated throughout or not
/// at all; each row is compared with the group's first.
fn sphere_group(data: &Dataset, g: &SphereGroup) -> Result<(), DataError> {
    let first = &data.rows[g.rows[0]];
    let articulated = first.sphere.and_then(|t| t.articulation).is_some();
    for &i in &g.rows {
        let r = &data.rows[i];
        let t = r.sphere.unwrap_or(Touch {
            diameter_mm: f64::NAN,
            articulation: None,
        });
        if t.diameter_mm != g.diameter_mm {
            return Err(group_error(
                data,
                r,
                "diameter_mm",
                format!(
                    "sphere group {} has two diameters: {} (line {}) and {}",
                    g.group, g.diameter_mm, first.line, t.diameter_mm
                ),
            ));
        }
        if r.probe != first.probe {
            return Err(group_error(
                data,
                r,
                "probe",
                format!(
                    "sphere group {} is touched with two probes ({} on line {}, {} here): \
                     a sphere's radius takes one stylus ball",
                    g.group,
                    probe_name(first.probe),
                    first.line,
                    probe_name(r.probe)
                ),
            ));
        }
        if t.articulation.is_some() != articulated {
            return Err(group_error(
                data,
                r,
                "articulation",
                format!(
                    "sphere group {} has rows with and without an articulation (line {} and this one): a group is one test",
                    g.group, first.line
                ),
            ));
        }
    }
    Ok(())
}

/// A length group has rows at both ends of the bar and one length on every row.
fn length_group(data: &Dataset, g: &LengthGroup) -> Result<(), DataError> {
    let all: Vec<usize> = g.a.iter().chain(&g.b).copied().collect();
    let first = &data.rows[all[0]];
    if g.a.is_empty() || g.b.is_empty() {
        let missing = if g.a.is_empty() { "a" } else { "b" };
        return Err(group_error(
            data,
            first,
            "end",
            format!("length group {} has no rows for end {missing}", g.group),
        ));
    }
    for &i in &all {
        let r = &data.rows[i];
        if r.length_mm != Some(g.length_mm) {
            return Err(group_error(
                data,
                r,
                "length_mm",
                format!(
                    "length group {} has two lengths: {} (line {}) and {}",
                    g.group,
                    g.length_mm,
                    first.line,
                    r.length_mm.unwrap_or(f64::NAN)
                ),
            ));
        }
    }
    Ok(())
}

/// A row's probe as messages name it.
pub fn probe_name(probe: Option<u8>) -> String {
    probe.map_or("the first probe".into(), |id| format!("probe {id}"))
}

impl Dataset {
    /// A dataset made in memory (the simulator, tests), checked like a file.
    pub fn from_rows(
        rows: Vec<Row>,
        dof: usize,
        has_temperature: bool,
        source: &str,
    ) -> Result<Dataset, DataError> {
        let data = Dataset {
            rows,
            dof,
            has_temperature,
            warnings: Vec::new(),
            source: source.to_string(),
        };
        for r in &data.rows {
            if r.theta.len() != dof {
                return Err(DataError {
                    file: data.source.clone(),
                    line: r.line,
                    column: "(row)".into(),
                    message: format!("{} readings for {dof} joints", r.theta.len()),
                });
            }
        }
        check_groups(&data)?;
        Ok(data)
    }

    /// The file `row` was read from: its own where the dataset merges several files, else
    /// the dataset's source.
    pub fn file_of<'a>(&'a self, row: &'a Row) -> &'a str {
        row.file.as_deref().unwrap_or(&self.source)
    }

    /// Where the first row of group `group` is, as messages name it: `b.csv, line 7`
    /// (`None` where no row has that group number).
    pub fn group_place(&self, group: i64) -> Option<String> {
        let r = self
            .rows
            .iter()
            .find(|r| r.kind != Kind::Point && r.group == group)?;
        Some(format!("{}, line {}", self.file_of(r), r.line))
    }

    /// Sorts the rows by what ties them together; groups come in group-number order.
    pub fn layout(&self) -> Layout {
        let mut layout = Layout::default();
        let mut spat: BTreeMap<i64, Vec<usize>> = BTreeMap::new();
        let mut length: BTreeMap<i64, (Vec<usize>, Vec<usize>, f64)> = BTreeMap::new();
        let mut sphere: BTreeMap<i64, Vec<usize>> = BTreeMap::new();
        for (i, r) in self.rows.iter().enumerate() {
            match r.kind {
                Kind::Point => layout.points.push(i),
                Kind::Spat => spat.entry(r.group).or_default().push(i),
                Kind::Sphere => sphere.entry(r.group).or_default().push(i),
                Kind::Length => {
                    let e = length.entry(r.group).or_insert_with(|| {
                        (Vec::new(), Vec::new(), r.length_mm.unwrap_or(f64::NAN))
                    });
                    match r.end {
                        Some(End::B) => e.1.push(i),
                        _ => e.0.push(i),
                    }
                }
            }
        }
        layout.spat = spat
            .into_iter()
            .map(|(group, rows)| SpatGroup { group, rows })
            .collect();
        layout.length = length
            .into_iter()
            .map(|(group, (a, b, length_mm))| LengthGroup {
                group,
                a,
                b,
                length_mm,
            })
            .collect();
        layout.sphere = sphere
            .into_iter()
            .map(|(group, rows)| SphereGroup {
                group,
                diameter_mm: self.rows[rows[0]]
                    .sphere
                    .map_or(f64::NAN, |t| t.diameter_mm),
                rows,
            })
            .collect();
        layout
    }

    /// The rows whose indices are given, as a dataset of their own (folds, sessions).
    pub fn subset(&self, indices: &[usize]) -> Dataset {
        Dataset {
            rows: indices.iter().map(|&i| self.rows[i].clone()).collect(),
            dof: self.dof,
            has_temperature: self.has_temperature,
            warnings: Vec::new(),
            source: self.source.clone(),
        }
    }

    /// Count of rows of a kind.
    pub fn count(&self, kind: Kind) -> usize {
        self.rows.iter().filter(|r| r.kind == kind).count()
    }

    /// The file text: a header, then one line per row. Numbers use Rust's shortest round-trip
    /// form, so reading the text back gives the same f64 values.
    pub fn to_csv(&self, comments: &[&str]) -> String {
        let mut s = String::new();
        for c in comments {
            let _ = writeln!(s, "# {c}");
        }
        let has_point = self.rows.iter().any(|r| r.kind == Kind::Point);
        let has_length = self.rows.iter().any(|r| r.kind == Kind::Length);
        let has_sphere = self.rows.iter().any(|r| r.kind == Kind::Sphere);
        let mut header = vec!["kind".to_string(), "group".to_string()];
        header.extend((1..=self.dof).map(|k| format!("j{k}")));
        if has_point {
            header.extend(["x", "y", "z"].map(String::from));
        }
        if has_length {
            header.extend(["end", "length_mm"].map(String::from));
        }
        if has_sphere {
            header.extend(["diameter_mm", "articulation"].map(String::from));
        }
        if self.has_temperature {
            header.push("temp_c".into());
        }
        let has_probe = self.rows.iter().any(|r| r.probe.is_some());
        if has_probe {
            header.push("probe".into());
        }
        let _ = writeln!(s, "{}", header.join(","));
        for r in &self.rows {
            let mut f: Vec<String> = vec![r.kind.name().into(), r.group.to_string()];
            f.extend(r.theta.iter().map(|t| t.to_string()));
            if has_point {
                match r.xyz {
                    Some(p) => f.extend(p.iter().map(|v| v.to_string())),
                    None => f.extend(["", "", ""].map(String::from)),
                }
            }
            if has_length {
                f.push(match r.end {
                    Some(End::A) => "a".into(),
                    Some(End::B) => "b".into(),
                    None => String::new(),
                });
                f.push(r.length_mm.map_or(String::new(), |l| l.to_string()));
            }
            if has_sphere {
                f.push(
                    r.sphere
                        .map_or(String::new(), |t| t.diameter_mm.to_string()),
                );
                f.push(
                    r.sphere
                        .and_then(|t| t.articulation)
                        .map_or(String::new(), |a| a.to_string()),
                );
            }
            if self.has_temperature {
                f.push(r.temp_c.to_string());
            }
            if has_probe {
                f.push(r.probe.map_or(String::new(), |id| id.to_string()));
            }
            let _ = writeln!(s, "{}", f.join(","));
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str =
        "# a comment\nkind,group,j1,j2,j3,j4,j5,j6,x,y,z,end,length_mm,temp_c,extra\n\
point,1,0.1,0.2,0.3,0.4,0.5,0.6,1,2,3,,,21,q\n\
spat,2,0.1,0.2,0.3,0.4,0.5,0.6,,,,,,,\n\
spat,2,0.2,0.2,0.3,0.4,0.5,0.6,,,,,,,\n\
length,3,0.1,0.2,0.3,0.4,0.5,0.6,,,,a,500,,\n\
length,3,0.1,0.3,0.3,0.4,0.5,0.6,,,,b,500,,\n";

    #[test]
    fn reads_every_kind() {
        let d = parse(GOOD, "t.csv", 6).unwrap();
        assert_eq!(d.rows.len(), 5);
        assert_eq!(d.rows[0].xyz, Some([1.0, 2.0, 3.0]));
        assert_eq!(d.rows[0].temp_c, 21.0);
        assert_eq!(d.rows[0].line, 3);
        assert_eq!(d.rows[1].temp_c, 20.0);
        assert_eq!(d.rows[4].end, Some(End::B));
        assert_eq!(d.warnings.len(), 1, "{:?}", d.warnings);
        let l = d.layout();
        assert_eq!(l.points, vec![0]);
        assert_eq!(l.spat[0].rows, vec![1, 2]);
        assert_eq!(
            (l.length[0].a.clone(), l.length[0].b.clone()),
            (vec![3], vec![4])
        );
    }

    #[test]
    fn round_trips_through_text() {
        let d = parse(GOOD, "t.csv", 6).unwrap();
        let text = d.to_csv(&["again"]);
        let e = parse(&text, "u.csv", 6).unwrap();
        let strip = |d: &Dataset| -> Vec<Row> {
            d.rows
                .iter()
                .map(|r| Row {
                    line: 0,
                    ..r.clone()
                })
                .collect()
        };
        assert_eq!(strip(&d), strip(&e));
    }

    fn bad(text: &str, dof: usize) -> DataError {
        let e = parse(text, "bad.csv", dof).unwrap_err();
        assert_eq!(e.file, "bad.csv");
        e
    }

    #[test]
    fn refusals_name_line_and_column() {
        let h = "kind,group,j1,j2,j3,j4,j5,j6,x,y,z\n";
        let e = bad(&format!("{h}point,1,0,0,0,0,0,0,1,2\n"), 6);
        assert_eq!((e.line, e.column.as_str()), (2, "(row)"));
        let e = bad(&format!("{h}point,1,0,0,0,zero,0,0,1,2,3\n"), 6);
        assert_eq!((e.line, e.column.as_str()), (2, "j4"));
        let e = bad(
            &format!("{h}point,1,0,0,0,0,0,0,1,2,3\npoint,1,0,0,0,0,0,0,1,,3\n"),
            6,
        );
        assert_eq!((e.line, e.column.as_str()), (3, "y"));
        let e = bad(&format!("{h}probe,1,0,0,0,0,0,0,1,2,3\n"), 6);
        assert_eq!((e.line, e.column.as_str()), (2, "kind"));
        let e = bad(&format!("{h}point,1,0,0,0,0,0,0,1,2,3\n"), 7);
        assert_eq!((e.line, e.column.as_str()), (1, "j7"));
        let e = bad("kind,group,j1,j2,j3,j4,j5,j6,j7\nspat,1,0,0,0,0,0,0,0\n", 6);
        assert_eq!((e.line, e.column.as_str()), (1, "j7"));
        let e = bad("kind,j1,j2,j3,j4,j5,j6\nspat,0,0,0,0,0,0\n", 6);
        assert_eq!((e.line, e.column.as_str()), (1, "group"));
        let e = bad("kind,group,j1,j2,j3,j4,j5,j6\npoint,1,0,0,0,0,0,0\n", 6);
        assert_eq!((e.line, e.column.as_str()), (2, "x"));
        let e = bad(
            "kind,group,j1,j2,j3,j4,j5,j6\nspat,1,0,0,0,0,0,0\nspat,2,0,0,0,0,0,0\nspat,2,1,0,0,0,0,0\n",
            6,
        );
        assert_eq!((e.line, e.column.as_str()), (2, "group"));
        assert!(e.message.contains("one row"), "{e}");
        let e = bad(
            "kind,group,j1,j2,j3,j4,j5,j6,end,length_mm\nlength,1,0,0,0,0,0,0,a,50\nlength,1,1,0,0,0,0,0,a,50\n",
            6,
        );
        assert_eq!(e.column, "end");
        let e = bad(
            "kind,group,j1,j2,j3,j4,j5,j6,end,length_mm\nlength,1,0,0,0,0,0,0,a,50\nlength,1,1,0,0,0,0,0,b,51\n",
            6,
        );
        assert_eq!((e.line, e.column.as_str()), (3, "length_mm"));
        let e = bad("kind,group,j1,j2,j3,j4,j5,j6\n", 6);
        assert!(e.message.contains("no data rows"), "{e}");
    }

    #[test]
    fn reads_the_mukca_files() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/mukca");
        let d = read(&dir.join("mukca-panda-panda_2.csv"), 7).unwrap();
        assert_eq!(d.rows.len(), 559);
        assert_eq!(d.layout().length.len(), 9);
        let k = read(&dir.join("mukca-gen3lite-dinova_1.csv"), 6).unwrap();
        assert_eq!(k.layout().length.len(), 4);
    }
}
