//! Anytime decisions: evidence from a stream of window probabilities accumulates from contact
//! on, a surface is named only once its posterior passes a threshold, and is held until its
//! posterior falls below a lower release level (hysteresis).
//!
//! Each window's class probabilities (a k-NN's votes, calibrated on held-out windows when it
//! was trained on several runs; an SVC's coupled probabilities) are one piece of evidence: the
//! posterior after windows 1..k is the normalized product of their probabilities, each raised
//! to a weight. Overlapping windows share samples, so a window
//! carries about `hop / window` of an independent window's evidence; that is the default
//! weight, which counts every sample once. A probability is floored before its logarithm: one
//! confidently wrong window then lowers a class by a bounded amount instead of excluding it
//! for the rest of the stroke. Only the last `memory` windows' worth of evidence counts, so
//! after the tool slides onto another surface the old evidence is gone within that many windows
//! and the new surface can be named. A window takes its share of the memory: 1 for a window of
//! the length the settings were made for, and over travel its evidence scale
//! ([`NakanoWindowing::evidence_scale`](crate::NakanoWindowing::evidence_scale)), so that the
//! memory holds the same travel at any speed (15 mm of 1.25 mm windows at 5 mm/s is 3 s, and
//! 7.5 s at 2 mm/s), as each window's weight already counts the same travel once.
//!
//! **A change of surface** is tested for while one is named, so that sliding onto the next
//! patch does not wait for the memory to forget the last one: for each other surface, a CUSUM
//! adds up each window's weighted log-likelihood ratio of that surface against the named one
//! (never below zero). Once one reaches the test's log-odds (default ln 99: the windows since it
//! last stood at zero favour that surface 99:1), the evidence from before those windows is
//! dropped, and a surface is named again, or another one, on them alone. A false change names
//! a wrong surface at once (the windows kept are the ones that favour it), so the default asks
//! more of a change than the default threshold asks of a name (9:1). One sum per surface rather
//! than one for whichever is best in each window: the best of several noisy terms is biased
//! upward and would add up to a change on a stroke that only wavers between look-alikes.
//!
//! [`SequentialState::push`] works on the state's own buffers: no allocation per window.

use serde::{Deserialize, Serialize};

use crate::RecognizeError;
use crate::{SettingError, UsageError};

/// Settings of [`SequentialState`], checked by [`SequentialParamsBuilder::build`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SequentialParams {
    threshold: f64,
    release: f64,
    weight: f64,
    floor: f64,
    memory: usize,
    /// The least share of the memory a window takes: the ring holds `memory / smallest_share`
    /// windows.
    #[serde(default = "one")]
    smallest_share: f64,
    /// Log-odds at which the change test drops the evidence before a change; `None` for no
    /// change test (the memory alone follows a new surface).
    #[serde(default)]
    change_log_odds: Option<f64>,
}

/// Builder of [`SequentialParams`]; every setting has a default.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SequentialParamsBuilder {
    threshold: f64,
    release: Option<f64>,
    weight: f64,
    floor: f64,
    memory: usize,
    smallest_share: f64,
    change_test: bool,
    change_log_odds: Option<f64>,
}

/// Default posterior a surface must reach to be named.
pub const DEFAULT_THRESHOLD: f64 = 0.9;

/// Default span of windows whose evidence counts, s: a new surface under the tool is named
/// within about this time.
pub const DEFAULT_MEMORY_S: f64 = 3.0;

/// Default likelihood ratio against the named surface at which the change test fires (see the
/// module doc for why it is above the default threshold's 9:1).
pub const DEFAULT_CHANGE_ODDS: f64 = 99.0;

/// Default floor of a window's class probability.
pub const DEFAULT_FLOOR: f64 = 1e-3;

/// The most windows a memory may hold, so that a hand-edited setting cannot size the ring past
/// memory.
const MAX_WINDOWS: f64 = 1e7;

fn one() -> f64 {
    1.0
}

impl SequentialParams {
    /// A builder with the defaults: threshold 0.9, release at half the threshold, weight 1,
    /// floor 1e-3, memory of 30 windows, a change test at [`DEFAULT_CHANGE_ODDS`].
    pub fn builder() -> SequentialParamsBuilder {
        SequentialParamsBuilder {
            threshold: DEFAULT_THRESHOLD,
            release: None,
            weight: 1.0,
            floor: DEFAULT_FLOOR,
            memory: 30,
            smallest_share: 1.0,
            change_test: true,
            change_log_odds: None,
        }
    }

