//! `[calibration]` of a calibration file: which calibration of the arm it is (`number`, the
//! maker's certificate number, monotonic per arm), when it was made (`date`) and until when it
//! is valid (`due`, optional). `docs/spec-reading.md` ("Anti-rollback") gives the reading: the
//! number and the date go into the signed table, where a hub refuses a lower number than its
//! live one's; the due date stays with the host tools, which warn past it (a hub has no
//! calendar). A file without the section is calibration number 0, no date: older files stay
//! readable.

use std::fmt;
use toml::{Table, Value};

use crate::calfile::CalFileError;

/// A calendar date (proleptic Gregorian), as ISO 8601 writes it (`2026-12-04`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Date {
    /// Year, 1900–9999.
    pub year: u16,
    /// Month, 1–12.
    pub month: u8,
    /// Day of the month, 1 to the month's length.
    pub day: u8,
}

impl Date {
    /// The date if it exists (year 1900–9999, a day the month has).
    pub fn new(year: u16, month: u8, day: u8) -> Option<Date> {
        let leap =
            year.is_multiple_of(4) && (!year.is_multiple_of(100) || year.is_multiple_of(400));
        let days = match month {
            1 | 3 | 5 | 7 | 8 | 10 | 12 => 31,
            4 | 6 | 9 | 11 => 30,
            2 if leap => 29,
            2 => 28,
            _ => return None,
        };
        ((1900..=9999).contains(&year) && (1..=days).contains(&day)).then_some(Date {
            year,
            month,
            day,
        })
    }

    /// `YYYY-MM-DD` exactly.
    pub fn parse(s: &str) -> Option<Date> {
        let b = s.as_bytes();
        if b.len() != 10 || b[4] != b'-' || b[7] != b'-' {
            return None;
        }
        let num = |r: std::ops::Range<usize>| -> Option<u16> {
            let t = &s[r];
            t.bytes()
                .all(|c| c.is_ascii_digit())
                .then(|| t.parse().ok())?
        };
        Date::new(num(0..4)?, num(5..7)? as u8, num(8..10)? as u8)
    }

    /// The table's encoding: the decimal number YYYYMMDD.
    pub fn yyyymmdd(&self) -> u32 {
        u32::from(self.year) * 10_000 + u32::from(self.month) * 100 + u32::from(self.day)
    }

    /// From the table's encoding; `None` for 0 (no date) or no date at all.
    pub fn from_yyyymmdd(v: u32) -> Option<Date> {
        let year = u16::try_from(v / 10_000).ok()?;
        Date::new(year, (v / 100 % 100) as u8, (v % 100) as u8)
    }

    /// Today (UTC) from the system clock.
    pub fn today() -> Date {
        let secs = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_secs());
        Date::from_days_since_epoch((secs / 86_400) as i64)
    }

    /// The date `days` after 1970-01-01 (Howard Hinnant's `civil_from_days`).
    pub fn from_days_since_epoch(days: i64) -> Date {
        let z = days + 719_468;
        let era = z.div_euclid(146_097);
        let doe = z.rem_euclid(146_097);
        let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
        let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
        let mp = (5 * doy + 2) / 153;
        let day = (doy - (153 * mp + 2) / 5 + 1) as u8;
        let month = if mp < 10 { mp + 3 } else { mp - 9 } as u8;
        let year = (yoe + era * 400 + i64::from(month <= 2)) as u16;
        Date { year, month, day }
    }
}

impl fmt::Display for Date {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:04}-{:02}-{:02}", self.year, self.month, self.day)
    }
}

/// `[calibration]`: number, date, due date.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Release {
    /// The calibration number (0 where the file has none).
    pub number: u32,
    /// The calibration date.
    pub date: Option<Date>,
    /// The date the calibration is due again (host tools only).
    pub due: Option<Date>,
}

impl Release {
    /// Whether the calibration is past its due date on `today` (never without one).
    pub fn overdue(&self, today: Date) -> bool {
        self.due.is_some_and(|d| today > d)
    }
}

fn err(path: &str, message: impl Into<String>) -> CalFileError {
    CalFileError {
        path: path.into(),
        message: message.into(),
    }
}

