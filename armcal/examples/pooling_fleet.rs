//! Power from the fleet (issue 30): the shoulder's gravity compliance pooled over a design's
//! arms ([`armcal::diagnose::pooling`]), on a simulated fleet of 8 arms whose compliances are
//! spread ±50 % around a mean, on null fleets (nothing hidden, false names counted over
//! seeds), and on MUKCa's Panda arms, with panda_4's pooled compliance and its nested held-out
//! gain: one recording per physical arm (as before), then every recording of an arm of three
//! sessions or more, each with its own probe and frame, combined by inverse variance, under
//! the grouping MUKCa documents and under the one the data give.
//!
//!     cargo run --release -p armcal --example pooling_fleet [seeds [mean compliance]]

use armcal::data::{Dataset, Kind};
use armcal::diagnose::fleet::{self, ErrorScale, UnitData};
use armcal::diagnose::fleet_pooled::pool_arms;
use armcal::diagnose::pooling::{self, Arm as Pooled, Design};
use armcal::diagnose::{self, FoldChoice};
use armcal::fit::options::Options as CalibOptions;
use armcal::mukca;
use armcal::params::Effect;
use armcal::sim;
use armcal::stats::{min_sign_p, sign_test_p, Paired};
use quatarm_ref::arm::Arm;

const ALPHA: f64 = 0.05;
const ROWS: usize = 120;
const SESSIONS: usize = 4;

/// A `default-6` arm with its own geometric errors and a shoulder compliance `g` (rad/mm):
/// `ROWS` tracker points in `SESSIONS` sessions.
fn arm_data(seed: u64, g: f64) -> Dataset {
    let mut rng = armcal::rng::rng(seed);
    let mut truth = sim::perturb(&Arm::default6(), 3e-4, 0.3, &mut rng);
    truth.joints[1].gravity = g;
    let d = sim::simulate(&truth, &sim::Options::new(Kind::Point, ROWS), &mut rng)
        .expect("simulation")
        .data;
    let rows = d
        .rows
        .into_iter()
        .enumerate()
        .map(|(i, mut r)| {
            r.group = 1 + (i % SESSIONS) as i64;
            r
        })
        .collect();
    Dataset::from_rows(rows, 6, false, "(simulated arm)").expect("rows")
}

fn opts() -> CalibOptions {
    CalibOptions {
        design_check: false,
        allow_degenerate: true,
        ..CalibOptions::default()
    }
}

/// Each arm's estimate (value, jackknife se, its df) of joint 2's compliance.
fn estimates(arms: &[(Arm, Dataset)], o: &CalibOptions) -> Vec<pooling::Estimate> {
    arms.iter()
        .map(|(start, d)| {
            pooling::estimate(start, d, o, Effect::Gravity(1))
                .expect("fit")
                .expect("three sessions")
        })
        .collect()
}

/// The arms' estimates pooled at `ALPHA`.
fn pool_estimates(est: &[pooling::Estimate]) -> (Design, Vec<Pooled>) {
    let y: Vec<f64> = est.iter().map(|e| e.value).collect();
    let se: Vec<f64> = est.iter().map(|e| e.se).collect();
    let df: Vec<f64> = est.iter().map(|e| e.df).collect();
    pooling::pool(&y, &se, &df, ALPHA).expect("pool")
}

fn print_pooled(names: &[String], d: &Design, arms: &[Pooled], unit: f64, uname: &str) {
    println!(
        "  design: mean {:+.3} {uname} (95 % [{:+.3}, {:+.3}], p = {:.2e}), spread τ {:.3} (95 % [{:.3}, {:.3}]), named: {}",
        d.mean / unit,
        d.mean_interval[0] / unit,
        d.mean_interval[1] / unit,
        d.mean_p,
        d.spread / unit,
        d.spread_interval[0] / unit,
        d.spread_interval[1] / unit,
        d.named
    );
    for (n, a) in names.iter().zip(arms) {
        println!(
            "    {n:<10} alone {:+.3} ± {:.3} (named {:<5})  pooled {:+.3} ± {:.3} ({:.1} df, B = {:.2}, named {})",
            a.estimate / unit,
            a.se / unit,
            a.named_alone,
            a.pooled / unit,
            a.pooled_se / unit,
            a.df,
            a.shrinkage,
            a.named_pooled
        );
    }
}

