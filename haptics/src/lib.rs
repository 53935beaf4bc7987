//! The haptic side of palpus: devices, the 1 kHz loop, control, force laws, the recorder and the
//! live recognizer. The simulated world they are tested against is the `sim` crate.
//!
//! May import `capture` (the data contract), `svm`, `identify`, `recognize` and `sim`, each through its
//! door (what its `lib.rs` re-exports), and no other palpus crate; only the binary imports
//! haptics. Threads with timing duties (haptic loop, watchdog, recorder) start here.
//!
//! - [`device`]: one small device interface (CHAI3D's) with its force gate, a simulated
//!   Omega.7, the real one through the vendor SDK, capture replay, HID pedals;
//! - [`rt`]: absolute-deadline pacing, real-time scheduling, the rate monitor, the watchdog and
//!   the loop itself (allocation-free per tick); it imports only `device`, `safety` and `error`;
//! - [`control`]: DOB and RFOB (Nakano ch. 2), PD + DOB motion control, admittance rendering
//!   (Li & Bi Fig. 11), the rubbing controller (Nakano Table 3.1);
//! - [`law`]: force laws over identified models (needle puncture, hard and soft friction);
//! - [`safety`]: force limits, the NaN guard;
//! - [`live_recognizer`]: the live surface recognizer (Nakano's SOM on the rubbing stream);
//! - [`recorder`]: samples to capture files through a lock-free ring;
//! - [`live`]: a window's view of a running loop (triple buffers and a bounded ring);
//! - [`acquire`]: the protocols `palpus capture` runs through a device;
//! - [`bench`](mod@bench): the loop benchmark (`palpus bench loop`), the full haptic path wired together;
//! - [`error`]: [`HapticsError`], every failure of the above as one type, wrapping the lower
//!   crates' errors; the variants the haptic thread can meet carry no heap data.

// The haptic thread reports failures through `HapticsError` (a device fault, a non-finite
// sample, the recognizer's map refusing a vector): boxing the lower crates' errors inside it to
// make it smaller would make those reports allocate.
#![allow(clippy::result_large_err)]

pub mod acquire;
pub mod bench;
pub mod control;
pub mod device;
pub mod error;
pub mod law;
pub mod live;
pub mod live_recognizer;
pub mod recorder;
pub mod rt;
pub mod safety;

pub use device::{
    DeviceSpecs, DeviceState, ForceCommand, ForceGate, ForceOverride, HapticDevice, HardwareWatchdog,
    InternalForces,
};
pub use error::{EarlyEnd, EndCause, HapticsError};
pub use rt::{Controller, HapticSample, LoopConfig, LoopHandle, RateStats, TickInput, TickOutput};
pub use safety::SafetyFilter;
