//! The calibration-file loader (`quatarm_ref::calfile::parse`, spec/calibration-file.md): any
//! text. Never a panic; an accepted arm is written back (`calfile::write`) as a file that
//! reads back to the same arm, and the table builder refuses or builds it without a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use quatarm_ref::calfile;

fuzz_target!(|bytes: &[u8]| {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    let Ok(parsed) = calfile::parse(text) else {
        return;
    };
    let written = calfile::write(&parsed.arm, &[]);
    let back = calfile::parse(&written)
        .unwrap_or_else(|e| panic!("its own output refused: {e}\n{written}"));
    assert_eq!(back.arm, parsed.arm, "{written}");
    let _ = armcal::tablebuild::build(&parsed.arm);
});
