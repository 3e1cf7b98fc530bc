//! The arm maker's public key an image checks tables against ([`quatarm::update::Accept`]).
//!
//! The QEMU images trust the repository's test key ([`TEST_MAKER_KEY`], `keys/README.md`), and
//! qemu-m4f its successor as the next key ([`TEST_KEYS`]), so that the end-to-end tests can
//! sign tables and rotate a hub. A real board's image embeds the key its build
//! was given: `QUATARM_MAKER_KEY=/path/to/maker.pub cargo xtask build --board NAME` (the
//! 32-byte file `armcal table keygen` writes; the private key stays offline). The board's
//! build script (`maker_key` in `boards/common/build_link.rs`) copies it beside its output,
//! and [`maker_key!`](crate::maker_key!) includes it. Without the variable the build takes
//! the test key and warns: such an image accepts any table signed with the published test
//! key, so it is for the bench, never for an arm.

/// The test key's 32 bytes (`keys/test-maker.pub`).
pub const TEST_MAKER_KEY: [u8; quatarm::signature::KEY_LEN] =
    *include_bytes!("../../../keys/test-maker.pub");

/// The test key's successor (`keys/test-maker-next.pub`): the next maker key of the QEMU
/// images, which a table signed with `keys/test-maker-next.pem` rotates a hub to
/// (`docs/update.md`, "Key rotation and revocation").
pub const TEST_NEXT_MAKER_KEY: [u8; quatarm::signature::KEY_LEN] =
    *include_bytes!("../../../keys/test-maker-next.pub");

/// The keys of a QEMU image that updates: the test key (generation 0) and its successor, so
/// that the end-to-end tests can rotate a hub and see the retired key refused.
pub const TEST_KEYS: quatarm::update::Keys = quatarm::update::Keys {
    generation: 0,
    current: TEST_MAKER_KEY,
    next: Some(TEST_NEXT_MAKER_KEY),
};

/// The key the board's build script chose (`QUATARM_MAKER_KEY`, else the test key), as a
/// `[u8; 32]`: expands in the board's crate, whose build script wrote the file.
#[macro_export]
macro_rules! maker_key {
    () => {
        *include_bytes!(concat!(env!("OUT_DIR"), "/maker.pub"))
    };
}

/// The keys of a real board's image, as its build script chose them: the current key
/// ([`maker_key!`](crate::maker_key!), generation 0) and the next (`QUATARM_NEXT_MAKER_KEY`;
/// with neither variable the test key's successor, so that a bench image can rotate; with a
/// maker key but no next, none, and the build warns that the image cannot rotate). A next
/// key in every field image is what lets a maker whose key leaks move the hubs to the next
/// and retire the old for good (`docs/update.md`), without a debug probe.
#[macro_export]
macro_rules! maker_keys {
    () => {
        quatarm::update::Keys {
            generation: 0,
            current: $crate::maker_key!(),
            next: $crate::maker_key::next_key(include_bytes!(concat!(
                env!("OUT_DIR"),
                "/maker-next.pub"
            ))),
        }
    };
}

/// The next key from the bytes the build script wrote: 32 bytes, or none (an empty file).
pub const fn next_key(bytes: &[u8]) -> Option<[u8; quatarm::signature::KEY_LEN]> {
    if bytes.len() != quatarm::signature::KEY_LEN {
        return None;
    }
    let mut key = [0u8; quatarm::signature::KEY_LEN];
    let mut i = 0;
    while i < key.len() {
        key[i] = bytes[i];
        i += 1;
    }
    Some(key)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The build script writes 32 bytes for a next key and an empty file for none: both read
    /// back as written, and a file of another length is no key (the build refuses it first).
    #[test]
    fn the_next_key_is_its_32_bytes_or_none() {
        let bytes = include_bytes!("../../../keys/test-maker-next.pub");
        assert_eq!(next_key(bytes), Some(TEST_NEXT_MAKER_KEY));
        assert_eq!(next_key(&[]), None);
        assert_eq!(next_key(&bytes[..31]), None);
        assert_ne!(next_key(bytes), Some(TEST_MAKER_KEY));
    }
}
