//! Anytime decisions on labelled captures: a k-NN's or SVM's window probabilities accumulated
//! from contact on ([`crate::sequential`]), scored for each threshold by how often a named
//! surface is right, how soon one is named, and how well the posterior is calibrated.
//!
//! **Fusing what the tool feels.** Several recognizers over the same surfaces (one over
//! Nakano's friction and roughness, one over the vibration spectrum) can feed one posterior:
//! every recognizer's windows are taken in the order they are decided, each raised to its own
//! weight, so a sense that speaks sooner is heard sooner. Where every recognizer's weight was
//! fitted on recordings held out of its training ([`RecognizerFile::fit_posterior_weight`]),
//! each keeps its own: the fit measured how much its windows say. Otherwise a recognizer's
//! weight is its own (`hop / window`, each sample counted once, or its fitted weight) times its
//! measured reliability relative to the most reliable one's, after Sinapov et al.'s
//! reliability-weighted fusion (IEEE T-RO 2011, Sec. IV-C): the reliability is its
//! cross-validated accuracy per window (recorded when it was trained, whole runs or trials held
//! out) less chance, `(a − 1/K) / (1 − 1/K)` for `K` surfaces; a recognizer no better than a
//! guess is refused, as it would add nothing. The most reliable recognizer weighs as it would
//! alone; a less reliable one less, so that where the two disagree the more reliable wins. Multiplying the two is right only as far as they err
//! independently (friction and vibration are different sensors, but the same surface drives
//! both), so the calibration of the fused posterior is reported beside its accuracy; two
//! recognizers over the same features would count one piece of evidence twice, and are
//! refused.

use std::borrow::Borrow;

use serde::Serialize;

use super::LabelledCapture;
use super::file::RecognizerFile;
use super::kept::change_sample;
use super::labelled::{class_index, class_named};
use crate::RecognizeError;
use crate::eval::{DecisionTiming, NamedDecision, stable_right_from};
use crate::features::{FeatureSet, NakanoWindowing, WindowlessCapture};
use crate::sequential::{SequentialParams, SequentialParamsBuilder, SequentialState};
use crate::{DataError, InputError, SettingError};

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
    /// The same decisions in travel, how much of the surface each took: the mean over those
    /// captures of the tool's path from contact to that decision, read through the play
    /// ([`crate::PlayedPath`]), m; and the surface with the longest such mean, and that mean,
    /// m. `None` where a capture has no position column.
    pub travel_to_stable_correct_m: Option<f64>,
    pub worst_surface_travel: Option<(String, f64)>,
    /// The same per surface, in the recognizer's order.
    pub surfaces: Vec<SurfaceWait>,
    /// Captures (of one surface) that do not end named right.
    pub not_stable: usize,
    /// Of the captures that slide onto another surface part-way: the mean time from the change
    /// to the named decision that starts the final run of right ones, s (over those that end
    /// named right), the longest, how many such captures there are, and how many of them do
    /// not end named right. The single-surface times above leave these captures out.
    pub change_followed_s: Option<f64>,
    pub slowest_change_s: Option<f64>,
    /// The same two in travel since the change, m.
    pub change_followed_m: Option<f64>,
    pub slowest_change_m: Option<f64>,
    pub changes: usize,
    pub changes_not_followed: usize,
    /// Changes of named surface (undecided stretches not counted) per second of stroke.
    pub flips_per_s: f64,
    /// The posterior's calibration over every window at this threshold (the change test runs
    /// only while a surface is named, so the posterior depends on the threshold a little).
    pub calibration: Calibration,
}

/// One surface's strokes of that surface alone, at one threshold.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SurfaceWait {
    pub surface: String,
    /// Its strokes, and how many of them end named right.
    pub strokes: usize,
    pub stable: usize,
    /// Over those that end named right, the mean time from contact to the decision that starts
    /// the final run of right ones, s, and the mean path by then, m (`None` where a capture has
    /// no position column).
    pub stable_right_s: Option<f64>,
    pub stable_right_m: Option<f64>,
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
/// over every window of every capture.
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
    /// The settings, with the first row's threshold (each row has its own).
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
    /// Windows short of their travel ([`NakanoWindowing::short_of_travel`]): over travel,
    /// rubbed slower than the slowest speed their windows read, which count for the travel
    /// they covered; of either windowing, a tool at rest, which counts not at all.
    pub short_of_travel: usize,
    /// One per threshold, in the order given.
    pub rows: Vec<SequentialRow>,
    /// The first row's calibration (with no thresholds, at the default one).
    pub calibration: Calibration,
    /// For a fused evaluation, each recognizer fused (the first is the one the window
    /// settings above describe) and the weight of its evidence; empty for one recognizer.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub fused: Vec<FusionMember>,
}

