//! The status word of every report: why a reading does or does not carry coordinates.
//!
//! ```text
//!  bit  15 | 14 13 12 11 10  9  8 | 7  6  5  4 | 3  2  1  0
//!       S  | encoder fault, joint  | table state| C  T  I  V
//!          |  7  6  5  4  3  2  1  | (code)     |
//!  V  TABLE_VALID        the calibration table passed every check at boot
//!  I  INPUT_ERROR        the replay frame for this slot failed COBS/CRC/decoding: dropped
//!  T  OVER_TEMPERATURE   temperature outside the rated range: no coordinates
//!  C  CHAIN_ERROR        the chain refused the reading (count out of range, wrong joint count)
//!  bits 4..7             TableState code (0 when the table is valid)
//!  bits 8..14            ENCODER_FAULT of joint 1..7 (parity, error flag, magnet, timeout)
//!  S  TEMP_SENSOR_FAULT  the arm's temperature sensor gave no valid reading: no coordinates
//! ```
//!
//! A report carries coordinates exactly when [`Status::is_measurement`] holds: a valid table
//! and none of the fault bits. The firmware never sends coordinates alongside a fault.

use serde::{Deserialize, Serialize};

/// The status flags of one report (see the module docs for the layout).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Status(pub u16);

/// What the boot check found in the calibration-table flash region.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum TableState {
    /// The table parsed and its CRC matched.
    Valid = 0,
    /// No table at all: the region holds no magic number (erased or never written).
    Missing = 1,
    /// The magic is there but the CRC does not match: a damaged or half-written table.
    Corrupt = 2,
    /// A table of a format version this firmware does not read.
    WrongVersion = 3,
    /// A table for an arm with a joint count this firmware is not built for.
    WrongJointCount = 4,
    /// Any other inconsistency (a length, a count, a flag combination that cannot be).
    Malformed = 5,
    /// A table whose counts per revolution differ from the resolution of the hub's encoders.
    WrongResolution = 6,
    /// A valid table without a signature, on a hub that holds its maker's key.
    Unsigned = 7,
    /// A valid table whose signature does not verify under the hub's key (another key, or
    /// bytes changed after signing).
    BadSignature = 8,
}

impl TableState {
    /// The 4-bit code as it travels in bits 4..7 of the status word.
    pub const fn code(self) -> u16 {
        self as u16
    }

    /// The state of a code read back from a status word; `None` for codes not defined here.
    pub const fn from_code(code: u16) -> Option<TableState> {
        Some(match code {
            0 => TableState::Valid,
            1 => TableState::Missing,
            2 => TableState::Corrupt,
            3 => TableState::WrongVersion,
            4 => TableState::WrongJointCount,
            5 => TableState::Malformed,
            6 => TableState::WrongResolution,
            7 => TableState::Unsigned,
            8 => TableState::BadSignature,
            _ => return None,
        })
    }

    /// A short lower-case name for logs and CSV.
    pub const fn name(self) -> &'static str {
        match self {
            TableState::Valid => "valid",
            TableState::Missing => "missing",
            TableState::Corrupt => "corrupt",
            TableState::WrongVersion => "wrong-version",
            TableState::WrongJointCount => "wrong-joint-count",
            TableState::Malformed => "malformed",
            TableState::WrongResolution => "wrong-resolution",
            TableState::Unsigned => "unsigned",
            TableState::BadSignature => "bad-signature",
        }
    }
}

impl From<&crate::table::TableError> for TableState {
    /// How the stream reports each reason the table parser gives for refusing a table.
    fn from(e: &crate::table::TableError) -> TableState {
        use crate::table::TableError as E;
        match e {
            E::Blank | E::BadMagic => TableState::Missing,
            E::Crc { .. } | E::Truncated { .. } | E::BadLength(_) => TableState::Corrupt,
            E::UnsupportedVersion(_) => TableState::WrongVersion,
            E::BadJointCount(_) | E::WrongJointCount { .. } => TableState::WrongJointCount,
            _ => TableState::Malformed,
        }
    }
}

impl Status {
    /// The calibration table passed every check at boot.
    pub const TABLE_VALID: u16 = 1 << 0;
    /// The incoming replay frame for this slot was damaged and dropped.
    pub const INPUT_ERROR: u16 = 1 << 1;
    /// The temperature is outside the rated range of the thermal model.
    pub const OVER_TEMPERATURE: u16 = 1 << 2;
    /// The chain refused the reading.
    pub const CHAIN_ERROR: u16 = 1 << 3;
    /// The hub's temperature sensor gave no valid reading (bus error, wrong part, no or a
    /// stale conversion): without the arm's temperature the thermal terms cannot be applied,
    /// and a point corrected for a temperature the hub made up would look measured.
    pub const TEMP_SENSOR_FAULT: u16 = 1 << 15;
    const TABLE_SHIFT: u16 = 4;
    const TABLE_MASK: u16 = 0xF << Self::TABLE_SHIFT;
    const FAULT_SHIFT: u16 = 8;
    const FAULT_MASK: u16 = 0x7F << Self::FAULT_SHIFT;

    /// The status of a hub whose boot check of the table gave `table`.
    pub const fn for_table(table: TableState) -> Status {
        match table {
            TableState::Valid => Status(Self::TABLE_VALID),
            other => Status(other.code() << Self::TABLE_SHIFT),
        }
    }

