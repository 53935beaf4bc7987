//! Importing researchers' CSV logs as captures: a column mapping, unit conversion and
//! resampling, so recordings made with other tools need no conversion scripts.
//!
//! # Input
//!
//! Any CSV file with a header row. The delimiter is detected from the header line among `,`,
//! `;` and tab (the most frequent one outside quotes wins; a single column means `,`). Lines
//! starting with `#` and blank lines are skipped, header names may be quoted, and fields are
//! trimmed. Columns the [`ColumnMap`] does not mention are ignored; every mapped cell must be
//! a finite decimal number (a decimal comma is an error, not a guess).
//!
//! # Column map
//!
//! `--map` is a comma-separated list of `target=source` entries: `target` is a capture column
//! (`time_s`, `tangential_position_m`, `friction_force_n`, `accel_x_mps2`, ... see
//! [`kind`](super::kind)) and `source` a column of the input. The source may carry a unit in
//! brackets, converted to SI (`x[mm]`, `t[ms]`, `az[g]`; see [`unit_to_si`] for the table), a
//! scale factor (`Fx*0.001`, `Fy*-1` to flip a sign convention), or both (`x[mm]*-1`). A unit
//! must measure what the target measures (the target's suffix says it: `_s`, `_m`, `_n`,
//! `_mps`, `_mps2`), so `friction_force_n=x[mm]` is rejected rather than silently scaled.
//!
//! # Time and resampling
//!
//! Time comes from the column mapped to `time_s`, or, for logs without one, from the input
//! rate (`input_rate_hz`: sample `i` at `i / rate`). It must be finite and strictly
//! increasing. The output is a uniform grid at the target rate starting at the first input
//! time (`t0 + k / rate`, up to the last input time):
//!
//! * **Pass-through.** If every input interval is within 1e-6 (relative) of the target
//!   period, the samples already are that grid: times and values are copied unchanged (after
//!   unit conversion). A capture written at 1 kHz and re-imported at 1 kHz is bit-for-bit
//!   the converted input.
//! * **Interpolation.** When upsampling, or at the same mean rate with jittered timestamps,
//!   each output sample is the linear interpolation of the two input samples around it.
//!   Linear interpolation adds no overshoot and its error is bounded by `h² / 8 · max|x''|`
//!   (`h` the input interval); it cannot create detail the input did not record.
//! * **Low-pass, then interpolation.** When the target rate is below the input's mean rate,
//!   content above the new Nyquist frequency would fold back into the band the models use
//!   (a 2 kHz vibration sampled at 1 kHz turns into a constant offset). So each column is
//!   first put on a uniform grid at the input's mean rate: as is if the input is uniform,
//!   else by linear interpolation, which removes the timestamp jitter without discarding
//!   resolution (at the input's own rate the interpolation's images fold back onto the
//!   input's frequencies rather than into the pass band). It is then low-passed by a
//!   zero-phase filter, a 4th-order Butterworth run forwards and backwards (8th-order
//!   magnitude, no phase lag, so events keep their time) with cut-off `0.4 × rate` (−6 dB
//!   there; −122 dB at 2 kHz for 10 kHz → 1 kHz), and finally linearly interpolated at the
//!   output grid (exact picking when the rates are integer multiples; what is left is
//!   smooth, so the error is that of the pass band, ~1e-6 relative for 7 Hz at 10 kHz).
//!   The ends are padded by odd reflection (as in `scipy.signal.filtfilt`), so a ramp or a
//!   constant has no start-up transient; the price is that whatever high-frequency content
//!   the very first and last samples carry leaks into the first and last few cut-off
//!   periods (~5 ms at a 1 kHz target). The filter is written here rather than taken from
//!   [`crate::signal`], which only has the pseudo-differentiator, and the workspace avoids
//!   a DSP dependency for two biquads.
//!
//! Timestamps are trusted as the true sampling instants. Interpolating a component near the
//! input's Nyquist frequency between jittered samples turns part of it into broadband noise
//! that no filter can separate: ±2 µs of jitter on a 10 kHz log leaves about 0.45 %
//! (−47 dB) of a 2 kHz vibration, where a uniform log gets the filter's full −122 dB. Gaps
//! in the input (a logger pausing) are bridged by the same interpolation; split such logs
//! before importing if that matters.
//!
//! # Output
//!
//! A [`Capture`] of the requested kind with `time_s` first and the other mapped columns in
//! the order of the map, and the metadata `device` (default `imported`), `rate_hz` (the
//! target rate), `units=si`, `source=<input file name>`, `map=<the spec without spaces>`,
//! `source_rate_hz=<mean input rate>` and the caller's extra keys (e.g. `surface=...`, which
//! the recognizers read as the class). Derived values are made metadata-safe (`µ` becomes
//! `u`, other non-printable-ASCII characters `_`); the caller's own values are checked and
//! rejected with a clear error instead.

use std::fmt;
use std::io;
use std::path::{Path, PathBuf};

use super::error::CaptureErrorKind;
use super::kind::{CaptureKind, TIME_S};
use super::{Capture, CaptureError, Metadata};

/// Metadata keys [`import_csv`] sets itself; the caller's extra metadata may not use them.
pub const IMPORT_KEYS: [&str; 3] = ["source", "map", "source_rate_hz"];

/// Relative tolerance on sampling intervals under which an input counts as uniform.
pub const UNIFORM_TOLERANCE: f64 = 1e-6;

/// Anti-aliasing cut-off as a fraction of the target rate.
pub const CUTOFF_FRACTION: f64 = 0.4;

/// Reflected padding at each end of the anti-aliasing filter, in cut-off periods (the
/// filter's impulse response has decayed to ~1e-4 after about five).
const PAD_CUTOFF_PERIODS: f64 = 8.0;

/// Refuse to build captures larger than this many rows (a wrong time unit would otherwise
/// ask for billions of samples).
const MAX_ROWS: usize = 200_000_000;

// --- Units -------------------------------------------------------------------------------

/// What a column measures, from its unit suffix.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// Seconds (`_s`).
    Time,
    /// Metres (`_m`).
    Length,
    /// Newtons (`_n`).
    Force,
    /// Metres per second (`_mps`).
    Velocity,
    /// Metres per second squared (`_mps2`).
    Acceleration,
}

impl Quantity {
    /// The quantity a capture column measures, from its suffix.
    pub fn of_column(name: &str) -> Option<Self> {
        // `_mps2` before `_mps`; `_s` cannot match `_mps` (no underscore before the `s`).
        [
            ("_mps2", Quantity::Acceleration),
            ("_mps", Quantity::Velocity),
            ("_s", Quantity::Time),
            ("_m", Quantity::Length),
            ("_n", Quantity::Force),
        ]
        .into_iter()
        .find(|(suffix, _)| name.ends_with(suffix))
        .map(|(_, q)| q)
    }

    /// The SI unit.
    pub fn si_unit(self) -> &'static str {
        match self {
            Quantity::Time => "s",
            Quantity::Length => "m",
            Quantity::Force => "N",
            Quantity::Velocity => "m/s",
            Quantity::Acceleration => "m/s2",
        }
    }
}

impl fmt::Display for Quantity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Quantity::Time => "time",
            Quantity::Length => "length",
            Quantity::Force => "force",
            Quantity::Velocity => "velocity",
            Quantity::Acceleration => "acceleration",
        })
    }
}

/// Standard gravity, m/s², for the `g` unit.
pub const STANDARD_GRAVITY_MPS2: f64 = 9.806_65;

