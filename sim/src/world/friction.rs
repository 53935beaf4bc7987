//! Contact friction ground truth for the Li & Bi rig (hard and soft contact).
//!
//! Li & Bi measure "pressure" P (the normal force) and friction F with a 3-axis strain-gauge
//! sensor, in kilogram-force. Inside palpus everything is SI; the paper's units appear only in
//! the constants' names and in the capture metadata that records them.

/// Standard gravity: 1 kgf = 9.80665 N (exact, by definition).
pub const STANDARD_GRAVITY_MPS2: f64 = 9.806_65;

/// Converts kilogram-force to newtons.
pub fn kgf_to_n(force_kgf: f64) -> f64 {
    force_kgf * STANDARD_GRAVITY_MPS2
}

/// Hard contact (aluminium plate): friction linear in the normal force, independent of speed.
///
/// Li & Bi (2007), Eq. 12, identified on their rig: `F = 0.1647·P + 0.0033` with F and P in
/// kgf. The slope is dimensionless and survives the unit change; the intercept becomes
/// `0.0033 kgf = 0.032362 N`. The paper attributes that intercept to "the imperfect
/// measurement hardware", so it is kept as part of what the rig reports.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HardContact {
    /// dF/dP (dimensionless friction coefficient).
    pub slope: f64,
    /// Friction at zero normal force, in newtons.
    pub intercept_n: f64,
}

impl HardContact {
    /// Paper slope (Eq. 12).
    pub const PAPER_SLOPE: f64 = 0.1647;
    /// Paper intercept (Eq. 12), in kgf.
    pub const PAPER_INTERCEPT_KGF: f64 = 0.0033;

    /// The law identified by Li & Bi, in SI.
    pub fn li_bi() -> Self {
        Self {
            slope: Self::PAPER_SLOPE,
            intercept_n: kgf_to_n(Self::PAPER_INTERCEPT_KGF),
        }
    }

    /// Friction resisting the sliding, in newtons, for normal force `normal_force_n`.
    pub fn friction_n(&self, normal_force_n: f64) -> f64 {
        self.slope * normal_force_n + self.intercept_n
    }
}

/// Soft contact (sponge): at a constant sliding speed friction is linear in the normal force,
/// `F = w(v)·P + m(v)` (Li & Bi Sec. II-B-2: "if the deformation of the soft material is not
/// large, we can assume that the friction-pressure relation for a constant velocity is linear"),
/// but slope and intercept change nonlinearly with speed — which is why the paper identifies
/// (w, m) per speed and then fits w(v), m(v) with RBF SVR.
///
/// The paper publishes the fitted curves only as figures (Figs. 6–8), so the shapes here are
/// ours, chosen to have the paper's features: a friction coefficient of the order of their
/// Coulomb fit (0.7648) that first falls with speed (Stribeck weakening from the static value)
/// and then rises and saturates (viscoelastic hysteresis in the foam grows with rate), and an
/// adhesion intercept that saturates with speed:
///
/// `w(v) = w0 + w1·(1 − exp(−v/v1)) + w2·exp(−(v/v2)²)`,
/// `m(v) = m0 + m1·tanh(v/vm)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SoftContact {
    /// Slope at high speed minus the rise: base friction coefficient.
    pub w0: f64,
    /// Rise of the slope with speed.
    pub w1: f64,
    /// Speed scale of the rise (m/s).
    pub v1_mps: f64,
    /// Extra static friction that the Stribeck effect removes as sliding starts.
    pub w2: f64,
    /// Stribeck speed (m/s).
    pub v2_mps: f64,
    /// Intercept at zero speed (N).
    pub m0_n: f64,
    /// Rise of the intercept (N).
    pub m1_n: f64,
    /// Speed scale of the intercept's rise (m/s).
    pub vm_mps: f64,
}

impl SoftContact {
    /// The sponge of the default capture set.
    pub fn sponge() -> Self {
        Self {
            w0: 0.45,
            w1: 0.35,
            v1_mps: 0.012,
            w2: 0.2,
            v2_mps: 0.003,
            m0_n: 0.04,
            m1_n: 0.25,
            vm_mps: 0.015,
        }
    }

    /// Slope w(v) of friction against normal force at sliding speed `speed_mps` (≥ 0).
    pub fn slope(&self, speed_mps: f64) -> f64 {
        let v = speed_mps.abs();
        self.w0 + self.w1 * (1.0 - (-v / self.v1_mps).exp()) + self.w2 * (-(v / self.v2_mps).powi(2)).exp()
    }

    /// Intercept m(v), in newtons.
    pub fn intercept_n(&self, speed_mps: f64) -> f64 {
        self.m0_n + self.m1_n * (speed_mps.abs() / self.vm_mps).tanh()
    }

    /// Friction resisting the sliding, in newtons.
    pub fn friction_n(&self, speed_mps: f64, normal_force_n: f64) -> f64 {
        self.slope(speed_mps) * normal_force_n + self.intercept_n(speed_mps)
    }

    /// The parameters as `(name, value)` pairs for capture metadata.
    pub fn parameters(&self) -> [(&'static str, f64); 8] {
        [
            ("w0", self.w0),
            ("w1", self.w1),
            ("v1_mps", self.v1_mps),
            ("w2", self.w2),
            ("v2_mps", self.v2_mps),
            ("m0_n", self.m0_n),
            ("m1_n", self.m1_n),
            ("vm_mps", self.vm_mps),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hard_contact_is_the_paper_law_in_si() {
        let law = HardContact::li_bi();
        // At P = 1 kgf the paper predicts 0.1647 + 0.0033 = 0.168 kgf.
        let f_n = law.friction_n(kgf_to_n(1.0));
        assert!((f_n / STANDARD_GRAVITY_MPS2 - 0.168).abs() < 1e-12);
        assert!((law.intercept_n - 0.032_361_945).abs() < 1e-9);
    }

    #[test]
    fn soft_contact_is_linear_in_pressure_at_each_speed_but_not_in_speed() {
        let s = SoftContact::sponge();
        for v in [0.002, 0.01, 0.04] {
            let f1 = s.friction_n(v, 2.0);
            let f2 = s.friction_n(v, 4.0);
            let f3 = s.friction_n(v, 6.0);
            assert!(((f3 - f2) - (f2 - f1)).abs() < 1e-12);
        }
        // The slope falls at low speed, then rises and saturates: it is not monotonic and its
        // curvature changes sign, so no line in v (Coulomb + viscous) fits it.
        let w: Vec<f64> = [0.0, 0.004, 0.008, 0.02, 0.04, 0.08]
            .iter()
            .map(|&v| s.slope(v))
            .collect();
        assert!(w[1] < w[0] - 0.05, "{w:?}");
        assert!(w[2] > w[1] && w[3] > w[2] + 0.05, "{w:?}");
        assert!(w[5] - w[4] < w[4] - w[3], "{w:?}");
        assert!(s.slope(0.0) > 0.3 && s.slope(0.04) < 0.85);
        assert!(s.intercept_n(0.04) > s.intercept_n(0.0));
    }
}
