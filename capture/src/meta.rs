//! The metadata line: `# palpus-capture format=1 kind=... device=... rate_hz=... units=si k=v ...`.

use std::fmt::Display;
use std::io::{self, Write};

use super::FORMAT_VERSION;
use super::error::CaptureErrorKind;
use super::kind::CaptureKind;

/// Line 1 of every capture starts with this marker.
pub const METADATA_MARKER: &str = "# palpus-capture";

/// Keys the format itself defines; they are always written first, in this
/// order, and cannot be used as free keys.
pub const RESERVED_KEYS: [&str; 5] = ["format", "kind", "device", "rate_hz", "units"];

/// The only unit system captures use.
const UNITS: &str = "si";

/// Everything on a capture's metadata line.
///
/// `format` and `units` are implied (always [`FORMAT_VERSION`] and `si`), the
/// other required keys are fields, and any number of free keys (seed,
/// surface name, ground-truth parameters such as `truth.mu`, ...) follow in
/// insertion order. Values are stored as strings exactly as they appear in
/// the file, so a value written with `Display` reads back as the same text.
#[derive(Debug, Clone, PartialEq)]
pub struct Metadata {
    kind: CaptureKind,
    device: String,
    rate_hz: f64,
    extra: Vec<(String, String)>,
}

impl Metadata {
    /// Metadata with the required keys and no free keys.
    ///
    /// Nothing is validated here; [`CaptureWriter::new`](super::CaptureWriter::new)
    /// and [`Capture::new`](super::Capture::new) reject a bad device name or
    /// rate with a typed error, so building metadata never panics.
    pub fn new(kind: CaptureKind, device: impl Into<String>, rate_hz: f64) -> Self {
        Metadata {
            kind,
            device: device.into(),
            rate_hz,
            extra: Vec::new(),
        }
    }

    /// Appends a free key (builder style). The value is stored via `Display`
    /// (`f64` displays as its shortest round-trip form). Validation happens
    /// at write time.
    pub fn with(mut self, key: impl Into<String>, value: impl Display) -> Self {
        self.extra.push((key.into(), value.to_string()));
        self
    }

    /// Sets a free key: replaces the value of an existing key in place
    /// (keeping its position), otherwise appends.
    pub fn insert(&mut self, key: impl Into<String>, value: impl Display) {
        let key = key.into();
        let value = value.to_string();
        match self.extra.iter_mut().find(|(k, _)| *k == key) {
            Some(slot) => slot.1 = value,
            None => self.extra.push((key, value)),
        }
    }

    /// What was recorded.
    pub fn kind(&self) -> CaptureKind {
        self.kind
    }

    /// The device or simulator that produced the capture.
    pub fn device(&self) -> &str {
        &self.device
    }

    /// Nominal sample rate in Hz.
    pub fn rate_hz(&self) -> f64 {
        self.rate_hz
    }

    /// Value of a free key. Required keys are not found here; use the
    /// accessors ([`Metadata::kind`], ...) for them.
    pub fn get(&self, key: &str) -> Option<&str> {
        self.extra.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
    }

    /// Free keys in insertion (= file) order.
    pub fn extra(&self) -> &[(String, String)] {
        &self.extra
    }

    /// Checks everything the writer needs: valid device and rate, and free
    /// keys that are well-formed, not reserved and not duplicated.
    pub(crate) fn validate(&self) -> Result<(), CaptureErrorKind> {
        validate_value("device", &self.device).map_err(CaptureErrorKind::BadMetadata)?;
        validate_rate(self.rate_hz).map_err(CaptureErrorKind::BadMetadata)?;
        for (i, (key, value)) in self.extra.iter().enumerate() {
            validate_key(key).map_err(CaptureErrorKind::BadMetadata)?;
            if RESERVED_KEYS.contains(&key.as_str()) {
                return Err(CaptureErrorKind::BadMetadata(format!(
                    "key `{key}` is reserved and cannot be a free key"
                )));
            }
            if self.extra[..i].iter().any(|(k, _)| k == key) {
                return Err(duplicate_key(key));
            }
            validate_value(key, value).map_err(CaptureErrorKind::BadMetadata)?;
        }
        Ok(())
    }

