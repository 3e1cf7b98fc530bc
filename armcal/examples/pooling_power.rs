//! Power and false causes of the pooled stage of `armcal diagnose --fleet` over seeds (issue
//! 30, rounds 4–5): simulated fleets of 8 `default-6` arms (120 tracker points in 4 sessions
//! each). Every one-unknown candidate the arms can test is pooled and named as the product
//! did until stop 40 ([`armcal::diagnose::fleet_pooled::pool_candidates`] with each arm's own
//! jackknife error, `ErrorScale::Own`: Holm over the candidates at the fleet's α = 0.01, each
//! arm by its pooled 99 % interval, t on its own error's degrees of freedom or arms − 1 where
//! fewer; the columns "own errors"), and the shoulder's candidate is also named by every rule
//! of [`armcal::diagnose::pooling_rules`] (the single-arm test among them).
//!
//! Three kinds of fleet:
//! - **the power curve**: the shoulder's gravity compliance spread ±50 % over the 8 arms
//!   around each of the means 2.5, 5, 7.5 and 10e-9 rad/mm (`seeds` fleets each, the same
//!   seeds at every mean: seed 500 + 100 s + arm, s = 0…, the first being §6's fleet);
//! - **the null fleet**: nothing hidden (`null_seeds` fleets, seeds 10 000 + 100 s + arm): any
//!   arm named is a false cause;
//! - **the mixed fleets**: 6 (then 7) arms with the compliance spread ±50 % around 1e-8 rad/mm
//!   and 2 (then 1) without it (`mixed_seeds` fleets each, seeds 30 000 + 100 s + arm): where
//!   the design's mean passes, the arms without the effect that a rule names are its false
//!   causes.
//!
//! Every rule is counted at the fleet's α = 0.01 and at 0.05 (the same estimates re-pooled,
//! Holm over the candidates at 0.05).
//!
//!     cargo run --release -p armcal --example pooling_power [seeds [null_seeds [mixed_seeds [parts]]]]
//!
//! `parts` (all by default) picks fleets: a comma-separated list of `spread`, `null`, `mixed6`,
//! `mixed7` (`pooling_power 0 0 300 mixed7`: the 7+1 mixed fleet over 300 seeds); `full` among
//! them also pools every candidate in the **full model** (each conditional on all the others,
//! [`armcal::diagnose::fleet_pooled::pool_candidates_full`]) and counts its product naming of
//! the shoulder's candidate as two more columns (`full model @ 0.01`, `@ 0.05`) and its other
//! candidates named apart (claims.md §7.9). `full` alone runs every fleet with it
//! (`pooling_power 20 40 30 full`; `pooling_power 0 0 300 mixed7,full`).
//!
//! Every fleet also counts `Rule::FleetScale` (claims.md §7.10), the shoulder's candidate
//! re-pooled with the error's scale pooled across the fleet
//! ([`armcal::diagnose::pooling::pool_fleet_scale`], its gate by Holm with the other
//! candidates' product p-values), and prints per fleet kind: its design passes, how often the
//! ratios' homogeneity test failed (the arms' own errors used), φ̂'s median and range, each
//! arm's pooled 99 % and 95 % intervals holding its true compliance (own errors and fleet
//! scale), and of the pairs with the effect the single arm does not name, how many each names.
//! Last, the lines "fleet scale on every candidate": the product's naming since stop 40
//! (`ErrorScale::Fleet`), every candidate re-pooled from the same estimates
//! ([`armcal::diagnose::fleet_pooled::repool`]) and named by Holm over their own p-values, with
//! the other candidates it names (claims.md §7.11).
//!
//! 20, 40 and 30 by default: 180 fleets, 7.5 minutes release on the shared 2-core
//! machine (docs/results/claims.md §7.6).

use armcal::data::{Dataset, Kind};
use armcal::diagnose::candidates;
use armcal::diagnose::fleet::ErrorScale;
use armcal::diagnose::fleet::{self, UnitData};
use armcal::diagnose::fleet_pooled::{pool_candidates, pool_candidates_full, repool, PooledEffect};
use armcal::diagnose::pooling::{self, t_critical, Arm as PooledArm};
use armcal::diagnose::pooling_rules::{Rule, RULES};
use armcal::params::Effect;
use armcal::sim;
use quatarm_ref::arm::Arm;

