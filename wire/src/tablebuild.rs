//! Building the firmware's binary calibration table from an arm (host side, f64).
//!
//! Everything constant is precomputed here in f64 so that the target does the least work per
//! point: the misalignment quaternion with the zero offset folded in,
//! M'_i = R(e1, δα) · R(e2, δβ) · R(u, Δθ) (the spec's M_i followed by the constant part of the
//! joint rotation, which commutes with the rest of R(u, ·)), the same as a matrix, the link and
//! probe vectors with their errors, and each probe's unit direction. The arm's first probe is
//! the table's (its id in the header), its other probes the block after every other
//! (`quatarm::table::probes`). Layout: `quatarm::table`.

use crate::budget::{budget_data, parameter_data};
use quatarm::table::parameters::MAX_PARAMETERS;
use quatarm::table::pose;
use quatarm::table::wobble::{WobbleData, WobbleTerm, MAX_TERMS as WOBBLE_TERMS};
use quatarm::table::{
    quat_to_matrix, Harmonic, JointData, ProbeData, TableData, FLAG_GEOMETRIC, MAX_HARMONICS,
    MAX_HARMONIC_ORDER, MAX_TABLE_LEN, SERIAL_LEN,
};
use quatarm_ref::arm::Wobble;
use quatarm_ref::forward::{axis_vector, rotation};
use quatarm_ref::release::Release;
use quatarm_ref::uncertainty::Uncertainty;
use quatarm_ref::{Arm, Axis, Joint, Probe};

/// Why an arm cannot become a table.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{path}: {message}")]
pub struct BuildError {
    /// Key path in calibration-file terms.
    pub path: String,
    /// Why.
    pub message: String,
}

fn err(path: impl Into<String>, message: impl Into<String>) -> BuildError {
    BuildError {
        path: path.into(),
        message: message.into(),
    }
}

