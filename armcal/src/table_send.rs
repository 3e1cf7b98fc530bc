//! `armcal table send`: a calibration table to a hub over its stream's UART, as the update
//! steps of `docs/update.md` (`Begin`, the chunks in order, `Commit`), each step sent only
//! after the hub accepted the one before it.
//!
//! The hub keeps measuring during an update, so its answers arrive between reports; this
//! reads the stream through the one decoder of the host ([`quatarm_wire::stream_decode`]) and
//! waits for each step's answer, skipping reports. After the commit the hub boots on the new
//! table and says so in its `Hello`; the send is done when that `Hello` names the table's CRC.

use std::io::{ErrorKind, Read, Write};

use anyhow::{anyhow, bail, Context, Result};
use quatarm::stream::{encode, LiveTable, ToDevice, MAX_FRAME};
use quatarm::table::Table;
use quatarm::update::session::Step;
use quatarm::update::Accepted;
use quatarm_wire::stream_decode::{Decoder, Item};

/// What a send achieved.
#[derive(Debug, PartialEq, Eq)]
pub struct Sent {
    /// Steps sent (`Begin`, chunks, `Commit`).
    pub steps: usize,
    /// Reports that arrived while the update ran (the arm kept measuring).
    pub reports_between: u64,
    /// The table the hub announced after the commit.
    pub live: LiveTable,
}

/// Sends `table` (checked here as the hub will check it, before a byte goes out) through
/// `port`. A refused step ends the send with the hub's reason; so does a port that stays
/// silent past its timeout (a read error of kind `TimedOut` or `WouldBlock`).
pub fn send(port: &mut (impl Read + Write), table: &[u8]) -> Result<Sent> {
    let crc = Table::parse(table)
        .map_err(|e| anyhow!("not a valid table: {e}"))?
        .crc();
    let mut decoder = Decoder::joining();
    let mut pending = std::collections::VecDeque::new();
    let mut reports_between = 0u64;
    port.write_all(&[0]).context("writing to the port")?;
    let steps: Vec<Step> = Step::sequence(table).collect();
    for (i, step) in steps.iter().enumerate() {
        let mut out = [0u8; MAX_FRAME];
        let n = encode(&ToDevice::Update(step.clone()), &mut out)?;
        port.write_all(&out[..n]).context("writing to the port")?;
        port.flush().ok();
        let answer = loop {
            match next(port, &mut decoder, &mut pending).with_context(|| {
                format!("waiting for the answer to step {} ({})", i + 1, name(step))
            })? {
                Item::Update(a) => break a,
                Item::Report(_) | Item::Backward { .. } | Item::Inconsistent(_) => {
                    reports_between += 1
                }
                _ => {}
            }
        };
        let last = i + 1 == steps.len();
        match (answer, last) {
            (Ok(Accepted::Committed { .. }), true)
            | (Ok(Accepted::Begun { .. } | Accepted::Chunk { .. }), false) => {}
            (Ok(a), _) => bail!("the hub answered {a:?} to step {} ({})", i + 1, name(step)),
            (Err(why), _) => bail!(
                "the hub refused step {} of {} ({}): {why:?}; its old table stays live",
                i + 1,
                steps.len(),
                name(step)
            ),
        }
    }
    // The hub boots on the new table and announces it.
    loop {
        match next(port, &mut decoder, &mut pending)
            .context("waiting for the hub's Hello after the commit")?
        {
            Item::Hello(h) => match h.live {
                Some(live) if live.crc == crc => {
                    return Ok(Sent {
                        steps: steps.len(),
                        reports_between,
                        live,
                    })
                }
                other => bail!(
                    "after the commit the hub announced {other:?}, not the table sent (CRC {crc:#010x})"
                ),
            },
            _ => continue,
        }
    }
}

/// A step in words, for messages.
fn name(step: &Step) -> String {
    match step {
        Step::Begin { len, crc } => format!("Begin, {len} bytes, CRC {crc:#010x}"),
        Step::Chunk { offset, bytes } => format!("chunk of {} bytes at {offset}", bytes.len()),
        Step::Commit => "Commit".into(),
        Step::Abort => "Abort".into(),
    }
}

/// The next decoded item, reading the port as needed.
fn next(
    port: &mut impl Read,
    decoder: &mut Decoder,
    pending: &mut std::collections::VecDeque<Item>,
) -> Result<Item> {
    let mut buf = [0u8; 256];
    loop {
        if let Some(item) = pending.pop_front() {
            return Ok(item);
        }
        match port.read(&mut buf) {
            Ok(0) => bail!("the port closed"),
            Ok(n) => pending.extend(decoder.push_all(&buf[..n])),
            Err(e) if matches!(e.kind(), ErrorKind::TimedOut | ErrorKind::WouldBlock) => {
                bail!("no answer from the hub before the port's timeout")
            }
            Err(e) if e.kind() == ErrorKind::Interrupted => continue,
            Err(e) => return Err(e).context("reading the port"),
        }
    }
}
