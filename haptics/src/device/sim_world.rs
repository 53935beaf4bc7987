//! What a simulated Omega.7 is made of: its mechanism's parameters and the world under its
//! tip. Apart from the device itself so that the device registry can describe a simulated
//! device's setup without importing the device.

use glam::DVec3;

use super::DeviceSpecs;
use sim::Encoder;
use sim::SurfacePatch;
use sim::{HardContact, SoftContact};
use sim::{NeedleSite, NeedleTissue};

/// Mechanical and sensing parameters of the simulated device.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimOmega7Config {
    /// Loop period the device is read and commanded at, s.
    pub period_s: f64,
    /// Physics sub-steps per period.
    pub substeps: u32,
    /// Moving mass per axis, kg.
    pub mass_kg: f64,
    /// Mechanism viscous friction, N·s/m.
    pub viscous_nspm: f64,
    /// Mechanism Coulomb friction, N.
    pub coulomb_n: f64,
    /// Encoder quantum, m.
    pub encoder_quantum_m: f64,
    /// Time constant of the velocity estimate, s.
    pub velocity_tau_s: f64,
    /// End-effector position at power-on, m.
    pub start_m: DVec3,
    /// Make `read_state` fail from this tick on (a cable pulled mid-run), for safety tests.
    pub fail_after_ticks: Option<u64>,
}

impl Default for SimOmega7Config {
    fn default() -> Self {
        Self {
            period_s: 1e-3,
            substeps: 10,
            mass_kg: 0.3,
            viscous_nspm: DeviceSpecs::OMEGA7.internal.viscous_nspm,
            coulomb_n: DeviceSpecs::OMEGA7.internal.coulomb_n,
            encoder_quantum_m: Encoder::OMEGA7_QUANTUM_M,
            velocity_tau_s: 0.005,
            start_m: DVec3::ZERO,
            fail_after_ticks: None,
        }
    }
}

/// How a surface resists sliding.
#[derive(Debug, Clone)]
pub enum Texture {
    /// No friction.
    Frictionless,
    /// Li & Bi's aluminium plate.
    Hard(HardContact),
    /// Li & Bi's sponge.
    Soft(SoftContact),
    /// One of Nakano's surfaces: height and friction fields along x, starting at `offset_m`
    /// into the patch.
    Patch {
        /// The surface.
        patch: Box<SurfacePatch>,
        /// Patch coordinate at device x = 0, m.
        offset_m: f64,
    },
}

/// What the end effector can touch.
#[derive(Debug, Clone)]
pub enum SimWorld {
    /// Free space.
    Free,
    /// A block of tissue whose surface is at `surface_z_m`, entered along −z. Entry sites lie
    /// on the x axis every `spacing_m` (site i at x = i·spacing); the needle meets the site
    /// nearest to it, so an experiment moves sideways to puncture fresh tissue.
    Needle {
        /// The insertion sites (stateful: punctured membranes stay punctured).
        sites: Vec<NeedleSite>,
        /// Distance between sites along x, m.
        spacing_m: f64,
        /// Height of the undeformed tissue surface, m.
        surface_z_m: f64,
        /// Lateral stiffness of the tissue around an inserted shaft, N/m.
        lateral_stiffness_npm: f64,
    },
    /// A horizontal surface at `surface_z_m`.
    Surface {
        /// Height of the surface's mean plane, m.
        surface_z_m: f64,
        /// Contact stiffness, N/m.
        stiffness_npm: f64,
        /// Contact damping, N·s/m.
        damping_nspm: f64,
        /// Friction and texture.
        texture: Texture,
    },
}

impl SimWorld {
    /// One site at the origin's (x, y), surface at `surface_z_m`; 300 N/m laterally.
    pub fn needle(site: NeedleSite, surface_z_m: f64) -> Self {
        SimWorld::Needle {
            sites: vec![site],
            spacing_m: 0.01,
            surface_z_m,
            lateral_stiffness_npm: 300.0,
        }
    }

