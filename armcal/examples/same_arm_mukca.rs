//! The same-arm statistic of every pair of MUKCa's Panda recordings, as
//! `armcal diagnose --fleet` computes it before the fleet test, without the fleet test:
//!
//!     cargo run --release -p armcal --example same_arm_mukca

use armcal::diagnose::fleet::{self, Options};
use armcal::diagnose::same_arm::{self, Grouping};
use std::path::PathBuf;

fn main() {
    let dir = armcal::mukca::default_dir();
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("data/mukca")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            let n = p.file_name().unwrap().to_string_lossy();
            n.starts_with("mukca-panda-") && n.ends_with(".csv")
        })
        .collect();
    paths.sort();
    let refs: Vec<&std::path::Path> = paths.iter().map(PathBuf::as_path).collect();
    let start = armcal::load::arm(&dir.join("mukca-panda-panda_2.toml")).expect("arm");
    let files = fleet::read_units(&refs, start.dof()).expect("files");
    let arms = same_arm::group(
        &start,
        &files,
        &Options::default(),
        &Grouping::Detect {
            alpha: same_arm::ALPHA,
        },
    )
    .expect("grouping");
    let mut pairs = arms.pairs.clone();
    pairs.sort_by(|a, b| (a.chi2 / a.dof as f64).total_cmp(&(b.chi2 / b.dof as f64)));
    for sp in &arms.splits {
        println!(
            "halves of {:<20} chi2 {:>6.1} on {:>2}: {:.2}",
            files[sp.recording].name,
            sp.chi2,
            sp.dof,
            sp.chi2 / sp.dof as f64
        );
    }
    println!("overdispersion (phi, D): {:?}", arms.overdispersion);
    println!("pair                                   chi2   k  chi2/k       F        p same");
    for p in &pairs {
        println!(
            "{:<19} {:<19} {:>8.1} {:>3} {:>7.2} {:>7.2} {:>8.1e} {}",
            files[p.a].name,
            files[p.b].name,
            p.chi2,
            p.dof,
            p.chi2 / p.dof as f64,
            p.f,
            p.p_value,
            p.same
        );
    }
    for g in &arms.groups {
        let names: Vec<&str> = g
            .recordings
            .iter()
            .map(|&i| files[i].name.as_str())
            .collect();
        println!("arm {}: {}", g.arm, names.join(" + "));
    }
}
