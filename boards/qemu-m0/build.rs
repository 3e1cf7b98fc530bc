//! Puts `memory.x` where the linker finds it and passes cortex-m-rt's `link.x`, defmt's
//! `defmt.x` (the table of interned log strings) and, for the hub binary only, `budget.x`
//! (32 KiB flash, 8 KiB RAM with the stack).
use std::{env, fs, path::PathBuf};

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    for file in ["memory.x", "budget.x"] {
        fs::copy(file, out.join(file)).expect("copy a linker script");
        println!("cargo:rerun-if-changed={file}");
    }
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rustc-link-arg=-Tlink.x");
    println!("cargo:rustc-link-arg=-Tdefmt.x");
    println!("cargo:rustc-link-arg-bin=qemu-m0=-Tbudget.x");
}
