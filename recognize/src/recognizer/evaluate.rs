//! Evaluation of a recognizer on labelled captures: its confusions and timing, the fusion of a
//! trial's behaviours, and a SOM's fit.

use std::borrow::Borrow;
use std::path::PathBuf;

#[cfg(doc)]
use super::TRIAL_KEY;
use super::file::{RecognizerBody, RecognizerFile};
use super::grouping::trial_of;
use super::labelled::{check_rate, class_index};
use super::{Decision, LabelledCapture};
use crate::RecognizeError;
use crate::eval::{ConfusionMatrix, stable_right_from};
use crate::features::{WindowlessCapture, windows};
#[cfg(doc)]
use crate::fusion::fuse;
use crate::fusion::fused_label;
use crate::{DataError, InputError};

/// One behaviour's scratches classified alone, in a [`FusedEvaluation`].
#[derive(Debug, Clone)]
pub struct BehaviourScore {
    /// The behaviour.
    pub behaviour: Option<String>,
    /// Its weight in the fusion.
    pub weight: f64,
    /// Its scratches, by true and predicted class.
    pub confusion: ConfusionMatrix<String>,
}

/// Result of fusing the behaviours of each trial (Sinapov Sec. IV-C).
///
/// The evaluated captures are grouped by surface and [`TRIAL_KEY`]: a group is one object
/// explored by one or more behaviours; a capture without a trial is a group of its own. Each
/// group gets one decision, the argmax of its scratches' class probabilities averaged with the
/// behaviours' weights ([`RecognizerFile::fusion_weights`], [`fuse`], [`fused_label`]); a
/// group of one scratch keeps that scratch's own decision.
#[derive(Debug, Clone)]
pub struct FusedEvaluation {
    /// One decision per group, by true and predicted class.
    pub confusion: ConfusionMatrix<String>,
    /// Groups (trials) evaluated.
    pub groups: usize,
    /// Groups of more than one scratch.
    pub multi_scratch_groups: usize,
    /// Each behaviour of the recognizer that occurs in the evaluated captures, alone.
    pub per_behaviour: Vec<BehaviourScore>,
}

impl FusedEvaluation {
    /// The best accuracy of a single behaviour alone.
    pub fn best_single_accuracy(&self) -> Option<f64> {
        self.per_behaviour
            .iter()
            .filter_map(|b| b.confusion.accuracy())
            .reduce(f64::max)
    }
}

/// A SOM's fit to a set of windows ([`RecognizerFile::som_quality`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SomQuality {
    /// Mean distance from each scaled window to its winner's reference vector.
    pub quantization_error: f64,
    /// Fraction of windows whose two best nodes are not neighbours on the line.
    pub topographic_error: f64,
    /// Windows measured.
    pub windows: usize,
}

/// Result of evaluating a recognizer on labelled captures.
#[derive(Debug, Clone)]
pub struct Evaluation {
    /// `som` or `knn`.
    pub method: &'static str,
    /// Every decision, by true and predicted class.
    pub confusion: ConfusionMatrix<String>,
    /// Window length, s (k-NN: the mean capture duration, its window is the whole scratch).
    pub window_s: f64,
    /// From a window's first sample to its decision, s (k-NN: the mean capture duration).
    pub decision_latency_s: f64,
    /// Mean over captures with a correct decision of the time from the capture's first sample
    /// to the first correct decision, s.
    pub time_to_first_correct_s: Option<f64>,
    /// Mean over captures whose last decision is correct of the time from the first sample to
    /// the decision that starts the final run of correct decisions, s.
    pub time_to_stable_s: Option<f64>,
    /// Changes of decision per second of decisions (pooled over captures).
    pub flips_per_s: f64,
    /// Captures evaluated.
    pub captures: usize,
    /// Captures never recognized correctly.
    pub never_correct: usize,
    /// Captures whose last decision is wrong.
    pub not_stable: usize,
    /// Captures that gave no decision (shorter than one decision window, or a tip that never
    /// travels far enough), and why. They still count in `captures`, `never_correct` and
    /// `not_stable`: a capture the recognizer cannot answer is one it never recognizes.
    pub windowless: Vec<WindowlessCapture>,
}

