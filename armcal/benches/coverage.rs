//! Coverage benchmark of the uncertainty budget (issue 11): calibrations of random simulated
//! arms (600 `point` readings, 5 µm instrument noise, 1 count of encoder noise), each read
//! afresh 5,000 times with its own noise and quantisation; the fraction of readings whose true
//! point is inside the predicted 95 % region (after one rigid alignment per calibration), and
//! of reading pairs whose true distance is within the distance's 95 % interval. Then first
//! order against Monte Carlo on U95.
//!
//! `cargo bench -p armcal --bench coverage` (release), or, reusing the test profile's build,
//! `cargo test --profile test -p armcal --bench coverage`. Arguments: calibrations, readings, encoder noise (counts), and a temperature sensor's noise
//! (°C) for the thermal variant;
//! or `mukca` for the real recordings, each unit's sessions held out one at a time (the nested
//! budget with the pose-dependent term, its scale per session, the pooled coverage with the
//! term's σ multiplied by m = 0…3 as a sensitivity, and both extrapolation flags per session);
//! `mukca-variants` for the variants measured towards each unit in 88–99 % (forms of the pose
//! term, a leverage-scaled one, κ pooled with the fleet's, few-groups factors), then round 4
//! (`armcal::uncertainty::realdata::forms`: the pose part times a per-reading factor from
//! leverage ratios of the chain, the pose part, the tip and the joints, every unit nested,
//! the choice among them scored by leaving units out); `mukca-variants round4` runs round 4
//! alone.
//! `placement [seeds] [hard=K]` checks ℓJ outside the data it was chosen on
//! (`armcal::uncertainty::realdata::placement`: simulated units whose last session is at a
//! new placement, under max(1, ℓ) and max(1, ℓ, ℓJ); `hard=K` the harder arm's factor).
//! `new-user` runs the new user instead (`Setup::NEW_USER`: `default-6-full` as the
//! truth, calibrated with the geometric model, the model term as `calibrate` estimates it);
//! `held-out` runs the benchmark with the model term estimated from 5 folds as `calibrate`
//! does (the instrument's noise declared); `held-out-undeclared` without declaring it.

use armcal::fit::design::poses::{limits, random_pose};
use armcal::uncertainty::coverage::{self, Setup};
use armcal::uncertainty::pose::conformal_scale;
use armcal::uncertainty::realdata::forms;
use armcal::uncertainty::{montecarlo, propagate, realdata, u95};
use std::time::Instant;

fn main() {
    if std::env::args().any(|a| a == "placement") {
        return placement();
    }
    if std::env::args().any(|a| a == "mukca-variants") {
        return mukca_variants();
    }
    if std::env::args().any(|a| a == "mukca") {
        return mukca();
    }
    let mut setup = Setup::BENCHMARK;
    if std::env::args().any(|a| a == "new-user") {
        setup = Setup::NEW_USER;
    }
    if std::env::args().any(|a| a.starts_with("held-out")) {
        setup.folds = 5;
        setup.instrument_known = !std::env::args().any(|a| a == "held-out-undeclared");
    }
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    if let Some(&c) = args.first() {
        setup.calibrations = c as usize;
    }
    if let Some(&r) = args.get(1) {
        setup.readings = r as usize;
    }
    if let Some(&e) = args.get(2) {
        setup.encoder_noise_counts = e;
    }
    if let Some(&t) = args.get(3) {
        setup.thermal = true;
        setup.temp_noise_c = t;
    }
    let t0 = Instant::now();
    println!(
        "coverage: {} calibrations × {} fresh readings; {} point rows, {} µm instrument noise, \
         {} count encoder noise{}",
        setup.calibrations,
        setup.readings,
        setup.point_rows,
        setup.noise_mm * 1e3,
        setup.encoder_noise_counts,
        if setup.thermal {
            format!(
                "; thermal arm at 15-25 °C, sensor noise {} °C",
                setup.temp_noise_c
            )
        } else {
            String::new()
        }
    );
    if setup.folds > 0 {
        println!(
            "  truth {}; model term from {} held-out folds, instrument noise {}",
            setup.truth_file.unwrap_or("perturbed default-6"),
            setup.folds,
            if setup.instrument_known {
                "declared"
            } else {
                "not declared (counted in the model term)"
            }
        );
    }
    println!("  trial  sphere(U95)  ellipsoid  distance  mean U95 µm  mean |error| µm  model µm");
    let mut total = coverage::Tally::default();
    for k in 0..setup.calibrations {
        let mut c = match coverage::calibrated(&setup, k) {
            Ok(c) => c,
            Err(e) => {
                println!("  {k:>5}  calibration failed: {e}");
                continue;
            }
        };
        let t = coverage::fresh(&c.truth, &c.arm, &c.budget, &setup, &mut c.rng);
        println!(
            "  {k:>5}  {:>11.4}  {:>9.4}  {:>8.4}  {:>11.2}  {:>15.2}  {:>8.2}",
            t.sphere(),
            t.ellipsoid(),
            t.distance(),
            t.u95_sum / t.points as f64 * 1e3,
            t.error_sum / t.points as f64 * 1e3,
            c.budget.model_mm * 1e3
        );
        total.add(&t);
    }
    println!(
        "  all    {:>11.4}  {:>9.4}  {:>8.4}   ({} readings, {} pairs; ideal 0.95)",
        total.sphere(),
        total.ellipsoid(),
        total.distance(),
        total.points,
        total.pairs
    );
    if setup.truth_file.is_none() {
        first_order_against_monte_carlo(&setup);
    }
    println!("  took {:.1} s", t0.elapsed().as_secs_f64());
}

/// U95 by both methods at 100 poses of the first calibration, 40,000 draws each (the 95th
/// percentile of 40,000 draws has a relative standard error of about 0.3 %).
fn first_order_against_monte_carlo(setup: &Setup) {
    let Ok(mut c) = coverage::calibrated(setup, 0) else {
        println!("  first order vs Monte Carlo: calibration failed");
        return;
    };
    let root = montecarlo::sqrt_cov(&c.budget.cov);
    let lim = limits(&c.arm);
    let mut worst: f64 = 0.0;
    let mut sum = 0.0;
    let n = 100;
    for _ in 0..n {
        let th = random_pose(&lim, &mut c.rng);
        let (_, s) = propagate::point(&c.arm, 0, &c.budget, &th, 20.0);
        let fo = u95::u95(&s);
        let mc = montecarlo::point(&c.arm, 0, &c.budget, &root, &th, 20.0, 40_000, &mut c.rng).u95;
        let rel = mc / fo - 1.0;
        worst = worst.max(rel.abs());
        sum += rel;
    }
    println!(
        "  first order vs Monte Carlo U95 at {n} poses (40,000 draws each): mean MC/FO − 1 = \
         {:+.2} %, largest |difference| {:.2} %",
        sum / n as f64 * 100.0,
        worst * 100.0
    );
}

