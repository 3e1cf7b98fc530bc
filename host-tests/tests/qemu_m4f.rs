//! qemu-m4f (mps2-an386, Cortex-M4F, f32 chain) end to end under QEMU: the cases of `common`,
//! the full recording within 1 µm and 1e-6 of the f64 reference.
//! Run by `cargo xtask test`, which builds the board first.

mod common;

common::board_tests! {
    board: "qemu-m4f",
    bounds: common::Bounds {
        tip_um: 1.0,
        dir: 1e-6,
    },
    full_recording: replays_the_recording_bit_identical_to_the_host_and_within_1um,
    update: update_with_resets,
    u95: u95_matches_the_host,
    wobble: wobble_applied,
    probes: probes_selected_and_updated,
    table_send: table_send_over_a_pty,
}

/// Anti-rollback end to end: a newer calibration number committed, the older one refused with
/// its status, before and after a reset (`common::rollback_refused`).
#[test]
#[ignore = "needs QEMU and the cross tool chain: run by cargo xtask test"]
fn an_older_calibration_number_is_refused() {
    common::rollback_refused("qemu-m4f");
}

/// Key rotation end to end: a table signed by the image's next key committed, then a table
/// signed by the retired key refused `RetiredKey`, before and after a reset
/// (`common::key_rotation`).
#[test]
#[ignore = "needs QEMU and the cross tool chain: run by cargo xtask test"]
fn a_table_signed_by_a_retired_key_is_refused_after_a_rotation() {
    common::key_rotation("qemu-m4f");
}

/// The budget's pose part through the hub's assembly: every streamed U95 equal to the host
/// build's (`common::pose_part_u95_is_the_host_builds`).
#[test]
#[ignore = "needs QEMU and the cross tool chain: run by cargo xtask test"]
fn the_pose_parts_u95_is_the_host_builds() {
    common::pose_part_u95_is_the_host_builds("qemu-m4f");
}
