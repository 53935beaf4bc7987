//! Admittance rendering on the simulated Omega.7: passivity of the defaults, and the needle
//! force-depth curve the operator's hand feels against the truth.

#![allow(clippy::unwrap_used)]

use crate::common::run_unpaced;
use glam::DVec3;
use haptics::{Admittance, AdmittanceConfig};
use haptics::{
    Environment, FreeSpace, NeedleEnvironment, NeedleLaw, NeedleLawConfig, NeedleQuasiStatic, ScalarModel,
};
use haptics::{SimOmega7, SimOmega7Config, SimTrace, SimWorld};
use sim::{HandImpedance, Waypoints};
use sim::{NeedleSite, NeedleTissue};

const SURFACE_Z_M: f64 = -0.02;

/// Runs `environment` through admittance control with a hand following `path`; returns the
/// physics trace.
fn render<E: Environment>(
    environment: E,
    config: AdmittanceConfig,
    hand: HandImpedance,
    path: Waypoints,
    seconds: f64,
) -> Vec<SimTrace> {
    let ticks = (seconds * 1000.0) as u64;
    let start = path.clone().target_at(0.0);
    let mut device = SimOmega7::new(
        SimOmega7Config {
            start_m: start,
            ..SimOmega7Config::default()
        },
        SimWorld::Free,
    )
    .with_hand(hand, Box::new(path))
    .with_trace(ticks as usize);
    let mut controller = Admittance::new(environment, config);
    run_unpaced(&mut device, &mut controller, ticks);
    device.trace().to_vec()
}

trait TargetAt {
    fn target_at(self, t: f64) -> DVec3;
}

impl TargetAt for Waypoints {
    fn target_at(mut self, t: f64) -> DVec3 {
        use sim::HandScript;
        self.target(t).position_m
    }
}

/// Energy in the hand's spring and the device's motion, J.
fn energy(t: &SimTrace, hand: HandImpedance) -> f64 {
    0.5 * 0.3 * t.velocity_mps.length_squared()
        + 0.5 * hand.stiffness_npm * (t.hand_target_m - t.position_m).length_squared()
}

fn window_max(trace: &[SimTrace], hand: HandImpedance, from_s: f64, to_s: f64) -> f64 {
    trace
        .iter()
        .filter(|t| t.time_s >= from_s && t.time_s < to_s)
        .map(|t| energy(t, hand))
        .fold(0.0, f64::max)
}

#[test]
fn defaults_are_passive_in_free_space_and_in_tissue() {
    let hand = HandImpedance::default();
    for (name, stiff_hand) in [
        ("light grip", hand),
        (
            "firm grip",
            HandImpedance {
                stiffness_npm: 800.0,
                damping_nspm: 6.0,
            },
        ),
    ] {
        // A flick: the hand jumps 5 mm sideways and down, then holds still.
        let top = DVec3::new(0.0, 0.0, SURFACE_Z_M + 0.003);
        let path = Waypoints::new(&[
            (0.0, top),
            (0.2, top),
            (0.21, top + DVec3::new(0.005, 0.0, -0.005)),
        ]);
        let free = render(FreeSpace, AdmittanceConfig::default(), stiff_hand, path, 3.0);
        // Pressing the capsule (no puncture) and holding.
        let law = NeedleLaw::new(
            NeedleQuasiStatic::new(NeedleTissue::bovine_liver()),
            NeedleLawConfig::default(),
        );
        let env = NeedleEnvironment::new(law, SURFACE_Z_M, [0.0, 0.0]);
        let press = Waypoints::new(&[
            (0.0, top),
            (0.2, top),
            (1.2, DVec3::new(0.0, 0.0, SURFACE_Z_M - 0.010)),
        ]);
        let tissue = render(env, AdmittanceConfig::default(), stiff_hand, press, 4.0);
        for (what, trace, hold_s) in [("free", &free, 0.25), ("tissue", &tissue, 1.25)] {
            let windows: Vec<f64> = (0..5)
                .map(|k| {
                    window_max(
                        trace,
                        stiff_hand,
                        hold_s + 0.3 * k as f64,
                        hold_s + 0.3 * (k + 1) as f64,
                    )
                })
                .collect();
            println!("{name} {what}: window energy maxima {windows:?}");
            for w in windows.windows(2) {
                assert!(
                    w[1] <= w[0] * 1.02 + 1e-7,
                    "{name} {what}: energy grew {windows:?}"
                );
            }
            let last = trace.last().unwrap();
            assert!(
                last.velocity_mps.length() < 2e-3,
                "{name} {what}: still moving {last:?}"
            );
        }
    }
}