/// Held-out coverage on every MUKCa unit with two sessions or more.
/// Issue 27 round 5's check of ℓJ outside its selection
/// ([`realdata::placement`]): per seed (the first number argument, 4 by default) and new
/// placement, the new placement's session's coverage under max(1, ℓ) and max(1, ℓ, ℓJ).
/// One held-out session of the placement check under one factor.
struct PlacedSession {
    seed: u64,
    name: String,
    /// Whether it is the scenario's new placement (else a training one held out in turn).
    new: bool,
    covered: usize,
    probings: usize,
    /// Median nested U95 and RMS deviation from the socket's centre (mm).
    u95_mm: f64,
    rms_mm: f64,
    /// Median ℓJ against the other sessions (the same under both factors).
    joint_leverage: f64,
    /// The pose term's κ its nested calibration validated.
    kappa: f64,
    /// Whether `calibrate --by-group` on every session of the seed names it as missed as a
    /// whole (the product's report, not nested; the same under both factors' columns).
    named: bool,
}

fn median_of(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

/// `placement [seeds] [hard=K]` (issue 27, rounds 5 and 6): ℓJ checked outside the data it
/// was chosen on. Simulated units of five sessions (four training placements, then a new
/// one), every session held out in turn through the product's nested path, under
/// max(1, ℓ) and max(1, ℓ, ℓJ). Seven scenarios: `default-6-full` with the new placement
/// `raised` and `bent-back` (round 5's), and the same truth with its harmonics and gravity
/// compliance multiplied by K (default 5, [`realdata::placement::amplified`]) at those two
/// and at each far placement (`realdata::placement::FAR`). Per seed every session's coverage, κ, median U95
/// and RMS deviation; per scenario the pooled coverage over every held-out session, the new
/// placement's and the training sessions' apart, with three 95 % intervals (Wilson over
/// probings as if independent; percentile bootstraps resampling whole sessions and whole
/// seeds), the worst session and the median over sessions of their median U95. A seed is
/// the honest replicate (its sessions share one calibration design and κ), so the seeds'
/// bootstrap is the interval to read.
fn placement() {
    use realdata::placement;
    let t0 = Instant::now();
    let seeds = std::env::args()
        .skip(1)
        .find_map(|a| a.parse::<u64>().ok())
        .unwrap_or(10);
    let k = std::env::args()
        .find_map(|a| a.strip_prefix("hard=").and_then(|v| v.parse::<f64>().ok()))
        .unwrap_or(5.0);
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/default-6-full.toml");
    let truth = match quatarm_ref::calfile::read(&path) {
        Ok(p) => p.arm,
        Err(e) => return println!("{}: {e}", path.display()),
    };
    let hard = placement::amplified(&truth, k);
    // `fold`: κ validated with each held-out row's ℓ against its fold's design (stop 42's
    // variant) under both factors.
    let fold = std::env::args().any(|a| a == "fold");
    if fold {
        println!("κ validated with each held-out row's ℓ against its fold's own design (`fold`)");
    }
    let nominal = quatarm_ref::arm::Arm::default6();
    println!(
        "placements: the geometric model fitted, 4 training sessions at placements {}, then a \
         new one; {} bar × {} probings a session; every session held out in turn; {seeds} \
         seeds",
        placement::TRAINING
            .iter()
            .map(|p| p.name)
            .collect::<Vec<_>>()
            .join(", "),
        placement::PROTOCOL.bars,
        placement::PROTOCOL.probings
    );
    let hard_name = format!("default-6-full, harmonics and gravity ×{k}");
    // Round 5's two scenarios, then the harder arm at every new placement (round 6).
    let scenarios: Vec<(&str, &quatarm_ref::arm::Arm, placement::Placement)> = placement::NEW
        .iter()
        .map(|p| ("default-6-full", &truth, *p))
        .chain(
            placement::NEW
                .iter()
                .chain(&placement::FAR)
                .map(|p| (hard_name.as_str(), &hard, *p)),
        )
        .collect();
    const FORMS: [&str; 2] = ["max(1, ℓ)", "max(1, ℓ, ℓJ)"];
    for (label, truth, new) in scenarios {
        let t1 = Instant::now();
        let mut all: [Vec<PlacedSession>; 2] = Default::default();
        for seed in 0..seeds {
            let Some(unit) = placement::unit(
                truth,
                &nominal,
                &placement::TRAINING,
                &new,
                &placement::PROTOCOL,
                seed,
            ) else {
                println!(
                    "  {label} / {} seed {seed}: a bar could not be placed",
                    new.name
                );
                continue;
            };
            let lj = placement::session_joint_leverages(&unit);
            let named = realdata::named_sessions(
                &unit,
                realdata::Rule::product(armcal::uncertainty::pose::two_group_scale(false)),
            )
            .unwrap_or_default();
            let c = [
                placement::coverage_with(&unit, false, fold),
                placement::coverage_with(&unit, true, fold),
            ];
            println!(
                "  {label} / new {} seed {seed}: session  ℓJ  RMS dev mm | {} covered, κ, \
                 median U95 mm | {} the same",
                new.name, FORMS[0], FORMS[1]
            );
            for name in unit.sessions.values() {
                let joint_leverage = lj.get(name).copied().unwrap_or(f64::NAN);
                let (mut cells, mut rms) = (Vec::new(), f64::NAN);
                for (f, c) in c.iter().enumerate() {
                    let Some(c) = c else { continue };
                    let Some(i) = c.per_session.iter().position(|s| &s.0 == name) else {
                        cells.push("failed".to_string());
                        continue;
                    };
                    let (n, frac) = (c.per_session[i].1, c.per_session[i].2);
                    let [u95_mm, rms_mm] = c.per_session_u95_rms_mm[i];
                    let kappa = c.pose_scale.get(i).map_or(f64::NAN, |p| p.0);
                    cells.push(format!("{frac:.3} of {n}, κ {kappa:.3}, U95 {u95_mm:.3}"));
                    rms = rms_mm;
                    all[f].push(PlacedSession {
                        seed,
                        name: name.clone(),
                        new: name == new.name,
                        covered: (frac * n as f64).round() as usize,
                        probings: n,
                        u95_mm,
                        rms_mm,
                        joint_leverage,
                        kappa,
                        named: named.get(name).is_some_and(|g| g.missed()),
                    });
                }
                println!(
                    "    {name:<11} {joint_leverage:>5.1} {rms:>6.3} | {}",
                    cells.join(" | ")
                );
            }
            for (f, c) in c.iter().enumerate() {
                match c {
                    Some(c) => println!(
                        "    {}: every session held out {:.3} of {}, median U95 {:.3} mm{}",
                        FORMS[f],
                        c.covered_nested,
                        c.probings,
                        c.nested_u95_mm,
                        if c.failed.is_empty() {
                            String::new()
                        } else {
                            format!("; failed: {}", c.failed.join("; "))
                        }
                    ),
                    None => println!("    {}: no coverage (fewer than 2 sessions)", FORMS[f]),
                }
            }
        }
        placement_summary(label, new.name, &all, t1.elapsed().as_secs_f64());
    }
    println!("  took {:.0} s", t0.elapsed().as_secs_f64());
}

/// A scenario's pooled figures under each factor: every held-out session, the new
/// placement's, the training ones'; then the sessions ℓJ moved.
fn placement_summary(label: &str, new: &str, all: &[Vec<PlacedSession>; 2], secs: f64) {
    const FORMS: [&str; 2] = ["max(1, ℓ)", "max(1, ℓ, ℓJ)"];
    println!("  SUMMARY {label} / new {new} ({secs:.0} s)");
    let factor_free = &all[1];
    for (what, pick) in [("new", true), ("training", false)] {
        let s: Vec<&PlacedSession> = factor_free.iter().filter(|s| s.new == pick).collect();
        println!(
            "    {what} sessions: {}, median RMS deviation {:.4} mm, median ℓJ {:.1}",
            s.len(),
            median_of(s.iter().map(|s| s.rms_mm).collect()),
            median_of(s.iter().map(|s| s.joint_leverage).collect())
        );
    }
    println!(
        "    factor          sessions  pooled  (covered/probings)  Wilson 95 %       \
         sessions' bootstrap  seeds' bootstrap  worst session                 < 0.88  median U95 mm  median κ"
    );
    for (f, v) in all.iter().enumerate() {
        for (what, pick) in [
            ("all", None),
            ("new", Some(true)),
            ("training", Some(false)),
        ] {
            let s: Vec<&PlacedSession> = v
                .iter()
                .filter(|s| pick.is_none_or(|p| s.new == p))
                .collect();
            let (k, n) = s
                .iter()
                .fold((0, 0), |(k, n), s| (k + s.covered, n + s.probings));
            let (wl, wh) = forms::wilson(k, n);
            let per_session: Vec<(usize, usize)> =
                s.iter().map(|s| (s.covered, s.probings)).collect();
            let (sl, sh) = forms::session_bootstrap(&per_session, 20_000, 27);
            let mut per_seed = std::collections::BTreeMap::<u64, (usize, usize)>::new();
            for x in &s {
                let e = per_seed.entry(x.seed).or_default();
                e.0 += x.covered;
                e.1 += x.probings;
            }
            let per_seed: Vec<(usize, usize)> = per_seed.into_values().collect();
            let (bl, bh) = forms::session_bootstrap(&per_seed, 20_000, 27);
            let frac = |s: &PlacedSession| s.covered as f64 / s.probings.max(1) as f64;
            let worst = s
                .iter()
                .min_by(|a, b| frac(a).total_cmp(&frac(b)))
                .map_or("-".to_string(), |w| {
                    format!("{:.3} (seed {} {})", frac(w), w.seed, w.name)
                });
            println!(
                "    {:<13} {what:<9} {:>3}  {:.3}  ({k}/{n})  [{wl:.3}, {wh:.3}]  [{sl:.3}, {sh:.3}]  \
                 [{bl:.3}, {bh:.3}]  {worst:<28}  {:>3}  {:.3}  {:.3}",
                if what == "all" { FORMS[f] } else { "" },
                s.len(),
                k as f64 / n.max(1) as f64,
                s.iter().filter(|s| frac(s) < 0.88).count(),
                median_of(s.iter().map(|s| s.u95_mm).collect()),
                median_of(s.iter().map(|s| s.kappa).collect()),
            );
        }
    }
    // The report's naming of missed sessions (calibrate --by-group on all five, not nested)
    // against the product's nested check: [nested ≥ 0.88, < 0.88][not named, named].
    for (what, pick) in [("new", true), ("training", false)] {
        let mut naming = Naming::default();
        for x in all[0].iter().filter(|s| s.new == pick) {
            naming.add(x.covered as f64 / x.probings.max(1) as f64, x.named);
        }
        println!("    {what} sessions named missed by calibrate's report: {naming}");
    }
    // The same sessions under both factors: which ℓJ moved, new and training apart.
    for (what, pick) in [("new", true), ("training", false)] {
        let (mut up, mut down, mut same) = (0, 0, 0);
        for a in all[0].iter().filter(|s| s.new == pick) {
            if let Some(b) = all[1].iter().find(|b| b.seed == a.seed && b.name == a.name) {
                match b.covered.cmp(&a.covered) {
                    std::cmp::Ordering::Greater => up += 1,
                    std::cmp::Ordering::Less => down += 1,
                    std::cmp::Ordering::Equal => same += 1,
                }
            }
        }
        println!(
            "    {what} sessions with ℓJ against max(1, ℓ): covered more {up}, less {down}, \
             the same {same}"
        );
    }
}

/// The report's naming of sessions missed as a whole (`calibrate --by-group` on every
/// session) against the nested check: counts by [nested ≥ 0.88, < 0.88][not named, named].
#[derive(Default)]
struct Naming([[usize; 2]; 2]);

impl Naming {
    /// One session: its nested coverage and whether the report named it.
    fn add(&mut self, nested: f64, named: bool) {
        self.0[usize::from(nested < BAND.0)][usize::from(named)] += 1;
    }
}

impl std::fmt::Display for Naming {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [above, below] = self.0;
        write!(
            f,
            "nested < {}: {} of {} named; nested ≥ {}: {} of {} named",
            BAND.0,
            below[1],
            below[0] + below[1],
            BAND.0,
            above[1],
            above[0] + above[1]
        )
    }
}

