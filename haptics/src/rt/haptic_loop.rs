//! The haptic loop: read device → controller (observers, models, admittance) → safety → write
//! force → hand the sample to the recorder and the live view.
//!
//! [`run`] is the loop itself, on the calling thread; [`spawn`] runs it on a thread of its own
//! with a watchdog beside it. Inside a tick nothing allocates, locks, logs or touches a file:
//! samples leave through a bounded SPSC ring (`rtrb`, dropped and counted when full, never
//! waited on) and the newest state through a triple buffer (`triple_buffer`, the reader never
//! blocks the writer), and all statistics are atomics ([`RateMonitor`]).
//!
//! A stall (a tick starting more than [`WatchdogConfig::stall`] after the one before) does not
//! end the run: the watchdog has held the force down meanwhile, the loop commands zero on the
//! tick after it and ramps back over [`WatchdogConfig::recover`], and the stall is counted
//! ([`RateStats::stalls`]). Only the rules of [`WatchdogConfig`] end a run on stalls.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::monitor::{RateMonitor, RateStats};
use super::pacer::{Pacer, Pacing};
use super::sched::{self, RtRequest, RtStatus};
use super::stall::{StallEnd, StallGuard, StallVerdict};
use super::watchdog::{Heartbeat, Watchdog, WatchdogConfig};
use crate::device::{DeviceSpecs, DeviceState, ForceCommand, HapticDevice};
use crate::error::HapticsError;
use crate::safety::{self, SafetyFilter};

/// Controller-defined values carried with each sample (estimated forces, model outputs, …):
/// eight for a controller, four more for a controller that wraps it (the live surface
/// recognizer's decisions).
pub const CHANNELS: usize = 12;

/// One tick, as recorded and shown live.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct HapticSample {
    /// Tick number from 0.
    pub tick: u64,
    /// Loop time, `tick · period`, s.
    pub time_s: f64,
    /// What the device reported.
    pub state: DeviceState,
    /// What was sent to the device, after the safety filter.
    pub command: ForceCommand,
    /// Controller-defined values; their meaning is the controller's (see its docs).
    pub channels: [f64; CHANNELS],
    /// Safety and model flags ([`crate::safety::flag`]).
    pub flags: u32,
}

/// What a controller sees each tick.
#[derive(Debug, Clone, Copy)]
pub struct TickInput<'a> {
    /// Tick number from 0.
    pub tick: u64,
    /// Loop time, s.
    pub time_s: f64,
    /// Nominal period, s.
    pub period_s: f64,
    /// The device's state this tick.
    pub state: &'a DeviceState,
    /// The command actually sent last tick (after safety), e.g. for a disturbance observer.
    pub applied: &'a ForceCommand,
    /// The device's limits and its mechanism's own forces (what an observer removes).
    pub specs: &'a DeviceSpecs,
}

/// What a controller returns each tick.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TickOutput {
    /// Force to command (the safety filter follows).
    pub command: ForceCommand,
    /// Values to record (see [`HapticSample::channels`]).
    pub channels: [f64; CHANNELS],
    /// Flags to record ([`crate::safety::flag`]).
    pub flags: u32,
}

/// The per-tick computation. Runs on the haptic thread: it must not allocate, lock, log or do
/// I/O.
pub trait Controller: Send {
    /// Computes this tick's command.
    fn tick(&mut self, input: &TickInput<'_>, output: &mut TickOutput);

    /// True when a scripted controller (a capture protocol) is done; the loop then stops.
    fn finished(&self) -> bool {
        false
    }
}

impl<C: Controller + ?Sized> Controller for Box<C> {
    fn tick(&mut self, input: &TickInput<'_>, output: &mut TickOutput) {
        (**self).tick(input, output);
    }
    fn finished(&self) -> bool {
        (**self).finished()
    }
}

/// A controller that commands no force (device read-out, replay, benchmarks of the bare loop).
#[derive(Debug, Clone, Copy, Default)]
pub struct ZeroForce;

impl Controller for ZeroForce {
    fn tick(&mut self, _: &TickInput<'_>, output: &mut TickOutput) {
        output.command = ForceCommand::ZERO;
    }
}

/// How the loop runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopConfig {
    /// Tick rate, Hz.
    pub rate_hz: f64,
    /// Real-time deadlines, or as fast as possible for simulated devices.
    pub pacing: Pacing,
    /// Real-time scheduling to ask for.
    pub rt: RtRequest,
    /// Watchdog and stall rules, or None (unpaced runs of a simulator; benchmarks that
    /// measure stalls without acting on them): stalls of a paced loop are then still counted
    /// against the default bound, but the force is left alone and no stall ends the run.
    pub watchdog: Option<WatchdogConfig>,
    /// Stop after this many ticks.
    pub max_ticks: Option<u64>,
}

