//! Calibration update in place: a new table written into the inactive one of two flash slots,
//! checked completely, then made live by a small state record, so that a power cut at any
//! moment leaves the hub on a valid table, the old or the new, never a mix.
//!
//! - [`layout`]: where the two slots and the two copies of the state record lie: copies in
//!   erase units of their own, or in the last bytes of each slot (for chips of large erase
//!   units, the STM32F4's 128 KiB sectors).
//! - [`record`]: the state record (which slot is live, sequence number, length, CRC), its
//!   encoding and its two copies.
//! - [`session`]: the update state machine, `Begin` / `Chunk` / `Commit`, each answered with a
//!   [`session::Refusal`] or accepted; the messages of the stream call it.
//! - [`boot`]: [`boot::live_table`], the table a hub uses at boot (every board with an update
//!   port boots through it: `board_common::flash`).
//!
//! - `mock` and `fixtures` (tests, and feature `mock-flash` for the fuzz target
//!   `update_session`): a NOR flash in RAM that can lose power part-way through any operation,
//!   and the tables and steps the tests send.
//!
//! Flash is reached through the `embedded-storage` crate's `NorFlash` traits, the interface
//! every embassy and `*-hal` flash driver implements (and embassy-boot and sequential-storage
//! are written against), so a board passes its own driver unchanged. `docs/update.md` gives
//! the record layout, the steps and the argument for power loss.

pub mod boot;
#[cfg(any(test, feature = "mock-flash"))]
pub mod fixtures;
pub mod layout;
#[cfg(any(test, feature = "mock-flash"))]
pub mod mock;
#[cfg(test)]
mod power_loss;
pub mod record;
#[cfg(test)]
mod rollback_tests;
pub mod session;
#[cfg(test)]
mod session_tests;

pub use boot::{floor, key_generation, live_slot, live_table, Accept, BootError, Keys, Live};
pub use layout::{Layout, LayoutError};
pub use record::StateRecord;
pub use session::{Accepted, Refusal, Updater};
