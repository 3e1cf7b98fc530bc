//! The update state machine. `Begin` picks the inactive slot and erases it; `Chunk`s write
//! the table in order; `Commit` checks the slot completely and only then writes the state
//! record that makes it live. Until that record is written the old table stays live (the
//! boot never reads the slot being written, see [`super::boot`]); each step answers
//! [`Accepted`] or a [`Refusal`] saying why, for a stream message to carry.
//!
//! The hash `Begin` carries is the table's own CRC-32 (its last four bytes), not a SHA-256:
//! it guards against transfer and flash errors, which CRC-32 detects over a 1.8 KB table as
//! well as any hash, and it is already in every image (the table's own check). Against a
//! forged table no unkeyed hash helps; that is the signature's job (Ed25519 over the table's
//! bytes, with its own SHA-512), which `Commit` will check through the same `verify_slot`.

use embedded_storage::nor_flash::NorFlash;
use heapless::Vec;

use super::boot::{self, Accept, FlashFault, SlotError};
use super::layout::{Layout, LayoutError, MAX_WRITE_SIZE};
use super::record::{self, StateRecord};

use crate::signature::{SignatureError, SIGNATURE_LEN};
use crate::stream::TableState;
use crate::table::{is_table_len, Table, MAX_TABLE_LEN};

/// Most table bytes one `Chunk` carries: the largest that keeps its `ToDevice` message
/// (variant bytes, offset varint, length byte, the bytes) and CRC within a frame's
/// [`MAX_PAYLOAD`](crate::stream::MAX_PAYLOAD) of 64 bytes, with offsets up to 2^21.
pub const CHUNK_LEN: usize = 48;

/// One step of an update, as the `ToDevice::Update` message carries it (`docs/protocol.md`).
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Step {
    /// Start (or restart) an update of a table of `len` bytes whose CRC (last four bytes) is
    /// `crc`.
    Begin {
        /// Table length in bytes.
        len: u32,
        /// The table's CRC-32.
        crc: u32,
    },
    /// Table bytes at `offset`; chunks come in order, `offset` is the count so far.
    Chunk {
        /// Where these bytes go in the table.
        offset: u32,
        /// The bytes.
        bytes: Vec<u8, CHUNK_LEN>,
    },
    /// Check the whole table and make it live.
    Commit,
    /// Give up; the old table stays live.
    Abort,
}

impl Step {
    /// Every step that sends `table` whole (a table, or a signed one: the table and its
    /// signature), as a host sends them: `Begin` with its length and the table's CRC (0 for
    /// bytes that are no table, which the hub then refuses), the chunks in order, `Commit`.
    /// The one place a table is cut into chunks (`armcal table send`, the tests, the fuzz
    /// seeds).
    pub fn sequence(table: &[u8]) -> impl Iterator<Item = Step> + '_ {
        let crc = Table::parse(table).map_or(0, |t| t.crc());
        let begin = Step::Begin {
            len: table.len() as u32,
            crc,
        };
        let chunks = table
            .chunks(CHUNK_LEN)
            .enumerate()
            .map(|(i, c)| Step::Chunk {
                offset: (i * CHUNK_LEN) as u32,
                // Cannot fail: `chunks` gives at most CHUNK_LEN bytes.
                bytes: Vec::from_slice(c).unwrap_or_default(),
            });
        core::iter::once(begin)
            .chain(chunks)
            .chain(core::iter::once(Step::Commit))
    }
}

// By hand: heapless's `defmt` support is for defmt 0.3; a chunk logs as its offset and length.
#[cfg(feature = "defmt")]
impl defmt::Format for Step {
    fn format(&self, f: defmt::Formatter) {
        match self {
            Step::Begin { len, crc } => {
                defmt::write!(f, "Begin {{ len: {=u32}, crc: {=u32:#x} }}", len, crc)
            }
            Step::Chunk { offset, bytes } => {
                defmt::write!(
                    f,
                    "Chunk {{ offset: {=u32}, {=usize} bytes }}",
                    offset,
                    bytes.len()
                )
            }
            Step::Commit => defmt::write!(f, "Commit"),
            Step::Abort => defmt::write!(f, "Abort"),
        }
    }
}

