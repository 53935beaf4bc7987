//! What the loop does after a stall: take the force away at once, give it back slowly, and end
//! the run only when stalls say the machine cannot keep the loop going.
//!
//! A stall is a tick that starts more than [`WatchdogConfig::stall`] after the previous one. The
//! watchdog has already scaled the force down while the loop was silent (see
//! [`super::watchdog`]); on the first tick after the stall the loop commands zero itself and
//! then ramps its commands back to full over [`WatchdogConfig::recover`]. The device state the
//! controller sees after a stall is not the one its last command was computed from, so the
//! force comes back gradually, not as a step the operator would feel as a kick.
//!
//! Everything here is plain data owned by the haptic thread: no allocation, no lock.

use std::time::Duration;

use super::watchdog::WatchdogConfig;

/// How many recent stall times are kept; bounds [`WatchdogConfig::max_stalls`].
const RECENT: usize = 32;

/// Why stalls end a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StallEnd {
    /// One stall was longer than [`WatchdogConfig::fatal_stall`].
    TooLong {
        /// How long the loop was silent.
        stall: Duration,
    },
    /// More than [`WatchdogConfig::max_stalls`] stalls within [`WatchdogConfig::stall_window`].
    TooMany {
        /// Stalls within the window, this one included.
        stalls: u32,
        /// The window.
        within: Duration,
    },
}

/// What one tick's start says.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StallVerdict {
    /// On time (or a late tick short of a stall).
    Running,
    /// The loop was silent this long; the force is ramped from zero again.
    Stalled(Duration),
}

/// The haptic thread's stall state: the recovery ramp and the recent stalls.
#[derive(Debug, Clone)]
pub struct StallGuard {
    detect_ns: u64,
    fatal_ns: u64,
    window_ns: u64,
    max_stalls: usize,
    /// Force scale added per tick while recovering.
    step: f64,
    /// Factor on this tick's command, 0–1.
    scale: f64,
    /// Loop-clock times of the most recent stalls (a ring).
    recent: [u64; RECENT],
    stalls: u64,
    /// Whether the run ramps and ends on stalls, or only counts them.
    acting: bool,
}

