//! quatarm hub on a NUCLEO-F446RE (STM32F446RE, Cortex-M4F): the f32 chain.
//!
//! - Stream: USART2 (PA2 TX, PA3 RX), which the on-board ST-LINK presents as a virtual COM
//!   port, at 921,600 baud (a report is at most 66 bytes: ~1,400 reports/s).
//! - Encoders: six AMS AS5047P on SPI1 (PA5 SCK, PA6 MISO, PA7 MOSI, mode 1, 8 MHz), chip
//!   selects PB0, PB1, PB2, PB10, PB12, PB13 for joints 1 to 6, sampled at 1 kHz. Their
//!   14-bit counts need a calibration table built with `encoder_counts = 16384`.
//! - Replay: frames from the host take over from the encoders until the host's `End`
//!   (hardware-in-the-loop runs with a recording).
//! - Log: defmt over RTT, read by a debug probe, apart from the stream.
//! - Temperature: a TI TMP117 on the arm's structure, on I2C1 (PB8 SCL = Arduino D15, PB9 SDA
//!   = D14, 400 kHz, address 0x48: ADD0 to GND), polled every 250 ms. The NUCLEO has no
//!   pull-ups on D14/D15: the sensor's breakout board provides them (or fit 2.2 kΩ to 3.3 V).
//!   Without a valid reading (sensor missing, wrong part, bus error, no conversion yet in
//!   the first second after boot) the reports carry `TEMP_SENSOR_FAULT` and no coordinates.
//! - Calibration: the live one of the two table slots (sectors 7 and 6, the state record in
//!   their trailers: `docs/update.md`), signed under the arm maker's key the build was given
//!   (`QUATARM_MAKER_KEY`; its successor `QUATARM_NEXT_MAKER_KEY`: `board_common::maker_keys`);
//!   updates over the stream (`armcal table send`), after which the hub boots again on the
//!   new table.
#![no_std]
#![no_main]

mod flash;

use core::cell::RefCell;

use board_common::flash::slots;
use board_common::live::{self, PollLink};
use board_common::{clock, maker_keys};
use cortex_m_rt::entry;
use embedded_hal_bus::spi::RefCellDevice;
use embedded_hal_nb::serial::{Read, Write};
use quatarm_drivers::{Address, As5047p, Tmp117};
use stm32f4xx_hal::{
    i2c::I2cExt,
    pac,
    prelude::*,
    rcc::Config,
    serial::{self, Serial},
    spi::{Mode, Phase, Polarity},
};

/// Core clock.
const CORE_HZ: u32 = 168_000_000;
/// Encoder sampling period.
const PERIOD_US: u64 = 1_000;

struct Usart2(Serial<pac::USART2, u8>);

impl PollLink for Usart2 {
    fn try_read(&mut self) -> Option<u8> {
        // An overrun or framing error loses bytes: the frame they belonged to then fails its
        // CRC and is reported as damaged, so the error itself needs no handling here.
        self.0.read().ok()
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            let _ = nb::block!(self.0.write(b));
        }
    }
}

#[entry]
fn main() -> ! {
    let (Some(dp), Some(cp)) = (pac::Peripherals::take(), cortex_m::Peripherals::take()) else {
        panic!()
    };
    let mut rcc = dp.RCC.freeze(Config::hsi().sysclk(CORE_HZ.Hz()));
    clock::start(cp.SYST);

    let gpioa = dp.GPIOA.split(&mut rcc);
    let gpiob = dp.GPIOB.split(&mut rcc);
    let Ok(serial) = Serial::new(
        dp.USART2,
        (gpioa.pa2, gpioa.pa3),
        serial::Config::default().baudrate(921_600.bps()),
        &mut rcc,
    ) else {
        panic!()
    };
    let mut link = Usart2(serial);

    let mode = Mode {
        polarity: Polarity::IdleLow,
        phase: Phase::CaptureOnSecondTransition,
    };
    let bus = RefCell::new(dp.SPI1.spi(
        (Some(gpioa.pa5), Some(gpioa.pa6), Some(gpioa.pa7)),
        mode,
        8.MHz(),
        &mut rcc,
    ));
    let cs = [
        gpiob.pb0.into_push_pull_output().erase(),
        gpiob.pb1.into_push_pull_output().erase(),
        gpiob.pb2.into_push_pull_output().erase(),
        gpiob.pb10.into_push_pull_output().erase(),
        gpiob.pb12.into_push_pull_output().erase(),
        gpiob.pb13.into_push_pull_output().erase(),
    ];
    let mut encoders = cs.map(|pin| {
        // Setting a GPIO output cannot fail on this chip (the error type is Infallible).
        let dev = RefCellDevice::new_no_delay(&bus, pin).unwrap_or_else(|e| match e {});
        As5047p::new(dev)
    });

    let i2c = dp.I2C1.i2c((gpiob.pb8, gpiob.pb9), 400.kHz(), &mut rcc);
    let mut thermometer = Tmp117::new(i2c, Address::Gnd, live::TEMP_STALE_POLLS);
    if thermometer.init().is_err() {
        defmt::warn!("TMP117 not found on I2C1 at 0x48: no coordinates until it answers");
    }

    // SAFETY: sectors 6 and 7, the calibration regions of memory.x, outside the image; only
    // the updater writes them.
    let cal_flash = unsafe { slots::trailer_map().window(flash::Sectors::new(dp.FLASH)) };

    live::run::<quatarm::F32, CORE_HZ, _>(
        &mut link,
        &mut encoders,
        &mut thermometer,
        PERIOD_US,
        cal_flash,
        maker_keys!(),
    )
}
