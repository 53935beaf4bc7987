//! The watchdog: if the haptic thread stops ticking, force ramps to zero.
//!
//! A stalled haptic thread cannot send commands, so the device would keep applying the last
//! one. The watchdog runs on its own thread, watches the heartbeat the haptic thread bumps each
//! tick, and when a tick is overdue it scales the device's force down through the device's
//! [`ForceOverride`] — a path that does not need the haptic thread. The ramp (rather than a cut)
//! avoids a step the operator would feel as a kick.
//!
//! When ticks resume, the loop takes the force over: it commands zero on its first tick and
//! ramps back itself ([`super::stall`]), and says so by acknowledging the trip. Only then does
//! the watchdog open the gate again, so the gate never lets a command through at full scale
//! that the loop has not already brought down. A stall that ends the run is never
//! acknowledged: the gate stays closed.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crate::device::ForceOverride;

/// Watchdog timing and the stall rules. `stall + ramp + poll` is the worst case from the last
/// tick to zero force.
///
/// The run survives a stall and ends only when one stall is longer than `fatal_stall` or
/// more than `max_stalls` happen within `stall_window`. The defaults and why:
/// - `fatal_stall` 100 ms: the force is already zero 10 ms into any stall, so the bound is not
///   about force during the stall but about what comes after it. After 100 ms the device
///   state the controller holds is no longer the hand's (a hand moving at 0.2 m/s has gone
///   20 mm, the whole depth of a needle insertion), and 100 ms is about where an operator
///   starts to react to the lost force (reaction times are 150–250 ms); giving force back to a
///   hand that has already pushed on would be a surprise, so such a run ends.
/// - `max_stalls` 5 within `stall_window` 1 s: every stall costs its `recover` time (100 ms)
///   of reduced force, so a sixth stall within a second means the force has been below what
///   the model says for most of that second — the rendering is no longer the tissue, and the
///   machine is not keeping 1 kHz. Occasional host stalls (a few per minute on a busy virtual
///   machine) are survived.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WatchdogConfig {
    /// How long after the last tick the watchdog starts ramping; a tick starting later than
    /// this after the previous one is a stall.
    pub stall: Duration,
    /// How long the ramp from full force to zero takes.
    pub ramp: Duration,
    /// How often the watchdog looks.
    pub poll: Duration,
    /// How long the loop takes to bring the force back from zero after a stall.
    pub recover: Duration,
    /// A single stall longer than this ends the run.
    pub fatal_stall: Duration,
    /// More stalls than this within `stall_window` end the run (at most 31 are tracked).
    pub max_stalls: u32,
    /// The window `max_stalls` is counted over.
    pub stall_window: Duration,
}

impl Default for WatchdogConfig {
    /// 4 ms + 5 ms + 0.5 ms: zero force within 10 ms of the last tick, and a margin of four
    /// periods at 1 kHz before a late tick trips it; force back over 100 ms; the run ends on a
    /// stall over 100 ms or on more than 5 stalls within 1 s (see the type's docs for why).
    fn default() -> Self {
        Self {
            stall: Duration::from_millis(4),
            ramp: Duration::from_millis(5),
            poll: Duration::from_micros(500),
            recover: Duration::from_millis(100),
            fatal_stall: Duration::from_millis(100),
            max_stalls: 5,
            stall_window: Duration::from_secs(1),
        }
    }
}

impl WatchdogConfig {
    /// Force scale `elapsed` after the last tick: 1 until `stall`, then a linear ramp that
    /// reaches 0 at `stall + ramp`.
    pub fn scale_after(&self, elapsed: Duration) -> f64 {
        if elapsed <= self.stall {
            return 1.0;
        }
        if self.ramp.is_zero() {
            return 0.0;
        }
        let into_ramp = (elapsed - self.stall).as_secs_f64() / self.ramp.as_secs_f64();
        (1.0 - into_ramp).clamp(0.0, 1.0)
    }

    /// Longest time from the last tick to zero force.
    pub fn worst_case_to_zero(&self) -> Duration {
        self.stall + self.ramp + self.poll
    }
}

/// What the haptic thread bumps every tick, on a clock shared with the watchdog.
#[derive(Debug)]
pub struct Heartbeat {
    epoch: Instant,
    last_ns: AtomicU64,
    beats: AtomicU64,
    tripped: AtomicBool,
    trips: AtomicU64,
    /// The trip count the loop last took over from (see the module docs).
    acknowledged: AtomicU64,
    /// How late the tick that tripped the watchdog was, ns (the largest stall seen).
    stall_ns: AtomicU64,
}

impl Heartbeat {
    /// A heartbeat whose clock starts now.
    pub fn new() -> Self {
        Self {
            epoch: Instant::now(),
            last_ns: AtomicU64::new(0),
            beats: AtomicU64::new(0),
            tripped: AtomicBool::new(false),
            trips: AtomicU64::new(0),
            acknowledged: AtomicU64::new(0),
            stall_ns: AtomicU64::new(0),
        }
    }

    /// Nanoseconds since the heartbeat's epoch.
    pub fn now_ns(&self) -> u64 {
        self.at_ns(Instant::now())
    }

    pub(crate) fn at_ns(&self, t: Instant) -> u64 {
        u64::try_from(t.saturating_duration_since(self.epoch).as_nanos()).unwrap_or(u64::MAX)
    }

