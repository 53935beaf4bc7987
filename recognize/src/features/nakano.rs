//! Nakano's five rubbing features (thesis Sec. 2.2, Eqs. 2.18–2.23), in batch over a window of a
//! capture and streaming with O(1) work per sample.
//!
//! The tip rubs along x (`tangential_position_m`) while force control holds it on the surface;
//! its height (`normal_position_m`) carries the surface's waviness and roughness, and the
//! reaction force along x (`friction_force_n`, the RFOB's estimate) is the friction. Per window of
//! `n` samples the feature vector is
//!
//! ```text
//! P = [ mean|z_r|   (Eq. 2.18, m)
//!       S²_rough    (Eq. 2.19, m²)
//!       λ̄ = x / k   (Eq. 2.20, m)
//!       mean f_x    (Eq. 2.21, N)
//!       S²_fric     (Eq. 2.22, N²) ]
//! ```
//!
//! **Roughness** `z_r` is the height minus its centred moving average over `2H + 1` samples
//! (a zero-phase high-pass: the moving average is symmetric, so it delays nothing). A moving
//! average of length `L` has its first null at wavelength `L` and passes wavelengths much longer
//! than `L` almost unchanged, so subtracting it keeps wavelengths shorter than `L` and removes
//! longer ones. The default length is 2.5 mm of travel at the protocol's 5 mm/s (`H` = 250 at
//! 1 kHz; [`NakanoConfig::at_rate`] keeps the same travel at other rates): that is ISO 4288's standard roughness cut-off `λc` = 2.5 mm, it keeps the
//! sandpapers' and styrols' roughness (wavelengths ≈ 0.3–2 mm) and removes the sheet's waviness
//! (≳ 10 mm) and any tilt of the sample. It was chosen by that reasoning, not tuned on test runs.
//!
//! **Following the speed**: both averages are lengths of travel (the thesis only says "a high
//! pass filter"; the cut-offs here are wavelengths), so a fixed length in samples cuts at a
//! wavelength proportional to the rubbing speed: at 20 mm/s the 2.5 mm cut-off would become
//! 10 mm and pass the waviness. With [`NakanoConfig::follow_speed`] set, the half-widths at each
//! sample are scaled by the travel per sample measured around it ([`SpeedFollowing`]), up to
//! maxima that set the lookahead. At the reference speed the widths are exactly the nominal
//! ones, so the features are those of the fixed filters (to rounding, ≤ 1e-13 relative on the
//! simulated 5 mm/s runs); on a simulated surface rubbed at 2 and 20 mm/s the roughness features
//! stay within 10 % of those at 5 mm/s (`tests/nakano_speed.rs`), against up to +2500 % with
//! fixed filters. The friction features are not filtered here: what speed does to them (through
//! the force observer's time-domain low-pass) is the sensor's.
//!
//! **Variance of roughness** (Eq. 2.19): the thesis prints `(mean|z_r| − z_r[i])²`, which reads
//! as a typo for the sample variance the text names; we use the variance of `z_r` about its own
//! mean (divided by `n`, as Eq. 2.19).
//!
//! **Mean wavelength** (Eq. 2.20): the roughness is smoothed by a second centred moving average
//! over `2S + 1` samples (default `S` = 20: 0.2 mm, below the finest roughness wavelength, above
//! the encoder's quantization steps, which would otherwise count as waves), then `k` is the
//! number of upward zero crossings inside the window and `x` the window's travel. With no
//! crossing the wavelength is at least the travel, so `λ̄ = x` (k taken as 1). A crossing is
//! counted between consecutive samples going from below `−CROSSING_GUARD_M` to at or above it:
//! the tiny guard (1 pm) keeps a flat signal, whose smoothed roughness is zero up to rounding,
//! from counting rounding noise as waves, and makes batch and streaming agree.
//!
//! **Lookahead**: a zero-phase filter needs future samples. The roughness at sample `i` needs the
//! height up to `i + H`, its smoothed value up to `i + H + S`; so a window ending at sample `e` can
//! be evaluated only once sample `e + H + S` has arrived ([`NakanoConfig::lookahead_samples`],
//! 270 samples = 0.27 s by default). A live decision's latency is the window plus that lookahead.
//! The batch function needs the same margin before the window (`H + S` samples) and after it.