/// A step that was carried out.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Accepted {
    /// The slot is erased and waits for `len` bytes.
    Begun {
        /// The slot being written.
        slot: u8,
    },
    /// Bytes written; the next chunk's offset.
    Chunk {
        /// Offset the next chunk must have.
        next: u32,
    },
    /// The new table is live.
    Committed {
        /// Its slot.
        slot: u8,
        /// Its state record's sequence number.
        seq: u32,
    },
    /// The update was abandoned.
    Aborted,
}

/// Why a step was refused. After a refusal of `Commit` or a flash fault the update is over
/// (a new `Begin` starts again); a refused `Chunk` may be resent.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Refusal {
    /// `Chunk` or `Commit` with no update begun.
    NotBegun,
    /// A length no table has, signed or not (a table of 6 or 7 joints, with or without its
    /// 64-byte signature).
    BadLength(u32),
    /// A chunk not at the next offset.
    OutOfOrder {
        /// The offset expected.
        expected: u32,
    },
    /// A chunk reaching past the length `Begin` gave.
    PastEnd {
        /// The length `Begin` gave.
        len: u32,
    },
    /// `Commit` before every byte arrived.
    Incomplete {
        /// Bytes received.
        received: u32,
        /// Bytes `Begin` announced.
        len: u32,
    },
    /// The written table fails a check of the boot, its signature included: the state a boot
    /// would report for it (the status word's table state, so that the host reads one
    /// vocabulary for both).
    Table(TableState),
    /// The written table is valid but is not what `Begin` announced (its length or CRC).
    NotAnnounced,
    /// The layout does not fit the flash.
    Layout(LayoutError),
    /// A flash operation failed.
    Flash(FlashFault),
    /// The sequence number would wrap (after 2^32 − 1 updates).
    SequenceExhausted,
    /// This hub takes no update over the stream (its board has no flash driver wired to
    /// [`Updater`]); the table is changed with a debug probe.
    NotSupported,
    /// The table's calibration number is below the highest this hub has made live: an older
    /// calibration sent back (anti-rollback, `docs/update.md`). Nothing changed. A deliberate
    /// return to older values is the maker's re-issue of them under a new, higher number.
    Rollback {
        /// The hub's floor: the highest calibration number it has made live.
        live: u32,
        /// The number of the table sent.
        offered: u32,
    },
    /// The table is signed by a maker's key this hub has retired (it moved to the next key):
    /// refused for good, whatever its number.
    RetiredKey,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    Idle,
    Receiving {
        slot: u8,
        len: u32,
        crc: u32,
        seq: u32,
        written: u32,
        /// The anti-rollback floor at `Begin`: the newest record's, or the live table's
        /// number where that is higher (a factory table, no record).
        floor: u32,
        /// The hub's key generation at `Begin`.
        gen: u8,
    },
}

/// An update in progress (or none). Holds no table bytes beyond one flash write unit.
#[derive(Debug)]
pub struct Updater {
    layout: Layout,
    accept: Accept,
    state: State,
    /// Bytes received but not yet written: less than one write unit.
    pending: Vec<u8, MAX_WRITE_SIZE>,
}

impl Updater {
    /// An updater for the slots of `layout`; `accept` is what the hub's boot requires of a
    /// table (its joint count, its signature): a table the boot would refuse is refused at
    /// commit.
    pub fn new(layout: Layout, accept: Accept) -> Updater {
        Updater {
            layout,
            accept,
            state: State::Idle,
            pending: Vec::new(),
        }
    }

    /// The layout this updater writes, as the boot must read it.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// What it requires of a table, as the boot does.
    pub fn accept(&self) -> &Accept {
        &self.accept
    }

