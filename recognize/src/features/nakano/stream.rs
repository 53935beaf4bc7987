//! Nakano's features streaming: O(1) work per sample over a sliding window (see
//! [`NakanoStream`]), agreeing with the batch ones to ~1e-9.

use super::*;
use crate::SettingError;

/// A fixed-capacity ring: pushing into a full ring evicts and returns the oldest value.
#[derive(Debug)]
struct Ring<T> {
    buf: Vec<T>,
    capacity: usize,
    head: usize,
}

/// Reserves the whole capacity, as [`Ring::new`] does: a derived clone would reserve only the
/// values present, so a copy of an unfed ring (a scene's recognizer, cloned for each haptic
/// thread) would grow its storage while the haptic thread fills it.
impl<T: Clone> Clone for Ring<T> {
    fn clone(&self) -> Self {
        let mut buf = Vec::with_capacity(self.capacity);
        buf.extend_from_slice(&self.buf);
        Self {
            buf,
            capacity: self.capacity,
            head: self.head,
        }
    }
}

impl<T: Copy> Ring<T> {
    fn new(capacity: usize) -> Self {
        Self {
            buf: Vec::with_capacity(capacity),
            capacity,
            head: 0,
        }
    }

    fn is_full(&self) -> bool {
        self.buf.len() == self.capacity
    }

    /// Empties the ring, keeping its storage.
    fn clear(&mut self) {
        self.buf.clear();
        self.head = 0;
    }

    /// Pushes `value`; returns the evicted oldest value when the ring was full.
    fn push(&mut self, value: T) -> Option<T> {
        if self.buf.len() < self.capacity {
            self.buf.push(value);
            return None;
        }
        let old = std::mem::replace(&mut self.buf[self.head], value);
        self.head = (self.head + 1) % self.capacity;
        Some(old)
    }

    /// The `k`-th oldest value (0 = oldest); `None` past the end.
    fn get(&self, k: usize) -> Option<T> {
        if k >= self.buf.len() {
            return None;
        }
        let at = if self.is_full() {
            (self.head + k) % self.capacity
        } else {
            k
        };
        self.buf.get(at).copied()
    }
}

/// A ring value that carries the running sum of the values pushed before it.
trait SumBefore: Copy {
    fn sum_before(&self) -> f64;
}

impl<T: SumBefore> Ring<T> {
    /// The sum of everything pushed before the `k`-th oldest value, for `k` up to the capacity
    /// (`k` = capacity: before a value not pushed yet, i.e. the running `total`).
    fn sum_before(&self, k: usize, total: f64) -> Option<f64> {
        if k == self.capacity {
            Some(total)
        } else {
            self.get(k).map(|v| v.sum_before())
        }
    }
}

/// One window's features from the stream.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StreamWindow {
    /// Index (from 0, counting pushed samples) of the window's first sample.
    pub start: u64,
    /// Position along the rubbing direction at the window's first sample, m (as pushed).
    pub start_position_m: f64,
    /// The features, as [`NakanoSignals::features`] gives for that window.
    pub features: [f64; FEATURES],
}

/// Nakano's features over a sliding window, updated in O(1) per sample.
///
/// Running sums replace every sum of the batch computation: the two centred moving averages,
/// the window's sum of `|z_r|` and count of upward crossings, and the window's mean and variance
/// of `z_r` and of the friction (Welford's sliding update; friction relative to its first sample).
/// After each push the window ending [`NakanoConfig::lookahead_samples`] samples ago is
/// complete, so its features are returned; memory is `O(window + H + S)`.
#[derive(Debug, Clone)]
pub struct NakanoStream {
    config: NakanoConfig,
    window_len: usize,
    pushed: u64,
    z_ref: Option<f64>,
    f_ref: Option<f64>,
    heights: Ring<HeightSample>,
    height_sum: f64,
    roughs: Ring<RoughSample>,
    rough_sum: f64,
    delayed: Ring<(f64, f64)>,
    previous_smoothed: Option<f64>,
    window_rough: Ring<f64>,
    window_position: Ring<f64>,
    window_friction: Ring<f64>,
    window_crossing: Ring<bool>,
    sum_abs_r: f64,
    rough_stats: SlidingMoments,
    friction_stats: SlidingMoments,
    crossings: usize,
    /// With a mirrored start ([`NakanoStream::with_mirrored_start`]): the stroke's first
    /// `pad + 1` samples, held until the mirror image they define can be pushed before them.
    mirror: Option<MirrorStart>,
}

/// The samples a mirrored start holds back, and how many it mirrors.
#[derive(Debug)]
struct MirrorStart {
    pad: usize,
    first: Vec<(f64, f64, f64)>,
}

impl Clone for MirrorStart {
    /// A copy with room for all `pad + 1` samples, as the original was made: a derived clone
    /// would hold only as many as were in, and grow (allocate) on the haptic thread.
    fn clone(&self) -> Self {
        let mut first = Vec::with_capacity(self.pad + 1);
        first.extend_from_slice(&self.first);
        Self { pad: self.pad, first }
    }
}

