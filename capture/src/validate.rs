//! Checks shared by the writer, the reader and [`Capture::new`](super::Capture::new),
//! so all three accept the same captures, but for the magnitude check ([`check_value`])
//! that only readers make (see the crate documentation for why).

use super::error::CaptureErrorKind;
use super::kind::{CaptureKind, TIME_S, magnitude_limit};

/// Checks a header against `kind`: every name known for the kind, no
/// duplicates, `time_s` first, all required columns present. Problems are
/// reported in that order, the first offending name winning.
pub(crate) fn check_columns<S: AsRef<str>>(kind: CaptureKind, columns: &[S]) -> Result<(), CaptureErrorKind> {
    for (i, name) in columns.iter().map(AsRef::as_ref).enumerate() {
        if !kind.allows_column(name) {
            return Err(CaptureErrorKind::UnknownColumn(name.to_owned()));
        }
        if columns[..i].iter().any(|c| c.as_ref() == name) {
            return Err(CaptureErrorKind::DuplicateColumn(name.to_owned()));
        }
    }
    let has = |name: &str| columns.iter().any(|c| c.as_ref() == name);
    if columns.first().map(AsRef::as_ref) != Some(TIME_S) {
        return Err(if has(TIME_S) {
            CaptureErrorKind::TimeNotFirst
        } else {
            CaptureErrorKind::MissingColumn(TIME_S.to_owned())
        });
    }
    match kind.required_columns().iter().find(|r| !has(r)) {
        Some(missing) => Err(CaptureErrorKind::MissingColumn((*missing).to_owned())),
        None => Ok(()),
    }
}

/// Rejects NaN and infinities: identification code downstream assumes every
/// sample is a real measurement.
pub(crate) fn check_finite(value: f64) -> Result<(), CaptureErrorKind> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(CaptureErrorKind::NotFinite)
    }
}

/// [`check_finite`], then the column's plausible magnitude
/// ([`magnitude_limit`]): a finite `1e308` is as useless downstream as an infinity, and
/// worse, since filters and fits would spread it over every sample.
pub(crate) fn check_value(column: &str, value: f64) -> Result<(), CaptureErrorKind> {
    check_finite(value)?;
    let limit = magnitude_limit(column);
    if value.abs() <= limit {
        Ok(())
    } else {
        Err(CaptureErrorKind::Implausible { value, limit })
    }
}

/// Enforces strictly increasing time, which downstream differentiation and
/// resampling rely on. `previous` is `None` for the first sample.
pub(crate) fn check_time(previous: Option<f64>, current: f64) -> Result<(), CaptureErrorKind> {
    match previous {
        Some(previous) if current <= previous => {
            Err(CaptureErrorKind::TimeNotIncreasing { previous, current })
        }
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(columns: &[&str]) -> CaptureErrorKind {
        check_columns(CaptureKind::Rubbing, columns).unwrap_err()
    }

    #[test]
    fn column_checks() {
        check_columns(
            CaptureKind::Rubbing,
            &[
                "time_s",
                "normal_force_n",
                "accel_z_mps2",
                "tangential_position_m",
            ],
        )
        .unwrap();
        check_columns(CaptureKind::Insertion, &["time_s", "depth_m", "axial_force_n"]).unwrap();
        assert!(matches!(
            err(&["time_s", "tangential_position_m", "normal_force_n", "depth_m"]),
            CaptureErrorKind::UnknownColumn(c) if c == "depth_m"
        ));
        assert!(matches!(
            err(&["time_s", "tangential_position_m", "normal_force_n", "normal_force_n"]),
            CaptureErrorKind::DuplicateColumn(c) if c == "normal_force_n"
        ));
        assert!(matches!(
            err(&["tangential_position_m", "time_s", "normal_force_n"]),
            CaptureErrorKind::TimeNotFirst
        ));
        assert!(matches!(
            err(&["tangential_position_m", "normal_force_n"]),
            CaptureErrorKind::MissingColumn(c) if c == "time_s"
        ));
        assert!(matches!(err(&[]), CaptureErrorKind::MissingColumn(c) if c == "time_s"));
        assert!(matches!(
            err(&["time_s", "tangential_position_m"]),
            CaptureErrorKind::MissingColumn(c) if c == "normal_force_n"
        ));
    }

    #[test]
    fn value_checks() {
        check_finite(-0.0).unwrap();
        check_finite(f64::MIN_POSITIVE / 2.0).unwrap();
        for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert!(matches!(check_finite(v), Err(CaptureErrorKind::NotFinite)));
        }
        check_value("normal_force_n", -1e6).unwrap();
        check_value("time_s", 1.7e9).unwrap();
        assert!(matches!(
            check_value("normal_force_n", 1e308),
            Err(CaptureErrorKind::Implausible { value, limit }) if value == 1e308 && limit == 1e6
        ));
        assert!(matches!(
            check_value("time_s", -1.7e12),
            Err(CaptureErrorKind::Implausible { limit, .. }) if limit == 1e10
        ));
        assert!(matches!(
            check_value("depth_m", f64::NAN),
            Err(CaptureErrorKind::NotFinite)
        ));
        check_time(None, -5.0).unwrap();
        check_time(Some(1.0), 1.0 + f64::EPSILON).unwrap();
        assert!(matches!(
            check_time(Some(1.0), 1.0),
            Err(CaptureErrorKind::TimeNotIncreasing { previous, current })
                if previous == 1.0 && current == 1.0
        ));
        assert!(matches!(
            check_time(Some(0.0), -0.0),
            Err(CaptureErrorKind::TimeNotIncreasing { .. })
        ));
    }
}
