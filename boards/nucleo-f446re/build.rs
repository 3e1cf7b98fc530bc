//! The linker scripts (`memory.x`, cortex-m-rt's `link.x`, defmt's `defmt.x`) and the arm
//! maker's public key the image checks tables against (`QUATARM_MAKER_KEY`).
include!("../common/build_link.rs");

fn main() {
    link_scripts(&["memory.x"]);
    maker_key();
}