/// Issue 27's band for each MUKCa unit's nested coverage.
const BAND: (f64, f64) = (0.88, 0.99);

/// Whether a unit's coverage `f` is in [`BAND`] (inclusive).
fn in_band_of(f: f64) -> bool {
    (BAND.0..=BAND.1).contains(&f)
}

fn mukca() {
    let dir = armcal::mukca::default_dir();
    let units = match armcal::mukca::unit_names(&dir) {
        Ok(u) => u,
        Err(e) => return println!("MUKCa: {e}"),
    };
    // `mukca joints`: the opt-in factor max(1, ℓ, ℓJ) (`--joint-leverage`), for the table
    // beside the product's max(1, ℓ).
    let joints = std::env::args().any(|a| a == "joints");
    // `mukca fold`: κ validated with each held-out row's ℓ against its fold's own design
    // (stop 42's variant).
    let fold = std::env::args().any(|a| a == "fold");
    let rule = |fleet: f64| realdata::Rule {
        joint_leverage: joints,
        fold_leverage: fold,
        ..realdata::Rule::product(fleet)
    };
    println!(
        "MUKCa, whole sessions held out: probings within their predicted 95 % region; the pose \
         part's factor {}",
        if joints {
            "max(1, ℓ, ℓJ) (`joints`: the opt-in joint leverage)"
        } else {
            "max(1, ℓ) (the product's)"
        }
    );
    let mut sessions: Vec<(usize, usize)> = Vec::new();
    let (mut in_band, mut band_units) = (0usize, Vec::<(String, Vec<(usize, usize)>)>::new());
    println!(
        "  unit                 sessions  probings  covered  +model  nested  median U95 mm \
         (+model) [nested]  RMS dev mm  probing mm  model mm  nested model mm"
    );
    let (mut pooled, mut judged, mut per_session) = (0.0, 0usize, Vec::new());
    let mut pooled_alt = 0.0;
    let mut sweep = [0.0; 6];
    let mut loaded = Vec::new();
    for (name, _) in units {
        match armcal::mukca::load(&dir, &name) {
            Ok(u) => loaded.push(u),
            Err(e) => println!("  {name:<20} {e}"),
        }
    }
    // The pose term's κ for two training sessions, per unit (conformal over its own
    // pair-trained scores); a unit is judged with the median of the *other* units' values.
    let scores: Vec<Vec<f64>> = loaded
        .iter()
        .map(|u| realdata::two_group_scores_with(u, joints))
        .collect();
    let kappa2: Vec<Option<f64>> = loaded
        .iter()
        .zip(&scores)
        .map(|(u, t)| {
            let t = t.clone();
            (!t.is_empty()).then(|| {
                let covered = |k: f64| t.iter().filter(|x| **x <= k).count() as f64 / t.len() as f64;
                let k = armcal::uncertainty::pose::conformal_scale(t.clone());
                println!(
                    "  two-session κ {:<20} {k:.3} from {} probings (covered at κ = 1: {:.3}, at κ = {k:.3}: {:.3}, never: {:.3})",
                    u.name,
                    t.len(),
                    covered(1.0),
                    covered(k),
                    t.iter().filter(|x| x.is_infinite()).count() as f64 / t.len() as f64
                );
                k
            })
        })
        .collect();
    let all: Vec<f64> = kappa2.iter().flatten().copied().collect();
    // The κ `calibrate` takes where two sessions cannot set it, and the report's naming of
    // missed sessions against the nested check.
    let two_group = armcal::uncertainty::pose::two_group_scale(joints);
    let mut naming = Naming::default();
    println!(
        "  two-session κ of the fleet (median over {} units): {:.3}; the default for this \
         factor (`pose::two_group_scale`): {:.3}",
        all.len(),
        realdata::fleet_scale(&all),
        two_group
    );
    for (k, unit) in loaded.iter().enumerate() {
        let others: Vec<f64> = kappa2
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != k)
            .filter_map(|(_, v)| *v)
            .collect();
        let fleet = realdata::fleet_scale(&others);
        // Sensitivity (not the rule): the κ at which the other units cover 95 % on average.
        let other_scores: Vec<Vec<f64>> = scores
            .iter()
            .enumerate()
            .filter(|(j, t)| *j != k && !t.is_empty())
            .map(|(_, t)| t.clone())
            .collect();
        let mean_fleet = realdata::fleet_scale_mean_coverage(&other_scores);
        let name = &unit.name;
        let Some(c) = realdata::unit_coverage(unit, rule(fleet)) else {
            println!("  {name:<20} one session: nothing to hold out");
            continue;
        };
        println!(
            "  {:<20} {:>8}  {:>8}  {:>7.3}  {:>6.3}  {:>6.3}  {:>8.4} ({:>8.4}) [{:>8.4}]  {:>10.4}  {:>10.4}  {:>8.4}  {:>15.4}",
            c.unit,
            c.sessions,
            c.probings,
            c.covered,
            c.covered_with_model,
            c.covered_nested,
            c.median_u95_mm[0],
            c.median_u95_mm[1],
            c.nested_u95_mm,
            c.rms_deviation_mm,
            c.probing_mm,
            c.model_mm,
            c.nested_model_mm
        );
        println!(
            "    pose term: two-session κ from the other units {fleet:.3}; scale per held-out \
             session {}; nested coverage with m × its σ: {}",
            c.pose_scale
                .iter()
                .map(|(k, v)| format!("{k:.2}{}", if *v { "" } else { "*" }))
                .collect::<Vec<_>>()
                .join(" "),
            c.pose_sweep
                .iter()
                .map(|(m, f)| format!("m={m}: {f:.3}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
        if c.sessions == 3 {
            if let Some(a) = realdata::unit_coverage(unit, rule(mean_fleet)) {
                println!(
                    "    sensitivity: κ at the other units' mean coverage 95 % {mean_fleet:.3}: \
                     nested {:.3}, median U95 {:.4} mm",
                    a.covered_nested, a.nested_u95_mm
                );
                pooled_alt += a.covered_nested * a.probings as f64;
            }
        } else if c.sessions > 3 {
            pooled_alt += c.covered_nested * c.probings as f64;
        }
        // What `calibrate --by-group` on every session names in its report (not nested),
        // against what the nested check finds.
        if let Some(named) = realdata::named_sessions(unit, rule(two_group)) {
            let said: Vec<String> = named
                .iter()
                .filter(|(_, g)| g.missed())
                .map(|(s, g)| format!("{s} ({:.1} %)", 100.0 * g.fraction()))
                .collect();
            println!(
                "    calibrate --by-group on all {} sessions names as missed as a whole: {}",
                named.len(),
                if said.is_empty() {
                    "none".to_string()
                } else {
                    said.join(", ")
                }
            );
            if c.sessions >= 3 {
                for (s, _, f, ..) in &c.per_session {
                    naming.add(*f, named.get(s).is_some_and(|g| g.missed()));
                }
            }
        }
        if c.sessions >= 3 {
            for (k, (_, f)) in c.pose_sweep.iter().enumerate() {
                sweep[k] += f * c.probings as f64;
            }
            pooled += c.covered_nested * c.probings as f64;
            judged += c.probings;
            let k = (c.covered_nested * c.probings as f64).round() as usize;
            let (lo, hi) = forms::wilson(k, c.probings);
            // The unit's own sessions resampled: its probings are not independent (a session
            // at a new placement is covered or missed as a whole), so this is the interval to
            // read against the band; Wilson's treats them as independent.
            let own: Vec<(usize, usize)> = c
                .per_session
                .iter()
                .map(|(_, n, f, ..)| ((f * *n as f64).round() as usize, *n))
                .collect();
            let (sl, sh) = forms::session_bootstrap(&own, 20_000, 27);
            sessions.extend_from_slice(&own);
            let inside = in_band_of(c.covered_nested);
            in_band += usize::from(inside);
            band_units.push((c.unit.clone(), own.clone()));
            println!(
                "    nested {:.3} (Wilson 95 % [{lo:.3}, {hi:.3}]; its {} sessions resampled \
                 [{sl:.3}, {sh:.3}]), {}",
                c.covered_nested,
                own.len(),
                if inside {
                    "in the band 88–99 %"
                } else {
                    "outside 88–99 %"
                }
            );
        }
        per_session.extend(c.per_session.iter().map(|(s, n, f, x, j, r)| {
            format!(
                "{}/{s}: {f:.3} of {n}, extrapolated {x:.2} (tip) {j:.2} (joints) {:.2} \
                 (a joint outside its range) {:.2} (by > {} rad)",
                c.unit,
                r[0],
                r[1],
                realdata::RANGE_MARGIN
            )
        }));
        for f in &c.failed {
            println!("    not judged: {f}");
        }
    }
    let (lo, hi) = forms::session_bootstrap(&sessions, 20_000, 27);
    println!(
        "  pooled over units with ≥ 3 sessions, nested model term: {:.3} of {judged} probings \
         (95 % [{lo:.3}, {hi:.3}], {} whole sessions resampled)",
        pooled / judged.max(1) as f64,
        sessions.len()
    );
    // What the band can show with these session counts: each unit's sessions drawn from the
    // other units' held-out sessions, as many as it has.
    let own: Vec<Vec<(usize, usize)>> = band_units.iter().map(|(_, s)| s.clone()).collect();
    let chance = forms::band_chance(&own, BAND, in_band, 20_000, 27);
    println!(
        "  units in 88–99 %: {in_band} of {}; with each unit's sessions drawn from the other \
         units' ({} draws): {:.2} of {} on average, all in {:.3} of draws, {in_band} or fewer in \
         {:.3}; per unit {}",
        own.len(),
        20_000,
        chance.mean_in_band,
        own.len(),
        chance.all_in_band,
        chance.at_most_observed,
        band_units
            .iter()
            .zip(&chance.per_unit)
            .map(|((name, s), p)| format!("{name} ({} sessions) {p:.3}", s.len()))
            .collect::<Vec<_>>()
            .join(", ")
    );
    println!(
        "  the report's naming (calibrate --by-group on every session, groups missed as a whole \
         at p < {}) against the nested check, sessions of units with ≥ 3: {naming}",
        armcal::uncertainty::misfit::GROUP_MISSED_P,
    );
    println!(
        "  pooled, sensitivity (3-session units at the other units' mean-coverage κ): {:.3}",
        pooled_alt / judged.max(1) as f64
    );
    println!(
        "  pooled, m × the pose term's σ (m = 0, 0.5, 1, 1.5, 2, 3): {}  (* in the scales: \
         not validated, two training sessions)",
        sweep
            .iter()
            .map(|f| format!("{:.3}", f / judged.max(1) as f64))
            .collect::<Vec<_>>()
            .join(" ")
    );
    println!("  per held-out session (nested budget):");
    for s in per_session {
        println!("    {s}");
    }
}

/// The shrinkage weights of S_b towards C measured by `mukca-variants` (0.5 is the budget's,
/// one group's worth with two groups; 1 is C's shape at S_b's size).
const FORMS: [f64; 5] = [0.0, 0.25, 0.5, 0.75, 1.0];

/// The columns of [`realdata::two_group_scores_by_form`] measured: the [`FORMS`], then the
/// two leverage forms.
const COLUMNS: [&str; 7] = [
    "λ = 0 (S_b raw)",
    "λ = 0.25",
    "λ = 0.5 (the budget's)",
    "λ = 0.75",
    "λ = 1 (C's shape)",
    "C itself (∝ leverage)",
    "λ = 0.5 × max(1, ℓ)",
];

/// Student's t at 97.5 % for one degree of freedom over the normal's: the few-groups
/// factor on σ for two training sessions (12.706/1.960).
const T_ONE_DOF: f64 = 6.483;

/// The variants of issue 27's last step, measured in one run (`docs/results/uncertainty.md`,
/// "The variants for each unit in 88–99 %"). Per unit with ≥ 3 sessions, its two-session
/// scores under each form of [`COLUMNS`] (also written to `mukca-forms.json` in Cargo's
/// temporary folder for benchmarks, `target/tmp/`); each 3-session unit's nested coverage under each form with the median of the *other* units'
/// κ (its pairs are its outer folds, so its scores are its nested coverage); few-groups
/// factors; the leverage ratio ℓ per session; and, for the units with ≥ 4 sessions, the
/// nested coverage with the fleet's κ pooled into their own (worth one group,
/// [`armcal::uncertainty::pose::pooled_scale`]).
fn mukca_variants() {
    let dir = armcal::mukca::default_dir();
    let Ok(units) = armcal::mukca::unit_names(&dir) else {
        return println!("MUKCa: no units");
    };
    let t0 = Instant::now();
    if std::env::args().any(|a| a == "round4") {
        return round4(&dir, &units);
    }
    let v = Variants::score(
        units
            .iter()
            .filter_map(|(n, _)| armcal::mukca::load(&dir, n).ok())
            .filter(|u| u.groups().len() >= 3)
            .collect(),
    );
    println!(
        "MUKCa variants ({:.0} s of scoring)",
        t0.elapsed().as_secs_f64()
    );
    v.print_kappa();
    v.dump();
    v.print_forms();
    v.print_few_groups();
    v.print_sessions();
    v.print_nested("κ pooled with the fleet's (worth one group)", |k| {
        realdata::Rule {
            prior_groups: 1.0,
            ..realdata::Rule::product(realdata::fleet_scale(&v.others(k, 2)))
        }
    });
    v.print_nested(
        "the leverage-scaled term through the nested path (κ validated on ℓ-scaled scores \
         where ≥ 3 training sessions, else the median of the other units' ℓ-form κ)",
        |k| realdata::Rule {
            leverage: true,
            ..realdata::Rule::product(realdata::fleet_scale(&v.others(k, 6)))
        },
    );
    round4(&dir, &units);
    println!("  took {:.0} s", t0.elapsed().as_secs_f64());
}

/// The pose part's factors measured in round 4 (`realdata::forms`): ℓ indices 0 = C dev,
/// 1 = P dev, 2 = C tip, 3 = joints.
const ROUND4_FACTORS: [forms::Factor; 16] = [
    forms::Factor::One,
    forms::Factor::Floored(0),
    forms::Factor::Floored(1),
    forms::Factor::Mix(0, 1),
    forms::Factor::Larger(0, 1),
    forms::Factor::Floored(2),
    forms::Factor::Mix(0, 2),
    forms::Factor::Raw(0),
    forms::Factor::Raw(1),
    forms::Factor::Raw(2),
    forms::Factor::Larger(0, 2),
    forms::Factor::Floored(3),
    forms::Factor::Root(3),
    forms::Factor::Mix(0, 3),
    forms::Factor::Larger(0, 3),
    forms::Factor::Larger(2, 3),
];

/// Round 4 of issue 27 (`docs/results/uncertainty.md`, "Round 4: panda_1 and dinova_2"):
/// every unit with ≥ 3 sessions fitted once per training set, then every variant of
/// [`ROUND4_FACTORS`] × (τ² scaled by the factor or not) × (validated κ × the t-ratio or
/// not) nested; the choice among them scored by leaving units out; the U95's split per
/// unit under the product, the leverage form and the chosen variants.
fn round4(dir: &std::path::Path, names: &[(String, String)]) {
    let t0 = Instant::now();
    let units: Vec<forms::UnitRows> = names
        .iter()
        .filter_map(|(n, _)| armcal::mukca::load(dir, n).ok())
        .filter_map(|u| forms::unit_rows(&u))
        .collect();
    println!(
        "round 4: {} units fitted per training set in {:.0} s",
        units.len(),
        t0.elapsed().as_secs_f64()
    );
    println!(
        "  leverage ratios per scored session (median over its probings, outer folds): ℓC ℓP ℓT ℓJ"
    );
    for u in &units {
        for t in &u.outer {
            let mut l: Vec<[f64; forms::NQ]> = t.scored.iter().map(|r| r.ratios(&t.norm)).collect();
            let mut med = |k: usize| {
                l.sort_by(|a, b| a[k].total_cmp(&b[k]));
                l.get(l.len() / 2).map_or(f64::NAN, |x| x[k])
            };
            let (a, b, c, d) = (med(0), med(1), med(2), med(3));
            let s = t.scored.first().map_or(-1, |r| r.session);
            println!(
                "    {}/{}: {a:.2} {b:.2} {c:.2} {d:.2}",
                u.name,
                u.sessions.get(&s).cloned().unwrap_or_default()
            );
        }
    }
    let kappas: Vec<forms::FactorKappas> = ROUND4_FACTORS
        .iter()
        .map(|f| forms::FactorKappas::of(&units, *f))
        .collect();
    println!("  κ scored in {:.0} s", t0.elapsed().as_secs_f64());
    println!(
        "  two-session κ per unit under each factor, and the 9 units' median (a product default):"
    );
    for fk in &kappas {
        println!(
            "    {:<24} {}  median {:.3}",
            fk.factor.name(),
            fk.two_session
                .iter()
                .map(|k| format!("{k:.3}"))
                .collect::<Vec<_>>()
                .join(" "),
            realdata::fleet_scale(&fk.two_session)
        );
    }
    let mut variants = Vec::new();
    for fk in &kappas {
        for iso_scaled in [false, true] {
            for t_corrected in [false, true] {
                variants.push((
                    forms::Variant {
                        factor: fk.factor,
                        iso_scaled,
                        t_corrected,
                    },
                    fk,
                ));
            }
        }
    }
    println!(
        "  nested coverage per unit ({}), in the band 88–99 %, pooled:",
        units
            .iter()
            .map(|u| u.name.as_str())
            .collect::<Vec<_>>()
            .join(" ")
    );
    let mut table = Vec::new();
    let mut results = Vec::new();
    for (v, fk) in &variants {
        let r = forms::nested(&units, v, fk);
        let cov: Vec<(f64, usize)> = r.iter().map(|x| (x.covered, x.probings)).collect();
        let (inside, _) = forms::merit(&cov);
        let n: usize = cov.iter().map(|c| c.1).sum();
        let pooled = cov.iter().map(|(c, p)| c * *p as f64).sum::<f64>() / n.max(1) as f64;
        println!(
            "    {:<40} {}  — {inside}/{} in, pooled {pooled:.3}",
            v.name(),
            r.iter()
                .map(|x| format!("{:.3}", x.covered))
                .collect::<Vec<_>>()
                .join(" "),
            r.len()
        );
        table.push(cov);
        results.push(r);
    }
    println!("  median U95 mm per unit:");
    for ((v, _), r) in variants.iter().zip(&results) {
        println!(
            "    {:<40} {}",
            v.name(),
            r.iter()
                .map(|x| format!("{:.3}", x.median_u95))
                .collect::<Vec<_>>()
                .join(" ")
        );
    }
    println!(
        "  sensitivity, not a selection: the product's κ (validated and fleet) times m, \
         nested coverage per unit"
    );
    for m in [0.0, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0] {
        let mut fk = kappas[0].clone();
        fk.two_session.iter_mut().for_each(|k| *k *= m);
        fk.validated.iter_mut().flatten().for_each(|k| *k *= m);
        let r = forms::nested(&units, &variants[0].0, &fk);
        println!(
            "    m = {m:<4} {}",
            r.iter()
                .map(|x| format!("{:.3}", x.covered))
                .collect::<Vec<_>>()
                .join(" ")
        );
    }
    let louo = forms::leave_one_unit_out(&table);
    let n: usize = table[0].iter().map(|c| c.1).sum();
    let pooled = louo
        .iter()
        .zip(&table[0])
        .map(|((_, c), (_, p))| c * *p as f64)
        .sum::<f64>()
        / n.max(1) as f64;
    println!("  the choice among the variants, each unit judged by the choice of the other units:");
    for ((b, c), u) in louo.iter().zip(&units) {
        println!("    {:<12} {:<40} {c:.3}", u.name, variants[*b].0.name());
    }
    println!(
        "    {} of {} in the band, pooled {pooled:.3}",
        louo.iter()
            .filter(|(_, c)| (forms::BAND.0..=forms::BAND.1).contains(c))
            .count(),
        louo.len()
    );
    println!(
        "  intervals (95 %): per unit Wilson over its probings (as if independent), pooled by \
         resampling whole sessions (20,000 draws)"
    );
    for &v in &[0usize, 4] {
        intervals(&variants[v].0.name(), &units, &results[v]);
    }
    let chosen: Vec<usize> = louo.iter().map(|(b, _)| *b).collect();
    if chosen.windows(2).all(|w| w[0] == w[1]) {
        if let Some(&b) = chosen.first() {
            intervals(&variants[b].0.name(), &units, &results[b]);
        }
    }
    let mut shown: Vec<usize> = vec![0, 4];
    for (b, _) in &louo {
        if !shown.contains(b) {
            shown.push(*b);
        }
    }
    for &v in &shown {
        println!(
            "  {}: per fold κ (* fleet), τ mm, median U95 mm, median share of its trace              [parameters, own, pose, isotropic], coverage",
            variants[v].0.name()
        );
        for (u, r) in units.iter().zip(&results[v]) {
            for j in &r.folds {
                let mut us: Vec<f64> = j.rows.iter().map(|x| x.1).collect();
                us.sort_by(f64::total_cmp);
                let share = |k: usize| {
                    let mut s: Vec<f64> = j
                        .rows
                        .iter()
                        .map(|x| x.2[k] / x.2.iter().sum::<f64>().max(1e-300))
                        .collect();
                    s.sort_by(f64::total_cmp);
                    s.get(s.len() / 2).copied().unwrap_or(f64::NAN)
                };
                println!(
                    "    {}/{}: κ {:.3}{} τ {:.4} U95 {:.3} [{:.2} {:.2} {:.2} {:.2}] {:.3} of {}",
                    u.name,
                    u.sessions.get(&j.session).cloned().unwrap_or_default(),
                    j.kappa,
                    if j.validated { "" } else { "*" },
                    j.tau,
                    us.get(us.len() / 2).copied().unwrap_or(f64::NAN),
                    share(0),
                    share(1),
                    share(2),
                    share(3),
                    j.rows.iter().filter(|x| x.0).count() as f64 / j.rows.len().max(1) as f64,
                    j.rows.len()
                );
            }
        }
    }
    println!("  round 4 took {:.0} s", t0.elapsed().as_secs_f64());
}

/// One variant's per-unit Wilson intervals and its pooled session-bootstrap interval.
fn intervals(name: &str, units: &[forms::UnitRows], r: &[forms::UnitResult]) {
    let mut sessions = Vec::new();
    let cells: Vec<String> = units
        .iter()
        .zip(r)
        .map(|(u, x)| {
            let k: usize = x.folds.iter().flat_map(|j| &j.rows).filter(|r| r.0).count();
            sessions.extend(
                x.folds
                    .iter()
                    .map(|j| (j.rows.iter().filter(|r| r.0).count(), j.rows.len())),
            );
            let (lo, hi) = forms::wilson(k, x.probings);
            format!("{} {:.3} [{lo:.3}, {hi:.3}]", u.name, x.covered)
        })
        .collect();
    let (k, n) = sessions
        .iter()
        .fold((0, 0), |(a, b), (k, n)| (a + k, b + n));
    let (lo, hi) = forms::session_bootstrap(&sessions, 20_000, 27);
    println!(
        "    {name}: {}; pooled {:.3} [{lo:.3}, {hi:.3}] over {} sessions",
        cells.join(", "),
        k as f64 / n.max(1) as f64,
        sessions.len()
    );
}

/// The units with ≥ 3 sessions, their two-session scores under each of [`COLUMNS`] (plus ℓ
/// last) and each unit's conformal κ per column.
struct Variants {
    loaded: Vec<armcal::mukca::Unit>,
    scores: Vec<Vec<(i64, Vec<f64>)>>,
    kappa: Vec<Vec<f64>>,
}

impl Variants {
    fn score(loaded: Vec<armcal::mukca::Unit>) -> Variants {
        let scores: Vec<Vec<(i64, Vec<f64>)>> = loaded
            .iter()
            .map(|u| realdata::two_group_scores_by_form(u, &FORMS))
            .collect();
        let kappa = scores
            .iter()
            .map(|sc| {
                (0..COLUMNS.len())
                    .map(|f| conformal_scale(sc.iter().map(|r| r.1[f]).collect()))
                    .collect()
            })
            .collect();
        Variants {
            loaded,
            scores,
            kappa,
        }
    }

    /// The other units' κ under column `f`.
    fn others(&self, k: usize, f: usize) -> Vec<f64> {
        self.kappa
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != k)
            .map(|(_, v)| v[f])
            .collect()
    }

    /// Unit `k`'s share of scores under column `f` covered at κ = `at`.
    fn covered(&self, k: usize, f: usize, at: f64) -> f64 {
        let sc = &self.scores[k];
        sc.iter().filter(|r| r.1[f] <= at).count() as f64 / sc.len().max(1) as f64
    }

    fn three(&self) -> Vec<usize> {
        (0..self.loaded.len())
            .filter(|&k| self.loaded[k].groups().len() == 3)
            .collect()
    }

    fn print_kappa(&self) {
        println!("  two-session κ per unit (conformal over its pair-trained scores), per form:");
        for (f, name) in COLUMNS.iter().enumerate() {
            println!(
                "    {name:<24} {}",
                self.loaded
                    .iter()
                    .zip(&self.kappa)
                    .map(|(u, k)| format!("{} {:.3}", u.name, k[f]))
                    .collect::<Vec<_>>()
                    .join("  ")
            );
        }
    }

    /// Every score to `target/tmp/mukca-forms.json`, for analyses beyond these tables.
    fn dump(&self) {
        let units: Vec<_> = self
            .loaded
            .iter()
            .zip(&self.scores)
            .map(
                |(u, sc)| serde_json::json!({"unit": u.name, "sessions": u.sessions, "scores": sc}),
            )
            .collect();
        let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("mukca-forms.json");
        let json = serde_json::json!({"columns": COLUMNS, "units": units});
        match std::fs::write(&path, json.to_string()) {
            Ok(()) => println!("  scores written to {}", path.display()),
            Err(e) => println!("  {}: {e}", path.display()),
        }
    }

    fn print_forms(&self) {
        let three = self.three();
        println!(
            "  3-session units, nested coverage (κ = median of the other units' κ; in 88–99 %?):"
        );
        for (f, name) in COLUMNS.iter().enumerate() {
            let cells: Vec<(f64, f64)> = three
                .iter()
                .map(|&k| {
                    let at = realdata::fleet_scale(&self.others(k, f));
                    (self.covered(k, f, at), at)
                })
                .collect();
            println!(
                "    {name:<24} {}  — {} of {} in the band",
                three
                    .iter()
                    .zip(&cells)
                    .map(|(&k, (c, at))| format!("{} {c:.3} (κ {at:.2})", self.loaded[k].name))
                    .collect::<Vec<_>>()
                    .join("  "),
                cells.iter().filter(|(c, _)| in_band_of(*c)).count(),
                cells.len()
            );
        }
    }

    fn print_few_groups(&self) {
        for f in [2, 6] {
            println!("  few-groups factors, form {}:", COLUMNS[f]);
            for k in self.three() {
                let mut o = self.others(k, f);
                o.sort_by(f64::total_cmp);
                let rank = ((0.95 * (o.len() + 1) as f64).ceil() as usize).clamp(1, o.len().max(1));
                let by_rank = o.get(rank - 1).copied().unwrap_or(0.0);
                let rows: Vec<f64> = self
                    .scores
                    .iter()
                    .enumerate()
                    .filter(|(j, _)| *j != k)
                    .flat_map(|(_, sc)| sc.iter().map(|r| r.1[f]))
                    .collect();
                let pooled = conformal_scale(rows);
                let t = T_ONE_DOF * realdata::fleet_scale(&o);
                println!(
                    "    {:<12} units' conformal rank {by_rank:.3} → {:.3}; other units' rows \
                     pooled {pooled:.3} → {:.3}; Student t (1 dof) × median {t:.3} → {:.3}",
                    self.loaded[k].name,
                    self.covered(k, f, by_rank),
                    self.covered(k, f, pooled),
                    self.covered(k, f, t)
                );
            }
        }
    }

    fn print_sessions(&self) {
        println!(
            "  per scored session (pairs of the others trained): leverage ratio ℓ median, 90th \
             percentile; κ95 at λ = 0.5"
        );
        for (u, sc) in self.loaded.iter().zip(&self.scores) {
            for (g, name) in &u.sessions {
                let mut l: Vec<f64> = sc.iter().filter(|r| r.0 == *g).map(|r| r.1[7]).collect();
                if l.is_empty() {
                    continue;
                }
                l.sort_by(f64::total_cmp);
                let k95 =
                    conformal_scale(sc.iter().filter(|r| r.0 == *g).map(|r| r.1[2]).collect());
                println!(
                    "    {}/{name}: ℓ {:.2}, {:.2}; κ95 {k95:.2}",
                    u.name,
                    l[l.len() / 2],
                    l[(9 * l.len()) / 10]
                );
            }
        }
    }

    /// Each unit's nested coverage under the rule `rule(k)` for unit k (the pooled rule only
    /// changes units with ≥ 4 sessions, so 3-session units are skipped for it).
    fn print_nested(&self, title: &str, rule: impl Fn(usize) -> realdata::Rule) {
        println!("  {title}:");
        let (mut inside, mut judged) = (0.0, 0usize);
        for (k, u) in self.loaded.iter().enumerate() {
            let r = rule(k);
            if r.prior_groups > 0.0 && u.groups().len() < 4 {
                continue;
            }
            let Some(c) = realdata::unit_coverage(u, r) else {
                continue;
            };
            println!(
                "    {:<12} nested {:.3} of {} ({}), median U95 {:.4} mm, κ per session {}; \
                 per session {}",
                c.unit,
                c.covered_nested,
                c.probings,
                if in_band_of(c.covered_nested) {
                    "in the band"
                } else {
                    "outside"
                },
                c.nested_u95_mm,
                c.pose_scale
                    .iter()
                    .map(|(k, _)| format!("{k:.2}"))
                    .collect::<Vec<_>>()
                    .join(" "),
                c.per_session
                    .iter()
                    .map(|(s, _, f, ..)| format!("{s} {f:.3}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
            inside += c.covered_nested * c.probings as f64;
            judged += c.probings;
        }
        println!(
            "    pooled {:.3} of {judged} (the units shown)",
            inside / judged.max(1) as f64
        );
    }
}