/// `(unit, quantity, multiply, divide)`: SI value = value × multiply / divide. Decimal
/// sub-units divide by an exact power of ten (0.001 is not exact in binary, 1000 is), so a
/// value written in mm converts to the correctly rounded value in m.
const UNITS: &[(&str, Quantity, f64, f64)] = &[
    ("s", Quantity::Time, 1.0, 1.0),
    ("ms", Quantity::Time, 1.0, 1e3),
    ("us", Quantity::Time, 1.0, 1e6),
    ("µs", Quantity::Time, 1.0, 1e6),
    ("μs", Quantity::Time, 1.0, 1e6),
    ("m", Quantity::Length, 1.0, 1.0),
    ("cm", Quantity::Length, 1.0, 1e2),
    ("mm", Quantity::Length, 1.0, 1e3),
    ("um", Quantity::Length, 1.0, 1e6),
    ("µm", Quantity::Length, 1.0, 1e6),
    ("μm", Quantity::Length, 1.0, 1e6),
    ("N", Quantity::Force, 1.0, 1.0),
    ("mN", Quantity::Force, 1.0, 1e3),
    ("kN", Quantity::Force, 1e3, 1.0),
    ("m/s", Quantity::Velocity, 1.0, 1.0),
    ("cm/s", Quantity::Velocity, 1.0, 1e2),
    ("mm/s", Quantity::Velocity, 1.0, 1e3),
    ("m/s2", Quantity::Acceleration, 1.0, 1.0),
    ("m/s^2", Quantity::Acceleration, 1.0, 1.0),
    ("mm/s2", Quantity::Acceleration, 1.0, 1e3),
    ("mm/s^2", Quantity::Acceleration, 1.0, 1e3),
    ("g", Quantity::Acceleration, STANDARD_GRAVITY_MPS2, 1.0),
];

/// The unit table: what `unit` measures and its size in SI units (`mm` → `(Length, 1e-3)`,
/// `g` → `(Acceleration, 9.80665)`), or `None` for an unknown unit. Unit names are
/// case-sensitive (`mN` is a millinewton, `MN` is not known); `µ` and `u` both mean micro.
pub fn unit_to_si(unit: &str) -> Option<(Quantity, f64)> {
    unit_scale(unit).map(|(q, s)| (q, s.factor()))
}

fn unit_scale(unit: &str) -> Option<(Quantity, Scale)> {
    UNITS
        .iter()
        .find(|(name, ..)| *name == unit)
        .map(|&(_, q, mul, div)| (q, Scale { mul, div }))
}

fn units_of(quantity: Quantity) -> String {
    let names: Vec<&str> = UNITS
        .iter()
        .filter(|(name, q, ..)| *q == quantity && name.is_ascii())
        .map(|(name, ..)| *name)
        .collect();
    names.join(", ")
}

/// A conversion to SI: `value × mul / div`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scale {
    mul: f64,
    div: f64,
}

impl Scale {
    /// No conversion.
    pub const IDENTITY: Scale = Scale { mul: 1.0, div: 1.0 };

    /// Converts one value.
    pub fn apply(self, value: f64) -> f64 {
        value * self.mul / self.div
    }

    /// The overall factor (SI value per input value).
    pub fn factor(self) -> f64 {
        self.mul / self.div
    }
}

// --- Column map --------------------------------------------------------------------------

/// One `target=source[unit]*factor` entry of a [`ColumnMap`].
#[derive(Debug, Clone, PartialEq)]
pub struct MapEntry {
    /// The capture column written.
    pub target: String,
    /// The input column read (header name, trimmed).
    pub source: String,
    /// The unit given in brackets, if any.
    pub unit: Option<String>,
    /// Conversion from the input's values to the target's SI values (unit × factor).
    pub scale: Scale,
    /// The entry as written, trimmed (for error messages).
    pub text: String,
}

/// Which input column becomes which capture column, and how to convert it: the parsed form
/// of `--map` (see the [module documentation](self)).
#[derive(Debug, Clone, PartialEq)]
pub struct ColumnMap {
    entries: Vec<MapEntry>,
    spec: String,
}

impl ColumnMap {
    /// Parses `target=source[unit]`, `target=source*factor` or `target=source[unit]*factor`
    /// entries separated by commas. Spaces around names are ignored. Targets must be capture
    /// columns (of any kind; [`import_csv`] checks them against the kind), each at most once;
    /// a unit must be in the [unit table](unit_to_si) and measure the target's quantity; a
    /// factor must be a finite non-zero number.
    pub fn parse(spec: &str) -> Result<ColumnMap, ImportError> {
        if spec.trim().is_empty() {
            return Err(ImportError::BadMap {
                entry: String::new(),
                reason: "the column map is empty (expected `target=source,...`)".into(),
            });
        }
        let mut entries: Vec<MapEntry> = Vec::new();
        for raw in spec.split(',') {
            let entry = parse_entry(raw.trim())?;
            if entries.iter().any(|e| e.target == entry.target) {
                return Err(ImportError::BadMap {
                    reason: format!("target `{}` is mapped more than once", entry.target),
                    entry: entry.text,
                });
            }
            entries.push(entry);
        }
        Ok(ColumnMap {
            entries,
            spec: spec.chars().filter(|c| !c.is_whitespace()).collect(),
        })
    }

    /// The entries in the order given.
    pub fn entries(&self) -> &[MapEntry] {
        &self.entries
    }

    /// The entry writing `target`, if any.
    pub fn get(&self, target: &str) -> Option<&MapEntry> {
        self.entries.iter().find(|e| e.target == target)
    }

    /// The spec as given, with whitespace removed (recorded as `map=` in the metadata).
    pub fn spec(&self) -> &str {
        &self.spec
    }
}

fn is_capture_column(name: &str) -> bool {
    CaptureKind::ALL.iter().any(|kind| kind.allows_column(name))
}

fn all_capture_columns() -> String {
    let mut names: Vec<&str> = Vec::new();
    for kind in CaptureKind::ALL {
        for name in kind.required_columns().iter().chain(kind.optional_columns()) {
            if !names.contains(name) {
                names.push(name);
            }
        }
    }
    names.join(", ")
}

fn parse_entry(entry: &str) -> Result<MapEntry, ImportError> {
    let bad = |reason: String| ImportError::BadMap {
        entry: entry.to_owned(),
        reason,
    };
    if entry.is_empty() {
        return Err(bad(
            "empty entry (two commas in a row, or a trailing comma?)".into()
        ));
    }
    let (target, source) = entry
        .split_once('=')
        .ok_or_else(|| bad("expected `target=source`".into()))?;
    let (target, mut source) = (target.trim(), source.trim());
    if target.is_empty() {
        return Err(bad("no target column before `=`".into()));
    }
    if !is_capture_column(target) {
        return Err(bad(format!(
            "`{target}` is not a capture column (known: {})",
            all_capture_columns()
        )));
    }
    let quantity =
        Quantity::of_column(target).ok_or_else(|| bad(format!("`{target}` has no unit suffix")))?;

    let mut scale = Scale::IDENTITY;
    // A factor follows the last `*` that is not inside the unit brackets.
    if let Some((rest, factor)) = source.rsplit_once('*')
        && !factor.contains(']')
    {
        let factor_text = factor.trim();
        let value: f64 = factor_text
            .parse()
            .map_err(|_| bad(format!("scale factor `{factor_text}` is not a number")))?;
        if !value.is_finite() || value == 0.0 {
            return Err(bad(format!(
                "scale factor `{factor_text}` must be finite and non-zero"
            )));
        }
        scale.mul = value;
        source = rest.trim();
    }
    let mut unit = None;
    if let Some(rest) = source.strip_suffix(']') {
        let (name, unit_text) = rest
            .rsplit_once('[')
            .ok_or_else(|| bad("`]` without `[`".into()))?;
        let unit_text = unit_text.trim();
        let (unit_quantity, unit_scale) = unit_scale(unit_text).ok_or_else(|| {
            bad(format!(
                "unknown unit `{unit_text}` (units of {quantity}: {})",
                units_of(quantity)
            ))
        })?;
        if unit_quantity != quantity {
            return Err(bad(format!(
                "unit `{unit_text}` is a {unit_quantity} unit but `{target}` is a {quantity} in {} \
                 (units of {quantity}: {})",
                quantity.si_unit(),
                units_of(quantity)
            )));
        }
        scale.div = unit_scale.div;
        scale.mul *= unit_scale.mul;
        unit = Some(unit_text.to_owned());
        source = name.trim();
    } else if source.contains('[') || source.contains(']') {
        return Err(bad(
            "a unit goes in brackets at the end of the source: `name[unit]`".into(),
        ));
    }
    if source.is_empty() {
        return Err(bad("no source column after `=`".into()));
    }
    Ok(MapEntry {
        target: target.to_owned(),
        source: source.to_owned(),
        unit,
        scale,
        text: entry.to_owned(),
    })
}

