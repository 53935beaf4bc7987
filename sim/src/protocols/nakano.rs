//! Nakano's rubbing experiment (thesis ch. 3, Tables 3.1–3.2): the Omega.7's tip moves along x
//! under position control at 5 mm/s while force control holds 0.3 N along z; the tip's height is
//! the roughness signal and the reaction force along x, estimated by the reaction-force
//! observer (RFOB, cut-off 50 rad/s) since the Omega.7 has no force sensor, is the friction
//! signal. Each surface is rubbed three times — one run to train, two to test — each time on
//! another track of the same surface.
//!
//! Logged at 1 kHz (the thesis samples at 0.3 ms; 1 kHz is the Omega.7's usual servo rate).

use capture::kind;
use capture::{Capture, CaptureError, CaptureErrorKind, CaptureKind, Metadata};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::columns::Columns;
use super::seed::{derive_seed, tag};
use crate::world::sensor::{Encoder, LowPass, Noise, PseudoDifferentiator, round_to};
use crate::world::surface::{RubbingSurface, SurfacePatch};

/// Device name written into these captures.
pub const DEVICE: &str = "sim-omega7";
/// Sample rate, Hz.
pub const RATE_HZ: f64 = 1000.0;
/// Commanded rubbing speed along x (Table 3.2), m/s.
pub const SPEED_MPS: f64 = 0.005;
/// Commanded normal force along z (Table 3.2), N.
pub const NORMAL_FORCE_N: f64 = 0.3;
/// Cut-off of the DOB and RFOB (Table 3.1), rad/s.
pub const OBSERVER_CUTOFF_RADPS: f64 = 50.0;
/// Length rubbed per run, m.
pub const STROKE_M: f64 = 0.03;
/// Runs per surface: one to train, two to test (thesis Sec. 3.2).
pub const RUNS: u32 = 3;

/// Noise of the RFOB estimate before its low-pass (from differentiating a quantized encoder and
/// from current noise), N.
const RFOB_NOISE_N: f64 = 0.02;
/// Electrical and vibration noise on the tip height before the encoder, m.
const HEIGHT_NOISE_M: f64 = 1e-6;
/// Time for the position controller to bring the tip up to speed, s.
const RAMP_S: f64 = 0.2;
/// Pseudo-differentiator time constant for the logged velocity, s.
const VELOCITY_TAU_S: f64 = 0.005;

/// The file a run of `surface` is written to, inside the set's `nakano/` folder.
pub fn run_file_name(surface: &RubbingSurface, run: u32) -> String {
    format!("{:02}_{}_run{run}.csv", surface.id, surface.name)
}

/// One rubbing run of `patch` at the thesis's [`SPEED_MPS`]. Run 0 is the training run.
pub fn rubbing_run(patch: &SurfacePatch, run: u32, seed: u64) -> Result<Capture, CaptureError> {
    rubbing_run_at(patch, run, seed, SPEED_MPS)
}

/// [`rubbing_run`] with the tip commanded along x at `speed_mps` instead (a positive, finite
/// speed; the same stroke length and ramp time, so a faster run is shorter).
pub fn rubbing_run_at(
    patch: &SurfacePatch,
    run: u32,
    seed: u64,
    speed_mps: f64,
) -> Result<Capture, CaptureError> {
    stroke(patch, None, run, seed, speed_mps)
}

/// Where the stroke of a two-patch run passes from its first patch onto its second: halfway,
/// so that each patch is rubbed for half the stroke (3 s at 5 mm/s).
pub const TWO_PATCH_CHANGE_M: f64 = STROKE_M / 2.0;

/// The least time a two-patch stroke rubs its second patch, s: what the half stroke lasts at
/// [`SPEED_MPS`]. A faster stroke goes on past the half stroke's end for that long, so that
/// how soon a recognizer follows the change is measured over the same time at every speed
/// (at 20 mm/s the half stroke alone would end 0.75 s after the seam).
pub const TWO_PATCH_AFTER_S: f64 = (STROKE_M - TWO_PATCH_CHANGE_M) / SPEED_MPS;

/// The file a two-patch run is written to, inside the set's `nakano_two_patch/` folder.
pub fn two_patch_file_name(first: &RubbingSurface, second: &RubbingSurface, run: u32) -> String {
    format!(
        "{:02}_{}_to_{:02}_{}_run{run}.csv",
        first.id, first.name, second.id, second.name
    )
}

/// One stroke that starts on `first` and slides onto `second` at [`TWO_PATCH_CHANGE_M`] of
/// travel, as over two patches laid side by side (the seam is a step in height where the two
/// surfaces' profiles meet), at `speed_mps`, rubbing the second for the rest of the stroke or
/// [`TWO_PATCH_AFTER_S`], whichever is longer. Its metadata name the second surface
/// (`surface_after`) and the time the tip crosses the seam (`surface_change_s`), so a
/// recognizer's evaluation can time how soon it follows the change.
pub fn two_patch_run(
    first: &SurfacePatch,
    second: &SurfacePatch,
    run: u32,
    seed: u64,
    speed_mps: f64,
) -> Result<Capture, CaptureError> {
    stroke(first, Some(second), run, seed, speed_mps)
}

