//! Defaults chosen on the training captures: when the user names neither the features, the
//! histogram's definition nor the window, training scores each candidate by cross-validation
//! grouped by recording on the training captures themselves, within a time budget, and trains
//! the most accurate. The table it chose from is kept in the recognizer file.
//!
//! A researcher cannot know which feature set, window and cell scaling their own rig wants:
//! defaults fixed on one generator are the weakest choice on a rig it did not model. The
//! search measures it instead, on exactly the recognizer `train` would fit: each candidate is
//! the same [`TrainSettings`] with only the searched fields changed, trained and evaluated by
//! [`protocol::run`] (k-fold by recording) — with three shortcuts that change the recognizer's
//! cost, not what it is: training and decision windows every [`SPARSE_HOP_S`] instead of every
//! hop (neighbouring windows 0.1 s apart share 97 % of their samples), the posterior's weight
//! not fitted (it does not change a window's decision), and an SVM over windows at
//! C = [`WINDOW_SVM_FALLBACK_C`](super::WINDOW_SVM_FALLBACK_C) instead of a search over C, not
//! cross-validated for a reliability ([`SvmC::Unscored`]).
//!
//! **Order and ties.** Candidates are tried in a fixed order: first each feature set with the
//! documented defaults ([`Method::features_for`]'s choice first), then the other cell scalings
//! and bands, then the shorter window. A candidate is chosen over an earlier one only when it
//! is more accurate by more than [`CLEAR_MARGIN_Z`] standard errors of the difference (windows
//! counted by how much they overlap): the documented default stands unless the captures say
//! clearly otherwise. A candidate that would overrun the budget (at what the last of its
//! feature set took) is listed as not tried, and cheaper ones after it still are; an SVM
//! still solving when the budget runs out is stopped and listed so (one over a channel of
//! noise alone can take minutes to separate nothing); a
//! candidate that cannot be trained or evaluated on these captures (no window holds its
//! histogram, every window slid too fast for its bands) is listed with the reason.

use std::time::{Duration, Instant};

use rayon::prelude::*;

use super::choice_table::{Candidate, CandidateScore, DefaultChoice, Outcome};
use super::train::{SPARSE_HOP_S, WINDOW_SVM_FALLBACK_C};
use super::{LabelledCapture, Method, SvmC, TrainSettings};
use crate::RecognizeError;
use crate::features::spectral::{CellScale, Histogram, HistogramBand, SpectrogramPlan};
use crate::features::{DECISION_WINDOW_S, FeatureSet};
use crate::protocol::{self, Split};
use crate::svc::{FitEvent, Progress};
use crate::{FeatureNeeds, SettingError};

/// Folds of the search's cross-validation (fewer when there are fewer recordings).
pub const SEARCH_FOLDS: usize = 5;
/// The search's default time budget, s: a candidate is not tried when the time spent and what
/// the last candidate of its set took would exceed it, and an SVM's solves stop when it runs
/// out.
pub const SEARCH_BUDGET_S: f64 = 20.0;
/// How many standard errors of the difference a later candidate must be more accurate by to
/// be chosen over an earlier one (see [`clearly_better`]).
pub const CLEAR_MARGIN_Z: f64 = 2.0;
/// The shorter window the search tries beside the default, s: the shortest that holds the
/// spectrotemporal histogram's five frames (1.92 s), rounded up.
pub const SHORT_WINDOW_S: f64 = 2.0;

/// What the user named on the command line; the search varies only the rest.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Named {
    /// `--features`.
    pub features: Option<FeatureSet>,
    /// `--cells`.
    pub cells: Option<CellScale>,
    /// `--bands`.
    pub band: Option<HistogramBand>,
    /// `--window-s` (or `--train-window-s`, which ties the training window to it).
    pub window_s: Option<f64>,
}

impl Named {
    /// Whether everything the search varies was named: then there is nothing to choose.
    pub fn all(&self) -> bool {
        self.features.is_some() && self.cells.is_some() && self.band.is_some() && self.window_s.is_some()
    }
}

