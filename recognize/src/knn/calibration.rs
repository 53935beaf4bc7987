//! Calibrated window probabilities of a k-NN: its vote fractions blended with the uniform
//! distribution, the blend fitted on held-out windows.
//!
//! A 3-NN's vote fractions are 0, 1/3, 2/3 and 1. As probabilities they are overconfident: a
//! window whose true surface got no vote would exclude that surface outright, and one that got
//! all three is called certain. Evidence accumulated over windows (a sequential posterior, or a
//! fusion with a better-calibrated classifier) then follows a few wrong windows too far.
//! Shrinking the votes toward the uniform distribution, `p = λ·votes + (1 − λ)/K`, keeps their
//! order (the k-NN's label is unchanged) and bounds each window's evidence. `λ` is the one that
//! maximises the likelihood of held-out windows under cross-validation by run or trial, as
//! Platt scaling fits an SVM's sigmoid: windows the model never saw, from runs it never saw.
//!
//! The fit is one-dimensional and convex: the mean held-out log-loss
//! `f(λ) = −mean ln(λ·aᵢ + (1 − λ)/K)` (`aᵢ` the vote fraction of window `i`'s true surface) has
//! an increasing derivative, whose root bisection finds to the last bit.

use serde::{Deserialize, Serialize};

use super::Votes;
#[cfg(doc)]
use super::held_out_votes;
use crate::RecognizeError;
use crate::{SettingError, UsageError};

/// How a k-NN over windows' votes become probabilities, and the cross-validation that chose it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct VoteCalibration {
    /// Weight `λ` of the vote fractions, in `[0, 1]`; `1 − λ` is spread evenly over the classes.
    pub votes_weight: f64,
    /// Accuracy per window under the cross-validation (the k-NN's label, which the blend
    /// does not change): the reliability its evidence is weighed by when fused.
    pub accuracy: f64,
    /// Folds of the cross-validation by run or trial.
    pub folds: usize,
    /// Held-out windows.
    pub windows: usize,
    /// Mean held-out log-loss of the blended probabilities, nats.
    pub log_loss: f64,
    /// Share of held-out windows whose true surface got no vote: their log-loss under the raw
    /// votes is infinite.
    pub unvoted: f64,
}

impl VoteCalibration {
    /// Fits the blend on held-out windows: `votes`, each window's k-NN label and vote
    /// fractions when its run was held out ([`held_out_votes`], over `folds` folds), and
    /// `labels`, their true classes (of `classes`).
    pub fn fit(
        votes: &[Votes],
        labels: &[usize],
        classes: usize,
        folds: usize,
    ) -> Result<Self, RecognizeError> {
        if votes.len() != labels.len() {
            return Err(RecognizeError::Usage(UsageError::Counts {
                features: votes.len(),
                labels: labels.len(),
            }));
        }
        let (mut correct, mut true_votes) = (0, Vec::with_capacity(votes.len()));
        for (&y, (label, p)) in labels.iter().zip(votes) {
            correct += usize::from(*label == y);
            true_votes.push(p.get(y).copied().unwrap_or(0.0));
        }
        let votes_weight = fit_votes_weight(&true_votes, classes)?;
        let windows = true_votes.len();
        Ok(Self {
            votes_weight,
            accuracy: correct as f64 / windows as f64,
            folds,
            windows,
            log_loss: mean_log_loss(votes_weight, &true_votes, classes),
            unvoted: true_votes.iter().filter(|&&a| a == 0.0).count() as f64 / windows as f64,
        })
    }

    /// Blends vote fractions `p` (one per class, summing to 1) in place.
    pub fn apply(&self, p: &mut [f64]) {
        let even = (1.0 - self.votes_weight) / p.len() as f64;
        for v in p {
            *v = self.votes_weight * *v + even;
        }
    }
}

