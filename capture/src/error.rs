//! Typed capture errors that always say where the problem is.

use std::error::Error;
use std::fmt;
use std::io;
use std::path::PathBuf;

use super::kind::CaptureKind;

/// A capture could not be read, written or built.
///
/// Carries the location (file, 1-based line, column name) separately from
/// the reason so callers can match on [`CaptureErrorKind`] while users get a
/// message that points at the offending spot, e.g.
/// `captures/a.csv:17: column `normal_force_n`: `0.3x` is not a number`.
///
/// For captures built in memory the file is `<memory>` (or `<writer>` for a
/// [`CaptureWriter`](super::CaptureWriter) without a name), and the line is
/// the line the offending sample would occupy in a file (row index + 3).
#[derive(Debug)]
pub struct CaptureError {
    /// The file (or pseudo-source such as `<memory>`) the error concerns.
    pub file: PathBuf,
    /// 1-based file line: metadata = 1, header = 2, first sample = 3.
    pub line: Option<usize>,
    /// Column whose field is bad, for per-field errors.
    pub column: Option<String>,
    /// What went wrong.
    pub kind: CaptureErrorKind,
}

impl CaptureError {
    /// An error about `file` with no line or column yet.
    pub fn new(file: impl Into<PathBuf>, kind: CaptureErrorKind) -> Self {
        CaptureError {
            file: file.into(),
            line: None,
            column: None,
            kind,
        }
    }

    /// Sets the 1-based line number.
    pub fn at_line(mut self, line: usize) -> Self {
        self.line = Some(line);
        self
    }

    /// Sets the column name.
    pub fn in_column(mut self, column: impl Into<String>) -> Self {
        self.column = Some(column.into());
        self
    }
}

impl fmt::Display for CaptureError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
        }
        if let Some(column) = &self.column {
            write!(f, ": column `{column}`")?;
        }
        write!(f, ": {}", self.kind)
    }
}

/// The reason is already part of our `Display`, so `source` skips the kind
/// and goes straight to the underlying cause (only I/O has one). This avoids
/// error-chain printers (anyhow) repeating the reason twice.
impl Error for CaptureError {
    fn source(&self) -> Option<&(dyn Error + 'static)> {
        self.kind.source()
    }
}

/// Why a capture was rejected.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CaptureErrorKind {
    /// Reading or writing the underlying stream failed.
    #[error("I/O error: {0}")]
    Io(#[source] io::Error),
    /// The file has no bytes at all.
    #[error("file is empty")]
    Empty,
    /// Line 1 does not start with `# palpus-capture`.
    #[error("first line is not a `# palpus-capture ...` metadata line")]
    NoMetadataLine,
    /// The metadata line (or a [`Metadata`](super::Metadata) value) is malformed.
    #[error("bad metadata: {0}")]
    BadMetadata(String),
    /// `format=` is not a version this build understands.
    #[error("unsupported format version `{0}` (this build reads version {v})", v = super::FORMAT_VERSION)]
    UnsupportedVersion(String),
    /// The capture is of another kind than the caller asked for.
    #[error("expected a {expected} capture, found a {found} capture")]
    WrongKind {
        /// Kind the caller asked for.
        expected: CaptureKind,
        /// Kind found in the metadata.
        found: CaptureKind,
    },
    /// `units=` is not `si`.
    #[error("unsupported units `{0}` (only `si` is supported)")]
    UnsupportedUnits(String),
    /// The file ends after the metadata line, before the header.
    #[error("no column header line")]
    NoHeader,
    /// A required column is absent (or [`Capture::column`](super::Capture::column)
    /// asked for a column the capture does not have).
    #[error("missing column `{0}`")]
    MissingColumn(String),
    /// A column name appears twice in the header.
    #[error("duplicate column `{0}`")]
    DuplicateColumn(String),
    /// A column name is not allowed for this capture kind.
    #[error("unknown column `{0}` for this capture kind")]
    UnknownColumn(String),
    /// `time_s` is present but not the first column.
    #[error("`time_s` must be the first column")]
    TimeNotFirst,
    /// A row has the wrong number of fields (`found == 0` is a blank line).
    #[error(
        "expected {expected} fields, found {found}{}",
        if *found == 0 { " (blank line)" } else { "" }
    )]
    FieldCount {
        /// Number of columns in the header.
        expected: usize,
        /// Number of fields in the row.
        found: usize,
    },
    /// In-memory data has a column whose length differs from the first column's.
    #[error("column has {found} samples, expected {expected}")]
    ColumnLength {
        /// Length of the `time_s` column.
        expected: usize,
        /// Length of this column.
        found: usize,
    },
    /// A field does not parse as a decimal number (the text is kept).
    #[error("`{0}` is not a number")]
    NotNumeric(String),
    /// A field is NaN or infinite (including overflowing literals like `1e999`).
    #[error("value is not finite")]
    NotFinite,
    /// `time_s` did not strictly increase from the previous sample.
    #[error("time {current} s is not after the previous sample's time {previous} s")]
    TimeNotIncreasing {
        /// Time of the previous sample.
        previous: f64,
        /// Time of this sample.
        current: f64,
    },
    /// A line ends in `\r\n`. The format is LF-only so that identical captures
    /// are identical bytes; convert the file with e.g. `dos2unix`.
    #[error("line ends with CR LF; captures use LF line endings only")]
    CarriageReturn,
    /// The last line has no trailing `\n`. The writer always ends lines, so
    /// this means the file was cut off (e.g. the recorder crashed).
    #[error("last line has no trailing newline (file truncated?)")]
    TruncatedLastLine,
    /// There is a header but no sample rows (or a writer finished without rows).
    #[error("no samples (a capture needs at least one data row)")]
    NoSamples,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_includes_location_parts_that_are_present() {
        let e = CaptureError::new("captures/a.csv", CaptureErrorKind::NotNumeric("0.3x".into()))
            .at_line(17)
            .in_column("normal_force_n");
        assert_eq!(
            e.to_string(),
            "captures/a.csv:17: column `normal_force_n`: `0.3x` is not a number"
        );
        let e = CaptureError::new("a.csv", CaptureErrorKind::Empty);
        assert_eq!(e.to_string(), "a.csv: file is empty");
        let e = CaptureError::new("a.csv", CaptureErrorKind::TimeNotFirst).at_line(2);
        assert_eq!(e.to_string(), "a.csv:2: `time_s` must be the first column");
    }

    #[test]
    fn source_skips_to_io_cause() {
        let e = CaptureError::new(
            "a.csv",
            CaptureErrorKind::Io(io::Error::new(io::ErrorKind::NotFound, "gone")),
        );
        assert_eq!(e.source().map(|s| s.to_string()), Some("gone".into()));
        assert!(
            CaptureError::new("a.csv", CaptureErrorKind::NotFinite)
                .source()
                .is_none()
        );
        let blank = CaptureErrorKind::FieldCount {
            expected: 3,
            found: 0,
        };
        assert_eq!(blank.to_string(), "expected 3 fields, found 0 (blank line)");
    }
}
