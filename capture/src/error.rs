//! The crate's one error type: captures, imported logs, JSON files and signals all fail with a
//! [`CaptureError`] that says where the problem is.

use std::error::Error;
use std::fmt;
use std::io;
use std::path::PathBuf;

use super::kind::CaptureKind;

/// A capture, imported log, JSON file or signal could not be read, written or built.
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
    ///
    /// `None` for errors about values that never were in a file: the slices given to
    /// [`signal`](super::signal) and a `--map` spec given to
    /// [`ColumnMap::parse`](super::import::ColumnMap::parse). An option rather than an empty
    /// path so that "no file" cannot be mistaken for a file name, and so that a caller that
    /// does know the file can see it is missing and add it (few places read this field).
    pub file: Option<PathBuf>,
    /// 1-based file line: metadata = 1, header = 2, first sample = 3 (for
    /// imported logs and JSON files, the line of the input).
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
            file: Some(file.into()),
            line: None,
            column: None,
            kind,
        }
    }

    /// An error about values that are not from a file (signal slices, a `--map` spec).
    pub fn without_file(kind: CaptureErrorKind) -> Self {
        CaptureError {
            file: None,
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
        match (&self.file, self.line) {
            (Some(file), Some(line)) => write!(f, "{}:{line}: ", file.display())?,
            (Some(file), None) => write!(f, "{}: ", file.display())?,
            (None, Some(line)) => write!(f, "line {line}: ")?,
            (None, None) => {}
        }
        if let Some(column) = &self.column {
            write!(f, "column `{column}`: ")?;
        }
        write!(f, "{}", self.kind)
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

/// Why a capture, imported log, JSON file or signal was rejected.
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
    /// There is no column header: a capture ends after its metadata line, or an imported log
    /// has only `#` comments and blank lines.
    #[error("no header row (the first line that is not a `#` comment must name the columns)")]
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
    /// A field does not parse as a decimal number (the text is kept). A comma can only be in
    /// the text of an imported log with another delimiter, where it is a decimal comma.
    #[error(
        "`{}` is not a number{}",
        .0,
        if .0.contains(',') { " (decimal commas are not supported)" } else { "" }
    )]
    NotNumeric(String),
    /// A field is NaN or infinite (including overflowing literals like `1e999`).
    #[error("value is not finite")]
    NotFinite,
    /// A field is finite but beyond the column's plausible magnitude
    /// ([`magnitude_limit`](super::kind::magnitude_limit)): a wrong unit or a logger's
    /// sentinel, which downstream filters and fits would spread over every sample.
    #[error(
        "{value:e} is outside ±{limit:e}, the largest magnitude a capture accepts in this \
         column (SI units; a wrong unit or a sentinel value?)"
    )]
    Implausible {
        /// The value.
        value: f64,
        /// The column's limit.
        limit: f64,
    },
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

    // --- JSON files (`json_file`) ---
    /// Not valid JSON for this kind of file (what serde said; the line is the error's line).
    #[error("{0}")]
    Json(String),
    /// A JSON file parsed but is inconsistent. The field is a JSON path such as
    /// `body.scaling`, not a CSV column, so it lives here rather than in
    /// [`CaptureError::column`].
    #[error("field `{field}`: {reason}")]
    Invalid {
        /// The offending field.
        field: String,
        /// Why.
        reason: String,
    },

    // --- Importing foreign CSV logs (`import`) ---
    /// A `--map` entry is malformed (bad syntax, unknown target or unit, duplicate target).
    #[error("--map entry `{entry}`: {reason}")]
    BadMap {
        /// The entry as written.
        entry: String,
        /// What is wrong with it.
        reason: String,
    },
    /// The map or spec does not fit the capture kind, or the rates or metadata are invalid.
    #[error("{0}")]
    BadSpec(String),
    /// The input log could not be read.
    #[error("cannot read: {0}")]
    CannotRead(#[source] io::Error),
    /// The CSV structure is broken (e.g. an unterminated quote); the CSV parser's message.
    #[error("malformed CSV: {0}")]
    Csv(String),
    /// An imported log has fewer than two data rows.
    #[error("found {0} data row(s); importing needs at least 2")]
    TooFewRows(usize),
    /// A mapped source column is not in the log's header.
    ///
    /// This and [`AmbiguousSource`](Self::AmbiguousSource) hold boxed `str`s and slices: they
    /// are the largest kinds, and `Vec`/`String` would make every `Result<_, CaptureError>`
    /// of the crate bigger to return (clippy's `result_large_err`).
    #[error(
        "--map entry `{entry}`: the input has no column `{column}` (its columns: {}){}",
        bounded_list(available),
        packed_hint(column, available.iter())
    )]
    UnknownSource {
        /// The map entry.
        entry: Box<str>,
        /// The missing source column.
        column: Box<str>,
        /// The log's header names.
        available: Box<[String]>,
    },
    /// A mapped source column appears more than once in the log's header.
    #[error("--map entry `{entry}`: the input has {count} columns named `{column}`")]
    AmbiguousSource {
        /// The map entry.
        entry: Box<str>,
        /// The duplicated header name.
        column: Box<str>,
        /// How many times it appears.
        count: usize,
    },
    /// A row of an imported log has another number of fields than its header.
    #[error("expected {expected} fields like the header, found {found}")]
    HeaderFieldCount {
        /// Fields in the header.
        expected: usize,
        /// Fields in this row.
        found: usize,
    },
    /// A mapped cell of an imported log is NaN or infinite, also after unit conversion (the
    /// cell's text is kept).
    #[error(
        "`{0}` is not finite (skip such rows with --non-finite drop, or interpolate them with --non-finite bridge)"
    )]
    NotFiniteText(String),
    /// A run of non-finite cells of an imported log cannot be bridged (`--non-finite bridge`):
    /// too long, at an end of the file, or in the time column.
    #[error("cannot bridge non-finite values: {0}")]
    CannotBridge(String),
    /// With time taken from position at a known speed, the position of an imported log did
    /// not strictly advance in the stroke direction (the sign of the speed).
    #[error(
        "position {current_m} m does not advance from the previous row's {previous_m} m in the \
         stroke direction of --speed-mps {speed_mps} (position must be strictly monotonic)"
    )]
    PositionNotMonotonic {
        /// Previous position, m.
        previous_m: f64,
        /// This position, m.
        current_m: f64,
        /// The speed time is derived with, m/s (its sign is the stroke direction).
        speed_mps: f64,
    },
    /// A mapped cell of an imported log is beyond the target column's plausible magnitude
    /// after unit conversion (the cell's text is kept; see
    /// [`magnitude_limit`](super::kind::magnitude_limit)).
    #[error(
        "`{text}` is {value:e} in SI units, outside ±{limit:e}, the largest magnitude a capture \
         accepts in `{target}` (check the unit in --map, or skip such rows with \
         --drop-implausible)"
    )]
    ImplausibleText {
        /// The cell as written.
        text: Box<str>,
        /// The value in SI units.
        value: f64,
        /// The target column's limit.
        limit: f64,
        /// The capture column the cell maps to.
        target: Box<str>,
    },
    /// The time of an imported log did not strictly increase (values converted to seconds).
    #[error("time {current} s is not after the previous row's {previous} s (time must strictly increase)")]
    RowTimeNotIncreasing {
        /// Previous time, s.
        previous: f64,
        /// This time, s.
        current: f64,
    },
    /// No target rate was given and the imported log is not uniformly sampled.
    #[error(
        "the input is not uniformly sampled (intervals {min_interval_s} to {max_interval_s} s, \
         mean rate {mean_rate_hz} Hz); give the output rate (--rate-hz) to resample it"
    )]
    NotUniform {
        /// Shortest interval, s.
        min_interval_s: f64,
        /// Longest interval, s.
        max_interval_s: f64,
        /// Mean rate, Hz.
        mean_rate_hz: f64,
    },
    /// The import's output would be larger than its budget; checked before anything is
    /// allocated. Boxed, like [`UnknownSource`](Self::UnknownSource)'s slices, to keep every
    /// `Result<_, CaptureError>` small.
    #[error("{0}")]
    TooManyRows(Box<OutputBudget>),
    /// Of several inputs, none has an unqualified `--map` source column.
    #[error(
        "--map entry `{entry}`: no input has a column `{column}` ({}){}",
        describe_inputs(inputs),
        packed_hint(column, inputs.iter().flat_map(|i| i.columns.iter()))
    )]
    SourceInNoInput {
        /// The map entry.
        entry: Box<str>,
        /// The source column looked for.
        column: Box<str>,
        /// Each input's file and column names, in input order.
        inputs: Box<[InputColumns]>,
    },
    /// Several inputs have an unqualified `--map` source column, so which one is meant is not
    /// known.
    #[error(
        "--map entry `{entry}`: inputs {} have a column `{column}`; say which with \
         `N:{column}` (N the input's number)",
        describe_files(files)
    )]
    SourceInSeveralInputs {
        /// The map entry.
        entry: Box<str>,
        /// The source column.
        column: Box<str>,
        /// The inputs that have it: 1-based number and file.
        files: Box<[(usize, PathBuf)]>,
    },
    /// The time ranges of several inputs do not overlap for enough output samples to join them.
    #[error(
        "the inputs' times overlap for {rows} sample(s) at {rate_hz} Hz, fewer than the \
         {min_rows} a join needs ({}); check the time columns, their units and --clock-offset-s",
        describe_ranges(ranges)
    )]
    NoOverlap {
        /// Output samples the overlap holds (0 when the ranges do not meet).
        rows: usize,
        /// Output rate, Hz.
        rate_hz: f64,
        /// The fewest a join produces.
        min_rows: usize,
        /// Each input's file and first and last time, s (clock offset applied), in input
        /// order.
        ranges: Box<[(PathBuf, f64, f64)]>,
    },
    /// Two inputs of one recording span times more than [`crate::import::MAX_SPAN_RATIO`]
    /// apart: one clock is read in other units than it counts (milliseconds as seconds).
    #[error("{0}")]
    SpansDisagree(Box<SpanMismatch>),

    // --- Signals (`signal`): slices, so these name indices rather than lines ---
    /// `time_s` and `position_m` differ in length.
    #[error("time_s has {time} samples but position_m has {position}")]
    LengthMismatch {
        /// Samples in `time_s`.
        time: usize,
        /// Samples in `position_m`.
        position: usize,
    },
    /// A sample is NaN or infinite.
    #[error("{column}[{index}] = {value} is not finite")]
    NonFiniteSample {
        /// `time_s` or `position_m`.
        column: &'static str,
        /// Sample index.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// Time does not strictly increase (a zero interval would divide by zero when τ = 0).
    #[error("time_s[{index}] = {time_s} s does not exceed time_s[{previous_index}] = {previous_s} s")]
    SampleTimeNotIncreasing {
        /// Index of the sample that is not later than its predecessor.
        index: usize,
        /// Its time.
        time_s: f64,
        /// Index of the predecessor.
        previous_index: usize,
        /// The predecessor's time.
        previous_s: f64,
    },
    /// A filter parameter is out of its domain.
    #[error("{name} = {value}: {reason}")]
    InvalidParameter {
        /// `period_s`, `tau_s` or `max_interval_s`.
        name: &'static str,
        /// The offending value.
        value: f64,
        /// What it must be.
        reason: &'static str,
    },
}

