//! qemu-m4f (mps2-an386, Cortex-M4F, f32 chain) end to end under QEMU.
//! Run by `cargo xtask test`, which builds the board first.

mod common;

use common::Bounds;

const BOARD: &str = "qemu-m4f";

#[test]
#[ignore = "needs QEMU and the cross tool chain: run by cargo xtask test"]
fn replays_the_recording_bit_identical_to_the_host_and_within_1um() {
    common::full_recording(
        BOARD,
        Bounds {
            tip_um: 1.0,
            dir: 1e-6,
        },
    );
}

#[test]
#[ignore = "needs QEMU and the cross tool chain: run by cargo xtask test"]
fn a_flipped_bit_in_an_incoming_frame_gives_input_error_and_no_coordinates() {
    common::flipped_bit_in_an_incoming_frame(BOARD);
}

#[test]
#[ignore = "needs QEMU and the cross tool chain: run by cargo xtask test"]
fn an_encoder_fault_gives_its_joint_bit_and_no_coordinates() {
    common::encoder_fault(BOARD);
}

#[test]
#[ignore = "needs QEMU and the cross tool chain: run by cargo xtask test"]
fn bad_tables_are_reported_and_give_no_coordinates() {
    common::bad_tables(BOARD);
}

#[test]
#[ignore = "needs QEMU and the cross tool chain: run by cargo xtask test"]
fn text_mode_prints_the_same_numbers() {
    common::text_mode(BOARD);
}

#[test]
#[ignore = "needs QEMU and the cross tool chain: run by cargo xtask test"]
fn the_defmt_log_decodes_on_the_host() {
    common::defmt_log(BOARD);
}