    /// Carries out one step. `scratch` holds a table while it is checked (`Begin` finds the
    /// live slot, `Commit` checks the new one).
    pub fn step<F: NorFlash>(
        &mut self,
        flash: &mut F,
        scratch: &mut [u8; MAX_TABLE_LEN],
        step: &Step,
    ) -> Result<Accepted, Refusal> {
        let result = match step {
            Step::Begin { len, crc } => self.begin(flash, scratch, *len, *crc),
            Step::Chunk { offset, bytes } => self.chunk(flash, *offset, bytes),
            Step::Commit => self.commit(flash, scratch),
            Step::Abort => {
                self.state = State::Idle;
                Ok(Accepted::Aborted)
            }
        };
        // A flash fault or a refused commit ends the update; a refused chunk does not.
        if matches!(result, Err(Refusal::Flash(_)))
            || (result.is_err() && matches!(step, Step::Commit))
        {
            self.state = State::Idle;
        }
        result
    }

    fn begin<F: NorFlash>(
        &mut self,
        flash: &mut F,
        scratch: &mut [u8; MAX_TABLE_LEN],
        len: u32,
        crc: u32,
    ) -> Result<Accepted, Refusal> {
        self.state = State::Idle;
        self.pending.clear();
        self.layout.check(flash).map_err(Refusal::Layout)?;
        let unsigned = (len as usize).checked_sub(SIGNATURE_LEN);
        if !is_table_len(len as usize) && !unsigned.is_some_and(is_table_len) {
            return Err(Refusal::BadLength(len));
        }
        let live = boot::live_table(flash, &self.layout, &self.accept, scratch)
            .ok()
            .map(|l| (l.slot, l.table.release().number));
        let slot = match live {
            Some((s, _)) => 1 - s,
            None => 0,
        };
        let copies = record::read_copies(flash, &self.layout);
        let gen = boot::key_generation(&self.accept, &copies);
        let newest = record::newest(&copies).map(|(_, r)| r);
        let seq = match newest {
            Some(r) => r.seq.checked_add(1).ok_or(Refusal::SequenceExhausted)?,
            None => 1,
        };
        let floor = boot::floor(&copies).max(live.map_or(0, |(_, n)| n));
        // A slot holds every table without a parameter block (the layout's check); one with
        // many parameters may not fit a small board's slot. A table never reaches into its
        // slot's trailer: the state record goes there.
        let area = self.layout.table_area::<F>(slot);
        if len > area.end - area.start {
            return Err(Refusal::BadLength(len));
        }
        // The whole slot, its trailer (and the record copy there) included.
        let region = &self.layout.slots()[usize::from(slot)];
        flash
            .erase(region.start, region.end)
            .map_err(|e| Refusal::Flash(FlashFault::of(e)))?;
        self.state = State::Receiving {
            slot,
            len,
            crc,
            seq,
            written: 0,
            floor,
            gen,
        };
        Ok(Accepted::Begun { slot })
    }

    fn chunk<F: NorFlash>(
        &mut self,
        flash: &mut F,
        offset: u32,
        bytes: &[u8],
    ) -> Result<Accepted, Refusal> {
        let State::Receiving {
            slot, len, written, ..
        } = self.state
        else {
            return Err(Refusal::NotBegun);
        };
        if offset != written {
            return Err(Refusal::OutOfOrder { expected: written });
        }
        let end = written.saturating_add(bytes.len() as u32);
        if end > len {
            return Err(Refusal::PastEnd { len });
        }
        let base = self.layout.slots()[usize::from(slot)].start;
        // Flash offset of the first pending byte.
        let mut at = base + written - self.pending.len() as u32;
        for &b in bytes {
            // Cannot fail: the buffer is flushed whenever it reaches a write unit.
            let _ = self.pending.push(b);
            if self.pending.len() == F::WRITE_SIZE {
                flash
                    .write(at, &self.pending)
                    .map_err(|e| Refusal::Flash(FlashFault::of(e)))?;
                at += F::WRITE_SIZE as u32;
                self.pending.clear();
            }
        }
        if let State::Receiving { written, .. } = &mut self.state {
            *written = end;
        }
        Ok(Accepted::Chunk { next: end })
    }

