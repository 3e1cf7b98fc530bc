//! The arm maker's public key the QEMU images trust: the repository's test key
//! (`keys/README.md`), so that the end-to-end tests can sign tables. A firmware image for a
//! real arm embeds its maker's own key instead (`armcal table keygen`).

/// The test key's 32 bytes (`keys/test-maker.pub`).
pub const TEST_MAKER_KEY: [u8; quatarm::signature::KEY_LEN] =
    *include_bytes!("../../../keys/test-maker.pub");