    /// Log-odds of the change test; `None` without one.
    pub fn change_log_odds(&self) -> Option<f64> {
        self.change_log_odds
    }

    /// Posterior at which a surface is named.
    pub fn threshold(&self) -> f64 {
        self.threshold
    }

    /// Posterior below which a named surface is no longer held.
    pub fn release(&self) -> f64 {
        self.release
    }

    /// Exponent of each window's probabilities.
    pub fn weight(&self) -> f64 {
        self.weight
    }

    /// Floor of a window's class probability.
    pub fn floor(&self) -> f64 {
        self.floor
    }

    /// Windows' worth of evidence that counts (windows of share 1).
    pub fn memory(&self) -> usize {
        self.memory
    }

    /// The least share of the memory a window takes.
    pub fn smallest_share(&self) -> f64 {
        self.smallest_share
    }

    /// These settings through [`SequentialParamsBuilder::build`]'s checks again: settings read
    /// back from a file were never built.
    fn checked(self) -> Result<Self, RecognizeError> {
        SequentialParamsBuilder {
            threshold: self.threshold,
            release: Some(self.release),
            weight: self.weight,
            floor: self.floor,
            memory: self.memory,
            smallest_share: self.smallest_share,
            change_test: self.change_log_odds.is_some(),
            change_log_odds: self.change_log_odds,
        }
        .build()
    }

    /// Windows the memory can hold: `memory / smallest_share`, rounded up.
    pub fn capacity(&self) -> usize {
        (self.memory as f64 / self.smallest_share).ceil() as usize
    }
}

impl SequentialParamsBuilder {
    /// Posterior at which a surface is named, in (0, 1).
    pub fn threshold(mut self, threshold: f64) -> Self {
        self.threshold = threshold;
        self
    }

    /// Posterior below which a named surface is let go, in (0, threshold]; default half the
    /// threshold.
    pub fn release(mut self, release: f64) -> Self {
        self.release = Some(release);
        self
    }

    /// Exponent of each window's probabilities, in (0, 1]: `hop / window` counts each sample
    /// once when windows overlap.
    pub fn weight(mut self, weight: f64) -> Self {
        self.weight = weight;
        self
    }

    /// Floor of a window's class probability, in (0, 1 / classes).
    pub fn floor(mut self, floor: f64) -> Self {
        self.floor = floor;
        self
    }

    /// Windows' worth of evidence that counts, at least 1.
    pub fn memory(mut self, memory: usize) -> Self {
        self.memory = memory;
        self
    }

    /// The least share of the memory a window takes, in (0, 1] (default 1): windows over
    /// travel take their evidence scale, which is least for the longest window. The memory
    /// holds at most `memory / smallest_share` windows; a window of a smaller share makes room
    /// by pushing the oldest out.
    pub fn smallest_share(mut self, share: f64) -> Self {
        self.smallest_share = share;
        self
    }

    /// Log-odds at which the change test drops the evidence before a change, > 0; default
    /// `ln` [`DEFAULT_CHANGE_ODDS`].
    pub fn change_log_odds(mut self, log_odds: f64) -> Self {
        self.change_test = true;
        self.change_log_odds = Some(log_odds);
        self
    }

    /// No change test: a new surface is followed only as the memory forgets the old one.
    pub fn without_change_test(mut self) -> Self {
        self.change_test = false;
        self
    }

