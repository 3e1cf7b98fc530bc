//! The linker scripts: `memory.x`, cortex-m-rt's `link.x`, defmt's `defmt.x` and, for the hub
//! binary only, `budget.x` (32 KiB flash, 8 KiB RAM with the stack).
include!("../common/build_link.rs");

fn main() {
    link_scripts(&["memory.x", "budget.x"]);
    println!("cargo:rustc-link-arg-bin=qemu-m0=-Tbudget.x");
}
