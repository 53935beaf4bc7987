//! The live view of a running loop, for a window: the newest sample, the loop's statistics and
//! the recent samples, handed over without a lock and without the writers ever waiting.
//!
//! [`channel`] makes the writing ends ([`LiveFeed`]) and the reading end ([`LiveView`]):
//! - the newest sample: a triple buffer the haptic thread writes every tick
//!   ([`crate::rt::LoopIo::live`]); the reader always gets the latest complete sample;
//! - the loop's statistics: a triple buffer written by the thread that supervises the loop
//!   (a few dozen times a second);
//! - the recent samples, in order, for plots and for decisions carried in the samples: a
//!   bounded SPSC ring (`rtrb`) fed off the haptic thread (the recorder's row map, which sees
//!   every sample the loop hands over). When the reader falls behind, new samples are dropped
//!   and counted, never waited for.
//!
//! None of the writers allocates or blocks; the reader copies what it wants to keep into a
//! [`RecentSamples`] of bounded length.

use std::collections::VecDeque;

use crate::rt::{HapticSample, RateStats};

/// Builds a live view whose ring holds `capacity` recent samples (at least 1).
pub fn channel(capacity: usize) -> (LiveFeed, LiveView) {
    let (newest_in, newest_out) = triple_buffer::triple_buffer(&HapticSample::default());
    let (stats_in, stats_out) = triple_buffer::triple_buffer(&None);
    let (producer, consumer) = rtrb::RingBuffer::new(capacity.max(1));
    (
        LiveFeed {
            newest: newest_in,
            recent: RecentWriter { producer, dropped: 0 },
            stats: StatsWriter { input: stats_in },
        },
        LiveView {
            newest: newest_out,
            seen: false,
            recent: consumer,
            stats: stats_out,
        },
    )
}

/// The writing ends, each for a different thread.
pub struct LiveFeed {
    /// The newest sample, for [`crate::rt::LoopIo::live`]: the haptic thread writes it every
    /// tick.
    pub newest: triple_buffer::Input<HapticSample>,
    /// The recent samples, in order.
    pub recent: RecentWriter,
    /// The loop's statistics.
    pub stats: StatsWriter,
}

impl std::fmt::Debug for LiveFeed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LiveFeed")
            .field("recent", &self.recent)
            .finish_non_exhaustive()
    }
}

/// Pushes recent samples into the view's ring.
pub struct RecentWriter {
    producer: rtrb::Producer<HapticSample>,
    dropped: u64,
}

impl RecentWriter {
    /// Hands over one sample; false (and counted) when the ring is full. Never waits, never
    /// allocates.
    pub fn push(&mut self, sample: &HapticSample) -> bool {
        let pushed = self.producer.push(*sample).is_ok();
        if !pushed {
            self.dropped += 1;
        }
        pushed
    }

    /// Samples the ring had no room for.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }
}

impl std::fmt::Debug for RecentWriter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RecentWriter")
            .field("capacity", &self.producer.buffer().capacity())
            .field("dropped", &self.dropped)
            .finish()
    }
}

/// Publishes the loop's statistics.
pub struct StatsWriter {
    input: triple_buffer::Input<Option<RateStats>>,
}

impl StatsWriter {
    /// Makes `stats` the newest; never waits, never allocates.
    pub fn publish(&mut self, stats: RateStats) {
        self.input.write(Some(stats));
    }
}

impl std::fmt::Debug for StatsWriter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StatsWriter").finish_non_exhaustive()
    }
}

/// The reading end, for one thread (the window's).
pub struct LiveView {
    newest: triple_buffer::Output<HapticSample>,
    seen: bool,
    recent: rtrb::Consumer<HapticSample>,
    stats: triple_buffer::Output<Option<RateStats>>,
}

impl LiveView {
    /// The newest sample the haptic thread wrote; None before its first tick.
    pub fn newest(&mut self) -> Option<HapticSample> {
        self.seen |= self.newest.updated();
        let sample = *self.newest.read();
        self.seen.then_some(sample)
    }

