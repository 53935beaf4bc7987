//! Needle insertion into layered tissue: the ground truth of the needle-puncture captures.
//!
//! The structure is Okamura, Simone & O'Leary, "Force modeling for needle insertion into soft
//! tissue", IEEE Trans. Biomed. Eng. 51(10), 2004 (bovine liver): the axial force is the sum of
//! - a **stiffness** force while a membrane (the liver capsule, a vessel wall) deflects ahead of
//!   the tip before it is punctured: the nonlinear spring `f = a1·u + a2·u²` in the deflection u;
//! - a **cutting** force while the tip advances into tissue it has not cut before (constant per
//!   tissue in Okamura et al.; here with a small rate term);
//! - **friction** along the shaft inside the tissue, a modified Karnopp model per unit inserted
//!   length: `L·(C·sgn v + b·v)` outside a small static band, relaxing while the needle is held.
//!
//! Puncture happens when the membrane's elastic force reaches its puncture force. The puncture
//! force falls with insertion speed (Mahvash & Dupont, "Mechanics of dynamic needle insertion
//! into a biological material", IEEE Trans. Biomed. Eng. 57(4), 2010: faster insertion
//! ruptures with less deformation), and deflection has a viscous part, so the identified force
//! must depend on both depth and speed — Li & Bi's Fig. 10.
//!
//! Magnitudes for the default liver ([`NeedleTissue::bovine_liver`]) are chosen so the capsule
//! puncture peak is 1.4–1.8 N at 11–13 mm for 1–10 mm/s, in the range reported for ex vivo
//! bovine liver insertions (peaks of about 1–3 N within 1–3 cm at 1–10 mm/s), with a vessel
//! wall 20 mm below the capsule giving a second, smaller puncture.
//!
//! Sign convention (as in captures): `depth_m` is the tip's displacement past the undeformed
//! tissue surface (negative in air); velocity is positive when inserting; the returned axial
//! force is the force resisting the needle, positive when it pushes the needle back out.
//! Withdrawal feels friction only.

/// A membrane the needle must puncture: a tissue surface or an internal wall.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Membrane {
    /// Name used in metadata (`capsule`, `vessel_wall`).
    pub name: &'static str,
    /// Depth of the membrane below the undeformed tissue surface, in metres.
    pub depth_m: f64,
    /// Linear stiffness coefficient a1 of the deflection force, N/m.
    pub a1_npm: f64,
    /// Quadratic stiffness coefficient a2, N/m².
    pub a2_npm2: f64,
    /// Elastic force at which the membrane ruptures when pushed very slowly, N.
    pub puncture_force_n: f64,
    /// Fraction by which the puncture force falls at high speed.
    pub rate_softening: f64,
    /// Speed scale of that fall, m/s.
    pub rate_scale_mps: f64,
    /// Viscous part of the deflection force, N·s/m.
    pub damping_nspm: f64,
}

impl Membrane {
    /// Puncture force at insertion speed `speed_mps`:
    /// `f_p(v) = f_p0·(1 − s·(1 − exp(−v/v_s)))`.
    pub fn puncture_force_at(&self, speed_mps: f64) -> f64 {
        let v = speed_mps.max(0.0);
        self.puncture_force_n * (1.0 - self.rate_softening * (1.0 - (-v / self.rate_scale_mps).exp()))
    }

    /// Elastic deflection force for deflection `u_m` (0 for u ≤ 0).
    pub fn elastic_force_n(&self, u_m: f64) -> f64 {
        if u_m <= 0.0 {
            0.0
        } else {
            self.a1_npm * u_m + self.a2_npm2 * u_m * u_m
        }
    }

    /// Deflection at which a membrane pushed at constant `speed_mps` ruptures: the positive
    /// root of `a1·u + a2·u² = f_p(v)`.
    pub fn puncture_deflection_m(&self, speed_mps: f64) -> f64 {
        let f = self.puncture_force_at(speed_mps);
        if self.a2_npm2 > 0.0 {
            (-self.a1_npm + (self.a1_npm * self.a1_npm + 4.0 * self.a2_npm2 * f).sqrt())
                / (2.0 * self.a2_npm2)
        } else {
            f / self.a1_npm
        }
    }
}

