//! `cargo xtask make-recording`: writes the shipped recording `data/recordings/default-6-session.csv`.
//!
//! A measuring session on `default-6` as an encoder hub would see it: the operator sweeps the
//! arm smoothly through its workspace (each joint a sum of slow sinusoids, hinges kept inside
//! ±170°), one reading every 5 ms for 60 s, while the arm warms from 18 °C to 27 °C. Counts are what 2^20-count
//! encoders read (rounded, wrapped into 0..2^20). Deterministic: a fixed seed, no clock.

use std::f64::consts::PI;
use std::fmt::Write as _;

use anyhow::Result;
use host_tests::boards::root;

/// Readings in the shipped recording.
pub const READINGS: usize = 12_000;
const COUNTS: f64 = 1_048_576.0;

/// xorshift64*: enough randomness for phases and rates, reproducible everywhere.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The recording as CSV text.
pub fn recording() -> String {
    let mut rng = Rng(0x5EED_0000_C0DE_0001);
    // Per joint: three sinusoids (amplitude rad, frequency Hz, phase).
    let mut terms = [[(0.0, 0.0, 0.0); 3]; 6];
    for (j, joint) in terms.iter_mut().enumerate() {
        let hinge = j % 2 == 1;
        for (k, t) in joint.iter_mut().enumerate() {
            let amp = if hinge { 1.0 } else { 2.5 } / (k as f64 + 1.0);
            *t = (
                amp * (0.5 + rng.next()),
                0.02 + 0.3 * rng.next(),
                2.0 * PI * rng.next(),
            );
        }
    }
    let mut s = String::from("# default-6 measuring session: 60 s, a reading every 5 ms, 2^20-count encoders, 18->27 degC\nc1,c2,c3,c4,c5,c6,temp_c\n");
    for i in 0..READINGS {
        let t = i as f64 * 0.005; // seconds
        for (j, joint) in terms.iter().enumerate() {
            let mut theta: f64 = joint
                .iter()
                .map(|(a, f, p)| a * (2.0 * PI * f * t + p).sin())
                .sum();
            if j % 2 == 1 {
                theta = theta.clamp(-170f64.to_radians(), 170f64.to_radians());
            }
            let count = (theta / (2.0 * PI) * COUNTS).round().rem_euclid(COUNTS) as u32;
            let _ = write!(s, "{count},");
        }
        let temp = 18.0 + 9.0 * (i as f64 / READINGS as f64) + 0.05 * (t * 0.7).sin();
        let _ = writeln!(s, "{temp:.3}");
    }
    s
}

/// Writes the file.
pub fn run() -> Result<()> {
    let dir = root().join("data/recordings");
    std::fs::create_dir_all(&dir)?;
    let path = dir.join("default-6-session.csv");
    std::fs::write(&path, recording())?;
    eprintln!("wrote {} ({READINGS} readings)", path.display());
    Ok(())
}
