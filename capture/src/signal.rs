//! Velocity from a measured position: Li & Bi's pseudo-differentiation (their Eq. 13).
//!
//! Differentiating a quantised encoder reading amplifies its noise; the paper passes the
//! backward difference through a first-order low-pass of time constant τ:
//!
//! ```text
//! v(z) = (z − 1) / ((T + τ) z − τ) · x(z)   ⇔   (T + τ) v[k] − τ v[k−1] = x[k] − x[k−1]
//! ```
//!
//! With τ = 0 this is the plain backward difference; a larger τ trades lag (τ seconds on a
//! ramp's acceleration) for less noise. On a constant-velocity ramp the output is exact at
//! every sample once the filter state equals that velocity, whatever τ is.
//!
//! [`PseudoDifferentiator`] is the streaming form for a fixed period (the haptic loop and the
//! simulated sensors); [`pseudo_differentiate`] runs the same recursion over a recorded capture,
//! using each sample's own interval so that sampling jitter does not turn into velocity errors,
//! and restarting after a pause in the recording (a protocol that repositions the rig between
//! constant-velocity segments restarts the position too: a difference across the pause is not a
//! velocity).

use crate::{CaptureError, CaptureErrorKind};

/// An interval longer than this many median intervals is a pause in the recording, not a
/// sampling interval. Sampling jitter is far below this; protocol pauses (0.5 s between 20 Hz
/// segments is 10 median intervals) are far above. `identify::aise` uses the same rule.
pub const PAUSE_FACTOR: f64 = 4.0;

/// Failures here are about slices, which have no file: they are [`CaptureError`]s without one
/// ([`CaptureError::without_file`]), whose kinds name the sample index instead of a line. A
/// caller that knows the file (a capture's source) can set [`CaptureError::file`].
fn fail(kind: CaptureErrorKind) -> CaptureError {
    CaptureError::without_file(kind)
}

/// The median interval between consecutive samples, s (`None` for fewer than two samples).
pub fn median_interval_s(time_s: &[f64]) -> Option<f64> {
    if time_s.len() < 2 {
        return None;
    }
    let mut dt: Vec<f64> = time_s.windows(2).map(|w| w[1] - w[0]).collect();
    let mid = dt.len() / 2;
    let (_, median, _) = dt.select_nth_unstable_by(mid, f64::total_cmp);
    Some(*median)
}

/// Streaming pseudo-differentiator (Li & Bi Eq. 13) at a fixed sampling period.
///
/// Allocation-free and branch-light so it can run in the 1 kHz haptic loop and in the simulated
/// sensors that produce captures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PseudoDifferentiator {
    period_s: f64,
    tau_s: f64,
    previous_position_m: Option<f64>,
    velocity_mps: f64,
}

impl PseudoDifferentiator {
    /// A differentiator sampled every `period_s` with time constant `tau_s`.
    ///
    /// Both are constants of the program (a loop rate, a filter setting), so this does not
    /// check them: a non-positive `period_s + tau_s` makes every output non-finite. Use
    /// [`PseudoDifferentiator::try_new`] for values that come from a file or a user.
    pub fn new(period_s: f64, tau_s: f64) -> Self {
        Self {
            period_s,
            tau_s,
            previous_position_m: None,
            velocity_mps: 0.0,
        }
    }

    /// [`PseudoDifferentiator::new`] for untrusted values: `period_s` must be finite and
    /// positive, `tau_s` finite and non-negative.
    pub fn try_new(period_s: f64, tau_s: f64) -> Result<Self, CaptureError> {
        check_period(period_s)?;
        check_tau(tau_s)?;
        Ok(Self::new(period_s, tau_s))
    }

    /// Starts from a known velocity (a rig that was already moving when logging began), so
    /// the output does not ramp up from zero over the first τ seconds.
    pub fn with_initial_velocity(mut self, velocity_mps: f64) -> Self {
        self.velocity_mps = velocity_mps;
        self
    }

    /// Feeds one position sample and returns the velocity estimate.
    ///
    /// The first sample only sets the reference position: it returns the initial velocity
    /// (0 unless [`PseudoDifferentiator::with_initial_velocity`] said otherwise).
    #[inline]
    pub fn update(&mut self, position_m: f64) -> f64 {
        if let Some(previous) = self.previous_position_m {
            self.velocity_mps = step(
                position_m - previous,
                self.period_s,
                self.tau_s,
                self.velocity_mps,
            );
        }
        self.previous_position_m = Some(position_m);
        self.velocity_mps
    }

    /// The latest velocity estimate, m/s.
    pub fn velocity_mps(&self) -> f64 {
        self.velocity_mps
    }

    /// The sampling period, s.
    pub fn period_s(&self) -> f64 {
        self.period_s
    }

    /// The filter time constant, s.
    pub fn tau_s(&self) -> f64 {
        self.tau_s
    }
}