/// A stretch of tissue between membranes that cuts harder or easier than the tissue's own
/// cutting force: subcutaneous fat, a dense ligament, the epidural space's loose fat.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CuttingLayer {
    /// Name used in metadata (`subcutaneous_fat`).
    pub name: &'static str,
    /// Depth below the undeformed surface where it starts, in metres; it reaches down to the
    /// next cutting layer.
    pub top_m: f64,
    /// Factor on the tissue's cutting force (both its parts) within it.
    pub cutting_factor: f64,
}

/// Parameters of a layered tissue.
#[derive(Debug, Clone, PartialEq)]
pub struct NeedleTissue {
    /// Membranes ordered by depth; the first one is the tissue surface (depth 0).
    pub membranes: Vec<Membrane>,
    /// Cutting layers ordered by depth; above the first (or with none) the factor is 1.
    pub cutting_layers: Vec<CuttingLayer>,
    /// Whether the tip keeps cutting the layer it is in while the next membrane starts to load,
    /// until the membrane resists more than the cutting did. In Okamura's liver a thin capsule
    /// or wall loads in front of soft parenchyma and cutting stops meanwhile (`false`); a needle
    /// cutting through a dense ligament into the next one feels no fall where the second
    /// starts to load (`true`), since nothing there gives way.
    pub cuts_while_loading: bool,
    /// Cutting force at zero speed, N.
    pub cutting_force_n: f64,
    /// Rate dependence of cutting, N·s/m.
    pub cutting_damping_nspm: f64,
    /// Coulomb friction per metre of shaft in tissue, N/m.
    pub coulomb_npm: f64,
    /// Viscous friction per metre of shaft per m/s, N·s/m².
    pub viscous_nspm2: f64,
    /// Half-width of Karnopp's static band, m/s.
    pub static_band_mps: f64,
    /// Time constant of the friction relaxing while the needle is held, s.
    pub relaxation_s: f64,
}

impl NeedleTissue {
    /// Ex vivo bovine liver: Glisson's capsule, parenchyma, a vessel wall 20 mm deep.
    pub fn bovine_liver() -> Self {
        Self {
            membranes: vec![
                Membrane {
                    name: "capsule",
                    depth_m: 0.0,
                    a1_npm: 30.0,
                    a2_npm2: 8000.0,
                    puncture_force_n: 1.8,
                    rate_softening: 0.25,
                    rate_scale_mps: 0.005,
                    damping_nspm: 15.0,
                },
                Membrane {
                    name: "vessel_wall",
                    depth_m: 0.020,
                    a1_npm: 60.0,
                    a2_npm2: 30_000.0,
                    puncture_force_n: 0.6,
                    rate_softening: 0.2,
                    rate_scale_mps: 0.005,
                    damping_nspm: 5.0,
                },
            ],
            cutting_layers: Vec::new(),
            cuts_while_loading: false,
            cutting_force_n: 0.25,
            cutting_damping_nspm: 10.0,
            coulomb_npm: 6.0,
            viscous_nspm2: 800.0,
            static_band_mps: 1e-4,
            relaxation_s: 1.5,
        }
    }

    /// A second tissue, for testing on what a model was not identified from: a layered phantom
    /// with three membranes at other depths, thicknesses and stiffnesses than the liver (a
    /// stiff skin-like surface that gives after ~5 mm, a fascia 9 mm down, a deep capsule at
    /// 20 mm), and more cutting and Coulomb friction but less viscous friction along the
    /// shaft.
    pub fn layered_phantom() -> Self {
        Self {
            membranes: vec![
                Membrane {
                    name: "skin",
                    depth_m: 0.0,
                    a1_npm: 80.0,
                    a2_npm2: 60_000.0,
                    puncture_force_n: 2.2,
                    rate_softening: 0.3,
                    rate_scale_mps: 0.004,
                    damping_nspm: 20.0,
                },
                Membrane {
                    name: "fascia",
                    depth_m: 0.009,
                    a1_npm: 120.0,
                    a2_npm2: 60_000.0,
                    puncture_force_n: 1.0,
                    rate_softening: 0.15,
                    rate_scale_mps: 0.006,
                    damping_nspm: 8.0,
                },
                Membrane {
                    name: "deep_capsule",
                    depth_m: 0.020,
                    a1_npm: 40.0,
                    a2_npm2: 15_000.0,
                    puncture_force_n: 0.8,
                    rate_softening: 0.25,
                    rate_scale_mps: 0.005,
                    damping_nspm: 6.0,
                },
            ],
            cutting_layers: Vec::new(),
            cuts_while_loading: false,
            cutting_force_n: 0.35,
            cutting_damping_nspm: 15.0,
            coulomb_npm: 9.0,
            viscous_nspm2: 500.0,
            static_band_mps: 1e-4,
            relaxation_s: 1.0,
        }
    }

