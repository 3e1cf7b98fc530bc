//! AMS AS5047P: 14-bit magnetic absolute encoder on SPI (mode 1, 16-bit frames, CSn toggled
//! between frames), after the public datasheet (ams, AS5047P v1-06).
//!
//! ```text
//!  command frame (to the part)            read frame (from the part)
//!  15    14    13 .............. 0        15    14    13 .............. 0
//!  PARC  R/W   ADDR                       PARD  EF    DATA
//!  even  1=rd  register address           even  error flag (read ERRFL)
//! ```
//! Parity bit 15 makes the count of ones in the whole 16-bit word even. The answer to a command
//! comes in the *next* frame, so one angle reading is three frames:
//! `DIAAGC` (answer: previous, ignored) → `ANGLECOM` (answer: DIAAGC) → `NOP` (answer: angle).
//! Checked on every reading: parity of both answers, the error flag (then `ERRFL` is read,
//! which also clears it), the magnetic field (`MAGH`, `MAGL`), CORDIC overflow (`COF`) and the
//! offset-compensation loop (`LF`): any of them is an error, never a count.

use embedded_hal::spi::SpiDevice;

use quatarm::encoder::AbsoluteEncoder;

/// The registers the driver uses (volatile register addresses of the datasheet, table 11).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u16)]
pub enum Register {
    /// No operation: reading it fetches the answer to the previous command.
    Nop = 0x0000,
    /// Error register: framing error, invalid command, parity error. Cleared by reading it.
    Errfl = 0x0001,
    /// Diagnostics and automatic gain control.
    Diaagc = 0x3FFC,
    /// Angle with dynamic angle error compensation.
    Anglecom = 0x3FFF,
}

/// `ERRFL` bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ErrorFlags(pub u16);

impl ErrorFlags {
    /// The part saw a framing error on SPI.
    pub const FRERR: u16 = 1 << 0;
    /// The part received a command for a register that does not exist.
    pub const INVCOMM: u16 = 1 << 1;
    /// The part received a command with bad parity.
    pub const PARERR: u16 = 1 << 2;
}

/// `DIAAGC` bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Diagnostics(pub u16);

impl Diagnostics {
    /// Magnetic field too weak (magnet missing or too far).
    pub const MAGL: u16 = 1 << 11;
    /// Magnetic field too strong.
    pub const MAGH: u16 = 1 << 10;
    /// CORDIC overflow: the angle is invalid.
    pub const COF: u16 = 1 << 9;
    /// Offset compensation finished (1): before that the angle is not yet valid.
    pub const LF: u16 = 1 << 8;

    /// True if the angle read beside this diagnostic word can be trusted.
    pub fn angle_valid(self) -> bool {
        self.0 & (Self::MAGL | Self::MAGH | Self::COF) == 0 && self.0 & Self::LF != 0
    }
}

/// Why a reading failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Error<E> {
    /// The SPI bus failed.
    Spi(E),
    /// An answer had odd parity: corrupted on the wire.
    Parity,
    /// The part raised its error flag; `ERRFL` said this.
    ErrorFlag(ErrorFlags),
    /// The diagnostics say the angle is not valid (magnet, CORDIC, compensation loop).
    Diagnostics(Diagnostics),
}

impl<E> From<E> for Error<E> {
    fn from(e: E) -> Self {
        Error::Spi(e)
    }
}

/// The driver: owns an SPI device with its chip select.
pub struct As5047p<SPI> {
    spi: SPI,
}

const EF: u16 = 1 << 14;
const DATA: u16 = 0x3FFF;

/// The command word that reads `reg`: R/W set, even parity in bit 15.
pub(crate) fn read_command(reg: Register) -> u16 {
    with_parity(EF | reg as u16)
}

fn with_parity(word: u16) -> u16 {
    let w = word & 0x7FFF;
    if w.count_ones() % 2 == 1 {
        w | 0x8000
    } else {
        w
    }
}

