//! Evaluations per second of each path on the host: `cargo bench -p armcal --bench chain`.
//! (On-target instruction counts: `cargo xtask bench-target`.)

use armcal::accuracy::{full_calibration, random_reading, Paths};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use rand::SeedableRng;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let arm = full_calibration();
    let paths = Paths::new(&arm).expect("table");
    let (Ok(qf), Ok(qx), Ok(mf), Ok(mx)) = (&paths.qf, &paths.qx, &paths.mf, &paths.mx) else {
        panic!("the full calibration fits every evaluator");
    };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let readings: Vec<(Vec<u32>, i32)> =
        (0..1000).map(|_| random_reading(&mut rng, &arm)).collect();
    let radians: Vec<(Vec<f64>, f64)> = readings
        .iter()
        .map(|(c, t)| (arm.counts_to_rad(c), f64::from(*t) / 1000.0))
        .collect();
    let mut g = c.benchmark_group("eval");
    g.throughput(Throughput::Elements(readings.len() as u64));
    g.bench_function("f32 quaternion", |b| {
        b.iter(|| {
            for (counts, t) in &readings {
                black_box(qf.eval(black_box(counts), *t).ok());
            }
        })
    });
    g.bench_function("fixed quaternion", |b| {
        b.iter(|| {
            for (counts, t) in &readings {
                black_box(qx.eval(black_box(counts), *t).ok());
            }
        })
    });
    g.bench_function("f32 matrix 3x4", |b| {
        b.iter(|| {
            for (counts, t) in &readings {
                black_box(mf.eval(black_box(counts), *t).ok());
            }
        })
    });
    g.bench_function("fixed matrix 3x4", |b| {
        b.iter(|| {
            for (counts, t) in &readings {
                black_box(mx.eval(black_box(counts), *t).ok());
            }
        })
    });
    g.bench_function("f64 reference", |b| {
        b.iter(|| {
            for (theta, t) in &radians {
                black_box(quatarm_ref::forward::forward(&arm, black_box(theta), *t));
            }
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
