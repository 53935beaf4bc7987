//! Friction over travel: the friction a window reads, filtered the same way at any rubbing speed.
//!
//! A rig without a force sensor reports friction through its reaction-force observer, a
//! first-order low-pass in *time* (cut-off `g`, 50 rad/s on Nakano's Omega.7). A surface's
//! friction varies along *travel* (asperity slopes, patches of grit), so rubbed four times as
//! fast its ripple comes four times as often and the observer passes less of it. Over 15 mm of a
//! simulated surface (`tests/nakano_speed.rs`), the friction variance reported through a 50 rad/s
//! observer moves by +15 % at 2 mm/s and by −60 % at 20 mm/s against 5 mm/s, where the roughness
//! features, their filters following the speed, move by less than 10 %.
//!
//! [`TravelFriction`] re-filters the observer's output `y` so that the whole chain is one
//! first-order low-pass over travel, with cut-off wavelength `λ`: at speed `v` that is a low-pass
//! in time at `g_t = 2π v / λ`. Sampled every `T` and discretised by backward Euler (as the
//! rubbing controller's observer and the simulator's are), the observer is
//! `y_k = y_{k−1} + a (f_k − y_{k−1})`, `a = gT / (1 + gT)`, so its input is
//! `f_k = y_{k−1} + (y_k − y_{k−1}) / a`, and that is low-passed again at
//! `b = g_t T / (1 + g_t T)`. Together they are the low-pass at `b` alone: at the speed where
//! `g_t = g` the output is the observer's own, slower it attenuates more, faster it gives back
//! what the observer took, and its noise with it (by up to `b / a` at high frequency, so that
//! ratio is capped at [`MAX_GAIN`]). A friction measured without an observer (a force sensor) is
//! low-passed at `b` directly. With the default `λ` = 2π · 5 mm/s / 50 rad/s = 0.63 mm, Nakano's
//! own protocol passes unchanged. Filtered, that friction variance moves by +0.3 % and −1.7 %.
//!
//! The speed is the travel per sample, smoothed over [`SPEED_SMOOTHING_S`] by a causal
//! first-order filter, so the filter runs sample by sample on the haptic thread exactly as over a
//! whole capture.

use serde::{Deserialize, Serialize};

use super::{PROTOCOL_SPEED_MPS, Rfob};
use crate::RecognizeError;

/// Time constant of the speed estimate, s: long enough to average an encoder's quantum steps
/// (1 µm against 2–20 µm of travel per millisecond), short next to a window.
pub const SPEED_SMOOTHING_S: f64 = 0.02;
/// Largest gain given back to what the observer attenuated, `b / a`: reached at about 10 × the
/// speed at which the filter passes the observer's output unchanged (50 mm/s with the default
/// wavelength). Faster, the friction is filtered over more travel than asked.
pub const MAX_GAIN: f64 = 10.0;

/// The friction filter a model's windows were computed with: a first-order low-pass over
/// travel, of cut-off wavelength `cutoff_m`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FrictionOverTravel {
    /// Cut-off wavelength of travel, m.
    pub cutoff_m: f64,
}

impl FrictionOverTravel {
    /// The wavelength Nakano's protocol shows a classifier: the default observer's cut-off
    /// ([`Rfob`], 50 rad/s) at the protocol's 5 mm/s, 2π · 0.005 / 50 = 0.63 mm.
    pub fn protocol() -> Self {
        Self {
            cutoff_m: std::f64::consts::TAU * PROTOCOL_SPEED_MPS / Rfob::default().cutoff_radps,
        }
    }

    /// Whether the wavelength can be used.
    pub fn check(&self) -> Result<(), RecognizeError> {
        if self.cutoff_m.is_finite() && self.cutoff_m > 0.0 {
            Ok(())
        } else {
            Err(RecognizeError::nakano_config(
                "the friction's cut-off wavelength must be positive and finite",
            ))
        }
    }

    /// The filter for friction reported through an observer of cut-off
    /// `observer_cutoff_radps` (`None`: measured directly), sampled at `rate_hz`.
    pub fn filter(
        &self,
        observer_cutoff_radps: Option<f64>,
        rate_hz: f64,
    ) -> Result<TravelFriction, RecognizeError> {
        self.check()?;
        let usable = |v: f64| v.is_finite() && v > 0.0;
        if !usable(rate_hz) || !observer_cutoff_radps.is_none_or(usable) {
            return Err(RecognizeError::nakano_config(
                "the sample rate and the observer's cut-off must be positive and finite",
            ));
        }
        let period_s = 1.0 / rate_hz;
        Ok(TravelFriction {
            cutoff_m: self.cutoff_m,
            observer_gain: observer_cutoff_radps.map(|g| backward_euler_gain(g, period_s)),
            period_s,
            speed_gain: 1.0 - (-period_s / SPEED_SMOOTHING_S).exp(),
            state: None,
        })
    }
}