impl<SPI: SpiDevice<u8>> As5047p<SPI> {
    /// A driver for the part behind `spi` (SPI mode 1, at most 10 MHz).
    pub fn new(spi: SPI) -> Self {
        As5047p { spi }
    }

    /// Gives the SPI device back.
    pub fn release(self) -> SPI {
        self.spi
    }

    /// One 16-bit frame, chip select around it: sends `command`, returns the raw answer to
    /// the command before it.
    fn frame(&mut self, command: u16) -> Result<u16, Error<SPI::Error>> {
        let mut buf = command.to_be_bytes();
        self.spi.transfer_in_place(&mut buf)?;
        Ok(u16::from_be_bytes(buf))
    }

    /// Checks an answer's parity and error flag; returns its 14 data bits.
    fn check(&mut self, answer: u16) -> Result<u16, Error<SPI::Error>> {
        if answer.count_ones() % 2 != 0 {
            return Err(Error::Parity);
        }
        if answer & EF != 0 {
            // Read ERRFL (clears it) to say what went wrong.
            self.frame(read_command(Register::Errfl))?;
            let errfl = self.frame(read_command(Register::Nop))?;
            return Err(Error::ErrorFlag(ErrorFlags(errfl & DATA)));
        }
        Ok(answer & DATA)
    }

    /// Reads one register (two frames).
    pub fn read_register(&mut self, reg: Register) -> Result<u16, Error<SPI::Error>> {
        self.frame(read_command(reg))?;
        let answer = self.frame(read_command(Register::Nop))?;
        self.check(answer)
    }

    /// Reads the compensated angle, 0..16384, with its diagnostics checked (three frames).
    pub fn read_angle(&mut self) -> Result<u16, Error<SPI::Error>> {
        self.frame(read_command(Register::Diaagc))?;
        let diag = self.frame(read_command(Register::Anglecom))?;
        let angle = self.frame(read_command(Register::Nop))?;
        let diag = Diagnostics(self.check(diag)?);
        let angle = self.check(angle)?;
        if !diag.angle_valid() {
            return Err(Error::Diagnostics(diag));
        }
        Ok(angle)
    }
}

impl<SPI: SpiDevice<u8>> AbsoluteEncoder for As5047p<SPI> {
    type Error = Error<SPI::Error>;

    fn counts_per_rev(&self) -> u32 {
        1 << 14
    }

