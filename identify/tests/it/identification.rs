//! Li & Bi's identifications on the committed capture set, evaluated on held-out captures.

#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use capture::{Capture, CaptureErrorKind, CaptureKind};
use identify::{Identified, IdentifyError, IdentifyOptions, ModelFile, ModelKind, identify};

fn capture(name: &str, kind: CaptureKind) -> Capture {
    Capture::read_file(
        format!(
            "{}/../assets/captures/li_bi/{name}.csv",
            env!("CARGO_MANIFEST_DIR")
        ),
        kind,
    )
    .unwrap()
}

/// Identifies `model` on the set's training capture and evaluates it on its test capture.
fn identify_held_out(set: &str, kind: CaptureKind, model: ModelKind) -> Identified {
    let (train, test) = (
        capture(&format!("{set}_train"), kind),
        capture(&format!("{set}_test"), kind),
    );
    identify(&train, Some(&test), &IdentifyOptions::new(model)).unwrap()
}

#[test]
fn soft_contact_svr_beats_both_baselines_on_held_out_data() {
    let r = identify_held_out("soft_contact", CaptureKind::Rubbing, ModelKind::SoftFriction).report;
    let (svr, cv, net) = (
        r.metrics.svr.aise,
        r.metrics.coulomb_viscous.unwrap().aise,
        r.metrics.rbf_network.unwrap().aise,
    );
    println!("soft AISE: SVR {svr:.3e}, Coulomb+viscous {cv:.3e}, RBF network {net:.3e}");
    assert!(svr < cv && svr < net, "{svr} {cv} {net}");
    assert_eq!(r.stage1.len(), 9);
    // Stage 1 recovers the truth's slope dip and rise (sponge law: 0.65 at rest, ~0.59 at
    // 4-6 mm/s, ~0.79 at 40 mm/s).
    let w: Vec<f64> = r.stage1.iter().map(|s| s[1]).collect();
    assert!(w[1] < w[0] && w[8] > w[1] + 0.15, "{w:?}");
}

#[test]
fn needle_svr_beats_the_rbf_network_on_held_out_data() {
    let identified = identify_held_out("needle", CaptureKind::Insertion, ModelKind::NeedlePuncture);
    let r = &identified.report;
    println!(
        "needle AISE: SVR {:.3e}, RBF network {:.3e}; {} SVs / {}",
        r.metrics.svr.aise,
        r.metrics.rbf_network.unwrap().aise,
        r.n_sv,
        r.n_train
    );
    assert_eq!(r.n_train, 350);
    assert!(r.metrics.coulomb_viscous.is_none());
    assert!(r.metrics.svr.aise < r.metrics.rbf_network.unwrap().aise);
    assert!(r.relative_gap < 1e-6);
    // The model reproduces the puncture: near the capsule the force is high, just past it low.
    let m = &identified.model;
    assert!(
        m.predict(&[0.0115, 0.005]) > 1.0,
        "{}",
        m.predict(&[0.0115, 0.005])
    );
    assert!(
        m.predict(&[0.0160, 0.005]) < 0.8,
        "{}",
        m.predict(&[0.0160, 0.005])
    );
}

#[test]
fn hard_contact_recovers_the_paper_law_and_model_files_round_trip() {
    let identified = identify_held_out("hard_contact", CaptureKind::Rubbing, ModelKind::HardFriction);
    let r = &identified.report;
    let (w, b_kgf) = (r.w.unwrap(), r.b_kgf.unwrap());
    assert!(
        (w - 0.1647).abs() < 0.005 && (b_kgf - 0.0033).abs() < 0.003,
        "w {w} b {b_kgf}"
    );
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("hard.json");
    identified.model.save(&path).unwrap();
    let loaded = ModelFile::load(&path).unwrap();
    assert_eq!(loaded, identified.model);
    for p in [1.0, 5.0, 14.0] {
        assert_eq!(loaded.predict(&[p]), w * p + r.b.unwrap());
    }
    assert_eq!(loaded.training[0].sha256.len(), 64);
    // Bad files are typed errors naming the field.
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::write(&path, text.replace("\"version\": 1", "\"version\": 9")).unwrap();
    match ModelFile::load(&path) {
        Err(IdentifyError::Capture(e)) => match e.kind {
            CaptureErrorKind::Invalid { field, .. } => assert_eq!(field, "version"),
            other => panic!("{other:?}"),
        },
        other => panic!("{other:?}"),
    }
    std::fs::write(&path, &text[..text.len() / 2]).unwrap();
    assert!(matches!(
        ModelFile::load(&path),
        Err(IdentifyError::Capture(e)) if matches!(e.kind, CaptureErrorKind::Json(_))
    ));
    let mut broken = identified.model.clone();
    broken.inputs.push(broken.inputs[0].clone());
    assert_eq!(broken.validate().unwrap_err().0, "inputs");
}

#[test]
fn wrong_capture_kind_is_a_clear_error() {
    let needle = capture("needle_train", CaptureKind::Insertion);
    let err = identify(&needle, None, &IdentifyOptions::new(ModelKind::SoftFriction)).unwrap_err();
    assert!(err.to_string().contains("rubbing capture"), "{err}");
}