/// Renders a needle law over `model` through admittance control on the simulator and
/// compares the force the hand feels with a fresh `NeedleSite` (the truth) stepped along the
/// very trajectory the device took. Returns (errors in tissue, errors while moving steadily,
/// peak felt, peak truth).
fn follow_truth<M: ScalarModel<2> + 'static>(model: M) -> (Errors, Errors, f64, f64) {
    let hand = HandImpedance::default();
    let top = DVec3::new(0.0, 0.0, SURFACE_Z_M + 0.002);
    let bottom = DVec3::new(0.0, 0.0, SURFACE_Z_M - 0.025);
    // 5 mm/s down to 25 mm, hold, 10 mm/s back up.
    let path = Waypoints::new(&[
        (0.0, top),
        (0.3, top),
        (0.3 + 0.027 / 0.005, bottom),
        (6.2, bottom),
        (6.2 + 0.027 / 0.01, top),
    ]);
    let law = NeedleLaw::new(model, NeedleLawConfig::default());
    let trace = render(
        NeedleEnvironment::new(law, SURFACE_Z_M, [0.0, 0.0]),
        AdmittanceConfig::default(),
        hand,
        path,
        9.5,
    );
    let mut site = NeedleSite::new(NeedleTissue::bovine_liver());
    let mut all = Errors::default();
    let mut steady = Errors::default();
    let (mut peak_truth, mut peak_felt) = (0.0f64, 0.0f64);
    let mut previous_depth = -0.002;
    let mut last_puncture_s = f64::NEG_INFINITY;
    for t in &trace {
        let depth = SURFACE_Z_M - t.position_m.z;
        let punctured = site.punctured();
        let truth = site
            .step(depth, (depth - previous_depth) / 1e-3, 1e-3)
            .axial_force_n;
        if site.punctured() > punctured {
            last_puncture_s = t.time_s;
        }
        previous_depth = depth;
        // The hand pushes down (−z) on the device: the felt force is minus its z component.
        let felt = -t.hand_force_n.z;
        if depth <= 0.0 {
            continue;
        }
        all.add(felt - truth);
        peak_truth = peak_truth.max(truth);
        peak_felt = peak_felt.max(felt);
        // Moving steadily: not within 0.3 s after a puncture (the device surges through the
        // cavity and the hand catches it), not while held (the truth's friction relaxes with
        // time, which no function of depth and velocity has).
        let held = (5.7..6.6).contains(&t.time_s);
        if !held && t.time_s - last_puncture_s > 0.3 {
            steady.add(felt - truth);
        }
    }
    (all, steady, peak_felt, peak_truth)
}

#[allow(clippy::print_stdout)] // The figures this test measures are part of its output.
fn report(what: &str, (all, steady, peak_felt, peak_truth): &(Errors, Errors, f64, f64)) {
    println!(
        "{what} via admittance: RMS error {:.4} N over {} samples in tissue (worst {:.3} N); \
         {:.4} N while moving steadily ({} samples); peak felt {peak_felt:.3} N vs truth {peak_truth:.3} N",
        all.rms(),
        all.n,
        all.worst,
        steady.rms(),
        steady.n
    );
}

/// The rendering chain with the closed-form truth model: what admittance control itself costs.
#[test]
fn rendered_needle_force_follows_the_truth_along_the_same_path() {
    let r = follow_truth(NeedleQuasiStatic::new(NeedleTissue::bovine_liver()));
    report("truth model", &r);
    let (all, steady, peak_felt, peak_truth) = r;
    assert!(steady.rms() < 0.07, "{}", steady.rms());
    assert!(all.rms() < 0.25, "{}", all.rms());
    assert!(
        (peak_felt - peak_truth).abs() < 0.1,
        "{peak_felt} vs {peak_truth}"
    );
}

/// The Done-when check: the needle model identified from the committed simulated captures,
/// rendered through admittance control on the simulator, reproduces the truth's force-depth
/// curve.
#[test]
fn identified_needle_model_rendered_follows_the_truth() {
    use capture::{Capture, CaptureKind};
    use identify::ModelKind;
    use identify::{IdentifyOptions, identify};
    let captures = concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/captures/li_bi");
    let train = Capture::read_file(format!("{captures}/needle_train.csv"), CaptureKind::Insertion).unwrap();
    let identified = identify(&train, None, &IdentifyOptions::new(ModelKind::NeedlePuncture)).unwrap();
    let model = haptics::needle_model(&identified.model).unwrap();
    let r = follow_truth(model);
    report("identified SVR", &r);
    let (all, steady, peak_felt, peak_truth) = r;
    // Measured with the default model (C = 100, γ = 30, 350 samples): 0.114 N in tissue,
    // 0.070 N moving steadily. The RBF surface smooths the rupture, so the felt peak falls
    // short of the truth's (1.20 N against 1.56 N): a kernel narrow enough to keep it overfits
    // the held-out capture.
    assert!(steady.rms() < 0.1, "{}", steady.rms());
    assert!(all.rms() < 0.15, "{}", all.rms());
    assert!(
        peak_felt > 0.7 * peak_truth && peak_felt < peak_truth + 0.1,
        "{peak_felt} vs {peak_truth}"
    );
}

#[derive(Default)]
struct Errors {
    sum2: f64,
    n: usize,
    worst: f64,
}

impl Errors {
    fn add(&mut self, e: f64) {
        self.sum2 += e * e;
        self.n += 1;
        self.worst = self.worst.max(e.abs());
    }

    fn rms(&self) -> f64 {
        (self.sum2 / self.n.max(1) as f64).sqrt()
    }
}
