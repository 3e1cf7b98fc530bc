//! `armcal simulate`: measurements of a virtual arm (`point`, `spat` or `length` data).

use super::args::ArgError;
use anyhow::bail;
use armcal::data::Kind;
use armcal::sim::{self, FrameChoice};
use quatarm_ref::arm::Arm;
use std::path::{Path, PathBuf};

/// Arguments of `armcal simulate`.
#[derive(clap::Args)]
pub struct Args {
    /// The truth: a calibration file with every term the virtual arm has.
    #[arg(long)]
    truth: PathBuf,
    /// The nominal arm the data are meant for; checked to have the truth's joints and axes.
    #[arg(long)]
    arm: Option<PathBuf>,
    /// Kind of data: point, spat, length or sphere (a test sphere's surface, 25 points per
    /// group over the upper hemisphere; `--articulations 5` for an L_Dia group).
    #[arg(long, value_parser = parse_kind, required_unless_present = "test")]
    kind: Option<Kind>,
    /// Rows to record (at most 1,000,000: the whole file is made and checked in memory
    /// before it is written).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=MAX_ROWS), required_unless_present = "test")]
    count: Option<u64>,
    /// A complete test set in place of one kind: `iso10360-12` (two spheres of 25 points, a
    /// 5×5 articulation test, ball bars of three lengths in five positions each, three SPAT
    /// cones; the positions are documented in `armcal::sim::protocol`).
    #[arg(long, value_parser = ["iso10360-12"], conflicts_with_all = ["kind", "count", "group_size", "articulations"])]
    test: Option<String>,
    /// Seed of the random generator: the same seed gives the same file.
    #[arg(long)]
    seed: u64,
    /// Noise per axis (µm, standard deviation): the instrument's for point data, the ball's
    /// seating for spat and length data.
    #[arg(long, default_value_t = 5.0, value_parser = super::args::non_negative)]
    noise_um: f64,
    /// Arm temperature range (°C), e.g. 16..28: each reading is drawn uniformly in it and
    /// recorded in `temp_c`.
    #[arg(long, value_parser = parse_range)]
    temp: Option<(f64, f64)>,
    /// Instrument frame of point data: random (an unknown rigid transform) or identity.
    #[arg(long, default_value = "random", value_parser = parse_frame)]
    frame: FrameChoice,
    /// Rows per spat group, bar position or sphere (default 8 for spat, 10 for length, 25 for
    /// sphere).
    #[arg(long)]
    group_size: Option<usize>,
    /// Ball-bar length for length data (mm; default 40 % of the arm's reach).
    #[arg(long, value_parser = parse_bar)]
    bar_mm: Option<f64>,
    /// Test sphere diameter for sphere data (mm).
    #[arg(long, default_value_t = 25.0, value_parser = parse_bar)]
    sphere_mm: f64,
    /// Sphere data: articulations per group (L_Dia: 5 sets of 5 points, each set in one arm
    /// posture); absent: one set (P_Size, P_Form).
    #[arg(long, value_parser = clap::value_parser!(u32).range(2..=25))]
    articulations: Option<u32>,
    /// Encoder noise (counts, standard deviation) added to the continuous true angle before
    /// it is quantised to a whole count; 0 is quantisation alone.
    #[arg(long, default_value_t = 0.0, value_parser = super::args::non_negative)]
    encoder_noise_counts: f64,
    /// Error of the temperature sensor (°C, standard deviation) added to the recorded
    /// `temp_c` (with `--temp`; the arm is at the true temperature).
    #[arg(long, default_value_t = 0.0, requires = "temp", value_parser = super::args::non_negative)]
    temp_noise_c: f64,
    /// A link of the truth that sags under its own weight, `LINK:UM` (LINK 1-based or
    /// `probe`): its end drops by UM µm times the cosine of its elevation, and the rest of the
    /// chain moves down with it. No calibration term holds this effect: it tests what a
    /// diagnosis says about what it cannot name. Point data only; repeatable.
    #[arg(long, value_name = "LINK:UM", value_parser = parse_sag)]
    sag: Vec<(String, f64)>,
    /// Take the rows with these probes of the truth's (their ids, in turn: row by row, a
    /// sphere group whole) and write a `probe` column; without it every row is the first
    /// probe's and there is no column.
    #[arg(long, value_name = "ID,ID,...", value_delimiter = ',')]
    probes: Vec<u8>,
    /// Output file (CSV of `spec/measured-data.md`).
    #[arg(short, long)]
    output: PathBuf,
}