/// The scratches of one trial: each one's behaviour index, decision and class probabilities.
type TrialScratches = Vec<(usize, usize, Vec<f64>)>;

impl RecognizerFile {
    /// Fuses the behaviours of each trial of `captures` (see [`FusedEvaluation`]); `None` for a
    /// SOM recognizer.
    ///
    /// Groups whose behaviours all weigh 0 (each never classified a held-out trial right)
    /// are fused with equal weights instead.
    pub fn evaluate_fused<C: Borrow<LabelledCapture>>(
        &self,
        captures: &[C],
    ) -> Result<Option<FusedEvaluation>, RecognizeError> {
        if !self.body.is_scratch() {
            return Ok(None);
        }
        let names = self.behaviour_names();
        let weights = self.fusion_weights();
        let mut alone: Vec<Option<ConfusionMatrix<String>>> = vec![None; names.len()];
        // (surface, trial) → the group's (behaviour, probabilities); trial-less captures alone.
        let mut trials: std::collections::BTreeMap<(usize, String), TrialScratches> =
            std::collections::BTreeMap::new();
        let mut singles: Vec<(usize, TrialScratches)> = Vec::new();
        for c in captures {
            let c = c.borrow();
            let truth = class_index(&self.classes, c)?;
            let (b, label, p) = self.scratch_prediction(c)?;
            let matrix = match &mut alone[b] {
                Some(m) => m,
                slot => slot.insert(ConfusionMatrix::new(self.classes.clone())?),
            };
            matrix.add(&self.classes[truth], &self.classes[label])?;
            match trial_of(c) {
                Some(trial) => trials
                    .entry((truth, trial.to_owned()))
                    .or_default()
                    .push((b, label, p)),
                None => singles.push((truth, vec![(b, label, p)])),
            }
        }
        let mut confusion = ConfusionMatrix::new(self.classes.clone())?;
        let mut multi_scratch_groups = 0;
        let groups: Vec<(usize, TrialScratches)> = trials
            .into_iter()
            .map(|((truth, _), members)| (truth, members))
            .chain(singles)
            .collect();
        for (truth, members) in &groups {
            multi_scratch_groups += usize::from(members.len() > 1);
            let l: Vec<usize> = members.iter().map(|(_, l, _)| *l).collect();
            let p: Vec<&[f64]> = members.iter().map(|(_, _, p)| p.as_slice()).collect();
            let w: Vec<f64> = members.iter().map(|(b, _, _)| weights[*b]).collect();
            let label = match fused_label(&l, &p, &w) {
                Err(RecognizeError::Data(DataError::ZeroTotalWeight)) => {
                    fused_label(&l, &p, &vec![1.0; p.len()])
                }
                other => other,
            }
            .map_err(|e| {
                RecognizeError::Input(InputError::UnusableCapture {
                    path: PathBuf::from(&self.classes[*truth]),
                    reason: format!("fusing a trial's behaviours: {e}"),
                })
            })?;
            confusion.add(&self.classes[*truth], &self.classes[label])?;
        }
        let per_behaviour = alone
            .into_iter()
            .enumerate()
            .filter_map(|(b, m)| {
                m.map(|confusion| BehaviourScore {
                    behaviour: names[b].map(str::to_owned),
                    weight: weights[b],
                    confusion,
                })
            })
            .collect();
        Ok(Some(FusedEvaluation {
            confusion,
            groups: groups.len(),
            multi_scratch_groups,
            per_behaviour,
        }))
    }

