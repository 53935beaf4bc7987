//! How a rubbing capture is cut into windows: the [`NakanoWindowing`] a SOM (or a classifier over
//! windows) trains and decides on, the windows it picks, and each window's feature vector.

use std::borrow::Cow;

use serde::{Deserialize, Serialize};

use super::FeatureSet;
use super::nakano::{self, FEATURES, FrictionOverTravel, NakanoConfig, NakanoSignals, PROTOCOL_SPEED_MPS};
use super::played_path::PlayedPath;
use super::spectral::{
    self, ACCEL_COLUMNS, BAND_HZ, CellScale, Histogram, SpectrogramPlan, VIBRATION_COLUMN,
};
use super::window_spectrum::{SPECTRUM_LEN, SpectrumScratch, WindowSpectrumPlan};
use crate::{InputError, SettingError};
use crate::{LabelledCapture, RecognizeError};
use capture::Capture;

/// Default decision window of a SOM recognizer, s (15 mm of travel at 5 mm/s).
pub const DECISION_WINDOW_S: f64 = 3.0;
/// Default training window of a SOM recognizer, s (5 mm of travel at 5 mm/s).
pub const TRAINING_WINDOW_S: f64 = 1.0;
/// Default time between a SOM recognizer's decisions, s.
pub const HOP_S: f64 = 0.1;

/// Windows over travel ([`NakanoWindowing::travel`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TravelWindows {
    /// Travel a decision window spans, m (path length).
    pub window_m: f64,
    /// Travel a training window spans, m, when not [`TravelWindows::window_m`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub training_window_m: Option<f64>,
    /// Most samples a window takes, however slowly the tip moves: where it spans less travel
    /// than asked.
    pub max_samples: usize,
    /// The fastest stroke whose windows' spectra are read, m/s: their bands over travel end
    /// at the Nyquist frequency at this speed ([`NakanoWindowing::reading_spectra_up_to`]).
    /// `None`: 0–200 Hz at the reference speed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fastest_speed_mps: Option<f64>,
}

/// How a rubbing stream is cut into the windows the map decides on.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NakanoWindowing {
    /// The two zero-phase moving averages.
    pub filters: NakanoConfig,
    /// Samples per decision window.
    pub window_samples: usize,
    /// Samples per window the map was trained on, when not [`NakanoWindowing::window_samples`]
    /// (see [`NakanoWindowing::with_training_window_s`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub training_window_samples: Option<usize>,
    /// Samples between decisions.
    pub hop_samples: usize,
    /// No decision on a window that starts before this travel from the first sample, m.
    pub start_travel_m: f64,
    /// Whether the stroke's start is extended by its mirror image ([`nakano::mirror_start`]),
    /// so that windows start at its first sample instead of waiting for the filters' margin
    /// before it. Anytime decisions use it; windows that start after some travel do not need it.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub mirrored_start: bool,
    /// Whether each window is decided the moment its last sample arrives, the filters'
    /// lookahead past it being its mirror image ([`nakano::EdgeWindow`]), instead of a
    /// lookahead later. A classifier is trained on windows computed the same way, so this is
    /// set when training and kept in the model.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub mirrored_end: bool,
    /// When set, the friction is filtered over travel before the windows read it
    /// ([`FrictionOverTravel`]), so that it reads the same at any rubbing speed. A classifier is
    /// trained on windows computed the same way, so this is set when training and kept in the
    /// model.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction_over_travel: Option<FrictionOverTravel>,
    /// When set, a window is the samples that span a length of travel back from its last
    /// sample instead of [`NakanoWindowing::window_samples`] (which then only times the
    /// decisions: the window keyed `s` ends where a window of `window_samples` starting at `s`
    /// would), so that a slower or faster stroke is decided on the same stretch of surface.
    /// Needs a mirrored end.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub travel: Option<TravelWindows>,
    /// Sample rate the windows are counted at, Hz.
    pub rate_hz: f64,
}

impl NakanoWindowing {
    /// The protocol's windowing: `window_s` and `hop_s` at `rate_hz`, the filters at that rate
    /// ([`NakanoConfig::at_rate`]: the same travel whatever the rate) following the measured
    /// speed at and above the protocol's 5 mm/s (so a faster stroke is filtered over the same
    /// travel, without lengthening the lookahead; see
    /// [`NakanoWindowing::following_speeds_down_to`] for slower strokes), and decisions from
    /// 5 mm of travel on (thesis Sec. 4.3).
    pub fn new(window_s: f64, hop_s: f64, rate_hz: f64) -> Result<Self, RecognizeError> {
        if !(rate_hz.is_finite() && rate_hz > 0.0 && rate_hz <= 1e6) {
            return Err(RecognizeError::Setting(SettingError::Parameter {
                of: "setting",
                name: "rate_hz",
                value: rate_hz,
                reason: "positive and at most 10^6 Hz",
            }));
        }
        let filters = NakanoConfig::at_rate(rate_hz)
            .and_then(|f| f.following_speed(PROTOCOL_SPEED_MPS, PROTOCOL_SPEED_MPS, rate_hz))
            .map_err(|_| {
                RecognizeError::Setting(SettingError::Parameter {
                    of: "setting",
                    name: "rate_hz",
                    value: rate_hz,
                    reason: "a rate at which Nakano's filters span whole samples",
                })
            })?;
        let windowing = Self {
            filters,
            window_samples: samples("window_s", window_s, rate_hz)?,
            training_window_samples: None,
            hop_samples: samples("hop_s", hop_s, rate_hz)?,
            start_travel_m: 0.005,
            mirrored_start: false,
            mirrored_end: false,
            friction_over_travel: None,
            travel: None,
            rate_hz,
        };
        windowing.check().map_err(setting_error)?;
        Ok(windowing)
    }

    /// The defaults at `rate_hz`: [`TRAINING_WINDOW_S`] windows to train on,
    /// [`DECISION_WINDOW_S`] windows to decide on, every [`HOP_S`].
    pub fn protocol(rate_hz: f64) -> Result<Self, RecognizeError> {
        Self::new(DECISION_WINDOW_S, HOP_S, rate_hz)?.with_training_window_s(TRAINING_WINDOW_S)
    }

    /// The same windowing with a decision window of `window_s` instead.
    pub fn with_window_s(self, window_s: f64) -> Result<Self, RecognizeError> {
        let windowing = Self {
            window_samples: samples("window_s", window_s, self.rate_hz)?,
            ..self
        };
        windowing.check().map_err(setting_error)?;
        Ok(windowing)
    }

    /// The same windowing with filters that follow the speed down to `slowest_speed_mps`
    /// instead of the protocol's 5 mm/s: a slower stroke is filtered over the same travel too,
    /// at the cost of a longer lookahead (the filters' longest spans), so of decision latency.
    pub fn following_speeds_down_to(self, slowest_speed_mps: f64) -> Result<Self, RecognizeError> {
        let invalid = |_| {
            RecognizeError::Setting(SettingError::Parameter {
                of: "setting",
                name: "slowest_speed_mps",
                value: slowest_speed_mps,
                reason: "positive, at most the protocol's 5 mm/s, and slow enough for filters of at most 10^6 samples",
            })
        };
        let nominal = NakanoConfig {
            follow_speed: None,
            ..self.filters
        };
        let windowing = Self {
            filters: nominal
                .following_speed(PROTOCOL_SPEED_MPS, slowest_speed_mps, self.rate_hz)
                .map_err(invalid)?,
            ..self
        };
        windowing.check().map_err(setting_error)?;
        Ok(windowing)
    }