/// One input of a multi-file import and its column names, for
/// [`CaptureErrorKind::SourceInNoInput`].
#[derive(Debug, Clone, PartialEq)]
pub struct InputColumns {
    /// The input file.
    pub file: PathBuf,
    /// Its column names (with a virtual `--unroll` column where the file has the packed ones).
    pub columns: Vec<String>,
}

fn describe_inputs(inputs: &[InputColumns]) -> String {
    let list: Vec<String> = inputs
        .iter()
        .enumerate()
        .map(|(i, input)| {
            format!(
                "{}: {} has {}",
                i + 1,
                input.file.display(),
                bounded_list(&input.columns)
            )
        })
        .collect();
    list.join("; ")
}

fn describe_files(files: &[(usize, PathBuf)]) -> String {
    let list: Vec<String> = files
        .iter()
        .map(|(n, file)| format!("{n} ({})", file.display()))
        .collect();
    list.join(" and ")
}

fn describe_ranges(ranges: &[(PathBuf, f64, f64)]) -> String {
    let list: Vec<String> = ranges
        .iter()
        .map(|(file, first, last)| format!("{} spans {first} s to {last} s", file.display()))
        .collect();
    list.join("; ")
}

/// An import's output size against its budget (see
/// [`import::MAX_OUTPUT_ROWS`](super::import::MAX_OUTPUT_ROWS) and
/// [`ImportSpec::max_upsample`](super::import::ImportSpec::max_upsample)), for
/// [`CaptureErrorKind::TooManyRows`].
#[derive(Debug, Clone, PartialEq)]
pub struct OutputBudget {
    /// Rows the output grid would have.
    pub rows: f64,
    /// Output rate, Hz.
    pub rate_hz: f64,
    /// Input time span, s.
    pub span_s: f64,
    /// Data rows read from the input.
    pub rows_in: usize,
    /// The budget the output exceeds, rows.
    pub limit: f64,
    /// Which budget, and the option that changes it, if any.
    pub reason: &'static str,
}