/// One recognizer of a fused anytime evaluation
/// ([`RecognizerFile::evaluate_sequential_fused`]) and the weight of its evidence.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FusionMember {
    /// Its method and features.
    pub method: &'static str,
    pub features: &'static str,
    /// Its windows' length and hop, s.
    pub window_s: f64,
    pub hop_s: f64,
    /// Its accuracy per window under cross-validation when it was trained.
    pub accuracy: f64,
    /// That accuracy's share above chance, `(a − 1/K) / (1 − 1/K)`.
    pub reliability: f64,
    /// The exponent its windows' probabilities are raised to: when every recognizer fused
    /// has a weight fitted on held-out recordings ([`RecognizerFile::posterior_weight`]), its
    /// own; else its weight alone ([`RecognizerFile::window_weight`]) times its reliability over
    /// the most reliable recognizer's.
    pub weight: f64,
    /// Whether its weight alone was fitted on held-out recordings.
    pub fitted: bool,
}

/// One capture's windows: truth, and each window's time from contact and probabilities.
pub(super) struct Stroke {
    pub(super) truth: usize,
    /// When the stroke slides onto another surface, and which.
    pub(super) change: Option<(f64, usize)>,
    /// The tool's path from contact to that change, read through the play, m (`None` without
    /// a position column).
    pub(super) change_travel_m: Option<f64>,
    pub(super) duration_s: f64,
    /// Its windows of every recognizer, in the order they are decided.
    pub(super) windows: Vec<StrokeWindow>,
}

/// One window of a stroke, as the posterior takes it.
pub(super) struct StrokeWindow {
    pub(super) at_s: f64,
    /// The tool's path from contact to the sample it is decided at, read through the play, m
    /// (`None` without a position column).
    pub(super) travel_m: Option<f64>,
    /// Its evidence scale ([`NakanoWindowing::evidence_scale`]) times its recognizer's weight
    /// relative to the first recognizer's.
    pub(super) scale: f64,
    /// Its share of the memory: its evidence scale alone.
    pub(super) share: f64,
    pub(super) probabilities: Vec<f64>,
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

/// `hop / window` of `windowing`, at most 1.
fn hop_weight(windowing: &NakanoWindowing) -> f64 {
    (windowing.hop_samples as f64 / windowing.rate_hz / windowing.window_s()).min(1.0)
}

/// The least share of the posterior's memory a window of `windowing` takes: its longest
/// window's evidence scale (1 for windows of fixed length).
fn smallest_share(windowing: &NakanoWindowing) -> f64 {
    windowing.evidence_scale(windowing.max_window_samples()).min(1.0)
}

impl RecognizerFile {
    /// The settings [`RecognizerFile::evaluate_sequential`] starts from for this recognizer:
    /// each window weighs [`RecognizerFile::window_weight`] (fitted on held-out recordings, or
    /// `hop / window`, every sample counted once), and the evidence of
    /// the last `memory_s` counts; `None` for a recognizer without window probabilities.
    pub fn sequential_params(&self, memory_s: f64) -> Option<SequentialParamsBuilder> {
        let w = self.window_probability_windowing()?;
        let hop_s = w.hop_samples as f64 / w.rate_hz;
        let memory = (memory_s / hop_s).round().max(1.0) as usize;
        Some(
            SequentialParams::builder()
                .weight(self.weight_of(w))
                .memory(memory)
                .smallest_share(smallest_share(w)),
        )
    }

    /// `hop / window` of a k-NN's or SVM's windows, at most 1: the weight that counts every
    /// sample once.
    pub fn hop_weight(&self) -> Option<f64> {
        self.window_probability_windowing().map(hop_weight)
    }

