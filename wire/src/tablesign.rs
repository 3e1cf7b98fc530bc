//! Signing tables on the host: the arm maker's Ed25519 key pair, a signed image (the table,
//! then its 64-byte signature: `quatarm::signature`), and the check a hub makes of it.
//!
//! The private key is a PKCS#8 PEM file, the format `openssl genpkey -algorithm ed25519`
//! writes, so a maker can keep it in the tools it already has (an HSM export, openssl); the
//! public key is its 32 raw bytes, what a firmware image embeds (`include_bytes!`).

use std::path::Path;

use ed25519_dalek::pkcs8::{DecodePrivateKey, EncodePrivateKey};
use ed25519_dalek::{Signer, SigningKey};
use quatarm::signature::{self, SignatureError, KEY_LEN, SIGNATURE_LEN};
use quatarm::table::Table;

/// Why a key, a table or a signature was refused, naming the file.
#[derive(Debug, thiserror::Error)]
pub enum SignError {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// What the system said.
        source: std::io::Error,
    },
    /// The private key file is not a PKCS#8 PEM Ed25519 key.
    #[error("{path}: not a PKCS#8 PEM Ed25519 private key ({why})")]
    PrivateKey {
        /// The file.
        path: String,
        /// What the decoder said.
        why: String,
    },
    /// The public key file is not 32 bytes.
    #[error("{path}: a public key is {KEY_LEN} raw bytes, this file has {len}")]
    PublicKey {
        /// The file.
        path: String,
        /// Its length.
        len: usize,
    },
    /// The bytes are not a table the firmware accepts.
    #[error("not a valid table: {0}")]
    Table(quatarm::table::TableError),
    /// The image has no signature after its table, or more bytes than one.
    #[error("{0}")]
    Layout(String),
    /// The signature does not verify.
    #[error("the signature does not verify under this key ({0:?})")]
    Signature(SignatureError),
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> SignError + '_ {
    move |source| SignError::Io {
        path: path.display().to_string(),
        source,
    }
}

/// A new key pair from the operating system's random source: the private key as PKCS#8 PEM,
/// the public key's 32 bytes.
pub fn keygen() -> Result<(String, [u8; KEY_LEN]), SignError> {
    let key = SigningKey::generate(&mut rand_core::OsRng);
    let pem = key
        .to_pkcs8_pem(Default::default())
        .map_err(|e| SignError::PrivateKey {
            path: "(new key)".into(),
            why: e.to_string(),
        })?;
    Ok((pem.to_string(), key.verifying_key().to_bytes()))
}

/// Reads a private key file.
pub fn read_private(path: &Path) -> Result<SigningKey, SignError> {
    let text = std::fs::read_to_string(path).map_err(io(path))?;
    SigningKey::from_pkcs8_pem(&text).map_err(|e| SignError::PrivateKey {
        path: path.display().to_string(),
        why: e.to_string(),
    })
}

/// Reads a public key file (32 raw bytes).
pub fn read_public(path: &Path) -> Result<[u8; KEY_LEN], SignError> {
    let bytes = std::fs::read(path).map_err(io(path))?;
    bytes
        .as_slice()
        .try_into()
        .map_err(|_| SignError::PublicKey {
            path: path.display().to_string(),
            len: bytes.len(),
        })
}

/// The signed image of `table` (checked as the firmware checks it first): the table, then
/// its signature under `key`. A table that already carries a signature is signed afresh.
pub fn sign(key: &SigningKey, table: &[u8]) -> Result<Vec<u8>, SignError> {
    let t = Table::parse(table).map_err(SignError::Table)?;
    let bytes = t.bytes();
    let mut out = bytes.to_vec();
    out.extend_from_slice(&key.sign(bytes).to_bytes());
    Ok(out)
}

/// Checks a signed image as a hub with `key` does; returns the table's length.
pub fn verify(key: &[u8; KEY_LEN], image: &[u8]) -> Result<usize, SignError> {
    let t = Table::parse(image).map_err(SignError::Table)?;
    let n = t.bytes().len();
    let sig: &[u8; SIGNATURE_LEN] = image[n..].try_into().map_err(|_| {
        SignError::Layout(format!(
            "a signed image is its table ({n} bytes) and {SIGNATURE_LEN} bytes of signature; this one has {} bytes after the table",
            image.len() - n
        ))
    })?;
    signature::verify(key, t.bytes(), sig).map_err(SignError::Signature)?;
    Ok(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_signed_table_verifies_under_its_key_only() {
        let text = include_str!("../../data/default-6.toml");
        let arm = quatarm_ref::calfile::parse(text).unwrap().arm;
        let table = crate::tablebuild::build(&arm).unwrap();
        let (pem, public) = keygen().unwrap();
        let key = SigningKey::from_pkcs8_pem(&pem).unwrap();
        let image = sign(&key, &table).unwrap();
        assert_eq!(image.len(), table.len() + SIGNATURE_LEN);
        assert_eq!(verify(&public, &image).unwrap(), table.len());
        // Signing a signed image signs the table again, not the signature.
        assert_eq!(sign(&key, &image).unwrap(), image);
        let (_, other) = keygen().unwrap();
        assert!(matches!(
            verify(&other, &image),
            Err(SignError::Signature(_))
        ));
        assert!(matches!(verify(&public, &table), Err(SignError::Layout(_))));
        let mut changed = image.clone();
        changed[100] ^= 1;
        assert!(verify(&public, &changed).is_err());
    }
}
