//! The 20 household surfaces of Sinapov et al. (Fig. 3) and air.
//!
//! Nobody measured these surfaces' relief or friction; the numbers are engineering estimates
//! chosen so that each surface's physics is plausible and so that the similarities the paper
//! built in on purpose survive: the two papers, the two floor mats, and surfaces and their
//! backs (7/12 corduroy, 5/13 thin floor mat, 8/15 leather and its cotton-wool back, 4/16 bumpy
//! leather and its plastic-pattern back) share materials but not patterns. The reasoning per
//! surface:
//!
//! - Floor mats (1, 5): rubber mats with a moulded square grid, so lateral and medial strokes
//!   both cross ribs; the thick one is softer (lower, more damped contact mode) and coarser.
//!   Their backs are grippy rubber with small dimples (13).
//! - Thin blue mat (2): thin foam with a fine embossing; soft and grippy.
//! - Cloths (3, 11, 14), cotton wool (15): fibrous, compliant (contact mode 50–90 Hz,
//!   ζ 0.4–0.6): they absorb high frequencies. The bed sheet has a fine square weave, the
//!   sparkly cloth sequins, the soft cloth only fuzz.
//! - Corduroy (7): ribs (wales) 3 mm apart running back to front, so lateral strokes cross
//!   them (3 mm) while medial strokes run along them (the 7° skew stretches them to ~25 mm);
//!   its back (12) is a diagonal twill with the ribs only faintly showing through.
//! - Leathers (4, 8): embossed hexagonal bumps (4 mm) or a faint grain; moderate stick-slip.
//!   The backs: the bumpy leather's is a stiffer plastic with a diagonal grid (16), the flat
//!   leather's is suede-like "cotton wool" (15).
//! - Bulletin board (6): cork, granular and broadband.
//! - Plastic kitchen mat (9): hard plastic ribs at 60°, so the two strokes see 2.4 and 1.4 mm.
//! - Table (10), wood (20): hard (contact mode ≥ 200 Hz, light damping), smooth; the wood has
//!   grain ridges running left to right, crossed by medial strokes only.
//! - Papers (17, 18): almost smooth (sub-micron fibre roughness, a few microns of fibre
//!   flocs), on the hard table; the yellow one a little rougher and grippier.
//! - Bubble wrap (19): 10 mm bubbles on a hexagonal lattice, ~1 mm of effective height, on a
//!   soft air-cushioned contact with little damping; its sharp valleys give a harmonic at 5 mm.
//!
//! Across the table: contact patches are 0.15 mm on hard surfaces and up to 0.8 mm on the
//! softest cloths; rigid surfaces lie the same way every time (`lie` 0.03) while cloth and
//! bubble wrap do not (0.2); worn or fuzzy surfaces are patchier than moulded ones.
//!
//! The levels this gives (RMS deviation of |a| from its 100-sample moving average, lateral
//! strokes): about 50–450 mg fast and 13–45 mg slow on the surfaces, 8.5 mg in air.

use std::f64::consts::PI;

use super::contact::{Contact, Texture};
use crate::world::profile::Band;

/// A band from micrometres of RMS and millimetres of wavelength.
fn band(rms_um: f64, wavelength_mm: f64, log_width: f64) -> Band {
    Band {
        rms_m: rms_um * 1e-6,
        wavelength_m: wavelength_mm * 1e-3,
        log_width,
    }
}

/// A directional texture; orientation in degrees from the lateral axis.
fn tex(rms_um: f64, wavelength_mm: f64, log_width: f64, orientation_deg: f64) -> Texture {
    Texture {
        band: band(rms_um, wavelength_mm, log_width),
        orientation_rad: orientation_deg * PI / 180.0,
    }
}

/// The same texture along three directions 60° apart: a hexagonal lattice.
fn hex(rms_um: f64, wavelength_mm: f64, log_width: f64, first_deg: f64) -> [Texture; 3] {
    [0.0, 60.0, 120.0].map(|d| tex(rms_um, wavelength_mm, log_width, first_deg + d))
}

/// The same texture along two perpendicular directions: a square grid.
fn grid(rms_um: f64, wavelength_mm: f64, log_width: f64, first_deg: f64) -> [Texture; 2] {
    [0.0, 90.0].map(|d| tex(rms_um, wavelength_mm, log_width, first_deg + d))
}

/// One row of the table, in table units; see [`Contact`] for what each field means.
struct Row {
    /// Isotropic roughness (µm RMS, mm peak wavelength, log width via [`band`]).
    roughness: Band,
    /// Directional textures (via [`tex`], [`hex`], [`grid`]).
    textures: Vec<Texture>,
    /// [`Contact::thickness_m`] in mm.
    thickness_mm: f64,
    /// [`Contact::normal_mode_hz`].
    mode_hz: f64,
    /// [`Contact::damping_ratio`].
    zeta: f64,
    /// [`Contact::friction`].
    mu: f64,
    /// [`Contact::stick_slip`].
    d_mu: f64,
    /// [`Contact::friction_variation`].
    mu_var: f64,
    /// [`Contact::shear_stiffness_n_per_m`] in kN/m.
    shear_kn_per_m: f64,
    /// [`Contact::contact_width_m`] in mm.
    width_mm: f64,
    /// [`Contact::placement_variation`].
    lie: f64,
    /// [`Contact::patchiness`].
    patches: f64,
}