/// A height sample in the stream's detrending span.
#[derive(Debug, Clone, Copy)]
struct HeightSample {
    /// Height relative to the stream's first sample, m.
    z: f64,
    /// Sum of the relative heights pushed before this one, m.
    before: f64,
    /// Position along the rubbing direction, m.
    x: f64,
}

impl SumBefore for HeightSample {
    fn sum_before(&self) -> f64 {
        self.before
    }
}

/// A roughness sample in the stream's smoothing span.
#[derive(Debug, Clone, Copy)]
struct RoughSample {
    r: f64,
    /// Sum of the roughness before this one, m.
    before: f64,
    /// Smoothing half-width at this sample.
    smoothing: usize,
}

impl SumBefore for RoughSample {
    fn sum_before(&self) -> f64 {
        self.before
    }
}

/// Mean and sum of squared deviations over a sliding window, updated in O(1) per sample with
/// Welford's update (and its sliding form on eviction), which avoids the cancellation of
/// `Σx²/n − mean²` when the variance is small against the mean.
#[derive(Debug, Clone, Copy, Default)]
struct SlidingMoments {
    count: f64,
    mean: f64,
    m2: f64,
}

impl SlidingMoments {
    /// Adds `x`; if `evicted` is given, it leaves the window at the same time.
    fn update(&mut self, x: f64, evicted: Option<f64>) {
        match evicted {
            None => {
                self.count += 1.0;
                let delta = x - self.mean;
                self.mean += delta / self.count;
                self.m2 += delta * (x - self.mean);
            }
            Some(old) => {
                let old_mean = self.mean;
                self.mean += (x - old) / self.count;
                self.m2 += (x - old) * (x - self.mean + old - old_mean);
            }
        }
    }

    /// Variance (divided by the count), clamped at 0 against rounding.
    fn variance(&self) -> f64 {
        (self.m2 / self.count).max(0.0)
    }
}

impl NakanoStream {
    /// A stream over windows of `window_len` samples.
    pub fn new(config: NakanoConfig, window_len: usize) -> Result<Self, RecognizeError> {
        if window_len < 2 {
            return Err(RecognizeError::Setting(SettingError::WindowTooShort {
                len: window_len,
            }));
        }
        config.check()?;
        let (h, s) = config.max_half_widths();
        Ok(Self {
            config,
            window_len,
            pushed: 0,
            z_ref: None,
            f_ref: None,
            heights: Ring::new(2 * h + 1),
            height_sum: 0.0,
            roughs: Ring::new(2 * s + 1),
            rough_sum: 0.0,
            delayed: Ring::new(h + s + 1),
            previous_smoothed: None,
            window_rough: Ring::new(window_len),
            window_position: Ring::new(window_len),
            window_friction: Ring::new(window_len),
            window_crossing: Ring::new(window_len - 1),
            sum_abs_r: 0.0,
            rough_stats: SlidingMoments::default(),
            friction_stats: SlidingMoments::default(),
            crossings: 0,
            mirror: None,
        })
    }

    /// The same stream with the stroke's start mirrored as [`mirror_start`] does: the first
    /// `lookahead` samples are held, then pushed after their mirror image, so windows start at
    /// the stroke's first sample; [`StreamWindow::start`] still counts the samples pushed, from
    /// 0. The holding buffer is allocated here.
    pub fn with_mirrored_start(mut self) -> Self {
        let pad = self.config.lookahead_samples();
        self.mirror = Some(MirrorStart {
            pad,
            first: Vec::with_capacity(pad + 1),
        });
        self
    }

    /// The filters' configuration.
    pub fn config(&self) -> &NakanoConfig {
        &self.config
    }

    /// Samples per window.
    pub fn window_len(&self) -> usize {
        self.window_len
    }

    /// Samples from a window's last sample to the sample that completes it: the window plus
    /// this is the decision latency.
    pub fn lookahead_samples(&self) -> usize {
        self.config.lookahead_samples()
    }

    /// Forgets every sample, as at the start of a new stroke; keeps the buffers (no allocation).
    pub fn reset(&mut self) {
        self.pushed = 0;
        self.z_ref = None;
        self.f_ref = None;
        self.heights.clear();
        self.height_sum = 0.0;
        self.roughs.clear();
        self.rough_sum = 0.0;
        self.delayed.clear();
        self.previous_smoothed = None;
        self.window_rough.clear();
        self.window_position.clear();
        self.window_friction.clear();
        self.window_crossing.clear();
        self.sum_abs_r = 0.0;
        self.rough_stats = SlidingMoments::default();
        self.friction_stats = SlidingMoments::default();
        self.crossings = 0;
        if let Some(m) = &mut self.mirror {
            m.first.clear();
        }
    }

