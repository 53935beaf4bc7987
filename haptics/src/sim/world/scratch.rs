//! Ground truth for vibrotactile scratching (Sinapov et al., "Vibrotactile recognition and
//! categorization of surfaces by a humanoid robot", IEEE T-RO 27(3), 2011).
//!
//! # The experiment being simulated
//! A Barrett WAM carries an ABS fingernail with an ADXL345 three-axis accelerometer on it
//! (Sinapov Sec. III-A). The nail scratches 20 household surfaces, plus air as a control,
//! with five behaviours (Table I): three lateral strokes (left to right) and two medial ones
//! (back to front), each about 12 inches long, played back from one recorded trajectory at
//! different speeds (Sec. III-D). A constant extra shoulder torque keeps the nail in contact.
//! The accelerometer is read over USB at 400 Hz, 10 bits per axis, through its on-board
//! digital low-pass filter and with no analog anti-aliasing filter (Sec. III-A). Each
//! behaviour is performed 10 times on each surface, and the surface is taken away and put
//! back between rounds (Sec. III-E).
//!
//! # The model, from surface to bits
//! 1. **Surface** ([`ScratchSurface`]): a fixed object whose height field is a sum of
//!    straight-crested random waves ("layers"), each a band-limited [`Profile`] along its
//!    own wave direction. Directional textures (corduroy ribs, wood grain, mat grids, bubble
//!    lattices) are one layer per direction; isotropic roughness is three layers 60° apart,
//!    the turning-bands construction (Matheron 1973; Mantoglou & Wilson 1982) that makes a
//!    2-D field with direction-independent statistics from 1-D processes. The relief is drawn
//!    from the surface id and [`WORLD_SEED`], never from the trial seed: every trial scratches
//!    the same object.
//! 2. **Placement and stroke**: each round puts the surface down at a random offset and a
//!    small rotation; the arm then moves the nail 0.305 m along a straight line with
//!    raised-cosine speed ramps. A layer with wave direction θ seen along a
//!    stroke of direction φ has its wavelength stretched by `1 / |cos(θ − φ)|`, so the same
//!    ribs give very different temporal frequencies to lateral and medial strokes, and the
//!    temporal frequency of any feature is `speed / wavelength`.
//! 3. **Nail** ([`scratch_trial`]): the nail tip averages the relief over its contact patch
//!    (longer on soft surfaces, so they absorb fine texture), then three linear modes of the
//!    nail, board and fingertip respond. Normally the nail is base-excited by the height under
//!    the contact through the surface's contact spring and damper (stiff surfaces ring high,
//!    soft ones low and damped), so its acceleration grows as `(speed / wavelength)²` below the
//!    mode; tangentially and sideways it is driven by the contact forces: friction (with
//!    stick-slip through the surface's shear compliance) and the normal force's tangential
//!    share on sloped relief ("ploughing"). Contact is unilateral: the force never pulls.
//! 4. **Arm**: the fingertip hangs on the arm's lowest (sway) mode, base-excited by the
//!    commanded motion and servo jitter, plus motor torque ripple whose frequency follows the
//!    speed. Air sees only this and the sensor's own noise.
//! 5. **Sensor** ([`Adxl345`] constants): specific force (gravity included) rotated into the
//!    sensor axes by a nail orientation that differs per trial and drifts during the stroke,
//!    a first-order digital low-pass at ODR/2 = 200 Hz, decimation to 400 Hz with no other
//!    filtering (so content above 200 Hz aliases, as in the real data), calibration
//!    errors, noise, 10-bit quantization and clipping at ±4 g.
//!
//! # What changes from trial to trial
//! Per round (shared by the five behaviours, as the surface stayed put): where and at what
//! angle the surface lies, hence which strip is scratched; how it lies (a log-normal factor on
//! the contact stiffness: folds in cloth, air under paper); and, through the strip, how rough
//! that part of the surface is (patches of wear and fuzz, [`Contact::patchiness`]). Per trial:
//! speed ±5 %, contact force ±15 % (which moves the contact mode and patch by Hertz's laws),
//! a millimetre of start position, the heading, the nail's orientation and its drift, servo
//! jitter and sensor noise. Surfaces built alike (the two papers, the two doormats) end up
//! about as far apart as two trials on one of them.
//!
//! Everything is simulated at [`SIM_RATE_HZ`] (8 kHz), well above the modes and the
//! texture frequencies that matter, with semi-implicit Euler steps (stable for `ω·dt < 2`;
//! here `ω·dt < 0.2`).

mod contact;
mod table;
#[cfg(test)]
mod tests;

use std::f64::consts::{FRAC_PI_2, FRAC_PI_3, PI, TAU};
use std::fmt;
use std::sync::Arc;

use capture::rng::stream_seed;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::profile::{Band, Profile};
use super::sensor::{LowPass, Noise, round_to};

pub use contact::{Contact, Texture};

/// Output data rate of the accelerometer as Sinapov et al. read it (Sec. III-A: "400 Hz").
pub const ACCEL_RATE_HZ: f64 = 400.0;
/// Internal simulation rate. A multiple of [`ACCEL_RATE_HZ`] so that the accelerometer output
/// is every `DECIMATION`-th internal sample (the ADXL345 samples, it does not average).
pub const SIM_RATE_HZ: f64 = 8000.0;
const DECIMATION: usize = 20;
/// Length of every stroke: "approximately 12 inches" (Sinapov Sec. III-D).
pub const STROKE_M: f64 = 0.305;
/// Standard gravity, for g ↔ m/s² conversions and the gravity the accelerometer feels.
pub const STANDARD_GRAVITY_MPS2: f64 = 9.80665;
/// Fixed world seed from which every surface's relief is drawn (with its id).
pub const WORLD_SEED: u64 = 0x5CA7_C4ED_2011_0400;