    /// Writes line 1 including its `\n`. Call [`Metadata::validate`] first.
    pub(crate) fn write_line(&self, out: &mut impl Write) -> io::Result<()> {
        write!(
            out,
            "{METADATA_MARKER} format={FORMAT_VERSION} kind={} device={} rate_hz=",
            self.kind, self.device
        )?;
        write_rate(out, self.rate_hz)?;
        write!(out, " units={UNITS}")?;
        for (key, value) in &self.extra {
            write!(out, " {key}={value}")?;
        }
        out.write_all(b"\n")
    }

    /// Parses line 1 (without its line terminator).
    ///
    /// Required keys may appear in any order (the writer puts them first);
    /// `format` is checked before anything else so a future version's file
    /// reports "unsupported version" rather than some incidental mismatch.
    pub(crate) fn parse_line(line: &str, expected: Option<CaptureKind>) -> Result<Self, CaptureErrorKind> {
        let rest = line
            .strip_prefix(METADATA_MARKER)
            .ok_or(CaptureErrorKind::NoMetadataLine)?;
        let tokens: Vec<(&str, &str)> = if rest.is_empty() {
            Vec::new()
        } else {
            let rest = rest.strip_prefix(' ').ok_or(CaptureErrorKind::NoMetadataLine)?;
            rest.split(' ')
                .map(|token| {
                    if token.is_empty() {
                        return Err(bad("empty token (tokens are separated by single spaces)"));
                    }
                    token
                        .split_once('=')
                        .ok_or_else(|| bad(format!("token `{token}` has no `=`")))
                })
                .collect::<Result<_, _>>()?
        };
        let find = |key: &str| tokens.iter().find(|(k, _)| *k == key).map(|(_, v)| *v);
        let require = |key: &str| find(key).ok_or_else(|| bad(format!("missing key `{key}`")));

        let format = require("format")?;
        if format.parse::<u32>() != Ok(FORMAT_VERSION) {
            return Err(CaptureErrorKind::UnsupportedVersion(format.to_owned()));
        }
        for (i, (key, value)) in tokens.iter().enumerate() {
            validate_key(key).map_err(CaptureErrorKind::BadMetadata)?;
            if tokens[..i].iter().any(|(k, _)| k == key) {
                return Err(duplicate_key(key));
            }
            validate_value(key, value).map_err(CaptureErrorKind::BadMetadata)?;
        }
        let kind: CaptureKind = require("kind")?
            .parse()
            .map_err(|e: super::kind::UnknownKind| bad(e.to_string()))?;
        if let Some(expected) = expected
            && expected != kind
        {
            return Err(CaptureErrorKind::WrongKind {
                expected,
                found: kind,
            });
        }
        let units = require("units")?;
        if units != UNITS {
            return Err(CaptureErrorKind::UnsupportedUnits(units.to_owned()));
        }
        let rate_text = require("rate_hz")?;
        let rate_hz: f64 = rate_text
            .parse()
            .map_err(|_| bad(format!("rate_hz `{rate_text}` is not a number")))?;
        validate_rate(rate_hz).map_err(CaptureErrorKind::BadMetadata)?;
        let device = require("device")?;
        let extra = tokens
            .iter()
            .filter(|(k, _)| !RESERVED_KEYS.contains(k))
            .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
            .collect();
        Ok(Metadata {
            kind,
            device: device.to_owned(),
            rate_hz,
            extra,
        })
    }
}

fn bad(msg: impl Into<String>) -> CaptureErrorKind {
    CaptureErrorKind::BadMetadata(msg.into())
}

fn duplicate_key(key: &str) -> CaptureErrorKind {
    bad(format!("duplicate key `{key}`"))
}

/// Keys are `[A-Za-z0-9_.-]+` so they never need quoting and can be dotted
/// (`truth.mu`).
fn validate_key(key: &str) -> Result<(), String> {
    if key.is_empty() {
        return Err("empty key".into());
    }
    match key
        .chars()
        .find(|&c| !(c.is_ascii_alphanumeric() || matches!(c, '_' | '.' | '-')))
    {
        Some(c) => Err(format!(
            "key `{}` contains {c:?} (keys are [A-Za-z0-9_.-]+)",
            key.escape_default()
        )),
        None => Ok(()),
    }
}

