//! TI TMP117: ±0.1 °C digital temperature sensor on I2C, after the public datasheet
//! (Texas Instruments SNOSD82D, September 2022).
//!
//! ```text
//!  register (section 7.6 Register Map)     reset   used for
//!  00h Temp_Result   T[15:0]                8000h   the latest conversion, two's complement,
//!                                                   1 LSB = 7.8125 m°C (section 7.3.3, table 7-1)
//!  01h Configuration                        0220h   mode, conversion cycle, Data_Ready
//!      15 HIGH_Alert  14 LOW_Alert  13 Data_Ready  12 EEPROM_Busy
//!      11:10 MOD (00 continuous, 01 shutdown, 10 continuous, 11 one-shot)
//!      9:7 CONV  6:5 AVG  4 T/nA  3 POL  2 DR/Alert  1 Soft_Reset
//!  0Fh Device_ID     REV[15:12] DID[11:0]   0117h   DID = 117h identifies the part
//! ```
//!
//! Every register is 16 bits, most significant byte first. A read writes the pointer byte,
//! then reads two bytes after a repeated start; a write sends the pointer and the two bytes
//! (section 7.5.3.1.3).
//!
//! What the driver checks, so that a reading is either right or an error:
//! - at start-up, and again after any bus error or a lost configuration, the device ID (a
//!   different part at the address is [`Error::WrongDevice`]), then it writes the
//!   configuration: continuous conversion (section 7.4.1), 8 averages, 1 s cycle (table 7-7),
//!   which is the factory default but not necessarily what the part's EEPROM holds;
//! - on every poll, the configuration register: `Data_Ready` set means a new conversion is in
//!   `Temp_Result` (reading the configuration clears the flag); a mode other than continuous
//!   means the part was reset to an EEPROM default we did not write ([`Error::NotConverting`]);
//! - between conversions the last result is served, but only for `max_stale` polls in a row:
//!   a part that stops converting becomes [`Error::Stale`] (and is configured afresh), never
//!   a frozen temperature;
//! - before the first conversion after a reset `Temp_Result` holds –256 °C (section 7.3.1):
//!   [`Error::NotReady`]; a result outside the part's –55…150 °C operating range is
//!   [`Error::Implausible`].

use embedded_hal::i2c::I2c;

use quatarm::temperature::TemperatureSensor;

/// The registers the driver uses (section 7.6).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum Register {
    /// The latest conversion result.
    TempResult = 0x00,
    /// Mode, conversion cycle, averaging and the status flags.
    Configuration = 0x01,
    /// Revision and device ID.
    DeviceId = 0x0F,
}

/// The I2C address, set by what the ADD0 pin is tied to (section 7.5.3.1.2, table 7-3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum Address {
    /// ADD0 to GND: 0x48 (the address of the common breakout boards).
    Gnd = 0x48,
    /// ADD0 to V+: 0x49.
    Vplus = 0x49,
    /// ADD0 to SDA: 0x4A.
    Sda = 0x4A,
    /// ADD0 to SCL: 0x4B.
    Scl = 0x4B,
}

/// Configuration register bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config(pub u16);

impl Config {
    /// A conversion finished since the configuration or result register was last read.
    pub const DATA_READY: u16 = 1 << 13;
    /// The conversion mode field, bits 11:10.
    pub const MOD_MASK: u16 = 0b11 << 10;
    /// Mode 01: shutdown, no conversions.
    pub const MOD_SHUTDOWN: u16 = 0b01 << 10;
    /// Mode 11: one conversion, then shutdown.
    pub const MOD_ONE_SHOT: u16 = 0b11 << 10;
    /// What the driver writes: continuous conversion (MOD 00), CONV 100 and AVG 01, which
    /// is 8 averages in a 1 s cycle (table 7-7): the arm's structure changes temperature over
    /// minutes, so averaging its noise down is worth more than a faster update.
    pub const CONTINUOUS_1S_AVG8: u16 = 0x0220;

    /// True if a new result is waiting.
    pub const fn data_ready(self) -> bool {
        self.0 & Self::DATA_READY != 0
    }

    /// True if the part converts continuously (MOD 00 or 10).
    pub const fn continuous(self) -> bool {
        let m = self.0 & Self::MOD_MASK;
        m != Self::MOD_SHUTDOWN && m != Self::MOD_ONE_SHOT
    }
}

/// The device ID field of a TMP117 (bits 11:0 of register 0Fh).
pub const DEVICE_ID: u16 = 0x0117;

/// The result register's reset value, –256 °C: no conversion finished yet.
const RESET_RESULT: i16 = i16::MIN;