    fn commit<F: NorFlash>(
        &mut self,
        flash: &mut F,
        scratch: &mut [u8; MAX_TABLE_LEN],
    ) -> Result<Accepted, Refusal> {
        let State::Receiving {
            slot,
            len,
            crc,
            seq,
            written,
            floor,
            gen,
        } = self.state
        else {
            return Err(Refusal::NotBegun);
        };
        if written != len {
            return Err(Refusal::Incomplete {
                received: written,
                len,
            });
        }
        if !self.pending.is_empty() {
            let at =
                self.layout.slots()[usize::from(slot)].start + written - self.pending.len() as u32;
            self.pending.resize(F::WRITE_SIZE, 0xff).ok();
            let w = flash.write(at, &self.pending);
            self.pending.clear();
            w.map_err(|e| Refusal::Flash(FlashFault::of(e)))?;
        }
        let mut rec = StateRecord {
            seq,
            slot,
            len,
            crc,
            floor,
            key_gen: gen,
        };
        let (number, key_gen) = self.check_new(flash, scratch, &rec)?;
        if number < floor {
            return Err(Refusal::Rollback {
                live: floor,
                offered: number,
            });
        }
        rec.floor = number.max(floor);
        rec.key_gen = key_gen;
        record::write(flash, &self.layout, &rec).map_err(|e| Refusal::Flash(FlashFault::of(e)))?;
        // Read back: the record just written must be the one the boot will follow.
        match record::newest(&record::read_copies(flash, &self.layout)) {
            Some((_, r)) if r == rec => {}
            _ => return Err(Refusal::Flash(FlashFault::Other)),
        }
        self.state = State::Idle;
        Ok(Accepted::Committed { slot, seq })
    }

    /// The commit's check of the written slot (`rec`: the record it would get, at the hub's
    /// key generation): the table's calibration number and the key generation it is signed
    /// at. A table that fails under the hub's key is tried under the next key (a rotation:
    /// the new table becomes the first signed by it, and its record retires the old key), and
    /// under the key just retired, to name the refusal.
    fn check_new<F: NorFlash>(
        &self,
        flash: &mut F,
        scratch: &mut [u8; MAX_TABLE_LEN],
        rec: &StateRecord,
    ) -> Result<(u32, u8), Refusal> {
        let refusal = |e: SlotError| match e {
            SlotError::Flash(f) => Refusal::Flash(f),
            SlotError::NotRecorded => Refusal::NotAnnounced,
            // `verify_slot` checks no floor (the commit compares the number itself); named
            // for completeness in the refusal it would be.
            SlotError::BelowFloor { number, floor } => Refusal::Rollback {
                live: floor,
                offered: number,
            },
            e @ (SlotError::Table(_) | SlotError::Signature(_) | SlotError::Resolution) => {
                Refusal::Table(e.state())
            }
        };
        let (layout, accept, gen) = (&self.layout, &self.accept, rec.key_gen);
        let mut verify = |gen: u8| {
            boot::verify_slot(
                flash,
                layout,
                rec.slot,
                accept,
                gen,
                Some(rec),
                &mut *scratch,
            )
            .map(|t| t.release().number)
        };
        let first = verify(gen);
        if first != Err(SlotError::Signature(SignatureError::Invalid)) {
            return first.map(|n| (n, gen)).map_err(refusal);
        }
        if let Some(next) = gen.checked_add(1) {
            if let Ok(n) = verify(next) {
                return Ok((n, next));
            }
        }
        if let Some(retired) = gen.checked_sub(1) {
            if verify(retired).is_ok() {
                return Err(Refusal::RetiredKey);
            }
        }
        first.map(|n| (n, gen)).map_err(refusal)
    }
}