// --- Spec, result, errors ------------------------------------------------------------------

/// What to import and how: see [`import_csv`].
#[derive(Debug, Clone, PartialEq)]
pub struct ImportSpec {
    /// The kind of capture to produce; decides which targets are required and allowed.
    pub kind: CaptureKind,
    /// Input columns to capture columns.
    pub map: ColumnMap,
    /// Output rate, Hz. `None`: keep the input's rate, which must then be uniform.
    pub rate_hz: Option<f64>,
    /// The input's rate, Hz, for inputs without a time column (sample `i` at `i / rate`).
    pub input_rate_hz: Option<f64>,
    /// The `device` metadata value.
    pub device: String,
    /// Extra metadata keys, in order (e.g. `surface=sandpaper_400`).
    pub metadata: Vec<(String, String)>,
}

impl ImportSpec {
    /// A spec keeping the input's rate, device `imported`, no extra metadata.
    pub fn new(kind: CaptureKind, map: ColumnMap) -> Self {
        ImportSpec {
            kind,
            map,
            rate_hz: None,
            input_rate_hz: None,
            device: "imported".into(),
            metadata: Vec::new(),
        }
    }
}

/// How the samples were put on the output grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Resampling {
    /// The input already was the output grid; values copied.
    PassThrough,
    /// Linear interpolation (upsampling, or removing jitter at the same rate).
    Interpolated,
    /// Zero-phase low-pass on a uniform intermediate grid, then sampling at the output grid.
    LowPassed {
        /// −6 dB cut-off of the forward-backward filter, Hz.
        cutoff_hz: f64,
        /// Rate of the intermediate grid the filter ran on, Hz.
        intermediate_rate_hz: f64,
    },
}

impl fmt::Display for Resampling {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Resampling::PassThrough => f.write_str("passed through"),
            Resampling::Interpolated => f.write_str("linear interpolation"),
            Resampling::LowPassed {
                cutoff_hz,
                intermediate_rate_hz,
            } => write!(
                f,
                "zero-phase low-pass at {cutoff_hz} Hz (on a {intermediate_rate_hz} Hz grid), \
                 then linear interpolation"
            ),
        }
    }
}

/// An imported capture and what the import did.
#[derive(Debug, Clone)]
pub struct Imported {
    /// The capture (not yet written).
    pub capture: Capture,
    /// Data rows read from the input.
    pub rows_in: usize,
    /// The input's mean rate, Hz: `(rows − 1) / (last time − first time)`.
    pub source_rate_hz: f64,
    /// The output rate, Hz.
    pub rate_hz: f64,
    /// How the output grid was filled.
    pub resampling: Resampling,
}

/// Why a CSV file could not be imported. Every variant about an input names the file, and
/// the line, column or `--map` entry where one applies.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ImportError {
    /// A `--map` entry is malformed (bad syntax, unknown target or unit, duplicate target).
    #[error("--map entry `{entry}`: {reason}")]
    BadMap {
        /// The entry as written.
        entry: String,
        /// What is wrong with it.
        reason: String,
    },
    /// The map or spec does not fit the capture kind, or the rates or metadata are invalid.
    #[error("{}: {reason}", file.display())]
    BadSpec {
        /// The input file.
        file: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// The input could not be read.
    #[error("{}: cannot read: {source}", file.display())]
    Io {
        /// The input file.
        file: PathBuf,
        /// The I/O error.
        #[source]
        source: io::Error,
    },
    /// The CSV structure is broken (e.g. an unterminated quote).
    #[error("{}:{line}: malformed CSV: {reason}", file.display())]
    Csv {
        /// The input file.
        file: PathBuf,
        /// 1-based line.
        line: u64,
        /// The CSV parser's message.
        reason: String,
    },
    /// There is no header row.
    #[error(
        "{}: no header row (the first line that is not a `#` comment must name the columns)",
        file.display()
    )]
    NoHeader {
        /// The input file.
        file: PathBuf,
    },
    /// Fewer than two data rows.
    #[error("{}: found {found} data row(s); importing needs at least 2", file.display())]
    TooFewRows {
        /// The input file.
        file: PathBuf,
        /// Data rows found.
        found: usize,
    },
    /// A mapped source column is not in the header.
    #[error(
        "{}: --map entry `{entry}`: the input has no column `{column}` (its columns: {})",
        file.display(),
        available.join(", ")
    )]
    UnknownSource {
        /// The input file.
        file: PathBuf,
        /// The map entry.
        entry: String,
        /// The missing source column.
        column: String,
        /// The input's header names.
        available: Vec<String>,
    },
    /// A mapped source column appears twice in the header.
    #[error("{}: --map entry `{entry}`: the input has {count} columns named `{column}`", file.display())]
    AmbiguousSource {
        /// The input file.
        file: PathBuf,
        /// The map entry.
        entry: String,
        /// The duplicated header name.
        column: String,
        /// How many times it appears.
        count: usize,
    },
    /// A data row has another number of fields than the header.
    #[error("{}:{line}: expected {expected} fields like the header, found {found}", file.display())]
    FieldCount {
        /// The input file.
        file: PathBuf,
        /// 1-based line.
        line: u64,
        /// Fields in the header.
        expected: usize,
        /// Fields in this row.
        found: usize,
    },
    /// A mapped cell is not a number.
    #[error(
        "{}:{line}: column `{column}`: `{text}` is not a number{}",
        file.display(),
        if text.contains(',') { " (decimal commas are not supported)" } else { "" }
    )]
    NotNumeric {
        /// The input file.
        file: PathBuf,
        /// 1-based line.
        line: u64,
        /// The input column.
        column: String,
        /// The cell.
        text: String,
    },
    /// A mapped cell is NaN or infinite (also after unit conversion).
    #[error("{}:{line}: column `{column}`: `{text}` is not finite", file.display())]
    NotFinite {
        /// The input file.
        file: PathBuf,
        /// 1-based line.
        line: u64,
        /// The input column.
        column: String,
        /// The cell.
        text: String,
    },
    /// Time did not strictly increase.
    #[error(
        "{}:{line}: column `{column}`: time {current} s is not after the previous row's {previous} s \
         (time must strictly increase)",
        file.display()
    )]
    TimeNotIncreasing {
        /// The input file.
        file: PathBuf,
        /// 1-based line.
        line: u64,
        /// The input's time column.
        column: String,
        /// Previous time, s (converted).
        previous: f64,
        /// This time, s (converted).
        current: f64,
    },
    /// No target rate was given and the input is not uniformly sampled.
    #[error(
        "{}: the input is not uniformly sampled (intervals {min_interval_s} to {max_interval_s} s, \
         mean rate {mean_rate_hz} Hz); give the output rate (--rate-hz) to resample it",
        file.display()
    )]
    NotUniform {
        /// The input file.
        file: PathBuf,
        /// Shortest interval, s.
        min_interval_s: f64,
        /// Longest interval, s.
        max_interval_s: f64,
        /// Mean rate, Hz.
        mean_rate_hz: f64,
    },
    /// The output would be unreasonably large.
    #[error(
        "{}: the output would have {rows} rows at {rate_hz} Hz over {span_s} s; check the time \
         unit and --rate-hz",
        file.display()
    )]
    TooManyRows {
        /// The input file.
        file: PathBuf,
        /// Rows the output grid would have.
        rows: f64,
        /// Output rate, Hz.
        rate_hz: f64,
        /// Input time span, s.
        span_s: f64,
    },
    /// The imported data did not make a valid capture (should not happen: everything is
    /// checked before).
    #[error("{}: building the capture: {source}", file.display())]
    Capture {
        /// The input file.
        file: PathBuf,
        /// The capture error.
        #[source]
        source: CaptureError,
    },
}

