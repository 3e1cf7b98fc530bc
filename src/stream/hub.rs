//! What every board's main loop does with a reading, in one place that host tests can reach.
//!
//! A board supplies the hardware (UART, clock, encoders) and a closure that runs its chain; the
//! [`Hub`] decides, from the boot check of the table and the faults of this reading, whether the
//! chain may run at all, numbers the reports and renders them in the current [`Mode`]. Keeping
//! this out of the boards means the rule "no coordinates beside a fault" is written, and tested,
//! once.
//!
//! The hub also keeps the table's probes, by id ([`Hub::with_probes`]), and which one is
//! mounted: every report carries its id, and a selection by the host ([`Hub::select`]) is
//! checked here before the board converts the probe into its chain's numbers.

use super::{
    encode, write_csv_header, write_csv_line, Coordinates, FrameError, Hello, LiveTable, Mode,
    NumberFormat, ProbeAnswer, ProbeRefusal, Reading, Report, Status, TableState, ToHost,
    MAX_CSV_LINE, MAX_FRAME, PROTOCOL_VERSION,
};
use crate::table::probes::MAX_PROBES;
use crate::table::Release;

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
    /// The id of the probe mounted (0 without a valid table).
    probe: u8,
    /// The table's probes by id, the first first: a probe's position is its index in the
    /// table (`Table::probe_at`). Ids only, 8 bytes and a length: the board converts a probe
    /// from the table when it is selected, rather than holding eight converted.
    probes: heapless::Vec<u8, MAX_PROBES>,
    /// The live table's calibration number and date, for the `Hello` (zeros without one).
    release: Release,
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
            probe: 0,
            probes: heapless::Vec::new(),
            release: Release { number: 0, date: 0 },
        }
    }

    /// The same hub, with the table's probes by id (`ids`: the first first, the one mounted
    /// at boot; the ninth and later are not taken: a table holds eight). Only with a valid
    /// table: a hub without one has no probe.
    pub fn with_probes(mut self, ids: impl IntoIterator<Item = u8>) -> Hub {
        if self.base.table_valid() {
            for id in ids {
                if self.probes.push(id).is_err() {
                    break;
                }
            }
            self.probe = self.probes.first().copied().unwrap_or(0);
        }
        self
    }

    /// The same hub, announcing the live table's calibration number and date (only with a
    /// valid table: a hub without one announces zeros).
    pub fn with_release(mut self, release: Release) -> Hub {
        if self.base.table_valid() {
            self.release = release;
        }
        self
    }

    /// The id of the probe mounted.
    pub fn probe(&self) -> u8 {
        self.probe
    }

    /// The table's probes by id, the first first.
    pub fn probes(&self) -> &[u8] {
        &self.probes
    }

    /// Selects the probe of id `id`: `mount` is given its index in the table and converts it
    /// into the chain's numbers (`false`: it could not, and the probe mounted before stays).
    /// Refused without a valid table or for an id the table does not hold; either way nothing
    /// changes. The selection holds until the next; every report after it carries `id`.
    pub fn select(&mut self, id: u8, mount: impl FnOnce(usize) -> bool) -> ProbeAnswer {
        if !self.base.table_valid() {
            return Err(ProbeRefusal::NoTable);
        }
        let k = self
            .probes
            .iter()
            .position(|&p| p == id)
            .ok_or(ProbeRefusal::Unknown)?;
        if !mount(k) {
            return Err(ProbeRefusal::Unknown);
        }
        self.probe = id;
        Ok(id)
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
            probe: self.probe,
            probes: self.probes.clone(),
            number: self.release.number,
            date: self.release.date,
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
            probe: self.probe,
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
            let release = Release {
                number: 4,
                date: 20261204,
            };
            let mut hub = Hub::new(state, 6, NumberFormat::Fixed).with_release(release);
            let r = hub.report(0, Ok(&reading(0, 20_000)), must_not_run);
            assert_eq!(r.point, None);
            assert_eq!(r.status.table(), state);
            assert!(!r.status.table_valid());
            match hub.hello() {
                ToHost::Hello(h) => {
                    assert_eq!(h.joints, 0);
                    assert_eq!(h.status.table(), state);
                    assert_eq!((h.number, h.date), (0, 0), "no table, no calibration");
                }
                other => panic!("{other:?}"),
            }
        }
    }

    /// Protocol 5: the `Hello` of a hub with a valid table names its calibration's number
    /// and date.
    #[test]
    fn hello_names_the_live_calibration() {
        let release = Release {
            number: 12,
            date: 20261204,
        };
        let hub = Hub::new(TableState::Valid, 6, NumberFormat::F32).with_release(release);
        match hub.hello() {
            ToHost::Hello(h) => assert_eq!(
                (h.protocol, h.number, h.date),
                (PROTOCOL_VERSION, 12, 20261204)
            ),
            other => panic!("{other:?}"),
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

    /// The probe table: the first probe is mounted at boot and named in the Hello; a
    /// selection mounts the probe at its index and every report after it carries its id; an
    /// unknown id, a probe the board cannot mount and a hub without a table change nothing.
    #[test]
    fn a_selected_probe_is_mounted_and_named_in_every_report() {
        let mut hub = Hub::new(TableState::Valid, 6, NumberFormat::Fixed).with_probes([4, 9, 0]);
        match hub.hello() {
            ToHost::Hello(h) => assert_eq!((h.probe, h.probes.as_slice()), (4, &[4, 9, 0][..])),
            other => panic!("{other:?}"),
        }
        assert_eq!(hub.report(0, Ok(&reading(0, 20_000)), ok_eval).probe, 4);
        let mut mounted = None;
        assert_eq!(hub.select(0, |k| mounted.replace(k).is_none()), Ok(0));
        assert_eq!(mounted, Some(2), "id 0 is the table's third probe");
        assert_eq!(hub.report(0, Ok(&reading(0, 20_000)), ok_eval).probe, 0);
        // Refused: nothing is mounted, the probe stays.
        let never = |_| -> bool { panic!("mounted a probe the table does not hold") };
        assert_eq!(hub.select(5, never), Err(ProbeRefusal::Unknown));
        assert_eq!(hub.select(9, |_| false), Err(ProbeRefusal::Unknown));
        assert_eq!(hub.probe(), 0);
        let r = hub.report(0, Ok(&reading(0b1, 20_000)), must_not_run);
        assert_eq!(
            (r.probe, r.point),
            (0, None),
            "a fault keeps the probe's id"
        );
        assert_eq!(hub.select(9, |k| k == 1), Ok(9));
        match hub.hello() {
            ToHost::Hello(h) => assert_eq!(h.probe, 9, "a Hello names the probe mounted"),
            other => panic!("{other:?}"),
        }
        // The answer is a frame behind a lone 0x00 in either mode.
        let mut out = [0u8; MAX_OUTPUT];
        for mode in [Mode::Binary, Mode::Text] {
            hub.set_mode(mode);
            let answer = ToHost::Probe(Err(ProbeRefusal::Unknown));
            let bytes = hub.render(&answer, &mut out);
            assert_eq!(bytes[0], 0);
            let mut reader = FrameReader::<MAX_FRAME>::new();
            let got: Vec<_> = bytes
                .iter()
                .filter_map(|&b| reader.push::<ToHost>(b))
                .collect();
            assert_eq!(got, vec![Ok(answer)]);
        }
        // Without a valid table: no probes, and a selection says why.
        let mut bad = Hub::new(TableState::Corrupt, 6, NumberFormat::F32).with_probes([4, 9]);
        assert_eq!(bad.select(4, never), Err(ProbeRefusal::NoTable));
        assert_eq!((bad.probe(), bad.probes()), (0, &[][..]));
        assert_eq!(
            bad.report(0, Ok(&reading(0, 20_000)), must_not_run).probe,
            0
        );
        // More than eight ids: the first eight are taken.
        let many = Hub::new(TableState::Valid, 6, NumberFormat::F32).with_probes(0..20);
        assert_eq!(many.probes(), &[0, 1, 2, 3, 4, 5, 6, 7]);
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
        assert!(text.ends_with(b",0.000007,0\n"), "U95, then the probe");
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