impl StallGuard {
    /// A guard for a loop of `period` under `config`. With `acting` false (a loop run without a
    /// watchdog) stalls are only detected and counted: the force is left alone and the run
    /// never ends because of them.
    pub fn new(config: &WatchdogConfig, period: Duration, acting: bool) -> Self {
        let ns = |d: Duration| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX);
        let step = if config.recover > period && !period.is_zero() {
            period.as_secs_f64() / config.recover.as_secs_f64()
        } else {
            1.0
        };
        Self {
            detect_ns: ns(config.stall),
            // A stall the watchdog does not see as one cannot be fatal.
            fatal_ns: ns(config.fatal_stall.max(config.stall)),
            window_ns: ns(config.stall_window),
            max_stalls: (config.max_stalls as usize).min(RECENT - 1),
            step,
            scale: 1.0,
            recent: [0; RECENT],
            stalls: 0,
            acting,
        }
    }

    /// A tick starts at `now_ns` on the loop's clock, `gap_ns` after the previous one (None
    /// for the first tick). `tripped` says the watchdog scaled the force down since the loop
    /// last looked, which restarts the ramp even when the gap alone is short of a stall.
    ///
    /// Sets this tick's [`StallGuard::scale`]; an error when the rules end the run.
    pub fn on_tick(
        &mut self,
        now_ns: u64,
        gap_ns: Option<u64>,
        tripped: bool,
    ) -> Result<StallVerdict, StallEnd> {
        let gap = gap_ns.unwrap_or(0);
        if gap <= self.detect_ns {
            if self.acting {
                self.scale = if tripped {
                    0.0
                } else {
                    (self.scale + self.step).min(1.0)
                };
            }
            return Ok(StallVerdict::Running);
        }
        let stall = Duration::from_nanos(gap);
        self.recent[(self.stalls % RECENT as u64) as usize] = now_ns;
        self.stalls += 1;
        if self.acting {
            self.scale = 0.0;
            if gap > self.fatal_ns {
                return Err(StallEnd::TooLong { stall });
            }
            let stalls = self.stalls_within_window(now_ns);
            if stalls > self.max_stalls as u32 {
                return Err(StallEnd::TooMany {
                    stalls,
                    within: Duration::from_nanos(self.window_ns),
                });
            }
        }
        Ok(StallVerdict::Stalled(stall))
    }

    /// Stalls (this one included) no older than the window, counting no further back than
    /// one more than the rule allows.
    fn stalls_within_window(&self, now_ns: u64) -> u32 {
        let kept = self.stalls.min((self.max_stalls + 1) as u64);
        let mut n = 0;
        for back in 0..kept {
            let at = self.recent[((self.stalls - 1 - back) % RECENT as u64) as usize];
            if now_ns.saturating_sub(at) <= self.window_ns {
                n += 1;
            }
        }
        n
    }

    /// The factor on this tick's command: 0 on the tick after a stall, back to 1 over the
    /// recovery time.
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// Whether this tick's command is held below what the controller asked for.
    pub fn recovering(&self) -> bool {
        self.scale < 1.0
    }

    /// Stalls so far.
    pub fn stalls(&self) -> u64 {
        self.stalls
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: u64 = 1_000_000;

    fn guard() -> StallGuard {
        StallGuard::new(&WatchdogConfig::default(), Duration::from_millis(1), true)
    }

    /// Ticks on time from `from` for `n` ticks; returns the scales and the next tick's time.
    fn run(g: &mut StallGuard, from: u64, n: u64) -> (Vec<f64>, u64) {
        let mut scales = Vec::new();
        for k in 0..n {
            assert_eq!(
                g.on_tick(from + k * MS, Some(MS), false),
                Ok(StallVerdict::Running)
            );
            scales.push(g.scale());
        }
        (scales, from + n * MS)
    }

    #[test]
    fn a_stall_zeroes_the_force_and_it_returns_over_100_ticks() {
        let mut g = guard();
        assert_eq!(g.on_tick(0, None, false), Ok(StallVerdict::Running));
        let (scales, t) = run(&mut g, MS, 10);
        assert!(scales.iter().all(|&s| s == 1.0));
        // 12 ms of silence: the tick that ends it commands nothing.
        let t = t + 11 * MS;
        assert_eq!(
            g.on_tick(t, Some(12 * MS), false),
            Ok(StallVerdict::Stalled(Duration::from_millis(12)))
        );
        assert_eq!(g.scale(), 0.0);
        assert_eq!(g.stalls(), 1);
        let (scales, _) = run(&mut g, t + MS, 120);
        // Linear, 1 % per tick: full force 100 ticks (100 ms) after the stall, not before.
        for (k, s) in scales.iter().enumerate() {
            let expected = ((k + 1) as f64 / 100.0).min(1.0);
            assert!((s - expected).abs() < 1e-9, "tick {k}: {s}");
        }
        assert!(scales[98] < 1.0 && scales[99] == 1.0);
    }

    #[test]
    fn a_watchdog_trip_restarts_the_ramp_without_counting_a_stall() {
        let mut g = guard();
        run(&mut g, 0, 5);
        assert_eq!(g.on_tick(5 * MS, Some(MS), true), Ok(StallVerdict::Running));
        assert_eq!(g.scale(), 0.0);
        assert_eq!(g.stalls(), 0);
    }

    #[test]
    fn late_ticks_short_of_a_stall_change_nothing() {
        let mut g = guard();
        assert_eq!(g.on_tick(4 * MS, Some(4 * MS), false), Ok(StallVerdict::Running));
        assert_eq!(g.scale(), 1.0);
    }

    #[test]
    fn one_stall_over_100_ms_ends_the_run() {
        let mut g = guard();
        assert_eq!(
            g.on_tick(101 * MS, Some(101 * MS), false),
            Err(StallEnd::TooLong {
                stall: Duration::from_millis(101)
            })
        );
        assert_eq!(g.scale(), 0.0);
        // The same stall within the bound is survived.
        let mut g = guard();
        assert!(g.on_tick(100 * MS, Some(100 * MS), false).is_ok());
    }

    #[test]
    fn more_than_five_stalls_within_a_second_end_the_run_and_five_do_not() {
        let mut g = guard();
        let mut t = 0;
        // Five stalls 150 ms apart: survived.
        for _ in 0..5 {
            t += 150 * MS;
            assert!(matches!(
                g.on_tick(t, Some(10 * MS), false),
                Ok(StallVerdict::Stalled(_))
            ));
        }
        // A sixth within a second of the first ends it.
        t += 150 * MS;
        assert_eq!(
            g.on_tick(t, Some(10 * MS), false),
            Err(StallEnd::TooMany {
                stalls: 6,
                within: Duration::from_secs(1)
            })
        );
        // Stalls spread out further than that go on for ever.
        let mut g = guard();
        for k in 1..=100 {
            assert!(g.on_tick(k * 250 * MS, Some(10 * MS), false).is_ok(), "stall {k}");
        }
        assert_eq!(g.stalls(), 100);
    }

    #[test]
    fn without_a_watchdog_stalls_are_only_counted() {
        let mut g = StallGuard::new(&WatchdogConfig::default(), Duration::from_millis(1), false);
        for k in 1..=10 {
            assert!(g.on_tick(k * 20 * MS, Some(500 * MS), false).is_ok());
            assert_eq!(g.scale(), 1.0);
        }
        assert_eq!(g.stalls(), 10);
    }
}
