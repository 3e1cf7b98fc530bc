//! The on-target benchmark: instructions per corrected point of the quaternion chain and of
//! the 3×4 matrix chain, on the same table and the same recorded readings.
//!
//! Run under `qemu -icount shift=0`, where every instruction takes 1 ns of virtual time and
//! SysTick counts the virtual core clock, so ticks convert to instructions. Each evaluation is
//! timed on its own (readings arrive over the UART, as in the replay) and the cost of reading
//! the clock is measured the same way and subtracted. A loop of known length, timed at the
//! start, gives the instructions per tick instead of trusting the machine's nominal clock.
//! The Ed25519 check of the table's signature is timed once the same way, and, where the
//! table carries an uncertainty budget, each point's U95 after its quaternion chain: the
//! reading's own terms alone (the matrix chain's frames, Σ_p's own terms from them, and the
//! radius) on every
//! board, and the whole U95 as the hub streams it (with the parameter part where the table
//! has the block) where the hub computes one. Results go to the defmt log (`cargo xtask
//! bench-target` decodes it).

use quatarm::matrix::Frames;
use quatarm::signature::{self, KEY_LEN, SIGNATURE_LEN};
use quatarm::stream::{Event, Replay};
use quatarm::uncertainty::OwnTerms;
use quatarm::{Chain, MatrixChain, Table};

use crate::calibration::{HubEvaluator, PointUncertainty, JOINTS};
use crate::{clock, Link};

/// Iterations of the calibration loop (2 instructions each).
const LOOP_ITERATIONS: u32 = 200_000;

#[inline(never)]
fn counted_loop(n: u32) {
    // `subs` + `bne`: exactly two instructions per iteration, on every Cortex-M.
    // SAFETY: touches only the register it is given.
    #[cfg(target_arch = "arm")]
    unsafe {
        core::arch::asm!(
            "1:",
            "subs {0}, #1",
            "bne 1b",
            inout(reg) n => _,
            options(nomem, nostack)
        );
    }
    // The host compiles this crate for its unit tests, which never run the benchmark.
    #[cfg(not(target_arch = "arm"))]
    let _ = n;
}

#[derive(Default)]
struct Sum {
    points: u32,
    ticks: u64,
    failures: u32,
}

impl Sum {
    /// One timed evaluation: `ticks` between the clock's two readings, `failed` if it gave
    /// no result. Called after the second reading, so the sum is outside what it times.
    fn add(&mut self, ticks: u64, failed: bool) {
        self.points += 1;
        self.ticks += ticks;
        self.failures += u32::from(failed);
    }
}

/// The sums of one run, one per thing timed.
#[derive(Default)]
struct Sums {
    /// Reading the clock twice: the overhead subtracted from the others.
    empty: Sum,
    /// The quaternion chain in full.
    quaternion: Sum,
    /// What the hub runs (the lean form where the arm fits it).
    hub: Sum,
    /// The 3×4 matrix chain.
    matrix: Sum,
    /// The reading's own U95 terms.
    own: Sum,
    /// The U95 as the hub streams it.
    u95: Sum,
}

impl Sums {
    /// The sums to the defmt log, one line each (`cargo xtask bench-target` reads them);
    /// `lean` says whether the hub's chain was the lean form.
    fn log(&self, lean: bool) {
        defmt::info!(
            "bench clock overhead {=u32} points {=u64} ticks",
            self.empty.points,
            self.empty.ticks
        );
        defmt::info!(
            "bench quaternion {=u32} points {=u64} ticks {=u32} failures",
            self.quaternion.points,
            self.quaternion.ticks,
            self.quaternion.failures
        );
        defmt::info!(
            "bench hub chain (lean {=bool}) {=u32} points {=u64} ticks {=u32} failures",
            lean,
            self.hub.points,
            self.hub.ticks,
            self.hub.failures
        );
        defmt::info!(
            "bench matrix {=u32} points {=u64} ticks {=u32} failures",
            self.matrix.points,
            self.matrix.ticks,
            self.matrix.failures
        );
        defmt::info!(
            "bench u95 own terms {=u32} points {=u64} ticks {=u32} failures",
            self.own.points,
            self.own.ticks,
            self.own.failures
        );
        defmt::info!(
            "bench u95 streamed {=u32} points {=u64} ticks {=u32} failures",
            self.u95.points,
            self.u95.ticks,
            self.u95.failures
        );
    }
}

