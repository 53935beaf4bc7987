//! The haptic side of palpus: devices, the 1 kHz loop, control, force laws, the recorder and the
//! live recognizer. The simulated world they are tested against is the `sim` crate.
//!
//! May import `capture` (the data contract), `svm`, `identify`, `recognize` and `sim`, each through its
//! door (what its `lib.rs` re-exports), and no other palpus crate; only the binary imports
//! haptics. Threads with timing duties (haptic loop, watchdog, recorder) start here.
//!
//! This file is the crate's door: other crates name what they use as `haptics::X`; two modules
//! are namespaces of their own, [`rt`] (the 1 kHz loop: `rt::spawn`, `rt::run` and their
//! settings) and [`acquire`] (the protocols `palpus capture` runs through a device), and so are
//! the telemetry layouts of a [`HapticSample`]: [`flag`] (its safety flags) and
//! [`admittance_channel`], [`rubbing_channel`], [`insertion_channel`] and [`recognizer_channel`]
//! (what each controller writes into its channels).
//!
//! Inside: `device` (one small device interface, CHAI3D's, with its force gate and one registry
//! of backends: a simulated Omega.7, the real one through the vendor SDK, capture replay, HID
//! pedals); [`rt`] (absolute-deadline pacing, real-time scheduling, the rate monitor, the
//! watchdog and the loop itself, allocation-free per tick; it imports only `device`, `safety`
//! and `error`); `control` (DOB and RFOB, Nakano ch. 2; PD + DOB motion control; admittance
//! rendering, Li & Bi Fig. 11; the rubbing controller, Nakano Table 3.1); `law` (force laws over
//! identified models: needle puncture, hard and soft friction); `safety` (force limits, the NaN
//! guard); `live_recognizer` (the live surface recognizer); `recorder` (samples to capture files
//! through a lock-free ring); `live` (a window's view of a running loop); `bench` (the loop
//! benchmark, `palpus bench loop`); `error` ([`HapticsError`], every failure of the above as one
//! type; the variants the haptic thread can meet carry no heap data).

// The haptic thread reports failures through `HapticsError` (a device fault, a non-finite
// sample, the recognizer's map refusing a vector): boxing the lower crates' errors inside it to
// make it smaller would make those reports allocate.
#![allow(clippy::result_large_err)]

pub mod acquire;
mod bench;
mod control;
mod device;
mod error;
mod law;
mod live;
mod live_recognizer;
mod recorder;
pub mod rt;
mod safety;

pub use acquire::needle::channel as insertion_channel;
pub use bench::{BenchConfig, BenchReport, insertion_hand, loop_bench};
pub use control::admittance::channel as admittance_channel;
pub use control::rubbing::channel as rubbing_channel;
pub use control::{
    AccelerationControl, Admittance, AdmittanceConfig, Direct, DisturbanceObserver, MotionGains, Observed,
    Observers3, ReactionForceObserver, RubbingController, RubbingPhase, RubbingPlan,
};
pub use device::fault::{FaultPoint, FaultyDevice};
pub use device::hid::{HidInfo, Pedal, PedalMapping, PedalState, list_hid_devices};
pub use device::omega7::{
    DhdLibrary, DhdOverride, FORCE_DIMENSION_VENDOR_ID, LIBRARY_ENV, LIBRARY_NAMES, OMEGA7_INTERNAL, Omega7,
    SdkVersion, UsbDevice, usb_devices,
};
pub use device::replay::ReplayDevice;
pub use device::sim_omega7::{SimOmega7, SimOmega7Config, SimTrace, SimWorld, Texture};
pub use device::{
    BUILTIN, Backend, BackendOption, DeviceChoice, DeviceSpecs, DeviceState, ForceCommand, ForceGate,
    ForceOverride, HapticDevice, HardwareWatchdog, InternalForces, Motion, OpenRequest, OpenedDevice,
    Registry, SimSetup, WATCHDOG_STEP, watchdog_steps,
};
pub use error::{EarlyEnd, EndCause, HapticsError};
pub use law::{
    AxialLaw, Environment, EnvironmentForce, Evaluation, FnModel, FreeSpace, FrictionLaw, FrictionSurface,
    Frictionless, HardFriction, InputBox, NeedleEnvironment, NeedleLaw, NeedleLawConfig, NeedleOutput,
    NeedleQuasiStatic, PhasedNeedleLaw, PunctureState, ScalarModel, SoftFriction, SvrForceModel,
    eval_clamped, hard_contact_model, hard_friction_model, needle_model, soft_contact_models,
    soft_friction_models,
};
pub use live::{LiveFeed, LiveView, RecentSamples, RecentWriter, StatsWriter, channel as live_channel};
pub use live_recognizer::channel as recognizer_channel;
pub use live_recognizer::{
    ChannelDecision, LiveDecision, LiveRecognizer, RUBBING_OBSERVER_CUTOFF_RADPS, SampleRecognizer,
    decision_in,
};
pub use recorder::{
    AnnotateThen, Recorder, RecorderConfig, RecorderStats, RecorderSummary, Recording, RowMap, annotate_then,
    partial_path, read_recording, record_to_file,
};
pub use rt::{Controller, HapticSample, LoopConfig, LoopHandle, RateStats, TickInput, TickOutput};
pub use safety::flag;
pub use safety::{SafetyFilter, SafetyFlags, scale_command};
