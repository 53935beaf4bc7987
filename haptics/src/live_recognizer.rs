//! The live surface recognizer of the haptic thread: Nakano's features updated in O(1) per
//! sample and a decision every hop, (surface, probability) out.
//!
//! Two kinds of recognizer run live, both over Nakano's rubbing features (the second also over
//! those features followed by the spectrum of the window's heights, `nakano_spectrum`, read
//! from the same samples at each window's last one):
//! - **A SOM** names the surface of each window on its own, with the map's margin as its
//!   confidence (Nakano's recognizer; it names nodes, not a distribution over the surfaces).
//! - **A k-NN or SVM over windows** gives every surface's probability per window; the windows
//!   are accumulated from the first one on ([`SequentialState`]: a posterior over the surfaces,
//!   named only once it passes the threshold and held by hysteresis). Until then the answer is
//!   "undecided", with the most probable surface and its posterior beside it.
//!
//! Everything it needs is allocated in [`LiveRecognizer::new`] (the stream's rings, the
//! classifier's buffers, the posterior's ring); [`LiveRecognizer::push`] does arithmetic on them
//! only — no allocation, no lock, no I/O. The per-sample work is the stream's running sums; the
//! classifier runs once per hop, on the sample that completes a window. It decides on exactly
//! the windows the offline pipeline decides on ([`RecognizerFile::decisions`],
//! [`RecognizerFile::evaluate_sequential`]) with the same classifier arithmetic; the features
//! come from the streaming sums instead of the batch ones and agree with them to ~1e-9 relative.
//! A model trained with a mirrored end ([`NakanoWindowing::mirrored_end`]) decides each window
//! at its last sample instead: the recognizer keeps the stroke's latest samples and computes the
//! window's features with the batch's own [`EdgeWindow`] once per hop (about 800 samples of
//! arithmetic, in buffers made here), so those agree with the offline ones exactly.
//!
//! **Fused senses** ([`LiveRecognizer::fused`], fed by [`LiveRecognizer::push_with_vibration`]):
//! a k-NN or SVM over the vibration spectrum of its own windows, each decided at its last
//! sample, adds its windows' evidence to the same posterior, weighted by its reliability as
//! `recognize eval --sequential --fuse` weighs it offline, and in the same order (at a sample
//! that completes windows of both, the Nakano recognizer's first). The vibration is the rig's:
//! no supported device has an accelerometer, so `palpus run` fuses nothing.
//!
//! A running session feeds it from the recorder thread ([`SampleRecognizer`]), which sees every
//! sample of the loop in order: the decisions are those the tick would make, while the haptic
//! thread spends nothing on them (a decision costs about 50 µs, a twentieth of a tick).

mod vibration;

use crate::acquire;
use crate::error::HapticsError;
use crate::rt::{CHANNELS, HapticSample};
#[cfg(doc)]
use recognize::RecognizerFile;
use std::collections::VecDeque;
use std::sync::Arc;

use recognize::nakano::{EdgeWindow, TravelFriction};
use recognize::{
    CellScale, DEFAULT_MEMORY_S, FEATURES, FeatureSet, NakanoStream, NakanoWindowing, PlayedPath,
    RecognizerBody, RecognizerFile as Model, SPECTRUM_LEN, SequentialParams, SequentialState, Som,
    SpectrumScratch, WindowClassifier, WindowSpan, WindowSpectrumPlan,
};
use vibration::VibrationSense;

/// Cut-off of the reaction-force observer whose friction [`SampleRecognizer`] reads
/// ([`acquire::rubbing_signals`]: the rubbing controller's, Nakano's gains), rad/s.
pub const RUBBING_OBSERVER_CUTOFF_RADPS: f64 = crate::control::MotionGains::NAKANO.g_reac_radps;

/// The longest window vector decided live: Nakano's features and a spectrum
/// ([`FeatureSet::NakanoSpectrum`]).
const MAX_WINDOW_FEATURES: usize = FEATURES + SPECTRUM_LEN;

/// One window's feature vector, in fixed storage: its first `len` values.
#[derive(Debug, Clone, Copy)]
struct WindowVector {
    values: [f64; MAX_WINDOW_FEATURES],
    len: usize,
}

impl WindowVector {
    fn nakano(features: [f64; FEATURES]) -> Self {
        let mut values = [0.0; MAX_WINDOW_FEATURES];
        values[..FEATURES].copy_from_slice(&features);
        Self {
            values,
            len: FEATURES,
        }
    }

