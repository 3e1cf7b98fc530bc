//! The coverage of the pooled model's 95 % intervals on simulated fleets (issue 30): each
//! arm's interval θ̃ ± t·se with τ̂²'s uncertainty (Morris's term) on t with the product's
//! degrees of freedom (the arm's own error's sessions − 1, or arms − 1 where fewer), with
//! Satterthwaite's, with arms − 1 (round 3's) and with the df that grow with the arm's
//! shrinkage (round 5's candidate, `pooling::shrinkage_df`), the Knapp–Hartung interval on both, and the
//! plug-in error (τ̂² taken as known), and the design mean's Hartung–Knapp interval, over
//! fleets of 3, 4 and 8 arms and a range of true spreads τ (in units of the arms' mean error),
//! the errors estimated from 4 sessions as on MUKCa
//! ([`armcal::diagnose::pooling::simulated_coverage`]). The last columns are the interval of
//! the error's scale pooled across the fleet (`pooling::pool_fleet_scale`, round 6: each
//! arm's model error known, its jackknife variance φ v² χ²_ν/ν, φ̂ pooled on Σν df and tested
//! for homogeneity at α), the share of fleets where that test failed and its width over the
//! plug-in's (docs/results/claims.md §7.10); then the same where the arms do not share one φ
//! (two values, 4 or 16 times apart, over alternate arms), with the coverage of the arms of
//! the high one; last, one more arm without a jackknife error joined on the fleet's scale
//! (`diagnose --fleet --join-short`), its φ the others' times 0.5, 1, 2 or 4.
//!
//!     cargo run --release -p armcal --example pooling_coverage [fleets [sessions [alpha]]]
//!
//! 20 000 fleets per cell and 4 sessions by default (about 2 minutes on the shared 2-core
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
    let alpha: f64 = std::env::args()
        .nth(3)
        .and_then(|s| s.parse().ok())
        .unwrap_or(0.05);
    let t0 = std::time::Instant::now();
    println!(
        "coverage of {:.0} % intervals, {fleets} simulated fleets per cell, errors from {sessions} sessions",
        100.0 * (1.0 - alpha)
    );
    println!(
        "arms  τ/s  | Morris: own df  Satterthwaite  k−1  shrinkage df | KH: k−1  own df | plug-in | width/plug-in: Morris own df, Satt, k−1, KH k−1, KH own df, shrinkage df | design mean (HK) | fleet scale: coverage, test failed, width/plug-in"
    );
    for arms in [3, 4, 8] {
        for tau in [0.0, 0.25, 0.5, 1.0, 2.0, 4.0] {
            let c = simulated_coverage(arms, tau, sessions, fleets, 30 + arms as u64, alpha);
            let w = c.width;
            println!(
                "{arms:>4}  {tau:>4.2} | {:>14.3}  {:>13.3}  {:>3.3}  {:>12.3} | {:>7.3}  {:>6.3} | {:>7.3} | {:.2}, {:.2}, {:.2}, {:.2}, {:.2}, {:.2} | {:.3} | {:.3}, {:.3}, {:.2}",
                c.with_df, c.satterthwaite, c.with_tau, c.shrinkage, c.kh, c.kh_df, c.plugin, w[0], w[1], w[2], w[3], w[4], w[5], c.mean,
                c.fleet_scale, c.fleet_scale_fallback, c.fleet_scale_width
            );
        }
    }
    // Arms that do not share one φ (`pooling::simulated_coverage_phi`): half the arms' model
    // errors φ_u = 4·ratio^(±½); the product's interval does not read them.
    println!(
        "\narms of two φ (ratio between them), {fleets} fleets per cell: product (Morris, own df) | fleet scale: coverage, of the high-φ arms, test failed"
    );
    for ratio in [4.0, 16.0] {
        for arms in [4, 8] {
            for tau in [0.0, 1.0] {
                let c = armcal::diagnose::pooling::simulated_coverage_phi(
                    arms,
                    tau,
                    sessions,
                    fleets,
                    30 + arms as u64,
                    alpha,
                    ratio,
                );
                println!(
                    "ratio {ratio:>4}  arms {arms}  τ/s {tau:.2} | {:.3} | {:.3}, {:.3}, {:.3}",
                    c.with_df, c.fleet_scale, c.fleet_scale_high_phi, c.fleet_scale_fallback
                );
            }
        }
    }
    // One more arm without a jackknife error (a 2-session recording, `diagnose --fleet
    // --join-short`), joined on the fleet's scale (`pooling::simulated_joined_coverage`): its
    // true error √2 times the others' middle one (half their sessions), its φ the others'
    // times `ratio` (1: the assumption the join makes).
    println!(
        "\nan arm without a jackknife joined on the fleet's scale, {fleets} fleets per cell: \
         fleets joined | its coverage | the others' | its width over theirs"
    );
    for ratio in [0.5, 1.0, 2.0, 4.0] {
        for arms in [4, 8] {
            for tau in [0.0, 1.0] {
                let c = armcal::diagnose::pooling::simulated_joined_coverage(
                    arms,
                    tau,
                    sessions,
                    fleets,
                    40 + arms as u64,
                    alpha,
                    (std::f64::consts::SQRT_2, ratio),
                );
                println!(
                    "φ ratio {ratio:>3}  arms {arms}+1  τ/s {tau:.2} | {:.3} | {:.3} | {:.3} | {:.2}",
                    c.joined, c.joined_coverage, c.others_coverage, c.joined_width
                );
            }
        }
    }
    println!("({:.1} s)", t0.elapsed().as_secs_f64());
}