use std::borrow::Cow;

use capture::Capture;
use capture::pseudo_differentiate;

use crate::RecognizeError;
use crate::{InputError, SettingError, UsageError};

/// Number of features in a Nakano feature vector (thesis Eq. 2.23: r = 5).
pub const FEATURES: usize = 5;

/// Names of the features, in vector order, with their units.
pub const FEATURE_NAMES: [&str; FEATURES] = [
    "roughness_mean_abs_m",
    "roughness_variance_m2",
    "roughness_wavelength_m",
    "friction_mean_n",
    "friction_variance_n2",
];

/// Smoothed roughness must rise from below minus this to count a wave, m (see the module doc).
pub const CROSSING_GUARD_M: f64 = 1e-12;

/// Column of the tip's position along the rubbing direction.
pub const POSITION_COLUMN: &str = capture::kind::TANGENTIAL_POSITION_M;
/// Column of the tip's height.
pub const HEIGHT_COLUMN: &str = capture::kind::NORMAL_POSITION_M;
/// Column of the friction (reaction force along x).
pub const FRICTION_COLUMN: &str = capture::kind::FRICTION_FORCE_N;
/// Column of the force commanded along x, for the reaction-force observer.
pub const COMMAND_FORCE_COLUMN: &str = capture::kind::TANGENTIAL_COMMAND_FORCE_N;
/// Column of the measured velocity along x (pseudo-differentiated from position when absent).
pub const VELOCITY_COLUMN: &str = capture::kind::TANGENTIAL_VELOCITY_MPS;

/// Metadata key of the cut-off of the observer that reported a capture's friction, rad/s.
pub const OBSERVER_CUTOFF_KEY: &str = "observer.cutoff_radps";

/// The cut-off of the observer a capture's friction went through, rad/s: for a friction column,
/// the metadata's [`OBSERVER_CUTOFF_KEY`] (without it, the friction was measured directly, by a
/// force sensor: `None`); for friction estimated here, the default [`Rfob`]'s.
pub fn observer_cutoff_radps(capture: &Capture) -> Result<Option<f64>, RecognizeError> {
    if !capture.has_column(FRICTION_COLUMN) {
        return Ok(Some(Rfob::default().cutoff_radps));
    }
    let Some(value) = capture.metadata().get(OBSERVER_CUTOFF_KEY) else {
        return Ok(None);
    };
    match value.trim().parse::<f64>() {
        Ok(g) if g.is_finite() && g > 0.0 => Ok(Some(g)),
        _ => Err(RecognizeError::Input(InputError::Metadata {
            key: OBSERVER_CUTOFF_KEY,
            value: value.to_owned(),
            reason: "a positive, finite cut-off in rad/s",
        })),
    }
}

/// The reaction-force observer (RFOB, thesis Sec. 2.1) that estimates friction for captures
/// without a `friction_force_n` column, from the commanded force and the velocity along x.
///
/// With nominal mass `M` and cut-off `g`, `F̂ = g/(s + g) · (F_cmd − M s v)`, implemented without
/// differentiating the velocity as `F̂ = LPF_g(F_cmd + M g v) − M g v` (exact discretisation of
/// the first-order low-pass). The device's own friction and gravity are not modelled (the
/// thesis identifies and subtracts them; a capture carries no model of them), so they end up in
/// the estimate. Friction is reported positive against the motion: the estimate is negated
/// where the velocity is negative.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Rfob {
    /// Nominal mass along x, kg (Table 3.1: 0.3 kg).
    pub nominal_mass_kg: f64,
    /// Observer cut-off, rad/s (Table 3.1: 50 rad/s).
    pub cutoff_radps: f64,
    /// Time constant of the pseudo-differentiator used when the capture has no velocity, s.
    pub velocity_tau_s: f64,
}