/// The `λ` in `[0, 1]` minimising [`mean_log_loss`] over `true_votes` (each held-out window's
/// vote fraction for its true class), with `classes` classes.
pub fn fit_votes_weight(true_votes: &[f64], classes: usize) -> Result<f64, RecognizeError> {
    if classes < 2 || true_votes.is_empty() || true_votes.iter().any(|a| !(0.0..=1.0).contains(a)) {
        return Err(RecognizeError::Setting(SettingError::Parameter {
            of: "vote calibration",
            name: "held-out votes",
            value: true_votes.len() as f64,
            reason: "needs at least one held-out window, two classes and vote fractions in [0, 1]",
        }));
    }
    let even = 1.0 / classes as f64;
    // f′(λ) = −mean (aᵢ − 1/K) / (λ·aᵢ + (1 − λ)/K); increasing, since f is convex.
    let slope = |lambda: f64| {
        -true_votes
            .iter()
            .map(|&a| (a - even) / (lambda * a + (1.0 - lambda) * even))
            .sum::<f64>()
            / true_votes.len() as f64
    };
    if slope(0.0) >= 0.0 {
        // The votes do no better than chance on held-out windows.
        return Ok(0.0);
    }
    if true_votes.iter().all(|&a| a > 0.0) && slope(1.0) <= 0.0 {
        return Ok(1.0);
    }
    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
    while hi - lo > f64::EPSILON {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        // At `hi = 1` with an unvoted window the slope is +∞, which bisection handles as any
        // positive value.
        if slope(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(0.5 * (lo + hi))
}

/// Mean log-loss, nats, of held-out windows whose true class got vote fractions `true_votes`,
/// blended with weight `votes_weight` over `classes` classes.
pub fn mean_log_loss(votes_weight: f64, true_votes: &[f64], classes: usize) -> f64 {
    let even = (1.0 - votes_weight) / classes as f64;
    -true_votes
        .iter()
        .map(|&a| (votes_weight * a + even).ln())
        .sum::<f64>()
        / true_votes.len() as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The minimum over a fine grid, by brute force: an independent check of the bisection.
    fn grid_minimum(true_votes: &[f64], classes: usize) -> f64 {
        (0..=100_000)
            .map(|i| i as f64 / 100_000.0)
            .min_by(|&a, &b| {
                mean_log_loss(a, true_votes, classes).total_cmp(&mean_log_loss(b, true_votes, classes))
            })
            .expect("non-empty grid")
    }

    #[test]
    fn the_blend_minimises_held_out_log_loss() {
        // A 3-NN over 4 surfaces: mostly right, some windows with no vote for the truth.
        let third = 1.0 / 3.0;
        let votes = [
            1.0,
            1.0,
            1.0,
            2.0 * third,
            1.0,
            0.0,
            third,
            1.0,
            1.0,
            0.0,
            1.0,
            2.0 * third,
        ];
        let lambda = fit_votes_weight(&votes, 4).expect("fits");
        assert!(lambda > 0.0 && lambda < 1.0, "{lambda}");
        assert!((lambda - grid_minimum(&votes, 4)).abs() < 2e-5, "{lambda}");
        // The optimum's closed-form condition: the derivative vanishes.
        let even = 0.25;
        let slope: f64 = votes
            .iter()
            .map(|&a| (a - even) / (lambda * a + (1.0 - lambda) * even))
            .sum();
        assert!(slope.abs() < 1e-9, "{slope}");
    }

    #[test]
    fn the_blend_stays_in_its_bounds() {
        // Always right with every vote: the raw votes are best.
        assert_eq!(fit_votes_weight(&[1.0; 5], 3).expect("fits"), 1.0);
        // No better than chance: the uniform distribution.
        assert_eq!(fit_votes_weight(&[0.0, 0.0, 0.5], 3).expect("fits"), 0.0);
        assert_eq!(fit_votes_weight(&[0.0; 4], 3).expect("fits"), 0.0);
        for bad in [&[][..], &[1.5][..], &[f64::NAN][..]] {
            assert!(fit_votes_weight(bad, 3).is_err(), "{bad:?}");
        }
        assert!(fit_votes_weight(&[1.0], 1).is_err());
    }

    #[test]
    fn blended_probabilities_keep_their_order_and_sum() {
        let c = VoteCalibration {
            votes_weight: 0.8,
            accuracy: 0.9,
            folds: 3,
            windows: 10,
            log_loss: 0.3,
            unvoted: 0.1,
        };
        let mut p = [2.0 / 3.0, 1.0 / 3.0, 0.0, 0.0];
        c.apply(&mut p);
        assert!((p.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        assert!(p[0] > p[1] && p[1] > p[2] && p[2] == p[3]);
        assert!((p[2] - 0.05).abs() < 1e-15, "{p:?}");
    }
}
