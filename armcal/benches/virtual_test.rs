//! Coverage of the virtual test (`armcal check --predict`, issue 12): for each of 40 seeded
//! virtual arms, calibrated from 600 `point` readings (5 µm instrument noise, 1 count of
//! encoder noise; the calibration's own budget, with the probing it cannot estimate from point
//! data set to the test's 2 µm), the ISO 10360-12 test set is recorded on the true arm and
//! checked with the calibration; the fraction of test values inside their predicted 95 %
//! interval is printed per test and in all.
//!
//! `cargo bench -p armcal --bench virtual_test [-- TESTS DRAWS]` (40 and 1,000 by default).

use armcal::acceptance::{self, statistics::Test, virtual_test};
use armcal::data::Kind;
use armcal::sim::{self, protocol};
use armcal::uncertainty::coverage::{self, Setup};
use std::collections::BTreeMap;

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let tests = args.first().copied().unwrap_or(40);
    let draws = args.get(1).copied().unwrap_or(1000);
    let setup = Setup {
        calibrations: tests,
        seed: 0x5e7,
        ..Setup::BENCHMARK
    };
    let probing_mm = 0.002;
    let mut inside: BTreeMap<Test, (usize, usize)> = BTreeMap::new();
    for k in 0..tests {
        let mut c = coverage::calibrated(&setup, k).expect("calibration");
        c.budget.probing_mm = probing_mm;
        let mut o = sim::Options::new(Kind::Point, 1);
        o.noise_mm = probing_mm;
        o.encoder_noise_counts = setup.encoder_noise_counts;
        let data = protocol::iso_10360_12(&c.truth, &o, &mut c.rng)
            .expect("test set")
            .data;
        let p =
            virtual_test::predict(&c.arm, &c.budget, &data, draws, k as u64).expect("prediction");
        let measured = acceptance::check(&c.arm, &data, None, None, false).expect("check");
        for r in &measured.tests {
            let i = p[&(r.test, r.group)];
            let v = r.value_um * 1e-3;
            let e = inside.entry(r.test).or_default();
            e.0 += usize::from(i.lo <= v && v <= i.hi);
            e.1 += 1;
        }
    }
    println!("virtual test: {tests} seeded tests, {draws} draws each");
    let (mut a, mut n) = (0, 0);
    for (t, (i, m)) in &inside {
        println!(
            "  {:<9} {i:>4} / {m:<4} inside their 95 % interval ({:.1} %)",
            t.key(),
            100.0 * *i as f64 / *m as f64
        );
        a += i;
        n += m;
    }
    println!(
        "  all       {a:>4} / {n:<4} ({:.1} %)",
        100.0 * a as f64 / n as f64
    );
}