    fn as_slice(&self) -> &[f64] {
        &self.values[..self.len]
    }
}

/// One live decision.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LiveDecision {
    /// Index into the recognizer's classes of the surface named; `None` while undecided (a
    /// posterior below the threshold). A SOM always names one.
    pub label: Option<usize>,
    /// The most probable surface (the one named, when one is).
    pub best: usize,
    /// Confidence in `[0, 1]` of `best`: its posterior, or for a SOM half the map's
    /// inner-product margin over the best node of another surface.
    pub confidence: f64,
    /// First sample (counted from 0 since construction, [`LiveRecognizer::reset`] or a
    /// non-finite sample, each of which starts a stroke) of the window decided on.
    pub window_start: u64,
}

/// How the windows' features become a decision.
#[derive(Debug, Clone)]
enum Decider {
    /// Nakano's map, one window at a time.
    Som {
        som: Box<Som<usize>>,
        scratch: [f64; FEATURES],
    },
    /// Window probabilities accumulated into a posterior.
    Sequential {
        classifier: Box<WindowClassifier>,
        state: Box<SequentialState>,
        probabilities: Vec<f64>,
    },
}

/// A recognizer over Nakano's rubbing features, fed one sample at a time.
#[derive(Debug, Clone)]
pub struct LiveRecognizer {
    method: &'static str,
    decider: Decider,
    windowing: NakanoWindowing,
    classes: Vec<String>,
    stream: NakanoStream,
    /// Without a mirrored end, the stroke's latest paths through the play, enough for the
    /// windows the stream completes ([`StreamPaths`]).
    stream_paths: StreamPaths,
    /// With a mirrored end, the stroke's latest samples, which replace the stream.
    edge: Option<Edge>,
    /// For a model whose windows read friction over travel, that filter, run from the
    /// stroke's first sample as the offline windows run it from the capture's.
    friction: Option<TravelFriction>,
    /// Vibration recognizers fused into the posterior ([`LiveRecognizer::fused`]).
    senses: Vec<VibrationSense>,
    first_position_m: Option<f64>,
    /// The stroke's path through the play, which windows over travel span.
    played: PlayedPath,
    current: Option<LiveDecision>,
}

/// The paths through the play ([`PlayedPath`]) of a stroke's latest samples, in fixed storage:
/// as many as a window and the filters' lookahead after it, so that the window the stream
/// completes is still held when it is decided.
#[derive(Debug, Clone)]
struct StreamPaths {
    ring: Vec<f64>,
    /// Samples pushed since the stroke began.
    pushed: u64,
}

impl StreamPaths {
    fn new(windowing: &NakanoWindowing) -> Self {
        Self {
            ring: vec![0.0; windowing.window_samples + windowing.lookahead_samples() + 1],
            pushed: 0,
        }
    }

    fn push(&mut self, path_m: f64) {
        let room = self.ring.len() as u64;
        self.ring[(self.pushed % room) as usize] = path_m;
        self.pushed += 1;
    }

    /// The evidence ([`NakanoWindowing::evidence`]) of the stream's window (of fixed length)
    /// starting at sample `start`, as the offline windows weigh it. The path never decreases,
    /// so the window's path is its last value less its first: exactly 0 where the offline sum
    /// of its steps is, and the share of a window of fixed length asks no more than that.
    fn evidence(&self, start: u64, windowing: &NakanoWindowing) -> f64 {
        let (room, len) = (self.ring.len() as u64, windowing.window_samples as u64);
        let held = start + len <= self.pushed && self.pushed - start <= room;
        debug_assert!(held, "window {start} not held ({} pushed)", self.pushed);
        if !held {
            return 1.0;
        }
        let at = |k: u64| self.ring[(k % room) as usize];
        let span = WindowSpan {
            len: windowing.window_samples,
            travel_m: at(start + len - 1) - at(start),
        };
        windowing.evidence(span)
    }

    fn clear(&mut self) {
        self.pushed = 0;
    }
}

/// A stroke's latest samples, and the window computed at its edge from them.
#[derive(Debug)]
struct Edge {
    window: EdgeWindow,
    /// For [`FeatureSet::NakanoSpectrum`], the spectrum of the window's heights after its
    /// Nakano features.
    spectrum: Option<HeightSpectrum>,
    /// Position, height, friction and the path through the play ([`PlayedPath`]), oldest
    /// first; at most [`EdgeWindow::history_samples`].
    samples: [VecDeque<f64>; 4],
    /// Samples pushed since the stroke began.
    pushed: u64,
}