const ROWS: usize = 120;
const SESSIONS: usize = 4;
const ARMS: usize = 8;

/// The means of the power curve (rad/mm).
const MEANS: [f64; 4] = [2.5e-9, 5e-9, 7.5e-9, 1e-8];

/// The mean of the mixed fleets' arms with the effect (rad/mm): every such arm's own estimate
/// names it in 0.73 of (fleet, arm) pairs at α = 0.01 on the spread fleet of this mean.
const MIXED: f64 = 1e-8;

/// Arms of each mixed fleet with the effect (the rest have none): with 2 of 8 without it the
/// design's mean cannot pass Holm at 0.01 over 5 candidates whatever the magnitude (the two
/// zeros make the arms' scatter, and Hartung–Knapp's error, grow with the mean), so the
/// fleet with 1 of 8 without it is where the gate can pass at 0.01.
const MIXED_WITH: [usize; 2] = [6, 7];

/// A `default-6` arm with its own geometric errors and a shoulder compliance `g` (rad/mm).
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

/// The levels every rule is counted at: the fleet's α (Holm over the candidates at 0.01, the
/// product's) and 0.05 (the same estimates re-pooled, Holm at 0.05).
const ALPHAS: [f64; 2] = [0.01, 0.05];

/// Column labels: every rule of [`RULES`] at each of [`ALPHAS`], then (with `full`) the
/// product's rule on the full model's estimates at each of [`ALPHAS`].
fn labels(full: bool) -> Vec<String> {
    let mut out: Vec<String> = ALPHAS
        .iter()
        .flat_map(|a| RULES.iter().map(move |r| format!("{} @ {a}", r.label())))
        .collect();
    if full {
        out.extend(ALPHAS.iter().map(|a| format!("full model @ {a}")));
    }
    out
}

/// The shoulder's candidate as each rule names it, and what the fleet-scale pool
/// ([`pooling::pool_fleet_scale`]) did, at each of [`ALPHAS`].
#[derive(Default)]
struct Shoulder {
    /// Per column of [`labels`] (without the full model's), per arm: named.
    cols: Vec<Vec<bool>>,
    /// Whether the product's design mean passed Holm.
    passed: [bool; 2],
    /// Whether the fleet-scale pool's design mean passed Holm (with the other candidates'
    /// product p-values).
    fs_passed: [bool; 2],
    /// Whether the fleet's scale was used (the ratios' homogeneity test passed at α).
    fs_scaled: [bool; 2],
    /// φ̂ and the homogeneity test's p (`NaN` without a dispersion).
    phi: (f64, f64),
    /// Arms whose pooled interval holds their true compliance: [product, fleet scale] ×
    /// [99 % (pooled at 0.01), 95 % (at 0.05)].
    covered: [[usize; 2]; 2],
}

/// Which arms each column of [`labels`] names for the shoulder's pooled candidate `p`
/// (pooled at the fleet's α, its design named by Holm over the fleet's candidates);
/// `named05` whether its design mean passes Holm at 0.05 over them; `others_p` the other
/// candidates' design-mean p-values (for the fleet-scale pool's own Holm gate); `truth` each
/// arm's true compliance.
fn named(p: &PooledEffect, named05: bool, others_p: &[f64], truth: &[f64]) -> Shoulder {
    let y: Vec<f64> = p.arms.iter().map(|a| a.value.estimate).collect();
    let se: Vec<f64> = p.arms.iter().map(|a| a.value.se).collect();
    let df: Vec<f64> = p.arms.iter().map(|a| a.value.se_df).collect();
    let model: Vec<f64> = p.arms.iter().map(|a| a.combined.model_se).collect();
    let first: Vec<PooledArm> = p.arms.iter().map(|a| a.value).collect();
    let mut sh = Shoulder {
        phi: (f64::NAN, f64::NAN),
        ..Shoulder::default()
    };
    for (i, &alpha) in ALPHAS.iter().enumerate() {
        let (d, arms) = if i == 0 {
            (p.design, first.clone())
        } else {
            match pooling::pool(&y, &se, &df, alpha) {
                Some((mut d, arms)) => {
                    d.named = named05;
                    (d, arms)
                }
                None => (p.design, first.clone()),
            }
        };
        sh.passed[i] = d.named;
        let (fd, farms) = match pooling::pool_fleet_scale(&y, &se, &df, &model, alpha) {
            Some((disp, scaled, mut fd, farms)) => {
                let mut ps = vec![fd.mean_p];
                ps.extend_from_slice(others_p);
                fd.named = fleet::holm(&ps, alpha)[0];
                sh.fs_scaled[i] = scaled;
                if let (0, Some(disp)) = (i, disp) {
                    sh.phi = (disp.phi, disp.p);
                }
                (fd, farms)
            }
            None => (d, arms.clone()),
        };
        sh.fs_passed[i] = fd.named;
        for r in RULES {
            let (d, arms) = if r.fleet_scaled() {
                (&fd, &farms)
            } else {
                (&d, &arms)
            };
            sh.cols
                .push(arms.iter().map(|a| r.names(d, a, alpha)).collect());
        }
        for (c, arms) in sh.covered.iter_mut().zip([&arms, &farms]) {
            c[i] += arms
                .iter()
                .zip(truth)
                .filter(|(a, g)| (a.pooled - **g).abs() <= t_critical(alpha, a.df) * a.pooled_se)
                .count();
        }
    }
    sh
}

