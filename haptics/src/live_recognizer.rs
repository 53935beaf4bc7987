//! The live surface recognizer of the haptic thread: Nakano's features updated in O(1) per
//! sample, a SOM decision every hop, (label, confidence) out.
//!
//! Everything it needs is allocated in [`LiveRecognizer::new`] (the stream's rings, the map, a
//! scratch vector); [`LiveRecognizer::push`] does arithmetic on them only — no allocation, no
//! lock, no I/O — so it can run inside the 1 kHz tick. It decides on exactly the windows the
//! offline pipeline ([`RecognizerFile::decisions`]) decides on, with the same map arithmetic
//! ([`Som::decide_into`]); the features come from the streaming sums instead of the batch ones
//! and agree with them to ~1e-9 relative.

use crate::acquire;
use crate::error::HapticsError;
use crate::rt::{CHANNELS, Controller, TickInput, TickOutput};
use recognize::{FEATURES, NakanoStream, NakanoWindowing, RecognizerBody, RecognizerFile, Som};

/// One live decision.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LiveDecision {
    /// Index into the recognizer's classes.
    pub label: usize,
    /// Confidence in `[0, 1]`: half the SOM's inner-product margin over the best node of
    /// another surface.
    pub confidence: f64,
    /// First sample (counted from 0 since construction, [`LiveRecognizer::reset`] or a
    /// non-finite sample, each of which starts a stroke) of the
    /// window decided on.
    pub window_start: u64,
}

/// Nakano's SOM recognizer, fed one sample per haptic tick.
#[derive(Debug, Clone)]
pub struct LiveRecognizer {
    som: Som<usize>,
    windowing: NakanoWindowing,
    classes: Vec<String>,
    stream: NakanoStream,
    scratch: [f64; FEATURES],
    first_position_m: Option<f64>,
    current: Option<LiveDecision>,
}

