//! A table of runs: named columns read from CSV (a sweep's `results.csv`, a study's table).
//!
//! Cells stay text until a column is asked for as numbers, so that an error can name the
//! line and the column of the cell that is wrong.

use super::RsmError;
use std::path::Path;

/// Rows of named columns.
#[derive(Debug, Clone)]
pub struct Table {
    /// Where it came from (file name), for messages.
    pub source: String,
    pub names: Vec<String>,
    /// Cells as text, row by row.
    pub rows: Vec<Vec<String>>,
    /// The line of each row in the file (1 is the header).
    pub lines: Vec<usize>,
}

impl Table {
    /// Reads a CSV file with a header row.
    pub fn read(path: impl AsRef<Path>) -> Result<Table, RsmError> {
        let path = path.as_ref();
        let file = path.display().to_string();
        let err = |cause: String| RsmError::Read {
            file: file.clone(),
            cause,
        };
        let mut reader = csv::ReaderBuilder::new()
            .trim(csv::Trim::All)
            .comment(Some(b'#'))
            .from_path(path)
            .map_err(|e| err(e.to_string()))?;
        let names: Vec<String> = reader
            .headers()
            .map_err(|e| err(e.to_string()))?
            .iter()
            .map(str::to_string)
            .collect();
        let mut rows = Vec::new();
        let mut lines = Vec::new();
        for record in reader.records() {
            let record = record.map_err(|e| err(e.to_string()))?;
            lines.push(record.position().map_or(0, |p| p.line() as usize));
            rows.push(record.iter().map(str::to_string).collect());
        }
        Ok(Table {
            source: file,
            names,
            rows,
            lines,
        })
    }

    /// A table from numeric columns (rows without gaps), for code that has its data already.
    pub fn from_columns(source: &str, columns: &[(&str, Vec<f64>)]) -> Table {
        let n = columns.first().map_or(0, |c| c.1.len());
        Table {
            source: source.to_string(),
            names: columns.iter().map(|c| c.0.to_string()).collect(),
            rows: (0..n)
                .map(|r| columns.iter().map(|c| format!("{:?}", c.1[r])).collect())
                .collect(),
            lines: (2..n + 2).collect(),
        }
    }

    /// Index of column `name`.
    pub fn column(&self, name: &str) -> Result<usize, RsmError> {
        self.names
            .iter()
            .position(|n| n == name)
            .ok_or_else(|| RsmError::NoColumn {
                file: self.source.clone(),
                name: name.to_string(),
                available: self.names.join(", "),
            })
    }

    /// Column `name` as numbers; an empty or non-numeric cell is an error naming its line.
    pub fn numbers(&self, name: &str) -> Result<Vec<f64>, RsmError> {
        let c = self.column(name)?;
        self.rows
            .iter()
            .zip(&self.lines)
            .map(|(row, &line)| {
                let cell = row.get(c).map_or("", String::as_str);
                if cell.is_empty() || cell.eq_ignore_ascii_case("na") || cell == "-" {
                    return Err(RsmError::Missing {
                        file: self.source.clone(),
                        line,
                        column: name.to_string(),
                    });
                }
                cell.parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| RsmError::NotNumber {
                        file: self.source.clone(),
                        line,
                        column: name.to_string(),
                        value: cell.to_string(),
                    })
            })
            .collect()
    }

    /// Text of column `name` (for filters such as a condition column).
    pub fn text(&self, name: &str) -> Result<Vec<String>, RsmError> {
        let c = self.column(name)?;
        Ok(self
            .rows
            .iter()
            .map(|r| r.get(c).cloned().unwrap_or_default())
            .collect())
    }

    /// The rows where `keep` is true.
    pub fn filter(&self, keep: &[bool]) -> Table {
        let pick = |k: usize| keep.get(k).copied().unwrap_or(false);
        Table {
            source: self.source.clone(),
            names: self.names.clone(),
            rows: (0..self.rows.len())
                .filter(|&k| pick(k))
                .map(|k| self.rows[k].clone())
                .collect(),
            lines: (0..self.rows.len())
                .filter(|&k| pick(k))
                .map(|k| self.lines[k])
                .collect(),
        }
    }
}
