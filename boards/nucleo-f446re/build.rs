//! The linker scripts: `memory.x`, cortex-m-rt's `link.x`, defmt's `defmt.x`.
include!("../common/build_link.rs");

fn main() {
    link_scripts(&["memory.x"]);
}