impl Default for LoopConfig {
    /// 1 kHz, real time, SCHED_FIFO if permitted, watchdog on.
    fn default() -> Self {
        Self {
            rate_hz: 1000.0,
            pacing: Pacing::REALTIME,
            rt: RtRequest::default(),
            watchdog: Some(WatchdogConfig::default()),
            max_ticks: None,
        }
    }
}

impl LoopConfig {
    /// 1 kHz as fast as the machine goes, no real-time scheduling, no watchdog: a run of a
    /// simulated or replayed device, whose clock is the tick count.
    pub fn unpaced() -> Self {
        Self {
            pacing: Pacing::Unpaced,
            rt: RtRequest::NONE,
            watchdog: None,
            ..Self::default()
        }
    }

    /// The period, or an error for a rate that is not a positive finite number up to 100 kHz.
    pub fn period(&self) -> Result<Duration, HapticsError> {
        if self.rate_hz.is_finite() && self.rate_hz > 0.0 && self.rate_hz <= 100_000.0 {
            Ok(Duration::from_secs_f64(1.0 / self.rate_hz))
        } else {
            Err(HapticsError::BadRate(self.rate_hz))
        }
    }
}

/// Where samples go.
#[derive(Default)]
pub struct LoopIo {
    /// To the recorder (bounded SPSC ring).
    pub samples: Option<rtrb::Producer<HapticSample>>,
    /// Newest sample for the UI (triple buffer).
    pub live: Option<triple_buffer::Input<HapticSample>>,
}

impl std::fmt::Debug for LoopIo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LoopIo")
            .field("samples", &self.samples.is_some())
            .field("live", &self.live.is_some())
            .finish()
    }
}

/// State shared between the haptic thread and everyone else; all of it lock-free.
#[derive(Debug)]
pub struct LoopShared {
    /// Timing statistics.
    pub monitor: RateMonitor,
    /// Bumped every tick; watched by the watchdog.
    pub heartbeat: Arc<Heartbeat>,
    stop: AtomicBool,
    rt_status: OnceLock<RtStatus>,
}

impl LoopShared {
    /// Shared state for a loop of this period.
    pub fn new(period: Duration) -> Self {
        Self {
            monitor: RateMonitor::new(period),
            heartbeat: Arc::new(Heartbeat::new()),
            stop: AtomicBool::new(false),
            rt_status: OnceLock::new(),
        }
    }

    /// Asks the loop to stop at its next tick.
    pub fn request_stop(&self) {
        self.stop.store(true, Ordering::Release);
    }

    /// What real-time scheduling the haptic thread got (once it has started).
    pub fn rt_status(&self) -> Option<RtStatus> {
        self.rt_status.get().copied()
    }
}

/// Why the loop ended without error.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// [`LoopShared::request_stop`] was called.
    Requested,
    /// [`LoopConfig::max_ticks`] reached.
    TickLimit,
    /// The controller's script ended.
    ControllerFinished,
    /// The device ran out of data (a replay).
    EndOfStream,
}

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunSummary {
    /// Ticks run.
    pub ticks: u64,
    /// Why it stopped.
    pub reason: StopReason,
    /// Stalls the run went through (see [`WatchdogConfig`]).
    pub stalls: u64,
}

