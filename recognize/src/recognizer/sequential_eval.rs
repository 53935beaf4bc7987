//! Anytime decisions on labelled captures: a k-NN's or SVM's window probabilities accumulated
//! from contact on ([`crate::sequential`]), scored for each threshold by how often a named
//! surface is right, how soon one is named, and how well the posterior is calibrated.

use std::borrow::Borrow;

use serde::Serialize;

use super::LabelledCapture;
use super::file::RecognizerFile;
use super::labelled::{class_index, class_named};
use crate::RecognizeError;
use crate::features::{NakanoWindowing, WindowlessCapture};
use crate::sequential::{SequentialParams, SequentialParamsBuilder, SequentialState};

/// Bins of the reliability diagram.
pub const RELIABILITY_BINS: usize = 10;

/// One threshold's anytime decisions, pooled over the captures.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SequentialRow {
    /// Posterior at which a surface is named.
    pub threshold: f64,
    /// Windows at which a surface was named (of [`SequentialEvaluation::steps`]).
    pub decided: usize,
    /// Of those, named right.
    pub correct: usize,
    /// Mean over captures that named a surface of the time from contact (the capture's first
    /// sample) to the first named one, s.
    pub time_to_first_decision_s: Option<f64>,
    /// Mean over captures that end named right of the time from contact to the named decision
    /// that starts the final run without a wrong one, s.
    pub time_to_stable_correct_s: Option<f64>,
    /// The surface with the longest such mean, and that mean, s.
    pub worst_surface: Option<(String, f64)>,
    /// Captures (of one surface) that do not end named right.
    pub not_stable: usize,
    /// Of the captures that slide onto another surface part-way: the mean time from the change
    /// to the named decision that starts the final run of right ones, s (over those that end
    /// named right), the longest, how many such captures there are, and how many of them do
    /// not end named right. The single-surface times above leave these captures out.
    pub change_followed_s: Option<f64>,
    pub slowest_change_s: Option<f64>,
    pub changes: usize,
    pub changes_not_followed: usize,
    /// Changes of named surface (undecided stretches not counted) per second of stroke.
    pub flips_per_s: f64,
}

impl SequentialRow {
    /// Fraction of named windows named right.
    pub fn accuracy(&self) -> Option<f64> {
        (self.decided > 0).then(|| self.correct as f64 / self.decided as f64)
    }
}

/// Windows whose top posterior fell in one bin of the reliability diagram.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ReliabilityBin {
    /// The bin's posterior range.
    pub lower: f64,
    pub upper: f64,
    /// Windows in it.
    pub count: usize,
    /// Their mean top posterior.
    pub mean_probability: f64,
    /// Fraction of them whose most probable surface is the true one.
    pub accuracy: f64,
}

/// How well the posterior's top probability matches how often its surface is the true one,
/// over every window of every capture (independent of the threshold).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Calibration {
    /// Mean over windows of Σ_c (posterior_c − [c is true])².
    pub brier: f64,
    /// Expected calibration error: the count-weighted mean of |accuracy − mean probability|
    /// over [`RELIABILITY_BINS`] equal bins of the top posterior.
    pub ece: f64,
    /// The bins (empty ones left out).
    pub bins: Vec<ReliabilityBin>,
}

/// [`RecognizerFile::evaluate_sequential`]'s result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SequentialEvaluation {
    /// The settings, with the first row's threshold (each row has its own; the calibration
    /// does not depend on it).
    pub params: SequentialParams,
    /// Window length and hop, s.
    pub window_s: f64,
    pub hop_s: f64,
    /// For windows over travel, the travel a window spans, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub window_m: Option<f64>,
    /// For friction filtered over travel, the filter's cut-off wavelength, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction_cutoff_m: Option<f64>,
    /// How long after its last sample a window is decided, s: the filters' lookahead, or 0
    /// with a mirrored end.
    pub decided_after_s: f64,
    /// Captures evaluated, and windows over all of them.
    pub captures: usize,
    pub steps: usize,
    /// One per threshold, in the order given.
    pub rows: Vec<SequentialRow>,
    pub calibration: Calibration,
}

/// One capture's windows: truth, and each window's time from contact and probabilities.
struct Stroke {
    truth: usize,
    /// When the stroke slides onto another surface, and which.
    change: Option<(f64, usize)>,
    duration_s: f64,
    /// Each window's time, its evidence scale ([`NakanoWindowing::evidence_scale`]) and
    /// its probabilities.
    windows: Vec<(f64, f64, Vec<f64>)>,
}

