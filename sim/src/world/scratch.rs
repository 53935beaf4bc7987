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
//!    straight-crested random waves ("layers"), each a band-limited [`Profile`](super::profile::Profile) along its
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
//!
//! Step 1 is `relief.rs`, step 2 `trial.rs` (what a trial draws), `stroke.rs` (the arm's
//! motion) and `path.rs` (the relief along it), steps 3 to 5 `simulate.rs`; `contact.rs` and `table.rs` hold the
//! surfaces' contact models.

mod contact;
mod path;
mod relief;
mod simulate;
mod stroke;
mod table;
#[cfg(test)]
mod tests;
mod trial;

use std::f64::consts::FRAC_PI_2;
use std::fmt;
use std::sync::Arc;

use capture::rng::stream_seed;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

pub use contact::{Contact, Texture};
use path::PathSignals;
use relief::Relief;
use simulate::simulate;
use trial::{TrialSetup, truth};

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
// Random streams
// ---------------------------------------------------------------------------------------------

const TAG_RELIEF: u64 = 1;
const TAG_PLACEMENT: u64 = 2;
const TAG_TRIAL: u64 = 3;

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
