//! Streaming, strict capture reader.
//!
//! Lines are parsed by hand with `BufRead::read_until` rather than with the
//! `csv` crate: strict truncation detection needs to see each line's
//! terminator, and the format is numeric-only with no quoting.

use std::fmt;
use std::io::BufRead;
use std::path::{Path, PathBuf};

use super::error::{CaptureError, CaptureErrorKind};
use super::kind::{CaptureKind, TIME_S};
use super::meta::{METADATA_MARKER, Metadata};
use super::validate::{check_columns, check_time, check_value};

/// Reads a capture row by row, validating as strictly as the writer does.
///
/// Rules, each reported as a typed [`CaptureError`] with the 1-based line
/// and, for per-field problems, the column name:
/// * lines end in `\n`; a last line without it is [`CaptureErrorKind::TruncatedLastLine`]
///   (the writer always ends lines, so the file was cut), and `\r\n` is
///   rejected with [`CaptureErrorKind::CarriageReturn`] (LF-only keeps
///   identical captures byte-identical);
/// * every data line has exactly one field per column (a blank line is
///   `FieldCount { found: 0 }`);
/// * fields are whatever Rust's `f64` parser accepts, and must then be
///   finite (`nan`, `inf` and overflowing literals like `1e999` are
///   [`CaptureErrorKind::NotFinite`]) and within the column's plausible
///   magnitude ([`magnitude_limit`](super::kind::magnitude_limit), else
///   [`CaptureErrorKind::Implausible`]);
/// * `time_s` strictly increases;
/// * there is at least one data row ([`CaptureErrorKind::NoSamples`]).
///
/// The line buffer is reused, so reading allocates nothing per row once the
/// caller's row vector has grown. After an error, drop the reader.
pub struct CaptureReader<R: BufRead> {
    inner: R,
    source: PathBuf,
    meta: Metadata,
    columns: Vec<String>,
    buf: Vec<u8>,
    /// Number of the line most recently read (1-based).
    line: usize,
    previous_time: Option<f64>,
    rows: usize,
}

impl<R: BufRead> fmt::Debug for CaptureReader<R> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("CaptureReader")
            .field("source", &self.source)
            .field("meta", &self.meta)
            .field("columns", &self.columns)
            .field("line", &self.line)
            .finish_non_exhaustive()
    }
}

impl<R: BufRead> CaptureReader<R> {
    /// Reads and validates the metadata line and the header. `source` names
    /// the input in errors; `expected` rejects captures of another kind with
    /// [`CaptureErrorKind::WrongKind`].
    pub fn new(
        inner: R,
        source: impl Into<PathBuf>,
        expected: Option<CaptureKind>,
    ) -> Result<Self, CaptureError> {
        let mut reader = CaptureReader {
            inner,
            source: source.into(),
            // Placeholder until line 1 is parsed; never observable.
            meta: Metadata::new(CaptureKind::Rubbing, "", 1.0),
            columns: Vec::new(),
            buf: Vec::with_capacity(256),
            line: 0,
            previous_time: None,
            rows: 0,
        };

        if !reader.next_line()? {
            return Err(CaptureError::new(&reader.source, CaptureErrorKind::Empty));
        }
        // Check the marker before truncation so that a random non-capture
        // file is reported as such, not as "truncated".
        if !reader.buf.starts_with(METADATA_MARKER.as_bytes()) {
            return Err(reader.error(CaptureErrorKind::NoMetadataLine));
        }
        let text = reader.line_content()?;
        let text = std::str::from_utf8(text)
            .map_err(|_| CaptureErrorKind::BadMetadata("metadata line is not ASCII".to_owned()));
        let meta = text
            .and_then(|text| Metadata::parse_line(text, expected))
            .map_err(|kind| reader.error(kind))?;
        reader.meta = meta;

        if !reader.next_line()? {
            return Err(reader.error_at(CaptureErrorKind::NoHeader, 2));
        }
        let header = reader.line_content()?;
        let columns: Vec<String> = header
            .split(|&b| b == b',')
            .map(|name| String::from_utf8_lossy(name).into_owned())
            .collect();
        check_columns(reader.meta.kind(), &columns).map_err(|kind| reader.error(kind))?;
        reader.columns = columns;
        Ok(reader)
    }

