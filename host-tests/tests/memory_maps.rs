//! Every board's `memory.x` (and the root template) gives the calibration table a region of
//! its own that holds the largest table, outside the firmware's flash and RAM, with the two
//! symbols the boards read; and the update's second slot and state record: copies in regions
//! of their own, or (no such regions, and the board's `main.rs` asks for `trailer_map`) in the
//! slots' trailers. A board with a region too small or overlapping its code would only show
//! on hardware; this checks it on every run.

use host_tests::boards::{self, root};
use quatarm::table::{table_len, MAX_JOINTS};

/// ORIGIN and LENGTH of region `name` (the parser the board list uses).
fn region(script: &str, name: &str) -> (u64, u64) {
    boards::region(script, name).unwrap_or_else(|e| panic!("{e:#}"))
}

/// Bytes a slot's trailer can take at most: the state record padded to the largest write unit
/// the update supports (`quatarm::update::layout::MAX_WRITE_SIZE`, the RP2040's page).
const MAX_TRAILER: u64 = quatarm::update::layout::MAX_WRITE_SIZE as u64;

/// Checks `path`; `main` is the board's `src/main.rs` (`None` for the template, which has
/// state regions of its own).
fn check(path: &std::path::Path, main: Option<&str>) {
    let script = std::fs::read_to_string(path).expect("memory.x");
    let who = path.display();
    let (ct, ct_len) = region(&script, "CALTABLE");
    let (flash, flash_len) = region(&script, "FLASH");
    let (ram, ram_len) = region(&script, "RAM");
    assert!(
        ct_len >= table_len(MAX_JOINTS) as u64,
        "{who}: CALTABLE of {ct_len} bytes cannot hold a {MAX_JOINTS}-joint table"
    );
    for sym in ["_cal_table_start = ORIGIN(CALTABLE)", "_cal_table_end"] {
        assert!(script.contains(sym), "{who}: no `{sym}`");
    }
    // The update's second slot and the state record (docs/update.md): each holds what it
    // must, and no two regions share a byte.
    let (b, b_len) = region(&script, "CALTABLE_B");
    assert!(
        b_len >= table_len(MAX_JOINTS) as u64,
        "{who}: CALTABLE_B of {b_len} bytes cannot hold a {MAX_JOINTS}-joint table"
    );
    let mut all = vec![
        ("FLASH", (flash, flash_len)),
        ("RAM", (ram, ram_len)),
        ("CALTABLE", (ct, ct_len)),
        ("CALTABLE_B", (b, b_len)),
    ];
    let state_regions = boards::region(&script, "CALSTATE0").is_ok();
    let trailers = main.is_some_and(|m| m.contains("slots::trailer_map()"));
    if state_regions {
        assert!(
            !trailers,
            "{who}: state regions of its own, but main.rs asks for `trailer_map`"
        );
        let s0 = region(&script, "CALSTATE0");
        let s1 = region(&script, "CALSTATE1");
        for (name, (_, len)) in [("CALSTATE0", s0), ("CALSTATE1", s1)] {
            assert!(
                len >= quatarm::update::record::RECORD_LEN as u64,
                "{who}: {name} cannot hold a state record"
            );
        }
        all.extend([("CALSTATE0", s0), ("CALSTATE1", s1)]);
        for sym in [
            "_cal_state0_start = ORIGIN(CALSTATE0)",
            "_cal_state0_end",
            "_cal_state1_start = ORIGIN(CALSTATE1)",
            "_cal_state1_end",
        ] {
            assert!(script.contains(sym), "{who}: no `{sym}`");
        }
    } else {
        // The record in the slots' trailers: the board must say so, no state symbol may be
        // left (a build asking for state regions then fails to link), and each slot holds the
        // largest table before its trailer.
        assert!(
            trailers,
            "{who}: no CALSTATE0 region, so main.rs must use `slots::trailer_map()`"
        );
        assert!(
            !script
                .lines()
                .any(|l| l.trim_start().starts_with("_cal_state")),
            "{who}: a `_cal_state` symbol without a state region"
        );
        for (name, len) in [("CALTABLE", ct_len), ("CALTABLE_B", b_len)] {
            assert!(
                len >= table_len(MAX_JOINTS) as u64 + MAX_TRAILER,
                "{who}: {name} of {len} bytes cannot hold a {MAX_JOINTS}-joint table and a trailer"
            );
        }
    }
    for (i, (n, (x, xl))) in all.iter().enumerate() {
        for (m, (y, yl)) in &all[i + 1..] {
            assert!(apart(*x, *xl, *y, *yl), "{who}: {n} overlaps {m}");
        }
    }
    for sym in ["_cal_slot1_start = ORIGIN(CALTABLE_B)", "_cal_slot1_end"] {
        assert!(script.contains(sym), "{who}: no `{sym}`");
    }
    // The flash driver's window starts at the lowest region and ends with the highest:
    // nothing of the firmware may lie between.
    let cal: Vec<_> = all.iter().skip(2).map(|(_, r)| *r).collect();
    let lo = cal.iter().map(|r| r.0).min().unwrap_or(0);
    let hi = cal.iter().map(|r| r.0 + r.1).max().unwrap_or(0);
    assert!(
        apart(lo, hi - lo, flash, flash_len),
        "{who}: the firmware lies within the calibration regions' span"
    );
}

