//! A researcher's sliding study, logged the way such rigs log: not captures but one CSV per
//! stream, each on its own clock.
//!
//! # The rig being simulated
//! A robot arm slides a tactile fingertip left to right over each of the 20 household surfaces
//! of [`household_surfaces`] (air, the scratch set's control, is left out: nothing to slide
//! on) at about 25 mm/s under force control at about 1.5 N, [`TRIALS`] trials per surface. The
//! surface is put down anew for every trial, so each trial slides over another strip of it. Per
//! trial the logger writes four files, named like `mat07_trial03_force.csv` (surface number as
//! in [`household_surfaces`], trial from 1):
//!
//! - `force`: `t_ms,Fx,Fy,Fz` in N from a wrist force/torque sensor, about 88 Hz;
//! - `position`: `t_ms,x_mm,y_mm,z_mm`, the fingertip from the arm's kinematics, about 88 Hz;
//! - `velocity`: `t_ms,vx_mm_s,vy_mm_s` from the joint velocities, about 88 Hz;
//! - `vibration`: `time_s,acc_0,…,acc_21,` — the fingertip's vibration sensor read at 2.2 kHz and
//!   delivered 22 samples per 100 Hz row (the first at the row's time), in g; every line, the
//!   header included, ends with a delimiter.
//!
//! The three 88 Hz streams are polled by the host: each has its own start, a clock-rate error of
//! up to ±0.3 % and a jitter of about a millisecond on every sample instant, so no two streams
//! share a sample time. The host stamps the position stream when it reads it, and now and then
//! reads two packets in one poll and stamps both with the same time ([`REPEAT_PROBABILITY`]). The
//! vibration sensor has its own crystal: its rows are evenly spaced on its own clock, started at
//! its own moment. All times count from the logger's start.
//!
//! # The physics
//! What the fingertip meets is the household surfaces' own model (the scratch world's contact
//! table): each surface is a [`SurfacePatch`] built from its roughness band, friction
//! coefficient and friction variation (so `F = N·(μ(x) + h′(x))`, waviness included), plus its
//! directional textures as met by a lateral slide (a texture with wave direction θ is crossed at
//! its wavelength stretched by `1 / |cos θ|`) in a second [`Profile`]. The relief is fixed per
//! surface ([`WORLD_SEED`]); the trial seed only moves the strip, the speed, the load, how the
//! surface lies and the sensors' noise.
//!
//! The fingertip rides on the surface's contact mode (the table's normal mode, damped by its
//! damping ratio, stiffer or softer with how the surface lies): base-excited by the height
//! under it, its acceleration is the normal vibration. The friction drives a shear mode of the
//! fingertip ([`SHEAR_MODE_HZ`]); the vibration sensor, tilted in the fingertip, reads a mix of
//! both through its anti-aliasing filter. The arm's force controller holds the normal force and
//! follows the surface's waviness with a few hertz of bandwidth, so the arm's z carries the
//! waviness and the fingertip's compression, not the fine roughness (which the soft fingertip
//! absorbs). Everything runs at [`SIM_RATE_HZ`]; each stream samples it at its own instants.

use std::f64::consts::{PI, TAU};
use std::fmt::Write as _;
use std::fs;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::seed::{derive_seed, tag};
use crate::SimError;
use crate::world::profile::{Band, Profile};
use crate::world::scratch::{Contact, STANDARD_GRAVITY_MPS2, ScratchSurface, WORLD_SEED, household_surfaces};
use crate::world::sensor::{Encoder, ForceSensor, LowPass, Noise, round_to};
use crate::world::surface::{RubbingSurface, SurfacePatch};

/// Folder of the set under the output folder.
pub const FOLDER: &str = "multistream";
/// Protocol name in the manifest.
pub const PROTOCOL: &str = "multistream_sliding";
/// Trials per surface written by `palpus gen --only multistream`: enough to train on the first
/// half and test on the second with five trials of each surface on either side — a classifier
/// over whole trials then has five vectors per surface, the fewest training warns about (the
/// study this set is shaped after has 50 per material). [`write_logs`] takes any number.
pub const TRIALS: u32 = 10;
/// Nominal rate of the polled streams (force, position, velocity), Hz.
pub const STREAM_RATE_HZ: f64 = 88.0;
/// Rows per second of the vibration log.
pub const VIBRATION_ROW_RATE_HZ: f64 = 100.0;
/// Vibration samples packed into one row.
pub const VIBRATION_PER_ROW: usize = 22;
/// The vibration sensor's sample rate, Hz.
pub const VIBRATION_RATE_HZ: f64 = VIBRATION_ROW_RATE_HZ * VIBRATION_PER_ROW as f64;
/// Nominal sliding speed, m/s.
pub const SPEED_MPS: f64 = 0.025;
/// Nominal normal force the arm's force controller holds, N.
pub const NORMAL_FORCE_N: f64 = 1.5;
/// Duration of the steady slide, s.
pub const SLIDE_S: f64 = 4.0;
/// Chance that the host stamps a position packet with the previous packet's time.
pub const REPEAT_PROBABILITY: f64 = 0.01;
/// Internal simulation rate: four times the vibration sensor's, well above every mode.
pub const SIM_RATE_HZ: f64 = 4.0 * VIBRATION_RATE_HZ;
/// Shear mode of the fingertip on the sensor's core, Hz.
pub const SHEAR_MODE_HZ: f64 = 120.0;

