//! Time tables: a column of times [s] and columns of values, read from a text file (CSV
//! with or without a header, or whitespace separated; `#` starts a comment). Scenario files
//! drive moving supports, platforms and loads from them (`motion_table`, `force_table`,
//! docs/scenario.md "Motion and force tables"); the interpolation is the core's
//! [`phstring::Sampled`] (docs/method.md §14).

use std::fmt;
use std::path::{Path, PathBuf};

use phstring::Sampled;

use crate::text::{clip, num};

/// Largest table file read [bytes] (64 MiB: a three-hour record at 20 Hz with seven columns
/// is about 20 MiB). Reading stops there, so a huge file is refused instead of read forever.
pub const MAX_TABLE_BYTES: u64 = 64 << 20;

/// A table as read: rows of `columns` numbers, the first column the time [s], strictly
/// increasing, every entry finite, at least two rows.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// The file, for messages.
    pub path: PathBuf,
    /// The times [s], one per row.
    pub times: Vec<f64>,
    /// The other columns, each with one value per row (`values[j][i]`: column `j + 2` of
    /// row `i`, in the file's units).
    pub values: Vec<Vec<f64>>,
    /// The 1-based line of the file that each row is on.
    pub lines: Vec<usize>,
    /// The header's fields (the first line with data, when its first field is not a
    /// number); empty without a header.
    pub header: Vec<String>,
}

impl Table {
    /// Column `j` after the time (0: the second column of the file) as a C¹ signal of time.
    /// Panics if `j` is not below the number of value columns.
    pub fn signal(&self, j: usize) -> Sampled {
        // The rows were checked when the table was read (finite, increasing, two or more).
        Sampled::new(self.times.clone(), self.values[j].clone())
            .unwrap_or_else(|e| unreachable!("checked table: {e}"))
    }

    /// The platform path of a table of the seven columns `t, x, y, z, roll, pitch, yaw`
    /// (`[[platform]]`, `--motion`); `None` for another number of columns.
    pub fn platform(&self) -> Option<phstring::PlatformPath> {
        (self.values.len() == 6)
            .then(|| phstring::PlatformPath::new(std::array::from_fn(|j| self.signal(j))))
    }

    /// `path:line` of row `i`, for messages.
    pub fn at_row(&self, i: usize) -> String {
        format!("{}:{}", self.path.display(), self.lines[i])
    }

    /// The row whose time is nearest to `t` [s] (for messages about a time).
    pub fn row_near(&self, t: f64) -> usize {
        let after = self.times.partition_point(|&s| s < t);
        match after {
            0 => 0,
            n if n == self.times.len() => n - 1,
            n if (self.times[n] - t) < (t - self.times[n - 1]) => n,
            n => n - 1,
        }
    }
}

/// What is wrong with a table file.
#[derive(Debug, thiserror::Error)]
pub enum TableError {
    /// The file cannot be read.
    #[error("cannot read table {}: {cause}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        cause: std::io::Error,
    },
    /// The file is larger than [`MAX_TABLE_BYTES`] or not UTF-8 text.
    #[error("table {}: {what}", path.display())]
    NotText {
        /// The file.
        path: PathBuf,
        /// Why.
        what: String,
    },
    /// A line of the file that is not a valid row.
    #[error("{}:{line}: {what}", path.display())]
    Row {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong, with the bad value.
        what: RowError,
    },
    /// Fewer than two rows of data.
    #[error("table {}: has {rows} rows of data, at least 2 are needed (time in the first column, then {} more)", path.display(), columns - 1)]
    TooFew {
        /// The file.
        path: PathBuf,
        /// Rows found.
        rows: usize,
        /// Columns expected.
        columns: usize,
    },
}

/// What is wrong with one line of a table.
#[derive(Debug, Clone, PartialEq)]
pub enum RowError {
    /// Another number of fields than the table has columns.
    Columns {
        /// Fields on the line.
        got: usize,
        /// Columns expected.
        want: usize,
        /// The line is one field that holds a `;` (a table separated by semicolons).
        semicolons: bool,
    },
    /// A field that is not a number (after the header line).
    NotANumber {
        /// 1-based column.
        column: usize,
        /// The field.
        field: String,
    },
    /// A number that is NaN or infinite.
    NotFinite {
        /// 1-based column.
        column: usize,
        /// The field.
        field: String,
    },
    /// A time not after the previous row's.
    NotIncreasing {
        /// The time [s].
        time: f64,
        /// The previous row's time [s].
        previous: f64,
        /// The previous row's line.
        previous_line: usize,
    },
}