    /// The exponent a window of whole evidence is raised to in the posterior: the weight
    /// fitted on held-out recordings when training could fit one
    /// ([`RecognizerFile::posterior_weight`]), else [`RecognizerFile::hop_weight`].
    pub fn window_weight(&self) -> Option<f64> {
        self.window_probability_windowing().map(|w| self.weight_of(w))
    }

    /// [`RecognizerFile::window_weight`] of this recognizer's windows, `windowing` (its own,
    /// or the same from contact on).
    fn weight_of(&self, windowing: &NakanoWindowing) -> f64 {
        self.posterior_weight
            .as_ref()
            .map_or(hop_weight(windowing), |p| p.weight)
    }

    /// The windows anytime decisions are made on: a k-NN's or SVM's own, from contact on (the
    /// start travel set to 0, and the stroke's start mirrored so that the first window starts
    /// at its first sample); `None` for a recognizer without window probabilities.
    pub fn sequential_windowing(&self) -> Option<NakanoWindowing> {
        self.window_probability_windowing().map(|own| own.from_contact())
    }

    /// [`RecognizerFile::sequential_windowing`], or the error saying this recognizer gives no
    /// window probabilities.
    pub(super) fn windowing_with_probabilities(&self) -> Result<NakanoWindowing, RecognizeError> {
        self.sequential_windowing()
            .ok_or(RecognizeError::Setting(SettingError::NoWindowProbabilities {
                method: self.method(),
                features: self.feature_set().name(),
            }))
    }

    /// A k-NN's or SVM's accuracy per window under the cross-validation by run or trial
    /// recorded when it was trained (an SVM's at its C; a k-NN's with its vote calibration);
    /// `None` for any other recognizer, or one trained on captures that could not be
    /// cross-validated (a single run or trial).
    fn cross_validated_window_accuracy(&self) -> Option<f64> {
        match &self.body {
            super::RecognizerBody::SvmWindows { c_search, .. } => {
                c_search.as_ref().and_then(|s| s.accuracy())
            }
            super::RecognizerBody::KnnWindows { calibration, .. } => calibration.map(|c| c.accuracy),
            _ => None,
        }
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
        self.evaluate_sequential_fused(&[], captures, thresholds, params)
    }

    /// The recognizers fused with `others` over time and their weights
    /// ([`FusionMember::weight`]): each must give window probabilities over the same surfaces,
    /// in the same order, and carry a cross-validated accuracy above chance.
    pub fn fusion_members(&self, others: &[&RecognizerFile]) -> Result<Vec<FusionMember>, RecognizeError> {
        let k = self.classes.len() as f64;
        let mut members = Vec::with_capacity(others.len() + 1);
        for (index, model) in std::iter::once(self).chain(others.iter().copied()).enumerate() {
            let windowing = model.windowing_with_probabilities()?;
            if model.classes != self.classes {
                return Err(RecognizeError::Input(InputError::FusionSurfaces {
                    index,
                    expected: self.classes.clone(),
                    got: model.classes.clone(),
                }));
            }
            let accuracy = model
                .cross_validated_window_accuracy()
                .ok_or(RecognizeError::Input(InputError::NoReliability {
                    index,
                    method: model.method(),
                    features: model.feature_set().name(),
                }))?;
            let reliability = (accuracy - 1.0 / k) / (1.0 - 1.0 / k);
            if reliability.is_nan() || reliability <= 0.0 {
                return Err(RecognizeError::Setting(SettingError::Unreliable {
                    index,
                    accuracy,
                }));
            }
            members.push(FusionMember {
                method: model.method(),
                features: model.feature_set().name(),
                window_s: windowing.window_s(),
                hop_s: windowing.hop_samples as f64 / windowing.rate_hz,
                accuracy,
                reliability,
                weight: model.weight_of(&windowing),
                fitted: model.posterior_weight.is_some(),
            });
        }
        // The product assumes each recognizer brings its own evidence: two over the same
        // features (or `both` or `nakano_spectrum` beside one of its parts) would count it
        // twice.
        let sets: Vec<FeatureSet> = std::iter::once(self)
            .chain(others.iter().copied())
            .map(RecognizerFile::feature_set)
            .collect();
        let overlap = |a: FeatureSet, b: FeatureSet| {
            use FeatureSet::{Both, Nakano, NakanoSpectrum};
            a == b
                || a == Both
                || b == Both
                || matches!((a, b), (Nakano, NakanoSpectrum) | (NakanoSpectrum, Nakano))
        };
        for (j, &b) in sets.iter().enumerate() {
            if let Some(i) = sets[..j].iter().position(|&a| overlap(a, b)) {
                return Err(RecognizeError::Setting(SettingError::FusionOverlap {
                    first: i,
                    second: j,
                    features: [sets[i].name(), b.name()],
                }));
            }
        }
        // A fitted weight has measured how much a recognizer's windows say, its reliability
        // included: scaling it by the reliability again would count that twice.
        if !members.iter().all(|m| m.fitted) {
            let most = members.iter().map(|m| m.reliability).fold(0.0, f64::max);
            for m in &mut members {
                m.weight *= m.reliability / most;
            }
        }
        Ok(members)
    }

