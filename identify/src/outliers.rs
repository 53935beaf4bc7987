//! Gross outliers of a recorded force, found before anything is fitted to it.
//!
//! Real records carry samples no tissue makes: a logger's spike (a 50 N or 10⁶ N sample in a
//! 1 N signal), a digitizing slip (one point of a curve read off a figure below its
//! neighbours), a bit flip. Fitted, one of them bends a least-squares law (a layer refitted to
//! a negative stiffness) and read by the puncture detector it is a drop while advancing.
//!
//! **The rule.** A run of one or two samples is an *excursion* when it lies on the same side
//! of both samples around it by more than the threshold, while those two (and the run's own
//! two samples) agree with each other to within half of that distance. The residual of the smooth fit here is the run's
//! distance from the straight line through its neighbours; a membrane's rupture is no
//! excursion, since the force stays down after it (its neighbours disagree by the drop). The
//! threshold is the puncture detector's: `max(10 σ, 0.05 N)` with σ the capture's own
//! white-noise level from the median absolute second difference ([`crate::force_noise_n`]),
//! so an excursion is exactly what could otherwise pass for a puncture, and white noise of σ
//! reaches it with a probability of about 1e-23 per sample.
//!
//! Identification drops the excursions' rows (each fit, the baselines' too, sees the capture
//! without them) and reports each one ([`Outlier`]); `IdentifyOptions::keep_outliers` keeps
//! them. The detector reads the force with them bridged by their neighbours' line.

use serde::Serialize;

/// Robust standard deviation of the white noise on `force_n` (see the module documentation);
/// 0 with fewer than 3 samples.
pub fn force_noise_n(force_n: &[f64]) -> f64 {
    if force_n.len() < 3 {
        return 0.0;
    }
    let mut d2: Vec<f64> = force_n
        .windows(3)
        .map(|w| (w[2] - 2.0 * w[1] + w[0]).abs())
        .collect();
    1.4826 * median(&mut d2) / 6f64.sqrt()
}

/// The median of `v` (reordered); NaN-free input.
pub(crate) fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// One row taken out of a fit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Outlier {
    /// 0-based data row in the capture as read.
    pub row: usize,
    /// Its time, s.
    pub time_s: f64,
    /// Its recorded force, N.
    pub force_n: f64,
    /// How far it lies from its neighbours' line, N (signed: negative for a dip).
    pub excursion_n: f64,
}

/// The outliers of one capture and the threshold that found them.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OutlierScreen {
    /// The capture.
    pub capture: std::path::PathBuf,
    /// Smallest excursion that counts, N.
    pub threshold_n: f64,
    /// Rows found, in order.
    pub rows: Vec<Outlier>,
    /// Whether they were kept in the fit (`--keep-outliers`).
    pub kept: bool,
}

/// Rows of `force_n` (in time order) that are excursions of one or two samples, with their
/// signed distance from their neighbours' line (module documentation).
pub(crate) fn excursions(time_s: &[f64], force_n: &[f64], threshold_n: f64) -> Vec<(usize, f64)> {
    let n = force_n.len();
    let mut out = Vec::new();
    let mut i = 1;
    while i + 1 < n {
        // A run of `len` samples from i, with neighbours i − 1 and i + len.
        let found = (1..=2).find_map(|len| {
            let after = i + len;
            if after >= n {
                return None;
            }
            let (a, b) = (force_n[i - 1], force_n[after]);
            let (ta, tb) = (time_s[i - 1], time_s[after]);
            let line = |k: usize| a + (b - a) * (time_s[k] - ta) / (tb - ta);
            let run = i..after;
            let up = run.clone().all(|k| force_n[k] - a.max(b) > threshold_n);
            let down = run.clone().all(|k| a.min(b) - force_n[k] > threshold_n);
            let closest = run
                .clone()
                .map(|k| (force_n[k] - a).abs().min((force_n[k] - b).abs()))
                .fold(f64::INFINITY, f64::min);
            // Two samples of a run agree with each other too: two points of a rising
            // loading and its rupture are no spike.
            let flat = (force_n[i] - force_n[after - 1]).abs() < 0.5 * closest;
            ((up || down) && flat && (b - a).abs() < 0.5 * closest)
                .then(|| run.map(|k| (k, force_n[k] - line(k))).collect::<Vec<_>>())
        });
        match found {
            Some(run) => {
                i += run.len() + 1;
                out.extend(run);
            }
            None => i += 1,
        }
    }
    out
}

/// `force_n` with every excursion replaced by its neighbours' line: what the puncture
/// detector reads.
pub(crate) fn bridged(time_s: &[f64], force_n: &[f64], threshold_n: f64) -> Vec<f64> {
    let mut out = force_n.to_vec();
    for (k, excursion) in excursions(time_s, force_n, threshold_n) {
        out[k] = force_n[k] - excursion;
    }
    out
}

/// The outliers of `force_n` (see the module documentation), rows numbered as in the
/// capture.
pub(crate) fn screen(
    capture: &std::path::Path,
    time_s: &[f64],
    force_n: &[f64],
    threshold_n: f64,
    kept: bool,
) -> OutlierScreen {
    OutlierScreen {
        capture: capture.to_owned(),
        threshold_n,
        rows: excursions(time_s, force_n, threshold_n)
            .into_iter()
            .map(|(row, excursion_n)| Outlier {
                row,
                time_s: time_s[row],
                force_n: force_n[row],
                excursion_n,
            })
            .collect(),
        kept,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(n: usize) -> (Vec<f64>, Vec<f64>) {
        let t: Vec<f64> = (0..n).map(|i| i as f64 * 0.01).collect();
        let f = t.iter().map(|t| 0.2 * t).collect();
        (t, f)
    }

    #[test]
    fn a_spike_a_dip_and_a_two_sample_spike_are_found_and_bridged() {
        let (t, mut f) = ramp(100);
        f[20] = 1e6;
        f[50] -= 0.09;
        f[70] += 50.0;
        f[71] += 48.0;
        let found: Vec<usize> = excursions(&t, &f, 0.05).iter().map(|e| e.0).collect();
        assert_eq!(found, vec![20, 50, 70, 71]);
        let clean = bridged(&t, &f, 0.05);
        let (_, truth) = ramp(100);
        for (a, b) in clean.iter().zip(&truth) {
            assert!((a - b).abs() < 1e-9, "{a} vs {b}");
        }
    }

    #[test]
    fn a_step_down_is_no_excursion() {
        // A rupture: rise, then the force stays down. Neither the peak nor the bottom is an
        // excursion, however sparse the sampling.
        let t: Vec<f64> = (0..8).map(f64::from).collect();
        let f = [0.2, 0.4, 0.7, 1.1, 1.6, 0.3, 0.32, 0.34];
        assert!(excursions(&t, &f, 0.05).is_empty());
        // A membrane opening into a lumen and a next one loading quickly: still a step.
        let g = [0.2, 0.6, 1.2, 0.1, 0.3, 0.6, 1.0, 0.2];
        assert!(excursions(&t, &g, 0.05).is_empty());
    }
}
