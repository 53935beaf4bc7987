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

/// Parameters of a layered tissue.
#[derive(Debug, Clone, PartialEq)]
pub struct NeedleTissue {
    /// Membranes ordered by depth; the first one is the tissue surface (depth 0).
    pub membranes: Vec<Membrane>,
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
            cutting_force_n: 0.35,
            cutting_damping_nspm: 15.0,
            coulomb_npm: 9.0,
            viscous_nspm2: 500.0,
            static_band_mps: 1e-4,
            relaxation_s: 1.0,
        }
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
        // membrane being pushed ahead of the tip.
        let pushing_membrane = force.stiffness_n > 0.0;
        if self.punctured > 0
            && velocity_mps > t.static_band_mps
            && depth_m > self.cut_depth_m
            && !pushing_membrane
        {
            force.cutting_n = t.cutting_force_n + t.cutting_damping_nspm * velocity_mps;
            self.cut_depth_m = depth_m;
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