    /// The parsed metadata line.
    pub fn metadata(&self) -> &Metadata {
        &self.meta
    }

    /// The column names, in file order (`time_s` first).
    pub fn columns(&self) -> &[String] {
        &self.columns
    }

    /// The name used for the input in errors.
    pub fn source(&self) -> &Path {
        &self.source
    }

    /// Reads the next sample into `row` (cleared first, one value per
    /// column). Returns `Ok(false)` at a clean end of file; reaching the end
    /// before any sample is [`CaptureErrorKind::NoSamples`].
    pub fn read_row(&mut self, row: &mut Vec<f64>) -> Result<bool, CaptureError> {
        if !self.next_line()? {
            if self.rows == 0 {
                return Err(CaptureError::new(&self.source, CaptureErrorKind::NoSamples));
            }
            return Ok(false);
        }
        let content = self.line_content()?;
        let found = if content.is_empty() {
            0
        } else {
            content.iter().filter(|&&b| b == b',').count() + 1
        };
        if found != self.columns.len() {
            return Err(self.error(CaptureErrorKind::FieldCount {
                expected: self.columns.len(),
                found,
            }));
        }
        row.clear();
        for (field, name) in content.split(|&b| b == b',').zip(&self.columns) {
            let value = parse_field(field, name).map_err(|kind| {
                CaptureError::new(&self.source, kind)
                    .at_line(self.line)
                    .in_column(name)
            })?;
            row.push(value);
        }
        check_time(self.previous_time, row[0]).map_err(|kind| self.error(kind).in_column(TIME_S))?;
        self.previous_time = Some(row[0]);
        self.rows += 1;
        Ok(true)
    }

    /// Reads the next raw line (with terminator) into `buf`; `false` at EOF.
    fn next_line(&mut self) -> Result<bool, CaptureError> {
        self.buf.clear();
        match self.inner.read_until(b'\n', &mut self.buf) {
            Ok(0) => Ok(false),
            Ok(_) => {
                self.line += 1;
                Ok(true)
            }
            Err(e) => Err(self.error_at(CaptureErrorKind::Io(e), self.line + 1)),
        }
    }

    /// The current line without its `\n`, after checking the terminator.
    fn line_content(&self) -> Result<&[u8], CaptureError> {
        let Some(content) = self.buf.strip_suffix(b"\n") else {
            return Err(self.error(CaptureErrorKind::TruncatedLastLine));
        };
        if content.ends_with(b"\r") {
            return Err(self.error(CaptureErrorKind::CarriageReturn));
        }
        Ok(content)
    }

    fn error(&self, kind: CaptureErrorKind) -> CaptureError {
        self.error_at(kind, self.line)
    }

    fn error_at(&self, kind: CaptureErrorKind, line: usize) -> CaptureError {
        CaptureError::new(&self.source, kind).at_line(line)
    }
}

fn parse_field(field: &[u8], column: &str) -> Result<f64, CaptureErrorKind> {
    let not_numeric = || CaptureErrorKind::NotNumeric(String::from_utf8_lossy(field).into_owned());
    let text = std::str::from_utf8(field).map_err(|_| not_numeric())?;
    let value: f64 = text.parse().map_err(|_| not_numeric())?;
    check_value(column, value)?;
    Ok(value)
}

#[cfg(test)]
mod tests {
    use super::*;

    const META: &str = "# palpus-capture format=1 kind=rubbing device=sim rate_hz=1000 units=si\n";
    const HEADER: &str = "time_s,tangential_position_m,normal_force_n\n";

