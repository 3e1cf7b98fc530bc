//! `armcal table build|show`: the firmware's binary calibration table.

use anyhow::Context;
use quatarm::table::{Table, FLAG_GEOMETRIC, FLAG_GRAVITY, FLAG_HARMONICS, FLAG_THERMAL};
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
    },
    /// Validate a binary table as the firmware does and print what it holds.
    Show {
        /// Table file.
        table: PathBuf,
    },
}

/// Runs the subcommand.
pub fn run(command: Command) -> anyhow::Result<()> {
    match command {
        Command::Build { calib, output } => {
            let (arm, budget) = armcal::load::calibration(&calib)?;
            let bytes = armcal::tablebuild::build_with(&arm, budget.as_ref())
                .with_context(|| calib.display().to_string())?;
            std::fs::write(&output, &bytes).with_context(|| output.display().to_string())?;
            let t = Table::parse(&bytes)?;
            println!(
                "{}: {} bytes, {} joints, CRC {:08x}",
                output.display(),
                bytes.len(),
                t.joint_count(),
                t.crc()
            );
            Ok(())
        }
        Command::Show { table } => {
            let bytes = std::fs::read(&table).with_context(|| table.display().to_string())?;
            let t = Table::parse(&bytes).with_context(|| table.display().to_string())?;
            print!("{}", show(&t));
            Ok(())
        }
    }
}

/// A person-readable listing of a validated table.
pub fn show(t: &Table<'_>) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let flags = t.flags();
    let names: Vec<&str> = [
        (FLAG_GEOMETRIC, "geometric"),
        (FLAG_HARMONICS, "harmonics"),
        (FLAG_GRAVITY, "gravity"),
        (FLAG_THERMAL, "thermal"),
    ]
    .iter()
    .filter(|(f, _)| flags & f != 0)
    .map(|(_, n)| *n)
    .collect();
    let _ = writeln!(
        s,
        "quatarm calibration table v{}, {} bytes, CRC {:08x} (valid)",
        quatarm::table::VERSION,
        t.bytes().len(),
        t.crc()
    );
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
    for i in 0..t.joint_count() {
        let Some(j) = t.joint(i) else { continue };
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
    }
    let p = t.probe();
    let _ = writeln!(
        s,
        "probe: vector (mm) = [{:.6}, {:.6}, {:.6}], direction = [{:.12}, {:.12}, {:.12}], thermal = {:e} /degC",
        p.vector[0], p.vector[1], p.vector[2], p.direction[0], p.direction[1], p.direction[2], p.thermal
    );
    s
}