/// Which measurement range and resolution the simulated ADXL345 runs at.
///
/// Sinapov et al. used 10-bit resolution (Sec. III-A). In 10-bit mode the data sheet (Analog
/// Devices ADXL345 Rev. E, Table 1) gives 256 LSB/g at ±2 g and 128 LSB/g at ±4 g. The roughest
/// surfaces here (bubble wrap, the floor mats, fast strokes) reach peaks above 1 g on top of the
/// gravity component of an axis, which ±2 g would clip, so the ±4 g range is used:
/// 7.8125 mg/LSB, codes −512..=511.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Adxl345;

impl Adxl345 {
    /// Measurement range, ± this many g.
    pub const RANGE_G: f64 = 4.0;
    /// One code: 1/128 g (data sheet Table 1, ±4 g, 10-bit).
    pub const LSB_MPS2: f64 = STANDARD_GRAVITY_MPS2 / 128.0;
    /// Most negative and most positive codes of a 10-bit two's complement reading.
    pub const CODE_MIN: i32 = -512;
    /// See [`Adxl345::CODE_MIN`].
    pub const CODE_MAX: i32 = 511;
    /// Bandwidth of the on-board digital filter: ODR/2 (data sheet Table 7, 400 Hz ODR →
    /// 200 Hz). Modelled as one first-order pole; the part has no analog anti-aliasing.
    pub const BANDWIDTH_HZ: f64 = 200.0;
    /// Noise per axis in g RMS at 400 Hz ODR. Data sheet, "Noise Performance": at 400 Hz ODR
    /// typically below 1.5 LSB RMS on x and y and 2.2 LSB RMS on z, at 3.9 mg/LSB (noise
    /// densities 290 and 430 µg/√Hz). The noise is analog, so it is the same in g whatever the
    /// range.
    pub const NOISE_G: [f64; 3] = [0.0059, 0.0059, 0.0086];
    /// Zero-g offset of this particular part, in g: one fixed draw well inside the data sheet's
    /// 0 g output limits (±150 mg on x and y, ±250 mg on z). The same sensor was used for
    /// every trial, so it is a constant.
    pub const OFFSET_G: [f64; 3] = [0.021, -0.034, 0.045];
    /// Relative sensitivity error of this part per axis (data sheet: 115..141 LSB/g around
    /// 128 at ±4 g, 10-bit, i.e. up to ±10 %); again fixed.
    pub const GAIN_ERROR: [f64; 3] = [0.012, -0.018, 0.025];
}

/// One of the five exploratory behaviours (Sinapov Table I).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Behaviour {
    /// Left to right, 3.9 s.
    LateralFast,
    /// Left to right, 7.5 s.
    LateralMedium,
    /// Left to right, 14.7 s.
    LateralSlow,
    /// Back to front, 4.6 s.
    MedialFast,
    /// Back to front, 7.9 s.
    MedialMedium,
}

impl Behaviour {
    /// All five, in Table I order.
    pub const ALL: [Behaviour; 5] = [
        Self::LateralFast,
        Self::LateralMedium,
        Self::LateralSlow,
        Self::MedialFast,
        Self::MedialMedium,
    ];

    /// Name for files and metadata.
    pub fn name(self) -> &'static str {
        match self {
            Self::LateralFast => "lateral_fast",
            Self::LateralMedium => "lateral_medium",
            Self::LateralSlow => "lateral_slow",
            Self::MedialFast => "medial_fast",
            Self::MedialMedium => "medial_medium",
        }
    }

    /// Nominal duration of the stroke (Sinapov Table I). Fast is the default playback speed
    /// doubled and slow halved (Sec. III-D), which these durations roughly reflect.
    pub fn duration_s(self) -> f64 {
        match self {
            Self::LateralFast => 3.9,
            Self::LateralMedium => 7.5,
            Self::LateralSlow => 14.7,
            Self::MedialFast => 4.6,
            Self::MedialMedium => 7.9,
        }
    }

    /// Sliding direction in the world (and, before placement rotation, on the surface): lateral
    /// strokes along +x (left to right), medial ones along +y (back to front).
    pub fn direction_rad(self) -> f64 {
        match self {
            Self::LateralFast | Self::LateralMedium | Self::LateralSlow => 0.0,
            Self::MedialFast | Self::MedialMedium => FRAC_PI_2,
        }
    }

    /// Length of the stroke: the same for every behaviour (Sec. III-D, "approximately 12 inches").
    pub fn stroke_m(self) -> f64 {
        STROKE_M
    }

    /// Position in [`Behaviour::ALL`], used to separate random streams.
    fn index(self) -> u64 {
        match self {
            Self::LateralFast => 0,
            Self::LateralMedium => 1,
            Self::LateralSlow => 2,
            Self::MedialFast => 3,
            Self::MedialMedium => 4,
        }
    }

    fn is_medial(self) -> bool {
        matches!(self, Self::MedialFast | Self::MedialMedium)
    }
}

