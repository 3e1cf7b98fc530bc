//! The one random generator of the tool, and the draws built on it.
//!
//! Every random draw (a simulation, a Monte Carlo budget, a hold-out's folds, the diagnosis's
//! scenarios, an effect's typical size) comes from one seeded ChaCha generator, so the same
//! seed gives the same numbers on every machine. A leaf: it imports nothing of the crate.

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;

/// The generator every random draw of the tool uses.
pub(crate) type SimRng = ChaCha8Rng;

/// A seeded generator.
pub fn rng(seed: u64) -> SimRng {
    use rand::SeedableRng;
    ChaCha8Rng::seed_from_u64(seed)
}

/// A standard normal draw (Box–Muller).
pub fn normal(rng: &mut SimRng) -> f64 {
    let u1: f64 = 1.0 - rng.gen::<f64>();
    let u2: f64 = rng.gen::<f64>();
    (-2.0 * u1.ln()).sqrt() * (2.0 * PI * u2).cos()
}