    /// The same windowing, trained on windows of `training_window_s`.
    ///
    /// Trained on one run per surface, a map learns each surface's spread from that run's
    /// windows only. Short training windows give it many, varied windows (the spread a surface
    /// shows from place to place), while long decision windows average more roughness waves
    /// into each decision: a 1 s training window with a 3 s decision window recognizes every
    /// Nakano surface at ≥ 95 % (`tests/it/recognition_nakano.rs`) where 1 s / 1 s does not.
    pub fn with_training_window_s(self, training_window_s: f64) -> Result<Self, RecognizeError> {
        let windowing = Self {
            training_window_samples: Some(samples("training_window_s", training_window_s, self.rate_hz)?),
            ..self
        };
        windowing.check().map_err(setting_error)?;
        Ok(windowing)
    }

    /// The same windowing, its settings checked ([`NakanoWindowing::check`]) after they were
    /// set field by field.
    pub(crate) fn checked(self) -> Result<Self, RecognizeError> {
        self.check().map_err(setting_error)?;
        Ok(self)
    }

    /// The windowing the map was trained with.
    pub fn training(&self) -> Self {
        Self {
            window_samples: self.training_window_samples.unwrap_or(self.window_samples),
            training_window_samples: None,
            travel: self.travel.map(|t| TravelWindows {
                window_m: t.training_window_m.unwrap_or(t.window_m),
                training_window_m: None,
                ..t
            }),
            ..*self
        }
    }

    /// The same windows from contact on, as anytime decisions take them: no travel before the
    /// first, and the stroke's start mirrored so that the first window starts at its first
    /// sample.
    pub fn from_contact(self) -> Self {
        Self {
            start_travel_m: 0.0,
            mirrored_start: true,
            ..self
        }
    }

    /// The same windowing over travel: each window spans the travel of its time window at
    /// the protocol's 5 mm/s (1.25 mm for 0.25 s), and takes at most as many samples as that
    /// travel at the slowest speed the filters follow (the protocol's 5 mm/s unless
    /// [`NakanoWindowing::following_speeds_down_to`] says slower). Needs a mirrored end.
    pub fn over_travel(self) -> Result<Self, RecognizeError> {
        self.over_travel_at(PROTOCOL_SPEED_MPS)
    }

    /// As [`NakanoWindowing::over_travel`], each window spanning the travel of its time window
    /// at `reference_speed_mps` instead of the protocol's 5 mm/s: a rig that slides at another
    /// speed keeps its windows as long, in time, at its own speed. This speed also sets the
    /// vibration bands over travel ([`NakanoWindowing::travel_reference_speed_mps`]).
    pub fn over_travel_at(self, reference_speed_mps: f64) -> Result<Self, RecognizeError> {
        if !(reference_speed_mps.is_finite() && reference_speed_mps > 0.0 && reference_speed_mps <= 10.0) {
            return Err(RecognizeError::Setting(SettingError::Parameter {
                of: "setting",
                name: "travel_speed_mps",
                value: reference_speed_mps,
                reason: "positive and at most 10 m/s",
            }));
        }
        let step_m = reference_speed_mps / self.rate_hz;
        let slowest_step_m = match &self.filters.follow_speed {
            Some(f) => {
                f.reference_step_m * self.filters.highpass_half_width as f64
                    / f.max_highpass_half_width as f64
            }
            None => step_m,
        };
        let travel_of = |samples: usize| samples as f64 * step_m;
        let longest = self.window_samples.max(self.training_window_samples.unwrap_or(0));
        let windowing = Self {
            travel: Some(TravelWindows {
                window_m: travel_of(self.window_samples),
                training_window_m: self.training_window_samples.map(travel_of),
                max_samples: (travel_of(longest) / slowest_step_m).ceil().max(longest as f64) as usize,
                fastest_speed_mps: None,
            }),
            ..self
        };
        windowing.check().map_err(setting_error)?;
        Ok(windowing)
    }

    /// The window that ends with the last of `path_m` (the stroke's path through the play,
    /// [`PlayedPath`], from its first sample, or at least the window's): its samples,
    /// [`NakanoWindowing::window_samples`], or over travel as many as span
    /// [`TravelWindows::window_m`] of that path back from its end, at least 2 and at most
    /// [`NakanoWindowing::max_window_samples`] or the samples there are; and the path they span
    /// (for a window of fixed length, over its last samples or those there are). Read through
    /// the play, a tool that trembles at rest spans nothing, and a stroke that turns back counts
    /// both ways less the play.
    pub fn window_span(&self, path_m: &[f64]) -> WindowSpan {
        let n = path_m.len();
        let (most, window_m) = match &self.travel {
            Some(travel) => (self.max_window_samples().min(n), travel.window_m),
            None => (self.window_samples.min(n), f64::INFINITY),
        };
        let mut len = 1;
        let mut travel_m = 0.0;
        while len < most && (len < 2 || travel_m < window_m) {
            travel_m += (path_m[n - len] - path_m[n - len - 1]).abs();
            len += 1;
        }
        if self.travel.is_none() {
            len = self.window_samples;
        }
        WindowSpan { len, travel_m }
    }

    /// The evidence a window of `span` carries, relative to a window of the nominal length:
    /// [`NakanoWindowing::evidence_scale`] of its length times
    /// [`NakanoWindowing::travel_share`]. The features of a tool at rest read one spot of a
    /// surface, not its texture, and none of it counts, whatever the windows; over travel, a
    /// window rubbed slower than the slowest speed the windows read counts for the travel it
    /// covered.
    pub fn evidence(&self, span: WindowSpan) -> f64 {
        self.evidence_scale(span.len) * self.travel_share(span)
    }

    /// The share of its travel a window of `span` covers: 0 for a window during which the tool
    /// never left the play ([`crate::PlayedPath`]), which read one spot of the surface, of fixed
    /// length or over travel; otherwise below 1 only over travel, for a window that takes the
    /// most samples a window takes and still spans less than its travel (rubbed slower than
    /// [`NakanoWindowing::slowest_speed_mps`]).
    pub fn travel_share(&self, span: WindowSpan) -> f64 {
        if span.len >= 2 && span.travel_m == 0.0 {
            return 0.0;
        }
        match &self.travel {
            Some(t) if span.len >= self.max_window_samples() && span.travel_m < t.window_m => {
                span.travel_m / t.window_m
            }
            _ => 1.0,
        }
    }

    /// Whether a window of `span` covers less than its travel, or none
    /// ([`NakanoWindowing::travel_share`]).
    pub fn short_of_travel(&self, span: WindowSpan) -> bool {
        self.travel_share(span) < 1.0
    }