impl Clone for Edge {
    /// A copy with room for the whole history, as the original was made: a derived clone
    /// would have room only for the samples in it and allocate on the haptic thread.
    fn clone(&self) -> Self {
        let room = self.window.history_samples();
        Self {
            window: self.window.clone(),
            spectrum: self.spectrum.clone(),
            samples: std::array::from_fn(|k| Self::ring_copy(&self.samples[k], room)),
            pushed: self.pushed,
        }
    }
}

/// The spectrum of a window's heights ([`FeatureSet::NakanoSpectrum`]), read as the offline
/// vectors read it ([`NakanoWindowing::spectrum_features`]), in buffers made here.
#[derive(Debug, Clone)]
struct HeightSpectrum {
    /// Shared by copies: the DFT's plan is read-only, and copying it would plan it again.
    plan: Arc<WindowSpectrumPlan>,
    scratch: SpectrumScratch,
    cell_scale: CellScale,
}

impl Edge {
    fn new(windowing: &NakanoWindowing, spectrum: Option<CellScale>) -> Result<Self, HapticsError> {
        let window = EdgeWindow::new(windowing.filters, windowing.max_window_samples())?;
        let room = window.history_samples();
        let spectrum = match spectrum {
            Some(cell_scale) => {
                let plan = WindowSpectrumPlan::new(windowing.rate_hz, windowing.max_window_samples())?;
                Some(HeightSpectrum {
                    scratch: plan.scratch(),
                    plan: Arc::new(plan),
                    cell_scale,
                })
            }
            None => None,
        };
        Ok(Self {
            window,
            spectrum,
            samples: std::array::from_fn(|_| VecDeque::with_capacity(room)),
            pushed: 0,
        })
    }

    /// A copy of `samples` with room for the whole history.
    fn ring_copy(ring: &VecDeque<f64>, room: usize) -> VecDeque<f64> {
        let mut copy = VecDeque::with_capacity(room);
        copy.extend(ring.iter().copied());
        copy
    }

    fn clear(&mut self) {
        self.samples.iter_mut().for_each(VecDeque::clear);
        self.pushed = 0;
    }

    /// Adds a sample (position, height, friction, path through the play); returns the start
    /// and features of the window it completes when that is a decision window (Nakano's, then
    /// the spectrum of its heights when it reads one), and its evidence relative to a window
    /// of the nominal length ([`NakanoWindowing::evidence`]) (`x0`: the stroke's first
    /// position).
    fn push(
        &mut self,
        sample: [f64; 4],
        x0: f64,
        windowing: &NakanoWindowing,
    ) -> Result<Option<(u64, WindowVector, f64)>, HapticsError> {
        let room = self.window.history_samples();
        for (ring, v) in self.samples.iter_mut().zip(sample) {
            if ring.len() == room {
                ring.pop_front();
            }
            ring.push_back(v);
        }
        self.pushed += 1;
        let len = windowing.window_samples;
        let Some(start) = self.pushed.checked_sub(len as u64) else {
            return Ok(None);
        };
        let [x, z, f, path] = &mut self.samples;
        let travel_m = (x[x.len() - len] - x0).abs();
        if !windowing.is_decision_window(start, travel_m) {
            return Ok(None);
        }
        // The rings hold the stroke from the window's history on, as the offline windows read.
        let (x, z, f, path) = (
            &*x.make_contiguous(),
            &*z.make_contiguous(),
            &*f.make_contiguous(),
            &*path.make_contiguous(),
        );
        let span = windowing.window_span(path);
        let features =
            self.window
                .features_of((self.pushed - span.len as u64) as usize, span.len, x, z, f)?;
        let mut vector = WindowVector::nakano(features);
        if let Some(h) = &mut self.spectrum {
            // The window's own samples, as the offline vectors read them.
            let r = z.len() - span.len..z.len();
            let bands = windowing.spectrum_features(
                &h.plan,
                &z[r.clone()],
                &path[r],
                h.cell_scale,
                &mut h.scratch,
            )?;
            vector.values[FEATURES..].copy_from_slice(&bands);
            vector.len = MAX_WINDOW_FEATURES;
        }
        Ok(Some((start, vector, windowing.evidence(span))))
    }
}

