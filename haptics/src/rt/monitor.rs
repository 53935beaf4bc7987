//! The rate monitor: what the haptic thread's timing looks like, readable from any thread.
//!
//! Everything is a relaxed atomic written by the haptic thread alone, so recording costs a few
//! atomic adds and never blocks; a reader may see a snapshot that is a tick out of date.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

/// Histogram resolution: 1 µs buckets.
const BUCKET_NS: u64 = 1_000;
/// Buckets up to 20 ms; anything longer lands in the last one (its exact value is in `max`).
const BUCKETS: usize = 20_000;

/// A histogram of durations with 1 µs buckets up to 20 ms, and the exact maximum.
#[derive(Debug)]
pub struct Histogram {
    counts: Box<[AtomicU64]>,
    count: AtomicU64,
    max_ns: AtomicU64,
    sum_ns: AtomicU64,
}

impl Default for Histogram {
    fn default() -> Self {
        Self::new()
    }
}

impl Histogram {
    /// An empty histogram.
    pub fn new() -> Self {
        Self {
            counts: (0..BUCKETS).map(|_| AtomicU64::new(0)).collect(),
            count: AtomicU64::new(0),
            max_ns: AtomicU64::new(0),
            sum_ns: AtomicU64::new(0),
        }
    }

    /// Adds one value.
    pub fn record_ns(&self, ns: u64) {
        let bucket = ((ns / BUCKET_NS) as usize).min(BUCKETS - 1);
        self.counts[bucket].fetch_add(1, Ordering::Relaxed);
        self.count.fetch_add(1, Ordering::Relaxed);
        self.sum_ns.fetch_add(ns, Ordering::Relaxed);
        self.max_ns.fetch_max(ns, Ordering::Relaxed);
    }

    /// Number of values.
    pub fn count(&self) -> u64 {
        self.count.load(Ordering::Relaxed)
    }

    /// Largest value.
    pub fn max(&self) -> Duration {
        Duration::from_nanos(self.max_ns.load(Ordering::Relaxed))
    }

    /// Mean value.
    pub fn mean(&self) -> Duration {
        let sum = self.sum_ns.load(Ordering::Relaxed);
        sum.checked_div(self.count())
            .map_or(Duration::ZERO, Duration::from_nanos)
    }

    /// The value below which a fraction `q` (0–1) of the values lie, to the bucket's upper
    /// edge (1 µs), and never above the maximum.
    pub fn quantile(&self, q: f64) -> Duration {
        let n = self.count();
        if n == 0 {
            return Duration::ZERO;
        }
        let rank = ((q.clamp(0.0, 1.0) * n as f64).ceil() as u64).max(1);
        let mut seen = 0;
        for (i, c) in self.counts.iter().enumerate() {
            seen += c.load(Ordering::Relaxed);
            if seen >= rank {
                let edge = Duration::from_nanos((i as u64 + 1) * BUCKET_NS);
                return edge.min(self.max());
            }
        }
        self.max()
    }

    /// How many values were above `threshold` (to bucket resolution).
    pub fn count_above(&self, threshold: Duration) -> u64 {
        let first = (threshold.as_nanos() as u64 / BUCKET_NS) as usize + 1;
        self.counts
            .iter()
            .skip(first)
            .map(|c| c.load(Ordering::Relaxed))
            .sum()
    }

    /// Forgets everything.
    pub fn reset(&self) {
        for c in self.counts.iter() {
            c.store(0, Ordering::Relaxed);
        }
        self.count.store(0, Ordering::Relaxed);
        self.max_ns.store(0, Ordering::Relaxed);
        self.sum_ns.store(0, Ordering::Relaxed);
    }

    fn summary(&self) -> Percentiles {
        Percentiles {
            p50: self.quantile(0.5),
            p99: self.quantile(0.99),
            p999: self.quantile(0.999),
            max: self.max(),
            mean: self.mean(),
        }
    }
}

/// The haptic thread's timing: periods, lateness against the absolute deadlines, compute time
/// per tick, overruns.
#[derive(Debug)]
pub struct RateMonitor {
    nominal_period_ns: u64,
    /// |actual period − nominal period|.
    period_error: Histogram,
    /// Wake-up time minus deadline.
    lateness: Histogram,
    /// Time from wake-up to the end of the tick's work.
    compute: Histogram,
    ticks: AtomicU64,
    overruns: AtomicU64,
    missed_slots: AtomicU64,
    first_tick_ns: AtomicU64,
    last_tick_ns: AtomicU64,
    dropped_samples: AtomicU64,
    safety_events: AtomicU64,
    model_clamps: AtomicU64,
    stalls: AtomicU64,
    longest_stall_ns: AtomicU64,
}