fn simulated(seeds: u64, mean: f64) {
    let gs: Vec<f64> = (0..8).map(|k| mean * (0.5 + k as f64 / 7.0)).collect();
    println!(
        "simulated fleet: 8 arms, joint-2 compliance {:.2}…{:.2}e-8 rad/mm (mean {:.1}e-8 ± 50 %), {ROWS} points in {SESSIONS} sessions each",
        gs[0] * 1e8,
        gs[7] * 1e8,
        mean * 1e8
    );
    let arms: Vec<(Arm, Dataset)> = gs
        .iter()
        .enumerate()
        .map(|(k, &g)| (Arm::default6(), arm_data(500 + k as u64, g)))
        .collect();
    let (d, pooled) = pool_estimates(&estimates(&arms, &opts()));
    let names: Vec<String> = gs.iter().map(|g| format!("g={:.2}e-8", g * 1e8)).collect();
    print_pooled(&names, &d, &pooled, 1e-8, "e-8 rad/mm");
    // The single-arm diagnosis (sessions held out, the whole vocabulary up to order 1).
    let dopts = diagnose::Options {
        folds: FoldChoice::ByGroup,
        max_order: 1,
        ..diagnose::Options::default()
    };
    let mut named_single = 0;
    for (i, (start, data)) in arms.iter().enumerate() {
        let causes: Vec<String> = match diagnose::diagnose(start, data, &dopts) {
            Ok(dg) => dg.extended.effects.iter().map(|e| e.spec()).collect(),
            Err(e) => vec![format!("error: {e}")],
        };
        if causes.iter().any(|c| c == &Effect::Gravity(1).spec()) {
            named_single += 1;
        }
        println!(
            "    {:<10} single-arm diagnosis names: [{}]",
            names[i],
            causes.join(" ")
        );
    }
    println!(
        "  named for the arm: single-arm diagnosis {named_single}/8, own estimate alone {}/8, pooled {}/8",
        pooled.iter().filter(|a| a.named_alone).count(),
        pooled.iter().filter(|a| a.named_pooled).count()
    );

    println!("null fleets: 8 arms with nothing hidden, {seeds} seeds");
    let (mut design_named, mut arm_names_pooled, mut arm_names_alone, mut fleets_alone) =
        (0, 0, 0, 0);
    for s in 0..seeds {
        let arms: Vec<(Arm, Dataset)> = (0..8)
            .map(|k| (Arm::default6(), arm_data(10_000 + 100 * s + k, 0.0)))
            .collect();
        let (d, pooled) = pool_estimates(&estimates(&arms, &opts()));
        design_named += d.named as usize;
        arm_names_pooled += pooled.iter().filter(|a| a.named_pooled).count();
        let alone = pooled.iter().filter(|a| a.named_alone).count();
        arm_names_alone += alone;
        fleets_alone += (alone > 0) as usize;
    }
    println!(
        "  design mean named in {design_named}/{seeds} fleets; arms named pooled {arm_names_pooled}/{}; \
         arms named by their own estimate alone {arm_names_alone}/{} (in {fleets_alone}/{seeds} fleets)",
        8 * seeds,
        8 * seeds
    );
}

/// MUKCa's Panda recordings pooled under one grouping into arms (name, recordings): every
/// recording of 3 sessions or more gives its own estimate (its own probe and frame), an arm's
/// recordings are combined by inverse variance, the arms pooled; then panda_4's nested
/// held-out gain with its pooled compliance fixed.
/// One way of pooling the fleet's scale in [`mukca_grouping`]: its name, the arms joined
/// without a jackknife (value, in-sample error) and their names.
type Way<'a> = (&'a str, &'a [(f64, f64)], &'a [String]);