impl LiveRecognizer {
    /// A recognizer for a loop running at `loop_hz`, from a loaded SOM recognizer file.
    pub fn new(model: &RecognizerFile, loop_hz: f64) -> Result<Self, HapticsError> {
        let RecognizerBody::Som { windowing, som } = &model.body else {
            return Err(HapticsError::LiveMethod {
                method: model.method(),
                features: model.body.feature_set().name(),
            });
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
            som: som.clone(),
            windowing: *windowing,
            classes: model.classes.clone(),
            stream: NakanoStream::new(windowing.filters, windowing.window_samples)?,
            scratch: [0.0; FEATURES],
            first_position_m: None,
            current: None,
        })
    }

    /// Feeds one tick: the tip's position along the rubbing direction and its height, m, and
    /// the friction (the RFOB's reaction force along x), N. Returns the new decision when this
    /// sample completes a decision window, `None` otherwise (the previous one stands, see
    /// [`LiveRecognizer::current`]).
    ///
    /// A non-finite sample is an error: it would poison the stream's running sums for good, so
    /// the stroke starts afresh from the next sample (a new window, the start travel counted
    /// again) while the last decision stands until a new one is made.
    pub fn push(
        &mut self,
        position_m: f64,
        height_m: f64,
        friction_n: f64,
    ) -> Result<Option<LiveDecision>, HapticsError> {
        if !(position_m.is_finite() && height_m.is_finite() && friction_n.is_finite()) {
            self.stream.reset();
            self.first_position_m = None;
            return Err(HapticsError::NotFiniteSample {
                position_m,
                height_m,
                friction_n,
            });
        }
        let x0 = *self.first_position_m.get_or_insert(position_m);
        let Some(window) = self.stream.push(position_m, height_m, friction_n) else {
            return Ok(None);
        };
        let travel_m = (window.start_position_m - x0).abs();
        if !self.windowing.is_decision_window(window.start, travel_m) {
            return Ok(None);
        }
        let d = self.som.decide_into(&window.features, &mut self.scratch)?;
        let decision = LiveDecision {
            label: self.som.node_labels().get(d.node).copied().unwrap_or(0),
            confidence: d.confidence,
            window_start: window.start,
        };
        self.current = Some(decision);
        Ok(Some(decision))
    }

    /// The latest decision, if any since the last reset.
    pub fn current(&self) -> Option<LiveDecision> {
        self.current
    }

    /// Forgets the stroke (tool lifted): the next sample starts a new one. No allocation.
    pub fn reset(&mut self) {
        self.stream.reset();
        self.first_position_m = None;
        self.current = None;
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

/// Channels [`Recognizing`] writes into every sample, after the wrapped controller's eight.
pub mod channel {
    /// Class index + 1 of the latest decision; 0 before the stroke's first decision.
    pub const LABEL: usize = 8;
    /// Confidence of the latest decision, `[0, 1]` (0 before the first).
    pub const CONFIDENCE: usize = 9;
    /// Decisions made since the stroke began: a sample where it steps carries a new decision.
    pub const DECISIONS: usize = 10;
}

/// The decision a sample's recognizer channels carry: `(label, confidence)`, or `None` before
/// the stroke's first decision.
pub fn decision_in(channels: &[f64; CHANNELS]) -> Option<(usize, f64)> {
    let label = channels[channel::LABEL];
    (label >= 1.0 && label.is_finite()).then(|| ((label - 1.0) as usize, channels[channel::CONFIDENCE]))
}

/// A rubbing controller with the live recognizer inside its tick: each tick the wrapped
/// controller runs, then the sample it produced (position, height and the RFOB's friction, as a
/// capture records them: [`acquire::rubbing_signals`]) is pushed into the recognizer, and the
/// latest decision is written into [`channel`]s of the same sample, so it reaches the recorder
/// and the UI with the force it was decided beside. A stroke (a run of rubbing-phase ticks)
/// starts the recognizer afresh, as a capture starts its windows afresh.
///
/// Nothing here allocates, locks, logs or does I/O. A non-finite sample sets
/// [`crate::safety::flag::RECOGNIZER_INPUT_NOT_FINITE`] on its tick and restarts the
/// recognizer's stroke from the next sample; the last decision stands until a new one.
#[derive(Debug)]
pub struct Recognizing<C> {
    inner: C,
    live: LiveRecognizer,
    rubbing: bool,
    decisions: u64,
}

impl<C: Controller> Recognizing<C> {
    /// Wraps `inner` (a rubbing controller) with `live`.
    pub fn new(inner: C, live: LiveRecognizer) -> Self {
        Self {
            inner,
            live,
            rubbing: false,
            decisions: 0,
        }
    }

    /// The recognizer (its classes name the labels).
    pub fn recognizer(&self) -> &LiveRecognizer {
        &self.live
    }
}

impl<C: Controller> Controller for Recognizing<C> {
    fn tick(&mut self, input: &TickInput<'_>, out: &mut TickOutput) {
        self.inner.tick(input, out);
        match acquire::rubbing_signals(input.state, &out.channels) {
            Some([x, z, f]) => {
                if !self.rubbing {
                    self.live.reset();
                    self.rubbing = true;
                    self.decisions = 0;
                }
                match self.live.push(x, z, f) {
                    Ok(Some(_)) => self.decisions += 1,
                    Ok(None) => {}
                    Err(_) => out.flags |= crate::safety::flag::RECOGNIZER_INPUT_NOT_FINITE,
                }
            }
            None => self.rubbing = false,
        }
        let current = self.live.current();
        out.channels[channel::LABEL] = current.map_or(0.0, |d| d.label as f64 + 1.0);
        out.channels[channel::CONFIDENCE] = current.map_or(0.0, |d| d.confidence);
        out.channels[channel::DECISIONS] = self.decisions as f64;
    }

    fn finished(&self) -> bool {
        self.inner.finished()
    }
}
