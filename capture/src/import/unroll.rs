//! Packed rows: a fast channel logged as several columns per row, unrolled into consecutive
//! samples of one virtual column.

use super::*;

/// Most columns one packed group may name: more is a typo in the range, and each column is
/// read like a mapped one.
pub const MAX_UNROLL_COLUMNS: usize = 10_000;

/// How the other (slow) mapped columns of a packed row are put on the unrolled timeline.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SlowColumns {
    /// Linear interpolation between the row's value and the next row's (the last row, with
    /// nothing after it, holds its value).
    #[default]
    Interpolate,
    /// Every unrolled sample of a row takes the row's value.
    Hold,
}

impl std::str::FromStr for SlowColumns {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "interpolate" => Ok(SlowColumns::Interpolate),
            "hold" => Ok(SlowColumns::Hold),
            _ => Err(format!("`{s}`: expected interpolate or hold")),
        }
    }
}

/// A fast channel packed several samples per row (`--unroll 'acc=acc_0..acc_21'`): the
/// columns `acc_0` to `acc_21` of each row are 22 consecutive samples of the virtual column
/// `acc`, spaced evenly over the row's interval (the time to the next row; for the last row,
/// the median row interval). `--map` reads `acc` like any other column.
#[derive(Debug, Clone, PartialEq)]
pub struct Unroll {
    /// The virtual column `--map` refers to.
    pub name: String,
    /// The packed columns, in sample order.
    pub columns: Vec<String>,
    /// How the other mapped columns follow the unrolled timeline.
    pub slow: SlowColumns,
    text: String,
}

impl Unroll {
    /// Parses `NAME=PREFIX<first>..PREFIX<last>` (`acc=acc_0..acc_21`; zero-padded numbers
    /// such as `a00..a15` keep their width). The range must name at least two columns and at
    /// most [`MAX_UNROLL_COLUMNS`].
    pub fn parse(text: &str, slow: SlowColumns) -> Result<Self, CaptureError> {
        let bad = |reason: &str| {
            CaptureError::without_file(CaptureErrorKind::BadSpec(format!("--unroll `{text}`: {reason}")))
        };
        let syntax = "expected NAME=PREFIX_0..PREFIX_N, e.g. `acc=acc_0..acc_21`";
        let (name, range) = text.split_once('=').ok_or_else(|| bad(syntax))?;
        let (name, range) = (name.trim(), range.trim());
        if name.is_empty() {
            return Err(bad(&format!("no virtual column name before `=`; {syntax}")));
        }
        let (first, last) = range.split_once("..").ok_or_else(|| bad(syntax))?;
        let split = |column: &str| {
            let column = column.trim();
            let digits = column.len() - column.trim_end_matches(|c: char| c.is_ascii_digit()).len();
            let (prefix, number) = column.split_at(column.len() - digits);
            let value = number.parse::<usize>().ok();
            value.map(|value| (prefix.to_owned(), number.len(), value))
        };
        let ((prefix, first_width, first), (last_prefix, last_width, last)) =
            match (split(first), split(last)) {
                (Some(a), Some(b)) => (a, b),
                _ => return Err(bad(&format!("both ends must end in a number; {syntax}"))),
            };
        if prefix != last_prefix {
            return Err(bad(&format!(
                "the ends have different prefixes `{prefix}` and `{last_prefix}`"
            )));
        }
        if last <= first {
            return Err(bad("the range must name at least two columns, the first first"));
        }
        let count = last - first + 1;
        if count > MAX_UNROLL_COLUMNS {
            return Err(bad(&format!(
                "{count} columns; at most {MAX_UNROLL_COLUMNS} (check the range)"
            )));
        }
        // `a00..a15`: the first number's leading zero says the names are padded.
        let width = if first_width > 1 && first_width == last_width {
            first_width
        } else {
            0
        };
        let columns = (first..=last)
            .map(|k| format!("{prefix}{k:0width$}"))
            .collect::<Vec<_>>();
        if columns.iter().any(|c| c == name) {
            return Err(bad(&format!("`{name}` is also one of the packed columns")));
        }
        Ok(Unroll {
            name: name.to_owned(),
            columns,
            slow,
            text: text.trim().to_owned(),
        })
    }

    /// The option as given, for messages.
    pub fn text(&self) -> &str {
        &self.text
    }
}

