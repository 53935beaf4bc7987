//! What is drawn at random for one trial (placement, stroke, force, nail orientation, contact
//! mode) and the ground truth it writes into the capture's metadata.

use std::f64::consts::TAU;

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::stroke::Stroke;
use super::{
    Adxl345, Behaviour, FORCE_DRIFT_LATERAL, FORCE_DRIFT_MEDIAL, FORCE_SPREAD, HEADING_JITTER_RAD,
    NAIL_JITTER_RAD, NAIL_ORIENTATION_RAD, PITCH_DRIFT_LATERAL_RAD, PITCH_DRIFT_MEDIAL_RAD,
    PLACEMENT_ROTATION_RAD, SIM_RATE_HZ, SPEED_SPREAD, START_JITTER_M, STROKE_M, SURFACE_SIDE_M,
    ScratchSurface,
};
use crate::world::sensor::{Noise, round_to};

/// Everything about one trial that is drawn at random, and what the arm does.
#[derive(Debug, Clone, Copy)]
pub(super) struct TrialSetup {
    pub(super) stroke: Stroke,
    pub(super) force_n: f64,
    pub(super) force_drift: f64,
    pub(super) start_m: [f64; 2],
    /// Heading of the stroke in the world and on the (rotated) surface.
    pub(super) world_heading_rad: f64,
    pub(super) surface_heading_rad: f64,
    pub(super) placement_rotation_rad: f64,
    pub(super) nail_rad: [f64; 3],
    pub(super) pitch_drift_rad: f64,
    pub(super) ripple_phase: f64,
    /// This trial's normal contact mode and contact patch length (0 for air).
    pub(super) normal_mode_hz: f64,
    pub(super) contact_width_m: f64,
}

impl TrialSetup {
    pub(super) fn draw(
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

/// Ground truth for the capture's metadata (the protocol adds the labels: surface, behaviour,
/// trial, seed). Numbers are printed in Rust's shortest round-trip form, lists are
/// `;`-separated, and nothing contains whitespace.
pub(super) fn truth(surface: &ScratchSurface, setup: &TrialSetup) -> Vec<(String, String)> {
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