/// Hamilton product.
pub fn qmul(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

/// R(axis, angle) as a quaternion.
pub fn axis_quat(axis: Axis, angle: f64) -> [f64; 4] {
    let mut q = [(angle / 2.0).cos(), 0.0, 0.0, 0.0];
    q[1 + axis.index()] = (angle / 2.0).sin();
    q
}

fn axis_code(a: Axis) -> u8 {
    a.index() as u8
}

/// The table contents for an arm: its serial, each joint's record and wobble block, its
/// probes, and the flags saying what the table holds. The first value the table cannot
/// carry is the error, named by its key path.
pub fn table_data(arm: &Arm) -> Result<TableData, BuildError> {
    let n = arm.dof();
    if !(6..=7).contains(&n) {
        return Err(err("joint", format!("{n} joints; the table takes 6 or 7")));
    }
    let mut d = TableData {
        joint_count: n as u8,
        ..TableData::default()
    };
    if let Some(s) = &arm.serial {
        d.serial = serial_data(s)?;
    }
    let mut geometric = false;
    for (i, j) in arm.joints.iter().enumerate() {
        let path = format!("joint[{}]", i + 1);
        d.wobble[i] = wobble_data(j, &path)?;
        d.joints[i] = joint_data(j, &path)?;
        geometric |= has_geometric_error(j);
    }
    geometric |= probes_into(arm, &mut d)?;
    d.flags = d.content_flags() | if geometric { FLAG_GEOMETRIC } else { 0 };
    Ok(d)
}

/// The serial padded with NULs to the table's field; refused when longer, or holding a NUL
/// itself (which would cut it short).
fn serial_data(s: &str) -> Result<[u8; SERIAL_LEN], BuildError> {
    if let Some(at) = s.bytes().position(|b| b == 0) {
        return Err(err(
            "serial",
            format!(
                "has a NUL character (byte {}), which the table uses as padding",
                at + 1
            ),
        ));
    }
    if s.len() > SERIAL_LEN {
        return Err(err(
            "serial",
            format!("{} bytes; the table holds at most {SERIAL_LEN}", s.len()),
        ));
    }
    let mut serial = [0u8; SERIAL_LEN];
    serial[..s.len()].copy_from_slice(s.as_bytes());
    Ok(serial)
}

/// A joint's record: its rotation (tilts, then the zero offset about the axis) as a unit
/// quaternion and a matrix, the link with its error, the thermal and gravity terms and the
/// harmonics. `path` (`joint[K]`) names it in errors.
fn joint_data(j: &Joint, path: &str) -> Result<JointData, BuildError> {
    let (e1, e2) = j.axis.perpendicular();
    let q = qmul(
        qmul(axis_quat(e1, j.tilt[0]), axis_quat(e2, j.tilt[1])),
        axis_quat(j.axis, j.zero_offset),
    );
    let norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    let q = q.map(|x| x / norm);
    Ok(JointData {
        axis: axis_code(j.axis),
        counts: j.encoder_counts,
        rotation: q,
        matrix: quat_to_matrix(&q),
        link: j.actual_link(),
        thermal: j.thermal,
        gravity: j.gravity,
        harmonic_count: j.harmonics.len() as u8,
        harmonics: harmonics_data(j, path)?,
    })
}

/// A joint's harmonics in the table's fixed array: at most [`MAX_HARMONICS`], each order in
/// 1..=[`MAX_HARMONIC_ORDER`].
fn harmonics_data(j: &Joint, path: &str) -> Result<[Harmonic; MAX_HARMONICS], BuildError> {
    if j.harmonics.len() > MAX_HARMONICS {
        return Err(err(
            format!("{path}.harmonics"),
            format!(
                "{} terms; the table holds {MAX_HARMONICS} per joint",
                j.harmonics.len()
            ),
        ));
    }
    let mut harmonics = [Harmonic::default(); MAX_HARMONICS];
    for (k, h) in j.harmonics.iter().enumerate() {
        if h.order == 0 || h.order > u32::from(MAX_HARMONIC_ORDER) {
            return Err(err(
                format!("{path}.harmonics[{}].order", k + 1),
                format!("{}; the table takes 1..={MAX_HARMONIC_ORDER}", h.order),
            ));
        }
        harmonics[k] = Harmonic {
            order: h.order as u16,
            sin: h.sin,
            cos: h.cos,
        };
    }
    Ok(harmonics)
}

/// Whether a joint carries a geometric error (the table's `FLAG_GEOMETRIC`): a zero offset, a
/// link error, or a tilt that is not a designed twist of a D–H arm (a multiple of π/2).
fn has_geometric_error(j: &Joint) -> bool {
    j.zero_offset != 0.0
        || j.link_error != [0.0; 3]
        || j.tilt.iter().any(|t| {
            let k = (t / std::f64::consts::FRAC_PI_2).round();
            (t - k * std::f64::consts::FRAC_PI_2).abs() > 1e-12
        })
}

/// The probes into `d`: the first in its record, the others in the block (the reference
/// keeps at most seven others, ids distinct; the table's parser checks both again). Whether
/// any probe carries an error (a geometric one).
fn probes_into(arm: &Arm, d: &mut TableData) -> Result<bool, BuildError> {
    let several = arm.probe_count() > 1;
    if arm.more_probes.len() > d.more_probes.len() {
        return Err(err(
            "probe",
            format!(
                "{} probes; the table holds {}",
                arm.probe_count(),
                d.more_probes.len() + 1
            ),
        ));
    }
    let mut geometric = false;
    for (k, p) in arm.probes().enumerate() {
        let path = if several {
            format!("probe[{}]", k + 1)
        } else {
            "probe".to_owned()
        };
        let data = probe_data(p, &path)?;
        match k {
            0 => d.probe = data,
            _ => d.more_probes[k - 1] = data,
        }
        geometric |= p.error != [0.0; 3];
    }
    d.more_probe_count = arm.more_probes.len() as u8;
    Ok(geometric)
}

/// A probe's record: its vector with its error, the unit direction, thermal expansion, ball
/// diameter and id. `path` names it in errors (`probe`, or `probe[K]` of several).
fn probe_data(p: &Probe, path: &str) -> Result<ProbeData, BuildError> {
    let v = p.actual();
    let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if len <= 0.0 {
        return Err(err(format!("{path}.vector"), "vector + error is zero"));
    }
    Ok(ProbeData {
        id: p.id,
        vector: v,
        direction: v.map(|x| x / len),
        thermal: p.thermal,
        ball_diameter: p.ball_diameter,
    })
}

/// A joint's axis wobble for the table: its non-zero terms, and the two fixed axes the chains
/// turn about (`quatarm::table::wobble`), f1 = R(u, −Δθ) R(e2, −β) e1 and f2 = R(u, −Δθ) e2
/// in the joint's frame (the identity the reference pins:
/// `a_wobble_is_the_fixed_tilt_then_two_turns_about_fixed_axes`).
fn wobble_data(j: &Joint, path: &str) -> Result<WobbleData, BuildError> {
    let terms: Vec<(usize, &Wobble)> = j
        .wobble
        .iter()
        .enumerate()
        .filter(|(_, w)| w.alpha != [0.0; 2] || w.beta != [0.0; 2])
        .collect();
    let mut d = WobbleData::default();
    if terms.is_empty() {
        return Ok(d);
    }
    if terms.len() > WOBBLE_TERMS {
        return Err(err(
            format!("{path}.wobble"),
            format!(
                "{} non-zero terms; the table holds {WOBBLE_TERMS} per joint",
                terms.len()
            ),
        ));
    }
    let mut sum = 0.0;
    for (slot, (k, w)) in d.terms.iter_mut().zip(&terms) {
        if w.order == 0 || w.order > u32::from(MAX_HARMONIC_ORDER) {
            return Err(err(
                format!("{path}.wobble[{}].order", k + 1),
                format!("{}; the table takes 1..={MAX_HARMONIC_ORDER}", w.order),
            ));
        }
        sum += w.alpha.iter().chain(&w.beta).map(|c| c.abs()).sum::<f64>();
        *slot = WobbleTerm {
            order: w.order as u16,
            alpha: w.alpha,
            beta: w.beta,
        };
    }
    // Finite and small, as the chains' second-order turns need; NaN is refused too.
    let small = sum <= quatarm::table::limits::HARMONIC_SUM;
    if !small {
        return Err(err(
            format!("{path}.wobble"),
            format!(
                "sum of |coefficients| {sum:.3e} rad; the table takes at most {:e}",
                quatarm::table::limits::HARMONIC_SUM
            ),
        ));
    }
    let (e1, e2) = j.axis.perpendicular();
    let (u, e1, e2) = (axis_vector(j.axis), axis_vector(e1), axis_vector(e2));
    let back = rotation(&u, -j.zero_offset);
    let f1 = back * rotation(&e2, -j.tilt[1]) * e1;
    let f2 = back * e2;
    d.f1 = [f1.x, f1.y, f1.z];
    d.f2 = [f2.x, f2.y, f2.z];
    d.count = terms.len() as u8;
    Ok(d)
}

/// Σ |components| of the links and the longest probe: the reach the table limits (the
/// firmware's chain checks it with the longest probe too).
fn reach_mm(d: &TableData) -> f64 {
    let l1 = |v: &[f64; 3]| v.iter().map(|x| x.abs()).sum::<f64>();
    let longest = std::iter::once(&d.probe)
        .chain(d.other_probes())
        .map(|p| l1(&p.vector))
        .fold(0.0, f64::max);
    d.joints[..usize::from(d.joint_count)]
        .iter()
        .map(|j| l1(&j.link))
        .sum::<f64>()
        + longest
}

/// The table bytes for an arm, checked by the firmware's own parser before they are returned.
pub fn build(arm: &Arm) -> Result<Vec<u8>, BuildError> {
    build_with(arm, None)
}

/// The table bytes for an arm with its uncertainty budget ([`crate::budget`]: the reading's
/// own terms, and the parameter covariance where the budget lists parameters), checked by
/// the firmware's own parser.
pub fn build_with(arm: &Arm, budget: Option<&Uncertainty>) -> Result<Vec<u8>, BuildError> {
    build_release(arm, budget, &Release::default())
}

/// [`build_with`], the table carrying the calibration's number and date (`[calibration]` of
/// the file, `quatarm_ref::release`): what a hub's anti-rollback compares.
pub fn build_release(
    arm: &Arm,
    budget: Option<&Uncertainty>,
    release: &Release,
) -> Result<Vec<u8>, BuildError> {
    let mut data = table_data(arm)?;
    data.release = quatarm::table::Release {
        number: release.number,
        date: release.date.map_or(0, |d| d.yyyymmdd()),
    };
    let reach = reach_mm(&data);
    // Finite by `table_data`'s checks; written so that NaN would be refused too.
    let fits = reach <= quatarm::table::limits::REACH_MM;
    if !fits {
        return Err(err(
            "joint.link",
            format!(
                "the arm reaches {reach:.1} mm (sum of |components| of the links and the \
                 longest probe); a table holds at most {} mm, since the stream's coordinates \
                 end at 2147.48 mm and heat may stretch the arm by 4 %",
                quatarm::table::limits::REACH_MM
            ),
        ));
    }
    let parameters = match budget {
        Some(u) => parameter_data(u, arm).map_err(|m| err("uncertainty.parameters", m))?,
        None => None,
    };
    let block = parameters.as_ref().map(|b| b.data());
    // Room for a pose part past what a hub holds, so that such a table is refused by name.
    let room = MAX_TABLE_LEN + pose::len(MAX_PARAMETERS, pose::MAX_FACTORS);
    let mut buf = vec![0u8; room];
    let len = data
        .encode_full(budget.map(budget_data).as_ref(), block.as_ref(), &mut buf)
        .map_err(|e| err("(table)", e.to_string()))?;
    if len > MAX_TABLE_LEN {
        let r = block.and_then(|b| b.pose).map_or(0, |p| p.count);
        return Err(err(
            "uncertainty.pose_factor",
            format!(
                "with the pose part's {r} columns the table is {len} bytes; a hub holds at \
                 most {MAX_TABLE_LEN}: write fewer columns"
            ),
        ));
    }
    buf.truncate(len);
    quatarm::Table::parse(&buf).map_err(|e| match e {
        quatarm::TableError::Invalid { joint, field } if joint > 0 => err(
            format!("joint[{joint}]"),
            format!("{field} out of the table's range"),
        ),
        other => err("(table)", other.to_string()),
    })?;
    Ok(buf)
}

#[cfg(test)]
mod release_tests {
    use super::*;

    /// `[calibration]`'s number and date reach the table; a file without it is number 0.
    #[test]
    fn the_number_and_date_reach_the_table() {
        let text = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../data/default-6.toml"
        ))
        .unwrap();
        let with = format!("{text}\n[calibration]\nnumber = 41\ndate = 2026-12-04\n");
        let p = quatarm_ref::calfile::parse(&with).unwrap();
        let t = build_release(&p.arm, None, &p.release).unwrap();
        let r = quatarm::Table::parse(&t).unwrap().release();
        assert_eq!((r.number, r.date), (41, 20261204));
        let p = quatarm_ref::calfile::parse(&text).unwrap();
        let t = build_release(&p.arm, None, &p.release).unwrap();
        let r = quatarm::Table::parse(&t).unwrap().release();
        assert_eq!((r.number, r.date), (0, 0));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use quatarm_ref::arm::Wobble;

    /// A wobble reaches the table with the axes the reference's identity names, only its
    /// non-zero terms, and too large or too many terms are refused with their key.
    #[test]
    fn an_axis_wobble_reaches_the_table_and_bad_ones_are_refused_with_their_key() {
        let mut arm = Arm::default6();
        arm.joints[2].wobble.push(Wobble {
            order: 2,
            alpha: [0.0; 2],
            beta: [0.0; 2],
        });
        let t = build_with(&arm, None).unwrap();
        let t = quatarm::Table::parse(&t).unwrap();
        assert_eq!(
            t.flags() & quatarm::table::FLAG_WOBBLE,
            0,
            "a zero entry is none"
        );
        let j = &mut arm.joints[2];
        (j.tilt, j.zero_offset) = ([2e-3, -3e-3], 0.4);
        j.wobble.push(Wobble {
            order: 3,
            alpha: [1e-5, 0.0],
            beta: [0.0, 3e-5],
        });
        let bytes = build_with(&arm, None).unwrap();
        let w = quatarm::Table::parse(&bytes).unwrap().joint_wobble(2);
        assert_eq!(
            (w.count, w.terms[0].order, w.terms[0].beta),
            (1, 3, [0.0, 3e-5])
        );
        // Joint 3 of default-6 turns about its own z (e1 = x, e2 = y): f2 = R(z, -0.4) y,
        // f1 = R(z, -0.4) R(y, 3e-3) x (R(y, φ) x = (cos φ, 0, -sin φ)).
        let (c, s) = (0.4f64.cos(), 0.4f64.sin());
        let want_f2 = [s, c, 0.0];
        let (cb, sb) = (3e-3f64.cos(), 3e-3f64.sin());
        let want_f1 = [c * cb, -s * cb, -sb];
        for k in 0..3 {
            assert!((w.f2[k] - want_f2[k]).abs() < 1e-15, "{:?}", w.f2);
            assert!((w.f1[k] - want_f1[k]).abs() < 1e-15, "{:?}", w.f1);
        }
        let mut big = arm.clone();
        big.joints[2].wobble[1].alpha = [6e-4, 6e-4];
        let e = build_with(&big, None).unwrap_err().to_string();
        assert!(e.contains("joint[3].wobble: sum of |coefficients|"), "{e}");
        let mut many = arm.clone();
        many.joints[2].wobble = (1..=5)
            .map(|order| Wobble {
                order,
                alpha: [1e-6, 0.0],
                beta: [0.0; 2],
            })
            .collect();
        let e = build_with(&many, None).unwrap_err().to_string();
        assert!(e.contains("joint[3].wobble: 5 non-zero terms"), "{e}");
        many.joints[2].wobble.truncate(4);
        many.joints[2].wobble[3].order = 65;
        let e = build_with(&many, None).unwrap_err().to_string();
        assert!(e.contains("joint[3].wobble[4].order: 65"), "{e}");
    }
}

