//! The coverage of the pooled model's 95 % intervals on simulated fleets (issue 30): each
//! arm's interval θ̃ ± t·se with τ̂²'s uncertainty (Morris's term) and with the plug-in error
//! (τ̂² taken as known), and the design mean's Hartung–Knapp interval, over fleets of 3, 4 and
//! 8 arms and a range of true spreads τ (in units of the arms' mean error), the errors
//! estimated from 4 sessions as on MUKCa ([`armcal::diagnose::pooling::simulated_coverage`]).
//!
//!     cargo run --release -p armcal --example pooling_coverage [fleets [sessions]]
//!
//! 20 000 fleets per cell and 4 sessions by default (about 4 minutes on the shared 2-core
//! machine); a large `sessions` (1000) makes the arms' errors known, which separates the
//! shortfall due to τ̂² from the one due to each arm's own error being estimated.

use armcal::diagnose::pooling::simulated_coverage;

fn main() {
    let fleets: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(20_000);
    let sessions: usize = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(4);
    let t0 = std::time::Instant::now();
    println!(
        "coverage of 95 % intervals, {fleets} simulated fleets per cell, errors from {sessions} sessions"
    );
    println!("arms  τ/s   arm: with τ̂² term  plug-in  (width ratio)   design mean (HK)");
    for arms in [3, 4, 8] {
        for tau in [0.0, 0.25, 0.5, 1.0, 2.0, 4.0] {
            let c = simulated_coverage(arms, tau, sessions, fleets, 30 + arms as u64, 0.05);
            println!(
                "{arms:>4}  {tau:>4.2}   {:>16.3}  {:>7.3}  ({:.2})          {:.3}",
                c.with_tau, c.plugin, c.width_ratio, c.mean
            );
        }
    }
    println!("({:.1} s)", t0.elapsed().as_secs_f64());
}
