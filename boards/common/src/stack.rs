//! Measuring the stack by painting: fill the free RAM between the statics and the stack
//! with a pattern at boot, and later find the deepest word the stack overwrote. The
//! measurement covers everything after [`paint`]; what ran before it (the reset handler) is
//! a few words.

use core::ptr::{addr_of, read_volatile, write_volatile};

const PATTERN: u32 = 0xA5C3_5A3C;
/// Words just below the live stack pointer left alone while painting (our own frame).
const GUARD_WORDS: usize = 16;

extern "C" {
    // cortex-m-rt's link.x: the first free address after the statics, and the stack top.
    static __sheap: u32;
    static _stack_start: u32;
}

fn bounds() -> (usize, usize) {
    (addr_of!(__sheap) as usize, addr_of!(_stack_start) as usize)
}

/// Paints the free RAM below the current stack pointer. Call first thing in `main`.
pub fn paint() {
    let (low, _) = bounds();
    let sp = cortex_m::register::msp::read() as usize;
    let mut p = low;
    while p + 4 * GUARD_WORDS < sp {
        // SAFETY: between the statics and the live stack nothing is in use yet.
        unsafe { write_volatile(p as *mut u32, PATTERN) };
        p += 4;
    }
}

/// The deepest the stack has been since [`paint`], in bytes below its top.
pub fn peak() -> usize {
    let (low, top) = bounds();
    let mut p = low;
    // SAFETY: reads of RAM between the statics and the stack top.
    while p < top && unsafe { read_volatile(p as *const u32) } == PATTERN {
        p += 4;
    }
    top - p
}

/// Bytes of RAM the statics take (from the start of RAM to the first free address).
pub fn statics(ram_start: usize) -> usize {
    bounds().0 - ram_start
}