    /// Checks every setting.
    pub fn build(self) -> Result<SequentialParams, RecognizeError> {
        let release = self.release.unwrap_or(0.5 * self.threshold);
        let bad = |name: &'static str, value: f64, reason: &'static str| {
            RecognizeError::Setting(SettingError::Parameter {
                of: "sequential decision parameter",
                name,
                value,
                reason,
            })
        };
        if !(self.threshold > 0.0 && self.threshold < 1.0) {
            return Err(bad("threshold", self.threshold, "must be in (0, 1)"));
        }
        if !(release > 0.0 && release <= self.threshold) {
            return Err(bad("release", release, "must be in (0, threshold]"));
        }
        if !(self.weight > 0.0 && self.weight <= 1.0) {
            return Err(bad("weight", self.weight, "must be in (0, 1]"));
        }
        if !(self.floor > 0.0 && self.floor < 0.5) {
            return Err(bad("floor", self.floor, "must be in (0, 0.5)"));
        }
        if self.memory == 0 {
            return Err(bad("memory", 0.0, "must be at least one window"));
        }
        if !(self.smallest_share > 0.0 && self.smallest_share <= 1.0) {
            return Err(bad("smallest_share", self.smallest_share, "must be in (0, 1]"));
        }
        if self.memory as f64 / self.smallest_share > MAX_WINDOWS {
            return Err(bad(
                "memory",
                self.memory as f64,
                "holds more than 10^7 windows at the smallest share",
            ));
        }
        let change_log_odds = self
            .change_test
            .then(|| self.change_log_odds.unwrap_or(DEFAULT_CHANGE_ODDS.ln()));
        if let Some(h) = change_log_odds
            && !(h.is_finite() && h > 0.0)
        {
            return Err(bad("change_log_odds", h, "must be positive and finite"));
        }
        Ok(SequentialParams {
            threshold: self.threshold,
            release,
            weight: self.weight,
            floor: self.floor,
            memory: self.memory,
            smallest_share: self.smallest_share,
            change_log_odds,
        })
    }
}

/// What [`SequentialState::push`] concluded after one window.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SequentialStep {
    /// The most probable class and its posterior.
    pub best: usize,
    /// Posterior of `best`.
    pub probability: f64,
    /// The surface named, if any: `None` is "undecided".
    pub decided: Option<usize>,
    /// Whether the change test fired at this window (the evidence before the change dropped).
    pub changed: bool,
}

/// Evidence of one stroke over `classes` surfaces.
#[derive(Debug, Clone)]
pub struct SequentialState {
    params: SequentialParams,
    /// Weighted log-probabilities of the windows held, window-major, as a ring of
    /// [`SequentialParams::capacity`] windows.
    ring: Vec<f64>,
    /// Each slot's share of the memory (0 for a free slot).
    shares: Vec<f64>,
    /// Their sum, kept as windows come and go: summing the ring every window made a push
    /// cost the memory's capacity (a memory of 10⁵ windows, 3 × 10⁵ additions a window).
    held_share: f64,
    /// Windows in the ring, and the slot the next one goes to.
    held: usize,
    next: usize,
    /// Sum of the ring's rows.
    sum: Vec<f64>,
    posterior: Vec<f64>,
    decided: Option<usize>,
    /// The change test's sum for each other surface against the named one, and the windows
    /// since it last stood at zero.
    cusum: Vec<f64>,
    since_zero: Vec<usize>,
}

impl SequentialState {
    /// An empty stroke over `classes` (at least 2) surfaces.
    pub fn new(params: SequentialParams, classes: usize) -> Result<Self, RecognizeError> {
        if classes < 2 {
            return Err(RecognizeError::Setting(SettingError::Parameter {
                of: "sequential decision",
                name: "classes",
                value: classes as f64,
                reason: "needs at least two surfaces",
            }));
        }
        if params.floor * classes as f64 >= 1.0 {
            return Err(RecognizeError::Setting(SettingError::Parameter {
                of: "sequential decision parameter",
                name: "floor",
                value: params.floor,
                reason: "must be below 1 / classes, or every class is floored alike",
            }));
        }
        // Settings read back from a file did not pass the builder's checks.
        let params = params.checked()?;
        Ok(Self {
            params,
            ring: vec![0.0; params.capacity() * classes],
            shares: vec![0.0; params.capacity()],
            held_share: 0.0,
            held: 0,
            next: 0,
            sum: vec![0.0; classes],
            posterior: vec![1.0 / classes as f64; classes],
            decided: None,
            cusum: vec![0.0; classes],
            since_zero: vec![0; classes],
        })
    }

    /// The settings.
    pub fn params(&self) -> &SequentialParams {
        &self.params
    }

    /// Forgets the stroke (contact lost): nothing is decided and the posterior is uniform.
    pub fn reset(&mut self) {
        self.ring.fill(0.0);
        self.shares.fill(0.0);
        self.held_share = 0.0;
        self.sum.fill(0.0);
        self.held = 0;
        self.next = 0;
        let k = self.posterior.len();
        self.posterior.fill(1.0 / k as f64);
        self.decided = None;
        self.clear_change_test();
    }

    /// The posterior over the surfaces after the windows pushed so far.
    pub fn posterior(&self) -> &[f64] {
        &self.posterior
    }

