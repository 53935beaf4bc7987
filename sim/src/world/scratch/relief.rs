//! The surface's height field: straight-crested random wave layers (turning bands for
//! isotropic roughness, one layer per direction of texture) and the patchiness envelope,
//! drawn from the surface id and the world seed.

use std::f64::consts::{FRAC_PI_3, PI};

use capture::rng::stream_seed;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::{Contact, SURFACE_SIDE_M, TAG_RELIEF, Texture, WORLD_SEED};
use crate::world::profile::{Band, Profile};

/// What a layer of the relief contributes.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum LayerKind {
    /// A turning band of the isotropic roughness (also drives the friction variation).
    Roughness,
    /// A directional texture.
    Texture,
    /// A turning band of the (dimensionless, unit-RMS) log-amplitude envelope of the roughness.
    Envelope,
}

/// One straight-crested wave field of the relief: a synthesised [`Profile`] along the wave
/// direction, kept as its grid values so that a stroke can walk it at a constant step without
/// a division and a modulo per sample (the values and the linear interpolation between them
/// are exactly those of [`Profile::height_m`] and [`Profile::slope`]).
#[derive(Clone, PartialEq)]
pub(super) struct Layer {
    pub(super) heights_m: Vec<f64>,
    pub(super) spacing_m: f64,
    pub(super) orientation_rad: f64,
    pub(super) kind: LayerKind,
}

impl Layer {
    pub(super) fn new(profile: &Profile, orientation_rad: f64, kind: LayerKind) -> Self {
        let spacing_m = profile.spacing_m();
        let n = (profile.period_m() / spacing_m).round() as usize;
        let heights_m = (0..n).map(|j| profile.height_m(j as f64 * spacing_m)).collect();
        Self {
            heights_m,
            spacing_m,
            orientation_rad,
            kind,
        }
    }

    /// Calls `f(i, height, slope)` at `ξ = ξ0 + i·step` for `i` in `0..count`, periodically.
    pub(super) fn walk(&self, xi0_m: f64, step_m: f64, count: usize, mut f: impl FnMut(usize, f64, f64)) {
        let h = &self.heights_m;
        let n = h.len();
        if n == 0 {
            return;
        }
        let period = n as f64;
        let mut u = (xi0_m / self.spacing_m).rem_euclid(period);
        let du = (step_m / self.spacing_m) % period;
        for i in 0..count {
            let j = (u as usize).min(n - 1);
            let frac = u - j as f64;
            let a = h[j];
            let b = if j + 1 == n { h[0] } else { h[j + 1] };
            f(i, a + (b - a) * frac, (b - a) / self.spacing_m);
            u += du;
            if u >= period {
                u -= period;
            } else if u < 0.0 {
                u += period;
            }
        }
    }
}

/// The height field of one surface: what it was built from (to detect stale caches) and the
/// layers.
#[derive(Clone, PartialEq)]
pub(super) struct Relief {
    pub(super) id: u32,
    pub(super) roughness: Option<Band>,
    pub(super) textures: Vec<Texture>,
    pub(super) layers: Vec<Layer>,
}

/// Typical size of the patches over which a surface's roughness amplitude changes.
pub const PATCH_WAVELENGTH_M: f64 = 0.12;

/// Number of turning bands for isotropic roughness: 3 directions 60° apart already give a
/// directional RMS within a few per cent of the mean.
pub(super) const TURNING_BANDS: usize = 3;

impl Relief {
    pub(super) fn synthesize(id: u32, contact: Option<&Contact>) -> Self {
        let Some(contact) = contact else {
            return Self {
                id,
                roughness: None,
                textures: Vec::new(),
                layers: Vec::new(),
            };
        };
        let mut rng = ChaCha8Rng::seed_from_u64(stream_seed(&[WORLD_SEED, TAG_RELIEF, u64::from(id)]));
        let mut layers = Vec::new();
        let base: f64 = rng.random_range(0.0..FRAC_PI_3);
        let r = contact.roughness;
        if r.rms_m > 0.0 && r.wavelength_m > 0.0 && r.log_width > 0.0 {
            let per_band = Band {
                rms_m: r.rms_m / (TURNING_BANDS as f64).sqrt(),
                ..r
            };
            for k in 0..TURNING_BANDS {
                let profile = synthesize_layer(per_band, &mut rng);
                layers.push(Layer::new(
                    &profile,
                    base + k as f64 * PI / TURNING_BANDS as f64,
                    LayerKind::Roughness,
                ));
            }
        }
        for t in &contact.textures {
            if t.band.rms_m > 0.0 && t.band.wavelength_m > 0.0 && t.band.log_width > 0.0 {
                let profile = synthesize_layer(t.band, &mut rng);
                layers.push(Layer::new(&profile, t.orientation_rad, LayerKind::Texture));
            }
        }
        // The patchiness envelope: a smooth isotropic field of unit RMS, drawn after the other
        // layers so that it does not change them.
        let envelope = Band {
            rms_m: 1.0 / (TURNING_BANDS as f64).sqrt(),
            wavelength_m: PATCH_WAVELENGTH_M,
            log_width: 0.4,
        };
        for k in 0..TURNING_BANDS {
            let profile = synthesize_layer(envelope, &mut rng);
            let orientation_rad = base + (k as f64 + 0.5) * PI / TURNING_BANDS as f64;
            layers.push(Layer::new(&profile, orientation_rad, LayerKind::Envelope));
        }
        Self {
            id,
            roughness: Some(contact.roughness),
            textures: contact.textures.clone(),
            layers,
        }
    }

    pub(super) fn built_from(&self, id: u32, contact: Option<&Contact>) -> bool {
        self.id == id
            && match contact {
                None => self.roughness.is_none() && self.layers.is_empty(),
                Some(c) => self.roughness == Some(c.roughness) && self.textures == c.textures,
            }
    }
}

/// A profile for one band: grid fine enough for the band's short-wavelength tail (2.5 log
/// widths below the peak, 10 points per wavelength, but no finer than 20 µm, below what the
/// nail tip can follow), at least [`SURFACE_SIDE_M`] long.
pub(super) fn synthesize_layer(band: Band, rng: &mut ChaCha8Rng) -> Profile {
    let shortest = band.wavelength_m * (-2.5 * band.log_width).exp();
    let spacing = (shortest / 10.0).clamp(20e-6, 0.5e-3);
    let n = ((SURFACE_SIDE_M / spacing).ceil() as usize).next_power_of_two();
    Profile::synthesize(&[band], spacing, n, rng)
}
