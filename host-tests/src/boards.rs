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

    /// A release binary of the board, as `cargo xtask build` leaves it.
    pub fn elf(&self, bin: &str) -> PathBuf {
        self.dir()
            .join("target")
            .join(self.target)
            .join("release")
            .join(bin)
    }
}
