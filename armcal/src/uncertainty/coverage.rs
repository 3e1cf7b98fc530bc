//! Coverage on simulated arms: is the predicted 95 % region honest (`spec/uncertainty.md`,
//! "What honest means")?
//!
//! Each trial draws a truth arm (random geometric errors about `default-6`), records `point`
//! data of it as the virtual arm does (instrument noise, encoder noise before quantisation),
//! calibrates the nominal arm on them, and estimates the budget as `armcal calibrate` does.
//! Then fresh readings, with their own noise and quantisation: the calibrated arm's point
//! against the truth's at the continuous angles.
//!
//! - Points: the calibration fixes its own base frame (the datum), so the estimates are first
//!   brought onto the truth by one rigid alignment over all the trial's readings; a reading is
//!   covered when the truth is within U95 of the aligned estimate (the sphere; the ellipsoid
//!   of Σ_p at the same level is counted too).
//! - Distances: reading pairs, gauge-free (no alignment); covered when the distance error is
//!   within 1.96 standard uncertainties.

use super::estimate::{self, Settings};
use super::{propagate, u95};
use crate::data::Kind;
use crate::fit::calib::{self};
use crate::fit::design::poses::{limits, random_pose};
use crate::fit::options::Options;
use crate::fit::residuals::best_rigid;
use crate::rng::SimRng;
use crate::sim;
use nalgebra::{Matrix3, Vector3};
use quatarm_ref::arm::Arm;
use quatarm_ref::forward;
use rand::Rng;

/// What to run.
#[derive(Clone, Copy, Debug)]
pub struct Setup {
    /// Calibrations (truth arms).
    pub calibrations: usize,
    /// Fresh readings per calibration.
    pub readings: usize,
    /// `point` rows per calibration.
    pub point_rows: usize,
    /// Instrument noise per axis (mm).
    pub noise_mm: f64,
    /// Encoder noise (counts) before quantisation.
    pub encoder_noise_counts: f64,
    /// First seed; trial k uses seed + k.
    pub seed: u64,
    /// A thermal arm: every link and the probe expand (κ about aluminium's 2.3e-5/°C), the
    /// readings are taken between 15 and 25 °C, and the calibration fits every κ.
    pub thermal: bool,
    /// Error of the temperature sensor (°C, standard deviation), in the calibration's data
    /// and in the fresh readings alike; the budget's `temperature_c`.
    pub temp_noise_c: f64,
    /// Folds of the held-out validation behind the budget's model term, as `calibrate` runs
    /// it (0: none, the model term 0).
    pub folds: usize,
    /// The truth is this calibration file (under the workspace's `data/`), with effects the
    /// calibration's geometric model misses, instead of a random geometric arm.
    pub truth_file: Option<&'static str>,
    /// Tell the budget the instrument's noise (`--instrument-mm`); else it is counted in the
    /// model term, the safe side.
    pub instrument_known: bool,
}

/// The thermal variant's temperature range (°C).
const TEMPS: (f64, f64) = (15.0, 25.0);

impl Setup {
    /// The benchmark: 10 calibrations × 5,000 readings, 600 rows, 5 µm, 1 count.
    pub const BENCHMARK: Setup = Setup {
        calibrations: 10,
        readings: 5000,
        point_rows: 600,
        noise_mm: 0.005,
        encoder_noise_counts: 1.0,
        seed: 0xc0_7e,
        thermal: false,
        temp_noise_c: 0.0,
        folds: 0,
        truth_file: None,
        instrument_known: true,
    };

    /// The new user: `data/default-6-full.toml` (harmonics, gravity, thermal, wobble)
    /// as the truth, 600 `point` rows with 5 µm of instrument noise, calibrated with the
    /// geometric model and the budget `calibrate` writes by default (5 folds held out, the
    /// instrument's noise not declared).
    pub const NEW_USER: Setup = Setup {
        calibrations: 4,
        readings: 5000,
        point_rows: 600,
        noise_mm: 0.005,
        encoder_noise_counts: 0.0,
        seed: 0x0e_5e,
        thermal: false,
        temp_noise_c: 0.0,
        folds: 5,
        truth_file: Some("default-6-full.toml"),
        instrument_known: false,
    };
}

