//! How closely the firmware paths follow the f64 reference: random poses of an arm, each
//! evaluated by the reference (`quatarm_ref::forward`, exact gravity) and by the four firmware
//! paths (quaternion and matrix chains, f32 and fixed point) on the binary table a board would
//! load. Also the arm used for it: `default-6` with a calibration that uses every term.

use nalgebra::Vector3;
use quatarm::{Arithmetic, Chain, ChainError, Fixed, MatrixChain, Point, Table, F32};
use quatarm_ref::arm::Wobble;
use quatarm_ref::{Arm, Harmonic};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The default seed of the benchmark.
pub const SEED: u64 = 20_260_426;

/// `default-6` with a realistic calibration that uses every term of the model: zero offsets
/// and tilts of a few mrad, link errors up to a millimetre, two encoder harmonics per joint
/// (eccentricity and ellipticity, up to 20"), gravity compliance on the three hinges, thermal
/// expansion of aluminium and carbon-fibre links and a steel probe. Deterministic.
pub fn full_calibration() -> Arm {
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let mut arm = Arm::default6();
    arm.name = Some("default-6-full".into());
    arm.serial = Some("SN-0001".into());
    // Rounded to 1e-7 (rad or mm) so that the file reads cleanly; + 0.0 turns −0 into 0.
    let mut r = |a: f64| (rng.gen_range(-a..a) * 1e7_f64).round() / 1e7 + 0.0;
    // Links 1, 3, 5 (columns and swivels) aluminium, 2, 4, 6 carbon fibre.
    let thermal = [23e-6, 2e-6, 23e-6, 2e-6, 23e-6, 2e-6];
    let gravity = [0.0, 4e-8, 0.0, 3e-8, 0.0, 1e-8];
    for (i, j) in arm.joints.iter_mut().enumerate() {
        j.zero_offset = r(3e-3);
        j.tilt = [r(3e-3), r(3e-3)];
        j.link_error = [r(1.0), r(1.0), r(1.0)];
        j.harmonics = vec![
            Harmonic {
                order: 1,
                sin: r(1e-4),
                cos: r(1e-4),
            },
            Harmonic {
                order: 2,
                sin: r(3e-5),
                cos: r(3e-5),
            },
        ];
        j.gravity = gravity[i];
        j.thermal = thermal[i];
    }
    arm.probe.error = [r(0.3), r(0.3), r(0.5)];
    arm.probe.thermal = 12e-6;
    arm
}

/// `arm` with an axis wobble on every joint (`armcal accuracy --wobble`): joint k's bearing
/// wobbles at order 1 + (k mod 3) and, on the hinges, at order 4 as well, each coefficient
/// up to `size` (rad; real bearings 2e-5–1e-4). Deterministic.
pub fn with_wobble(arm: &Arm, size: f64) -> Arm {
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    let mut arm = arm.clone();
    let mut r = |a: f64| (rng.gen_range(-a..a) * 1e8_f64).round() / 1e8 + 0.0;
    for k in 0..arm.dof() {
        let hinge = arm.is_hinge(k);
        let j = &mut arm.joints[k];
        j.wobble = vec![Wobble {
            order: 1 + (k as u32 % 3),
            alpha: [r(size), r(size)],
            beta: [r(size), r(size)],
        }];
        if hinge {
            j.wobble.push(Wobble {
                order: 4,
                alpha: [r(size / 2.0), r(size / 2.0)],
                beta: [r(size / 2.0), r(size / 2.0)],
            });
        }
    }
    arm.name = arm.name.map(|n| format!("{n}+wobble"));
    arm
}

/// A random reading: counts (hinges within ±170°, swivels anywhere) and a temperature in
/// milli-degrees, 10–35 °C.
pub fn random_reading(rng: &mut impl Rng, arm: &Arm) -> (Vec<u32>, i32) {
    let counts = (0..arm.dof())
        .map(|k| {
            let n = arm.joints[k].encoder_counts;
            if arm.is_hinge(k) {
                let lim = (f64::from(n) * 170.0 / 360.0) as i64;
                let c = rng.gen_range(-lim..=lim);
                c.rem_euclid(i64::from(n)) as u32
            } else {
                rng.gen_range(0..n)
            }
        })
        .collect();
    (counts, rng.gen_range(10_000..=35_000))
}

