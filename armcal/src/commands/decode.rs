//! `armcal decode`: a hub's binary stream to CSV, from a serial port, a file or stdin.
//!
//! The CSV is the hub's own text mode (`quatarm::stream::write_csv_line`), so a capture
//! decoded here and a terminal session in text mode read the same. Announcements and damaged
//! frames go to stderr as they come; the counts that tell whether the capture can be trusted
//! (reports, lost, CRC errors) close the run on stderr.

use std::io::{BufWriter, Read, Write};
use std::path::PathBuf;
use std::time::Duration;

use anyhow::{Context, Result};
use armcal::stream_decode::{Decoder, Item};
use quatarm::stream::{write_csv_line, CSV_HEADER, MAX_CSV_LINE};

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
}

/// Runs the subcommand.
pub fn run(args: Args) -> Result<()> {
    let (mut source, joining): (Box<dyn Read>, bool) = match (&args.port, &args.input) {
        (Some(port), _) => {
            let p = serialport::new(port, args.baud)
                .timeout(Duration::from_secs(3600))
                .open()
                .with_context(|| format!("opening serial port {port}"))?;
            (Box::new(p), !args.from_start)
        }
        (None, Some(path)) if path.as_os_str() != "-" => {
            let f =
                std::fs::File::open(path).with_context(|| format!("opening {}", path.display()))?;
            (Box::new(std::io::BufReader::new(f)), false)
        }
        _ => (Box::new(std::io::stdin().lock()), false),
    };
    let mut decoder = if joining {
        Decoder::joining()
    } else {
        Decoder::from_start()
    };
    let stdout = std::io::stdout();
    let mut out = BufWriter::new(stdout.lock());
    out.write_all(CSV_HEADER.as_bytes())?;
    let mut buf = [0u8; 4096];
    let mut line = [0u8; MAX_CSV_LINE];
    'read: loop {
        let n = match source.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) if e.kind() == std::io::ErrorKind::TimedOut => continue,
            Err(e) => return Err(e).context("reading the stream"),
        };
        for &b in &buf[..n] {
            match decoder.push(b) {
                Some(Item::Report(r)) => {
                    let len = write_csv_line(&r, &mut line);
                    out.write_all(&line[..len])?;
                    if args
                        .max_reports
                        .is_some_and(|m| decoder.stats().reports >= m)
                    {
                        break 'read;
                    }
                }
                Some(Item::Hello(h)) => eprintln!(
                    "# hub: protocol {}, {:?}, {} joints, table {}",
                    h.protocol,
                    h.precision,
                    h.joints,
                    h.status.table().name()
                ),
                Some(Item::Damaged(e)) => eprintln!("# damaged frame: {e}"),
                None => {}
            }
        }
        if args.port.is_some() {
            out.flush()?;
        }
    }
    out.flush()?;
    let s = decoder.stats();
    eprintln!(
        "decode: {} reports ({} with coordinates), {} lost, {} crc errors, {} other damaged frames, {} bytes skipped",
        s.reports,
        s.points,
        s.lost,
        s.crc_errors,
        s.other_errors,
        s.skipped_bytes
    );
    Ok(())
}