impl fmt::Display for RowError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Columns {
                got,
                want,
                semicolons,
            } => write!(
                f,
                "has {got} columns, the table needs {want} (time, then {}){}",
                want - 1,
                if *semicolons {
                    "; `;` is not a separator: separate the columns by commas, spaces or tabs"
                } else {
                    ""
                }
            ),
            Self::NotANumber { column, field } => {
                write!(f, "column {column} \"{}\" is not a number", clip(field))
            }
            Self::NotFinite { column, field } => {
                write!(f, "column {column} is {}, not a finite number", clip(field))
            }
            Self::NotIncreasing {
                time,
                previous,
                previous_line,
            } => write!(
                f,
                "time {} s is not after {} s (line {previous_line}): times must increase strictly",
                num(*time),
                num(*previous)
            ),
        }
    }
}

/// Reads the table at `path` with `columns` columns (the time and `columns − 1` values).
pub fn read_table(path: &Path, columns: usize) -> Result<Table, TableError> {
    parse_table(&read_text(path)?, path, columns)
}

/// Reads the table at `path` with as many columns as its first line with data has (at
/// least two: the time and one value).
pub fn read_table_any(path: &Path) -> Result<Table, TableError> {
    let text = read_text(path)?;
    let columns = text.lines().find_map(fields).map_or(2, |f| f.len().max(2));
    parse_table(&text, path, columns)
}