impl Candidate {
    /// `base` with this candidate's features, window and histogram.
    pub fn settings(&self, base: &TrainSettings) -> TrainSettings {
        TrainSettings {
            features: self.features,
            window_s: self.window_s.unwrap_or(base.window_s),
            histogram: self.histogram.unwrap_or(base.histogram),
            ..base.clone()
        }
    }
}

/// The candidates to score and how, for one training.
#[derive(Debug, Clone)]
pub struct DefaultSearch {
    base: TrainSettings,
    candidates: Vec<Candidate>,
    budget_s: f64,
}

impl DefaultSearch {
    /// The candidates for training as `base` says on captures shaped like `first`, varying
    /// only what `named` leaves open: the feature sets `first` carries the columns of and the
    /// method takes that decide on what the default decides on (windows, or whole captures),
    /// each histogram's cell scaling and band (the Nyquist band only where the
    /// rate puts it above the paper's 200 Hz), and windows of [`DECISION_WINDOW_S`] and
    /// [`SHORT_WINDOW_S`] (a window shorter than a histogram's five frames is left out for
    /// `both`). `budget_s` bounds the search's time (see [`SEARCH_BUDGET_S`]).
    pub fn new(base: TrainSettings, named: Named, first: &LabelledCapture, budget_s: f64) -> Self {
        let rate_hz = first.capture.metadata().rate_hz();
        let method = base.method;
        let windows: Vec<f64> = match named.window_s {
            Some(s) => vec![s],
            None => vec![DECISION_WINDOW_S, SHORT_WINDOW_S],
        };
        let holds_a_histogram = |window_s: f64| {
            SpectrogramPlan::at_rate(rate_hz)
                .is_ok_and(|plan| (window_s * rate_hz).round() >= plan.min_samples() as f64)
        };
        let default_set = method.features_for(first, windows[0]);
        let sets: Vec<FeatureSet> = match named.features {
            Some(f) => vec![f],
            None => {
                let mut sets = vec![default_set];
                let takes: &[FeatureSet] = match method {
                    Method::Som => &[FeatureSet::Nakano, FeatureSet::Both, FeatureSet::Spectral],
                    Method::Knn | Method::Svm => &[
                        FeatureSet::Nakano,
                        FeatureSet::Both,
                        FeatureSet::Spectral,
                        FeatureSet::NakanoSpectrum,
                        FeatureSet::Vibration,
                    ],
                };
                // Whole captures and windows are not compared: see `same_decisions`.
                sets.extend(takes.iter().copied().filter(|f| {
                    *f != default_set
                        && same_decisions(*f, default_set)
                        && f.missing_columns(first).is_empty()
                }));
                sets
            }
        };
        let cells: Vec<CellScale> = match named.cells {
            Some(c) => vec![c],
            None => vec![CellScale::Mean, CellScale::UnitSum],
        };
        let nyquist_differs = HistogramBand::Nyquist.top_hz(rate_hz) > HistogramBand::Paper.top_hz(rate_hz);
        let bands: Vec<HistogramBand> = match named.band {
            Some(b) => vec![b],
            None if nyquist_differs => HistogramBand::ALL.to_vec(),
            None => vec![HistogramBand::Paper],
        };
        // Histograms of a set, the defaults first.
        let histograms = |features: FeatureSet| -> Vec<Option<Histogram>> {
            match features {
                FeatureSet::Nakano => vec![None],
                FeatureSet::Spectral | FeatureSet::Both => bands
                    .iter()
                    .flat_map(|&band| cells.iter().map(move |&c| Some(Histogram::new(c).over(band))))
                    .collect(),
                // A window spectrum has bands of its own; only its cells are chosen.
                FeatureSet::Vibration | FeatureSet::NakanoSpectrum => {
                    cells.iter().map(|&c| Some(Histogram::new(c))).collect()
                }
            }
        };
        let mut candidates = Vec::new();
        // Each set at the defaults, then the other histograms, then the other windows.
        for tier in 0..3 {
            for &features in &sets {
                let set_windows: Vec<Option<f64>> = match features {
                    FeatureSet::Spectral => vec![None],
                    FeatureSet::Both => windows
                        .iter()
                        .copied()
                        .filter(|&s| holds_a_histogram(s))
                        .map(Some)
                        .collect(),
                    _ => windows.iter().copied().map(Some).collect(),
                };
                let set_histograms = histograms(features);
                for (w, window_s) in set_windows.iter().enumerate() {
                    for (h, histogram) in set_histograms.iter().enumerate() {
                        let in_tier = match (w, h) {
                            (0, 0) => 0,
                            (0, _) => 1,
                            _ => 2,
                        };
                        if in_tier == tier {
                            candidates.push(Candidate {
                                features,
                                window_s: *window_s,
                                histogram: *histogram,
                            });
                        }
                    }
                }
            }
        }
        Self {
            base,
            candidates,
            budget_s,
        }
    }