impl Stroke {
    /// The surface under the tool at `t_s`.
    fn truth_at(&self, t_s: f64) -> usize {
        match self.change {
            Some((at_s, after)) if t_s >= at_s => after,
            _ => self.truth,
        }
    }
}

impl RecognizerFile {
    /// The settings [`RecognizerFile::evaluate_sequential`] starts from for this recognizer:
    /// each window weighs `hop / window` (every sample counted once), and the evidence of
    /// the last `memory_s` counts; `None` for a recognizer without window probabilities.
    pub fn sequential_params(&self, memory_s: f64) -> Option<SequentialParamsBuilder> {
        let w = self.window_probability_windowing()?;
        let hop_s = w.hop_samples as f64 / w.rate_hz;
        let memory = (memory_s / hop_s).round().max(1.0) as usize;
        Some(
            SequentialParams::builder()
                .weight((hop_s / w.window_s()).min(1.0))
                .memory(memory),
        )
    }

    /// The windows anytime decisions are made on: a k-NN's or SVM's own, from contact on (the
    /// start travel set to 0, and the stroke's start mirrored so that the first window starts
    /// at its first sample); `None` for a recognizer without window probabilities.
    pub fn sequential_windowing(&self) -> Option<NakanoWindowing> {
        self.window_probability_windowing().map(|own| NakanoWindowing {
            start_travel_m: 0.0,
            mirrored_start: true,
            ..*own
        })
    }

    /// The windowing of a k-NN or SVM over windows.
    fn window_probability_windowing(&self) -> Option<&NakanoWindowing> {
        match &self.body {
            super::RecognizerBody::KnnWindows { windowing, .. }
            | super::RecognizerBody::SvmWindows { windowing, .. } => Some(windowing),
            _ => None,
        }
    }

    /// Anytime decisions on `captures` at each of `thresholds`, the other settings from
    /// `params` (see [`RecognizerFile::sequential_params`]), on the windows of
    /// [`RecognizerFile::sequential_windowing`].
    ///
    /// Only a k-NN or SVM over windows gives each window's probabilities; any other recognizer
    /// is refused, saying so.
    pub fn evaluate_sequential<C: Borrow<LabelledCapture>>(
        &self,
        captures: &[C],
        thresholds: &[f64],
        params: SequentialParamsBuilder,
    ) -> Result<SequentialEvaluation, RecognizeError> {
        let Some(windowing) = self.sequential_windowing() else {
            return Err(RecognizeError::NoWindowProbabilities {
                method: self.method(),
                features: self.feature_set().name(),
            });
        };
        let classes = self.classes.len();
        let mut strokes = Vec::with_capacity(captures.len());
        for c in captures {
            let c = c.borrow();
            let rate_hz = c.capture.metadata().rate_hz();
            let windows = self
                .window_probabilities(c, Some(&windowing))?
                .unwrap_or_default()
                .into_iter()
                .map(|w| {
                    (
                        w.decision.decided_at as f64 / rate_hz,
                        w.evidence_scale,
                        w.probabilities,
                    )
                })
                .collect();
            let change = match &c.change {
                Some(ch) => Some((ch.at_s, class_named(&self.classes, &ch.after, c)?)),
                None => None,
            };
            strokes.push(Stroke {
                truth: class_index(&self.classes, c)?,
                change,
                duration_s: c.samples() as f64 / rate_hz,
                windows,
            });
        }
        let steps = strokes.iter().map(|s| s.windows.len()).sum();
        if steps == 0 {
            let captures = captures
                .iter()
                .map(|c| WindowlessCapture::of(c.borrow(), &windowing, "decision"))
                .collect();
            return Err(RecognizeError::NoDecisions { captures });
        }
        let base = match thresholds.first() {
            Some(&t) => params.threshold(t).build()?,
            None => params.build()?,
        };
        let mut rows = Vec::with_capacity(thresholds.len());
        for &threshold in thresholds {
            let params = params.threshold(threshold).build()?;
            rows.push(self.sequential_row(&strokes, params)?);
        }
        Ok(SequentialEvaluation {
            params: base,
            window_s: windowing.window_s(),
            hop_s: windowing.hop_samples as f64 / windowing.rate_hz,
            window_m: windowing.travel.map(|t| t.window_m),
            friction_cutoff_m: windowing.friction_over_travel.map(|f| f.cutoff_m),
            decided_after_s: windowing.lookahead_samples() as f64 / windowing.rate_hz,
            captures: captures.len(),
            steps,
            rows,
            calibration: calibration(&strokes, base, classes)?,
        })
    }