    /// A lumbar epidural approach in the midline (L3–L4), as a Tuohy needle meets it: skin,
    /// subcutaneous fat, the supraspinous and interspinous ligaments, the ligamentum flavum, the
    /// epidural space and the dura. Four of the layers are membranes that give with a pop
    /// (skin, supraspinous ligament, ligamentum flavum, dura); fat, the interspinous ligament
    /// and the epidural space are cutting layers.
    ///
    /// Measured anatomy and mechanics it follows:
    /// - depth from skin to the epidural space: mean 41.8 mm, 84 % under 50 mm in 234
    ///   parturients (Kim, Cheun, Choi & Bae, Korean J. Anesthesiol. 26(2):299–302, 1993);
    ///   here the ligamentum flavum gives 40.5–41 mm deep;
    /// - the epidural space is about 4 mm wide and 6 mm deep behind the ligamentum flavum
    ///   (IEEE Xplore 8794199, 2019): the dura lies 5 mm behind where the ligament gives;
    /// - resistance peaks at the ligamentum flavum and falls suddenly in the epidural space, the
    ///   loss of resistance (Vaughan, Dubey, Wee & Isaacs 2012, porcine lumbar spine: syringe
    ///   pressure peaks of 62.7–66.7 kPa at the ligamentum flavum, then a loss of pressure);
    ///   here the flavum's puncture force is the largest in the path;
    /// - the ligamentum flavum's peak force is larger at 2 mm/s than at 0.4 mm/s (Naemura &
    ///   Saito, IFMBE Proc. 25/6:28–31, 2009): its puncture force rises with speed
    ///   (a negative rate softening), where the skin's and the dura's fall;
    /// - the dura tents 2–6 mm ahead of a Tuohy needle before it is punctured (Zarzur &
    ///   Gonçalves 1992; Lewis et al., Br. J. Anaesth. 85:238–241, 2000, measured the tenting
    ///   and the peak force at dural puncture): here about 4 mm.
    ///
    /// The axial forces themselves (a few newtons; the flavum gives at 5–6 N, about 7 N with the
    /// shaft's friction) are this model's choice on that pattern: no study we can cite gives a Tuohy needle's axial force per
    /// layer in vivo. They stay within an Omega.7's 12 N.
    pub fn lumbar_epidural() -> Self {
        Self {
            membranes: vec![
                Membrane {
                    name: "skin",
                    depth_m: 0.0,
                    a1_npm: 100.0,
                    a2_npm2: 40_000.0,
                    puncture_force_n: 2.4,
                    rate_softening: 0.3,
                    rate_scale_mps: 0.004,
                    damping_nspm: 20.0,
                },
                Membrane {
                    name: "supraspinous_ligament",
                    depth_m: 0.016,
                    a1_npm: 300.0,
                    a2_npm2: 150_000.0,
                    puncture_force_n: 2.2,
                    rate_softening: 0.15,
                    rate_scale_mps: 0.005,
                    damping_nspm: 30.0,
                },
                Membrane {
                    name: "ligamentum_flavum",
                    depth_m: 0.037,
                    a1_npm: 600.0,
                    a2_npm2: 250_000.0,
                    puncture_force_n: 5.0,
                    rate_softening: -0.2,
                    rate_scale_mps: 0.003,
                    damping_nspm: 60.0,
                },
                Membrane {
                    name: "dura",
                    depth_m: 0.046,
                    a1_npm: 120.0,
                    a2_npm2: 30_000.0,
                    puncture_force_n: 1.0,
                    rate_softening: 0.2,
                    rate_scale_mps: 0.005,
                    damping_nspm: 8.0,
                },
            ],
            cutting_layers: vec![
                CuttingLayer {
                    name: "subcutaneous_fat",
                    top_m: 0.0,
                    cutting_factor: 0.4,
                },
                CuttingLayer {
                    name: "interspinous_ligament",
                    top_m: 0.018,
                    cutting_factor: 2.5,
                },
                CuttingLayer {
                    name: "epidural_space",
                    top_m: 0.037,
                    cutting_factor: 0.1,
                },
                CuttingLayer {
                    name: "subarachnoid_space",
                    top_m: 0.046,
                    cutting_factor: 0.05,
                },
            ],
            cuts_while_loading: true,
            cutting_force_n: 0.6,
            cutting_damping_nspm: 20.0,
            coulomb_npm: 15.0,
            viscous_nspm2: 800.0,
            static_band_mps: 1e-4,
            relaxation_s: 1.5,
        }
    }

