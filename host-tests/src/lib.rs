//! Tests live in `tests/`. The library holds what they share with `cargo xtask`: the board
//! list, the QEMU runner and the recordings a replay sends.

pub mod boards;
pub mod defmt_log;
pub mod e2e;
pub mod qemu;
pub mod recording;
pub mod soak;
