//! Power and false causes of the pooled stage of `armcal diagnose --fleet` over seeds (issue
//! 30, round 4): simulated fleets of 8 `default-6` arms (120 tracker points in 4 sessions
//! each), one with the shoulder's gravity compliance spread ±50 % around a mean (`spread`),
//! one with nothing hidden (`null`), each over `seeds` seeds. Every one-unknown candidate the
//! arms can test is pooled and named as the product does
//! ([`armcal::diagnose::fleet_pooled::pool_candidates`]: Holm over the candidates at the
//! fleet's α = 0.01, each arm by its pooled 99 % interval, t on its own error's degrees of
//! freedom or arms − 1 where fewer), beside the rules it replaces or could add:
//!
//! - round 3: the pooled interval on t with arms − 1 degrees of freedom;
//! - Satterthwaite: on [`pooling::satterthwaite_df`];
//! - one-sided: the design's mean passed, the arm's pooled value on its side, one-sided at α
//!   on the product's degrees of freedom;
//! - or own: the product's rule, or, once the design's mean passes, the arm's own interval
//!   (t on its sessions − 1) excluding 0 on the mean's side;
//! - own alone: the arm's own estimate, t on its sessions − 1 (no pooling);
//! - α = 0.05: the product's rule at α = 0.05 (the candidates re-pooled from the same
//!   estimates, Holm over them).
//!
//! A third fleet has half its arms with twice the spread fleet's compliances and half with
//! none: where the design's mean passes, the arms without the effect that a rule names are
//! its false causes.
//!
//!     cargo run --release -p armcal --example pooling_power [seeds [mean compliance]]
//!
//! 20 seeds each and a mean of 2.5e-9 rad/mm by default (the fleet of
//! `examples/pooling_fleet.rs`, whose seed 0 is this one's); a few minutes release.

use armcal::data::{Dataset, Kind};
use armcal::diagnose::candidates;
use armcal::diagnose::fleet::{self, UnitData};
use armcal::diagnose::fleet_pooled::{pool_candidates, PooledEffect};
use armcal::diagnose::pooling;
use armcal::params::Effect;
use armcal::sim;
use armcal::stats::{t_critical, t_tail};
use quatarm_ref::arm::Arm;

const ROWS: usize = 120;
const SESSIONS: usize = 4;
const ARMS: usize = 8;

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

/// The rules compared, in the order of [`named`]'s columns.
const RULES: [&str; 7] = [
    "product (own df)",
    "round 3 (k − 1 df)",
    "Satterthwaite df",
    "one-sided, own df",
    "product or own",
    "own estimate alone",
    "product at α = 0.05",
];

/// Which arms each rule names for `p` (one row per rule, [`RULES`]); `named05` whether its
/// design mean passes Holm at 0.05 over the fleet's candidates.
fn named(p: &PooledEffect, named05: bool, alpha: f64) -> Vec<Vec<bool>> {
    let k = p.arms.len();
    let tk = t_critical(alpha, (k - 1) as f64);
    let y: Vec<f64> = p.arms.iter().map(|a| a.value.estimate).collect();
    let se: Vec<f64> = p.arms.iter().map(|a| a.value.se).collect();
    let df: Vec<f64> = p.arms.iter().map(|a| a.value.se_df).collect();
    let re = pooling::pool(&y, &se, &df, 0.05);
    let mut out = vec![Vec::with_capacity(k); RULES.len()];
    for (i, a) in p.arms.iter().enumerate() {
        let v = &a.value;
        let own = 2.0 * t_tail((v.estimate / v.se).abs(), v.se_df) < alpha;
        let z = (v.pooled / v.pooled_se).abs();
        let own_part = (1.0 - v.shrinkage) * v.se * v.se;
        let satt = pooling::satterthwaite_df(
            own_part,
            v.shrinkage,
            v.se_df,
            v.pooled_se.powi(2) - own_part,
            k,
        );
        let mean_side = v.pooled * p.design.mean > 0.0;
        let row = [
            v.named_pooled,
            p.named && z > tk,
            p.named && 2.0 * t_tail(z, satt) < alpha,
            p.named && mean_side && t_tail(z, v.df) < alpha,
            v.named_pooled || (p.named && own && v.estimate * p.design.mean > 0.0),
            own,
            named05 && re.as_ref().is_some_and(|(_, arms)| arms[i].named_pooled),
        ];
        for (o, r) in out.iter_mut().zip(row) {
            o.push(r);
        }
    }
    out
}

/// The shoulder candidate in one fleet: each rule's arms, and whether its design mean passed.
type Shoulder = (Vec<Vec<bool>>, bool);

