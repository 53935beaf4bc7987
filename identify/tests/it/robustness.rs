//! Identification on captures far from the paper's: absurd values, long captures, extreme
//! scales. Whatever it writes must load again; what it cannot fit is an error naming the
//! capture.

#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use capture::{Capture, CaptureKind};
use identify::{IdentifyError, IdentifyOptions, ModelFile, ModelKind, identify};

fn li_bi(name: &str) -> PathBuf {
    PathBuf::from(format!(
        "{}/../assets/captures/li_bi/{name}.csv",
        env!("CARGO_MANIFEST_DIR")
    ))
}

/// The capture at `src` with `edit(row index, fields)` applied to every data row, written to
/// `dst`.
fn edited(src: &Path, dst: &Path, mut edit: impl FnMut(usize, &mut Vec<String>)) {
    let text = std::fs::read_to_string(src).unwrap();
    let mut out = String::new();
    for (i, line) in text.lines().enumerate() {
        if i < 2 {
            out.push_str(line);
        } else {
            let mut fields: Vec<String> = line.split(',').map(str::to_owned).collect();
            edit(i - 2, &mut fields);
            out.push_str(&fields.join(","));
        }
        out.push('\n');
    }
    std::fs::write(dst, out).unwrap();
}

/// The hard-contact training capture with one friction force of 1e308.
fn hard_with_huge_force(dir: &Path) -> PathBuf {
    let path = dir.join("hard_huge.csv");
    edited(&li_bi("hard_contact_train"), &path, |i, f| {
        if i == 7 {
            let last = f.len() - 1;
            f[last] = "1e308".into();
        }
    });
    path
}

#[test]
fn a_force_too_large_to_square_is_refused_naming_the_capture() {
    let dir = tempfile::tempdir().unwrap();
    let huge = hard_with_huge_force(dir.path());
    // The reader may refuse the value itself, naming the file.
    if let Err(e) = Capture::read_file(&huge, CaptureKind::Rubbing) {
        assert!(e.to_string().contains("hard_huge.csv"), "{e}");
    }
    // Identification must not rely on that: the same capture built in memory.
    let good = Capture::read_file(li_bi("hard_contact_train"), CaptureKind::Rubbing).unwrap();
    let mut data: Vec<Vec<f64>> = good
        .columns()
        .iter()
        .map(|c| good.column(c).unwrap().to_vec())
        .collect();
    let last = data.len() - 1;
    data[last][7] = 1e308;
    let Ok(huge) = Capture::new(good.metadata().clone(), good.columns().to_vec(), data) else {
        return; // refused on construction too: nothing reaches a fit
    };
    let source = huge.source().display().to_string();
    let options = IdentifyOptions::new(ModelKind::HardFriction);
    let e = identify(&huge, None, &options).unwrap_err();
    assert!(e.to_string().contains(&source), "{e}");
    // A sane training capture evaluated on the absurd one: the metric names the test capture.
    let e = identify(&good, Some(&huge), &options).unwrap_err();
    assert!(
        matches!(&e, IdentifyError::NonFiniteMetric { path, .. } if path == huge.source()),
        "{e}"
    );
}

/// `rows` rows of the hard-contact law with a deterministic wobble, as a capture.
fn long_hard_capture(rows: usize) -> Capture {
    let header = std::fs::read_to_string(li_bi("hard_contact_train")).unwrap();
    let mut text: String = header.lines().take(2).map(|l| format!("{l}\n")).collect();
    for i in 0..rows {
        let p = 0.5 + 9.5 * ((i * 7919) % rows) as f64 / rows as f64;
        let noise = 0.01 * (((i * 104_729) % 13) as f64 - 6.0) / 6.0;
        let f = 0.1647 * p + 0.0324 + noise;
        writeln!(text, "{},{},0.01,{p},{f}", i as f64 * 0.2, i as f64 * 0.002).unwrap();
    }
    Capture::read_from(
        std::io::BufReader::new(text.as_bytes()),
        Path::new("long_hard.csv"),
        Some(CaptureKind::Rubbing),
    )
    .unwrap()
}