    /// Reads `text` completely, returning the rows or the first error.
    fn read_all(text: &str, expected: Option<CaptureKind>) -> Result<Vec<Vec<f64>>, CaptureError> {
        let mut reader = CaptureReader::new(text.as_bytes(), "captures/a.csv", expected)?;
        let mut rows = Vec::new();
        let mut row = Vec::new();
        while reader.read_row(&mut row)? {
            rows.push(row.clone());
        }
        Ok(rows)
    }

    /// Reads `META + HEADER + body` and returns the error it must produce.
    fn body_error(body: &str) -> CaptureError {
        read_all(&format!("{META}{HEADER}{body}"), None).unwrap_err()
    }

    fn assert_at(e: &CaptureError, line: Option<usize>, column: Option<&str>) {
        assert_eq!(e.file.as_deref(), Some(Path::new("captures/a.csv")), "{e}");
        assert_eq!(e.line, line, "{e}");
        assert_eq!(e.column.as_deref(), column, "{e}");
        let shown = e.to_string();
        let mut prefix = "captures/a.csv".to_owned();
        if let Some(line) = line {
            prefix += &format!(":{line}");
        }
        if let Some(column) = column {
            prefix += &format!(": column `{column}`");
        }
        assert!(shown.starts_with(&(prefix + ": ")), "{shown}");
    }

    #[test]
    fn reads_a_valid_capture() {
        let text = format!("{META}{HEADER}0.0,0.0,0.3\n0.001,5e-6,-0.0\n0.002,1E2,+7\n");
        let mut reader = CaptureReader::new(text.as_bytes(), "a.csv", Some(CaptureKind::Rubbing)).unwrap();
        assert_eq!(reader.metadata().device(), "sim");
        assert_eq!(reader.metadata().rate_hz(), 1000.0);
        assert_eq!(reader.columns(), HEADER.trim_end().split(',').collect::<Vec<_>>());
        let mut row = vec![99.0; 10];
        assert!(reader.read_row(&mut row).unwrap());
        assert_eq!(row, [0.0, 0.0, 0.3]);
        assert!(reader.read_row(&mut row).unwrap());
        assert_eq!(row, [0.001, 5e-6, 0.0]);
        assert!(row[2].is_sign_negative());
        assert!(reader.read_row(&mut row).unwrap());
        assert_eq!(row, [0.002, 100.0, 7.0]);
        assert!(!reader.read_row(&mut row).unwrap());
        assert!(!reader.read_row(&mut row).unwrap(), "EOF is sticky");
    }

    #[test]
    fn empty_file() {
        let e = read_all("", None).unwrap_err();
        assert!(matches!(e.kind, CaptureErrorKind::Empty));
        assert_at(&e, None, None);
    }

    #[test]
    fn first_line_is_not_metadata() {
        for text in [
            "time_s,depth_m\n",
            "time_s,depth_m",
            "\n",
            "#palpus-capture format=1\n",
            "# palpus-captured format=1\n",
        ] {
            let e = read_all(text, None).unwrap_err();
            assert!(
                matches!(e.kind, CaptureErrorKind::NoMetadataLine),
                "{text:?}: {e}"
            );
            assert_at(&e, Some(1), None);
        }
    }

