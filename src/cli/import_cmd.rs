//! `palpus import`.

use std::path::{Path, PathBuf};

use anyhow::Context;
use capture::CaptureKind;
use capture::{
    ColumnMap, DEFAULT_MAX_UPSAMPLE, Header, ImportSpec, NonFinite, RepeatedTime, SlowColumns,
    TimeFromPosition, Unroll, check_output, import_streams,
};
use clap::Args;

/// Import a CSV log recorded with another tool as a capture, or join several logs recorded
/// on separate clocks into one.
///
/// Reads a CSV file with a header row (`,`, `;` or tab delimited, detected; `#` lines and
/// blank lines skipped; --no-header or --columns for a file without a header row; a delimiter
/// ending every line is ignored), takes the columns named in --map, converts them to SI units,
/// resamples them onto a uniform grid and writes a capture that `palpus identify` and the
/// recognizers read like any other.
///
/// --map is a comma-separated list of `target=source` entries: target is a capture column
/// (time_s, tangential_position_m, normal_force_n, friction_force_n, accel_x_mps2, depth_m,
/// axial_force_n, ...), source a column of the CSV, optionally followed by a unit in brackets
/// and/or a scale factor, e.g.
///
///   time_s=t[ms],tangential_position_m=x[mm],normal_force_n=Fz[mN],friction_force_n=Fx*-1
///
/// Units: s ms us, m cm mm um, N mN kN, m/s cm/s mm/s, m/s2 mm/s2 g (9.80665 m/s2). Every
/// required column of the kind must be mapped (time may come from --input-rate-hz instead).
///
/// Resampling: an input already uniform at the output rate is copied unchanged; an input
/// whose mean rate is below 1.01 × the output rate (upsampling, or the same nominal rate
/// with a clock error or jitter) is linearly interpolated; a faster one first has what the
/// new rate cannot represent removed by a zero-phase low-pass (4th-order Butterworth
/// forwards and backwards, cut-off 0.4 × the output rate), so fast vibrations do not alias
/// into slow forces. The metadata records the source file, the map and the source rate.
///
/// Time from position: a curve digitized against position (force–depth) has no time;
/// --time-from-position 'depth[mm]' --speed-mps 0.005 sets time = (depth − first depth) /
/// speed. The unit is required; the speed's sign is the stroke direction, in which the
/// position must strictly advance.
///
/// Limits, checked before anything is allocated or written: rates from 1 Hz to 100 kHz; the
/// output at most --max-upsample times the input's rows (default 1000), and never more than
/// 10^7 rows when it is bigger than the input. Every mapped value, in SI units, must be
/// within ±1e6 (±1e10 s for time): larger is a wrong unit or a logger's sentinel, and one
/// such value would spread over every resampled row. --drop-implausible skips such rows
/// instead and says how many. Non-finite cells (nan, inf) follow --non-finite
/// error|drop|bridge: bridge interpolates runs of at most 10 rows in time from the finite
/// values around them (not at the file's ends, not in time); unset, it is drop with
/// --drop-implausible and error without.
///
/// Time must strictly increase; --repeated-time mean|drop merges consecutive rows with the
/// same time into their mean or keeps the first of them, and says how many rows went.
///
/// Packed rows: --unroll 'acc=acc_0..acc_21' reads the columns acc_0 to acc_21 of each row
/// as 22 consecutive samples of a virtual column `acc` (spaced evenly up to the next row's
/// time; the last row over the median row interval) that --map reads like any other
/// (`accel_x_mps2=acc[g]`); the other mapped columns are interpolated between rows (or held,
/// --unroll-slow hold). Needs a time column.
///
/// Several inputs (streams logged in separate files on separate clocks, e.g. forces in one
/// file, position in another, a packed vibration channel in a third):
///
///   palpus import force.csv position.csv vib.csv --kind rubbing --rate-hz 1000
///     --map 'time_s=t[ms],normal_force_n=Fz,friction_force_n=Fx,tangential_position_m=x[mm],accel_x_mps2=acc[g]'
///     --unroll 'acc=acc_0..acc_21' --out trial.csv
///
/// Inputs are numbered 1, 2, 3 in the order given. `time_s=` names the time column every
/// input has; each input is read on its own time column. An input whose time column has
/// another name gets its own entry, `time_s=3:stamp[us]`. Any other source column is looked
/// up among the inputs: it must be in exactly one of them (the error names the files that
/// have it, or lists every file's columns if none has); `2:x[mm]` reads it from input 2.
/// --unroll applies to the input(s) with the packed columns; --no-header, --columns,
/// --repeated-time, --non-finite and --drop-implausible apply to every input. Each input is
/// cleaned, then resampled onto the one output grid by the rule above, decided by its own
/// measured rate (interpolated when below 1.01 × --rate-hz, else low-passed first). The grid
/// spans the time all inputs cover (what one input has before or after it is cut, and
/// printed); inputs that overlap for fewer than 4 output samples are an error listing each
/// file's time range. --clock-offset-s 2=0.013 adds 0.013 s to input 2's times first.
/// --rate-hz is required; --input-rate-hz and --time-from-position take one input. The metadata records every input (source_N, source_N_sha256,
/// source_N_map, source_N_rate_hz). A loop over trials changes only the file names:
///
///   for t in 1 2 3; do palpus import f$t.csv p$t.csv v$t.csv --map ... --out trial$t.csv; done
#[derive(Debug, Args)]
pub(crate) struct ImportArgs {
    /// The CSV file(s) to import; several are joined on their own clocks (inputs 1, 2, ...
    /// in this order).
    #[arg(value_name = "IN.csv", required = true, num_args = 1..)]
    inputs: Vec<PathBuf>,
    /// Capture kind to produce: rubbing or insertion.
    #[arg(long)]
    kind: CaptureKind,
    /// Column mapping, e.g. `time_s=t[ms],tangential_position_m=x[mm],normal_force_n=Fz*0.001`.
    #[arg(long, value_name = "SPEC")]
    map: String,
    /// Output rate, Hz, from 1 to 100000 (default: the input's rate, which must then be
    /// uniform; required with several inputs).
    #[arg(long, value_name = "HZ")]
    rate_hz: Option<f64>,
    /// The input's rate, Hz, from 1 to 100000, when it has no time column (row i is at
    /// i / rate).
    #[arg(long, value_name = "HZ")]
    input_rate_hz: Option<f64>,
    /// The output may have at most this many times the input's rows (at least 1); an output
    /// bigger than the input is capped at 10^7 rows whatever this says.
    #[arg(long, value_name = "FACTOR", default_value_t = DEFAULT_MAX_UPSAMPLE)]
    max_upsample: f64,
    /// Skip rows with a finite mapped value beyond ±1e6 in SI units (±1e10 s for time)
    /// instead of failing; the number skipped is printed.
    #[arg(long)]
    drop_implausible: bool,
    /// Non-finite mapped cells (nan, inf): `error` (refuse the file), `drop` (skip the row)
    /// or `bridge` (interpolate in time from the column's finite neighbours, at most 10 rows
    /// in a row, not at the file's ends, not in time); the number dropped or bridged is
    /// printed. Default: drop with --drop-implausible, else error.
    #[arg(long, value_name = "MODE")]
    non_finite: Option<NonFinite>,
    /// Take time from this position column at --speed-mps: `depth[mm]` (the unit in
    /// brackets is required). time = (position − first position) / speed.
    #[arg(
        long,
        value_name = "COLUMN[UNIT]",
        requires = "speed_mps",
        conflicts_with = "input_rate_hz"
    )]
    time_from_position: Option<String>,
    /// With --time-from-position: the constant speed, m/s; negative if the position
    /// decreases during the stroke.
    #[arg(
        long,
        value_name = "M_PER_S",
        requires = "time_from_position",
        allow_negative_numbers = true
    )]
    speed_mps: Option<f64>,
    /// The file has no header row: its first line is data and its columns are named 0, 1,
    /// 2, ... so --map refers to them by index (`time_s=0[ms],normal_force_n=2`).
    #[arg(long)]
    no_header: bool,
    /// The file has no header row: these are its columns' names, comma-separated
    /// (`--columns t,x,Fz`), and its first line is data.
    #[arg(long, value_name = "NAMES", conflicts_with = "no_header")]
    columns: Option<String>,
    /// Consecutive rows with the same time: `error` (refuse the file), `mean` (merge them
    /// into one row, the mean of each column) or `drop` (keep the first); the number of rows
    /// merged or dropped is printed.
    #[arg(long, value_name = "MODE", default_value = "error")]
    repeated_time: RepeatedTime,
    /// A fast channel packed several samples per row: `NAME=PREFIX_0..PREFIX_N`
    /// (`acc=acc_0..acc_21`). Each row's packed columns become consecutive samples of the
    /// virtual column NAME, spaced evenly over the row's interval, which --map then reads.
    #[arg(long, value_name = "NAME=FIRST..LAST")]
    unroll: Option<String>,
    /// With --unroll: how the other mapped columns fill the unrolled samples between rows:
    /// `interpolate` (linearly, towards the next row) or `hold` (the row's value).
    #[arg(long, value_name = "MODE", default_value = "interpolate", requires = "unroll")]
    unroll_slow: SlowColumns,
    /// Add this many seconds to input N's times (before joining several), repeatable:
    /// `--clock-offset-s 2=0.013` (input 2's clock reads 13 ms less than the others').
    #[arg(long = "clock-offset-s", value_name = "N=SECONDS", value_parser = parse_offset, allow_hyphen_values = true)]
    clock_offset_s: Vec<(usize, f64)>,
    /// The `device` recorded in the metadata.
    #[arg(long, default_value = "imported", value_name = "NAME")]
    device: String,
    /// Extra metadata, repeatable: `--meta surface=sandpaper_400 --meta behaviour=scratch`
    /// (the recognizers read the class from `surface`). No spaces in values.
    #[arg(long = "meta", value_name = "KEY=VALUE", value_parser = super::meta_arg::parse_meta)]
    meta: Vec<(String, String)>,
    /// The capture file to write (written atomically: nothing is left on error).
    #[arg(long, value_name = "FILE")]
    out: PathBuf,
    /// Print nothing but errors.
    #[arg(long, short)]
    quiet: bool,
}

