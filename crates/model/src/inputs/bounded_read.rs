//! Reading what a user names without unbounded memory: whole text files (task, design) up to
//! a size, and record streams (tools CSV and JSON) whose every record is at most a length.
//! `rank --tools /dev/zero` or `--task /dev/zero` is then a clear error after a megabyte, not
//! an abort on a multi-gigabyte allocation.
//!
//! A record stream is bounded by a [`Read`] adapter ([`RecordLimit`]) in front of the parser
//! (the `csv` crate, `serde_json`): it follows the records' boundaries byte by byte (a CSV row
//! ends at a line break outside quotes; a JSON tool is one element of the top-level array) and
//! fails the read, with a [`RecordTooLong`] naming the line, once a record passes the limit.
//! The parsers then stop with that error, having buffered at most one record.

use std::fmt;
use std::io::{self, Read};
use std::ops::ControlFlow;
use std::path::Path;

/// The longest record (a CSV row, a JSON tool) a tools file may have.
pub const MAX_RECORD_BYTES: usize = 1 << 20;

/// The largest task or design file.
pub const MAX_TEXT_FILE_BYTES: u64 = 1 << 20;

/// A whole text file of at most [`MAX_TEXT_FILE_BYTES`]; `what` names it in the error
/// ("task file"), which says what is wrong: a folder, a missing or unreadable file, a file too
/// large, or one that is not UTF-8.
pub fn read_text_file(path: &Path, what: &str) -> Result<String, String> {
    let file = toolconf_files::input::open_stream(path).map_err(|e| match e {
        toolconf_files::input::InputError::NotAFile(kind) => format!("is {kind}, not a {what}"),
        toolconf_files::input::InputError::Io(e) => format!("cannot read the {what}: {e}"),
        e => e.to_string(),
    })?;
    let mut bytes = Vec::new();
    file.take(MAX_TEXT_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("cannot read the {what}: {e}"))?;
    if bytes.len() as u64 > MAX_TEXT_FILE_BYTES {
        return Err(format!(
            "is larger than {} bytes (1 MiB), more than any {what} needs",
            MAX_TEXT_FILE_BYTES
        ));
    }
    String::from_utf8(bytes).map_err(|e| {
        format!(
            "is not UTF-8 text (an invalid byte at offset {})",
            e.utf8_error().valid_up_to()
        )
    })
}

/// A record longer than [`MAX_RECORD_BYTES`]: the error [`RecordLimit`] fails the read with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RecordTooLong {
    /// The 1-based line the record starts on.
    pub line: u64,
    pub limit: usize,
    /// "row" or "tool".
    pub record: &'static str,
}

impl fmt::Display for RecordTooLong {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "a {} longer than {} bytes (1 MiB) starts here: no tool needs that many",
            self.record, self.limit
        )
    }
}

impl std::error::Error for RecordTooLong {}

/// A quoted CSV cell still open at the end of the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct UnclosedQuote {
    /// The 1-based line the quote opens on.
    pub line: u64,
}

impl fmt::Display for UnclosedQuote {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a quoted cell opens here and is never closed (a \" is missing)")
    }
}

impl std::error::Error for UnclosedQuote {}

/// The [`RecordTooLong`] or [`UnclosedQuote`] inside an I/O error, if that is what it is.
pub fn record_error(e: &io::Error) -> Option<(u64, String)> {
    let inner = e.get_ref()?;
    if let Some(long) = inner.downcast_ref::<RecordTooLong>() {
        return Some((long.line, long.to_string()));
    }
    inner
        .downcast_ref::<UnclosedQuote>()
        .map(|q| (q.line, q.to_string()))
}

/// Where a format's records begin and end.
pub trait Records {
    /// "row" or "tool", for the error.
    const RECORD: &'static str;
    /// Takes `bytes` in order up to and including the first that ends a record, and returns its
    /// index; None if none of them does (all taken).
    fn next_end(&mut self, bytes: &[u8]) -> Option<usize>;
    /// Line breaks taken so far.
    fn lines(&self) -> u64;
    /// At the end of the input: the line of a quote left open, if any.
    fn open_quote(&self) -> Option<u64> {
        None
    }
}

