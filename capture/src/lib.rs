//! The capture file format: what a haptic device or simulator recorded.
//!
//! A capture is a small, strict CSV dialect in SI units:
//!
//! ```text
//! # palpus-capture format=1 kind=rubbing device=sim-omega7 rate_hz=1000 units=si seed=42 truth.mu=0.58
//! time_s,tangential_position_m,normal_position_m,normal_force_n,friction_force_n
//! 0.0,0.0,0.00012,0.3,0.174
//! 0.001,5e-6,0.00013,0.301,0.1738
//! ```
//!
//! * Line 1 is the metadata line ([`Metadata`]): the marker `# palpus-capture`,
//!   then space-separated `key=value` tokens. The writer emits the required
//!   keys `format`, `kind`, `device`, `rate_hz`, `units` first, then free keys
//!   in insertion order. Keys are `[A-Za-z0-9_.-]+`; values are non-empty
//!   printable ASCII without whitespace (a token splits at its first `=`).
//! * Line 2 names the columns; which are allowed depends on the
//!   [`CaptureKind`] (see its `required_columns`/`optional_columns` and the
//!   column constants in [`kind`] for meanings and sign conventions).
//!   `time_s` is always first.
//! * Lines 3… are samples, one `f64` per column, written in shortest
//!   round-trip form: writing then reading gives bit-identical values, and
//!   identical input gives identical bytes. Every line ends with `\n`.
//!   Values are finite; readers also require them within their column's
//!   plausible magnitude ([`kind::magnitude_limit`]: ±10⁶ SI, ±10¹⁰ s for
//!   `time_s`).
//!
//! [`CaptureWriter`] and [`CaptureReader`] stream rows; [`Capture`] holds a
//! whole capture in memory, column-major. All three enforce the same rules
//! and report problems as a [`CaptureError`] naming file, line and column,
//! except one: [`CaptureReader`] (and so [`Capture::read_file`]) and [`import_csv`] also refuse
//! values beyond [`kind::magnitude_limit`], while the writer and [`Capture::new`] store any
//! finite value, so that a recorder never loses a run to one glitching sample and the
//! bad value is reported, with its line and column, by whoever reads the file.
//!
//! Besides the format itself this crate holds what every consumer of captures shares:
//! [`import_csv`] and [`import_streams`] of foreign logs, [`pseudo_differentiate`] (velocity from
//! position), [`json_file`] (the project's JSON files), [`rng`] (the one seeded generator) and [`CaptureRef`] (how a trained
//! file names its captures). It imports no other palpus crate. Everything in it that can fail
//! fails with a [`CaptureError`]; those about no file (signal slices, a `--map` spec) have
//! no [`CaptureError::file`].

mod atomic;
mod error;
mod import;
pub mod json_file;
pub mod kind;
mod meta;
mod reader;
mod reference;
pub mod rng;
mod signal;
mod validate;
mod writer;

use std::fs::File;
use std::io::{self, BufRead, BufReader, Write};
use std::path::{Path, PathBuf};

pub use atomic::write_atomically;
pub use error::{CaptureError, CaptureErrorKind, InputColumns, OutputBudget, SpanMismatch};
pub use import::{
    ColumnMap, DEFAULT_MAX_UPSAMPLE, Header, IMPORT_KEYS, ImportSpec, Imported, MAX_OUTPUT_ROWS, MAX_RATE_HZ,
    MAX_SPAN_RATIO, MAX_UNROLL_COLUMNS, MIN_RATE_HZ, MapEntry, NonFinite, Quantity, RepeatedTime, Resampling,
    STANDARD_GRAVITY_MPS2, Scale, SlowColumns, StreamReport, TimeFromPosition, Unroll, check_output,
    import_csv, import_csv_report, import_streams, unit_to_si,
};
pub use kind::{CaptureKind, UnknownKind};
pub use meta::{METADATA_MARKER, Metadata, RESERVED_KEYS};
pub use reader::CaptureReader;
pub use reference::{CaptureRef, sha256_hex};
pub use signal::{
    PAUSE_FACTOR, PseudoDifferentiator, median_interval_s, pseudo_differentiate,
    pseudo_differentiate_with_pauses,
};
pub use writer::CaptureWriter;