#[cfg(test)]
mod probe_tests {
    use super::*;
    use quatarm::table::{FLAG_PROBES, FLAG_THERMAL};

    fn repo(path: &str) -> std::path::PathBuf {
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("..")
            .join(path)
    }

    /// A format-4 table as format 3: without the release fields before the CRC, version 3,
    /// its length and CRC rewritten.
    fn as_format_3(t: &[u8]) -> Vec<u8> {
        use quatarm::table::{CRC, OLD_VERSION, RELEASE_LEN};
        let n = t.len() - RELEASE_LEN;
        let mut out = t[..n - 4].to_vec();
        out[4..6].copy_from_slice(&OLD_VERSION.to_le_bytes());
        out[40..44].copy_from_slice(&(n as u32).to_le_bytes());
        let crc = CRC.checksum(&out);
        out.extend_from_slice(&crc.to_le_bytes());
        out
    }

    fn read(path: &str) -> quatarm_ref::calfile::Parsed {
        quatarm_ref::calfile::read(&repo(path)).unwrap()
    }

    /// Tables of one probe are byte for byte what the builder wrote before there were
    /// several: the table fuzz target's seeds, written by it then (`cargo xtask
    /// fuzz-seeds`), with and without a budget, 6 and 7 joints.
    #[test]
    fn single_probe_tables_are_unchanged() {
        let cases = [
            ("data/default-6-full.toml", false, "seed-default-6-full.bin"),
            (
                "data/default-6-full.toml",
                true,
                "seed-default-6-full-budget.bin",
            ),
            ("data/default-6.toml", false, "seed-default-6.bin"),
            (
                "data/mukca/mukca-panda-panda_3-repo-calibrated.toml",
                false,
                "seed-panda_3.bin",
            ),
        ];
        for (file, budget, seed) in cases {
            let f = read(file);
            let built = build_with(&f.arm, f.uncertainty.as_ref().filter(|_| budget)).unwrap();
            let before = std::fs::read(repo("fuzz/corpus/table_parse").join(seed)).unwrap();
            // Seeds written before format 4 are format 3: the format-4 table without its
            // release fields (number and date, 0 here) must be them byte for byte.
            let built = if before.get(4) == Some(&3) {
                as_format_3(&built)
            } else {
                built
            };
            assert!(built == before, "{file}: the table changed");
        }
    }

