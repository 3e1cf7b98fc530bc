//! The arm's temperature: what the chain's thermal expansion terms are evaluated at.
//!
//! [`TemperatureSensor`] is what the hub needs of the sensor on the arm: the latest reading in
//! milli-degrees Celsius, or an error. A hub never makes a temperature up: when the sensor
//! fails, the report carries `Status::TEMP_SENSOR_FAULT` and no coordinates (see
//! `docs/protocol.md`), exactly as an encoder fault withholds the point. The driver for a real
//! part (TI TMP117, ±0.1 °C, on I2C) is `quatarm_drivers::Tmp117`, in a crate of its own so
//! that a user of the chain alone does not pull in embedded-hal.

/// A temperature sensor on the arm's structure.
pub trait TemperatureSensor {
    /// Why a reading failed.
    type Error;

    /// The latest temperature in milli-degrees Celsius, checked by the driver (device
    /// identity, conversion state, plausibility); an error rather than a stale or made-up
    /// value.
    fn read_mc(&mut self) -> Result<i32, Self::Error>;
}
