//! Line-by-line reading of text payloads, with line numbers for error messages.

use std::io::{BufRead, Read};

use crate::io::failure::{Failure, Result};

/// Longest line read: particle tables have lines of a few hundred bytes; a file without line
/// breaks (all zeros, CR-only) must not be read whole into memory as one line.
const MAX_LINE_BYTES: u64 = 1 << 20;

pub(in crate::io) struct Lines<R> {
    reader: R,
    buf: Vec<u8>,
    line: usize,
}

impl<R: BufRead> Lines<R> {
    /// `lines_before` is the number of lines already consumed (a PLY header), so that the
    /// numbers reported are the file's.
    pub fn new(reader: R, lines_before: usize) -> Self {
        Self {
            reader,
            buf: Vec::new(),
            line: lines_before,
        }
    }

    /// Number of the last line read (1-based), or of the last line before the text.
    pub fn line(&self) -> usize {
        self.line
    }

    /// The next line that is not blank, trimmed, with its number; `None` at the end of the file.
    pub fn next_non_blank(&mut self) -> Result<Option<(usize, &str)>> {
        loop {
            self.buf.clear();
            let n = (&mut self.reader)
                .take(MAX_LINE_BYTES)
                .read_until(b'\n', &mut self.buf)
                .map_err(|e| Failure::io(format_args!("read error after line {}", self.line), e))?;
            if n == 0 {
                return Ok(None);
            }
            self.line += 1;
            if n as u64 == MAX_LINE_BYTES && self.buf.last() != Some(&b'\n') {
                bail_format!(
                    "line {} is longer than {} MiB: not a text table (no line breaks?)",
                    self.line,
                    MAX_LINE_BYTES >> 20
                );
            }
            if !self.buf.trim_ascii().is_empty() {
                break;
            }
        }
        match std::str::from_utf8(self.buf.trim_ascii()) {
            Ok(text) => Ok(Some((self.line, text))),
            Err(_) => bail_format!("line {} is not valid UTF-8 text", self.line),
        }
    }
}