/// A stroke over `patch`, or over `patch` then `then` from [`TWO_PATCH_CHANGE_M`] on.
fn stroke(
    patch: &SurfacePatch,
    then: Option<&SurfacePatch>,
    run: u32,
    seed: u64,
    speed_mps: f64,
) -> Result<Capture, CaptureError> {
    if !(speed_mps.is_finite() && speed_mps > 0.0) {
        return Err(CaptureError::without_file(CaptureErrorKind::Invalid {
            field: "command.speed_mps".into(),
            reason: format!("{speed_mps}: the rubbing speed must be positive and finite"),
        }));
    }
    let surface = patch.surface();
    let mut rng = ChaCha8Rng::seed_from_u64(match then {
        None => derive_seed(seed, &[tag::NAKANO, u64::from(surface.id), u64::from(run)]),
        Some(next) => derive_seed(
            seed,
            &[
                tag::NAKANO,
                u64::from(surface.id),
                u64::from(run),
                u64::from(next.surface().id),
            ],
        ),
    });
    let dt = 1.0 / RATE_HZ;
    let encoder = Encoder {
        quantum_m: Encoder::OMEGA7_QUANTUM_M,
    };
    let height_noise = Noise::new(HEIGHT_NOISE_M);
    let rfob_noise = Noise::new(RFOB_NOISE_N);
    let mut friction_observer = LowPass::new(OBSERVER_CUTOFF_RADPS, dt);
    let mut normal_observer = LowPass::new(OBSERVER_CUTOFF_RADPS, dt);
    let mut velocity = PseudoDifferentiator::new(dt, VELOCITY_TAU_S);
    // Each run uses its own track: a start well apart from the other runs' on the patch, and the
    // sample sits a little differently on the table each time (tilt).
    let track = patch.track_length_m();
    let start_m = (f64::from(run) / f64::from(RUNS) + rng.random_range(0.0..0.1)) * track;
    let tilt = rng.random_range(-2e-3..2e-3);
    let mut cols = Columns::new(&[
        kind::TIME_S,
        kind::TANGENTIAL_POSITION_M,
        kind::TANGENTIAL_VELOCITY_MPS,
        kind::COMMANDED_VELOCITY_MPS,
        kind::NORMAL_POSITION_M,
        kind::NORMAL_FORCE_N,
        kind::FRICTION_FORCE_N,
    ]);
    let stroke_m = match then {
        None => STROKE_M,
        Some(_) => STROKE_M.max(TWO_PATCH_CHANGE_M + speed_mps * TWO_PATCH_AFTER_S),
    };
    // The linear ramp covers half the distance a full-speed start would.
    let steps = ((stroke_m / speed_mps + RAMP_S / 2.0) * RATE_HZ).round() as usize;
    let mut x = 0.0;
    let mut change_s = None;
    for k in 0..steps {
        let t = k as f64 * dt;
        let command = speed_mps * (t / RAMP_S).min(1.0);
        x += command * dt;
        let under = match then {
            Some(next) if x >= TWO_PATCH_CHANGE_M => {
                change_s.get_or_insert(t);
                next
            }
            _ => patch,
        };
        let contact = under.contact(start_m + x);
        let z = contact.height_m + tilt * x + height_noise.sample(&mut rng);
        let friction_n = under.friction_n(start_m + x, NORMAL_FORCE_N);
        let x_measured = encoder.read(x);
        cols.push(&[
            k as f64 / RATE_HZ,
            x_measured,
            round_to(velocity.update(x_measured), 1e-6),
            command,
            encoder.read(z),
            round4(normal_observer.update(NORMAL_FORCE_N + rfob_noise.sample(&mut rng))),
            round4(friction_observer.update(friction_n + rfob_noise.sample(&mut rng))),
        ]);
    }
    let mut meta = Metadata::new(CaptureKind::Rubbing, DEVICE, RATE_HZ)
        .with("protocol", "nakano_rubbing")
        .with("source", "Nakano-thesis-ch3-Tables3.1-3.2")
        .with("seed", seed)
        .with("surface", surface.name)
        .with("surface_id", surface.id)
        .with("run", run)
        .with("role", if run == 0 { "train" } else { "test" })
        .with("command.speed_mps", speed_mps)
        .with("command.normal_force_n", NORMAL_FORCE_N)
        .with("friction_source", "rfob")
        .with(recognize::nakano::OBSERVER_CUTOFF_KEY, OBSERVER_CUTOFF_RADPS)
        .with("sensor.encoder_quantum_m", Encoder::OMEGA7_QUANTUM_M)
        .with("sensor.height_noise_m", HEIGHT_NOISE_M)
        .with("sensor.rfob_noise_n", RFOB_NOISE_N)
        .with("track.start_m", start_m)
        .with("track.tilt", tilt)
        .with("truth.roughness_rms_m", surface.roughness.rms_m)
        .with("truth.roughness_wavelength_m", surface.roughness.wavelength_m)
        .with("truth.friction_coefficient", surface.friction_coefficient)
        .with("truth.friction_variation", surface.friction_variation)
        .with("truth.friction_law", "F=N*(mu(x)+dh/dx)");
    if let (Some(next), Some(t)) = (then, change_s) {
        meta.insert(recognize::SURFACE_AFTER_KEY, next.surface().name);
        meta.insert(recognize::SURFACE_CHANGE_S_KEY, t);
        meta.insert("truth.change_m", TWO_PATCH_CHANGE_M);
    }
    cols.into_capture(meta)
}

/// Observer outputs are reported to 0.1 mN.
fn round4(force_n: f64) -> f64 {
    round_to(force_n, 1e-4)
}
