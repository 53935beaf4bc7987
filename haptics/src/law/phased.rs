//! The phase-aware needle model ([`identify::PhaseModel`]) on the haptic thread.
//!
//! The model carries its own state machine (layers punctured, the channel cut so far), the
//! same code the identification scores it with, so what a trainee feels is what the report
//! measured. This law only maps its phases onto [`PunctureState`] for recording and the
//! overlay, and its domain checks onto the safety flags: a tick outside the depths and
//! velocities a phase was fitted on is rendered by the phase's bounded fallback (velocity held
//! to the trained range) and flagged [`flag::MODEL_INPUT_CLAMPED`], so the run counts it.

use identify::{ModelBody, ModelFile, ModelKind, Phase, PhaseModel, PhaseState};

use super::needle::{AxialLaw, NeedleLawConfig, NeedleOutput, PunctureState};
use crate::error::HapticsError;
use crate::safety::flag;

/// The phase-aware needle law.
#[derive(Debug, Clone)]
pub struct PhasedNeedleLaw {
    model: PhaseModel,
    config: NeedleLawConfig,
    state: PhaseState,
    /// Depth of the latest rupture while the tip is still within the puncture's travel.
    rupture_depth_m: Option<f64>,
    last: PunctureState,
}

impl PhasedNeedleLaw {
    /// The law over a phase model; `config` gives the puncture travel and nothing else (the
    /// model carries its own thresholds and hold band).
    pub fn new(model: PhaseModel, config: NeedleLawConfig) -> Self {
        Self {
            model,
            config,
            state: PhaseState::default(),
            rupture_depth_m: None,
            last: PunctureState::Approach,
        }
    }

    /// The law of a `needle-phases` model file.
    pub fn from_file(file: &ModelFile, config: NeedleLawConfig) -> Result<Self, HapticsError> {
        match (&file.body, file.kind) {
            (ModelBody::Phases(p), ModelKind::NeedlePhases) => Ok(Self::new((**p).clone(), config)),
            _ => Err(HapticsError::WrongModelKind {
                expected: ModelKind::NeedlePhases,
                found: file.kind,
            }),
        }
    }

    /// The model.
    pub fn model(&self) -> &PhaseModel {
        &self.model
    }

    /// Layers punctured in this insertion.
    pub fn punctured(&self) -> usize {
        self.state.punctured()
    }
}