/// CSV rows as the `csv` crate reads them by default (csv-core's state machine for `,`, `"`,
/// doubled quotes as escapes and any of CR, LF, CRLF ending a row): a quote opens a quoted cell
/// only as a cell's first byte, and a line break inside one does not end the row.
#[derive(Debug, Default)]
pub struct CsvRows {
    state: CsvState,
    /// Line breaks taken, and the one the open quote was on.
    line: u64,
    quote_line: u64,
    /// Bytes of the UTF-8 byte-order mark (which the `csv` crate skips) still possible.
    started: bool,
    /// Inside a row (not at its first byte): a `#` there is data, not a comment.
    in_row: bool,
    /// In a comment line (`#` as a row's first byte, the reader's `comment(Some(b'#'))`), which
    /// ends at its line break whatever quotes it holds.
    comment: bool,
}

#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
enum CsvState {
    #[default]
    FieldStart,
    Unquoted,
    Quoted,
    /// A quote inside a quoted cell: the cell's end, or the first of a doubled quote.
    QuoteInQuoted,
}

impl CsvRows {
    /// The row ends at `at`, on the line break `byte`: the next byte starts a row.
    fn row_ends(&mut self, at: usize, byte: u8) -> usize {
        self.line += u64::from(byte == b'\n');
        self.state = CsvState::FieldStart;
        self.in_row = false;
        at
    }

    /// Where this chunk's bytes start: past the byte-order mark at the input's start; and at a
    /// row's first byte, whether the row is a comment.
    #[inline]
    fn start(&mut self, bytes: &[u8]) -> usize {
        let mut i = 0;
        if !self.started && !bytes.is_empty() {
            self.started = true;
            if bytes.starts_with(b"\xEF\xBB\xBF") {
                i = 3;
            }
        }
        if i < bytes.len() && !self.in_row {
            self.comment = bytes[i] == b'#';
            self.in_row = true;
        }
        i
    }

    /// The common row, without a quote: its end is the next line break, found at memchr's
    /// speed (SIMD), cell boundaries need not be followed. `Continue` when a quote (or a quoted
    /// cell already open) needs [`Self::walk`].
    #[inline]
    fn unquoted_end(&mut self, bytes: &[u8], i: usize) -> ControlFlow<Option<usize>> {
        use CsvState::*;
        if !matches!(self.state, FieldStart | Unquoted) {
            return ControlFlow::Continue(());
        }
        if let Some(k) = memchr::memchr3(b'\n', b'\r', b'"', &bytes[i..]) {
            let at = i + k;
            if bytes[at] != b'"' {
                return ControlFlow::Break(Some(self.row_ends(at, bytes[at])));
            }
            return ControlFlow::Continue(());
        }
        // No line break and no quote: whether the last byte ends a cell or not, the state is
        // one of these two, and FieldStart matters only before a quote.
        self.state = if bytes.last() == Some(&b',') {
            FieldStart
        } else {
            Unquoted
        };
        ControlFlow::Break(None)
    }

    /// csv-core's state machine from `bytes[i]`, byte by byte where quotes are involved: the
    /// row's end, or None if these bytes do not end it.
    fn walk(&mut self, bytes: &[u8], mut i: usize) -> Option<usize> {
        use CsvState::*;
        while i < bytes.len() {
            i = self.skip_plain(bytes, i)?;
            let byte = bytes[i];
            let terminator = byte == b'\n' || byte == b'\r';
            let (next, ends) = match (self.state, byte) {
                (Quoted, _) => (QuoteInQuoted, false),
                (QuoteInQuoted, b'"') => (Quoted, false),
                (FieldStart, b'"') => {
                    self.quote_line = self.line;
                    (Quoted, false)
                }
                (_, b',') => (FieldStart, false),
                (_, _) if terminator => (FieldStart, true),
                (_, _) => (Unquoted, false),
            };
            if ends {
                return Some(self.row_ends(i, byte));
            }
            self.line += u64::from(byte == b'\n');
            self.state = next;
            i += 1;
        }
        None
    }

