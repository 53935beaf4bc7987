//! Importing researchers' CSV logs as captures: a column mapping, unit conversion and
//! resampling, so recordings made with other tools need no conversion scripts.
//!
//! # Input
//!
//! Any CSV file with a header row. The delimiter is detected from the header line among `,`,
//! `;` and tab (the most frequent one outside quotes wins; a single column means `,`). Lines
//! starting with `#` and blank lines are skipped, header names may be quoted, and fields are
//! trimmed. A file without a header row is read with [`Header::Named`] (`--columns a,b,c`)
//! or [`Header::Numbered`] (`--no-header`: columns `0`, `1`, `2`, ... so `--map` names them
//! by index); then its first line is data. When a header row is expected and a mapped column
//! is missing, a first line made only of numbers is said to look like data.
//!
//! A delimiter at the end of every line (`t,x,Fz,` — robot-middleware exports write one) is
//! tolerated without an option: the header's empty last name is ignored, and rows may have
//! one field more than the header as long as that field is empty. Whether rows carry it is
//! decided by the first data row and must then hold for every row, and a non-empty extra
//! field is an error naming its line and field, so a row with a value too many is never
//! read as a trailing delimiter. Automatic because the one shape it accepts, an empty field
//! after the last named one on every row, holds no data to misread. Columns the [`ColumnMap`] does not mention are ignored; every mapped cell must be
//! a finite decimal number (a decimal comma is an error, not a guess) whose value in SI units
//! is within its target column's [`magnitude_limit`] (±10⁶ SI, ±10¹⁰ s for time): a logger's
//! `1e308` sentinel would otherwise pass as finite and the low-pass would spread it over
//! every output sample. With [`ImportSpec::drop_implausible`] (`--drop-implausible`), rows
//! with a finite but out-of-range mapped value are skipped and counted instead; the
//! resampling then bridges them like any gap.
//!
//! Non-finite cells (`nan`, `inf`, or a value that overflows on conversion) follow
//! [`ImportSpec::non_finite`] (`--non-finite error|drop|bridge`): an error naming line and
//! column, the row skipped, or the cell interpolated linearly in time from the finite cells
//! before and after it in its column ([`NonFinite::Bridge`]). A bridge spans at most
//! [`MAX_BRIDGE_ROWS`] consecutive rows, needs a finite neighbour on both sides (not at the
//! file's first or last row) and never applies to time, which places the row: anything else
//! is an error that says so, since a longer gap is missing data, not a dropout. Unset, the
//! mode is `drop` with `--drop-implausible` (which has always skipped non-finite rows) and
//! `error` without; so `--drop-implausible` decides about finite values, `--non-finite`, when
//! given, about NaN and infinity. Dropped rows are counted in [`Imported::rows_dropped`]
//! (those for a non-finite cell also in [`Imported::rows_non_finite`]), bridged cells in
//! [`Imported::cells_bridged`].
//!
//! Repeated timestamps (consecutive rows with the same time, as loggers that stamp with a
//! coarse clock write) are an error by default; [`ImportSpec::repeated_time`]
//! (`--repeated-time mean|drop`) merges each run of them into its mean or keeps its first
//! row, counted in [`Imported::rows_repeated`]. Only consecutive equal times are merged: a
//! time that goes back stays an error.
//!
//! # Packed rows
//!
//! Some rigs log a fast channel several samples per row: a 2.2 kHz accelerometer as 22
//! columns `acc_0` to `acc_21` of each 100 Hz row, with one timestamp per row.
//! [`ImportSpec::unroll`] (`--unroll 'acc=acc_0..acc_21'`, see [`Unroll`]) makes the packed
//! columns of each row consecutive samples of a virtual column `acc`, spaced evenly over the
//! row's interval (the time to the next row; for the last row, the median row interval), and
//! `--map` reads `acc` like any other column (`accel_x_mps2=acc[g]`). The other mapped
//! columns are linearly interpolated between their row's value and the next row's
//! ([`SlowColumns::Interpolate`], the default: a slow force sampled once a row is a line
//! between rows, not a staircase) or held over the row ([`SlowColumns::Hold`],
//! `--unroll-slow hold`); the last row holds its values. Each packed column is read, checked
//! and bridged like a mapped one, before unrolling; the unrolled samples then go through
//! the resampling below like any input, and [`Imported::rows_in`] counts them. Needs a time
//! column; a packed column missing, a column next to the range (`acc_22`: samples left out
//! would shift the rest), or row times that do not increase is an error naming the file and
//! the column (and line).
//!
//! # Several inputs
//!
//! Rigs often log each sensor to its own file on its own clock: forces in one at ~88 Hz,
//! position in another at slightly different instants, a vibration channel packed in a
//! third. [`import_streams`] joins such files into one capture (`palpus import force.csv
//! position.csv vib.csv --rate-hz 1000 --map ...`); [`import_csv_report`] is its one-input
//! case, so a single file goes through the same code.
//!
//! Inputs are numbered from 1 in the order given. `time_s=t[ms]` names the time column every
//! input has, each input being read on its own; `time_s=3:stamp[us]` gives input 3 a time
//! column of its own (the unqualified entry then serves the others). Any other source is
//! looked up among the inputs' columns (plus the virtual [`Unroll`] column in the inputs
//! that have its packed columns) and must be in exactly one: a column in several
//! ([`SourceInSeveralInputs`](crate::CaptureErrorKind::SourceInSeveralInputs)) or in none
//! ([`SourceInNoInput`](crate::CaptureErrorKind::SourceInNoInput), listing every input's
//! columns) is an error naming the files. `2:x[mm]` reads `x` from input 2 whatever the
//! others have. Every input must give at least one column besides its time. The options on
//! how to read a file ([`ImportSpec::header`], `repeated_time`, `non_finite`,
//! `drop_implausible`) apply to every input; [`ImportSpec::unroll`] to the inputs whose
//! entries read its virtual column.
//!
//! Each input is read, cleaned (dropped, bridged, merged rows), unrolled and checked as a
//! single file is, then shifted by its clock offset if one is given
//! ([`ImportSpec::clock_offsets_s`], `--clock-offset-s 2=0.013`: 13 ms added to input 2's
//! times). The output grid runs at [`ImportSpec::rate_hz`] (required) from the latest first
//! time to the earliest last time of the inputs, so every output sample is inside every
//! input; what an input has outside is cut and reported ([`StreamReport::cut_start_s`],
//! [`StreamReport::cut_end_s`]). An overlap of fewer than [`MIN_JOINED_ROWS`] output samples
//! is an error ([`NoOverlap`](crate::CaptureErrorKind::NoOverlap)) listing each file's time
//! range. Each input is then resampled onto the grid by the rule below, decided by its own
//! measured rate: interpolated if it is below `1 + RATE_TOLERANCE` times the output rate,
//! else low-passed over its whole length first (so the cut adds no filter edge). Nothing is
//! passed through unchanged: the grid starts at another input's time. The output budget
//! below holds per input. The metadata names every input in `source` (comma-separated) and,
//! per input `N`, `source_N` (file name), `source_N_sha256`, `source_N_map` (its entries),
//! `source_N_rate_hz` (its mean rate) and `source_N_clock_offset_s` where given, instead of
//! `source_rate_hz`. One input may be given a clock offset too (`source_1_clock_offset_s`).
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
//! A source starting with digits and a colon names an input ([several
//! inputs](#several-inputs)): `2:x[mm]` is column `x` of input 2, so a column whose own name
//! starts that way cannot be mapped (`Fz:1` or `t:ms` are names as they stand).
//!
//! # Time and resampling
//!
//! Time comes from the column mapped to `time_s`; for logs without one, from the input
//! rate (`input_rate_hz`: sample `i` at `i / rate`); or, for curves digitized against
//! position (force–depth plots have no time), from a position column at a known constant
//! speed ([`ImportSpec::time_from_position`], `--time-from-position 'depth[mm]' --speed-mps
//! 0.005`): `time = (position − first position) / speed`. The position's unit is required,
//! and the speed's sign is the stroke direction: the position must strictly advance in it
//! (a row that does not is an error naming its line; equal positions are repeated times, see
//! below). Time must be finite and strictly increasing. The output is a uniform grid at the
//! target rate starting at the first input time (`t0 + k / rate`, up to the last input time).
//! Which of the three paths below is taken depends on the measured mean rate compared with
//! the target, with a relative tolerance [`RATE_TOLERANCE`] (1 %), so two logs of the same
//! nominal rate take the same path whatever their clock's error:
//!
//! * **Pass-through.** If every input interval is within 1e-6 (relative) of the target
//!   period, the samples already are that grid: times and values are copied unchanged (after
//!   unit conversion). A capture written at 1 kHz and re-imported at 1 kHz is bit-for-bit
//!   the converted input.
//! * **Interpolation.** When the input's mean rate is below the target's `1 + RATE_TOLERANCE`
//!   times (upsampling, or the same nominal rate with a clock error or jittered timestamps),
//!   each output sample is the linear interpolation of the two input samples around it. For
//!   an input up to 1 % faster, what is not low-passed lies in the top 1 % of its band.
//!   Linear interpolation adds no overshoot and its error is bounded by `h² / 8 · max|x''|`
//!   (`h` the input interval); it cannot create detail the input did not record.
//! * **Low-pass, then interpolation.** When the input's mean rate is above the target's
//!   `1 + RATE_TOLERANCE` times, content above the new Nyquist frequency would fold back into the band the models use
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
//! # Size budget
//!
//! The output's size is checked before anything of that size is allocated: rates
//! (`--rate-hz`, `--input-rate-hz`) must be from [`MIN_RATE_HZ`] to [`MAX_RATE_HZ`], the
//! output may have at most [`ImportSpec::max_upsample`] times the input's rows (default
//! [`DEFAULT_MAX_UPSAMPLE`], `--max-upsample`), and an output larger than its input at most
//! [`MAX_OUTPUT_ROWS`] rows. So a few bytes of input with a wrong time unit are an error
//! naming the numbers, not gigabytes of capture.
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
//! `source_rate_hz=<mean input rate>` (with several inputs, the per-input keys of
//! [Several inputs](#several-inputs) instead) and the caller's extra keys (e.g. `surface=...`, which
//! the recognizers read as the class). Derived values are made metadata-safe (`µ` becomes
//! `u`, other non-printable-ASCII characters `_`); the caller's own values are checked and
//! rejected with a clear error instead.