/// Runs the loop on the calling thread until stopped, finished or failed.
///
/// Opens the device's force gate and enables its forces at the start, and sends zero force
/// (and disables forces) at the end, whatever the outcome. Between its first and its last tick
/// this function performs no heap allocation.
///
/// A stall is survived (force to zero, then back over [`WatchdogConfig::recover`]) unless
/// [`WatchdogConfig`]'s rules say otherwise: one stall over `fatal_stall` ends the run with
/// [`HapticsError::WatchdogTripped`], too many within `stall_window` with
/// [`HapticsError::RepeatedStalls`]. An unpaced run has no deadlines, so it has no stalls.
pub fn run<D, C>(
    device: &mut D,
    controller: &mut C,
    io: &mut LoopIo,
    shared: &LoopShared,
    config: &LoopConfig,
) -> Result<RunSummary, HapticsError>
where
    D: HapticDevice + ?Sized,
    C: Controller + ?Sized,
{
    let period = config.period()?;
    let period_s = period.as_secs_f64();
    let status = sched::apply_to_current_thread(&config.rt);
    // Set once per shared state; a second run on the same state keeps the first report.
    let _ = shared.rt_status.set(status);
    let specs = *device.specs();
    let safety = SafetyFilter::new(&specs);
    let monitor = &shared.monitor;
    let heartbeat = &*shared.heartbeat;
    let stall_rules = config.watchdog.unwrap_or_default();
    let mut guard = StallGuard::new(&stall_rules, period, config.watchdog.is_some());
    // An unpaced run without a watchdog is a simulation on the tick clock: nothing is late.
    let watch_stalls = config.watchdog.is_some() || config.pacing != Pacing::Unpaced;
    // The watchdog's trips the loop has taken over. One from an earlier run on the same shared
    // state is over: this run opens the gate below and starts its commands afresh.
    let mut seen_trips = heartbeat.trips();
    heartbeat.acknowledge(seen_trips);

    // A new run starts with the gate open, even after a previous run's watchdog closed it.
    device.force_override().set_force_scale(1.0);
    // The device's own watchdog, where it has one, at the software watchdog's period: a
    // stall of the whole host (which stops the software watchdog too) still releases the force.
    if let Some(w) = config.watchdog
        && let Err(e) = device.arm_watchdog(w.stall)
    {
        safe_stop(device);
        return Err(e.in_loop_at(0));
    }
    if let Err(e) = device.enable_forces(true) {
        safe_stop(device);
        return Err(e.in_loop_at(0));
    }
    let mut pacer = Pacer::new(period, config.pacing, Instant::now());
    let mut applied = ForceCommand::ZERO;
    let mut previous_wake: Option<Instant> = None;
    let mut tick = 0u64;
    let mut out = TickOutput::default();
    let reason = loop {
        if shared.stop.load(Ordering::Acquire) {
            break StopReason::Requested;
        }
        if config.max_ticks.is_some_and(|max| tick >= max) {
            break StopReason::TickLimit;
        }
        if controller.finished() {
            break StopReason::ControllerFinished;
        }
        let wake = pacer.wait();
        let woke_ns = heartbeat.at_ns(wake.at);
        let gap_ns = previous_wake.map(|p| wake.at.duration_since(p).as_nanos() as u64);
        heartbeat.beat(wake.at);
        monitor.record_wake(woke_ns, wake.late.as_nanos() as u64, wake.skipped, gap_ns);
        previous_wake = Some(wake.at);
        // Read after the beat: a trip counted from here on is one this tick has not answered.
        let trips = heartbeat.trips();
        if watch_stalls {
            match guard.on_tick(woke_ns, gap_ns, trips != seen_trips) {
                Ok(StallVerdict::Running) => {}
                Ok(StallVerdict::Stalled(stall)) => monitor.record_stall(stall),
                Err(end) => {
                    monitor.record_stall(Duration::from_nanos(gap_ns.unwrap_or(0)));
                    safe_stop(device);
                    return Err(match end {
                        StallEnd::TooLong { stall } => HapticsError::WatchdogTripped { tick, stall },
                        StallEnd::TooMany { stalls, within } => {
                            HapticsError::RepeatedStalls { stalls, within, tick }
                        }
                    });
                }
            }
        }

        let state = match device.read_state() {
            Ok(s) => s,
            Err(e) if e.is_end_of_stream() => break StopReason::EndOfStream,
            Err(e) => {
                safe_stop(device);
                return Err(e.in_loop_at(tick));
            }
        };
        let time_s = tick as f64 * period_s;
        let input = TickInput {
            tick,
            time_s,
            period_s,
            state: &state,
            applied: &applied,
            specs: &specs,
        };
        out.flags = 0;
        controller.tick(&input, &mut out);
        let (command, mut safety_flags) = safety.apply(&out.command);
        let command = if guard.recovering() {
            safety_flags |= safety::flag::STALL_RECOVERY;
            safety::scale_command(&command, guard.scale())
        } else {
            command
        };
        if let Err(e) = device.command(&command) {
            safe_stop(device);
            return Err(e.in_loop_at(tick));
        }
        if watch_stalls && trips != seen_trips {
            // This tick's command went out at the ramp's start: the gate may open again.
            heartbeat.acknowledge(trips);
            seen_trips = trips;
        }
        applied = command;
        let sample = HapticSample {
            tick,
            time_s,
            state,
            command,
            channels: out.channels,
            flags: out.flags | safety_flags,
        };
        if let Some(ring) = io.samples.as_mut() {
            let mut pending = ring.push(sample);
            // Unpaced runs are simulations with no deadline to keep: wait for the recorder
            // instead of losing samples. Real-time runs never wait.
            while config.pacing == Pacing::Unpaced && pending.is_err() && !ring.is_abandoned() {
                std::thread::yield_now();
                pending = ring.push(sample);
            }
            if pending.is_err() {
                monitor.record_dropped_sample();
            }
        }
        if let Some(live) = io.live.as_mut() {
            live.write(sample);
        }
        monitor.record_flags(sample.flags);
        monitor.record_compute(wake.at.elapsed().as_nanos() as u64);
        tick += 1;
    };
    safe_stop(device);
    Ok(RunSummary {
        ticks: tick,
        reason,
        stalls: guard.stalls(),
    })
}