fn mukca_grouping(
    title: &str,
    grouping: &[(&str, &[&str])],
    units: &[UnitData],
    start: &Arm,
    o: &fleet::Options,
) {
    println!("{title}");
    let index = |n: &str| units.iter().position(|u| u.name == n).expect("loaded");
    let arms: Vec<(String, Vec<usize>)> = grouping
        .iter()
        .map(|(a, recs)| (a.to_string(), recs.iter().map(|r| index(r)).collect()))
        .collect();
    let testable = vec![vec![Effect::Gravity(1)]; units.len()];
    let pooled = pool_arms(start, units, &arms, &testable, o).expect("pooled");
    let Some(p) = pooled.effects.first() else {
        println!("  nothing pooled");
        return;
    };
    let d = &p.design;
    println!(
        "  design: {} arms, mean {:+.3} µrad/mm (95 % [{:+.3}, {:+.3}], p = {:.3}), spread τ {:.3} (95 % [{:.3}, {:.3}])",
        d.arms,
        d.mean * 1e6,
        d.mean_interval[0] * 1e6,
        d.mean_interval[1] * 1e6,
        d.mean_p,
        d.spread * 1e6,
        d.spread_interval[0] * 1e6,
        d.spread_interval[1] * 1e6
    );
    for a in &p.arms {
        let per: Vec<String> = a
            .recordings
            .iter()
            .zip(&a.per_recording)
            .map(|(r, e)| format!("{r} {:+.3} ± {:.3}", e.value * 1e6, e.se * 1e6))
            .collect();
        println!(
            "    {:<8} {} → alone {:+.3} ± {:.3}{}; pooled {:+.3} ± {:.3} (plug-in ± {:.3}, {:.1} df, B = {:.2}, named {})",
            a.arm,
            per.join(", "),
            a.value.estimate * 1e6,
            a.value.se * 1e6,
            if a.combined.recordings > 1 {
                format!(" (Q = {:.2}, p = {:.2})", a.combined.q, a.combined.q_p)
            } else {
                String::new()
            },
            a.value.pooled * 1e6,
            a.value.pooled_se * 1e6,
            a.value.pooled_se_plugin * 1e6,
            a.value.df,
            a.value.shrinkage,
            a.value.named_pooled
        );
    }
    for (who, why) in &pooled.left_out {
        println!("    {who} left out: {why}");
    }
    // The error's scale pooled across the arms (claims.md §7.10): each recording's ratio of
    // its jackknife variance to its fit's in-sample one, the arms' pooled φ̂ and the
    // homogeneity test of their ratios, and the arms pooled with s̃ = √φ̂·v where it passes.
    for a in &p.arms {
        let r: Vec<String> = a
            .recordings
            .iter()
            .zip(&a.per_recording)
            .map(|(n, e)| {
                format!(
                    "{n}: model se {:.4}, r = s²/v² {:.1} ({} df)",
                    e.model_se * 1e6,
                    (e.se / e.model_se).powi(2),
                    e.df
                )
            })
            .collect();
        println!("    ratio {:<8} {}", a.arm, r.join("; "));
    }
    let y: Vec<f64> = p.arms.iter().map(|a| a.value.estimate).collect();
    let se: Vec<f64> = p.arms.iter().map(|a| a.value.se).collect();
    let df: Vec<f64> = p.arms.iter().map(|a| a.value.se_df).collect();
    let v: Vec<f64> = p.arms.iter().map(|a| a.combined.model_se).collect();
    // Arms with no recording of 3 sessions (no jackknife error: panda_7's 2 sessions) join
    // through the fleet's scale: their recording of most sessions (2 or more), fitted once.
    let mut joined_names = Vec::new();
    let mut joined = Vec::new();
    for (name, recs) in grouping
        .iter()
        .filter(|(a, _)| p.arms.iter().all(|b| b.arm != *a))
    {
        let best = recs
            .iter()
            .map(|r| &units[index(r)])
            .max_by_key(|u| armcal::fit::holdout::by_group(&u.data).len())
            .filter(|u| armcal::fit::holdout::by_group(&u.data).len() >= 2);
        let Some(u) = best else { continue };
        let geo = fleet::geometric_options(o);
        if let Ok(Some(e)) = pooling::estimate_in_sample(start, &u.data, &geo, Effect::Gravity(1)) {
            println!(
                "    {name} (recording {}, {} sessions, no jackknife): {:+.3}, model se {:.4}",
                u.name,
                armcal::fit::holdout::by_group(&u.data).len(),
                e.0 * 1e6,
                e.1 * 1e6
            );
            joined_names.push(name.to_string());
            joined.push(e);
        }
    }
    // As `armcal diagnose --fleet` pools (the arms of 3 sessions or more), then with the arms
    // of 2 sessions joined.
    let ways: [Way; 2] = [
        ("as diagnose --fleet", &[], &[]),
        ("arms of 2 sessions joined", &joined, &joined_names),
    ];
    for (way, joined, joined_names) in ways {
        if way != ways[0].0 && joined.is_empty() {
            continue;
        }
        println!("  {way}:");
        match pooling::pool_fleet_scale_joined(&y, &se, &df, &v, joined, ALPHA) {
            Some((disp, scaled, fd, farms)) => {
                if let Some(disp) = disp {
                    let rs: Vec<String> = disp.ratios.iter().map(|r| format!("{r:.1}")).collect();
                    println!(
                        "  error's scale across the arms: r = [{}], φ̂ = {:.1} on {:.1} df, Bartlett {:.2} (p = {:.3}): scale {}",
                        rs.join(", "),
                        disp.phi,
                        disp.df,
                        disp.bartlett,
                        disp.p,
                        if scaled { "pooled" } else { "not pooled (the arms' own errors)" }
                    );
                }
                println!(
                    "  pooled with it: design mean {:+.3} µrad/mm (p = {:.3}), spread τ {:.3}",
                    fd.mean * 1e6,
                    fd.mean_p,
                    fd.spread * 1e6
                );
                let names = p
                    .arms
                    .iter()
                    .map(|a| a.arm.clone())
                    .chain(joined_names.iter().cloned());
                for (a, f) in names.zip(&farms) {
                    println!(
                        "    {:<8} s̃ {:.3} ({:.0} df) → pooled {:+.3} ± {:.3} ({:.0} df, named {})",
                        a,
                        f.se * 1e6,
                        f.se_df,
                        f.pooled * 1e6,
                        f.pooled_se * 1e6,
                        f.df,
                        f.named_pooled
                    );
                }
            }
            None => println!("  error's scale across the arms: not pooled"),
        }
    }
    // panda_4 (one recording): its pooled value from its other sessions and the other arms.
    let i4 = p
        .arms
        .iter()
        .position(|a| a.arm == "panda_4")
        .expect("panda_4");
    let others: Vec<pooling::Estimate> = p
        .arms
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != i4)
        .map(|(_, a)| pooling::Estimate {
            value: a.value.estimate,
            se: a.value.se,
            df: a.value.se_df,
            model_se: a.combined.model_se,
        })
        .collect();
    let folds = pooling::pooled_holdout(
        start,
        &units[index("panda_4")].data,
        &fleet::geometric_options(o),
        Effect::Gravity(1),
        &[],
        &others,
        ALPHA,
    )
    .expect("panda_4");
    let (b, a): (Vec<f64>, Vec<f64>) = folds.iter().map(|f| (f.before_ms, f.after_ms)).unzip();
    let values: Vec<f64> = folds.iter().map(|f| f.value * 1e6).collect();
    let p = Paired::of(&b, &a);
    let better = b.iter().zip(&a).filter(|(x, y)| y < x).count();
    let n = b.len();
    let rms = |x: &[f64]| 1e3 * (x.iter().sum::<f64>() / n.max(1) as f64).sqrt();
    println!(
        "  panda_4 with its pooled compliance fixed (nested; θ̃ {:.2}…{:.2} µrad/mm over the folds): RMS {:.1} → {:.1} µm, better on {better}/{n}, \
         paired t = {:.2} ({} df, one-sided p = {:.3}), sign test p = {:.4} (smallest possible {:.4})",
        values.iter().copied().fold(f64::INFINITY, f64::min),
        values.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        rms(&b),
        rms(&a),
        p.z(),
        n.saturating_sub(1),
        p.p_value(),
        sign_test_p(better, n),
        min_sign_p(n)
    );
}