// --- Import ------------------------------------------------------------------------------

/// Imports the CSV file at `path` as a capture, as described in the
/// [module documentation](self). Nothing is written; see [`Capture::write_file`].
pub fn import_csv(path: &Path, spec: &ImportSpec) -> Result<Capture, ImportError> {
    import_csv_report(path, spec).map(|imported| imported.capture)
}

/// [`import_csv`], also returning the row count, rates and the resampling applied.
pub fn import_csv_report(path: &Path, spec: &ImportSpec) -> Result<Imported, ImportError> {
    let file = path.to_path_buf();
    let bad_spec = |reason: String| ImportError::BadSpec {
        file: file.clone(),
        reason,
    };
    let time_entry = spec.map.get(TIME_S);
    match (time_entry, spec.input_rate_hz) {
        (None, None) => {
            return Err(bad_spec(
                "no time: map `time_s=<column>` or give the input's rate (--input-rate-hz)".into(),
            ));
        }
        (Some(entry), Some(_)) => {
            return Err(bad_spec(format!(
                "time is given twice: by --map entry `{}` and by the input rate (--input-rate-hz); \
                 give one",
                entry.text
            )));
        }
        _ => {}
    }
    check_map_against_kind(spec).map_err(&bad_spec)?;
    for (what, rate) in [
        ("--rate-hz", spec.rate_hz),
        ("--input-rate-hz", spec.input_rate_hz),
    ] {
        if let Some(rate) = rate
            && !(rate.is_finite() && rate > 0.0)
        {
            return Err(bad_spec(format!("{what} {rate}: must be finite and positive")));
        }
    }
    // Check the caller's metadata before reading a possibly large file.
    let mut meta = Metadata::new(spec.kind, spec.device.clone(), spec.rate_hz.unwrap_or(1.0));
    for (key, value) in &spec.metadata {
        if IMPORT_KEYS.contains(&key.as_str()) {
            return Err(bad_spec(format!(
                "metadata key `{key}` is set by the import itself (from the input)"
            )));
        }
        meta = meta.with(key, value);
    }
    meta.validate().map_err(|kind| bad_spec(metadata_reason(kind)))?;

    let table = read_table(path, &spec.map)?;
    let rows_in = table.lines.len();
    if rows_in < 2 {
        return Err(ImportError::TooFewRows { file, found: rows_in });
    }
    let time: Vec<f64> = match (time_entry, spec.input_rate_hz) {
        (Some(entry), _) => {
            let index = spec.map.entries.iter().position(|e| e.target == entry.target);
            let time = index.map(|i| table.columns[i].clone()).unwrap_or_default();
            check_increasing(&file, &entry.source, &time, &table.lines)?;
            time
        }
        (None, Some(rate)) => (0..rows_in).map(|i| i as f64 / rate).collect(),
        (None, None) => Vec::new(), // rejected above
    };
    let (t0, t_last) = (time[0], time[rows_in - 1]);
    let span = t_last - t0;
    let source_rate_hz = (rows_in - 1) as f64 / span;
    let rate_hz = match spec.rate_hz {
        Some(rate) => rate,
        None => {
            let rate = snap_rate(source_rate_hz);
            if !is_uniform(&time, rate) {
                let (min, max) = interval_range(&time);
                return Err(ImportError::NotUniform {
                    file,
                    min_interval_s: min,
                    max_interval_s: max,
                    mean_rate_hz: source_rate_hz,
                });
            }
            rate
        }
    };
    let rows_out = (span * rate_hz + UNIFORM_TOLERANCE).floor() + 1.0;
    if rows_out.is_nan() || rows_out > MAX_ROWS as f64 {
        return Err(ImportError::TooManyRows {
            file,
            rows: rows_out,
            rate_hz,
            span_s: span,
        });
    }
    let rows_out = rows_out as usize;

    // Column order: time first, then the other targets in map order.
    let (order, inputs): (Vec<&str>, Vec<&[f64]>) = spec
        .map
        .entries
        .iter()
        .zip(&table.columns)
        .filter(|(entry, _)| entry.target != TIME_S)
        .map(|(entry, column)| (entry.target.as_str(), column.as_slice()))
        .unzip();

    let (out_time, mut out_data, resampling) = if is_uniform(&time, rate_hz) {
        let data = inputs.iter().map(|column| column.to_vec()).collect();
        (time.clone(), data, Resampling::PassThrough)
    } else {
        let grid: Vec<f64> = (0..rows_out).map(|k| t0 + k as f64 / rate_hz).collect();
        if rate_hz < source_rate_hz * (1.0 - UNIFORM_TOLERANCE) {
            // The filter runs on a uniform grid at the input's own mean rate: no resolution
            // is lost, and the images of the input's samples fold back onto themselves
            // rather than into the pass band (a grid at another rate would alias them).
            let intermediate_rate_hz = snap_rate(source_rate_hz);
            let cutoff_hz = CUTOFF_FRACTION * rate_hz;
            let uniform_input = is_uniform(&time, intermediate_rate_hz);
            let mid_grid: Vec<f64> = if uniform_input {
                time.clone()
            } else {
                (0..rows_in)
                    .map(|j| t0 + j as f64 / intermediate_rate_hz)
                    .collect()
            };
            let filter = LowPass::butterworth4(cutoff_hz, intermediate_rate_hz);
            let data = inputs
                .iter()
                .map(|column| {
                    let smooth = if uniform_input {
                        filter.filtfilt(column)
                    } else {
                        filter.filtfilt(&interpolate(&time, column, &mid_grid))
                    };
                    interpolate(&mid_grid, &smooth, &grid)
                })
                .collect();
            let resampling = Resampling::LowPassed {
                cutoff_hz,
                intermediate_rate_hz,
            };
            (grid, data, resampling)
        } else {
            let data = inputs
                .iter()
                .map(|column| interpolate(&time, column, &grid))
                .collect();
            (grid, data, Resampling::Interpolated)
        }
    };

    let mut columns = vec![TIME_S.to_owned()];
    columns.extend(order.iter().map(|&name| name.to_owned()));
    let mut data = vec![out_time];
    data.append(&mut out_data);

    let source_name = path
        .file_name()
        .map(|name| name.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string());
    let mut meta = Metadata::new(spec.kind, spec.device.clone(), rate_hz)
        .with("source", metadata_safe(&source_name))
        .with("map", metadata_safe(spec.map.spec()))
        .with("source_rate_hz", snap_rate(source_rate_hz));
    for (key, value) in &spec.metadata {
        meta = meta.with(key, value);
    }
    let capture =
        Capture::new(meta, columns, data).map_err(|source| ImportError::Capture { file, source })?;
    Ok(Imported {
        capture,
        rows_in,
        source_rate_hz,
        rate_hz,
        resampling,
    })
}

fn metadata_reason(kind: CaptureErrorKind) -> String {
    match kind {
        CaptureErrorKind::BadMetadata(reason) => format!("metadata: {reason}"),
        other => other.to_string(),
    }
}

