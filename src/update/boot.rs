//! The table a hub uses at boot: the slot the newest valid state record names, if its table
//! verifies (the record's length and CRC, then every check of [`Table::parse`]); else the
//! slot of the other record; else whichever slot holds a valid table, slot 0 first (a board
//! whose factory table was flashed by a probe has no record yet).

use embedded_storage::nor_flash::{NorFlash, NorFlashError, NorFlashErrorKind};

use super::layout::{Layout, LayoutError};
use super::record::{self, StateRecord};
use crate::signature::{self, SignatureError, KEY_LEN, SIGNATURE_LEN};
use crate::stream::TableState;
use crate::table::{Table, TableError, MAX_JOINTS, MAX_TABLE_LEN};

/// What a slot's table must be for this hub to boot on it (and an update to commit it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Accept {
    /// The joint count the hub drives (`None`: any the format allows).
    pub joints: Option<usize>,
    /// The arm maker's public keys: with them, only a table signed under the key of the
    /// hub's generation is accepted ([`crate::signature`], [`Keys`]); without them, signed
    /// and unsigned tables alike.
    pub keys: Option<Keys>,
    /// The counts per revolution of the hub's encoders, joint 1 first (`None`: any). A table
    /// made for other encoders would turn every count into a wrong angle: refused at commit
    /// and passed over at boot like a corrupt one, so an update cannot leave a hub that
    /// measures nothing.
    pub counts: Option<[u32; MAX_JOINTS]>,
}

impl Accept {
    /// Tables for `joints` joints, signed or not.
    pub const fn joints(joints: usize) -> Accept {
        Accept {
            joints: Some(joints),
            keys: None,
            counts: None,
        }
    }

    /// The same, for encoders of these counts per revolution (joint 1 first; joints past the
    /// slice's end must have 0, which no table has).
    pub fn for_encoders(self, counts_per_rev: &[u32]) -> Accept {
        let mut counts = [0; MAX_JOINTS];
        for (c, &n) in counts.iter_mut().zip(counts_per_rev) {
            *c = n;
        }
        Accept {
            counts: Some(counts),
            ..self
        }
    }

    /// The same, and signed under `key` (generation 0, no next key).
    pub const fn signed_by(self, key: [u8; KEY_LEN]) -> Accept {
        self.signed_by_keys(Keys {
            generation: 0,
            current: key,
            next: None,
        })
    }

    /// The same, and signed under the key of the hub's generation among `keys`.
    pub const fn signed_by_keys(self, keys: Keys) -> Accept {
        Accept {
            keys: Some(keys),
            ..self
        }
    }

    /// The key a table must be signed under on a hub at key generation `gen` (`None`: no
    /// key of this image, so no signed table is accepted; also `None` on a hub without keys).
    fn key_at(&self, gen: u8) -> Option<&[u8; KEY_LEN]> {
        self.keys.as_ref().and_then(|k| k.of(gen))
    }
}

/// The maker's keys an image holds: the current one and the one that replaces it when it
/// leaks or expires (`docs/update.md`, "Key rotation"). A hub trusts exactly one of them at a
/// time, the key of its generation, persisted in the state record: `generation` until a table
/// signed by `next` is committed, `generation + 1` from then on, for good (the record's
/// generation never goes down, and the retired key is never tried again but to name a
/// refusal). An image built later with the next pair (`generation + 1`, a newer next) takes
/// over a hub that rotated; a hub whose generation is past both keys of its image accepts no
/// table until reflashed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Keys {
    /// The generation of `current` (0 for an image's first key).
    pub generation: u8,
    /// The key of `generation`.
    pub current: [u8; KEY_LEN],
    /// The key of `generation + 1`, where the image has one.
    pub next: Option<[u8; KEY_LEN]>,
}

impl Keys {
    /// The key of generation `gen`, where this image holds it.
    pub fn of(&self, gen: u8) -> Option<&[u8; KEY_LEN]> {
        if gen == self.generation {
            Some(&self.current)
        } else if Some(gen) == self.generation.checked_add(1) {
            self.next.as_ref()
        } else {
            None
        }
    }
}

/// The key generation a hub is at: the highest of the valid records' and the image's own
/// (an image built with newer keys moves the hub forward; nothing moves it back).
pub fn key_generation(accept: &Accept, copies: &[Option<StateRecord>; 2]) -> u8 {
    let image = accept.keys.map_or(0, |k| k.generation);
    copies
        .iter()
        .flatten()
        .map(|r| r.key_gen)
        .fold(image, u8::max)
}

