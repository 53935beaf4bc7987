//! The search grid written on a command line: `c=1e1..1e5:5,gamma=10..1000:5,epsilon=0.02`.
//!
//! Each item names one hyperparameter and gives either one value or a range `lo..hi:count` of
//! `count` log-spaced values from `lo` to `hi`, both ends included: C and γ act multiplicatively
//! (a decade changes a fit as much anywhere on the scale) and ε spans decades of sensor noise,
//! so a log spacing spends the points where a linear one would crowd them at the top. A name
//! left out keeps the model's own values ([`SearchGrid::default_for`]).

use thiserror::Error;

use crate::model_file::ModelKind;
use crate::plausibility::Plausibility;
use crate::search::SearchGrid;

/// The most values one range may ask for: a grid is explored point by point with a
/// cross-validation each, and 100 values of one name already make hundreds of fits.
pub const MAX_GRID_VALUES: usize = 100;

/// Why a grid spec was refused; every variant names the item it is about.
#[derive(Debug, Error, PartialEq)]
pub enum GridSpecError {
    /// An item is not `name=value`.
    #[error("`{item}`: expected name=value or name=lo..hi:count")]
    Syntax {
        /// The item as written.
        item: String,
    },
    /// An unknown name.
    #[error("`{item}`: unknown name `{name}` (c, gamma or epsilon)")]
    UnknownName {
        /// The item as written.
        item: String,
        /// The name.
        name: String,
    },
    /// A name given twice.
    #[error("`{name}` is given twice")]
    Repeated {
        /// The name.
        name: String,
    },
    /// A value that is not a finite number, or a count that is not a whole number.
    #[error("`{item}`: `{text}` is not {what}")]
    Number {
        /// The item as written.
        item: String,
        /// The text that failed.
        text: String,
        /// What it should be.
        what: &'static str,
    },
    /// A value out of the hyperparameter's range.
    #[error("`{item}`: {value} is out of range: {reason}")]
    OutOfRange {
        /// The item as written.
        item: String,
        /// The value.
        value: f64,
        /// The range.
        reason: &'static str,
    },
    /// A range whose ends or count do not make one.
    #[error("`{item}`: {reason}")]
    Range {
        /// The item as written.
        item: String,
        /// Why.
        reason: String,
    },
    /// γ for the linear hard-contact model.
    #[error("`{item}`: the hard-contact model is linear and has no γ")]
    NoGamma {
        /// The item as written.
        item: String,
    },
}

impl SearchGrid {
    /// The model's own grid with the names `spec` gives replaced by its values.
    pub fn from_spec(kind: ModelKind, spec: &str) -> Result<Self, GridSpecError> {
        let mut grid = Self::default_for(kind);
        let mut seen: Vec<&str> = Vec::new();
        for item in spec.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let syntax = || GridSpecError::Syntax {
                item: item.to_owned(),
            };
            let (name, value) = item.split_once('=').ok_or_else(syntax)?;
            let (name, value) = (name.trim(), value.trim());
            if name.is_empty() || value.is_empty() {
                return Err(syntax());
            }
            let (slot, positive): (&mut Vec<f64>, bool) = match name {
                "c" => (&mut grid.c, true),
                "gamma" if kind == ModelKind::HardFriction => {
                    return Err(GridSpecError::NoGamma {
                        item: item.to_owned(),
                    });
                }
                "gamma" => (&mut grid.gamma, true),
                "epsilon" => (&mut grid.epsilon, false),
                _ => {
                    return Err(GridSpecError::UnknownName {
                        item: item.to_owned(),
                        name: name.to_owned(),
                    });
                }
            };
            if seen.contains(&name) {
                return Err(GridSpecError::Repeated {
                    name: name.to_owned(),
                });
            }
            seen.push(name);
            *slot = values(item, value, positive)?;
            for &v in slot.iter() {
                let (c, epsilon, gamma) = match name {
                    "c" => (Some(v), None, None),
                    "epsilon" => (None, Some(v), None),
                    _ => (None, None, Some(v)),
                };
                Plausibility::check_hyperparameters(c, epsilon, gamma).map_err(|(_, value, reason)| {
                    GridSpecError::OutOfRange {
                        item: item.to_owned(),
                        value,
                        reason,
                    }
                })?;
            }
        }
        Ok(grid)
    }
}