use kind::TIME_S;
use validate::{check_columns, check_finite, check_time};

/// The format version written on line 1 (`format=1`); the reader rejects others.
pub const FORMAT_VERSION: u32 = 1;

/// Source name used in errors for captures built in memory.
const MEMORY: &str = "<memory>";

/// A whole capture in memory: metadata, column names and column-major data.
///
/// A `Capture` is always valid: it has at least one sample, its columns suit
/// its kind, every value is finite and time strictly increases. So writing
/// one cannot fail except on I/O, and reading it back gives an equal
/// capture.
///
/// Equality compares content (metadata, columns, data) and ignores
/// [`Capture::source`], so a capture equals itself after a round trip
/// through a file.
#[derive(Debug, Clone)]
pub struct Capture {
    meta: Metadata,
    columns: Vec<String>,
    data: Vec<Vec<f64>>,
    source: PathBuf,
}

impl PartialEq for Capture {
    fn eq(&self, other: &Self) -> bool {
        self.meta == other.meta && self.columns == other.columns && self.data == other.data
    }
}

impl Capture {
    /// Builds a capture from column-major `data` (`data[i]` is the column
    /// named `columns[i]`), applying the writer's validation. Errors name
    /// the source `<memory>` and the line each sample would have in a file
    /// (row index + 3).
    pub fn new(meta: Metadata, columns: Vec<String>, data: Vec<Vec<f64>>) -> Result<Self, CaptureError> {
        let err = |kind| CaptureError::new(MEMORY, kind);
        meta.validate().map_err(|kind| err(kind).at_line(1))?;
        check_columns(meta.kind(), &columns).map_err(|kind| err(kind).at_line(2))?;
        if data.len() != columns.len() {
            return Err(err(CaptureErrorKind::FieldCount {
                expected: columns.len(),
                found: data.len(),
            }));
        }
        let len = data[0].len();
        if len == 0 {
            return Err(err(CaptureErrorKind::NoSamples));
        }
        for (column, name) in data.iter().zip(&columns) {
            if column.len() != len {
                return Err(err(CaptureErrorKind::ColumnLength {
                    expected: len,
                    found: column.len(),
                })
                .in_column(name));
            }
        }
        // Row-major so the reported problem is the first one a file reader
        // would hit.
        let mut previous_time = None;
        for row in 0..len {
            let at = |kind| err(kind).at_line(row + 3);
            for (column, name) in data.iter().zip(&columns) {
                check_finite(column[row]).map_err(|kind| at(kind).in_column(name))?;
            }
            let time = data[0][row];
            check_time(previous_time, time).map_err(|kind| at(kind).in_column(TIME_S))?;
            previous_time = Some(time);
        }
        Ok(Capture {
            meta,
            columns,
            data,
            source: PathBuf::from(MEMORY),
        })
    }

    /// Reads and validates a capture file, which must be of kind `expected`.
    pub fn read_file(path: impl AsRef<Path>, expected: CaptureKind) -> Result<Self, CaptureError> {
        let path = path.as_ref();
        let file = File::open(path).map_err(|e| CaptureError::new(path, CaptureErrorKind::Io(e)))?;
        Self::read_from(BufReader::new(file), path, Some(expected))
    }

    /// Reads a whole capture from `inner`; `source` names it in errors and
    /// becomes [`Capture::source`].
    pub fn read_from<R: BufRead>(
        inner: R,
        source: impl Into<PathBuf>,
        expected: Option<CaptureKind>,
    ) -> Result<Self, CaptureError> {
        let mut reader = CaptureReader::new(inner, source, expected)?;
        let mut data: Vec<Vec<f64>> = vec![Vec::new(); reader.columns().len()];
        let mut row = Vec::with_capacity(data.len());
        while reader.read_row(&mut row)? {
            for (column, &value) in data.iter_mut().zip(&row) {
                column.push(value);
            }
        }
        let source = reader.source().to_path_buf();
        Ok(Capture {
            meta: reader.metadata().clone(),
            columns: reader.columns().to_vec(),
            data,
            source,
        })
    }

