//! How well an identified model reproduces a measurement (Li & Bi Sec. III, Tables I–II).
//!
//! The paper's index is the average integral squared error over an observation of duration T,
//!
//! ```text
//! AISE = (1/T) ∫₀ᵀ e(t)² dt,    e = F_mea − F̂,
//! ```
//!
//! (T = 10 s, evaluated at a 0.2 s step), and its error bound is `max |F_mea − F̂|`. Captures are
//! sampled, sometimes unevenly and with pauses between protocol segments, so the integral has
//! to be evaluated on samples. Two evaluations are provided:
//!
//! * [`aise`] (used by [`Metrics`] and so by every report): the trapezoid rule on `e²` over the
//!   samples' own times, divided by the observed duration. An interval longer than
//!   [`PAUSE_FACTOR`] × the median interval is a pause in the recording (the rig repositioning
//!   between constant-velocity segments, say): nothing was observed there, so it adds neither
//!   to the integral nor to T. On an evenly sampled, unbroken capture this is exactly the
//!   trapezoid over `[t₀, t_last]`.
//! * [`aise_paper`]: the paper's own discretisation — the error linearly interpolated onto the
//!   grid `t₀ + kΔ`, `k = 0 … N−1`, `N = T/Δ`, and `AISE ≈ (Δ/T) Σ e_k²` (the left Riemann sum
//!   of the definition; with Δ = 0.2 s, T = 10 s that is the mean of 50 squared errors). Use it
//!   to compare with the paper's tables; it ignores everything after T.
//!
//! Both are the same integral; they differ by the quadrature error, which vanishes as the
//! sampling gets finer (see the tests).

use serde::{Deserialize, Serialize};

pub use capture::PAUSE_FACTOR;
use capture::kind;
use capture::median_interval_s;

use crate::error::{self, IdentifyError, check_finite};

/// The paper's observation duration T for AISE, s.
pub const PAPER_DURATION_S: f64 = 10.0;
/// The paper's sampling step for AISE, s.
pub const PAPER_STEP_S: f64 = 0.2;

/// Accuracy of a model on one capture, in the target's unit (N for forces).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    /// Average integral squared error, unit² (see [`aise`] for how it is evaluated).
    pub aise: f64,
    /// The paper's identification error bound `max |F_mea − F̂|`, unit.
    pub error_bound: f64,
    /// Root mean squared error over the samples (each sample weighs the same), unit.
    pub rmse: f64,
    /// Number of samples.
    pub n: usize,
}

impl Metrics {
    /// Metrics of `predicted` against `measured`, sampled at `time_s` (strictly increasing).
    pub fn compute(time_s: &[f64], measured: &[f64], predicted: &[f64]) -> Result<Self, IdentifyError> {
        let error = errors(time_s, measured, predicted)?;
        Ok(Self {
            aise: aise(time_s, &error)?,
            error_bound: error_bound(&error)?,
            rmse: rmse(&error)?,
            n: error.len(),
        })
    }
}

/// `measured − predicted`, after checking lengths, finiteness and time order.
pub fn errors(time_s: &[f64], measured: &[f64], predicted: &[f64]) -> Result<Vec<f64>, IdentifyError> {
    check_time(time_s)?;
    check_series("measured", measured, time_s.len())?;
    check_series("predicted", predicted, time_s.len())?;
    Ok(measured.iter().zip(predicted).map(|(m, p)| m - p).collect())
}

/// AISE by the trapezoid rule over the samples' own times, pauses excluded (see the module
/// documentation): `Σ_{k ∉ gaps} ½ (e_k² + e_{k+1}²) Δt_k / Σ_{k ∉ gaps} Δt_k`, with a gap being an
/// interval longer than [`PAUSE_FACTOR`] × the median interval.
pub fn aise(time_s: &[f64], error: &[f64]) -> Result<f64, IdentifyError> {
    check_time(time_s)?;
    check_series("error", error, time_s.len())?;
    let median_s = median_interval_s(time_s).ok_or(IdentifyError::TooFewSamples { found: time_s.len() })?;
    let max_interval_s = PAUSE_FACTOR * median_s;
    aise_trapezoid_checked(time_s, error, max_interval_s)
}