impl Default for Rfob {
    fn default() -> Self {
        Self {
            nominal_mass_kg: 0.3,
            cutoff_radps: 50.0,
            velocity_tau_s: 0.005,
        }
    }
}

impl Rfob {
    /// Friction estimated from `capture`'s `tangential_command_force_n` and velocity
    /// (`tangential_velocity_mps`, or position pseudo-differentiated when that is absent).
    pub fn friction_n(&self, capture: &Capture) -> Result<Vec<f64>, RecognizeError> {
        let usable = [self.nominal_mass_kg, self.cutoff_radps, self.velocity_tau_s]
            .iter()
            .all(|v| v.is_finite() && *v > 0.0);
        if !usable {
            return Err(RecognizeError::nakano_config(
                "RFOB mass, cut-off and time constant must be positive",
            ));
        }
        let command = capture
            .column(COMMAND_FORCE_COLUMN)
            .map_err(|e| RecognizeError::Input(InputError::NakanoColumn(Box::new(e))))?;
        let time = capture.time();
        let velocity: Cow<'_, [f64]> = match capture.column(VELOCITY_COLUMN) {
            Ok(v) => Cow::Borrowed(v),
            Err(_) => Cow::Owned(
                pseudo_differentiate(
                    time,
                    capture
                        .column(POSITION_COLUMN)
                        .map_err(|e| RecognizeError::Input(InputError::NakanoColumn(Box::new(e))))?,
                    self.velocity_tau_s,
                )
                .map_err(|e| RecognizeError::Input(InputError::Velocity(Box::new(e))))?,
            ),
        };
        let mg = self.nominal_mass_kg * self.cutoff_radps;
        let mut state = command[0] + mg * velocity[0];
        let mut out = Vec::with_capacity(command.len());
        for k in 0..command.len() {
            let input = command[k] + mg * velocity[k];
            if k > 0 {
                let dt = time[k] - time[k - 1];
                state += (1.0 - (-self.cutoff_radps * dt).exp()) * (input - state);
            }
            let reaction = state - mg * velocity[k];
            out.push(if velocity[k] < 0.0 { -reaction } else { reaction });
        }
        Ok(out)
    }
}

/// The two zero-phase moving averages, as half-widths in samples.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NakanoConfig {
    /// Half-width `H` of the detrending average: roughness = height − mean of `2H + 1` samples.
    pub highpass_half_width: usize,
    /// Half-width `S` of the smoothing before wave counting (mean of `2S + 1` samples).
    pub smoothing_half_width: usize,
    /// When set, both half-widths are scaled at every sample by the measured travel per sample,
    /// so that they span the same travel at any rubbing speed (see [`SpeedFollowing`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub follow_speed: Option<SpeedFollowing>,
}

/// How the filters follow the rubbing speed.
///
/// The cut-offs are wavelengths of travel, so a filter of fixed length in samples cuts at a
/// wavelength proportional to the speed. Following the speed, the half-widths at sample `i` are
/// `H · step_ref / step_i` and `S · step_ref / step_i` (rounded), where `step_i` is the travel
/// per sample measured over the `2·max_highpass_half_width + 1` samples centred on `i` — wide
/// enough that the encoder's quantization and noise barely move it, centred so that it needs
/// no lookahead beyond the filters'. They are capped at the maximum half-widths, which set the
/// lookahead: below the speed where the cap is reached, the filters span less travel than
/// asked. The detrending half-width is at least 1 sample.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SpeedFollowing {
    /// Travel per sample at which `H` and `S` span their wavelengths, m.
    pub reference_step_m: f64,
    /// Largest detrending half-width, samples.
    pub max_highpass_half_width: usize,
    /// Largest smoothing half-width, samples.
    pub max_smoothing_half_width: usize,
}

impl Default for NakanoConfig {
    /// 2.5 mm cut-off and 0.2 mm smoothing at 5 mm/s and 1 kHz (`H` = 250, `S` = 20), fixed in
    /// samples (not following the speed).
    fn default() -> Self {
        Self {
            highpass_half_width: 250,
            smoothing_half_width: 20,
            follow_speed: None,
        }
    }
}