use std::fmt;
use std::path::{Path, PathBuf};

use crate::error::CaptureErrorKind;
use crate::kind::{CaptureKind, TIME_S, magnitude_limit};
use crate::{Capture, CaptureError, Metadata, OutputBudget, SpanMismatch};

mod column_map;
mod join;
mod resample;
mod table;
mod units;
mod unroll;

pub use column_map::*;
use join::*;
use resample::*;
use table::*;
pub use units::*;
pub use unroll::*;

/// Metadata keys [`import_csv`] sets itself; the caller's extra metadata may not use them
/// (nor `source_N...`, set per input by [`import_streams`]).
pub const IMPORT_KEYS: [&str; 4] = ["source", "map", "source_rate_hz", "time_from"];

/// Relative tolerance on sampling intervals under which an input counts as uniform.
pub const UNIFORM_TOLERANCE: f64 = 1e-6;

/// Relative tolerance between the input's mean rate and the target rate under which they
/// count as the same rate: the input is interpolated onto the grid, not low-passed.
pub const RATE_TOLERANCE: f64 = 0.01;

/// Most consecutive non-finite cells of one column [`NonFinite::Bridge`] interpolates over
/// (10 ms at 1 kHz): a dropout, where a longer run is missing data.
pub const MAX_BRIDGE_ROWS: usize = 10;

