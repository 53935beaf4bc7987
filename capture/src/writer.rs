//! Streaming capture writer.

use std::fmt;
use std::io::{BufWriter, Write};
use std::path::PathBuf;

use super::error::{CaptureError, CaptureErrorKind};
use super::kind::TIME_S;
use super::meta::Metadata;
use super::validate::{check_columns, check_finite, check_time};

/// Output buffer size. Rows are ~100 bytes, so this batches several hundred
/// rows per underlying write.
const BUFFER_BYTES: usize = 64 * 1024;

/// Writes a capture row by row, e.g. from a recorder thread or a generator
/// producing millions of samples.
///
/// The header is validated and written by [`CaptureWriter::new`]; each row
/// is validated in full *before* any of its bytes are written, so a rejected
/// row leaves the output intact and the writer usable. Values are formatted
/// with `ryu` (shortest round-trip) into a reused stack buffer and copied
/// into an internal `BufWriter`, so writing allocates nothing per row.
///
/// After an I/O error the output is in an unspecified state; stop writing.
/// Dropping the writer without [`CaptureWriter::finish`] still flushes (as
/// `BufWriter` does) but ignores errors, so call `finish`.
pub struct CaptureWriter<W: Write> {
    out: BufWriter<W>,
    source: PathBuf,
    columns: Vec<String>,
    previous_time: Option<f64>,
    rows: usize,
    number: ryu::Buffer,
}

impl<W: Write> fmt::Debug for CaptureWriter<W> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("CaptureWriter")
            .field("source", &self.source)
            .field("columns", &self.columns)
            .field("rows", &self.rows)
            .finish_non_exhaustive()
    }
}

impl<W: Write> CaptureWriter<W> {
    /// Validates `meta` and `columns` (against `meta.kind()`) and writes
    /// lines 1 and 2. Errors name the pseudo-file `<writer>`; use
    /// [`CaptureWriter::with_source`] to name the real destination.
    pub fn new(inner: W, meta: &Metadata, columns: &[&str]) -> Result<Self, CaptureError> {
        Self::with_source(inner, "<writer>", meta, columns)
    }

    /// Like [`CaptureWriter::new`], with `source` (usually the destination
    /// path) used in error messages.
    pub fn with_source(
        inner: W,
        source: impl Into<PathBuf>,
        meta: &Metadata,
        columns: &[&str],
    ) -> Result<Self, CaptureError> {
        let source = source.into();
        meta.validate()
            .map_err(|kind| CaptureError::new(&source, kind).at_line(1))?;
        check_columns(meta.kind(), columns).map_err(|kind| CaptureError::new(&source, kind).at_line(2))?;
        let mut writer = CaptureWriter {
            out: BufWriter::with_capacity(BUFFER_BYTES, inner),
            source,
            columns: columns.iter().map(|&c| c.to_owned()).collect(),
            previous_time: None,
            rows: 0,
            number: ryu::Buffer::new(),
        };
        meta.write_line(&mut writer.out)
            .and_then(|()| {
                writer.out.write_all(columns.join(",").as_bytes())?;
                writer.out.write_all(b"\n")
            })
            .map_err(|e| writer.io_error(e))?;
        Ok(writer)
    }

    /// Validates and appends one sample: `row` has one value per column, in
    /// header order; all values finite; `time_s` strictly greater than the
    /// previous row's.
    pub fn write_row(&mut self, row: &[f64]) -> Result<(), CaptureError> {
        let line = self.rows + 3;
        let at = |kind| CaptureError::new(&self.source, kind).at_line(line);
        if row.len() != self.columns.len() {
            return Err(at(CaptureErrorKind::FieldCount {
                expected: self.columns.len(),
                found: row.len(),
            }));
        }
        for (&value, name) in row.iter().zip(&self.columns) {
            check_finite(value).map_err(|kind| at(kind).in_column(name))?;
        }
        check_time(self.previous_time, row[0]).map_err(|kind| at(kind).in_column(TIME_S))?;

        let result = (|| {
            for (i, &value) in row.iter().enumerate() {
                if i > 0 {
                    self.out.write_all(b",")?;
                }
                self.out.write_all(self.number.format_finite(value).as_bytes())?;
            }
            self.out.write_all(b"\n")
        })();
        result.map_err(|e| self.io_error(e))?;
        self.previous_time = Some(row[0]);
        self.rows += 1;
        Ok(())
    }