/// Values are non-empty printable ASCII without whitespace, so the line can
/// be split on spaces. `=` is allowed (tokens split at the first `=`).
fn validate_value(key: &str, value: &str) -> Result<(), String> {
    if value.is_empty() {
        return Err(format!("key `{key}` has an empty value"));
    }
    match value.chars().find(|&c| !c.is_ascii_graphic()) {
        Some(c) => Err(format!(
            "value of `{key}` contains {c:?} (values are printable ASCII without whitespace)"
        )),
        None => Ok(()),
    }
}

fn validate_rate(rate_hz: f64) -> Result<(), String> {
    if rate_hz.is_finite() && rate_hz > 0.0 {
        Ok(())
    } else {
        Err(format!("rate_hz must be finite and positive, got {rate_hz}"))
    }
}

/// Integral rates (the usual case) are written as integers (`rate_hz=1000`),
/// others in shortest round-trip form; both parse back to the same `f64`.
fn write_rate(out: &mut impl Write, rate_hz: f64) -> io::Result<()> {
    if rate_hz.fract() == 0.0 && rate_hz < 1e15 {
        // f64's Display never uses exponents, and is exact for integers.
        write!(out, "{rate_hz}")
    } else {
        out.write_all(ryu::Buffer::new().format_finite(rate_hz).as_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(meta: &Metadata) -> String {
        let mut out = Vec::new();
        meta.write_line(&mut out).unwrap();
        String::from_utf8(out).unwrap()
    }

    fn bad_msg(result: Result<impl std::fmt::Debug, CaptureErrorKind>) -> String {
        match result {
            Err(CaptureErrorKind::BadMetadata(msg)) => msg,
            other => panic!("expected BadMetadata, got {other:?}"),
        }
    }

    #[test]
    fn writes_required_keys_first_then_free_keys_in_order() {
        let meta = Metadata::new(CaptureKind::Rubbing, "sim-omega7", 1000.0)
            .with("seed", 42)
            .with("surface", "sandpaper_120")
            .with("truth.mu", 0.58);
        meta.validate().unwrap();
        assert_eq!(
            line(&meta),
            "# palpus-capture format=1 kind=rubbing device=sim-omega7 rate_hz=1000 units=si \
             seed=42 surface=sandpaper_120 truth.mu=0.58\n"
        );
        let parsed = Metadata::parse_line(line(&meta).trim_end(), Some(CaptureKind::Rubbing));
        assert_eq!(parsed.unwrap(), meta);
    }

    #[test]
    fn non_integral_rates_round_trip() {
        for rate in [0.1, 1e-300, 2.5e20, 1e15, 999.999_999_999_9] {
            let meta = Metadata::new(CaptureKind::Insertion, "d", rate);
            let text = line(&meta);
            let parsed = Metadata::parse_line(text.trim_end(), None).unwrap();
            assert_eq!(parsed.rate_hz().to_bits(), rate.to_bits(), "{text}");
        }
    }

    #[test]
    fn insert_replaces_in_place_and_get_sees_free_keys_only() {
        let mut meta = Metadata::new(CaptureKind::Rubbing, "d", 1.0)
            .with("a", 1)
            .with("b", 2);
        meta.insert("a", "x");
        meta.insert("c", 3.5);
        assert_eq!(
            meta.extra(),
            &[
                ("a".to_owned(), "x".to_owned()),
                ("b".to_owned(), "2".to_owned()),
                ("c".to_owned(), "3.5".to_owned()),
            ]
        );
        assert_eq!(meta.get("a"), Some("x"));
        assert_eq!(meta.get("device"), None);
        assert_eq!(meta.get("zzz"), None);
    }

    #[test]
    fn validate_rejects_bad_keys_values_and_rates() {
        let base = || Metadata::new(CaptureKind::Rubbing, "dev", 1000.0);
        assert!(bad_msg(base().with("has space", 1).validate()).contains("key `has space`"));
        assert!(bad_msg(base().with("a=b", 1).validate()).contains("key `a=b`"));
        assert!(bad_msg(base().with("", 1).validate()).contains("empty key"));
        assert!(bad_msg(base().with("k", "two words").validate()).contains("value of `k`"));
        assert!(bad_msg(base().with("k", "tab\there").validate()).contains("value of `k`"));
        assert!(bad_msg(base().with("k", "é").validate()).contains("value of `k`"));
        assert!(bad_msg(base().with("k", "").validate()).contains("empty value"));
        assert!(bad_msg(base().with("k", 1).with("k", 2).validate()).contains("duplicate key `k`"));
        assert!(bad_msg(base().with("units", "si").validate()).contains("reserved"));
        let dev = Metadata::new(CaptureKind::Rubbing, "my device", 1000.0);
        assert!(bad_msg(dev.validate()).contains("value of `device`"));
        for rate in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let meta = Metadata::new(CaptureKind::Rubbing, "dev", rate);
            assert!(bad_msg(meta.validate()).contains("rate_hz"));
        }
        // '=' inside a value is fine: tokens split at the first '='.
        base().with("expr", "a=b").validate().unwrap();
    }

    #[test]
    fn parse_accepts_required_keys_in_any_order_and_values_with_equals() {
        let meta = Metadata::parse_line(
            "# palpus-capture units=si x=a=b rate_hz=1e3 device=d kind=insertion format=1",
            None,
        )
        .unwrap();
        assert_eq!(meta.kind(), CaptureKind::Insertion);
        assert_eq!(meta.device(), "d");
        assert_eq!(meta.rate_hz(), 1000.0);
        assert_eq!(meta.get("x"), Some("a=b"));
        assert_eq!(meta.extra().len(), 1);
    }

    #[test]
    fn parse_rejects_each_problem_with_a_specific_error() {
        const OK: &str = "format=1 kind=rubbing device=d rate_hz=10 units=si";
        let parse = |rest: &str| Metadata::parse_line(&format!("# palpus-capture {rest}"), None);
        assert!(matches!(
            Metadata::parse_line("time_s,depth_m", None),
            Err(CaptureErrorKind::NoMetadataLine)
        ));
        assert!(matches!(
            Metadata::parse_line("# palpus-captured format=1", None),
            Err(CaptureErrorKind::NoMetadataLine)
        ));
        assert!(bad_msg(Metadata::parse_line("# palpus-capture", None)).contains("missing key `format`"));
        assert!(matches!(
            parse("format=2 kind=rubbing"),
            Err(CaptureErrorKind::UnsupportedVersion(v)) if v == "2"
        ));
        assert!(matches!(
            parse("format=one"),
            Err(CaptureErrorKind::UnsupportedVersion(v)) if v == "one"
        ));
        assert!(matches!(
            parse("format=1 kind=rubbing device=d rate_hz=10 units=mm"),
            Err(CaptureErrorKind::UnsupportedUnits(u)) if u == "mm"
        ));
        assert!(matches!(
            Metadata::parse_line(&format!("# palpus-capture {OK}"), Some(CaptureKind::Insertion)),
            Err(CaptureErrorKind::WrongKind {
                expected: CaptureKind::Insertion,
                found: CaptureKind::Rubbing
            })
        ));
        let bad_lines = [
            (format!("{OK}  seed=1"), "empty token"),
            (format!("{OK} seed=1 "), "empty token"),
            (format!("{OK} seed"), "token `seed` has no `=`"),
            (format!("{OK} seed=1 seed=2"), "duplicate key `seed`"),
            (format!("{OK} kind=rubbing"), "duplicate key `kind`"),
            (format!("{OK} k=\tv"), "value of `k`"),
            (format!("{OK} k!=v"), "key `k!`"),
            (format!("{OK} k="), "empty value"),
            (
                "format=1 kind=rubbing rate_hz=10 units=si".to_owned(),
                "key `device`",
            ),
            (
                "format=1 kind=stroking device=d rate_hz=10 units=si".to_owned(),
                "unknown capture kind `stroking`",
            ),
            (
                "format=1 kind=rubbing device=d rate_hz=fast units=si".to_owned(),
                "rate_hz `fast` is not a number",
            ),
            (
                "format=1 kind=rubbing device=d rate_hz=-5 units=si".to_owned(),
                "finite and positive",
            ),
            (
                "format=1 kind=rubbing device=d rate_hz=inf units=si".to_owned(),
                "finite and positive",
            ),
        ];
        for (line, expected) in &bad_lines {
            let msg = bad_msg(parse(line));
            assert!(msg.contains(expected), "{line:?}: {msg}");
        }
    }
}
