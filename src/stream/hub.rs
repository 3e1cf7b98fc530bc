//! What every board's main loop does with a reading, in one place that host tests can reach.
//!
//! A board supplies the hardware (UART, clock, encoders) and a closure that runs its chain; the
//! [`Hub`] decides, from the boot check of the table and the faults of this reading, whether the
//! chain may run at all, numbers the reports and renders them in the current [`Mode`]. Keeping
//! this out of the boards means the rule "no coordinates beside a fault" is written, and tested,
//! once.

use super::{
    encode, write_csv_header, write_csv_line, Coordinates, FrameError, Hello, LiveTable, Mode,
    NumberFormat, Reading, Report, Status, TableState, ToHost, MAX_CSV_LINE, MAX_FRAME,
    PROTOCOL_VERSION,
};

/// The rated temperature range of the thermal model, milli-degrees Celsius. Outside it the
/// hub reports `OVER_TEMPERATURE` and no coordinates: the expansion model is only
/// calibrated between these limits.
pub const RATED_TEMP_MC: core::ops::RangeInclusive<i32> = 0..=40_000;

/// Longest output of [`Hub::render`]: a frame behind its lone delimiter, or a CSV line.
pub const MAX_OUTPUT: usize = if MAX_FRAME + 1 > MAX_CSV_LINE {
    MAX_FRAME + 1
} else {
    MAX_CSV_LINE
};

/// The state a hub keeps between readings.
#[derive(Clone, Debug)]
pub struct Hub {
    seq: u32,
    base: Status,
    joints: u8,
    precision: NumberFormat,
    mode: Mode,
    live: Option<LiveTable>,
}

impl Hub {
    /// A hub whose boot check of the table gave `table`, for a chain of `joints` joints (0 if
    /// there is no valid table).
    pub fn new(table: TableState, joints: u8, precision: NumberFormat) -> Hub {
        Hub {
            seq: 0,
            base: Status::for_table(table),
            joints: if table == TableState::Valid {
                joints
            } else {
                0
            },
            precision,
            mode: Mode::Binary,
            live: None,
        }
    }

    /// The same hub, announcing `live` as the table in use (only with a valid table: a hub
    /// without one names none).
    pub fn with_live(mut self, live: LiveTable) -> Hub {
        if self.base.table_valid() {
            self.live = Some(live);
        }
        self
    }

    /// The boot announcement.
    pub fn hello(&self) -> ToHost {
        ToHost::Hello(Hello {
            protocol: PROTOCOL_VERSION,
            precision: self.precision,
            joints: self.joints,
            status: self.base,
            live: self.live,
        })
    }

    /// The boot check's verdict on the table.
    pub fn table(&self) -> TableState {
        self.base.table()
    }

    /// Joints of the valid table (0 without one).
    pub fn joints(&self) -> u8 {
        self.joints
    }

    /// The chain arithmetic of this hub.
    pub fn precision(&self) -> NumberFormat {
        self.precision
    }

    /// The output mode.
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// Switches the output mode. The `Hello` that follows says the stream restarted, so the
    /// report count restarts with it (`docs/protocol.md`: a `Hello` resets `seq`).
    pub fn set_mode(&mut self, mode: Mode) {
        self.mode = mode;
        self.seq = 0;
    }

    /// The report for one slot: `reading` is what arrived (or why nothing usable did),
    /// `eval` runs the chain on counts and a temperature (m°C). `eval` is called only when
    /// the table is valid, the reading intact, fault-free and in the rated temperature range;
    /// its error gives `CHAIN_ERROR` and no coordinates.
    pub fn report<E>(
        &mut self,
        time_us: u64,
        reading: Result<&Reading, FrameError>,
        eval: impl FnOnce(&[u32], i32) -> Result<Coordinates, E>,
    ) -> Report {
        match reading {
            Err(_) => self.finish(time_us, self.base.with(Status::INPUT_ERROR), None, eval),
            Ok(r) => self.report_sample(
                time_us,
                r.counts.as_slice(),
                r.faults,
                Some(r.temp_mc),
                eval,
            ),
        }
    }

    /// The report for one sample of the hub's own sensors: encoder `counts` with their
    /// `faults` (bit j for joint j + 1) and the arm temperature in m°C, `None` when the
    /// temperature sensor gave no valid reading. Without a temperature the report carries
    /// `TEMP_SENSOR_FAULT` and no coordinates: the hub never evaluates the chain at a
    /// temperature it made up. Otherwise as [`Hub::report`].
    pub fn report_sample<E>(
        &mut self,
        time_us: u64,
        counts: &[u32],
        faults: u8,
        temp_mc: Option<i32>,
        eval: impl FnOnce(&[u32], i32) -> Result<Coordinates, E>,
    ) -> Report {
        let mut status = self.base.with_encoder_faults(faults);
        match temp_mc {
            None => status = status.with(Status::TEMP_SENSOR_FAULT),
            Some(t) if !RATED_TEMP_MC.contains(&t) => {
                status = status.with(Status::OVER_TEMPERATURE)
            }
            Some(_) => {}
        }
        if usize::from(self.joints) != counts.len() && status.table_valid() {
            status = status.with(Status::CHAIN_ERROR);
        }
        let input = temp_mc.map(|t| (counts, t));
        self.finish(time_us, status, input, eval)
    }

