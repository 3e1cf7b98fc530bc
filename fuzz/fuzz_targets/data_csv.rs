//! armcal's measured-data CSV reader (`armcal::data::parse`, spec/data-file.md): any text, for
//! a 6- or 7-joint arm. Never a panic; what it accepts it writes back (`Dataset::to_csv`) as
//! text that reads back to the same rows.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|bytes: &[u8]| {
    let Some((&pick, rest)) = bytes.split_first() else {
        return;
    };
    let Ok(text) = std::str::from_utf8(rest) else {
        return;
    };
    let dof = 6 + usize::from(pick & 1);
    let Ok(ds) = armcal::data::parse(text, "fuzz.csv", dof) else {
        return;
    };
    let written = ds.to_csv(&[]);
    let back = armcal::data::parse(&written, "written.csv", dof)
        .unwrap_or_else(|e| panic!("its own output refused: {e}\n{written}"));
    // The same rows; only their line numbers may differ (comments are not written back).
    let without_lines = |rows: &[armcal::data::Row]| {
        rows.iter()
            .map(|r| armcal::data::Row {
                line: 0,
                ..r.clone()
            })
            .collect::<Vec<_>>()
    };
    assert_eq!(
        without_lines(&back.rows),
        without_lines(&ds.rows),
        "{written}"
    );
    assert_eq!(back.has_temperature, ds.has_temperature);
});
