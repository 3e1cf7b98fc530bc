//! One C baseline as an image for QEMU mps2-an386: compiled with arm-none-eabi-gcc from
//! `bench/c/` and the generated headers, run under `-icount shift=0`, its log read back.

use anyhow::{bail, Context, Result};
use host_tests::boards::root;
use host_tests::qemu::wait_until;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

/// The compiler the C baselines need.
pub const GCC: &str = "arm-none-eabi-gcc";

/// The flags of every C baseline: the (gcc's `-O2` for the Cortex-M4F's FPU), in
/// gcc's default GNU C mode, whose `-ffp-contract=fast` fuses a multiply and an add into one
/// `vfma` (an ISO mode such as `-std=c11` turns that off: [`CChain::LeanUnfused`]).
pub const CFLAGS: &[&str] = &[
    "-O2",
    "-mcpu=cortex-m4",
    "-mthumb",
    "-mfpu=fpv4-sp-d16",
    "-mfloat-abi=hard",
    "-Wall",
    "-Wextra",
    "-Werror",
];

/// The C chains, by their file in `bench/c/` (`chain_<name>.c`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CChain {
    /// Newlib's `sinf`/`cosf` per joint, full 3×4 products, the geometry only (not the
    /// calibrated model: a team's first version).
    DhGeometry,
    /// Newlib's `sinf`/`cosf` per joint, full 3×4 products.
    DhSinf,
    /// The calibrated 3×4 matrix chain, inner products written out.
    Matrix,
    /// The lean forward chain.
    Lean,
    /// The same, built with `-ffp-contract=off`: no fused multiply–add, as the Rust chains
    /// (whose host build is bit for bit the hub's).
    LeanUnfused,
}

impl CChain {
    /// Every C chain, in the table's order.
    pub const ALL: [CChain; 5] = [
        CChain::DhGeometry,
        CChain::DhSinf,
        CChain::Matrix,
        CChain::Lean,
        CChain::LeanUnfused,
    ];

    /// The file stem after `chain_`.
    pub fn file(self) -> &'static str {
        match self {
            CChain::DhGeometry | CChain::DhSinf => "dh",
            CChain::Matrix => "matrix",
            CChain::Lean | CChain::LeanUnfused => "lean",
        }
    }

    /// The image's name (its file's, with the variant's).
    pub fn image(self) -> &'static str {
        match self {
            CChain::LeanUnfused => "lean-unfused",
            CChain::DhGeometry => "dh-geometry",
            c => c.file(),
        }
    }

    /// Flags of this chain beyond [`CFLAGS`].
    pub fn extra_flags(self) -> &'static [&'static str] {
        match self {
            CChain::LeanUnfused => &["-ffp-contract=off"],
            CChain::DhGeometry => &["-DGEOMETRY_ONLY"],
            _ => &[],
        }
    }

    /// The row's label.
    pub fn label(self) -> &'static str {
        match self {
            CChain::DhGeometry => {
                "C, D–H style 3×4 with newlib sinf/cosf, geometry only (no harmonics, gravity, thermal: not the model)"
            }
            CChain::DhSinf => "C, D–H style 3×4 with newlib sinf/cosf (full model)",
            CChain::Matrix => "C, calibrated 3×4 matrix chain, inner products written out",
            CChain::Lean => "C, lean forward chain (Rz·Rx a joint, Euler split at boot)",
            CChain::LeanUnfused => {
                "C, the same lean chain with -ffp-contract=off (no fused multiply–add)"
            }
        }
    }
}

/// Where arm-none-eabi-gcc is, if on the PATH.
pub fn gcc() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join(GCC))
        .find(|p| p.is_file())
}

/// "arm-none-eabi-gcc 12.2.1", if it runs.
pub fn gcc_version() -> Option<String> {
    let out = Command::new(gcc()?).arg("-dumpversion").output().ok()?;
    let v = String::from_utf8_lossy(&out.stdout).trim().to_string();
    (out.status.success() && !v.is_empty()).then(|| format!("{GCC} {v}"))
}

/// The C sources' folder.
pub fn sources() -> PathBuf {
    root().join("bench/c")
}