    /// The candidates, in the order they are tried.
    pub fn candidates(&self) -> &[Candidate] {
        &self.candidates
    }

    /// Whether there is more than one candidate, i.e. anything to choose.
    pub fn has_choice(&self) -> bool {
        self.candidates.len() > 1
    }

    /// The settings a candidate is cross-validated with: its own, with windows every
    /// [`SPARSE_HOP_S`], no posterior weight fitted and, for an SVM over windows, C fixed.
    pub fn scored_settings(&self, candidate: &Candidate) -> TrainSettings {
        let full = candidate.settings(&self.base);
        let windowed_svm = full.method == Method::Svm && full.features != FeatureSet::Spectral;
        TrainSettings {
            hop_s: full.hop_s.max(SPARSE_HOP_S),
            fit_posterior_weight: false,
            c: if windowed_svm {
                SvmC::Unscored(WINDOW_SVM_FALLBACK_C)
            } else {
                full.c.clone()
            },
            ..full
        }
    }

    /// What the search reads from each capture at `rate_hz`: every candidate's training and
    /// decision windows (or histograms). A candidate whose settings are invalid at this rate
    /// is left out here and fails in [`DefaultSearch::run`] with the same error.
    pub fn needs(&self, rate_hz: f64) -> FeatureNeeds {
        self.candidates.iter().fold(
            FeatureNeeds::new(),
            |needs, c| match FeatureNeeds::training_and_decisions(&self.scored_settings(c), rate_hz) {
                Ok(more) => needs.merged(more),
                Err(_) => needs,
            },
        )
    }

    /// Scores the candidates on `captures` (read with [`DefaultSearch::needs`]) in order until
    /// the budget is spent, and chooses one (see the [module documentation](self)).
    pub fn run(&self, captures: &[LabelledCapture], progress: Progress<'_>) -> DefaultChoice {
        let start = Instant::now();
        let folds = protocol::recordings(captures).min(SEARCH_FOLDS);
        progress(FitEvent::Step {
            what: "choosing the features",
            total: self.candidates.len(),
        });
        let mut rows: Vec<CandidateScore> = Vec::with_capacity(self.candidates.len());
        for candidate in &self.candidates {
            // What a candidate will take, from the last of its set (and window) scored: one
            // that would overrun the budget is left for the cheaper ones after it.
            let like = |same_window: bool| {
                rows.iter().rev().find_map(|r| match r.outcome {
                    Outcome::Scored { seconds, .. }
                        if r.candidate.features == candidate.features
                            && (!same_window || r.candidate.window_s == candidate.window_s) =>
                    {
                        Some(seconds)
                    }
                    _ => None,
                })
            };
            let expected_s = like(true).or_else(|| like(false)).unwrap_or(0.0);
            let outcome = if start.elapsed().as_secs_f64() + expected_s > self.budget_s {
                Outcome::NotTried
            } else {
                self.score(candidate, captures, folds, start)
            };
            progress(FitEvent::Advance);
            rows.push(CandidateScore {
                candidate: *candidate,
                outcome,
            });
        }
        let hop_s = self.base.hop_s.max(SPARSE_HOP_S);
        let chosen = choose(&rows, hop_s);
        DefaultChoice {
            folds,
            hop_s,
            budget_s: self.budget_s,
            rows,
            chosen,
        }
    }

