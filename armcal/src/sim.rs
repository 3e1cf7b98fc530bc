//! The virtual arm: measurements of a known ("truth") arm, recorded as an instrument would.
//!
//! A pose is drawn uniformly inside the joint limits (hinges ±170°, swivels a full turn).
//! The ball is where the truth model, every term of the spec included, puts it at the
//! *continuous* joint angles; the file records the angles quantised to encoder counts, as the
//! encoders give them. So quantisation is a small real error of the data (a count of 2^20 per
//! turn is 6 µrad), exactly as on a real arm.
//!
//! - `point`: the ball centre through an unknown rigid instrument frame, with Gaussian noise
//!   on each axis.
//! - `spat`: a fixed point (the ball of a first random pose), then further poses found by a
//!   numeric inverse from random starting poses, so they spread over the redundant joints;
//!   each probing misses the point by the noise, as a ball seats imperfectly in its cone.
//! - `length`: a ball bar of fixed length in random positions, each ball probed from several
//!   poses found the same way.
//!
//! Everything is drawn from one ChaCha generator seeded by the caller: the same seed gives the
//! same file on every machine.

use crate::data::{Dataset, Kind, Row};
use crate::fit::design::groups::{length_group, spat_group, Turns};
use crate::fit::design::poses::{count_angle, limits, random_pose, Limits};
use crate::fit::design::sphere;
use crate::geometry::{frame_matrix, reach};
use crate::rng::{normal, SimRng};
use nalgebra::Vector3;
use quatarm_ref::arm::{Arm, Frame};
use quatarm_ref::forward;
use rand::Rng;
use std::f64::consts::PI;

pub mod protocol;

/// The touch directions of a `sphere` group of `n` points (upper hemisphere).
pub fn sphere_directions(n: usize) -> Vec<Vector3<f64>> {
    sphere::directions(n, 0.0)
}

/// The arm with random geometric errors: zero offsets and tilts with standard deviation
/// `angle` (rad), link and probe errors with `length` (mm) per component. Nominal values stay.
pub fn perturb(arm: &Arm, angle: f64, length: f64, rng: &mut SimRng) -> Arm {
    let mut a = arm.clone();
    for j in &mut a.joints {
        j.zero_offset += angle * normal(rng);
        j.tilt[0] += angle * normal(rng);
        j.tilt[1] += angle * normal(rng);
        for c in 0..3 {
            j.link_error[c] += length * normal(rng);
        }
    }
    for c in 0..3 {
        a.probe.error[c] += length * normal(rng);
    }
    a
}

/// A rotation drawn uniformly (Shoemake) and a translation within ±2 m.
pub fn random_frame(rng: &mut SimRng) -> Frame {
    let (u1, u2, u3): (f64, f64, f64) = (rng.gen(), rng.gen(), rng.gen());
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    let q = [
        a * (2.0 * PI * u2).sin(),
        a * (2.0 * PI * u2).cos(),
        b * (2.0 * PI * u3).sin(),
        b * (2.0 * PI * u3).cos(),
    ];
    Frame {
        rotation: q,
        translation: [
            rng.gen_range(-2000.0..2000.0),
            rng.gen_range(-2000.0..2000.0),
            rng.gen_range(-2000.0..2000.0),
        ],
    }
}

/// Readings of a noisy encoder: the continuous angle plus Gaussian noise of `noise_counts`
/// counts (standard deviation), then rounded to a whole count. The reading's error is the
/// noise plus the quantisation, standard deviation √(noise² + 1/12) counts. With no noise
/// the generator is not drawn from, so noise-free files stay what they were.
pub fn read_encoders(arm: &Arm, theta: &[f64], noise_counts: f64, rng: &mut SimRng) -> Vec<f64> {
    theta
        .iter()
        .zip(&arm.joints)
        .map(|(t, j)| {
            let z = if noise_counts > 0.0 {
                noise_counts * normal(rng)
            } else {
                0.0
            };
            count_angle(*t, j.encoder_counts, z)
        })
        .collect()
}