/// The hub's anti-rollback floor: the highest calibration number the valid records say was
/// made live (0 without a record). Like the key generation it only grows, and the highest of
/// both copies counts, so a torn newest record cannot lower it below the previous one's.
pub fn floor(copies: &[Option<StateRecord>; 2]) -> u32 {
    copies.iter().flatten().map(|r| r.floor).fold(0, u32::max)
}

/// A flash operation failed; what the driver said, in a form a stream message can carry.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FlashFault {
    /// Offset or length not aligned to the device's unit.
    NotAligned,
    /// Outside the device.
    OutOfBounds,
    /// Anything else the driver reports (a write or erase that failed, a timeout).
    Other,
}

impl FlashFault {
    /// The fault of a driver's error.
    pub fn of<E: NorFlashError>(e: E) -> FlashFault {
        match e.kind() {
            NorFlashErrorKind::NotAligned => FlashFault::NotAligned,
            NorFlashErrorKind::OutOfBounds => FlashFault::OutOfBounds,
            _ => FlashFault::Other,
        }
    }
}

/// Why no slot holds a table the hub can use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BootError {
    /// The layout does not fit the device.
    Layout(LayoutError),
    /// Neither slot holds a valid table: what each slot's bytes are (blank, corrupt, ...).
    NoTable([SlotError; 2]),
}

/// Why one slot's table cannot be used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SlotError {
    /// The slot could not be read.
    Flash(FlashFault),
    /// The bytes are not a valid table.
    Table(TableError),
    /// A valid table, but not the one the state record names (another length or CRC).
    NotRecorded,
    /// A valid table whose signature is missing or wrong, on a hub with a key.
    Signature(SignatureError),
    /// A valid table for encoders of another resolution than the hub's.
    Resolution,
    /// A valid table whose calibration number is below the hub's anti-rollback floor
    /// ([`floor`]): never made live at boot (an older record's slot after the newest one's
    /// was lost, an offered table left complete in a slot by a refused or cut update).
    BelowFloor {
        /// The table's calibration number.
        number: u32,
        /// The floor it is below.
        floor: u32,
    },
}

impl SlotError {
    /// How the stream reports the slot: the status word's table state.
    pub fn state(&self) -> TableState {
        match self {
            // A table the state record does not allow is reported like one it does not name.
            SlotError::Flash(_) | SlotError::NotRecorded | SlotError::BelowFloor { .. } => {
                TableState::Corrupt
            }
            SlotError::Table(t) => TableState::from(t),
            SlotError::Resolution => TableState::WrongResolution,
            SlotError::Signature(SignatureError::Missing) => TableState::Unsigned,
            SlotError::Signature(_) => TableState::BadSignature,
        }
    }
}

/// The live table and where it came from.
#[derive(Clone, Copy, Debug)]
pub struct Live<'b> {
    /// The slot (0 or 1).
    pub slot: u8,
    /// The sequence number of the state record that names it; `None` when no record did and
    /// the slot was found by its contents alone.
    pub seq: Option<u32>,
    /// The table, parsed and checked.
    pub table: Table<'b>,
}