    #[test]
    fn metadata_problems_are_on_line_1() {
        type Check = fn(&CaptureErrorKind) -> bool;
        let cases: &[(&str, Check)] = &[
            (
                "# palpus-capture format=2 kind=rubbing\n",
                |k| matches!(k, CaptureErrorKind::UnsupportedVersion(v) if v == "2"),
            ),
            (
                "# palpus-capture format=1 kind=rubbing device=d rate_hz=1 units=imperial\n",
                |k| matches!(k, CaptureErrorKind::UnsupportedUnits(u) if u == "imperial"),
            ),
            (
                "# palpus-capture format=1 kind=insertion device=d rate_hz=1 units=si\n",
                |k| {
                    matches!(
                        k,
                        CaptureErrorKind::WrongKind {
                            expected: CaptureKind::Rubbing,
                            found: CaptureKind::Insertion
                        }
                    )
                },
            ),
            (
                "# palpus-capture format=1 kind=rubbing device=d rate_hz=1 units=si a=1 a=2\n",
                |k| matches!(k, CaptureErrorKind::BadMetadata(m) if m.contains("duplicate key `a`")),
            ),
            (
                "# palpus-capture format=1 kind=rubbing rate_hz=1 units=si\n",
                |k| matches!(k, CaptureErrorKind::BadMetadata(m) if m.contains("`device`")),
            ),
            (
                "# palpus-capture format=1 kind=rubbing device=d rate_hz=1 units=si\r\n",
                |k| matches!(k, CaptureErrorKind::CarriageReturn),
            ),
            (
                "# palpus-capture format=1 kind=rubbing device=\u{e9} rate_hz=1 units=si\n",
                |k| matches!(k, CaptureErrorKind::BadMetadata(m) if m.contains("value of `device`")),
            ),
        ];
        for (text, is_expected) in cases {
            let e = read_all(&format!("{text}{HEADER}0,0,0\n"), Some(CaptureKind::Rubbing)).unwrap_err();
            assert!(is_expected(&e.kind), "{text:?}: {e}");
            assert_at(&e, Some(1), None);
        }
        // A file cut inside the metadata line.
        let e = read_all(
            "# palpus-capture format=1 kind=rubbing device=d rate_hz=1 units=si",
            None,
        )
        .unwrap_err();
        assert!(matches!(e.kind, CaptureErrorKind::TruncatedLastLine));
        assert_at(&e, Some(1), None);
        // Invalid UTF-8 on the metadata line.
        let mut bytes = b"# palpus-capture format=1 kind=rubbing device=\xff rate_hz=1 units=si\n".to_vec();
        bytes.extend_from_slice(HEADER.as_bytes());
        let e = CaptureReader::new(&bytes[..], "captures/a.csv", None).unwrap_err();
        assert!(matches!(&e.kind, CaptureErrorKind::BadMetadata(m) if m.contains("not ASCII")));
        assert_at(&e, Some(1), None);
    }

    #[test]
    fn header_problems_are_on_line_2() {
        let cases: &[(&str, &str)] = &[
            (
                "time_s,tangential_position_m,normal_force_n,depth_m\n",
                "unknown column `depth_m` for this capture kind",
            ),
            (
                "time_s,tangential_position_m\n",
                "missing column `normal_force_n`",
            ),
            (
                "tangential_position_m,normal_force_n\n",
                "missing column `time_s`",
            ),
            (
                "time_s,time_s,tangential_position_m,normal_force_n\n",
                "duplicate column `time_s`",
            ),
            (
                "tangential_position_m,time_s,normal_force_n\n",
                "`time_s` must be the first column",
            ),
            (
                "time_s, tangential_position_m,normal_force_n\n",
                "unknown column ` tangential_position_m` for this capture kind",
            ),
            ("\n", "unknown column `` for this capture kind"),
            (
                "time_s,tangential_position_m,normal_force_n\r\n",
                "line ends with CR LF; captures use LF line endings only",
            ),
            (
                "time_s,tangential_position_m,normal_force_n",
                "last line has no trailing newline (file truncated?)",
            ),
        ];
        for (header, reason) in cases {
            let e = read_all(&format!("{META}{header}"), None).unwrap_err();
            assert_at(&e, Some(2), None);
            assert_eq!(e.to_string(), format!("captures/a.csv:2: {reason}"), "{header:?}");
        }
        let e = read_all(&format!("{META}time_s,depth_m,axial_force_n\n0,0,0\n"), None).unwrap_err();
        assert!(matches!(e.kind, CaptureErrorKind::UnknownColumn(c) if c == "depth_m"));
        let e = read_all(META, None).unwrap_err();
        assert!(matches!(e.kind, CaptureErrorKind::NoHeader));
        assert_at(&e, Some(2), None);
    }

