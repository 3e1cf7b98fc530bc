//! Measured data (`spec/measured-data.md`): the CSV an arm's owner records, read into rows.
//!
//! Reading is all-or-nothing: the first problem found is returned with the file, the line and
//! the column at fault, and no rows are returned with it, so a tool can never fit half a file.
//! Rows keep their line number so that later stages (calibration, diagnosis) can point back
//! into the file too.

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
}

impl Kind {
    /// The file's spelling.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Point => "point",
            Kind::Spat => "spat",
            Kind::Length => "length",
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
    /// Arm temperature at the reading (°C); 20 where the file records none.
    pub temp_c: f64,
    /// 1-based line of the row in its file (0 for rows made in memory).
    pub line: usize,
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
#[error("{file}: line {line}, column {column}: {message}")]
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

/// Reads a data file for an arm with `dof` joints.
pub fn read(path: &std::path::Path, dof: usize) -> Result<Dataset, DataError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| DataError {
        file: file.clone(),
        line: 0,
        column: "(file)".into(),
        message: format!("cannot read: {e}"),
    })?;
    parse(&text, &file, dof)
}

/// Column positions found in the header.
struct Columns {
    kind: usize,
    group: usize,
    joints: Vec<usize>,
    xyz: Option<[usize; 3]>,
    end: Option<usize>,
    length: Option<usize>,
    temp: Option<usize>,
}

/// Reads data from text; `file` names it in errors.
pub fn parse(text: &str, file: &str, dof: usize) -> Result<Dataset, DataError> {
    let err = |line: usize, column: &str, message: String| DataError {
        file: file.to_string(),
        line,
        column: column.to_string(),
        message,
    };
    let mut reader = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .flexible(true)
        .from_reader(text.as_bytes());
    let header_line = reader
        .headers()
        .map_err(|e| err(csv_line(&e), "(header)", format!("not CSV: {e}")))?
        .clone();
    if header_line.is_empty() || header_line.iter().all(str::is_empty) {
        return Err(err(1, "(header)", "no header row".into()));
    }
    let hline = reader.position().line().max(1) as usize;
    let hline = first_content_line(text).unwrap_or(hline);
    let names: Vec<String> = header_line.iter().map(|s| s.to_string()).collect();
    let mut warnings = Vec::new();
    let mut seen: BTreeMap<&str, usize> = BTreeMap::new();
    let mut joint_cols: BTreeMap<usize, usize> = BTreeMap::new();
    for (i, n) in names.iter().enumerate() {
        if seen.insert(n.as_str(), i).is_some() {
            return Err(err(hline, n, "column appears twice".into()));
        }
        if let Some(k) = joint_index(n) {
            joint_cols.insert(k, i);
        } else if !matches!(
            n.as_str(),
            "kind" | "group" | "x" | "y" | "z" | "end" | "length_mm" | "temp_c"
        ) {
            warnings.push(format!(
                "{file}: line {hline}: unknown column `{n}` ignored"
            ));
        }
    }
    let need = |name: &str| -> Result<usize, DataError> {
        seen.get(name)
            .copied()
            .ok_or_else(|| err(hline, name, "missing column".into()))
    };
    let file_dof = joint_cols.keys().next_back().copied().unwrap_or(0);
    for k in 1..=file_dof.max(dof) {
        if !joint_cols.contains_key(&k) {
            return Err(err(
                hline,
                &format!("j{k}"),
                missing_joint(k, file_dof, dof),
            ));
        }
    }
    if file_dof != dof {
        return Err(err(
            hline,
            &format!("j{file_dof}"),
            format!("the data has {file_dof} joint columns, the arm has {dof} joints"),
        ));
    }
    let columns = Columns {
        kind: need("kind")?,
        group: need("group")?,
        joints: (1..=dof).map(|k| joint_cols[&k]).collect(),
        xyz: match (seen.get("x"), seen.get("y"), seen.get("z")) {
            (Some(&x), Some(&y), Some(&z)) => Some([x, y, z]),
            _ => None,
        },
        end: seen.get("end").copied(),
        length: seen.get("length_mm").copied(),
        temp: seen.get("temp_c").copied(),
    };

    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| err(csv_line(&e), "(row)", format!("not CSV: {e}")))?;
        let line = record.position().map_or(0, |p| p.line() as usize);
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
        rows.push(parse_row(&record, line, &names, &columns, &err)?);
    }
    if rows.is_empty() {
        return Err(err(hline, "(file)", "no data rows".into()));
    }
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