    /// Over travel, the slowest speed at which a window spans its travel within the most
    /// samples a window takes, m/s; `None` for windows of fixed length.
    pub fn slowest_speed_mps(&self) -> Option<f64> {
        self.travel
            .map(|t| t.window_m * self.rate_hz / self.max_window_samples() as f64)
    }

    /// How much of an independent window's evidence a window of `len` samples carries
    /// relative to one of [`NakanoWindowing::window_samples`]: the share of its samples that
    /// are new since the last decision, `hop / len` (at most 1), over `hop / window_samples`.
    /// Exactly 1 for windows of fixed length.
    pub fn evidence_scale(&self, len: usize) -> f64 {
        if len == self.window_samples {
            return 1.0;
        }
        let new = |n: usize| (self.hop_samples as f64 / n.max(1) as f64).min(1.0);
        new(len) / new(self.window_samples)
    }

    /// Samples the longest window takes: [`NakanoWindowing::window_samples`], or over travel
    /// at most [`TravelWindows::max_samples`].
    pub fn max_window_samples(&self) -> usize {
        self.travel
            .map_or(self.window_samples, |t| t.max_samples.max(self.window_samples))
    }

    /// Length of the training windows, s.
    pub fn training_window_s(&self) -> f64 {
        self.training().window_s()
    }

    /// The first setting out of range: its name, its value and what it must be. The bounds
    /// keep a hand-edited recognizer file from sizing buffers past memory or overflowing the
    /// filters' sample arithmetic.
    pub(crate) fn check(&self) -> Result<(), (&'static str, f64, &'static str)> {
        const MAX_HALF_WIDTH: usize = 1_000_000;
        const MAX_WINDOW: usize = 10_000_000;
        let windows = [
            ("window_samples", Some(self.window_samples)),
            ("training_window_samples", self.training_window_samples),
        ];
        for (name, n) in windows {
            if let Some(n) = n
                && !(2..=MAX_WINDOW).contains(&n)
            {
                return Err((name, n as f64, "from 2 to 10^7 samples"));
            }
        }
        if !(1..=MAX_WINDOW).contains(&self.hop_samples) {
            return Err(("hop_samples", self.hop_samples as f64, "from 1 to 10^7 samples"));
        }
        let filters = [
            ("filters.highpass_half_width", self.filters.highpass_half_width, 1),
            (
                "filters.smoothing_half_width",
                self.filters.smoothing_half_width,
                0,
            ),
        ];
        for (name, n, least) in filters {
            if !(least..=MAX_HALF_WIDTH).contains(&n) {
                let reason = if least == 1 {
                    "from 1 to 10^6 samples (the rate is too low for the roughness filter)"
                } else {
                    "at most 10^6 samples"
                };
                return Err((name, n as f64, reason));
            }
        }
        if let Some(follow) = &self.filters.follow_speed {
            let maxima = [
                (
                    "filters.follow_speed.max_highpass_half_width",
                    follow.max_highpass_half_width,
                ),
                (
                    "filters.follow_speed.max_smoothing_half_width",
                    follow.max_smoothing_half_width,
                ),
            ];
            for (name, n) in maxima {
                if n > MAX_HALF_WIDTH {
                    return Err((name, n as f64, "at most 10^6 samples"));
                }
            }
            if self.filters.check().is_err() {
                return Err((
                    "filters.follow_speed.reference_step_m",
                    follow.reference_step_m,
                    "positive and finite, with maximum half-widths at least the nominal ones",
                ));
            }
        }
        if self.mirrored_end {
            let margin = self.filters.lookahead_samples();
            for (name, n) in windows {
                if let Some(n) = n
                    && !nakano::EdgeWindow::mirror_reaches(n, margin)
                {
                    return Err((
                        name,
                        n as f64,
                        "long enough to be decided at its last sample: at least a seventh of the \
                         filters' margin (their longest half-widths together) plus one sample",
                    ));
                }
            }
        }
        if let Some(travel) = &self.friction_over_travel
            && travel.check().is_err()
        {
            return Err((
                "friction_over_travel.cutoff_m",
                travel.cutoff_m,
                "positive and finite",
            ));
        }
        if let Some(travel) = &self.travel {
            let usable = |m: f64| m.is_finite() && m > 0.0;
            if !usable(travel.window_m) || !travel.training_window_m.is_none_or(usable) {
                return Err(("travel.window_m", travel.window_m, "positive and finite"));
            }
            if !(2..=MAX_WINDOW).contains(&travel.max_samples) {
                return Err((
                    "travel.max_samples",
                    travel.max_samples as f64,
                    "from 2 to 10^7 samples",
                ));
            }
            if !self.mirrored_end {
                return Err((
                    "travel.window_m",
                    travel.window_m,
                    "windows over travel are decided at their last sample: set mirrored_end",
                ));
            }
        }
        if !(self.start_travel_m.is_finite() && self.start_travel_m >= 0.0) {
            return Err(("start_travel_m", self.start_travel_m, "finite and not negative"));
        }
        if !(self.rate_hz.is_finite() && self.rate_hz > 0.0 && self.rate_hz <= 1e6) {
            return Err(("rate_hz", self.rate_hz, "positive and at most 10^6 Hz"));
        }
        Ok(())
    }

    /// With windows over travel, the speed at which a window spans as much time as one of
    /// [`NakanoWindowing::window_samples`], m/s: the reference speed the windows were made at
    /// ([`NakanoWindowing::over_travel_at`]). `None` for windows of fixed length.
    pub fn travel_reference_speed_mps(&self) -> Option<f64> {
        self.travel
            .map(|t| t.window_m * self.rate_hz / self.window_samples as f64)
    }

    /// The same windows over travel, their spectra ([`FeatureSet::Vibration`],
    /// [`FeatureSet::NakanoSpectrum`]) read in bands over travel that end at the Nyquist
    /// frequency at `fastest_speed_mps`: the whole of a surface's wavelengths that a stroke
    /// that fast still samples, in 25 bands of cycles per metre. Without it the bands span
    /// 0–200 Hz at the windows' reference speed, and a stroke faster than 2.5 times that
    /// (at 1 kHz) cannot be read. A window slid faster than `fastest_speed_mps` is a typed
    /// error. Needs windows over travel.
    pub fn reading_spectra_up_to(self, fastest_speed_mps: f64) -> Result<Self, RecognizeError> {
        let invalid = |reason| {
            RecognizeError::Setting(SettingError::Parameter {
                of: "setting",
                name: "fastest_speed_mps",
                value: fastest_speed_mps,
                reason,
            })
        };
        let Some(travel) = self.travel else {
            return Err(invalid("needs windows over travel"));
        };
        if !(fastest_speed_mps.is_finite() && fastest_speed_mps > 0.0 && fastest_speed_mps <= 10.0) {
            return Err(invalid("positive and at most 10 m/s"));
        }
        Ok(Self {
            travel: Some(TravelWindows {
                fastest_speed_mps: Some(fastest_speed_mps),
                ..travel
            }),
            ..self
        })
    }