/// Per-trial spread (uniform, ±) of the speed and of the held normal force.
const SPEED_SPREAD: f64 = 0.1;
const FORCE_SPREAD: f64 = 0.1;
/// Still contact before the arm starts and after it stops, s; the arm's raised-cosine speed
/// ramps, s.
const DWELL_S: f64 = 0.3;
const RAMP_S: f64 = 0.3;
/// Clock-rate error of each polled stream (uniform, ±) and the RMS jitter of its instants, s.
const CLOCK_ERROR: f64 = 0.003;
const POLL_JITTER_S: f64 = 0.001;
/// Clock-rate error of the vibration sensor's crystal (uniform, ±).
const CRYSTAL_ERROR: f64 = 50e-6;
/// Effective mass of the fingertip on the contact and shear springs, kg.
const FINGERTIP_MASS_KG: f64 = 0.02;
const SHEAR_DAMPING: f64 = 0.3;
/// The friction's slow part (set by μ and the load) is carried by the arm; what the shear mode
/// feels is the friction minus this low-pass of it, rad/s.
const FRICTION_MEAN_CUTOFF_RADPS: f64 = TAU * 5.0;
/// Tilt of the vibration sensor's axis from the surface normal towards the slide, rad, and its
/// spread (RMS) from one mounting of the fingertip to the next.
const SENSOR_TILT_RAD: f64 = 0.5;
const SENSOR_TILT_SPREAD_RAD: f64 = 0.05;
/// The vibration sensor: anti-aliasing pole, noise (RMS), report quantum, all in g or Hz.
const VIBRATION_BANDWIDTH_HZ: f64 = 1000.0;
const VIBRATION_NOISE_G: f64 = 0.002;
const VIBRATION_QUANTUM_G: f64 = 1e-4;
/// The wrist force/torque sensor: its filter's pole (Hz), noise (N RMS), 16-bit ADC over ±20 N,
/// reported to 0.1 mN; cross-talk from the slide direction into Fy.
const FT_BANDWIDTH_HZ: f64 = 30.0;
const FT_NOISE_N: f64 = 0.008;
const FT_RANGE_N: f64 = 20.0;
const FT_CROSSTALK: f64 = 0.03;
/// Bandwidth of the arm's normal force controller, Hz, and the fingertip's normal stiffness
/// (its compression shows in the arm's z), N/m.
const FORCE_LOOP_HZ: f64 = 4.0;
const FINGERTIP_STIFFNESS_N_PER_M: f64 = 2500.0;
/// The arm's pose: reported to 1 µm with 3 µm of RMS noise; velocity to 0.01 mm/s with
/// 0.15 mm/s of RMS noise.
const POSE_QUANTUM_M: f64 = 1e-6;
const POSE_NOISE_M: f64 = 3e-6;
const VELOCITY_QUANTUM_MPS: f64 = 1e-5;
const VELOCITY_NOISE_MPS: f64 = 1.5e-4;
/// Where on the table the strips start (x) and lie (y), m.
const TABLE_X_M: f64 = 0.40;
const TABLE_Y_M: f64 = -0.15;
/// Grid of the texture profile: the same 5 µm as the surface patch's, 2^16 points.
const TEXTURE_GRID_M: f64 = 5e-6;
const TEXTURE_POINTS: usize = 1 << 16;
/// Longest stretched texture wavelength kept, m: a texture crossed almost along its crests is
/// met as a slow waviness, which a fifth of the profile's period still represents.
const MAX_STRETCHED_WAVELENGTH_M: f64 = 0.06;

/// Streams of one trial, in the order written.
pub const STREAMS: [&str; 4] = ["force", "position", "velocity", "vibration"];

/// A household surface as the sliding fingertip meets it.
#[derive(Debug, Clone)]
pub struct SlidingSurface {
    /// The surface of the scratch world it realises (never air).
    pub surface: ScratchSurface,
    contact: Contact,
    patch: SurfacePatch,
    texture: Profile,
}

impl SlidingSurface {
    /// The surface's fields along a lateral slide; `None` for air.
    pub fn new(surface: &ScratchSurface) -> Option<Self> {
        let contact = surface.contact.as_ref()?;
        let rubbing = RubbingSurface {
            id: surface.id,
            name: surface.name,
            roughness: contact.roughness,
            friction_coefficient: contact.friction,
            friction_variation: contact.friction_variation,
        };
        let bands: Vec<Band> = contact
            .textures
            .iter()
            .map(|t| Band {
                wavelength_m: (t.band.wavelength_m / t.orientation_rad.cos().abs().max(1e-3))
                    .min(MAX_STRETCHED_WAVELENGTH_M),
                ..t.band
            })
            .collect();
        let mut rng = ChaCha8Rng::seed_from_u64(derive_seed(
            WORLD_SEED,
            &[tag::MULTISTREAM, u64::from(surface.id)],
        ));
        let texture = Profile::synthesize(&bands, TEXTURE_GRID_M, TEXTURE_POINTS, &mut rng);
        Some(Self {
            surface: surface.clone(),
            contact: contact.clone(),
            patch: SurfacePatch::new(&rubbing),
            texture,
        })
    }

    /// The relief and friction coefficient along `length_m` of slide from `start_m`, the height
    /// averaged over the contact patch (a triangle of base `contact_width_m`, as the scratch
    /// world's nail sees it): wavelengths shorter than the patch do not reach the fingertip.
    fn track(&self, start_m: f64, length_m: f64, contact_width_m: f64) -> Track {
        let step = TEXTURE_GRID_M;
        let half = (contact_width_m / (4.0 * step)).round().max(0.0) as usize;
        let pad = 2 * half + 1;
        let n = (length_m / step).ceil() as usize + 2;
        let x = |i: usize| start_m + (i as f64 - pad as f64) * step;
        let raw: Vec<f64> = (0..n + 2 * pad)
            .map(|i| self.patch.contact(x(i)).height_m + self.texture.height_m(x(i)))
            .collect();
        // Two boxcars of 2·half + 1 points make the triangle.
        let smoothed = boxcar(&boxcar(&raw, half), half);
        Track {
            step_m: step,
            height_m: smoothed[pad..pad + n].to_vec(),
            friction_coefficient: (0..n)
                .map(|i| self.patch.contact(x(i + pad)).friction_coefficient)
                .collect(),
        }
    }
}

/// Centred moving average over `2·half + 1` points, cut at the ends.
fn boxcar(v: &[f64], half: usize) -> Vec<f64> {
    let mut prefix = Vec::with_capacity(v.len() + 1);
    prefix.push(0.0);
    for &x in v {
        prefix.push(prefix[prefix.len() - 1] + x);
    }
    (0..v.len())
        .map(|i| {
            let lo = i.saturating_sub(half);
            let hi = (i + half + 1).min(v.len());
            (prefix[hi] - prefix[lo]) / (hi - lo) as f64
        })
        .collect()
}

/// One trial's strip of a surface on a uniform grid of slide distance.
struct Track {
    step_m: f64,
    height_m: Vec<f64>,
    friction_coefficient: Vec<f64>,
}

impl Track {
    /// Height (m), slope and friction coefficient at `s_m` of slide (linear interpolation).
    fn at(&self, s_m: f64) -> (f64, f64, f64) {
        let u = (s_m / self.step_m).max(0.0);
        let i = (u.floor() as usize).min(self.height_m.len() - 2);
        let frac = (u - i as f64).min(1.0);
        let (a, b) = (self.height_m[i], self.height_m[i + 1]);
        let (ma, mb) = (self.friction_coefficient[i], self.friction_coefficient[i + 1]);
        (a + (b - a) * frac, (b - a) / self.step_m, ma + (mb - ma) * frac)
    }
}

/// The 20 surfaces, numbered as in [`household_surfaces`].
pub fn sliding_surfaces() -> Vec<SlidingSurface> {
    household_surfaces()
        .iter()
        .filter_map(SlidingSurface::new)
        .collect()
}

