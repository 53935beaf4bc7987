//! Reading a foreign CSV log into columns, with the delimiter detected and every failure
//! naming its line.

use super::*;

/// The mapped columns of an input file, converted to SI, in map order.
pub(super) struct Table {
    pub(super) columns: Vec<Vec<f64>>,
    /// 1-based file line of each data row.
    pub(super) lines: Vec<usize>,
    /// Rows skipped for an implausible value (with `drop_implausible`) or a non-finite one
    /// (with [`NonFinite::Drop`]).
    pub(super) dropped: usize,
    /// Of `dropped`, those for a non-finite value.
    pub(super) dropped_non_finite: usize,
    /// The input's column names (from the header row, `--columns` or numbered).
    pub(super) header: Vec<String>,
    /// SHA-256 of the file's bytes, hex.
    pub(super) sha256: String,
}

/// Reads the mapped columns of `path`, the column names coming from [`ImportSpec::header`]. A
/// finite mapped value beyond its target's [`magnitude_limit`] after conversion is an error
/// naming line and column, or, with [`ImportSpec::drop_implausible`], drops its row; a
/// non-finite one is an error, drops its row, or is kept as NaN for [`bridge_non_finite`],
/// as [`non_finite_mode`] says. A trailing delimiter is tolerated as the
/// [module documentation](super) says. With `header_only`, stops after the column names
/// (no rows, nothing mapped is looked up, no hash).
pub(super) fn read_table(path: &Path, spec: &ImportSpec, header_only: bool) -> Result<Table, CaptureError> {
    let (map, drop_implausible) = (&spec.map, spec.drop_implausible);
    let non_finite = non_finite_mode(spec);
    let fail = |kind| CaptureError::new(path, kind);
    let bytes_all = &std::fs::read(path).map_err(|source| fail(CaptureErrorKind::CannotRead(source)))?;
    let bytes = bytes_all.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes_all);
    let mut reader = csv::ReaderBuilder::new()
        .delimiter(detect_delimiter(bytes))
        .comment(Some(b'#'))
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(bytes);
    // The csv crate's line numbers skip comment and blank lines; count them from byte offsets.
    let mut lines = LineCounter::new(bytes);
    let csv_error = |e: csv::Error, lines: &mut LineCounter<'_>, fallback_line: usize| {
        let line = e.position().map_or(fallback_line, |p| lines.line_at(p.byte()));
        fail(CaptureErrorKind::Csv(e.to_string())).at_line(line)
    };
    let is_blank = |record: &csv::ByteRecord| record.iter().all(<[u8]>::is_empty);

    let mut record = csv::ByteRecord::new();
    // The first line that is not a comment or blank: the header, or, without one, the first
    // data row (then it is kept in `record` and read as data below).
    let has_first = loop {
        match reader.read_byte_record(&mut record) {
            Ok(false) => break false,
            Ok(true) if is_blank(&record) => continue,
            Ok(true) => break true,
            Err(e) => return Err(csv_error(e, &mut lines, 1)),
        }
    };
    // Without a trailing delimiter an empty last field is a column of its own; with one, every
    // line ends in an empty field, so the first line's empty last field is the delimiter's.
    let width_of = |record: &csv::ByteRecord| match record.iter().next_back() {
        Some(b"") if record.len() > 1 => record.len() - 1,
        _ => record.len(),
    };
    let mut header: Vec<String> = match &spec.header {
        Header::FirstLine if !has_first => return Err(fail(CaptureErrorKind::NoHeader)),
        Header::FirstLine => record
            .iter()
            .map(|name| String::from_utf8_lossy(name).into_owned())
            .collect(),
        Header::Named(names) => names.iter().map(|name| name.trim().to_owned()).collect(),
        Header::Numbered => (0..width_of(&record)).map(|i| i.to_string()).collect(),
    };
    if matches!(spec.header, Header::FirstLine) && width_of(&record) < header.len() {
        header.pop();
    }
    if header_only {
        return Ok(Table {
            columns: Vec::new(),
            lines: Vec::new(),
            dropped: 0,
            dropped_non_finite: 0,
            header,
            sha256: String::new(),
        });
    }
    let sha256 = crate::sha256_hex(bytes_all);
    if let Some(unroll) = &spec.unroll {
        check_range(unroll, &header).map_err(|reason| fail(CaptureErrorKind::BadSpec(reason)))?;
    }
    let mut pending = has_first && !matches!(spec.header, Header::FirstLine);
    // A first line of numbers read as a header is the usual cause of a missing column.
    let looks_like_data = matches!(spec.header, Header::FirstLine)
        && header
            .iter()
            .all(|name| name.parse::<f64>().is_ok_and(f64::is_finite));
    let mut indices = Vec::with_capacity(map.entries.len());
    for entry in &map.entries {
        let mut matches: Vec<usize> = (0..header.len()).filter(|&i| header[i] == entry.source).collect();
        // Loggers often write the unit into the header (`t[ms]`): `time_s=t[ms]` then names
        // that column, its unit read from the map as always.
        if matches.is_empty()
            && let Some(unit) = &entry.unit
        {
            let with_unit = format!("{}[{unit}]", entry.source);
            matches = (0..header.len())
                .filter(|&i| header[i].replace(' ', "") == with_unit)
                .collect();
        }
        match matches.as_slice() {
            [] if looks_like_data => {
                return Err(fail(CaptureErrorKind::BadMap {
                    entry: entry.text.clone(),
                    reason: format!(
                        "the input has no column `{}`: its first line `{}` looks like data, not \
                         a header; use --no-header (columns named 0, 1, 2, ...) or --columns",
                        entry.source,
                        header.join(",")
                    ),
                })
                .at_line(record.position().map_or(1, |p| lines.line_at(p.byte()))));
            }
            [] => {
                return Err(fail(CaptureErrorKind::UnknownSource {
                    entry: entry.text.as_str().into(),
                    column: entry.source.as_str().into(),
                    available: header.clone().into(),
                }));
            }
            [i] => indices.push(*i),
            _ => {
                return Err(fail(CaptureErrorKind::AmbiguousSource {
                    entry: entry.text.as_str().into(),
                    column: entry.source.as_str().into(),
                    count: matches.len(),
                }));
            }
        }
    }

    let mut table = Table {
        columns: vec![Vec::new(); map.entries.len()],
        lines: Vec::new(),
        dropped: 0,
        dropped_non_finite: 0,
        header,
        sha256,
    };
    let limits: Vec<f64> = map.entries.iter().map(|e| magnitude_limit(&e.target)).collect();
    let mut row = Vec::with_capacity(map.entries.len());
    let mut last_line = 1;
    let width = table.header.len();
    // Whether rows end in an empty extra field (a trailing delimiter): the first row decides.
    let mut trailing: Option<bool> = None;
    loop {
        if pending {
            pending = false;
        } else {
            match reader.read_byte_record(&mut record) {
                Ok(false) => break,
                Ok(true) if is_blank(&record) => continue,
                Ok(true) => {}
                Err(e) => return Err(csv_error(e, &mut lines, last_line + 1)),
            }
        }
        let line = match record.position() {
            Some(position) => lines.line_at(position.byte()),
            None => last_line + 1,
        };
        last_line = line;
        let found = record.len();
        let count_error = |expected: usize| {
            let kind = match spec.header {
                Header::Named(_) => CaptureErrorKind::BadSpec(format!(
                    "--columns names {width} columns, but this row has {found} fields"
                )),
                _ => CaptureErrorKind::HeaderFieldCount { expected, found },
            };
            fail(kind).at_line(line)
        };
        let extra = found == width + 1;
        if extra && !record[width].is_empty() {
            // A value past the last named column is data the map cannot reach, not a
            // trailing delimiter.
            let field = format!("field {} (after the last named column)", width + 1);
            return Err(count_error(width).in_column(field));
        }
        let expected = match *trailing.get_or_insert(extra) {
            true => width + 1,
            false => width,
        };
        if found != expected {
            return Err(count_error(expected));
        }
        row.clear();
        for (entry, &i) in map.entries.iter().zip(&indices) {
            let cell = &record[i];
            let value: f64 = std::str::from_utf8(cell)
                .ok()
                .and_then(|s| s.parse().ok())
                .ok_or_else(|| {
                    fail(CaptureErrorKind::NotNumeric(
                        String::from_utf8_lossy(cell).into_owned(),
                    ))
                    .at_line(line)
                    .in_column(&entry.source)
                })?;
            // Checked after conversion: the limit is in SI units, and a scale can overflow.
            row.push(entry.scale.apply(value));
        }
        // A finite implausible value drops its row before any non-finite cell is looked at,
        // so the row's fate does not depend on the order of the map.
        let beyond = |(&value, &limit): (&f64, &f64)| value.is_finite() && value.abs() > limit;
        if drop_implausible && row.iter().zip(&limits).any(beyond) {
            table.dropped += 1;
            continue;
        }
        let mut drop_row = false;
        for (((entry, &i), &limit), &value) in map.entries.iter().zip(&indices).zip(&limits).zip(&row) {
            let text = || String::from_utf8_lossy(&record[i]).into_owned();
            let at = |kind| fail(kind).at_line(line).in_column(&entry.source);
            if value.is_finite() {
                if value.abs() > limit {
                    return Err(at(CaptureErrorKind::ImplausibleText {
                        text: text().into(),
                        value,
                        limit,
                        target: entry.target.as_str().into(),
                    }));
                }
                continue;
            }
            match non_finite {
                NonFinite::Error => return Err(at(CaptureErrorKind::NotFiniteText(text()))),
                NonFinite::Drop => drop_row = true,
                NonFinite::Bridge if entry.target == TIME_S => {
                    return Err(at(CaptureErrorKind::CannotBridge(format!(
                        "`{}` is the row's time, which places it; skip such rows with \
                         --non-finite drop",
                        text()
                    ))));
                }
                // Kept as is; `bridge_non_finite` fills it once every row is read.
                NonFinite::Bridge => {}
            }
        }
        if drop_row {
            table.dropped += 1;
            table.dropped_non_finite += 1;
            continue;
        }
        for (column, &value) in table.columns.iter_mut().zip(&row) {
            column.push(value);
        }
        table.lines.push(line);
    }
    Ok(table)
}