/// The part's operating range in result LSBs: –55 °C and 150 °C at 7.8125 m°C.
const OPERATING_RAW: core::ops::RangeInclusive<i16> = -7040..=19200;

/// Why a reading failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Error<E> {
    /// The I2C bus failed (no acknowledge: sensor missing or unpowered; arbitration; …).
    I2c(E),
    /// The part at the address is not a TMP117: the whole `Device_ID` register it gave.
    WrongDevice(u16),
    /// No conversion has finished since the part was (re)configured.
    NotReady,
    /// No new conversion for more polls in a row than the driver was told to accept.
    Stale,
    /// The part is not in continuous conversion: it was reset to an EEPROM default we did not
    /// write. The driver reconfigures it on the next poll.
    NotConverting(Config),
    /// A result outside the part's operating range (raw register value).
    Implausible(i16),
}

impl<E> From<E> for Error<E> {
    fn from(e: E) -> Self {
        Error::I2c(e)
    }
}

/// Milli-degrees Celsius of a `Temp_Result` code, rounded to the nearest (ties up):
/// 1 LSB = 7.8125 m°C = 125/16 m°C, so the conversion is exact before rounding.
pub const fn raw_to_mc(raw: i16) -> i32 {
    (raw as i32 * 125 + 8).div_euclid(16)
}

/// The driver: owns the I2C bus (or a shared-bus device of it).
pub struct Tmp117<I2C> {
    i2c: I2C,
    address: u8,
    max_stale: u16,
    configured: bool,
    latest: Option<i32>,
    stale: u16,
}

impl<I2C: I2c> Tmp117<I2C> {
    /// A driver for the part at `address` on `i2c`. `max_stale` is how many polls in a row
    /// may find no new conversion and still get the previous one: a board that polls every
    /// P ms passes about 2 s / P (twice the 1 s conversion cycle), so that clock drift
    /// between the two chips never trips it but a part that stopped converting does.
    /// Nothing is sent on the bus until [`Tmp117::init`] or the first reading.
    pub fn new(i2c: I2C, address: Address, max_stale: u16) -> Self {
        Tmp117 {
            i2c,
            address: address as u8,
            max_stale,
            configured: false,
            latest: None,
            stale: 0,
        }
    }

    /// Gives the bus back.
    pub fn release(self) -> I2C {
        self.i2c
    }

    /// Reads one register.
    pub fn read_register(&mut self, reg: Register) -> Result<u16, Error<I2C::Error>> {
        let mut buf = [0u8; 2];
        self.i2c.write_read(self.address, &[reg as u8], &mut buf)?;
        Ok(u16::from_be_bytes(buf))
    }

    /// Checks the device ID and writes the configuration (continuous, 8 averages, 1 s). The
    /// previous result is forgotten: the first reading after this waits for a conversion.
    pub fn init(&mut self) -> Result<(), Error<I2C::Error>> {
        self.configured = false;
        self.latest = None;
        self.stale = 0;
        let id = self.read_register(Register::DeviceId)?;
        if id & 0x0FFF != DEVICE_ID {
            return Err(Error::WrongDevice(id));
        }
        let [hi, lo] = Config::CONTINUOUS_1S_AVG8.to_be_bytes();
        self.i2c
            .write(self.address, &[Register::Configuration as u8, hi, lo])?;
        self.configured = true;
        Ok(())
    }

    /// One poll: the new result if a conversion finished, else the previous one while it is
    /// fresh enough (see the module docs for every check).
    pub fn read_temperature(&mut self) -> Result<i32, Error<I2C::Error>> {
        let result = self.poll();
        if matches!(
            result,
            Err(Error::I2c(_) | Error::NotConverting(_) | Error::Stale)
        ) {
            // Start again from the identity check: the part may have been replaced, reset or
            // stopped converting.
            self.configured = false;
        }
        result
    }

    fn poll(&mut self) -> Result<i32, Error<I2C::Error>> {
        if !self.configured {
            self.init()?;
        }
        let config = Config(self.read_register(Register::Configuration)?);
        if !config.continuous() {
            return Err(Error::NotConverting(config));
        }
        if config.data_ready() {
            let raw = self.read_register(Register::TempResult)? as i16;
            if raw == RESET_RESULT {
                return Err(Error::NotReady);
            }
            if !OPERATING_RAW.contains(&raw) {
                return Err(Error::Implausible(raw));
            }
            let mc = raw_to_mc(raw);
            self.latest = Some(mc);
            self.stale = 0;
            return Ok(mc);
        }
        self.stale = self.stale.saturating_add(1);
        match self.latest {
            None => Err(Error::NotReady),
            Some(_) if self.stale > self.max_stale => Err(Error::Stale),
            Some(mc) => Ok(mc),
        }
    }
}