    /// Pushes buffered rows to the underlying writer (e.g. periodically from
    /// a recorder so a crash loses little).
    pub fn flush(&mut self) -> Result<(), CaptureError> {
        self.out.flush().map_err(|e| self.io_error(e))
    }

    /// Number of rows accepted so far.
    pub fn rows_written(&self) -> usize {
        self.rows
    }

    /// The column names, in header order.
    pub fn columns(&self) -> &[String] {
        &self.columns
    }

    /// Flushes and returns the underlying writer.
    ///
    /// Fails with [`CaptureErrorKind::NoSamples`] if no row was written:
    /// the reader rejects such a file, and the writer never produces a file
    /// the reader rejects.
    pub fn finish(mut self) -> Result<W, CaptureError> {
        self.flush()?;
        if self.rows == 0 {
            return Err(CaptureError::new(&self.source, CaptureErrorKind::NoSamples));
        }
        let source = self.source;
        self.out
            .into_inner()
            .map_err(|e| CaptureError::new(source, CaptureErrorKind::Io(e.into_error())))
    }

    fn io_error(&self, e: std::io::Error) -> CaptureError {
        CaptureError::new(&self.source, CaptureErrorKind::Io(e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::CaptureKind;
    use std::io;

    const COLS: &[&str] = &["time_s", "tangential_position_m", "normal_force_n"];

    fn meta() -> Metadata {
        Metadata::new(CaptureKind::Rubbing, "sim-omega7", 1000.0).with("seed", 42)
    }

    fn text(bytes: Vec<u8>) -> String {
        String::from_utf8(bytes).unwrap()
    }

    #[test]
    fn writes_the_documented_layout() {
        let mut w = CaptureWriter::new(Vec::new(), &meta(), COLS).unwrap();
        w.write_row(&[0.0, 0.0, 0.3]).unwrap();
        w.write_row(&[0.001, 5e-6, -0.0]).unwrap();
        w.write_row(&[0.002, 1e300, 5e-324]).unwrap();
        assert_eq!(w.rows_written(), 3);
        assert_eq!(
            text(w.finish().unwrap()),
            "# palpus-capture format=1 kind=rubbing device=sim-omega7 rate_hz=1000 units=si seed=42\n\
             time_s,tangential_position_m,normal_force_n\n\
             0.0,0.0,0.3\n\
             0.001,5e-6,-0.0\n\
             0.002,1e300,5e-324\n"
        );
    }

    #[test]
    fn rejects_bad_headers_with_line_2() {
        let cases: &[(&[&str], &str)] = &[
            (
                &["time_s", "tangential_position_m", "normal_force_n", "depth_m"],
                "unknown column `depth_m` for this capture kind",
            ),
            (
                &["time_s", "tangential_position_m"],
                "missing column `normal_force_n`",
            ),
            (
                &["time_s", "tangential_position_m", "normal_force_n", "time_s"],
                "duplicate column `time_s`",
            ),
            (
                &["normal_force_n", "time_s", "tangential_position_m"],
                "`time_s` must be the first column",
            ),
        ];
        for (columns, reason) in cases {
            let e = CaptureWriter::new(Vec::new(), &meta(), columns).unwrap_err();
            assert_eq!(e.line, Some(2), "{columns:?}");
            assert_eq!(e.to_string(), format!("<writer>:2: {reason}"));
        }
        let e = CaptureWriter::new(Vec::new(), &meta(), &["time_s", "depth_m"]).unwrap_err();
        assert!(matches!(e.kind, CaptureErrorKind::UnknownColumn(c) if c == "depth_m"));
    }

    #[test]
    fn rejects_bad_metadata_with_line_1() {
        for bad in [
            meta().with("two words", 1),
            meta().with("noequals", "a b"),
            meta().with("k", "x\ty"),
            meta().with("seed", 43),
            Metadata::new(CaptureKind::Rubbing, "dev", f64::NAN),
        ] {
            let e = CaptureWriter::with_source(Vec::new(), "out.csv", &bad, COLS).unwrap_err();
            assert!(matches!(e.kind, CaptureErrorKind::BadMetadata(_)), "{e}");
            assert_eq!(e.line, Some(1));
            assert!(e.to_string().starts_with("out.csv:1: bad metadata: "), "{e}");
        }
    }

    #[test]
    fn rejects_bad_rows_without_writing_them() {
        let mut w = CaptureWriter::with_source(Vec::new(), "out.csv", &meta(), COLS).unwrap();
        w.write_row(&[1.0, 0.0, 0.0]).unwrap();

        let e = w.write_row(&[2.0, 0.0]).unwrap_err();
        assert!(matches!(
            e.kind,
            CaptureErrorKind::FieldCount {
                expected: 3,
                found: 2
            }
        ));
        assert_eq!((e.line, e.column.as_deref()), (Some(4), None));

        let e = w.write_row(&[2.0, 0.0, f64::NAN]).unwrap_err();
        assert!(matches!(e.kind, CaptureErrorKind::NotFinite));
        assert_eq!((e.line, e.column.as_deref()), (Some(4), Some("normal_force_n")));
        assert_eq!(
            e.to_string(),
            "out.csv:4: column `normal_force_n`: value is not finite"
        );

        let e = w.write_row(&[f64::INFINITY, 0.0, 0.0]).unwrap_err();
        assert_eq!(e.column.as_deref(), Some("time_s"));
        assert!(matches!(e.kind, CaptureErrorKind::NotFinite));

        let e = w.write_row(&[1.0, 0.0, 0.0]).unwrap_err();
        assert!(matches!(
            e.kind,
            CaptureErrorKind::TimeNotIncreasing { previous, current } if previous == 1.0 && current == 1.0
        ));
        assert_eq!((e.line, e.column.as_deref()), (Some(4), Some("time_s")));
        let e = w.write_row(&[0.5, 0.0, 0.0]).unwrap_err();
        assert!(matches!(e.kind, CaptureErrorKind::TimeNotIncreasing { .. }));

        // The writer is still usable and none of the rejected rows leaked out.
        w.write_row(&[1.5, 2.0, 3.0]).unwrap();
        assert_eq!(w.rows_written(), 2);
        let out = text(w.finish().unwrap());
        assert!(out.ends_with("\n1.0,0.0,0.0\n1.5,2.0,3.0\n"), "{out}");
        assert_eq!(out.lines().count(), 4);
    }

    #[test]
    fn finish_without_rows_is_no_samples() {
        let w = CaptureWriter::new(Vec::new(), &meta(), COLS).unwrap();
        let e = w.finish().unwrap_err();
        assert!(matches!(e.kind, CaptureErrorKind::NoSamples));
        assert_eq!(e.line, None);
    }

    /// Accepts `budget` bytes, then fails every write.
    struct FailAfter {
        budget: usize,
    }

    impl Write for FailAfter {
        fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
            if self.budget == 0 {
                return Err(io::Error::other("disk full"));
            }
            let n = buf.len().min(self.budget);
            self.budget -= n;
            Ok(n)
        }
        fn flush(&mut self) -> io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn io_errors_surface_as_io_kind() {
        let mut w = CaptureWriter::with_source(FailAfter { budget: 10 }, "out.csv", &meta(), COLS).unwrap();
        w.write_row(&[0.0, 0.0, 0.0]).unwrap(); // still buffered
        let e = w.flush().unwrap_err();
        assert!(matches!(&e.kind, CaptureErrorKind::Io(io) if io.to_string() == "disk full"));
        assert_eq!(e.to_string(), "out.csv: I/O error: disk full");
        assert_eq!(
            std::error::Error::source(&e).map(ToString::to_string),
            Some("disk full".into())
        );
    }
}
