//! The text mode: one CSV line per report, for a person at a terminal and for `armcal decode`.
//!
//! Written with integer arithmetic only, no `core::fmt`: on a Cortex-M0 the formatting
//! machinery alone would cost several KiB of the 32 KiB budget. Millimetres get six decimals
//! (the nanometre the stream carries), direction components nine, U95 six. A report without
//! coordinates leaves those seven fields empty, and one without U95 its own, so a
//! spreadsheet never sees a made-up zero. The mounted probe's id comes last (protocol 4), so
//! the columns before it are where they were.

use super::{Report, Status};

/// The header line (with its newline) that matches [`write_csv_line`].
pub const CSV_HEADER: &str = "seq,time_us,status,x_mm,y_mm,z_mm,nx,ny,nz,u95_mm,probe\n";

/// Longest line [`write_csv_line`] writes, newline included.
pub const MAX_CSV_LINE: usize = 144;

/// Writes [`CSV_HEADER`] into `out`; returns its length (0 if `out` is too small).
pub fn write_csv_header(out: &mut [u8]) -> usize {
    let h = CSV_HEADER.as_bytes();
    match out.get_mut(..h.len()) {
        Some(dst) => {
            dst.copy_from_slice(h);
            h.len()
        }
        None => 0,
    }
}

/// Writes one report as a CSV line, newline included, into `out`; returns its length.
/// `out` must hold [`MAX_CSV_LINE`] bytes; a shorter one gets a truncated line (no panic).
pub fn write_csv_line(report: &Report, out: &mut [u8]) -> usize {
    let mut w = Cursor { out, len: 0 };
    w.unsigned(u64::from(report.seq));
    w.byte(b',');
    w.unsigned(report.time_us);
    w.byte(b',');
    w.hex16(report.status);
    if let Some(p) = &report.point {
        for v in p.xyz_nm {
            w.byte(b',');
            w.decimal(i64::from(v), 6);
        }
        for v in p.dir_e9 {
            w.byte(b',');
            w.decimal(i64::from(v), 9);
        }
        w.byte(b',');
        if let Some(u) = p.u95_nm {
            w.decimal(i64::from(u), 6);
        }
    } else {
        for _ in 0..7 {
            w.byte(b',');
        }
    }
    w.byte(b',');
    w.unsigned(u64::from(report.probe));
    w.byte(b'\n');
    w.len
}

/// 10^0 to 10^19: every power of ten a u64 holds.
const POW10: [u64; 20] = {
    let mut p = [1u64; 20];
    let mut i = 1;
    while i < 20 {
        p[i] = p[i - 1] * 10;
        i += 1;
    }
    p
};

struct Cursor<'a> {
    out: &'a mut [u8],
    len: usize,
}

