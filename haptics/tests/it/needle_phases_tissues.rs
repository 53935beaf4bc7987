//! The phase-aware needle model on tissues and strokes it was not tuned on: a second tissue
//! with three layers at other depths and other parameters, and held-out strokes whose speed
//! varies within the stroke, generated here from the simulated world.
#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use capture::Capture;
use identify::{IdentifyOptions, ModelBody, ModelKind, identify};
use sim::Split;
use sim::li_bi::{NeedleProtocol, NeedleTissueKind, SpeedProfile, needle_insertion_with};

fn insertion(seed: u64, split: Split, tissue: NeedleTissueKind, speed: SpeedProfile) -> Capture {
    needle_insertion_with(
        seed,
        split,
        NeedleProtocol {
            tissue,
            speed,
            ..NeedleProtocol::default()
        },
    )
    .unwrap()
}

/// The rupture depths the simulated tissue had in insertion `k` (from the capture's metadata).
fn truth_punctures(c: &Capture, k: usize) -> Vec<f64> {
    c.metadata()
        .get(&format!("truth.insertion.{k}.puncture_depths_m"))
        .unwrap()
        .split(';')
        .map(|d| d.parse().unwrap())
        .collect()
}

/// Identifies the phases on `train`, scores them on `test` and checks that the model ruptures
/// where the tissue did in every held-out stroke (within 1 mm), that every puncture the
/// detector measured is rendered within 10 % of its peak, and that the phases beat every
/// baseline's held-out AISE. Returns the layers' contact depths.
fn held_out(train: &Capture, test: &Capture) -> Vec<f64> {
    let r = identify(train, Some(test), &IdentifyOptions::new(ModelKind::NeedlePhases)).unwrap();
    let m = &r.report.metrics;
    for (name, other) in [
        ("smooth SVR", m.smooth_svr.unwrap().aise),
        ("Okamura piecewise", m.okamura_piecewise.unwrap().aise),
        ("RBF network", m.rbf_network.unwrap().aise),
        ("Fc+c·v+k·d", m.coulomb_viscous_stiffness.unwrap().aise),
    ] {
        assert!(m.svr.aise < other, "phases {} vs {name} {other}", m.svr.aise);
    }
    let ModelBody::Phases(p) = &r.model.body else {
        panic!("not a phase model")
    };
    // Every rupture the tissue had: the model's own ruptures along the same stroke, within
    // 1 mm (independent of the detector).
    let depth = test.column("depth_m").unwrap();
    let velocity = test.column("velocity_mps").unwrap();
    let steps = p.simulate(depth, velocity);
    let mut model_ruptures: Vec<Vec<f64>> = Vec::new();
    for i in 0..steps.len() {
        if depth[i] > 0.0 && (i == 0 || depth[i - 1] <= 0.0) {
            model_ruptures.push(Vec::new());
        }
        if steps[i].ruptured {
            model_ruptures.last_mut().unwrap().push(depth[i]);
        }
    }
    let insertions: usize = test.metadata().get("insertions").unwrap().parse().unwrap();
    assert_eq!(model_ruptures.len(), insertions);
    let (mut measured, mut truths) = (0, 0);
    for (k, model_k) in model_ruptures.iter().enumerate() {
        let truth = truth_punctures(test, k);
        truths += truth.len();
        assert_eq!(
            model_k.len(),
            truth.len(),
            "insertion {k}: {model_k:?} vs {truth:?}"
        );
        for (m, t) in model_k.iter().zip(&truth) {
            assert!(
                (m - t).abs() < 1e-3,
                "insertion {k}: rupture at {m} vs the tissue's {t}"
            );
        }
        // The peaks, where the detector found the puncture in the noisy recording.
        for c in r.report.punctures.iter().filter(|c| c.stroke == k) {
            if !truth.iter().any(|t| (t - c.measured_depth_m).abs() < 1e-3) {
                // A drop the detector took for a puncture where the tissue had none.
                continue;
            }
            measured += 1;
            let depth = c.predicted_depth_m.unwrap_or(f64::NAN);
            let peak = c.predicted_peak_force_n.unwrap_or(f64::NAN);
            assert!((depth - c.measured_depth_m).abs() < 1e-3, "{c:?}");
            assert!((peak / c.measured_peak_force_n - 1.0).abs() < 0.10, "{c:?}");
        }
    }
    assert!(
        2 * measured >= truths,
        "{measured} of {truths} punctures measured"
    );
    p.layers.iter().map(|l| l.contact_depth_m).collect()
}

#[test]
fn a_second_tissue_with_three_layers_is_reproduced_on_held_out_strokes_of_varying_speed() {
    let train = insertion(
        1,
        Split::Train,
        NeedleTissueKind::LayeredPhantom,
        SpeedProfile::Constant,
    );
    let truth_depths: Vec<f64> = ["skin", "fascia", "deep_capsule"]
        .iter()
        .map(|m| {
            train
                .metadata()
                .get(&format!("truth.{m}.depth_m"))
                .unwrap()
                .parse()
                .unwrap()
        })
        .collect();
    for test in [
        insertion(
            2,
            Split::Test,
            NeedleTissueKind::LayeredPhantom,
            SpeedProfile::Constant,
        ),
        insertion(
            3,
            Split::Test,
            NeedleTissueKind::LayeredPhantom,
            SpeedProfile::Varying,
        ),
    ] {
        let contacts = held_out(&train, &test);
        assert_eq!(contacts.len(), 3, "{contacts:?}");
        for (c, t) in contacts.iter().zip(&truth_depths) {
            assert!((c - t).abs() < 1e-3, "contact {c} vs membrane {t}");
        }
    }
}

#[test]
fn the_liver_model_follows_strokes_whose_speed_varies() {
    let train = insertion(
        1,
        Split::Train,
        NeedleTissueKind::BovineLiver,
        SpeedProfile::Constant,
    );
    let test = insertion(
        4,
        Split::Test,
        NeedleTissueKind::BovineLiver,
        SpeedProfile::Varying,
    );
    assert_eq!(held_out(&train, &test).len(), 2);
}