/// Every required column of the kind is mapped (time may come from the input rate instead)
/// and every target is allowed.
fn check_map_against_kind(spec: &ImportSpec) -> Result<(), String> {
    let kind = spec.kind;
    if let Some(entry) = spec.map.entries().iter().find(|e| !kind.allows_column(&e.target)) {
        let allowed: Vec<&str> = kind
            .required_columns()
            .iter()
            .chain(kind.optional_columns())
            .copied()
            .collect();
        return Err(format!(
            "--map entry `{}`: column `{}` is not allowed in a {kind} capture (allowed: {})",
            entry.text,
            entry.target,
            allowed.join(", ")
        ));
    }
    let missing: Vec<&str> = kind
        .required_columns()
        .iter()
        .copied()
        .filter(|&name| spec.map.get(name).is_none())
        .filter(|&name| !(name == TIME_S && spec.input_rate_hz.is_some()))
        .collect();
    if !missing.is_empty() {
        return Err(format!(
            "a {kind} capture needs {}, which --map does not map (required: {})",
            missing
                .iter()
                .map(|m| format!("`{m}`"))
                .collect::<Vec<_>>()
                .join(", "),
            kind.required_columns().join(", ")
        ));
    }
    Ok(())
}

/// The mapped columns of an input file, converted to SI, in map order.
struct Table {
    columns: Vec<Vec<f64>>,
    /// 1-based file line of each data row.
    lines: Vec<u64>,
}

fn read_table(path: &Path, map: &ColumnMap) -> Result<Table, ImportError> {
    let file = path.to_path_buf();
    let bytes = std::fs::read(path).map_err(|source| ImportError::Io {
        file: file.clone(),
        source,
    })?;
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(&bytes);
    let mut reader = csv::ReaderBuilder::new()
        .delimiter(detect_delimiter(bytes))
        .comment(Some(b'#'))
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(bytes);
    // The csv crate's line numbers skip comment and blank lines; count them from byte offsets.
    let mut lines = LineCounter::new(bytes);
    let csv_error = |e: csv::Error, lines: &mut LineCounter<'_>, fallback_line: u64| ImportError::Csv {
        file: file.clone(),
        line: e.position().map_or(fallback_line, |p| lines.line_at(p.byte())),
        reason: e.to_string(),
    };
    let is_blank = |record: &csv::ByteRecord| record.iter().all(<[u8]>::is_empty);

    let mut record = csv::ByteRecord::new();
    let header: Vec<String> = loop {
        match reader.read_byte_record(&mut record) {
            Ok(false) => return Err(ImportError::NoHeader { file }),
            Ok(true) if is_blank(&record) => continue,
            Ok(true) => {
                break record
                    .iter()
                    .map(|name| String::from_utf8_lossy(name).into_owned())
                    .collect();
            }
            Err(e) => return Err(csv_error(e, &mut lines, 1)),
        }
    };
    let mut indices = Vec::with_capacity(map.entries.len());
    for entry in &map.entries {
        let matches: Vec<usize> = (0..header.len()).filter(|&i| header[i] == entry.source).collect();
        match matches.as_slice() {
            [] => {
                return Err(ImportError::UnknownSource {
                    file,
                    entry: entry.text.clone(),
                    column: entry.source.clone(),
                    available: header,
                });
            }
            [i] => indices.push(*i),
            _ => {
                return Err(ImportError::AmbiguousSource {
                    file,
                    entry: entry.text.clone(),
                    column: entry.source.clone(),
                    count: matches.len(),
                });
            }
        }
    }

    let mut table = Table {
        columns: vec![Vec::new(); map.entries.len()],
        lines: Vec::new(),
    };
    let mut last_line = 1;
    loop {
        match reader.read_byte_record(&mut record) {
            Ok(false) => break,
            Ok(true) if is_blank(&record) => continue,
            Ok(true) => {}
            Err(e) => return Err(csv_error(e, &mut lines, last_line + 1)),
        }
        let line = match record.position() {
            Some(position) => lines.line_at(position.byte()),
            None => last_line + 1,
        };
        last_line = line;
        if record.len() != header.len() {
            return Err(ImportError::FieldCount {
                file,
                line,
                expected: header.len(),
                found: record.len(),
            });
        }
        for ((entry, &i), column) in map.entries.iter().zip(&indices).zip(&mut table.columns) {
            let cell = &record[i];
            let text = || String::from_utf8_lossy(cell).into_owned();
            let value: f64 = std::str::from_utf8(cell)
                .ok()
                .and_then(|s| s.parse().ok())
                .ok_or_else(|| ImportError::NotNumeric {
                    file: file.clone(),
                    line,
                    column: entry.source.clone(),
                    text: text(),
                })?;
            let value = entry.scale.apply(value);
            if !value.is_finite() {
                return Err(ImportError::NotFinite {
                    file,
                    line,
                    column: entry.source.clone(),
                    text: text(),
                });
            }
            column.push(value);
        }
        table.lines.push(line);
    }
    Ok(table)
}

/// 1-based line numbers of ascending byte offsets, counting newlines incrementally.
struct LineCounter<'a> {
    bytes: &'a [u8],
    offset: usize,
    line: u64,
}

impl<'a> LineCounter<'a> {
    fn new(bytes: &'a [u8]) -> Self {
        LineCounter {
            bytes,
            offset: 0,
            line: 1,
        }
    }

    /// The line of the record the csv reader reports at byte `offset`; offsets must not
    /// decrease between calls. The reader's offset is where it started looking, so empty and
    /// `#` lines it skipped before the record are skipped here too.
    fn line_at(&mut self, offset: u64) -> u64 {
        let mut end = usize::try_from(offset)
            .unwrap_or(usize::MAX)
            .min(self.bytes.len());
        loop {
            let rest = &self.bytes[end..];
            let skipped = match rest.first() {
                Some(b'#') => rest.iter().position(|&b| b == b'\n').map(|i| i + 1),
                Some(b'\n') => Some(1),
                Some(b'\r') => Some(if rest.get(1) == Some(&b'\n') { 2 } else { 1 }),
                _ => None,
            };
            match skipped {
                Some(len) => end += len,
                None => break,
            }
        }
        if end > self.offset {
            let newlines = self.bytes[self.offset..end]
                .iter()
                .filter(|&&b| b == b'\n')
                .count();
            self.line += newlines as u64;
            self.offset = end;
        }
        self.line
    }
}

/// The delimiter of the header line: whichever of tab, `;` and `,` occurs most often outside
/// double quotes (ties in that order), `,` if none does.
fn detect_delimiter(bytes: &[u8]) -> u8 {
    let header = bytes
        .split(|&b| b == b'\n')
        .map(<[u8]>::trim_ascii)
        .find(|line| !line.is_empty() && !line.starts_with(b"#"))
        .unwrap_or_default();
    let mut counts = [(b'\t', 0usize), (b';', 0), (b',', 0)];
    let mut quoted = false;
    for &b in header {
        if b == b'"' {
            quoted = !quoted;
        } else if !quoted && let Some(slot) = counts.iter_mut().find(|(d, _)| *d == b) {
            slot.1 += 1;
        }
    }
    // `max_by_key` returns the last maximum, so scan in reverse priority order.
    counts
        .iter()
        .rev()
        .filter(|(_, n)| *n > 0)
        .max_by_key(|(_, n)| *n)
        .map_or(b',', |(d, _)| *d)
}

fn check_increasing(file: &Path, column: &str, time: &[f64], lines: &[u64]) -> Result<(), ImportError> {
    for (i, pair) in time.windows(2).enumerate() {
        // Values are finite (checked while reading), so `<=` is the whole negation of `>`.
        if pair[1] <= pair[0] {
            return Err(ImportError::TimeNotIncreasing {
                file: file.to_path_buf(),
                line: lines[i + 1],
                column: column.to_owned(),
                previous: pair[0],
                current: pair[1],
            });
        }
    }
    Ok(())
}