/// Most rows one file gets: a calibration needs thousands, and the file is made whole in
/// memory (a count of 10^11 was a 10 TB allocation).
const MAX_ROWS: u64 = 1_000_000;

fn parse_bar(s: &str) -> Result<f64, ArgError> {
    let value = super::args::positive(s)?;
    let max = armcal::limits::COORDINATE_MM;
    if value > max {
        return Err(ArgError::TooLong { value, max });
    }
    Ok(value)
}

/// `LINK:UM` of `--sag`: the link as written (checked against the arm later) and the size.
fn parse_sag(s: &str) -> Result<(String, f64), String> {
    let (link, um) = s
        .split_once(':')
        .ok_or_else(|| format!("`{s}`: give LINK:UM, e.g. `2:30` (link 2, 30 µm)"))?;
    let um: f64 = um
        .parse()
        .ok()
        .filter(|v: &f64| v.is_finite() && v.abs() <= 1e4)
        .ok_or_else(|| format!("`{s}`: `{um}` is not a size in µm (at most 10000)"))?;
    Ok((link.to_string(), um))
}

fn parse_kind(s: &str) -> Result<Kind, ArgError> {
    match s {
        "point" => Ok(Kind::Point),
        "spat" => Ok(Kind::Spat),
        "length" => Ok(Kind::Length),
        "sphere" => Ok(Kind::Sphere),
        _ => Err(ArgError::NotOneOf {
            given: s.to_string(),
            what: "a kind",
            choices: "point, spat, length or sphere",
        }),
    }
}

fn parse_frame(s: &str) -> Result<FrameChoice, ArgError> {
    match s {
        "random" => Ok(FrameChoice::Random),
        "identity" => Ok(FrameChoice::Identity),
        _ => Err(ArgError::NotOneOf {
            given: s.to_string(),
            what: "a frame",
            choices: "random or identity",
        }),
    }
}

fn parse_range(s: &str) -> Result<(f64, f64), ArgError> {
    let bad = || ArgError::NotRange(s.to_string());
    let (a, b) = s.split_once("..").ok_or_else(bad)?;
    let lo: f64 = a.trim().parse().map_err(|_| bad())?;
    let hi: f64 = b.trim().parse().map_err(|_| bad())?;
    if !(lo.is_finite() && hi.is_finite()) || hi < lo {
        return Err(bad());
    }
    let r = armcal::limits::temp_range_c();
    if !(r.contains(&lo) && r.contains(&hi)) {
        return Err(ArgError::TemperatureOutside {
            given: s.to_string(),
            lo: *r.start(),
            hi: *r.end(),
        });
    }
    Ok((lo, hi))
}

/// The noise options, when set (a file made without them reads as it always did).
fn noise_note(encoder: f64, temp: f64) -> String {
    let mut s = String::new();
    if encoder > 0.0 {
        s += &format!(", encoder noise {encoder} counts");
    }
    if temp > 0.0 {
        s += &format!(", temperature sensor noise {temp} °C");
    }
    s
}

/// Runs the subcommand: the truth (and the nominal arm, if given) read and checked, the
/// rows simulated, then the file written only if its text reads back.
pub fn run(a: Args) -> anyhow::Result<()> {
    let mut inputs = vec![(a.truth.as_path(), "truth")];
    if let Some(arm) = &a.arm {
        inputs.push((arm.as_path(), "nominal arm"));
    }
    armcal::output::check(&[(&a.output, "simulated data")], &inputs)?;
    let truth = armcal::load::arm(&a.truth)?;
    if let Some(path) = &a.arm {
        same_arm(path, &armcal::load::arm(path)?, &a.truth, &truth)?;
    }
    let kind = a.kind.unwrap_or(Kind::Point);
    let opts = options(&a, kind, &truth)?;
    let mut rng = armcal::rng::rng(a.seed);
    let s = match a.test {
        Some(_) => sim::protocol::iso_10360_12(&truth, &opts, &mut rng)?,
        None => sim::simulate(&truth, &opts, &mut rng)?,
    };
    let what = match &a.test {
        Some(t) => format!("test set {t}"),
        None => format!("kind {}", kind.name()),
    };
    let comments = comments(&a, &s, &what);
    let refs: Vec<&str> = comments.iter().map(String::as_str).collect();
    let text = s.data.to_csv(&refs);
    // What is written must read back: a truth or a bar whose rows the reader refuses is
    // refused here, with the reader's reason, instead of writing a file nothing can use.
    let name = a.output.display().to_string();
    armcal::data::parse(&text, &name, truth.dof())
        .map_err(|e| anyhow::anyhow!("the simulated rows would not read back: {e}"))?;
    let mut files = armcal::output::Staged::guarding(&inputs);
    files.write(&a.output, text.as_bytes())?;
    files.commit()?;
    eprintln!(
        "armcal: wrote {} ({} rows, {what})",
        a.output.display(),
        s.data.rows.len(),
    );
    Ok(())
}

