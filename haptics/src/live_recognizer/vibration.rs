//! A vibration sense fused into the live posterior: a k-NN or SVM over each window's vibration
//! spectrum (`--features vibration`), fed one sample at a time.
//!
//! Its windows are placed as the offline ones are (Nakano's windows of its own windowing, from
//! contact on, each decided at its last sample) and read through the same function
//! ([`NakanoWindowing::spectrum_features`]), so each window's probabilities are the offline
//! ones to the bit. Everything is allocated when it is built: per sample it writes two ring
//! slots; per decision window it copies the window out of the rings, takes one DFT in its own
//! buffers and classifies.

use std::sync::Arc;

use recognize::{FeatureSet, NakanoWindowing, RecognizerFile as Model, WindowClassifier};
use recognize::{SpectrumScratch, WindowSpectrumPlan};

use crate::error::HapticsError;

/// The latest positions, paths through the play and vibration samples of a stroke, newest
/// last, in fixed storage.
#[derive(Debug, Clone)]
struct Rings {
    position_m: Vec<f64>,
    path_m: Vec<f64>,
    vibration_mps2: Vec<f64>,
    /// Where the next sample goes.
    head: usize,
    /// Samples pushed since the stroke began.
    pushed: u64,
}

impl Rings {
    fn new(room: usize) -> Self {
        Self {
            position_m: vec![0.0; room],
            path_m: vec![0.0; room],
            vibration_mps2: vec![0.0; room],
            head: 0,
            pushed: 0,
        }
    }

    fn room(&self) -> usize {
        self.position_m.len()
    }

    fn push(&mut self, position_m: f64, path_m: f64, vibration_mps2: f64) {
        self.position_m[self.head] = position_m;
        self.path_m[self.head] = path_m;
        self.vibration_mps2[self.head] = vibration_mps2;
        self.head = (self.head + 1) % self.room();
        self.pushed += 1;
    }

    /// The position `back` samples before the newest (0: the newest); `back` below the room
    /// and the samples pushed.
    fn position_back(&self, back: usize) -> f64 {
        let room = self.room();
        self.position_m[(self.head + room - 1 - back) % room]
    }

    /// Copies the paths and vibration samples held, oldest first, into `path_m` and
    /// `vibration_mps2` (each as long as the room); returns how many.
    fn copy_into(&self, path_m: &mut [f64], vibration_mps2: &mut [f64]) -> usize {
        let room = self.room();
        let held = (self.pushed.min(room as u64)) as usize;
        let first = (self.head + room - held) % room;
        for k in 0..held {
            let i = (first + k) % room;
            path_m[k] = self.path_m[i];
            vibration_mps2[k] = self.vibration_mps2[i];
        }
        held
    }

    fn clear(&mut self) {
        self.head = 0;
        self.pushed = 0;
    }
}

/// One of a sense's decision windows.
pub(super) struct SenseWindow<'a> {
    /// Its first sample, counted from the stroke's first.
    pub start: u64,
    /// Its class probabilities.
    pub probabilities: &'a [f64],
    /// Its evidence scale, relative to the Nakano recognizer's windows.
    pub scale: f64,
    /// Its share of the posterior's memory: its own evidence scale.
    pub share: f64,
}

/// A recognizer over the vibration spectrum of its own windows, and everything it works in.
#[derive(Debug, Clone)]
pub(super) struct VibrationSense {
    classifier: Box<WindowClassifier>,
    windowing: NakanoWindowing,
    /// Shared by copies: the DFT's plan is read-only, and copying it would plan it again.
    plan: Arc<WindowSpectrumPlan>,
    scratch: SpectrumScratch,
    rings: Rings,
    /// A window copied out of the rings.
    window_path_m: Vec<f64>,
    window_vibration_mps2: Vec<f64>,
    /// Its windows' weight relative to the Nakano recognizer's.
    factor: f64,
    probabilities: Vec<f64>,
}

impl VibrationSense {
    /// The sense of `model` (recognizer `index` of those fused), at `loop_hz`, whose windows
    /// weigh `factor` times the Nakano recognizer's.
    pub(super) fn new(model: &Model, index: usize, loop_hz: f64, factor: f64) -> Result<Self, HapticsError> {
        let refused = |reason| HapticsError::LiveFusion {
            index,
            method: model.method(),
            features: model.feature_set().name(),
            reason,
        };
        if model.feature_set() != FeatureSet::Vibration {
            return Err(refused(
                "only a recognizer over the vibration spectrum (`--features vibration`) is fused with the \
                 Nakano recognizer live",
            ));
        }
        let classifier = WindowClassifier::new(model)?;
        let windowing = *classifier.windowing();
        if !windowing.mirrored_end {
            return Err(refused(
                "its windows are decided after the filters' lookahead; live, a fused window must be decided at \
                 its last sample (train it with `--mirrored-end`)",
            ));
        }
        let same_rate = (loop_hz - windowing.rate_hz).abs() <= 1e-9 * windowing.rate_hz;
        if !same_rate {
            return Err(HapticsError::LiveRate {
                loop_hz,
                model_hz: windowing.rate_hz,
            });
        }
        let room = windowing.max_window_samples();
        let plan = WindowSpectrumPlan::new(windowing.rate_hz, room)?;
        let classes = classifier.classes();
        Ok(Self {
            scratch: plan.scratch(),
            plan: Arc::new(plan),
            classifier: Box::new(classifier),
            windowing,
            rings: Rings::new(room),
            window_path_m: vec![0.0; room],
            window_vibration_mps2: vec![0.0; room],
            factor,
            probabilities: vec![0.0; classes],
        })
    }

    /// Adds a sample: its position, the stroke's path through the play to it
    /// ([`recognize::PlayedPath`]) and its vibration (`x0`: the stroke's first position);
    /// returns the decision window it completes, if any.
    pub(super) fn push(
        &mut self,
        position_m: f64,
        path_m: f64,
        vibration_mps2: f64,
        x0: f64,
    ) -> Result<Option<SenseWindow<'_>>, HapticsError> {
        self.rings.push(position_m, path_m, vibration_mps2);
        let len = self.windowing.window_samples;
        let Some(start) = self.rings.pushed.checked_sub(len as u64) else {
            return Ok(None);
        };
        let travel_m = (self.rings.position_back(len - 1) - x0).abs();
        if !self.windowing.is_decision_window(start, travel_m) {
            return Ok(None);
        }
        let held = self
            .rings
            .copy_into(&mut self.window_path_m, &mut self.window_vibration_mps2);
        let span = self.windowing.window_span(&self.window_path_m[..held]);
        let r = held - span.len..held;
        let features = self.windowing.spectrum_features(
            &self.plan,
            &self.window_vibration_mps2[r.clone()],
            &self.window_path_m[r],
            self.classifier.cell_scale(),
            &mut self.scratch,
        )?;
        self.classifier
            .probabilities_into(&features, &mut self.probabilities)?;
        Ok(Some(SenseWindow {
            start,
            probabilities: &self.probabilities,
            scale: self.windowing.evidence(span) * self.factor,
            share: self.windowing.evidence(span),
        }))
    }

    /// Forgets the stroke.
    pub(super) fn clear(&mut self) {
        self.rings.clear();
    }
}