    /// The newest statistics published; None before the first.
    pub fn stats(&mut self) -> Option<RateStats> {
        *self.stats.read()
    }

    /// Calls `f` on every sample pushed since the last call, oldest first; returns how many.
    pub fn drain(&mut self, mut f: impl FnMut(&HapticSample)) -> usize {
        let mut n = 0;
        while let Ok(sample) = self.recent.pop() {
            f(&sample);
            n += 1;
        }
        n
    }
}

impl std::fmt::Debug for LiveView {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LiveView")
            .field("seen", &self.seen)
            .field("pending", &self.recent.slots())
            .finish_non_exhaustive()
    }
}

/// The reader's copy of the most recent samples: at most `capacity`, oldest dropped first.
#[derive(Debug, Clone)]
pub struct RecentSamples {
    samples: VecDeque<HapticSample>,
    capacity: usize,
}

impl RecentSamples {
    /// Room for `capacity` samples (at least 1), allocated once.
    pub fn new(capacity: usize) -> Self {
        let capacity = capacity.max(1);
        Self {
            samples: VecDeque::with_capacity(capacity),
            capacity,
        }
    }

    /// Appends a sample, dropping the oldest when full.
    pub fn push(&mut self, sample: &HapticSample) {
        if self.samples.len() == self.capacity {
            self.samples.pop_front();
        }
        self.samples.push_back(*sample);
    }

    /// The samples kept, oldest first, as one slice.
    pub fn as_slice(&mut self) -> &[HapticSample] {
        self.samples.make_contiguous()
    }

    /// The newest sample kept.
    pub fn last(&self) -> Option<&HapticSample> {
        self.samples.back()
    }

    /// How many are kept.
    pub fn len(&self) -> usize {
        self.samples.len()
    }

    /// Whether none are kept.
    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(tick: u64) -> HapticSample {
        HapticSample {
            tick,
            time_s: tick as f64 * 1e-3,
            ..HapticSample::default()
        }
    }

    #[test]
    fn the_view_gets_the_newest_sample_and_every_recent_one_in_order() {
        let (mut feed, mut view) = channel(8);
        assert_eq!(view.newest(), None);
        assert_eq!(view.stats(), None);
        for tick in 0..5 {
            feed.newest.write(sample(tick));
            assert!(feed.recent.push(&sample(tick)));
        }
        assert_eq!(view.newest().map(|s| s.tick), Some(4));
        // No new write: the newest stays.
        assert_eq!(view.newest().map(|s| s.tick), Some(4));
        let mut ticks = Vec::new();
        assert_eq!(view.drain(|s| ticks.push(s.tick)), 5);
        assert_eq!(ticks, [0, 1, 2, 3, 4]);
        assert_eq!(view.drain(|_| {}), 0);
        let stats = RateStats {
            ticks: 5,
            ..RateStats::default()
        };
        feed.stats.publish(stats);
        assert_eq!(view.stats(), Some(stats));
    }

    #[test]
    fn a_full_ring_drops_new_samples_and_counts_them() {
        let (mut feed, mut view) = channel(3);
        let pushed: Vec<bool> = (0..5).map(|t| feed.recent.push(&sample(t))).collect();
        assert_eq!(pushed, [true, true, true, false, false]);
        assert_eq!(feed.recent.dropped(), 2);
        let mut ticks = Vec::new();
        view.drain(|s| ticks.push(s.tick));
        assert_eq!(ticks, [0, 1, 2]);
    }

    #[test]
    fn recent_samples_keep_the_newest() {
        let mut recent = RecentSamples::new(3);
        assert!(recent.is_empty());
        for t in 0..5 {
            recent.push(&sample(t));
        }
        assert_eq!(recent.len(), 3);
        assert_eq!(recent.last().map(|s| s.tick), Some(4));
        let ticks: Vec<u64> = recent.as_slice().iter().map(|s| s.tick).collect();
        assert_eq!(ticks, [2, 3, 4]);
    }
}