    /// [`RecognizerFile::sequential_params`] for this recognizer fused with `others`: the
    /// first recognizer's weight ([`FusionMember::weight`]), and the memory holding the last
    /// `memory_s` of every recognizer's windows.
    pub fn fused_sequential_params(
        &self,
        others: &[&RecognizerFile],
        memory_s: f64,
    ) -> Result<SequentialParamsBuilder, RecognizeError> {
        let members = self.fusion_members(others)?;
        let memory = members
            .iter()
            .map(|m| (memory_s / m.hop_s).round().max(1.0) as usize)
            .sum();
        let mut smallest = 1.0f64;
        for model in std::iter::once(self).chain(others.iter().copied()) {
            smallest = smallest.min(smallest_share(&model.windowing_with_probabilities()?));
        }
        Ok(SequentialParams::builder()
            .weight(members[0].weight)
            .memory(memory)
            .smallest_share(smallest))
    }

    /// [`RecognizerFile::evaluate_sequential`] with the evidence of `others` fused in
    /// ([`RecognizerFile::fusion_members`]): every recognizer's windows, in the order they are
    /// decided, each window's weight scaled from `params`' (the first recognizer's, as
    /// [`RecognizerFile::fused_sequential_params`] sets it) to its recognizer's. With no
    /// others it is [`RecognizerFile::evaluate_sequential`], bit for bit.
    pub fn evaluate_sequential_fused<C: Borrow<LabelledCapture>>(
        &self,
        others: &[&RecognizerFile],
        captures: &[C],
        thresholds: &[f64],
        params: SequentialParamsBuilder,
    ) -> Result<SequentialEvaluation, RecognizeError> {
        let windowing = self.windowing_with_probabilities()?;
        let fused = if others.is_empty() {
            Vec::new()
        } else {
            self.fusion_members(others)?
        };
        // Each recognizer's windowing and the factor from the first one's weight to its own.
        let mut sources = vec![(self, windowing, 1.0)];
        for (model, member) in others.iter().zip(fused.iter().skip(1)) {
            let own = model.windowing_with_probabilities()?;
            sources.push((model, own, member.weight / fused[0].weight));
        }
        let mut strokes = Vec::with_capacity(captures.len());
        let mut short_of_travel = 0;
        for c in captures {
            strokes.push(self.stroke(&sources, c.borrow(), &mut short_of_travel)?);
        }
        let steps = strokes.iter().map(|s| s.windows.len()).sum();
        if steps == 0 {
            let captures = captures
                .iter()
                .map(|c| WindowlessCapture::of(c.borrow(), &windowing, "decision"))
                .collect();
            return Err(RecognizeError::Data(DataError::NoDecisions { captures }));
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
        let calibration = match rows.first() {
            Some(row) => row.calibration.clone(),
            None => self.sequential_row(&strokes, base)?.calibration,
        };
        Ok(SequentialEvaluation {
            params: base,
            window_s: windowing.window_s(),
            hop_s: windowing.hop_samples as f64 / windowing.rate_hz,
            window_m: windowing.travel.map(|t| t.window_m),
            friction_cutoff_m: windowing.friction_over_travel.map(|f| f.cutoff_m),
            decided_after_s: windowing.lookahead_samples() as f64 / windowing.rate_hz,
            captures: captures.len(),
            steps,
            short_of_travel,
            rows,
            calibration,
            fused,
        })
    }

    /// One capture's windows from every recognizer of `sources` (each with its windowing and
    /// the factor from the first recognizer's weight to its own), in the order they are
    /// decided, labelled against this recognizer's surfaces; adds the windows short of their
    /// travel to `short_of_travel`.
    pub(super) fn stroke(
        &self,
        sources: &[(&RecognizerFile, NakanoWindowing, f64)],
        c: &LabelledCapture,
        short_of_travel: &mut usize,
    ) -> Result<Stroke, RecognizeError> {
        let rate_hz = c.capture.metadata().rate_hz();
        let path = c.played_path();
        let travel_at = |sample: usize| path.at(sample);
        let mut windows = Vec::new();
        for (model, windowing, factor) in sources {
            windows.extend(
                model
                    .window_probabilities(c, Some(windowing))?
                    .unwrap_or_default()
                    .into_iter()
                    .inspect(|w| *short_of_travel += usize::from(w.short_of_travel))
                    .map(|w| StrokeWindow {
                        at_s: w.decision.decided_at as f64 / rate_hz,
                        travel_m: travel_at(w.decision.decided_at),
                        scale: w.evidence_scale * factor,
                        share: w.evidence_scale,
                        probabilities: w.probabilities,
                    }),
            );
        }
        // Stable: windows decided at the same sample keep the recognizers' order.
        windows.sort_by(|a, b| a.at_s.total_cmp(&b.at_s));
        let change = match &c.change {
            Some(ch) => Some((ch.at_s, class_named(&self.classes, &ch.after, c)?)),
            None => None,
        };
        let change_travel_m = change.and_then(|(at_s, _)| travel_at(change_sample(at_s, rate_hz)));
        Ok(Stroke {
            truth: class_index(&self.classes, c)?,
            change,
            change_travel_m,
            duration_s: c.samples() as f64 / rate_hz,
            windows,
        })
    }

    pub(super) fn sequential_row(
        &self,
        strokes: &[Stroke],
        params: SequentialParams,
    ) -> Result<SequentialRow, RecognizeError> {
        let classes = self.classes.len();
        let mut state = SequentialState::new(params, classes)?;
        let (mut decided, mut correct, mut flips, mut not_stable) = (0, 0, 0, 0);
        let (mut first, mut stable, mut stable_m) = (Vec::new(), Vec::new(), Vec::new());
        let mut strokes_by_class = vec![0; classes];
        let mut stable_by_class: Vec<Vec<f64>> = vec![Vec::new(); classes];
        let mut stable_m_by_class: Vec<Vec<Option<f64>>> = vec![Vec::new(); classes];
        let mut duration_s = 0.0;
        let (mut followed, mut followed_m, mut not_followed) = (Vec::new(), Vec::new(), 0);
        let mut tally = CalibrationTally::default();
        for s in strokes {
            state.reset();
            duration_s += s.duration_s;
            // Each named decision: when, the path by then, and the surface named.
            let mut named: Vec<(f64, Option<f64>, usize)> = Vec::new();
            for w in &s.windows {
                let step = state.push_window(&w.probabilities, w.scale, w.share)?;
                tally.add(state.posterior(), step.best, step.probability, s.truth_at(w.at_s));
                if let Some(d) = step.decided {
                    named.push((w.at_s, w.travel_m, d));
                }
            }
            decided += named.len();
            correct += named.iter().filter(|(t, _, d)| *d == s.truth_at(*t)).count();
            flips += named.windows(2).filter(|w| w[0].2 != w[1].2).count();
            if let Some((at_s, after)) = s.change {
                // The named decision that starts the final run naming the surface slid onto.
                match stable_right_from(&named, |&(.., d)| d == after).map(|k| named[k]) {
                    Some((t, travel_m, _)) if t >= at_s => {
                        followed.push(t - at_s);
                        followed_m.push(travel_m.zip(s.change_travel_m).map(|(a, b)| a - b));
                    }
                    _ => not_followed += 1,
                }
                continue;
            }
            strokes_by_class[s.truth] += 1;
            let timing = DecisionTiming::of(
                &named
                    .iter()
                    .map(|&(time_s, travel_m, d)| NamedDecision {
                        time_s,
                        travel_m,
                        right: d == s.truth,
                    })
                    .collect::<Vec<_>>(),
            );
            first.extend(timing.first_named_after_s);
            match timing.stable_right_after_s {
                Some(t) => {
                    stable.push(t);
                    stable_m.push(timing.stable_right_after_m);
                    stable_by_class[s.truth].push(t);
                    stable_m_by_class[s.truth].push(timing.stable_right_after_m);
                }
                None => not_stable += 1,
            }
        }
        let mean = |v: &[f64]| (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64);
        // Travel is reported only where every capture it is taken over has it.
        let all = |v: &[Option<f64>]| v.iter().copied().collect::<Option<Vec<f64>>>();
        let surfaces: Vec<SurfaceWait> = (0..classes)
            .filter(|&c| strokes_by_class[c] > 0)
            .map(|c| SurfaceWait {
                surface: self.classes[c].clone(),
                strokes: strokes_by_class[c],
                stable: stable_by_class[c].len(),
                stable_right_s: mean(&stable_by_class[c]),
                stable_right_m: all(&stable_m_by_class[c]).and_then(|v| mean(&v)),
            })
            .collect();
        let worst = |of: fn(&SurfaceWait) -> Option<f64>| {
            surfaces
                .iter()
                .filter_map(|w| of(w).map(|v| (w.surface.clone(), v)))
                .max_by(|a, b| a.1.total_cmp(&b.1))
        };
        let worst_surface = worst(|w| w.stable_right_s);
        let worst_surface_travel = all(&stable_m).and(worst(|w| w.stable_right_m));
        let followed_m = all(&followed_m);
        Ok(SequentialRow {
            threshold: params.threshold(),
            decided,
            correct,
            time_to_first_decision_s: mean(&first),
            time_to_stable_correct_s: mean(&stable),
            worst_surface,
            travel_to_stable_correct_m: all(&stable_m).and_then(|v| mean(&v)),
            worst_surface_travel,
            surfaces,
            not_stable,
            change_followed_s: mean(&followed),
            slowest_change_s: followed.iter().copied().reduce(f64::max),
            change_followed_m: followed_m.as_deref().and_then(mean),
            slowest_change_m: followed_m.and_then(|v| v.into_iter().reduce(f64::max)),
            changes: followed.len() + not_followed,
            changes_not_followed: not_followed,
            flips_per_s: if duration_s > 0.0 {
                flips as f64 / duration_s
            } else {
                0.0
            },
            calibration: tally.calibration(),
        })
    }
}

/// The posterior's calibration, a window at a time.
#[derive(Default)]
struct CalibrationTally {
    /// Per bin of the top posterior: windows, their summed top posterior, and how many of them
    /// had the true surface on top.
    bins: [(usize, f64, usize); RELIABILITY_BINS],
    brier: f64,
    windows: usize,
}

impl CalibrationTally {
    /// One window's `posterior`, its most probable surface `best` and that surface's
    /// `probability`, when the surface under the tool is `truth`.
    fn add(&mut self, posterior: &[f64], best: usize, probability: f64, truth: usize) {
        self.brier += posterior
            .iter()
            .enumerate()
            .map(|(c, q)| (q - f64::from(u8::from(c == truth))).powi(2))
            .sum::<f64>();
        self.windows += 1;
        let bin = ((probability * RELIABILITY_BINS as f64) as usize).min(RELIABILITY_BINS - 1);
        let b = &mut self.bins[bin];
        b.0 += 1;
        b.1 += probability;
        b.2 += usize::from(best == truth);
    }

    fn calibration(&self) -> Calibration {
        let n = self.windows.max(1);
        let bins: Vec<ReliabilityBin> = self
            .bins
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
        Calibration {
            brier: self.brier / n as f64,
            ece,
            bins,
        }
    }
}