/// Times the loop of known length and logs it: its ticks give the instructions per tick.
fn time_calibration_loop() {
    let t0 = clock::ticks();
    counted_loop(LOOP_ITERATIONS);
    let t1 = clock::ticks();
    defmt::info!(
        "bench calibration loop {=u32} instructions {=u64} ticks",
        2 * LOOP_ITERATIONS,
        t1 - t0
    );
}

/// Times the Ed25519 check of the table's signature (the bytes after it in the region) under
/// `key`, once: it is deterministic, and runs once per boot or update.
fn time_signature(key: &[u8; KEY_LEN], table: &Table<'_>, region: &[u8]) {
    let n = table.bytes().len();
    let Some(sig) = region
        .get(n..n + SIGNATURE_LEN)
        .and_then(|s| <&[u8; SIGNATURE_LEN]>::try_from(s).ok())
    else {
        defmt::error!("bench: no room for a signature after the table");
        return;
    };
    let a = clock::ticks();
    let ok = core::hint::black_box(signature::verify(key, table.bytes(), sig)).is_ok();
    let b = clock::ticks();
    defmt::info!("bench signature {=u64} ticks {=bool} valid", b - a, ok);
}

/// Times the signature check once, then both chains on every reading until `End`, then logs
/// the sums.
pub fn run<L: Link, P: HubEvaluator>(link: &mut L, region: &[u8], key: &[u8; KEY_LEN]) {
    let Ok(table) = Table::parse_for(region, JOINTS) else {
        defmt::error!("bench: no valid table");
        return;
    };
    let (Ok(quat), Ok(matrix)) = (Chain::<P>::new(&table), MatrixChain::<P>::new(&table)) else {
        defmt::error!("bench: the table does not fit a chain");
        return;
    };

    time_calibration_loop();
    time_signature(key, &table, region);
    let own = OwnTerms::new(&table);
    let mut uncertainty = None;
    <P::Uncertainty<'_> as PointUncertainty<'_, P>>::build_in(&mut uncertainty, &table);
    defmt::info!(
        "bench uncertainty budget {=bool}, streamed U95 {=bool}, parameter block {=bool}",
        own.is_some(),
        uncertainty.is_some(),
        table.parameters().is_some()
    );

    let mut sums = Sums::default();
    let mut replay = Replay::new();
    loop {
        let Some(event) = replay.push(link.read()) else {
            continue;
        };
        let r = match event {
            Event::Reading(r) => r,
            Event::End => break,
            _ => continue,
        };
        let counts = core::hint::black_box(r.counts.as_slice());
        let temp = core::hint::black_box(r.temp_mc);

        let a = clock::ticks();
        let b = clock::ticks();
        sums.empty.add(b - a, false);

        let a = clock::ticks();
        let res = core::hint::black_box(quat.eval_quaternion(counts, temp));
        let b = clock::ticks();
        sums.quaternion.add(b - a, res.is_err());

        // What the hub runs: the lean form where the arm fits it ([`quatarm::lean`]).
        let a = clock::ticks();
        let res = core::hint::black_box(quat.eval(counts, temp));
        let b = clock::ticks();
        sums.hub.add(b - a, res.is_err());

        if let (Some(u), Ok(_)) = (&own, &res) {
            let a = clock::ticks();
            let mut frames = Frames::default();
            let got = core::hint::black_box(
                matrix
                    .eval_frames(counts, temp, &mut frames)
                    .map(|t| u.covariance(&frames, t.xyz.map(P::l_to_f32)).u95_nm()),
            );
            let b = clock::ticks();
            sums.own.add(b - a, got.is_err());
        }
        if let (Some(u), Ok(p)) = (&uncertainty, &res) {
            let a = clock::ticks();
            let got = core::hint::black_box(u.u95_nm(&quat, counts, temp, p));
            let b = clock::ticks();
            sums.u95.add(b - a, got.is_none());
        }

        let a = clock::ticks();
        let res = core::hint::black_box(matrix.eval(counts, temp));
        let b = clock::ticks();
        sums.matrix.add(b - a, res.is_err());
        link.write(&[0]);
    }
    sums.log(quat.is_lean());
}
