//! Arms anywhere inside the binary table's limits (`host_tests::arms::case`: any axes,
//! counts, fixed rotations, links and probe up to the table's lengths, harmonics, gravity
//! compliance and thermal expansion up to their limits, readings anywhere at any accepted
//! temperature), each checked against the f64 reference: either a refusal that names its
//! limit, or both quaternion chains within the firmware's bounds (f32 1 µm and 1e-6, fixed
//! point 0.1 µm and 1e-7) on every reading. The target that found issue 15's 15.8 µm.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Err(e) = host_tests::arms::check_bytes(data) {
        let case = host_tests::arms::case(&mut arbitrary::Unstructured::new(data));
        panic!("{e}\n{:#?}", case.map(|c| c.arm));
    }
});