impl<I2C: I2c> TemperatureSensor for Tmp117<I2C> {
    type Error = Error<I2C::Error>;

    fn read_mc(&mut self) -> Result<i32, Self::Error> {
        self.read_temperature()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_hal::i2c::ErrorKind;
    use embedded_hal_mock::eh1::i2c::{Mock, Transaction};

    const ADDR: u8 = 0x48;

    fn read(reg: Register, value: u16) -> Transaction {
        Transaction::write_read(ADDR, vec![reg as u8], value.to_be_bytes().to_vec())
    }

    fn init_ok() -> Vec<Transaction> {
        vec![
            read(Register::DeviceId, 0x0117),
            Transaction::write(ADDR, vec![0x01, 0x02, 0x20]),
        ]
    }

    const READY: u16 = Config::CONTINUOUS_1S_AVG8 | Config::DATA_READY;
    const WAITING: u16 = Config::CONTINUOUS_1S_AVG8;

    fn sample(raw: u16) -> Vec<Transaction> {
        vec![
            read(Register::Configuration, READY),
            read(Register::TempResult, raw),
        ]
    }

    #[test]
    fn codes_convert_as_in_table_7_1() {
        // Table 7-1 of the datasheet, in m°C.
        assert_eq!(raw_to_mc(0xF380u16 as i16), -25_000);
        assert_eq!(raw_to_mc(0xFFF0u16 as i16), -125);
        assert_eq!(raw_to_mc(0x0000), 0);
        assert_eq!(raw_to_mc(0x0010), 125);
        assert_eq!(raw_to_mc(0x0080), 1_000);
        assert_eq!(raw_to_mc(0x0C80), 25_000);
        assert_eq!(raw_to_mc(0x3200), 100_000);
        assert_eq!(raw_to_mc(i16::MIN), -256_000);
        // One LSB either side of zero rounds to the nearest m°C (7.8125 → 8).
        assert_eq!(raw_to_mc(0x0001), 8);
        assert_eq!(raw_to_mc(-1), -8);
        // 20.5 °C and -0.5 °C are exact.
        assert_eq!(raw_to_mc(2624), 20_500);
        assert_eq!(raw_to_mc(-64), -500);
        // Within half a m°C of the exact value over the whole range.
        for raw in i16::MIN..=i16::MAX {
            let exact = f64::from(raw) * 7.8125;
            assert!((f64::from(raw_to_mc(raw)) - exact).abs() <= 0.5, "{raw}");
        }
    }

    #[test]
    fn first_reading_checks_the_part_configures_it_and_converts() {
        let mut t = init_ok();
        t.extend(sample(0x0A40)); // 20.5 °C
        t.extend(sample(0xFD80)); // -5 °C
        let mut i2c = Mock::new(&t);
        let mut s = Tmp117::new(i2c.clone(), Address::Gnd, 8);
        assert_eq!(s.read_mc(), Ok(20_500));
        assert_eq!(s.read_mc(), Ok(-5_000));
        i2c.done();
    }

    #[test]
    fn another_part_at_the_address_is_refused_and_checked_again() {
        let mut t = vec![read(Register::DeviceId, 0x0116)]; // a TMP116
        t.extend(init_ok());
        t.extend(sample(0x0C80));
        let mut i2c = Mock::new(&t);
        let mut s = Tmp117::new(i2c.clone(), Address::Gnd, 8);
        assert_eq!(s.read_mc(), Err(Error::WrongDevice(0x0116)));
        assert_eq!(s.read_mc(), Ok(25_000));
        i2c.done();
    }

    #[test]
    fn a_new_silicon_revision_is_still_a_tmp117() {
        let mut t = vec![read(Register::DeviceId, 0x1117)];
        t.push(Transaction::write(ADDR, vec![0x01, 0x02, 0x20]));
        let mut i2c = Mock::new(&t);
        let mut s = Tmp117::new(i2c.clone(), Address::Gnd, 8);
        assert_eq!(s.init(), Ok(()));
        i2c.done();
    }

    #[test]
    fn a_bus_error_is_an_error_and_the_next_poll_starts_from_the_id() {
        let mut t = init_ok();
        t.push(
            Transaction::write_read(ADDR, vec![0x01], vec![0, 0]).with_error(
                ErrorKind::NoAcknowledge(embedded_hal::i2c::NoAcknowledgeSource::Address),
            ),
        );
        t.extend(init_ok());
        t.extend(sample(0x0C80));
        let mut i2c = Mock::new(&t);
        let mut s = Tmp117::new(i2c.clone(), Address::Gnd, 8);
        assert_eq!(
            s.read_mc(),
            Err(Error::I2c(ErrorKind::NoAcknowledge(
                embedded_hal::i2c::NoAcknowledgeSource::Address
            )))
        );
        assert_eq!(s.read_mc(), Ok(25_000));
        i2c.done();
    }

    #[test]
    fn a_missing_sensor_fails_at_init() {
        let t = [Transaction::write_read(ADDR, vec![0x0F], vec![0, 0]).with_error(ErrorKind::Bus)];
        let mut i2c = Mock::new(&t);
        let mut s = Tmp117::new(i2c.clone(), Address::Gnd, 8);
        assert_eq!(s.init(), Err(Error::I2c(ErrorKind::Bus)));
        i2c.done();
    }

    #[test]
    fn before_the_first_conversion_there_is_no_temperature() {
        let mut t = init_ok();
        t.push(read(Register::Configuration, WAITING));
        // Data_Ready but the reset value still in the register: not a measurement.
        t.extend(sample(0x8000));
        let mut i2c = Mock::new(&t);
        let mut s = Tmp117::new(i2c.clone(), Address::Gnd, 8);
        assert_eq!(s.read_mc(), Err(Error::NotReady));
        assert_eq!(s.read_mc(), Err(Error::NotReady));
        i2c.done();
    }

    #[test]
    fn between_conversions_the_last_result_holds_until_it_is_stale() {
        let mut t = init_ok();
        t.extend(sample(0x0C80));
        for _ in 0..3 {
            t.push(read(Register::Configuration, WAITING));
        }
        t.extend(init_ok()); // a stale part is checked and configured afresh
        t.extend(sample(0x0A00)); // 20 °C: fresh again
        t.push(read(Register::Configuration, WAITING));
        let mut i2c = Mock::new(&t);
        let mut s = Tmp117::new(i2c.clone(), Address::Gnd, 2);
        assert_eq!(s.read_mc(), Ok(25_000));
        assert_eq!(s.read_mc(), Ok(25_000));
        assert_eq!(s.read_mc(), Ok(25_000));
        assert_eq!(
            s.read_mc(),
            Err(Error::Stale),
            "third poll without a conversion"
        );
        assert_eq!(s.read_mc(), Ok(20_000));
        assert_eq!(s.read_mc(), Ok(20_000));
        i2c.done();
    }

    #[test]
    fn a_part_out_of_continuous_mode_is_reported_and_reconfigured() {
        let mut t = init_ok();
        t.push(read(
            Register::Configuration,
            Config::MOD_SHUTDOWN | Config::DATA_READY,
        ));
        t.extend(init_ok());
        t.extend(sample(0x0C80));
        let mut i2c = Mock::new(&t);
        let mut s = Tmp117::new(i2c.clone(), Address::Gnd, 8);
        assert_eq!(
            s.read_mc(),
            Err(Error::NotConverting(Config(
                Config::MOD_SHUTDOWN | Config::DATA_READY
            )))
        );
        assert_eq!(s.read_mc(), Ok(25_000));
        i2c.done();
    }

    #[test]
    fn results_outside_the_operating_range_are_refused() {
        let mut t = init_ok();
        t.extend(sample(0x4B01)); // 150.0078 °C
        t.extend(sample((-7041i16) as u16)); // -55.0078 °C
        t.extend(sample(0x4B00)); // 150 °C exactly: in range
        let mut i2c = Mock::new(&t);
        let mut s = Tmp117::new(i2c.clone(), Address::Gnd, 8);
        assert_eq!(s.read_mc(), Err(Error::Implausible(0x4B01)));
        assert_eq!(s.read_mc(), Err(Error::Implausible(-7041)));
        assert_eq!(s.read_mc(), Ok(150_000));
        i2c.done();
    }

    #[test]
    fn other_addresses_are_used_on_the_bus() {
        let t = [
            Transaction::write_read(0x4B, vec![0x0F], vec![0x01, 0x17]),
            Transaction::write(0x4B, vec![0x01, 0x02, 0x20]),
        ];
        let mut i2c = Mock::new(&t);
        let mut s = Tmp117::new(i2c.clone(), Address::Scl, 8);
        assert_eq!(s.init(), Ok(()));
        i2c.done();
    }
}