/// Anti-aliasing cut-off as a fraction of the target rate.
pub const CUTOFF_FRACTION: f64 = 0.4;

/// Reflected padding at each end of the anti-aliasing filter, in cut-off periods (the
/// filter's impulse response has decayed to ~1e-4 after about five).
const PAD_CUTOFF_PERIODS: f64 = 8.0;

/// Slowest output or input rate accepted, Hz. Below 1 Hz nothing a haptic model uses is left,
/// and a rate given in kHz by mistake (`--rate-hz 1` for 1 kHz) still passes, but a rate
/// of 0.001 cannot be meant.
pub const MIN_RATE_HZ: f64 = 1.0;

/// Fastest output or input rate accepted, Hz. Haptic loops run at 1 kHz and texture
/// accelerometers are sampled at up to a few tens of kHz, so 100 kHz covers every rig while
/// a time unit mistaken by 10³ or more (`--rate-hz 3e7`) is refused before it allocates.
pub const MAX_RATE_HZ: f64 = 1e5;

/// Default of [`ImportSpec::max_upsample`]: an output may have at most this many times the
/// input's rows (1 Hz to 1 kHz, or 100 Hz to 100 kHz). More is not resampling but inventing
/// samples, usually from a wrong time unit (a 2-row log spanning 10⁵ s at 1 kHz would be
/// 10⁸ rows, 3.8 GB).
pub const DEFAULT_MAX_UPSAMPLE: f64 = 1000.0;

/// Largest output of an import that is bigger than its input, in rows, whatever
/// [`ImportSpec::max_upsample`] says: 10⁷ rows is 2.8 h at 1 kHz or 100 s at 100 kHz, and
/// about 80 MB per column in memory (the output is built in memory before it is written). An
/// output no larger than its input (pass-through, downsampling) is not limited: the input was
/// already read into memory.
pub const MAX_OUTPUT_ROWS: usize = 10_000_000;

/// Fewest output samples a join of several inputs may have: a shorter overlap is clocks in
/// different origins or units (or an offset given wrongly), not a recording.
pub const MIN_JOINED_ROWS: usize = 4;

/// Inputs of one recording whose time spans differ by more than this factor are refused
/// ([`CaptureErrorKind::SpansDisagree`]): a clock counting milliseconds read as seconds spans
/// 1000 times the others, and the overlap would keep a few of its rows.
pub const MAX_SPAN_RATIO: f64 = 10.0;

/// Refuses inputs whose spans lie more than [`MAX_SPAN_RATIO`] apart (the longest against the
/// shortest).
fn check_spans(paths: &[&Path], streams: &[Stream]) -> Result<(), CaptureError> {
    let span = |s: &Stream| s.time[s.time.len() - 1] - s.time[0];
    let order = |a: &&(&&Path, &Stream), b: &&(&&Path, &Stream)| span(a.1).total_cmp(&span(b.1));
    let pairs: Vec<(&&Path, &Stream)> = paths.iter().zip(streams).collect();
    let (Some(short), Some(long)) = (pairs.iter().min_by(order), pairs.iter().max_by(order)) else {
        return Ok(());
    };
    let (short_s, long_s) = (span(short.1), span(long.1));
    if short_s > 0.0 && long_s > MAX_SPAN_RATIO * short_s {
        let rate = |s: &Stream, span_s: f64| (s.time.len() - 1) as f64 / span_s;
        return Err(CaptureError::without_file(CaptureErrorKind::SpansDisagree(
            Box::new(SpanMismatch {
                long: long.0.to_path_buf(),
                long_s,
                long_rate_hz: rate(long.1, long_s),
                short: short.0.to_path_buf(),
                short_s,
                short_rate_hz: rate(short.1, short_s),
                ratio: MAX_SPAN_RATIO,
            }),
        )));
    }
    Ok(())
}

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
    /// The output may have at most this many times the input's rows (default
    /// [`DEFAULT_MAX_UPSAMPLE`]); never more than [`MAX_OUTPUT_ROWS`] when it grows. Must be
    /// finite and at least 1.
    pub max_upsample: f64,
    /// Skip rows with a finite mapped value beyond its target's [`magnitude_limit`] (counted
    /// in [`Imported::rows_dropped`]) instead of failing on them.
    pub drop_implausible: bool,
    /// What to do with non-finite mapped cells; `None`: [`NonFinite::Drop`] with
    /// `drop_implausible`, else [`NonFinite::Error`].
    pub non_finite: Option<NonFinite>,
    /// Derive time from a position column at a constant speed (no `time_s` in the map and no
    /// `input_rate_hz` then).
    pub time_from_position: Option<TimeFromPosition>,
    /// Where the column names come from (default: the first line).
    pub header: Header,
    /// What to do with consecutive rows of the same time (default: an error).
    pub repeated_time: RepeatedTime,
    /// A fast channel packed several samples per row, unrolled into a virtual column that
    /// the map reads (`--unroll`); needs a time column. With several inputs it applies to
    /// those whose mapped columns read the virtual column.
    pub unroll: Option<Unroll>,
    /// Clock offsets, s, by 1-based input number (`--clock-offset-s 2=0.013`): the offset is
    /// added to that input's times before the inputs are joined. Each input at most once.
    pub clock_offsets_s: Vec<(usize, f64)>,
}

/// Where an input's column names come from.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Header {
    /// The first line that is not a comment or blank names the columns.
    #[default]
    FirstLine,
    /// The file has no header row; these are its columns' names (`--columns`).
    Named(Vec<String>),
    /// The file has no header row; its columns are named `0`, `1`, `2`, ... (`--no-header`).
    Numbered,
}