impl LiveRecognizer {
    /// A recognizer for a loop running at `loop_hz`, from a loaded recognizer file: a SOM over
    /// Nakano's features, or a k-NN or SVM over windows of them with the default anytime
    /// settings ([`Model::sequential_params`] over [`DEFAULT_MEMORY_S`], threshold 0.9).
    pub fn new(model: &Model, loop_hz: f64) -> Result<Self, HapticsError> {
        let params = model
            .sequential_params(DEFAULT_MEMORY_S)
            .map(|b| b.build())
            .transpose()?;
        Self::build(model, loop_hz, params)
    }

    /// As [`LiveRecognizer::new`], a k-NN or SVM with the anytime settings `params` (its
    /// threshold, memory and weight); a SOM, which gives no posterior to threshold, is refused.
    pub fn with_params(model: &Model, loop_hz: f64, params: SequentialParams) -> Result<Self, HapticsError> {
        Self::build(model, loop_hz, Some(params))
    }

    fn build(model: &Model, loop_hz: f64, params: Option<SequentialParams>) -> Result<Self, HapticsError> {
        let refused = || HapticsError::LiveMethod {
            method: model.method(),
            features: model.body.feature_set().name(),
        };
        let (decider, windowing) = match (&model.body, params) {
            (RecognizerBody::Som { .. }, Some(_)) => {
                return Err(HapticsError::LiveThreshold {
                    method: model.method(),
                });
            }
            (RecognizerBody::Som { windowing, som }, None) => (
                Decider::Som {
                    som: Box::new(som.clone()),
                    scratch: [0.0; FEATURES],
                },
                *windowing,
            ),
            (RecognizerBody::KnnWindows { .. } | RecognizerBody::SvmWindows { .. }, Some(params))
                if model.body.feature_set() == FeatureSet::Nakano
                    || (model.body.feature_set() == FeatureSet::NakanoSpectrum
                        && model.sequential_windowing().is_some_and(|w| w.mirrored_end)) =>
            {
                let classifier = WindowClassifier::new(model)?;
                let windowing = *classifier.windowing();
                let classes = classifier.classes();
                (
                    Decider::Sequential {
                        classifier: Box::new(classifier),
                        state: Box::new(SequentialState::new(params, classes)?),
                        probabilities: vec![0.0; classes],
                    },
                    windowing,
                )
            }
            _ => return Err(refused()),
        };
        let height_spectrum = match &decider {
            Decider::Sequential { classifier, .. }
                if model.body.feature_set() == FeatureSet::NakanoSpectrum =>
            {
                Some(classifier.cell_scale())
            }
            _ => None,
        };
        // Written so that a NaN rate is refused too.
        let same_rate = (loop_hz - windowing.rate_hz).abs() <= 1e-9 * windowing.rate_hz;
        if !same_rate {
            return Err(HapticsError::LiveRate {
                loop_hz,
                model_hz: windowing.rate_hz,
            });
        }
        Ok(Self {
            method: model.method(),
            decider,
            windowing,
            classes: model.classes.clone(),
            stream_paths: StreamPaths::new(&windowing),
            stream: {
                let stream = NakanoStream::new(windowing.filters, windowing.window_samples)?;
                if windowing.mirrored_start {
                    stream.with_mirrored_start()
                } else {
                    stream
                }
            },
            edge: windowing
                .mirrored_end
                .then(|| Edge::new(&windowing, height_spectrum))
                .transpose()?,
            friction: windowing
                .friction_over_travel
                .map(|travel| travel.filter(Some(RUBBING_OBSERVER_CUTOFF_RADPS), loop_hz))
                .transpose()?,
            senses: Vec::new(),
            first_position_m: None,
            played: PlayedPath::new(),
            current: None,
        })
    }