/// One fleet of compliances `gs` (arm k's data from seed `base + k`): the shoulder
/// candidate's naming, and the other candidates named (candidate, arms) at the product's α
/// and at 0.05.
fn fleet_once(gs: &[f64], base: u64) -> (Shoulder, Vec<(String, usize)>, Vec<String>) {
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
    let o = fleet::Options::default();
    let p = pool_candidates(&start, &units, &arms, &testable, &o);
    let ps: Vec<f64> = p.effects.iter().map(|e| e.design.mean_p).collect();
    let holm05 = fleet::holm(&ps, 0.05);
    let mut shoulder = (vec![vec![false; gs.len()]; RULES.len()], false);
    let mut others = Vec::new();
    let mut others05 = Vec::new();
    for (e, &n05) in p.effects.iter().zip(&holm05) {
        if e.effect == Effect::Gravity(1) {
            shoulder = (named(e, n05, o.alpha), e.named);
        } else {
            if e.named {
                let arms = e.arms.iter().filter(|a| a.value.named_pooled).count();
                others.push((e.term.clone(), arms));
            }
            if n05 {
                others05.push(e.term.clone());
            }
        }
    }
    (shoulder, others, others05)
}

fn run(title: &str, gs: &[f64], base: u64, seeds: u64) {
    let with: Vec<bool> = gs.iter().map(|g| *g != 0.0).collect();
    let n_with = with.iter().filter(|w| **w).count();
    let n_without = gs.len() - n_with;
    let gs_text: Vec<String> = gs.iter().map(|g| format!("{:.2}", g * 1e9)).collect();
    println!(
        "{title}: {seeds} fleets of {} arms, joint-2 compliance [{}]e-9 rad/mm",
        gs.len(),
        gs_text.join(", ")
    );
    println!("  seed  design  arms with the effect named, then arms without it named, per rule ({}) | other candidates named (α = 0.01) (α = 0.05)", RULES.join(", "));
    // Per rule: arms with the effect named, fleets with every such arm named, arms without
    // it named, fleets with any of those named.
    let mut tally = vec![[0usize; 4]; RULES.len()];
    let (mut design, mut other_fleets, mut other_arms, mut other05) = (0, 0, 0, 0);
    for s in 0..seeds {
        let ((rules, d), others, others05) = fleet_once(gs, base + 100 * s);
        let mut cells = Vec::new();
        for (t, r) in tally.iter_mut().zip(&rules) {
            let right = r.iter().zip(&with).filter(|(n, w)| **n && **w).count();
            let wrong = r.iter().zip(&with).filter(|(n, w)| **n && !**w).count();
            t[0] += right;
            t[1] += (n_with > 0 && right == n_with) as usize;
            t[2] += wrong;
            t[3] += (wrong > 0) as usize;
            cells.push(format!("{right}/{wrong}"));
        }
        println!(
            "  {s:>4}  {:<6}  {} | {:?} {:?}",
            d,
            cells.join("  "),
            others,
            others05
        );
        design += d as usize;
        other_fleets += (!others.is_empty()) as usize;
        other_arms += others.iter().map(|o| o.1).sum::<usize>();
        other05 += (!others05.is_empty()) as usize;
    }
    println!(
        "  design mean of joint 2's compliance named (Holm, α = 0.01): {design}/{seeds} fleets"
    );
    for (name, t) in RULES.iter().zip(&tally) {
        println!(
            "  {name:<20} with the effect: {}/{} (fleet, arm) pairs named ({:.3}), every such arm in {}/{seeds} fleets; \
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
}

fn main() {
    let seeds: u64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(20);
    let mean: f64 = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(2.5e-9);
    let t = std::time::Instant::now();
    let gs: Vec<f64> = (0..ARMS)
        .map(|k| mean * (0.5 + k as f64 / (ARMS - 1) as f64))
        .collect();
    run("spread fleet", &gs, 500, seeds);
    println!("({:.0} s)", t.elapsed().as_secs_f64());
    run("null fleet", &[0.0; ARMS], 10_000, seeds);
    println!("({:.0} s)", t.elapsed().as_secs_f64());
    // Half the arms with twice the spread fleet's compliances, half with none: the per-arm
    // rule's false causes where the design's mean passes.
    let half: Vec<f64> = (0..ARMS)
        .map(|k| {
            if k < ARMS / 2 {
                2.0 * mean * (0.5 + k as f64 / (ARMS / 2 - 1) as f64)
            } else {
                0.0
            }
        })
        .collect();
    run("half fleet", &half, 20_000, seeds);
    println!("({:.0} s)", t.elapsed().as_secs_f64());
}