/// A household surface (or air) as the fingernail sees it.
///
/// The relief (the height field) is synthesised once, in [`ScratchSurface::new`], from the
/// id, the texture parameters and [`WORLD_SEED`]; it is shared between clones. If the id or
/// the public texture parameters are changed afterwards, [`scratch_trial`] notices and
/// synthesises the relief again for that call (correct, but slow: build a new surface
/// instead). The other parameters are read at every trial.
#[derive(Clone)]
pub struct ScratchSurface {
    /// Number in Sinapov Fig. 3 (1..=20), air is 21.
    pub id: u32,
    /// Name after Sinapov Fig. 3, snake case.
    pub name: &'static str,
    /// The contact model; `None` for air (no contact, the control condition).
    pub contact: Option<Contact>,
    relief: Arc<Relief>,
}

impl ScratchSurface {
    /// A surface with the given contact model (or air for `None`); synthesises its relief.
    pub fn new(id: u32, name: &'static str, contact: Option<Contact>) -> Self {
        let relief = Arc::new(Relief::synthesize(id, contact.as_ref()));
        Self {
            id,
            name,
            contact,
            relief,
        }
    }

    /// True for the control condition: nothing to touch.
    pub fn is_air(&self) -> bool {
        self.contact.is_none()
    }

    /// Nominal contact force on this surface before the per-trial variation, in N (0 for air).
    pub fn nominal_force_n(&self) -> f64 {
        self.contact.as_ref().map_or(0.0, |c| {
            BASE_FORCE_N + CONTROLLER_STIFFNESS_N_PER_M * c.thickness_m.max(0.0)
        })
    }
}

impl PartialEq for ScratchSurface {
    /// The relief is a function of the id and the parameters, so comparing those suffices.
    fn eq(&self, other: &Self) -> bool {
        self.id == other.id && self.name == other.name && self.contact == other.contact
    }
}

impl fmt::Debug for ScratchSurface {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("ScratchSurface")
            .field("id", &self.id)
            .field("name", &self.name)
            .field("contact", &self.contact)
            .field("relief_layers", &self.relief.layers.len())
            .finish()
    }
}

/// The 20 household surfaces of Sinapov et al. (Fig. 3) and air (21 entries, air last), ids as
/// numbered in Sinapov Fig. 3; their contact models are in `table.rs`.
pub fn household_surfaces() -> Vec<ScratchSurface> {
    table::household_contacts()
        .into_iter()
        .map(|(id, name, contact)| ScratchSurface::new(id, name, contact))
        .collect()
}

/// One recorded trial as the accelerometer and the arm saw it, sampled at [`ACCEL_RATE_HZ`].
#[derive(Debug, Clone, PartialEq)]
pub struct ScratchRecording {
    /// `k / 400`, starting at 0.
    pub time_s: Vec<f64>,
    /// Arc length along the stroke from the arm encoders, rounded to 1e-5 m.
    pub tangential_position_m: Vec<f64>,
    /// Contact force, rounded to 1e-4 N (0 for air and whenever the nail is off the surface).
    pub normal_force_n: Vec<f64>,
    /// Sensor x, y, z in m/s², gravity included, quantized to the ADXL345 LSB (see [`Adxl345`])
    /// and clipped at its range, then rounded to 1e-4.
    pub accel_mps2: [Vec<f64>; 3],
    /// Ground truth for the capture's metadata (`truth.*` keys, values without whitespace).
    pub truth: Vec<(String, String)>,
}

// ---------------------------------------------------------------------------------------------
// World constants. Each says where it comes from.
// ---------------------------------------------------------------------------------------------

