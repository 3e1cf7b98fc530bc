//! Signed tables: an Ed25519 signature (RFC 8032) over a table's bytes, checked against the arm
//! maker's public key in the firmware image, at boot and at an update's commit.
//!
//! A signed image is the table followed by its 64-byte signature; the table format itself
//! is unchanged (its header gives its length, so the signature starts where the table ends),
//! and an unsigned table is the table alone. The CRC inside the table catches transfer and
//! flash errors; only the signature tells a table the maker made from one anyone could make.
//!
//! Verification is `ed25519-dalek`'s `verify_strict` (dalek-cryptography, audited by
//! Quarkslab in 2019, no_std): it refuses the small-order keys and non-canonical signatures
//! that plain `verify` lets through, so a table has exactly one valid signature per key.
//! Built without the `fast` feature: its precomputed basepoint tables (~30 KB) do not fit a
//! hub, and verification runs once per boot or update. `docs/update.md` gives the sizes and
//! the verification time measured on the QEMU boards.

use ed25519_dalek::{Signature, VerifyingKey};

/// Bytes of a signature.
pub const SIGNATURE_LEN: usize = 64;

/// Bytes of a public key.
pub const KEY_LEN: usize = 32;

/// Why a table's signature is not accepted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SignatureError {
    /// The table carries no signature (the slot ends, or the update's length, at the table).
    Missing,
    /// The firmware's key is not a valid Ed25519 public key (a build error, reported as such).
    BadKey,
    /// The signature does not verify under the key: another key, or changed bytes.
    Invalid,
}

/// Checks `signature` over `table` under `key`.
pub fn verify(
    key: &[u8; KEY_LEN],
    table: &[u8],
    signature: &[u8; SIGNATURE_LEN],
) -> Result<(), SignatureError> {
    let key = VerifyingKey::from_bytes(key).map_err(|_| SignatureError::BadKey)?;
    let sig = Signature::from_bytes(signature);
    key.verify_strict(table, &sig)
        .map_err(|_| SignatureError::Invalid)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// RFC 8032, section 7.1, TEST 2 (one-byte message 0x72).
    const KEY: [u8; 32] = [
        0x3d, 0x40, 0x17, 0xc3, 0xe8, 0x43, 0x89, 0x5a, 0x92, 0xb7, 0x0a, 0xa7, 0x4d, 0x1b, 0x7e,
        0xbc, 0x9c, 0x98, 0x2c, 0xcf, 0x2e, 0xc4, 0x96, 0x8c, 0xc0, 0xcd, 0x55, 0xf1, 0x2a, 0xf4,
        0x66, 0x0c,
    ];
    const SIG: [u8; 64] = [
        0x92, 0xa0, 0x09, 0xa9, 0xf0, 0xd4, 0xca, 0xb8, 0x72, 0x0e, 0x82, 0x0b, 0x5f, 0x64, 0x25,
        0x40, 0xa2, 0xb2, 0x7b, 0x54, 0x16, 0x50, 0x3f, 0x8f, 0xb3, 0x76, 0x22, 0x23, 0xeb, 0xdb,
        0x69, 0xda, 0x08, 0x5a, 0xc1, 0xe4, 0x3e, 0x15, 0x99, 0x6e, 0x45, 0x8f, 0x36, 0x13, 0xd0,
        0xf1, 0x1d, 0x8c, 0x38, 0x7b, 0x2e, 0xae, 0xb4, 0x30, 0x2a, 0xee, 0xb0, 0x0d, 0x29, 0x16,
        0x12, 0xbb, 0x0c, 0x00,
    ];

    #[test]
    fn the_rfc_8032_vector_verifies_and_any_change_is_refused() {
        assert_eq!(verify(&KEY, &[0x72], &SIG), Ok(()));
        assert_eq!(verify(&KEY, &[0x73], &SIG), Err(SignatureError::Invalid));
        let mut sig = SIG;
        sig[10] ^= 1;
        assert_eq!(verify(&KEY, &[0x72], &sig), Err(SignatureError::Invalid));
        let mut key = KEY;
        key[0] ^= 1;
        assert_ne!(verify(&key, &[0x72], &SIG), Ok(()));
    }
}