    /// Factor on the cutting force at `depth_m`: the deepest cutting layer starting at or
    /// above it, 1 above them all.
    pub fn cutting_factor_at(&self, depth_m: f64) -> f64 {
        self.cutting_layers
            .iter()
            .rev()
            .find(|l| l.top_m <= depth_m)
            .map_or(1.0, |l| l.cutting_factor)
    }

    /// Depth (from the undeformed surface) at which membrane `index` ruptures when the needle
    /// advances at constant `speed_mps`.
    pub fn puncture_depth_m(&self, index: usize, speed_mps: f64) -> Option<f64> {
        self.membranes
            .get(index)
            .map(|m| m.depth_m + m.puncture_deflection_m(speed_mps))
    }

    /// Axial force just before membrane `index` ruptures when the needle advances at constant
    /// `speed_mps` (above the static band): the membrane's puncture force and its viscous
    /// deflection force, plus — once the surface is breached — the shaft's friction over the
    /// depth inserted by then. Cutting stops while a membrane is pushed, so it adds nothing.
    /// This is the peak a recording of this tissue shows at that puncture.
    pub fn puncture_peak_force_n(&self, index: usize, speed_mps: f64) -> Option<f64> {
        let m = self.membranes.get(index)?;
        let v = speed_mps.max(0.0);
        let depth_m = self.puncture_depth_m(index, v)?;
        let friction_n = if index > 0 && v > self.static_band_mps {
            depth_m * (self.coulomb_npm + self.viscous_nspm2 * v)
        } else {
            0.0
        };
        Some(m.puncture_force_at(v) + m.damping_nspm * v + friction_n)
    }

    /// The parameters as `(name, value)` pairs for capture metadata.
    pub fn parameters(&self) -> Vec<(String, f64)> {
        let mut out = vec![
            ("cutting_force_n".to_owned(), self.cutting_force_n),
            ("cutting_damping_nspm".to_owned(), self.cutting_damping_nspm),
            ("coulomb_npm".to_owned(), self.coulomb_npm),
            ("viscous_nspm2".to_owned(), self.viscous_nspm2),
            ("static_band_mps".to_owned(), self.static_band_mps),
            ("relaxation_s".to_owned(), self.relaxation_s),
        ];
        // Only tissues with cutting layers name them: the others' captures keep their bytes.
        for l in &self.cutting_layers {
            out.push((format!("{}.top_m", l.name), l.top_m));
            out.push((format!("{}.cutting_factor", l.name), l.cutting_factor));
        }
        for m in &self.membranes {
            for (key, value) in [
                ("depth_m", m.depth_m),
                ("a1_npm", m.a1_npm),
                ("a2_npm2", m.a2_npm2),
                ("puncture_force_n", m.puncture_force_n),
                ("rate_softening", m.rate_softening),
                ("rate_scale_mps", m.rate_scale_mps),
                ("damping_nspm", m.damping_nspm),
            ] {
                out.push((format!("{}.{key}", m.name), value));
            }
        }
        out
    }
}