/// The running filter of [`FrictionOverTravel`] (see the module doc): one sample at a time, no
/// allocation.
#[derive(Debug, Clone, PartialEq)]
pub struct TravelFriction {
    cutoff_m: f64,
    /// The observer's `a` (see the module doc); `None` for friction measured directly.
    observer_gain: Option<f64>,
    period_s: f64,
    speed_gain: f64,
    state: Option<State>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct State {
    position_m: f64,
    speed_mps: f64,
    /// The observer's last output.
    reported_n: f64,
    low_n: f64,
}

impl TravelFriction {
    /// A new stroke from the next sample.
    pub fn reset(&mut self) {
        self.state = None;
    }

    /// The filtered friction at a sample where the tip is at `position_m` and the friction
    /// reported is `friction_n`. A stroke starts at rest: its first sample passes unchanged.
    pub fn push(&mut self, position_m: f64, friction_n: f64) -> f64 {
        let Some(state) = &mut self.state else {
            self.state = Some(State {
                position_m,
                speed_mps: 0.0,
                reported_n: friction_n,
                low_n: friction_n,
            });
            return friction_n;
        };
        let step_mps = (position_m - state.position_m).abs() / self.period_s;
        state.position_m = position_m;
        state.speed_mps += self.speed_gain * (step_mps - state.speed_mps);
        let cutoff_radps = std::f64::consts::TAU * state.speed_mps / self.cutoff_m;
        let mut b = backward_euler_gain(cutoff_radps, self.period_s);
        let input_n = match self.observer_gain {
            Some(a) => {
                b = b.min(MAX_GAIN * a);
                state.reported_n + (friction_n - state.reported_n) / a
            }
            None => friction_n,
        };
        state.reported_n = friction_n;
        state.low_n += b * (input_n - state.low_n);
        state.low_n
    }

