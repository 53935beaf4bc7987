//! The posterior's window weight as a recognizer file keeps it: fitted on recordings held out
//! of training (see
//! [`RecognizerFile::fit_posterior_weight`](crate::RecognizerFile::fit_posterior_weight) for how
//! and why).

use serde::{Deserialize, Serialize};

use crate::sequential::DEFAULT_MEMORY_S;

/// Weights tried per doubling of the weight.
pub const WEIGHT_STEPS_PER_OCTAVE: i32 = 4;

/// The weights tried, in steps of [`WEIGHT_STEPS_PER_OCTAVE`] per octave from `hop / window`:
/// three octaves below it and two above (capped at 1, a window's whole evidence). Below,
/// because windows that overlap or repeat one another say less than they seem to; above,
/// because a classifier's window probabilities can be too cautious (a k-NN's vote fractions
/// hedge, an SVM's Platt scaling is fitted on its own cross-validation).
pub const WEIGHT_OCTAVES: (i32, i32) = (-3, 2);

/// Most folds of the fit's cross-validation: one recording held out at a time up to this many
/// recordings, more sharing a fold beyond. A fold's recognizer, trained without its recordings,
/// is less sure than the one trained on all of them, so the weight fitted on the folds is too
/// low by what the folds lack: held out a fifth at a time, the scene's SVM was fitted 0.048 and
/// left its posterior underconfident on tracks it never saw (calibration error 3.3 %), held out
/// one of 21 recordings at a time, 0.057 and 2.5 %. Past 20 recordings a fold keeps at least
/// 95 % of them, and more folds would only cost refits.
pub const WEIGHT_FIT_FOLDS: usize = 20;

/// The posterior's weight fitted on held-out recordings, and what it was measured against.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PosteriorWeight {
    /// The exponent of a window of whole evidence's probabilities.
    pub weight: f64,
    /// `hop / window`: the weight without the fit.
    pub hop_weight: f64,
    /// Folds of the cross-validation by recording.
    pub folds: usize,
    /// Held-out windows the posterior was scored on.
    pub windows: usize,
    /// The posterior's mean Brier score over them at `weight`.
    pub brier: f64,
    /// The same at `hop_weight`.
    pub hop_brier: f64,
    /// The posterior's memory the weight was fitted at, s (as `--memory-s` gives it: over
    /// travel, the travel of that long at the windows' speed). A window's weight and the
    /// memory trade against each other, so a posterior that keeps another memory is outside
    /// what the fit measured. Files written before the field fitted at
    /// [`DEFAULT_MEMORY_S`].
    #[serde(default = "default_memory_s")]
    pub memory_s: f64,
}

fn default_memory_s() -> f64 {
    DEFAULT_MEMORY_S
}

impl PosteriorWeight {
    /// Checks a fit read from a file: `Err((field, reason))`.
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        for (field, w) in [("weight", self.weight), ("hop_weight", self.hop_weight)] {
            if !(w > 0.0 && w <= 1.0) {
                return Err((field, format!("{w} is not in (0, 1]")));
            }
        }
        if self.folds < 2 {
            return Err(("folds", format!("{} folds; cross-validation needs 2", self.folds)));
        }
        for (field, b) in [("brier", self.brier), ("hop_brier", self.hop_brier)] {
            if !(0.0..=2.0).contains(&b) {
                return Err((field, format!("{b} is not a Brier score in [0, 2]")));
            }
        }
        if !(self.memory_s.is_finite() && self.memory_s > 0.0) {
            return Err((
                "memory_s",
                format!("{} s is not a positive memory", self.memory_s),
            ));
        }
        Ok(())
    }

    /// Whether a posterior keeping `memory_s` keeps the memory this weight was fitted at (to
    /// the millisecond, as memories are given).
    pub fn fitted_at_memory(&self, memory_s: f64) -> bool {
        (self.memory_s - memory_s).abs() < 5e-4
    }
}