/// File stem of one trial's logs: `mat07_trial03` (trial counted from 1, as people do).
pub fn trial_stem(surface_id: u32, trial: u32) -> String {
    format!("mat{surface_id:02}_trial{:02}", trial + 1)
}

/// One trial's four logs: `(stream, CSV text, data rows)` in [`STREAMS`] order.
#[derive(Debug, Clone)]
pub struct TrialLogs {
    /// Per stream: its name, the file's text, its number of data rows.
    pub files: Vec<(&'static str, String, usize)>,
    /// Ground truth of the trial: speed (m/s), held normal force (N), strip start (m).
    pub truth: TrialTruth,
}

/// What a trial drew.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrialTruth {
    /// Steady sliding speed, m/s.
    pub speed_mps: f64,
    /// Normal force the controller held, N.
    pub normal_force_n: f64,
    /// Where on the surface's track the slide started, m.
    pub track_start_m: f64,
    /// Contact mode on this placement, Hz.
    pub normal_mode_hz: f64,
    /// How long the arm slid at its steady speed, s (the study's).
    pub slide_s: f64,
}

/// The internal state sampled by every stream at [`SIM_RATE_HZ`].
struct Trace {
    x_m: Vec<f64>,
    z_arm_m: Vec<f64>,
    speed_mps: Vec<f64>,
    /// Tangential (resisting the slide) and normal force at the wrist, through its sensor's
    /// filter.
    friction_n: Vec<f64>,
    normal_n: Vec<f64>,
    /// The vibration sensor's filtered reading, m/s².
    vibration_mps2: Vec<f64>,
}

/// Simulates and logs trial `trial` of `surface` in `study`, the arm sliding at about its
/// speed for its slide time: deterministic in `(surface, trial, seed, study)`. The speed and
/// the slide time change nothing else a trial draws (its strip, load, placement, noise), so a
/// trial slid at two speeds crosses the same stretch of the same surface.
pub fn trial_logs(surface: &SlidingSurface, trial: u32, seed: u64, study: SlidingStudy) -> TrialLogs {
    let speed_mps = study.speed_mps;
    let id = u64::from(surface.surface.id);
    let mut rng = ChaCha8Rng::seed_from_u64(derive_seed(seed, &[tag::MULTISTREAM, id, u64::from(trial)]));
    let contact = &surface.contact;
    let unit = Noise::new(1.0);
    let speed_mps = speed_mps * (1.0 + rng.random_range(-SPEED_SPREAD..=SPEED_SPREAD));
    let force_n = NORMAL_FORCE_N * (1.0 + rng.random_range(-FORCE_SPREAD..=FORCE_SPREAD));
    let track_start_m = rng.random_range(0.0..surface.patch.track_length_m());
    let lie = (contact.placement_variation.max(0.0) * unit.sample(&mut rng)).exp();
    let normal_mode_hz = contact.normal_mode_hz * lie.sqrt();
    let tilt_rad = SENSOR_TILT_RAD + SENSOR_TILT_SPREAD_RAD * unit.sample(&mut rng);
    let truth = TrialTruth {
        speed_mps,
        normal_force_n: force_n,
        track_start_m,
        normal_mode_hz,
        slide_s: study.slide_s,
    };
    let rig = RigDraw::new(
        study.rig,
        &mut ChaCha8Rng::seed_from_u64(derive_seed(
            seed,
            &[tag::MULTISTREAM, id, u64::from(trial), tag::RIG_EFFECT],
        )),
    );
    let trace = simulate(
        surface,
        &truth,
        contact.damping_ratio,
        contact.contact_width_m,
        tilt_rad,
        &rig,
    );
    let duration_s = (trace.x_m.len() - 1) as f64 / SIM_RATE_HZ;
    let sample = |v: &[f64], t: f64| v[((t * SIM_RATE_HZ).round().max(0.0) as usize).min(v.len() - 1)];

    let ft = ForceSensor::new(FT_NOISE_N, 16, FT_RANGE_N, 1e-4);
    let pose = Encoder {
        quantum_m: POSE_QUANTUM_M,
    };
    let pose_noise = Noise::new(POSE_NOISE_M);
    let velocity_noise = Noise::new(VELOCITY_NOISE_MPS);
    let y_m = TABLE_Y_M + 0.002 * unit.sample(&mut rng);

    let mut files = Vec::with_capacity(STREAMS.len());
    // Force: the sensor pulls back against the slide (−x) and pushes up (+z).
    let instants = poll_instants(duration_s, &mut rng);
    let mut text = String::from("t_ms,Fx,Fy,Fz\n");
    for &t in &instants {
        let friction = sample(&trace.friction_n, t);
        let fx = ft.read(-friction + rig.offset_n(t), &mut rng) + 0.0;
        let fy = ft.read(FT_CROSSTALK * friction, &mut rng) + 0.0;
        let fz = ft.read(sample(&trace.normal_n, t), &mut rng);
        let _ = writeln!(text, "{:.3},{fx},{fy},{fz}", t * 1e3);
    }
    files.push(("force", text, instants.len()));

    let instants = poll_instants(duration_s, &mut rng);
    let mut text = String::from("t_ms,x_mm,y_mm,z_mm\n");
    let mut stamp_ms = f64::NEG_INFINITY;
    for &t in &instants {
        // Two packets read in one poll carry the first one's stamp.
        if !(stamp_ms.is_finite() && rng.random_bool(REPEAT_PROBABILITY)) {
            stamp_ms = round_to(t * 1e3, 1e-3);
        }
        let x = pose.read(TABLE_X_M + sample(&trace.x_m, t) + pose_noise.sample(&mut rng));
        let y = pose.read(y_m + pose_noise.sample(&mut rng));
        let z = pose.read(sample(&trace.z_arm_m, t) + pose_noise.sample(&mut rng));
        let _ = writeln!(
            text,
            "{stamp_ms:.3},{},{},{}",
            decimal(x * 1e3, 1e-3),
            decimal(y * 1e3, 1e-3),
            decimal(z * 1e3, 1e-3)
        );
    }
    files.push(("position", text, instants.len()));

    let instants = poll_instants(duration_s, &mut rng);
    let mut text = String::from("t_ms,vx_mm_s,vy_mm_s\n");
    for &t in &instants {
        let vx = round_to(
            sample(&trace.speed_mps, t) + velocity_noise.sample(&mut rng),
            VELOCITY_QUANTUM_MPS,
        );
        let vy = round_to(velocity_noise.sample(&mut rng), VELOCITY_QUANTUM_MPS);
        let _ = writeln!(
            text,
            "{:.3},{},{}",
            t * 1e3,
            decimal(vx * 1e3, 1e-2),
            decimal(vy * 1e3, 1e-2)
        );
    }
    files.push(("velocity", text, instants.len()));

    // Vibration: rows evenly spaced on the sensor's own crystal.
    let period_s = (1.0 + rng.random_range(-CRYSTAL_ERROR..=CRYSTAL_ERROR)) / VIBRATION_RATE_HZ;
    let start_s = rng.random_range(0.0..1.0 / VIBRATION_ROW_RATE_HZ);
    let rows = ((duration_s - start_s) / (period_s * VIBRATION_PER_ROW as f64)).floor() as usize;
    let noise = Noise::new(VIBRATION_NOISE_G);
    let mut text = String::from("time_s,");
    for k in 0..VIBRATION_PER_ROW {
        let _ = write!(text, "acc_{k},");
    }
    text.push('\n');
    for row in 0..rows {
        let first = row * VIBRATION_PER_ROW;
        let _ = write!(text, "{:.6},", start_s + first as f64 * period_s);
        for k in 0..VIBRATION_PER_ROW {
            let t = start_s + (first + k) as f64 * period_s;
            let signal = match rig.effect {
                RigEffect::NoiseOnly => 0.0,
                _ => sample(&trace.vibration_mps2, t) / STANDARD_GRAVITY_MPS2,
            };
            let g = signal + noise.sample(&mut rng);
            let _ = write!(text, "{},", decimal(g, VIBRATION_QUANTUM_G));
        }
        text.push('\n');
    }
    files.push(("vibration", text, rows));
    TrialLogs { files, truth }
}