    /// To the next byte from `i` that can change the state (cells are short: a plain loop beats
    /// a memchr call per cell), counting the line breaks inside a quoted cell; None at the end
    /// of the bytes.
    #[inline]
    fn skip_plain(&mut self, bytes: &[u8], mut i: usize) -> Option<usize> {
        match self.state {
            CsvState::Unquoted => {
                while i < bytes.len() && !matches!(bytes[i], b',' | b'\n' | b'\r') {
                    i += 1;
                }
            }
            CsvState::Quoted => {
                while i < bytes.len() && bytes[i] != b'"' {
                    self.line += u64::from(bytes[i] == b'\n');
                    i += 1;
                }
            }
            CsvState::FieldStart | CsvState::QuoteInQuoted => {}
        }
        (i < bytes.len()).then_some(i)
    }
}

impl Records for CsvRows {
    const RECORD: &'static str = "row";

    fn next_end(&mut self, bytes: &[u8]) -> Option<usize> {
        let i = self.start(bytes);
        if self.comment {
            let k = memchr::memchr2(b'\n', b'\r', &bytes[i..])?;
            self.comment = false;
            return Some(self.row_ends(i + k, bytes[i + k]));
        }
        if let ControlFlow::Break(end) = self.unquoted_end(bytes, i) {
            return end;
        }
        self.walk(bytes, i)
    }

    fn lines(&self) -> u64 {
        self.line
    }

    fn open_quote(&self) -> Option<u64> {
        (self.state == CsvState::Quoted).then_some(self.quote_line + 1)
    }
}

/// The elements of a JSON file's top-level array: a record ends at a `,` or `]` of the array
/// itself (outside strings, at depth 1), so whitespace before and after counts too.
#[derive(Debug, Default)]
pub struct JsonElements {
    depth: u32,
    in_string: bool,
    escaped: bool,
    line: u64,
}

impl Records for JsonElements {
    const RECORD: &'static str = "tool";

    fn next_end(&mut self, bytes: &[u8]) -> Option<usize> {
        let mut i = 0;
        while i < bytes.len() {
            if self.in_string {
                if self.escaped {
                    self.escaped = false;
                    i += 1;
                    continue;
                }
                // Keys and values are short: a plain loop beats a memchr call per string.
                while i < bytes.len() && !matches!(bytes[i], b'"' | b'\\') {
                    i += 1;
                }
                if i == bytes.len() {
                    return None;
                }
                match bytes[i] {
                    b'\\' => self.escaped = true,
                    _ => self.in_string = false,
                }
                i += 1;
                continue;
            }
            let ends = match bytes[i] {
                b'"' => {
                    self.in_string = true;
                    false
                }
                b'[' | b'{' => {
                    self.depth += 1;
                    self.depth == 1
                }
                b']' | b'}' => {
                    self.depth = self.depth.saturating_sub(1);
                    self.depth == 0
                }
                b',' => self.depth == 1,
                b'\n' => {
                    self.line += 1;
                    false
                }
                _ => false,
            };
            if ends {
                return Some(i);
            }
            i += 1;
        }
        None
    }

    fn lines(&self) -> u64 {
        self.line
    }
}

/// A reader that fails once a record of `R` passes [`MAX_RECORD_BYTES`] (and, for CSV, at the
/// end of a file whose last quote is never closed).
pub struct RecordLimit<R, T> {
    inner: R,
    records: T,
    /// Bytes of the current record so far, and the line it started on (0-based).
    length: usize,
    start_line: u64,
    limit: usize,
}

impl<R: Read, T: Records> RecordLimit<R, T> {
    pub fn new(inner: R, records: T) -> Self {
        Self::with_limit(inner, records, MAX_RECORD_BYTES)
    }

    pub fn with_limit(inner: R, records: T, limit: usize) -> Self {
        Self {
            inner,
            records,
            length: 0,
            start_line: 0,
            limit,
        }
    }

    fn too_long(&self) -> io::Error {
        io::Error::new(
            io::ErrorKind::InvalidData,
            RecordTooLong {
                line: self.start_line + 1,
                limit: self.limit,
                record: T::RECORD,
            },
        )
    }
}