    /// With windows over travel, the speed at which the spectra's bands over travel span
    /// 0 … [`BAND_HZ`], m/s: [`NakanoWindowing::travel_reference_speed_mps`], or where the
    /// bands end at the Nyquist frequency at [`TravelWindows::fastest_speed_mps`].
    pub fn spectrum_reference_speed_mps(&self) -> Option<f64> {
        match self.travel?.fastest_speed_mps {
            Some(fastest) => Some(fastest * 2.0 * BAND_HZ / self.rate_hz),
            None => self.travel_reference_speed_mps(),
        }
    }

    /// Window length, s.
    pub fn window_s(&self) -> f64 {
        self.window_samples as f64 / self.rate_hz
    }

    /// From a window's first sample to the sample that completes it (the window plus the
    /// filters' lookahead), s: how old the oldest sample of a decision is.
    pub fn decision_latency_s(&self) -> f64 {
        (self.window_samples + self.lookahead_samples()) as f64 / self.rate_hz
    }

    /// Whether a window starting at sample `start`, `travel_m` from the first sample, is
    /// decided on.
    pub fn is_decision_window(&self, start: u64, travel_m: f64) -> bool {
        let first = self.first_start() as u64;
        start >= first
            && (start - first).is_multiple_of(self.hop_samples as u64)
            && travel_m >= self.start_travel_m
    }

    /// The first sample a window can start at: the filters' margin, or with a mirrored start
    /// the stroke's first sample.
    pub fn first_start(&self) -> usize {
        if self.mirrored_start {
            0
        } else {
            self.filters.lookahead_samples()
        }
    }

    /// The sample at which the window starting at `start` is complete.
    pub fn decided_at(&self, start: usize) -> usize {
        start + self.window_samples - 1 + self.lookahead_samples()
    }

    /// Samples a decision waits for after its window: the filters' lookahead, or none with a
    /// mirrored end.
    pub fn lookahead_samples(&self) -> usize {
        if self.mirrored_end {
            0
        } else {
            self.filters.lookahead_samples()
        }
    }
}

fn setting_error((name, value, reason): (&'static str, f64, &'static str)) -> RecognizeError {
    RecognizeError::Setting(SettingError::Parameter {
        of: "setting",
        name,
        value,
        reason,
    })
}

fn samples(name: &'static str, seconds: f64, rate_hz: f64) -> Result<usize, RecognizeError> {
    let n = (seconds * rate_hz).round();
    if !(seconds.is_finite() && seconds > 0.0 && (1.0..=1e7).contains(&n)) {
        return Err(RecognizeError::Setting(SettingError::Parameter {
            of: "setting",
            name,
            value: seconds,
            reason: "positive, at least one sample and at most 10^7 samples",
        }));
    }
    Ok(n as usize)
}

/// A capture that gave no window, and why: too short for one window, or its tip never travels
/// far enough (no sliding contact) for a window to start.
#[derive(Debug, Clone, PartialEq)]
pub struct WindowlessCapture {
    /// The capture.
    pub path: std::path::PathBuf,
    /// Why it gave no window, a clause that follows the capture's name (`is 0.400 s long; …`).
    pub reason: String,
}

impl std::fmt::Display for WindowlessCapture {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "capture {} {}", self.path.display(), self.reason)
    }
}

impl WindowlessCapture {
    /// Why `c` gives no window of `windowing`, whose windows are `kind` (`decision`,
    /// `training`) windows. Only meaningful for a capture that [`windows`] found none in.
    pub(crate) fn of(c: &LabelledCapture, windowing: &NakanoWindowing, kind: &str) -> Self {
        let rate = windowing.rate_hz;
        let len = windowing.window_samples;
        let samples = c.samples();
        let secs = |n: usize| n as f64 / rate;
        let travel_mm = |at: f64| 1e3 * at;
        let start = windowing.start_travel_m;
        let travel = match c.kept() {
            Some(kept) => kept.travel().clone(),
            None => Travel::of(&c.capture, [start]),
        };
        // The samples before the first window and after it.
        let needed = windowing.first_start() + len + windowing.lookahead_samples();
        let reason = if samples < needed {
            format!(
                "is {:.3} s long; a {kind} window needs {} s, {:.3} s with the filters' margins",
                secs(samples),
                secs(len),
                secs(needed)
            )
        } else {
            match travel.reached(start) {
                Some(None) => format!(
                    "moves its tip only {:.3} mm (no sliding contact?); a {kind} window starts after {} mm of travel",
                    travel_mm(travel.most_m),
                    travel_mm(start)
                ),
                Some(Some(at)) => format!(
                    "reaches {} mm of travel at {:.3} s of its {:.3} s; no {} s {kind} window fits after that",
                    travel_mm(start),
                    secs(at),
                    secs(samples),
                    secs(len)
                ),
                None => format!("gave no {kind} window"),
            }
        };
        Self {
            path: c.reference.path.clone(),
            reason,
        }
    }
}

/// How far a capture's tip travels from its first sample: the most, and the first sample at
/// which it has travelled each of some distances (the start travels of windowings), as
/// [`WindowlessCapture::of`] explains a capture without windows.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Travel {
    /// The farthest the tip gets from its first position, m (0 without a position column).
    most_m: f64,
    /// Each distance, m, and the first sample at least that far (`None`: never).
    reached: Vec<(f64, Option<usize>)>,
}

impl Travel {
    /// The travel of `capture`'s tip, and when it first covers each of `distances_m`.
    pub(crate) fn of(capture: &Capture, distances_m: impl IntoIterator<Item = f64>) -> Self {
        let position: &[f64] = NakanoSignals::from_capture(capture).map_or(&[], |s| s.position_m());
        let x0 = position.first().copied().unwrap_or_default();
        let most_m = position.iter().map(|x| (x - x0).abs()).fold(0.0, f64::max);
        let reached = distances_m
            .into_iter()
            .map(|d| (d, position.iter().position(|x| (x - x0).abs() >= d)))
            .collect();
        Self { most_m, reached }
    }

    /// When the tip first covers `distance_m`; `None` when that distance was not measured.
    fn reached(&self, distance_m: f64) -> Option<Option<usize>> {
        self.reached
            .iter()
            .find(|(d, _)| *d == distance_m)
            .map(|(_, at)| *at)
    }
}

/// How many samples a window takes and the path length they span, m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowSpan {
    /// Samples.
    pub len: usize,
    /// Path length over them, m.
    pub travel_m: f64,
}