impl fmt::Display for OutputBudget {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let OutputBudget {
            rows,
            rate_hz,
            span_s,
            rows_in,
            limit,
            reason,
        } = self;
        write!(
            f,
            "the output would have {rows} rows ({rate_hz} Hz over {span_s} s) from {rows_in} \
             input rows, more than {limit} ({reason}); check the time unit and --rate-hz"
        )
    }
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

    #[test]
    fn display_without_a_file_is_the_location_that_is_known() {
        let kind = || CaptureErrorKind::LengthMismatch { time: 2, position: 1 };
        let e = CaptureError::without_file(kind());
        assert_eq!(e.to_string(), "time_s has 2 samples but position_m has 1");
        let e = CaptureError::without_file(kind()).at_line(4).in_column("x");
        assert_eq!(
            e.to_string(),
            "line 4: column `x`: time_s has 2 samples but position_m has 1"
        );
    }
}

/// Most characters of names a message echoes: a log with 10⁵ columns must not make an error
/// of megabytes.
const LIST_CHARS: usize = 300;

/// `names` comma-separated, cut after [`LIST_CHARS`] characters with how many were left out.
/// When the missing source `column` is a packed channel the inputs spread over numbered
/// columns (`pac_0` … `pac_21`), the `--unroll` that makes it one: without it the map finds no
/// column `pac` and would not say why. Empty otherwise.
fn packed_hint<'a>(column: &str, names: impl Iterator<Item = &'a String>) -> String {
    let mut numbered: Vec<(u64, &str)> = names
        .filter_map(|name| {
            let rest = name.strip_prefix(column)?;
            let digits = rest.strip_prefix(['_', '-', '.']).unwrap_or(rest);
            let index = (!digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()))
                .then(|| digits.parse::<u64>().ok())??;
            Some((index, name.as_str()))
        })
        .collect();
    numbered.sort_unstable();
    match (numbered.first(), numbered.last()) {
        (Some((_, first)), Some((_, last))) if numbered.len() >= 2 => format!(
            "; {} numbered columns {first} … {last} look like packed samples of it: unroll them \
             into one with --unroll '{column}={first}..{last}'",
            numbered.len()
        ),
        _ => String::new(),
    }
}