/// AISE by the trapezoid rule with an explicit pause threshold: intervals longer than
/// `max_interval_s` are not observation time. `f64::INFINITY` integrates over every interval.
pub fn aise_trapezoid(time_s: &[f64], error: &[f64], max_interval_s: f64) -> Result<f64, IdentifyError> {
    check_time(time_s)?;
    check_series("error", error, time_s.len())?;
    if max_interval_s.is_nan() || max_interval_s <= 0.0 {
        return Err(IdentifyError::InvalidParameter {
            name: "max_interval_s",
            value: max_interval_s,
            reason: "must be positive",
        });
    }
    aise_trapezoid_checked(time_s, error, max_interval_s)
}

fn aise_trapezoid_checked(time_s: &[f64], error: &[f64], max_interval_s: f64) -> Result<f64, IdentifyError> {
    if time_s.len() < 2 {
        return Err(IdentifyError::TooFewSamples { found: time_s.len() });
    }
    let mut integral = 0.0;
    let mut duration_s = 0.0;
    for k in 0..time_s.len() - 1 {
        let dt = time_s[k + 1] - time_s[k];
        if dt <= max_interval_s {
            integral += 0.5 * (error[k] * error[k] + error[k + 1] * error[k + 1]) * dt;
            duration_s += dt;
        }
    }
    if duration_s > 0.0 {
        Ok(integral / duration_s)
    } else {
        Err(IdentifyError::InvalidParameter {
            name: "max_interval_s",
            value: max_interval_s,
            reason: "every interval is longer, so nothing is left to average over",
        })
    }
}

/// The paper's discretisation of AISE: the error linearly interpolated at `t₀ + kΔ` for
/// `k = 0 … N−1` with `N = round(duration_s / step_s)`, and `(Δ/T) Σ e_k²` with `T = NΔ`.
/// The samples must cover `[t₀, t₀ + (N−1)Δ]`.
pub fn aise_paper(time_s: &[f64], error: &[f64], step_s: f64, duration_s: f64) -> Result<f64, IdentifyError> {
    check_time(time_s)?;
    check_series("error", error, time_s.len())?;
    for (name, value) in [("step_s", step_s), ("duration_s", duration_s)] {
        if !(value.is_finite() && value > 0.0) {
            return Err(IdentifyError::InvalidParameter {
                name,
                value,
                reason: "must be finite and positive",
            });
        }
    }
    let steps = (duration_s / step_s).round();
    if !(1.0..=1e9).contains(&steps) {
        return Err(IdentifyError::InvalidParameter {
            name: "duration_s",
            value: duration_s,
            reason: "must hold between 1 and 1e9 steps",
        });
    }
    let n = steps as usize;
    let t0 = time_s[0];
    let last_s = t0 + (n - 1) as f64 * step_s;
    let end_s = time_s[time_s.len() - 1];
    // Grid points are computed as t₀ + kΔ; allow the last one to overshoot by rounding.
    if last_s > end_s + 1e-9 * step_s.max(end_s.abs()) {
        return Err(IdentifyError::TooShort {
            covered_s: end_s - t0,
            needed_s: last_s - t0,
        });
    }
    let mut sum = 0.0;
    let mut j = 0;
    for k in 0..n {
        let t = (t0 + k as f64 * step_s).min(end_s);
        while j + 1 < time_s.len() - 1 && time_s[j + 1] <= t {
            j += 1;
        }
        let e = if time_s.len() == 1 {
            error[0]
        } else {
            let (ta, tb) = (time_s[j], time_s[j + 1]);
            let w = ((t - ta) / (tb - ta)).clamp(0.0, 1.0);
            error[j] + w * (error[j + 1] - error[j])
        };
        sum += e * e;
    }
    Ok(sum / n as f64)
}

/// The paper's error bound `max |e|`.
pub fn error_bound(error: &[f64]) -> Result<f64, IdentifyError> {
    check_nonempty_finite("error", error)?;
    Ok(error.iter().fold(0.0, |m, e| m.max(e.abs())))
}

