//! CSV rows written as they are computed: the header and each row are one `write_all` on an
//! unbuffered file, the temporary beside the target ([`crate::file::create_streaming`]), renamed
//! over it at [`CsvWriter::finish`]: an interrupted or failed run keeps the file that was there.
//!
//! Numbers are written exactly (Rust's shortest round-trip form, in exponent notation outside
//! 1e-4 ≤ |x| < 1e16); a non-finite number becomes an empty cell, so no file ever holds `NaN` or
//! `inf`. Text cells are quoted when they hold a comma or a quote (RFC 4180); line breaks inside
//! text become spaces, so every row is one line.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::file::Streaming;
use crate::WriteError;

/// One cell of a row.
#[derive(Debug, Clone, PartialEq)]
pub enum Cell {
    Empty,
    Int(i64),
    Num(f64),
    Text(String),
}

impl From<f64> for Cell {
    fn from(v: f64) -> Self {
        Cell::Num(v)
    }
}

impl From<Option<f64>> for Cell {
    fn from(v: Option<f64>) -> Self {
        v.map_or(Cell::Empty, Cell::Num)
    }
}

impl From<usize> for Cell {
    fn from(v: usize) -> Self {
        Cell::Int(i64::try_from(v).unwrap_or(i64::MAX))
    }
}

impl From<bool> for Cell {
    fn from(v: bool) -> Self {
        Cell::Int(i64::from(v))
    }
}

impl From<&str> for Cell {
    fn from(v: &str) -> Self {
        Cell::Text(v.to_string())
    }
}

impl From<String> for Cell {
    fn from(v: String) -> Self {
        Cell::Text(v)
    }
}

/// A number as written to a result file ("" if not finite).
pub fn format_number(x: f64) -> String {
    if !x.is_finite() {
        String::new()
    } else if x == 0.0 {
        "0".to_string()
    } else if (1e-4..1e16).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

fn format_text(s: &str) -> String {
    let s: String = s
        .chars()
        .map(|c| if c == '\n' || c == '\r' { ' ' } else { c })
        .collect();
    if s.contains([',', '"']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s
    }
}

fn format_row(cells: &[Cell]) -> String {
    let mut line = cells
        .iter()
        .map(|c| match c {
            Cell::Empty => String::new(),
            Cell::Int(i) => i.to_string(),
            Cell::Num(x) => format_number(*x),
            Cell::Text(s) => format_text(s),
        })
        .collect::<Vec<_>>()
        .join(",");
    line.push('\n');
    line
}

/// An open CSV file with a fixed header; its rows reach the target at [`CsvWriter::finish`].
pub struct CsvWriter {
    file: Streaming,
    path: PathBuf,
    columns: usize,
}

impl CsvWriter {
    /// Starts the file at `path` (its temporary, for a new or regular file) with the header.
    pub fn create(path: &Path, header: &[&str]) -> Result<Self, WriteError> {
        let file = crate::file::create_streaming(path).map_err(WriteError::at(path))?;
        let mut writer = Self {
            file,
            path: path.to_path_buf(),
            columns: header.len(),
        };
        let cells: Vec<Cell> = header.iter().map(|h| Cell::from(*h)).collect();
        writer.row(cells)?;
        Ok(writer)
    }

    /// Appends one row; it must have as many cells as the header.
    pub fn row(&mut self, cells: Vec<Cell>) -> Result<(), WriteError> {
        assert_eq!(
            cells.len(),
            self.columns,
            "row of {} has {} cells, header has {}",
            self.path.display(),
            cells.len(),
            self.columns
        );
        self.file
            .write_all(format_row(&cells).as_bytes())
            .map_err(WriteError::at(&self.path))
    }

    /// Renames the whole file over its target (writes nothing more to a device).
    pub fn finish(self) -> Result<(), WriteError> {
        self.file.finish().map_err(WriteError::at(&self.path))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_exact_and_never_nan() {
        assert_eq!(format_number(0.1), "0.1");
        assert_eq!(format_number(-1234.5), "-1234.5");
        assert_eq!(format_number(1e-7), "1e-7");
        assert_eq!(format_number(2.5e20), "2.5e20");
        assert_eq!(format_number(f64::NAN), "");
        assert_eq!(format_number(f64::INFINITY), "");
        let x = 0.1 + 0.2;
        assert_eq!(format_number(x).parse::<f64>().unwrap(), x);
    }

    #[test]
    fn text_is_quoted_when_needed() {
        let row = format_row(&[
            Cell::from("plain"),
            Cell::from("a, b"),
            Cell::from("say \"hi\"\nthere"),
            Cell::Empty,
            Cell::from(3usize),
            Cell::from(Some(f64::NAN)),
        ]);
        assert_eq!(row, "plain,\"a, b\",\"say \"\"hi\"\" there\",,3,\n");
    }
}