/// Zero force, forces off; errors are ignored because this is already the way out.
fn safe_stop<D: HapticDevice + ?Sized>(device: &mut D) {
    let _ = device.command(&ForceCommand::ZERO);
    let _ = device.enable_forces(false);
}

/// What a finished haptic thread hands back.
#[derive(Debug)]
pub struct LoopOutcome<D, C> {
    /// The device, forces off.
    pub device: D,
    /// The controller, with its final state.
    pub controller: C,
    /// The loop's sample outputs (the ring's producer is dropped when this is, which tells the
    /// recorder the run is over).
    pub io: LoopIo,
    /// How the run ended.
    pub result: Result<RunSummary, HapticsError>,
}

/// A loop running on its own thread.
#[derive(Debug)]
pub struct LoopHandle<D, C> {
    shared: Arc<LoopShared>,
    thread: JoinHandle<LoopOutcome<D, C>>,
    watchdog: Option<Watchdog>,
}

/// Starts the loop on a thread named `haptic`, with a watchdog if configured.
pub fn spawn<D, C>(
    device: D,
    controller: C,
    io: LoopIo,
    config: LoopConfig,
) -> Result<LoopHandle<D, C>, HapticsError>
where
    D: HapticDevice + 'static,
    C: Controller + 'static,
{
    let shared = Arc::new(LoopShared::new(config.period()?));
    let watchdog = match config.watchdog {
        Some(w) => Some(
            Watchdog::spawn(w, shared.heartbeat.clone(), device.force_override()).map_err(|source| {
                HapticsError::Spawn {
                    thread: "watchdog",
                    source,
                }
            })?,
        ),
        None => None,
    };
    let thread_shared = shared.clone();
    let thread = std::thread::Builder::new()
        .name("haptic".into())
        .spawn(move || {
            let (mut device, mut controller, mut io) = (device, controller, io);
            let result = run(&mut device, &mut controller, &mut io, &thread_shared, &config);
            LoopOutcome {
                device,
                controller,
                io,
                result,
            }
        })
        .map_err(|source| HapticsError::Spawn {
            thread: "haptic",
            source,
        })?;
    Ok(LoopHandle {
        shared,
        thread,
        watchdog,
    })
}

impl<D, C> LoopHandle<D, C> {
    /// The lock-free shared state (monitor, heartbeat).
    pub fn shared(&self) -> &Arc<LoopShared> {
        &self.shared
    }

    /// Timing statistics so far.
    pub fn stats(&self) -> RateStats {
        self.shared.monitor.snapshot()
    }

    /// Asks the loop to stop at its next tick.
    pub fn stop(&self) {
        self.shared.request_stop();
    }

    /// Whether the haptic thread has ended.
    pub fn is_finished(&self) -> bool {
        self.thread.is_finished()
    }

    /// Waits for the loop to end, then stops the watchdog.
    pub fn join(mut self) -> Result<LoopOutcome<D, C>, HapticsError> {
        let outcome = self
            .thread
            .join()
            .map_err(|_| HapticsError::Panicked { thread: "haptic" });
        if let Some(w) = self.watchdog.take() {
            w.stop();
        }
        outcome
    }
}