    /// The table state this status reports (`Malformed` for an undefined code).
    pub const fn table(self) -> TableState {
        match TableState::from_code((self.0 & Self::TABLE_MASK) >> Self::TABLE_SHIFT) {
            Some(state) => state,
            None => TableState::Malformed,
        }
    }

    /// True if the table was valid at boot.
    pub const fn table_valid(self) -> bool {
        self.0 & Self::TABLE_VALID != 0
    }

    /// This status with `flag` (one of the associated bit constants) set.
    pub const fn with(self, flag: u16) -> Status {
        Status(self.0 | flag)
    }

    /// True if `flag` is set.
    pub const fn has(self, flag: u16) -> bool {
        self.0 & flag == flag
    }

    /// This status with the encoder faults of `joints` set: bit j of `joints` is joint j + 1.
    /// A fault of an eighth joint (bit 7) cannot be represented: no arm has one, so the
    /// reading is malformed and is marked `INPUT_ERROR` rather than silently masked.
    pub const fn with_encoder_faults(self, joints: u8) -> Status {
        let s = self.0 | (((joints & 0x7F) as u16) << Self::FAULT_SHIFT);
        if joints & 0x80 != 0 {
            Status(s | Self::INPUT_ERROR)
        } else {
            Status(s)
        }
    }

    /// The encoder faults, bit j for joint j + 1.
    pub const fn encoder_faults(self) -> u8 {
        ((self.0 & Self::FAULT_MASK) >> Self::FAULT_SHIFT) as u8
    }

    /// True if the word can be what a hub sends: bit 0 (`TABLE_VALID`) set exactly when the
    /// table state is 0 (valid), and a table state that is defined (0 to 8; 9 to 15 are
    /// reserved). A hub builds its status from [`Status::for_table`], which keeps both; a word
    /// that breaks them (F5 of `../shared/repro/round2`: bit 0 beside "bad signature") says
    /// two things at once, and a host cannot tell which holds.
    pub const fn is_coherent(self) -> bool {
        let code = (self.0 & Self::TABLE_MASK) >> Self::TABLE_SHIFT;
        TableState::from_code(code).is_some() && self.table_valid() == (code == 0)
    }

    /// True if a report with this status may carry coordinates: a valid table (bit 0 and table
    /// state 0) and no fault.
    pub const fn is_measurement(self) -> bool {
        self.table_valid()
            && self.0 & Self::TABLE_MASK == 0
            && self.0
                & (Self::INPUT_ERROR
                    | Self::OVER_TEMPERATURE
                    | Self::CHAIN_ERROR
                    | Self::TEMP_SENSOR_FAULT)
                == 0
            && self.encoder_faults() == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_states_round_trip_through_the_word() {
        for code in 0..16 {
            if let Some(state) = TableState::from_code(code) {
                let s = Status::for_table(state);
                assert_eq!(s.table(), state);
                assert_eq!(s.table_valid(), state == TableState::Valid);
                assert_eq!(s.is_measurement(), state == TableState::Valid);
            }
        }
    }

    /// F5 of `../shared/repro/round2`: bit 0 beside a table state other than 0 (0x0081 bad
    /// signature, 0x0011 missing) is no measurement and no word a hub sends; nor is a
    /// reserved state (9 to 15), nor state 0 without bit 0.
    #[test]
    fn bit_0_means_table_state_0_and_nothing_else() {
        for code in 0..16u16 {
            let defined = TableState::from_code(code).is_some();
            let with_bit = Status(code << 4 | Status::TABLE_VALID);
            let without = Status(code << 4);
            assert_eq!(with_bit.is_coherent(), code == 0, "{with_bit:?}");
            assert_eq!(without.is_coherent(), defined && code != 0, "{without:?}");
            assert_eq!(with_bit.is_measurement(), code == 0, "{with_bit:?}");
            assert!(!without.is_measurement());
        }
        for state in (0..9).filter_map(TableState::from_code) {
            assert!(Status::for_table(state).is_coherent(), "{state:?}");
        }
    }

    #[test]
    fn every_fault_withholds_coordinates() {
        let ok = Status::for_table(TableState::Valid);
        assert!(ok.is_measurement());
        for flag in [
            Status::INPUT_ERROR,
            Status::OVER_TEMPERATURE,
            Status::CHAIN_ERROR,
            Status::TEMP_SENSOR_FAULT,
        ] {
            assert!(!ok.with(flag).is_measurement());
            assert!(ok.with(flag).has(flag));
        }
        for joint in 0..7 {
            let s = ok.with_encoder_faults(1 << joint);
            assert!(!s.is_measurement());
            assert_eq!(s.encoder_faults(), 1 << joint);
            assert!(s.table_valid(), "fault bits must not touch the table bits");
            assert!(!s.has(Status::TEMP_SENSOR_FAULT), "nor the sensor bit");
        }
        assert_eq!(ok.with_encoder_faults(0x80).encoder_faults(), 0);
    }
    #[test]
    fn a_fault_of_an_eighth_joint_is_an_input_error_not_dropped() {
        let s = Status(Status::TABLE_VALID).with_encoder_faults(0x80);
        assert!(s.has(Status::INPUT_ERROR));
        assert!(!s.is_measurement());
        assert!(!Status(Status::TABLE_VALID)
            .with_encoder_faults(0x01)
            .has(Status::INPUT_ERROR));
    }
}