/// The state of one insertion site: which membranes are punctured, how deep the cut goes and
/// the friction the shaft currently holds. A fresh site starts intact.
#[derive(Debug, Clone, PartialEq)]
pub struct NeedleSite {
    tissue: NeedleTissue,
    punctured: usize,
    cut_depth_m: f64,
    friction_n: f64,
    punctures: Vec<f64>,
}

/// What the tissue does to the needle in one step.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NeedleForce {
    /// Total axial force resisting the needle, N.
    pub axial_force_n: f64,
    /// Elastic + viscous deflection force of the membrane ahead of the tip, N.
    pub stiffness_n: f64,
    /// Cutting force, N.
    pub cutting_n: f64,
    /// Shaft friction, N.
    pub friction_n: f64,
}

impl NeedleSite {
    /// A fresh, intact insertion site.
    pub fn new(tissue: NeedleTissue) -> Self {
        // At most one puncture per membrane: reserving them now keeps `step` allocation-free,
        // so a site can live on the haptic thread (the simulated Omega.7).
        let punctures = Vec::with_capacity(tissue.membranes.len());
        Self {
            tissue,
            punctured: 0,
            cut_depth_m: 0.0,
            friction_n: 0.0,
            punctures,
        }
    }

    /// The tissue this site is made of.
    pub fn tissue(&self) -> &NeedleTissue {
        &self.tissue
    }

    /// Number of membranes punctured so far.
    pub fn punctured(&self) -> usize {
        self.punctured
    }

    /// Depths at which punctures happened, in order.
    pub fn puncture_depths_m(&self) -> &[f64] {
        &self.punctures
    }