/// Roughness cut-off of the default filters, m of travel (ISO 4288's `λc`, see the module doc).
pub const ROUGHNESS_CUTOFF_M: f64 = 2.5e-3;
/// Span of the default smoothing before wave counting, m of travel.
pub const WAVE_SMOOTHING_M: f64 = 0.2e-3;
/// Rubbing speed of Nakano's protocol, m/s: the default filters' spans in travel become
/// samples at this speed.
pub const PROTOCOL_SPEED_MPS: f64 = 5e-3;

impl NakanoConfig {
    /// The default filters ([`ROUGHNESS_CUTOFF_M`], [`WAVE_SMOOTHING_M`] at
    /// [`PROTOCOL_SPEED_MPS`]) for samples at `rate_hz`: the same travel at any rate, so a log at
    /// 100 Hz or 10 kHz is filtered as the 1 kHz captures are (`H` = 250, `S` = 20 there).
    pub fn at_rate(rate_hz: f64) -> Result<Self, RecognizeError> {
        Self::from_wavelengths(ROUGHNESS_CUTOFF_M, WAVE_SMOOTHING_M, PROTOCOL_SPEED_MPS, rate_hz)
    }

    /// Filters given as wavelengths of travel: the detrending average spans `cutoff_m`, the
    /// smoothing spans `smoothing_m`, at rubbing speed `speed_mps` sampled at `rate_hz`.
    pub fn from_wavelengths(
        cutoff_m: f64,
        smoothing_m: f64,
        speed_mps: f64,
        rate_hz: f64,
    ) -> Result<Self, RecognizeError> {
        let all_positive = [cutoff_m, smoothing_m, speed_mps, rate_hz]
            .iter()
            .all(|v| v.is_finite() && *v > 0.0);
        if !all_positive {
            return Err(RecognizeError::nakano_config(
                "wavelengths, speed and rate must be positive and finite",
            ));
        }
        let step_m = speed_mps / rate_hz;
        let half = |span_m: f64| (span_m / step_m / 2.0).round();
        let (h, s) = (half(cutoff_m), half(smoothing_m));
        if h > 1e7 || s > 1e7 {
            return Err(RecognizeError::nakano_config(
                "filter spans more than 10^7 samples",
            ));
        }
        Ok(Self {
            highpass_half_width: h as usize,
            smoothing_half_width: s as usize,
            follow_speed: None,
        })
    }

    /// The same filters following the measured speed ([`SpeedFollowing`]): they span their
    /// travel at `rate_hz` when the tip moves at `reference_speed_mps`, and at any speed down
    /// to `slowest_speed_mps`, below which they stay at their longest.
    pub fn following_speed(
        self,
        reference_speed_mps: f64,
        slowest_speed_mps: f64,
        rate_hz: f64,
    ) -> Result<Self, RecognizeError> {
        let all_positive = [reference_speed_mps, slowest_speed_mps, rate_hz]
            .iter()
            .all(|v| v.is_finite() && *v > 0.0);
        if !all_positive || slowest_speed_mps > reference_speed_mps {
            return Err(RecognizeError::nakano_config(
                "speeds and rate must be positive and finite, the slowest speed at most the reference",
            ));
        }
        let stretch = reference_speed_mps / slowest_speed_mps;
        let longest = |half: usize| (half as f64 * stretch).ceil();
        let (h, s) = (
            longest(self.highpass_half_width),
            longest(self.smoothing_half_width),
        );
        if h > 1e7 || s > 1e7 {
            return Err(RecognizeError::nakano_config(
                "filter spans more than 10^7 samples",
            ));
        }
        let config = Self {
            follow_speed: Some(SpeedFollowing {
                reference_step_m: reference_speed_mps / rate_hz,
                max_highpass_half_width: (h as usize).max(1),
                max_smoothing_half_width: s as usize,
            }),
            ..self
        };
        config.check()?;
        Ok(config)
    }