    #[test]
    fn header_only_is_no_samples() {
        let e = body_error("");
        assert!(matches!(e.kind, CaptureErrorKind::NoSamples));
        assert_at(&e, None, None);
        assert_eq!(
            e.to_string(),
            "captures/a.csv: no samples (a capture needs at least one data row)"
        );
    }

    #[test]
    fn truncated_last_line_even_if_it_parses() {
        for body in ["0,0,0\n1,2,3", "0,0,0\n1,2", "0,0,0\n1"] {
            let e = body_error(body);
            assert!(
                matches!(e.kind, CaptureErrorKind::TruncatedLastLine),
                "{body:?}: {e}"
            );
            assert_at(&e, Some(4), None);
        }
        let e = body_error("0,0");
        assert!(matches!(e.kind, CaptureErrorKind::TruncatedLastLine));
        assert_at(&e, Some(3), None);
    }

    #[test]
    fn crlf_data_lines_are_rejected() {
        let e = body_error("0,0,0\n1,2,3\r\n");
        assert!(matches!(e.kind, CaptureErrorKind::CarriageReturn));
        assert_at(&e, Some(4), None);
    }

    #[test]
    fn wrong_field_counts_and_blank_lines() {
        let cases = [
            ("0,0,0\n\n1,1,1\n", 4, 0),
            ("0,0,0\n1,1,1\n\n", 5, 0),
            ("0,0\n", 3, 2),
            ("0,0,0,0\n", 3, 4),
            ("0,0,0\n1,1,1,\n", 4, 4),
        ];
        for (body, line, found) in cases {
            let e = body_error(body);
            assert!(
                matches!(e.kind, CaptureErrorKind::FieldCount { expected: 3, found: f } if f == found),
                "{body:?}: {e}"
            );
            assert_at(&e, Some(line), None);
        }
        assert_eq!(
            body_error("0,0,0\n\n").to_string(),
            "captures/a.csv:4: expected 3 fields, found 0 (blank line)"
        );
    }

    #[test]
    fn non_numeric_fields_name_their_column() {
        let cases = [
            ("0,0,0.3x\n", 3, "normal_force_n", "0.3x"),
            ("0,0,0\n1, 2,3\n", 4, "tangential_position_m", " 2"),
            ("0,,0\n", 3, "tangential_position_m", ""),
            ("abc,0,0\n", 3, "time_s", "abc"),
            ("0,0,0\n1,0x10,3\n", 4, "tangential_position_m", "0x10"),
            ("0,0,1_000\n", 3, "normal_force_n", "1_000"),
        ];
        for (body, line, column, text) in cases {
            let e = body_error(body);
            assert!(
                matches!(&e.kind, CaptureErrorKind::NotNumeric(t) if t == text),
                "{body:?}: {e}"
            );
            assert_at(&e, Some(line), Some(column));
        }
        assert_eq!(
            body_error("0,0,0.3x\n").to_string(),
            "captures/a.csv:3: column `normal_force_n`: `0.3x` is not a number"
        );
        // Invalid UTF-8 in a field.
        let mut bytes = format!("{META}{HEADER}0,?,0\n").into_bytes();
        bytes[META.len() + HEADER.len() + 2] = 0xff;
        let mut reader = CaptureReader::new(&bytes[..], "captures/a.csv", None).unwrap();
        let e = reader.read_row(&mut Vec::new()).unwrap_err();
        assert!(matches!(&e.kind, CaptureErrorKind::NotNumeric(t) if t == "\u{fffd}"));
        assert_at(&e, Some(3), Some("tangential_position_m"));
    }