/// `sqrt(mean(e²))`, every sample weighing the same.
pub fn rmse(error: &[f64]) -> Result<f64, IdentifyError> {
    check_nonempty_finite("error", error)?;
    Ok((error.iter().map(|e| e * e).sum::<f64>() / error.len() as f64).sqrt())
}

fn check_time(time_s: &[f64]) -> Result<(), IdentifyError> {
    check_nonempty_finite(kind::TIME_S, time_s)?;
    for k in 1..time_s.len() {
        if time_s[k] <= time_s[k - 1] {
            return Err(IdentifyError::TimeNotIncreasing {
                index: k,
                time_s: time_s[k],
                previous_s: time_s[k - 1],
            });
        }
    }
    Ok(())
}

fn check_series(name: &'static str, values: &[f64], expected: usize) -> Result<(), IdentifyError> {
    error::check_series(name, values, expected)?;
    check_nonempty_finite(name, values)
}

fn check_nonempty_finite(name: &'static str, values: &[f64]) -> Result<(), IdentifyError> {
    if values.is_empty() {
        return Err(IdentifyError::Empty);
    }
    check_finite(name, values)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn grid(n: usize, dt: f64) -> Vec<f64> {
        (0..n).map(|k| k as f64 * dt).collect()
    }

    #[test]
    fn sine_error_over_whole_periods_has_aise_one_half() {
        // ∫₀ᵀ sin²(2πt/P) dt / T = ½ for T a multiple of P. The trapezoid rule is exact for
        // trigonometric polynomials of degree < samples per period, so this holds to rounding.
        let t = grid(1001, 0.01); // 10 s, 10 periods of 1 s
        let e: Vec<f64> = t.iter().map(|t| (2.0 * PI * t).sin()).collect();
        assert!((aise(&t, &e).unwrap() - 0.5).abs() < 1e-12);
        // The paper's discretisation of sin²(2πt/0.7) at t = 0.2k, k = 0…49: sin² = ½ − ½cos(kθ)
        // with θ = 8π/7, which repeats every 7 steps and sums to 0 over k = 0…48; k = 49 adds
        // cos(56π) = 1. So the sum is ½ − ½·(1/50) = 0.49 (grid points fall on samples).
        let e: Vec<f64> = t.iter().map(|t| (2.0 * PI * t / 0.7).sin()).collect();
        let paper = aise_paper(&t, &e, PAPER_STEP_S, PAPER_DURATION_S).unwrap();
        assert!((paper - 0.49).abs() < 1e-9, "{paper}");
    }

    #[test]
    fn constant_error_gives_its_square_bound_and_rmse() {
        let t = grid(51, 0.2);
        let e = vec![-0.3; 51];
        let m = Metrics::compute(&t, &e, &vec![0.0; 51]).unwrap();
        assert!((m.aise - 0.09).abs() < 1e-15);
        assert_eq!(m.error_bound, 0.3);
        assert!((m.rmse - 0.3).abs() < 1e-15);
        assert_eq!(m.n, 51);
        assert!((aise_paper(&t, &e, PAPER_STEP_S, PAPER_DURATION_S).unwrap() - 0.09).abs() < 1e-15);
    }

    #[test]
    fn linear_error_matches_the_integral_of_t_squared() {
        // e = t on [0, 2]: (1/2)∫₀² t² dt = 4/3. The trapezoid rule overestimates ∫ f by exactly
        // (b − a) h² f'' / 12 for a quadratic f, here 2·h²·2/12, i.e. h²/6 after dividing by T = 2.
        let h = 0.01;
        let t = grid(201, h);
        let aise_t = aise(&t, &t).unwrap();
        assert!((aise_t - (4.0 / 3.0 + h * h / 6.0)).abs() < 1e-12, "{aise_t}");
        // The paper's left Riemann sum at step 0.2 over T = 2: (1/10) Σ_{k<10} (0.2k)² = 1.14.
        let paper = aise_paper(&t, &t, 0.2, 2.0).unwrap();
        assert!((paper - 1.14).abs() < 1e-12, "{paper}");
    }

    #[test]
    fn pauses_are_not_observation_time() {
        // A 1 s segment with e = 1 and a 0.5 s segment with e = 2 (100 Hz), 3 s apart. Observed:
        // (1·1 + 4·0.5) / 1.5 = 2. Integrating across the pause would add (1 + 4)/2 · 3 over 4.5 s.
        let mut t = grid(101, 0.01);
        t.extend(grid(51, 0.01).iter().map(|t| t + 4.0));
        let e: Vec<f64> = (0..152).map(|k| if k < 101 { 1.0 } else { 2.0 }).collect();
        assert!((aise(&t, &e).unwrap() - 2.0).abs() < 1e-12);
        let across = aise_trapezoid(&t, &e, f64::INFINITY).unwrap();
        assert!((across - (1.0 + 2.0 + 7.5) / 4.5).abs() < 1e-12, "{across}");
    }

    #[test]
    fn uneven_sampling_is_weighted_by_time() {
        // e = 1 on dense samples for 1 s, then e = 3 on two samples 1 s apart: trapezoid pieces
        // 1·1, (1 + 9)/2 · 0.5, 9 · 0.5 over 2 s. The sparse interval (0.5 s = 5 medians) would be
        // a pause under the default rule, so use an explicit threshold.
        let mut t = grid(101, 0.01);
        t.extend([1.5, 2.0]);
        let mut e = vec![1.0; 101];
        e.extend([3.0, 3.0]);
        let a = aise_trapezoid(&t, &e, 1.0).unwrap();
        assert!((a - (1.0 + 2.5 + 4.5) / 2.0).abs() < 1e-12, "{a}");
        // The plain per-sample mean would be dominated by the dense part.
        assert!((rmse(&e).unwrap().powi(2) - (101.0 + 18.0) / 103.0).abs() < 1e-12);
    }

    #[test]
    fn error_bound_is_the_largest_magnitude() {
        assert_eq!(error_bound(&[0.1, -0.7, 0.5]).unwrap(), 0.7);
        assert!((rmse(&[3.0, -4.0]).unwrap() - 12.5f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn metrics_serialise_with_their_names() {
        let m = Metrics {
            aise: 2.5e-4,
            error_bound: 0.04,
            rmse: 0.015,
            n: 320,
        };
        let json = serde_json::to_string(&m).unwrap();
        assert_eq!(
            json,
            r#"{"aise":0.00025,"error_bound":0.04,"rmse":0.015,"n":320}"#
        );
        assert_eq!(serde_json::from_str::<Metrics>(&json).unwrap(), m);
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        let t = [0.0, 0.1, 0.2];
        assert!(matches!(
            Metrics::compute(&t, &[1.0, 2.0], &[1.0, 2.0, 3.0]),
            Err(IdentifyError::LengthMismatch {
                name: "measured",
                found: 2,
                expected: 3
            })
        ));
        assert!(matches!(
            Metrics::compute(&t, &[1.0, f64::INFINITY, 2.0], &[0.0; 3]),
            Err(IdentifyError::NonFinite {
                name: "measured",
                index: 1,
                ..
            })
        ));
        assert!(matches!(
            Metrics::compute(&[0.0, 0.2, 0.1], &[0.0; 3], &[0.0; 3]),
            Err(IdentifyError::TimeNotIncreasing { index: 2, .. })
        ));
        assert!(matches!(
            Metrics::compute(&[], &[], &[]),
            Err(IdentifyError::Empty)
        ));
        assert!(matches!(
            Metrics::compute(&[0.0], &[1.0], &[0.0]),
            Err(IdentifyError::TooFewSamples { found: 1 })
        ));
        assert!(matches!(
            aise_paper(&t, &[0.0; 3], PAPER_STEP_S, PAPER_DURATION_S),
            Err(IdentifyError::TooShort { .. })
        ));
        assert!(matches!(
            aise_paper(&t, &[0.0; 3], 0.0, 1.0),
            Err(IdentifyError::InvalidParameter { name: "step_s", .. })
        ));
        assert!(matches!(
            aise_trapezoid(&t, &[0.0; 3], f64::NAN),
            Err(IdentifyError::InvalidParameter {
                name: "max_interval_s",
                ..
            })
        ));
    }
}