/// Which instrument frame `point` data are recorded in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameChoice {
    /// A random rigid transform (the unknown frame of a laser tracker).
    Random,
    /// The arm's base frame.
    Identity,
}

/// What to simulate.
#[derive(Clone, Debug)]
pub struct Options {
    /// Kind of data.
    pub kind: Kind,
    /// Rows to record.
    pub count: usize,
    /// Noise per axis (mm, standard deviation).
    pub noise_mm: f64,
    /// Temperature range (°C): each reading uniform in it; `None` is 20 °C and no column.
    pub temp: Option<(f64, f64)>,
    /// Instrument frame of `point` data.
    pub frame: FrameChoice,
    /// Rows per `spat` or `length` group.
    pub group_size: usize,
    /// Ball-bar length (mm); `None` is 40 % of the arm's reach.
    pub bar_mm: Option<f64>,
    /// Test sphere diameter D for `sphere` data (mm).
    pub sphere_mm: f64,
    /// `sphere` data: articulations per group (L_Dia: 5), `None` for one (P_Size, P_Form).
    pub articulations: Option<usize>,
    /// Encoder noise before quantisation (counts, standard deviation; [`read_encoders`]).
    pub encoder_noise_counts: f64,
    /// Error of the temperature sensor (°C, standard deviation): the recorded `temp_c` is the
    /// arm's true temperature plus this noise.
    pub temp_noise_c: f64,
    /// Links bending under their own weight (`point` data only): an effect of the truth that
    /// the model and the diagnosis' vocabulary do not hold, to test what a diagnosis says
    /// about what it cannot name.
    pub sag: Vec<Sag>,
    /// The ids of the probes rows are taken with, in turn (row by row; a `sphere` group
    /// whole): a `probe` column. Empty: the arm's first probe, and no column.
    pub probes: Vec<u8>,
}

/// A link that sags under its own weight, on the truth side only: the end of link `link`
/// (0-based: from joint `link`'s origin to the next joint's, or the probe's tip after the
/// last joint) drops by `mm` · cos ε, ε the link's elevation above the horizontal (a
/// cantilever's tip deflection under its own weight is proportional to the weight's moment,
/// which is proportional to the link's horizontal reach), and everything beyond the link
/// moves down with it. No calibration term moves the ball this way: a gravity compliance
/// turns a joint by its moment, and this translates the rest of the chain straight down.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sag {
    /// Link, 0-based (`dof`: the probe).
    pub link: usize,
    /// Deflection of its end when horizontal (mm).
    pub mm: f64,
}

impl Sag {
    /// The ball's displacement (mm, base frame) at true angles `theta` and temperature `tc`.
    pub fn displacement(&self, truth: &Arm, theta: &[f64], tc: f64) -> Vector3<f64> {
        let c = forward::evaluate(truth, theta, tc);
        let n = truth.dof();
        let (a, b) = match self.link {
            k if k < n => (c.origins[k], c.origins[k + 1]),
            _ => (c.origins[n], c.p),
        };
        let d = b - a;
        let horizontal = d.x.hypot(d.y);
        let len = d.norm();
        if len > 0.0 {
            -Vector3::z() * self.mm * horizontal / len
        } else {
            Vector3::zeros()
        }
    }
}

impl Options {
    /// Defaults for a kind and count: 5 µm noise, 20 °C, random frame, groups of 8 (spat) or
    /// 10 (length, 5 per ball).
    pub fn new(kind: Kind, count: usize) -> Options {
        Options {
            kind,
            count,
            noise_mm: 0.005,
            temp: None,
            frame: FrameChoice::Random,
            group_size: match kind {
                Kind::Length => 10,
                Kind::Sphere => 25,
                _ => 8,
            },
            bar_mm: None,
            sphere_mm: 25.0,
            articulations: None,
            encoder_noise_counts: 0.0,
            temp_noise_c: 0.0,
            sag: Vec::new(),
            probes: Vec::new(),
        }
    }
}