    /// Whether the configuration can be used: a speed-following one needs a positive finite
    /// reference step and maximum half-widths at least the nominal ones (and at least 1 for the
    /// detrending, which measures the speed over its span).
    pub fn check(&self) -> Result<(), RecognizeError> {
        let Some(follow) = &self.follow_speed else {
            return Ok(());
        };
        let usable = follow.reference_step_m.is_finite()
            && follow.reference_step_m > 0.0
            && follow.max_highpass_half_width >= self.highpass_half_width.max(1)
            && follow.max_smoothing_half_width >= self.smoothing_half_width;
        if usable {
            Ok(())
        } else {
            Err(RecognizeError::nakano_config(
                "speed following needs a positive reference step and maximum half-widths at least the nominal ones",
            ))
        }
    }

    /// The longest half-widths the filters take, `(H, S)`: the nominal ones, or the maxima when
    /// following the speed.
    pub fn max_half_widths(&self) -> (usize, usize) {
        match &self.follow_speed {
            None => (self.highpass_half_width, self.smoothing_half_width),
            Some(f) => (f.max_highpass_half_width, f.max_smoothing_half_width),
        }
    }

    /// Half-widths `(H, S)` at a sample where the tip travels `step_m` per sample (measured as
    /// [`SpeedFollowing`] says); the nominal ones when not following the speed.
    pub fn half_widths_at(&self, step_m: f64) -> (usize, usize) {
        let Some(follow) = &self.follow_speed else {
            return (self.highpass_half_width, self.smoothing_half_width);
        };
        // A stationary tip (step 0) takes the longest filters; the ratio is computed first so
        // that exactly the reference step gives exactly the nominal widths.
        let ratio = follow.reference_step_m / step_m;
        let scale = |half: usize, max: usize| {
            let w = (half as f64 * ratio).round();
            if w.is_nan() || w >= max as f64 {
                max
            } else {
                w as usize
            }
        };
        (
            scale(self.highpass_half_width, follow.max_highpass_half_width).max(1),
            scale(self.smoothing_half_width, follow.max_smoothing_half_width),
        )
    }

    /// Samples the filters need beyond a window's last sample (and before its first): `H + S`
    /// at their longest.
    pub fn lookahead_samples(&self) -> usize {
        let (h, s) = self.max_half_widths();
        h + s
    }
}

/// The three signals Nakano's features read, borrowed from a capture or from slices.
#[derive(Debug, Clone)]
pub struct NakanoSignals<'a> {
    position_m: &'a [f64],
    height_m: &'a [f64],
    friction_n: Cow<'a, [f64]>,
}

impl<'a> NakanoSignals<'a> {
    /// The columns `tangential_position_m`, `normal_position_m` and `friction_force_n`; without
    /// a friction column, friction is estimated by the default [`Rfob`] from
    /// `tangential_command_force_n` (an error names that column if it is missing too).
    pub fn from_capture(capture: &'a Capture) -> Result<Self, RecognizeError> {
        let friction_n = match capture.column(FRICTION_COLUMN) {
            Ok(f) => Cow::Borrowed(f),
            Err(_) => Cow::Owned(Rfob::default().friction_n(capture)?),
        };
        Ok(Self {
            position_m: capture
                .column(POSITION_COLUMN)
                .map_err(|e| RecognizeError::Input(InputError::NakanoColumn(Box::new(e))))?,
            height_m: capture
                .column(HEIGHT_COLUMN)
                .map_err(|e| RecognizeError::Input(InputError::NakanoColumn(Box::new(e))))?,
            friction_n,
        })
    }

    /// Signals from slices of equal length.
    pub fn new(
        position_m: &'a [f64],
        height_m: &'a [f64],
        friction_n: &'a [f64],
    ) -> Result<Self, RecognizeError> {
        if position_m.len() != height_m.len() || position_m.len() != friction_n.len() {
            return Err(RecognizeError::Usage(UsageError::SignalLengths {
                position: position_m.len(),
                height: height_m.len(),
                friction: friction_n.len(),
            }));
        }
        Ok(Self {
            position_m,
            height_m,
            friction_n: Cow::Borrowed(friction_n),
        })
    }