    /// Pushes one sample; returns the features of the window that it completes, if any.
    pub fn push(&mut self, position_m: f64, height_m: f64, friction_n: f64) -> Option<StreamWindow> {
        let Some(m) = &mut self.mirror else {
            return self.push_sample(position_m, height_m, friction_n);
        };
        let pad = m.pad;
        if m.first.len() > pad {
            // Counted from the stroke's first sample, not the mirror's.
            return self.push_sample(position_m, height_m, friction_n).and_then(|w| {
                Some(StreamWindow {
                    start: w.start.checked_sub(pad as u64)?,
                    ..w
                })
            });
        }
        m.first.push((position_m, height_m, friction_n));
        if m.first.len() <= pad {
            return None;
        }
        // The first `pad + 1` samples are in: their mirror image, then them. No window of
        // these completes (a window's first sample needs `pad` samples before it, and its
        // last the lookahead after it).
        let held = std::mem::take(&mut m.first);
        let (x0, z0, _) = held[0];
        for &(x, z, f) in held[1..].iter().rev() {
            let _ = self.push_sample(2.0 * x0 - x, 2.0 * z0 - z, f);
        }
        for &(x, z, f) in &held {
            let _ = self.push_sample(x, z, f);
        }
        // The buffer goes back, keeping its room (and the stroke marked as started).
        if let Some(m) = &mut self.mirror {
            m.first = held;
        }
        None
    }

    /// Pushes one sample into the filters and the window.
    fn push_sample(&mut self, position_m: f64, height_m: f64, friction_n: f64) -> Option<StreamWindow> {
        self.pushed += 1;
        let (hmax, smax) = self.config.max_half_widths();
        let z = height_m - *self.z_ref.get_or_insert(height_m);
        self.delayed.push((position_m, friction_n));
        self.heights.push(HeightSample {
            z,
            before: self.height_sum,
            x: position_m,
        });
        self.height_sum += z;
        if !self.heights.is_full() {
            return None;
        }
        // The centre of the detrending span is `hmax` samples back; the sum of the heights
        // from `k` samples after the oldest on is the total minus what came before it.
        let before = |k: usize| self.heights.sum_before(k, self.height_sum);
        let step = step_m(self.heights.get(0)?.x, self.heights.get(2 * hmax)?.x, hmax);
        let (h, s) = self.config.half_widths_at(step);
        let centre = self.heights.get(hmax)?.z;
        let rough = centre - (before(hmax + h + 1)? - before(hmax - h)?) / (2 * h + 1) as f64;
        self.roughs.push(RoughSample {
            r: rough,
            before: self.rough_sum,
            smoothing: s,
        });
        self.rough_sum += rough;
        if !self.roughs.is_full() {
            return None;
        }
        let rough_before = |k: usize| self.roughs.sum_before(k, self.rough_sum);
        let RoughSample { r, smoothing: s, .. } = self.roughs.get(smax)?;
        let smoothed = (rough_before(smax + s + 1)? - rough_before(smax - s)?) / (2 * s + 1) as f64;
        let previous = self.previous_smoothed.replace(smoothed);
        // The sample the lookahead (the longest H + S) back is the newest one whose smoothed
        // roughness is now known; the delay line holds exactly lookahead + 1 samples, so it is
        // the oldest there.
        let (position, friction) = self.delayed.get(0)?;
        let f = friction - *self.f_ref.get_or_insert(friction);
        let evicted = self.window_rough.push(r);
        self.sum_abs_r += r.abs() - evicted.map_or(0.0, f64::abs);
        self.rough_stats.update(r, evicted);
        let evicted = self.window_friction.push(f);
        self.friction_stats.update(f, evicted);
        self.window_position.push(position);
        if let Some(previous) = previous {
            let crossing = previous < -CROSSING_GUARD_M && smoothed >= -CROSSING_GUARD_M;
            if self.window_crossing.push(crossing) == Some(true) {
                self.crossings -= 1;
            }
            self.crossings += usize::from(crossing);
        }
        if !self.window_rough.is_full() {
            return None;
        }
        let n = self.window_len as f64;
        let travel = (self.window_position.get(self.window_len - 1)? - self.window_position.get(0)?).abs();
        let wavelength = travel / self.crossings.max(1) as f64;
        let lag = (hmax + smax + self.window_len) as u64;
        Some(StreamWindow {
            start: self.pushed - lag,
            start_position_m: self.window_position.get(0)?,
            features: [
                self.sum_abs_r / n,
                self.rough_stats.variance(),
                wavelength,
                self.friction_stats.mean + self.f_ref.unwrap_or(0.0),
                self.friction_stats.variance(),
            ],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_copy_of_an_unfed_stream_has_all_its_storage() {
        let stream = NakanoStream::new(NakanoConfig::default(), 3000)
            .expect("valid")
            .clone();
        let rings = [
            (stream.heights.buf.capacity(), stream.heights.capacity),
            (stream.roughs.buf.capacity(), stream.roughs.capacity),
            (stream.window_rough.buf.capacity(), stream.window_rough.capacity),
            (
                stream.window_position.buf.capacity(),
                stream.window_position.capacity,
            ),
            (
                stream.window_friction.buf.capacity(),
                stream.window_friction.capacity,
            ),
            (
                stream.window_crossing.buf.capacity(),
                stream.window_crossing.capacity,
            ),
            (stream.delayed.buf.capacity(), stream.delayed.capacity),
        ];
        for (reserved, capacity) in rings {
            assert!(capacity > 0);
            assert!(reserved >= capacity, "{reserved} < {capacity}");
        }
    }
}
