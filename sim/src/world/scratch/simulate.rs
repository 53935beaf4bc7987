//! The time loop of one trial at the simulation rate: the arm's sway, the nail's modes
//! against the contact (stick-slip through the shear spring), and the accelerometer chain
//! from specific force to 10-bit codes.

use std::f64::consts::TAU;

use rand_chacha::ChaCha8Rng;

use super::path::PathSignals;
use super::trial::TrialSetup;
use super::{
    ACCEL_RATE_HZ, ARM_DAMPING, ARM_MODE_HZ, Adxl345, CROSS_MODE_HZ, Contact, DECIMATION, IN_PLANE_MASS_KG,
    NAIL_DAMPING_MIN, NAIL_MASS_KG, RIPPLE_ALONG_MPS2, RIPPLE_VERTICAL_MPS2, SERVO_JITTER_MPS2, SIM_RATE_HZ,
    STANDARD_GRAVITY_MPS2, ScratchRecording, TANGENTIAL_MODE_HZ,
};
use crate::world::sensor::{LowPass, Noise, round_to};

/// A damped mode `x'' = −ω²x − 2ζωx' + f/m`, stepped by semi-implicit Euler.
#[derive(Debug, Clone, Copy)]
pub(super) struct Mode {
    pub(super) omega: f64,
    pub(super) zeta: f64,
    pub(super) x: f64,
    pub(super) v: f64,
}

impl Mode {
    pub(super) fn new(hz: f64, zeta: f64) -> Self {
        Self {
            omega: TAU * hz,
            zeta,
            x: 0.0,
            v: 0.0,
        }
    }

    /// Puts the mode at rest in equilibrium under a constant specific force (m/s²).
    pub(super) fn settle(&mut self, f_per_m: f64) {
        self.x = f_per_m / (self.omega * self.omega);
        self.v = 0.0;
    }

    /// Spring and damper acceleration `−ω²x − 2ζωx'` in the current state.
    pub(super) fn restoring(&self) -> f64 {
        -self.omega * self.omega * self.x - 2.0 * self.zeta * self.omega * self.v
    }

    /// Advances by `dt` under the specific force `f_per_m` (m/s²); returns the acceleration.
    pub(super) fn step(&mut self, f_per_m: f64, dt: f64) -> f64 {
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
pub(super) struct ShearContact {
    pub(super) stiffness_n_per_m: f64,
    pub(super) stretch_m: f64,
}

impl ShearContact {
    /// Advances by `dt` at sliding speed `w_mps`; returns the friction force on the nail,
    /// positive along the stroke's direction of motion resisting it (i.e. the drag).
    pub(super) fn step(&mut self, w_mps: f64, mu_k: f64, d_mu: f64, normal_n: f64, dt: f64) -> f64 {
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
pub(super) fn rotation(roll: f64, pitch: f64, yaw: f64) -> [[f64; 3]; 3] {
    let (sr, cr) = roll.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    let (sy, cy) = yaw.sin_cos();
    [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
}

/// The time loop: arm, nail, sensor.
pub(super) fn simulate(
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
pub(super) fn quantize(mps2: f64) -> f64 {
    let code = (mps2 / Adxl345::LSB_MPS2)
        .round()
        .clamp(f64::from(Adxl345::CODE_MIN), f64::from(Adxl345::CODE_MAX));
    round_to(code * Adxl345::LSB_MPS2, 1e-4)
}
