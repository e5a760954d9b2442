//! A CSV output file that always ends on a whole record, also when a write fails (a full
//! disk): rows are buffered and written out in whole records where possible, and a failed
//! write cuts the file back to the end of its last whole record, so nothing that was
//! written before is lost and no row is left cut. A record is one row (`energy.csv`) or
//! the rows of one step (`ports.csv`) or of one frame (`positions.csv`).

use std::fs::File;
use std::io::{ErrorKind, Seek, SeekFrom, Write};
use std::path::PathBuf;

use crate::output::OutputError;

/// Bytes buffered before the buffer is written out at the end of a record.
pub(crate) const CSV_BUFFER: usize = 64 << 10;

/// Bytes buffered before the buffer is written out within a record (a frame of
/// `positions.csv` of a large mesh): the memory a file may take.
pub(crate) const CSV_BUFFER_MAX: usize = 16 * CSV_BUFFER;

/// What a CSV file is written to: a file that can be cut back.
pub(crate) trait Sink: Write {
    /// Cuts the file to `len` bytes and continues writing there.
    fn cut(&mut self, len: u64) -> std::io::Result<()>;
}

impl Sink for File {
    fn cut(&mut self, len: u64) -> std::io::Result<()> {
        self.set_len(len)?;
        self.seek(SeekFrom::Start(len)).map(|_| ())
    }
}

/// A CSV file written in whole records (see the module documentation).
pub(crate) struct Csv<F: Sink = File> {
    /// The file (for messages).
    pub path: PathBuf,
    f: F,
    /// Rows not written yet.
    buf: Vec<u8>,
    /// Ends of the whole records in `buf`.
    marks: Vec<usize>,
    /// Bytes in the file.
    disk: u64,
    /// Bytes in the file up to the end of its last whole record.
    whole: u64,
    /// A write failed: the file was cut back to its last whole record and the rows after
    /// it are lost.
    incomplete: bool,
}

impl Csv<File> {
    /// Creates (truncates) the file at `path` and writes `header` as its first record.
    pub fn create(path: PathBuf, header: &str) -> Result<Self, OutputError> {
        let f = File::create(&path).map_err(|cause| OutputError::Io {
            path: path.clone(),
            cause,
        })?;
        let mut c = Self::new(path, f, 0);
        c.row(header)?;
        Ok(c)
    }
}

impl<F: Sink> Csv<F> {
    /// A CSV file `f` (named `path`) of `len` bytes, which end a whole record, written on at
    /// its end.
    pub fn new(path: PathBuf, f: F, len: u64) -> Self {
        Self {
            path,
            f,
            buf: Vec::new(),
            marks: Vec::new(),
            disk: len,
            whole: len,
            incomplete: false,
        }
    }

    /// Adds a row to the current record (ended by [`Self::end_record`]).
    pub fn line(&mut self, s: &str) -> Result<(), OutputError> {
        self.text(s).end_line()
    }

    /// Appends `s` to the row being built (ended by [`Self::end_line`]).
    pub fn text(&mut self, s: &str) -> &mut Self {
        self.buf.extend_from_slice(s.as_bytes());
        self
    }

    /// Appends `,` and `value` (an index, a count, a word) to the row being built.
    pub fn field(&mut self, value: impl std::fmt::Display) -> &mut Self {
        // Writing into a Vec<u8> cannot fail.
        let _ = write!(self.buf, ",{value}");
        self
    }

    /// Appends `x` as [`crate::files::num`] writes it to the row being built.
    pub fn num(&mut self, x: f64) -> &mut Self {
        crate::files::push_num(&mut self.buf, x);
        self
    }

    /// Appends `,x` for each of `xs` to the row being built.
    pub fn nums(&mut self, xs: &[f64]) -> &mut Self {
        for &x in xs {
            self.buf.push(b',');
            crate::files::push_num(&mut self.buf, x);
        }
        self
    }

    /// Ends the row being built: it becomes a line of the current record.
    pub fn end_line(&mut self) -> Result<(), OutputError> {
        self.buf.push(b'\n');
        if self.buf.len() >= CSV_BUFFER_MAX {
            self.write_out()?;
        }
        Ok(())
    }