fn parse_offset(s: &str) -> Result<(usize, f64), String> {
    let parsed = s
        .split_once('=')
        .and_then(|(input, seconds)| Some((input.trim().parse().ok()?, seconds.trim().parse().ok()?)));
    parsed.ok_or_else(|| format!("`{s}`: expected N=SECONDS (input number, offset in s), e.g. 2=0.013"))
}

pub(crate) fn run(args: &ImportArgs) -> anyhow::Result<()> {
    let map = ColumnMap::parse(&args.map)?;
    let spec = ImportSpec {
        kind: args.kind,
        map,
        rate_hz: args.rate_hz,
        input_rate_hz: args.input_rate_hz,
        device: args.device.clone(),
        metadata: args.meta.clone(),
        max_upsample: args.max_upsample,
        drop_implausible: args.drop_implausible,
        non_finite: args.non_finite,
        time_from_position: match (&args.time_from_position, args.speed_mps) {
            (Some(column), Some(speed)) => Some(TimeFromPosition::new(column, speed)?),
            _ => None,
        },
        header: match (&args.columns, args.no_header) {
            (Some(names), _) => Header::Named(names.split(',').map(|n| n.trim().to_owned()).collect()),
            (None, true) => Header::Numbered,
            (None, false) => Header::FirstLine,
        },
        repeated_time: args.repeated_time,
        unroll: match &args.unroll {
            Some(text) => Some(Unroll::parse(text, args.unroll_slow)?),
            None => None,
        },
        clock_offsets_s: args.clock_offset_s.clone(),
    };
    // Import errors name the input file (and line, column or map entry) themselves.
    let inputs: Vec<&Path> = args.inputs.iter().map(PathBuf::as_path).collect();
    check_output(&args.out, &inputs)?;
    let imported = import_streams(&inputs, &spec)?;
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    imported
        .capture
        .write_file(&args.out)
        .with_context(|| format!("writing {}", args.out.display()))?;
    if !args.quiet {
        if let [stream] = imported.streams.as_slice() {
            // The metadata's `source_rate_hz` is the mean rate, written as an integer when
            // within 1e-6 of one.
            let source_rate = imported.capture.metadata().get("source_rate_hz").unwrap_or("?");
            println!(
                "imported {} rows at {source_rate} Hz from {} -> {} rows at {} Hz into {} ({})",
                imported.rows_in,
                stream.file.display(),
                imported.capture.len(),
                imported.rate_hz,
                args.out.display(),
                imported.resampling
            );
        } else {
            let grid = imported.capture.column(capture::kind::TIME_S)?;
            println!(
                "joined {} inputs -> {} rows at {} Hz from {:.6} s to {:.6} s into {}",
                imported.streams.len(),
                imported.capture.len(),
                imported.rate_hz,
                grid.first().copied().unwrap_or(f64::NAN),
                grid.last().copied().unwrap_or(f64::NAN),
                args.out.display()
            );
            for (i, stream) in imported.streams.iter().enumerate() {
                let offset = if stream.clock_offset_s != 0.0 {
                    format!(", clock offset {} s", stream.clock_offset_s)
                } else {
                    String::new()
                };
                println!(
                    "  {}: {} ({}): {} rows at {:.6} Hz from {:.6} s to {:.6} s{offset}; cut {:.6} s \
                     before and {:.6} s after; {}",
                    i + 1,
                    stream.file.display(),
                    stream.map,
                    stream.rows_in,
                    stream.source_rate_hz,
                    stream.first_time_s,
                    stream.last_time_s,
                    stream.cut_start_s,
                    stream.cut_end_s,
                    stream.resampling
                );
            }
        }
        let implausible = imported.rows_dropped - imported.rows_non_finite;
        if implausible > 0 {
            println!("dropped {implausible} row(s) with an implausible value (--drop-implausible)");
        }
        if imported.rows_non_finite > 0 {
            println!(
                "dropped {} row(s) with a non-finite value (--non-finite drop)",
                imported.rows_non_finite
            );
        }
        if imported.cells_bridged > 0 {
            println!(
                "bridged {} non-finite cell(s) by linear interpolation in time (--non-finite bridge)",
                imported.cells_bridged
            );
        }
        if imported.rows_repeated > 0 {
            let how = match args.repeated_time {
                RepeatedTime::Mean => "merged into the row before them",
                _ => "dropped",
            };
            println!(
                "{} row(s) repeating the previous row's time {how} (--repeated-time)",
                imported.rows_repeated
            );
        }
    }
    Ok(())
}
