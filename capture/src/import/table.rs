//! Reading a foreign CSV log into columns, with the delimiter detected and every failure
//! naming its line.

use super::*;

/// The mapped columns of an input file, converted to SI, in map order.
pub(super) struct Table {
    pub(super) columns: Vec<Vec<f64>>,
    /// 1-based file line of each data row.
    pub(super) lines: Vec<usize>,
    /// Rows skipped for a non-finite or implausible value (only with `drop_implausible`).
    pub(super) dropped: usize,
}

/// Reads the mapped columns of `path`. A mapped value that is not finite or beyond its target's
/// [`magnitude_limit`] after conversion is an error naming line and column, or, with
/// `drop_implausible`, drops its row.
pub(super) fn read_table(
    path: &Path,
    map: &ColumnMap,
    drop_implausible: bool,
) -> Result<Table, CaptureError> {
    let fail = |kind| CaptureError::new(path, kind);
    let bytes = std::fs::read(path).map_err(|source| fail(CaptureErrorKind::CannotRead(source)))?;
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
    let csv_error = |e: csv::Error, lines: &mut LineCounter<'_>, fallback_line: usize| {
        let line = e.position().map_or(fallback_line, |p| lines.line_at(p.byte()));
        fail(CaptureErrorKind::Csv(e.to_string())).at_line(line)
    };
    let is_blank = |record: &csv::ByteRecord| record.iter().all(<[u8]>::is_empty);

    let mut record = csv::ByteRecord::new();
    let header: Vec<String> = loop {
        match reader.read_byte_record(&mut record) {
            Ok(false) => return Err(fail(CaptureErrorKind::NoHeader)),
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
                return Err(fail(CaptureErrorKind::UnknownSource {
                    entry: entry.text.as_str().into(),
                    column: entry.source.as_str().into(),
                    available: header.into(),
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
    };
    let limits: Vec<f64> = map.entries.iter().map(|e| magnitude_limit(&e.target)).collect();
    let mut row = Vec::with_capacity(map.entries.len());
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
            let kind = CaptureErrorKind::HeaderFieldCount {
                expected: header.len(),
                found: record.len(),
            };
            return Err(fail(kind).at_line(line));
        }
        row.clear();
        let mut implausible = false;
        for ((entry, &i), &limit) in map.entries.iter().zip(&indices).zip(&limits) {
            let cell = &record[i];
            let text = || String::from_utf8_lossy(cell).into_owned();
            let value: f64 = std::str::from_utf8(cell)
                .ok()
                .and_then(|s| s.parse().ok())
                .ok_or_else(|| {
                    fail(CaptureErrorKind::NotNumeric(text()))
                        .at_line(line)
                        .in_column(&entry.source)
                })?;
            let value = entry.scale.apply(value);
            // Checked after conversion: the limit is in SI units, and a scale can overflow.
            let plausible = value.abs() <= limit; // false for NaN
            if drop_implausible && !plausible {
                implausible = true;
                break;
            }
            if !value.is_finite() {
                let kind = CaptureErrorKind::NotFiniteText(text());
                return Err(fail(kind).at_line(line).in_column(&entry.source));
            }
            if !plausible {
                let kind = CaptureErrorKind::ImplausibleText {
                    text: text().into(),
                    value,
                    limit,
                    target: entry.target.as_str().into(),
                };
                return Err(fail(kind).at_line(line).in_column(&entry.source));
            }
            row.push(value);
        }
        if implausible {
            table.dropped += 1;
            continue;
        }
        for (column, &value) in table.columns.iter_mut().zip(&row) {
            column.push(value);
        }
        table.lines.push(line);
    }
    Ok(table)
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
