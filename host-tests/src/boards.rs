//! The boards of `boards/`, as the tools that build and run them need to know them.
//!
//! Each board states its own facts once, in the files its build already reads: the target
//! triple in `.cargo/config.toml` (`[build] target`), the QEMU machine in the same file's
//! runner (`-M NAME`, QEMU boards only), the calibration table's address in `memory.x`
//! (`CALTABLE`'s `ORIGIN`, which the firmware links against) and the core clock in
//! `src/main.rs` (`const CORE_HZ: u32 = …;`, which the firmware runs SysTick at). [`boards`]
//! reads them from there, so a board changed in one place cannot disagree with the tools.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use anyhow::{anyhow, bail, Context, Result};

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

/// Every board, QEMU ones first, with the chain arithmetic its `src/main.rs` instantiates
/// (the one fact a build file does not state in a form a tool can read).
const BOARD_LIST: [(&str, &str); 4] = [
    ("qemu-m4f", "f32"),
    ("qemu-m0", "fixed"),
    ("nucleo-f446re", "f32"),
    ("rp-pico", "fixed"),
];

/// Every board, read from its files once; an error names the file and the key at fault.
pub fn boards() -> Result<&'static [Board]> {
    static BOARDS: OnceLock<Result<Vec<Board>, String>> = OnceLock::new();
    BOARDS
        .get_or_init(|| {
            BOARD_LIST
                .iter()
                .map(|&(name, precision)| load(name, precision))
                .collect::<Result<Vec<_>>>()
                .map_err(|e| format!("{e:#}"))
        })
        .as_deref()
        .map_err(|e| anyhow!("{e}"))
}

/// The board called `name`.
pub fn board(name: &str) -> Result<Board> {
    let all = boards()?;
    all.iter().copied().find(|b| b.name == name).ok_or_else(|| {
        let names: Vec<&str> = all.iter().map(|b| b.name).collect();
        anyhow!("no board {name} (boards: {})", names.join(", "))
    })
}

fn load(name: &'static str, precision: &'static str) -> Result<Board> {
    let dir = root().join("boards").join(name);
    let read = |rel: &str| {
        let path = dir.join(rel);
        std::fs::read_to_string(&path)
            .with_context(|| format!("reading {}", path.display()))
            .map(|text| (path, text))
    };

    let (config_path, config) = read(".cargo/config.toml")?;
    let at = |key: &str| format!("{}: `{key}`", config_path.display());
    let config: toml::Table = toml::from_str(&config).with_context(|| at("(file)"))?;
    let target = config
        .get("build")
        .and_then(|b| b.get("target"))
        .and_then(|t| t.as_str())
        .with_context(|| format!("{}: no string", at("build.target")))?
        .to_owned();
    let runner = config
        .get("target")
        .and_then(|t| t.get(target.as_str()))
        .and_then(|t| t.get("runner"))
        .and_then(|r| r.as_str())
        .with_context(|| format!("{}: no string", at(&format!("target.{target}.runner"))))?;
    let mut words = runner.split_whitespace();
    let qemu = if words.next().is_some_and(|w| w.starts_with("qemu-system-")) {
        let machine = words
            .skip_while(|w| *w != "-M")
            .nth(1)
            .with_context(|| {
                format!(
                    "{}: a QEMU runner without `-M MACHINE`",
                    at(&format!("target.{target}.runner"))
                )
            })?
            .to_owned();
        let (memory_path, memory) = read("memory.x")?;
        let (origin, _) =
            region(&memory, "CALTABLE").with_context(|| format!("{}", memory_path.display()))?;
        let table_addr = u32::try_from(origin).with_context(|| {
            format!(
                "{}: CALTABLE's ORIGIN {origin:#x} beyond 32 bits",
                memory_path.display()
            )
        })?;
        let (main_path, main) = read("src/main.rs")?;
        let core_hz = core_hz(&main).with_context(|| format!("{}", main_path.display()))?;
        Some(QemuMachine {
            machine: machine.leak(),
            table_addr,
            core_hz,
        })
    } else {
        None
    };
    Ok(Board {
        name,
        target: target.leak(),
        precision,
        qemu,
    })
}