    /// Three probes: the first's id in the header, the others in the block in file order,
    /// each as the reference has it; the reach taken with the longest.
    #[test]
    fn every_probe_reaches_the_table() {
        let arm = read("data/default-6-probes.toml").arm;
        let bytes = build(&arm).unwrap();
        let t = quatarm::Table::parse(&bytes).unwrap();
        assert_ne!(t.flags() & FLAG_PROBES, 0);
        assert_ne!(t.flags() & FLAG_THERMAL, 0);
        assert_eq!(t.probe_count(), 3);
        assert_eq!(bytes[44], 1);
        for (k, p) in arm.probes().enumerate() {
            let d = t.probe_at(k).unwrap();
            let v = p.actual();
            assert_eq!(
                (d.id, d.vector, d.thermal),
                (p.id, v, p.thermal),
                "probe {k}"
            );
            assert_eq!(d.ball_diameter, p.ball_diameter);
            let len = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            assert_eq!(d.direction, v.map(|x| x / len));
        }
        // A longer probe than the arm can hold: refused by its length, naming the reach.
        let mut long = arm.clone();
        long.more_probes[1].vector = [0.0, 0.0, 700.0];
        let e = build(&long).unwrap_err().to_string();
        assert!(e.contains("longest probe"), "{e}");
        // A zero vector names its probe.
        let mut zero = arm.clone();
        zero.more_probes[0].vector = [0.0; 3];
        zero.more_probes[0].error = [0.0; 3];
        assert_eq!(build(&zero).unwrap_err().path, "probe[2].vector");
    }
}
