//! CSV histories (a header line, then one row of numbers per record), for
//! time histories of a solve and pose histories of a labour run, and a
//! reader for such tables (through the `csv` crate: quoted cells, CRLF
//! line ends and a byte-order mark, as spreadsheets write them).
//! Numbers are written in Rust's shortest exact form, so reading a file
//! back gives the same `f64` bit for bit.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::error::{ReadError, WriteError};

/// Writes a CSV file row by row; rows must match the header's width.
pub struct CsvWriter {
    path: PathBuf,
    columns: usize,
    /// None once a write failed: the rows not written are dropped, never
    /// written later behind a cut (see [`CsvWriter::failed`]).
    out: Option<BufWriter<File>>,
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
            out: Some(BufWriter::new(file)),
        };
        let line = header.join(",");
        writer.write_line(&line)?;
        Ok(writer)
    }

    /// One write per line, so that the buffer goes to the file in whole
    /// lines and a full disk never leaves half a row.
    fn write_line(&mut self, line: &str) -> Result<(), WriteError> {
        let Some(out) = self.out.as_mut() else {
            return Err(self.stopped());
        };
        let written = out.write_all(format!("{line}\n").as_bytes());
        written.map_err(|cause| self.failed(cause))
    }

    /// The error of a write that failed, after cutting the file back to its
    /// last whole line: a full disk can take part of a buffer, and a table
    /// that ends in half a row would be read as a wrong number. The rows
    /// still buffered are dropped with the writer, so that no later flush
    /// (nor the drop) writes them behind the cut.
    fn failed(&mut self, cause: std::io::Error) -> WriteError {
        if let Some(out) = self.out.take() {
            let (file, _unwritten) = out.into_parts();
            if let Ok(text) = std::fs::read(&self.path) {
                let whole = text.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
                if whole < text.len() {
                    let _ = file.set_len(whole as u64);
                }
            }
        }
        WriteError::Io { path: self.path.clone(), cause }
    }

    /// The error of a write after one failed.
    fn stopped(&self) -> WriteError {
        let cause = std::io::Error::other("an earlier write to it failed; the rows before that are kept");
        WriteError::Io { path: self.path.clone(), cause }
    }

    /// Appends one row; a NaN is a value not recorded (no trunk, a spine
    /// that does not bend) and is written as an empty cell, which
    /// spreadsheets and data frames read as missing.
    pub fn row(&mut self, values: &[f64]) -> Result<(), WriteError> {
        self.row_with_labels(values, &[])
    }

    /// Appends one row of numbers followed by text labels (names such as
    /// `pelvic_floor`, without commas, quotes or line breaks; an empty label
    /// is a missing value).
    pub fn row_with_labels(&mut self, values: &[f64], labels: &[&str]) -> Result<(), WriteError> {
        let shape_error = |problem: String| WriteError::Shape {
            path: self.path.clone(),
            problem,
        };
        if values.len() + labels.len() != self.columns {
            return Err(shape_error(format!(
                "a row of {} values under a header of {} columns",
                values.len() + labels.len(),
                self.columns
            )));
        }
        if let Some(bad) = labels.iter().find(|l| l.contains([',', '"', '\n', '\r'])) {
            return Err(shape_error(format!("label {bad:?} holds a comma, quote or line break")));
        }
        // Debug is the shortest exact form, with an exponent for tiny or huge values.
        let line = values
            .iter()
            .map(|v| if v.is_nan() { String::new() } else { format!("{v:?}") })
            .chain(labels.iter().map(|l| l.to_string()))
            .collect::<Vec<_>>()
            .join(",");
        self.write_line(&line)
    }

    /// Flushes what is buffered to the file (done on drop too, but without
    /// a chance to see the error).
    pub fn flush(&mut self) -> Result<(), WriteError> {
        let Some(out) = self.out.as_mut() else {
            return Err(self.stopped());
        };
        let flushed = out.flush();
        flushed.map_err(|cause| self.failed(cause))
    }
}

