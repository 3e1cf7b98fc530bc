//! Recordings of encoder readings: CSV `c1..cN` (counts), optional `temp_c` (20 where absent)
//! and `faults` (bit j for joint j + 1), one row per reading, as `data/recordings/` ships them;
//! turned into the frames a replay sends.

use std::path::Path;

use anyhow::{bail, Context, Result};
use quatarm::stream::{encode, Counts, Mode, Reading, ToDevice, MAX_FRAME};

/// Reads a recording.
pub fn read(path: &Path) -> Result<Vec<Reading>> {
    let mut rdr = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .from_path(path)
        .with_context(|| format!("opening {}", path.display()))?;
    let headers = rdr.headers()?.clone();
    let mut count_cols = Vec::new();
    for j in 1.. {
        match headers.iter().position(|h| h == format!("c{j}")) {
            Some(i) => count_cols.push(i),
            None => break,
        }
    }
    if count_cols.is_empty() || count_cols.len() > 7 {
        bail!("{}: needs columns c1..cN, N ≤ 7", path.display());
    }
    let temp_col = headers.iter().position(|h| h == "temp_c");
    let fault_col = headers.iter().position(|h| h == "faults");
    let mut out = Vec::new();
    for (row, rec) in rdr.records().enumerate() {
        let rec = rec?;
        let line = row + 2;
        let mut counts = [0u32; 7];
        for (j, &c) in count_cols.iter().enumerate() {
            counts[j] = rec[c]
                .trim()
                .parse()
                .with_context(|| format!("{}:{line}: c{}", path.display(), j + 1))?;
        }
        let temp_c: f64 = match temp_col {
            Some(c) => rec[c]
                .trim()
                .parse()
                .with_context(|| format!("{}:{line}: temp_c", path.display()))?,
            None => 20.0,
        };
        let faults: u8 = match fault_col {
            Some(c) => rec[c]
                .trim()
                .parse()
                .with_context(|| format!("{}:{line}: faults", path.display()))?,
            None => 0,
        };
        out.push(Reading {
            seq: row as u32,
            counts: Counts::new(&counts[..count_cols.len()]).expect("at most 7 counts"),
            temp_mc: (temp_c * 1000.0).round() as i32,
            faults,
        });
    }
    Ok(out)
}

/// One frame of a message to a hub.
pub fn frame(msg: &ToDevice) -> Vec<u8> {
    let mut out = [0u8; MAX_FRAME];
    let n = encode(msg, &mut out).expect("every ToDevice fits a frame");
    out[..n].to_vec()
}

/// The bytes of a whole replay: a delimiter, optionally a mode switch, every reading, `End`.
pub fn replay_bytes(readings: &[Reading], mode: Option<Mode>) -> Vec<u8> {
    let mut bytes = vec![0u8];
    if let Some(m) = mode {
        bytes.extend(frame(&ToDevice::SetMode(m)));
    }
    for r in readings {
        bytes.extend(frame(&ToDevice::Reading(*r)));
    }
    bytes.extend(frame(&ToDevice::End));
    bytes
}

/// The CSV `armcal eval` reads for the same readings (counts and temperature).
pub fn eval_csv(readings: &[Reading]) -> String {
    let n = readings.first().map_or(0, |r| r.counts.as_slice().len());
    let mut s = String::new();
    for j in 1..=n {
        s.push_str(&format!("c{j},"));
    }
    s.push_str("temp_c\n");
    for r in readings {
        for c in r.counts.as_slice() {
            s.push_str(&format!("{c},"));
        }
        s.push_str(&format!("{}\n", f64::from(r.temp_mc) / 1000.0));
    }
    s
}
