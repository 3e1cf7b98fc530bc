//! Every board's `memory.x` (and the root template) gives the calibration table a region of
//! its own that holds the largest table, outside the firmware's flash and RAM, with the two
//! symbols the boards read. A board with a region too small or overlapping its code would
//! only show on hardware; this checks it on every run.

use host_tests::boards::{root, BOARDS};
use quatarm::table::{table_len, MAX_JOINTS};

/// ORIGIN and LENGTH of region `name` in a linker script's MEMORY block.
fn region(script: &str, name: &str) -> (u64, u64) {
    let line = script
        .lines()
        .map(str::trim)
        .find(|l| {
            l.split(|c: char| c.is_whitespace() || c == ':')
                .next()
                .is_some_and(|w| w == name)
        })
        .unwrap_or_else(|| panic!("no {name} region"));
    let value = |key: &str| -> u64 {
        let rest = line[line.find(key).unwrap_or_else(|| panic!("{name}: no {key}"))..]
            .split('=')
            .nth(1)
            .expect("key = value");
        expr(rest.split(',').next().unwrap_or(rest))
    };
    (value("ORIGIN"), value("LENGTH"))
}

/// A sum of terms such as `2048K - 0x100 - 4K`, as the boards' scripts write lengths.
fn expr(e: &str) -> u64 {
    let e = e.replace(' ', "");
    let mut total: i64 = 0;
    let mut sign = 1;
    for (i, part) in e.split_inclusive(['+', '-']).enumerate() {
        let (term, next) = match part.strip_suffix('+') {
            Some(t) => (t, 1),
            None => match part.strip_suffix('-') {
                Some(t) => (t, -1),
                None => (part, 1),
            },
        };
        assert!(i == 0 || !term.is_empty(), "bad expression {e}");
        total += sign * term_value(term) as i64;
        sign = next;
    }
    u64::try_from(total).expect("non-negative")
}

fn term_value(v: &str) -> u64 {
    if let Some(h) = v.strip_prefix("0x") {
        u64::from_str_radix(&h.replace('_', ""), 16).expect("hex")
    } else if let Some(k) = v.strip_suffix('K') {
        k.parse::<u64>().expect("length in K") * 1024
    } else if let Some(m) = v.strip_suffix('M') {
        m.parse::<u64>().expect("length in M") * 1024 * 1024
    } else {
        v.parse().expect("decimal")
    }
}

fn check(path: &std::path::Path) {
    let script = std::fs::read_to_string(path).expect("memory.x");
    let who = path.display();
    let (ct, ct_len) = region(&script, "CALTABLE");
    let (flash, flash_len) = region(&script, "FLASH");
    let (ram, ram_len) = region(&script, "RAM");
    assert!(
        ct_len >= table_len(MAX_JOINTS) as u64,
        "{who}: CALTABLE of {ct_len} bytes cannot hold a {MAX_JOINTS}-joint table"
    );
    let apart = |a: u64, al: u64, b: u64, bl: u64| a + al <= b || b + bl <= a;
    assert!(
        apart(ct, ct_len, flash, flash_len),
        "{who}: CALTABLE overlaps FLASH"
    );
    assert!(
        apart(ct, ct_len, ram, ram_len),
        "{who}: CALTABLE overlaps RAM"
    );
    for sym in ["_cal_table_start = ORIGIN(CALTABLE)", "_cal_table_end"] {
        assert!(script.contains(sym), "{who}: no `{sym}`");
    }
}

#[test]
fn every_board_reserves_a_calibration_region() {
    for b in &BOARDS {
        check(&b.dir().join("memory.x"));
    }
}

#[test]
fn the_template_reserves_a_calibration_region() {
    check(&root().join("memory.x"));
}

#[test]
fn the_parser_reads_what_it_checks() {
    let s = "MEMORY\n{\n  FLASH : ORIGIN = 0x08000000, LENGTH = 384K\n  CALTABLE : ORIGIN = 0x0806_0000, LENGTH = 1M\n}";
    assert_eq!(region(s, "FLASH"), (0x0800_0000, 384 * 1024));
    assert_eq!(region(s, "CALTABLE"), (0x0806_0000, 1024 * 1024));
    assert_eq!(expr("2048K - 0x100 - 4K"), 2048 * 1024 - 256 - 4096);
    assert_eq!(expr("16K+0x10"), 16 * 1024 + 16);
}
