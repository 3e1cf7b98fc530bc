//! The provenance a report opens with: what was measured, with what, when, and against what,
//! so that the page alone tells an auditor which files gave it (each with its SHA-256).

use crate::data::Dataset;
use quatarm_ref::arm::Arm;
use sha2::{Digest, Sha256};
use std::path::Path;

/// The SHA-256 of a file's bytes, in hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// A file named with its SHA-256 (`path (SHA-256 …)`), or with why it could not be read.
pub(crate) fn file_with_hash(path: &Path) -> String {
    match std::fs::read(path) {
        Ok(b) => format!("{} (SHA-256 {})", path.display(), sha256_hex(&b)),
        Err(e) => format!("{} (not readable for its hash: {e})", path.display()),
    }
}

/// Seconds since 1970 as `YYYY-MM-DD HH:MM UTC`.
pub(crate) fn utc(seconds: i64) -> String {
    let date = quatarm_ref::release::Date::from_days_since_epoch(seconds.div_euclid(86_400));
    let s = seconds.rem_euclid(86_400);
    format!("{date} {:02}:{:02} UTC", s / 3600, s % 3600 / 60)
}

/// Now, or `SOURCE_DATE_EPOCH` where set (a reproducible report, the convention of
/// reproducible builds).
pub fn now() -> String {
    let seconds = std::env::var("SOURCE_DATE_EPOCH")
        .ok()
        .and_then(|s| s.trim().parse::<i64>().ok())
        .unwrap_or_else(|| {
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_secs() as i64)
        });
    utc(seconds)
}

/// The data's temperature range (°C).
pub fn temperatures(data: &Dataset) -> String {
    let (lo, hi) = data
        .rows
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), r| {
            (lo.min(r.temp_c), hi.max(r.temp_c))
        });
    if !lo.is_finite() {
        "no rows".into()
    } else if data.has_temperature {
        format!("{lo:.1} … {hi:.1} °C")
    } else {
        "not recorded (the data has no temperature column: 20 °C assumed)".into()
    }
}

/// What every report's header says.
pub struct Provenance<'a> {
    /// The arm (its serial, its name, its stylus ball).
    pub arm: &'a Arm,
    /// The arm's file as the command read it, with what it is (`calibration file`, `start
    /// arm`), where it read one.
    pub arm_file: Option<(&'a str, &'a Path)>,
    /// The data files.
    pub data_files: Vec<&'a Path>,
    /// The data.
    pub data: &'a Dataset,
    /// The MPE file, where given.
    pub mpe: Option<&'a Path>,
    /// The decision rule, where the report decides.
    pub rule: Option<&'a str>,
}

impl<'a> Provenance<'a> {
    /// The header of a fit's report (`calibrate`, `diagnose`): the fitted `arm`, the start
    /// arm's file where one was read, the data; no MPE file and no decision rule.
    pub fn of_fit(
        arm: &'a Arm,
        start_file: Option<&'a Path>,
        data_files: &'a [std::path::PathBuf],
        data: &'a Dataset,
    ) -> Self {
        Provenance {
            arm,
            arm_file: start_file.map(|p| ("start arm", p)),
            data_files: data_files.iter().map(std::path::PathBuf::as_path).collect(),
            data,
            mpe: None,
            rule: None,
        }
    }
}

impl Provenance<'_> {
    /// The header's rows.
    pub fn facts(&self) -> Vec<(String, String)> {
        let mut f = vec![
            (
                "arm serial".to_string(),
                self.arm.serial.clone().unwrap_or_else(|| {
                    "not given (add `serial = \"…\"` to the calibration file)".into()
                }),
            ),
            (
                "arm model".into(),
                self.arm.name.clone().unwrap_or_else(|| "not named".into()),
            ),
            ("date of the report".into(), now()),
            (
                "software".into(),
                format!("armcal {}", env!("CARGO_PKG_VERSION")),
            ),
        ];
        if let Some((what, path)) = self.arm_file {
            f.push((what.into(), file_with_hash(path)));
        }
        for d in &self.data_files {
            f.push(("data file".into(), file_with_hash(d)));
        }
        f.push(("data".into(), format!("{} rows", self.data.rows.len())));
        f.push(("temperature range".into(), temperatures(self.data)));
        f.push((
            "stylus ball diameter".into(),
            format!("{} mm", self.arm.probe.ball_diameter),
        ));
        if let Some(m) = self.mpe {
            f.push(("MPE file".into(), file_with_hash(m)));
        }
        if let Some(r) = self.rule {
            f.push(("decision rule".into(), r.to_string()));
        }
        f
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_and_hashes_are_right() {
        assert_eq!(utc(0), "1970-01-01 00:00 UTC");
        // 2000-02-29 12:34 UTC, a leap day.
        assert_eq!(utc(951_827_640), "2000-02-29 12:34 UTC");
        assert_eq!(utc(1_798_761_600), "2027-01-01 00:00 UTC");
        // FIPS 180-2's example.
        assert_eq!(
            sha256_hex(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }
}