/// One step of Eq. 13 solved for `v[k]`: `v[k] = (Δx + τ v[k−1]) / (Δt + τ)`.
#[inline]
fn step(dx_m: f64, dt_s: f64, tau_s: f64, previous_mps: f64) -> f64 {
    (dx_m + tau_s * previous_mps) / (dt_s + tau_s)
}

/// Pseudo-differentiates a recorded position (Eq. 13) with each sample's own interval
/// `t[k] − t[k−1]` in place of `T`, for captures that carry position but no velocity.
///
/// The recording is split into segments at pauses (intervals longer than [`PAUSE_FACTOR`] ×
/// the median interval); see [`pseudo_differentiate_with_pauses`] for the rest.
pub fn pseudo_differentiate(
    time_s: &[f64],
    position_m: &[f64],
    tau_s: f64,
) -> Result<Vec<f64>, CaptureError> {
    check_inputs(time_s, position_m, tau_s)?;
    let max_interval_s = median_interval_s(time_s).map_or(f64::INFINITY, |m| PAUSE_FACTOR * m);
    Ok(differentiate_checked(time_s, position_m, tau_s, max_interval_s))
}

/// [`pseudo_differentiate`] with an explicit pause threshold: an interval longer than
/// `max_interval_s` starts a new segment (`f64::INFINITY`: one continuous recording).
///
/// The first sample of a segment has no predecessor; it is given the segment's first forward
/// difference `(x[s+1] − x[s]) / (t[s+1] − t[s])`, and the filter starts from that value. On a
/// rig that was already moving this avoids a start-up transient of length ~τ (a ramp is exact
/// from the first sample on); on a rig at rest the first difference is ~0 anyway. A segment of
/// a single sample gets velocity 0; an empty input gives an empty output.
///
/// Within a segment the recursion is the exact Eq. 13 with `T = Δt[k]`, so a constant velocity
/// is reproduced exactly across sampling jitter; the filter's time constant stays τ seconds.
pub fn pseudo_differentiate_with_pauses(
    time_s: &[f64],
    position_m: &[f64],
    tau_s: f64,
    max_interval_s: f64,
) -> Result<Vec<f64>, CaptureError> {
    check_inputs(time_s, position_m, tau_s)?;
    if max_interval_s.is_nan() || max_interval_s <= 0.0 {
        return Err(fail(CaptureErrorKind::InvalidParameter {
            name: "max_interval_s",
            value: max_interval_s,
            reason: "must be positive",
        }));
    }
    Ok(differentiate_checked(time_s, position_m, tau_s, max_interval_s))
}

fn differentiate_checked(time_s: &[f64], position_m: &[f64], tau_s: f64, max_interval_s: f64) -> Vec<f64> {
    let n = time_s.len();
    let starts_segment = |k: usize| k == 0 || time_s[k] - time_s[k - 1] > max_interval_s;
    let mut velocity_mps = Vec::with_capacity(n);
    let mut v = 0.0;
    for k in 0..n {
        v = if !starts_segment(k) {
            step(
                position_m[k] - position_m[k - 1],
                time_s[k] - time_s[k - 1],
                tau_s,
                v,
            )
        } else if k + 1 < n && !starts_segment(k + 1) {
            (position_m[k + 1] - position_m[k]) / (time_s[k + 1] - time_s[k])
        } else {
            0.0
        };
        velocity_mps.push(v);
    }
    velocity_mps
}

fn check_inputs(time_s: &[f64], position_m: &[f64], tau_s: f64) -> Result<(), CaptureError> {
    check_tau(tau_s)?;
    if time_s.len() != position_m.len() {
        return Err(fail(CaptureErrorKind::LengthMismatch {
            time: time_s.len(),
            position: position_m.len(),
        }));
    }
    for (index, (&t, &x)) in time_s.iter().zip(position_m).enumerate() {
        check_finite("time_s", index, t)?;
        check_finite("position_m", index, x)?;
        if index > 0 && t <= time_s[index - 1] {
            return Err(fail(CaptureErrorKind::SampleTimeNotIncreasing {
                index,
                time_s: t,
                previous_index: index - 1,
                previous_s: time_s[index - 1],
            }));
        }
    }
    Ok(())
}

fn check_finite(column: &'static str, index: usize, value: f64) -> Result<(), CaptureError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(fail(CaptureErrorKind::NonFiniteSample { column, index, value }))
    }
}

fn check_period(period_s: f64) -> Result<(), CaptureError> {
    if period_s.is_finite() && period_s > 0.0 {
        Ok(())
    } else {
        Err(fail(CaptureErrorKind::InvalidParameter {
            name: "period_s",
            value: period_s,
            reason: "must be finite and positive",
        }))
    }
}

