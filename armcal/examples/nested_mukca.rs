//! The nested held-out test ([`armcal::diagnose::nested`]) of every MUKCa unit with three
//! sessions or more: the whole diagnosis rerun without each session, the session scored by
//! the models fitted on the others, by held-out RMS and by MUKCa's own score (mean distance of
//! the ball centres from their socket's centre).
//!
//!     cargo run --release -p armcal --example nested_mukca [unit ...]

use armcal::diagnose::{nested, Options};
use armcal::mukca;
use armcal::stats::{sign_test_p, Paired};

fn main() {
    let dir = mukca::default_dir();
    let units = mukca::units_or_all(&dir, std::env::args().skip(1)).expect("data/mukca");
    for name in units {
        let unit = mukca::load(&dir, &name).expect("unit");
        if unit.groups().len() < 3 {
            println!("{name}: {} session(s), not tested\n", unit.groups().len());
            continue;
        }
        let t0 = std::time::Instant::now();
        let n = match nested::nested(&unit.arm, &unit.data, &Options::default()) {
            Ok(n) => n,
            Err(e) => {
                println!("{name}: {e}\n");
                continue;
            }
        };
        println!(
            "{name} ({} sessions, {:.1} s)",
            n.sessions(),
            t0.elapsed().as_secs_f64()
        );
        println!("  {}", n.headline());
        let chosen: Vec<String> = n
            .chosen
            .iter()
            .map(|(e, k)| format!("{} {k}/{}", e.spec(), n.sessions()))
            .collect();
        println!(
            "  chosen across folds: {}",
            if chosen.is_empty() {
                "nothing".into()
            } else {
                chosen.join(", ")
            }
        );
        // MUKCa's score of each held-out session, geometric and diagnosed models fitted on the
        // other sessions.
        let (mut b, mut a) = (Vec::new(), Vec::new());
        for f in &n.folds {
            let s = unit.sessions_data(&[f.group]);
            let sb = mukca::session_score(&f.geometric.arm, &s);
            let sa = mukca::session_score(&f.extended.arm, &s);
            let causes: Vec<String> = f.chosen.iter().map(|e| e.spec()).collect();
            println!(
                "    {:<14} RMS {:>7.1} → {:>7.1} µm  score {:.4} → {:.4} mm  [{}]",
                unit.sessions.get(&f.group).cloned().unwrap_or_default(),
                1e3 * f.before_ms.sqrt(),
                1e3 * f.after_ms.sqrt(),
                sb,
                sa,
                causes.join(" ")
            );
            b.push(sb);
            a.push(sa);
        }
        let k = b.len().max(1) as f64;
        let better = b.iter().zip(&a).filter(|(x, y)| y < x).count();
        let p = Paired::of(&b, &a);
        println!(
            "  MUKCa score {:.4} → {:.4} mm, better on {better}/{}, paired t = {:.2} ({} df, p = {:.2e}), sign p = {:.3}",
            b.iter().sum::<f64>() / k,
            a.iter().sum::<f64>() / k,
            b.len(),
            p.z(),
            b.len().saturating_sub(1),
            p.p_value(),
            sign_test_p(better, b.len())
        );
        for (g, e) in &n.failed {
            println!("  session {g} not scored: {e}");
        }
        println!();
    }
}