/// Every decision window of a capture: the sample it is keyed by (where a window of
/// [`NakanoWindowing::window_samples`] ending where it ends would start: its first sample but
/// for windows over travel), its span (length in samples and travel), and its features.
pub(crate) fn windows(
    c: &LabelledCapture,
    windowing: &NakanoWindowing,
) -> Result<Vec<(usize, WindowSpan, [f64; FEATURES])>, RecognizeError> {
    if let Some(kept) = c.kept() {
        let vectors = kept
            .windows(windowing, FeatureSet::Nakano, Histogram::default())
            .ok_or_else(|| c.not_kept(format!("Nakano's features of {}", describe(windowing))))?;
        return Ok(vectors
            .vectors
            .iter()
            .map(|(s, span, v)| {
                let mut f = [0.0; FEATURES];
                f.copy_from_slice(&v[..FEATURES]);
                (*s, *span, f)
            })
            .collect());
    }
    let nakano = |source| RecognizeError::Features {
        path: c.reference.path.clone(),
        features: "Nakano",
        source: Box::new(source),
    };
    let mut signals = NakanoSignals::from_capture(&c.capture).map_err(nakano)?;
    if let Some(travel) = &windowing.friction_over_travel {
        let observer = nakano::observer_cutoff_radps(&c.capture).map_err(nakano)?;
        let mut filter = travel.filter(observer, windowing.rate_hz).map_err(nakano)?;
        signals = signals.with_friction_over_travel(&mut filter);
    }
    let x = signals.position_m();
    let Some(&x0) = x.first() else {
        return Ok(Vec::new());
    };
    let path = PlayedPath::series(x);
    let margin = windowing.filters.lookahead_samples();
    let len = windowing.window_samples;
    if windowing.mirrored_end {
        // Each window as known at its last sample; before the stroke's first sample the
        // edge window mirrors on its own, so a mirrored start needs no extension here.
        let (z, f) = (signals.height_m(), signals.friction_n());
        let mut edge =
            nakano::EdgeWindow::new(windowing.filters, windowing.max_window_samples()).map_err(nakano)?;
        return (windowing.first_start()..)
            .step_by(windowing.hop_samples)
            .take_while(|s| s + len <= signals.len())
            .filter(|&s| windowing.is_decision_window(s as u64, (x[s] - x0).abs()))
            .map(|s| {
                let end = s + len;
                let span = windowing.window_span(&path[..end]);
                let start = end - span.len;
                let known = edge.history_start(start)..end;
                let features = edge
                    .features_of(start, span.len, &x[known.clone()], &z[known.clone()], &f[known])
                    .map_err(nakano)?;
                Ok((s, span, features))
            })
            .collect();
    }
    // With a mirrored start, window `s` of the capture is window `s + pad` of the extended
    // signals.
    let (extended, pad) = if windowing.mirrored_start {
        (nakano::mirror_start(&signals, margin), margin)
    } else {
        (None, 0)
    };
    let signals = match &extended {
        Some((x, z, f)) => NakanoSignals::new(x, z, f).map_err(nakano)?,
        None if pad > 0 => return Ok(Vec::new()),
        None => signals,
    };
    (windowing.first_start()..)
        .step_by(windowing.hop_samples)
        .take_while(|s| s + pad + len + margin <= signals.len())
        .filter(|&s| windowing.is_decision_window(s as u64, (x[s] - x0).abs()))
        .map(|s| {
            Ok((
                s,
                windowing.window_span(&path[..s + len]),
                signals
                    .features(s + pad, len, &windowing.filters)
                    .map_err(nakano)?,
            ))
        })
        .collect()
}

/// The feature vectors of the windows of `c` that `windowing` picks: Nakano's five features,
/// followed for [`FeatureSet::Both`] by the spectrotemporal histogram of the window's own
/// accelerometer samples (`start .. start + window_samples`, all before the decision): of the
/// three axes' magnitude when the capture has them, else of its single-axis
/// [`VIBRATION_COLUMN`], as a whole scratch's histogram is
/// ([`SpectrogramPlan::capture_features`]).
pub(crate) fn window_vectors(
    c: &LabelledCapture,
    windowing: &NakanoWindowing,
    features: FeatureSet,
    histogram: Histogram,
) -> Result<WindowVectors, RecognizeError> {
    if let Some(kept) = c.kept() {
        let kept = kept
            .windows(windowing, features, histogram)
            .ok_or_else(|| c.not_kept(format!("{features} features of {}", describe(windowing))))?;
        return Ok(WindowVectors {
            vectors: kept
                .vectors
                .iter()
                .map(|(s, span, v)| (*s, *span, v[..features.dim()].to_vec()))
                .collect(),
            too_fast: kept.too_fast,
        });
    }
    window_vectors_from(c, windowing, features, histogram, windows(c, windowing)?)
}

/// Nakano's features of a capture's windows, as [`windows`] gives them.
pub(crate) type NakanoWindows = Vec<(usize, WindowSpan, [f64; FEATURES])>;

/// [`window_vectors`] of a capture with samples, from its Nakano windows (`nakano`, the
/// [`windows`] of `windowing`), so that feature sets over the same windows compute them once.
pub(crate) fn window_vectors_from(
    c: &LabelledCapture,
    windowing: &NakanoWindowing,
    features: FeatureSet,
    histogram: Histogram,
    nakano: NakanoWindows,
) -> Result<WindowVectors, RecognizeError> {
    let all = |vectors| {
        Ok(WindowVectors {
            vectors,
            too_fast: TooFastWindows::default(),
        })
    };
    if features == FeatureSet::Nakano {
        return all(nakano.into_iter().map(|(s, n, f)| (s, n, f.to_vec())).collect());
    }
    let features_error = |features, source| RecognizeError::Features {
        path: c.reference.path.clone(),
        features,
        source: Box::new(source),
    };
    let spectral = |source| features_error(spectrum_name(FeatureSet::Vibration), source);
    let nakano_column = |name| {
        c.capture
            .column(name)
            .map_err(|e| spectral(RecognizeError::Input(InputError::NakanoColumn(Box::new(e)))))
    };
    if features == FeatureSet::NakanoSpectrum {
        let height_spectrum = |source| features_error(spectrum_name(FeatureSet::NakanoSpectrum), source);
        let path_m = PlayedPath::series(nakano_column(nakano::POSITION_COLUMN)?);
        let height = Axes::One(nakano_column(nakano::HEIGHT_COLUMN)?);
        let (spectra, too_fast) =
            window_spectra(nakano, windowing, height, &path_m, histogram).map_err(height_spectrum)?;
        return Ok(WindowVectors {
            vectors: spectra
                .into_iter()
                .map(|(s, span, nakano, spectrum)| {
                    (s, span, nakano.iter().chain(&spectrum).copied().collect())
                })
                .collect(),
            too_fast,
        });
    }
    let column = |name| {
        c.capture
            .column(name)
            .map_err(|e| spectral(RecognizeError::Input(InputError::NoAccelerometer(Box::new(e)))))
    };
    let has_axes = ACCEL_COLUMNS.iter().all(|name| c.capture.has_column(name));
    let axes = if !has_axes && c.capture.has_column(VIBRATION_COLUMN) {
        Axes::One(column(VIBRATION_COLUMN)?)
    } else {
        let [x, y, z] = ACCEL_COLUMNS;
        Axes::Three(column(x)?, column(y)?, column(z)?)
    };
    if features == FeatureSet::Vibration {
        let path_m = PlayedPath::series(nakano_column(nakano::POSITION_COLUMN)?);
        let (spectra, too_fast) =
            window_spectra(nakano, windowing, axes, &path_m, histogram).map_err(spectral)?;
        return Ok(WindowVectors {
            vectors: spectra
                .into_iter()
                .map(|(s, span, _, spectrum)| (s, span, spectrum.to_vec()))
                .collect(),
            too_fast,
        });
    }
    let plan = SpectrogramPlan::over_band(windowing.rate_hz, histogram.band).map_err(spectral)?;
    let len = windowing.window_samples;
    let vectors = nakano
        .into_iter()
        .map(|(s, span, f)| {
            let h = match axes {
                Axes::Three(x, y, z) => {
                    let range = s..(s + len).min(x.len());
                    plan.features(&x[range.clone()], &y[range.clone()], &z[range], histogram.cells)
                }
                Axes::One(v) => plan.single_axis_features(&v[s..(s + len).min(v.len())], histogram.cells),
            }
            .map_err(spectral)?;
            Ok((s, span, f.iter().copied().chain(h).collect()))
        })
        .collect::<Result<_, RecognizeError>>()?;
    all(vectors)
}

