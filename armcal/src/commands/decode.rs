//! `armcal decode`: a hub's binary stream to CSV, from a serial port, a file or stdin.
//!
//! The CSV is the hub's own text mode (`quatarm::stream::write_csv_line`), so a capture
//! decoded here and a terminal session in text mode read the same. Announcements and damaged
//! frames go to stderr as they come; the counts that tell whether the capture can be trusted
//! (reports, lost, CRC errors) close the run on stderr.

use std::io::{BufWriter, Read, Write};
use std::path::PathBuf;
use std::time::Duration;

use anyhow::{bail, Context, Result};
use armcal::stream_decode::{Decoder, Inconsistency, Item, Stats};
use quatarm::stream::{write_csv_line, Hello, CSV_HEADER, MAX_CSV_LINE, PROTOCOL_VERSION};

/// Arguments of `armcal decode`.
#[derive(clap::Args)]
pub struct Args {
    /// A capture file; `-` or nothing reads stdin. Ignored with `--port`.
    input: Option<PathBuf>,
    /// Read a serial port instead (for instance /dev/ttyACM0).
    #[arg(long)]
    port: Option<String>,
    /// Baud rate of the serial port.
    #[arg(long, default_value_t = 115_200)]
    baud: u32,
    /// Stop after this many reports (a serial port otherwise reads until interrupted).
    #[arg(long)]
    max_reports: Option<u64>,
    /// Take the first byte as the start of a frame. Default for files and stdin; a serial
    /// port is joined mid-stream (bytes before the first delimiter are skipped).
    #[arg(long)]
    from_start: bool,
    /// The calibration file of the arm whose hub is read: a warning on stderr when it is
    /// past the due date its `[calibration]` gives.
    #[arg(long)]
    calib: Option<PathBuf>,
    #[command(flatten)]
    accept: super::accept::AcceptArgs,
    /// Go on when the hub announces a table other than the one `--calib` builds (refused as
    /// another arm's or another calibration's table).
    #[arg(long)]
    accept_misfit: bool,
}

/// Runs the subcommand.
///
/// Nothing goes to stdout until the first report: a run that fails (an unreadable input, a
/// capture in which no frame passed its checks) leaves no partial CSV behind.
pub fn run(args: Args) -> Result<()> {
    let accept = armcal::plausible::Accept {
        misfit: args.accept_misfit,
        ..args.accept.accept()
    };
    let expected = match &args.calib {
        Some(calib) => {
            armcal::plausible::calibration(calib, accept)?;
            armcal::load::warn_if_due(calib)?;
            Some(hub_table(calib)?)
        }
        None => None,
    };
    let (mut source, joining, name) = open(&args)?;
    let mut decoder = if joining {
        Decoder::joining()
    } else {
        Decoder::from_start()
    };
    let stdout = std::io::stdout();
    let mut out = BufWriter::new(stdout.lock());
    let mut header_written = false;
    let mut buf = [0u8; 4096];
    let mut line = [0u8; MAX_CSV_LINE];
    let mut total = 0u64;
    // The first bytes, to tell a text-mode capture from noise when no frame decodes.
    let mut head = Vec::new();
    'read: loop {
        let n = match source.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) if e.kind() == std::io::ErrorKind::TimedOut => continue,
            Err(e) => return Err(e).with_context(|| format!("reading {name}")),
        };
        total += n as u64;
        if head.len() < CSV_HEADER.len() {
            head.extend_from_slice(&buf[..n.min(CSV_HEADER.len() - head.len())]);
        }
        for &b in &buf[..n] {
            let Some(item) = decoder.push(b) else {
                continue;
            };
            note(&item);
            if let (Item::Hello(h), Some(expected)) = (&item, &expected) {
                // Before any report of that table is written.
                out.flush()?;
                armcal::plausible::hub(expected, &name, h.joints, h.live.map(|l| l.crc), accept)?;
            }
            if let Some(r) = item.report() {
                if !header_written {
                    out.write_all(CSV_HEADER.as_bytes())?;
                    header_written = true;
                }
                let len = write_csv_line(r, &mut line);
                out.write_all(&line[..len])?;
                if args
                    .max_reports
                    .is_some_and(|m| decoder.stats().reports >= m)
                {
                    break 'read;
                }
            }
        }
        if args.port.is_some() {
            out.flush()?;
        }
    }
    summarise(&decoder.finish(), &name, total, &head)?;
    if !header_written {
        out.write_all(CSV_HEADER.as_bytes())?;
    }
    out.flush()?;
    Ok(())
}

/// What a hub running `calib`'s table announces: its joint count and the CRCs of the tables
/// `armcal table build` makes from it, with and without the covariance.
fn hub_table(calib: &std::path::Path) -> Result<armcal::plausible::HubTable> {
    let (arm, budget, release) = armcal::load::calibration_release(calib)?;
    let built = |b: Option<&quatarm_ref::calfile::Uncertainty>| -> Result<u32> {
        let bytes = armcal::tablebuild::build_release(&arm, b, &release)
            .with_context(|| calib.display().to_string())?;
        Ok(quatarm::table::Table::parse(&bytes)
            .map_err(|e| anyhow::anyhow!("{}: {e:?}", calib.display()))?
            .crc())
    };
    let mut crcs = vec![built(budget.as_ref())?];
    if let Some(b) = &budget {
        crcs.push(built(Some(&b.without_covariance()))?);
    }
    crcs.dedup();
    Ok(armcal::plausible::HubTable {
        file: calib.display().to_string(),
        joints: arm.dof(),
        crcs,
    })
}