pub(crate) fn bounded_list(names: &[String]) -> String {
    let mut out = String::new();
    for (i, name) in names.iter().enumerate() {
        let sep = if i == 0 { "" } else { ", " };
        if out.len() + sep.len() + name.len() > LIST_CHARS {
            out.push_str(&format!("{sep}… and {} more", names.len() - i));
            break;
        }
        out.push_str(sep);
        out.push_str(name);
    }
    out
}

#[cfg(test)]
mod bounded_tests {
    use super::{bounded_list, packed_hint};

    #[test]
    fn a_missing_column_spread_over_numbered_ones_points_at_unroll() {
        let names: Vec<String> = ["t", "pac_0", "pac_2", "pac_1", "pdc", "pac_x", "pac"]
            .iter()
            .map(|s| (*s).to_owned())
            .collect();
        assert_eq!(
            packed_hint("pac", names.iter()),
            "; 3 numbered columns pac_0 … pac_2 look like packed samples of it: unroll them into \
             one with --unroll 'pac=pac_0..pac_2'"
        );
        let plain: Vec<String> = ["acc0", "acc1", "acc10"]
            .iter()
            .map(|s| (*s).to_owned())
            .collect();
        assert!(packed_hint("acc", plain.iter()).contains("--unroll 'acc=acc0..acc10'"));
        assert_eq!(packed_hint("pdc", names.iter()), "");
        assert_eq!(packed_hint("force", names.iter()), "");
    }

    #[test]
    fn a_long_list_is_cut_with_the_count_left_out() {
        let names: Vec<String> = (0..100_000).map(|i| format!("column_{i}")).collect();
        let listed = bounded_list(&names);
        assert!(listed.len() < 330, "{}", listed.len());
        assert!(listed.starts_with("column_0, column_1, "), "{listed}");
        let left: usize = listed
            .rsplit("and ")
            .next()
            .unwrap()
            .trim_end_matches(" more")
            .parse()
            .unwrap();
        assert_eq!(left + listed.matches("column_").count(), 100_000);
        assert_eq!(bounded_list(&names[..3]), "column_0, column_1, column_2");
    }
}

/// Two inputs whose time spans disagree ([`CaptureErrorKind::SpansDisagree`]).
#[derive(Debug, Clone, PartialEq)]
pub struct SpanMismatch {
    /// The input with the longer span.
    pub long: PathBuf,
    /// Its span, s.
    pub long_s: f64,
    /// Its mean row rate, Hz.
    pub long_rate_hz: f64,
    /// The input with the shorter span.
    pub short: PathBuf,
    /// Its span, s.
    pub short_s: f64,
    /// Its mean row rate, Hz.
    pub short_rate_hz: f64,
    /// The ratio refused beyond.
    pub ratio: f64,
}

impl fmt::Display for SpanMismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} spans {} s ({:.4} rows/s) but {} spans {} s ({:.4} rows/s), more than {}× apart: \
             streams of one recording cover the same time; give the longer clock's unit in --map \
             (e.g. `time_s=t[ms]`)",
            self.long.display(),
            self.long_s,
            self.long_rate_hz,
            self.short.display(),
            self.short_s,
            self.short_rate_hz,
            self.ratio
        )
    }
}
