//! The table a recognizer's defaults were chosen from ([`super::DefaultSearch`]): each
//! candidate and how it fared under cross-validation, as the recognizer file keeps it.

use serde::{Deserialize, Serialize};

use crate::features::FeatureSet;
use crate::features::spectral::{CellScale, Histogram};

/// One candidate: a feature set, with its window and histogram where it has them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Candidate {
    /// The features.
    pub features: FeatureSet,
    /// The decision (and training) window, s; `None` for whole captures (`spectral`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub window_s: Option<f64>,
    /// The histogram's or window spectrum's definition; `None` for Nakano's features alone.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub histogram: Option<Histogram>,
}

impl Candidate {
    /// As the table prints it: `both, 3 s windows, mean cells, paper band`.
    pub fn describe(&self) -> String {
        let mut parts = vec![self.features.name().to_owned()];
        parts.push(match self.window_s {
            Some(s) => format!("{s} s windows"),
            None => "whole captures".to_owned(),
        });
        match (self.histogram, self.features) {
            (Some(h), FeatureSet::Spectral | FeatureSet::Both) => parts.push(h.to_string()),
            (Some(h), _) => parts.push(
                match h.cells {
                    CellScale::Mean => "mean cells",
                    CellScale::UnitSum => "unit-sum cells",
                }
                .to_owned(),
            ),
            (None, _) => {}
        }
        parts.join(", ")
    }
}

/// How one candidate fared.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "outcome", rename_all = "snake_case")]
pub enum Outcome {
    /// Cross-validated.
    Scored {
        /// Share of held-out decisions that named the right surface.
        accuracy: f64,
        /// Held-out decisions (windows, or whole captures).
        decisions: u64,
        /// Wall-clock time of its cross-validation, s.
        seconds: f64,
    },
    /// It could not be trained or evaluated on these captures.
    Failed {
        /// Why, in the words of the error.
        reason: String,
    },
    /// The budget was spent before its turn.
    NotTried,
    /// Still being cross-validated when the budget ran out: stopped, not scored.
    Stopped {
        /// Wall-clock time it ran, s.
        seconds: f64,
    },
}

/// One row of the table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CandidateScore {
    /// The candidate.
    pub candidate: Candidate,
    /// How it fared.
    #[serde(flatten)]
    pub outcome: Outcome,
}

impl CandidateScore {
    /// Its accuracy, if it was scored.
    pub fn accuracy(&self) -> Option<f64> {
        match self.outcome {
            Outcome::Scored { accuracy, .. } => Some(accuracy),
            _ => None,
        }
    }
}

/// The table a recognizer's defaults were chosen from, as its file keeps it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DefaultChoice {
    /// Folds of the cross-validation by recording.
    pub folds: usize,
    /// Distance between the candidates' windows, s.
    pub hop_s: f64,
    /// The time budget, s.
    pub budget_s: f64,
    /// Every candidate, in the order tried.
    pub rows: Vec<CandidateScore>,
    /// The row chosen; when no candidate could be scored, the first (the documented default).
    pub chosen: usize,
}

impl DefaultChoice {
    /// The chosen candidate.
    pub fn chosen(&self) -> &Candidate {
        &self.rows[self.chosen].candidate
    }

    /// Checks the table's shape; `Err((field, reason))`.
    pub(crate) fn validate(&self) -> Result<(), (String, String)> {
        let bad = |field: &str, reason: String| Err((format!("default_choice.{field}"), reason));
        if self.rows.is_empty() {
            return bad("rows", "no candidates".into());
        }
        if self.chosen >= self.rows.len() {
            return bad(
                "chosen",
                format!("{} is not a row (there are {})", self.chosen, self.rows.len()),
            );
        }
        for (i, row) in self.rows.iter().enumerate() {
            if let Outcome::Scored { accuracy, .. } = row.outcome
                && !(0.0..=1.0).contains(&accuracy)
            {
                return bad(
                    &format!("rows[{i}].accuracy"),
                    format!("{accuracy} is not in 0 … 1"),
                );
            }
        }
        Ok(())
    }
}