/// A capture's windows as a windowing picks them: each readable window's first sample, span
/// and feature vector, and the windows left out because they slid too fast to be read.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct WindowVectors {
    pub vectors: Vec<(usize, WindowSpan, Vec<f64>)>,
    pub too_fast: TooFastWindows,
}

/// How an error names the spectrum a feature set reads: the tip height's for
/// [`FeatureSet::NakanoSpectrum`], the accelerometer's otherwise.
fn spectrum_name(features: FeatureSet) -> &'static str {
    match features {
        FeatureSet::NakanoSpectrum => "height spectrum",
        _ => "spectrotemporal",
    }
}

impl WindowVectors {
    /// The windows read, for deciding on capture `c`: none read because every one slid too
    /// fast is the typed error a single window would be (named as `window_vectors` names a
    /// feature set's errors), since nothing can be said of that capture; some read, the rest
    /// are left out.
    pub(crate) fn decidable(
        self,
        c: &LabelledCapture,
        features: FeatureSet,
    ) -> Result<Vec<(usize, WindowSpan, Vec<f64>)>, RecognizeError> {
        let t = self.too_fast;
        if !self.vectors.is_empty() || t.count == 0 {
            return Ok(self.vectors);
        }
        Err(RecognizeError::Features {
            path: c.reference.path.clone(),
            features: spectrum_name(features),
            source: Box::new(RecognizeError::Setting(SettingError::TooFastForBands {
                speed_mps: t.fastest_mps,
                max_speed_mps: t.readable_up_to_mps,
                rate_hz: t.rate_hz,
            })),
        })
    }
}

/// Windows over travel left out because they slid faster than their bands can be read at the
/// capture's rate (their top band would pass the Nyquist frequency).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TooFastWindows {
    /// How many.
    pub count: usize,
    /// The fastest of them, m/s.
    pub fastest_mps: f64,
    /// The fastest speed the bands read at, m/s (the slowest such limit where captures differ
    /// in rate).
    pub readable_up_to_mps: f64,
    /// The rate that limit is at, Hz.
    pub rate_hz: f64,
}

impl TooFastWindows {
    /// Counts one window slid at `speed_mps` where `readable_up_to_mps` is the limit at
    /// `rate_hz`.
    pub(crate) fn add(&mut self, speed_mps: f64, readable_up_to_mps: f64, rate_hz: f64) {
        self.merge(Self {
            count: 1,
            fastest_mps: speed_mps,
            readable_up_to_mps,
            rate_hz,
        });
    }

    /// Both counts together.
    pub(crate) fn merge(&mut self, other: Self) {
        if other.count == 0 {
            return;
        }
        if self.count == 0 || other.readable_up_to_mps < self.readable_up_to_mps {
            self.readable_up_to_mps = other.readable_up_to_mps;
            self.rate_hz = other.rate_hz;
        }
        self.count += other.count;
        self.fastest_mps = self.fastest_mps.max(other.fastest_mps);
    }
}

/// A window's first sample, span, Nakano features and spectrum.
type SpectrumWindow = (usize, WindowSpan, [f64; FEATURES], [f64; SPECTRUM_LEN]);

/// Nakano's windows, each with its spectrum ([`FeatureSet::Vibration`]'s vectors alone,
/// [`FeatureSet::NakanoSpectrum`]'s after the window's Nakano features): of each window's own
/// samples of `axes` (the `len` that end where the window ends, so that a window over travel
/// reads the same stretch as its Nakano features), all before its decision. Over travel, the
/// bands are too ([`WindowSpectrumPlan::features_over_travel`]), at the window's path
/// (`path_m`, the capture's [`PlayedPath`]) over its duration; a window slid too fast for
/// them is left out and counted.
fn window_spectra(
    nakano: Vec<(usize, WindowSpan, [f64; FEATURES])>,
    windowing: &NakanoWindowing,
    axes: Axes<'_>,
    path_m: &[f64],
    histogram: Histogram,
) -> Result<(Vec<SpectrumWindow>, TooFastWindows), RecognizeError> {
    let plan = WindowSpectrumPlan::new(windowing.rate_hz, windowing.max_window_samples())?;
    let mut scratch = plan.scratch();
    let samples = match axes {
        Axes::Three(x, ..) => x.len(),
        Axes::One(v) => v.len(),
    };
    let mut too_fast = TooFastWindows::default();
    let mut out = Vec::with_capacity(nakano.len());
    for (s, span, nakano) in nakano {
        let end = (s + windowing.window_samples).min(samples);
        let r = end.saturating_sub(span.len)..end;
        let signal = match axes {
            Axes::Three(x, y, z) => {
                Cow::Owned(spectral::magnitude(&x[r.clone()], &y[r.clone()], &z[r.clone()])?)
            }
            Axes::One(v) => Cow::Borrowed(&v[r.clone()]),
        };
        // The window spectrum's own bands: a histogram's band does not apply to it.
        match windowing.spectrum_features(&plan, &signal, &path_m[r], histogram.cells, &mut scratch) {
            Ok(spectrum) => out.push((s, span, nakano, spectrum)),
            // A window the bands cannot read at this rate is left out and counted, not fatal:
            // a rig's position stream can read a burst of speed over a few slow samples.
            Err(RecognizeError::Setting(SettingError::TooFastForBands {
                speed_mps,
                max_speed_mps,
                rate_hz,
            })) => too_fast.add(speed_mps, max_speed_mps, rate_hz),
            Err(e) => return Err(e),
        }
    }
    Ok((out, too_fast))
}

