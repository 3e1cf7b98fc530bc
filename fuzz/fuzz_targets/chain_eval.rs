//! The chain on valid tables with arbitrary counts and temperatures: the shipped tables, some
//! of their values replaced by arbitrary ones (kept only if the table parser accepts the
//! result), evaluated by the quaternion and the matrix chain in f32 and fixed point. Never a
//! panic (overflow checks are on); every result finite with a unit direction, or an error.
#![no_main]

use arbitrary::Arbitrary;
use libfuzzer_sys::fuzz_target;
use quatarm::table::{TableData, MAX_TABLE_LEN};
use quatarm::{Arithmetic, Chain, Fixed, MatrixChain, Point, Table, F32};
use quatarm_fuzz::tables;

/// One value of a table replaced.
#[derive(Arbitrary, Debug)]
enum Tweak {
    Link {
        joint: u8,
        k: u8,
        mm: f64,
    },
    Thermal {
        joint: u8,
        kappa: f64,
    },
    Gravity {
        joint: u8,
        g: f64,
    },
    Harmonic {
        joint: u8,
        slot: u8,
        order: u16,
        sin: f64,
        cos: f64,
        count: u8,
    },
    Probe {
        k: u8,
        mm: f64,
    },
    ProbeThermal {
        kappa: f64,
    },
    Counts {
        joint: u8,
        counts: u32,
    },
}

#[derive(Arbitrary, Debug)]
struct Input {
    table: u8,
    tweaks: Vec<Tweak>,
    /// Counts (raw, or reduced below each joint's counts per revolution) and m°C.
    readings: Vec<(Vec<u32>, bool, i32)>,
}

fn apply(data: &mut TableData, tweak: &Tweak) {
    let n = usize::from(data.joint_count);
    let j = |joint: &u8| usize::from(*joint) % n;
    match tweak {
        Tweak::Link { joint, k, mm } => data.joints[j(joint)].link[usize::from(*k) % 3] = *mm,
        Tweak::Thermal { joint, kappa } => data.joints[j(joint)].thermal = *kappa,
        Tweak::Gravity { joint, g } => data.joints[j(joint)].gravity = *g,
        Tweak::Harmonic {
            joint,
            slot,
            order,
            sin,
            cos,
            count,
        } => {
            let jd = &mut data.joints[j(joint)];
            let h = &mut jd.harmonics[usize::from(*slot) % jd.harmonics.len()];
            (h.order, h.sin, h.cos) = (*order, *sin, *cos);
            jd.harmonic_count = count % (jd.harmonics.len() as u8 + 1);
        }
        Tweak::Probe { k, mm } => data.probe.vector[usize::from(*k) % 3] = *mm,
        Tweak::ProbeThermal { kappa } => data.probe.thermal = *kappa,
        Tweak::Counts { joint, counts } => data.joints[j(joint)].counts = *counts,
    }
}

fn check<P: Arithmetic>(p: Point<P>) {
    let xyz = p.xyz_f64();
    let dir = p.dir_f64();
    assert!(
        xyz.iter().chain(&dir).all(|v| v.is_finite()),
        "{xyz:?} {dir:?}"
    );
    let norm = dir.iter().map(|v| v * v).sum::<f64>().sqrt();
    assert!(
        (norm - 1.0).abs() < 1e-3,
        "direction of norm {norm}: {dir:?}"
    );
}

fuzz_target!(|input: Input| {
    let base = &tables()[usize::from(input.table) % tables().len()];
    let mut data = Table::parse(base).expect("a built table parses").data();
    for t in input.tweaks.iter().take(8) {
        apply(&mut data, t);
    }
    data.flags |= data.content_flags();
    let mut bytes = vec![0u8; MAX_TABLE_LEN];
    let Ok(len) = data.encode(&mut bytes) else {
        return;
    };
    let Ok(table) = Table::parse(&bytes[..len]) else {
        return;
    };
    let per_rev: Vec<u32> = (0..table.joint_count())
        .map(|i| table.joint(i).map_or(1, |j| j.counts.max(1)))
        .collect();
    let f32q = Chain::<F32>::new(&table).ok();
    let fixq = Chain::<Fixed>::new(&table).ok();
    let f32m = MatrixChain::<F32>::new(&table).ok();
    let fixm = MatrixChain::<Fixed>::new(&table).ok();
    for (counts, wrap, temp_mc) in input.readings.iter().take(16) {
        let counts: Vec<u32> = if *wrap {
            counts
                .iter()
                .zip(per_rev.iter().cycle())
                .map(|(c, m)| c % m)
                .collect()
        } else {
            counts.clone()
        };
        if let Some(Ok(p)) = f32q.as_ref().map(|c| c.eval(&counts, *temp_mc)) {
            check(p);
        }
        if let Some(Ok(p)) = fixq.as_ref().map(|c| c.eval(&counts, *temp_mc)) {
            check(p);
        }
        if let Some(Ok(p)) = f32m.as_ref().map(|c| c.eval(&counts, *temp_mc)) {
            check(p);
        }
        if let Some(Ok(p)) = fixm.as_ref().map(|c| c.eval(&counts, *temp_mc)) {
            check(p);
        }
    }
});