impl<R: Read, T: Records> Read for RecordLimit<R, T> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.inner.read(buf)?;
        if n == 0 {
            if let Some(line) = self.records.open_quote() {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidData,
                    UnclosedQuote { line },
                ));
            }
            return Ok(0);
        }
        // Segment by segment, each up to a record's end: the limit is checked per segment, so
        // a record is refused within a read buffer (8 KiB) of the limit.
        let mut rest = &buf[..n];
        while !rest.is_empty() {
            let end = self.records.next_end(rest);
            let (segment, after) = rest.split_at(end.map_or(rest.len(), |i| i + 1));
            self.length += segment.len();
            if self.length > self.limit {
                return Err(self.too_long());
            }
            if end.is_some() {
                self.length = 0;
                self.start_line = self.records.lines();
            }
            rest = after;
        }
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read_all<T: Records>(input: &[u8], records: T, limit: usize) -> io::Result<Vec<u8>> {
        let mut out = Vec::new();
        RecordLimit::with_limit(input, records, limit)
            .read_to_end(&mut out)
            .map(|_| out)
    }

    #[test]
    fn csv_rows_end_at_line_breaks_outside_quotes() {
        let ok = b"name,m1\n\"a,\nb\",0.3\r\n\"say \"\"hi\"\"\",0.4\n5\" hammer,0.5\n";
        assert_eq!(read_all(ok, CsvRows::default(), 20).unwrap(), ok);
        let e = read_all(
            b"name,m1\n\"abcdefghijklmnopq,0.3\n",
            CsvRows::default(),
            16,
        )
        .unwrap_err();
        assert_eq!(record_error(&e).unwrap().0, 2);
        let e = read_all(
            b"name,m1\nx,0.3\n\"open,0.3\nmore\n",
            CsvRows::default(),
            100,
        )
        .unwrap_err();
        let (line, message) = record_error(&e).unwrap();
        assert_eq!(line, 3);
        assert!(message.contains("never closed"), "{message}");
        // A byte-order mark does not hide a quote at the start of the first cell.
        let e = read_all(b"\xEF\xBB\xBF\"name,m1\n", CsvRows::default(), 100).unwrap_err();
        assert_eq!(record_error(&e).unwrap().0, 1);
    }

    #[test]
    fn csv_comment_lines_end_at_their_line_break_whatever_their_quotes() {
        // As the reader's comment(Some(b'#')) skips them: a quote in a comment opens nothing.
        let ok = b"name,m1\n# Wera, \"Kraftform 0.3 kg\nx,0.3\ny#2,0.4\n";
        assert_eq!(read_all(ok, CsvRows::default(), 30).unwrap(), ok);
        // A '#' inside a row is data: its quote still opens a cell.
        let e = read_all(b"name,m1\nx#,\"open\n", CsvRows::default(), 100).unwrap_err();
        assert!(record_error(&e).unwrap().1.contains("never closed"));
    }

    #[test]
    fn json_tools_end_at_the_top_level_arrays_commas() {
        let ok = br#"[{"name": "a,]", "m1": 0.3}, {"name": "b\"}", "m1": [1, 2]}]"#;
        assert_eq!(read_all(ok, JsonElements::default(), 40).unwrap(), ok);
        assert!(read_all(ok, JsonElements::default(), 20).is_err());
        let spaces = vec![b' '; 1000];
        let e = read_all(&spaces, JsonElements::default(), 100).unwrap_err();
        assert!(record_error(&e)
            .unwrap()
            .1
            .contains("tool longer than 100 bytes"));
    }

    #[test]
    fn a_text_file_is_read_whole_up_to_its_limit() {
        let dir = std::env::temp_dir().join(format!("toolconf-bounded-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        assert_eq!(
            read_text_file(&dir, "task file").unwrap_err(),
            "is a folder, not a task file"
        );
        let big = dir.join("big.toml");
        std::fs::write(&big, vec![b'#'; MAX_TEXT_FILE_BYTES as usize + 1]).unwrap();
        assert!(read_text_file(&big, "task file")
            .unwrap_err()
            .contains("larger than 1048576 bytes"));
        std::fs::write(&big, b"kind = \"position\"\xFF").unwrap();
        assert!(read_text_file(&big, "task file")
            .unwrap_err()
            .contains("not UTF-8 text (an invalid byte at offset 17)"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