/// Whether every interval is within [`UNIFORM_TOLERANCE`] of the period `1 / rate_hz`.
fn is_uniform(time: &[f64], rate_hz: f64) -> bool {
    let period = 1.0 / rate_hz;
    time.windows(2)
        .all(|pair| ((pair[1] - pair[0]) - period).abs() <= UNIFORM_TOLERANCE * period)
}

fn interval_range(time: &[f64]) -> (f64, f64) {
    time.windows(2)
        .map(|pair| pair[1] - pair[0])
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), dt| {
            (lo.min(dt), hi.max(dt))
        })
}

/// A mean rate within [`UNIFORM_TOLERANCE`] of an integer is that integer (a 1 kHz log whose
/// times are written in decimal has a mean rate of 999.9999999997 Hz).
fn snap_rate(rate_hz: f64) -> f64 {
    let rounded = rate_hz.round();
    if rounded > 0.0 && (rate_hz - rounded).abs() <= UNIFORM_TOLERANCE * rate_hz {
        rounded
    } else {
        rate_hz
    }
}

/// A value the metadata line accepts: printable ASCII without whitespace (`µ`/`μ` → `u`,
/// anything else → `_`).
fn metadata_safe(text: &str) -> String {
    let safe: String = text
        .chars()
        .map(|c| match c {
            'µ' | 'μ' => 'u',
            c if c.is_ascii_graphic() => c,
            _ => '_',
        })
        .collect();
    if safe.is_empty() { "_".into() } else { safe }
}

/// Linear interpolation of `(time, value)` at the ascending `at` times; outside the input's
/// span the end values are held (the grid only leaves it by rounding).
fn interpolate(time: &[f64], value: &[f64], at: &[f64]) -> Vec<f64> {
    let last = time.len() - 1;
    let mut j = 0;
    at.iter()
        .map(|&t| {
            while j < last && time[j + 1] <= t {
                j += 1;
            }
            if j == last || t <= time[j] {
                return value[j];
            }
            let w = (t - time[j]) / (time[j + 1] - time[j]);
            value[j] + (value[j + 1] - value[j]) * w
        })
        .collect()
}

/// A cascade of biquads (direct form II transposed), run forwards and backwards.
///
/// Hand-written because neither [`crate::signal`] nor the workspace's dependencies have an
/// IIR low-pass, and two biquads do not justify a DSP crate.
#[derive(Debug, Clone)]
struct LowPass {
    /// `[b0, b1, b2, a1, a2]` per section, normalised so `a0 = 1`.
    sections: Vec<[f64; 5]>,
    /// Samples of odd-reflection padding at each end.
    pad: usize,
}

impl LowPass {
    /// 4th-order Butterworth low-pass with −3 dB at `cutoff_hz` (−6 dB run forwards and
    /// backwards), by the bilinear transform with pre-warping (the RBJ cookbook biquad with
    /// the Butterworth pole-pair Qs `1 / (2 cos θ)`, θ = π/8, 3π/8).
    fn butterworth4(cutoff_hz: f64, rate_hz: f64) -> Self {
        let w0 = 2.0 * std::f64::consts::PI * cutoff_hz / rate_hz;
        let (sin, cos) = w0.sin_cos();
        let sections = [1.0_f64, 3.0]
            .iter()
            .map(|k| {
                let q = 1.0 / (2.0 * (k * std::f64::consts::PI / 8.0).cos());
                let alpha = sin / (2.0 * q);
                let a0 = 1.0 + alpha;
                let b0 = (1.0 - cos) / 2.0 / a0;
                [b0, 2.0 * b0, b0, -2.0 * cos / a0, (1.0 - alpha) / a0]
            })
            .collect();
        let pad = (PAD_CUTOFF_PERIODS * rate_hz / cutoff_hz).ceil() as usize;
        LowPass { sections, pad }
    }

    /// Zero-phase filtering: forwards, then backwards, over the signal extended at both ends
    /// by its odd reflection (`2 x[0] − x[k]`), each pass starting in the steady state of its
    /// first sample. A constant or a straight line passes unchanged.
    fn filtfilt(&self, x: &[f64]) -> Vec<f64> {
        let n = x.len();
        if n < 2 {
            return x.to_vec();
        }
        let pad = self.pad.min(n - 1);
        let (first, last) = (x[0], x[n - 1]);
        let mut ext = Vec::with_capacity(n + 2 * pad);
        ext.extend((1..=pad).rev().map(|k| 2.0 * first - x[k]));
        ext.extend_from_slice(x);
        ext.extend((1..=pad).map(|k| 2.0 * last - x[n - 1 - k]));
        self.run(&mut ext);
        ext.reverse();
        self.run(&mut ext);
        ext.reverse();
        ext[pad..pad + n].to_vec()
    }

    /// One causal pass in place, each section starting at the steady state for `x[0]` (the
    /// DC gain is 1, so every section sees the same constant).
    fn run(&self, x: &mut [f64]) {
        let Some(&v) = x.first() else { return };
        for &[b0, b1, b2, a1, a2] in &self.sections {
            let mut z2 = (b2 - a2) * v;
            let mut z1 = (b1 - a1) * v + z2;
            for sample in x.iter_mut() {
                let input = *sample;
                let output = b0 * input + z1;
                z1 = b1 * input - a1 * output + z2;
                z2 = b2 * input - a2 * output;
                *sample = output;
            }
        }
    }

