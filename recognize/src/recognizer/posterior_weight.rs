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
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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
    /// How the anytime decisions at `weight` did on the held-out strokes: how far into a
    /// stroke and how soon this rig's surfaces were named. Files written before the field have
    /// none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub held_out: Option<HeldOutDecisions>,
}

/// The anytime decisions on the strokes held out of the weight's fit, at the fitted weight and
/// one threshold: what the recognizer's surfaces need on the rig they were recorded on. The
/// path (through the play) is what carries to another stroke speed, as long as the windows
/// read that speed as well.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeldOutDecisions {
    /// The posterior a surface was named at.
    pub threshold: f64,
    /// Held-out strokes of one surface, and of those, how many did not end named right.
    pub strokes: usize,
    pub not_stable: usize,
    /// Share of the named decisions that named the right surface.
    pub named_right: f64,
    /// Mean over the strokes that end named right of the time from contact to the decision that
    /// starts the final run of right ones, s, and of the tool's path by then, m (`None` where
    /// a capture has no position column).
    pub stable_right_s: f64,
    pub stable_right_m: Option<f64>,
    /// The surface with the longest mean path to its stable right decision (or time, without
    /// positions), its mean time, s, and its mean path, m.
    pub slowest_surface: String,
    pub slowest_surface_s: f64,
    pub slowest_surface_m: Option<f64>,
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
        match &self.held_out {
            Some(h) => h.check(),
            None => Ok(()),
        }
    }

    /// Whether a posterior keeping `memory_s` keeps the memory this weight was fitted at (to
    /// the millisecond, as memories are given).
    pub fn fitted_at_memory(&self, memory_s: f64) -> bool {
        (self.memory_s - memory_s).abs() < 5e-4
    }
}

impl HeldOutDecisions {
    /// Checks decisions read from a file: `Err((field, reason))`.
    fn check(&self) -> Result<(), (&'static str, String)> {
        if !(self.threshold > 0.0 && self.threshold <= 1.0) {
            return Err((
                "held_out.threshold",
                format!("{} is not in (0, 1]", self.threshold),
            ));
        }
        if !(0.0..=1.0).contains(&self.named_right) {
            return Err((
                "held_out.named_right",
                format!("{} is not a share in [0, 1]", self.named_right),
            ));
        }
        if self.not_stable >= self.strokes {
            return Err((
                "held_out.not_stable",
                format!(
                    "{} of {} strokes: some stroke must end named right",
                    self.not_stable, self.strokes
                ),
            ));
        }
        let lengths = [
            ("held_out.stable_right_s", Some(self.stable_right_s)),
            ("held_out.stable_right_m", self.stable_right_m),
            ("held_out.slowest_surface_s", Some(self.slowest_surface_s)),
            ("held_out.slowest_surface_m", self.slowest_surface_m),
        ];
        for (field, v) in lengths {
            if let Some(v) = v
                && !(v.is_finite() && v >= 0.0)
            {
                return Err((field, format!("{v} is not a time or path of at least 0")));
            }
        }
        Ok(())
    }
}

impl std::fmt::Display for HeldOutDecisions {
    /// "at 0.9 on 21 held-out strokes: the stable right surface 4.8 mm (1.08 s) into a stroke
    /// on average, 8.4 mm (1.83 s) on the slowest surface (sandpaper_80); 100.0 % of named
    /// decisions right, 0 of 21 strokes not ending right"
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let at = |m: Option<f64>, s: f64| match m {
            Some(m) => format!("{:.1} mm ({s:.2} s)", 1e3 * m),
            None => format!("{s:.2} s"),
        };
        write!(
            f,
            "at {} on {} held-out strokes: the stable right surface {} into a stroke on average, {} on \
             the slowest surface ({}); {:.1} % of named decisions right, {} of {} strokes not ending right",
            self.threshold,
            self.strokes,
            at(self.stable_right_m, self.stable_right_s),
            at(self.slowest_surface_m, self.slowest_surface_s),
            self.slowest_surface,
            100.0 * self.named_right,
            self.not_stable,
            self.strokes
        )
    }
}