    /// A k-NN or SVM over Nakano's windows (`model`) with the evidence of vibration
    /// recognizers (`others`: k-NNs or SVMs over `--features vibration` windows, each decided
    /// at its last sample) fused into its posterior, as `recognize eval --sequential --fuse`
    /// fuses them offline: every recognizer's windows in the order they are decided (the
    /// Nakano recognizer's first at the same sample), each weighing its share of the fusion
    /// ([`Model::fusion_members`]). `params` are the fusion's
    /// ([`Model::fused_sequential_params`], with a threshold). Fed by
    /// [`LiveRecognizer::push_with_vibration`].
    pub fn fused(
        model: &Model,
        others: &[&Model],
        loop_hz: f64,
        params: SequentialParams,
    ) -> Result<Self, HapticsError> {
        let members = model.fusion_members(others)?;
        let mut live = Self::build(model, loop_hz, Some(params))?;
        for (index, (other, member)) in others.iter().zip(&members[1..]).enumerate() {
            let factor = member.weight / members[0].weight;
            live.senses
                .push(VibrationSense::new(other, index + 1, loop_hz, factor)?);
        }
        Ok(live)
    }

    /// Feeds one tick: the tip's position along the rubbing direction and its height, m, and
    /// the friction (the RFOB's reaction force along x), N. Returns the new decision when this
    /// sample completes a decision window, `None` otherwise (the previous one stands, see
    /// [`LiveRecognizer::current`]).
    ///
    /// A non-finite sample is an error: it would poison the stream's running sums for good, so
    /// the stroke starts afresh from the next sample (a new window, the start travel counted
    /// again, the posterior uniform) while the last decision stands until a new one is made.
    pub fn push(
        &mut self,
        position_m: f64,
        height_m: f64,
        friction_n: f64,
    ) -> Result<Option<LiveDecision>, HapticsError> {
        if !self.senses.is_empty() {
            return Err(HapticsError::VibrationNeeded {
                senses: self.senses.len(),
            });
        }
        self.push_sample(position_m, height_m, friction_n, None)
    }

    /// [`LiveRecognizer::push`] for a recognizer with vibration senses fused
    /// ([`LiveRecognizer::fused`]): the same sample's vibration too, m/s² (the accelerometer's
    /// magnitude or its single axis, as the vibration recognizers were trained on). Without
    /// senses the vibration is not used. A non-finite vibration starts the stroke afresh, as a
    /// non-finite position does. A window one sense cannot read (slid past its spectrum's
    /// bands) is an error too, but every other sense still takes the sample: the error comes
    /// after them, and a decision one of them made on it is [`LiveRecognizer::current`].
    pub fn push_with_vibration(
        &mut self,
        position_m: f64,
        height_m: f64,
        friction_n: f64,
        vibration_mps2: f64,
    ) -> Result<Option<LiveDecision>, HapticsError> {
        if !vibration_mps2.is_finite() {
            self.restart_stroke();
            return Err(HapticsError::NotFiniteVibration { vibration_mps2 });
        }
        self.push_sample(position_m, height_m, friction_n, Some(vibration_mps2))
    }

    /// The Nakano recognizer's window, then each sense's, that this sample completes.
    fn push_sample(
        &mut self,
        position_m: f64,
        height_m: f64,
        friction_n: f64,
        vibration_mps2: Option<f64>,
    ) -> Result<Option<LiveDecision>, HapticsError> {
        if !(position_m.is_finite() && height_m.is_finite() && friction_n.is_finite()) {
            self.restart_stroke();
            return Err(HapticsError::NotFiniteSample {
                position_m,
                height_m,
                friction_n,
            });
        }
        let x0 = *self.first_position_m.get_or_insert(position_m);
        let path_m = self.played.push(position_m);
        let friction_n = match &mut self.friction {
            Some(filter) => filter.push(position_m, friction_n),
            None => friction_n,
        };
        // A window of one sense that cannot be read must not keep this sample from the others:
        // each sense is fed every sample, and the first error is returned once all were.
        let mut failed = None;
        let window = match &mut self.edge {
            Some(edge) => edge
                .push([position_m, height_m, friction_n, path_m], x0, &self.windowing)
                .unwrap_or_else(|e| {
                    failed = Some(e);
                    None
                }),
            None => {
                self.stream_paths.push(path_m);
                self.stream
                    .push(position_m, height_m, friction_n)
                    .filter(|w| {
                        let travel_m = (w.start_position_m - x0).abs();
                        self.windowing.is_decision_window(w.start, travel_m)
                    })
                    .map(|w| {
                        // A SOM decides each window alone, and weighs none.
                        let evidence = match self.decider {
                            Decider::Som { .. } => 1.0,
                            Decider::Sequential { .. } => {
                                self.stream_paths.evidence(w.start, &self.windowing)
                            }
                        };
                        (w.start, WindowVector::nakano(w.features), evidence)
                    })
            }
        };
        let mut decided = None;
        if let Some((window_start, features, evidence_scale)) = window {
            match self.decide(window_start, features.as_slice(), evidence_scale) {
                Ok(d) => {
                    decided = Some(d);
                    self.current = decided;
                }
                Err(e) => failed = failed.or(Some(e)),
            }
        }
        if let (Some(v), Decider::Sequential { state, .. }) = (vibration_mps2, &mut self.decider) {
            for sense in &mut self.senses {
                let step = match sense.push(position_m, path_m, v, x0) {
                    Ok(Some(w)) => state
                        .push_window(w.probabilities, w.scale, w.share)
                        .map(|step| (step, w.start))
                        .map_err(HapticsError::from),
                    Ok(None) => continue,
                    Err(e) => Err(e),
                };
                match step {
                    Ok((step, window_start)) => {
                        decided = Some(LiveDecision {
                            label: step.decided,
                            best: step.best,
                            confidence: step.probability,
                            window_start,
                        });
                        self.current = decided;
                    }
                    Err(e) => failed = failed.or(Some(e)),
                }
            }
        }
        match failed {
            Some(e) => Err(e),
            None => Ok(decided),
        }
    }