    /// Magnitude of one forward pass at `freq_hz` (for tests).
    #[cfg(test)]
    fn gain(&self, freq_hz: f64, rate_hz: f64) -> f64 {
        let w = 2.0 * std::f64::consts::PI * freq_hz / rate_hz;
        let (s1, c1, s2, c2) = (w.sin(), w.cos(), (2.0 * w).sin(), (2.0 * w).cos());
        self.sections
            .iter()
            .map(|&[b0, b1, b2, a1, a2]| {
                let (nr, ni) = (b0 + b1 * c1 + b2 * c2, -(b1 * s1 + b2 * s2));
                let (dr, di) = (1.0 + a1 * c1 + a2 * c2, -(a1 * s1 + a2 * s2));
                ((nr * nr + ni * ni) / (dr * dr + di * di)).sqrt()
            })
            .product()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map(spec: &str) -> ColumnMap {
        ColumnMap::parse(spec).unwrap()
    }

    fn map_err(spec: &str) -> (String, String) {
        match ColumnMap::parse(spec) {
            Err(ImportError::BadMap { entry, reason }) => (entry, reason),
            other => panic!("expected BadMap for `{spec}`, got {other:?}"),
        }
    }

    #[test]
    fn parses_units_factors_and_spaces() {
        let m = map(
            " time_s = t[ms] , tangential_position_m=x[mm],normal_force_n=Fz*-0.001, friction_force_n=Fx[mN]*2 ",
        );
        assert_eq!(
            m.spec(),
            "time_s=t[ms],tangential_position_m=x[mm],normal_force_n=Fz*-0.001,friction_force_n=Fx[mN]*2"
        );
        let e = m.entries();
        assert_eq!(e.len(), 4);
        assert_eq!((e[0].target.as_str(), e[0].source.as_str()), ("time_s", "t"));
        assert_eq!(e[0].unit.as_deref(), Some("ms"));
        assert_eq!(e[0].scale.apply(1500.0), 1.5);
        assert_eq!(e[1].scale.apply(1.0), 0.001);
        assert_eq!(e[2].source, "Fz");
        assert_eq!(e[2].unit, None);
        assert_eq!(e[2].scale.apply(300.0), -0.3);
        assert_eq!(e[3].scale.apply(150.0), 0.3);
        assert_eq!(
            m.get("friction_force_n").map(|e| e.text.as_str()),
            Some("friction_force_n=Fx[mN]*2")
        );
        // Source names may contain spaces and odd characters; plain names have no scale.
        let m = map("depth_m=Tip depth (m),axial_force_n=F.axial,time_s=\"t\"");
        assert_eq!(m.entries()[0].source, "Tip depth (m)");
        assert_eq!(m.entries()[0].scale, Scale::IDENTITY);
        assert_eq!(m.entries()[2].source, "\"t\"");
        assert_eq!(map("accel_z_mps2=az[g]").entries()[0].scale.factor(), 9.806_65);
    }

    #[test]
    fn decimal_units_divide_exactly() {
        // 0.1 mm is the correctly rounded 1e-4 m (0.1 * 0.001 would not be).
        assert_eq!(map("depth_m=d[mm]").entries()[0].scale.apply(0.1), 1e-4);
        assert_eq!(map("depth_m=d[um]").entries()[0].scale.apply(3.0), 3e-6);
        assert_eq!(map("depth_m=d[µm]").entries()[0].scale.apply(3.0), 3e-6);
        assert_eq!(map("time_s=t[us]").entries()[0].scale.apply(7.0), 7e-6);
    }

    #[test]
    fn unit_table() {
        let cases = [
            ("m", Quantity::Length, 1.0),
            ("cm", Quantity::Length, 1e-2),
            ("mm", Quantity::Length, 1e-3),
            ("um", Quantity::Length, 1e-6),
            ("µm", Quantity::Length, 1e-6),
            ("s", Quantity::Time, 1.0),
            ("ms", Quantity::Time, 1e-3),
            ("us", Quantity::Time, 1e-6),
            ("N", Quantity::Force, 1.0),
            ("mN", Quantity::Force, 1e-3),
            ("kN", Quantity::Force, 1e3),
            ("m/s", Quantity::Velocity, 1.0),
            ("mm/s", Quantity::Velocity, 1e-3),
            ("m/s2", Quantity::Acceleration, 1.0),
            ("g", Quantity::Acceleration, 9.806_65),
        ];
        for (unit, quantity, factor) in cases {
            let (q, f) = unit_to_si(unit).unwrap();
            assert_eq!(q, quantity, "{unit}");
            assert!((f - factor).abs() <= 1e-15 * factor, "{unit}: {f} vs {factor}");
        }
        for unknown in ["MN", "inch", "", "G", "mm/s3"] {
            assert_eq!(unit_to_si(unknown), None, "{unknown}");
        }
        assert_eq!(
            Quantity::of_column("tangential_velocity_mps"),
            Some(Quantity::Velocity)
        );
        assert_eq!(Quantity::of_column("accel_x_mps2"), Some(Quantity::Acceleration));
        assert_eq!(Quantity::of_column("time_s"), Some(Quantity::Time));
        assert_eq!(Quantity::of_column("depth_m"), Some(Quantity::Length));
        assert_eq!(Quantity::of_column("axial_force_n"), Some(Quantity::Force));
    }

    #[test]
    fn map_errors_name_the_entry_and_reason() {
        let (entry, reason) = map_err("time_s=t,depth_m=d[ft]");
        assert_eq!(entry, "depth_m=d[ft]");
        assert!(
            reason.contains("unknown unit `ft`") && reason.contains("mm"),
            "{reason}"
        );
        let (entry, reason) = map_err("friction_force_n=x[mm]");
        assert_eq!(entry, "friction_force_n=x[mm]");
        assert!(
            reason.contains("length unit") && reason.contains("force"),
            "{reason}"
        );
        let (_, reason) = map_err("time_s=t,time_s=u");
        assert!(reason.contains("`time_s` is mapped more than once"), "{reason}");
        let (entry, reason) = map_err("pressure_pa=p");
        assert_eq!(entry, "pressure_pa=p");
        assert!(
            reason.contains("not a capture column") && reason.contains("depth_m"),
            "{reason}"
        );
        assert!(map_err("time_s").1.contains("expected `target=source`"));
        assert!(map_err("=t").1.contains("no target"));
        assert!(map_err("time_s=").1.contains("no source"));
        assert!(map_err("time_s=[ms]").1.contains("no source"));
        assert!(map_err("time_s=t,,depth_m=d").1.contains("empty entry"));
        assert!(map_err("time_s=t,").1.contains("empty entry"));
        assert!(map_err("").1.contains("empty"));
        assert!(
            map_err("time_s=t*x")
                .1
                .contains("scale factor `x` is not a number")
        );
        assert!(map_err("time_s=t*0").1.contains("non-zero"));
        assert!(map_err("time_s=t*inf").1.contains("finite"));
        assert!(map_err("time_s=t[ms").1.contains("brackets"));
        assert!(map_err("time_s=t]").1.contains("`]` without `[`"));
        let display = ColumnMap::parse("time_s=t[h]").unwrap_err().to_string();
        assert!(
            display.starts_with("--map entry `time_s=t[h]`: unknown unit `h`"),
            "{display}"
        );
    }

    #[test]
    fn delimiter_detection() {
        assert_eq!(
            detect_delimiter(b"# comment; with, stuff\n\na;b;c\n1;2;3\n"),
            b';'
        );
        assert_eq!(detect_delimiter(b"a\tb\tc\n"), b'\t');
        assert_eq!(detect_delimiter(b"\"x;y\",b,c\n"), b',');
        assert_eq!(detect_delimiter(b"a,b;c\n"), b';'); // tie: `;` before `,`
        assert_eq!(detect_delimiter(b"time\n1\n"), b',');
        assert_eq!(detect_delimiter(b""), b',');
    }

    #[test]
    fn interpolation_is_linear_and_exact_at_samples() {
        let t = [0.0, 1.0, 3.0];
        let x = [0.0, 2.0, -2.0];
        assert_eq!(
            interpolate(&t, &x, &[-1.0, 0.0, 0.5, 1.0, 2.0, 3.0, 4.0]),
            vec![0.0, 0.0, 1.0, 2.0, 0.0, -2.0, -2.0]
        );
    }

    #[test]
    fn butterworth_has_the_designed_response() {
        let rate = 10_000.0;
        let f = LowPass::butterworth4(400.0, rate);
        assert!((f.gain(0.0, rate) - 1.0).abs() < 1e-12);
        // −3 dB at the cut-off per pass.
        assert!((f.gain(400.0, rate) - 0.5_f64.sqrt()).abs() < 1e-9);
        // Bilinear 4th order: |H| = 1 / sqrt(1 + (tan(πf/fs) / tan(πfc/fs))^8).
        let ratio = (std::f64::consts::PI * 0.2).tan() / (std::f64::consts::PI * 0.04).tan();
        let expected = 1.0 / (1.0 + ratio.powi(8)).sqrt();
        assert!((f.gain(2000.0, rate) / expected - 1.0).abs() < 1e-6);
        // A constant and a ramp pass unchanged (steady-state start, odd reflection).
        let ramp: Vec<f64> = (0..500).map(|i| 0.3 + 0.01 * i as f64).collect();
        for (a, b) in f.filtfilt(&ramp).iter().zip(&ramp) {
            assert!((a - b).abs() < 1e-9, "{a} vs {b}");
        }
        assert_eq!(f.filtfilt(&[4.0]), vec![4.0]);
        assert!(f.filtfilt(&[1.0, 2.0]).iter().all(|v| v.is_finite()));
    }

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        path
    }

    fn rubbing(spec: &str) -> ImportSpec {
        ImportSpec::new(CaptureKind::Rubbing, map(spec))
    }

    const RUB_MAP: &str = "time_s=t[ms],tangential_position_m=x[mm],normal_force_n=Fz";

