//! The calibration table's own flash region. `memory.x` of each board defines it and exports
//! `_cal_table_start` and `_cal_table_end`; the table is written there separately from the
//! firmware (QEMU: `-device loader,file=CAL.bin,addr=…`), so a new calibration needs no
//! firmware build. The bytes are whatever is there: erased flash, zeros, or a table; the
//! table parser decides which.

extern "C" {
    static _cal_table_start: u8;
    static _cal_table_end: u8;
}

/// The whole region, as bytes.
pub fn bytes() -> &'static [u8] {
    // SAFETY: the linker script defines both symbols around a region of flash that nothing
    // writes while the firmware runs; its bytes are plain data whatever they hold.
    unsafe {
        let start = core::ptr::addr_of!(_cal_table_start);
        let end = core::ptr::addr_of!(_cal_table_end);
        let len = (end as usize).saturating_sub(start as usize);
        core::slice::from_raw_parts(start, len)
    }
}
