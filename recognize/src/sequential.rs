//! Anytime decisions: evidence from a stream of window probabilities accumulates from contact
//! on, a surface is named only once its posterior passes a threshold, and is held until its
//! posterior falls below a lower release level (hysteresis).
//!
//! Each window's class probabilities (a k-NN's votes, an SVC's coupled probabilities) are one
//! piece of evidence: the posterior after windows 1..k is the normalized product of their
//! probabilities, each raised to a weight. Overlapping windows share samples, so a window
//! carries about `hop / window` of an independent window's evidence; that is the default
//! weight, which counts every sample once. A probability is floored before its logarithm: one
//! confidently wrong window then lowers a class by a bounded amount instead of excluding it
//! for the rest of the stroke. Only the last `memory` windows count, so after the tool slides
//! onto another surface the old evidence is gone within that many windows and the new surface
//! can be named.
//!
//! [`SequentialState::push`] works on the state's own buffers: no allocation per window.

use serde::{Deserialize, Serialize};

use crate::RecognizeError;

/// Settings of [`SequentialState`], checked by [`SequentialParamsBuilder::build`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SequentialParams {
    threshold: f64,
    release: f64,
    weight: f64,
    floor: f64,
    memory: usize,
}

/// Builder of [`SequentialParams`]; every setting has a default.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SequentialParamsBuilder {
    threshold: f64,
    release: Option<f64>,
    weight: f64,
    floor: f64,
    memory: usize,
}

/// Default posterior a surface must reach to be named.
pub const DEFAULT_THRESHOLD: f64 = 0.9;

/// Default span of windows whose evidence counts, s: a new surface under the tool is named
/// within about this time.
pub const DEFAULT_MEMORY_S: f64 = 3.0;

/// Default floor of a window's class probability.
pub const DEFAULT_FLOOR: f64 = 1e-3;

impl SequentialParams {
    /// A builder with the defaults: threshold 0.9, release at half the threshold, weight 1,
    /// floor 1e-3, memory of 30 windows.
    pub fn builder() -> SequentialParamsBuilder {
        SequentialParamsBuilder {
            threshold: DEFAULT_THRESHOLD,
            release: None,
            weight: 1.0,
            floor: DEFAULT_FLOOR,
            memory: 30,
        }
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

    /// Windows whose evidence counts.
    pub fn memory(&self) -> usize {
        self.memory
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

    /// Windows whose evidence counts, at least 1.
    pub fn memory(mut self, memory: usize) -> Self {
        self.memory = memory;
        self
    }

    /// Checks every setting.
    pub fn build(self) -> Result<SequentialParams, RecognizeError> {
        let release = self.release.unwrap_or(0.5 * self.threshold);
        let bad = |name: &'static str, value: f64, reason: &'static str| RecognizeError::Parameter {
            of: "sequential decision parameter",
            name,
            value,
            reason,
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
        Ok(SequentialParams {
            threshold: self.threshold,
            release,
            weight: self.weight,
            floor: self.floor,
            memory: self.memory,
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
}

/// Evidence of one stroke over `classes` surfaces.
#[derive(Debug, Clone)]
pub struct SequentialState {
    params: SequentialParams,
    /// Weighted log-probabilities of the last `memory` windows, window-major, as a ring.
    ring: Vec<f64>,
    /// Windows in the ring (at most `memory`), and the slot the next one goes to.
    held: usize,
    next: usize,
    /// Sum of the ring's rows.
    sum: Vec<f64>,
    posterior: Vec<f64>,
    decided: Option<usize>,
}

impl SequentialState {
    /// An empty stroke over `classes` (at least 2) surfaces.
    pub fn new(params: SequentialParams, classes: usize) -> Result<Self, RecognizeError> {
        if classes < 2 {
            return Err(RecognizeError::Parameter {
                of: "sequential decision",
                name: "classes",
                value: classes as f64,
                reason: "needs at least two surfaces",
            });
        }
        if params.floor * classes as f64 >= 1.0 {
            return Err(RecognizeError::Parameter {
                of: "sequential decision parameter",
                name: "floor",
                value: params.floor,
                reason: "must be below 1 / classes, or every class is floored alike",
            });
        }
        Ok(Self {
            params,
            ring: vec![0.0; params.memory * classes],
            held: 0,
            next: 0,
            sum: vec![0.0; classes],
            posterior: vec![1.0 / classes as f64; classes],
            decided: None,
        })
    }

    /// The settings.
    pub fn params(&self) -> &SequentialParams {
        &self.params
    }

    /// Forgets the stroke (contact lost): nothing is decided and the posterior is uniform.
    pub fn reset(&mut self) {
        self.ring.fill(0.0);
        self.sum.fill(0.0);
        self.held = 0;
        self.next = 0;
        let k = self.posterior.len();
        self.posterior.fill(1.0 / k as f64);
        self.decided = None;
    }

    /// The posterior over the surfaces after the windows pushed so far.
    pub fn posterior(&self) -> &[f64] {
        &self.posterior
    }

    /// Adds one window's class probabilities (one per surface; non-negative, finite). The
    /// window is refused, the state unchanged, if they are not.
    pub fn push(&mut self, probabilities: &[f64]) -> Result<SequentialStep, RecognizeError> {
        let k = self.sum.len();
        if probabilities.len() != k {
            return Err(RecognizeError::Counts {
                features: probabilities.len(),
                labels: k,
            });
        }
        if let Some(&p) = probabilities.iter().find(|p| !(p.is_finite() && **p >= 0.0)) {
            return Err(RecognizeError::Parameter {
                of: "window probability",
                name: "p",
                value: p,
                reason: "must be finite and non-negative",
            });
        }
        let total: f64 = probabilities.iter().sum();
        let SequentialParams { weight, floor, .. } = self.params;
        let row = &mut self.ring[self.next * k..(self.next + 1) * k];
        for ((slot, s), &p) in row.iter_mut().zip(&mut self.sum).zip(probabilities) {
            // A window whose probabilities all vanish says nothing: it adds the same to all.
            let p = if total > 0.0 { p / total } else { 1.0 / k as f64 };
            let evidence = weight * p.max(floor).ln();
            *s += evidence - *slot;
            *slot = evidence;
        }
        self.next = (self.next + 1) % self.params.memory;
        self.held = (self.held + 1).min(self.params.memory);
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
        let (best, probability) =
            self.posterior
                .iter()
                .copied()
                .enumerate()
                .fold(
                    (0, f64::NEG_INFINITY),
                    |b, (i, q)| if q > b.1 { (i, q) } else { b },
                );
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
        Ok(SequentialStep {
            best,
            probability,
            decided: self.decided,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(threshold: f64, memory: usize) -> SequentialParams {
        SequentialParams::builder()
            .threshold(threshold)
            .memory(memory)
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

    #[test]
    fn bad_settings_and_windows_are_refused() {
        assert!(SequentialParams::builder().threshold(1.0).build().is_err());
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