/// A CSV file read whole: its column names and its data rows, every cell
/// trimmed.
#[derive(Debug, Clone, PartialEq)]
pub struct CsvTable {
    /// The file, for errors.
    pub path: PathBuf,
    pub header: Vec<String>,
    pub rows: Vec<CsvRow>,
}

/// One data row and the line it starts on (1-based, the header is line 1).
#[derive(Debug, Clone, PartialEq)]
pub struct CsvRow {
    pub line: usize,
    pub cells: Vec<String>,
}

impl CsvTable {
    /// Reads `path` (bounded as every user file is: [`crate::input`]).
    pub fn read(path: &Path) -> Result<Self, ReadError> {
        let bytes = crate::input::read_bytes(path).map_err(|cause| ReadError::Io {
            path: path.to_path_buf(),
            cause,
        })?;
        Self::parse(path, &bytes)
    }

    /// Parses CSV bytes; `path` only names the file in errors. A row of
    /// another width than the header is refused at its line; blank lines
    /// are skipped.
    pub fn parse(path: &Path, bytes: &[u8]) -> Result<Self, ReadError> {
        let syntax = |line: usize, problem: String, fix: &str| ReadError::Syntax {
            path: path.to_path_buf(),
            line,
            problem,
            fix: fix.to_string(),
        };
        let mut reader = ::csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .trim(::csv::Trim::All)
            .comment(Some(b'#'))
            .from_reader(bytes);
        let mut header: Option<Vec<String>> = None;
        let mut rows = Vec::new();
        let mut lines = LineCounter::new(bytes);
        for record in reader.records() {
            let record = record.map_err(|e| {
                let line = e.position().map_or(0, |p| lines.line_of_record(p.byte() as usize));
                syntax(line, format!("not readable as CSV ({e})"), "save the table as CSV in UTF-8")
            })?;
            let line = record.position().map_or(0, |p| lines.line_of_record(p.byte() as usize));
            let cells: Vec<String> = record.iter().map(str::to_string).collect();
            match &header {
                None => {
                    check_header(&cells).map_err(|(problem, fix)| syntax(line, problem, fix))?;
                    header = Some(cells);
                }
                Some(names) => {
                    if cells.len() != names.len() {
                        return Err(syntax(
                            line,
                            format!("the row has {} cells under a header of {} columns", cells.len(), names.len()),
                            "give every row one cell per column (an empty cell for a missing value)",
                        ));
                    }
                    rows.push(CsvRow { line, cells });
                }
            }
        }
        let Some(header) = header else {
            return Err(ReadError::Content {
                path: path.to_path_buf(),
                problem: "the file is empty".into(),
                fix: "give a header line of column names, then one row per sample".into(),
            });
        };
        Ok(CsvTable {
            path: path.to_path_buf(),
            header,
            rows,
        })
    }

    /// The index of the column named `name`, in any case (`TIME_S` for
    /// `time_s`; the header names each column once in any case).
    pub fn column(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h.eq_ignore_ascii_case(name))
    }

    /// The number in `column` of `row`: `None` for an empty cell, an error
    /// naming the line and the column for anything that is not a finite
    /// number.
    pub fn number(&self, row: &CsvRow, column: usize) -> Result<Option<f64>, ReadError> {
        let cell = &row.cells[column];
        if cell.is_empty() {
            return Ok(None);
        }
        match cell.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(Some(x)),
            parsed => Err(ReadError::Syntax {
                path: self.path.clone(),
                line: row.line,
                problem: format!(
                    "`{}` = {cell:?} is not {}",
                    self.header[column],
                    if parsed.is_ok() { "a finite number" } else { "a number" }
                ),
                fix: "write a finite number (a decimal point, not a comma)".into(),
            }),
        }
    }
}

/// A row of numbers with `None` (a value not recorded) as NaN, which
/// [`CsvWriter::row`] writes as an empty cell.
pub fn missing_as_nan(values: &[Option<f64>]) -> Vec<f64> {
    values.iter().map(|v| v.unwrap_or(f64::NAN)).collect()
}

