//! The diagnosis measured: hidden effects named over many seeds, held-out RMS before and
//! after, fresh-pose error of the extended model, time per diagnosis.
//!
//!     cargo bench -p armcal --bench diagnosis                  # point data, seeds 1..=40
//!     cargo bench -p armcal --bench diagnosis -- spat          # spat + length data
//!     cargo bench -p armcal --bench diagnosis -- null          # no hidden effect
//!     cargo bench -p armcal --bench diagnosis -- wobble        # one axis wobble, orders 1–3
//!     cargo bench -p armcal --bench diagnosis -- seeds 1 100   # another range
//!     cargo bench -p armcal --bench diagnosis -- mukca         # the real robots

use armcal::diagnose::{self, scenario};
use armcal::fit::residuals::compare_aligned;
use armcal::params::Effect;
use quatarm_ref::arm::Arm;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    if args.iter().any(|a| a == "mukca") {
        mukca();
        return;
    }
    let spat = args.iter().any(|a| a == "spat");
    let null = args.iter().any(|a| a == "null");
    let wobble = args.iter().any(|a| a == "wobble");
    let (lo, hi) = match args.iter().position(|a| a == "seeds") {
        Some(i) => (
            args.get(i + 1).and_then(|s| s.parse().ok()).unwrap_or(1),
            args.get(i + 2).and_then(|s| s.parse().ok()).unwrap_or(40),
        ),
        None => (1u64, 40u64),
    };
    let opts = diagnose::Options::default();
    let mut ok = 0;
    let mut total = 0;
    let mut secs = Vec::new();
    println!(
        "{:>5}  {:<58} {:<58} {:>8} {:>8} {:>8} {:>7} {:>7} {:>6}",
        "seed", "hidden", "named", "ho geo", "ho ext", "floor", "fresh g", "fresh e", "s"
    );
    for seed in lo..=hi {
        let s = if null {
            scenario::with_families(seed, &[])
        } else if wobble {
            scenario::with_families(seed, &[scenario::Family::Wobble])
        } else {
            scenario::draw(seed)
        };
        let data = if spat {
            scenario::spat_length(&s, 400, 200)
        } else {
            scenario::points(&s, 600)
        };
        let t0 = Instant::now();
        let d = match diagnose::diagnose(&Arm::default6(), &data, &opts) {
            Ok(d) => d,
            Err(e) => {
                println!("{seed:>5}  error: {e}");
                total += 1;
                continue;
            }
        };
        let dt = t0.elapsed().as_secs_f64();
        secs.push(dt);
        let named: Vec<(Effect, Vec<Effect>)> = d
            .causes
            .iter()
            .map(|c| (c.effect, c.indistinguishable.clone()))
            .collect();
        let mut want = s.expected.clone();
        want.sort();
        let mut got = named.clone();
        got.sort();
        let right = want == got;
        total += 1;
        ok += usize::from(right);
        let poses = scenario::fresh_poses(seed, 2000);
        let fresh_g = compare_aligned(&d.baseline.fit.arm, &s.truth, &poses).rms_um;
        let fresh_e = compare_aligned(&d.extended.fit.arm, &s.truth, &poses).rms_um;
        let floor = armcal::fit::residuals::summarise(
            &armcal::fit::residuals::residuals(&s.truth, &data, None),
            &data,
        )
        .all
        .rms_um;
        let show = |v: &[(Effect, Vec<Effect>)]| {
            if v.is_empty() {
                "none".to_string()
            } else {
                v.iter()
                    .map(|(e, i)| {
                        let mut t = e.spec();
                        for x in i {
                            t += &format!("~{}", x.spec().trim_start_matches('+'));
                        }
                        t
                    })
                    .collect::<Vec<_>>()
                    .join(" ")
            }
        };
        println!(
            "{seed:>5}  {:<58} {:<58} {:>8.2} {:>8.2} {:>8.2} {:>7.2} {:>7.2} {:>6.2}{}",
            show(&s.expected),
            show(&named),
            d.baseline.holdout.summary.all.rms_um,
            d.extended.holdout.summary.all.rms_um,
            floor,
            fresh_g,
            fresh_e,
            dt,
            if right { "" } else { "  <-- WRONG" }
        );
    }
    secs.sort_by(f64::total_cmp);
    println!(
        "\nexact causes named: {ok}/{total}; time per diagnosis median {:.2} s, max {:.2} s",
        secs.get(secs.len() / 2).copied().unwrap_or(0.0),
        secs.last().copied().unwrap_or(0.0)
    );
}

/// Every MUKCa unit, sessions held out one at a time: what the diagnosis names, its held-out
/// RMS, and the authors' score (mean distance from the socket centre) leaving each session
/// out, for the geometric and the extended model.
fn mukca() {
    use armcal::mukca;
    let dir = mukca::default_dir();
    let opts = diagnose::Options {
        folds: diagnose::FoldChoice::ByGroup,
        ..diagnose::Options::default()
    };
    println!(
        "| unit | sessions | named causes (magnitude) | strongest candidate left out: F-test p, \
         held-out p | held-out RMS geometric → extended (µm) | MUKCa score, leave one session \
         out: geometric → extended (mm) | s |"
    );
    println!("|---|---|---|---|---|---|---|");
    for (name, _) in mukca::unit_names(&dir).expect("mukca-groups.csv") {
        let unit = mukca::load(&dir, &name).expect("unit");
        let sessions = unit.groups().len();
        let t0 = Instant::now();
        let d = match diagnose::diagnose(&unit.arm, &unit.data, &opts) {
            Ok(d) => d,
            Err(e) => {
                println!("| {name} | {sessions} | – ({e}) | – | – | – | – |");
                continue;
            }
        };
        let dt = t0.elapsed().as_secs_f64();
        let causes = if d.causes.is_empty() {
            "none".to_string()
        } else {
            d.causes
                .iter()
                .map(|c| format!("{} ({:.3e} {})", c.effect.spec(), c.magnitude, c.unit))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let rejected: Vec<String> = d
            .confirmations
            .iter()
            .filter(|c| !c.named)
            .map(|c| format!("{} rejected on refits", c.effect.spec()))
            .collect();
        let score = |effects: &[Effect]| {
            let o = armcal::fit::options::Options {
                terms: armcal::params::Terms::with(effects),
                ..armcal::fit::options::Options::default()
            };
            mukca::loso(&unit, &o)
        };
        let geo_loso = score(&[]);
        let geo = geo_loso.mean_after;
        // A named cause's check by the authors' score: sessions better, paired p.
        let (ext, check) = if d.causes.is_empty() {
            (geo, String::new())
        } else {
            let e = score(&d.extended.effects);
            let v = geo_loso.versus(&e);
            (
                e.mean_after,
                format!(" ({}/{} sessions, p = {:.0e})", v.better, v.sessions, v.p),
            )
        };
        let strongest = d
            .selection
            .left_out
            .iter()
            .filter(|c| c.separable)
            .min_by(|a, b| a.p.total_cmp(&b.p))
            .map_or("–".to_string(), |c| {
                format!("{} ({:.1e}, {:.2})", c.effect.spec(), c.p, c.p_holdout)
            });
        println!(
            "| {name} | {sessions} | {causes}{} | {strongest} | {:.1} → {:.1} | {geo:.3} → {ext:.3}{check} | {dt:.1} |",
            if rejected.is_empty() {
                String::new()
            } else {
                format!(" ({})", rejected.join(", "))
            },
            d.baseline.holdout.summary.all.rms_um,
            d.extended.holdout.summary.all.rms_um,
        );
    }
}
