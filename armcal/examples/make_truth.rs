//! Writes a truth arm for the virtual arm: `default-6` with random geometric errors (zero
//! offsets and tilts 0.3 mrad, link and probe errors 0.3 mm per component, standard
//! deviations), as the round trip of `docs/results/calibration.md` uses.
//!
//! `cargo run -p armcal --example make_truth -- SEED OUT.toml`
fn main() {
    let mut args = std::env::args().skip(1);
    let seed: u64 = args.next().and_then(|s| s.parse().ok()).unwrap_or(1);
    let out = args.next().unwrap_or_else(|| "truth.toml".into());
    let truth = armcal::sim::perturb(
        &quatarm_ref::Arm::default6(),
        3e-4,
        0.3,
        &mut armcal::rng::rng(seed),
    );
    let header = format!("default-6 with random geometric errors, seed {seed}");
    let text = quatarm_ref::calfile::write(&truth, &[&header]);
    if let Err(e) = std::fs::write(&out, text) {
        eprintln!("make_truth: {out}: {e}");
        std::process::exit(1);
    }
}