/// The values of one item: `v`, or `lo..hi:count` log-spaced.
fn values(item: &str, text: &str, positive: bool) -> Result<Vec<f64>, GridSpecError> {
    let number = |t: &str| -> Result<f64, GridSpecError> {
        let v: f64 = t.trim().parse().map_err(|_| GridSpecError::Number {
            item: item.to_owned(),
            text: t.trim().to_owned(),
            what: "a number",
        })?;
        let reason = if positive {
            "must be positive and finite"
        } else {
            "must be zero or positive, and finite"
        };
        if !v.is_finite() || v < 0.0 || (positive && v == 0.0) {
            return Err(GridSpecError::OutOfRange {
                item: item.to_owned(),
                value: v,
                reason,
            });
        }
        Ok(v)
    };
    let Some((range, count)) = text.split_once(':') else {
        if text.contains("..") {
            return Err(GridSpecError::Range {
                item: item.to_owned(),
                reason: "a range needs a count: lo..hi:count".into(),
            });
        }
        return Ok(vec![number(text)?]);
    };
    let (lo, hi) = range.split_once("..").ok_or_else(|| GridSpecError::Range {
        item: item.to_owned(),
        reason: "a count follows a range: lo..hi:count".into(),
    })?;
    let (lo, hi) = (number(lo)?, number(hi)?);
    let count: usize = count.trim().parse().map_err(|_| GridSpecError::Number {
        item: item.to_owned(),
        text: count.trim().to_owned(),
        what: "a whole number of values",
    })?;
    let range_error = |reason: String| GridSpecError::Range {
        item: item.to_owned(),
        reason,
    };
    if !(1..=MAX_GRID_VALUES).contains(&count) {
        return Err(range_error(format!(
            "a count of 1 to {MAX_GRID_VALUES} values, not {count}"
        )));
    }
    if lo > hi {
        return Err(range_error(format!("the range runs from {lo} down to {hi}")));
    }
    if count == 1 {
        return if lo == hi {
            Ok(vec![lo])
        } else {
            Err(range_error(format!(
                "one value cannot span {lo}..{hi}: give a count of at least 2"
            )))
        };
    }
    if lo == 0.0 {
        return Err(range_error(
            "a log-spaced range cannot start at 0: give 0 alone, or a positive start".into(),
        ));
    }
    let ratio = hi / lo;
    let last = (count - 1) as f64;
    Ok((0..count)
        .map(|i| match i {
            0 => lo,
            i if i == count - 1 => hi,
            i => lo * ratio.powf(i as f64 / last),
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &[f64], b: &[f64]) -> bool {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| ((x - y) / y).abs() < 1e-12)
    }

    #[test]
    fn ranges_are_log_spaced_with_both_ends_and_names_left_out_keep_the_defaults() {
        let grid = SearchGrid::from_spec(
            ModelKind::NeedlePuncture,
            "c=1e1..1e5:5, gamma=10..1000:3,epsilon=0.02",
        )
        .expect("valid");
        assert!(close(&grid.c, &[1e1, 1e2, 1e3, 1e4, 1e5]));
        assert!(close(&grid.gamma, &[10.0, 100.0, 1000.0]));
        assert_eq!(grid.epsilon, [0.02]);
        let defaults = SearchGrid::default_for(ModelKind::NeedlePuncture);
        assert_eq!(grid.folds, defaults.folds);
        let only_c = SearchGrid::from_spec(ModelKind::NeedlePuncture, "c=5..5:1").expect("valid");
        assert_eq!(only_c.c, [5.0]);
        assert_eq!((only_c.gamma, only_c.epsilon), (defaults.gamma, defaults.epsilon));
        // ε may be exactly 0 on its own.
        assert_eq!(
            SearchGrid::from_spec(ModelKind::HardFriction, "epsilon=0")
                .expect("valid")
                .epsilon,
            [0.0]
        );
        assert_eq!(
            SearchGrid::from_spec(ModelKind::SoftFriction, "").expect("empty"),
            SearchGrid::default_for(ModelKind::SoftFriction)
        );
    }

    #[test]
    fn every_bad_spec_is_a_typed_error_naming_its_item() {
        let kind = ModelKind::NeedlePuncture;
        let err = |spec: &str| SearchGrid::from_spec(kind, spec).expect_err(spec);
        assert!(matches!(err("c"), GridSpecError::Syntax { .. }));
        assert!(matches!(err("=3"), GridSpecError::Syntax { .. }));
        assert!(matches!(err("k=3"), GridSpecError::UnknownName { name, .. } if name == "k"));
        assert!(matches!(err("c=1,c=2"), GridSpecError::Repeated { name } if name == "c"));
        assert!(matches!(err("c=ten"), GridSpecError::Number { text, .. } if text == "ten"));
        assert!(matches!(err("c=1..10:x"), GridSpecError::Number { text, .. } if text == "x"));
        assert!(matches!(err("c=0"), GridSpecError::OutOfRange { .. }));
        assert!(matches!(err("gamma=-1"), GridSpecError::OutOfRange { .. }));
        assert!(matches!(err("epsilon=nan"), GridSpecError::OutOfRange { .. }));
        assert!(matches!(err("c=inf"), GridSpecError::OutOfRange { .. }));
        assert!(matches!(err("c=1..10"), GridSpecError::Range { .. }));
        assert!(matches!(err("c=1:3"), GridSpecError::Range { .. }));
        assert!(matches!(err("c=10..1:3"), GridSpecError::Range { .. }));
        assert!(matches!(err("c=1..10:0"), GridSpecError::Range { .. }));
        assert!(matches!(err("c=1..10:101"), GridSpecError::Range { .. }));
        assert!(matches!(err("c=1..10:1"), GridSpecError::Range { .. }));
        assert!(matches!(err("epsilon=0..1:3"), GridSpecError::Range { .. }));
        let linear = SearchGrid::from_spec(ModelKind::HardFriction, "gamma=1");
        assert!(matches!(linear, Err(GridSpecError::NoGamma { .. })));
        let text = err("c=1e1..1e5:x").to_string();
        assert!(text.contains("`c=1e1..1e5:x`") && text.contains("`x`"), "{text}");
    }
}