    /// Cross-validates `candidate`; an SVM still solving when the search's budget (from
    /// `search_start`) runs out is stopped.
    fn score(
        &self,
        candidate: &Candidate,
        captures: &[LabelledCapture],
        folds: usize,
        search_start: Instant,
    ) -> Outcome {
        let start = Instant::now();
        let settings = TrainSettings {
            time_budget: Duration::try_from_secs_f64(self.budget_s)
                .ok()
                .map(|budget| (search_start, budget)),
            ..self.scored_settings(candidate)
        };
        if folds < 2 {
            return Outcome::Failed {
                reason: RecognizeError::Setting(SettingError::Parameter {
                    of: "setting",
                    name: "folds",
                    value: folds as f64,
                    reason: "cross-validation by recording needs at least two recordings",
                })
                .to_string(),
            };
        }
        // The folds train on all cores at once: a SOM's map trains on one.
        let rounds: Vec<Result<protocol::ProtocolResult, RecognizeError>> = (1..=folds)
            .into_par_iter()
            .map(|fold| {
                protocol::run(captures, Split::KFold { folds }, 1, Some(fold), |train, _| {
                    settings.train_observed(train, &|_| {}).map_err(Box::new)
                })
            })
            .collect();
        let pooled = rounds
            .into_iter()
            .map(|round| round.map(|r| r.evaluation))
            .collect::<Result<Vec<_>, _>>()
            .and_then(|evaluations| protocol::pool(&evaluations));
        match pooled {
            Ok(Some(e)) => match e.confusion.accuracy() {
                Some(accuracy) => Outcome::Scored {
                    accuracy,
                    decisions: e.confusion.total(),
                    seconds: start.elapsed().as_secs_f64(),
                },
                None => Outcome::Failed {
                    reason: "no held-out decision".to_owned(),
                },
            },
            Ok(None) => Outcome::Failed {
                reason: "no held-out decision".to_owned(),
            },
            Err(e) if e.ran_out_of_time() => Outcome::Stopped {
                seconds: start.elapsed().as_secs_f64(),
            },
            Err(e) => Outcome::Failed { reason: e.chain() },
        }
    }
}

/// Whether two feature sets decide on the same things: both on windows, or both on whole
/// captures. The search keeps the documented default's: a whole capture is decided once, at
/// its end, where windows are decided every hop from the first seconds on (and live), so
/// their accuracies count different things; and the search's sparser windows (every
/// [`SPARSE_HOP_S`]) cost a windowed candidate training vectors that a whole capture's one
/// histogram does not lose, which would tilt the comparison.
fn same_decisions(a: FeatureSet, b: FeatureSet) -> bool {
    (a == FeatureSet::Spectral) == (b == FeatureSet::Spectral)
}

/// The row chosen: the first scored, replaced by a later one only when that is
/// [`clearly_better`] than it; the first row when none was scored.
fn choose(rows: &[CandidateScore], hop_s: f64) -> usize {
    let mut best: Option<(usize, Score)> = None;
    for (i, row) in rows.iter().enumerate() {
        let Some(score) = Score::of(row, hop_s) else {
            continue;
        };
        match best {
            Some((_, b)) if !clearly_better(score, b) => {}
            _ => best = Some((i, score)),
        }
    }
    best.map_or(0, |(i, _)| i)
}

/// A scored candidate's accuracy and how many of its held-out decisions count as independent.
#[derive(Debug, Clone, Copy)]
struct Score {
    accuracy: f64,
    independent: f64,
}

impl Score {
    /// Windows every `hop_s` over `window_s` share all but `hop_s` of their samples, so a
    /// window counts for `hop_s / window_s` of an independent decision (at most one); a whole
    /// capture counts for one.
    fn of(row: &CandidateScore, hop_s: f64) -> Option<Self> {
        let Outcome::Scored {
            accuracy, decisions, ..
        } = row.outcome
        else {
            return None;
        };
        let share = row.candidate.window_s.map_or(1.0, |w| (hop_s / w).min(1.0));
        Some(Self {
            accuracy,
            independent: (decisions as f64 * share).max(1.0),
        })
    }

    /// The variance of the accuracy as an estimate, with one right and one wrong decision
    /// added (Laplace), so that a perfect or a hopeless score is not taken as exact.
    fn variance(self) -> f64 {
        let p = (self.accuracy * self.independent + 1.0) / (self.independent + 2.0);
        p * (1.0 - p) / self.independent
    }
}

