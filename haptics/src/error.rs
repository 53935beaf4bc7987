//! Every failure of the haptic side, as one type.
//!
//! The haptic thread can meet some of these mid-run; those variants carry only static text and
//! numbers, so building and reporting one does not allocate. This file sits at the crate root
//! and imports only the lower crates and the standard library, so that `rt` may use it without
//! reaching up into control, laws, the simulated world or the recorder.

use std::fmt;
use std::path::PathBuf;
use std::time::Duration;

use capture::CaptureError;
use identify::{IdentifyError, ModelKind};
use recognize::RecognizeError;
use sim::SimError;
use svm::SvmError;

/// Why a haptics operation failed: a device, the loop, a recording, a capture protocol, the
/// live recognizer, or an identified model.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum HapticsError {
    /// A vendor's library could not be loaded.
    #[error("{sdk} was not found ({tried}): install it, or run on the simulated device")]
    SdkMissing {
        /// The library, as its backend names it (which vendor, which version).
        sdk: &'static str,
        /// What was tried and why each failed.
        tried: String,
    },
    /// A vendor's library lacks a function the device needs.
    #[error("{library} has no `{symbol}`: install {sdk}, or run on the simulated device")]
    SymbolMissing {
        /// The library a backend needs, as it names it (which vendor, which version).
        sdk: &'static str,
        /// The library file.
        library: String,
        /// The missing function.
        symbol: &'static str,
    },
    /// The vendor's library loaded but found no device.
    #[error("no {device} is connected ({detail}): connect and power it on, or run on the simulated device")]
    NoDevice {
        /// The device, as its backend names it.
        device: &'static str,
        /// What the library said.
        detail: String,
    },
    /// A device call returned an error code. Inside the loop, the loop then sent zero force and
    /// stopped, and `tick` says when.
    #[error("{call} failed (code {code}){}", InLoop(*tick))]
    DeviceCall {
        /// The function that failed.
        call: &'static str,
        /// Its return code.
        code: i32,
        /// The loop's tick when it failed (0: as the loop enabled forces); `None` outside the
        /// loop.
        tick: Option<u64>,
    },
    /// The device stopped answering or reported a fault.
    #[error("device fault: {what}{}", InLoop(*tick))]
    DeviceFault {
        /// What went wrong.
        what: &'static str,
        /// The loop's tick when it failed; `None` outside the loop.
        tick: Option<u64>,
    },
    /// The device was used after `close`.
    #[error("device is closed{}", InLoop(*tick))]
    DeviceClosed {
        /// The loop's tick when it was used; `None` outside the loop.
        tick: Option<u64>,
    },
    /// A replayed capture has no more samples: the normal end of a replay.
    #[error("the replayed capture has ended")]
    EndOfReplay,
    /// A capture could not be used for replay.
    #[error("cannot replay {source_name}: {reason}")]
    BadReplay {
        /// The capture's file.
        source_name: String,
        /// Why.
        reason: String,
    },
    /// HID enumeration or opening failed.
    #[error("HID: {0}")]
    Hid(#[from] hidapi::HidError),
    /// The haptic thread stalled and the watchdog ramped the force to zero.
    #[error(
        "the haptic thread stalled for {stall:?} before tick {tick}; the watchdog ramped the force to zero"
    )]
    WatchdogTripped {
        /// The first tick after the stall.
        tick: u64,
        /// How long the loop was silent.
        stall: Duration,
    },
    /// The haptic thread stalled more often than a run survives; each time the force was
    /// ramped to zero.
    #[error(
        "the haptic thread stalled {stalls} times within {within:?} (the last before tick {tick}); the force was ramped to zero"
    )]
    RepeatedStalls {
        /// Stalls within the window, the last one included.
        stalls: u32,
        /// The window they were counted over.
        within: Duration,
        /// The first tick after the last stall.
        tick: u64,
    },
    /// The configured loop rate is unusable.
    #[error("loop rate {0} Hz is not in (0, 100000]")]
    BadRate(f64),
    /// A thread could not be started.
    #[error("cannot start the {thread} thread")]
    Spawn {
        /// Which (`haptic`, `watchdog`, `recorder`, `pedal`).
        thread: &'static str,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A thread panicked (a bug); what it owned was dropped with it.
    #[error("the {thread} thread panicked")]
    Panicked {
        /// Which (`haptic`, `recorder`).
        thread: &'static str,
    },
    /// A file or folder could not be created or written.
    #[error("cannot {action} {}", path.display())]
    Io {
        /// What was being done (`create`, `write`).
        action: &'static str,
        /// The path that failed.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A finished recording could not be renamed over its target; it is kept whole under its
    /// partial name and the target is as it was.
    #[error("the recording is in {} but could not replace {}", partial.display(), target.display())]
    RecordingNotPlaced {
        /// The finished recording.
        partial: PathBuf,
        /// The file it was to replace.
        target: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The simulated world or one of its protocols refused a setting or could not write.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// No registered device backend has this name, or its option is missing or unwanted.
    #[error("device `{given}`: {reason} (expected one of: {expected})")]
    UnknownDevice {
        /// What was asked for (at most 200 characters of it).
        given: String,
        /// What is wrong with it.
        reason: String,
        /// The registered devices, comma-separated.
        expected: String,
    },
    /// No simulated surface has this name.
    #[error("unknown surface `{name}` (expected one of: {expected})")]
    UnknownSurface {
        /// The name asked for.
        name: String,
        /// The known names, comma-separated.
        expected: String,
    },
    /// Only a recognizer over Nakano's rubbing features, per window, runs live.
    #[error(
        "a {method} recognizer over {features} features cannot run live: only a som, k-NN or svm \
         over windows of nakano features, or a k-NN or svm over windows of nakano_spectrum features \
         decided at their last sample, decides from the rubbing stream"
    )]
    LiveMethod {
        /// The recognizer's method.
        method: &'static str,
        /// Its features (`nakano`, `spectral`, `both`).
        features: &'static str,
    },
    /// A decision threshold was given for a recognizer without a posterior to hold it to.
    #[error(
        "a {method} recognizer names a surface per window and has no posterior to threshold: a \
         threshold needs a k-NN or svm over windows"
    )]
    LiveThreshold {
        /// The recognizer's method.
        method: &'static str,
    },
    /// The loop's rate is not the rate the recognizer's windows are counted at.
    #[error("the loop runs at {loop_hz} Hz but the recognizer's windows are counted at {model_hz} Hz")]
    LiveRate {
        /// The loop's rate, Hz.
        loop_hz: f64,
        /// The recognizer's rate, Hz.
        model_hz: f64,
    },
    /// A recognizer cannot be fused into a live Nakano recognizer.
    #[error("recognizer {index} ({method} over {features} windows) cannot be fused live: {reason}")]
    LiveFusion {
        /// Its index among those fused (0: the Nakano recognizer).
        index: usize,
        /// Its method.
        method: &'static str,
        /// Its features.
        features: &'static str,
        /// Why.
        reason: &'static str,
    },
    /// A recognizer that fuses a vibration sense was fed a sample without one.
    #[error(
        "this live recognizer fuses {senses} vibration recognizer(s): every sample needs the tool's vibration"
    )]
    VibrationNeeded {
        /// Vibration recognizers fused.
        senses: usize,
    },
    /// A live vibration sample was NaN or infinite; the stroke starts afresh from the next one.
    #[error("non-finite vibration sample ({vibration_mps2} m/s²)")]
    NotFiniteVibration {
        /// The sample, m/s².
        vibration_mps2: f64,
    },
    /// A live sample was NaN or infinite; the stroke starts afresh from the next one.
    #[error("non-finite sample (position {position_m} m, height {height_m} m, friction {friction_n} N)")]
    NotFiniteSample {
        /// Position along the rubbing direction, m.
        position_m: f64,
        /// Height, m.
        height_m: f64,
        /// Friction, N.
        friction_n: f64,
    },
    /// A model file models something other than what the force law needs.
    #[error("a {found} model cannot drive this law (it needs a {expected} model)")]
    WrongModelKind {
        /// What the law needs.
        expected: ModelKind,
        /// What the file holds.
        found: ModelKind,
    },
    /// A model's input box has corners that are not finite or not ordered.
    #[error("input box dimension {dimension}: [{lo}, {hi}] is not a finite, ordered range")]
    BadInputBox {
        /// Which input.
        dimension: usize,
        /// Its lower bound.
        lo: f64,
        /// Its upper bound.
        hi: f64,
    },
    /// A capture could not be read, validated or written.
    #[error(transparent)]
    Capture(#[from] CaptureError),
    /// An SVR could not be put on the fast path.
    #[error(transparent)]
    Svm(#[from] SvmError),
    /// A model file could not be used.
    #[error(transparent)]
    Identify(#[from] IdentifyError),
    /// The recognizer (its feature stream or its map) refused.
    #[error(transparent)]
    Recognize(#[from] RecognizeError),
}

/// What ended a haptic run before its end, as far as the operator must know: the watchdog
/// released the force, or the device failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EndCause {
    /// The haptic thread stalled ([`HapticsError::WatchdogTripped`],
    /// [`HapticsError::RepeatedStalls`]).
    Watchdog,
    /// The device failed, faulted or was closed under the loop.
    Device,
}

/// How a run ended early: what failed, in words, and the cause the exit code reports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EarlyEnd {
    /// The error that ended the run.
    pub message: String,
    /// Its cause, where it is one the operator must act on.
    pub cause: Option<EndCause>,
}

impl From<&HapticsError> for EarlyEnd {
    fn from(e: &HapticsError) -> Self {
        Self {
            message: e.to_string(),
            cause: e.end_cause(),
        }
    }
}

impl fmt::Display for EarlyEnd {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl HapticsError {
    /// What this error says about the end of a run, when it ended one.
    pub fn end_cause(&self) -> Option<EndCause> {
        match self {
            Self::WatchdogTripped { .. } | Self::RepeatedStalls { .. } => Some(EndCause::Watchdog),
            Self::DeviceCall { .. } | Self::DeviceFault { .. } | Self::DeviceClosed { .. } => {
                Some(EndCause::Device)
            }
            _ => None,
        }
    }

    /// Whether this is the orderly end of a finite device (a replay), not a failure.
    pub fn is_end_of_stream(&self) -> bool {
        matches!(self, HapticsError::EndOfReplay)
    }

    /// The same failure, marked as met by the loop at tick `at` (after which the loop sent zero
    /// force). Moves data only, so the haptic thread can call it without allocating; failures
    /// that carry no tick are returned unchanged.
    pub fn in_loop_at(mut self, at: u64) -> Self {
        if let HapticsError::DeviceCall { tick, .. }
        | HapticsError::DeviceFault { tick, .. }
        | HapticsError::DeviceClosed { tick } = &mut self
        {
            *tick = Some(at);
        }
        self
    }
}

/// The tail of a device failure's message: where the loop met it, without allocating.
struct InLoop(Option<u64>);

impl fmt::Display for InLoop {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(tick) => write!(f, " at loop tick {tick}; force set to zero"),
            None => Ok(()),
        }
    }
}