impl NakanoWindowing {
    /// The spectrum of one window ([`FeatureSet::Vibration`]'s features, the last of
    /// [`FeatureSet::NakanoSpectrum`]'s): of `signal` (the window's vibration samples, a single
    /// axis or the axes' magnitude, or its heights), over travel when the windows are
    /// ([`NakanoWindowing::spectrum_reference_speed_mps`], at the speed along `path_m`, the
    /// same samples' [`PlayedPath`]), by `plan` (made for
    /// [`NakanoWindowing::max_window_samples`] at this rate) in `scratch`. The offline vectors
    /// and the live recognizer both read windows through it, so the two agree to the bit.
    pub fn spectrum_features(
        &self,
        plan: &WindowSpectrumPlan,
        signal: &[f64],
        path_m: &[f64],
        cell_scale: CellScale,
        scratch: &mut SpectrumScratch,
    ) -> Result<[f64; SPECTRUM_LEN], RecognizeError> {
        match self.spectrum_reference_speed_mps() {
            Some(reference) => {
                let speed_mps = path_speed_mps(path_m, self.rate_hz);
                plan.features_over_travel_with(signal, speed_mps, reference, cell_scale, scratch)
            }
            None => plan.features_with(signal, cell_scale, scratch),
        }
    }
}

/// The path along `path_m` (a [`PlayedPath`]'s) over its duration at `rate_hz`, m/s; 0 for
/// fewer than two samples.
fn path_speed_mps(path_m: &[f64], rate_hz: f64) -> f64 {
    if path_m.len() < 2 {
        return 0.0;
    }
    let travel_m: f64 = path_m.windows(2).map(|p| (p[1] - p[0]).abs()).sum();
    travel_m * rate_hz / (path_m.len() - 1) as f64
}