/// `value` to a multiple of `quantum`, printed without a sign when it rounds to zero (as loggers
/// print it).
fn decimal(value: f64, quantum: f64) -> f64 {
    round_to(value, quantum) + 0.0
}

/// A polled stream's sample instants over `[0, duration_s]`: its own start, clock-rate error and
/// jitter, strictly increasing.
fn poll_instants(duration_s: f64, rng: &mut ChaCha8Rng) -> Vec<f64> {
    let period_s = (1.0 + rng.random_range(-CLOCK_ERROR..=CLOCK_ERROR)) / STREAM_RATE_HZ;
    let jitter = Noise::new(POLL_JITTER_S);
    let mut t_s = rng.random_range(0.0..period_s);
    let mut instants = Vec::with_capacity((duration_s / period_s) as usize + 1);
    let mut last = f64::NEG_INFINITY;
    while t_s <= duration_s {
        // Jitter never reorders packets: a late one is read after the one before it.
        let at = (t_s + jitter.sample(rng)).clamp(0.0, duration_s).max(last + 1e-4);
        if at > duration_s {
            break;
        }
        instants.push(at);
        last = at;
        t_s += period_s;
    }
    instants
}

/// The trial at [`SIM_RATE_HZ`]: arm, fingertip, sensors' analog filters.
fn simulate(
    surface: &SlidingSurface,
    truth: &TrialTruth,
    damping: f64,
    contact_width_m: f64,
    tilt_rad: f64,
    rig: &RigDraw,
) -> Trace {
    let dt = 1.0 / SIM_RATE_HZ;
    let duration_s = 2.0 * DWELL_S + 2.0 * RAMP_S + truth.slide_s;
    let steps = (duration_s * SIM_RATE_HZ).round() as usize + 1;
    let mut trace = Trace {
        x_m: Vec::with_capacity(steps),
        z_arm_m: Vec::with_capacity(steps),
        speed_mps: Vec::with_capacity(steps),
        friction_n: Vec::with_capacity(steps),
        normal_n: Vec::with_capacity(steps),
        vibration_mps2: Vec::with_capacity(steps),
    };
    let omega_n = TAU * truth.normal_mode_hz;
    let zeta = damping;
    let omega_t = TAU * SHEAR_MODE_HZ;
    let (sin_tilt, cos_tilt) = tilt_rad.sin_cos();
    let ft_filter = LowPass::new(TAU * FT_BANDWIDTH_HZ, dt);
    let (mut ft_friction, mut ft_normal) = (ft_filter, ft_filter);
    let mut vibration_filter = LowPass::new(TAU * VIBRATION_BANDWIDTH_HZ, dt);
    let mut friction_mean = LowPass::new(FRICTION_MEAN_CUTOFF_RADPS, dt);
    let mut arm_follow = LowPass::new(TAU * FORCE_LOOP_HZ, dt);
    // The sensor on its mount: unit gain below the mount's mode, Q at it.
    let omega_r = TAU * rig.resonance_hz;
    let (mut mount, mut mount_dot) = (0.0, 0.0);
    let travel_m = truth.speed_mps * (truth.slide_s + RAMP_S) * (1.0 + 1e-6);
    let track = surface.track(truth.track_start_m, travel_m, contact_width_m);
    let (height0, _, _) = track.at(0.0);
    // Fingertip at rest on the surface; shear mode relaxed.
    let (mut z, mut z_dot) = (height0, 0.0);
    let (mut q, mut q_dot) = (0.0, 0.0);
    let mut s = 0.0;
    for k in 0..steps {
        let t = k as f64 * dt;
        let v = speed_at(t, truth.speed_mps, truth.slide_s);
        s += v * dt;
        let (height, slope, mu) = track.at(s);
        // Normal: base excitation through the contact spring and damper; the contact never pulls.
        let y_dot = v * slope;
        let a_n = omega_n * omega_n * (height - z) + 2.0 * zeta * omega_n * (y_dot - z_dot);
        let normal = (truth.normal_force_n + FINGERTIP_MASS_KG * a_n).max(0.0);
        let a_n = (normal - truth.normal_force_n) / FINGERTIP_MASS_KG;
        z_dot += a_n * dt;
        z += z_dot * dt;
        // Tangential: the friction while sliding (none at rest), its fast part on the shear mode.
        // F = N·(μ(x) + h′(x)), the surface patch's law, with the slope the patch-averaged
        // relief's.
        let friction = if v > 0.0 { normal * (mu + slope) } else { 0.0 };
        let fluctuation = friction - friction_mean.update(friction);
        let a_t =
            -omega_t * omega_t * q - 2.0 * SHEAR_DAMPING * omega_t * q_dot - fluctuation / FINGERTIP_MASS_KG;
        q_dot += a_t * dt;
        q += q_dot * dt;
        trace.x_m.push(s);
        trace.speed_mps.push(v);
        trace.friction_n.push(ft_friction.update(friction));
        trace.normal_n.push(ft_normal.update(normal));
        // The arm follows the surface's height slowly; the fingertip's compression adds to it.
        trace
            .z_arm_m
            .push(arm_follow.update(z) + normal / FINGERTIP_STIFFNESS_N_PER_M);
        let felt = cos_tilt * a_n + sin_tilt * a_t;
        let felt = if rig.effect == RigEffect::Resonance {
            let mount_ddot = omega_r * omega_r * (felt - mount) - omega_r / RESONANCE_Q * mount_dot;
            mount_dot += mount_ddot * dt;
            mount += mount_dot * dt;
            mount
        } else {
            felt
        };
        trace.vibration_mps2.push(vibration_filter.update(felt));
    }
    trace
}

