//! Tests live in `tests/`. The library holds what they share with `cargo xtask` and the fuzz
//! targets: the board list, the QEMU runners (the UART on a socket; on a pseudo-terminal in
//! `pty`, for the `armcal` binary), the recordings a replay sends and the generator of arms
//! inside the table's limits.

pub mod arms;
pub mod boards;
pub mod defmt_log;
pub mod e2e;
pub mod pty;
pub mod qemu;
pub mod recording;
pub mod session;
pub mod soak;