/// The value of `const CORE_HZ: u32 = …;` in a board's `src/main.rs`.
fn core_hz(main: &str) -> Result<u32> {
    let (n, line) = main
        .lines()
        .enumerate()
        .find(|(_, l)| l.trim_start().starts_with("const CORE_HZ: u32 ="))
        .context("no `const CORE_HZ: u32 = …;`")?;
    let value = line
        .split_once('=')
        .map(|(_, v)| v.trim().trim_end_matches(';').trim().replace('_', ""))
        .unwrap_or_default();
    value
        .parse()
        .with_context(|| format!("line {}: CORE_HZ is not an integer literal: {line}", n + 1))
}

/// ORIGIN and LENGTH of region `name` in a linker script's MEMORY block.
pub fn region(script: &str, name: &str) -> Result<(u64, u64)> {
    let (n, line) = script
        .lines()
        .enumerate()
        .map(|(n, l)| (n, l.trim()))
        .find(|(_, l)| {
            l.split(|c: char| c.is_whitespace() || c == ':')
                .next()
                .is_some_and(|w| w == name)
        })
        .with_context(|| format!("no {name} region"))?;
    let value = |key: &str| -> Result<u64> {
        let rest = line
            .find(key)
            .and_then(|i| line[i..].split('=').nth(1))
            .with_context(|| format!("line {}: {name} has no `{key} = …`", n + 1))?;
        expr(rest.split(',').next().unwrap_or(rest))
            .with_context(|| format!("line {}: {name}'s {key}", n + 1))
    };
    Ok((value("ORIGIN")?, value("LENGTH")?))
}

/// A sum of terms such as `2048K - 0x100 - 4K`, as the boards' scripts write lengths.
pub fn expr(e: &str) -> Result<u64> {
    let e = e.replace(' ', "");
    let mut total: i64 = 0;
    let mut sign = 1;
    for (i, part) in e.split_inclusive(['+', '-']).enumerate() {
        let (term, next) = match part.strip_suffix('+') {
            Some(t) => (t, 1),
            None => match part.strip_suffix('-') {
                Some(t) => (t, -1),
                None => (part, 1),
            },
        };
        if i > 0 && term.is_empty() {
            bail!("bad expression {e}");
        }
        let v = i64::try_from(term_value(term)?).with_context(|| format!("{term} too large"))?;
        total += sign * v;
        sign = next;
    }
    u64::try_from(total).with_context(|| format!("{e} is negative"))
}

fn term_value(v: &str) -> Result<u64> {
    let bad = || format!("`{v}` is not a number");
    Ok(if let Some(h) = v.strip_prefix("0x") {
        u64::from_str_radix(&h.replace('_', ""), 16).with_context(bad)?
    } else if let Some(k) = v.strip_suffix('K') {
        k.parse::<u64>().with_context(bad)? * 1024
    } else if let Some(m) = v.strip_suffix('M') {
        m.parse::<u64>().with_context(bad)? * 1024 * 1024
    } else {
        v.parse().with_context(bad)?
    })
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_board_reads_from_its_own_files() {
        let all = boards().unwrap_or_else(|e| panic!("{e:#}"));
        assert_eq!(all.len(), BOARD_LIST.len());
        for b in all {
            assert!(b.target.starts_with("thumbv"), "{}: {}", b.name, b.target);
            // The QEMU boards are exactly those named so, each with its machine and clock.
            assert_eq!(b.qemu.is_some(), b.name.starts_with("qemu-"), "{}", b.name);
            if let Some(m) = b.qemu {
                assert!(!m.machine.is_empty() && m.core_hz > 0, "{}: {m:?}", b.name);
                assert_ne!(
                    m.table_addr, 0,
                    "{}: the table is not at the vector table",
                    b.name
                );
            }
        }
        assert!(board("no-such-board").is_err());
    }

    #[test]
    fn the_clock_is_read_from_its_constant() {
        let main = "use x;\n/// The clock.\nconst CORE_HZ: u32 = 25_000_000;\nfn main() {}\n";
        assert_eq!(core_hz(main).unwrap(), 25_000_000);
        assert!(core_hz("const CORE: u32 = 1;").is_err());
        let bad = core_hz("\nconst CORE_HZ: u32 = 25 * MHZ;").unwrap_err();
        assert!(format!("{bad:#}").contains("line 2"), "{bad:#}");
    }
}