    /// The decision on one window of Nakano's features.
    fn decide(
        &mut self,
        window_start: u64,
        features: &[f64],
        evidence_scale: f64,
    ) -> Result<LiveDecision, HapticsError> {
        let decision = match &mut self.decider {
            Decider::Som { som, scratch } => {
                let d = som.decide_into(features, scratch)?;
                let label = som.node_labels().get(d.node).copied().unwrap_or(0);
                LiveDecision {
                    label: Some(label),
                    best: label,
                    confidence: d.confidence,
                    window_start,
                }
            }
            Decider::Sequential {
                classifier,
                state,
                probabilities,
            } => {
                classifier.probabilities_into(features, probabilities)?;
                let step = state.push_scaled(probabilities, evidence_scale)?;
                LiveDecision {
                    label: step.decided,
                    best: step.best,
                    confidence: step.probability,
                    window_start,
                }
            }
        };
        Ok(decision)
    }

    /// A new stroke from the next sample, the last decision kept.
    fn restart_stroke(&mut self) {
        self.stream.reset();
        self.stream_paths.clear();
        if let Some(edge) = &mut self.edge {
            edge.clear();
        }
        if let Some(filter) = &mut self.friction {
            filter.reset();
        }
        self.senses.iter_mut().for_each(VibrationSense::clear);
        self.first_position_m = None;
        self.played.reset();
        if let Decider::Sequential { state, .. } = &mut self.decider {
            state.reset();
        }
    }

    /// Vibration recognizers fused into the posterior.
    pub fn vibration_senses(&self) -> usize {
        self.senses.len()
    }

    /// The latest decision, if any since the last reset.
    pub fn current(&self) -> Option<LiveDecision> {
        self.current
    }

    /// The posterior over the surfaces after the stroke's windows so far (uniform before the
    /// first), for a k-NN or SVM; `None` for a SOM.
    pub fn posterior(&self) -> Option<&[f64]> {
        match &self.decider {
            Decider::Sequential { state, .. } => Some(state.posterior()),
            Decider::Som { .. } => None,
        }
    }

    /// The anytime settings of a k-NN or SVM; `None` for a SOM.
    pub fn sequential_params(&self) -> Option<&SequentialParams> {
        match &self.decider {
            Decider::Sequential { state, .. } => Some(state.params()),
            Decider::Som { .. } => None,
        }
    }

    /// Forgets the stroke (tool lifted): the next sample starts a new one. No allocation.
    pub fn reset(&mut self) {
        self.restart_stroke();
        self.current = None;
    }

    /// The recognizer's method: `som`, `knn` or `svm`.
    pub fn method(&self) -> &'static str {
        self.method
    }

    /// The features its windows are decided on: `nakano`, or `nakano_spectrum` when its edge
    /// reads the heights' spectrum too.
    pub fn features(&self) -> FeatureSet {
        if self.edge.as_ref().is_some_and(|e| e.spectrum.is_some()) {
            FeatureSet::NakanoSpectrum
        } else {
            FeatureSet::Nakano
        }
    }

    /// Class names; [`LiveDecision::label`] indexes them.
    pub fn classes(&self) -> &[String] {
        &self.classes
    }

    /// The windows it decides on.
    pub fn windowing(&self) -> &NakanoWindowing {
        &self.windowing
    }
}

