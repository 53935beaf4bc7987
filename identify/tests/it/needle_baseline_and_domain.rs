//! The needle's physical baseline, and the warning that a test capture leaves the training
//! domain.

#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use std::path::{Path, PathBuf};

use capture::{Capture, CaptureKind, kind};
use identify::{CoulombViscousStiffness, IdentifyOptions, ModelKind, identify, out_of_domain};

fn li_bi(name: &str) -> PathBuf {
    PathBuf::from(format!(
        "{}/../assets/captures/li_bi/{name}.csv",
        env!("CARGO_MANIFEST_DIR")
    ))
}

fn needle(path: &Path) -> Capture {
    Capture::read_file(path, CaptureKind::Insertion).unwrap()
}

/// The needle test capture played `factor` times faster: time divided by it, velocities and
/// the sample rate multiplied by it; depths and forces unchanged.
fn faster(dir: &Path, factor: f64) -> PathBuf {
    let text = std::fs::read_to_string(li_bi("needle_test")).unwrap();
    let mut lines = text.lines();
    let meta = lines
        .next()
        .unwrap()
        .replace("rate_hz=100 ", &format!("rate_hz={} ", 100.0 * factor));
    let header = lines.next().unwrap();
    let columns: Vec<&str> = header.split(',').collect();
    let mut out = format!("{meta}\n{header}\n");
    for line in lines {
        let fields: Vec<String> = line
            .split(',')
            .zip(&columns)
            .map(|(f, &c)| {
                let v: f64 = f.parse().unwrap();
                match c {
                    kind::TIME_S => (v / factor).to_string(),
                    kind::VELOCITY_MPS | kind::COMMANDED_VELOCITY_MPS => (v * factor).to_string(),
                    _ => f.to_owned(),
                }
            })
            .collect();
        out.push_str(&fields.join(","));
        out.push('\n');
    }
    let path = dir.join("needle_fast.csv");
    std::fs::write(&path, out).unwrap();
    path
}

#[test]
fn the_needle_law_recovers_its_coefficients_from_noiseless_data() {
    let (fc, c, k): (f64, f64, f64) = (0.12, 35.0, 41.5);
    // Insertions at three speeds, holds and a withdrawal, so that sgn(v), v and depth vary
    // independently.
    let mut depth = Vec::new();
    let mut velocity: Vec<f64> = Vec::new();
    for (i, v) in [0.001, 0.0025, 0.01, 0.0, -0.005].into_iter().enumerate() {
        for j in 0..40 {
            depth.push(0.001 * (i + 1) as f64 + 0.0005 * j as f64);
            velocity.push(v);
        }
    }
    let force: Vec<f64> = depth
        .iter()
        .zip(&velocity)
        .map(|(&d, &v)| {
            let sgn = if v > 0.0 {
                1.0
            } else if v < 0.0 {
                -1.0
            } else {
                0.0
            };
            fc * sgn + c * v + k * d
        })
        .collect();
    let law = CoulombViscousStiffness::fit(&depth, &velocity, &force).unwrap();
    assert!((law.coulomb_n - fc).abs() < 1e-9, "{law:?}");
    assert!((law.viscous_nspm - c).abs() < 1e-6, "{law:?}");
    assert!((law.stiffness_npm - k).abs() < 1e-8, "{law:?}");
    for (i, &f) in force.iter().enumerate() {
        assert!((law.predict(depth[i], velocity[i]) - f).abs() < 1e-10);
    }
}

#[test]
fn the_needle_law_is_refused_without_independent_regressors() {
    // One speed: sgn(v) and v are proportional, so Fc and c cannot be told apart.
    let depth: Vec<f64> = (0..20).map(|i| 0.001 * f64::from(i)).collect();
    let velocity = vec![0.005; 20];
    let force: Vec<f64> = depth.iter().map(|d| 40.0 * d).collect();
    assert!(CoulombViscousStiffness::fit(&depth, &velocity, &force).is_err());
}

#[test]
fn the_needle_report_has_the_physical_baseline_and_no_friction_law() {
    let (train, test) = (needle(&li_bi("needle_train")), needle(&li_bi("needle_test")));
    let r = identify(
        &train,
        Some(&test),
        &IdentifyOptions::new(ModelKind::NeedlePuncture),
    )
    .unwrap()
    .report;
    assert!(r.metrics.coulomb_viscous.is_none());
    let law = r.metrics.coulomb_viscous_stiffness.unwrap();
    assert_eq!(law.n, r.metrics.svr.n);
    // A linear law has no puncture: the SVR beats it.
    assert!(
        r.metrics.svr.aise < law.aise,
        "{} {}",
        r.metrics.svr.aise,
        law.aise
    );
    // The held-out capture comes from the same protocol: inside the training domain.
    assert!(r.test_out_of_domain.is_empty(), "{:?}", r.test_out_of_domain);
}

#[test]
fn a_faster_test_capture_is_out_of_the_velocity_domain() {
    let dir = tempfile::tempdir().unwrap();
    let (train, fast) = (needle(&li_bi("needle_train")), needle(&faster(dir.path(), 3.0)));
    let identified = identify(
        &train,
        Some(&fast),
        &IdentifyOptions::new(ModelKind::NeedlePuncture),
    )
    .unwrap();
    let found = &identified.report.test_out_of_domain;
    assert_eq!(found.len(), 1, "{found:?}");
    let o = &found[0];
    assert_eq!(o.input, kind::VELOCITY_MPS);
    assert_eq!(o.range, identified.model.input_range[1]);
    assert!(o.fraction > 0.1 && o.fraction <= 1.0, "{o:?}");
    assert!(o.max > 2.0 * o.range[1] && o.min < 2.0 * o.range[0], "{o:?}");
    // The same computation from the model and the capture alone.
    assert_eq!(&out_of_domain(&identified.model, &fast).unwrap(), found);
    // Without a test capture there is nothing to report.
    let alone = identify(&train, None, &IdentifyOptions::new(ModelKind::NeedlePuncture)).unwrap();
    assert!(alone.report.test_out_of_domain.is_empty());
}