fn mukca_fleet() {
    let dir = mukca::default_dir();
    let names = [
        "panda_1",
        "panda_1_with_sensor",
        "panda_2",
        "panda_left",
        "panda_3",
        "panda_3_bis",
        "panda_right",
        "panda_4",
        "panda_6",
        "panda_7",
    ];
    let loaded: Vec<mukca::Unit> = names
        .iter()
        .map(|n| mukca::load(&dir, n).expect("unit"))
        .collect();
    let start = loaded[2].arm.clone();
    let units: Vec<UnitData> = loaded
        .into_iter()
        .map(|u| UnitData {
            name: u.name,
            file: format!("{}.csv", u.stem),
            data: u.data,
        })
        .collect();
    // Each arm first on its own jackknife errors (`ErrorScale::Own`), then the same estimates
    // on the fleet's error scale (the product's default since stop 40) in each grouping's
    // "error's scale across the arms" lines, with panda_7 joined there.
    let o = fleet::Options {
        alpha: ALPHA,
        error_scale: ErrorScale::Own,
        ..fleet::Options::default()
    };
    println!("MUKCa Panda arms, joint-2 compliance (µrad/mm; session jackknife errors, then the fleet's error scale; each recording fitted with its own probe and frame)");
    mukca_grouping(
        "one recording per physical arm (the table before issue 30's refit: panda_3_bis and panda_1 left out)",
        &[
            ("panda_2", &["panda_2"]),
            ("panda_3", &["panda_3"]),
            ("panda_4", &["panda_4"]),
            ("panda_6", &["panda_6"]),
            ("panda_7", &["panda_7"]),
        ],
        &units,
        &start,
        &o,
    );
    mukca_grouping(
        "every recording; arms as MUKCa documents or names them (panda_right with panda_3 and panda_left with panda_2: the \
         bimanual command of its README; panda_3_bis with panda_3 and panda_1_with_sensor with panda_1: the recordings' names); panda_1 its own arm",
        &[
            ("panda_1", &["panda_1", "panda_1_with_sensor"]),
            ("panda_2", &["panda_2", "panda_left"]),
            ("panda_3", &["panda_3", "panda_3_bis", "panda_right"]),
            ("panda_4", &["panda_4"]),
            ("panda_6", &["panda_6"]),
            ("panda_7", &["panda_7"]),
        ],
        &units,
        &start,
        &o,
    );
    mukca_grouping(
        "every recording; arms as the data group them (armcal diagnose --fleet's detection: panda_1 with panda_2 too)",
        &[
            (
                "panda_2",
                &["panda_2", "panda_1", "panda_1_with_sensor", "panda_left"],
            ),
            ("panda_3", &["panda_3", "panda_3_bis", "panda_right"]),
            ("panda_4", &["panda_4"]),
            ("panda_6", &["panda_6"]),
            ("panda_7", &["panda_7"]),
        ],
        &units,
        &start,
        &o,
    );
}

fn main() {
    let seeds: u64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(20);
    // The fleet's mean compliance (rad/mm): 2.5e-9 is where a single arm's 120 points in 4
    // sessions leave it near its noise.
    let mean: f64 = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(2.5e-9);
    let t = std::time::Instant::now();
    mukca_fleet();
    println!("({:.0} s)\n", t.elapsed().as_secs_f64());
    simulated(seeds, mean);
    println!("({:.0} s)", t.elapsed().as_secs_f64());
}