/// Refuses a nominal arm (`path`) that is not the truth's arm: another joint count, or a
/// joint of another axis or link.
fn same_arm(path: &Path, nominal: &Arm, truth_path: &Path, truth: &Arm) -> anyhow::Result<()> {
    if nominal.dof() != truth.dof() {
        bail!(
            "{}: {} joints, the truth {} has {}",
            path.display(),
            nominal.dof(),
            truth_path.display(),
            truth.dof()
        );
    }
    for (k, (n, t)) in nominal.joints.iter().zip(&truth.joints).enumerate() {
        if n.axis != t.axis || n.link != t.link {
            bail!(
                "{}: joint {} has axis {} and link {:?}, the truth {} and {:?}: not the same arm",
                path.display(),
                k + 1,
                n.axis.name(),
                n.link,
                t.axis.name(),
                t.link
            );
        }
    }
    Ok(())
}

/// The simulation's options from the arguments (`--group-size` and `--sag` checked against
/// the truth here).
fn options(a: &Args, kind: Kind, truth: &Arm) -> anyhow::Result<sim::Options> {
    let mut opts = sim::Options::new(kind, a.count.unwrap_or(1) as usize);
    opts.noise_mm = a.noise_um * 1e-3;
    opts.temp = a.temp;
    opts.frame = a.frame;
    if let Some(g) = a.group_size {
        if g < 2 {
            bail!("--group-size must be 2 or more");
        }
        opts.group_size = g;
    }
    opts.bar_mm = a.bar_mm;
    opts.sphere_mm = a.sphere_mm;
    opts.articulations = a.articulations.map(|k| k as usize);
    opts.encoder_noise_counts = a.encoder_noise_counts;
    opts.temp_noise_c = a.temp_noise_c;
    opts.probes = a.probes.clone();
    for (link, um) in &a.sag {
        opts.sag.push(sim::Sag {
            link: sag_link(link, *um, truth.dof())?,
            mm: um * 1e-3,
        });
    }
    Ok(opts)
}

/// The 0-based link of `--sag LINK:UM` on an arm of `dof` joints (`probe`: the last).
fn sag_link(link: &str, um: f64, dof: usize) -> anyhow::Result<usize> {
    Ok(match link {
        "probe" => dof,
        j => match j.parse::<usize>() {
            Ok(k) if (1..=dof).contains(&k) => k - 1,
            _ => {
                bail!("--sag {link}:{um}: `{link}` is not a link of this arm (1..={dof} or probe)")
            }
        },
    })
}

/// The file's comment lines: how it was made (truth, `what`, rows, seed, noise) and the
/// instrument frame drawn, so that a reader can check a calibration against it.
fn comments(a: &Args, s: &sim::Simulated, what: &str) -> [String; 2] {
    let f = &s.frame;
    [
        format!(
            "simulated by armcal simulate: truth {}, {what}, {} rows, seed {}, noise {} µm per axis{}",
            a.truth.display(),
            s.data.rows.len(),
            a.seed,
            a.noise_um,
            noise_note(a.encoder_noise_counts, a.temp_noise_c)
        ),
        format!(
            "instrument frame (x_ref = R p + t): rotation (w, x, y, z) = [{:?}, {:?}, {:?}, {:?}], translation = [{:?}, {:?}, {:?}] mm",
            f.rotation[0], f.rotation[1], f.rotation[2], f.rotation[3],
            f.translation[0], f.translation[1], f.translation[2]
        ),
    ]
}
