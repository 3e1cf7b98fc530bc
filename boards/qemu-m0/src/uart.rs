//! nRF51 UART (not UARTE), polled, as QEMU's microbit machine models it (0x4000_2000).
//! Events are cleared before the access that may set them again (nRF51 reference manual,
//! UART chapter): RXDRDY before reading RXD, TXDRDY before writing TXD.

use core::ptr::{read_volatile, write_volatile};

use board_common::Link;

const BASE: usize = 0x4000_2000;
const TASKS_STARTRX: usize = 0x000;
const TASKS_STARTTX: usize = 0x008;
const EVENTS_RXDRDY: usize = 0x108;
const EVENTS_TXDRDY: usize = 0x11C;
const ENABLE: usize = 0x500;
const RXD: usize = 0x518;
const TXD: usize = 0x51C;
const BAUDRATE: usize = 0x524;
const BAUD_115200: u32 = 0x01D7_E000;

fn reg(off: usize) -> *mut u32 {
    (BASE + off) as *mut u32
}

/// The nRF51's UART0.
pub struct Uart(());

impl Uart {
    /// Enables the UART and starts both directions.
    ///
    /// # Safety
    /// Only one `Uart` may exist: it owns the peripheral.
    pub unsafe fn take() -> Uart {
        write_volatile(reg(BAUDRATE), BAUD_115200);
        write_volatile(reg(ENABLE), 4);
        write_volatile(reg(TASKS_STARTTX), 1);
        write_volatile(reg(TASKS_STARTRX), 1);
        Uart(())
    }
}

impl Link for Uart {
    /// Sends every byte, one at a time.
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            // SAFETY: the registers of the UART this value owns.
            unsafe {
                write_volatile(reg(EVENTS_TXDRDY), 0);
                write_volatile(reg(TXD), u32::from(b));
                while read_volatile(reg(EVENTS_TXDRDY)) == 0 {}
            }
        }
    }

    /// Waits for one received byte.
    fn read(&mut self) -> u8 {
        // SAFETY: the registers of the UART this value owns.
        unsafe {
            while read_volatile(reg(EVENTS_RXDRDY)) == 0 {}
            write_volatile(reg(EVENTS_RXDRDY), 0);
            read_volatile(reg(RXD)) as u8
        }
    }
}
