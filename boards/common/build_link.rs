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

/// Copies the arm maker's public key into `$OUT_DIR/maker.pub`, where
/// `board_common::maker_key!` includes it: the 32-byte file `QUATARM_MAKER_KEY` names
/// (absolute, or relative to the board's folder), else the repository's test key with a
/// warning that the image is not for an arm (`board_common::maker_key`). A file of another
/// length fails the build.
#[allow(dead_code)] // the QEMU boards embed the test key directly
fn maker_key() {
    const VAR: &str = "QUATARM_MAKER_KEY";
    println!("cargo:rerun-if-env-changed={VAR}");
    let path = match std::env::var_os(VAR) {
        Some(p) => std::path::PathBuf::from(p),
        None => {
            println!(
                "cargo:warning=no {VAR}: this image trusts the repository's TEST key \
                 (keys/test-maker.pub); set {VAR}=/path/to/maker.pub for an arm"
            );
            std::path::PathBuf::from("../../keys/test-maker.pub")
        }
    };
    let out = std::path::PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    copy_key(VAR, &path, &out.join("maker.pub"));
    next_maker_key(&out, std::env::var_os(VAR).is_some());
}

/// Copies the maker's next public key into `$OUT_DIR/maker-next.pub`
/// (`board_common::maker_keys!`): the 32-byte file `QUATARM_NEXT_MAKER_KEY` names; without
/// it, the test key's successor (`keys/test-maker-next.pub`) when the image trusts the test
/// key, else an empty file (no next key) and a warning that the image cannot rotate its key.
#[allow(dead_code)]
fn next_maker_key(out: &std::path::Path, maker_given: bool) {
    const VAR: &str = "QUATARM_NEXT_MAKER_KEY";
    println!("cargo:rerun-if-env-changed={VAR}");
    let path = match std::env::var_os(VAR) {
        Some(p) => std::path::PathBuf::from(p),
        None if maker_given => {
            println!(
                "cargo:warning=no {VAR}: this image holds no next maker key and cannot be \
                 rotated off a leaked key without a debug probe (docs/update.md)"
            );
            std::fs::write(out.join("maker-next.pub"), []).expect("write maker-next.pub");
            return;
        }
        None => std::path::PathBuf::from("../../keys/test-maker-next.pub"),
    };
    copy_key(VAR, &path, &out.join("maker-next.pub"));
}

/// Copies the public key at `path` (named by the variable `var`) to `to`, and has cargo
/// rebuild when it changes: a 32-byte Ed25519 public key, else the build fails naming both.
#[allow(dead_code)]
fn copy_key(var: &str, path: &std::path::Path, to: &std::path::Path) {
    println!("cargo:rerun-if-changed={}", path.display());
    let key =
        std::fs::read(path).unwrap_or_else(|e| panic!("{var}: reading {}: {e}", path.display()));
    assert!(
        key.len() == 32,
        "{var}: {} is {} bytes, not a 32-byte Ed25519 public key (armcal table keygen)",
        path.display(),
        key.len()
    );
    std::fs::write(to, key).unwrap_or_else(|e| panic!("writing {}: {e}", to.display()));
}
