//! The binary table parser (`quatarm::table`): any bytes in flash are refused with an error or
//! accepted as a table whose every value is inside the table's limits and from which both
//! chains build or refuse cleanly. Never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use quatarm::{Chain, Fixed, MatrixChain, Table, F32};

fuzz_target!(|bytes: &[u8]| {
    let Ok(table) = Table::parse(bytes) else {
        return;
    };
    // An accepted table reads back and re-encodes to the same bytes.
    let data = table.data();
    let mut out = vec![0u8; quatarm::table::MAX_TABLE_LEN];
    let n = data.encode(&mut out).expect("an accepted table re-encodes");
    assert_eq!(
        &out[..n],
        &bytes[..n],
        "re-encoding an accepted table changed it"
    );
    assert_eq!(Table::parse(&out[..n]).map(|t| t.data()), Ok(data));
    let _ = Chain::<F32>::new(&table);
    let _ = Chain::<Fixed>::new(&table);
    let _ = MatrixChain::<F32>::new(&table);
    let _ = MatrixChain::<Fixed>::new(&table);
});