/// Compiles `chain` with the headers in `gen` into `gen/<file>.elf`.
pub fn build(gcc: &Path, chain: CChain, gen: &Path) -> Result<PathBuf> {
    let src = sources();
    let elf = gen.join(format!("{}.elf", chain.image()));
    let out = Command::new(gcc)
        .args(CFLAGS)
        .args(chain.extra_flags())
        .arg("-I")
        .arg(gen)
        .arg("-I")
        .arg(&src)
        .arg(src.join("startup.c"))
        .arg(src.join("main.c"))
        .arg(src.join(format!("chain_{}.c", chain.file())))
        .arg("-T")
        .arg(src.join("link.ld"))
        .args(["-nostartfiles", "--specs=nano.specs", "--specs=nosys.specs"])
        .arg("-o")
        .arg(&elf)
        .arg("-lm")
        .output()
        .with_context(|| format!("starting {}", gcc.display()))?;
    if !out.status.success() {
        bail!(
            "{GCC} failed on bench/c/chain_{}.c:\n{}",
            chain.file(),
            String::from_utf8_lossy(&out.stderr)
        );
    }
    Ok(elf)
}

/// What one image logged.
#[derive(Debug)]
pub struct Log {
    /// Instructions per point, the clock's cost subtracted.
    pub instructions: f64,
    /// Each reading's result (centre mm, direction), `None` where the chain refused it.
    pub points: Vec<Option<[f32; 6]>>,
}

fn field(line: &str, before: &str) -> Result<f64> {
    let w: Vec<&str> = line.split_whitespace().collect();
    let k = w
        .iter()
        .position(|&x| x == before)
        .with_context(|| format!("no `{before}` in `{line}`"))?;
    let v = k
        .checked_sub(1)
        .and_then(|k| w.get(k))
        .with_context(|| format!("nothing before `{before}` in `{line}`"))?;
    v.parse()
        .with_context(|| format!("`{v}` in `{line}` is not a number"))
}

/// Parses an image's log (see `bench/c/main.c`).
pub fn parse(log: &str) -> Result<Log> {
    let line = |start: &str| {
        log.lines()
            .find(|l| l.starts_with(start))
            .with_context(|| format!("the C bench log has no `{start}` line"))
    };
    let cal = line("calibration loop")?;
    let per_tick = field(cal, "instructions")? / field(cal, "ticks")?;
    let empty = line("clock overhead")?;
    let chain = line("chain ")?;
    let overhead = field(empty, "ticks")? / field(empty, "points")?;
    let instructions = (field(chain, "ticks")? / field(chain, "points")? - overhead) * per_tick;
    let mut points = Vec::new();
    for l in log.lines().filter(|l| l.starts_with("point ")) {
        let w: Vec<&str> = l.split_whitespace().collect();
        if w.len() != 9 {
            bail!("malformed C bench line `{l}`");
        }
        let k: usize = w[1].parse().with_context(|| format!("in `{l}`"))?;
        if k != points.len() {
            bail!("C bench point {k} out of order (expected {})", points.len());
        }
        if w[2] != "0" {
            points.push(None);
            continue;
        }
        let mut v = [0f32; 6];
        for (x, h) in v.iter_mut().zip(&w[3..]) {
            *x = f32::from_bits(u32::from_str_radix(h, 16).with_context(|| format!("in `{l}`"))?);
        }
        points.push(Some(v));
    }
    Ok(Log {
        instructions,
        points,
    })
}

/// Runs `elf` under QEMU mps2-an386 with `-icount shift=0`; its log. Semihosting's
/// `SYS_WRITE0` goes to QEMU's stderr (its console), with any message of QEMU's own: the
/// parser keeps only its own lines.
pub fn run(elf: &Path) -> Result<Log> {
    let mut child = Command::new("qemu-system-arm")
        .args(["-M", "mps2-an386", "-display", "none", "-monitor", "none"])
        .args(["-serial", "null", "-icount", "shift=0"])
        .args(["-semihosting-config", "enable=on,target=native"])
        .arg("-kernel")
        .arg(elf)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .context("starting qemu-system-arm")?;
    let mut stderr = child.stderr.take().context("qemu stderr")?;
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = stderr.read_to_string(&mut s);
        s
    });
    let status = wait_until(&mut child, Duration::from_secs(300))?;
    let log = reader
        .join()
        .map_err(|_| anyhow::anyhow!("reading QEMU's output"))?;
    match status {
        None => bail!("{}: QEMU did not exit within 300 s", elf.display()),
        Some(s) if !s.success() => bail!(
            "{}: the C bench failed ({s}); the end of its log:\n{}",
            elf.display(),
            log.lines().rev().take(5).collect::<Vec<_>>().join("\n")
        ),
        Some(_) => parse(&log),
    }
}