fn check_tau(tau_s: f64) -> Result<(), CaptureError> {
    if tau_s.is_finite() && tau_s >= 0.0 {
        Ok(())
    } else {
        Err(fail(CaptureErrorKind::InvalidParameter {
            name: "tau_s",
            value: tau_s,
            reason: "must be finite and non-negative",
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `|H(e^{jωT})|` of Eq. 13, computed with complex arithmetic written out by hand.
    fn gain(omega_radps: f64, period_s: f64, tau_s: f64) -> f64 {
        let (s, c) = (omega_radps * period_s).sin_cos();
        // numerator z − 1, denominator (T + τ) z − τ, with z = c + j s.
        let num = ((c - 1.0).powi(2) + s * s).sqrt();
        let den = (((period_s + tau_s) * c - tau_s).powi(2) + ((period_s + tau_s) * s).powi(2)).sqrt();
        num / den
    }

    #[test]
    fn streaming_form_is_exact_on_a_ramp_once_initialised() {
        let (period, tau) = (1e-3, 5e-3);
        let mut d = PseudoDifferentiator::new(period, tau).with_initial_velocity(0.004);
        assert_eq!(d.update(0.0), 0.004);
        for k in 1..50 {
            let v = d.update(0.004 * k as f64 * period);
            assert!((v - 0.004).abs() < 1e-12, "k={k}: {v}");
        }
    }

    #[test]
    fn streaming_form_from_rest_converges_with_the_filter_pole() {
        // From v = 0 on a ramp of slope a: v[k] = a (1 − α^k), α = τ / (T + τ).
        let (period, tau, a) = (1e-3, 4e-3, 0.02);
        let alpha = tau / (period + tau);
        let mut d = PseudoDifferentiator::new(period, tau);
        d.update(0.0);
        for k in 1..40 {
            let v = d.update(a * k as f64 * period);
            let expected = a * (1.0 - alpha.powi(k));
            assert!((v - expected).abs() < 1e-14, "k={k}: {v} vs {expected}");
        }
    }

    #[test]
    fn zero_tau_is_the_backward_difference() {
        let t: Vec<f64> = (0..20).map(|k| k as f64 * 0.01).collect();
        let x: Vec<f64> = t.iter().map(|t| t * t * t).collect();
        let v = pseudo_differentiate(&t, &x, 0.0).unwrap();
        for k in 1..t.len() {
            let expected = (x[k] - x[k - 1]) / (t[k] - t[k - 1]);
            assert!((v[k] - expected).abs() < 1e-12, "k={k}");
        }
        assert_eq!(v[0], v[1]);
    }

    #[test]
    fn constant_acceleration_lags_by_half_a_period_plus_tau() {
        // x = ½ a t²: the backward difference is a (t − T/2); the first-order lag adds τ.
        let (period, tau, a) = (1e-3, 2e-3, 3.0);
        let mut d = PseudoDifferentiator::new(period, tau);
        let mut v = 0.0;
        let mut t = 0.0;
        for k in 0..400 {
            t = k as f64 * period;
            v = d.update(0.5 * a * t * t);
        }
        let expected = a * (t - period / 2.0 - tau);
        assert!((v - expected).abs() < 1e-9, "{v} vs {expected}");
    }

    #[test]
    fn sinusoid_amplitude_follows_the_transfer_function() {
        let (period, tau) = (1e-3, 5e-3);
        for omega in [2.0, 30.0, 200.0, 1000.0] {
            let mut d = PseudoDifferentiator::new(period, tau);
            let n = 40_000;
            let mut peak: f64 = 0.0;
            for k in 0..n {
                let v = d.update((omega * k as f64 * period).sin());
                if k > n / 2 {
                    peak = peak.max(v.abs());
                }
            }
            let expected = gain(omega, period, tau);
            // The sampled peak misses the true crest by at most 1 − cos(ωT/2).
            let sampling = 1.0 - (omega * period / 2.0).cos();
            assert!(
                peak <= expected * (1.0 + 1e-9) && peak >= expected * (1.0 - sampling - 1e-6),
                "ω={omega}: peak {peak}, |H| {expected}"
            );
        }
    }

    #[test]
    fn batch_on_uniform_times_equals_the_streaming_form() {
        let (period, tau) = (0.01, 0.01);
        let t: Vec<f64> = (0..300).map(|k| k as f64 * period).collect();
        let x: Vec<f64> = t.iter().map(|t| 0.01 * (3.0 * t).sin() + 0.002 * t).collect();
        let batch = pseudo_differentiate(&t, &x, tau).unwrap();
        let first = (x[1] - x[0]) / (t[1] - t[0]);
        let mut d = PseudoDifferentiator::new(period, tau).with_initial_velocity(first);
        for (k, &xk) in x.iter().enumerate() {
            let v = d.update(xk);
            // Same recursion; the only difference is t[k] − t[k−1] vs `period` in the last bits.
            assert!((v - batch[k]).abs() < 1e-10, "k={k}: {v} vs {}", batch[k]);
        }
    }

    #[test]
    fn batch_is_exact_on_a_ramp_with_jitter_and_gaps() {
        let mut t = vec![0.0];
        for k in 1..200 {
            let dt = if k % 50 == 0 {
                0.5
            } else {
                0.01 + 0.004 * ((k * 7919) % 11) as f64 / 11.0
            };
            t.push(t[k - 1] + dt);
        }
        let x: Vec<f64> = t.iter().map(|t| 0.3 - 0.025 * t).collect();
        // Whether the 0.5 s gaps count as pauses or not, a ramp is a ramp.
        for v in [
            pseudo_differentiate(&t, &x, 0.02).unwrap(),
            pseudo_differentiate_with_pauses(&t, &x, 0.02, f64::INFINITY).unwrap(),
        ] {
            for (k, vk) in v.iter().enumerate() {
                assert!((vk + 0.025).abs() < 1e-12, "k={k}: {vk}");
            }
        }
    }

    #[test]
    fn a_pause_restarts_the_filter() {
        // Two constant-velocity segments at 20 Hz, the rig moved back to 0 during a 0.5 s pause
        // (as the soft-contact protocol does), then a lone sample after another pause.
        let mut t: Vec<f64> = (0..40).map(|k| k as f64 * 0.05).collect();
        let mut x: Vec<f64> = t.iter().map(|t| 0.002 * t).collect();
        let start = t[39] + 0.5;
        for k in 0..40 {
            t.push(start + k as f64 * 0.05);
            x.push(0.004 * k as f64 * 0.05);
        }
        t.push(t[79] + 1.0);
        x.push(0.5);
        let v = pseudo_differentiate(&t, &x, 0.01).unwrap();
        for k in 0..40 {
            assert!(
                (v[k] - 0.002).abs() < 1e-12 && (v[40 + k] - 0.004).abs() < 1e-12,
                "k={k}"
            );
        }
        assert_eq!(v[80], 0.0);
        // Treated as one recording, the jump back to 0 reads as moving backwards at ~7.6 mm/s.
        let across = pseudo_differentiate_with_pauses(&t, &x, 0.01, f64::INFINITY).unwrap();
        assert!(across[40] < -0.007, "{}", across[40]);
        assert!((median_interval_s(&t).unwrap() - 0.05).abs() < 1e-15);
        assert_eq!(median_interval_s(&t[..1]), None);
    }

    #[test]
    fn degenerate_lengths() {
        assert_eq!(pseudo_differentiate(&[], &[], 0.01).unwrap(), Vec::<f64>::new());
        assert_eq!(pseudo_differentiate(&[1.0], &[5.0], 0.01).unwrap(), vec![0.0]);
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        /// The kind of the error, which has no file: these are slices.
        fn kind<T: std::fmt::Debug>(result: Result<T, CaptureError>) -> CaptureErrorKind {
            let e = result.unwrap_err();
            assert!(e.file.is_none(), "{e}");
            e.kind
        }
        assert!(matches!(
            kind(pseudo_differentiate(&[0.0, 1.0], &[0.0], 0.0)),
            CaptureErrorKind::LengthMismatch { time: 2, position: 1 }
        ));
        assert!(matches!(
            kind(pseudo_differentiate(&[0.0, 1.0, 1.0], &[0.0, 1.0, 2.0], 0.0)),
            CaptureErrorKind::SampleTimeNotIncreasing {
                index: 2,
                previous_index: 1,
                ..
            }
        ));
        assert!(matches!(
            kind(pseudo_differentiate(&[0.0, 1.0], &[0.0, f64::NAN], 0.0)),
            CaptureErrorKind::NonFiniteSample {
                column: "position_m",
                index: 1,
                ..
            }
        ));
        assert!(matches!(
            kind(pseudo_differentiate(&[0.0, 1.0], &[0.0, 1.0], -1e-3)),
            CaptureErrorKind::InvalidParameter { name: "tau_s", .. }
        ));
        assert!(matches!(
            kind(pseudo_differentiate_with_pauses(
                &[0.0, 1.0],
                &[0.0, 1.0],
                0.0,
                0.0
            )),
            CaptureErrorKind::InvalidParameter {
                name: "max_interval_s",
                ..
            }
        ));
        assert!(matches!(
            kind(PseudoDifferentiator::try_new(0.0, 0.01)),
            CaptureErrorKind::InvalidParameter { name: "period_s", .. }
        ));
        let d = PseudoDifferentiator::try_new(1e-3, 0.0).unwrap();
        assert_eq!((d.period_s(), d.tau_s(), d.velocity_mps()), (1e-3, 0.0, 0.0));
    }
}