    /// The same signals with the friction passed through `filter` from the first sample on
    /// ([`FrictionOverTravel`]).
    pub fn with_friction_over_travel(self, filter: &mut TravelFriction) -> Self {
        let friction_n = filter.apply(self.position_m, &self.friction_n);
        Self {
            friction_n: Cow::Owned(friction_n),
            ..self
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.position_m.len()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.position_m.is_empty()
    }

    /// Height of the tip, m.
    pub fn height_m(&self) -> &'a [f64] {
        self.height_m
    }

    /// Friction along the rubbing direction, N (measured, or the RFOB's estimate).
    pub fn friction_n(&self) -> &[f64] {
        &self.friction_n
    }

    /// Position along the rubbing direction, m.
    pub fn position_m(&self) -> &'a [f64] {
        self.position_m
    }

    /// Features (Eq. 2.23) of the window of `len` samples starting at `start`. The window needs
    /// [`NakanoConfig::lookahead_samples`] samples of margin on each side for the filters.
    pub fn features(
        &self,
        start: usize,
        len: usize,
        config: &NakanoConfig,
    ) -> Result<[f64; FEATURES], RecognizeError> {
        window_features(
            self.position_m,
            self.height_m,
            &self.friction_n,
            start,
            len,
            config,
            &mut FeatureBuffers::default(),
        )
    }
}

/// Working memory of one window's features, kept between windows so that a live recognizer
/// computes them without allocating.
#[derive(Debug, Clone, Default)]
struct FeatureBuffers {
    prefix: Vec<f64>,
    rough: Vec<f64>,
    smoothing: Vec<usize>,
    rough_prefix: Vec<f64>,
}

impl FeatureBuffers {
    /// Room for a window of `len` samples and a margin of `margin` each side.
    fn with_capacity(len: usize, margin: usize) -> Self {
        let span = len + 2 * margin + 1;
        Self {
            prefix: Vec::with_capacity(span),
            rough: Vec::with_capacity(span),
            smoothing: Vec::with_capacity(span),
            rough_prefix: Vec::with_capacity(span),
        }
    }
}

/// [`NakanoSignals::features`] on signals given as slices, in `buffers`.
fn window_features(
    position_m: &[f64],
    height_m: &[f64],
    friction_n: &[f64],
    start: usize,
    len: usize,
    config: &NakanoConfig,
    buffers: &mut FeatureBuffers,
) -> Result<[f64; FEATURES], RecognizeError> {
    if len < 2 {
        return Err(RecognizeError::Setting(SettingError::WindowTooShort { len }));
    }
    let margin = config.lookahead_samples();
    let out_of_range = RecognizeError::Usage(UsageError::WindowOutOfRange {
        start,
        len,
        margin,
        samples: position_m.len(),
    });
    let (Some(first), Some(end)) = (start.checked_sub(margin), start.checked_add(len)) else {
        return Err(out_of_range);
    };
    match end.checked_add(margin) {
        Some(last) if last <= position_m.len() && last <= height_m.len() && end <= friction_n.len() => {}
        _ => return Err(out_of_range),
    }
    config.check()?;
    let (hmax, smax) = config.max_half_widths();
    // Local indices below are into `z` and `x`, which start at sample `first`.
    let z = &height_m[first..end + margin];
    let x = &position_m[first..end + margin];
    let z_ref = z[0];
    // Prefix sums of the height relative to the first sample used (keeps the sums small).
    let FeatureBuffers {
        prefix,
        rough,
        smoothing,
        rough_prefix,
    } = buffers;
    prefix_sums_into(z.iter().map(|v| v - z_ref), prefix);
    // Half-widths at local index j (needs j ± hmax inside `x`).
    let widths = |j: usize| config.half_widths_at(step_m(x[j - hmax], x[j + hmax], hmax));
    // Roughness at local index j with half-width h (needs j − h ≥ 0 and j + h < z.len()).
    let rough_at =
        |j: usize, h: usize| (z[j] - z_ref) - (prefix[j + h + 1] - prefix[j - h]) / (2 * h + 1) as f64;
    // Roughness over the window and `smax` samples each side, for the smoothing, with the
    // smoothing half-width at each of those samples.
    let offset = margin - smax; // local index of sample start − smax
    rough.clear();
    smoothing.clear();
    for j in offset..offset + len + 2 * smax {
        let (h, s) = widths(j);
        rough.push(rough_at(j, h));
        smoothing.push(s);
    }
    let window = &rough[smax..smax + len];
    let n = len as f64;
    let mean_abs = window.iter().map(|v| v.abs()).sum::<f64>() / n;
    let mean = window.iter().sum::<f64>() / n;
    let var = window.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
    // Smoothed roughness at each window sample, then upward crossings between neighbours.
    prefix_sums_into(rough.iter().copied(), rough_prefix);
    let smoothed = |i: usize| {
        let s = smoothing[i];
        (rough_prefix[i + s + 1] - rough_prefix[i - s]) / (2 * s + 1) as f64
    };
    let waves = (smax + 1..smax + len)
        .filter(|&i| smoothed(i - 1) < -CROSSING_GUARD_M && smoothed(i) >= -CROSSING_GUARD_M)
        .count();
    let travel = (position_m[end - 1] - position_m[start]).abs();
    let wavelength = travel / waves.max(1) as f64;
    let f = &friction_n[start..end];
    let f_mean = f.iter().sum::<f64>() / n;
    let f_var = f.iter().map(|v| (v - f_mean).powi(2)).sum::<f64>() / n;
    Ok([mean_abs, var, wavelength, f_mean, f_var])
}

