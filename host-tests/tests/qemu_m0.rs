//! qemu-m0 (microbit, Cortex-M0, fixed-point chain) end to end under QEMU: the cases of
//! `common`, the full recording within 0.1 µm and 1e-7 of the f64 reference.
//! Run by `cargo xtask test`, which builds the board first.

mod common;

common::board_tests! {
    board: "qemu-m0",
    bounds: common::Bounds {
        tip_um: 0.1,
        dir: 1e-7,
    },
    full_recording: replays_the_recording_bit_identical_to_the_host_and_within_0_1um,
    update: update_not_supported,
    u95: no_u95,
    wobble: wobble_refused,
    probes: probes_selected,
    table_send: table_send_refused_over_a_pty,
}