/// Error statistics of one path.
#[derive(Clone, Copy, Debug, Default)]
pub struct Stats {
    /// Poses.
    pub n: u64,
    /// Largest tip error (µm).
    pub max_um: f64,
    /// Sum of squared tip errors (µm²).
    pub sum_sq_um: f64,
    /// Largest direction error |n − n_ref|.
    pub max_dir: f64,
    /// Sum of squared direction errors.
    pub sum_sq_dir: f64,
}

impl Stats {
    fn add(&mut self, tip_um: f64, dir: f64) {
        self.n += 1;
        self.max_um = self.max_um.max(tip_um);
        self.sum_sq_um += tip_um * tip_um;
        self.max_dir = self.max_dir.max(dir);
        self.sum_sq_dir += dir * dir;
    }
    fn merge(&mut self, o: &Stats) {
        self.n += o.n;
        self.max_um = self.max_um.max(o.max_um);
        self.sum_sq_um += o.sum_sq_um;
        self.max_dir = self.max_dir.max(o.max_dir);
        self.sum_sq_dir += o.sum_sq_dir;
    }
    /// RMS tip error (µm).
    pub fn rms_um(&self) -> f64 {
        (self.sum_sq_um / self.n.max(1) as f64).sqrt()
    }
    /// RMS direction error.
    pub fn rms_dir(&self) -> f64 {
        (self.sum_sq_dir / self.n.max(1) as f64).sqrt()
    }
}

/// The measured paths, in report order.
pub const PATHS: [&str; 5] = [
    "f32 quaternion",
    "fixed quaternion",
    "f32 matrix 3x4",
    "fixed matrix 3x4",
    "f64 first-order gravity",
];

/// Everything [`measure`] found.
#[derive(Clone, Debug, Default)]
pub struct Report {
    /// One entry per [`PATHS`] name.
    pub stats: [Stats; 5],
    /// Why a firmware path (the first four of [`PATHS`]) has no chain for this arm (its
    /// `stats` are then empty).
    pub refused: [Option<ChainError>; 4],
}

fn errors<P: Arithmetic>(pt: &Point<P>, p: &Vector3<f64>, n: &Vector3<f64>) -> (f64, f64) {
    let x = pt.xyz_f64();
    let d = pt.dir_f64();
    let tip = (Vector3::from(x) - p).norm() * 1000.0;
    let dir = (Vector3::from(d) - n).norm();
    (tip, dir)
}

/// The reference with the spec's first-order gravity correction instead of the exact second
/// pass: what the matrix chain computes, in f64.
pub(crate) fn first_order_gravity(
    arm: &Arm,
    theta: &[f64],
    temp_c: f64,
) -> (Vector3<f64>, Vector3<f64>) {
    let c = quatarm_ref::forward::pass(arm, theta, temp_c, &vec![0.0; arm.dof()]);
    let (mut p, mut n) = (c.p, c.n);
    for (k, j) in arm.joints.iter().enumerate() {
        if j.gravity != 0.0 {
            let d = c.p - c.origins[k];
            let e = j.gravity * c.axes[k].dot(&d.cross(&Vector3::z()));
            p += e * c.axes[k].cross(&d);
            n += e * c.axes[k].cross(&c.n);
        }
    }
    (p, n)
}

/// The four firmware chains built from one table, each or the evaluator's refusal of the
/// arm (a reach beyond its range, a value it cannot hold).
pub struct Paths {
    /// f32 quaternion chain.
    pub qf: Result<Chain<F32>, ChainError>,
    /// Fixed quaternion chain.
    pub qx: Result<Chain<Fixed>, ChainError>,
    /// f32 matrix chain.
    pub mf: Result<MatrixChain<F32>, ChainError>,
    /// Fixed matrix chain.
    pub mx: Result<MatrixChain<Fixed>, ChainError>,
}