    /// `count` fresh sites of `tissue`, `spacing_m` apart along x.
    pub fn needle_block(tissue: &NeedleTissue, count: usize, spacing_m: f64, surface_z_m: f64) -> Self {
        SimWorld::Needle {
            sites: (0..count.max(1))
                .map(|_| NeedleSite::new(tissue.clone()))
                .collect(),
            spacing_m,
            surface_z_m,
            lateral_stiffness_npm: 300.0,
        }
    }

    /// The needle site nearest to `x_m`, if this is tissue.
    pub fn needle_site(&self, x_m: f64) -> Option<&NeedleSite> {
        match self {
            SimWorld::Needle { sites, spacing_m, .. } => sites.get(site_index(x_m, *spacing_m, sites.len())),
            _ => None,
        }
    }

    /// A surface at `surface_z_m`: 3000 N/m, 3 N·s/m.
    pub fn surface(texture: Texture, surface_z_m: f64) -> Self {
        SimWorld::Surface {
            surface_z_m,
            stiffness_npm: 3000.0,
            damping_nspm: 3.0,
            texture,
        }
    }

    /// Force of the world on the tip at `x` moving at `v`, stepping stateful contacts by `dt`.
    pub(super) fn force(&mut self, x: DVec3, v: DVec3, dt: f64) -> DVec3 {
        match self {
            SimWorld::Free => DVec3::ZERO,
            SimWorld::Needle {
                sites,
                spacing_m,
                surface_z_m,
                lateral_stiffness_npm,
            } => {
                let depth = *surface_z_m - x.z;
                let i = site_index(x.x, *spacing_m, sites.len());
                let Some(site) = sites.get_mut(i) else {
                    return DVec3::ZERO;
                };
                let axial = site.step(depth, -v.z, dt).axial_force_n;
                let lateral = if site.punctured() > 0 && depth > 0.0 {
                    DVec3::new(i as f64 * *spacing_m - x.x, -x.y, 0.0) * *lateral_stiffness_npm
                } else {
                    DVec3::ZERO
                };
                lateral + DVec3::new(0.0, 0.0, axial)
            }
            SimWorld::Surface {
                surface_z_m,
                stiffness_npm,
                damping_nspm,
                texture,
            } => {
                let (height, slope, mu) = match texture {
                    Texture::Patch { patch, offset_m } => {
                        let c = patch.contact(*offset_m + x.x);
                        (c.height_m, c.slope, Some(c.friction_coefficient))
                    }
                    _ => (0.0, 0.0, None),
                };
                let penetration = *surface_z_m + height - x.z;
                if penetration <= 0.0 {
                    return DVec3::ZERO;
                }
                let normal = (*stiffness_npm * penetration - *damping_nspm * v.z).max(0.0);
                let tangential = DVec3::new(v.x, v.y, 0.0);
                let speed = tangential.length();
                let magnitude = match texture {
                    Texture::Frictionless => 0.0,
                    Texture::Hard(law) => law.friction_n(normal),
                    Texture::Soft(law) => law.friction_n(speed, normal),
                    Texture::Patch { .. } => normal * mu.unwrap_or(0.0),
                };
                // Regularised Coulomb: full friction above 0.2 mm/s.
                let friction = if speed > 0.0 {
                    -tangential / speed * magnitude * (speed / 2e-4).min(1.0)
                } else {
                    DVec3::ZERO
                };
                // Climbing an asperity of slope h' costs N·h' along x (surface.rs).
                DVec3::new(-normal * slope, 0.0, normal) + friction
            }
        }
    }
}

fn site_index(x_m: f64, spacing_m: f64, count: usize) -> usize {
    if spacing_m > 0.0 && x_m.is_finite() {
        ((x_m / spacing_m).round().max(0.0) as usize).min(count.saturating_sub(1))
    } else {
        0
    }
}
