//! Drivers for the parts of a quatarm hub, on embedded-hal 1.0.
//!
//! `quatarm` itself is the chain, the calibration table and the stream: it says what a hub
//! needs of a joint's encoder ([`quatarm::encoder::AbsoluteEncoder`]) and of the arm's
//! temperature sensor ([`quatarm::temperature::TemperatureSensor`]) and nothing about buses.
//! This crate implements those traits for real parts, so that a user of the chain alone (the
//! host tool, the QEMU boards, another hub) does not pull in embedded-hal:
//!
//! - [`As5047p`]: AMS AS5047P, 14-bit magnetic absolute encoder on SPI
//!   ([`embedded_hal::spi::SpiDevice`]); parity, error flags, magnetic field and CORDIC
//!   overflow checked on every reading.
//! - [`Tmp117`]: TI TMP117, ±0.1 °C temperature sensor on I2C ([`embedded_hal::i2c::I2c`]);
//!   device identity, conversion state, staleness and plausibility checked.
//!
//! Every failure is an error value, never a made-up count or temperature: the hub turns it
//! into a fault bit of the report and withholds the point (`docs/protocol.md`).
//!
//! # Example
//!
//! Reading a TMP117 through any `I2c` implementation (here the bus is a mock that plays the
//! part's answers: its device ID, the configuration write, then one conversion of 20.5 °C):
//!
//! ```
//! use embedded_hal_mock::eh1::i2c::{Mock, Transaction};
//! use quatarm::temperature::TemperatureSensor;
//! use quatarm_drivers::{Address, Tmp117};
//!
//! let bus = [
//!     Transaction::write_read(0x48, vec![0x0F], vec![0x01, 0x17]), // Device_ID: a TMP117
//!     Transaction::write(0x48, vec![0x01, 0x02, 0x20]), // continuous, 8 averages, 1 s
//!     Transaction::write_read(0x48, vec![0x01], vec![0x22, 0x20]), // Data_Ready set
//!     Transaction::write_read(0x48, vec![0x00], vec![0x0A, 0x40]), // 20.5 °C
//! ];
//! let mut i2c = Mock::new(&bus);
//! let mut sensor = Tmp117::new(i2c.clone(), Address::Gnd, 8);
//! assert_eq!(sensor.read_mc(), Ok(20_500));
//! i2c.done();
//! ```
#![cfg_attr(not(test), no_std)]
#![deny(missing_docs)]

pub mod as5047p;
pub mod tmp117;

pub use as5047p::As5047p;
pub use tmp117::{Address, Tmp117};