/// Side of the square of surface from which a placement offset is drawn; every layer is
/// periodic, so any offset lands on a valid, different patch.
const SURFACE_SIDE_M: f64 = 0.6;
/// Contact force with no surface thickness: Sinapov's constant extra shoulder torque (a few
/// N·m, Sec. III-D) over a lever arm of roughly a metre gives a few newtons.
const BASE_FORCE_N: f64 = 2.6;
/// Stiffness of the WAM's position loop at the fingertip in the pressing direction: a surface
/// `t` thick raises the contact by `t` above the recorded path and adds `k·t`.
const CONTROLLER_STIFFNESS_N_PER_M: f64 = 50.0;
/// Per-trial spread of the contact force (uniform, ±): the torque is constant but the pose at
/// contact, and with it the lever arm, is not.
const FORCE_SPREAD: f64 = 0.15;
/// Per-trial spread of the playback speed (uniform, ±): PID tracking of a recorded trajectory.
const SPEED_SPREAD: f64 = 0.05;
/// Duration of each raised-cosine speed ramp (start and stop), capped at a quarter of the
/// stroke's duration: a PID playing back a recorded trajectory starts and stops smoothly.
const RAMP_S: f64 = 0.35;
/// Along-stroke change of the contact force, as a fraction, from start to end: reaching
/// forward (medial) lengthens the lever arm of the constant shoulder torque; lateral strokes
/// swing around the shoulder and change it little.
const FORCE_DRIFT_MEDIAL: f64 = -0.12;
const FORCE_DRIFT_LATERAL: f64 = 0.03;
/// Effective mass of nail, evaluation board and tape on the normal contact spring, in kg.
const NAIL_MASS_KG: f64 = 0.025;
/// Effective mass of the in-plane (tangential and sideways) modes, in kg: the nail bends with
/// the distal finger link it is taped to, so more of the finger takes part than normally.
const IN_PLANE_MASS_KG: f64 = 0.06;
/// Tangential (bending) and sideways modes of the nail on the finger, in Hz.
const TANGENTIAL_MODE_HZ: f64 = 140.0;
const CROSS_MODE_HZ: f64 = 180.0;
/// Least damping of the nail's own modes, whatever the surface (taped ABS on a finger).
const NAIL_DAMPING_MIN: f64 = 0.08;
/// Nominal sensor orientation relative to the world (roll, pitch, yaw; ZYX), in rad: the nail
/// meets the surface inclined by about 35°. Per-trial jitter and along-stroke pitch drift
/// come on top (Sec. III-D: orientation was not held constant).
const NAIL_ORIENTATION_RAD: [f64; 3] = [0.10, 0.60, 0.20];
const NAIL_JITTER_RAD: f64 = 0.035;
const PITCH_DRIFT_LATERAL_RAD: f64 = 0.07;
const PITCH_DRIFT_MEDIAL_RAD: f64 = 0.12;
/// Placement of the surface between rounds: rotation spread (uniform, ±) and how far the
/// start of the stroke wanders per behaviour (RMS, both axes), and the path's heading error.
const PLACEMENT_ROTATION_RAD: f64 = 0.05;
const START_JITTER_M: f64 = 1e-3;
const HEADING_JITTER_RAD: f64 = 0.01;
/// Arm sway: the WAM's lowest structural mode as seen at the fingertip, and the servo jitter
/// that excites it (RMS acceleration noise, held for one output period).
const ARM_MODE_HZ: f64 = 9.0;
const ARM_DAMPING: f64 = 0.1;
const SERVO_JITTER_MPS2: f64 = 0.1;
/// Motor torque ripple: its period in fingertip travel (motor electrical cycle through the
/// cable reductions) and amplitude along-stroke and vertically, in m/s².
const RIPPLE_WAVELENGTH_M: f64 = 3e-3;
const RIPPLE_ALONG_MPS2: f64 = 0.03;
const RIPPLE_VERTICAL_MPS2: f64 = 0.02;
/// Grid step of the along-path signals precomputed per trial.
const PATH_STEP_M: f64 = 20e-6;
/// The patchiness envelope is sampled every this many path points (0.64 mm) and interpolated.
const ENVELOPE_STRIDE: usize = 32;

// ---------------------------------------------------------------------------------------------
// Relief
// ---------------------------------------------------------------------------------------------