/// A file of the workspace's `data/` directory, as the truth of a trial.
pub fn data_arm(name: &str) -> Result<Arm, super::BudgetError> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("data")
        .join(name);
    crate::load::arm(&path).map_err(|e| super::BudgetError::Truth(e.to_string()))
}

/// Counts of one trial, or of all.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Tally {
    /// Readings judged.
    pub points: usize,
    /// Truth within U95 of the aligned estimate.
    pub in_sphere: usize,
    /// Truth within the 95 % ellipsoid of Σ_p.
    pub in_ellipsoid: usize,
    /// Pairs judged.
    pub pairs: usize,
    /// Distance error within 1.96 u_d.
    pub in_distance: usize,
    /// Sum of U95 (mm), for the mean.
    pub u95_sum: f64,
    /// Sum of |aligned error| (mm), for the mean.
    pub error_sum: f64,
}

impl Tally {
    /// Adds another tally's counts.
    pub fn add(&mut self, o: &Tally) {
        self.points += o.points;
        self.in_sphere += o.in_sphere;
        self.in_ellipsoid += o.in_ellipsoid;
        self.pairs += o.pairs;
        self.in_distance += o.in_distance;
        self.u95_sum += o.u95_sum;
        self.error_sum += o.error_sum;
    }

    /// Fraction of points in the sphere.
    pub fn sphere(&self) -> f64 {
        self.in_sphere as f64 / self.points.max(1) as f64
    }
    /// Fraction of points in the ellipsoid.
    pub fn ellipsoid(&self) -> f64 {
        self.in_ellipsoid as f64 / self.points.max(1) as f64
    }
    /// Fraction of distances covered.
    pub fn distance(&self) -> f64 {
        self.in_distance as f64 / self.pairs.max(1) as f64
    }
}

/// χ²(3) 95 % quantile: the ellipsoid's squared Mahalanobis radius.
const CHI2_3_95: f64 = 7.814_727_903_251_178;

/// The budget's reading term for an encoder of this noise: noise and quantisation together.
pub fn reading_sd(noise_counts: f64) -> f64 {
    (noise_counts * noise_counts + 1.0 / 12.0).sqrt()
}

/// A calibrated simulated arm: the truth, the calibration, its budget, and the generator
/// that made them (to go on with fresh readings).
pub struct Calibrated {
    /// The truth arm.
    pub truth: Arm,
    /// The calibrated arm.
    pub arm: Arm,
    /// Its budget.
    pub budget: super::Budget,
    /// The trial's generator.
    pub rng: SimRng,
}

/// Calibration `k` of the setup.
pub fn calibrated(setup: &Setup, k: usize) -> Result<Calibrated, super::BudgetError> {
    let mut rng = crate::rng::rng(setup.seed.wrapping_add(k as u64));
    let nominal = Arm::default6();
    let mut truth = match setup.truth_file {
        Some(name) => data_arm(name)?,
        None => sim::perturb(&nominal, 3e-4, 0.3, &mut rng),
    };
    let mut o = sim::Options::new(Kind::Point, setup.point_rows);
    o.noise_mm = setup.noise_mm;
    o.encoder_noise_counts = setup.encoder_noise_counts;
    let mut opts = Options::default();
    if setup.thermal {
        for j in &mut truth.joints {
            j.thermal = 2.3e-5 + 2e-6 * crate::rng::normal(&mut rng);
        }
        truth.probe.thermal = 1e-5;
        o.temp = Some(TEMPS);
        o.temp_noise_c = setup.temp_noise_c;
        let key = crate::effects::thermal::KEY;
        opts.terms = crate::params::Terms::parse(&format!("+{key}:*"), 6)?;
    }
    let data = sim::simulate(&truth, &o, &mut rng)?.data;
    let fit = calib::calibrate(&nominal, &data, &opts)?;
    let settings = Settings {
        encoder_counts: reading_sd(setup.encoder_noise_counts),
        probing_mm: Some(0.0),
        temperature_c: setup.temp_noise_c,
        instrument_mm: if setup.instrument_known {
            setup.noise_mm
        } else {
            0.0
        },
        model_mm: (setup.folds == 0).then_some(0.0),
        ..Settings::default()
    };
    let held = (setup.folds > 0).then(|| {
        let folds = crate::fit::holdout::kfold(&data, setup.folds, 0x0f01d);
        crate::fit::holdout::validate(&nominal, &data, &opts, &folds)
    });
    let in_sample = crate::fit::residuals::summarise(
        &crate::fit::residuals::residuals(&fit.arm, &data, fit.frame),
        &data,
    )
    .all
    .rms_um;
    let budget = estimate::from_fit(&fit, &data, held.as_ref(), in_sample, &settings)?.budget;
    Ok(Calibrated {
        truth,
        arm: fit.arm,
        budget,
        rng,
    })
}

