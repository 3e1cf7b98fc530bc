//! The C baselines (`bench/c/`): the same model and calibration as the Rust bench, written
//! in C the ways a firmware team would, built with arm-none-eabi-gcc and measured on QEMU's
//! Cortex-M4F as the Rust chains are (instructions a point over the same recorded readings,
//! flash, accuracy against the f64 reference). Where the compiler is missing they are not
//! measured, and the output says so.

pub mod header;
pub mod image;
pub mod table;

use anyhow::{Context, Result};
use nalgebra::Vector3;
use object::{Object, ObjectSymbol};
use quatarm::stream::Reading;
use quatarm_ref::arm::Arm;
use std::path::Path;

pub use image::CChain;

/// Tip and direction errors of one chain against the f64 reference over the readings.
#[derive(Clone, Copy, Debug, Default)]
pub struct Accuracy {
    /// Largest tip error (µm).
    pub tip_max_um: f64,
    /// RMS tip error (µm).
    pub tip_rms_um: f64,
    /// Largest direction error (|n − n_ref|).
    pub dir_max: f64,
    /// Readings compared.
    pub points: usize,
    /// Readings the chain refused.
    pub refused: usize,
}

/// Compares each reading's result (centre mm, direction; `None`: refused) with the f64
/// reference (`quatarm_ref::forward::forward`, exact gravity) at the same counts and
/// temperature.
pub fn accuracy(
    arm: &Arm,
    readings: &[Reading],
    results: impl IntoIterator<Item = Option<[f64; 6]>>,
) -> Accuracy {
    let mut a = Accuracy::default();
    let mut sq = 0.0;
    for (r, got) in readings.iter().zip(results) {
        let Some(g) = got else {
            a.refused += 1;
            continue;
        };
        let theta = arm.counts_to_rad(r.counts.as_slice());
        let pose = quatarm_ref::forward::forward(arm, &theta, f64::from(r.temp_mc) / 1000.0);
        let tip = (Vector3::new(g[0], g[1], g[2]) - pose.p).norm() * 1000.0;
        let dir = (Vector3::new(g[3], g[4], g[5]) - pose.n).norm();
        a.tip_max_um = a.tip_max_um.max(tip);
        a.dir_max = a.dir_max.max(dir);
        sq += tip * tip;
        a.points += 1;
    }
    if a.points > 0 {
        a.tip_rms_um = (sq / a.points as f64).sqrt();
    }
    a
}

/// One measured C chain.
#[derive(Debug)]
pub struct CRow {
    /// Which.
    pub chain: CChain,
    /// Instructions a point.
    pub instructions: f64,
    /// Flash of the image (every loadable byte) without the readings it carries.
    pub flash: u64,
    /// Bytes of `chain_eval` (with what the compiler inlined into it).
    pub code: u64,
    /// Against the reference.
    pub accuracy: Accuracy,
}

/// Why the C rows are missing, or them.
pub enum Outcome {
    /// Every chain measured.
    Measured(Vec<CRow>),
    /// Not measured (no compiler, or a calibration the C chains do not take): the reason.
    Skipped(String),
}

/// The sizes that matter of an image: (flash without the readings, `chain_eval`'s bytes).
fn flash_and_code(elf: &Path) -> Result<(u64, u64)> {
    let (flash, _) = crate::bench::sizes(elf)?;
    let data = std::fs::read(elf).with_context(|| format!("reading {}", elf.display()))?;
    let file = object::File::parse(&*data)?;
    let size_of = |name: &str| {
        file.symbols()
            .find(|s| s.name() == Ok(name))
            .map(|s| s.size())
            .with_context(|| format!("{}: no symbol `{name}`", elf.display()))
    };
    let readings = size_of("reading_counts")? + size_of("reading_temp_mc")?;
    Ok((flash - readings, size_of("chain_eval")?))
}

/// Generates the headers into `gen` from `arm` and `readings`.
pub fn write_headers(arm: &Arm, source: &str, readings: &[Reading], gen: &Path) -> Result<()> {
    std::fs::create_dir_all(gen).with_context(|| format!("creating {}", gen.display()))?;
    let cal = header::calibration(arm, source)?;
    let rd = header::readings(readings, arm.dof(), "the recording")?;
    std::fs::write(gen.join("cal.h"), cal)?;
    std::fs::write(gen.join("readings.h"), rd)?;
    Ok(())
}

/// Builds and runs `chains` on `readings` with `arm`'s calibration, headers and images in
/// `gen`; the skip reason where arm-none-eabi-gcc is not found.
pub fn measure(
    arm: &Arm,
    source: &str,
    readings: &[Reading],
    chains: &[CChain],
    gen: &Path,
) -> Result<Outcome> {
    measure_with(image::gcc(), arm, source, readings, chains, gen)
}

/// [`measure`] with the compiler given (`None`: not found).
fn measure_with(
    gcc: Option<std::path::PathBuf>,
    arm: &Arm,
    source: &str,
    readings: &[Reading],
    chains: &[CChain],
    gen: &Path,
) -> Result<Outcome> {
    let Some(gcc) = gcc else {
        return Ok(Outcome::Skipped(format!(
            "C baselines skipped: {} not found (`cargo xtask setup`, as root, installs gcc-arm-none-eabi and libnewlib-arm-none-eabi)",
            image::GCC
        )));
    };
    if let Err(e) = header::calibration(arm, source) {
        return Ok(Outcome::Skipped(format!("C baselines skipped: {e:#}")));
    }
    write_headers(arm, source, readings, gen)?;
    let mut rows = Vec::new();
    for &chain in chains {
        let elf = image::build(&gcc, chain, gen)?;
        let log = image::run(&elf)?;
        if log.points.len() != readings.len() {
            anyhow::bail!(
                "C chain {}: {} results for {} readings",
                chain.file(),
                log.points.len(),
                readings.len()
            );
        }
        let results = log.points.iter().map(|p| p.map(|v| v.map(f64::from)));
        let (flash, code) = flash_and_code(&elf)?;
        rows.push(CRow {
            chain,
            instructions: log.instructions,
            flash,
            code,
            accuracy: accuracy(arm, readings, results),
        });
    }
    Ok(Outcome::Measured(rows))
}