impl RateMonitor {
    /// A monitor for a loop of nominal period `period`.
    pub fn new(period: Duration) -> Self {
        Self {
            nominal_period_ns: period.as_nanos() as u64,
            period_error: Histogram::new(),
            lateness: Histogram::new(),
            compute: Histogram::new(),
            ticks: AtomicU64::new(0),
            overruns: AtomicU64::new(0),
            missed_slots: AtomicU64::new(0),
            first_tick_ns: AtomicU64::new(0),
            last_tick_ns: AtomicU64::new(0),
            dropped_samples: AtomicU64::new(0),
            safety_events: AtomicU64::new(0),
            model_clamps: AtomicU64::new(0),
            stalls: AtomicU64::new(0),
            longest_stall_ns: AtomicU64::new(0),
        }
    }

    /// Nominal period.
    pub fn nominal_period(&self) -> Duration {
        Duration::from_nanos(self.nominal_period_ns)
    }

    /// Records a tick that woke at `woke_ns` (on the loop's clock), `late_ns` after its
    /// deadline, after a period of `period_ns` (None for the first tick), having skipped
    /// `skipped` deadlines it woke after.
    pub(crate) fn record_wake(&self, woke_ns: u64, late_ns: u64, skipped: u64, period_ns: Option<u64>) {
        if self.ticks.fetch_add(1, Ordering::Relaxed) == 0 {
            self.first_tick_ns.store(woke_ns, Ordering::Relaxed);
        }
        self.last_tick_ns.store(woke_ns, Ordering::Relaxed);
        self.lateness.record_ns(late_ns);
        if late_ns > self.nominal_period_ns {
            self.overruns.fetch_add(1, Ordering::Relaxed);
        }
        if skipped > 0 {
            self.missed_slots.fetch_add(skipped, Ordering::Relaxed);
        }
        if let Some(p) = period_ns {
            self.period_error.record_ns(p.abs_diff(self.nominal_period_ns));
        }
    }

    pub(crate) fn record_compute(&self, ns: u64) {
        self.compute.record_ns(ns);
    }

    pub(crate) fn record_dropped_sample(&self) {
        self.dropped_samples.fetch_add(1, Ordering::Relaxed);
    }

    /// Records a stall of this length (the silence between two ticks).
    pub(crate) fn record_stall(&self, stall: Duration) {
        self.stalls.fetch_add(1, Ordering::Relaxed);
        self.longest_stall_ns.fetch_max(
            u64::try_from(stall.as_nanos()).unwrap_or(u64::MAX),
            Ordering::Relaxed,
        );
    }

    pub(crate) fn record_flags(&self, flags: u32) {
        use crate::safety::flag;
        // The ramp after a stall is counted as the stall, not tick by tick as safety events.
        if flags & !(flag::MODEL_INPUT_CLAMPED | flag::STALL_RECOVERY) != 0 {
            self.safety_events.fetch_add(1, Ordering::Relaxed);
        }
        if flags & flag::MODEL_INPUT_CLAMPED != 0 {
            self.model_clamps.fetch_add(1, Ordering::Relaxed);
        }
    }

    /// Ticks so far.
    pub fn ticks(&self) -> u64 {
        self.ticks.load(Ordering::Relaxed)
    }

    /// Forgets the statistics (not the tick count), e.g. after a warm-up.
    pub fn reset_statistics(&self) {
        self.period_error.reset();
        self.lateness.reset();
        self.compute.reset();
        self.overruns.store(0, Ordering::Relaxed);
        self.missed_slots.store(0, Ordering::Relaxed);
        self.ticks.store(0, Ordering::Relaxed);
        self.stalls.store(0, Ordering::Relaxed);
        self.longest_stall_ns.store(0, Ordering::Relaxed);
    }

    /// Everything at once.
    pub fn snapshot(&self) -> RateStats {
        let ticks = self.ticks();
        let span_ns = self
            .last_tick_ns
            .load(Ordering::Relaxed)
            .saturating_sub(self.first_tick_ns.load(Ordering::Relaxed));
        let mean_rate_hz = if ticks > 1 && span_ns > 0 {
            (ticks - 1) as f64 / (span_ns as f64 * 1e-9)
        } else {
            0.0
        };
        RateStats {
            ticks,
            nominal_rate_hz: 1e9 / self.nominal_period_ns.max(1) as f64,
            mean_rate_hz,
            period_error: self.period_error.summary(),
            lateness: self.lateness.summary(),
            compute: self.compute.summary(),
            overruns: self.overruns.load(Ordering::Relaxed),
            missed_slots: self.missed_slots.load(Ordering::Relaxed),
            late_over_2ms: self.lateness.count_above(Duration::from_millis(2)),
            dropped_samples: self.dropped_samples.load(Ordering::Relaxed),
            safety_events: self.safety_events.load(Ordering::Relaxed),
            model_clamps: self.model_clamps.load(Ordering::Relaxed),
            stalls: self.stalls.load(Ordering::Relaxed),
            longest_stall: Duration::from_nanos(self.longest_stall_ns.load(Ordering::Relaxed)),
        }
    }
}

