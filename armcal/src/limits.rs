//! The physical limits of every value armcal reads, in one place.
//!
//! A finite number can still be absurd: a link of 1e300 mm, a bar of 1e308 mm, a reading of
//! 1e300 °C. Such values pass a "finite number" check and turn into inf or NaN somewhere in a
//! fit (where a hang or a wrong "converged" follows), so the readers refuse them with their
//! place instead. Where the firmware has a limit for the same quantity it is taken from
//! `quatarm` (the binary table's validation, the chain's temperature range), so that the host
//! and a board agree; the others are bounds no real arm or instrument comes near.

use quatarm::model::{REFERENCE_TEMP_MC, TEMP_RANGE_MC};
use quatarm::table::budget::limits as budget;
use quatarm::table::limits as table;
use quatarm_ref::calfile::Limits;
use std::f64::consts::TAU;

/// Distances of the world the arm works in (mm): `point` coordinates, a bar's `length_mm`, an
/// instrument frame's translation. 100 m: a laser tracker's range is 80 m.
pub const COORDINATE_MM: f64 = 1.0e5;

/// |joint reading| (rad): a thousand turns. Beyond it a reading is no encoder's, and the
/// firmware's count conversion (and f64's resolution of the angle, 1e-12 rad here) would not
/// hold.
pub(crate) const JOINT_RAD: f64 = 1000.0 * TAU;

/// Temperatures (°C) the firmware's chain accepts (20 °C ± 100 °C): every command takes the
/// same range, so a reading the host evaluates is one a board could too.
pub fn temp_range_c() -> std::ops::RangeInclusive<f64> {
    let lo = f64::from(REFERENCE_TEMP_MC - TEMP_RANGE_MC) / 1000.0;
    let hi = f64::from(REFERENCE_TEMP_MC + TEMP_RANGE_MC) / 1000.0;
    lo..=hi
}

/// Bounds of a calibration file's values. Lengths and thermal expansion are the binary
/// table's (`quatarm::table::limits`); gravity compliance, harmonics and wobble are allowed
/// beyond the table's accuracy limits (the host evaluates such terms exactly, and `diagnose`
/// may name one that the firmware cannot apply), up to physical bounds: 1e-4 rad/mm droops a
/// metre-long lever by 0.1 rad, 0.1 rad of encoder error (or of a bearing's wobble) is 6°.
/// Angles within one turn either way (a Denavit–Hartenberg twist or θ offset is a full angle,
/// never more than a turn). The `[uncertainty]` budget's standard uncertainties are the
/// table's budget limits (`quatarm::table::budget::limits`): a budget the hub would refuse
/// is refused where it is read, with its key, rather than turned into an infinite
/// covariance and a U95 of 0 (issue 27, F2).
pub const CALFILE: Limits = Limits {
    length_mm: table::LENGTH_MM,
    angle_rad: TAU,
    harmonic_rad: 0.1,
    wobble_rad: 0.1,
    gravity: 1.0e-4,
    thermal: table::THERMAL,
    translation_mm: COORDINATE_MM,
    budget_counts: budget::ENCODER_COUNTS,
    budget_mm: budget::LENGTH_MM,
    budget_temperature_c: budget::TEMPERATURE_C,
};

/// At most this many characters of a name from the input are echoed in a message.
pub const SHOWN_CHARS: usize = 40;

/// Text from the input as a message shows it: cut after [`SHOWN_CHARS`] characters (a 50 MB
/// column name is not echoed whole), with the full length said.
pub fn shown(s: &str) -> String {
    match s.char_indices().nth(SHOWN_CHARS) {
        None => s.to_string(),
        Some((at, _)) => format!("{}… ({} bytes)", &s[..at], s.len()),
    }
}

/// A number as a message shows it: plainly when moderate, in exponent form when huge or tiny
/// (1e308 rather than 309 digits).
pub fn number(x: f64) -> String {
    if x == 0.0 || (1e-4..1e7).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_firmware_temperature_range() {
        assert_eq!(temp_range_c(), -80.0..=120.0);
    }

    #[test]
    fn numbers_stay_short() {
        assert_eq!(number(121.0), "121");
        assert_eq!(number(1e308), "1e308");
        assert_eq!(number(-2.5e-9), "-2.5e-9");
    }

    #[test]
    fn long_names_are_cut() {
        assert_eq!(shown("j1"), "j1");
        let long = "x".repeat(50_000_000);
        let s = shown(&long);
        assert!(s.len() < 80, "{s}");
        assert!(s.ends_with("(50000000 bytes)"), "{s}");
    }
}
