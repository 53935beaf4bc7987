//! The phase-aware needle model: identified from the committed captures, scored along the
//! held-out capture's strokes against the smooth models, and refused clearly where the data
//! cannot make it.

#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use std::path::PathBuf;

use capture::{Capture, CaptureKind};
use identify::{
    IdentifyError, IdentifyOptions, ModelBody, ModelFile, ModelKind, PhaseForm, PunctureParams, identify,
    identify_phases,
};

fn li_bi(name: &str) -> Capture {
    let path = PathBuf::from(format!(
        "{}/../assets/captures/li_bi/{name}.csv",
        env!("CARGO_MANIFEST_DIR")
    ));
    Capture::read_file(&path, CaptureKind::Insertion).unwrap()
}

/// A truth value from the capture's metadata (`truth.vessel_wall.depth_m`, …).
fn truth(c: &Capture, key: &str) -> f64 {
    c.metadata().get(key).unwrap().parse().unwrap()
}

#[test]
fn both_layers_are_found_and_every_held_out_puncture_is_reproduced() {
    let (train, test) = (li_bi("needle_train"), li_bi("needle_test"));
    let r = identify(
        &train,
        Some(&test),
        &IdentifyOptions::new(ModelKind::NeedlePhases),
    )
    .unwrap();
    let ModelBody::Phases(p) = &r.model.body else {
        panic!("not a phase model")
    };
    // Two layers, each meeting its membrane within a millimetre of where the tissue has it.
    assert_eq!(p.layers.len(), 2, "{p:?}");
    for (layer, name) in p.layers.iter().zip(["capsule", "vessel_wall"]) {
        let at = truth(&train, &format!("truth.{name}.depth_m"));
        assert!((layer.contact_depth_m - at).abs() < 1e-3, "{name}: {layer:?}");
    }
    // The phases beat the smooth SVR, the RBF network and F = Fc·sgn(v) + c·v + k·d on the
    // held-out capture.
    let m = &r.report.metrics;
    let phases = m.svr.aise;
    for (name, other) in [
        ("smooth SVR", m.smooth_svr.unwrap().aise),
        ("RBF network", m.rbf_network.unwrap().aise),
        ("Fc+c·v+k·d", m.coulomb_viscous_stiffness.unwrap().aise),
    ] {
        assert!(phases < other, "phases {phases} vs {name} {other}");
    }
    // Every measured puncture of the held-out strokes: rendered within 1 mm and 10 % of its
    // peak.
    assert_eq!(r.report.punctures.len(), 8, "{:?}", r.report.punctures);
    for c in &r.report.punctures {
        let depth = c.predicted_depth_m.unwrap_or(f64::NAN);
        let peak = c.predicted_peak_force_n.unwrap_or(f64::NAN);
        assert!((depth - c.measured_depth_m).abs() < 1e-3, "{c:?}");
        assert!((peak / c.measured_peak_force_n - 1.0).abs() < 0.10, "{c:?}");
    }
    // The baselines' punctures on the same strokes: neither reproduces as many within 1 mm
    // and 10 % of the peak.
    let within = |list: &[identify::PunctureComparison]| {
        list.iter()
            .filter(|c| {
                c.predicted_depth_m
                    .is_some_and(|d| (d - c.measured_depth_m).abs() < 1e-3)
                    && c.predicted_peak_force_n
                        .is_some_and(|f| (f / c.measured_peak_force_n - 1.0).abs() < 0.10)
            })
            .count()
    };
    let names: Vec<&str> = r
        .report
        .baseline_punctures
        .iter()
        .map(|b| b.model.as_str())
        .collect();
    assert_eq!(names, ["okamura_piecewise", "smooth_svr"]);
    for b in &r.report.baseline_punctures {
        assert_eq!(b.punctures.len(), 8, "{}", b.model);
        assert!(within(&b.punctures) < within(&r.report.punctures), "{}", b.model);
    }
    // Written and read back unchanged; a hand-edited threshold is refused with its field.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("phases.json");
    r.model.save(&path).unwrap();
    assert_eq!(ModelFile::load(&path).unwrap(), r.model);
    let text = std::fs::read_to_string(&path).unwrap();
    let broken = text.replacen("\"coefficients\": [", "\"coefficients\": [1e400, ", 1);
    let e = ModelFile::from_slice(broken.as_bytes(), &path);
    assert!(e.is_err(), "a non-finite threshold was accepted");
    let mut no_layers = r.model.clone();
    if let ModelBody::Phases(p) = &mut no_layers.body {
        p.layers.clear();
    }
    let (field, _) = no_layers.validate().unwrap_err();
    assert_eq!(field, "body.layers");
}