    /// Ends the current record: the file may be cut back to here.
    pub fn end_record(&mut self) -> Result<(), OutputError> {
        self.marks.push(self.buf.len());
        if self.buf.len() >= CSV_BUFFER {
            self.write_out()?;
        }
        Ok(())
    }

    /// Adds one row as a record of its own.
    pub fn row(&mut self, s: &str) -> Result<(), OutputError> {
        self.line(s)?;
        self.end_record()
    }

    /// Writes out everything buffered.
    pub fn flush(&mut self) -> Result<(), OutputError> {
        self.write_out()?;
        self.f.flush().map_err(|cause| self.fail(cause))
    }

    /// Bytes in the file after a flush (for a checkpoint: they end a whole record when
    /// called between records).
    pub fn len(&mut self) -> Result<u64, OutputError> {
        self.flush()?;
        Ok(self.disk)
    }

    /// Whether a write failed and the file was cut back (rows after its end are lost).
    pub fn is_incomplete(&self) -> bool {
        self.incomplete
    }

    /// Writes the buffer; on a failure, cuts the file back to its last whole record.
    fn write_out(&mut self) -> Result<(), OutputError> {
        let mut done = 0;
        let mut failure = None;
        while done < self.buf.len() {
            match self.f.write(&self.buf[done..]) {
                Ok(0) => {
                    failure = Some(std::io::Error::from(ErrorKind::WriteZero));
                    break;
                }
                Ok(n) => done += n,
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => {
                    failure = Some(e);
                    break;
                }
            }
        }
        if let Some(&m) = self.marks.iter().rev().find(|&&m| m <= done) {
            self.whole = self.disk + m as u64;
        }
        self.disk += done as u64;
        // A partial record at the end of a complete write stays buffered on disk only; it is
        // completed by the next write, or cut back by a failed one.
        self.buf.clear();
        self.marks.clear();
        match failure {
            None => Ok(()),
            Some(cause) => Err(self.fail(cause)),
        }
    }

    /// Cuts the file back to its last whole record after `cause`, drops what is buffered,
    /// and returns the error (the cut's own failure, if any, is part of the message).
    fn fail(&mut self, cause: std::io::Error) -> OutputError {
        self.incomplete = true;
        self.buf.clear();
        self.marks.clear();
        let cause = match self.f.cut(self.whole) {
            Ok(()) => {
                self.disk = self.whole;
                cause
            }
            Err(e) => std::io::Error::new(
                cause.kind(),
                format!("{cause}; cutting it back to its last whole row failed too: {e}"),
            ),
        };
        OutputError::Io {
            path: self.path.clone(),
            cause,
        }
    }
}

/// A CSV file checked for a resume at `len` bytes and not changed yet: all files of a resume
/// are checked before any is cut back, so a refused resume leaves the folder as it was.
pub(crate) struct PendingCsv {
    path: PathBuf,
    f: File,
    len: u64,
}

impl PendingCsv {
    /// Opens an existing file for appending at `len` bytes (cut back by
    /// [`PendingCsv::commit`]). The file must be at least `len` bytes long and byte `len − 1`
    /// must end a row.
    pub fn open(path: PathBuf, len: u64) -> Result<Self, OutputError> {
        use std::io::Read;
        let io = |cause| OutputError::Io {
            path: path.clone(),
            cause,
        };
        let mut f = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(&path)
            .map_err(io)?;
        let actual = f.metadata().map_err(io)?.len();
        if actual < len {
            return Err(OutputError::Mismatch {
                path: path.clone(),
                reason: format!(
                    "it has {actual} bytes, fewer than the {len} bytes the checkpoint recorded"
                ),
            });
        }
        if len > 0 {
            let mut last = [0u8];
            f.seek(SeekFrom::Start(len - 1)).map_err(io)?;
            f.read_exact(&mut last).map_err(io)?;
            if last[0] != b'\n' {
                return Err(OutputError::Mismatch {
                    path: path.clone(),
                    reason: format!("the checkpoint's length {len} does not end a row of the file"),
                });
            }
        }
        Ok(Self { path, f, len })
    }