    /// Runs the chain if `status` allows a measurement, numbers and returns the report.
    fn finish<E>(
        &mut self,
        time_us: u64,
        mut status: Status,
        input: Option<(&[u32], i32)>,
        eval: impl FnOnce(&[u32], i32) -> Result<Coordinates, E>,
    ) -> Report {
        let mut point = None;
        if let (true, Some((counts, temp_mc))) = (status.is_measurement(), input) {
            match eval(counts, temp_mc) {
                Ok(c) => point = Some(c),
                Err(_) => status = status.with(Status::CHAIN_ERROR),
            }
        }
        let report = Report {
            seq: self.seq,
            time_us,
            status,
            point,
        };
        self.seq = self.seq.wrapping_add(1);
        report
    }

    /// Renders a message in the current mode into `out` (at least [`MAX_OUTPUT`] bytes);
    /// returns the bytes to send. In text mode a report is a CSV line and a `Hello` the CSV
    /// header line. A binary `Hello` goes out behind a lone `0x00`, so that it is a frame of
    /// its own whatever came before it (a CSV line, after a switch back from text mode, has
    /// no delimiter). An update answer is a frame in either mode, behind a lone `0x00` too:
    /// an update is driven by a program, never read at a terminal.
    pub fn render<'a>(&self, msg: &ToHost, out: &'a mut [u8]) -> &'a [u8] {
        let n = match (self.mode, msg) {
            (Mode::Binary, m @ ToHost::Report(_)) => encode(m, out).unwrap_or(0),
            (Mode::Text, ToHost::Report(r)) => write_csv_line(r, out),
            (Mode::Text, ToHost::Hello(_)) => write_csv_header(out),
            (_, m) => match out.split_first_mut() {
                Some((first, rest)) => {
                    *first = 0;
                    encode(m, rest).map_or(0, |n| n + 1)
                }
                None => 0,
            },
        };
        &out[..n]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stream::{Counts, FrameReader, CSV_HEADER};

    fn reading(faults: u8, temp_mc: i32) -> Reading {
        Reading {
            seq: 0,
            counts: Counts::new(&[1, 2, 3, 4, 5, 6]).unwrap(),
            temp_mc,
            faults,
        }
    }

    const POINT: Coordinates = Coordinates {
        xyz_nm: [1, 2, 3],
        dir_e9: [0, 0, 1_000_000_000],
        u95_nm: Some(7),
    };

    fn ok_eval(_: &[u32], _: i32) -> Result<Coordinates, ()> {
        Ok(POINT)
    }

    fn must_not_run(_: &[u32], _: i32) -> Result<Coordinates, ()> {
        panic!("the chain ran on a reading that must not give coordinates")
    }

    #[test]
    fn a_good_reading_gives_the_chain_result() {
        let mut hub = Hub::new(TableState::Valid, 6, NumberFormat::F32);
        let r = hub.report(5, Ok(&reading(0, 20_000)), ok_eval);
        assert_eq!(r.point, Some(POINT));
        assert_eq!(r.status, Status(Status::TABLE_VALID));
        assert_eq!(r.time_us, 5);
        assert_eq!(hub.report(6, Ok(&reading(0, 20_000)), ok_eval).seq, 1);
    }

    #[test]
    fn no_table_no_coordinates_and_the_reason_is_reported() {
        for state in [
            TableState::Missing,
            TableState::Corrupt,
            TableState::WrongVersion,
            TableState::WrongJointCount,
            TableState::Malformed,
        ] {
            let mut hub = Hub::new(state, 6, NumberFormat::Fixed);
            let r = hub.report(0, Ok(&reading(0, 20_000)), must_not_run);
            assert_eq!(r.point, None);
            assert_eq!(r.status.table(), state);
            assert!(!r.status.table_valid());
            match hub.hello() {
                ToHost::Hello(h) => {
                    assert_eq!(h.joints, 0);
                    assert_eq!(h.status.table(), state);
                }
                other => panic!("{other:?}"),
            }
        }
    }

    #[test]
    fn faults_withhold_coordinates() {
        let mut hub = Hub::new(TableState::Valid, 6, NumberFormat::F32);
        let r = hub.report(0, Ok(&reading(0b10_0000, 20_000)), must_not_run);
        assert_eq!((r.point, r.status.encoder_faults()), (None, 0b10_0000));
        let r = hub.report(0, Err(FrameError::Crc), must_not_run);
        assert!(r.point.is_none() && r.status.has(Status::INPUT_ERROR));
        let r = hub.report(0, Ok(&reading(0, 40_001)), must_not_run);
        assert!(r.point.is_none() && r.status.has(Status::OVER_TEMPERATURE));
        let r = hub.report(0, Ok(&reading(0, -1)), must_not_run);
        assert!(r.point.is_none() && r.status.has(Status::OVER_TEMPERATURE));
        let r = hub.report(0, Ok(&reading(0, 20_000)), |_, _| Err::<Coordinates, _>(()));
        assert!(r.point.is_none() && r.status.has(Status::CHAIN_ERROR));
        let mut seven = Hub::new(TableState::Valid, 7, NumberFormat::F32);
        let r = seven.report(0, Ok(&reading(0, 20_000)), must_not_run);
        assert!(r.point.is_none() && r.status.has(Status::CHAIN_ERROR));
        // Every one of them still took a sequence number: the host sees no gap.
        assert_eq!(hub.report(0, Ok(&reading(0, 20_000)), ok_eval).seq, 5);
    }

    #[test]
    fn without_a_temperature_there_are_no_coordinates() {
        let mut hub = Hub::new(TableState::Valid, 6, NumberFormat::F32);
        let counts = [1, 2, 3, 4, 5, 6];
        let r = hub.report_sample(0, &counts, 0, None, must_not_run);
        assert_eq!(r.point, None);
        assert_eq!(
            r.status,
            Status(Status::TABLE_VALID | Status::TEMP_SENSOR_FAULT)
        );
        // Beside an encoder fault both are reported.
        let r = hub.report_sample(0, &counts, 0b1, None, must_not_run);
        assert!(r.status.has(Status::TEMP_SENSOR_FAULT) && r.status.encoder_faults() == 1);
        // A working sensor: the chain runs at the measured temperature.
        let r = hub.report_sample(0, &counts, 0, Some(23_456), |c, t| {
            assert_eq!((c, t), (&counts[..], 23_456));
            Ok::<_, ()>(POINT)
        });
        assert_eq!(
            (r.point, r.status),
            (Some(POINT), Status(Status::TABLE_VALID))
        );
        // Out of the rated range it is over-temperature, not a sensor fault.
        let r = hub.report_sample(0, &counts, 0, Some(45_000), must_not_run);
        assert!(r.status.has(Status::OVER_TEMPERATURE) && !r.status.has(Status::TEMP_SENSOR_FAULT));
        assert_eq!(r.seq, 3);
        // Without a valid table the sensor fault is still reported.
        let mut bad = Hub::new(TableState::Corrupt, 6, NumberFormat::F32);
        let r = bad.report_sample(0, &counts, 0, None, must_not_run);
        assert!(r.status.has(Status::TEMP_SENSOR_FAULT) && r.point.is_none());
    }

    #[test]
    fn render_follows_the_mode() {
        let mut hub = Hub::new(TableState::Valid, 6, NumberFormat::F32);
        let report = hub.report(1, Ok(&reading(0, 20_000)), ok_eval);
        let mut out = [0u8; MAX_OUTPUT];
        let bin = hub.render(&ToHost::Report(report), &mut out).to_vec();
        let mut reader = FrameReader::<MAX_FRAME>::new();
        let got: Vec<_> = bin
            .iter()
            .filter_map(|&b| reader.push::<ToHost>(b))
            .collect();
        assert_eq!(got, vec![Ok(ToHost::Report(report))]);
        hub.set_mode(Mode::Text);
        let text = hub.render(&ToHost::Report(report), &mut out);
        assert!(text.starts_with(b"0,1,0x0001,0.000001,"));
        // In text mode a Hello is the header line.
        assert_eq!(hub.render(&hub.hello(), &mut out), CSV_HEADER.as_bytes());
    }

    #[test]
    fn a_mode_change_restarts_the_count_and_a_binary_hello_stands_alone() {
        let mut hub = Hub::new(TableState::Valid, 6, NumberFormat::F32);
        let _ = hub.report(1, Ok(&reading(0, 20_000)), ok_eval);
        hub.set_mode(Mode::Text);
        let mut out = [0u8; MAX_OUTPUT];
        let report = hub.report(1, Ok(&reading(0, 20_000)), ok_eval);
        let line = hub.render(&ToHost::Report(report), &mut out).to_vec();
        assert!(line.starts_with(b"0,"), "seq restarts at the mode change");
        hub.set_mode(Mode::Binary);
        let hello = hub.render(&hub.hello(), &mut out).to_vec();
        // After a CSV line (no delimiter of its own) the Hello still decodes as a frame.
        let mut reader = FrameReader::<MAX_FRAME>::new();
        let got: Vec<_> = line
            .iter()
            .chain(&hello)
            .filter_map(|&b| reader.push::<ToHost>(b))
            .filter_map(Result::ok)
            .collect();
        assert_eq!(got, vec![hub.hello()]);
        assert_eq!(hub.report(1, Ok(&reading(0, 20_000)), ok_eval).seq, 0);
    }
}