/// The accelerometer columns a window's histogram is computed from.
#[derive(Clone, Copy)]
enum Axes<'a> {
    /// The three axes (their magnitude).
    Three(&'a [f64], &'a [f64], &'a [f64]),
    /// A single vibration axis.
    One(&'a [f64]),
}

/// A windowing in words, for errors: its window, hop and rate.
fn describe(windowing: &NakanoWindowing) -> String {
    format!(
        "{} s windows every {} s at {} Hz",
        windowing.window_s(),
        windowing.hop_samples as f64 / windowing.rate_hz,
        windowing.rate_hz
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 0.25 s windows every 0.1 s at 1 kHz, decided at their last sample, the filters following
    /// the speed down to 2 mm/s, over travel: 1.25 mm, at most 625 samples.
    fn over_travel() -> NakanoWindowing {
        NakanoWindowing {
            mirrored_end: true,
            ..NakanoWindowing::new(0.25, 0.1, 1000.0)
                .expect("valid")
                .following_speeds_down_to(0.002)
                .expect("valid")
        }
        .over_travel()
        .expect("valid")
    }

    /// Positions of a tip moving `step_m` per sample, `n` samples.
    fn steady(step_m: f64, n: usize) -> Vec<f64> {
        (0..n).map(|k| k as f64 * step_m).collect()
    }

    #[test]
    fn a_window_over_travel_spans_its_travel_at_any_speed() {
        let w = over_travel();
        let travel = w.travel.expect("over travel");
        assert!((travel.window_m - 1.25e-3).abs() < 1e-15);
        assert_eq!(travel.max_samples, 625);
        // 1.25 mm at 5, 2 and 20 µm per sample (the last step may round past it).
        for (step_m, len) in [(5e-6, 251), (2e-6, 626), (20e-6, 64)] {
            let x = steady(step_m, 2000);
            let got = w.window_span(&x).len;
            assert!(got.abs_diff(len) <= 1, "{step_m}: {got}");
            let span = (x[x.len() - 1] - x[x.len() - got]).abs();
            assert!(span >= 1.25e-3 - 1e-12 || got == 625, "{step_m}: {span}");
        }
        // Slower than 2 mm/s, capped; at the stroke's start, all there is; a stroke that turns
        // back counts both ways, less the play; a still tip takes the longest window.
        assert_eq!(w.window_span(&steady(1e-6, 2000)).len, 625);
        assert_eq!(w.window_span(&steady(5e-6, 100)).len, 100);
        let there_and_back: Vec<f64> = (0..400)
            .map(|k| {
                if k < 200 {
                    k as f64 * 5e-6
                } else {
                    (400 - k) as f64 * 5e-6
                }
            })
            .collect();
        // Back: 0.8 mm past the play's 0.2 mm (200 samples); out: the other 0.45 mm.
        let span = w.window_span(&PlayedPath::series(&there_and_back));
        assert!(span.len.abs_diff(291) <= 1, "{span:?}");
        assert!(span.travel_m >= 1.25e-3 - 1e-12, "{span:?}");
        assert_eq!(w.window_span(&[0.0; 1000]).len, 625);
        assert_eq!(w.window_span(&[0.0]).len, 1);
        // Windows of fixed length are what they were.
        let fixed = NakanoWindowing::new(0.25, 0.1, 1000.0).expect("valid");
        assert_eq!(fixed.window_span(&steady(2e-6, 2000)).len, 250);
    }

    /// Down to the slowest speed a window's evidence is its length's; below it, at the most
    /// samples, the share of its travel it covers; at rest, none. Fixed windows count whole
    /// unless the tool never left the play.
    #[test]
    fn a_window_short_of_its_travel_counts_for_the_travel_it_covers() {
        let w = over_travel();
        let evidence = |step_m: f64| w.evidence(w.window_span(&steady(step_m, 2000)));
        for step_m in [5e-6, 2.5e-6, 20e-6] {
            let span = w.window_span(&steady(step_m, 2000));
            assert!(span.travel_m >= 1.25e-3 - 1e-12, "{step_m}: {span:?}");
            assert_eq!(evidence(step_m), w.evidence_scale(span.len));
        }
        // 1 mm/s: 625 samples over 0.624 mm, about half the travel, of the 2 mm/s floor 0.4.
        let span = w.window_span(&steady(1e-6, 2000));
        assert_eq!(span.len, 625);
        assert!((span.travel_m - 0.624e-3).abs() < 1e-12, "{span:?}");
        assert!(
            (evidence(1e-6) - 0.4 * 0.624 / 1.25).abs() < 1e-9,
            "{}",
            evidence(1e-6)
        );
        assert_eq!(w.evidence(w.window_span(&[0.0; 1000])), 0.0);
        // A hand that trembles 30 µm at 9 Hz, read by a 10 µm encoder: its samples' own path
        // would make a window of rubbing; through the play it is at rest.
        let trembling: Vec<f64> = (0..1000)
            .map(|k| (3.0 * (2.0 * std::f64::consts::PI * 9.0 * k as f64 / 1e3).sin()).round() * 1e-5)
            .collect();
        // 120 µm a cycle: 0.68 mm over 625 samples, 54 % of the travel, of the floor's 0.4.
        let raw = w.evidence(w.window_span(&trembling));
        assert!((raw - 0.4 * 0.675 / 1.25).abs() < 0.02, "{raw}");
        assert_eq!(w.evidence(w.window_span(&PlayedPath::series(&trembling))), 0.0);
        assert!(w.short_of_travel(span) && !w.short_of_travel(w.window_span(&steady(2.5e-6, 2000))));
        assert!((w.slowest_speed_mps().expect("over travel") - 0.002).abs() < 1e-12);
        // At the stroke's start a window short of its travel but not of samples counts whole.
        let start = w.window_span(&steady(5e-6, 100));
        assert_eq!(w.evidence(start), w.evidence_scale(100));
        assert!(!w.short_of_travel(start));
        // A window of fixed length counts whole however slowly it was rubbed, and for nothing if
        // the tool never left the play.
        let fixed = NakanoWindowing::new(0.25, 0.1, 1000.0).expect("valid");
        assert_eq!(fixed.evidence(fixed.window_span(&steady(0.1e-6, 2000))), 1.0);
        assert!(!fixed.short_of_travel(fixed.window_span(&steady(0.1e-6, 2000))));
        assert_eq!(fixed.evidence(fixed.window_span(&[0.0; 1000])), 0.0);
        assert!(fixed.short_of_travel(fixed.window_span(&[0.0; 1000])));
        assert_eq!(fixed.slowest_speed_mps(), None);
        let fixed_span = fixed.window_span(&steady(2e-6, 2000));
        assert_eq!(fixed_span.len, 250);
        assert!(
            (fixed_span.travel_m - 249.0 * 2e-6).abs() < 1e-12,
            "{fixed_span:?}"
        );
    }

    #[test]
    fn windows_over_travel_at_a_rigs_own_speed() {
        // 0.25 s at 2.2 kHz over travel at 25 mm/s: 6.25 mm, up to 1.25 s (the filters follow
        // down to the protocol's 5 mm/s).
        let w = NakanoWindowing {
            mirrored_end: true,
            ..NakanoWindowing::new(0.25, 0.1, 2200.0).expect("valid")
        };
        let at = w.over_travel_at(0.025).expect("valid");
        let travel = at.travel.expect("over travel");
        assert!((travel.window_m - 6.25e-3).abs() < 1e-15);
        assert_eq!(travel.max_samples, 2750);
        assert!((at.travel_reference_speed_mps().expect("over travel") - 0.025).abs() < 1e-15);
        let protocol = w.over_travel().expect("valid");
        assert!((protocol.travel_reference_speed_mps().expect("over travel") - 0.005).abs() < 1e-15);
        assert_eq!(protocol, w.over_travel_at(0.005).expect("valid"));
        assert_eq!(w.travel_reference_speed_mps(), None);
        for bad in [0.0, -0.01, f64::NAN, f64::INFINITY, 11.0] {
            assert!(
                matches!(
                    w.over_travel_at(bad),
                    Err(RecognizeError::Setting(SettingError::Parameter {
                        name: "travel_speed_mps",
                        ..
                    }))
                ),
                "{bad}"
            );
        }
        // The path speed of a window: its length over its duration, turns counted both ways.
        assert!((path_speed_mps(&steady(25e-6 / 2.2, 551), 2200.0) - 0.025).abs() < 1e-12);
        assert_eq!(path_speed_mps(&[0.0], 2200.0), 0.0);
        assert!((path_speed_mps(&[0.0, 1e-5, 0.0], 1000.0) - 0.01).abs() < 1e-15);
    }

    #[test]
    fn spectra_read_up_to_the_fastest_stroke() {
        let w = over_travel();
        // By default 0–200 Hz at the windows' 5 mm/s: readable up to 12.5 mm/s at 1 kHz.
        assert_eq!(w.spectrum_reference_speed_mps(), Some(0.005));
        let fast = w.reading_spectra_up_to(0.025).expect("valid");
        // The bands end at 500 Hz at 25 mm/s: 0–200 Hz at 10 mm/s.
        assert!((fast.spectrum_reference_speed_mps().expect("over travel") - 0.01).abs() < 1e-15);
        // Nothing else changes: the windows' travel, the training windows, the file.
        assert_eq!(fast.travel_reference_speed_mps(), w.travel_reference_speed_mps());
        assert_eq!(
            fast.training().travel.and_then(|t| t.fastest_speed_mps),
            Some(0.025)
        );
        let text = serde_json::to_string(&fast).expect("json");
        assert_eq!(
            serde_json::from_str::<NakanoWindowing>(&text).expect("back"),
            fast
        );
        assert!(!serde_json::to_string(&w).expect("json").contains("fastest"));
        // A window at 25 mm/s is read; one at 26 mm/s passes the Nyquist frequency.
        let plan = WindowSpectrumPlan::new(1000.0, w.max_window_samples()).expect("plan");
        let mut scratch = plan.scratch();
        let signal: Vec<f64> = (0..60).map(|k| (k as f64 * 0.7).sin()).collect();
        let read = |w: &NakanoWindowing, step_m: f64, scratch: &mut SpectrumScratch| {
            w.spectrum_features(&plan, &signal, &steady(step_m, 60), CellScale::Mean, scratch)
        };
        assert!(read(&fast, 25e-6, &mut scratch).is_ok());
        assert!(read(&fast, 26e-6, &mut scratch).is_err());
        assert!(read(&w, 25e-6, &mut scratch).is_err());
        assert!(read(&w, 12.5e-6, &mut scratch).is_ok());
        // Only over travel, and only a speed.
        let fixed = NakanoWindowing::new(0.25, 0.1, 1000.0).expect("valid");
        for (windowing, bad) in [(fixed, 0.025), (w, 0.0), (w, -0.01), (w, f64::NAN), (w, 11.0)] {
            assert!(
                matches!(
                    windowing.reading_spectra_up_to(bad),
                    Err(RecognizeError::Setting(SettingError::Parameter {
                        name: "fastest_speed_mps",
                        ..
                    }))
                ),
                "{bad}"
            );
        }
    }

    #[test]
    fn a_window_weighs_the_share_of_its_samples_that_are_new() {
        let w = over_travel();
        assert_eq!(w.evidence_scale(250), 1.0);
        // 625 samples (2 mm/s): 100 new of 625 against 100 of 250.
        assert!((w.evidence_scale(625) - 0.4).abs() < 1e-12);
        // 63 samples (20 mm/s): every sample is new, against 0.4.
        assert!((w.evidence_scale(63) - 2.5).abs() < 1e-12);
    }

    #[test]
    fn windows_over_travel_need_a_mirrored_end_and_keep_their_settings() {
        let plain = NakanoWindowing::new(0.25, 0.1, 1000.0).expect("valid");
        assert!(plain.over_travel().is_err());
        let w = over_travel();
        let training = NakanoWindowing {
            training_window_samples: Some(500),
            ..w
        }
        .over_travel()
        .expect("valid")
        .training();
        let t = training.travel.expect("over travel");
        assert!((t.window_m - 2.5e-3).abs() < 1e-15);
        assert_eq!(t.max_samples, 1250);
        let text = serde_json::to_string(&w).expect("json");
        assert_eq!(serde_json::from_str::<NakanoWindowing>(&text).expect("back"), w);
        let old = serde_json::to_string(&plain).expect("json");
        assert!(!old.contains("\"travel\""), "{old}");
        let bad = NakanoWindowing {
            travel: Some(TravelWindows {
                window_m: f64::NAN,
                ..w.travel.expect("over travel")
            }),
            ..w
        };
        assert!(bad.check().is_err());
    }
}