/// Sums of the values before each index into `out`: `out[k]` = sum of the first `k` values.
fn prefix_sums_into(values: impl Iterator<Item = f64>, out: &mut Vec<f64>) {
    out.clear();
    let mut acc = 0.0;
    out.push(acc);
    for v in values {
        acc += v;
        out.push(acc);
    }
}

/// Travel per sample between two positions `2 · half` samples apart, m (`half` ≥ 1; with 0 the
/// speed is not followed and the step is unused).
fn step_m(before: f64, after: f64, half: usize) -> f64 {
    (after - before).abs() / (2 * half.max(1)) as f64
}

/// Features of the window of `len` samples starting at `start` of `capture` (see
/// [`NakanoSignals::features`]).
pub fn capture_features(
    capture: &Capture,
    start: usize,
    len: usize,
    config: &NakanoConfig,
) -> Result<[f64; FEATURES], RecognizeError> {
    NakanoSignals::from_capture(capture)?.features(start, len, config)
}

/// A stroke's signals extended before its first sample by `pad` samples of their mirror image,
/// so that the zero-phase filters have their margin at the very start: the heights and positions
/// are reflected through the first sample (`2·v₀ − v_j`, which continues a slope and a tilt
/// straight on, where an even reflection would fold them into a kink the high-pass would call
/// roughness), the friction repeated as its mirror (it is never filtered, and no window reaches
/// before the first sample). The roughness a reflected profile shows has the amplitude and
/// wavelengths of the real one, so the first windows' features are those of a stroke that had
/// started earlier, not of a truncated filter. `None` for a stroke of at most `pad` samples.
pub fn mirror_start(signals: &NakanoSignals<'_>, pad: usize) -> Option<(Vec<f64>, Vec<f64>, Vec<f64>)> {
    if signals.len() <= pad {
        return None;
    }
    let reflect = |v: &[f64]| -> Vec<f64> {
        (1..=pad)
            .rev()
            .map(|j| 2.0 * v[0] - v[j])
            .chain(v.iter().copied())
            .collect()
    };
    let f = &signals.friction_n;
    Some((
        reflect(signals.position_m),
        reflect(signals.height_m),
        (1..=pad).rev().map(|j| f[j]).chain(f.iter().copied()).collect(),
    ))
}

mod edge;
mod friction;
mod stream;

pub use edge::EdgeWindow;
pub use friction::{FrictionOverTravel, MAX_GAIN, SPEED_SMOOTHING_S, TravelFriction};
pub use stream::{NakanoStream, StreamWindow};

#[cfg(test)]
mod tests;