/// What to do with consecutive input rows that have the same time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RepeatedTime {
    /// Refuse the input, naming the line (time must strictly increase).
    #[default]
    Error,
    /// Replace each run of rows with the same time by one row, the mean of every column.
    Mean,
    /// Keep the first row of each run of rows with the same time.
    Drop,
}

/// What to do with a non-finite mapped cell (`nan`, `inf`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NonFinite {
    /// Refuse the input, naming line and column.
    #[default]
    Error,
    /// Skip the row.
    Drop,
    /// Interpolate the cell linearly in time from its column's finite neighbours (at most
    /// [`MAX_BRIDGE_ROWS`] in a row, not at the file's ends, not in the time column).
    Bridge,
}

impl std::str::FromStr for NonFinite {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "error" => Ok(NonFinite::Error),
            "drop" => Ok(NonFinite::Drop),
            "bridge" => Ok(NonFinite::Bridge),
            _ => Err(format!("`{s}`: expected drop, bridge or error")),
        }
    }
}

/// Time from position at a constant speed: `time = (position − first position) / speed`.
#[derive(Debug, Clone, PartialEq)]
pub struct TimeFromPosition {
    /// The input column holding the position.
    pub source: String,
    /// The position's unit (a length unit of the [unit table](unit_to_si)).
    pub unit: String,
    /// The speed, m/s; its sign is the direction the position advances in.
    pub speed_mps: f64,
    scale: Scale,
}

impl TimeFromPosition {
    /// `column` is `name[unit]` with a length unit (`depth[mm]`); the speed must be finite
    /// and non-zero.
    pub fn new(column: &str, speed_mps: f64) -> Result<Self, CaptureError> {
        let bad = |reason: String| {
            CaptureError::without_file(CaptureErrorKind::BadSpec(format!(
                "--time-from-position `{column}`: {reason}"
            )))
        };
        let units = units_of(Quantity::Length);
        let (name, unit) = column
            .trim()
            .strip_suffix(']')
            .and_then(|rest| rest.rsplit_once('['))
            .map(|(name, unit)| (name.trim(), unit.trim()))
            .ok_or_else(|| {
                bad(format!(
                    "give the position's unit in brackets, e.g. `depth[mm]` ({units})"
                ))
            })?;
        if name.is_empty() {
            return Err(bad("no column name before the unit".into()));
        }
        let scale = match unit_scale(unit) {
            Some((Quantity::Length, scale)) => scale,
            _ => return Err(bad(format!("`{unit}` is not a length unit ({units})"))),
        };
        if !(speed_mps.is_finite() && speed_mps != 0.0) {
            return Err(bad(format!(
                "--speed-mps {speed_mps}: must be finite and non-zero (its sign is the stroke \
                 direction)"
            )));
        }
        Ok(TimeFromPosition {
            source: name.to_owned(),
            unit: unit.to_owned(),
            speed_mps,
            scale,
        })
    }

    /// The map entry reading the position as seconds from an arbitrary origin.
    fn time_entry(&self) -> MapEntry {
        MapEntry {
            target: TIME_S.to_owned(),
            source: self.source.clone(),
            input: None,
            unit: Some(self.unit.clone()),
            scale: Scale {
                mul: self.scale.mul,
                div: self.scale.div * self.speed_mps,
            },
            text: format!("--time-from-position {}[{}]", self.source, self.unit),
        }
    }

    /// The `time_from` metadata value.
    fn describe(&self) -> String {
        format!("{}[{}]@{}mps", self.source, self.unit, self.speed_mps)
    }
}

impl std::str::FromStr for RepeatedTime {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "error" => Ok(RepeatedTime::Error),
            "mean" => Ok(RepeatedTime::Mean),
            "drop" => Ok(RepeatedTime::Drop),
            _ => Err(format!("`{s}`: expected mean, drop or error")),
        }
    }
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
            max_upsample: DEFAULT_MAX_UPSAMPLE,
            drop_implausible: false,
            non_finite: None,
            time_from_position: None,
            header: Header::FirstLine,
            repeated_time: RepeatedTime::Error,
            unroll: None,
            clock_offsets_s: Vec::new(),
        }
    }
}

/// How the samples were put on the output grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Resampling {
    /// The input already was the output grid; values copied.
    PassThrough,
    /// Linear interpolation (upsampling, or an input rate within [`RATE_TOLERANCE`] of the
    /// target: jitter or a clock's error at the same nominal rate).
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
    /// Data rows read from the input and used (without the dropped ones, and counting each
    /// run of repeated times merged by [`ImportSpec::repeated_time`] once); with
    /// [`ImportSpec::unroll`], the unrolled samples.
    pub rows_in: usize,
    /// Rows skipped for an implausible value (with [`ImportSpec::drop_implausible`]) or a
    /// non-finite one (with [`NonFinite::Drop`]).
    pub rows_dropped: usize,
    /// Of [`Imported::rows_dropped`], those skipped for a non-finite value.
    pub rows_non_finite: usize,
    /// Non-finite cells interpolated from their neighbours ([`NonFinite::Bridge`]).
    pub cells_bridged: usize,
    /// Rows merged into the row before them (or dropped) for repeating its time (with
    /// [`RepeatedTime::Mean`] or [`RepeatedTime::Drop`]; else 0).
    pub rows_repeated: usize,
    /// The input's mean rate, Hz: `(rows − 1) / (last time − first time)`.
    pub source_rate_hz: f64,
    /// The output rate, Hz.
    pub rate_hz: f64,
    /// How the output grid was filled.
    pub resampling: Resampling,
    /// Each input, in input order (one for [`import_csv_report`]). With several inputs the
    /// counts above are their sums, and `source_rate_hz` and `resampling` those of the first
    /// input; see here for the others.
    pub streams: Vec<StreamReport>,
}