/// Percentiles of one timing quantity.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Percentiles {
    /// Median.
    pub p50: Duration,
    /// 99th percentile.
    pub p99: Duration,
    /// 99.9th percentile.
    pub p999: Duration,
    /// Largest.
    pub max: Duration,
    /// Mean.
    pub mean: Duration,
}

/// A snapshot of [`RateMonitor`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RateStats {
    /// Ticks run.
    pub ticks: u64,
    /// The rate asked for, Hz.
    pub nominal_rate_hz: f64,
    /// Ticks per second between the first and the last tick, Hz.
    pub mean_rate_hz: f64,
    /// |period − nominal period|.
    pub period_error: Percentiles,
    /// Wake-up time minus absolute deadline.
    pub lateness: Percentiles,
    /// Work per tick (device, observers, models, control, safety, hand-offs).
    pub compute: Percentiles,
    /// Ticks that started more than a whole period after their deadline (a missed slot).
    pub overruns: u64,
    /// Deadlines skipped because the tick due at them woke after the next one: force updates
    /// the device never got.
    pub missed_slots: u64,
    /// Ticks that started more than 2 ms late.
    pub late_over_2ms: u64,
    /// Samples the recorder ring had no room for.
    pub dropped_samples: u64,
    /// Ticks whose command the safety filter had to change.
    pub safety_events: u64,
    /// Ticks where a force law clamped its model's inputs to the training range.
    pub model_clamps: u64,
    /// Stalls: ticks that started more than the watchdog's bound after the previous one
    /// (the force was ramped to zero and back each time, or the run ended).
    pub stalls: u64,
    /// The longest silence between two ticks counted as a stall.
    pub longest_stall: Duration,
}

impl RateStats {
    /// Relative deviation of the mean rate from the nominal rate.
    pub fn rate_error(&self) -> f64 {
        if self.nominal_rate_hz > 0.0 {
            (self.mean_rate_hz - self.nominal_rate_hz).abs() / self.nominal_rate_hz
        } else {
            0.0
        }
    }

    /// Relative deviation from the nominal rate of the deadlines the loop kept or skipped: the
    /// ticks run plus the slots missed, over the same span. A loop that keeps absolute
    /// deadlines holds this near zero however long the machine stops it, since every slot
    /// lost to a late wake-up is counted; a loop whose deadlines drift (each one set from the
    /// late wake-up before it) shows the drift here too.
    pub fn deadline_rate_error(&self) -> f64 {
        if self.ticks > 1 && self.nominal_rate_hz > 0.0 {
            let periods = (self.ticks - 1) as f64;
            let rate_hz = self.mean_rate_hz * (periods + self.missed_slots as f64) / periods;
            (rate_hz - self.nominal_rate_hz).abs() / self.nominal_rate_hz
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_come_from_the_buckets() {
        let h = Histogram::new();
        for us in 1..=1000u64 {
            h.record_ns(us * 1000 - 500);
        }
        assert_eq!(h.count(), 1000);
        assert_eq!(h.quantile(0.5), Duration::from_micros(500));
        assert_eq!(h.quantile(0.99), Duration::from_micros(990));
        assert_eq!(h.quantile(0.999), Duration::from_micros(999));
        assert_eq!(h.max(), Duration::from_nanos(999_500));
        assert_eq!(h.quantile(1.0), h.max());
        assert_eq!(h.count_above(Duration::from_micros(900)), 99);
        h.record_ns(1_000_000_000);
        assert_eq!(h.max(), Duration::from_secs(1));
        assert_eq!(h.count_above(Duration::from_millis(2)), 1);
    }

    #[test]
    fn monitor_counts_overruns_and_rate() {
        let m = RateMonitor::new(Duration::from_millis(1));
        m.record_wake(0, 0, 0, None);
        for k in 1..=1000u64 {
            m.record_wake(k * 1_000_000, 10_000, 0, Some(1_000_000));
        }
        // Due at 1.001 s, woken at 1.0035 s: the slots at 1.002 s and 1.003 s are skipped.
        m.record_wake(1_003_500_000, 2_500_000, 2, Some(2_500_000));
        let s = m.snapshot();
        assert_eq!(s.ticks, 1002);
        assert_eq!(s.overruns, 1);
        assert_eq!(s.missed_slots, 2);
        assert_eq!(s.late_over_2ms, 1);
        assert!(
            (s.mean_rate_hz - 1001.0 / 1.0035).abs() < 1e-6,
            "{}",
            s.mean_rate_hz
        );
        // The mean rate is two slots short; the deadlines kept and skipped are all there, but
        // for the last tick's lateness.
        let kept = 1.0 - 1003.0 / 1003.5;
        assert!(s.rate_error() > 4.0 * kept, "{}", s.rate_error());
        assert!(
            (s.deadline_rate_error() - kept).abs() < 1e-12,
            "{}",
            s.deadline_rate_error()
        );
        assert_eq!(s.period_error.p50, Duration::from_micros(1));
        assert_eq!(s.period_error.max, Duration::from_micros(1500));
    }
}