/// Whether `new` is more accurate than `old` by more than [`CLEAR_MARGIN_Z`] standard errors
/// of their difference. With few held-out recordings, every candidate's estimate is noisy and
/// the most accurate of twenty is flattered by its luck; the documented default is then kept.
fn clearly_better(new: Score, old: Score) -> bool {
    new.accuracy - old.accuracy > CLEAR_MARGIN_Z * (new.variance() + old.variance()).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An SVM candidate still solving when the search's budget runs out is stopped and listed
    /// as such, not as failed; with time left the same candidate is scored.
    #[test]
    fn a_candidate_still_solving_when_the_budget_runs_out_is_stopped() {
        let captures = super::super::tests::vibrating_surfaces(5.0, 0..3);
        let base = TrainSettings {
            window_s: 2.0,
            hop_s: 0.2,
            ..TrainSettings::new(Method::Svm)
        };
        let named = Named {
            features: Some(FeatureSet::Vibration),
            cells: Some(CellScale::Mean),
            band: Some(HistogramBand::Paper),
            window_s: Some(2.0),
        };
        let score = |budget_s: f64, start: Instant| {
            let search = DefaultSearch::new(base.clone(), named, &captures[0], budget_s);
            let needs = search.needs(1000.0);
            let kept: Vec<LabelledCapture> = captures
                .iter()
                .map(|c| c.clone().keep_features(&needs).expect("keeps"))
                .collect();
            search.score(&search.candidates()[0], &kept, 3, start)
        };
        let start = Instant::now();
        std::thread::sleep(Duration::from_millis(20));
        assert!(
            matches!(score(0.01, start), Outcome::Stopped { seconds } if seconds >= 0.0),
            "{:?}",
            score(0.01, start)
        );
        assert!(
            matches!(score(60.0, Instant::now()), Outcome::Scored { .. }),
            "{:?}",
            score(60.0, Instant::now())
        );
    }

    fn row(accuracy: Option<f64>, decisions: u64) -> CandidateScore {
        CandidateScore {
            candidate: Candidate {
                features: FeatureSet::Nakano,
                window_s: Some(3.0),
                histogram: None,
            },
            outcome: match accuracy {
                Some(accuracy) => Outcome::Scored {
                    accuracy,
                    decisions,
                    seconds: 1.0,
                },
                None => Outcome::NotTried,
            },
        }
    }

    /// The earlier candidate stands unless a later one beats it beyond twice the standard
    /// error of the difference; windows 0.5 s apart over 3 s count for a sixth each.
    #[test]
    fn a_later_candidate_is_chosen_only_when_clearly_more_accurate() {
        // 60,000 windows count as 10,000: at 95 % the margin is 2·√(2·0.0475/10⁴) = 0.62 points.
        let n = 60_000;
        let rows = [
            row(Some(0.950), n),
            row(Some(0.955), n),
            row(None, n),
            row(Some(0.957), n),
        ];
        assert_eq!(choose(&rows, 0.5), 3);
        let rows = [row(Some(0.950), n), row(Some(0.955), n), row(Some(0.9555), n)];
        assert_eq!(choose(&rows, 0.5), 0);
        // The same 2.6 points over 300 windows (50 independent) is noise.
        let rows = [row(Some(0.927), 300), row(Some(0.953), 300)];
        assert_eq!(choose(&rows, 0.5), 0);
        // Windows as far apart as they are long count whole.
        let rows = [row(Some(0.927), 3000), row(Some(0.953), 3000)];
        assert_eq!(choose(&rows, 3.0), 1);
        let rows = [
            row(None, n),
            row(Some(0.80), n),
            row(Some(0.90), n),
            row(Some(0.9005), n),
        ];
        assert_eq!(choose(&rows, 0.5), 2);
        assert_eq!(choose(&[row(None, n), row(None, n)], 0.5), 0);
        // A perfect score is not taken as exact: 100 % of 10 does not beat 90 % of 10.
        assert_eq!(choose(&[row(Some(0.9), 60), row(Some(1.0), 60)], 0.5), 0);
    }
}