/// What the import did with one of its inputs.
#[derive(Debug, Clone, PartialEq)]
pub struct StreamReport {
    /// The input file.
    pub file: PathBuf,
    /// SHA-256 of its bytes, hex.
    pub sha256: String,
    /// The `--map` entries read from it (its time included), as written, comma-separated.
    pub map: String,
    /// Rows read and used, as [`Imported::rows_in`].
    pub rows_in: usize,
    /// Rows skipped, as [`Imported::rows_dropped`].
    pub rows_dropped: usize,
    /// Of `rows_dropped`, those for a non-finite value.
    pub rows_non_finite: usize,
    /// Non-finite cells bridged.
    pub cells_bridged: usize,
    /// Rows merged for a repeated time.
    pub rows_repeated: usize,
    /// Its mean rate, Hz, which decided how it was resampled.
    pub source_rate_hz: f64,
    /// How it was put on the output grid.
    pub resampling: Resampling,
    /// The clock offset added to its times, s (0 unless given).
    pub clock_offset_s: f64,
    /// Its first time, s, offset applied.
    pub first_time_s: f64,
    /// Its last time, s, offset applied.
    pub last_time_s: f64,
    /// How much of its start lies before the output's first sample, s (the other inputs
    /// start later); 0 for one input.
    pub cut_start_s: f64,
    /// How much of its end lies after the earliest last time of the inputs, s (the other
    /// inputs end earlier); 0 for one input. The output's last sample is less than one
    /// output period before that time.
    pub cut_end_s: f64,
}

// --- Import ------------------------------------------------------------------------------

/// Refuses an output that is one of `inputs` (the same file, by whatever path): every input
/// is read before the capture is written, so the write would replace that input with the
/// capture made from it.
pub fn check_output(out: &Path, inputs: &[&Path]) -> Result<(), CaptureError> {
    let Ok(out_file) = out.canonicalize() else {
        // An output that does not exist yet is no input.
        return Ok(());
    };
    match inputs
        .iter()
        .find(|input| input.canonicalize().is_ok_and(|f| f == out_file))
    {
        Some(input) => Err(CaptureError::new(
            input,
            CaptureErrorKind::BadSpec(format!(
                "--out {} is this input: the capture would replace it; write it to another file",
                out.display()
            )),
        )),
        None => Ok(()),
    }
}

/// Imports the CSV file at `path` as a capture, as described in the
/// [module documentation](self). Nothing is written; see [`Capture::write_file`].
///
/// Every error names the file, and the line, column or `--map` entry where one applies.
pub fn import_csv(path: &Path, spec: &ImportSpec) -> Result<Capture, CaptureError> {
    import_csv_report(path, spec).map(|imported| imported.capture)
}

/// [`import_csv`], also returning the row count, rates and the resampling applied: the
/// one-input case of [`import_streams`].
pub fn import_csv_report(path: &Path, spec: &ImportSpec) -> Result<Imported, CaptureError> {
    import_streams(&[path], spec)
}

