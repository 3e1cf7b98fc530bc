//! The linker scripts: `memory.x`, cortex-m-rt's `link.x`, defmt's `defmt.x` and, for the hub
//! binary only, `budget.x` (32 KiB flash, 8 KiB RAM with the stack). With the feature
//! `pico-profile` (the Pico's profile on this core, for its benchmark image) no budget is
//! linked, and `pico-profile.x` moves the table region's end and the stack's top.
include!("../common/build_link.rs");

fn main() {
    if std::env::var_os("CARGO_FEATURE_PICO_PROFILE").is_some() {
        link_scripts(&["memory.x", "pico-profile.x"]);
        println!("cargo:rustc-link-arg=-Tpico-profile.x");
    } else {
        link_scripts(&["memory.x", "budget.x"]);
        println!("cargo:rustc-link-arg-bin=qemu-m0=-Tbudget.x");
    }
}
