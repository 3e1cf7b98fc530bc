// The linker setup every board's build script makes, `include!`d by each (a build-helper
// crate would be a dependency, and a lock-file entry, for fifteen lines).

/// Puts the board's linker scripts (`memory.x`, and any it adds) where the linker finds
/// them, and passes cortex-m-rt's `link.x` and defmt's `defmt.x` (the table of interned log
/// strings).
fn link_scripts(files: &[&str]) {
    let out = std::path::PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    for file in files {
        std::fs::copy(file, out.join(file)).expect("copy a linker script");
        println!("cargo:rerun-if-changed={file}");
    }
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=../common/build_link.rs");
    println!("cargo:rustc-link-arg=-Tlink.x");
    println!("cargo:rustc-link-arg=-Tdefmt.x");
}