fn missing_joint(k: usize, file_dof: usize, dof: usize) -> String {
    if k > file_dof {
        format!("missing column: the arm has {dof} joints, the data has {file_dof} joint columns")
    } else {
        "missing column: joint columns must run j1, j2, … without a gap".into()
    }
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

fn csv_line(e: &csv::Error) -> usize {
    e.position().map_or(0, |p| p.line() as usize)
}

fn joint_index(name: &str) -> Option<usize> {
    let digits = name.strip_prefix('j')?;
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    digits.parse().ok().filter(|k| *k >= 1)
}

fn parse_row(
    record: &csv::StringRecord,
    line: usize,
    names: &[String],
    c: &Columns,
    err: &dyn Fn(usize, &str, String) -> DataError,
) -> Result<Row, DataError> {
    let cell = |i: usize| record.get(i).unwrap_or("");
    let number = |i: usize| -> Result<f64, DataError> {
        let s = cell(i);
        match s.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            Ok(_) => Err(err(
                line,
                &names[i],
                format!("`{s}` is not a finite number"),
            )),
            Err(_) if s.is_empty() => Err(err(line, &names[i], "empty: a number is needed".into())),
            Err(_) => Err(err(line, &names[i], format!("`{s}` is not a number"))),
        }
    };
    let kind = match cell(c.kind) {
        "point" => Kind::Point,
        "spat" => Kind::Spat,
        "length" => Kind::Length,
        other => {
            return Err(err(
                line,
                "kind",
                format!("unknown kind `{other}`: point, spat or length"),
            ))
        }
    };
    let group = {
        let s = cell(c.group);
        match s.parse::<i64>() {
            Ok(g) => g,
            Err(_) => match s.parse::<f64>() {
                Ok(f) if f.is_finite() && f.fract() == 0.0 && f.abs() < 9e15 => f as i64,
                _ => return Err(err(line, "group", format!("`{s}` is not an integer"))),
            },
        }
    };
    let theta = c
        .joints
        .iter()
        .map(|&i| number(i))
        .collect::<Result<Vec<_>, _>>()?;
    let xyz = if kind == Kind::Point {
        let Some(cols) = c.xyz else {
            let missing = ["x", "y", "z"]
                .into_iter()
                .find(|n| !names.iter().any(|m| m == n))
                .unwrap_or("x");
            return Err(err(
                line,
                missing,
                "missing column: `point` rows need x, y and z".into(),
            ));
        };
        Some([number(cols[0])?, number(cols[1])?, number(cols[2])?])
    } else {
        None
    };
    let (end, length_mm) = if kind == Kind::Length {
        let Some(ce) = c.end else {
            return Err(err(
                line,
                "end",
                "missing column: `length` rows need it".into(),
            ));
        };
        let Some(cl) = c.length else {
            return Err(err(
                line,
                "length_mm",
                "missing column: `length` rows need it".into(),
            ));
        };
        let end = match cell(ce) {
            "a" | "A" => End::A,
            "b" | "B" => End::B,
            other => return Err(err(line, "end", format!("`{other}` is not an end: a or b"))),
        };
        let l = number(cl)?;
        if l <= 0.0 {
            return Err(err(
                line,
                "length_mm",
                format!("{l} is not a positive length"),
            ));
        }
        (Some(end), Some(l))
    } else {
        (None, None)
    };
    let temp_c = match c.temp {
        Some(i) if !cell(i).is_empty() => number(i)?,
        _ => quatarm_ref::forward::REFERENCE_TEMP_C,
    };
    Ok(Row {
        kind,
        group,
        theta,
        xyz,
        end,
        length_mm,
        temp_c,
        line,
    })
}

/// Checks what ties rows together: spat groups of two rows or more, length groups with both
/// ends and one length, no group number shared by spat and length rows.
fn check_groups(data: &Dataset) -> Result<(), DataError> {
    let err = |row: &Row, column: &str, message: String| DataError {
        file: data.source.clone(),
        line: row.line,
        column: column.to_string(),
        message,
    };
    let mut kinds: BTreeMap<i64, (Kind, usize)> = BTreeMap::new();
    for (i, r) in data.rows.iter().enumerate() {
        if r.kind == Kind::Point {
            continue;
        }
        match kinds.get(&r.group) {
            Some(&(k, first)) if k != r.kind => {
                return Err(err(
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
    let layout = data.layout();
    for g in &layout.spat {
        if g.rows.len() < 2 {
            let r = &data.rows[g.rows[0]];
            return Err(err(
                r,
                "group",
                format!(
                    "spat group {} has one row: a fixed point needs two poses or more",
                    g.group
                ),
            ));
        }
    }
    for g in &layout.length {
        let all: Vec<usize> = g.a.iter().chain(&g.b).copied().collect();
        let first = &data.rows[all[0]];
        if g.a.is_empty() || g.b.is_empty() {
            let missing = if g.a.is_empty() { "a" } else { "b" };
            return Err(err(
                first,
                "end",
                format!("length group {} has no rows for end {missing}", g.group),
            ));
        }
        for &i in &all {
            let r = &data.rows[i];
            if r.length_mm != Some(g.length_mm) {
                return Err(err(
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
    }
    Ok(())
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

    /// Sorts the rows by what ties them together; groups come in group-number order.
    pub fn layout(&self) -> Layout {
        let mut layout = Layout::default();
        let mut spat: BTreeMap<i64, Vec<usize>> = BTreeMap::new();
        let mut length: BTreeMap<i64, (Vec<usize>, Vec<usize>, f64)> = BTreeMap::new();
        for (i, r) in self.rows.iter().enumerate() {
            match r.kind {
                Kind::Point => layout.points.push(i),
                Kind::Spat => spat.entry(r.group).or_default().push(i),
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
        let mut header = vec!["kind".to_string(), "group".to_string()];
        header.extend((1..=self.dof).map(|k| format!("j{k}")));
        if has_point {
            header.extend(["x", "y", "z"].map(String::from));
        }
        if has_length {
            header.extend(["end", "length_mm"].map(String::from));
        }
        if self.has_temperature {
            header.push("temp_c".into());
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
            if self.has_temperature {
                f.push(r.temp_c.to_string());
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
