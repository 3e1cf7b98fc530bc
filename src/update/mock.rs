//! A NOR flash in RAM for the tests, with a power cut: erase sets a unit to 0xFF, a write can
//! only clear bits (the stored byte becomes `old & new`), and after a chosen number of
//! operations (one write unit written, or one erase unit erased) the power goes: that
//! operation is left untouched, done, or with random bits, and every later one fails.
//! Like sequential-storage's mock, it refuses a second write of a word before its erase
//! (flash with ECC, as on the STM32L4/H7, forbids it), so the tests also show that the update
//! never relies on rewriting a word.

use embedded_storage::nor_flash::{
    ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};
use std::vec::Vec;

/// What the operation under way when the power goes leaves behind.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cut {
    /// Nothing of it.
    Untouched,
    /// All of it (the power went just after).
    Done,
    /// Some of it: a write clears a random part of the bits it clears; an erase leaves
    /// random bytes.
    Random(u64),
}

/// The mock's error: a misuse, or no power.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MockError {
    /// Offset or length not aligned.
    NotAligned,
    /// A word written twice without an erase between.
    Rewrite,
    /// Outside the device.
    OutOfBounds,
    /// The power is off.
    PowerLost,
}

impl NorFlashError for MockError {
    fn kind(&self) -> NorFlashErrorKind {
        match self {
            MockError::NotAligned => NorFlashErrorKind::NotAligned,
            MockError::OutOfBounds => NorFlashErrorKind::OutOfBounds,
            MockError::Rewrite | MockError::PowerLost => NorFlashErrorKind::Other,
        }
    }
}

/// The mock flash.
#[derive(Clone, Debug)]
pub struct MockFlash {
    /// The contents.
    pub mem: Vec<u8>,
    /// Operations done so far.
    pub ops: usize,
    /// The operation (0-based) at which the power goes, and what it leaves.
    pub cut: Option<(usize, Cut)>,
    /// Per write unit: written since its last erase (or since the image was loaded).
    written: Vec<bool>,
    powered: bool,
    rng: u64,
}

impl MockFlash {
    /// Erased flash of `len` bytes.
    pub fn new(len: usize) -> MockFlash {
        MockFlash::from_image(std::vec![0xff; len])
    }

    /// A flash holding `mem`, powered, with no cut planned: what a reboot finds.
    pub fn from_image(mem: Vec<u8>) -> MockFlash {
        MockFlash {
            written: std::vec![false; mem.len() / Self::WRITE_SIZE],
            mem,
            ops: 0,
            cut: None,
            powered: true,
            rng: 0,
        }
    }

    /// Whether the power went.
    pub fn power_lost(&self) -> bool {
        !self.powered
    }

    fn random(&mut self) -> u8 {
        // xorshift64: enough to scatter bits; the seed makes each case reproducible.
        let mut x = self.rng;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.rng = x;
        (x >> 24) as u8
    }

    /// Counts one operation; `Some(cut)` if the power goes during it.
    fn operation(&mut self) -> Result<Option<Cut>, MockError> {
        if !self.powered {
            return Err(MockError::PowerLost);
        }
        let n = self.ops;
        self.ops += 1;
        match self.cut {
            Some((at, cut)) if at == n => {
                self.powered = false;
                if let Cut::Random(seed) = cut {
                    self.rng = seed | 1;
                }
                Ok(Some(cut))
            }
            _ => Ok(None),
        }
    }

    fn range(&self, offset: u32, len: usize, unit: usize) -> Result<usize, MockError> {
        let at = offset as usize;
        if at % unit != 0 || len % unit != 0 {
            return Err(MockError::NotAligned);
        }
        if at + len > self.mem.len() {
            return Err(MockError::OutOfBounds);
        }
        Ok(at)
    }
}

impl ErrorType for MockFlash {
    type Error = MockError;
}

impl ReadNorFlash for MockFlash {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), MockError> {
        if !self.powered {
            return Err(MockError::PowerLost);
        }
        let at = self.range(offset, bytes.len(), 1)?;
        bytes.copy_from_slice(&self.mem[at..at + bytes.len()]);
        Ok(())
    }

    fn capacity(&self) -> usize {
        self.mem.len()
    }
}

impl NorFlash for MockFlash {
    const WRITE_SIZE: usize = 4;
    const ERASE_SIZE: usize = 1024;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), MockError> {
        let len = (to as usize)
            .checked_sub(from as usize)
            .ok_or(MockError::OutOfBounds)?;
        let start = self.range(from, len, Self::ERASE_SIZE)?;
        for unit in (start..start + len).step_by(Self::ERASE_SIZE) {
            let cut = self.operation()?;
            let words = unit / Self::WRITE_SIZE..(unit + Self::ERASE_SIZE) / Self::WRITE_SIZE;
            // A torn erase leaves the unit in no state a write may rely on: not writable.
            self.written[words].fill(cut.is_some());
            for i in unit..unit + Self::ERASE_SIZE {
                self.mem[i] = match cut {
                    None | Some(Cut::Done) => 0xff,
                    Some(Cut::Untouched) => self.mem[i],
                    Some(Cut::Random(_)) => self.random(),
                };
            }
            if cut.is_some() {
                return Err(MockError::PowerLost);
            }
        }
        Ok(())
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), MockError> {
        let start = self.range(offset, bytes.len(), Self::WRITE_SIZE)?;
        for (k, word) in bytes.chunks(Self::WRITE_SIZE).enumerate() {
            let at = start + k * Self::WRITE_SIZE;
            if self.written[at / Self::WRITE_SIZE] {
                return Err(MockError::Rewrite);
            }
            let cut = self.operation()?;
            self.written[at / Self::WRITE_SIZE] = true;
            for (i, &new) in word.iter().enumerate() {
                let old = self.mem[at + i];
                self.mem[at + i] = match cut {
                    None | Some(Cut::Done) => old & new,
                    Some(Cut::Untouched) => old,
                    // Of the bits this write clears, a random part is cleared.
                    Some(Cut::Random(_)) => old & !(old & !new & self.random()),
                };
            }
            if cut.is_some() {
                return Err(MockError::PowerLost);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nor_semantics_and_cut() {
        let mut f = MockFlash::new(2048);
        f.mem[..4].copy_from_slice(&[0x0f, 0xf0, 0x55, 0xaa]);
        f.write(0, &[0xff, 0x00, 0xff, 0xff]).unwrap();
        assert_eq!(
            &f.mem[..4],
            &[0x0f, 0x00, 0x55, 0xaa],
            "writes only clear bits"
        );
        assert_eq!(f.write(0, &[0; 4]), Err(MockError::Rewrite));
        assert_eq!(f.write(1, &[0; 4]), Err(MockError::NotAligned));
        f.erase(0, 1024).unwrap();
        assert!(f.mem[..1024].iter().all(|&b| b == 0xff));
        f.write(0, &[0; 4]).unwrap();
        let mut f = MockFlash::new(2048);
        f.cut = Some((1, Cut::Untouched));
        assert_eq!(f.write(0, &[0; 8]), Err(MockError::PowerLost));
        assert_eq!(&f.mem[..8], &[0, 0, 0, 0, 0xff, 0xff, 0xff, 0xff]);
        assert_eq!(f.write(8, &[0; 4]), Err(MockError::PowerLost));
        assert!(f.power_lost());
    }
}
