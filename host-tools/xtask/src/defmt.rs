//! The firmware's defmt log (its semihosting output under QEMU), decoded in this process against
//! the ELF's string table with `defmt-decoder` — what `defmt-print` does, without a tool to
//! install on every fresh machine or a second child process to bound.

use anyhow::{Context, Result, bail};
use defmt_decoder::{DecodeError, Table};
use std::fmt::Write as _;
use std::path::Path;

/// The log text of `bytes`, one line per defmt frame (`LEVEL message`, or the message alone for
/// `println!`). A malformed frame fails: the log is the run's verdict, it must read whole.
pub fn decode(elf: &Path, bytes: &[u8]) -> Result<String> {
    let elf_bytes = std::fs::read(elf).with_context(|| format!("{}", elf.display()))?;
    let table = Table::parse(&elf_bytes)
        .with_context(|| format!("the defmt table of {}", elf.display()))?
        .with_context(|| format!("{} has no defmt table", elf.display()))?;
    let mut stream = table.new_stream_decoder();
    stream.received(bytes);
    let mut text = String::new();
    loop {
        match stream.decode() {
            Ok(frame) => {
                let _ = match frame.level() {
                    Some(level) => writeln!(
                        text,
                        "{} {}",
                        level.as_str().to_uppercase(),
                        frame.display_message()
                    ),
                    None => writeln!(text, "{}", frame.display_message()),
                };
            }
            // The end of the bytes; a frame cut by the end of the run is dropped.
            Err(DecodeError::UnexpectedEof) => break,
            Err(DecodeError::Malformed) => {
                bail!("malformed defmt frame after:\n{text}")
            }
        }
    }
    Ok(text)
}