/// Imports several CSV files recorded on separate clocks as one capture, each read on its
/// own time column and all resampled onto one uniform grid, as the
/// [module documentation](self#several-inputs) says; one path is [`import_csv_report`].
///
/// Every error names the file (or, for an unqualified column found in several inputs or in
/// none, every input), and the line, column or `--map` entry where one applies.
pub fn import_streams(paths: &[&Path], spec: &ImportSpec) -> Result<Imported, CaptureError> {
    let Some(&first) = paths.first() else {
        return Err(CaptureError::without_file(CaptureErrorKind::BadSpec(
            "no input file given".into(),
        )));
    };
    let single = paths.len() == 1;
    let fail = |kind| CaptureError::new(first, kind);
    // With one input a spec error names it, as the single-file import always did; with
    // several it concerns them all, and the message names the option.
    let bad_spec = |reason: String| {
        let error = CaptureError::without_file(CaptureErrorKind::BadSpec(reason));
        CaptureError {
            file: single.then(|| first.to_path_buf()),
            ..error
        }
    };
    if !single {
        for (what, given) in [
            ("--input-rate-hz", spec.input_rate_hz.is_some()),
            ("--time-from-position", spec.time_from_position.is_some()),
        ] {
            if given {
                return Err(bad_spec(format!(
                    "{what} is for one input; joining several needs each one's time column \
                     (`time_s=<column>` in --map)"
                )));
            }
        }
        if spec.rate_hz.is_none() {
            return Err(bad_spec(
                "joining several inputs needs the output rate (--rate-hz): their own rates \
                 differ"
                    .into(),
            ));
        }
    }
    let with_time;
    let spec = match &spec.time_from_position {
        Some(from) => {
            if let Some(entry) = spec.map.get(TIME_S) {
                return Err(bad_spec(format!(
                    "time is given twice: by --map entry `{}` and by --time-from-position; give one",
                    entry.text
                )));
            }
            if spec.input_rate_hz.is_some() {
                return Err(bad_spec(
                    "time is given twice: by --input-rate-hz and by --time-from-position; give one".into(),
                ));
            }
            // Time is read like a mapped column, so units, limits, non-finite cells and
            // repeated values are handled as for a time column.
            let mut extended = spec.clone();
            extended.map.entries.push(from.time_entry());
            with_time = extended;
            &with_time
        }
        None => spec,
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
        if let Some(rate) = rate {
            if !(rate.is_finite() && rate > 0.0) {
                return Err(bad_spec(format!("{what} {rate}: must be finite and positive")));
            }
            if !(MIN_RATE_HZ..=MAX_RATE_HZ).contains(&rate) {
                return Err(bad_spec(format!(
                    "{what} {rate}: must be from {MIN_RATE_HZ} to {MAX_RATE_HZ} Hz (check the unit)"
                )));
            }
        }
    }
    if spec.repeated_time != RepeatedTime::Error && time_entry.is_none() {
        return Err(bad_spec(
            "--repeated-time needs a time column (`time_s=<column>` in --map); with \
             --input-rate-hz every row has its own time"
                .into(),
        ));
    }
    if let Header::Named(names) = &spec.header
        && (names.is_empty() || names.iter().any(|n| n.trim().is_empty()))
    {
        return Err(bad_spec(format!(
            "--columns `{}`: every column needs a name (`a,b,c`)",
            names.join(",")
        )));
    }
    if !(spec.max_upsample.is_finite() && spec.max_upsample >= 1.0) {
        return Err(bad_spec(format!(
            "--max-upsample {}: must be finite and at least 1",
            spec.max_upsample
        )));
    }
    let offsets = clock_offsets(paths, spec).map_err(&bad_spec)?;
    // Check the caller's metadata before reading a possibly large file.
    let mut meta = Metadata::new(spec.kind, spec.device.clone(), spec.rate_hz.unwrap_or(1.0));
    for (key, value) in &spec.metadata {
        if IMPORT_KEYS.contains(&key.as_str()) || is_stream_key(key) {
            return Err(bad_spec(format!(
                "metadata key `{key}` is set by the import itself (from the input)"
            )));
        }
        meta = meta.with(key, value);
    }
    meta.validate().map_err(|kind| bad_spec(metadata_reason(kind)))?;

    let specs = resolve(paths, spec)?;
    let streams = paths
        .iter()
        .zip(&specs)
        .zip(&offsets)
        .map(|((path, file_spec), &offset_s)| read_stream(path, file_spec, offset_s))
        .collect::<Result<Vec<_>, _>>()?;

    check_spans(paths, &streams)?;
    // The grid spans the time all inputs cover; with one input, all of it.
    let lo = streams
        .iter()
        .map(|s| s.time[0])
        .fold(f64::NEG_INFINITY, f64::max);
    let hi = streams
        .iter()
        .map(|s| s.time[s.time.len() - 1])
        .fold(f64::INFINITY, f64::min);
    let rate_hz = match spec.rate_hz {
        Some(rate) => rate,
        None => {
            // Only one input gets here (several need --rate-hz).
            let stream = &streams[0];
            let rate = snap_rate(stream.source_rate_hz);
            if !is_uniform(&stream.time, rate) {
                let (min, max) = interval_range(&stream.time);
                return Err(fail(CaptureErrorKind::NotUniform {
                    min_interval_s: min,
                    max_interval_s: max,
                    mean_rate_hz: stream.source_rate_hz,
                }));
            }
            rate
        }
    };
    let span = hi - lo;
    // The budget is checked in floating point before anything of the output's size exists.
    let rows_out = (span * rate_hz + UNIFORM_TOLERANCE).floor() + 1.0;
    if !single && (rows_out.is_nan() || rows_out < MIN_JOINED_ROWS as f64) {
        return Err(CaptureError::without_file(CaptureErrorKind::NoOverlap {
            rows: if rows_out > 0.0 { rows_out as usize } else { 0 },
            rate_hz,
            min_rows: MIN_JOINED_ROWS,
            ranges: paths
                .iter()
                .zip(&streams)
                .map(|(path, s)| (path.to_path_buf(), s.time[0], s.time[s.time.len() - 1]))
                .collect(),
        }));
    }
    let too_many = |path: &Path, rows_in: usize, limit: f64, reason| {
        CaptureError::new(
            path,
            CaptureErrorKind::TooManyRows(Box::new(OutputBudget {
                rows: rows_out,
                rate_hz,
                span_s: span,
                rows_in,
                limit,
                reason,
            })),
        )
    };
    // Each stream may be upsampled at most --max-upsample times: a stream with too few rows
    // for the grid is as likely a wrong time unit as a single file is.
    for (path, stream) in paths.iter().zip(&streams) {
        let upsample_limit = spec.max_upsample * stream.rows_in as f64;
        if rows_out.is_nan() || rows_out > upsample_limit {
            return Err(too_many(
                path,
                stream.rows_in,
                upsample_limit,
                "the input's rows times --max-upsample",
            ));
        }
    }
    let (largest, most_rows_in) = paths
        .iter()
        .zip(&streams)
        .map(|(path, s)| (*path, s.rows_in))
        .max_by_key(|&(_, rows)| rows)
        .unwrap_or((first, 0));
    if rows_out > MAX_OUTPUT_ROWS as f64 && rows_out > most_rows_in as f64 {
        return Err(too_many(
            largest,
            most_rows_in,
            MAX_OUTPUT_ROWS as f64,
            "the most an import may add, whatever --max-upsample says",
        ));
    }
    let rows_out = rows_out as usize;

    // One input already uniform at the output rate is copied as it is; otherwise every
    // stream is resampled onto the same grid, each by its own measured rate.
    let pass_through = single && is_uniform(&streams[0].time, rate_hz);
    let grid: Vec<f64> = if pass_through {
        streams[0].time.clone()
    } else {
        (0..rows_out).map(|k| lo + k as f64 / rate_hz).collect()
    };
    let mut resampled = Vec::with_capacity(streams.len());
    for stream in &streams {
        resampled.push(if pass_through {
            (stream.columns.clone(), Resampling::PassThrough)
        } else {
            resample_stream(stream, &grid, rate_hz)
        });
    }

    // Column order: time first, then the other targets in map order.
    let mut columns = vec![TIME_S.to_owned()];
    let mut data = vec![grid];
    for entry in spec.map.entries.iter().filter(|e| e.target != TIME_S) {
        let (s, c) = streams
            .iter()
            .enumerate()
            .find_map(|(s, stream)| {
                let c = stream.targets.iter().position(|t| *t == entry.target)?;
                Some((s, c))
            })
            .ok_or_else(|| bad_spec(format!("--map entry `{}` was read from no input", entry.text)))?;
        let column = std::mem::take(&mut resampled[s].0[c]);
        // Inputs are within their limits, but the low-pass can overshoot a step by a few
        // percent, so a value just inside a limit may come out just beyond it; refuse rather
        // than write a capture that no reader would accept.
        let limit = magnitude_limit(&entry.target);
        if let Some(&value) = column.iter().find(|v| v.is_nan() || v.abs() > limit) {
            return Err(
                CaptureError::new(paths[s], CaptureErrorKind::Implausible { value, limit })
                    .in_column(&entry.target),
            );
        }
        columns.push(entry.target.clone());
        data.push(column);
    }

    let file_name = |path: &Path| {
        path.file_name()
            .map(|name| name.to_string_lossy().into_owned())
            .unwrap_or_else(|| path.display().to_string())
    };
    let names: Vec<String> = paths.iter().map(|p| metadata_safe(&file_name(p))).collect();
    let mut meta = Metadata::new(spec.kind, spec.device.clone(), rate_hz)
        .with("source", names.join(","))
        .with("map", metadata_safe(spec.map.spec()));
    if single {
        meta = meta.with("source_rate_hz", snap_rate(streams[0].source_rate_hz));
        // Rare for one input, but a shifted clock must not go unrecorded.
        if offsets[0] != 0.0 {
            meta = meta.with("source_1_clock_offset_s", offsets[0]);
        }
    } else {
        for (i, ((name, stream), offset_s)) in names.iter().zip(&streams).zip(&offsets).enumerate() {
            let key = |what: &str| format!("source_{}{what}", i + 1);
            meta = meta
                .with(key(""), name)
                .with(key("_sha256"), &stream.sha256)
                .with(key("_map"), metadata_safe(&stream.map))
                .with(key("_rate_hz"), snap_rate(stream.source_rate_hz));
            if *offset_s != 0.0 {
                meta = meta.with(key("_clock_offset_s"), offset_s);
            }
        }
    }
    if let Some(from) = &spec.time_from_position {
        meta = meta.with("time_from", metadata_safe(&from.describe()));
    }
    for (key, value) in &spec.metadata {
        meta = meta.with(key, value);
    }
    // Should not happen: everything was checked above. If it does, name the input file; the
    // line dropped is a line of the output, which the user never sees.
    let capture = Capture::new(meta, columns, data).map_err(|e| CaptureError {
        file: Some(first.to_path_buf()),
        line: None,
        ..e
    })?;
    let reports: Vec<StreamReport> = paths
        .iter()
        .zip(streams)
        .zip(resampled)
        .zip(&offsets)
        .map(|(((path, stream), (_, resampling)), &clock_offset_s)| {
            let (first_s, last_s) = (stream.time[0], stream.time[stream.time.len() - 1]);
            StreamReport {
                file: path.to_path_buf(),
                sha256: stream.sha256,
                map: stream.map,
                rows_in: stream.rows_in,
                rows_dropped: stream.rows_dropped,
                rows_non_finite: stream.rows_non_finite,
                cells_bridged: stream.cells_bridged,
                rows_repeated: stream.rows_repeated,
                source_rate_hz: stream.source_rate_hz,
                resampling,
                clock_offset_s,
                first_time_s: first_s,
                last_time_s: last_s,
                cut_start_s: lo - first_s,
                cut_end_s: last_s - hi,
            }
        })
        .collect();
    let total = |count: fn(&StreamReport) -> usize| reports.iter().map(count).sum::<usize>();
    Ok(Imported {
        capture,
        rows_in: total(|s| s.rows_in),
        rows_dropped: total(|s| s.rows_dropped),
        rows_non_finite: total(|s| s.rows_non_finite),
        cells_bridged: total(|s| s.cells_bridged),
        rows_repeated: total(|s| s.rows_repeated),
        source_rate_hz: reports[0].source_rate_hz,
        rate_hz,
        resampling: reports[0].resampling,
        streams: reports,
    })
}