/// Channels [`SampleRecognizer`] writes into every sample, after the controller's eight.
pub mod channel {
    /// Class index + 1 of the surface named; 0 before the stroke's first decision and while
    /// undecided.
    pub const LABEL: usize = 8;
    /// Confidence of the latest decision's most probable surface, `[0, 1]` (0 before the
    /// first).
    pub const CONFIDENCE: usize = 9;
    /// Decisions made since the stroke began: a sample where it steps carries a new decision.
    pub const DECISIONS: usize = 10;
    /// Class index + 1 of the most probable surface, named or not; 0 before the first
    /// decision.
    pub const BEST: usize = 11;
}

/// What a sample's recognizer channels say about the latest decision.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChannelDecision {
    /// The surface named; `None` while undecided.
    pub label: Option<usize>,
    /// The most probable surface.
    pub best: usize,
    /// Its confidence, `[0, 1]`.
    pub confidence: f64,
}

/// The decision a sample's recognizer channels carry, or `None` before the stroke's first.
pub fn decision_in(channels: &[f64; CHANNELS]) -> Option<ChannelDecision> {
    let index = |v: f64| (v >= 1.0 && v.is_finite()).then_some((v - 1.0) as usize);
    let best = index(channels[channel::BEST])?;
    Some(ChannelDecision {
        label: index(channels[channel::LABEL]),
        best,
        confidence: channels[channel::CONFIDENCE],
    })
}

/// The live recognizer over a loop's samples, run where the samples arrive off the haptic
/// thread (the recorder's [`crate::recorder::annotate_then`]), so a decision never costs the
/// 1 kHz tick anything. Each rubbing sample (position, height and the RFOB's friction, as a
/// capture records them: [`acquire::rubbing_signals`]) is pushed into the recognizer in loop
/// order, and the latest decision is written into [`channel`]s of the same sample, so it
/// reaches the capture, the report and the UI beside the force it was decided with. A stroke
/// (a run of rubbing-phase samples) starts the recognizer afresh, as a capture starts its
/// windows afresh. The samples are the loop's, in order, so the decisions are the same as if
/// they had been made in the tick; only when they show on a screen is later, by the ring's
/// delay (a few milliseconds).
///
/// Nothing here allocates, locks, logs or does I/O. A non-finite sample gets
/// [`crate::safety::flag::RECOGNIZER_INPUT_NOT_FINITE`] and restarts the recognizer's stroke
/// from the next sample; a window the recognizer cannot read (a spectrum slid past its bands)
/// gets [`crate::safety::flag::RECOGNIZER_WINDOW_UNREAD`] and adds nothing. Either way the
/// last decision stands until a new one.
#[derive(Debug, Clone)]
pub struct SampleRecognizer {
    live: LiveRecognizer,
    rubbing: bool,
    decisions: u64,
}

impl SampleRecognizer {
    pub fn new(live: LiveRecognizer) -> Self {
        Self {
            live,
            rubbing: false,
            decisions: 0,
        }
    }

    /// Pushes `sample` (the next of the loop's, in order) and writes the latest decision into
    /// its channels.
    pub fn annotate(&mut self, sample: &mut HapticSample) {
        match acquire::rubbing_signals(&sample.state, &sample.channels) {
            Some([x, z, f]) => {
                if !self.rubbing {
                    self.live.reset();
                    self.rubbing = true;
                    self.decisions = 0;
                }
                match self.live.push(x, z, f) {
                    Ok(Some(_)) => self.decisions += 1,
                    Ok(None) => {}
                    Err(HapticsError::NotFiniteSample { .. }) => {
                        sample.flags |= crate::safety::flag::RECOGNIZER_INPUT_NOT_FINITE;
                    }
                    Err(_) => sample.flags |= crate::safety::flag::RECOGNIZER_WINDOW_UNREAD,
                }
            }
            None => self.rubbing = false,
        }
        let current = self.live.current();
        let out = &mut sample.channels;
        out[channel::LABEL] = current.and_then(|d| d.label).map_or(0.0, |l| l as f64 + 1.0);
        out[channel::BEST] = current.map_or(0.0, |d| d.best as f64 + 1.0);
        out[channel::CONFIDENCE] = current.map_or(0.0, |d| d.confidence);
        out[channel::DECISIONS] = self.decisions as f64;
    }
}
