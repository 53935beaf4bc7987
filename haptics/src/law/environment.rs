//! Virtual environments: where the force laws meet geometry. An environment maps the virtual
//! tool's position and velocity to the force the virtual world exerts on it; the admittance
//! controller ([`crate::control::admittance`]) makes the device follow the virtual tool.

use glam::DVec3;

use super::friction::FrictionLaw;
use super::needle::{AxialLaw, PunctureState};

/// The force a virtual world exerts on the tool.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct EnvironmentForce {
    /// Force on the tool, N.
    pub force_n: DVec3,
    /// [`crate::safety::flag`] bits from model evaluations.
    pub flags: u32,
    /// A state code for recording (e.g. [`PunctureState::code`]).
    pub state: f64,
    /// The law's main input, for recording (needle depth, normal force), SI.
    pub input: f64,
}

/// A virtual world the haptic thread renders. Allocation-free.
pub trait Environment: Send {
    /// Force on the tool at `position_m` moving at `velocity_mps`.
    fn force(&mut self, position_m: DVec3, velocity_mps: DVec3) -> EnvironmentForce;
}

/// Nothing to touch.
#[derive(Debug, Clone, Copy, Default)]
pub struct FreeSpace;

impl Environment for FreeSpace {
    fn force(&mut self, _: DVec3, _: DVec3) -> EnvironmentForce {
        EnvironmentForce::default()
    }
}

/// A needle inserted downwards (−z) into tissue whose surface is at `surface_z_m`, along a
/// vertical axis through `entry_xy_m`. Inside the tissue the shaft is held on its axis by a
/// lateral spring (tissue does not let a needle move sideways freely).
#[derive(Debug, Clone)]
pub struct NeedleEnvironment<L> {
    /// The puncture law.
    pub law: L,
    /// Height of the tissue surface, m.
    pub surface_z_m: f64,
    /// Entry point (x, y), m.
    pub entry_xy_m: [f64; 2],
    /// Lateral stiffness of the tissue around the shaft, N/m.
    pub lateral_stiffness_npm: f64,
}

impl<L: AxialLaw> NeedleEnvironment<L> {
    /// Tissue with its surface at `surface_z_m`, entered at `entry_xy_m`, lateral stiffness
    /// 200 N/m.
    pub fn new(law: L, surface_z_m: f64, entry_xy_m: [f64; 2]) -> Self {
        Self {
            law,
            surface_z_m,
            entry_xy_m,
            lateral_stiffness_npm: 200.0,
        }
    }
}

impl<L: AxialLaw> Environment for NeedleEnvironment<L> {
    fn force(&mut self, p: DVec3, v: DVec3) -> EnvironmentForce {
        let depth_m = self.surface_z_m - p.z;
        let out = self.law.step(depth_m, -v.z);
        let lateral = if matches!(out.state, PunctureState::Approach | PunctureState::CapsuleLoading) {
            DVec3::ZERO
        } else {
            let k = self.lateral_stiffness_npm;
            DVec3::new(
                k * (self.entry_xy_m[0] - p.x),
                k * (self.entry_xy_m[1] - p.y),
                0.0,
            )
        };
        EnvironmentForce {
            force_n: lateral + DVec3::new(0.0, 0.0, out.axial_force_n),
            flags: out.flags,
            state: out.state.code(),
            input: depth_m,
        }
    }
}

/// A horizontal surface at `surface_z_m`, rendered as a stiff spring–damper below it, with a
/// friction law acting against the tangential (x, y) velocity.
#[derive(Debug, Clone)]
pub struct FrictionSurface<L> {
    /// The friction law.
    pub law: L,
    /// Height of the surface, m.
    pub surface_z_m: f64,
    /// Contact stiffness, N/m (at most the device's maximum stiffness).
    pub stiffness_npm: f64,
    /// Contact damping, N·s/m.
    pub damping_nspm: f64,
    /// Speed over which friction builds up from zero (a regularised Coulomb law; the
    /// discontinuous one chatters at zero speed), m/s.
    pub stick_speed_mps: f64,
}

impl<L: FrictionLaw> FrictionSurface<L> {
    /// A surface at `surface_z_m`: 2000 N/m, 5 N·s/m, friction regularised over 2 mm/s.
    pub fn new(law: L, surface_z_m: f64) -> Self {
        Self {
            law,
            surface_z_m,
            stiffness_npm: 2000.0,
            damping_nspm: 5.0,
            stick_speed_mps: 0.002,
        }
    }
}

impl<L: FrictionLaw> Environment for FrictionSurface<L> {
    fn force(&mut self, p: DVec3, v: DVec3) -> EnvironmentForce {
        let penetration_m = self.surface_z_m - p.z;
        if penetration_m <= 0.0 || !penetration_m.is_finite() {
            return EnvironmentForce::default();
        }
        let normal_n = (self.stiffness_npm * penetration_m - self.damping_nspm * v.z).max(0.0);
        let tangential = DVec3::new(v.x, v.y, 0.0);
        let speed = tangential.length();
        let (friction_n, flags) = self.law.friction_n(normal_n, speed);
        let friction = if speed > 0.0 && speed.is_finite() {
            -tangential / speed * friction_n * (speed / self.stick_speed_mps).min(1.0)
        } else {
            DVec3::ZERO
        };
        EnvironmentForce {
            force_n: DVec3::new(0.0, 0.0, normal_n) + friction,
            flags,
            state: 1.0,
            input: normal_n,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::law::friction::HardFriction;
    use crate::law::needle::{NeedleLaw, NeedleLawConfig};
    use crate::law::reference::{NeedleQuasiStatic, hard_contact_model};
    use sim::HardContact;
    use sim::NeedleTissue;

    #[test]
    fn needle_environment_pushes_up_when_inserting_down() {
        let law = NeedleLaw::new(
            NeedleQuasiStatic::new(NeedleTissue::bovine_liver()),
            NeedleLawConfig::default(),
        );
        let mut env = NeedleEnvironment::new(law, 0.0, [0.0, 0.0]);
        assert_eq!(
            env.force(DVec3::new(0.0, 0.0, 0.001), DVec3::ZERO).force_n,
            DVec3::ZERO
        );
        let f = env.force(DVec3::new(0.0, 0.0, -0.005), DVec3::new(0.0, 0.0, -0.005));
        assert!(f.force_n.z > 0.1 && f.input == 0.005, "{f:?}");
    }

    #[test]
    fn friction_opposes_sliding_and_scales_with_load() {
        let mut s = FrictionSurface::new(HardFriction::new(hard_contact_model(HardContact::li_bi())), 0.0);
        let f = s.force(DVec3::new(0.0, 0.0, -0.001), DVec3::new(0.01, 0.0, 0.0));
        assert!((f.force_n.z - 2.0).abs() < 1e-12);
        assert!((f.force_n.x + HardContact::li_bi().friction_n(2.0)).abs() < 1e-12);
        assert_eq!(
            s.force(DVec3::new(0.0, 0.0, 0.001), DVec3::X).force_n,
            DVec3::ZERO
        );
    }
}
