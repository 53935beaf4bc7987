//! What the fingernail feels of a surface: the contact model the scratch simulation reads and
//! the household table fills in.

use crate::world::profile::Band;

/// A directional texture: a random wave field whose crests are straight and perpendicular to
/// `orientation_rad`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Texture {
    /// Height spectrum along the wave direction (RMS in m, peak wavelength in m). A narrow
    /// `log_width` (≲ 0.2) is an almost periodic pattern such as ribs or bubbles.
    pub band: Band,
    /// Direction of the wave vector on the surface, in radians from the lateral (+x) axis.
    /// Ribs that run back to front have orientation ≈ 0, so lateral strokes cross them.
    pub orientation_rad: f64,
}

/// What the nail feels of a surface it touches: the relief, the contact's compliance and its
/// friction. The relief is the surface's own; the rounded ABS tip (1/8 inch thick, Sinapov
/// Fig. 2) averages it over [`Contact::contact_width_m`].
#[derive(Debug, Clone, PartialEq)]
pub struct Contact {
    /// Isotropic roughness (RMS height in m, peak wavelength in m, log width).
    pub roughness: Band,
    /// Directional textures on top of the roughness.
    pub textures: Vec<Texture>,
    /// Thickness of the surface in m. The trajectory was recorded at table height, so a
    /// thicker surface meets the nail early and the position controller adds force:
    /// `F0 = BASE_FORCE_N + CONTROLLER_STIFFNESS_N_PER_M · thickness` (in `scratch.rs`).
    pub thickness_m: f64,
    /// Natural frequency of the nail's normal mode on this surface, in Hz: nail mass on the
    /// contact stiffness of the surface (hard surfaces ring high, soft ones low).
    pub normal_mode_hz: f64,
    /// Damping ratio of the contact (dimensionless); soft and fibrous surfaces absorb more.
    pub damping_ratio: f64,
    /// Kinetic friction coefficient between ABS and the surface (dimensionless).
    pub friction: f64,
    /// Static minus kinetic friction coefficient: the stick-slip tendency (0 = smooth sliding).
    pub stick_slip: f64,
    /// Relative RMS variation of the friction coefficient along the surface; it follows the
    /// roughness (asperities grip), so its spectrum is the roughness spectrum.
    pub friction_variation: f64,
    /// Length of the contact patch along the stroke, in m: the nail tip averages the relief
    /// over it (a triangular pressure profile of this base), so wavelengths shorter than about
    /// this width do not reach the nail. The nail sinks into soft surfaces, so their patch is
    /// longer and their fine texture is absorbed.
    pub contact_width_m: f64,
    /// Relative RMS change of the contact stiffness from one placement to the next
    /// (dimensionless): how differently the surface lies on the table each time it is put
    /// down (folds in cloth, air under paper or bubble wrap, a curling mat). Rigid surfaces
    /// vary little.
    pub placement_variation: f64,
    /// Relative RMS variation of the roughness amplitude across the surface (dimensionless):
    /// wear, fuzz, dirt and fibre density come in patches (≈ `scratch::PATCH_WAVELENGTH_M`), so each
    /// placement scrapes a rougher or smoother strip. Manufactured patterns do not vary.
    pub patchiness: f64,
    /// Tangential (shear) stiffness of the contact in N/m: how far the surface and nail tip
    /// deform before a stuck contact lets go. With `stick_slip` it sets the stick-slip period
    /// `2·Δμ·F / (k·v)`.
    pub shear_stiffness_n_per_m: f64,
}
