//! Closed-form models of the simulated world's ground truth, behind the same [`ScalarModel`]
//! interface as identified models: they check the force laws, and stand in for identified
//! models where none has been loaded.

use super::model::{FnModel, InputBox, ScalarModel};
use sim::NeedleTissue;
use sim::{HardContact, SoftContact};

/// The needle force of [`NeedleTissue`] for a steady insertion into a fresh site: at speed
/// `v > 0` and depth `d`, the force the needle meets when it got to `d` at constant `v`
/// (membranes deflect until they rupture at their rate-dependent puncture force, then cutting
/// and shaft friction); at `v < 0`, withdrawal friction with every membrane punctured; at
/// rest, the membrane's elastic force or nothing (held friction relaxes away). This is the
/// surface that identifying `f(depth, velocity)` from the needle captures aims at.
#[derive(Debug, Clone)]
pub struct NeedleQuasiStatic {
    tissue: NeedleTissue,
    input_box: InputBox<2>,
}

impl NeedleQuasiStatic {
    /// The model of `tissue`, with the training box of the Li & Bi needle protocol: depth
    /// 0–30 mm, velocity ±10 mm/s.
    pub fn new(tissue: NeedleTissue) -> Self {
        Self {
            tissue,
            input_box: InputBox {
                lo: [0.0, -0.010],
                hi: [0.030, 0.010],
            },
        }
    }

    /// The tissue.
    pub fn tissue(&self) -> &NeedleTissue {
        &self.tissue
    }

    /// Axial force at depth `d` (m) and velocity `v` (m/s), N.
    pub fn force_n(&self, d: f64, v: f64) -> f64 {
        let t = &self.tissue;
        if d <= 0.0 || !d.is_finite() || !v.is_finite() {
            return 0.0;
        }
        let moving = v.abs() > t.static_band_mps;
        let friction = |d: f64| {
            if moving {
                d * (t.coulomb_npm * v.signum() + t.viscous_nspm2 * v)
            } else {
                0.0
            }
        };
        if v < 0.0 {
            return friction(d);
        }
        let mut stiffness = 0.0;
        for (k, m) in t.membranes.iter().enumerate() {
            let u = d - m.depth_m;
            if u <= 0.0 {
                break;
            }
            if u < m.puncture_deflection_m(v) {
                stiffness = (m.elastic_force_n(u) + m.damping_nspm * v).max(0.0);
                if k == 0 {
                    // The capsule is intact: no shaft in tissue, nothing cut.
                    return stiffness;
                }
                break;
            }
        }
        let cutting = if moving && stiffness == 0.0 {
            t.cutting_force_n + t.cutting_damping_nspm * v
        } else {
            0.0
        };
        stiffness + cutting + friction(d)
    }
}

impl ScalarModel<2> for NeedleQuasiStatic {
    fn eval(&self, x: &[f64; 2]) -> f64 {
        self.force_n(x[0], x[1])
    }
    fn input_box(&self) -> InputBox<2> {
        self.input_box
    }
}

/// Hard contact friction `F(P) = slope·P + intercept` as a model of the normal force, on the
/// Li & Bi protocol's range 0–20 N.
pub fn hard_contact_model(law: HardContact) -> impl ScalarModel<1> + Clone {
    FnModel::new(
        InputBox {
            lo: [0.0],
            hi: [20.0],
        },
        move |x: &[f64; 1]| law.friction_n(x[0]),
    )
}

/// Soft contact's slope `w(v)` and intercept `m(v)` as models of the sliding speed, on the Li
/// & Bi protocol's speeds 2–40 mm/s.
pub fn soft_contact_models(law: SoftContact) -> (impl ScalarModel<1> + Clone, impl ScalarModel<1> + Clone) {
    let speeds = InputBox {
        lo: [0.002],
        hi: [0.040],
    };
    (
        FnModel::new(speeds, move |x: &[f64; 1]| law.slope(x[0])),
        FnModel::new(speeds, move |x: &[f64; 1]| law.intercept_n(x[0])),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use sim::NeedleSite;

    #[test]
    fn quasi_static_needle_matches_a_stepped_site_away_from_punctures() {
        let tissue = NeedleTissue::bovine_liver();
        let model = NeedleQuasiStatic::new(tissue.clone());
        for speed in [0.001, 0.005, 0.01] {
            let mut site = NeedleSite::new(tissue.clone());
            let dt = 1e-4;
            let mut d = -0.001;
            let mut worst: f64 = 0.0;
            while d < 0.03 {
                d += speed * dt;
                let truth = site.step(d, speed, dt).axial_force_n;
                let near_puncture =
                    (0..2).any(|k| (tissue.puncture_depth_m(k, speed).unwrap() - d).abs() < 2.0 * speed * dt);
                if !near_puncture {
                    worst = worst.max((model.force_n(d, speed) - truth).abs());
                }
            }
            assert!(worst < 1e-9, "{speed}: {worst}");
            // Withdrawal.
            let f = site.step(0.0299, -speed, dt).axial_force_n;
            assert!((model.force_n(0.0299, -speed) - f).abs() < 1e-12);
        }
    }

    #[test]
    fn friction_models_are_the_world_laws() {
        let hard = hard_contact_model(HardContact::li_bi());
        assert_eq!(hard.eval(&[3.0]), HardContact::li_bi().friction_n(3.0));
        let s = SoftContact::sponge();
        let (w, m) = soft_contact_models(s);
        assert_eq!(w.eval(&[0.01]) * 2.0 + m.eval(&[0.01]), s.friction_n(0.01, 2.0));
    }
}