/// One input read, cleaned and on its own clock (offset applied), not yet resampled.
struct Stream {
    time: Vec<f64>,
    /// The capture columns read from it other than time, in map order, and their values.
    targets: Vec<String>,
    columns: Vec<Vec<f64>>,
    rows_in: usize,
    rows_dropped: usize,
    rows_non_finite: usize,
    cells_bridged: usize,
    rows_repeated: usize,
    source_rate_hz: f64,
    sha256: String,
    /// The map entries read from it, as written.
    map: String,
}

/// Reads one input with its own part of the map (`spec`, from [`resolve`]): rows checked,
/// non-finite cells bridged, repeated times merged, packed rows unrolled, time checked to
/// increase and shifted by `offset_s`.
fn read_stream(path: &Path, spec: &ImportSpec, offset_s: f64) -> Result<Stream, CaptureError> {
    let fail = |kind| CaptureError::new(path, kind);
    let bad_spec = |reason: String| fail(CaptureErrorKind::BadSpec(reason));
    let time_entry = spec.map.get(TIME_S);
    // Packed columns are read as columns of their own and unrolled once the rows are clean.
    let packed;
    let (read_spec, groups) = match &spec.unroll {
        Some(unroll) => {
            let (expanded, groups) = expand(spec, unroll).map_err(&bad_spec)?;
            packed = expanded;
            (&packed, Some(groups))
        }
        None => (spec, None),
    };
    let mut table = read_table(path, read_spec, false)?;
    let time_index = read_spec.map.entries.iter().position(|e| e.target == TIME_S);
    let cells_bridged = bridge_non_finite(path, read_spec, &mut table, time_index)?;
    // Time from position starts at the first row; `origin` keeps the offset for messages.
    let stroke = match (&spec.time_from_position, time_index) {
        (Some(from), Some(i)) => {
            let origin = table.columns[i].first().copied().unwrap_or(0.0);
            table.columns[i].iter_mut().for_each(|t| *t -= origin);
            Some((from.speed_mps, origin))
        }
        _ => None,
    };
    let rows_repeated = match (time_index, spec.repeated_time) {
        (Some(i), RepeatedTime::Mean | RepeatedTime::Drop) => {
            merge_repeated_times(&mut table, i, spec.repeated_time)
        }
        _ => 0,
    };
    if let (Some(unroll), Some(groups), Some(entry)) = (&spec.unroll, &groups, time_entry) {
        if table.lines.len() < 2 {
            return Err(fail(CaptureErrorKind::TooFewRows(table.lines.len())));
        }
        // Each row's samples are spread over its interval, so rows must be in time order.
        let rows = time_index
            .map(|i| table.columns[i].as_slice())
            .unwrap_or_default();
        check_increasing(path, &entry.source, rows, &table.lines, stroke)?;
        let time = spec
            .map
            .entries
            .iter()
            .position(|e| e.target == TIME_S)
            .unwrap_or(0);
        table = unroll_rows(table, groups, time, unroll);
    }
    let rows_in = table.lines.len();
    if rows_in < 2 {
        return Err(fail(CaptureErrorKind::TooFewRows(rows_in)));
    }
    let mut time: Vec<f64> = match (time_entry, spec.input_rate_hz) {
        (Some(entry), _) => {
            let index = spec.map.entries.iter().position(|e| e.target == entry.target);
            let time = index.map(|i| table.columns[i].clone()).unwrap_or_default();
            check_increasing(path, &entry.source, &time, &table.lines, stroke)?;
            time
        }
        (None, Some(rate)) => (0..rows_in).map(|i| i as f64 / rate).collect(),
        (None, None) => {
            return Err(fail(CaptureErrorKind::BadSpec(
                "no time: map `time_s=<column>` or give the input's rate (--input-rate-hz)".into(),
            )));
        }
    };
    if offset_s != 0.0 {
        time.iter_mut().for_each(|t| *t += offset_s);
    }
    let source_rate_hz = (rows_in - 1) as f64 / (time[rows_in - 1] - time[0]);
    let (targets, columns): (Vec<String>, Vec<Vec<f64>>) = spec
        .map
        .entries
        .iter()
        .zip(table.columns)
        .filter(|(entry, _)| entry.target != TIME_S)
        .map(|(entry, column)| (entry.target.clone(), column))
        .unzip();
    Ok(Stream {
        time,
        targets,
        columns,
        rows_in,
        rows_dropped: table.dropped,
        rows_non_finite: table.dropped_non_finite,
        cells_bridged,
        rows_repeated,
        source_rate_hz,
        sha256: table.sha256,
        map: spec.map.spec().to_owned(),
    })
}