    /// Evaluates on `captures`; `window_s` overrides a SOM's window length.
    ///
    /// A capture that gives no decision window does not fail the evaluation: it is listed in
    /// [`Evaluation::windowless`] (the CLI warns about each), since the other captures are
    /// still scored. When no capture gives a decision there is nothing to score, and the
    /// evaluation is refused with [`DataError::NoDecisions`] naming every capture and why,
    /// rather than reporting an accuracy over zero decisions.
    pub fn evaluate<C: Borrow<LabelledCapture>>(
        &self,
        captures: &[C],
        window_s: Option<f64>,
    ) -> Result<Evaluation, RecognizeError> {
        let windowing = match (self.windowing(), window_s) {
            (Some(w), Some(s)) => Some(w.with_window_s(s)?),
            (w, _) => w.copied(),
        };
        let mut confusion = ConfusionMatrix::new(self.classes.clone())?;
        let (mut first, mut stable) = (Vec::new(), Vec::new());
        let (mut flips, mut span_s, mut duration_s) = (0usize, 0.0, 0.0);
        let mut windowless = Vec::new();
        for c in captures {
            let c = c.borrow();
            let truth = class_index(&self.classes, c)?;
            let rate_hz = c.capture.metadata().rate_hz();
            duration_s += c.samples() as f64 / rate_hz;
            let decisions = self.decisions(c, windowing.as_ref())?;
            if decisions.is_empty() {
                windowless.push(match &windowing {
                    Some(w) => WindowlessCapture::of(c, w, "decision"),
                    None => WindowlessCapture {
                        path: c.reference.path.clone(),
                        reason: "gave no decision".to_owned(),
                    },
                });
            }
            for d in &decisions {
                confusion.add(&self.classes[truth], &self.classes[d.label])?;
            }
            let at_s = |d: &Decision| d.decided_at as f64 / rate_hz;
            if let Some(d) = decisions.iter().find(|d| d.label == truth) {
                first.push(at_s(d));
            }
            if let Some(k) = stable_right_from(&decisions, |d| d.label == truth) {
                stable.push(at_s(&decisions[k]));
            }
            flips += decisions.windows(2).filter(|p| p[0].label != p[1].label).count();
            if let (Some(a), Some(b)) = (decisions.first(), decisions.last()) {
                span_s += at_s(b) - at_s(a);
            }
        }
        if confusion.total() == 0 {
            return Err(RecognizeError::Data(DataError::NoDecisions {
                captures: windowless,
            }));
        }
        let mean = |v: &[f64]| (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64);
        let (window_s, decision_latency_s) = match &windowing {
            Some(w) => (w.window_s(), w.decision_latency_s()),
            None => {
                let mean_s = duration_s / captures.len().max(1) as f64;
                (mean_s, mean_s)
            }
        };
        Ok(Evaluation {
            method: self.method(),
            confusion,
            window_s,
            decision_latency_s,
            time_to_first_correct_s: mean(&first),
            time_to_stable_s: mean(&stable),
            flips_per_s: if span_s > 0.0 { flips as f64 / span_s } else { 0.0 },
            captures: captures.len(),
            never_correct: captures.len() - first.len(),
            not_stable: captures.len() - stable.len(),
            windowless,
        })
    }

    /// How well a SOM recognizer's map fits the windows of `captures` — its training windows
    /// when `training`, else its decision windows (of `window_s` when given, as
    /// [`RecognizerFile::evaluate`] takes them): the quantization and topographic errors
    /// (Kohonen's measures of fit and of order). `None` for other recognizers, or when no
    /// capture is long enough for a window.
    pub fn som_quality<C: Borrow<LabelledCapture>>(
        &self,
        captures: &[C],
        training: bool,
        window_s: Option<f64>,
    ) -> Result<Option<SomQuality>, RecognizeError> {
        let RecognizerBody::Som { windowing, som } = &self.body else {
            return Ok(None);
        };
        let windowing = match (training, window_s) {
            (true, _) => windowing.training(),
            (false, Some(s)) => windowing.with_window_s(s)?,
            (false, None) => *windowing,
        };
        let mut data = Vec::new();
        for c in captures {
            let c = c.borrow();
            check_rate(c, windowing.rate_hz)?;
            data.extend(windows(c, &windowing)?.into_iter().map(|(_, _, f)| f.to_vec()));
        }
        if data.is_empty() {
            return Ok(None);
        }
        Ok(Some(SomQuality {
            quantization_error: som.quantization_error(&data).map_err(RecognizeError::som)?,
            topographic_error: som.topographic_error(&data).map_err(RecognizeError::som)?,
            windows: data.len(),
        }))
    }
}