impl Row {
    fn contact(self) -> Contact {
        Contact {
            roughness: self.roughness,
            textures: self.textures,
            thickness_m: self.thickness_mm * 1e-3,
            normal_mode_hz: self.mode_hz,
            damping_ratio: self.zeta,
            friction: self.mu,
            stick_slip: self.d_mu,
            friction_variation: self.mu_var,
            contact_width_m: self.width_mm * 1e-3,
            placement_variation: self.lie,
            patchiness: self.patches,
            shear_stiffness_n_per_m: self.shear_kn_per_m * 1e3,
        }
    }
}

/// The 20 surfaces' contact models and air (21 entries, air last) with their ids as numbered in
/// Sinapov Fig. 3 and their names.
pub(super) fn household_contacts() -> Vec<(u32, &'static str, Option<Contact>)> {
    #[rustfmt::skip]
    let rows: [(&'static str, Row); 20] = [
        ("thick_floor_mat", Row { roughness: band(11.0, 0.75, 0.9), textures: grid(90.0, 5.5, 0.15, 0.0).to_vec(),
            thickness_mm: 15.0, mode_hz: 95.0, zeta: 0.33, mu: 0.80, d_mu: 0.08, mu_var: 0.05, shear_kn_per_m: 3.0, width_mm: 0.45, lie: 0.1, patches: 0.2 }),
        ("thin_blue_mat", Row { roughness: band(8.0, 1.2, 0.7), textures: grid(15.0, 1.5, 0.3, 30.0).to_vec(),
            thickness_mm: 6.0, mode_hz: 75.0, zeta: 0.40, mu: 0.70, d_mu: 0.10, mu_var: 0.04, shear_kn_per_m: 2.5, width_mm: 0.5, lie: 0.12, patches: 0.2 }),
        ("soft_cloth", Row { roughness: band(20.0, 1.0, 1.0), textures: vec![tex(10.0, 0.8, 0.3, 0.0)],
            thickness_mm: 3.0, mode_hz: 50.0, zeta: 0.55, mu: 0.50, d_mu: 0.02, mu_var: 0.15, shear_kn_per_m: 1.5, width_mm: 0.8, lie: 0.2, patches: 0.3 }),
        ("leather_with_bumps", Row { roughness: band(8.0, 0.5, 0.8), textures: hex(60.0, 4.0, 0.25, 0.0).to_vec(),
            thickness_mm: 2.0, mode_hz: 120.0, zeta: 0.30, mu: 0.60, d_mu: 0.06, mu_var: 0.05, shear_kn_per_m: 4.0, width_mm: 0.3, lie: 0.1, patches: 0.25 }),
        ("thin_floor_mat", Row { roughness: band(10.0, 0.7, 0.9), textures: grid(80.0, 5.0, 0.15, 0.0).to_vec(),
            thickness_mm: 5.0, mode_hz: 110.0, zeta: 0.30, mu: 0.75, d_mu: 0.07, mu_var: 0.05, shear_kn_per_m: 3.5, width_mm: 0.4, lie: 0.1, patches: 0.2 }),
        ("bulletin_board", Row { roughness: band(8.0, 0.45, 1.0), textures: vec![tex(8.0, 2.5, 0.7, 45.0)],
            thickness_mm: 10.0, mode_hz: 130.0, zeta: 0.30, mu: 0.50, d_mu: 0.03, mu_var: 0.10, shear_kn_per_m: 5.0, width_mm: 0.3, lie: 0.05, patches: 0.25 }),
        ("corduroy", Row { roughness: band(8.0, 0.4, 0.8), textures: vec![tex(70.0, 3.0, 0.1, 7.0), tex(20.0, 1.5, 0.1, 7.0)],
            thickness_mm: 1.5, mode_hz: 80.0, zeta: 0.40, mu: 0.55, d_mu: 0.02, mu_var: 0.08, shear_kn_per_m: 2.0, width_mm: 0.5, lie: 0.15, patches: 0.3 }),
        ("leather_flat", Row { roughness: band(3.0, 0.5, 0.8), textures: vec![tex(6.0, 1.2, 0.5, 20.0)],
            thickness_mm: 2.0, mode_hz: 120.0, zeta: 0.30, mu: 0.65, d_mu: 0.07, mu_var: 0.05, shear_kn_per_m: 4.0, width_mm: 0.3, lie: 0.1, patches: 0.25 }),
        ("plastic_kitchen_mat", Row { roughness: band(2.0, 0.3, 0.8), textures: vec![tex(20.0, 1.2, 0.15, 60.0)],
            thickness_mm: 1.0, mode_hz: 150.0, zeta: 0.20, mu: 0.45, d_mu: 0.05, mu_var: 0.03, shear_kn_per_m: 6.0, width_mm: 0.15, lie: 0.08, patches: 0.2 }),
        ("table", Row { roughness: band(0.8, 0.3, 0.9), textures: vec![tex(4.0, 6.0, 0.8, 0.0)],
            thickness_mm: 0.0, mode_hz: 210.0, zeta: 0.10, mu: 0.30, d_mu: 0.04, mu_var: 0.03, shear_kn_per_m: 10.0, width_mm: 0.15, lie: 0.03, patches: 0.3 }),
        ("bed_sheet", Row { roughness: band(5.0, 0.5, 0.9), textures: grid(6.0, 0.35, 0.15, 0.0).to_vec(),
            thickness_mm: 1.0, mode_hz: 70.0, zeta: 0.45, mu: 0.45, d_mu: 0.01, mu_var: 0.08, shear_kn_per_m: 2.0, width_mm: 0.5, lie: 0.2, patches: 0.3 }),
        ("corduroy_back", Row { roughness: band(8.0, 0.4, 0.8), textures: vec![tex(7.0, 0.8, 0.2, 50.0), tex(15.0, 3.0, 0.1, 7.0)],
            thickness_mm: 1.5, mode_hz: 85.0, zeta: 0.40, mu: 0.50, d_mu: 0.02, mu_var: 0.08, shear_kn_per_m: 2.0, width_mm: 0.5, lie: 0.15, patches: 0.3 }),
        ("thin_floor_mat_back", Row { roughness: band(7.0, 0.6, 0.8), textures: hex(20.0, 2.0, 0.2, 10.0).to_vec(),
            thickness_mm: 5.0, mode_hz: 115.0, zeta: 0.28, mu: 0.90, d_mu: 0.12, mu_var: 0.04, shear_kn_per_m: 3.0, width_mm: 0.4, lie: 0.1, patches: 0.2 }),
        ("sparkly_cloth", Row { roughness: band(6.0, 0.5, 0.8),
            textures: vec![tex(6.0, 0.5, 0.15, 0.0), tex(18.0, 2.5, 0.6, 30.0), tex(18.0, 2.5, 0.6, 120.0)],
            thickness_mm: 1.0, mode_hz: 90.0, zeta: 0.40, mu: 0.40, d_mu: 0.02, mu_var: 0.20, shear_kn_per_m: 3.0, width_mm: 0.5, lie: 0.2, patches: 0.3 }),
        ("cotton_wool", Row { roughness: band(18.0, 0.7, 1.0), textures: Vec::new(),
            thickness_mm: 2.0, mode_hz: 55.0, zeta: 0.55, mu: 0.60, d_mu: 0.01, mu_var: 0.12, shear_kn_per_m: 1.5, width_mm: 0.8, lie: 0.2, patches: 0.3 }),
        ("plastic_pattern", Row { roughness: band(2.5, 0.4, 0.8), textures: grid(22.0, 2.5, 0.2, 45.0).to_vec(),
            thickness_mm: 2.0, mode_hz: 160.0, zeta: 0.18, mu: 0.35, d_mu: 0.03, mu_var: 0.03, shear_kn_per_m: 6.0, width_mm: 0.15, lie: 0.08, patches: 0.2 }),
        ("paper_white", Row { roughness: band(0.5, 0.3, 0.9), textures: vec![tex(2.0, 2.0, 0.8, 0.0)],
            thickness_mm: 0.1, mode_hz: 190.0, zeta: 0.18, mu: 0.35, d_mu: 0.015, mu_var: 0.05, shear_kn_per_m: 8.0, width_mm: 0.15, lie: 0.1, patches: 0.25 }),
        ("paper_yellow", Row { roughness: band(0.57, 0.32, 0.9), textures: vec![tex(2.2, 2.0, 0.8, 0.0)],
            thickness_mm: 0.1, mode_hz: 185.0, zeta: 0.19, mu: 0.37, d_mu: 0.015, mu_var: 0.05, shear_kn_per_m: 8.0, width_mm: 0.15, lie: 0.1, patches: 0.25 }),
        ("bubble_wrap", Row { roughness: band(3.0, 0.4, 0.8),
            textures: [hex(450.0, 10.0, 0.08, 17.0), hex(100.0, 5.0, 0.1, 17.0)].concat(),
            thickness_mm: 8.0, mode_hz: 60.0, zeta: 0.20, mu: 0.50, d_mu: 0.08, mu_var: 0.05, shear_kn_per_m: 3.0, width_mm: 0.4, lie: 0.2, patches: 0.15 }),
        ("wood", Row { roughness: band(1.5, 0.3, 0.9), textures: vec![tex(6.0, 1.2, 0.5, 92.0)],
            thickness_mm: 20.0, mode_hz: 220.0, zeta: 0.10, mu: 0.40, d_mu: 0.02, mu_var: 0.05, shear_kn_per_m: 10.0, width_mm: 0.15, lie: 0.03, patches: 0.3 }),
    ];
    let mut contacts: Vec<(u32, &'static str, Option<Contact>)> = rows
        .into_iter()
        .zip(1u32..)
        .map(|((name, row), id)| (id, name, Some(row.contact())))
        .collect();
    contacts.push((21, "air", None));
    contacts
}