/// The arm's commanded speed: still, a raised-cosine ramp up, the slide, a ramp down, still.
fn speed_at(t_s: f64, speed_mps: f64, slide_s: f64) -> f64 {
    let ramp = |u: f64| speed_mps * 0.5 * (1.0 - (PI * u.clamp(0.0, 1.0)).cos());
    let up = t_s - DWELL_S;
    let down = t_s - DWELL_S - RAMP_S - slide_s;
    if up <= 0.0 || down >= RAMP_S {
        0.0
    } else if up < RAMP_S {
        ramp(up / RAMP_S)
    } else if down <= 0.0 {
        speed_mps
    } else {
        ramp(1.0 - down / RAMP_S)
    }
}

/// A fault of a real rig that a recognizer has to see past, applied to every trial of a study.
/// Each trial draws its own (from a stream of its own, so that a study without one writes the
/// bytes it always did).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RigEffect {
    /// None: the rig as modelled.
    #[default]
    None,
    /// The vibration sensor's mount rings at its own frequency, [`RESONANCE_HZ`] (±5 % per
    /// trial), whatever the sliding speed: a lightly damped mode (Q = [`RESONANCE_Q`]) between
    /// fingertip and sensor, so every surface's vibration is amplified there.
    Resonance,
    /// The force sensor's offset drifts: each trial starts up to ±[`DRIFT_OFFSET_N`] off and
    /// drifts by up to ±[`DRIFT_RATE_N_PER_S`], as a strain gauge warming up does. The friction
    /// read is off by as much.
    Drift,
    /// The vibration channel carries the sensor's noise only (a loose connector): nothing of
    /// the surface.
    NoiseOnly,
}

impl RigEffect {
    /// Every effect besides none.
    pub const ALL: [Self; 3] = [Self::Resonance, Self::Drift, Self::NoiseOnly];

    /// `resonance`, `drift` or `noise-only` (`none` for none), as `palpus gen --rig-effect`
    /// spells it.
    pub fn name(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Resonance => "resonance",
            Self::Drift => "drift",
            Self::NoiseOnly => "noise-only",
        }
    }

    /// One line for the set's README.
    fn describe(self) -> &'static str {
        match self {
            Self::None => "",
            Self::Resonance => {
                "Rig effect: the vibration sensor's mount rings at about 160 Hz (Q 8) whatever the speed.\n"
            }
            Self::Drift => {
                "Rig effect: the force sensor's offset starts up to 0.1 N off and drifts up to 0.03 N/s.\n"
            }
            Self::NoiseOnly => "Rig effect: the vibration channel carries the sensor's noise only.\n",
        }
    }
}

/// [`RigEffect::Resonance`]: the mount's natural frequency, Hz (inside the spectrotemporal
/// histogram's 0–200 Hz, where it weighs on every surface's cells).
pub const RESONANCE_HZ: f64 = 160.0;
/// [`RigEffect::Resonance`]: its quality factor (its gain at resonance).
pub const RESONANCE_Q: f64 = 8.0;
/// [`RigEffect::Drift`]: the largest offset a trial starts with, N.
pub const DRIFT_OFFSET_N: f64 = 0.1;
/// [`RigEffect::Drift`]: the fastest drift, N/s.
pub const DRIFT_RATE_N_PER_S: f64 = 0.03;

/// What a trial's rig effect drew.
#[derive(Debug, Clone, Copy, PartialEq)]
struct RigDraw {
    effect: RigEffect,
    resonance_hz: f64,
    offset_n: f64,
    drift_n_per_s: f64,
}

impl RigDraw {
    fn new(effect: RigEffect, rng: &mut ChaCha8Rng) -> Self {
        let mut within = |limit: f64| rng.random_range(-limit..=limit);
        Self {
            effect,
            resonance_hz: RESONANCE_HZ * (1.0 + within(0.05)),
            offset_n: within(DRIFT_OFFSET_N),
            drift_n_per_s: within(DRIFT_RATE_N_PER_S),
        }
    }

    /// The force sensor's offset at `t_s`, N.
    fn offset_n(&self, t_s: f64) -> f64 {
        match self.effect {
            RigEffect::Drift => self.offset_n + self.drift_n_per_s * t_s,
            _ => 0.0,
        }
    }
}

/// How many trials of each surface the study slides, how fast and for how long, and on which rig.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlidingStudy {
    /// Trials per surface.
    pub trials: u32,
    /// Nominal sliding speed, m/s (each trial within ±10 % of it).
    pub speed_mps: f64,
    /// Time at the steady speed, s (plus a dwell and a ramp at either end).
    pub slide_s: f64,
    /// A fault of the rig every trial shows.
    pub rig: RigEffect,
}

impl Default for SlidingStudy {
    /// [`TRIALS`] trials at [`SPEED_MPS`] for [`SLIDE_S`], on the rig as modelled.
    fn default() -> Self {
        Self {
            trials: TRIALS,
            speed_mps: SPEED_MPS,
            slide_s: SLIDE_S,
            rig: RigEffect::None,
        }
    }
}

impl SlidingStudy {
    /// The fastest nominal speed simulated, m/s: past it the vibration sensor's 1 kHz
    /// bandwidth cuts off the coarsest textures' fundamentals.
    pub const MAX_SPEED_MPS: f64 = 0.5;

    /// The same study at `speed_mps`: positive and at most [`SlidingStudy::MAX_SPEED_MPS`], or
    /// a typed error.
    pub fn at_speed(self, speed_mps: f64) -> Result<Self, SimError> {
        let study = Self { speed_mps, ..self };
        study.check()?;
        Ok(study)
    }

    /// The longest slide simulated, s: a trial's trace is held in memory at [`SIM_RATE_HZ`].
    pub const MAX_SLIDE_S: f64 = 60.0;

    /// The most trials per surface (two digits in a trial's file name).
    pub const MAX_TRIALS: u32 = 99;

    /// The same study with `trials` trials of each surface, each slid for `slide_s` (1 to
    /// [`SlidingStudy::MAX_TRIALS`], and over 0 up to [`SlidingStudy::MAX_SLIDE_S`]), or a
    /// typed error.
    pub fn with_shape(self, trials: u32, slide_s: f64) -> Result<Self, SimError> {
        let study = Self {
            trials,
            slide_s,
            ..self
        };
        study.check()?;
        Ok(study)
    }