impl Paths {
    /// Builds the table of `arm` and every chain from it.
    pub fn new(arm: &Arm) -> anyhow::Result<Paths> {
        let bytes = crate::tablebuild::build(arm)?;
        let t = Table::parse(&bytes)?;
        Ok(Paths {
            qf: Chain::new(&t),
            qx: Chain::new(&t),
            mf: MatrixChain::new(&t),
            mx: MatrixChain::new(&t),
        })
    }

    /// Each path's refusal, in [`PATHS`] order.
    pub fn refused(&self) -> [Option<ChainError>; 4] {
        [
            self.qf.as_ref().err().copied(),
            self.qx.as_ref().err().copied(),
            self.mf.as_ref().err().copied(),
            self.mx.as_ref().err().copied(),
        ]
    }
}

/// Evaluates `poses` random readings (from `seed`) with every path against the reference,
/// on `threads` threads; `progress` is called with the number of poses done.
pub fn measure(
    arm: &Arm,
    poses: u64,
    seed: u64,
    threads: usize,
    progress: &(dyn Fn(u64) + Sync),
) -> anyhow::Result<Report> {
    let paths = Paths::new(arm)?;
    let threads = threads.max(1) as u64;
    let chunk = 10_000u64;
    let chunks = poses.div_ceil(chunk);
    let results: Vec<anyhow::Result<Report>> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                let paths = &paths;
                s.spawn(move || -> anyhow::Result<Report> {
                    let mut rep = Report::default();
                    let mut c = t;
                    while c < chunks {
                        // Each chunk has its own stream: the result does not depend on threads.
                        let mut rng = ChaCha8Rng::seed_from_u64(seed);
                        rng.set_stream(c);
                        let count = chunk.min(poses - c * chunk);
                        for _ in 0..count {
                            let (counts, temp_mc) = random_reading(&mut rng, arm);
                            one(arm, paths, &counts, temp_mc, &mut rep)?;
                        }
                        progress(count);
                        c += threads;
                    }
                    Ok(rep)
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("worker thread"))
            .collect()
    });
    let mut total = Report {
        refused: paths.refused(),
        ..Report::default()
    };
    for r in results {
        let r = r?;
        for (a, b) in total.stats.iter_mut().zip(&r.stats) {
            a.merge(b);
        }
    }
    Ok(total)
}

/// One reading through every path.
pub fn one(
    arm: &Arm,
    paths: &Paths,
    counts: &[u32],
    temp_mc: i32,
    rep: &mut Report,
) -> anyhow::Result<()> {
    let theta = arm.counts_to_rad(counts);
    let temp_c = f64::from(temp_mc) / 1000.0;
    let r = quatarm_ref::forward::forward(arm, &theta, temp_c);
    if let Ok(c) = &paths.qf {
        let e = errors(&c.eval(counts, temp_mc)?, &r.p, &r.n);
        rep.stats[0].add(e.0, e.1);
    }
    if let Ok(c) = &paths.qx {
        let e = errors(&c.eval(counts, temp_mc)?, &r.p, &r.n);
        rep.stats[1].add(e.0, e.1);
    }
    if let Ok(c) = &paths.mf {
        let e = errors(&c.eval(counts, temp_mc)?, &r.p, &r.n);
        rep.stats[2].add(e.0, e.1);
    }
    if let Ok(c) = &paths.mx {
        let e = errors(&c.eval(counts, temp_mc)?, &r.p, &r.n);
        rep.stats[3].add(e.0, e.1);
    }
    let (p1, n1) = first_order_gravity(arm, &theta, temp_c);
    rep.stats[4].add((p1 - r.p).norm() * 1000.0, (n1 - r.n).norm());
    Ok(())
}
