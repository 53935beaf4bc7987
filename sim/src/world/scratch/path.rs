//! The relief the nail meets along one stroke, sampled on a uniform grid of arc length and
//! averaged over the contact patch.

use std::f64::consts::TAU;

use super::relief::{LayerKind, Relief};
use super::trial::TrialSetup;
use super::{Contact, ENVELOPE_STRIDE, PATH_STEP_M, RIPPLE_WAVELENGTH_M, STROKE_M};

// ---------------------------------------------------------------------------------------------
// Along-path signals
// ---------------------------------------------------------------------------------------------

/// The relief as met along one stroke, on a uniform grid of arc length: height, sideways
/// slope, normalised roughness (for the friction) and the motor ripple phase.
pub(super) struct PathSignals {
    /// Per grid point: height (m), sideways slope, normalised roughness, ripple phase sine.
    pub(super) points: Vec<[f64; 4]>,
}

/// Values at one arc length.
#[derive(Clone, Copy, Default)]
pub(super) struct PathSample {
    pub(super) height_m: f64,
    pub(super) slope: f64,
    pub(super) cross_slope: f64,
    pub(super) roughness: f64,
    pub(super) ripple: f64,
}

impl PathSignals {
    /// Samples every layer along the line from `start` (surface coordinates, m) in direction
    /// `heading_rad` (surface coordinates). A layer with wave direction θ is met at
    /// `ξ = start·(cos θ, sin θ) + s·cos(θ − φ)`; its gradient `p'(ξ)·(cos θ, sin θ)` has the
    /// sideways component `p'(ξ)·sin(θ − φ)`.
    pub(super) fn new(relief: &Relief, contact: Option<&Contact>, setup: &TrialSetup) -> Self {
        let (start, heading_rad) = (setup.start_m, setup.surface_heading_rad);
        let n = (STROKE_M / PATH_STEP_M).ceil() as usize + 2;
        // Triangular contact kernel of base `contact_width_m` = two boxcars of half that width,
        // each `2·half + 1` grid points; the grid is padded so the result covers the stroke.
        let half = ((setup.contact_width_m / (4.0 * PATH_STEP_M)).round().max(0.0) as usize).min(1000);
        let pad = 2 * half;
        let padded = n + 2 * pad;
        // Height and sideways slope of the textures and of the roughness, and the envelope.
        let mut texture = [vec![0.0; padded], vec![0.0; padded]];
        let mut rough = [vec![0.0; padded], vec![0.0; padded]];
        // The envelope varies over centimetres: sample it every `ENVELOPE_STRIDE` points.
        let mut envelope = vec![0.0; padded / ENVELOPE_STRIDE + 2];
        for layer in &relief.layers {
            let (sin_t, cos_t) = layer.orientation_rad.sin_cos();
            let (sin_rel, cos_rel) = (layer.orientation_rad - heading_rad).sin_cos();
            // ξ at grid point i (arc length (i − pad)·step).
            let xi0 = start[0] * cos_t + start[1] * sin_t - pad as f64 * PATH_STEP_M * cos_rel;
            let step = PATH_STEP_M * cos_rel;
            match layer.kind {
                LayerKind::Envelope => {
                    let count = envelope.len();
                    layer.walk(xi0, step * ENVELOPE_STRIDE as f64, count, |i, z, _| {
                        envelope[i] += z
                    });
                }
                LayerKind::Roughness | LayerKind::Texture => {
                    let [h, c] = if layer.kind == LayerKind::Roughness {
                        &mut rough
                    } else {
                        &mut texture
                    };
                    layer.walk(xi0, step, padded, |i, z, slope| {
                        h[i] += z;
                        c[i] += slope * sin_rel;
                    });
                }
            }
        }
        // Roughness amplitude modulated by the patches: exp(σ·e), e of unit RMS (the slope of
        // the slowly varying envelope itself is negligible next to the roughness slope).
        let patchiness = contact.map_or(0.0, |c| c.patchiness.max(0.0));
        let roughness_rms_m = contact.map_or(0.0, |c| c.roughness.rms_m);
        let mut height_m = texture[0].clone();
        let mut cross_slope = texture[1].clone();
        let mut roughness = vec![0.0; padded];
        let gains: Vec<f64> = envelope.iter().map(|e| (patchiness * e).exp()).collect();
        for i in 0..padded {
            let (k, frac) = (
                i / ENVELOPE_STRIDE,
                (i % ENVELOPE_STRIDE) as f64 / ENVELOPE_STRIDE as f64,
            );
            let gain = gains[k] + (gains[k + 1] - gains[k]) * frac;
            height_m[i] += gain * rough[0][i];
            cross_slope[i] += gain * rough[1][i];
            if roughness_rms_m > 0.0 {
                roughness[i] = gain * rough[0][i] / roughness_rms_m;
            }
        }
        let smooth = |v: Vec<f64>| boxcar(&boxcar(&v, half), half);
        // sin(2π s / λ + φ) on the grid by rotating a unit phasor one step at a time.
        let (sin_step, cos_step) = (TAU * PATH_STEP_M / RIPPLE_WAVELENGTH_M).sin_cos();
        let (mut sin_p, mut cos_p) = setup.ripple_phase.sin_cos();
        let mut ripple = Vec::with_capacity(n);
        for _ in 0..n {
            ripple.push(sin_p);
            (sin_p, cos_p) = (
                sin_p * cos_step + cos_p * sin_step,
                cos_p * cos_step - sin_p * sin_step,
            );
        }
        let (height_m, cross_slope, roughness) = (smooth(height_m), smooth(cross_slope), smooth(roughness));
        let points = (0..n)
            .map(|i| {
                let get = |v: &[f64]| v.get(i).copied().unwrap_or(0.0);
                [get(&height_m), get(&cross_slope), get(&roughness), get(&ripple)]
            })
            .collect();
        Self { points }
    }

    /// Linear interpolation at arc length `s_m` (clamped to the grid). The along-path slope
    /// is that of the interpolating segment, so height and slope are consistent.
    #[inline]
    pub(super) fn at(&self, s_m: f64) -> PathSample {
        let p = &self.points;
        if p.len() < 2 {
            return PathSample::default();
        }
        let u = (s_m * (1.0 / PATH_STEP_M)).max(0.0);
        // u ≥ 0, so truncation is the floor.
        let i = (u as usize).min(p.len() - 2);
        let frac = (u - i as f64).min(1.0);
        let (a, b) = (p[i], p[i + 1]);
        let lerp = |k: usize| a[k] + (b[k] - a[k]) * frac;
        PathSample {
            height_m: lerp(0),
            slope: (b[0] - a[0]) * (1.0 / PATH_STEP_M),
            cross_slope: lerp(1),
            roughness: lerp(2),
            ripple: lerp(3),
        }
    }
}

/// Centred moving average over `2·half + 1` points, only where the window fits: the result is
/// `2·half` shorter than the input.
pub(super) fn boxcar(v: &[f64], half: usize) -> Vec<f64> {
    if half == 0 {
        return v.to_vec();
    }
    let width = 2 * half + 1;
    if v.len() < width {
        return Vec::new();
    }
    let mut out = Vec::with_capacity(v.len() - 2 * half);
    let mut sum: f64 = v[..width].iter().sum();
    out.push(sum / width as f64);
    for i in width..v.len() {
        sum += v[i] - v[i - width];
        out.push(sum / width as f64);
    }
    out
}