#[test]
fn a_long_capture_is_thinned_to_the_budget_deterministically() {
    let train = long_hard_capture(100_000);
    let options = IdentifyOptions {
        max_fit_samples: 150,
        ..IdentifyOptions::new(ModelKind::HardFriction)
    };
    let first = identify(&train, None, &options).unwrap();
    let r = &first.report;
    assert_eq!((r.n_rows, r.n_fit_rows, r.n_train), (100_000, 150, 150));
    // Metrics still cover every row.
    assert_eq!(first.model.train_metrics.unwrap().n, 100_000);
    assert!((r.w.unwrap() - 0.1647).abs() < 0.01, "{:?}", r.w);
    let again = identify(&train, None, &options).unwrap();
    assert_eq!(again.model.body, first.model.body);
}

#[test]
fn soft_contact_caps_every_segment() {
    // The generator's sponge law over 9 constant-speed segments of 400 rows each, with the
    // normal force sweeping 0.5–5 N and a deterministic ±0.015 N wobble.
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(li_bi("soft_contact_train")).unwrap();
    let mut out: String = text.lines().take(2).map(|l| format!("{l}\n")).collect();
    let speeds = [0.002, 0.004, 0.006, 0.009, 0.013, 0.018, 0.024, 0.032, 0.04];
    let w = |v: f64| 0.45 + 0.35 * (1.0 - (-v / 0.012).exp()) + 0.2 * (-(v / 0.003).powi(2)).exp();
    let m = |v: f64| 0.04 + 0.25 * (v / 0.015).tanh();
    let mut k = 0usize;
    let mut x = 0.0;
    for v in speeds {
        for j in 0..400 {
            let p = 2.75 + 2.25 * (std::f64::consts::TAU * j as f64 / 97.0).sin();
            let wobble = 0.015 * (((k * 7919) % 13) as f64 - 6.0) / 6.0;
            x += v * 0.05;
            let t = 0.5 + 0.05 * k as f64;
            writeln!(
                out,
                "{t:.3},{x:.6},{v},{v},{p:.5},{:.5}",
                w(v) * p + m(v) + wobble
            )
            .unwrap();
            k += 1;
        }
    }
    let path = dir.path().join("soft_long.csv");
    std::fs::write(&path, out).unwrap();
    let train = Capture::read_file(&path, CaptureKind::Rubbing).unwrap();
    let r = identify(&train, None, &IdentifyOptions::new(ModelKind::SoftFriction))
        .unwrap()
        .report;
    assert_eq!(r.n_rows, 3600);
    assert_eq!(r.n_fit_rows, 9 * identify::MAX_SEGMENT_SAMPLES);
    assert_eq!(r.stage1.len(), 9);
}

#[test]
fn models_identified_at_extreme_scales_load_again_or_are_refused_naming_the_capture() {
    let dir = tempfile::tempdir().unwrap();
    for (name, factor) in [("tiny", 1e-4), ("large", 1e2)] {
        let path = dir.path().join(format!("hard_{name}.csv"));
        edited(&li_bi("hard_contact_train"), &path, |_, f| {
            let last = f.len() - 1;
            let v: f64 = f[last].parse().unwrap();
            f[last] = format!("{}", v * factor);
        });
        let train = Capture::read_file(&path, CaptureKind::Rubbing).unwrap();
        for max_fit_samples in [2, 20_000] {
            let options = IdentifyOptions {
                max_fit_samples,
                ..IdentifyOptions::new(ModelKind::HardFriction)
            };
            match identify(&train, None, &options) {
                Ok(identified) => {
                    let out = dir.path().join(format!("{name}_{max_fit_samples}.json"));
                    identified.model.save(&out).unwrap();
                    assert_eq!(ModelFile::load(&out).unwrap(), identified.model);
                }
                Err(e) => assert!(e.to_string().contains(&format!("hard_{name}.csv")), "{e}"),
            }
        }
    }
}