    #[test]
    fn non_finite_fields_name_their_column() {
        let cases = [
            ("0,nan,0\n", 3, "tangential_position_m"),
            ("0,0,0\n1,0,inf\n", 4, "normal_force_n"),
            ("0,0,-inf\n", 3, "normal_force_n"),
            ("0,0,NaN\n", 3, "normal_force_n"),
            ("1e999,0,0\n", 3, "time_s"),
            ("0,-1e999,0\n", 3, "tangential_position_m"),
            ("0,infinity,0\n", 3, "tangential_position_m"),
        ];
        for (body, line, column) in cases {
            let e = body_error(body);
            assert!(matches!(e.kind, CaptureErrorKind::NotFinite), "{body:?}: {e}");
            assert_at(&e, Some(line), Some(column));
        }
        // Tiny literals underflow to (sub)normals or zero, which are finite and fine.
        let rows = read_all(&format!("{META}{HEADER}0,1e-999,4.9e-324\n"), None).unwrap();
        assert_eq!(rows[0][1], 0.0);
        assert_eq!(rows[0][2].to_bits(), 1);
    }

    #[test]
    fn implausible_magnitudes_name_line_and_column() {
        let cases = [
            ("0,0,1e308\n", 3, "normal_force_n", 1e308, 1e6),
            (
                "0,0,0\n1,-1000000.5,0\n",
                4,
                "tangential_position_m",
                -1_000_000.5,
                1e6,
            ),
            ("0,0,0\n1.7e12,0,0\n", 4, "time_s", 1.7e12, 1e10),
        ];
        for (body, line, column, value, limit) in cases {
            let e = body_error(body);
            assert!(
                matches!(e.kind, CaptureErrorKind::Implausible { value: v, limit: l }
                    if v == value && l == limit),
                "{body:?}: {e}"
            );
            assert_at(&e, Some(line), Some(column));
        }
        assert_eq!(
            body_error("0,0,1e308\n").to_string(),
            "captures/a.csv:3: column `normal_force_n`: 1e308 is outside ±1e6, the largest \
             magnitude a capture accepts in this column (SI units; a wrong unit or a sentinel \
             value?)"
        );
        // The limits themselves are plausible, and Unix-epoch seconds are valid times.
        let rows = read_all(&format!("{META}{HEADER}1.7e9,-1e6,1e6\n"), None).unwrap();
        assert_eq!(rows[0], [1.7e9, -1e6, 1e6]);
    }

    #[test]
    fn time_must_strictly_increase() {
        for (body, line, previous, current) in [
            ("0,0,0\n0,0,0\n", 4, 0.0, 0.0),
            ("0,0,0\n1,0,0\n2,0,0\n1.5,0,0\n", 6, 2.0, 1.5),
            ("-1,0,0\n-2,0,0\n", 4, -1.0, -2.0),
        ] {
            let e = body_error(body);
            assert!(
                matches!(e.kind, CaptureErrorKind::TimeNotIncreasing { previous: p, current: c }
                    if p == previous && c == current),
                "{body:?}: {e}"
            );
            assert_at(&e, Some(line), Some("time_s"));
        }
        assert_eq!(
            body_error("0,0,0\n0,0,0\n").to_string(),
            "captures/a.csv:4: column `time_s`: time 0 s is not after the previous sample's time 0 s"
        );
    }

    /// A reader that fails after yielding some bytes.
    struct Broken<'a>(&'a [u8]);

    impl std::io::Read for Broken<'_> {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            if self.0.is_empty() {
                return Err(std::io::Error::other("cable unplugged"));
            }
            let n = self.0.len().min(buf.len());
            buf[..n].copy_from_slice(&self.0[..n]);
            self.0 = &self.0[n..];
            Ok(n)
        }
    }

    #[test]
    fn io_errors_carry_the_line_being_read() {
        let text = format!("{META}{HEADER}0,0,0\n");
        let mut reader = CaptureReader::new(
            std::io::BufReader::new(Broken(text.as_bytes())),
            "captures/a.csv",
            None,
        )
        .unwrap();
        let mut row = Vec::new();
        assert!(reader.read_row(&mut row).unwrap());
        let e = reader.read_row(&mut row).unwrap_err();
        assert!(matches!(&e.kind, CaptureErrorKind::Io(io) if io.to_string() == "cable unplugged"));
        assert_at(&e, Some(4), None);
    }
}