    /// Adds one window's class probabilities (one per surface; non-negative, finite). The
    /// window is refused, the state unchanged, if they are not.
    pub fn push(&mut self, probabilities: &[f64]) -> Result<SequentialStep, RecognizeError> {
        self.push_scaled(probabilities, 1.0)
    }

    /// [`SequentialState::push`] for a window whose evidence is `scale` times that of the
    /// windows the settings' weight was set for (positive): its weight is `scale · weight`, at
    /// most 1, and it takes `scale` of the memory. A window longer than those shares more of
    /// its samples with the last one, a shorter one less (windows over travel,
    /// [`NakanoWindowing::evidence_scale`](crate::NakanoWindowing::evidence_scale)).
    pub fn push_scaled(
        &mut self,
        probabilities: &[f64],
        scale: f64,
    ) -> Result<SequentialStep, RecognizeError> {
        self.push_window(probabilities, scale, scale)
    }

    /// [`SequentialState::push_scaled`] for a window whose share of the memory is not its
    /// evidence scale: a fused recognizer's window weighs its recognizer's reliability too,
    /// but takes only its own length's share of the memory. A window of no evidence (scale 0:
    /// rubbed by a tool at rest) changes nothing and takes no room; the step says where the
    /// posterior stands.
    pub fn push_window(
        &mut self,
        probabilities: &[f64],
        scale: f64,
        share: f64,
    ) -> Result<SequentialStep, RecognizeError> {
        for (name, value) in [("evidence scale", scale), ("memory share", share)] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(RecognizeError::Setting(SettingError::Parameter {
                    of: "window",
                    name,
                    value,
                    reason: "must be finite and not negative",
                }));
            }
        }
        if scale == 0.0 {
            let (best, probability) = self.best();
            return Ok(SequentialStep {
                best,
                probability,
                decided: self.decided,
                changed: false,
            });
        }
        let weight = (self.params.weight * scale).min(1.0);
        let k = self.sum.len();
        if probabilities.len() != k {
            return Err(RecognizeError::Usage(UsageError::Counts {
                features: probabilities.len(),
                labels: k,
            }));
        }
        if let Some(&p) = probabilities.iter().find(|p| !(p.is_finite() && **p >= 0.0)) {
            return Err(RecognizeError::Setting(SettingError::Parameter {
                of: "window probability",
                name: "p",
                value: p,
                reason: "must be finite and non-negative",
            }));
        }
        self.make_room(share);
        let total: f64 = probabilities.iter().sum();
        let floor = self.params.floor;
        let row = &mut self.ring[self.next * k..(self.next + 1) * k];
        for ((slot, s), &p) in row.iter_mut().zip(&mut self.sum).zip(probabilities) {
            // A window whose probabilities all vanish says nothing: it adds the same to all.
            let p = if total > 0.0 { p / total } else { 1.0 / k as f64 };
            let evidence = weight * p.max(floor).ln();
            *s += evidence - *slot;
            *slot = evidence;
        }
        self.shares[self.next] = share;
        self.held_share += share;
        let change = self.change_test();
        self.next = (self.next + 1) % self.shares.len();
        self.held += 1;
        if let Some(windows) = change {
            self.keep_last(windows.min(self.held));
            self.decided = None;
            self.clear_change_test();
        }
        let changed = change.is_some();
        // The softmax of the summed evidence, shifted by its largest term so it cannot overflow.
        let top = self.sum.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let mut norm = 0.0;
        for (q, &s) in self.posterior.iter_mut().zip(&self.sum) {
            *q = (s - top).exp();
            norm += *q;
        }
        for q in &mut self.posterior {
            *q /= norm;
        }
        let (best, probability) = self.best();
        self.decided = match self.decided {
            // Held while it keeps enough support, unless another surface passes the threshold.
            Some(d)
                if self.posterior[d] >= self.params.release
                    && !(best != d && probability >= self.params.threshold) =>
            {
                Some(d)
            }
            _ => (probability >= self.params.threshold).then_some(best),
        };
        if self.decided.is_none() {
            self.clear_change_test();
        }
        Ok(SequentialStep {
            best,
            probability,
            decided: self.decided,
            changed,
        })
    }

    /// The change test on the window just written at `next`: its evidence for each other
    /// surface against the named one added to that surface's CUSUM. Once one reaches the test's
    /// log-odds, the number of windows its excursion spans (the evidence to keep).
    fn change_test(&mut self) -> Option<usize> {
        let (Some(d), Some(h)) = (self.decided, self.params.change_log_odds) else {
            return None;
        };
        let k = self.sum.len();
        let row = &self.ring[self.next * k..(self.next + 1) * k];
        let mut fired: Option<(f64, usize)> = None;
        for (c, ((s, n), &e)) in self
            .cusum
            .iter_mut()
            .zip(&mut self.since_zero)
            .zip(row)
            .enumerate()
        {
            if c == d {
                continue;
            }
            *s = (*s + e - row[d]).max(0.0);
            *n = if *s > 0.0 { *n + 1 } else { 0 };
            if *s >= h && fired.is_none_or(|(best, _)| *s > best) {
                fired = Some((*s, *n));
            }
        }
        fired.map(|(_, windows)| windows)
    }

    /// The most probable surface and its posterior.
    fn best(&self) -> (usize, f64) {
        self.posterior
            .iter()
            .copied()
            .enumerate()
            .fold(
                (0, f64::NEG_INFINITY),
                |b, (i, q)| if q > b.1 { (i, q) } else { b },
            )
    }

    /// Pushes the oldest windows out until one of `share` fits in the memory beside those left
    /// (and in the ring). The slot at `next` is left to be overwritten, as it is when the ring
    /// is full and the shares are all 1, so that a memory of windows of one length sums its
    /// evidence exactly as a plain ring of `memory` windows does.
    fn make_room(&mut self, share: f64) {
        let capacity = self.shares.len();
        let k = self.sum.len();
        if self.held == capacity {
            self.held -= 1;
            self.held_share -= self.shares[self.next];
            self.shares[self.next] = 0.0;
        }
        // Shares that fill the memory in exact arithmetic (fifteen of 0.4 in six) fit in it.
        let limit = self.params.memory as f64 * (1.0 + 1e-9);
        while self.held > 0 && self.held_share + share > limit {
            let oldest = (self.next + capacity - self.held) % capacity;
            let row = &mut self.ring[oldest * k..(oldest + 1) * k];
            for (s, e) in self.sum.iter_mut().zip(row.iter_mut()) {
                *s -= *e;
                *e = 0.0;
            }
            self.held -= 1;
            self.held_share -= self.shares[oldest];
            self.shares[oldest] = 0.0;
        }
        if self.held == 0 {
            // Nothing held: no rounding of the running sum carries over.
            self.held_share = 0.0;
        }
    }

    /// Starts the change test afresh.
    fn clear_change_test(&mut self) {
        self.cusum.fill(0.0);
        self.since_zero.fill(0);
    }

    /// Drops every window but the last `keep` from the evidence.
    fn keep_last(&mut self, keep: usize) {
        let k = self.sum.len();
        let capacity = self.shares.len();
        for age in keep..capacity {
            // The window `age + 1` pushes ago sits just before `next`, going back.
            let slot = (self.next + capacity - 1 - age) % capacity;
            self.ring[slot * k..(slot + 1) * k].fill(0.0);
            self.shares[slot] = 0.0;
        }
        self.held = keep;
        self.held_share = self.shares.iter().sum();
        self.sum.fill(0.0);
        for row in self.ring.chunks_exact(k) {
            for (s, e) in self.sum.iter_mut().zip(row) {
                *s += e;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Without the change test, which has a test of its own.
    fn params(threshold: f64, memory: usize) -> SequentialParams {
        SequentialParams::builder()
            .threshold(threshold)
            .memory(memory)
            .without_change_test()
            .build()
            .expect("valid")
    }

    #[test]
    fn the_posterior_is_the_normalized_product_of_the_windows() {
        let mut s = SequentialState::new(params(0.99, 10), 3).expect("state");
        let windows = [[0.5, 0.3, 0.2], [0.6, 0.1, 0.3], [0.2, 0.5, 0.3]];
        for w in &windows {
            s.push(w).expect("push");
        }
        let product: Vec<f64> = (0..3).map(|c| windows.iter().map(|w| w[c]).product()).collect();
        let total: f64 = product.iter().sum();
        for (q, p) in s.posterior().iter().zip(&product) {
            assert!(
                (q - p / total).abs() < 1e-12,
                "{:?} vs {product:?}",
                s.posterior()
            );
        }
    }

    #[test]
    fn undecided_until_the_threshold_then_held_until_the_release() {
        let mut s = SequentialState::new(params(0.9, 50), 2).expect("state");
        // Each window favours class 0 by 2:1: the posterior is 2^k / (2^k + 1).
        let steps: Vec<SequentialStep> = (0..5)
            .map(|_| s.push(&[2.0 / 3.0, 1.0 / 3.0]).expect("push"))
            .collect();
        // 2, 4, 8 → 0.667, 0.8, 0.889 undecided; 16 → 0.941 decided.
        assert_eq!(
            steps.iter().map(|s| s.decided).collect::<Vec<_>>(),
            [None, None, None, Some(0), Some(0)]
        );
        // Evidence for class 1 at 1:2 per window, the odds of class 0 going 32 → 16 → 8 → 4 → 2
        // → 1 → ½ → ¼: held down to 0.5, let go at 1/3 (below the release of 0.45), and class 1
        // at 0.8 is not yet named.
        let back: Vec<Option<usize>> = (0..7)
            .map(|_| s.push(&[1.0 / 3.0, 2.0 / 3.0]).expect("push").decided)
            .collect();
        assert_eq!(back, [Some(0), Some(0), Some(0), Some(0), Some(0), None, None]);
    }

    #[test]
    fn old_evidence_leaves_after_the_memory() {
        let mut s = SequentialState::new(params(0.9, 4), 2).expect("state");
        for _ in 0..20 {
            s.push(&[0.9, 0.1]).expect("push");
        }
        assert_eq!(s.push(&[0.9, 0.1]).expect("push").decided, Some(0));
        // Four windows for class 1 replace the memory entirely.
        let mut last = None;
        for _ in 0..4 {
            last = s.push(&[0.1, 0.9]).expect("push").decided;
        }
        assert_eq!(last, Some(1));
        assert!((s.posterior()[1] - 0.9f64.powi(4) / (0.9f64.powi(4) + 0.1f64.powi(4))).abs() < 1e-12);
    }

    #[test]
    fn a_change_of_surface_drops_the_evidence_from_before_it() {
        let default = SequentialParams::builder().build().expect("valid");
        assert_eq!(default.change_log_odds(), Some(DEFAULT_CHANGE_ODDS.ln()));
        let with = SequentialParams::builder()
            .threshold(0.9)
            .memory(200)
            .change_log_odds(9f64.ln())
            .build()
            .expect("valid");
        let without = params(0.9, 200);
        let run = |p: SequentialParams| {
            let mut s = SequentialState::new(p, 2).expect("state");
            // Fifty windows of class 0 at 4:1, then class 1 at 1:4.
            let first: Vec<SequentialStep> = (0..50).map(|_| s.push(&[0.8, 0.2]).expect("push")).collect();
            let then: Vec<SequentialStep> = (0..60).map(|_| s.push(&[0.2, 0.8]).expect("push")).collect();
            (first, then)
        };
        let (first, then) = run(with);
        assert!(first.iter().all(|s| !s.changed));
        assert_eq!(first.last().map(|s| s.decided), Some(Some(0)));
        // Each window against class 0 is ln 4 = 1.386: the CUSUM passes ln 9 = 2.197 on the
        // second, and the evidence from before the two is dropped. Their posterior for class 1
        // is 16/17 = 0.941, past the threshold: named at once.
        assert_eq!(then.iter().position(|s| s.changed), Some(1));
        assert_eq!(then[1].decided, Some(1));
        assert!((then[1].probability - 16.0 / 17.0).abs() < 1e-12, "{:?}", then[1]);
        assert_eq!(then.iter().filter(|s| s.changed).count(), 1);
        // Without the test the fifty old windows must be outweighed first, and then the
        // posterior raised to 0.9: 52 windows.
        let (_, slow) = run(without);
        assert!(slow.iter().all(|s| !s.changed));
        let named = slow.iter().position(|s| s.decided == Some(1)).expect("named");
        assert_eq!(named, 51);
        // Windows that only waver do not fire it: 2:1 against, then 1:2, repeatedly.
        let mut s = SequentialState::new(with, 2).expect("state");
        for _ in 0..20 {
            s.push(&[0.8, 0.2]).expect("push");
        }
        for i in 0..200 {
            let p = if i % 2 == 0 {
                [1.0 / 3.0, 2.0 / 3.0]
            } else {
                [2.0 / 3.0, 1.0 / 3.0]
            };
            assert!(!s.push(&p).expect("push").changed, "window {i}");
        }
        assert!(SequentialParams::builder().change_log_odds(0.0).build().is_err());
        assert!(
            SequentialParams::builder()
                .change_log_odds(f64::INFINITY)
                .build()
                .is_err()
        );
        assert_eq!(params(0.9, 3).change_log_odds(), None);
    }

    #[test]
    fn a_floored_window_does_not_exclude_a_class() {
        let mut s = SequentialState::new(params(0.9, 50), 2).expect("state");
        s.push(&[1.0, 0.0]).expect("push");
        // Floor 1e-3: one window is a likelihood ratio of 1000, undone by seven at 1:3 (2187).
        for _ in 0..7 {
            s.push(&[0.25, 0.75]).expect("push");
        }
        assert!(s.posterior()[1] > 0.5, "{:?}", s.posterior());
        s.reset();
        assert_eq!(s.posterior(), [0.5, 0.5]);
    }

    /// A window's evidence is raised to `scale · weight`, capped at 1: with weight 0.4, a
    /// window scaled by 0.5 counts as 0.2 and one scaled by 5 as 1.
    #[test]
    fn a_scaled_window_weighs_its_share() {
        let weighted = SequentialParams::builder()
            .weight(0.4)
            .without_change_test()
            .build()
            .expect("valid");
        let odds = |scales: &[f64]| {
            let mut s = SequentialState::new(weighted, 2).expect("state");
            for &scale in scales {
                s.push_scaled(&[0.8, 0.2], scale).expect("push");
            }
            s.posterior()[0] / s.posterior()[1]
        };
        assert!((odds(&[1.0]) - 4f64.powf(0.4)).abs() < 1e-12);
        assert!((odds(&[0.5, 0.5]) - 4f64.powf(0.4)).abs() < 1e-12);
        assert!((odds(&[5.0]) - 4.0).abs() < 1e-12);
        let mut s = SequentialState::new(weighted, 2).expect("state");
        for bad in [-1.0, f64::NAN, f64::INFINITY] {
            assert!(s.push_scaled(&[0.8, 0.2], bad).is_err(), "{bad}");
        }
        assert_eq!(s.posterior(), [0.5, 0.5]);
    }

    /// A window of no evidence (a tool at rest) leaves the posterior, the decision and the
    /// memory as they were: the stream goes on exactly as without it.
    #[test]
    fn a_window_of_no_evidence_changes_nothing() {
        let p = SequentialParams::builder().memory(6).build().expect("valid");
        let mut with = SequentialState::new(p, 3).expect("state");
        let mut without = SequentialState::new(p, 3).expect("state");
        for i in 0..80 {
            let a = with.push(&varied(i)).expect("push");
            let b = without.push(&varied(i)).expect("push");
            assert_eq!(a, b);
            let before = with.posterior().to_vec();
            let still = with.push_window(&[0.0, 0.0, 1.0], 0.0, 0.0).expect("still");
            assert_eq!(with.posterior(), before.as_slice());
            assert_eq!(
                (still.best, still.probability, still.decided),
                (a.best, a.probability, a.decided)
            );
            assert!(!still.changed);
        }
        assert!(with.push_scaled(&[0.2, 0.3, 0.5], 0.0).is_ok());
    }

    /// Probabilities of window `i` of a stream that favours one class, then the other, with
    /// every window different, so that a window held or dropped shows in the posterior.
    fn varied(i: usize) -> [f64; 3] {
        let x = (i as f64 * 0.37).sin().abs();
        if i < 40 {
            [0.5 + 0.3 * x, 0.3 - 0.2 * x, 0.2 - 0.1 * x]
        } else {
            [0.1 + 0.1 * x, 0.3 - 0.2 * x, 0.6 + 0.1 * x]
        }
    }

    /// A memory of `memory` windows' worth holds `memory / share` windows of that share: the
    /// posterior is the one of a memory of that many whole windows, window by window.
    #[test]
    fn a_window_takes_its_share_of_the_memory() {
        let shared = |share: f64, smallest: f64| {
            let p = SequentialParams::builder()
                .memory(6)
                .smallest_share(smallest)
                .without_change_test()
                .build()
                .expect("valid");
            let mut s = SequentialState::new(p, 3).expect("state");
            (0..80)
                .map(|i| {
                    s.push_window(&varied(i), 1.0, share).expect("push");
                    s.posterior().to_vec()
                })
                .collect::<Vec<_>>()
        };
        let whole = |memory: usize| {
            let mut s = SequentialState::new(params(0.9, memory), 3).expect("state");
            (0..80)
                .map(|i| {
                    s.push(&varied(i)).expect("push");
                    s.posterior().to_vec()
                })
                .collect::<Vec<_>>()
        };
        let close = |a: &[Vec<f64>], b: &[Vec<f64>]| {
            a.iter()
                .flatten()
                .zip(b.iter().flatten())
                .all(|(x, y)| (x - y).abs() < 1e-12)
        };
        // Windows over travel at 2.5 times slower than trained (share 0.4): 15 windows held.
        assert!(close(&shared(0.4, 0.4), &whole(15)));
        // Half a window each: 12; two windows each (faster): 3.
        assert!(close(&shared(0.5, 0.25), &whole(12)));
        assert!(close(&shared(2.0, 1.0), &whole(3)));
        // A window below the smallest share finds the ring full: it holds 6 / 0.5 = 12.
        assert!(close(&shared(0.25, 0.5), &whole(12)));
        assert!(!close(&shared(0.5, 0.5), &whole(11)));
        // One window of more than the whole memory is held alone.
        assert!(close(&shared(7.0, 1.0), &whole(1)));
    }

    /// The change test keeps the windows since the change, whatever their shares, and the
    /// memory goes on from those.
    #[test]
    fn a_change_keeps_the_shares_of_the_windows_since_it() {
        let p = SequentialParams::builder()
            .memory(6)
            .smallest_share(0.5)
            .build()
            .expect("valid");
        let mut s = SequentialState::new(p, 3).expect("state");
        let mut changed_at = None;
        for i in 0..80 {
            if s.push_window(&varied(i), 1.0, 0.5).expect("push").changed {
                changed_at.get_or_insert(i);
            }
        }
        let at = changed_at.expect("the stream changes class at window 40");
        assert!((40..52).contains(&at), "{at}");
        // Long after the change the ring holds twelve windows of half a share, as without one.
        let mut plain = SequentialState::new(params(0.9, 12), 3).expect("state");
        for i in 0..80 {
            plain.push(&varied(i)).expect("push");
        }
        for (a, b) in s.posterior().iter().zip(plain.posterior()) {
            assert!(
                (a - b).abs() < 1e-12,
                "{:?} vs {:?}",
                s.posterior(),
                plain.posterior()
            );
        }
        for bad in [-1.0, f64::NAN, f64::INFINITY] {
            assert!(s.push_window(&[0.3, 0.3, 0.4], 1.0, bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn bad_settings_and_windows_are_refused() {
        assert!(SequentialParams::builder().threshold(1.0).build().is_err());
        for share in [0.0, -0.5, 1.5, f64::NAN] {
            assert!(
                SequentialParams::builder().smallest_share(share).build().is_err(),
                "{share}"
            );
        }
        // Settings read back from a file are checked again before a ring is sized from them.
        let text = serde_json::to_string(&params(0.9, 30)).expect("json");
        for (share, memory) in [("0.0", "30"), ("1e-9", "30"), ("0.5", "0")] {
            let edited = text
                .replace("\"smallest_share\":1.0", &format!("\"smallest_share\":{share}"))
                .replace("\"memory\":30", &format!("\"memory\":{memory}"));
            let read: SequentialParams = serde_json::from_str(&edited).expect("parses");
            assert!(SequentialState::new(read, 2).is_err(), "{edited}");
        }
        assert!(
            SequentialParams::builder()
                .memory(10_000)
                .smallest_share(1e-4)
                .build()
                .is_err()
        );
        assert!(
            SequentialParams::builder()
                .threshold(0.8)
                .release(0.9)
                .build()
                .is_err()
        );
        assert!(SequentialParams::builder().weight(0.0).build().is_err());
        assert!(SequentialParams::builder().floor(0.6).build().is_err());
        assert!(SequentialParams::builder().memory(0).build().is_err());
        assert!(SequentialState::new(params(0.9, 3), 1).is_err());
        let floor = SequentialParams::builder()
            .floor(0.4)
            .build()
            .expect("valid alone");
        assert!(SequentialState::new(floor, 3).is_err());
        let mut s = SequentialState::new(params(0.9, 3), 2).expect("state");
        assert!(s.push(&[0.5]).is_err());
        assert!(s.push(&[f64::NAN, 0.5]).is_err());
        assert!(s.push(&[-0.1, 0.5]).is_err());
        assert_eq!(s.posterior(), [0.5, 0.5]);
    }
}