    /// Writes the capture to `w` and returns it (flushed).
    pub fn write_to<W: Write>(&self, w: W) -> Result<W, CaptureError> {
        self.write_named(w, &self.source)
    }

    /// Writes the capture to `path` atomically (see [`write_atomically`]):
    /// on any error nothing is left at `path` (an existing file is kept) and
    /// no temporary file remains.
    pub fn write_file(&self, path: impl AsRef<Path>) -> Result<(), CaptureError> {
        /// Keeps capture errors typed through `write_atomically`.
        enum Failure {
            Io(io::Error),
            Capture(CaptureError),
        }
        impl From<io::Error> for Failure {
            fn from(e: io::Error) -> Self {
                Failure::Io(e)
            }
        }

        let path = path.as_ref();
        write_atomically(path, |out| {
            self.write_named(out, path).map(drop).map_err(Failure::Capture)
        })
        .map_err(|failure| match failure {
            Failure::Io(e) => CaptureError::new(path, CaptureErrorKind::Io(e)),
            Failure::Capture(e) => e,
        })
    }

    fn write_named<W: Write>(&self, w: W, source: &Path) -> Result<W, CaptureError> {
        let columns: Vec<&str> = self.columns.iter().map(String::as_str).collect();
        let mut writer = CaptureWriter::with_source(w, source, &self.meta, &columns)?;
        let mut row = Vec::with_capacity(columns.len());
        for i in 0..self.len() {
            row.clear();
            row.extend(self.data.iter().map(|column| column[i]));
            writer.write_row(&row)?;
        }
        writer.finish()
    }

    /// The metadata line.
    pub fn metadata(&self) -> &Metadata {
        &self.meta
    }

    /// Column names in file order (`time_s` first).
    pub fn columns(&self) -> &[String] {
        &self.columns
    }

    /// Number of samples (rows); at least 1.
    pub fn len(&self) -> usize {
        self.data[0].len()
    }

    /// Always `false`: a capture has at least one sample. Provided for API
    /// completeness next to [`Capture::len`].
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether the capture has the named column.
    pub fn has_column(&self, name: &str) -> bool {
        self.columns.iter().any(|c| c == name)
    }

    /// The samples of column `name`, or a [`CaptureErrorKind::MissingColumn`]
    /// error naming the capture's file (optional columns may be absent).
    pub fn column(&self, name: &str) -> Result<&[f64], CaptureError> {
        match self.columns.iter().position(|c| c == name) {
            Some(i) => Ok(&self.data[i]),
            None => Err(CaptureError::new(
                &self.source,
                CaptureErrorKind::MissingColumn(name.to_owned()),
            )),
        }
    }

    /// The `time_s` column (always present).
    pub fn time(&self) -> &[f64] {
        &self.data[0]
    }

    /// All columns, in the order of [`Capture::columns`].
    pub fn data(&self) -> &[Vec<f64>] {
        &self.data
    }

    /// Where the capture came from: its file, or `<memory>`.
    pub fn source(&self) -> &Path {
        &self.source
    }

    /// The same capture, from the same source, without the rows `drop` names (0-based, any
    /// order; indices past the end are ignored). Time still increases and every value stays
    /// finite, so only taking every row away fails.
    pub fn without_rows(&self, drop: &[usize]) -> Result<Self, CaptureError> {
        let mut keep = vec![true; self.len()];
        for &i in drop {
            if let Some(k) = keep.get_mut(i) {
                *k = false;
            }
        }
        if !keep.contains(&true) {
            return Err(CaptureError::new(&self.source, CaptureErrorKind::NoSamples));
        }
        let data = self
            .data
            .iter()
            .map(|column| {
                column
                    .iter()
                    .zip(&keep)
                    .filter(|(_, k)| **k)
                    .map(|(v, _)| *v)
                    .collect()
            })
            .collect();
        Ok(Capture {
            meta: self.meta.clone(),
            columns: self.columns.clone(),
            data,
            source: self.source.clone(),
        })
    }
}

#[cfg(test)]
mod tests;