    #[test]
    fn imports_a_uniform_file_unchanged_with_metadata() {
        let dir = tempfile::tempdir().unwrap();
        let path = write(
            dir.path(),
            "log 1.csv",
            "\u{feff}# exported by a logger\n\"t\";\"x\";\"Fz\";\"other\"\n\n\
             0;1.5;0.3;a\n10;2.5;0.31;b\n20;3.5;0.32;c\r\n",
        );
        let mut spec = rubbing(&format!("{RUB_MAP}, friction_force_n=Fz*0.5"));
        spec.metadata.push(("surface".into(), "sandpaper_400".into()));
        let imported = import_csv_report(&path, &spec).unwrap();
        assert_eq!(imported.resampling, Resampling::PassThrough);
        assert_eq!(imported.rows_in, 3);
        assert_eq!(imported.rate_hz, 100.0);
        let c = imported.capture;
        assert_eq!(
            c.columns(),
            &[
                "time_s",
                "tangential_position_m",
                "normal_force_n",
                "friction_force_n"
            ]
        );
        assert_eq!(c.time(), &[0.0, 0.01, 0.02]);
        assert_eq!(
            c.column("tangential_position_m").unwrap(),
            &[0.0015, 0.0025, 0.0035]
        );
        assert_eq!(c.column("friction_force_n").unwrap(), &[0.15, 0.155, 0.16]);
        let m = c.metadata();
        assert_eq!(
            (m.kind(), m.device(), m.rate_hz()),
            (CaptureKind::Rubbing, "imported", 100.0)
        );
        assert_eq!(m.get("source"), Some("log_1.csv"));
        assert_eq!(
            m.get("map"),
            Some("time_s=t[ms],tangential_position_m=x[mm],normal_force_n=Fz,friction_force_n=Fz*0.5")
        );
        assert_eq!(m.get("source_rate_hz"), Some("100"));
        assert_eq!(m.get("surface"), Some("sandpaper_400"));
    }

    #[test]
    fn time_from_the_input_rate() {
        let dir = tempfile::tempdir().unwrap();
        let path = write(dir.path(), "a.tsv", "x\tFz\n1\t0.1\n2\t0.2\n3\t0.3\n4\t0.4\n");
        let mut spec = rubbing("tangential_position_m=x,normal_force_n=Fz");
        assert!(
            matches!(import_csv(&path, &spec), Err(ImportError::BadSpec { reason, .. }) if reason.contains("no time"))
        );
        spec.input_rate_hz = Some(4.0);
        spec.rate_hz = Some(8.0);
        let c = import_csv(&path, &spec).unwrap();
        assert_eq!(c.time(), &[0.0, 0.125, 0.25, 0.375, 0.5, 0.625, 0.75]);
        assert_eq!(
            c.column("tangential_position_m").unwrap(),
            &[1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0]
        );
        let mut both = rubbing("time_s=x,tangential_position_m=x,normal_force_n=Fz");
        both.input_rate_hz = Some(4.0);
        assert!(
            import_csv(&path, &both)
                .unwrap_err()
                .to_string()
                .contains("time is given twice")
        );
    }

    #[test]
    fn file_errors_name_file_line_and_column() {
        let dir = tempfile::tempdir().unwrap();
        let err = |text: &str, spec: &ImportSpec| {
            let path = write(dir.path(), "in.csv", text);
            import_csv(&path, spec).unwrap_err().to_string()
        };
        let spec = rubbing(RUB_MAP);
        let e = err("# c\nt,x,Fz\n0,1,2\n\n1,1x,2\n", &spec);
        assert!(e.ends_with("in.csv:5: column `x`: `1x` is not a number"), "{e}");
        let e = err("t;x;Fz\n0;1;2\n1;1,5;2\n", &spec);
        assert!(
            e.contains(":3: column `x`: `1,5` is not a number (decimal commas"),
            "{e}"
        );
        let e = err("t,x,Fz\n0,1,\n", &spec);
        assert!(e.contains(":2: column `Fz`: `` is not a number"), "{e}");
        let e = err("t,x,Fz\n0,1,2\n1,1,nan\n", &spec);
        assert!(e.contains(":3: column `Fz`: `nan` is not finite"), "{e}");
        let e = err("t,x,Fz\n0,1,2\n1,1\n", &spec);
        assert!(
            e.contains(":3: expected 3 fields like the header, found 2"),
            "{e}"
        );
        let e = err("t,x,Fz\n0,1,2\n2,1,2\n2,1,2\n", &spec);
        assert!(
            e.contains("in.csv:4: column `t`: time 0.002 s is not after the previous row's 0.002 s"),
            "{e}"
        );
        let e = err("t,x,Fz\n0,1,2\n1,1,2\n0.5,1,2\n", &spec);
        assert!(e.contains(":4:") && e.contains("not after"), "{e}");
        let e = err("t,x,Force\n0,1,2\n", &spec);
        assert!(
            e.contains(
                "--map entry `normal_force_n=Fz`: the input has no column `Fz` (its columns: t, x, Force)"
            ),
            "{e}"
        );
        let e = err("t,x,Fz,Fz\n0,1,2,3\n", &spec);
        assert!(e.contains("2 columns named `Fz`"), "{e}");
        let e = err("# only a comment\n\n", &spec);
        assert!(e.contains("no header row"), "{e}");
        let e = err("t,x,Fz\n0,1,2\n", &spec);
        assert!(e.contains("found 1 data row(s)"), "{e}");
        let e = err("t,x,Fz\n0,1,2\n1,\"2,3\n", &spec);
        assert!(e.contains("in.csv:"), "{e}");
        let e = err("t,x,Fz\n0,1,2\n1,1,2\n3,1,2\n", &spec);
        assert!(
            e.contains("not uniformly sampled") && e.contains("--rate-hz"),
            "{e}"
        );
        let missing = import_csv(Path::new("/nonexistent/in.csv"), &spec)
            .unwrap_err()
            .to_string();
        assert!(
            missing.starts_with("/nonexistent/in.csv: cannot read"),
            "{missing}"
        );
    }

    #[test]
    fn spec_errors_are_reported_before_reading() {
        let path = Path::new("never_read.csv");
        let e = |spec: &ImportSpec| import_csv(path, spec).unwrap_err().to_string();
        let missing = e(&rubbing("time_s=t,friction_force_n=f"));
        assert!(
            missing.starts_with(
                "never_read.csv: a rubbing capture needs `tangential_position_m`, `normal_force_n`"
            ),
            "{missing}"
        );
        let wrong = e(&rubbing(&format!("{RUB_MAP},depth_m=d")));
        assert!(
            wrong.contains("column `depth_m` is not allowed in a rubbing capture"),
            "{wrong}"
        );
        let mut spec = rubbing(RUB_MAP);
        spec.rate_hz = Some(-1.0);
        assert!(e(&spec).contains("--rate-hz -1: must be finite and positive"));
        let mut spec = rubbing(RUB_MAP);
        spec.device = "my rig".into();
        assert!(e(&spec).contains("metadata: value of `device`"), "{}", e(&spec));
        let mut spec = rubbing(RUB_MAP);
        spec.metadata.push(("surface".into(), "sand paper".into()));
        assert!(e(&spec).contains("value of `surface`"), "{}", e(&spec));
        let mut spec = rubbing(RUB_MAP);
        spec.metadata.push(("source".into(), "x".into()));
        assert!(e(&spec).contains("`source` is set by the import"), "{}", e(&spec));
        let mut spec = rubbing(RUB_MAP);
        spec.metadata.push(("kind".into(), "x".into()));
        assert!(e(&spec).contains("reserved"), "{}", e(&spec));
    }

    #[test]
    fn metadata_safe_values() {
        assert_eq!(metadata_safe("a b\tc"), "a_b_c");
        assert_eq!(metadata_safe("x[µm]"), "x[um]");
        assert_eq!(metadata_safe("é"), "_");
        assert_eq!(metadata_safe(""), "_");
        assert_eq!(snap_rate(999.999_999_999_7), 1000.0);
        assert_eq!(snap_rate(1000.5), 1000.5);
    }
}
