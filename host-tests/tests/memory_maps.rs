//! Every board's `memory.x` (and the root template) gives the calibration table a region of
//! its own that holds the largest table, outside the firmware's flash and RAM, with the two
//! symbols the boards read. A board with a region too small or overlapping its code would
//! only show on hardware; this checks it on every run.

use host_tests::boards::{self, root};
use quatarm::table::{table_len, MAX_JOINTS};

/// ORIGIN and LENGTH of region `name` (the parser the board list uses).
fn region(script: &str, name: &str) -> (u64, u64) {
    boards::region(script, name).unwrap_or_else(|e| panic!("{e:#}"))
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
    // The update's second slot and the two state-record copies (docs/update.md): each holds
    // what it must, and no two regions share a byte.
    let (b, b_len) = region(&script, "CALTABLE_B");
    assert!(
        b_len >= table_len(MAX_JOINTS) as u64,
        "{who}: CALTABLE_B of {b_len} bytes cannot hold a {MAX_JOINTS}-joint table"
    );
    let s0 = region(&script, "CALSTATE0");
    let s1 = region(&script, "CALSTATE1");
    for (name, (_, len)) in [("CALSTATE0", s0), ("CALSTATE1", s1)] {
        assert!(
            len >= quatarm::update::record::RECORD_LEN as u64,
            "{who}: {name} cannot hold a state record"
        );
    }
    let all = [
        ("FLASH", (flash, flash_len)),
        ("RAM", (ram, ram_len)),
        ("CALTABLE", (ct, ct_len)),
        ("CALTABLE_B", (b, b_len)),
        ("CALSTATE0", s0),
        ("CALSTATE1", s1),
    ];
    for (i, (n, (x, xl))) in all.iter().enumerate() {
        for (m, (y, yl)) in &all[i + 1..] {
            assert!(apart(*x, *xl, *y, *yl), "{who}: {n} overlaps {m}");
        }
    }
    for sym in [
        "_cal_slot1_start = ORIGIN(CALTABLE_B)",
        "_cal_slot1_end",
        "_cal_state0_start = ORIGIN(CALSTATE0)",
        "_cal_state0_end",
        "_cal_state1_start = ORIGIN(CALSTATE1)",
        "_cal_state1_end",
    ] {
        assert!(script.contains(sym), "{who}: no `{sym}`");
    }
}

#[test]
fn every_board_reserves_a_calibration_region() {
    for b in boards::boards().unwrap() {
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
    assert_eq!(
        boards::expr("2048K - 0x100 - 4K").unwrap(),
        2048 * 1024 - 256 - 4096
    );
    assert_eq!(boards::expr("16K+0x10").unwrap(), 16 * 1024 + 16);
    assert!(boards::expr("16K++4").is_err());
    assert!(boards::expr("0x10 - 1M").is_err());
    assert!(boards::region(s, "RAM").is_err());
}
