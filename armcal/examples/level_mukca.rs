//! The assumption under the gravity terms, tested on MUKCa ([`armcal::diagnose::level`]): the
//! base's tilt fitted through the shoulder's gravity compliance (joint 2) for every unit with
//! three sessions or more, its jackknife interval over the sessions, Hotelling's test of level,
//! each session's leave-one-out estimate, and the compliance level and tilted.
//!
//!     cargo run --release -p armcal --example level_mukca [unit ...]

use armcal::diagnose::level::test_level;
use armcal::mukca;
use armcal::params::Effect;

fn main() {
    let dir = mukca::default_dir();
    let units = mukca::units_or_all(&dir, std::env::args().skip(1)).expect("data/mukca");
    let deg = 180.0 / std::f64::consts::PI;
    let opts = mukca::options(None);
    println!("| unit | sessions | δα (°) [95 %] | δβ (°) [95 %] | T², p (level) | g level → tilted (µrad/mm) | RMS level → tilted (µm) |");
    println!("|---|---|---|---|---|---|---|");
    for name in units {
        let unit = mukca::load(&dir, &name).expect("unit");
        let n = unit.groups().len();
        if n < 3 {
            continue;
        }
        let t0 = std::time::Instant::now();
        match test_level(&unit.arm, &unit.data, &opts, &[Effect::Gravity(1)]) {
            Ok(l) => {
                println!(
                    "| {name} | {n} | {:+.2} [{:+.2}, {:+.2}] | {:+.2} [{:+.2}, {:+.2}] | {:.2}, {:.3} | {:.3} → {:.3} | {:.1} → {:.1} |",
                    l.tilt[0] * deg,
                    l.interval[0][0] * deg,
                    l.interval[0][1] * deg,
                    l.tilt[1] * deg,
                    l.interval[1][0] * deg,
                    l.interval[1][1] * deg,
                    l.t2,
                    l.p_value,
                    l.gravity[0].1 * 1e6,
                    l.gravity[0].2 * 1e6,
                    l.rms_um[0],
                    l.rms_um[1]
                );
                let each: Vec<String> = l
                    .without_session
                    .iter()
                    .map(|(g, t)| {
                        format!(
                            "{} ({:+.2}°, {:+.2}°)",
                            unit.sessions.get(g).cloned().unwrap_or_default(),
                            t[0] * deg,
                            t[1] * deg
                        )
                    })
                    .collect();
                eprintln!(
                    "{name}: without each session: {}; {:.0} s",
                    each.join(", "),
                    t0.elapsed().as_secs_f64()
                );
            }
            Err(e) => println!("| {name} | {n} | {e} | | | | |"),
        }
    }
}