/// One fleet's outcome.
struct Outcome {
    /// Per column of [`labels`], per arm: named.
    named: Vec<Vec<bool>>,
    /// Whether the shoulder's design mean passed Holm at each of [`ALPHAS`].
    design: [bool; 2],
    /// The fleet-scale pool of the shoulder's candidate (its `cols` moved to `named`).
    fs: Shoulder,
    /// Other candidates named at the fleet's α (candidate, arms named).
    others: Vec<(String, usize)>,
    /// Whether some other candidate's design mean passed Holm at 0.05.
    others05: bool,
    /// Whether the shoulder's design mean passed Holm at each of [`ALPHAS`] in the full model.
    design_full: [bool; 2],
    /// The full model's other candidates named at the fleet's α (candidate, arms named).
    others_full: Vec<(String, usize)>,
    /// Whether some other candidate's design mean passed Holm at 0.05 in the full model.
    others_full05: bool,
    /// Every candidate pooled with the fleet's error scale (`ErrorScale::Fleet`, the same
    /// estimates [`repool`]ed), at each of [`ALPHAS`]: against the geometric model alone,
    /// then (with `full`) in the full model.
    fleet: Vec<[Everywhere; 2]>,
}

/// The fleet's error scale for every candidate (the product's naming since stop 40), at one α:
/// the shoulder's arms named, whether its design passed, the other candidates named (candidate,
/// arms named).
#[derive(Default)]
struct Everywhere {
    shoulder: Vec<bool>,
    design: bool,
    others: Vec<(String, usize)>,
    /// Arms whose pooled interval (at 1 − α) holds their true value: the shoulder's (its
    /// compliance) and every other candidate's (0), and how many intervals there were.
    covered: [usize; 2],
}

/// [`Everywhere`] of the candidates `effects` pooled again with the fleet's error scale at
/// `alpha`.
fn everywhere(
    p: &armcal::diagnose::fleet_pooled::PooledFleet,
    truth: &[f64],
    alpha: f64,
) -> Everywhere {
    let r = repool(p, ErrorScale::Fleet, alpha);
    let mut out = Everywhere {
        shoulder: vec![false; truth.len()],
        ..Everywhere::default()
    };
    for e in &r.effects {
        let zero = vec![0.0; truth.len()];
        let want = if e.effect == Effect::Gravity(1) {
            truth
        } else {
            &zero
        };
        for (a, g) in e.arms.iter().zip(want) {
            let half = t_critical(alpha, a.value.df) * a.value.pooled_se;
            out.covered[0] += ((a.value.pooled - g).abs() <= half) as usize;
            out.covered[1] += 1;
        }
        if e.effect == Effect::Gravity(1) {
            out.design = e.named;
            out.shoulder = e.arms.iter().map(|a| a.value.named_pooled).collect();
        } else if e.named {
            let n = e.arms.iter().filter(|a| a.value.named_pooled).count();
            out.others.push((e.term.clone(), n));
        }
    }
    out
}