    /// Its speed, trials or slide time out of range, as a typed error.
    pub fn check(&self) -> Result<(), SimError> {
        let v = self.speed_mps;
        if !(v.is_finite() && v > 0.0 && v <= Self::MAX_SPEED_MPS) {
            return Err(SimError::Setting {
                name: "slide_speed_mps",
                value: v,
                reason: "positive and at most 0.5 m/s",
            });
        }
        if !(1..=Self::MAX_TRIALS).contains(&self.trials) {
            return Err(SimError::Setting {
                name: "slide_trials",
                value: f64::from(self.trials),
                reason: "1 to 99 trials per surface",
            });
        }
        let s = self.slide_s;
        if !(s.is_finite() && s > 0.0 && s <= Self::MAX_SLIDE_S) {
            return Err(SimError::Setting {
                name: "slide_s",
                value: s,
                reason: "positive and at most 60 s",
            });
        }
        Ok(())
    }
}

/// Writes every trial of every surface under `out/multistream/`, with a `materials.csv` (surface
/// number, name, ground truth), a `trials.csv` (what each trial drew) and a `README.md` that says
/// how to import the logs. `written` is called after each log file.
pub fn write_logs(
    out: &Path,
    seed: u64,
    study: SlidingStudy,
    written: &mut dyn FnMut(LogFile),
) -> Result<(), SimError> {
    study.check()?;
    let SlidingStudy {
        trials,
        speed_mps,
        slide_s,
        rig,
    } = study;
    let folder = out.join(FOLDER);
    fs::create_dir_all(&folder).map_err(|source| SimError::Io {
        action: "create",
        path: folder.clone(),
        source,
    })?;
    let mut materials =
        String::from("surface_id,name,friction,roughness_rms_m,roughness_wavelength_m,normal_mode_hz\n");
    let mut trial_table =
        String::from("stem,name,trial,speed_mps,normal_force_n,track_start_m,normal_mode_hz\n");
    for surface in sliding_surfaces() {
        let s = &surface.surface;
        let c = &surface.contact;
        let _ = writeln!(
            materials,
            "{},{},{},{},{},{}",
            s.id, s.name, c.friction, c.roughness.rms_m, c.roughness.wavelength_m, c.normal_mode_hz
        );
        for trial in 0..trials {
            let logs = trial_logs(&surface, trial, seed, study);
            let stem = trial_stem(s.id, trial);
            let t = logs.truth;
            let _ = writeln!(
                trial_table,
                "{stem},{},{},{},{},{},{}",
                s.name,
                trial + 1,
                round_to(t.speed_mps, 1e-7),
                round_to(t.normal_force_n, 1e-6),
                round_to(t.track_start_m, 1e-6),
                round_to(t.normal_mode_hz, 1e-3)
            );
            for (stream, text, rows) in logs.files {
                let relative = PathBuf::from(FOLDER).join(format!("{stem}_{stream}.csv"));
                let bytes = write_text(out, &relative, &text)?;
                written(LogFile {
                    path: relative,
                    surface: s.name,
                    stream,
                    rows,
                    bytes,
                });
            }
        }
    }
    write_text(out, &PathBuf::from(FOLDER).join("materials.csv"), &materials)?;
    write_text(out, &PathBuf::from(FOLDER).join("trials.csv"), &trial_table)?;
    write_text(
        out,
        &PathBuf::from(FOLDER).join("README.md"),
        &format!("{}{}", readme(trials, speed_mps, slide_s), rig.describe()),
    )?;
    Ok(())
}

/// One log file [`write_logs`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct LogFile {
    /// Path relative to the output folder.
    pub path: PathBuf,
    /// Name of the surface it is of.
    pub surface: &'static str,
    /// Which of [`STREAMS`] it holds.
    pub stream: &'static str,
    /// Data rows.
    pub rows: usize,
    /// Size on disk.
    pub bytes: u64,
}

fn write_text(out: &Path, relative: &Path, text: &str) -> Result<u64, SimError> {
    let path = out.join(relative);
    capture::write_atomically(&path, |w| w.write_all(text.as_bytes())).map_err(
        |source: std::io::Error| SimError::Io {
            action: "write",
            path,
            source,
        },
    )?;
    Ok(text.len() as u64)
}

/// The `--map` that imports one trial's four files, given in the order of [`STREAMS`]: the
/// polled streams' `t_ms` in milliseconds, the vibration's own `time_s` (input 4) in seconds,
/// friction as the force the sensor feels against the slide, the arm's z as the height.
pub const IMPORT_MAP: &str = "time_s=t_ms[ms],time_s=4:time_s[s],friction_force_n=Fx*-1,\
                              normal_force_n=Fz,tangential_position_m=x_mm[mm],\
                              normal_position_m=z_mm[mm],tangential_velocity_mps=vx_mm_s[mm/s],\
                              vibration_mps2=acc[g]";
/// The `--unroll` that reads the packed vibration row as 22 samples.
pub const IMPORT_UNROLL: &str = "acc=acc_0..acc_21";
/// The output rate the README imports at: the vibration sensor's own, Hz.
pub const IMPORT_RATE_HZ: f64 = VIBRATION_RATE_HZ;