/// The text of the table file at `path` (at most [`MAX_TABLE_BYTES`], UTF-8).
fn read_text(path: &Path) -> Result<String, TableError> {
    use std::io::Read as _;
    let read_err = |cause| TableError::Read {
        path: path.to_path_buf(),
        cause,
    };
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .map_err(read_err)?
        .take(MAX_TABLE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(read_err)?;
    let not_text = |what: String| TableError::NotText {
        path: path.to_path_buf(),
        what,
    };
    if bytes.len() as u64 > MAX_TABLE_BYTES {
        return Err(not_text(format!(
            "is larger than {} MiB",
            MAX_TABLE_BYTES >> 20
        )));
    }
    let text = String::from_utf8(bytes).map_err(|e| {
        not_text(format!(
            "is not UTF-8 text (byte {})",
            e.utf8_error().valid_up_to()
        ))
    })?;
    Ok(text)
}

/// The fields of a line without its comment: comma separated if it has a comma, else
/// whitespace separated. `None` for a line with nothing but a comment or blanks.
fn fields(line: &str) -> Option<Vec<&str>> {
    let data = line.split('#').next().unwrap_or("").trim();
    if data.is_empty() {
        return None;
    }
    Some(if data.contains(',') {
        data.split(',').map(str::trim).collect()
    } else {
        data.split_whitespace().collect()
    })
}

/// Parses the text of a table file (`path` for messages) with `columns` columns. The first
/// line with data is a header (skipped) if its first field is not a number.
pub fn parse_table(text: &str, path: &Path, columns: usize) -> Result<Table, TableError> {
    let row_err = |line: usize, what: RowError| TableError::Row {
        path: path.to_path_buf(),
        line,
        what,
    };
    let mut table = Table {
        path: path.to_path_buf(),
        times: Vec::new(),
        values: vec![Vec::new(); columns.saturating_sub(1)],
        lines: Vec::new(),
        header: Vec::new(),
    };
    let mut first = true;
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let Some(f) = fields(raw) else { continue };
        let is_header = first && f[0].parse::<f64>().is_err();
        first = false;
        if f.len() != columns {
            return Err(row_err(
                line,
                RowError::Columns {
                    got: f.len(),
                    want: columns,
                    semicolons: f.len() == 1 && f[0].contains(';'),
                },
            ));
        }
        if is_header {
            table.header = f.iter().map(|x| x.to_string()).collect();
            continue;
        }
        let mut row = Vec::with_capacity(columns);
        for (j, field) in f.iter().enumerate() {
            let (column, field) = (j + 1, field.to_string());
            match field.parse::<f64>() {
                Ok(x) if x.is_finite() => row.push(x),
                Ok(_) => return Err(row_err(line, RowError::NotFinite { column, field })),
                Err(_) => return Err(row_err(line, RowError::NotANumber { column, field })),
            }
        }
        if let (Some(&previous), Some(&previous_line)) = (table.times.last(), table.lines.last())
            && row[0] <= previous
        {
            return Err(row_err(
                line,
                RowError::NotIncreasing {
                    time: row[0],
                    previous,
                    previous_line,
                },
            ));
        }
        table.times.push(row[0]);
        for (col, &x) in table.values.iter_mut().zip(&row[1..]) {
            col.push(x);
        }
        table.lines.push(line);
    }
    if table.times.len() < 2 {
        return Err(TableError::TooFew {
            path: path.to_path_buf(),
            rows: table.times.len(),
            columns,
        });
    }
    Ok(table)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str, columns: usize) -> Result<Table, TableError> {
        parse_table(text, Path::new("m.csv"), columns)
    }

    fn message(text: &str, columns: usize) -> String {
        parse(text, columns).unwrap_err().to_string()
    }

    #[test]
    fn reads_csv_with_header_and_comments_and_whitespace_tables() {
        let csv = "# surge and heave of the fairlead\n\nt, x, z\n-1.0, 100.0, -10\n0, 100.5, -10.25 # at rest\n2.5e0,101,-10\n";
        let t = parse(csv, 3).unwrap();
        assert_eq!(t.times, vec![-1.0, 0.0, 2.5]);
        assert_eq!(
            t.values,
            vec![vec![100.0, 100.5, 101.0], vec![-10.0, -10.25, -10.0]]
        );
        assert_eq!(t.lines, vec![4, 5, 6]);
        assert_eq!(t.at_row(1), "m.csv:5");
        let ws = "0.0   1.0\t2.0\n  1.0 3.0 4.0\n";
        let w = parse(ws, 3).unwrap();
        assert_eq!(w.values, vec![vec![1.0, 3.0], vec![2.0, 4.0]]);
        assert_eq!(w.row_near(0.4), 0);
        assert_eq!(w.row_near(0.6), 1);
    }

    #[test]
    fn refuses_bad_rows_naming_the_line_and_value() {
        assert_eq!(
            message("0, 1, 2\n1, 2\n", 3),
            "m.csv:2: has 2 columns, the table needs 3 (time, then 2)"
        );
        // A table written with semicolons (a spreadsheet's CSV in some locales) is one
        // column per line: the message says `;` is not a separator.
        assert_eq!(
            message("t;x\n0;1\n1;2\n", 2),
            "m.csv:1: has 1 columns, the table needs 2 (time, then 1); `;` is not a separator: separate the columns by commas, spaces or tabs"
        );
        assert_eq!(
            message("0 1;2\n", 3),
            "m.csv:1: has 2 columns, the table needs 3 (time, then 2)"
        );
        assert_eq!(
            message("t x\n0 1\n1 abc\n", 2),
            "m.csv:3: column 2 \"abc\" is not a number"
        );
        assert_eq!(
            message("0 1\n1 NaN\n", 2),
            "m.csv:2: column 2 is NaN, not a finite number"
        );
        assert_eq!(
            message("0 1\n# gap\n2 1\n2 5\n", 2),
            "m.csv:4: time 2 s is not after 2 s (line 3): times must increase strictly"
        );
        assert_eq!(
            message("0 1\n-1 5\n", 2),
            "m.csv:2: time -1 s is not after 0 s (line 1): times must increase strictly"
        );
        assert_eq!(
            message("t, x\n0, 1\n", 2),
            "table m.csv: has 1 rows of data, at least 2 are needed (time in the first column, then 1 more)"
        );
        assert_eq!(
            message("time surge heave\n0 1\n", 2),
            "m.csv:1: has 3 columns, the table needs 2 (time, then 1)"
        );
        assert_eq!(
            message("0, 1,\n1, 2, \n", 2),
            "m.csv:1: has 3 columns, the table needs 2 (time, then 1)"
        );
    }

    #[test]
    fn read_table_names_a_missing_file() {
        let e = read_table(Path::new("/nonexistent/surge.csv"), 2).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("cannot read table /nonexistent/surge.csv: "),
            "{e}"
        );
    }

    #[test]
    fn signal_interpolates_a_column() {
        let t = parse("0 0 10\n1 1 10\n2 4 10\n", 3).unwrap();
        let x = t.signal(0);
        // x = t² is reproduced exactly (quadratic), z = 10 constant.
        assert!((x.value(1.5) - 2.25).abs() < 1e-15);
        assert!((x.rate(1.5) - 3.0).abs() < 1e-15);
        assert_eq!(t.signal(1).value(0.7), 10.0);
    }
}