/// A spec whose map reads every packed column: each entry reading [`Unroll::name`] is
/// replaced, in place, by one entry per packed column. Also returns, for each entry of the
/// original map, the indices of its columns in the expanded map.
pub(super) fn expand(spec: &ImportSpec, unroll: &Unroll) -> Result<(ImportSpec, Vec<Vec<usize>>), String> {
    let what = format!("--unroll `{}`", unroll.text);
    if spec.input_rate_hz.is_some() {
        return Err(format!(
            "{what} needs a time column (`time_s=<column>` in --map): the packed samples are \
             spaced over each row's interval"
        ));
    }
    if !spec.map.entries.iter().any(|e| e.source == unroll.name) {
        return Err(format!("{what}: no --map entry reads `{}`", unroll.name));
    }
    let mut expanded = spec.clone();
    expanded.map.entries.clear();
    let mut groups = Vec::with_capacity(spec.map.entries.len());
    for entry in &spec.map.entries {
        if entry.source != unroll.name {
            groups.push(vec![expanded.map.entries.len()]);
            expanded.map.entries.push(entry.clone());
            continue;
        }
        if entry.target == TIME_S {
            return Err(format!(
                "{what}: `{}` cannot be the time; time comes from a column of its own",
                entry.text
            ));
        }
        let start = expanded.map.entries.len();
        for column in &unroll.columns {
            let mut packed = entry.clone();
            packed.source = column.clone();
            expanded.map.entries.push(packed);
        }
        groups.push((start..expanded.map.entries.len()).collect());
    }
    Ok((expanded, groups))
}

/// The input columns around the packed range (`acc_22` after `acc_0..acc_21`): the range
/// then leaves samples out, which would put the rest at the wrong times.
pub(super) fn check_range(unroll: &Unroll, header: &[String]) -> Result<(), String> {
    let stray = |column: &String| header.contains(column);
    if header.contains(&unroll.name) {
        return Err(format!(
            "--unroll `{}`: the input already has a column `{}`; name the virtual column \
             differently",
            unroll.text, unroll.name
        ));
    }
    let (first, last) = (&unroll.columns[0], &unroll.columns[unroll.columns.len() - 1]);
    let mut around = neighbours(first, last).into_iter().flatten().flatten();
    if let Some(column) = around.find(|c| stray(c)) {
        return Err(format!(
            "--unroll `{}`: the input also has column `{column}`, next to the range; a row's \
             packed samples must all be named, or their times come out wrong",
            unroll.text
        ));
    }
    Ok(())
}

/// The names just before the first and just after the last packed column, same width.
fn neighbours(first: &str, last: &str) -> Option<[Option<String>; 2]> {
    let number = |column: &str| {
        let digits = column.len() - column.trim_end_matches(|c: char| c.is_ascii_digit()).len();
        let (prefix, number) = column.split_at(column.len() - digits);
        number
            .parse::<usize>()
            .ok()
            .map(|n| (prefix.to_owned(), number.len(), n))
    };
    let (prefix, width, first) = number(first)?;
    let (_, last_width, last) = number(last)?;
    let width = if width > 1 && width == last_width {
        width
    } else {
        0
    };
    let before = first.checked_sub(1).map(|k| format!("{prefix}{k:0width$}"));
    let after = last.checked_add(1).map(|k| format!("{prefix}{k:0width$}"));
    Some([before, after])
}

/// Turns each row into `n` samples as [`Unroll`] says: `groups` gives, for each original map
/// entry, its columns in `table` (one, or `n` for a packed entry), `time` the original
/// entry of the time. Row times must strictly increase and there must be at least two rows.
/// Each sample keeps its row's line, for messages.
pub(super) fn unroll_rows(table: Table, groups: &[Vec<usize>], time: usize, unroll: &Unroll) -> Table {
    let n = unroll.columns.len();
    let rows = table.lines.len();
    let times = &table.columns[groups[time][0]];
    let mut intervals: Vec<f64> = times.windows(2).map(|p| p[1] - p[0]).collect();
    intervals.sort_by(f64::total_cmp);
    let median = match intervals.len() {
        0 => 0.0,
        len if len % 2 == 1 => intervals[len / 2],
        len => 0.5 * (intervals[len / 2 - 1] + intervals[len / 2]),
    };
    let mut columns = vec![Vec::with_capacity(rows * n); groups.len()];
    let mut lines = Vec::with_capacity(rows * n);
    for row in 0..rows {
        let next = row + 1 < rows;
        let interval = if next { times[row + 1] - times[row] } else { median };
        for k in 0..n {
            let fraction = k as f64 / n as f64;
            for (g, (group, out)) in groups.iter().zip(columns.iter_mut()).enumerate() {
                let value = if g == time {
                    times[row] + interval * fraction
                } else if group.len() > 1 {
                    table.columns[group[k]][row]
                } else {
                    let column = &table.columns[group[0]];
                    match unroll.slow {
                        SlowColumns::Interpolate if next => {
                            column[row] + (column[row + 1] - column[row]) * fraction
                        }
                        _ => column[row],
                    }
                };
                out.push(value);
            }
            lines.push(table.lines[row]);
        }
    }
    Table {
        columns,
        lines,
        dropped: table.dropped,
        dropped_non_finite: table.dropped_non_finite,
        header: table.header,
        sha256: table.sha256,
    }
}
