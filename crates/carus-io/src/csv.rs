//! CSV histories (a header line, then one row of numbers per record), for
//! time histories of a solve and, later, pose histories of a labour run.
//! Numbers are written in Rust's shortest exact form, so reading a file
//! back gives the same `f64` bit for bit.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::error::WriteError;

/// Writes a CSV file row by row; rows must match the header's width.
pub struct CsvWriter {
    path: PathBuf,
    columns: usize,
    out: BufWriter<File>,
}

impl CsvWriter {
    /// Creates `path` and writes the header (column names without commas,
    /// quotes or line breaks, such as `time_s`).
    pub fn create(path: &Path, header: &[&str]) -> Result<Self, WriteError> {
        if let Some(bad) = header
            .iter()
            .find(|h| h.is_empty() || h.contains([',', '"', '\n', '\r']))
        {
            return Err(WriteError::Shape {
                path: path.to_path_buf(),
                problem: format!(
                    "column name {bad:?} is empty or holds a comma, quote or line break"
                ),
            });
        }
        let file = File::create(path).map_err(|cause| WriteError::Io {
            path: path.to_path_buf(),
            cause,
        })?;
        let mut writer = CsvWriter {
            path: path.to_path_buf(),
            columns: header.len(),
            out: BufWriter::new(file),
        };
        let line = header.join(",");
        writer.write_line(&line)?;
        Ok(writer)
    }

    fn write_line(&mut self, line: &str) -> Result<(), WriteError> {
        writeln!(self.out, "{line}").map_err(|cause| WriteError::Io {
            path: self.path.clone(),
            cause,
        })
    }

    /// Appends one row; a NaN is a value not recorded (no trunk, a spine
    /// that does not bend) and is written as an empty cell, which
    /// spreadsheets and data frames read as missing.
    pub fn row(&mut self, values: &[f64]) -> Result<(), WriteError> {
        if values.len() != self.columns {
            return Err(WriteError::Shape {
                path: self.path.clone(),
                problem: format!(
                    "a row of {} values under a header of {} columns",
                    values.len(),
                    self.columns
                ),
            });
        }
        // Debug is the shortest exact form, with an exponent for tiny or huge values.
        let line = values
            .iter()
            .map(|v| if v.is_nan() { String::new() } else { format!("{v:?}") })
            .collect::<Vec<_>>()
            .join(",");
        self.write_line(&line)
    }

    /// Flushes what is buffered to the file (done on drop too, but without
    /// a chance to see the error).
    pub fn flush(&mut self) -> Result<(), WriteError> {
        self.out.flush().map_err(|cause| WriteError::Io {
            path: self.path.clone(),
            cause,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::temp;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]
        #[test]
        fn rows_read_back_bit_for_bit(rows in proptest::collection::vec(proptest::array::uniform3(any::<f64>()), 0..20)) {
            let (_dir, path) = temp("history.csv");
            let mut csv = CsvWriter::create(&path, &["time_s", "reaction_x_n", "kinetic_j"]).unwrap();
            for row in &rows {
                csv.row(row).unwrap();
            }
            csv.flush().unwrap();
            let text = std::fs::read_to_string(&path).unwrap();
            let mut lines = text.lines();
            prop_assert_eq!(lines.next(), Some("time_s,reaction_x_n,kinetic_j"));
            for row in &rows {
                let back: Vec<&str> = lines.next().unwrap().split(',').collect();
                prop_assert_eq!(back.len(), 3);
                for (a, b) in row.iter().zip(&back) {
                    match a.is_nan() {
                        true => prop_assert_eq!(*b, ""),
                        false => prop_assert_eq!(a.to_bits(), b.parse::<f64>().unwrap().to_bits()),
                    }
                }
            }
            prop_assert_eq!(lines.next(), None);
        }
    }

    #[test]
    fn a_value_not_recorded_is_an_empty_cell() {
        let (_dir, path) = temp("gaps.csv");
        let mut csv = CsvWriter::create(&path, &["a", "b", "c"]).unwrap();
        csv.row(&[1.5, f64::NAN, -0.25]).unwrap();
        csv.flush().unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "a,b,c\n1.5,,-0.25\n");
    }

    #[test]
    fn ragged_rows_and_bad_names_are_refused() {
        let (_dir, path) = temp("ragged.csv");
        let mut csv = CsvWriter::create(&path, &["a", "b"]).unwrap();
        let err = csv.row(&[1.0]).unwrap_err().to_string();
        assert!(
            err.contains("a row of 1 values under a header of 2 columns"),
            "{err}"
        );
        assert!(CsvWriter::create(&path, &["a,b"]).is_err());
    }
}