    /// Cuts the file back to the checked length and appends from there.
    pub fn commit(self) -> Result<Csv, OutputError> {
        let Self { path, mut f, len } = self;
        f.cut(len).map_err(|cause| OutputError::Io {
            path: path.clone(),
            cause,
        })?;
        Ok(Csv::new(path, f, len))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file of at most `capacity` bytes: a write beyond it writes what fits, and the next
    /// one fails like a full disk.
    struct Small {
        bytes: Vec<u8>,
        pos: usize,
        capacity: usize,
    }

    impl Write for Small {
        fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
            let room = self.capacity.saturating_sub(self.pos);
            if room == 0 {
                return Err(std::io::Error::from(ErrorKind::StorageFull));
            }
            let n = room.min(b.len());
            self.bytes.truncate(self.pos);
            self.bytes.extend_from_slice(&b[..n]);
            self.pos += n;
            Ok(n)
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    impl Sink for Small {
        fn cut(&mut self, len: u64) -> std::io::Result<()> {
            self.bytes.truncate(len as usize);
            self.pos = len as usize;
            Ok(())
        }
    }

    fn small(capacity: usize) -> Csv<Small> {
        let f = Small {
            bytes: Vec::new(),
            pos: 0,
            capacity,
        };
        Csv::new("x.csv".into(), f, 0)
    }

    #[test]
    fn a_full_disk_leaves_whole_records() {
        // Rows of 10 bytes; the "disk" takes 95 bytes.
        let mut c = small(95);
        c.row("t,a,b,c,d").unwrap();
        for k in 0..20 {
            c.row(&format!("{k:09}")).unwrap();
        }
        let e = c.flush().unwrap_err();
        assert!(e.to_string().contains("x.csv"), "{e}");
        assert!(c.is_incomplete());
        // 9 whole rows fit in 95 bytes; the 10th, cut after 5 bytes, is cut back.
        assert_eq!(c.f.bytes.len(), 90);
        assert!(c.f.bytes.ends_with(b"000000007\n"));
        assert_eq!(c.len().unwrap(), 90);

        // A record of several rows (a frame) goes whole or not at all.
        let mut c = small(95);
        for frame in 0..4 {
            for node in 0..3 {
                c.line(&format!("{frame},{node:07}")).unwrap();
            }
            c.end_record().unwrap();
        }
        assert!(c.flush().is_err());
        // Frames of 30 bytes: three fit (90 bytes), the fourth is cut back entirely.
        assert_eq!(c.f.bytes.len(), 90);
        assert!(c.f.bytes.ends_with(b"2,0000002\n"));
    }

    #[test]
    fn a_record_written_in_parts_is_cut_back_whole() {
        // A record larger than the buffer is written out in parts; a failure in a later part
        // cuts back to the record before it, written in an earlier call.
        let row = "0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcde";
        let mut c = small(3 * CSV_BUFFER_MAX);
        c.row("header").unwrap();
        let mut lines = 0;
        let err = loop {
            if let Err(e) = c.line(row) {
                break e;
            }
            lines += 1;
        };
        assert!(matches!(err, OutputError::Io { .. }), "{err}");
        assert!(
            lines * 64 > 2 * CSV_BUFFER_MAX,
            "{lines} rows were written out"
        );
        assert_eq!(c.f.bytes, b"header\n");
        assert!(c.is_incomplete());
    }

    #[test]
    fn records_are_written_out_at_their_end() {
        let mut c = small(usize::MAX);
        let row = "x".repeat(1023);
        for _ in 0..(CSV_BUFFER / 1024 - 1) {
            c.row(&row).unwrap();
        }
        assert!(
            c.f.bytes.is_empty(),
            "below the buffer: nothing written yet"
        );
        c.line(&row).unwrap();
        assert!(c.f.bytes.is_empty(), "within a record: not written");
        c.end_record().unwrap();
        assert_eq!(c.f.bytes.len(), CSV_BUFFER);
        assert_eq!(c.len().unwrap(), CSV_BUFFER as u64);
        assert!(!c.is_incomplete());
    }
}