#[cfg(test)]
mod tests {
    use super::*;
    use host_tests::e2e::{default_calibration_path, default_recording_path};

    /// The C sources build with arm-none-eabi-gcc and each chain agrees with the f64
    /// reference on the first 20 recorded readings (under QEMU, seconds). Without the
    /// compiler or QEMU this test checks nothing and says so on stderr.
    #[test]
    fn c_chains_build_and_agree_with_the_reference() {
        let missing: Vec<&str> = [
            (image::gcc().is_none(), image::GCC),
            (
                !std::process::Command::new("qemu-system-arm")
                    .arg("--version")
                    .output()
                    .is_ok_and(|o| o.status.success()),
                "qemu-system-arm",
            ),
        ]
        .into_iter()
        .filter_map(|(m, n)| m.then_some(n))
        .collect();
        if !missing.is_empty() {
            eprintln!(
                "C BASELINES NOT TESTED: {} not found; this test checked nothing",
                missing.join(" and ")
            );
            return;
        }
        let path = default_calibration_path();
        let arm = quatarm_ref::calfile::read(&path).unwrap().arm;
        let readings: Vec<Reading> = host_tests::recording::read(&default_recording_path())
            .unwrap()
            .into_iter()
            .take(20)
            .collect();
        let gen = tempdir();
        let Outcome::Measured(rows) =
            measure(&arm, "the test", &readings, &CChain::ALL, gen.path()).unwrap()
        else {
            panic!("the shipped calibration is one the C chains take");
        };
        for r in &rows {
            eprintln!(
                "{:?}: {:.0} instructions a point, {:?}",
                r.chain, r.instructions, r.accuracy
            );
            assert_eq!(r.accuracy.points, 20, "{:?} refused a reading", r.chain);
            if r.chain == CChain::DhGeometry {
                // Not the model: the harmonics, gravity and expansion it leaves out move the
                // tip by tens of µm, but the geometry puts it within a millimetre.
                assert!(
                    (10.0..1000.0).contains(&r.accuracy.tip_max_um),
                    "{:?}",
                    r.accuracy
                );
                continue;
            }
            // f32 over a 1.5 m arm: the C chains were within 0.4 µm; the sinf one
            // rounds its angles in float radians, up to ~1 µm.
            let bound = if r.chain == CChain::DhSinf { 3.0 } else { 1.0 };
            assert!(
                r.accuracy.tip_max_um < bound,
                "{:?}: {:?}",
                r.chain,
                r.accuracy
            );
            assert!(r.accuracy.dir_max < 2e-6, "{:?}: {:?}", r.chain, r.accuracy);
            assert!(r.instructions > 100.0, "{:?}: {}", r.chain, r.instructions);
        }
    }

    fn tempdir() -> tempfile::TempDir {
        tempfile::tempdir().unwrap()
    }

    /// Without the compiler nothing is built or run, and the table says the C rows were
    /// skipped, with no number in their place.
    #[test]
    fn without_the_compiler_the_c_rows_are_skipped_not_passed() {
        let gen = tempdir();
        let arm = Arm::default6();
        let out = measure_with(None, &arm, "default6", &[], &CChain::ALL, gen.path()).unwrap();
        let Outcome::Skipped(why) = &out else {
            panic!("measured without a compiler");
        };
        assert!(
            why.starts_with("C baselines skipped: arm-none-eabi-gcc not found"),
            "{why}"
        );
        assert!(
            std::fs::read_dir(gen.path()).unwrap().next().is_none(),
            "wrote headers"
        );
        let text = table::render(&[], &out, "gcc", (1, 2), 0);
        assert!(
            text.contains("| C baselines skipped: arm-none-eabi-gcc not found"),
            "{text}"
        );
        assert!(!text.contains("| C, "), "{text}");
    }

    /// An arm the C chains do not model is refused with the file and the joint named.
    #[test]
    fn a_wobble_is_refused_by_name() {
        let path = host_tests::boards::root().join("data/default-6-wobble.toml");
        let arm = quatarm_ref::calfile::read(&path).unwrap().arm;
        let e = header::calibration(&arm, "data/default-6-wobble.toml").unwrap_err();
        assert!(
            e.to_string()
                .starts_with("data/default-6-wobble.toml: joint 1 has an axis wobble"),
            "{e}"
        );
    }

    /// A refused reading is counted as refused, not compared.
    #[test]
    fn a_refused_reading_is_not_compared() {
        let arm = Arm::default6();
        let r = Reading {
            seq: 0,
            counts: quatarm::stream::Counts::new(&[0; 6]).unwrap(),
            temp_mc: 20_000,
            faults: 0,
        };
        let straight_up = Some([0.0, 0.0, 1500.0, 0.0, 0.0, 1.0]);
        let a = accuracy(&arm, &[r, r], [straight_up, None]);
        assert_eq!((a.points, a.refused), (1, 1));
        assert!(a.tip_max_um < 1e-6, "{a:?}");
        let off = Some([0.0, 0.001, 1500.0, 0.0, 0.0, 1.0]);
        let a = accuracy(&arm, &[r], [off]);
        assert!((a.tip_max_um - 1.0).abs() < 1e-9, "{a:?}");
    }
}
