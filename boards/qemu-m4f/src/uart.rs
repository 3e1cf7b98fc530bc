//! ARM CMSDK APB UART, as QEMU's mps2 machines model it (UART0 at 0x4000_4000).

use core::ptr::{read_volatile, write_volatile};

use board_common::Link;

const DATA: usize = 0x00;
const STATE: usize = 0x04;
const CTRL: usize = 0x08;
const BAUDDIV: usize = 0x10;
const STATE_TX_FULL: u32 = 1 << 0;
const STATE_RX_FULL: u32 = 1 << 1;
const CTRL_TX_EN: u32 = 1 << 0;
const CTRL_RX_EN: u32 = 1 << 1;

/// One CMSDK UART, polled.
pub struct Uart {
    base: usize,
}

impl Uart {
    /// UART0 of the mps2 boards.
    pub const UART0: usize = 0x4000_4000;

    /// Enables transmit and receive. `bauddiv` = clock / baud (QEMU wants at least 16).
    ///
    /// # Safety
    /// `base` must be the address of a CMSDK UART that nothing else uses.
    pub unsafe fn new(base: usize, bauddiv: u32) -> Uart {
        write_volatile((base + BAUDDIV) as *mut u32, bauddiv);
        write_volatile((base + CTRL) as *mut u32, CTRL_TX_EN | CTRL_RX_EN);
        Uart { base }
    }

    fn reg(&self, off: usize) -> *mut u32 {
        (self.base + off) as *mut u32
    }
}

impl Link for Uart {
    /// Sends every byte, waiting while the transmit buffer is full.
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            // SAFETY: registers of the UART this value owns (see `new`).
            unsafe {
                while read_volatile(self.reg(STATE)) & STATE_TX_FULL != 0 {}
                write_volatile(self.reg(DATA), u32::from(b));
            }
        }
    }

    /// Waits for one received byte.
    fn read(&mut self) -> u8 {
        // SAFETY: registers of the UART this value owns (see `new`).
        unsafe {
            while read_volatile(self.reg(STATE)) & STATE_RX_FULL == 0 {}
            read_volatile(self.reg(DATA)) as u8
        }
    }
}