    fn sequential_row(
        &self,
        strokes: &[Stroke],
        params: SequentialParams,
    ) -> Result<SequentialRow, RecognizeError> {
        let classes = self.classes.len();
        let mut state = SequentialState::new(params, classes)?;
        let (mut decided, mut correct, mut flips, mut not_stable) = (0, 0, 0, 0);
        let (mut first, mut stable) = (Vec::new(), Vec::new());
        let mut stable_by_class: Vec<Vec<f64>> = vec![Vec::new(); classes];
        let mut duration_s = 0.0;
        let (mut followed, mut not_followed) = (Vec::new(), 0);
        for s in strokes {
            state.reset();
            duration_s += s.duration_s;
            let mut named: Vec<(f64, usize)> = Vec::new();
            for (t, scale, p) in &s.windows {
                if let Some(d) = state.push_scaled(p, *scale)?.decided {
                    named.push((*t, d));
                }
            }
            decided += named.len();
            correct += named.iter().filter(|(t, d)| *d == s.truth_at(*t)).count();
            flips += named.windows(2).filter(|w| w[0].1 != w[1].1).count();
            // The named decision that starts the final run of right ones, if the stroke ends
            // named right.
            let final_right = |truth: usize| match named.last() {
                Some(&(_, d)) if d == truth => {
                    let wrong = named.iter().rposition(|(_, d)| *d != truth);
                    Some(named[wrong.map_or(0, |w| w + 1)].0)
                }
                _ => None,
            };
            if let Some((at_s, after)) = s.change {
                match final_right(after) {
                    Some(t) if t >= at_s => followed.push(t - at_s),
                    _ => not_followed += 1,
                }
                continue;
            }
            if let Some(&(t, _)) = named.first() {
                first.push(t);
            }
            match final_right(s.truth) {
                Some(t) => {
                    stable.push(t);
                    stable_by_class[s.truth].push(t);
                }
                None => not_stable += 1,
            }
        }
        let mean = |v: &[f64]| (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64);
        let worst_surface = stable_by_class
            .iter()
            .enumerate()
            .filter_map(|(c, v)| mean(v).map(|m| (self.classes[c].clone(), m)))
            .max_by(|a, b| a.1.total_cmp(&b.1));
        Ok(SequentialRow {
            threshold: params.threshold(),
            decided,
            correct,
            time_to_first_decision_s: mean(&first),
            time_to_stable_correct_s: mean(&stable),
            worst_surface,
            not_stable,
            change_followed_s: mean(&followed),
            slowest_change_s: followed.iter().copied().reduce(f64::max),
            changes: followed.len() + not_followed,
            changes_not_followed: not_followed,
            flips_per_s: if duration_s > 0.0 {
                flips as f64 / duration_s
            } else {
                0.0
            },
        })
    }
}

/// The posterior's calibration over every window of `strokes` (the threshold plays no part).
fn calibration(
    strokes: &[Stroke],
    params: SequentialParams,
    classes: usize,
) -> Result<Calibration, RecognizeError> {
    let mut state = SequentialState::new(params, classes)?;
    let mut bins = [(0usize, 0.0f64, 0usize); RELIABILITY_BINS];
    let (mut brier, mut n) = (0.0, 0usize);
    for s in strokes {
        state.reset();
        for (t, scale, p) in &s.windows {
            let step = state.push_scaled(p, *scale)?;
            let truth = s.truth_at(*t);
            brier += state
                .posterior()
                .iter()
                .enumerate()
                .map(|(c, q)| (q - f64::from(u8::from(c == truth))).powi(2))
                .sum::<f64>();
            n += 1;
            let bin = ((step.probability * RELIABILITY_BINS as f64) as usize).min(RELIABILITY_BINS - 1);
            bins[bin].0 += 1;
            bins[bin].1 += step.probability;
            bins[bin].2 += usize::from(step.best == truth);
        }
    }
    let n = n.max(1);
    let bins: Vec<ReliabilityBin> = bins
        .iter()
        .enumerate()
        .filter(|(_, b)| b.0 > 0)
        .map(|(i, &(count, sum, right))| ReliabilityBin {
            lower: i as f64 / RELIABILITY_BINS as f64,
            upper: (i + 1) as f64 / RELIABILITY_BINS as f64,
            count,
            mean_probability: sum / count as f64,
            accuracy: right as f64 / count as f64,
        })
        .collect();
    let ece = bins
        .iter()
        .map(|b| b.count as f64 / n as f64 * (b.accuracy - b.mean_probability).abs())
        .sum();
    Ok(Calibration {
        brier: brier / n as f64,
        ece,
        bins,
    })
}