/// Reads slot `slot` into `buf` and checks it completely: as `accept` says (joints, the
/// signature under the key of generation `gen`), and against the record's length and CRC if
/// given. The one check of a slot, used by the boot and by the update's commit.
///
/// A record's length is the table's, or the table's plus [`SIGNATURE_LEN`] for a signed one;
/// without a record (a table flashed by a probe) the bytes after the table are its signature
/// unless they are erased (0xFF).
pub(crate) fn verify_slot<'b, F: NorFlash>(
    flash: &mut F,
    layout: &Layout,
    slot: u8,
    accept: &Accept,
    gen: u8,
    rec: Option<&StateRecord>,
    buf: &'b mut [u8; MAX_TABLE_LEN],
) -> Result<Table<'b>, SlotError> {
    // The slot's bytes a table may take (not its trailer, where the state record lies).
    let region = layout.table_area::<F>(slot);
    let start = region.start;
    let fault = |e: F::Error| SlotError::Flash(FlashFault::of(e));
    // A slot may be smaller than the largest table (one with many parameters): read no
    // further than it.
    let span = ((region.end - region.start) as usize).min(buf.len());
    let buf = &mut buf[..span];
    flash.read(start, buf).map_err(fault)?;
    let table = match accept.joints {
        Some(n) => Table::parse_for(buf, n),
        None => Table::parse(buf),
    }
    .map_err(SlotError::Table)?;
    if let Some(counts) = &accept.counts {
        let fits = (0..table.joint_count())
            .all(|i| table.joint(i).map(|j| j.counts) == counts.get(i).copied());
        if !fits {
            return Err(SlotError::Resolution);
        }
    }
    let len = table.bytes().len() as u32;
    let signed = match rec {
        Some(r) if table.crc() != r.crc => return Err(SlotError::NotRecorded),
        Some(r) if r.len == len => false,
        Some(r) if r.len == len + SIGNATURE_LEN as u32 => true,
        Some(_) => return Err(SlotError::NotRecorded),
        None => true,
    };
    if accept.keys.is_some() {
        let mut sig = [0xffu8; SIGNATURE_LEN];
        if signed && start + len + SIGNATURE_LEN as u32 <= region.end {
            flash.read(start + len, &mut sig).map_err(fault)?;
        }
        // Erased flash reads 0xFF; QEMU's RAM-backed regions read 0 beyond a loaded file.
        if !signed || sig.iter().all(|&b| b == 0xff) || sig.iter().all(|&b| b == 0) {
            return Err(SlotError::Signature(SignatureError::Missing));
        }
        // No key of this generation in the image: nothing verifies.
        let key = accept
            .key_at(gen)
            .ok_or(SlotError::Signature(SignatureError::Invalid))?;
        signature::verify(key, table.bytes(), &sig).map_err(SlotError::Signature)?;
    }
    Ok(table)
}

/// Which slot boots, and the record that names it (see the module's rule); `buf` is scratch.
/// A board whose flash is memory-mapped takes the slot's bytes from there and keeps the table
/// in flash; [`live_table`] is this plus a copy into `buf`.
pub fn live_slot<F: NorFlash>(
    flash: &mut F,
    layout: &Layout,
    accept: &Accept,
    buf: &mut [u8; MAX_TABLE_LEN],
) -> Result<(u8, Option<StateRecord>), BootError> {
    layout.check(flash).map_err(BootError::Layout)?;
    let copies = record::read_copies(flash, layout);
    // One key for both slots and every rule: a table signed by a retired key never boots.
    let gen = key_generation(accept, &copies);
    // One floor for both slots: a table below it never boots, whichever record names it or
    // none (the older record's slot when the newest one's fails; a lower table an update
    // left whole in the other slot before its commit was refused or cut).
    let floor = floor(&copies);
    let mut verify = |slot: u8, rec: Option<&StateRecord>| {
        let number = verify_slot(flash, layout, slot, accept, gen, rec, buf)?
            .release()
            .number;
        if number < floor {
            return Err(SlotError::BelowFloor { number, floor });
        }
        Ok(())
    };
    if let Some((first, _)) = record::newest(&copies) {
        for rec in [copies[first], copies[1 - first]].into_iter().flatten() {
            if verify(rec.slot, Some(&rec)).is_ok() {
                return Ok((rec.slot, Some(rec)));
            }
        }
    }
    let mut why = [SlotError::Table(TableError::Blank); 2];
    for slot in 0..2u8 {
        match verify(slot, None) {
            Ok(()) => return Ok((slot, None)),
            Err(e) => why[usize::from(slot)] = e,
        }
    }
    Err(BootError::NoTable(why))
}

/// The table to boot on, read into `buf` (`accept`: what the hub requires of it). Never a slot that fails any check; the old table while an update has not
/// written its record; the new one once it has.
pub fn live_table<'b, F: NorFlash>(
    flash: &mut F,
    layout: &Layout,
    accept: &Accept,
    buf: &'b mut [u8; MAX_TABLE_LEN],
) -> Result<Live<'b>, BootError> {
    let (slot, rec) = live_slot(flash, layout, accept, buf)?;
    let gen = key_generation(accept, &record::read_copies(flash, layout));
    // Read again for the borrow of `buf`: `live_slot` may have tried another slot last.
    let table = verify_slot(flash, layout, slot, accept, gen, rec.as_ref(), buf).map_err(|e| {
        let mut why = [SlotError::Table(TableError::Blank); 2];
        why[usize::from(slot)] = e;
        BootError::NoTable(why)
    })?;
    Ok(Live {
        slot,
        seq: rec.map(|r| r.seq),
        table,
    })
}