fn apart(a: u64, al: u64, b: u64, bl: u64) -> bool {
    a + al <= b || b + bl <= a
}

#[test]
fn every_board_reserves_a_calibration_region() {
    for b in boards::boards().unwrap() {
        let main = std::fs::read_to_string(b.dir().join("src/main.rs")).expect("main.rs");
        check(&b.dir().join("memory.x"), Some(&main));
    }
}

/// A board whose profile takes the parameter block and the wobble (`board-common`'s features
/// `u95` and `wobble` in its `Cargo.toml`) has both slots large enough for the largest table
/// with both blocks: 7 joints, 8 probes, every joint's wobble and 64 parameters (13,824
/// bytes). The Pico's 4 KiB slots held only tables without the block; a 52-parameter table
/// would have been refused by its length.
#[test]
fn a_board_that_takes_the_parameter_block_has_slots_for_it() {
    use quatarm::table::{parameters, wobble, MAX_PLAIN_TABLE_LEN};
    let largest =
        MAX_PLAIN_TABLE_LEN + parameters::len(parameters::MAX_PARAMETERS) + wobble::len(MAX_JOINTS);
    let mut profiled = vec![];
    for b in boards::boards().unwrap() {
        let manifest = std::fs::read_to_string(b.dir().join("Cargo.toml")).expect("Cargo.toml");
        let common = manifest
            .lines()
            .find(|l| l.starts_with("board-common = "))
            .unwrap_or_else(|| panic!("{}: no board-common dependency", b.name));
        let takes = |f: &str| common.contains(&format!("\"{f}\""));
        if !(takes("u95") && takes("wobble")) {
            continue;
        }
        profiled.push(b.name);
        let script = std::fs::read_to_string(b.dir().join("memory.x")).expect("memory.x");
        for name in ["CALTABLE", "CALTABLE_B"] {
            let (_, len) = region(&script, name);
            assert!(
                len >= largest as u64,
                "{}: {name} of {len} bytes cannot hold a table of {largest} bytes",
                b.name
            );
        }
    }
    // The profiles as docs/results/boards.md gives them: all but qemu-m0.
    profiled.sort_unstable();
    assert_eq!(profiled, ["nucleo-f446re", "qemu-m4f", "rp-pico"]);
}

#[test]
fn the_template_reserves_a_calibration_region() {
    check(&root().join("memory.x"), None);
}