/// Simulated data and the frame the `point` rows were recorded in.
#[derive(Clone, Debug)]
pub struct Simulated {
    /// The rows.
    pub data: Dataset,
    /// The instrument frame (identity for spat and length data).
    pub frame: Frame,
}

/// Why a simulation made no data.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// `--count 0`.
    #[error("nothing to simulate: --count is 0")]
    NoRows,
    /// A spat or length group needs two rows.
    #[error("{0} data need two rows or more")]
    TooFewRows(&'static str),
    /// No pose tried puts the probe on the group's target.
    #[error("could not place group {0}: the arm does not reach it from any pose tried")]
    Unreachable(i64),
    /// A sagging link that the arm does not have.
    #[error("sag of link {0}: the arm has links 1..={1} and the probe ({1} + 1)")]
    SagLink(usize, usize),
    /// Sag is simulated on `point` data only.
    #[error("a sagging link is simulated on point data only, not {0}")]
    SagNeedsPoints(&'static str),
    /// A probe the arm does not carry.
    #[error("probe {0}: the arm has no probe of that id")]
    NoProbe(u8),
    /// The rows made do not form valid data (the reader's own checks).
    #[error(transparent)]
    Data(#[from] crate::data::DataError),
}

/// Records `opts.count` rows of the truth arm: the rows at the continuous true angles and
/// temperatures first (`point_rows`, `group_rows`), then what the instruments read of
/// them (`read_instruments`).
pub fn simulate(truth: &Arm, opts: &Options, rng: &mut SimRng) -> Result<Simulated, SimError> {
    check_options(truth, opts)?;
    let lim = limits(truth);
    let turns = Turns::new(truth, &opts.probes).map_err(SimError::NoProbe)?;
    let identity = Frame {
        rotation: [1.0, 0.0, 0.0, 0.0],
        translation: [0.0; 3],
    };
    let frame = match (opts.kind, opts.frame) {
        (Kind::Point, FrameChoice::Random) => random_frame(rng),
        _ => identity,
    };
    let mut temp = |rng: &mut SimRng| match opts.temp {
        Some((lo, hi)) if hi > lo => rng.gen_range(lo..hi),
        Some((lo, _)) => lo,
        None => forward::REFERENCE_TEMP_C,
    };
    let mut rows = match opts.kind {
        Kind::Point => point_rows(&turns, &lim, &frame, opts, &mut temp, rng),
        Kind::Spat | Kind::Length | Kind::Sphere => {
            group_rows(truth, &turns, &lim, opts, &mut temp, rng)?
        }
    };
    read_instruments(truth, &mut rows, opts, rng);
    let data = Dataset::from_rows(rows, truth.dof(), opts.temp.is_some(), "(simulated)")?;
    Ok(Simulated { data, frame })
}

/// Refuses options that cannot make a file: no rows, a sagging link the arm lacks or on
/// other than `point` data, a group kind with fewer than two rows.
fn check_options(truth: &Arm, opts: &Options) -> Result<(), SimError> {
    if opts.count == 0 {
        return Err(SimError::NoRows);
    }
    if let Some(s) = opts.sag.iter().find(|s| s.link > truth.dof()) {
        return Err(SimError::SagLink(s.link + 1, truth.dof()));
    }
    if opts.kind != Kind::Point && !opts.sag.is_empty() {
        return Err(SimError::SagNeedsPoints(opts.kind.name()));
    }
    if opts.kind != Kind::Point && opts.count < 2 {
        return Err(SimError::TooFewRows(opts.kind.name()));
    }
    Ok(())
}

/// `point` rows: the ball at random poses (sag added), seen through the instrument `frame`
/// with Gaussian noise on each axis.
fn point_rows(
    turns: &Turns,
    lim: &Limits,
    frame: &Frame,
    opts: &Options,
    temp: &mut dyn FnMut(&mut SimRng) -> f64,
    rng: &mut SimRng,
) -> Vec<Row> {
    let r = frame_matrix(frame);
    let t = Vector3::from(frame.translation);
    let mut rows = Vec::with_capacity(opts.count);
    for i in 0..opts.count {
        let (probe, mounted) = turns.at(i);
        let th = random_pose(lim, rng);
        let tc = temp(rng);
        let p = forward::forward(mounted, &th, tc).p
            + opts
                .sag
                .iter()
                .map(|s| s.displacement(mounted, &th, tc))
                .sum::<Vector3<f64>>();
        let noise = Vector3::new(normal(rng), normal(rng), normal(rng)) * opts.noise_mm;
        let x = r * p + t + noise;
        rows.push(Row::point(1, th, [x.x, x.y, x.z], tc, probe));
    }
    rows
}

/// `spat`, `length` or `sphere` rows in groups of about `opts.group_size`, each group made by
/// the design's generator of its kind; a group no pose reaches is an error naming it.
fn group_rows(
    truth: &Arm,
    turns: &Turns,
    lim: &Limits,
    opts: &Options,
    temp: &mut dyn FnMut(&mut SimRng) -> f64,
    rng: &mut SimRng,
) -> Result<Vec<Row>, SimError> {
    let sizes = group_sizes(opts.count, opts.group_size.max(2));
    let bar = opts.bar_mm.unwrap_or(0.4 * reach(truth));
    let mut rows = Vec::with_capacity(opts.count);
    for (g, size) in sizes.into_iter().enumerate() {
        let group = g as i64 + 1;
        let made = match opts.kind {
            Kind::Spat => spat_group(turns, lim, size, opts.noise_mm, group, temp, rng),
            Kind::Sphere => sphere::group(
                turns.at(g),
                lim,
                &sphere::Test {
                    points: size,
                    diameter_mm: opts.sphere_mm,
                    articulations: opts.articulations,
                    noise_mm: opts.noise_mm,
                },
                group,
                temp,
                rng,
            ),
            _ => length_group(turns, lim, size, bar, opts.noise_mm, group, temp, rng),
        };
        rows.extend(made.ok_or(SimError::Unreachable(group))?);
    }
    Ok(rows)
}

/// What the instruments read of rows made at the continuous true angles and temperatures:
/// the angles through the encoders (quantised, with their noise), the thermometer with its.
fn read_instruments(truth: &Arm, rows: &mut [Row], opts: &Options, rng: &mut SimRng) {
    for r in rows {
        r.theta = read_encoders(truth, &r.theta, opts.encoder_noise_counts, rng);
        if opts.temp_noise_c > 0.0 {
            r.temp_c += opts.temp_noise_c * normal(rng);
        }
    }
}

/// Splits `count` rows into groups of about `size`, none smaller than two.
fn group_sizes(count: usize, size: usize) -> Vec<usize> {
    let groups = count.div_ceil(size).max(1);
    let groups = groups.min(count / 2).max(1);
    let base = count / groups;
    let extra = count % groups;
    (0..groups).map(|g| base + usize::from(g < extra)).collect()
}

#[cfg(test)]
mod tests {
    use crate::fit::design::poses::quantise;

    #[test]
    fn encoder_noise_is_noise_plus_quantisation() {
        let arm = Arm::default6();
        let mut r = rng(4);
        let lim = limits(&arm);
        let per_count = 2.0 * PI / f64::from(arm.joints[0].encoder_counts);
        let (mut ss, mut n) = (0.0, 0);
        for _ in 0..4000 {
            let th = random_pose(&lim, &mut r);
            assert_eq!(read_encoders(&arm, &th, 0.0, &mut r), quantise(&arm, &th));
            for (a, b) in read_encoders(&arm, &th, 1.0, &mut r).iter().zip(&th) {
                let mut d = a - b;
                d -= 2.0 * PI * (d / (2.0 * PI)).round();
                ss += (d / per_count).powi(2);
                n += 1;
            }
        }
        let sd = (ss / n as f64).sqrt();
        // √(1 + 1/12) = 1.0408; 24,000 values give ±0.5 %.
        assert!((sd - 1.0408).abs() < 0.02, "{sd}");
    }
    use super::*;
    use crate::rng::rng;

    #[test]
    fn same_seed_same_data() {
        let truth = perturb(&Arm::default6(), 3e-4, 0.3, &mut rng(1));
        let o = Options::new(Kind::Point, 20);
        let a = simulate(&truth, &o, &mut rng(7)).unwrap();
        let b = simulate(&truth, &o, &mut rng(7)).unwrap();
        assert_eq!(a.data, b.data);
        let c = simulate(&truth, &o, &mut rng(8)).unwrap();
        assert_ne!(a.data, c.data);
    }

    #[test]
    fn readings_are_whole_counts() {
        let truth = Arm::default6();
        let s = simulate(&truth, &Options::new(Kind::Spat, 16), &mut rng(3)).unwrap();
        for r in &s.data.rows {
            for t in &r.theta {
                let c = t * f64::from(1u32 << 20) / (2.0 * PI);
                assert!((c - c.round()).abs() < 1e-6, "{c}");
            }
        }
    }

    #[test]
    fn spat_rows_probe_one_point() {
        let truth = perturb(&Arm::default6(), 3e-4, 0.3, &mut rng(2));
        let mut o = Options::new(Kind::Spat, 24);
        o.noise_mm = 0.0;
        let s = simulate(&truth, &o, &mut rng(4)).unwrap();
        let layout = s.data.layout();
        assert_eq!(layout.spat.len(), 3);
        for g in &layout.spat {
            let ps: Vec<Vector3<f64>> = g
                .rows
                .iter()
                .map(|&i| forward::forward(&truth, &s.data.rows[i].theta, 20.0).p)
                .collect();
            let spread = ps.iter().map(|p| (p - ps[0]).norm()).fold(0.0, f64::max);
            // Only quantisation separates them: a few µm at most.
            assert!(spread < 0.02, "{spread}");
            let angles = g
                .rows
                .iter()
                .map(|&i| (s.data.rows[i].theta[1] - s.data.rows[g.rows[0]].theta[1]).abs())
                .fold(0.0, f64::max);
            assert!(angles > 0.1, "poses should differ: {angles}");
        }
    }

    #[test]
    fn length_groups_have_the_bar_length() {
        let truth = Arm::default6();
        let mut o = Options::new(Kind::Length, 20);
        o.noise_mm = 0.0;
        let s = simulate(&truth, &o, &mut rng(5)).unwrap();
        for g in s.data.layout().length {
            let c = |idx: &[usize]| {
                idx.iter()
                    .map(|&i| forward::forward(&truth, &s.data.rows[i].theta, 20.0).p)
                    .sum::<Vector3<f64>>()
                    / idx.len() as f64
            };
            let d = (c(&g.a) - c(&g.b)).norm();
            assert!((d - g.length_mm).abs() < 0.01, "{d} vs {}", g.length_mm);
            assert!((g.length_mm - 0.4 * 1500.0).abs() < 1e-9);
        }
    }

    #[test]
    fn point_rows_go_through_the_frame() {
        let truth = Arm::default6();
        let mut o = Options::new(Kind::Point, 10);
        o.noise_mm = 0.0;
        let s = simulate(&truth, &o, &mut rng(6)).unwrap();
        let r = frame_matrix(&s.frame);
        let t = Vector3::from(s.frame.translation);
        for row in &s.data.rows {
            let p = forward::forward(&truth, &row.theta, 20.0).p;
            let x = Vector3::from(row.xyz.unwrap());
            assert!((r * p + t - x).norm() < 0.02);
        }
    }
}