/// What a layer of the relief contributes.
#[derive(Clone, Copy, PartialEq, Eq)]
enum LayerKind {
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
struct Layer {
    heights_m: Vec<f64>,
    spacing_m: f64,
    orientation_rad: f64,
    kind: LayerKind,
}

impl Layer {
    fn new(profile: &Profile, orientation_rad: f64, kind: LayerKind) -> Self {
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
    fn walk(&self, xi0_m: f64, step_m: f64, count: usize, mut f: impl FnMut(usize, f64, f64)) {
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
struct Relief {
    id: u32,
    roughness: Option<Band>,
    textures: Vec<Texture>,
    layers: Vec<Layer>,
}

/// Typical size of the patches over which a surface's roughness amplitude changes.
pub const PATCH_WAVELENGTH_M: f64 = 0.12;

/// Number of turning bands for isotropic roughness: 3 directions 60° apart already give a
/// directional RMS within a few per cent of the mean.
const TURNING_BANDS: usize = 3;

impl Relief {
    fn synthesize(id: u32, contact: Option<&Contact>) -> Self {
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

    fn built_from(&self, id: u32, contact: Option<&Contact>) -> bool {
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
fn synthesize_layer(band: Band, rng: &mut ChaCha8Rng) -> Profile {
    let shortest = band.wavelength_m * (-2.5 * band.log_width).exp();
    let spacing = (shortest / 10.0).clamp(20e-6, 0.5e-3);
    let n = ((SURFACE_SIDE_M / spacing).ceil() as usize).next_power_of_two();
    Profile::synthesize(&[band], spacing, n, rng)
}

// ---------------------------------------------------------------------------------------------
// Random streams
// ---------------------------------------------------------------------------------------------

const TAG_RELIEF: u64 = 1;
const TAG_PLACEMENT: u64 = 2;
const TAG_TRIAL: u64 = 3;

// ---------------------------------------------------------------------------------------------
// Stroke kinematics
// ---------------------------------------------------------------------------------------------

/// A straight stroke of fixed length played back in a given time: raised-cosine speed ramps at
/// both ends around a constant-speed middle. The plateau speed is `length / (duration − ramp)`
/// since each half-cosine ramp covers half the distance of a constant-speed one. The
/// acceleration is continuous, as a PID tracking a smooth recorded trajectory would give.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Stroke {
    length_m: f64,
    duration_s: f64,
    ramp_s: f64,
    speed_mps: f64,
}

impl Stroke {
    fn new(length_m: f64, duration_s: f64) -> Self {
        let ramp_s = RAMP_S.min(0.25 * duration_s);
        Self {
            length_m,
            duration_s,
            ramp_s,
            speed_mps: length_m / (duration_s - ramp_s),
        }
    }

    /// Arc length, speed and acceleration at time `t_s`.
    fn at(&self, t_s: f64) -> (f64, f64, f64) {
        let t = t_s.clamp(0.0, self.duration_s);
        let (v, tr) = (self.speed_mps, self.ramp_s);
        if t < tr {
            let (sin, cos) = (PI * t / tr).sin_cos();
            (
                0.5 * v * (t - tr / PI * sin),
                0.5 * v * (1.0 - cos),
                0.5 * v * PI / tr * sin,
            )
        } else if t > self.duration_s - tr {
            let tau = self.duration_s - t;
            let (sin, cos) = (PI * tau / tr).sin_cos();
            (
                self.length_m - 0.5 * v * (tau - tr / PI * sin),
                0.5 * v * (1.0 - cos),
                -0.5 * v * PI / tr * sin,
            )
        } else {
            (0.5 * v * tr + v * (t - tr), v, 0.0)
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Along-path signals
// ---------------------------------------------------------------------------------------------

/// The relief as met along one stroke, on a uniform grid of arc length: height, sideways
/// slope, normalised roughness (for the friction) and the motor ripple phase.
struct PathSignals {
    /// Per grid point: height (m), sideways slope, normalised roughness, ripple phase sine.
    points: Vec<[f64; 4]>,
}

/// Values at one arc length.
#[derive(Clone, Copy, Default)]
struct PathSample {
    height_m: f64,
    slope: f64,
    cross_slope: f64,
    roughness: f64,
    ripple: f64,
}

impl PathSignals {
    /// Samples every layer along the line from `start` (surface coordinates, m) in direction
    /// `heading_rad` (surface coordinates). A layer with wave direction θ is met at
    /// `ξ = start·(cos θ, sin θ) + s·cos(θ − φ)`; its gradient `p'(ξ)·(cos θ, sin θ)` has the
    /// sideways component `p'(ξ)·sin(θ − φ)`.
    fn new(relief: &Relief, contact: Option<&Contact>, setup: &TrialSetup) -> Self {
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
    fn at(&self, s_m: f64) -> PathSample {
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
fn boxcar(v: &[f64], half: usize) -> Vec<f64> {
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

// ---------------------------------------------------------------------------------------------
// Nail dynamics
// ---------------------------------------------------------------------------------------------

/// A damped mode `x'' = −ω²x − 2ζωx' + f/m`, stepped by semi-implicit Euler.
#[derive(Debug, Clone, Copy)]
struct Mode {
    omega: f64,
    zeta: f64,
    x: f64,
    v: f64,
}

impl Mode {
    fn new(hz: f64, zeta: f64) -> Self {
        Self {
            omega: TAU * hz,
            zeta,
            x: 0.0,
            v: 0.0,
        }
    }

    /// Puts the mode at rest in equilibrium under a constant specific force (m/s²).
    fn settle(&mut self, f_per_m: f64) {
        self.x = f_per_m / (self.omega * self.omega);
        self.v = 0.0;
    }

    /// Spring and damper acceleration `−ω²x − 2ζωx'` in the current state.
    fn restoring(&self) -> f64 {
        -self.omega * self.omega * self.x - 2.0 * self.zeta * self.omega * self.v
    }

    /// Advances by `dt` under the specific force `f_per_m` (m/s²); returns the acceleration.
    fn step(&mut self, f_per_m: f64, dt: f64) -> f64 {
        let a = -self.omega * self.omega * self.x - 2.0 * self.zeta * self.omega * self.v + f_per_m;
        self.v += a * dt;
        self.x += self.v * dt;
        a
    }
}

/// The friction contact: a shear spring between nail tip and surface that stays stuck until
/// its force exceeds the static limit `μ_s·F`, then slips. Slipping is fast next to sticking
/// (the relaxation-oscillation regime), so a slip is one step in which the force falls by
/// `2·Δμ·F` (an undamped release overshoots the kinetic level by as much as it started above
/// it). The excess travel past the limit is carried, so the mean stick-slip period is
/// `2·Δμ·F / (k·w)` exactly, whatever the time step. With `Δμ = 0` the force simply saturates
/// at `μ_k·F`: smooth sliding whose force still follows the local friction coefficient.
#[derive(Debug, Clone, Copy)]
struct ShearContact {
    stiffness_n_per_m: f64,
    stretch_m: f64,
}

impl ShearContact {
    /// Advances by `dt` at sliding speed `w_mps`; returns the friction force on the nail,
    /// positive along the stroke's direction of motion resisting it (i.e. the drag).
    fn step(&mut self, w_mps: f64, mu_k: f64, d_mu: f64, normal_n: f64, dt: f64) -> f64 {
        let k = self.stiffness_n_per_m;
        self.stretch_m += w_mps * dt;
        let limit = (mu_k + d_mu) * normal_n;
        let kinetic = mu_k * normal_n / k;
        let drop = 2.0 * d_mu * normal_n / k;
        if k * self.stretch_m > limit {
            self.stretch_m = (self.stretch_m - drop).min(kinetic);
        } else if k * self.stretch_m < -limit {
            self.stretch_m = (self.stretch_m + drop).max(-kinetic);
        }
        k * self.stretch_m
    }
}

/// The nail orientation as a sensor-to-world rotation (ZYX Euler angles).
fn rotation(roll: f64, pitch: f64, yaw: f64) -> [[f64; 3]; 3] {
    let (sr, cr) = roll.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    let (sy, cy) = yaw.sin_cos();
    [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
}

/// Everything about one trial that is drawn at random, and what the arm does.
#[derive(Debug, Clone, Copy)]
struct TrialSetup {
    stroke: Stroke,
    force_n: f64,
    force_drift: f64,
    start_m: [f64; 2],
    /// Heading of the stroke in the world and on the (rotated) surface.
    world_heading_rad: f64,
    surface_heading_rad: f64,
    placement_rotation_rad: f64,
    nail_rad: [f64; 3],
    pitch_drift_rad: f64,
    ripple_phase: f64,
    /// This trial's normal contact mode and contact patch length (0 for air).
    normal_mode_hz: f64,
    contact_width_m: f64,
}

impl TrialSetup {
    fn draw(
        surface: &ScratchSurface,
        behaviour: Behaviour,
        placement: &mut ChaCha8Rng,
        rng: &mut ChaCha8Rng,
    ) -> Self {
        // The placement (offset and rotation on the table) is shared by all five behaviours of
        // one round: the surface was swapped only after all five (Sinapov Sec. III-E).
        let offset = [
            placement.random_range(0.0..SURFACE_SIDE_M),
            placement.random_range(0.0..SURFACE_SIDE_M),
        ];
        let placement_rotation_rad = placement.random_range(-PLACEMENT_ROTATION_RAD..=PLACEMENT_ROTATION_RAD);
        let jitter = Noise::new(1.0);
        let lie = jitter.sample(placement);
        let speed_factor = 1.0 + rng.random_range(-SPEED_SPREAD..=SPEED_SPREAD);
        let stroke = Stroke::new(STROKE_M, behaviour.duration_s() / speed_factor);
        let force_n = surface.nominal_force_n() * (1.0 + rng.random_range(-FORCE_SPREAD..=FORCE_SPREAD));
        let force_drift = if behaviour.is_medial() {
            FORCE_DRIFT_MEDIAL
        } else {
            FORCE_DRIFT_LATERAL
        };
        let world_heading_rad = behaviour.direction_rad() + HEADING_JITTER_RAD * jitter.sample(rng);
        // The stroke starts half a stroke before the common centre of both strokes, in world
        // coordinates; the same world point on the placed surface is found by undoing the
        // placement rotation and adding its offset.
        let (sw, cw) = behaviour.direction_rad().sin_cos();
        let world_start = [
            -0.5 * STROKE_M * cw + START_JITTER_M * jitter.sample(rng),
            -0.5 * STROKE_M * sw + START_JITTER_M * jitter.sample(rng),
        ];
        let (sp, cp) = (-placement_rotation_rad).sin_cos();
        let start_m = [
            offset[0] + cp * world_start[0] - sp * world_start[1],
            offset[1] + sp * world_start[0] + cp * world_start[1],
        ];
        let nail_rad = NAIL_ORIENTATION_RAD.map(|a| a + NAIL_JITTER_RAD * jitter.sample(rng));
        let drift = if behaviour.is_medial() {
            PITCH_DRIFT_MEDIAL_RAD
        } else {
            PITCH_DRIFT_LATERAL_RAD
        };
        let pitch_drift_rad = drift * (1.0 + 0.2 * jitter.sample(rng));
        let ripple_phase = rng.random_range(0.0..TAU);
        // Hertz (Johnson, Contact Mechanics, 1985, Ch. 4): for a rounded tip on a flat the
        // contact radius grows as F^(1/3) and so does the normal stiffness dF/dδ, so the mode
        // goes as F^(1/6). The placement scales the stiffness by a log-normal factor.
        let (normal_mode_hz, contact_width_m) = surface.contact.as_ref().map_or((0.0, 0.0), |c| {
            let load = (force_n / surface.nominal_force_n()).max(1e-3);
            let stiffness = (c.placement_variation.max(0.0) * lie).exp();
            (
                c.normal_mode_hz * stiffness.sqrt() * load.powf(1.0 / 6.0),
                c.contact_width_m * load.cbrt(),
            )
        });
        Self {
            stroke,
            force_n,
            force_drift,
            start_m,
            world_heading_rad,
            surface_heading_rad: world_heading_rad - placement_rotation_rad,
            placement_rotation_rad,
            nail_rad,
            pitch_drift_rad,
            ripple_phase,
            normal_mode_hz,
            contact_width_m,
        }
    }
}

/// Simulates one trial: deterministic in `(surface, behaviour, trial, seed)`.
///
/// Two random streams are used, both ChaCha8 seeded through SplitMix64 from their inputs:
/// the placement stream `(seed, surface id, trial)` — shared by the five behaviours of a
/// round — and the trial stream `(seed, surface id, behaviour, trial)` for everything else.
pub fn scratch_trial(
    surface: &ScratchSurface,
    behaviour: Behaviour,
    trial: u32,
    seed: u64,
) -> ScratchRecording {
    let id = u64::from(surface.id);
    let mut placement = ChaCha8Rng::seed_from_u64(stream_seed(&[seed, TAG_PLACEMENT, id, u64::from(trial)]));
    let mut rng = ChaCha8Rng::seed_from_u64(stream_seed(&[
        seed,
        TAG_TRIAL,
        id,
        behaviour.index(),
        u64::from(trial),
    ]));
    let setup = TrialSetup::draw(surface, behaviour, &mut placement, &mut rng);
    let relief = if surface.relief.built_from(surface.id, surface.contact.as_ref()) {
        Arc::clone(&surface.relief)
    } else {
        Arc::new(Relief::synthesize(surface.id, surface.contact.as_ref()))
    };
    let path = PathSignals::new(&relief, surface.contact.as_ref(), &setup);
    let mut recording = simulate(surface.contact.as_ref(), &setup, &path, &mut rng);
    recording.truth = truth(surface, &setup);
    recording
}

/// The time loop: arm, nail, sensor.
fn simulate(
    contact: Option<&Contact>,
    setup: &TrialSetup,
    path: &PathSignals,
    rng: &mut ChaCha8Rng,
) -> ScratchRecording {
    let dt = 1.0 / SIM_RATE_HZ;
    let stroke = setup.stroke;
    let n_out = (stroke.duration_s * ACCEL_RATE_HZ).floor() as usize + 1;
    let mut time_s = Vec::with_capacity(n_out);
    let mut position = Vec::with_capacity(n_out);
    let mut force = Vec::with_capacity(n_out);
    let mut accel: [Vec<f64>; 3] = std::array::from_fn(|_| Vec::with_capacity(n_out));

    // Nail modes. On air there is no contact: the modes stay at rest.
    let zeta = contact.map_or(NAIL_DAMPING_MIN, |c| c.damping_ratio.max(NAIL_DAMPING_MIN));
    let omega_n = TAU * setup.normal_mode_hz;
    let mut tangential = Mode::new(TANGENTIAL_MODE_HZ, zeta);
    let mut cross = Mode::new(CROSS_MODE_HZ, zeta);
    let mut arm = Mode::new(ARM_MODE_HZ, ARM_DAMPING);
    let mut shear = ShearContact {
        stiffness_n_per_m: contact.map_or(1.0, |c| c.shear_stiffness_n_per_m.max(1.0)),
        stretch_m: 0.0,
    };
    // Normal: absolute nail height z over the surface height y under it; starts at rest on it.
    // In plane, the nail starts at rest too, deflected by the static share of the normal force
    // on the local slopes (the shear contact is unloaded until the arm moves).
    let p0 = path.at(0.0);
    let mut z = p0.height_m;
    let mut z_dot = 0.0;
    let force_at = |s_m: f64| setup.force_n * (1.0 + setup.force_drift * (s_m / stroke.length_m - 0.5));
    if contact.is_some() {
        tangential.settle(-force_at(0.0) * p0.slope / IN_PLANE_MASS_KG);
        cross.settle(-force_at(0.0) * p0.cross_slope / IN_PLANE_MASS_KG);
    }

    let (sh, ch) = setup.world_heading_rad.sin_cos();
    let omega_lp = TAU * Adxl345::BANDWIDTH_HZ;
    let mut filters = [LowPass::new(omega_lp, dt); 3];
    let noise = Adxl345::NOISE_G.map(|g| Noise::new(g * STANDARD_GRAVITY_MPS2));
    let servo = Noise::new(SERVO_JITTER_MPS2);
    let mut servo_mps2 = 0.0;
    let mut rot = rotation(setup.nail_rad[0], setup.nail_rad[1], setup.nail_rad[2]);
    let mut contact_force = 0.0;

    let n_steps = (n_out - 1) * DECIMATION + 1;
    for k in 0..n_steps {
        let t = k as f64 * dt;
        let (s, v, a_cmd) = stroke.at(t);
        let p = path.at(s);
        let out = k % DECIMATION == 0;
        if out {
            // Orientation drifts slowly with the stroke: refresh it at the output rate. The
            // servo jitter is held for one output period.
            let u = s / stroke.length_m - 0.5;
            rot = rotation(
                setup.nail_rad[0],
                setup.nail_rad[1] + setup.pitch_drift_rad * u,
                setup.nail_rad[2],
            );
            servo_mps2 = servo.sample(rng);
        }

        // Arm: the fingertip hangs on the arm's compliance (the sway mode), base-excited by the
        // commanded motion plus servo jitter b: r'' = −ω²r − 2ζωr' − b'' for r = x − b, and the
        // fingertip's own acceleration b'' + r'' = −ω²r − 2ζωr' is the jitter and the command
        // seen through the mode (the command, at ~1 Hz, passes unchanged). Torque ripple
        // follows the travelled distance.
        arm.step(-(a_cmd + servo_mps2), dt);
        let mut along = arm.restoring() + RIPPLE_ALONG_MPS2 * p.ripple;
        let mut side = 0.0;
        let mut up = RIPPLE_VERTICAL_MPS2 * p.ripple;

        if let Some(c) = contact {
            let f0 = force_at(s);
            // Normal: base excitation through the contact spring and damper,
            //   m z'' = F_c − F0,  F_c = max(0, F0 + m(ω²(y − z) + 2ζω(y' − z'))),
            // y the height under the tip and y' = v·dy/ds. Above the mode the nail no longer
            // follows the relief: the compliance of soft surfaces filters it.
            let y_dot = v * p.slope;
            let spring = omega_n * omega_n * (p.height_m - z) + 2.0 * zeta * omega_n * (y_dot - z_dot);
            contact_force = (f0 + NAIL_MASS_KG * spring).max(0.0);
            let a_n = (contact_force - f0) / NAIL_MASS_KG;
            z_dot += a_n * dt;
            z += z_dot * dt;
            // Tangential: friction through the shear contact, plus the share of the normal force
            // that a slope pushes backwards (F·dy/ds); sideways the same for the cross slope.
            let mu_k = (c.friction * (1.0 + c.friction_variation * p.roughness)).max(0.0);
            let w = v + tangential.v;
            let drag = shear.step(w, mu_k, c.stick_slip.max(0.0), contact_force, dt);
            let a_t = tangential.step(-(drag + contact_force * p.slope) / IN_PLANE_MASS_KG, dt);
            let a_c = cross.step(-contact_force * p.cross_slope / IN_PLANE_MASS_KG, dt);
            along += a_t;
            side += a_c;
            up += a_n;
        }

        // Specific force in the world (gravity read as +1 g up), then into sensor axes (Rᵀ f),
        // through the on-board filter at the internal rate.
        let fw = [
            along * ch - side * sh,
            along * sh + side * ch,
            up + STANDARD_GRAVITY_MPS2,
        ];
        let mut filtered = [0.0; 3];
        for (axis, (lp, y)) in filters.iter_mut().zip(&mut filtered).enumerate() {
            let f_axis = rot[0][axis] * fw[0] + rot[1][axis] * fw[1] + rot[2][axis] * fw[2];
            *y = lp.update(f_axis);
        }
        if out {
            time_s.push(time_s.len() as f64 / ACCEL_RATE_HZ);
            position.push(round_to(s, 1e-5));
            force.push(round_to(contact_force, 1e-4));
            for (axis, (column, y)) in accel.iter_mut().zip(filtered).enumerate() {
                let reading = y * (1.0 + Adxl345::GAIN_ERROR[axis])
                    + Adxl345::OFFSET_G[axis] * STANDARD_GRAVITY_MPS2
                    + noise[axis].sample(rng);
                column.push(quantize(reading));
            }
        }
    }
    ScratchRecording {
        time_s,
        tangential_position_m: position,
        normal_force_n: force,
        accel_mps2: accel,
        truth: Vec::new(),
    }
}

/// ADXL345 output: nearest code, clipped to the 10-bit range, back in m/s² rounded to 1e-4.
fn quantize(mps2: f64) -> f64 {
    let code = (mps2 / Adxl345::LSB_MPS2)
        .round()
        .clamp(f64::from(Adxl345::CODE_MIN), f64::from(Adxl345::CODE_MAX));
    round_to(code * Adxl345::LSB_MPS2, 1e-4)
}

/// Ground truth for the capture's metadata (the protocol adds the labels: surface, behaviour,
/// trial, seed). Numbers are printed in Rust's shortest round-trip form, lists are
/// `;`-separated, and nothing contains whitespace.
fn truth(surface: &ScratchSurface, setup: &TrialSetup) -> Vec<(String, String)> {
    let mut t: Vec<(String, String)> = Vec::new();
    let mut put = |key: &str, value: String| t.push((format!("truth.{key}"), value));
    let num = |x: f64| format!("{}", round_to(x, 1e-9));
    // Lists are `;`-separated (commas would confuse CSV tools reading the metadata line);
    // a surface without textures says `none` rather than leaving the value empty.
    let list = |items: Vec<String>| {
        if items.is_empty() {
            "none".to_owned()
        } else {
            items.join(";")
        }
    };
    put("contact", (!surface.is_air()).to_string());
    put("stroke_m", num(setup.stroke.length_m));
    put("duration_s", num(setup.stroke.duration_s));
    put("ramp_s", num(setup.stroke.ramp_s));
    put("speed_mps", num(setup.stroke.speed_mps));
    put("direction_rad", num(setup.world_heading_rad));
    put("direction_on_surface_rad", num(setup.surface_heading_rad));
    put("placement_rotation_rad", num(setup.placement_rotation_rad));
    put("start_x_m", num(setup.start_m[0]));
    put("start_y_m", num(setup.start_m[1]));
    put(
        "normal_force_n",
        num(if surface.is_air() { 0.0 } else { setup.force_n }),
    );
    put("nail_roll_rad", num(setup.nail_rad[0]));
    put("nail_pitch_rad", num(setup.nail_rad[1]));
    put("nail_yaw_rad", num(setup.nail_rad[2]));
    put("nail_pitch_drift_rad", num(setup.pitch_drift_rad));
    put("accel_range_g", num(Adxl345::RANGE_G));
    put("accel_lsb_mps2", num(Adxl345::LSB_MPS2));
    put("accel_bandwidth_hz", num(Adxl345::BANDWIDTH_HZ));
    put("sim_rate_hz", num(SIM_RATE_HZ));
    if let Some(c) = &surface.contact {
        put("roughness_rms_m", num(c.roughness.rms_m));
        put("roughness_wavelength_m", num(c.roughness.wavelength_m));
        // What this stroke meets of each texture: its wavelength stretched by 1/|cos(θ − φ)|.
        let along: Vec<String> = c
            .textures
            .iter()
            .map(|x| {
                let stretch = (x.orientation_rad - setup.surface_heading_rad)
                    .cos()
                    .abs()
                    .max(1e-3);
                num(x.band.wavelength_m / stretch)
            })
            .collect();
        put(
            "texture_rms_m",
            list(c.textures.iter().map(|x| num(x.band.rms_m)).collect()),
        );
        put("texture_wavelength_along_stroke_m", list(along));
        put("normal_mode_hz", num(setup.normal_mode_hz));
        put("contact_width_m", num(setup.contact_width_m));
        put("damping_ratio", num(c.damping_ratio));
        put("friction", num(c.friction));
        put("stick_slip", num(c.stick_slip));
        put("shear_stiffness_n_per_m", num(c.shear_stiffness_n_per_m));
    }
    t
}