    /// One tick happened at `at`.
    pub fn beat(&self, at: Instant) {
        self.last_ns.store(self.at_ns(at), Ordering::Release);
        self.beats.fetch_add(1, Ordering::Relaxed);
    }

    /// Ticks so far.
    pub fn beats(&self) -> u64 {
        self.beats.load(Ordering::Relaxed)
    }

    /// Whether the watchdog is holding the force down (a stall the loop has not taken over).
    pub fn tripped(&self) -> bool {
        self.tripped.load(Ordering::Acquire)
    }

    /// How many times the watchdog tripped.
    pub fn trips(&self) -> u64 {
        self.trips.load(Ordering::Acquire)
    }

    /// The loop has commanded zero after trip number `trips` and ramps the force itself from
    /// here; the watchdog may open the gate again.
    pub(crate) fn acknowledge(&self, trips: u64) {
        self.acknowledged.fetch_max(trips, Ordering::Release);
    }

    /// The longest stall the watchdog saw.
    pub fn stall(&self) -> Duration {
        Duration::from_nanos(self.stall_ns.load(Ordering::Relaxed))
    }
}

impl Default for Heartbeat {
    fn default() -> Self {
        Self::new()
    }
}

/// A running watchdog thread; stops when dropped or [`Watchdog::stop`]ped.
#[derive(Debug)]
pub struct Watchdog {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Watchdog {
    /// Starts watching `heartbeat`; acts on `output` when it stalls. The watchdog arms itself
    /// at the first beat, so a loop still opening its device is not tripped.
    pub fn spawn(
        config: WatchdogConfig,
        heartbeat: Arc<Heartbeat>,
        output: Arc<dyn ForceOverride>,
    ) -> std::io::Result<Self> {
        let stop = Arc::new(AtomicBool::new(false));
        let stopping = stop.clone();
        let thread = std::thread::Builder::new()
            .name("haptic-watchdog".into())
            .spawn(move || watch(&config, &heartbeat, output.as_ref(), &stopping))?;
        Ok(Self {
            stop,
            thread: Some(thread),
        })
    }

    /// Stops the watchdog thread and waits for it.
    pub fn stop(mut self) {
        self.shutdown();
    }

    fn shutdown(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(t) = self.thread.take() {
            // A panicking watchdog thread has nothing left to clean up.
            let _ = t.join();
        }
    }
}

impl Drop for Watchdog {
    fn drop(&mut self) {
        self.shutdown();
    }
}

fn watch(config: &WatchdogConfig, heartbeat: &Heartbeat, output: &dyn ForceOverride, stop: &AtomicBool) {
    // The watchdog must be as punctual as what it guards; ask for real time too (best effort,
    // one priority above a default haptic thread's).
    super::sched::apply_to_current_thread(&super::sched::RtRequest {
        fifo_priority: Some(81),
        pin: super::sched::PinRequest::None,
    });
    while !stop.load(Ordering::Acquire) {
        std::thread::sleep(config.poll);
        if heartbeat.beats() == 0 {
            continue;
        }
        // The clock first, then the heartbeat: if this thread is preempted between the two
        // reads (a busy or virtualised machine can take it off its core for milliseconds
        // while the haptic thread runs on), the beat read is newer than the clock, never
        // older, so a pause of the watchdog itself is not mistaken for a stall of the loop.
        let now = heartbeat.now_ns();
        let last = heartbeat.last_ns.load(Ordering::Acquire);
        let elapsed = Duration::from_nanos(now.saturating_sub(last));
        if elapsed <= config.stall {
            // Ticking again. Open the gate only once the loop has taken the force down itself
            // (its commands now start from zero), never before: until then the last command
            // at full scale is what the gate would let through.
            if heartbeat.tripped() && heartbeat.acknowledged.load(Ordering::Acquire) >= heartbeat.trips() {
                heartbeat.tripped.store(false, Ordering::Release);
                output.set_force_scale(1.0);
            }
            continue;
        }
        if !heartbeat.tripped() {
            heartbeat.trips.fetch_add(1, Ordering::AcqRel);
            heartbeat.tripped.store(true, Ordering::Release);
        }
        heartbeat
            .stall_ns
            .fetch_max(elapsed.as_nanos() as u64, Ordering::Relaxed);
        // Within one stall the scale only goes down.
        let scale = config.scale_after(elapsed).min(output.force_scale());
        output.set_force_scale(scale);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_reaches_zero_within_10_ms_of_the_last_tick() {
        let c = WatchdogConfig::default();
        assert!(c.worst_case_to_zero() <= Duration::from_millis(10));
        assert_eq!(c.scale_after(Duration::from_millis(1)), 1.0);
        assert_eq!(c.scale_after(c.stall), 1.0);
        let mid = c.scale_after(c.stall + c.ramp / 2);
        assert!((mid - 0.5).abs() < 1e-9, "{mid}");
        assert_eq!(c.scale_after(c.stall + c.ramp), 0.0);
        assert_eq!(c.scale_after(Duration::from_secs(1)), 0.0);
        // Monotone.
        let mut previous = 1.0;
        for us in 0..12_000 {
            let s = c.scale_after(Duration::from_micros(us));
            assert!(s <= previous);
            previous = s;
        }
    }
}