/// The effective [`ImportSpec::non_finite`]: unset, `drop` with `drop_implausible` (which
/// has always skipped non-finite rows too), else `error`.
pub(super) fn non_finite_mode(spec: &ImportSpec) -> NonFinite {
    spec.non_finite.unwrap_or(if spec.drop_implausible {
        NonFinite::Drop
    } else {
        NonFinite::Error
    })
}

/// Fills each run of non-finite cells left by [`NonFinite::Bridge`] by linear interpolation in time
/// between the finite cells before and after it in the same column (by row index where the
/// time column is absent or does not increase across the run). A run longer than
/// [`MAX_BRIDGE_ROWS`] or touching the first or last row is an error naming its first line
/// and the column. Returns the number of cells filled.
pub(super) fn bridge_non_finite(
    path: &Path,
    spec: &ImportSpec,
    table: &mut Table,
    time: Option<usize>,
) -> Result<usize, CaptureError> {
    if non_finite_mode(spec) != NonFinite::Bridge {
        return Ok(0);
    }
    let rows = table.lines.len();
    let times: Vec<f64> = match time {
        Some(i) => table.columns[i].clone(),
        None => (0..rows).map(|r| r as f64).collect(),
    };
    let mut bridged = 0;
    for (entry, column) in spec.map.entries.iter().zip(table.columns.iter_mut()) {
        let mut start = 0;
        while start < rows {
            if column[start].is_finite() {
                start += 1;
                continue;
            }
            let end = (start..rows).find(|&r| column[r].is_finite()).unwrap_or(rows);
            let run = end - start;
            let fail = |reason: String| {
                CaptureError::new(path, CaptureErrorKind::CannotBridge(reason))
                    .at_line(table.lines[start])
                    .in_column(&entry.source)
            };
            let lines = format!("line {} to {}", table.lines[start], table.lines[end - 1]);
            if start == 0 || end == rows {
                let side = if start == 0 { "first" } else { "last" };
                return Err(fail(format!(
                    "{run} non-finite value(s) ({lines}) reach the file's {side} row, so there \
                     is no finite value on both sides to interpolate between; skip such rows \
                     with --non-finite drop"
                )));
            }
            if run > MAX_BRIDGE_ROWS {
                return Err(fail(format!(
                    "{run} consecutive non-finite values ({lines}), more than the \
                     {MAX_BRIDGE_ROWS} a bridge may span; that is missing data, not a dropout \
                     (skip such rows with --non-finite drop, or split the file)"
                )));
            }
            let (before, after) = (start - 1, end);
            let (t0, t1) = (times[before], times[after]);
            let (v0, v1) = (column[before], column[after]);
            for r in start..end {
                let w = if t1 > t0 && (t0..=t1).contains(&times[r]) {
                    (times[r] - t0) / (t1 - t0)
                } else {
                    (r - before) as f64 / (after - before) as f64
                };
                column[r] = v0 + (v1 - v0) * w;
            }
            bridged += run;
            start = end;
        }
    }
    Ok(bridged)
}