/// The 1-based line a record starts on, from the byte where the csv crate
/// says it starts: that byte can be the `\n` left of the row before's
/// `\r\n`, or a blank or `#` line the reader skipped (the crate's line
/// count is off in both cases). Counted forwards, as records come in order.
struct LineCounter<'a> {
    bytes: &'a [u8],
    at: usize,
    line: usize,
}

impl<'a> LineCounter<'a> {
    fn new(bytes: &'a [u8]) -> Self {
        LineCounter { bytes, at: 0, line: 1 }
    }

    fn line_of_record(&mut self, start: usize) -> usize {
        let start = start.min(self.bytes.len());
        if start >= self.at {
            self.line += self.bytes[self.at..start].iter().filter(|&&b| b == b'\n').count();
            self.at = start;
        }
        // Past line ends and skipped lines to the record's first byte.
        let (mut line, mut at) = (self.line, self.at);
        loop {
            match self.bytes.get(at) {
                Some(b'\r') => at += 1,
                Some(b'\n') => {
                    line += 1;
                    at += 1;
                }
                Some(b'#') if at == 0 || self.bytes[at - 1] == b'\n' => {
                    match self.bytes[at..].iter().position(|&b| b == b'\n') {
                        Some(end) => {
                            at += end + 1;
                            line += 1;
                        }
                        None => break,
                    }
                }
                _ => break,
            }
        }
        line
    }
}

