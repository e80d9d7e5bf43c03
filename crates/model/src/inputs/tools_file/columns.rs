//! Tools held in memory as columns (a pandas DataFrame's, a dict of arrays', a NumPy structured
//! array's), read row by row through the same checks as a tools file ([`read_columns`]).
//!
//! A column is a tools file's column: `name`, `model` and the models' parameters. A cell is
//! empty, as a CSV cell is, when it is missing (NaN, None) or empty text; text is trimmed as the
//! CSV reader trims it. So a frame written to CSV and read back gives the same tools and the
//! same messages, with `row N` (the tool's 1-based position) where a file says `line N`.

use super::{build_row, check_keys, present_keys, Cell, ToolFileError, ToolRow};

/// One column of tools in memory.
#[derive(Debug, Clone, PartialEq)]
pub enum Column {
    /// Numbers; NaN is an empty cell (pandas' and NumPy's missing value).
    Numbers(Vec<f64>),
    /// Cells of any kind, as an object column holds them.
    Cells(Vec<MemoryCell>),
}

impl Column {
    pub fn len(&self) -> usize {
        match self {
            Column::Numbers(v) => v.len(),
            Column::Cells(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn cell(&self, i: usize) -> Cell<'_> {
        match self {
            Column::Numbers(v) if v[i].is_nan() => Cell::Absent,
            Column::Numbers(v) => Cell::Number(v[i]),
            Column::Cells(v) => match &v[i] {
                MemoryCell::Empty => Cell::Absent,
                MemoryCell::Number(x) if x.is_nan() => Cell::Absent,
                MemoryCell::Number(x) => Cell::Number(*x),
                MemoryCell::Text(t) if t.trim().is_empty() => Cell::Absent,
                MemoryCell::Text(t) => Cell::Text(t.trim()),
                MemoryCell::Other(shown) => Cell::Other(shown.clone()),
            },
        }
    }
}

/// One cell of an object column.
#[derive(Debug, Clone, PartialEq)]
pub enum MemoryCell {
    Empty,
    Text(String),
    Number(f64),
    /// Anything else, as the caller shows it in an error (a list, a date, a bool ...).
    Other(String),
}

/// Hands every row of `columns` (name and cells, every column as long) to `each`, in order, as
/// [`read_tools`](super::read_tools) hands a file's: the same checks and messages, placed at
/// `row N` with N counted from `first_row` (1 for a whole table; a later block of a larger
/// table gives its first row's number, so that every row keeps its place in the whole).
/// `source` names the table in errors (`tools DataFrame, row 7: m2 = 'heavy' is not a number`).
/// Returns the number of rows; columns of different lengths or an unknown column are an error
/// before any row, and a table without rows is an error.
pub fn read_columns(
    source: &str,
    columns: &[(String, Column)],
    first_row: usize,
    mut each: impl FnMut(Result<ToolRow, ToolFileError>) -> Result<(), ToolFileError>,
) -> Result<usize, ToolFileError> {
    let fatal = |message: String| ToolFileError {
        file: source.into(),
        place: String::new(),
        message,
        row_level: false,
    };
    let Some((first_name, first)) = columns.first() else {
        return Err(fatal("no tools: there are no columns".into()));
    };
    let rows = first.len();
    if let Some((name, c)) = columns.iter().find(|(_, c)| c.len() != rows) {
        return Err(fatal(format!(
            "column '{name}' has {} values, column '{first_name}' {rows}: every column needs \
             one value per tool",
            c.len()
        )));
    }
    check_keys(columns.iter().map(|(name, _)| name.as_str()), "column").map_err(fatal)?;
    if rows == 0 {
        return Err(fatal("no tools: the columns have no rows".into()));
    }
    let present = present_keys(|k| columns.iter().any(|(name, _)| name == k));
    for i in 0..rows {
        let row = first_row + i;
        let cell = |key: &str| match columns.iter().find(|(name, _)| name == key) {
            None => Cell::Absent,
            Some((_, column)) => column.cell(i),
        };
        let result = build_row(row, &cell, &present).map_err(|message| ToolFileError {
            file: source.into(),
            place: format!("row {row}"),
            message,
            row_level: true,
        });
        each(result)?;
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::registry::ModelKind;

    fn numbers(name: &str, v: &[f64]) -> (String, Column) {
        (name.into(), Column::Numbers(v.to_vec()))
    }

    fn read(columns: &[(String, Column)], first_row: usize) -> Result<Vec<ToolRow>, String> {
        let mut rows = Vec::new();
        read_columns("tools dict", columns, first_row, |r| {
            rows.push(r?);
            Ok(())
        })
        .map_err(|e| e.to_string())?;
        Ok(rows)
    }

    #[test]
    fn rows_are_numbered_from_the_first_row_and_nan_is_an_empty_cell() {
        let names = Column::Cells(vec![MemoryCell::Text(" three ".into()), MemoryCell::Empty]);
        let models = Column::Cells(vec![
            MemoryCell::Text("arm3".into()),
            MemoryCell::Text(String::new()),
        ]);
        let columns = vec![
            ("name".into(), names),
            ("model".into(), models),
            numbers("m1", &[0.3, 0.3]),
            numbers("m2", &[0.3, 0.4]),
            numbers("m3", &[0.2, f64::NAN]),
            numbers("l1", &[0.3, 0.5]),
            numbers("l2", &[0.3, 0.2]),
            numbers("l3", &[0.2, f64::NAN]),
        ];
        let rows = read(&columns, 41).unwrap();
        assert_eq!(rows[0].row, 41);
        assert_eq!(rows[0].name.as_deref(), Some("three"));
        assert_eq!(rows[0].tool.model(), ModelKind::Arm3);
        assert_eq!((rows[1].row, rows[1].label()), (42, "row 42".to_string()));
        assert_eq!(rows[1].tool.model(), ModelKind::Arm2);
    }

    #[test]
    fn bad_tables_and_rows_are_named_by_column_and_row() {
        let base = || {
            vec![
                numbers("m1", &[0.3, 0.3]),
                numbers("m2", &[0.3, f64::NAN]),
                numbers("l1", &[0.3, 0.3]),
                numbers("l2", &[0.3, 0.3]),
            ]
        };
        assert_eq!(
            read(&base(), 1).unwrap_err(),
            "tools dict, row 2: m2 is missing (model arm2 needs it)"
        );
        let mut text = base();
        text[1].1 = Column::Cells(vec![
            MemoryCell::Number(0.3),
            MemoryCell::Text("heavy".into()),
        ]);
        assert_eq!(
            read(&text, 7).unwrap_err(),
            "tools dict, row 8: m2 = 'heavy' is not a number"
        );
        let mut short = base();
        short[3].1 = Column::Numbers(vec![0.3]);
        assert!(read(&short, 1)
            .unwrap_err()
            .starts_with("tools dict: column 'l2' has 1 values, column 'm1' 2"));
        let mut unknown = base();
        unknown.push(numbers("weight", &[1.0, 1.0]));
        assert!(read(&unknown, 1)
            .unwrap_err()
            .starts_with("tools dict: unknown column 'weight' (known: name, model,"));
        assert_eq!(
            read(&[numbers("m1", &[])], 1).unwrap_err(),
            "tools dict: no tools: the columns have no rows"
        );
    }
}
