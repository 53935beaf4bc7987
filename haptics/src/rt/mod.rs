//! The real-time side: pacing, scheduling, the rate monitor, the watchdog and the loop.

pub mod haptic_loop;
pub mod monitor;
pub mod pacer;
pub mod sched;
pub mod stall;
pub mod watchdog;

pub use haptic_loop::{
    CHANNELS, Controller, HapticSample, LoopConfig, LoopHandle, LoopIo, LoopOutcome, LoopShared, RunSummary,
    StopReason, TickInput, TickOutput, ZeroForce, run, spawn,
};
pub use monitor::{Percentiles, RateMonitor, RateStats};
pub use pacer::{Pacer, Pacing};
pub use sched::{PinRequest, Pinning, Priority, RtRequest, RtStatus};
pub use stall::{StallEnd, StallGuard, StallVerdict};
pub use watchdog::{Heartbeat, Watchdog, WatchdogConfig};
