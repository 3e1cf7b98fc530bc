//! quatarm hub on a Raspberry Pi Pico (RP2040, Cortex-M0+, no FPU): the fixed-point chain.
//!
//! - Stream: UART0 (GP0 TX, GP1 RX) at 921,600 baud, to a USB–serial adapter or a second
//!   Pico running a debug probe firmware with its UART bridge.
//! - Encoders: six AMS AS5047P on SPI0 (GP2 SCK, GP3 MOSI, GP4 MISO, mode 1, 8 MHz), chip
//!   selects GP5 to GP10 for joints 1 to 6, sampled at 1 kHz. Their 14-bit counts need a
//!   calibration table built with `encoder_counts = 16384` (checked at boot).
//! - Replay: frames from the host take over from the encoders until the host's `End`.
//! - Log: defmt over RTT, read by a debug probe, apart from the stream.
//! - Temperature: a TI TMP117 on the arm's structure, on I2C0 (GP16 SDA, GP17 SCL, 400 kHz,
//!   address 0x48: ADD0 to GND), polled every 250 ms. GP4/GP5, I2C0's first pin pair, are
//!   taken by SPI0 MISO and joint 1's chip select. The RP2040's internal pull-ups are
//!   enabled but weak for 400 kHz: the sensor's breakout board provides proper ones.
//!   Without a valid reading (sensor missing, wrong part, bus error, no conversion yet in
//!   the first second after boot) the reports carry `TEMP_SENSOR_FAULT` and no coordinates.
//! - Calibration: the live one of the two 16 KiB table slots (the last 40 KiB of flash: slots
//!   and state record copies, `docs/update.md`), signed under the arm maker's key the build
//!   was given (`QUATARM_MAKER_KEY`; its successor `QUATARM_NEXT_MAKER_KEY`:
//!   `board_common::maker_keys`); updates over the stream (`armcal table send`), after which
//!   the hub boots again on the new table.
//! - Profile (features `u95`, `wobble` of `board-common`): the table's axis wobble and
//!   parameter block are taken, and every report carries its point's U95 — from the
//!   fixed-point matrix chain's frames, its columns in software f32 (no FPU), the parameter
//!   part's product in integers (`quatarm/fixed-u95`: 3.1× fewer instructions than in
//!   software f32; `docs/results/boards.md`, "Board profiles").
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
use fugit::RateExtU32;
use quatarm_drivers::{Address, As5047p, Tmp117};
use rp2040_hal::{
    clocks::init_clocks_and_plls,
    gpio::{FunctionI2c, FunctionSpi, FunctionUart, Pin, Pins, PullUp},
    i2c::I2C,
    pac,
    sio::Sio,
    spi::Spi,
    uart::{DataBits, StopBits, UartConfig, UartDevice, UartPeripheral, ValidUartPinout},
    watchdog::Watchdog,
    Clock,
};

/// The second-stage boot loader for the Pico's W25Q080 flash.
#[link_section = ".boot2"]
#[used]
#[no_mangle]
pub static BOOT2_FIRMWARE: [u8; 256] = rp2040_boot2::BOOT_LOADER_W25Q080;

/// The Pico's crystal.
const XOSC_HZ: u32 = 12_000_000;
/// Core clock after `init_clocks_and_plls`.
const CORE_HZ: u32 = 125_000_000;
/// Encoder sampling period.
const PERIOD_US: u64 = 1_000;

struct Uart0<D: UartDevice, P: ValidUartPinout<D>>(UartPeripheral<rp2040_hal::uart::Enabled, D, P>);

impl<D: UartDevice, P: ValidUartPinout<D>> PollLink for Uart0<D, P> {
    fn try_read(&mut self) -> Option<u8> {
        // A lost byte makes its frame fail the CRC: reported as damaged, nothing to do here.
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
    let (Some(mut dp), Some(cp)) = (pac::Peripherals::take(), cortex_m::Peripherals::take()) else {
        panic!()
    };
    let mut watchdog = Watchdog::new(dp.WATCHDOG);
    let Ok(clocks) = init_clocks_and_plls(
        XOSC_HZ,
        dp.XOSC,
        dp.CLOCKS,
        dp.PLL_SYS,
        dp.PLL_USB,
        &mut dp.RESETS,
        &mut watchdog,
    ) else {
        panic!()
    };
    clock::start(cp.SYST);
    let sio = Sio::new(dp.SIO);
    let pins = Pins::new(dp.IO_BANK0, dp.PADS_BANK0, sio.gpio_bank0, &mut dp.RESETS);

    let uart_pins = (
        pins.gpio0.into_function::<FunctionUart>(),
        pins.gpio1.into_function::<FunctionUart>(),
    );
    let Ok(uart) = UartPeripheral::new(dp.UART0, uart_pins, &mut dp.RESETS).enable(
        UartConfig::new(921_600.Hz(), DataBits::Eight, None, StopBits::One),
        clocks.peripheral_clock.freq(),
    ) else {
        panic!()
    };
    let mut link = Uart0(uart);

    let spi_pins = (
        pins.gpio3.into_function::<FunctionSpi>(),
        pins.gpio4.into_function::<FunctionSpi>(),
        pins.gpio2.into_function::<FunctionSpi>(),
    );
    let bus = RefCell::new(Spi::<_, _, _, 8>::new(dp.SPI0, spi_pins).init(
        &mut dp.RESETS,
        clocks.peripheral_clock.freq(),
        8.MHz(),
        embedded_hal::spi::MODE_1,
    ));
    let cs = [
        pins.gpio5.into_push_pull_output().into_dyn_pin(),
        pins.gpio6.into_push_pull_output().into_dyn_pin(),
        pins.gpio7.into_push_pull_output().into_dyn_pin(),
        pins.gpio8.into_push_pull_output().into_dyn_pin(),
        pins.gpio9.into_push_pull_output().into_dyn_pin(),
        pins.gpio10.into_push_pull_output().into_dyn_pin(),
    ];
    let mut encoders = cs.map(|pin| {
        // Setting a GPIO output cannot fail on this chip (the error type is Infallible).
        let dev = RefCellDevice::new_no_delay(&bus, pin).unwrap_or_else(|e| match e {});
        As5047p::new(dev)
    });

    let sda: Pin<_, FunctionI2c, PullUp> = pins.gpio16.reconfigure();
    let scl: Pin<_, FunctionI2c, PullUp> = pins.gpio17.reconfigure();
    let i2c = I2C::i2c0(
        dp.I2C0,
        sda,
        scl,
        400.kHz(),
        &mut dp.RESETS,
        clocks.system_clock.freq(),
    );
    let mut thermometer = Tmp117::new(i2c, Address::Gnd, live::TEMP_STALE_POLLS);
    if thermometer.init().is_err() {
        defmt::warn!("TMP117 not found on I2C0 at 0x48: no coordinates until it answers");
    }

    // SAFETY: the calibration sectors of memory.x, outside the image; only the updater
    // writes them; core 1 is never started and no DMA reads flash.
    let cal_flash = unsafe { slots::map().window(flash::Qspi::new()) };

    live::run::<quatarm::Fixed, CORE_HZ, _>(
        &mut link,
        &mut encoders,
        &mut thermometer,
        PERIOD_US,
        cal_flash,
        maker_keys!(),
    )
}