    /// Advances the site by `dt_s` with the tip at `depth_m` moving at `velocity_mps`, and
    /// returns the force on the needle.
    pub fn step(&mut self, depth_m: f64, velocity_mps: f64, dt_s: f64) -> NeedleForce {
        let t = &self.tissue;
        let mut force = NeedleForce::default();

        // Shaft friction acts on the length inside tissue, once the surface is breached.
        let inside_m = if self.punctured > 0 { depth_m.max(0.0) } else { 0.0 };
        if velocity_mps.abs() > t.static_band_mps {
            self.friction_n =
                inside_m * (t.coulomb_npm * velocity_mps.signum() + t.viscous_nspm2 * velocity_mps);
        } else {
            // Held: the tissue around the shaft relaxes (and the shaft may have left it).
            let decay = (-dt_s / t.relaxation_s).exp();
            let limit = inside_m * t.coulomb_npm;
            self.friction_n = (self.friction_n * decay).clamp(-limit, limit);
        }
        force.friction_n = self.friction_n;

        if let Some(m) = t.membranes.get(self.punctured) {
            let u = depth_m - m.depth_m;
            let elastic = m.elastic_force_n(u);
            if u > 0.0 && velocity_mps >= 0.0 && elastic >= m.puncture_force_at(velocity_mps) {
                self.punctured += 1;
                self.punctures.push(depth_m);
                // The tip now stands in the cavity it pushed open: the tissue up to here is cut.
                self.cut_depth_m = self.cut_depth_m.max(depth_m);
            } else if u > 0.0 {
                force.stiffness_n = elastic + m.damping_nspm * velocity_mps;
                if force.stiffness_n < 0.0 {
                    force.stiffness_n = 0.0;
                }
            }
        }

        // Cutting: only when advancing past everything cut before, in tissue, with no intact
        // membrane being pushed ahead of the tip (or, where the tissue cuts while loading, only
        // as far as the cutting exceeds the membrane's resistance).
        let pushing_membrane = force.stiffness_n > 0.0;
        if self.punctured > 0 && velocity_mps > t.static_band_mps && depth_m > self.cut_depth_m {
            let cutting_n = t.cutting_force_n + t.cutting_damping_nspm * velocity_mps;
            if !pushing_membrane {
                force.cutting_n = cutting_n * t.cutting_factor_at(depth_m);
                self.cut_depth_m = depth_m;
            } else if t.cuts_while_loading {
                // The layer being cut is the one the tip last cut, in front of the membrane.
                let cutting_n = cutting_n * t.cutting_factor_at(self.cut_depth_m);
                force.cutting_n = (cutting_n - force.stiffness_n).max(0.0);
            }
        }

        force.axial_force_n = force.stiffness_n + force.cutting_n + force.friction_n;
        force
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Inserts at constant speed to `to_m` and returns (depth, force) pairs every `dt`.
    fn insert(site: &mut NeedleSite, speed: f64, to_m: f64, dt: f64) -> Vec<(f64, f64)> {
        let mut out = Vec::new();
        let mut d = -0.002;
        while d < to_m {
            d += speed * dt;
            out.push((d, site.step(d, speed, dt).axial_force_n));
        }
        out
    }

    #[test]
    fn force_drops_at_the_predicted_puncture_depths() {
        let tissue = NeedleTissue::bovine_liver();
        for speed in [0.001, 0.005, 0.01] {
            let mut site = NeedleSite::new(tissue.clone());
            let trace = insert(&mut site, speed, 0.03, 1e-4);
            assert_eq!(site.punctured(), 2);
            for (k, &at) in site.puncture_depths_m().iter().enumerate() {
                let predicted = tissue.puncture_depth_m(k, speed).unwrap();
                assert!(
                    (at - predicted).abs() < speed * 1e-4 + 1e-9,
                    "{k} {at} {predicted}"
                );
                // The force falls by most of the membrane's puncture force across the event.
                let i = trace.iter().position(|&(d, _)| d >= at).unwrap();
                let before = trace[i - 1].1;
                let after = trace[i].1;
                let expected_drop = tissue.membranes[k].puncture_force_at(speed) * 0.5;
                assert!(before - after > expected_drop, "{k}: {before} -> {after}");
            }
        }
    }

    #[test]
    fn puncture_peaks_are_the_largest_forces_before_each_rupture() {
        let tissue = NeedleTissue::bovine_liver();
        for speed in [0.001, 0.004, 0.01] {
            let mut site = NeedleSite::new(tissue.clone());
            let trace = insert(&mut site, speed, 0.03, 1e-5);
            let mut from = 0;
            for (k, &at) in site.puncture_depths_m().iter().enumerate() {
                let to = trace.iter().position(|&(d, _)| d >= at).unwrap();
                let simulated = trace[from..to].iter().map(|p| p.1).fold(0.0, f64::max);
                let predicted = tissue.puncture_peak_force_n(k, speed).unwrap();
                // One step short of the rupture the force lies below it by the elastic
                // force's growth over that step.
                assert!(
                    (simulated - predicted).abs() < 2e-3 && simulated <= predicted,
                    "{k} at {speed} m/s: {simulated} vs {predicted}"
                );
                from = to;
            }
        }
        assert!(
            NeedleTissue::bovine_liver()
                .puncture_peak_force_n(2, 0.001)
                .is_none()
        );
    }

    #[test]
    fn peak_force_is_in_the_bovine_liver_range() {
        for speed in [0.001, 0.01] {
            let mut site = NeedleSite::new(NeedleTissue::bovine_liver());
            let trace = insert(&mut site, speed, 0.03, 1e-4);
            let (depth, peak) = trace
                .iter()
                .copied()
                .fold((0.0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
            assert!((1.0..=3.0).contains(&peak), "peak {peak} N");
            assert!((0.01..=0.03).contains(&depth), "at {depth} m");
        }
    }

    #[test]
    fn the_lumbar_spine_gives_skin_to_dura_in_order_and_loses_resistance_at_the_flavum() {
        let tissue = NeedleTissue::lumbar_epidural();
        for speed in [0.001, 0.003, 0.01] {
            let mut site = NeedleSite::new(tissue.clone());
            let trace = insert(&mut site, speed, 0.055, 1e-5);
            assert_eq!(site.punctured(), 4, "at {speed} m/s");
            for (k, &at) in site.puncture_depths_m().iter().enumerate() {
                let predicted = tissue.puncture_depth_m(k, speed).unwrap();
                assert!(
                    (at - predicted).abs() < speed * 1e-5 + 1e-9,
                    "{k}: {at} vs {predicted}"
                );
            }
            let at = site.puncture_depths_m();
            // The flavum gives 40.5–41 mm deep and the dura lies 5 mm behind it (the cited
            // anatomy in `lumbar_epidural`).
            assert!((0.0405..=0.041).contains(&at[2]), "flavum at {}", at[2]);
            let space = tissue.membranes[3].depth_m - at[2];
            assert!((0.0045..=0.0058).contains(&space), "epidural space {space}");
            // Loss of resistance: the flavum's peak is the largest force before the dura and
            // the force behind it falls to less than a fifth of it.
            let peak_before = |depth: f64| {
                trace
                    .iter()
                    .filter(|p| p.0 < depth)
                    .map(|p| p.1)
                    .fold(0.0, f64::max)
            };
            let flavum = peak_before(at[2]);
            assert!((flavum - peak_before(at[1])) > 2.0, "{flavum}");
            let behind = trace.iter().find(|p| p.0 > at[2] + 0.001).map(|p| p.1).unwrap();
            assert!(behind < 0.2 * flavum, "{behind} after {flavum}");
            // Cutting through the interspinous ligament into the flavum, nothing gives where
            // the flavum starts to load: the force never falls between the two punctures.
            let between: Vec<f64> = trace
                .iter()
                .filter(|p| p.0 > at[1] + 0.002 && p.0 < at[2])
                .map(|p| p.1)
                .collect();
            assert!(
                between.windows(2).all(|w| w[1] >= w[0] - 1e-9),
                "the force falls before the flavum gives at {speed} m/s"
            );
        }
        // The flavum's puncture force rises with speed, as measured; the skin's falls.
        let m = &tissue.membranes;
        assert!(m[2].puncture_force_at(0.002) > m[2].puncture_force_at(0.0004));
        assert!(m[0].puncture_force_at(0.002) < m[0].puncture_force_at(0.0004));
    }

    #[test]
    fn faster_insertion_punctures_earlier() {
        let t = NeedleTissue::bovine_liver();
        let slow = t.puncture_depth_m(0, 0.001).unwrap();
        let fast = t.puncture_depth_m(0, 0.01).unwrap();
        assert!(fast < slow - 0.001, "{slow} {fast}");
    }

    #[test]
    fn withdrawal_feels_only_friction_and_reinsertion_does_not_cut_again() {
        let mut site = NeedleSite::new(NeedleTissue::bovine_liver());
        insert(&mut site, 0.005, 0.03, 1e-4);
        let t = site.tissue().clone();
        let f = site.step(0.0299, -0.005, 1e-4);
        assert_eq!(f.cutting_n, 0.0);
        assert_eq!(f.stiffness_n, 0.0);
        let expected = 0.0299 * (-t.coulomb_npm + t.viscous_nspm2 * -0.005);
        assert!((f.axial_force_n - expected).abs() < 1e-12);
        // Back in along the existing channel: friction only, positive now.
        let f = site.step(0.0295, 0.005, 1e-4);
        assert_eq!(f.cutting_n, 0.0);
        assert!((f.axial_force_n - 0.0295 * (t.coulomb_npm + t.viscous_nspm2 * 0.005)).abs() < 1e-12);
        // Out of the tissue: nothing.
        assert_eq!(site.step(-0.001, -0.005, 1e-4).axial_force_n, 0.0);
    }

    #[test]
    fn held_needle_relaxes_and_never_exceeds_static_friction() {
        let mut site = NeedleSite::new(NeedleTissue::bovine_liver());
        insert(&mut site, 0.01, 0.025, 1e-4);
        let moving = site.step(0.025, 0.01, 1e-4).friction_n;
        let mut held = moving;
        for _ in 0..15_000 {
            held = site.step(0.025, 0.0, 1e-4).friction_n;
        }
        // 1.5 s at τ = 1.5 s: e^-1 of the static-limited value.
        let limit = 0.025 * site.tissue().coulomb_npm;
        assert!(
            held < limit && (held - limit * (-1.0f64).exp()).abs() < 1e-3,
            "{moving} {held}"
        );
    }
}