    /// The filtered friction of a whole stroke, from its first sample.
    pub fn apply(&mut self, position_m: &[f64], friction_n: &[f64]) -> Vec<f64> {
        self.reset();
        position_m
            .iter()
            .zip(friction_n)
            .map(|(&x, &f)| self.push(x, f))
            .collect()
    }
}

/// The gain of a first-order low-pass at `cutoff_radps` discretised by backward Euler every
/// `period_s`: `gT / (1 + gT)`.
fn backward_euler_gain(cutoff_radps: f64, period_s: f64) -> f64 {
    let gt = cutoff_radps * period_s;
    gt / (1.0 + gt)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stroke at a constant `speed_mps` after rest, friction `f(x)` seen through a first-order
    /// observer at `g` rad/s (backward Euler) when given: positions and friction.
    fn stroke(speed_mps: f64, seconds: f64, g: Option<f64>, f: impl Fn(f64) -> f64) -> (Vec<f64>, Vec<f64>) {
        let dt = 1e-3;
        let n = (seconds / dt) as usize;
        let mut y = f(0.0);
        (0..n)
            .map(|k| {
                let x = speed_mps * k as f64 * dt;
                if let Some(g) = g {
                    y += backward_euler_gain(g, dt) * (f(x) - y);
                } else {
                    y = f(x);
                }
                (x, y)
            })
            .unzip()
    }

    /// Amplitude of the last `n` samples' sinusoid about their mean.
    fn amplitude(v: &[f64]) -> f64 {
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        (2.0 * v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / v.len() as f64).sqrt()
    }

    /// A ripple of wavelength `w` over travel comes out of observer and filter with the
    /// amplitude of the one low-pass at `b` (backward Euler at `g_t = 2π v / λ`), within 1 %, at
    /// any speed; that is within 6 % of the continuous low-pass over travel,
    /// `1 / sqrt(1 + (λ / w)²)`, up to 20 mm/s (the ripple at 40 Hz, 0.25 rad a sample), where
    /// the observer alone is off by more than 10 %.
    #[test]
    fn a_ripple_over_travel_keeps_its_amplitude_at_any_speed() {
        let travel = FrictionOverTravel::protocol();
        let wavelength_m = 0.5e-3;
        let continuous = 1.0 / (1.0 + (travel.cutoff_m / wavelength_m).powi(2)).sqrt();
        for speed_mps in [0.002, 0.005, 0.02] {
            let ripple = |x: f64| 0.2 + 0.01 * (x * std::f64::consts::TAU / wavelength_m).sin();
            let (x, y) = stroke(speed_mps, 3.0, Some(50.0), ripple);
            let mut filter = travel.filter(Some(50.0), 1000.0).expect("usable");
            let out = filter.apply(&x, &y);
            let gain = amplitude(&out[out.len() - 1000..]) / 0.01;
            // |b / (1 − (1 − b) e^{−iωT})| at the ripple's ω.
            let b = backward_euler_gain(std::f64::consts::TAU * speed_mps / travel.cutoff_m, 1e-3);
            let wt = std::f64::consts::TAU * speed_mps / wavelength_m * 1e-3;
            let (re, im) = (1.0 - (1.0 - b) * wt.cos(), (1.0 - b) * wt.sin());
            let discrete = b / (re * re + im * im).sqrt();
            assert!(
                (gain - discrete).abs() < 0.01 * discrete,
                "{speed_mps} m/s: gain {gain}, the low-pass at b: {discrete}"
            );
            assert!(
                (gain - continuous).abs() < 0.06 * continuous,
                "{speed_mps} m/s: gain {gain}, over travel: {continuous}"
            );
            let seen = amplitude(&y[y.len() - 1000..]) / 0.01;
            if speed_mps != 0.005 {
                assert!(
                    (seen - continuous).abs() > 0.1 * continuous,
                    "{speed_mps} m/s: the observer alone gives {seen}"
                );
            }
        }
    }

    /// At the protocol's speed the observer's output passes unchanged once the speed estimate
    /// has settled; a force sensor's friction is low-passed over travel; a constant friction
    /// passes unchanged at any speed.
    #[test]
    fn the_protocol_passes_unchanged_and_a_steady_friction_stays() {
        let travel = FrictionOverTravel::protocol();
        let ripple = |x: f64| 0.2 + 0.01 * (x * std::f64::consts::TAU / 0.5e-3).sin();
        let (x, y) = stroke(0.005, 2.0, Some(50.0), ripple);
        let out = travel.filter(Some(50.0), 1000.0).expect("usable").apply(&x, &y);
        for k in 500..x.len() {
            assert!(
                (out[k] - y[k]).abs() < 1e-9,
                "sample {k}: {} against {}",
                out[k],
                y[k]
            );
        }
        let (x, f) = stroke(0.005, 2.0, None, ripple);
        let out = travel.filter(None, 1000.0).expect("usable").apply(&x, &f);
        let expected = 1.0 / (1.0 + (travel.cutoff_m / 0.5e-3).powi(2)).sqrt();
        let gain = amplitude(&out[1000..]) / 0.01;
        assert!(
            (gain - expected).abs() < 0.03 * expected,
            "sensor: {gain} against {expected}"
        );
        for speed_mps in [0.001, 0.05] {
            let (x, f) = stroke(speed_mps, 1.0, Some(50.0), |_| 0.3);
            let out = travel.filter(Some(50.0), 1000.0).expect("usable").apply(&x, &f);
            assert!(out.iter().all(|v| (v - 0.3).abs() < 1e-12), "{speed_mps} m/s");
        }
    }

    /// A jump in position (a lost encoder count, a teleport) cannot blow the friction up: what
    /// the observer took is given back at most [`MAX_GAIN`] times.
    #[test]
    fn a_jump_in_position_is_bounded() {
        let mut filter = FrictionOverTravel::protocol()
            .filter(Some(50.0), 1000.0)
            .expect("usable");
        filter.push(0.0, 0.3);
        filter.push(0.0, 0.3);
        let out = filter.push(1.0, 0.31);
        assert!((out - 0.3).abs() <= MAX_GAIN * 0.01 * (1.0 + 1e-9), "{out}");
    }

    #[test]
    fn unusable_settings_are_refused() {
        assert!(FrictionOverTravel { cutoff_m: 0.0 }.filter(None, 1000.0).is_err());
        assert!(
            FrictionOverTravel::protocol()
                .filter(Some(f64::NAN), 1000.0)
                .is_err()
        );
        assert!(FrictionOverTravel::protocol().filter(None, -1.0).is_err());
    }
}