#[test]
fn a_capture_without_a_puncture_is_refused_with_the_reason() {
    // A steady insertion into tissue that never gives: friction growing with depth.
    let n = 3000;
    let time: Vec<f64> = (0..n).map(|i| i as f64 * 0.01).collect();
    let depth: Vec<f64> = time.iter().map(|t| 0.001 * t - 0.001).collect();
    let velocity = vec![0.001; n];
    let force: Vec<f64> = depth.iter().map(|d| 10.0 * d.max(0.0)).collect();
    let e = identify_phases(
        PhaseForm::Full,
        std::path::Path::new("steady.csv"),
        &time,
        &depth,
        &velocity,
        &force,
        &PunctureParams::default(),
    )
    .unwrap_err();
    assert!(
        matches!(&e, IdentifyError::Data { reason, .. } if reason.contains("no puncture")),
        "{e}"
    );
    assert!(e.to_string().contains("steady.csv"), "{e}");
}

#[test]
fn the_state_machine_is_the_same_along_any_prefix_of_a_trajectory() {
    // What the haptic thread feels at each tick depends only on the ticks before it.
    let train = li_bi("needle_train");
    let r = identify(&train, None, &IdentifyOptions::new(ModelKind::NeedlePhases)).unwrap();
    let ModelBody::Phases(p) = &r.model.body else {
        panic!("not a phase model")
    };
    let d = train.column("depth_m").unwrap();
    let v = train.column("velocity_mps").unwrap();
    let whole = p.simulate(d, v);
    let half = p.simulate(&d[..d.len() / 2], &v[..v.len() / 2]);
    assert_eq!(&whole[..half.len()], &half[..]);
    assert!(whole.iter().all(|s| s.force_n.is_finite()));
}

#[test]
fn strokes_faster_than_any_trained_are_reported_per_phase() {
    let train = li_bi("needle_train");
    let r = identify(&train, None, &IdentifyOptions::new(ModelKind::NeedlePhases)).unwrap();
    let ModelBody::Phases(p) = &r.model.body else {
        panic!("not a phase model")
    };
    let d = train.column("depth_m").unwrap();
    let v = train.column("velocity_mps").unwrap();
    // Its own strokes: the advancing phases stay inside what they were fitted on.
    let own = p.domain_exits(d, v);
    assert!(
        own.iter()
            .all(|e| !e.phase.starts_with("cutting") && !e.phase.starts_with("loading")),
        "{own:?}"
    );
    // Three times as fast: every advancing phase is left, and each exit says how fast.
    let fast: Vec<f64> = v.iter().map(|x| 3.0 * x).collect();
    let exits = p.domain_exits(d, &fast);
    for phase in [
        "loading layer 1",
        "cutting below layer 1",
        "loading layer 2",
        "cutting below layer 2",
    ] {
        let e = exits
            .iter()
            .find(|e| e.phase == phase)
            .unwrap_or_else(|| panic!("{phase}: {exits:?}"));
        assert!(e.rows > 0 && e.fraction > 0.0 && e.fraction <= 1.0, "{e:?}");
        assert!(e.velocity_mps[1] > 0.011, "{e:?}");
    }
}

#[test]
fn every_part_is_scored_against_an_svr_on_held_out_strokes_and_renders_the_winner() {
    let r = identify(
        &li_bi("needle_train"),
        None,
        &IdentifyOptions::new(ModelKind::NeedlePhases),
    )
    .unwrap();
    let ModelBody::Phases(p) = &r.model.body else {
        panic!("not a phase model")
    };
    let names: Vec<&str> = r.report.parts.iter().map(|c| c.part.as_str()).collect();
    for part in [
        "loading layer 1",
        "cutting below layer 1",
        "loading layer 2",
        "cutting below layer 2",
        "withdrawal",
    ] {
        assert!(names.contains(&part), "{part} missing from {names:?}");
    }
    for c in &r.report.parts {
        assert_eq!(c.strokes, 5, "{c:?}");
        let (law, svr) = (c.parametric_rmse_n.unwrap(), c.svr_rmse_n.unwrap());
        assert!(law > 0.0 && svr > 0.0, "{c:?}");
        let rendered = match c.part.as_str() {
            "cutting below layer 1" => p.layers[0].after.svr.is_some(),
            "cutting below layer 2" => p.layers[1].after.svr.is_some(),
            "withdrawal" => p.withdrawal.svr.is_some(),
            // Loadings stay parametric whatever the score.
            _ => {
                assert_eq!(c.uses, "parametric", "{c:?}");
                continue;
            }
        };
        assert_eq!(rendered, c.uses == "svr", "{c:?}");
        assert_eq!(c.uses == "svr", svr < 0.9 * law, "{c:?}");
    }
    // Part SVRs stay within their support-vector budget.
    for s in p
        .layers
        .iter()
        .filter_map(|l| l.after.svr.as_ref())
        .chain(p.withdrawal.svr.as_ref())
    {
        assert!(s.svr.n_sv() <= 32, "{}", s.svr.n_sv());
    }
}
