//! The boards' defmt log, decoded on the host: the firmware sends only indices and arguments
//! (over semihosting under QEMU, RTT on real boards); the strings live in the ELF's `.defmt`
//! table, which `defmt-decoder` reads.

use std::path::Path;

use anyhow::{anyhow, Context, Result};
use defmt_decoder::{DecodeError, StreamDecoder, Table};

/// The log messages in `bytes`, as text, with the `elf` that produced them.
pub fn decode(elf: &Path, bytes: &[u8]) -> Result<Vec<String>> {
    let elf_bytes = std::fs::read(elf).with_context(|| format!("reading {}", elf.display()))?;
    let table =
        Table::parse(&elf_bytes)?.ok_or_else(|| anyhow!("{} has no defmt table", elf.display()))?;
    let mut decoder: Box<dyn StreamDecoder + Send + Sync + '_> = table.new_stream_decoder();
    decoder.received(bytes);
    let mut lines = Vec::new();
    loop {
        match decoder.decode() {
            Ok(frame) => lines.push(frame.display_message().to_string()),
            Err(DecodeError::UnexpectedEof) => break,
            Err(DecodeError::Malformed) => return Err(anyhow!("malformed defmt frame")),
        }
    }
    Ok(lines)
}

/// The number in a log line of the form `… <key> N …` (for instance `stack peak N bytes`).
pub fn number_after(lines: &[String], key: &str) -> Option<u64> {
    lines.iter().find_map(|l| {
        let rest = &l[l.find(key)? + key.len()..];
        rest.split_whitespace()
            .next()?
            .trim_matches(',')
            .parse()
            .ok()
    })
}