    fn read_count(&mut self) -> Result<u32, Self::Error> {
        self.read_angle().map(u32::from)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_hal::spi::ErrorKind;
    use embedded_hal_mock::eh1::spi::{Mock, Transaction};
    use quatarm::encoder::read_joints;

    /// The frames of one exchange: `sent` command, `answer` (raw word) back.
    fn frame(sent: u16, answer: u16) -> Vec<Transaction<u8>> {
        vec![
            Transaction::transaction_start(),
            Transaction::transfer_in_place(
                sent.to_be_bytes().to_vec(),
                answer.to_be_bytes().to_vec(),
            ),
            Transaction::transaction_end(),
        ]
    }

    /// A data word as the part sends it: even parity, error flag as given.
    fn answer(data: u16, ef: bool) -> u16 {
        with_parity((data & DATA) | if ef { EF } else { 0 })
    }

    fn angle_exchange(diag: u16, angle: u16) -> Vec<Transaction<u8>> {
        let mut t = frame(read_command(Register::Diaagc), 0xFFFF);
        t.extend(frame(read_command(Register::Anglecom), diag));
        t.extend(frame(read_command(Register::Nop), angle));
        t
    }

    const GOOD_DIAG: u16 = Diagnostics::LF | 0x80; // loop finished, AGC mid-range

    #[test]
    fn command_words_match_the_datasheet() {
        // Datasheet examples: read ANGLECOM = 0xFFFF, read NOP = 0xC000, read ERRFL = 0x4001.
        assert_eq!(read_command(Register::Anglecom), 0xFFFF);
        assert_eq!(read_command(Register::Nop), 0xC000);
        assert_eq!(read_command(Register::Errfl), 0x4001);
        assert_eq!(read_command(Register::Diaagc), 0xFFFC);
    }

    #[test]
    fn a_clean_reading_gives_the_angle() {
        let mut spi = Mock::new(&angle_exchange(
            answer(GOOD_DIAG, false),
            answer(12345, false),
        ));
        let mut enc = As5047p::new(spi.clone());
        assert_eq!(enc.read_count(), Ok(12345));
        assert_eq!(enc.counts_per_rev(), 16384);
        spi.done();
    }

    #[test]
    fn a_flipped_bit_is_a_parity_error() {
        let bad = answer(12345, false) ^ 0x0010;
        let mut spi = Mock::new(&angle_exchange(answer(GOOD_DIAG, false), bad));
        let mut enc = As5047p::new(spi.clone());
        assert_eq!(enc.read_count(), Err(Error::Parity));
        spi.done();
    }

    #[test]
    fn the_error_flag_reads_and_reports_errfl() {
        let mut t = angle_exchange(answer(GOOD_DIAG, true), answer(0, false));
        t.extend(frame(read_command(Register::Errfl), 0));
        t.extend(frame(
            read_command(Register::Nop),
            answer(ErrorFlags::PARERR, false),
        ));
        let mut spi = Mock::new(&t);
        let mut enc = As5047p::new(spi.clone());
        assert_eq!(
            enc.read_count(),
            Err(Error::ErrorFlag(ErrorFlags(ErrorFlags::PARERR)))
        );
        spi.done();
    }

    #[test]
    fn a_weak_magnet_is_not_an_angle() {
        let diag = GOOD_DIAG | Diagnostics::MAGL;
        let mut spi = Mock::new(&angle_exchange(answer(diag, false), answer(777, false)));
        let mut enc = As5047p::new(spi.clone());
        assert_eq!(enc.read_count(), Err(Error::Diagnostics(Diagnostics(diag))));
        spi.done();
    }

    #[test]
    fn the_compensation_loop_must_have_finished() {
        let diag = 0x80; // LF clear
        let mut spi = Mock::new(&angle_exchange(answer(diag, false), answer(777, false)));
        let mut enc = As5047p::new(spi.clone());
        assert!(matches!(enc.read_count(), Err(Error::Diagnostics(_))));
        spi.done();
    }

    /// An SPI device whose bus always fails (the mock crate cannot inject SPI errors).
    struct BrokenBus;
    impl embedded_hal::spi::ErrorType for BrokenBus {
        type Error = ErrorKind;
    }
    impl SpiDevice<u8> for BrokenBus {
        fn transaction(
            &mut self,
            _: &mut [embedded_hal::spi::Operation<'_, u8>],
        ) -> Result<(), ErrorKind> {
            Err(ErrorKind::Overrun)
        }
    }

    #[test]
    fn a_bus_error_is_passed_on() {
        let mut enc = As5047p::new(BrokenBus);
        assert_eq!(enc.read_count(), Err(Error::Spi(ErrorKind::Overrun)));
    }

    #[test]
    fn faults_are_reported_per_joint() {
        // Three encoders on three chip selects: joint 2 has a parity error.
        let mut buses = [
            Mock::new(&angle_exchange(
                answer(GOOD_DIAG, false),
                answer(100, false),
            )),
            Mock::new(&angle_exchange(
                answer(GOOD_DIAG, false),
                answer(200, false) ^ 1,
            )),
            Mock::new(&angle_exchange(
                answer(GOOD_DIAG, false),
                answer(300, false),
            )),
        ];
        let mut encs = buses.clone().map(As5047p::new);
        let mut counts = [0u32; 3];
        assert_eq!(read_joints(&mut encs, &mut counts), 0b010);
        assert_eq!(counts, [100, 0, 300]);
        for b in &mut buses {
            b.done();
        }
    }
}
