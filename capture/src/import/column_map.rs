//! The column map: which foreign column becomes which capture column, in which unit.

use super::*;

/// One `target=source[unit]*factor` entry of a [`ColumnMap`].
#[derive(Debug, Clone, PartialEq)]
pub struct MapEntry {
    /// The capture column written.
    pub target: String,
    /// The input column read (header name, trimmed).
    pub source: String,
    /// The input the column is read from, 1-based, when the source is qualified (`2:x`);
    /// `None`: the one input that has the column (see [`import_streams`]).
    pub input: Option<usize>,
    /// The unit given in brackets, if any.
    pub unit: Option<String>,
    /// Conversion from the input's values to the target's SI values (unit × factor).
    pub scale: Scale,
    /// The entry as written, trimmed (for error messages).
    pub text: String,
}

/// Which input column becomes which capture column, and how to convert it: the parsed form
/// of `--map` (see the [module documentation](super)).
#[derive(Debug, Clone, PartialEq)]
pub struct ColumnMap {
    pub(super) entries: Vec<MapEntry>,
    pub(super) spec: String,
}

impl ColumnMap {
    /// Parses `target=source[unit]`, `target=source*factor` or `target=source[unit]*factor`
    /// entries separated by commas. Spaces around names are ignored. Targets must be capture
    /// columns (of any kind; [`import_csv`] checks them against the kind), each at most once
    /// except `time_s`, which may be given once unqualified and once per input (`time_s=t[ms],
    /// time_s=3:stamp[us]`: every input's time is `t` but the third's, `stamp`); a unit must be
    /// in the [unit table](unit_to_si) and measure the target's quantity; a factor must be a
    /// finite non-zero number. A source `N:name` (digits, then `:`) reads `name` from the
    /// `N`th input (1-based) of [`import_streams`].
    pub fn parse(spec: &str) -> Result<ColumnMap, CaptureError> {
        if spec.trim().is_empty() {
            return Err(CaptureError::without_file(CaptureErrorKind::BadMap {
                entry: String::new(),
                reason: "the column map is empty (expected `target=source,...`)".into(),
            }));
        }
        let mut entries: Vec<MapEntry> = Vec::new();
        for raw in spec.split(',') {
            let entry = parse_entry(raw.trim())?;
            // Time is read in every input, so each may name its own time column.
            let clash = |e: &&MapEntry| {
                e.target == entry.target && (entry.target != TIME_S || e.input == entry.input)
            };
            if let Some(earlier) = entries.iter().find(clash) {
                let once = format!("target `{}` is mapped more than once", entry.target);
                let reason = match (entry.target == TIME_S, entry.input) {
                    (true, Some(n)) => format!("{once} for input {n} (`{}`)", earlier.text),
                    (true, None) => format!(
                        "{once} (`{}`); one input's own time column is `time_s=N:column`",
                        earlier.text
                    ),
                    (false, _) => once,
                };
                return Err(CaptureError::without_file(CaptureErrorKind::BadMap {
                    reason,
                    entry: entry.text,
                }));
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

    /// The (first) entry writing `target`, if any.
    pub fn get(&self, target: &str) -> Option<&MapEntry> {
        self.entries.iter().find(|e| e.target == target)
    }

    /// The spec as given, with whitespace removed (recorded as `map=` in the metadata).
    pub fn spec(&self) -> &str {
        &self.spec
    }
}

pub(super) fn is_capture_column(name: &str) -> bool {
    CaptureKind::ALL.iter().any(|kind| kind.allows_column(name))
}

pub(super) fn all_capture_columns() -> String {
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

pub(super) fn parse_entry(entry: &str) -> Result<MapEntry, CaptureError> {
    let bad = |reason: String| {
        CaptureError::without_file(CaptureErrorKind::BadMap {
            entry: entry.to_owned(),
            reason,
        })
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
    // `2:x` reads `x` from the second input; a name with a colon after something other than
    // digits (`Fz:1`) stays a name.
    let mut input = None;
    if let Some((number, name)) = source.split_once(':')
        && !number.is_empty()
        && number.trim().chars().all(|c| c.is_ascii_digit())
    {
        let n: usize = number.trim().parse().ok().filter(|&n| n >= 1).ok_or_else(|| {
            bad(format!(
                "input `{number}` in `{source}`: inputs are numbered from 1"
            ))
        })?;
        input = Some(n);
        source = name.trim();
    }
    if source.is_empty() {
        return Err(bad("no source column after `=`".into()));
    }
    Ok(MapEntry {
        target: target.to_owned(),
        source: source.to_owned(),
        input,
        unit,
        scale,
        text: entry.to_owned(),
    })
}