/// A header a table can be read by: every column named once, and the
/// commas that separate them. A file of another separator reads as a
/// header of one column; JSON as one whose first cell opens an object or
/// a list (its commas split it into many).
fn check_header(cells: &[String]) -> Result<(), (String, &'static str)> {
    if cells.first().is_some_and(|first| first.trim_start().starts_with(['{', '['])) {
        return Err(("the file is JSON, not CSV".into(), "give a JSON pose history a .json name"));
    }
    if let [only] = cells {
        if let Some(separator) = [';', '\t', '|'].into_iter().find(|c| only.contains(*c)) {
            return Err((
                format!("the columns are separated by {separator:?}, not commas"),
                "save the table as CSV with commas between the columns and decimal points (a spreadsheet's \"CSV (comma delimited)\")",
            ));
        }
    }
    if let Some(empty) = cells.iter().position(String::is_empty) {
        return Err((
            format!("column {} of the header has no name", empty + 1),
            "give every column a name in the first line",
        ));
    }
    for (i, name) in cells.iter().enumerate() {
        if let Some(j) = cells[..i].iter().position(|h| h.eq_ignore_ascii_case(name)) {
            return Err((
                format!("columns {} and {} are both named `{name}`", j + 1, i + 1),
                "name every column once",
            ));
        }
    }
    Ok(())
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
    fn a_written_table_reads_back_with_its_labels() {
        let (_dir, path) = temp("labelled.csv");
        let mut csv = CsvWriter::create(&path, &["time_s", "force_n", "site"]).unwrap();
        csv.row_with_labels(&[0.1, f64::NAN], &["pelvic_floor"]).unwrap();
        csv.row_with_labels(&[0.2, -3.5e-9], &[""]).unwrap();
        assert!(csv.row_with_labels(&[0.3, 1.0], &["a,b"]).is_err());
        csv.flush().unwrap();
        let table = CsvTable::read(&path).unwrap();
        assert_eq!(table.header, ["time_s", "force_n", "site"]);
        assert_eq!(table.rows.len(), 2);
        let force = table.column("force_n").unwrap();
        assert_eq!(table.number(&table.rows[0], force).unwrap(), None);
        assert_eq!(table.number(&table.rows[1], force).unwrap(), Some(-3.5e-9));
        assert_eq!(table.rows[0].cells[2], "pelvic_floor");
        assert_eq!(table.rows[1].line, 3);
    }

    /// What spreadsheets write: a byte-order mark, quoted names, CRLF,
    /// spaces, a blank last line.
    #[test]
    fn spreadsheet_csv_is_read_and_bad_cells_are_named() {
        let text = "\u{feff}\"time_s\", x_mm\r\n0, 1.5\r\n0.5,\r\n\r\n";
        let table = CsvTable::parse(Path::new("sheet.csv"), text.as_bytes()).unwrap();
        assert_eq!(table.header, ["time_s", "x_mm"]);
        assert_eq!(table.number(&table.rows[0], 1).unwrap(), Some(1.5));
        assert_eq!(table.number(&table.rows[1], 1).unwrap(), None);

        let comma = CsvTable::parse(Path::new("sheet.csv"), b"t,x\n0,1\n1,\"2,5\"\n").unwrap();
        let e = comma.number(&comma.rows[1], 1).unwrap_err().to_string();
        assert!(e.starts_with("sheet.csv:3: `x` = \"2,5\" is not a number"), "{e}");
        let ragged = CsvTable::parse(Path::new("r.csv"), b"t,x\n0,1\n1\n").unwrap_err().to_string();
        assert!(ragged.starts_with("r.csv:3: the row has 1 cells under a header of 2 columns"), "{ragged}");
        let unnamed = CsvTable::parse(Path::new("u.csv"), b"t,,x\n").unwrap_err().to_string();
        assert!(unnamed.contains("column 2 of the header has no name"), "{unnamed}");
        assert!(CsvTable::parse(Path::new("e.csv"), b"").is_err());
    }

    /// Lines are counted as an editor shows them, whatever the line ends,
    /// blank lines and comments before a row.
    #[test]
    fn errors_name_the_line_an_editor_shows() {
        for text in [
            "t,x\n0,1\n1,a\n",
            "t,x\r\n0,1\r\n1,a\r\n",
            "# note\nt,x\n\n1,a\n",
            "\u{feff}t,x\r\n# two\r\n# comments\r\n1,a\r\n",
        ] {
            let table = CsvTable::parse(Path::new("t.csv"), text.as_bytes()).unwrap();
            let row = table.rows.last().unwrap();
            let expected = text.trim_start_matches('\u{feff}').lines().position(|l| l.starts_with("1,a")).unwrap() + 1;
            assert_eq!(row.line, expected, "{text:?}");
            let e = table.number(row, 1).unwrap_err().to_string();
            assert!(e.starts_with(&format!("t.csv:{expected}:")), "{e}");
        }
        let ragged = CsvTable::parse(Path::new("r.csv"), b"t,x\r\n0,1\r\n1\r\n").unwrap_err().to_string();
        assert!(ragged.starts_with("r.csv:3:"), "{ragged}");
        let unnamed = CsvTable::parse(Path::new("u.csv"), b"# a\n# b\nt,,x\n").unwrap_err().to_string();
        assert!(unnamed.starts_with("u.csv:3:"), "{unnamed}");
    }

    #[test]
    fn headers_of_other_files_and_repeated_names_are_named() {
        let refused = |text: &str| CsvTable::parse(Path::new("t.csv"), text.as_bytes()).unwrap_err().to_string();
        assert!(refused("time_s;x_mm\n0;1,5\n").contains("separated by ';'"));
        assert!(refused("time_s\tx_mm\n0\t1\n").contains("separated by '\\t'"));
        assert!(refused("{\"head\": 1}\n").contains("the file is JSON"));
        // A JSON object of many keys on one line, as carus writes its pose history.
        assert!(refused("{\"canal\":{\"normal\":[0.0,1.0,0.0]},\"samples\":[]}\n").contains("the file is JSON"));
        assert!(refused("t,x,T\n").contains("columns 1 and 3 are both named `T`"));
        let table = CsvTable::parse(Path::new("t.csv"), b"# from the tracker\nTIME_S,x\n1,inf\n").unwrap();
        assert_eq!(table.column("time_s"), Some(0));
        let e = table.number(&table.rows[0], 1).unwrap_err().to_string();
        assert!(e.contains("`x` = \"inf\" is not a finite number"), "{e}");
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
