//! Recordings of one MUKCa arm compared with the probe refitted per recording (issue 30).
//!
//! "The model extended on panda_3 predicts panda_3_bis better" compared two calibrations of
//! panda_3 on another recording of the same arm with panda_3's own probe; a recording's tool
//! is its own (0.1–0.5 mm apart), so part of any difference is the probe. Here each model of
//! an arm, fitted on all sessions of its main recording, is scored on every session of the
//! arm's other recordings twice, by MUKCa's score (mean distance of the ball centres from
//! their socket's centre):
//! - **as is**: with the main recording's probe (the comparison before);
//! - **probe refitted per recording** ([`armcal::diagnose::gauge_free::refit_probe`]): the
//!   tool (probe offset, last joint's zero and tilt) refitted on the recording's **other**
//!   sessions, every other unknown held, and the session scored (held out). A recording of
//!   one session has no other session: its tool is refitted on that session itself (in
//!   sample for the tool only, said in the output).
//!
//! Per session the gain of the extended model (geometric − extended score), the number of
//! sessions better, the exact sign test, the paired t and its 95 % t interval of the mean gain.
//!
//!     cargo run --release -p armcal --example same_arm_probe_mukca       # about 1 minute

use armcal::data::Dataset;
use armcal::diagnose::gauge_free::refit_probe;
use armcal::fit::calib::calibrate;
use armcal::fit::options::Options;
use armcal::mukca::{self, Unit};
use armcal::params::{Effect, Terms};
use armcal::stats::{min_sign_p, sign_test_p, t_critical, Paired};
use quatarm_ref::arm::Arm;

/// `arm` scored on `session` of `unit`: as is, and with its tool refitted on `unit`'s other
/// sessions (or on the session itself when it is the only one).
fn scores(arm: &Arm, unit: &Unit, g: i64, opts: &Options) -> (f64, f64) {
    let session = unit.sessions_data(&[g]);
    let others: Vec<i64> = unit.groups().into_iter().filter(|x| *x != g).collect();
    let tool_data: Dataset = if others.is_empty() {
        session.clone()
    } else {
        unit.sessions_data(&others)
    };
    let refit = refit_probe(arm, &tool_data, opts).expect("tool refit");
    (
        mukca::session_score(arm, &session),
        mukca::session_score(&refit.arm, &session),
    )
}

/// The evidence of per-session gains `d` (mm, positive: the second model better).
fn evidence(label: &str, d: &[f64]) {
    let n = d.len();
    let better = d.iter().filter(|x| **x > 0.0).count();
    let mean = d.iter().sum::<f64>() / n.max(1) as f64;
    let paired = Paired::of(d, &vec![0.0; n]);
    let half = if n > 1 {
        let sd = (d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt();
        t_critical(0.05, (n - 1) as f64) * sd / (n as f64).sqrt()
    } else {
        f64::INFINITY
    };
    println!(
        "  {label}: mean gain {:+.4} mm, 95 % t interval [{:+.4}, {:+.4}]; better on {better}/{n}; paired t = {:.2} ({} df, one-sided p = {:.3}); sign test p = {:.4} (smallest possible {:.4})",
        mean,
        mean - half,
        mean + half,
        paired.z(),
        n.saturating_sub(1),
        paired.p_value(),
        sign_test_p(better, n),
        min_sign_p(n)
    );
}

fn main() {
    let t0 = std::time::Instant::now();
    let dir = mukca::default_dir();
    let opts = mukca::options(None);
    let fit = |u: &Unit, terms: Terms| {
        calibrate(
            &u.arm,
            &u.data,
            &Options {
                terms,
                ..opts.clone()
            },
        )
        .expect("fit")
        .arm
    };
    // panda_3's diagnosis (docs/results/claims.md §1): joint 2's gravity compliance and
    // joint 3's order-1 harmonic.
    let causes = [Effect::Gravity(1), Effect::Harmonic { joint: 2, order: 1 }];
    let p3 = mukca::load(&dir, "panda_3").expect("panda_3");
    let geo = fit(&p3, Terms::geometric());
    let ext = fit(&p3, Terms::with(&causes));
    println!(
        "panda_3's models fitted on its 6 sessions: geometric, and + {}",
        causes.map(|c| c.spec()).join(" ")
    );
    let (mut as_is, mut refit) = (Vec::new(), Vec::new());
    for other in ["panda_3_bis", "panda_right"] {
        let u = mukca::load(&dir, other).expect("recording");
        let alone = u.groups().len() == 1;
        for g in u.groups() {
            let (g0, g1) = scores(&geo, &u, g, &opts);
            let (e0, e1) = scores(&ext, &u, g, &opts);
            println!(
                "    {other:<12} {:<12} as is {g0:.4} → {e0:.4} mm ({:+.4}); probe refitted{} {g1:.4} → {e1:.4} mm ({:+.4})",
                u.sessions[&g],
                g0 - e0,
                if alone {
                    " (on this session: its recording has no other)"
                } else {
                    " (on the recording's other sessions)"
                },
                g1 - e1
            );
            as_is.push(g0 - e0);
            refit.push(g1 - e1);
        }
    }
    println!("panda_3's extended model against its geometric one on the arm's other recordings (panda_3_bis 3 sessions, panda_right 1):");
    evidence("as is (panda_3's probe)", &as_is);
    evidence("probe refitted per recording", &refit);

    // How much of a model's error on another recording of its arm is the tool: each arm's
    // geometric model on its other recordings, as is and with the probe refitted.
    println!("geometric model of the main recording on the arm's other recordings (mean MUKCa score over their sessions):");
    for (main, others) in [
        ("panda_3", &["panda_3_bis", "panda_right"][..]),
        ("panda_2", &["panda_1", "panda_left"][..]),
    ] {
        let m = mukca::load(&dir, main).expect("main");
        let geo = fit(&m, Terms::geometric());
        for other in others {
            let u = mukca::load(&dir, other).expect("recording");
            let (mut a, mut b, mut own) = (0.0, 0.0, 0.0);
            let gs = u.groups();
            for &g in &gs {
                let (x, y) = scores(&geo, &u, g, &opts);
                a += x;
                b += y;
                // The recording's own geometric calibration on its other sessions (or, alone,
                // on the session itself): what a model of this recording reaches.
                let rest: Vec<i64> = gs.iter().copied().filter(|x| *x != g).collect();
                let train = if rest.is_empty() { vec![g] } else { rest };
                let own_fit = calibrate(
                    &u.arm,
                    &u.sessions_data(&train),
                    &Options {
                        terms: Terms::geometric(),
                        ..opts.clone()
                    },
                )
                .expect("own fit");
                own += mukca::session_score(&own_fit.arm, &u.sessions_data(&[g]));
            }
            let k = gs.len() as f64;
            println!(
                "    {main} → {other:<11} ({} session(s)): as is {:.3} mm, probe refitted {:.3} mm; the recording's own geometric fit {:.3} mm{}",
                gs.len(),
                a / k,
                b / k,
                own / k,
                if gs.len() == 1 { " (in sample)" } else { " (held out)" }
            );
        }
    }
    println!("({:.0} s)", t0.elapsed().as_secs_f64());
}
