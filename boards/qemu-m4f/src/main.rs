//! quatarm hub on QEMU `mps2-an386` (Cortex-M4F): the f32 chain, fed by a recording over
//! CMSDK UART0, streaming reports back on the same UART.
//!
//! Boot: the live one of the two table slots, validated, announced in `Hello`. Then replay,
//! and carry out calibration updates (`docs/update.md`), until the host sends `End`, and exit QEMU with success (any panic exits with failure).
#![no_std]
#![no_main]

mod uart;

use board_common::calibration::JOINTS;
use board_common::flash::ram_nor::Ram;
use board_common::flash::slots;
use board_common::maker_key::TEST_KEYS;
use board_common::qemu;
use cortex_m_rt::entry;
use quatarm::update::Accept;

/// mps2-an386 core clock: 25 MHz.
const CORE_HZ: u32 = 25_000_000;
/// 115200 baud (QEMU does not pace the UART, but the divider must be valid).
const BAUDDIV: u32 = CORE_HZ / 115_200;

/// Start of RAM in `memory.x`.
const RAM_START: usize = 0x2000_0000;

#[entry]
fn main() -> ! {
    qemu::hub_main::<quatarm::F32, CORE_HZ, _, _>(
        RAM_START,
        // A table must be signed under the (test) maker key of the hub's generation to boot
        // or to be committed; one signed by the next test key rotates the hub to it.
        Accept::joints(JOINTS).signed_by_keys(TEST_KEYS),
        || {
            // SAFETY: UART0 is used by nothing else.
            unsafe { uart::Uart::new(uart::Uart::UART0, BAUDDIV) }
        },
        // SAFETY: the calibration regions of memory.x, RAM outside the image that only
        // the updater touches. 4 KiB: the state record's copies, the smallest regions.
        unsafe { slots::map().window(Ram::<4096>) },
    )
}
