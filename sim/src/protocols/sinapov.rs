//! Sinapov et al.'s scratching experiment (IEEE T-RO 2011, Sec. III): an accelerometer-bearing
//! fingernail scratches 20 household surfaces and air with five exploratory behaviours, ten
//! trials each; the accelerometer is read at 400 Hz. The physics lives in
//! [`crate::world::scratch`]; this module turns a trial into a capture.

use capture::kind::{
    ACCEL_X_MPS2, ACCEL_Y_MPS2, ACCEL_Z_MPS2, NORMAL_FORCE_N, TANGENTIAL_POSITION_M, TIME_S,
};
use capture::{Capture, CaptureError, CaptureKind, Metadata};

use crate::world::scratch::{ACCEL_RATE_HZ, Behaviour, ScratchSurface, scratch_trial};

/// Device name written into these captures.
pub const DEVICE: &str = "sim-wam-fingernail-adxl345";
/// Trials per behaviour and surface (Sinapov Sec. III-E).
pub const TRIALS: u32 = 10;

/// One scratching trial as a capture.
pub fn scratch_capture(
    surface: &ScratchSurface,
    behaviour: Behaviour,
    trial: u32,
    seed: u64,
) -> Result<Capture, CaptureError> {
    let rec = scratch_trial(surface, behaviour, trial, seed);
    let mut meta = Metadata::new(CaptureKind::Rubbing, DEVICE, ACCEL_RATE_HZ)
        .with("protocol", "sinapov_scratch")
        .with("source", "Sinapov-2011-IEEE-TRO")
        .with("seed", seed)
        .with("surface", surface.name)
        .with("surface_id", surface.id)
        .with("behaviour", behaviour.name())
        .with("trial", trial);
    for (key, value) in rec.truth {
        meta.insert(key, value);
    }
    let [ax, ay, az] = rec.accel_mps2;
    Capture::new(
        meta,
        [
            TIME_S,
            TANGENTIAL_POSITION_M,
            NORMAL_FORCE_N,
            ACCEL_X_MPS2,
            ACCEL_Y_MPS2,
            ACCEL_Z_MPS2,
        ]
        .map(String::from)
        .to_vec(),
        vec![
            rec.time_s,
            rec.tangential_position_m,
            rec.normal_force_n,
            ax,
            ay,
            az,
        ],
    )
}