/// The STM32F446RE's sectors (16, 16, 16, 16, 64, 128, 128, 128 KiB from 0x0800_0000): the
/// firmware has sectors 0–5 (256 KiB), the two slots are sectors 6 and 7, whole, with the
/// state record in their trailers (docs/update.md).
#[test]
fn the_nucleo_gives_the_firmware_sectors_0_to_5() {
    let b = boards::board("nucleo-f446re").unwrap();
    let script = std::fs::read_to_string(b.dir().join("memory.x")).unwrap();
    let k = 1024;
    assert_eq!(region(&script, "FLASH"), (0x0800_0000, 256 * k));
    assert_eq!(region(&script, "CALTABLE_B"), (0x0804_0000, 128 * k));
    assert_eq!(region(&script, "CALTABLE"), (0x0806_0000, 128 * k));
    assert!(boards::region(&script, "CALSTATE0").is_err());
    let mut sectors = vec![];
    let mut at = 0x0800_0000u64;
    for len in [16, 16, 16, 16, 64, 128, 128, 128] {
        sectors.push(at);
        at += len * k;
    }
    for name in ["FLASH", "CALTABLE_B", "CALTABLE"] {
        let (start, len) = region(&script, name);
        assert!(
            sectors.contains(&start) && (sectors.contains(&(start + len)) || start + len == at),
            "{name} is not whole sectors"
        );
    }
}

/// The NUCLEO's flash driver (`src/flash.rs`, a thumb-only crate without host tests) refuses
/// to erase or program below its `SECTOR_6`: that bound must be where `memory.x` ends the
/// firmware and starts the lowest slot, and its guards and sector numbers must count from it
/// (it was sector 5's, 0x0802_0000, after the firmware had grown to sectors 0-5).
#[test]
fn the_nucleo_flash_driver_refuses_the_firmwares_sectors() {
    let b = boards::board("nucleo-f446re").unwrap();
    let script = std::fs::read_to_string(b.dir().join("memory.x")).unwrap();
    let src = std::fs::read_to_string(b.dir().join("src/flash.rs")).unwrap();
    let bound = src
        .lines()
        .find_map(|l| l.strip_prefix("const SECTOR_6: usize = "))
        .and_then(|v| v.strip_suffix(';'))
        .expect("no `const SECTOR_6: usize = ...;` in the NUCLEO's flash.rs");
    let bound = boards::expr(bound).unwrap();
    let (flash, flash_len) = region(&script, "FLASH");
    let lowest_slot = region(&script, "CALTABLE_B")
        .0
        .min(region(&script, "CALTABLE").0);
    assert_eq!(bound, 0x0804_0000, "sector 6 of the STM32F446RE");
    assert_eq!(
        bound,
        flash + flash_len,
        "the guard is not the firmware's end"
    );
    assert_eq!(
        bound, lowest_slot,
        "the guard is not the lowest slot's start"
    );
    for code in [
        "from < SECTOR_6 ||",
        "addr < SECTOR_6 ||",
        "(6 + (at - SECTOR_6) / SECTOR_LEN)",
    ] {
        assert!(src.contains(code), "no `{code}` in the NUCLEO's flash.rs");
    }
}

#[test]
fn the_parser_reads_what_it_checks() {
    let s = "MEMORY\n{\n  FLASH : ORIGIN = 0x08000000, LENGTH = 384K\n  CALTABLE : ORIGIN = 0x0806_0000, LENGTH = 1M\n}";
    assert_eq!(region(s, "FLASH"), (0x0800_0000, 384 * 1024));
    assert_eq!(region(s, "CALTABLE"), (0x0806_0000, 1024 * 1024));
    assert_eq!(
        boards::expr("2048K - 0x100 - 4K").unwrap(),
        2048 * 1024 - 256 - 4096
    );
    assert_eq!(boards::expr("16K+0x10").unwrap(), 16 * 1024 + 16);
    assert!(boards::expr("16K++4").is_err());
    assert!(boards::expr("0x10 - 1M").is_err());
    assert!(boards::region(s, "RAM").is_err());
}