/// The shoulder's candidate named by the product's rule at each of [`ALPHAS`] (per arm), the
/// other candidates named at the fleet's α (candidate, arms named), and whether any other's
/// design mean passed Holm at 0.05, from the pooled candidates `effects`.
type Named = (
    Vec<Vec<bool>>,
    [bool; 2],
    Vec<(String, usize)>,
    bool,
    Shoulder,
);

/// Reads [`Named`] from the pooled candidates `effects` of arms whose true compliances are
/// `truth` (all rules of [`RULES`], or the product's only with `product_only`).
fn read(effects: &[PooledEffect], truth: &[f64], product_only: bool) -> Named {
    let arms = truth.len();
    let ps: Vec<f64> = effects.iter().map(|e| e.design.mean_p).collect();
    let holm05 = fleet::holm(&ps, 0.05);
    let cols = if product_only {
        ALPHAS.len()
    } else {
        ALPHAS.len() * RULES.len()
    };
    let mut out: Named = (
        vec![vec![false; arms]; cols],
        [false; 2],
        Vec::new(),
        false,
        Shoulder::default(),
    );
    for (e, &n05) in effects.iter().zip(&holm05) {
        if e.effect == Effect::Gravity(1) {
            let others_p: Vec<f64> = effects
                .iter()
                .filter(|o| o.effect != e.effect)
                .map(|o| o.design.mean_p)
                .collect();
            let mut sh = named(e, n05, &others_p, truth);
            let all = std::mem::take(&mut sh.cols);
            let design = sh.passed;
            out.4 = sh;
            out.0 = if product_only {
                // The product is the first rule at each α.
                all.into_iter().step_by(RULES.len()).collect()
            } else {
                all
            };
            out.1 = design;
        } else {
            if e.named {
                let arms = e.arms.iter().filter(|a| a.value.named_pooled).count();
                out.2.push((e.term.clone(), arms));
            }
            out.3 |= n05;
        }
    }
    out
}

/// One fleet of compliances `gs` (arm k's data from seed `base + k`); with `full`, also
/// pooled in the full model.
fn fleet_once(gs: &[f64], base: u64, full: bool) -> Outcome {
    let start = Arm::default6();
    let units: Vec<UnitData> = gs
        .iter()
        .enumerate()
        .map(|(k, &g)| UnitData {
            name: format!("arm_{k}"),
            file: format!("arm_{k}.csv"),
            data: arm_data(base + k as u64, g),
        })
        .collect();
    let arms: Vec<(String, Vec<usize>)> = units
        .iter()
        .enumerate()
        .map(|(k, u)| (u.name.clone(), vec![k]))
        .collect();
    let testable: Vec<Vec<Effect>> = units
        .iter()
        .map(|u| {
            candidates::candidates_up_to(&start, &u.data, 1)
                .testable
                .iter()
                .map(|c| c.effect)
                .collect()
        })
        .collect();
    // Each arm's own errors (the product's naming until stop 40), the fleet's error scale
    // counted from the same estimates below.
    let o = fleet::Options {
        error_scale: ErrorScale::Own,
        ..fleet::Options::default()
    };
    let p = pool_candidates(&start, &units, &arms, &testable, &o);
    let both = |p: &_| [everywhere(p, gs, ALPHAS[0]), everywhere(p, gs, ALPHAS[1])];
    let mut fleet = vec![both(&p)];
    let (mut named, design, others, others05, fs) = read(&p.effects, gs, false);
    let (mut others_full, mut others_full05, mut design_full) = (Vec::new(), false, [false; 2]);
    if full {
        let f = pool_candidates_full(&start, &units, &arms, &testable, &o);
        for (what, why) in &f.left_out {
            eprintln!("full model, seed {base}: {what}: {why}");
        }
        let (n, df, of, of05, _) = read(&f.effects, gs, true);
        fleet.push(both(&f));
        named.extend(n);
        (others_full, others_full05, design_full) = (of, of05, df);
    }
    Outcome {
        named,
        design,
        fs,
        others,
        others05,
        others_full,
        others_full05,
        design_full,
        fleet,
    }
}

/// Per column: arms with the effect named, fleets with every such arm named, arms without it
/// named, fleets with any of those named.
type Tally = Vec<[usize; 4]>;

