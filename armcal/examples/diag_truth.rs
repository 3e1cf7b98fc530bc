//! Writes a truth arm with hidden extended effects for the diagnosis demo: `default-6` with
//! random geometric errors and effects of the families named (default: one or two of random
//! family), drawn from the seed as the diagnosis tests draw them (`armcal::diagnose::scenario`).
//! Prints the hidden effects to stderr.
//!
//! `cargo run --release -p armcal --example diag_truth -- SEED OUT.toml [harmonic|gravity|thermal]…`
use armcal::diagnose::scenario::{self, Family};

fn main() {
    let mut args = std::env::args().skip(1);
    let seed: u64 = args.next().and_then(|s| s.parse().ok()).unwrap_or(1);
    let out = args.next().unwrap_or_else(|| "truth.toml".into());
    let families: Vec<Family> = args
        .filter_map(|a| match a.as_str() {
            "harmonic" => Some(Family::Harmonic),
            "gravity" => Some(Family::Gravity),
            "thermal" => Some(Family::Thermal),
            other => {
                eprintln!("diag_truth: unknown family `{other}` ignored");
                None
            }
        })
        .collect();
    let s = if families.is_empty() {
        scenario::draw(seed)
    } else {
        scenario::with_families(seed, &families)
    };
    let hidden: Vec<String> = s.hidden.iter().map(|e| e.spec()).collect();
    let header = format!(
        "default-6 with random geometric errors and hidden effects {}, seed {seed}",
        hidden.join(" ")
    );
    if let Err(e) = std::fs::write(&out, quatarm_ref::calfile::write(&s.truth, &[&header])) {
        eprintln!("diag_truth: {out}: {e}");
        std::process::exit(1);
    }
    eprintln!("hidden: {}", hidden.join(" "));
}