/// Resamples one stream's columns at `grid` by its own measured rate: linear interpolation
/// when it is not clearly faster than `rate_hz`, else the zero-phase low-pass first.
fn resample_stream(stream: &Stream, grid: &[f64], rate_hz: f64) -> (Vec<Vec<f64>>, Resampling) {
    let (time, source_rate_hz) = (&stream.time, stream.source_rate_hz);
    let (t0, rows_in) = (time[0], time.len());
    // Only a clearly faster input is low-passed: within the tolerance, a clock's error must
    // not decide between two different filters for the same nominal rate.
    if source_rate_hz > rate_hz * (1.0 + RATE_TOLERANCE) {
        // The filter runs on a uniform grid at the input's own mean rate: no resolution is
        // lost, and the images of the input's samples fold back onto themselves rather than
        // into the pass band (a grid at another rate would alias them). It runs over the
        // whole stream, so cutting it to the other inputs' span adds no edge of its own.
        let intermediate_rate_hz = snap_rate(source_rate_hz);
        let cutoff_hz = CUTOFF_FRACTION * rate_hz;
        let uniform_input = is_uniform(time, intermediate_rate_hz);
        let mid_grid: Vec<f64> = if uniform_input {
            time.clone()
        } else {
            (0..rows_in)
                .map(|j| t0 + j as f64 / intermediate_rate_hz)
                .collect()
        };
        let filter = LowPass::butterworth4(cutoff_hz, intermediate_rate_hz);
        let data = stream
            .columns
            .iter()
            .map(|column| {
                let smooth = if uniform_input {
                    filter.filtfilt(column)
                } else {
                    filter.filtfilt(&interpolate(time, column, &mid_grid))
                };
                interpolate(&mid_grid, &smooth, grid)
            })
            .collect();
        let resampling = Resampling::LowPassed {
            cutoff_hz,
            intermediate_rate_hz,
        };
        (data, resampling)
    } else {
        let data = stream
            .columns
            .iter()
            .map(|column| interpolate(time, column, grid))
            .collect();
        (data, Resampling::Interpolated)
    }
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

/// Time strictly increases; with time from position (`stroke`: the speed and the first
/// row's position over it), an error is said in positions.
fn check_increasing(
    file: &Path,
    column: &str,
    time: &[f64],
    lines: &[usize],
    stroke: Option<(f64, f64)>,
) -> Result<(), CaptureError> {
    for (i, pair) in time.windows(2).enumerate() {
        // Values are finite (checked while reading), so `<=` is the whole negation of `>`.
        if pair[1] <= pair[0] {
            let kind = match stroke {
                Some((speed_mps, origin)) => CaptureErrorKind::PositionNotMonotonic {
                    previous_m: (pair[0] + origin) * speed_mps,
                    current_m: (pair[1] + origin) * speed_mps,
                    speed_mps,
                },
                None => CaptureErrorKind::RowTimeNotIncreasing {
                    previous: pair[0],
                    current: pair[1],
                },
            };
            return Err(CaptureError::new(file, kind)
                .at_line(lines[i + 1])
                .in_column(column));
        }
    }
    Ok(())
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

#[cfg(test)]
mod tests;

#[cfg(test)]
mod join_tests;