/// Replaces each run of consecutive rows with the same value in column `time` by one row:
/// the run's mean ([`RepeatedTime::Mean`]) or its first row (otherwise), at the first row's
/// line. Returns how many rows were removed.
pub(super) fn merge_repeated_times(table: &mut Table, time: usize, mode: RepeatedTime) -> usize {
    let rows = table.lines.len();
    let mut kept = 0;
    let mut start = 0;
    while start < rows {
        let t = table.columns[time][start];
        let end = (start + 1..rows)
            .find(|&i| table.columns[time][i] != t)
            .unwrap_or(rows);
        for (c, column) in table.columns.iter_mut().enumerate() {
            // The time column keeps its value exactly: a sum divided back may round.
            column[kept] = if mode == RepeatedTime::Mean && c != time {
                column[start..end].iter().sum::<f64>() / (end - start) as f64
            } else {
                column[start]
            };
        }
        table.lines[kept] = table.lines[start];
        kept += 1;
        start = end;
    }
    for column in &mut table.columns {
        column.truncate(kept);
    }
    table.lines.truncate(kept);
    rows - kept
}

/// 1-based line numbers of ascending byte offsets, counting newlines incrementally.
pub(super) struct LineCounter<'a> {
    pub(super) bytes: &'a [u8],
    pub(super) offset: usize,
    pub(super) line: usize,
}

impl<'a> LineCounter<'a> {
    pub(super) fn new(bytes: &'a [u8]) -> Self {
        LineCounter {
            bytes,
            offset: 0,
            line: 1,
        }
    }

    /// The line of the record the csv reader reports at byte `offset`; offsets must not
    /// decrease between calls. The reader's offset is where it started looking, so empty and
    /// `#` lines it skipped before the record are skipped here too.
    pub(super) fn line_at(&mut self, offset: u64) -> usize {
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
            self.line += newlines;
            self.offset = end;
        }
        self.line
    }
}

/// The delimiter of the header line: whichever of tab, `;` and `,` occurs most often outside
/// double quotes (ties in that order), `,` if none does.
pub(super) fn detect_delimiter(bytes: &[u8]) -> u8 {
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