impl Cursor<'_> {
    fn byte(&mut self, b: u8) {
        if let Some(slot) = self.out.get_mut(self.len) {
            *slot = b;
            self.len += 1;
        }
    }

    fn unsigned(&mut self, v: u64) {
        self.digits(v, 0);
    }

    /// `v / 10^decimals` with exactly `decimals` digits after the point.
    fn decimal(&mut self, v: i64, decimals: usize) {
        if v < 0 {
            self.byte(b'-');
        }
        self.digits(v.unsigned_abs(), decimals);
    }

    /// `v` in decimal, a point before its last `point` digits (none for 0), without leading
    /// zeros before the units. Digit by digit, subtracting powers of ten: no division, which
    /// is a call to the runtime's 64-bit division on the Cortex-M0 (its code, 1.3 KB, is more
    /// than the hub's image has room for).
    fn digits(&mut self, mut v: u64, point: usize) {
        let mut started = false;
        for (i, &p) in POW10.iter().enumerate().rev() {
            let mut d = b'0';
            while v >= p {
                v -= p;
                d += 1;
            }
            started |= d != b'0' || i <= point;
            if started {
                self.byte(d);
                if i == point && i > 0 {
                    self.byte(b'.');
                }
            }
        }
    }

    fn hex16(&mut self, s: Status) {
        self.byte(b'0');
        self.byte(b'x');
        for shift in [12, 8, 4, 0] {
            let nib = ((s.0 >> shift) & 0xF) as u8;
            self.byte(if nib < 10 {
                b'0' + nib
            } else {
                b'a' + nib - 10
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stream::Coordinates;

    fn line(r: &Report) -> String {
        let mut out = [0u8; MAX_CSV_LINE];
        let n = write_csv_line(r, &mut out);
        String::from_utf8(out[..n].to_vec()).unwrap()
    }

    #[test]
    fn coordinates_are_exact_decimal_renderings() {
        let r = Report {
            seq: 42,
            time_us: 1_000_001,
            status: Status(0x0001),
            point: Some(Coordinates {
                xyz_nm: [1_234_567_891, -5, 0],
                dir_e9: [-1_000_000_000, 12, 999_999_999],
                u95_nm: Some(12_345),
            }),
            probe: 7,
        };
        assert_eq!(
            line(&r),
            "42,1000001,0x0001,1234.567891,-0.000005,0.000000,-1.000000000,0.000000012,\
             0.999999999,0.012345,7\n"
        );
        let without = Report {
            point: r.point.map(|p| Coordinates { u95_nm: None, ..p }),
            ..r
        };
        assert!(line(&without).ends_with(",0.999999999,,7\n"));
    }

    #[test]
    fn no_point_leaves_the_fields_empty() {
        let r = Report {
            seq: 0,
            time_us: 0,
            status: Status(0x0120),
            point: None,
            probe: 0,
        };
        assert_eq!(line(&r), "0,0,0x0120,,,,,,,,0\n");
    }

    #[test]
    fn the_longest_line_fits_and_matches_the_header() {
        let r = Report {
            seq: u32::MAX,
            time_us: u64::MAX,
            status: Status(0xFFFF),
            point: Some(Coordinates {
                xyz_nm: [i32::MIN; 3],
                dir_e9: [i32::MIN; 3],
                u95_nm: Some(u32::MAX),
            }),
            probe: u8::MAX,
        };
        let l = line(&r);
        assert!(l.len() <= MAX_CSV_LINE);
        assert!(l.ends_with('\n'));
        assert_eq!(l.split(',').count(), CSV_HEADER.split(',').count());
        // Matches Rust's own formatting of the same value.
        assert!(l.contains(&format!(",{:.6},", f64::from(i32::MIN) / 1e6)));
    }

    proptest::proptest! {
        /// Every field renders as Rust's own formatting of the same value: the division-free
        /// digits of any integer the report carries.
        #[test]
        fn fields_render_as_rust_formats_them(seq in proptest::num::u32::ANY,
                                              time in proptest::num::u64::ANY,
                                              x in proptest::num::i32::ANY,
                                              n in proptest::num::i32::ANY,
                                              u in proptest::num::u32::ANY,
                                              probe in proptest::num::u8::ANY) {
            let r = Report {
                seq,
                time_us: time,
                status: Status(1),
                point: Some(Coordinates { xyz_nm: [x, 0, -1], dir_e9: [n, 0, 1], u95_nm: Some(u) }),
                probe,
            };
            let l = line(&r);
            let f: Vec<&str> = l.trim_end().split(',').collect();
            let mm = |v: i32| {
                let s = if v < 0 { "-" } else { "" };
                let a = v.unsigned_abs();
                format!("{s}{}.{:06}", a / 1_000_000, a % 1_000_000)
            };
            let e9 = |v: i32| {
                let s = if v < 0 { "-" } else { "" };
                let a = v.unsigned_abs();
                format!("{s}{}.{:09}", a / 1_000_000_000, a % 1_000_000_000)
            };
            proptest::prop_assert_eq!(f[0], seq.to_string());
            proptest::prop_assert_eq!(f[1], time.to_string());
            proptest::prop_assert_eq!(f[3], mm(x));
            proptest::prop_assert_eq!(f[5], "-0.000001");
            proptest::prop_assert_eq!(f[6], e9(n));
            proptest::prop_assert_eq!(f[9].to_owned(), format!("{}.{:06}", u / 1_000_000, u % 1_000_000));
            proptest::prop_assert_eq!(f[10], probe.to_string());
        }
    }

    #[test]
    fn a_short_buffer_truncates_without_panicking() {
        let r = Report {
            seq: 1,
            time_us: 2,
            status: Status(1),
            point: None,
            probe: 0,
        };
        let mut out = [0u8; 5];
        assert_eq!(write_csv_line(&r, &mut out), 5);
        assert_eq!(&out, b"1,2,0");
    }
}
