//! The real-time side: pacing, scheduling, the rate monitor, the watchdog and the loop.

mod haptic_loop;
mod monitor;
mod pacer;
mod sched;
mod stall;
mod watchdog;

pub use haptic_loop::{
    CHANNELS, Controller, HapticSample, LoopConfig, LoopHandle, LoopIo, LoopOutcome, LoopShared, RunSummary,
    StopReason, TickInput, TickOutput, ZeroForce, run, spawn,
};
pub use monitor::{Percentiles, RateMonitor, RateStats};
pub use pacer::{Pacer, Pacing};
pub use sched::{PinRequest, Pinning, Priority, RtRequest, RtStatus, core_count};
pub use stall::{StallEnd, StallGuard, StallVerdict};
pub use watchdog::{Heartbeat, Watchdog, WatchdogConfig};