/// Calibration `k` and its fresh readings.
pub fn trial(setup: &Setup, k: usize) -> Result<Tally, super::BudgetError> {
    let mut c = calibrated(setup, k)?;
    Ok(fresh(&c.truth, &c.arm, &c.budget, setup, &mut c.rng))
}

/// Fresh readings of `truth` through the calibrated `arm` and its budget.
pub fn fresh(
    truth: &Arm,
    arm: &Arm,
    budget: &super::Budget,
    setup: &Setup,
    rng: &mut SimRng,
) -> Tally {
    let lim = limits(truth);
    let mut reads = Vec::with_capacity(setup.readings);
    for _ in 0..setup.readings {
        let th = random_pose(&lim, rng);
        let (t_true, t_read) = if setup.thermal {
            let t = rng.gen_range(TEMPS.0..TEMPS.1);
            (t, t + setup.temp_noise_c * crate::rng::normal(rng))
        } else {
            (forward::REFERENCE_TEMP_C, forward::REFERENCE_TEMP_C)
        };
        let r = sim::read_encoders(truth, &th, setup.encoder_noise_counts, rng);
        let (p, s) = propagate::point(arm, 0, budget, &r, t_read);
        reads.push((forward::forward(truth, &th, t_true).p, p, s, r, t_read));
    }
    let est: Vec<Vector3<f64>> = reads.iter().map(|x| x.1).collect();
    let tru: Vec<Vector3<f64>> = reads.iter().map(|x| x.0).collect();
    let align = best_rigid(&est, &tru);
    let mut tally = Tally::default();
    for (truth_p, p, s, _, _) in &reads {
        let e = align.apply(p) - truth_p;
        let sr: Matrix3<f64> = align.rot * s * align.rot.transpose();
        let u = u95::u95(&sr);
        tally.points += 1;
        tally.u95_sum += u;
        tally.error_sum += e.norm();
        tally.in_sphere += usize::from(e.norm() <= u);
        if let Some(inv) = sr.try_inverse() {
            tally.in_ellipsoid += usize::from((e.transpose() * inv * e)[(0, 0)] <= CHI2_3_95);
        }
    }
    for pair in reads.chunks_exact(2) {
        let (a, b) = (&pair[0], &pair[1]);
        let (d, ud) = propagate::distance(arm, budget, (&a.3, a.4), (&b.3, b.4));
        let err = d - (a.0 - b.0).norm();
        tally.pairs += 1;
        tally.in_distance += usize::from(err.abs() <= 1.959_963_984_540_054 * ud);
    }
    tally
}

/// Every trial: the per-trial tallies and their total.
pub fn run(setup: &Setup) -> Result<(Vec<Tally>, Tally), super::BudgetError> {
    let mut all = Vec::with_capacity(setup.calibrations);
    let mut total = Tally::default();
    for k in 0..setup.calibrations {
        let t = trial(setup, k)?;
        total.add(&t);
        all.push(t);
    }
    Ok((all, total))
}