/// Runs `seeds` fleets of compliances `gs` (with `full`, also in the full model), prints each
/// and the summary; returns the tally, the fleets whose design mean passed at each of
/// [`ALPHAS`], and the fleets with another candidate named at the fleet's α (the arms named),
/// the full model's after.
fn run(title: &str, gs: &[f64], base: u64, seeds: u64, full: bool) -> (Tally, [usize; 2], String) {
    let with: Vec<bool> = gs.iter().map(|g| *g != 0.0).collect();
    let n_with = with.iter().filter(|w| **w).count();
    let n_without = gs.len() - n_with;
    let gs_text: Vec<String> = gs.iter().map(|g| format!("{:.2}", g * 1e9)).collect();
    let cols = labels(full);
    println!(
        "{title}: {seeds} fleets of {} arms, joint-2 compliance [{}]e-9 rad/mm",
        gs.len(),
        gs_text.join(", ")
    );
    println!(
        "  seed  design  arms with the effect named/arms without it named, per rule ({}) | other candidates named (α = 0.01), any at 0.05",
        cols.join(", ")
    );
    let mut tally: Tally = vec![[0usize; 4]; cols.len()];
    let (mut design, mut other_fleets, mut other_arms, mut other05) = ([0; 2], 0, 0, 0);
    let (mut full_fleets, mut full_arms, mut full05, mut full_design) = (0, 0, 0, [0; 2]);
    // The fleet-scale pool: design passes, fleets where the homogeneity test failed (the
    // arms' own errors used), coverage of the true compliance (as `Shoulder::covered`), φ̂s.
    let (mut fs_design, mut fs_fallback) = ([0usize; 2], [0usize; 2]);
    let mut covered = [[0usize; 2]; 2];
    let mut phis: Vec<f64> = Vec::new();
    // Pairs with the effect the single arm does not name, and of them named by the product
    // and by the fleet scale, at each of [`ALPHAS`].
    let mut beyond = [[0usize; 3]; 2];
    // Every candidate with the fleet's error scale, at each of [`ALPHAS`]: pairs with the
    // effect named, fleets with all of them, arms without it named, fleets with one, design
    // passes, fleets with another candidate named, its arms.
    let mut every = vec![[[0usize; 9]; 2]; 1 + full as usize];
    let col = |i: usize, r: Rule| i * RULES.len() + RULES.iter().position(|x| *x == r).unwrap();
    for s in 0..seeds {
        let o = fleet_once(gs, base + 100 * s, full);
        let mut cells = Vec::new();
        for (t, r) in tally.iter_mut().zip(&o.named) {
            let right = r.iter().zip(&with).filter(|(n, w)| **n && **w).count();
            let wrong = r.iter().zip(&with).filter(|(n, w)| **n && !**w).count();
            t[0] += right;
            t[1] += (n_with > 0 && right == n_with) as usize;
            t[2] += wrong;
            t[3] += (wrong > 0) as usize;
            cells.push(format!("{right}/{wrong}"));
        }
        for (i, b) in beyond.iter_mut().enumerate() {
            for u in (0..gs.len()).filter(|u| with[*u] && !o.named[col(i, Rule::OwnAlone)][*u]) {
                b[0] += 1;
                b[1] += o.named[col(i, Rule::OwnErrors)][u] as usize;
                b[2] += o.named[col(i, Rule::FleetScale)][u] as usize;
            }
        }
        for i in 0..2 {
            fs_design[i] += o.fs.fs_passed[i] as usize;
            fs_fallback[i] += !o.fs.fs_scaled[i] as usize;
            for (c, oc) in covered.iter_mut().zip(&o.fs.covered) {
                c[i] += oc[i];
            }
        }
        for (t, e) in every.iter_mut().flatten().zip(o.fleet.iter().flatten()) {
            let right = e
                .shoulder
                .iter()
                .zip(&with)
                .filter(|(n, w)| **n && **w)
                .count();
            let wrong = e
                .shoulder
                .iter()
                .zip(&with)
                .filter(|(n, w)| **n && !**w)
                .count();
            t[0] += right;
            t[1] += (n_with > 0 && right == n_with) as usize;
            t[2] += wrong;
            t[3] += (wrong > 0) as usize;
            t[4] += e.design as usize;
            t[5] += (!e.others.is_empty()) as usize;
            t[6] += e.others.iter().map(|o| o.1).sum::<usize>();
            t[7] += e.covered[0];
            t[8] += e.covered[1];
        }
        if o.fs.phi.0.is_finite() {
            phis.push(o.fs.phi.0);
        }
        println!(
            "  {s:>4}  {:<11}  {} | {:?} {} | fleet scale: design {}/{}, scale used {}/{}, φ̂ {:.2} (homogeneity p {:.3}){}",
            format!("{}/{}", o.design[0], o.design[1]),
            cells.join("  "),
            o.others,
            o.others05,
            o.fs.fs_passed[0],
            o.fs.fs_passed[1],
            o.fs.fs_scaled[0],
            o.fs.fs_scaled[1],
            o.fs.phi.0,
            o.fs.phi.1,
            if full {
                format!(
                    " | full model: design {}/{}, {:?} {}",
                    o.design_full[0], o.design_full[1], o.others_full, o.others_full05
                )
            } else {
                String::new()
            }
        );
        full_fleets += (!o.others_full.is_empty()) as usize;
        full_arms += o.others_full.iter().map(|o| o.1).sum::<usize>();
        full05 += o.others_full05 as usize;
        for (n, d) in full_design.iter_mut().zip(o.design_full) {
            *n += d as usize;
        }
        for (n, d) in design.iter_mut().zip(o.design) {
            *n += d as usize;
        }
        other_fleets += (!o.others.is_empty()) as usize;
        other_arms += o.others.iter().map(|o| o.1).sum::<usize>();
        other05 += o.others05 as usize;
    }
    println!(
        "  design mean of joint 2's compliance named (Holm): {}/{seeds} fleets at α = 0.01, {}/{seeds} at 0.05",
        design[0],
        design[1]
    );
    for (name, t) in cols.iter().zip(&tally) {
        println!(
            "  {name:<29} with the effect: {}/{} (fleet, arm) pairs named ({:.3}), every such arm in {}/{seeds} fleets; \
             without it: {}/{} named, in {}/{seeds} fleets",
            t[0],
            n_with as u64 * seeds,
            t[0] as f64 / (n_with as u64 * seeds).max(1) as f64,
            t[1],
            t[2],
            n_without as u64 * seeds,
            t[3]
        );
    }
    println!(
        "  other candidates named: in {other_fleets}/{seeds} fleets ({other_arms} arms) at α = 0.01; \
         design means in {other05}/{seeds} fleets at α = 0.05"
    );
    if full {
        println!(
            "  full model: design mean of joint 2's compliance named (Holm): {}/{seeds} fleets at \
             α = 0.01, {}/{seeds} at 0.05",
            full_design[0], full_design[1]
        );
        println!(
            "  full model, other candidates named: in {full_fleets}/{seeds} fleets ({full_arms} arms) \
             at α = 0.01; design means in {full05}/{seeds} fleets at α = 0.05"
        );
    }
    phis.sort_by(f64::total_cmp);
    let q = |f: f64| {
        phis.get(((phis.len().max(1) - 1) as f64 * f) as usize)
            .copied()
            .unwrap_or(f64::NAN)
    };
    let n_arms = gs.len() as u64 * seeds;
    let fs_text = format!(
        "fleet scale: design passes {}, {}; homogeneity fails (own errors used) in {}, {} fleets at 0.01, 0.05; \
         φ̂ median {:.2} [{:.2} … {:.2}]; true compliance covered, own errors 99 % {}/{n_arms}, 95 % {}/{n_arms}; \
         fleet scale 99 % {}/{n_arms}, 95 % {}/{n_arms}; of the pairs with the effect the single arm does not \
         name: at 0.01 {}, own errors name {}, the fleet scale {}; at 0.05 {}, {}, {}",
        fs_design[0],
        fs_design[1],
        fs_fallback[0],
        fs_fallback[1],
        q(0.5),
        q(0.0),
        q(1.0),
        covered[0][0],
        covered[0][1],
        covered[1][0],
        covered[1][1],
        beyond[0][0],
        beyond[0][1],
        beyond[0][2],
        beyond[1][0],
        beyond[1][1],
        beyond[1][2]
    );
    println!("  {fs_text}");
    for (model, t) in ["", "full model, "]
        .iter()
        .zip(&every)
        .flat_map(|(m, e)| e.iter().map(move |t| (m, t)))
        .zip(ALPHAS.iter().cycle())
        .map(|((m, t), a)| ((m, a), t))
    {
        let (model, a) = model;
        println!(
            "  {model}fleet scale on every candidate @ {a}: design passes {}/{seeds}; with the effect {}/{} \
             pairs named, every such arm in {}/{seeds} fleets; without it {}/{} named, in \
             {}/{seeds} fleets; other candidates named in {}/{seeds} fleets ({} arms); every \
             candidate's interval holds its true value for {}/{} arms",
            t[4],
            t[0],
            n_with as u64 * seeds,
            t[1],
            t[2],
            n_without as u64 * seeds,
            t[3],
            t[5],
            t[6],
            t[7],
            t[8]
        );
    }
    let mut others = format!("{other_fleets} ({other_arms}); {fs_text}");
    if full {
        others += &format!(
            "; full model {full_fleets} ({full_arms}), its design passes {}, {}",
            full_design[0], full_design[1]
        );
    }
    (tally, design, others)
}