impl AxialLaw for PhasedNeedleLaw {
    fn step(&mut self, depth_m: f64, velocity_mps: f64) -> NeedleOutput {
        let s = self.model.step(&mut self.state, depth_m, velocity_mps);
        if s.ruptured {
            self.rupture_depth_m = Some(depth_m);
        }
        let state = match s.phase {
            Phase::Air => {
                self.rupture_depth_m = None;
                PunctureState::Approach
            }
            Phase::Loading(_) => {
                self.rupture_depth_m = None;
                PunctureState::CapsuleLoading
            }
            Phase::Withdrawal => {
                self.rupture_depth_m = None;
                PunctureState::Withdrawal
            }
            Phase::Cutting(_) | Phase::Channel | Phase::Held => match self.rupture_depth_m {
                Some(at) if depth_m <= at + self.config.puncture_travel_m => PunctureState::Puncture,
                _ => {
                    self.rupture_depth_m = None;
                    if s.phase == Phase::Held && self.last == PunctureState::Withdrawal {
                        PunctureState::Withdrawal
                    } else {
                        PunctureState::Insertion
                    }
                }
            },
        };
        self.last = state;
        NeedleOutput {
            axial_force_n: s.force_n,
            state,
            flags: if s.out_of_domain {
                flag::MODEL_INPUT_CLAMPED
            } else {
                0
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use identify::{Domain, LayerModel, Loading, ShaftLaw, Threshold};

    fn law_of(d: [f64; 2], v: [f64; 2]) -> ShaftLaw {
        ShaftLaw {
            constant_n: 0.2,
            per_depth_npm: 10.0,
            per_speed_nspm: 5.0,
            per_depth_speed_nspm2: 0.0,
            domain: Domain {
                depth_m: d,
                velocity_mps: v,
            },
            svr: None,
        }
    }

    /// Two layers at 0 and 20 mm that give 10 mm and 3 mm below their contacts.
    fn model() -> PhaseModel {
        let layer = |contact: f64, deflection: f64, a1: f64, after: ShaftLaw| LayerModel {
            contact_depth_m: contact,
            loading: Loading {
                offset_n: 0.0,
                a1_npm: a1,
                a2_npm2: 0.0,
                damping_nspm: 0.0,
                domain: Domain {
                    depth_m: [contact, contact + deflection],
                    velocity_mps: [0.001, 0.01],
                },
            },
            threshold: Threshold {
                coefficients: vec![deflection],
                speed_mps: [0.001, 0.01],
                rms_m: 0.0,
            },
            after,
            events: 5,
            peak_force_n: a1 * deflection,
        };
        PhaseModel {
            layers: vec![
                layer(0.0, 0.010, 150.0, law_of([0.01, 0.02], [0.001, 0.01])),
                layer(0.020, 0.003, 200.0, law_of([0.023, 0.03], [0.001, 0.01])),
            ],
            withdrawal: ShaftLaw {
                constant_n: 0.0,
                per_depth_npm: -8.0,
                per_speed_nspm: 5.0,
                per_depth_speed_nspm2: 0.0,
                domain: Domain {
                    depth_m: [0.0, 0.03],
                    velocity_mps: [-0.01, -0.001],
                },
                svr: None,
            },
            withdrawal_source: identify::WithdrawalSource::Measured,
            above: None,
            hold_band_mps: 2e-4,
        }
    }

    #[test]
    fn both_layers_give_within_one_tick_and_stay_punctured_until_the_tool_leaves() {
        let mut law = PhasedNeedleLaw::new(model(), NeedleLawConfig::default());
        let (v, dt) = (0.005, 1e-3);
        let mut d = -0.001;
        let mut trace = Vec::new();
        while d < 0.028 {
            d += v * dt;
            trace.push((d, law.step(d, v)));
        }
        let ruptures: Vec<usize> = (1..trace.len())
            .filter(|&i| {
                trace[i].1.state == PunctureState::Puncture && trace[i - 1].1.state != PunctureState::Puncture
            })
            .collect();
        assert_eq!(ruptures.len(), 2, "{ruptures:?}");
        for (&i, (at, peak)) in ruptures
            .iter()
            .zip([(0.010, 1.5), (0.023, 0.2 + 10.0 * 0.023 + 5.0 * 0.005 + 0.6)])
        {
            let (before, after) = (trace[i - 1], trace[i]);
            // Where the threshold says, the peak the loading gives, and the drop in one tick.
            assert!((after.0 - at).abs() <= v * dt + 1e-12, "{} vs {at}", after.0);
            assert!(
                before.1.axial_force_n > after.1.axial_force_n + 0.3,
                "{before:?} {after:?}"
            );
            assert!(
                (before.1.axial_force_n - peak).abs() < 0.05,
                "{} vs {peak}",
                before.1.axial_force_n
            );
        }
        assert_eq!(law.punctured(), 2);
        // Back above the vessel wall and in again: no third puncture, friction only.
        let mut again = Vec::new();
        for k in 0..2000 {
            let d = 0.028 - 0.000_005 * k as f64;
            again.push(law.step(d, -0.005).state);
        }
        for k in 0..2000 {
            let d = 0.018 + 0.000_005 * k as f64;
            again.push(law.step(d, 0.005).state);
        }
        assert!(!again.contains(&PunctureState::Puncture));
        assert!(!again.contains(&PunctureState::CapsuleLoading));
        assert_eq!(law.punctured(), 2);
        // Out of the tissue: a fresh site.
        assert_eq!(law.step(-0.001, -0.005).state, PunctureState::Approach);
        assert_eq!(law.punctured(), 0);
    }

    #[test]
    fn a_needle_trembling_at_rest_keeps_its_friction_and_a_real_reversal_flips_it() {
        let mut law = PhasedNeedleLaw::new(model(), NeedleLawConfig::default());
        let mut d = 0.0;
        while d < 0.015 {
            d += 5e-6;
            law.step(d, 0.005);
        }
        let moving = law.step(d, 0.005).axial_force_n;
        // ±1 mm/s around rest, as a hand under admittance control trembles: the force never
        // reaches the withdrawal friction a hard reversal would flip to every other tick.
        let trembling: Vec<f64> = (0..200)
            .map(|k| law.step(d, if k % 2 == 0 { 0.001 } else { -0.001 }).axial_force_n)
            .collect();
        let (lo, hi) = trembling
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &f| {
                (a.min(f), b.max(f))
            });
        let (pulling, _) = law.model().withdrawal.eval(d, -0.001);
        assert!(pulling < 0.0);
        assert!(
            lo > pulling / 2.0 && hi <= moving + 1e-12,
            "{lo} {hi}: moving {moving}, withdrawal {pulling}"
        );
        // At rest the shaft keeps most of the channel's friction (static friction holds it).
        let (channel, _) = law.model().withdrawal.eval(d, -0.005);
        let rest = law.step(d, 0.0).axial_force_n;
        assert!(rest > -0.5 * channel, "{rest} vs {}", -channel);
        // Pulling out for real: withdrawal friction, which pulls the needle in.
        let out = law.step(d - 1e-4, -0.005);
        assert_eq!(out.state, PunctureState::Withdrawal);
        assert!(out.axial_force_n < 0.0, "{out:?}");
    }

    #[test]
    fn a_surge_beyond_the_trained_speeds_is_bounded_and_flagged() {
        let mut law = PhasedNeedleLaw::new(model(), NeedleLawConfig::default());
        let mut d = 0.0;
        while law.punctured() == 0 {
            d += 5e-6;
            law.step(d, 0.005);
        }
        let slow = law.step(d + 1e-3, 0.01);
        let fast = law.step(d + 2e-3, 1.0);
        assert_eq!(slow.flags, 0);
        assert_eq!(fast.flags, flag::MODEL_INPUT_CLAMPED);
        // The viscous term stops at the fastest trained speed.
        assert!(
            fast.axial_force_n < slow.axial_force_n + 0.05,
            "{slow:?} {fast:?}"
        );
        for (d, v) in [(f64::NAN, 0.01), (0.01, f64::INFINITY), (f64::INFINITY, f64::NAN)] {
            assert!(law.step(d, v).axial_force_n.is_finite());
        }
    }
}