fn date(t: &Table, key: &str, path: &str) -> Result<Option<Date>, CalFileError> {
    let text = match t.get(key) {
        None => return Ok(None),
        Some(Value::String(s)) => s.clone(),
        // A TOML local date (`date = 2026-12-04`); a date-time or a time is refused below.
        Some(Value::Datetime(d)) => d.to_string(),
        Some(_) => return Err(err(path, "must be a date, YYYY-MM-DD")),
    };
    Date::parse(&text).map(Some).ok_or_else(|| {
        err(
            path,
            format!("{text:?} is no date YYYY-MM-DD (year 1900–9999)"),
        )
    })
}

/// Reads `[calibration]` (`value`: the section), adding its unknown keys to `unknown`.
pub fn parse(value: Option<&Value>, unknown: &mut Vec<String>) -> Result<Release, CalFileError> {
    let t = match value {
        None => return Ok(Release::default()),
        Some(Value::Table(t)) => t,
        Some(_) => return Err(err("calibration", "must be a table ([calibration])")),
    };
    for k in t.keys() {
        if !matches!(k.as_str(), "number" | "date" | "due") {
            unknown.push(format!("calibration.{k}"));
        }
    }
    let number = match t.get("number") {
        None => 0,
        Some(Value::Integer(n)) => u32::try_from(*n).map_err(|_| {
            err(
                "calibration.number",
                format!("{n}: an integer from 0 to {}", u32::MAX),
            )
        })?,
        Some(_) => return Err(err("calibration.number", "must be an integer")),
    };
    let release = Release {
        number,
        date: date(t, "date", "calibration.date")?,
        due: date(t, "due", "calibration.due")?,
    };
    if let (Some(d), Some(due)) = (release.date, release.due) {
        if due < d {
            return Err(err(
                "calibration.due",
                format!("{due} is before the calibration's date {d}"),
            ));
        }
    }
    Ok(release)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<(Release, Vec<String>), CalFileError> {
        let root: Table = text.parse().unwrap();
        let mut unknown = Vec::new();
        parse(root.get("calibration"), &mut unknown).map(|r| (r, unknown))
    }

    #[test]
    fn the_section_reads_and_bad_values_name_their_key() {
        let (r, u) =
            read("[calibration]\nnumber = 12\ndate = 2026-12-04\ndue = \"2027-12-04\"\nx = 1\n")
                .unwrap();
        assert_eq!(r.number, 12);
        assert_eq!(r.date.unwrap().yyyymmdd(), 20261204);
        assert_eq!(r.due.unwrap().to_string(), "2027-12-04");
        assert_eq!(u, vec!["calibration.x".to_string()]);
        assert!(r.overdue(Date::new(2027, 12, 5).unwrap()));
        assert!(!r.overdue(Date::new(2027, 12, 4).unwrap()));
        assert_eq!(read("name = 'a'\n").unwrap().0, Release::default());
        for (text, key) in [
            ("[calibration]\nnumber = -1\n", "calibration.number"),
            ("[calibration]\nnumber = 4294967296\n", "calibration.number"),
            ("[calibration]\nnumber = 1.5\n", "calibration.number"),
            ("[calibration]\ndate = \"2026-02-30\"\n", "calibration.date"),
            ("[calibration]\ndate = \"4.12.2026\"\n", "calibration.date"),
            (
                "[calibration]\ndate = 2026-12-04T10:00:00\n",
                "calibration.date",
            ),
            (
                "[calibration]\ndate = 2026-12-04\ndue = 2026-12-03\n",
                "calibration.due",
            ),
            ("calibration = 3\n", "calibration"),
        ] {
            assert_eq!(read(text).unwrap_err().path, key, "{text}");
        }
    }

    #[test]
    fn dates_convert() {
        assert_eq!(Date::from_days_since_epoch(0).to_string(), "1970-01-01");
        assert_eq!(
            Date::from_days_since_epoch(20_791).to_string(),
            "2026-12-04"
        );
        assert_eq!(
            Date::from_yyyymmdd(20240229).unwrap().to_string(),
            "2024-02-29"
        );
        assert_eq!(Date::from_yyyymmdd(20230229), None);
        assert_eq!(Date::from_yyyymmdd(0), None);
    }
}
