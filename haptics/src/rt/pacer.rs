//! Absolute-deadline pacing: sleep most of the period, spin the rest.
//!
//! Deadlines are `start + k·period`, never "now + period", so a late tick does not shift every
//! later one and the mean rate stays exact. A tick that misses whole periods skips them instead
//! of bursting to catch up: a haptic device wants evenly spaced commands, not a volley.

use std::time::{Duration, Instant};

/// How the loop waits between ticks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pacing {
    /// Real time: absolute deadlines every period.
    Realtime {
        /// How long before each deadline to stop sleeping and spin. The OS wakes a sleeping
        /// thread late by tens of microseconds (more under load); spinning the last stretch
        /// buys punctuality for that much CPU per tick.
        spin: Duration,
    },
    /// No waiting: each tick starts when the previous one ends. For simulated devices only,
    /// whose clock is the tick count (captures and tests faster than real time).
    Unpaced,
}

impl Pacing {
    /// Real time with a 200 µs spin.
    pub const REALTIME: Pacing = Pacing::Realtime {
        spin: Duration::from_micros(200),
    };
}

/// When one tick woke up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Wake {
    /// The wake-up instant.
    pub at: Instant,
    /// How late it was against its deadline.
    pub late: Duration,
    /// Deadlines skipped because this tick woke after them.
    pub skipped: u64,
}

/// Keeps absolute deadlines.
#[derive(Debug, Clone)]
pub struct Pacer {
    period: Duration,
    pacing: Pacing,
    next: Instant,
}

impl Pacer {
    /// A pacer whose first deadline is `start`.
    pub fn new(period: Duration, pacing: Pacing, start: Instant) -> Self {
        Self {
            period,
            pacing,
            next: start,
        }
    }

    /// Waits for the next deadline and schedules the one after it.
    pub fn wait(&mut self) -> Wake {
        let deadline = self.next;
        match self.pacing {
            Pacing::Unpaced => {
                let at = Instant::now();
                self.next = at;
                return Wake {
                    at,
                    late: Duration::ZERO,
                    skipped: 0,
                };
            }
            Pacing::Realtime { spin } => {
                let now = Instant::now();
                if let Some(ahead) = deadline.checked_duration_since(now)
                    && ahead > spin
                {
                    std::thread::sleep(ahead - spin);
                }
                while Instant::now() < deadline {
                    std::hint::spin_loop();
                }
            }
        }
        let at = Instant::now();
        let late = at.saturating_duration_since(deadline);
        let mut skipped = 0;
        self.next = deadline + self.period;
        if at >= self.next && !self.period.is_zero() {
            // Missed one or more whole periods: resume at the first deadline still ahead.
            let behind = at.duration_since(self.next);
            let periods = behind.as_nanos() / self.period.as_nanos() + 1;
            skipped = u64::try_from(periods).unwrap_or(u64::MAX);
            self.next += self.period * u32::try_from(periods).unwrap_or(u32::MAX);
        }
        Wake { at, late, skipped }
    }

    /// The nominal period.
    pub fn period(&self) -> Duration {
        self.period
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deadlines_are_absolute_and_missed_ones_are_skipped() {
        let period = Duration::from_millis(2);
        let start = Instant::now();
        let mut p = Pacer::new(period, Pacing::REALTIME, start);
        let w = p.wait();
        assert!(w.at >= start);
        // A tick that overslept by 3.5 periods skips the deadlines it missed.
        std::thread::sleep(period * 4);
        let w = p.wait();
        assert!(w.skipped >= 3, "{w:?}");
        let next = p.next;
        assert!(next > w.at && next <= w.at + period);
        // The grid stays the same: deadlines are start + k·period.
        let k = next.duration_since(start).as_nanos() % period.as_nanos();
        assert_eq!(k, 0);
    }

    #[test]
    fn unpaced_never_waits() {
        // Its first deadline an hour away and then every 10 s: a pacer that waited for a
        // deadline would wake after it.
        let start = Instant::now() + Duration::from_secs(3600);
        let mut p = Pacer::new(Duration::from_secs(10), Pacing::Unpaced, start);
        for _ in 0..1000 {
            let w = p.wait();
            assert!(w.at < start && w.late.is_zero() && w.skipped == 0, "{w:?}");
        }
    }
}