/// How to read the set: layout, units, and the import of every trial.
fn readme(trials: u32, speed_mps: f64, slide_s: f64) -> String {
    // To a tenth of a millimetre per second, so that 0.035 reads 35, not 35.00000000000001.
    let speed_mm_s = (speed_mps * 1e4).round() / 10.0;
    format!(
        "# Sliding study: 20 surfaces x {trials} trials, one CSV per stream\n\
         \n\
         Simulated by `palpus gen --only multistream` (see sim::protocols::multistream).\n\
         A robot arm slides a tactile fingertip left to right at about {speed_mm_s} mm/s under about 1.5 N\n\
         for {slide_s} s.\n\
         Surface numbers and names: materials.csv; what each trial drew: trials.csv.\n\
         \n\
         Per trial `matNN_trialTT_*.csv`:\n\
         - force: t_ms,Fx,Fy,Fz (N), about 88 Hz, own clock, jittered; Fx resists the slide (negative)\n\
         - position: t_ms,x_mm,y_mm,z_mm, about 88 Hz, own clock, jittered, some repeated stamps\n\
         - velocity: t_ms,vx_mm_s,vy_mm_s, about 88 Hz, own clock, jittered\n\
         - vibration: time_s,acc_0..acc_21 (g), 22 samples at 2.2 kHz per 100 Hz row, the first at\n\
         \x20 the row's time; every line ends with a delimiter\n\
         \n\
         Import every trial as one capture, labelled by surface and trial (from this folder):\n\
         \n\
         ```sh\n\
         mkdir -p captures\n\
         for f in *_force.csv; do\n\
         \x20 s=${{f%_force.csv}}\n\
         \x20 palpus import \"$s\"_force.csv \"$s\"_position.csv \"$s\"_velocity.csv \"$s\"_vibration.csv \\\n\
         \x20   --kind rubbing --rate-hz {IMPORT_RATE_HZ} --repeated-time mean --unroll '{IMPORT_UNROLL}' \\\n\
         \x20   --map '{IMPORT_MAP}' \\\n\
         \x20   --meta surface=\"${{s%%_*}}\" --meta trial=\"$((10#${{s##*trial}}))\" --out \"captures/$s.csv\"\n\
         done\n\
         ```\n"
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows(text: &str) -> Vec<Vec<f64>> {
        text.lines()
            .skip(1)
            .map(|l| {
                l.trim_end_matches(',')
                    .split(',')
                    .map(|c| c.parse().expect("number"))
                    .collect()
            })
            .collect()
    }

    #[test]
    fn streams_have_their_own_jittered_clocks_and_the_vibration_is_packed() {
        let surfaces = sliding_surfaces();
        assert_eq!(surfaces.len(), 20);
        let corduroy = surfaces
            .iter()
            .find(|s| s.surface.name == "corduroy")
            .expect("corduroy");
        let logs = trial_logs(corduroy, 0, 1, SlidingStudy::default());
        let names: Vec<&str> = logs.files.iter().map(|f| f.0).collect();
        assert_eq!(names, STREAMS);
        let mut starts = Vec::new();
        for (stream, text, n) in &logs.files[..3] {
            let r = rows(text);
            assert_eq!(r.len(), *n);
            let t: Vec<f64> = r.iter().map(|row| row[0] * 1e-3).collect();
            let steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
            let mean_rate = (t.len() - 1) as f64 / (t[t.len() - 1] - t[0]);
            assert!(
                (mean_rate / STREAM_RATE_HZ - 1.0).abs() < 0.01,
                "{stream}: {mean_rate}"
            );
            let spread = steps
                .iter()
                .map(|d| (d - 1.0 / mean_rate).abs())
                .fold(0.0, f64::max);
            assert!(spread > 5e-4, "{stream}: no jitter");
            let repeats = steps.iter().filter(|&&d| d == 0.0).count();
            if *stream == "position" {
                assert!(repeats > 0, "position: no repeated stamp");
            } else {
                assert_eq!(repeats, 0, "{stream}");
                assert!(steps.iter().all(|&d| d > 0.0), "{stream}");
            }
            starts.push(t[0]);
        }
        assert!(starts[0] != starts[1] && starts[1] != starts[2]);
        let (_, text, n) = &logs.files[3];
        assert!(text.lines().all(|l| l.ends_with(',')));
        assert!(text.starts_with("time_s,acc_0,acc_1,"));
        let r = rows(text);
        assert_eq!(r.len(), *n);
        assert!(r.iter().all(|row| row.len() == 1 + VIBRATION_PER_ROW));
        let rate = (r.len() - 1) as f64 / (r[r.len() - 1][0] - r[0][0]);
        assert!((rate - VIBRATION_ROW_RATE_HZ).abs() < 0.01, "{rate}");
    }

    #[test]
    fn friction_follows_the_surface_and_the_slide_is_at_about_25_mm_per_s() {
        let surfaces = sliding_surfaces();
        for name in ["table", "thin_floor_mat_back"] {
            let s = surfaces.iter().find(|s| s.surface.name == name).expect("surface");
            let logs = trial_logs(s, 2, 9, SlidingStudy::default());
            let mu = s.surface.contact.as_ref().expect("contact").friction;
            let force = rows(&logs.files[0].1);
            let velocity = rows(&logs.files[2].1);
            // Steady slide: speed above 90 % of nominal spread.
            let steady: Vec<f64> = velocity.iter().map(|r| r[1]).filter(|&v| v > 20.0).collect();
            let mean_speed = steady.iter().sum::<f64>() / steady.len() as f64;
            assert!((mean_speed - 25.0).abs() < 2.6, "{name}: {mean_speed} mm/s");
            let sliding: Vec<&Vec<f64>> = force
                .iter()
                .filter(|r| {
                    let t = r[0] * 1e-3;
                    t > DWELL_S + RAMP_S + 0.2 && t < DWELL_S + RAMP_S + SLIDE_S
                })
                .collect();
            let ratio = sliding.iter().map(|r| -r[1] / r[3]).sum::<f64>() / sliding.len() as f64;
            assert!((ratio / mu - 1.0).abs() < 0.15, "{name}: {ratio} vs {mu}");
            let fz = sliding.iter().map(|r| r[3]).sum::<f64>() / sliding.len() as f64;
            assert!(
                (fz / NORMAL_FORCE_N - 1.0).abs() < FORCE_SPREAD + 0.02,
                "{name}: {fz}"
            );
        }
    }

    #[test]
    fn asked_for_by_name_only() {
        use super::super::CaptureSet;
        assert_eq!("multistream".parse::<CaptureSet>(), Ok(CaptureSet::Multistream));
        assert!(!CaptureSet::ALL.contains(&CaptureSet::Multistream));
    }

    #[test]
    fn same_seed_same_bytes_other_trial_other_bytes() {
        let surfaces = sliding_surfaces();
        let a = trial_logs(&surfaces[4], 1, 3, SlidingStudy::default());
        let b = trial_logs(&surfaces[4], 1, 3, SlidingStudy::default());
        let c = trial_logs(&surfaces[4], 2, 3, SlidingStudy::default());
        for i in 0..STREAMS.len() {
            assert_eq!(a.files[i].1, b.files[i].1);
            assert_ne!(a.files[i].1, c.files[i].1);
        }
    }

    #[test]
    fn a_trial_slid_faster_crosses_the_same_strip_faster() {
        let surfaces = sliding_surfaces();
        let slow = trial_logs(&surfaces[4], 1, 3, SlidingStudy::default()).truth;
        let fast = trial_logs(
            &surfaces[4],
            1,
            3,
            SlidingStudy::default().at_speed(2.0 * SPEED_MPS).expect("valid"),
        )
        .truth;
        assert!((fast.speed_mps - 2.0 * slow.speed_mps).abs() < 1e-15);
        assert_eq!(
            (fast.track_start_m, fast.normal_force_n, fast.normal_mode_hz),
            (slow.track_start_m, slow.normal_force_n, slow.normal_mode_hz)
        );
        let study = SlidingStudy::default();
        assert_eq!(study.at_speed(0.05).expect("valid").speed_mps, 0.05);
        for bad in [0.0, -0.025, f64::NAN, 0.6] {
            assert!(
                matches!(study.at_speed(bad), Err(SimError::Setting { .. })),
                "{bad}"
            );
        }
        assert!(readme(10, 0.05, 4.0).contains("at about 50 mm/s"));
    }

    /// A study of a real one's shape: more trials, each slid longer; a trial draws the same
    /// strip, load and placement whatever the slide time, and only the slide lasts longer.
    #[test]
    fn a_longer_slide_lasts_longer_on_the_same_strip() {
        let surfaces = sliding_surfaces();
        let study = SlidingStudy::default().with_shape(25, 7.0).expect("valid");
        assert_eq!((study.trials, study.slide_s), (25, 7.0));
        let short = trial_logs(&surfaces[2], 3, 1, SlidingStudy::default());
        let long = trial_logs(&surfaces[2], 3, 1, study);
        assert_eq!(long.truth.slide_s, 7.0);
        assert_eq!(
            (
                long.truth.speed_mps,
                long.truth.track_start_m,
                long.truth.normal_force_n
            ),
            (
                short.truth.speed_mps,
                short.truth.track_start_m,
                short.truth.normal_force_n
            )
        );
        // The packed vibration rows at 100 Hz: 3 s more, 300 rows more (within a row of jitter).
        let (a, b) = (rows(&short.files[3].1).len(), rows(&long.files[3].1).len());
        assert!((b as i64 - a as i64 - 300).abs() <= 1, "{a} → {b}");
        assert!(
            readme(25, SPEED_MPS, 7.0).contains("20 surfaces x 25 trials")
                && readme(25, SPEED_MPS, 7.0).contains("for 7 s")
        );
        for (trials, slide_s) in [
            (0, 4.0),
            (100, 4.0),
            (10, 0.0),
            (10, -1.0),
            (10, f64::NAN),
            (10, 61.0),
        ] {
            assert!(
                matches!(
                    SlidingStudy::default().with_shape(trials, slide_s),
                    Err(SimError::Setting { .. })
                ),
                "{trials} trials of {slide_s} s"
            );
        }
    }

    #[test]
    fn rougher_surfaces_vibrate_more() {
        let surfaces = sliding_surfaces();
        let rms = |name: &str| {
            let s = surfaces.iter().find(|s| s.surface.name == name).expect("surface");
            let r = rows(&trial_logs(s, 0, 5, SlidingStudy::default()).files[3].1);
            let v: Vec<f64> = r.iter().flat_map(|row| row[1..].to_vec()).collect();
            let mean = v.iter().sum::<f64>() / v.len() as f64;
            (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / v.len() as f64).sqrt()
        };
        // Two hard surfaces, 22 µm of moulded grid against under a micrometre of finish.
        let table = rms("table");
        let pattern = rms("plastic_pattern");
        assert!(
            pattern > 2.0 * table,
            "plastic pattern {pattern} g, table {table} g"
        );
    }

    /// Each rig effect shows where it should and nowhere else: the drift in the force log
    /// alone, the resonance and the noise in the vibration log alone; a study without one
    /// draws exactly what it did.
    #[test]
    fn rig_effects_show_in_their_own_log_and_leave_the_others_as_drawn() {
        let surfaces = sliding_surfaces();
        let surface = surfaces
            .iter()
            .find(|s| s.surface.name == "plastic_pattern")
            .expect("surface");
        let on = |rig| {
            trial_logs(
                surface,
                2,
                1,
                SlidingStudy {
                    rig,
                    ..SlidingStudy::default()
                },
            )
        };
        let plain = on(RigEffect::None);
        let column = |logs: &TrialLogs, file: usize, col: usize| -> Vec<f64> {
            rows(&logs.files[file].1).iter().map(|r| r[col]).collect()
        };
        let vibration = |logs: &TrialLogs| -> Vec<f64> {
            rows(&logs.files[3].1)
                .iter()
                .flat_map(|r| r[1..].to_vec())
                .collect()
        };
        // Power of `v` (g, at 2.2 kHz) between `lo` and `hi` Hz, by a direct DFT over 1 s.
        let power = |v: &[f64], lo: f64, hi: f64| -> f64 {
            let n = 2200.min(v.len());
            let v = &v[v.len() / 2 - n / 2..][..n];
            let mean = v.iter().sum::<f64>() / n as f64;
            (lo as usize..hi as usize)
                .map(|f| {
                    let (mut re, mut im) = (0.0, 0.0);
                    for (k, x) in v.iter().enumerate() {
                        let phase = TAU * f as f64 * k as f64 / 2200.0;
                        re += (x - mean) * phase.cos();
                        im -= (x - mean) * phase.sin();
                    }
                    re * re + im * im
                })
                .sum()
        };

        let drift = on(RigEffect::Drift);
        for file in [1, 2, 3] {
            assert_eq!(drift.files[file], plain.files[file], "only the force log drifts");
        }
        let (fx, fx0) = (column(&drift, 0, 1), column(&plain, 0, 1));
        let offsets: Vec<f64> = fx.iter().zip(&fx0).map(|(a, b)| a - b).collect();
        assert!(offsets.iter().any(|d| d.abs() > 1e-3), "the offset shows");
        assert!(
            offsets
                .iter()
                .all(|d| d.abs() <= DRIFT_OFFSET_N + 0.5 * DRIFT_RATE_N_PER_S * 12.0)
        );
        // Crosstalk and the normal force are the sensor's other axes: untouched.
        assert_eq!(column(&drift, 0, 3), column(&plain, 0, 3));

        let quiet = on(RigEffect::NoiseOnly);
        for file in [0, 1, 2] {
            assert_eq!(
                quiet.files[file], plain.files[file],
                "only the vibration log is quiet"
            );
        }
        let rms = |v: &[f64]| {
            let mean = v.iter().sum::<f64>() / v.len() as f64;
            (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / v.len() as f64).sqrt()
        };
        let (q, p) = (rms(&vibration(&quiet)), rms(&vibration(&plain)));
        assert!(
            q < 1.5 * VIBRATION_NOISE_G && p > 5.0 * q,
            "noise only {q} g, the surface {p} g"
        );

        let ringing = on(RigEffect::Resonance);
        for file in [0, 1, 2] {
            assert_eq!(
                ringing.files[file], plain.files[file],
                "only the vibration log rings"
            );
        }
        let share = |v: &[f64]| power(v, 150.0, 171.0) / power(v, 20.0, 400.0);
        let (r, p) = (share(&vibration(&ringing)), share(&vibration(&plain)));
        assert!(r > 3.0 * p, "near 160 Hz: {r} of the power ringing, {p} without");
        assert_eq!(
            RigEffect::ALL.map(RigEffect::name),
            ["resonance", "drift", "noise-only"]
        );
    }
}