/// A compliance spread ±50 % around `mean` over `n` arms.
fn spread(mean: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| mean * (0.5 + k as f64 / (n.max(2) - 1) as f64))
        .collect()
}

fn main() {
    let arg = |i: usize, default: u64| -> u64 {
        std::env::args()
            .nth(i)
            .and_then(|s| s.parse().ok())
            .unwrap_or(default)
    };
    let (seeds, null_seeds, mixed_seeds) = (arg(1, 20), arg(2, 40), arg(3, 30));
    // Which fleets to run: a comma-separated list of `spread`, `null`, `mixed6`, `mixed7`.
    let parts = std::env::args()
        .nth(4)
        .unwrap_or_else(|| "spread,null,mixed6,mixed7".to_string());
    let full = parts.split(',').any(|p| p == "full");
    let parts = if parts == "full" {
        "spread,null,mixed6,mixed7".to_string()
    } else {
        parts
    };
    let part = |name: &str| parts.split(',').any(|p| p == name);
    let t = std::time::Instant::now();
    let cols = labels(full);
    let mut summary = Vec::new();
    for mean in MEANS.into_iter().filter(|_| part("spread")) {
        let (tally, design, others) = run("spread fleet", &spread(mean, ARMS), 500, seeds, full);
        println!("({:.0} s)", t.elapsed().as_secs_f64());
        summary.push((
            format!("spread {:.1}e-9", mean * 1e9),
            seeds,
            tally,
            design,
            others,
        ));
    }
    if part("null") {
        let (tally, design, others) = run("null fleet", &[0.0; ARMS], 10_000, null_seeds, full);
        println!("({:.0} s)", t.elapsed().as_secs_f64());
        summary.push(("null".to_string(), null_seeds, tally, design, others));
    }
    for with in MIXED_WITH
        .into_iter()
        .filter(|w| part(&format!("mixed{w}")))
    {
        let mut gs = spread(MIXED, with);
        gs.resize(ARMS, 0.0);
        let (tally, design, others) = run("mixed fleet", &gs, 30_000, mixed_seeds, full);
        println!("({:.0} s)", t.elapsed().as_secs_f64());
        summary.push((
            format!("mixed {with}+{} at {:.1}e-9", ARMS - with, MIXED * 1e9),
            mixed_seeds,
            tally,
            design,
            others,
        ));
    }
    // One table: per fleet and column, with-effect pairs named / fleets with all of them named
    // / without-effect arms named / fleets with a false cause.
    println!(
        "\nsummary (per column: pairs with the effect named | fleets with every such arm named | \
         arms without it named | fleets with a false cause)"
    );
    println!(
        "fleet | seeds | design passes at 0.01, 0.05 | other candidates named: fleets (arms) | {}",
        cols.join(" | ")
    );
    for (name, n, tally, design, others) in &summary {
        let cells: Vec<String> = tally
            .iter()
            .map(|t| format!("{} | {} | {} | {}", t[0], t[1], t[2], t[3]))
            .collect();
        println!(
            "{name} | {n} | {}, {} | {others} | {}",
            design[0],
            design[1],
            cells.join(" || ")
        );
    }
    println!("({:.0} s)", t.elapsed().as_secs_f64());
}