/// The stream to read, whether the decoder joins it mid-stream (a live port, unless
/// `--from-start`), and its name for messages.
fn open(args: &Args) -> Result<(Box<dyn Read>, bool, String)> {
    Ok(match (&args.port, &args.input) {
        (Some(port), _) => {
            let p = serialport::new(port, args.baud)
                .timeout(Duration::from_secs(3600))
                .open()
                .with_context(|| format!("opening serial port {port}"))?;
            (Box::new(p), !args.from_start, port.clone())
        }
        (None, Some(path)) if path.as_os_str() != "-" => {
            if path.is_dir() {
                bail!("{} is a directory, not a captured stream", path.display());
            }
            let f =
                std::fs::File::open(path).with_context(|| format!("opening {}", path.display()))?;
            let name = path.display().to_string();
            (Box::new(std::io::BufReader::new(f)), false, name)
        }
        _ => (Box::new(std::io::stdin().lock()), false, "stdin".to_owned()),
    })
}

/// The live table's calibration number and date as a `Hello` of protocol 5 names them (an
/// older hub's says nothing of them; a hub without a valid table has none).
fn calibration(h: &Hello) -> String {
    if h.protocol < 5 || !h.status.table_valid() {
        return String::new();
    }
    let date = quatarm_ref::release::Date::from_yyyymmdd(h.date)
        .map_or_else(|| "no date".to_string(), |d| format!("dated {d}"));
    format!(", calibration number {}, {date}", h.number)
}

/// Says on stderr what a decoded item other than a plain report means.
fn note(item: &Item) {
    match item {
        Item::Hello(h) => eprintln!(
            "# hub: protocol {}, {:?}, {} joints, table {}{}{}{}",
            h.protocol,
            h.precision,
            h.joints,
            h.status.table().name(),
            match h.live {
                Some(l) => format!(
                    " (slot {}, record {}, CRC {:#010x})",
                    l.slot, l.seq, l.crc
                ),
                None => String::new(),
            },
            if h.probes.is_empty() {
                String::new()
            } else {
                format!(", probe {} of {:?}", h.probe, h.probes.as_slice())
            },
            calibration(h)
        ),
        Item::Update(a) => eprintln!("# update: {a:?}"),
        Item::Probe(Ok(id)) => eprintln!("# probe {id} mounted"),
        Item::Probe(Err(e)) => eprintln!("# probe selection refused: {e:?}"),
        Item::Damaged(e) => eprintln!("# damaged frame: {e}"),
        Item::Repeated(r) => {
            eprintln!("# report {} repeated: not written again", r.seq)
        }
        Item::Backward { report, expected } => eprintln!(
            "# report {} where {expected} was due, without a hub restart: numbering restarts from it",
            report.seq
        ),
        Item::Inconsistent(r, why) => eprintln!(
            "# report {} (status {:#06x}, probe {}) {}: written without coordinates",
            r.seq,
            r.status.0,
            r.probe,
            match why {
                Inconsistency::Status =>
                    "has a status that contradicts itself (bit 0 means table state 0, states 9-15 are reserved)",
                Inconsistency::Forbidden => "carries coordinates beside a status that forbids them",
                Inconsistency::Missing => "has no coordinates although its status has no fault",
                Inconsistency::UnknownProbe => "names a probe its hub's Hello does not list",
                Inconsistency::Direction => "carries a direction that is no unit vector",
            }
        ),
        Item::Report(_) => {}
    }
}

/// Prints the decoder's counts; an empty stream, or one without a single valid frame, is an
/// error (with a hint when it looks like the hub's text mode).
fn summarise(s: &Stats, name: &str, total: u64, head: &[u8]) -> Result<()> {
    eprintln!(
        "decode: {} reports ({} with coordinates), {} lost, {} crc errors, {} other damaged frames, {} bytes skipped, {} repeated, {} backward, {} inconsistent, {} unterminated bytes",
        s.reports,
        s.points,
        s.lost,
        s.crc_errors,
        s.other_errors,
        s.skipped_bytes,
        s.repeated,
        s.backward,
        s.inconsistent,
        s.unterminated_bytes
    );
    if s.foreign_protocol > 0 || s.undecodable > 0 {
        eprintln!(
            "# {name}: {} Hello(s) of a protocol other than versions 1–{PROTOCOL_VERSION}, {} frame(s) with a good CRC that are no message of version {PROTOCOL_VERSION}: a hub of another protocol version, or a sender that breaks it (an option tag other than 0 or 1, an overlong varint; docs/protocol.md)",
            s.foreign_protocol, s.undecodable
        );
    }
    if s.unterminated_bytes > 0 {
        eprintln!(
            "# {} bytes at the end of {name} never reached a frame delimiter (0x00)",
            s.unterminated_bytes
        );
    }
    if total == 0 {
        bail!("{name} is empty: no stream to decode");
    }
    if s.valid_frames() == 0 {
        let hint = if looks_like_text_mode(head) {
            ": it looks like the hub's text mode (CSV), which is already readable and needs no decoding"
        } else {
            ""
        };
        bail!(
            "no valid frame in the {total} bytes of {name} ({} damaged){hint}",
            s.damaged()
        );
    }
    Ok(())
}

/// True if a capture starts like the hub's text mode: its header, or a CSV row of it.
fn looks_like_text_mode(head: &[u8]) -> bool {
    let first_line = head.split(|&b| b == b'\n').next().unwrap_or_default();
    let header_line = CSV_HEADER.trim_end().as_bytes();
    let header_like = first_line.len() >= 3 && header_line.starts_with(first_line)
        || first_line.starts_with(header_line);
    let row_like = first_line.contains(&b',')
        && first_line
            .iter()
            .all(|&b| b.is_ascii_hexdigit() || b",x.-".contains(&b));
    header_like || row_like
}
