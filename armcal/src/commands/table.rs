//! `armcal table build|show|keygen|sign|verify|send`: the firmware's binary calibration
//! table, its signature, and sending it to a hub.

use anyhow::Context;
use quatarm::table::{Table, FLAG_GEOMETRIC, FLAG_GRAVITY, FLAG_HARMONICS, FLAG_THERMAL};
use quatarm_wire::tablesign;
use std::path::PathBuf;

/// `armcal table` subcommands.
#[derive(clap::Subcommand)]
pub enum Command {
    /// Build a binary table from a calibration file.
    Build {
        /// Calibration file (TOML).
        calib: PathBuf,
        /// Output file.
        #[arg(short, long)]
        output: PathBuf,
        /// Leave the `[uncertainty]` parameters' covariance out of the table (it keeps the
        /// reading's own terms): for the fixed-point hubs, which refuse a table with it and
        /// stream no U95.
        #[arg(long)]
        without_covariance: bool,
        #[command(flatten)]
        accept: super::accept::AcceptArgs,
    },
    /// Validate a binary table as the firmware does and print what it holds.
    Show {
        /// Table file.
        table: PathBuf,
    },
    /// Make an Ed25519 key pair for signing tables: OUT.pem, the private key (PKCS#8 PEM;
    /// keep it secret), and OUT.pub, the 32-byte public key the firmware image embeds.
    Keygen {
        /// Path without extension.
        #[arg(long)]
        out: PathBuf,
    },
    /// Sign a binary table: write the table followed by its 64-byte Ed25519 signature, the
    /// image a hub with the matching public key accepts.
    Sign {
        /// Table file (a signed one is signed afresh).
        table: PathBuf,
        /// Private key (PKCS#8 PEM, from `keygen` or `openssl genpkey -algorithm ed25519`).
        #[arg(long)]
        key: PathBuf,
        /// Output file.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Check a signed table as a hub does; exit 1 if it does not verify under the key.
    Verify {
        /// Signed table file.
        table: PathBuf,
        /// Public key (32 raw bytes, as `keygen` writes it).
        #[arg(long)]
        key: PathBuf,
    },
    /// Send a binary table to a hub over its stream's UART (`docs/update.md`): it is written
    /// into the hub's inactive flash slot, checked completely, then made live; until then, and
    /// whenever a step is refused or the power fails, the old table stays live.
    Send {
        /// Table file.
        table: PathBuf,
        /// The hub's serial port (for instance /dev/ttyACM0).
        #[arg(long)]
        port: String,
        /// Baud rate of the serial port.
        #[arg(long, default_value_t = 115_200)]
        baud: u32,
        /// Seconds to wait for each answer of the hub before giving up (the old table stays),
        /// however many reports it sends meanwhile.
        #[arg(long, default_value_t = 5.0)]
        timeout: f64,
    },
}

/// Runs the subcommand.
pub fn run(command: Command) -> anyhow::Result<()> {
    match command {
        Command::Build {
            calib,
            output,
            without_covariance,
            accept,
        } => build(calib, output, without_covariance, accept.accept()),
        Command::Send {
            table,
            port,
            baud,
            timeout,
        } => send(table, port, baud, timeout),
        Command::Keygen { out } => keygen(out),
        Command::Sign { table, key, output } => sign(table, key, output),
        Command::Verify { table, key } => verify(table, key),
        Command::Show { table } => show_file(table),
    }
}

/// `table build`: the calibration file's table, written all or nothing.
fn build(
    calib: PathBuf,
    output: PathBuf,
    without_covariance: bool,
    accept: armcal::plausible::Accept,
) -> anyhow::Result<()> {
    armcal::output::check(&[(&output, "table")], &[(&calib, "calibration file")])?;
    armcal::plausible::calibration(&calib, accept)?;
    let (arm, mut budget, release) = armcal::load::calibration_release(&calib)?;
    if without_covariance {
        budget = budget.map(|u| u.without_covariance());
    }
    let bytes = armcal::tablebuild::build_release(&arm, budget.as_ref(), &release)
        .with_context(|| calib.display().to_string())?;
    let t = Table::parse(&bytes)?;
    let mut files = armcal::output::Staged::guarding(&[(&calib, "calibration file")]);
    files.write(&output, &bytes)?;
    files.commit()?;
    println!(
        "{}: {} bytes, {} joints, CRC {:08x}, {}{}",
        output.display(),
        bytes.len(),
        t.joint_count(),
        t.crc(),
        release_line(&t),
        if t.wobble().is_some() {
            " (with an axis wobble: the f32 hubs apply it; the Cortex-M0 hubs refuse the table)"
        } else {
            ""
        }
    );
    Ok(())
}

/// `table send`: a table to a hub over its serial port, step by step.
fn send(table: PathBuf, port: String, baud: u32, timeout: f64) -> anyhow::Result<()> {
    let bytes = std::fs::read(&table).with_context(|| table.display().to_string())?;
    if !(timeout > 0.0 && timeout.is_finite()) {
        anyhow::bail!("--timeout {timeout}: a positive number of seconds");
    }
    let timeout = std::time::Duration::from_secs_f64(timeout);
    let mut p = serialport::new(&port, baud)
        .timeout(timeout)
        .open()
        .with_context(|| format!("opening serial port {port}"))?;
    let sent = armcal::table_send::send(&mut p, &bytes, timeout)
        .with_context(|| format!("sending {} to {port}", table.display()))?;
    println!(
        "{}: live on the hub in slot {}, record {}, CRC {:08x} ({} steps, {} reports while it ran)",
        table.display(),
        sent.live.slot,
        sent.live.seq,
        sent.live.crc,
        sent.steps,
        sent.reports_between
    );
    Ok(())
}

/// `table keygen`: a new signing key pair, both files or neither.
fn keygen(out: PathBuf) -> anyhow::Result<()> {
    let (pem, public) = tablesign::keygen()?;
    let (private_path, public_path) = (out.with_extension("pem"), out.with_extension("pub"));
    armcal::output::check(
        &[(&private_path, "private key"), (&public_path, "public key")],
        &[],
    )?;
    // Both new, the private one readable by its owner alone; both or neither.
    let mut files = armcal::output::Staged::new();
    files.write_private(&private_path, pem.as_bytes(), "private key")?;
    files.write_new(&public_path, &public, "public key", 0o644)?;
    files.commit()?;
    println!(
        "{}: private key (keep it secret); {}: public key {}",
        private_path.display(),
        public_path.display(),
        public
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect::<String>()
    );
    Ok(())
}

/// `table sign`: the table followed by its signature.
fn sign(table: PathBuf, key: PathBuf, output: PathBuf) -> anyhow::Result<()> {
    let inputs = [(table.as_path(), "table"), (key.as_path(), "private key")];
    armcal::output::check(&[(&output, "signed table")], &inputs)?;
    let k = tablesign::read_private(&key)?;
    let bytes = std::fs::read(&table).with_context(|| table.display().to_string())?;
    let image = tablesign::sign(&k, &bytes).with_context(|| table.display().to_string())?;
    let mut files = armcal::output::Staged::guarding(&inputs);
    files.write(&output, &image)?;
    files.commit()?;
    println!(
        "{}: {} bytes, table and signature",
        output.display(),
        image.len()
    );
    Ok(())
}

/// `table verify`: whether the signed table's signature verifies under the public key.
fn verify(table: PathBuf, key: PathBuf) -> anyhow::Result<()> {
    let k = tablesign::read_public(&key)?;
    let bytes = std::fs::read(&table).with_context(|| table.display().to_string())?;
    let n = tablesign::verify(&k, &bytes).with_context(|| table.display().to_string())?;
    println!(
        "{}: a {n}-byte table, signature valid under {}",
        table.display(),
        key.display()
    );
    Ok(())
}

/// `table show`: the table, listed.
fn show_file(table: PathBuf) -> anyhow::Result<()> {
    let bytes = std::fs::read(&table).with_context(|| table.display().to_string())?;
    let t = Table::parse(&bytes).with_context(|| table.display().to_string())?;
    print!("{}", show(&t));
    Ok(())
}

/// The table's calibration number and date, as `table build` and `table show` print them.
pub fn release_line(t: &Table<'_>) -> String {
    let r = t.release();
    let date = quatarm_ref::release::Date::from_yyyymmdd(r.date)
        .map_or_else(|| "no date".to_string(), |d| format!("dated {d}"));
    if t.version() == quatarm::table::OLD_VERSION {
        format!(
            "calibration number 0, no date (a version-{} table: a hub with a numbered table refuses it)",
            t.version()
        )
    } else {
        format!("calibration number {}, {date}", r.number)
    }
}

/// A person-readable listing of a validated table: its header, each joint, each probe, its
/// uncertainty budget.
pub fn show(t: &Table<'_>) -> String {
    let mut s = String::new();
    show_header(&mut s, t);
    for i in 0..t.joint_count() {
        show_joint(&mut s, t, i);
    }
    show_probes(&mut s, t);
    show_budget(&mut s, t);
    s
}

/// Version, size, CRC, release, serial, joints and the terms the table carries.
fn show_header(s: &mut String, t: &Table<'_>) {
    use std::fmt::Write as _;
    let flags = t.flags();
    let names: Vec<&str> = [
        (FLAG_GEOMETRIC, "geometric"),
        (FLAG_HARMONICS, "harmonics"),
        (FLAG_GRAVITY, "gravity"),
        (FLAG_THERMAL, "thermal"),
        (quatarm::table::FLAG_WOBBLE, "axis wobble (f32 hubs only)"),
    ]
    .iter()
    .filter(|(f, _)| flags & f != 0)
    .map(|(_, n)| *n)
    .collect();
    let _ = writeln!(
        s,
        "quatarm calibration table v{}, {} bytes, CRC {:08x} (valid)",
        t.version(),
        t.bytes().len(),
        t.crc()
    );
    let _ = writeln!(s, "{}", release_line(t));
    let _ = writeln!(s, "serial: {}", String::from_utf8_lossy(t.serial()));
    let _ = writeln!(s, "joints: {}", t.joint_count());
    let _ = writeln!(
        s,
        "terms: {}",
        if names.is_empty() {
            "nominal".into()
        } else {
            names.join(", ")
        }
    );
}

/// Joint `i` (0-based): its axis, rotation, link, thermal and gravity terms, harmonics and
/// axis wobble.
fn show_joint(s: &mut String, t: &Table<'_>, i: usize) {
    use std::fmt::Write as _;
    let Some(j) = t.joint(i) else { return };
    let _ = writeln!(
        s,
        "joint {}: axis {}, {} counts/rev",
        i + 1,
        ["x", "y", "z"][usize::from(j.axis).min(2)],
        j.counts
    );
    let q = j.rotation;
    let _ = writeln!(
        s,
        "  M' (w,x,y,z) = [{:.12}, {:.12}, {:.12}, {:.12}]",
        q[0], q[1], q[2], q[3]
    );
    let _ = writeln!(
        s,
        "  link (mm) = [{:.6}, {:.6}, {:.6}]",
        j.link[0], j.link[1], j.link[2]
    );
    let _ = writeln!(
        s,
        "  thermal = {:e} /degC, gravity = {:e} rad/mm",
        j.thermal, j.gravity
    );
    for h in &j.harmonics[..usize::from(j.harmonic_count)] {
        let _ = writeln!(
            s,
            "  harmonic order {}: sin {:e}, cos {:e} rad",
            h.order, h.sin, h.cos
        );
    }
    let w = t.joint_wobble(i);
    for term in &w.terms[..usize::from(w.count).min(w.terms.len())] {
        let _ = writeln!(
            s,
            "  axis wobble order {}: alpha sin {:e}, cos {:e}; beta sin {:e}, cos {:e} rad",
            term.order, term.alpha[0], term.alpha[1], term.beta[0], term.beta[1]
        );
    }
    if w.count > 0 {
        let _ = writeln!(
            s,
            "    about f1 = [{:.12}, {:.12}, {:.12}], f2 = [{:.12}, {:.12}, {:.12}]",
            w.f1[0], w.f1[1], w.f1[2], w.f2[0], w.f2[1], w.f2[2]
        );
    }
}

/// Every probe, the first (mounted at boot) first.
fn show_probes(s: &mut String, t: &Table<'_>) {
    use std::fmt::Write as _;
    for k in 0..t.probe_count() {
        let Some(p) = t.probe_at(k) else { continue };
        let _ = writeln!(
            s,
            "probe {}{}: vector (mm) = [{:.6}, {:.6}, {:.6}], direction = [{:.12}, {:.12}, {:.12}], thermal = {:e} /degC, ball diameter = {} mm",
            p.id,
            if k == 0 { " (mounted at boot)" } else { "" },
            p.vector[0],
            p.vector[1],
            p.vector[2],
            p.direction[0],
            p.direction[1],
            p.direction[2],
            p.thermal,
            p.ball_diameter
        );
    }
}

/// The uncertainty budget and the parameter covariance, or that there is none.
fn show_budget(s: &mut String, t: &Table<'_>) {
    use std::fmt::Write as _;
    let Some(b) = t.budget() else {
        let _ = writeln!(s, "uncertainty: none (the hub streams no U95)");
        return;
    };
    let counts: Vec<String> = (0..t.joint_count())
        .map(|i| format!("{}", b.encoder_counts(i)))
        .collect();
    let _ = writeln!(
        s,
        "uncertainty: encoder [{}] counts, probing {} mm, model {} mm, temperature {} degC",
        counts.join(", "),
        b.probing_mm(),
        b.model_mm(),
        b.temperature_c()
    );
    let _ = match t.parameters() {
        Some(p) => writeln!(
            s,
            "  parameter covariance: {} parameters (f32 hubs only)",
            p.count()
        ),
        None => writeln!(s, "  parameter covariance: none"),
    };
}
