//! Where a hub's own joint readings come from: absolute encoders.
//!
//! [`AbsoluteEncoder`] is what the hub needs of one joint's encoder: its resolution and one
//! reading, or an error. [`read_joints`] reads a whole arm and turns every error into a fault
//! bit of that joint, which the stream carries (`Status::with_encoder_faults`): a hub never
//! guesses a count. The driver for a real part (AMS AS5047P on SPI) is
//! `quatarm_drivers::As5047p`, in a crate of its own so that a user of the chain alone does not
//! pull in embedded-hal. Recorded readings replayed over the UART (the QEMU boards,
//! hardware-in-the-loop runs) arrive through [`crate::stream::Replay`] instead, the decoder of
//! the stream's receive side.

/// An absolute rotary encoder: every reading is the shaft angle in counts, no homing needed.
pub trait AbsoluteEncoder {
    /// Why a reading failed.
    type Error;

    /// Counts per revolution (the table's `encoder_counts` of the joint must equal it).
    fn counts_per_rev(&self) -> u32;

    /// One reading in `0..counts_per_rev()`, checked (parity, CRC, error flags) by the driver.
    fn read_count(&mut self) -> Result<u32, Self::Error>;
}

/// Reads every joint, joint 1 first, into `counts`; returns the faults, bit j for joint j + 1.
/// The count of a faulty joint is left as it was (and must not be used: the fault withholds
/// the point). Joints beyond the eighth, or beyond the length of `counts`, are not read.
pub fn read_joints<E: AbsoluteEncoder>(encoders: &mut [E], counts: &mut [u32]) -> u8 {
    let mut faults = 0u8;
    for (j, (enc, count)) in encoders
        .iter_mut()
        .zip(counts.iter_mut())
        .take(8)
        .enumerate()
    {
        match enc.read_count() {
            Ok(c) if c < enc.counts_per_rev() => *count = c,
            _ => faults |= 1 << j,
        }
    }
    faults
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Fake(Result<u32, ()>);
    impl AbsoluteEncoder for Fake {
        type Error = ();
        fn counts_per_rev(&self) -> u32 {
            1000
        }
        fn read_count(&mut self) -> Result<u32, ()> {
            self.0
        }
    }

    #[test]
    fn each_failing_joint_sets_its_own_bit_and_keeps_its_old_count() {
        let mut encs = [Fake(Ok(1)), Fake(Err(())), Fake(Ok(3)), Fake(Ok(1000))];
        let mut counts = [7u32; 4];
        let faults = read_joints(&mut encs, &mut counts);
        assert_eq!(faults, 0b1010, "joint 2 failed, joint 4 read out of range");
        assert_eq!(counts, [1, 7, 3, 7]);
    }
}
