//! The boards of `boards/`, as the tools that build and run them need to know them.

use std::path::{Path, PathBuf};

/// How QEMU runs a board.
#[derive(Debug, Clone, Copy)]
pub struct QemuMachine {
    /// `-M` value.
    pub machine: &'static str,
    /// Where `memory.x` puts the calibration region (the loader's `addr=`).
    pub table_addr: u32,
    /// Core clock: SysTick counts it, and under `-icount shift=0` one instruction takes 1 ns,
    /// so one tick is `1e9 / core_hz` instructions.
    pub core_hz: u32,
}

/// One firmware crate.
#[derive(Debug, Clone, Copy)]
pub struct Board {
    /// Folder name under `boards/`, also the crate and main binary name.
    pub name: &'static str,
    /// Rust target triple.
    pub target: &'static str,
    /// The chain arithmetic it runs (`f32` or `fixed`), as `armcal eval --precision` names it.
    pub precision: &'static str,
    /// Set for the boards QEMU runs.
    pub qemu: Option<QemuMachine>,
}

/// Every board, QEMU ones first.
pub const BOARDS: [Board; 4] = [
    Board {
        name: "qemu-m4f",
        target: "thumbv7em-none-eabihf",
        precision: "f32",
        qemu: Some(QemuMachine {
            machine: "mps2-an386",
            table_addr: 0x0004_0000,
            core_hz: 25_000_000,
        }),
    },
    Board {
        name: "qemu-m0",
        target: "thumbv6m-none-eabi",
        precision: "fixed",
        qemu: Some(QemuMachine {
            machine: "microbit",
            table_addr: 0x0003_C000,
            core_hz: 16_000_000,
        }),
    },
    Board {
        name: "nucleo-f446re",
        target: "thumbv7em-none-eabihf",
        precision: "f32",
        qemu: None,
    },
    Board {
        name: "rp-pico",
        target: "thumbv6m-none-eabi",
        precision: "fixed",
        qemu: None,
    },
];

/// The board called `name`.
pub fn board(name: &str) -> Option<Board> {
    BOARDS.iter().copied().find(|b| b.name == name)
}

/// The workspace root (this crate lives in `host-tests/`).
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("host-tests sits in the workspace root")
        .to_path_buf()
}

impl Board {
    /// The board's crate folder.
    pub fn dir(&self) -> PathBuf {
        root().join("boards").join(self.name)
    }

    /// A release binary of the board as `cargo xtask build` leaves it, built by the tool
    /// chain [`Toolchain::current`] names.
    pub fn elf(&self, bin: &str) -> PathBuf {
        self.elf_by(Toolchain::current(self), bin)
    }

    /// A release binary of the board built by `toolchain`.
    pub fn elf_by(&self, toolchain: Toolchain, bin: &str) -> PathBuf {
        toolchain
            .target_dir(&self.dir())
            .join(self.target)
            .join("release")
            .join(bin)
    }
}

/// The environment variable that names the firmware tool chain (`rustup` or `debian`) the
/// QEMU tests run and single-board commands build with; `cargo xtask test` sets it for each
/// tool chain in turn.
pub const TOOLCHAIN_ENV: &str = "QUATARM_FIRMWARE";

/// A kind of compiler that builds the firmware. Each builds a board into its own folder, so
/// that the images of both stand side by side.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Toolchain {
    /// rustup's compiler with the thumb targets.
    Rustup,
    /// Debian's `rustc-web` with `-Z build-std=core`.
    Debian,
}

impl Toolchain {
    /// Both kinds, in the order they are preferred.
    pub const ALL: [Toolchain; 2] = [Toolchain::Rustup, Toolchain::Debian];

    /// Its name, as [`TOOLCHAIN_ENV`] takes it.
    pub fn name(self) -> &'static str {
        match self {
            Toolchain::Rustup => "rustup",
            Toolchain::Debian => "debian",
        }
    }

    /// The folder it builds a board crate in `dir` into.
    pub fn target_dir(self, dir: &Path) -> PathBuf {
        dir.join("target").join(self.name())
    }

    /// The tool chain named by [`TOOLCHAIN_ENV`]; unset, the first kind that has built `board`
    /// (rustup's first).
    pub fn current(board: &Board) -> Toolchain {
        let named = std::env::var(TOOLCHAIN_ENV).ok();
        Self::ALL
            .into_iter()
            .find(|t| match named.as_deref() {
                Some(n) => t.name() == n,
                None => t
                    .target_dir(&board.dir())
                    .join(board.target)
                    .join("release")
                    .join(board.name)
                    .exists(),
            })
            .unwrap_or(Toolchain::Rustup)
    }
}
