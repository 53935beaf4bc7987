//! Time to certify a model's force bound ([`ModelFile::certify`]) on models identified from
//! several captures, against the sampled check it replaced (33 × 33 predictions over the
//! model's input range) run on the same model in the same run, and the worst case a file
//! within the caps can pose: a phase part with the largest number of support vectors allowed.
//!
//! Run with `cargo bench -p identify --bench certify`. Prints, per model: the median of 15
//! certifications, ms; the work spent (kernel evaluations); the bound proved; the ratio to
//! the sampled grid's median.

use std::hint::black_box;
use std::path::PathBuf;
use std::time::Instant;

use capture::{Capture, CaptureKind};
use identify::{
    DeviceEnvelope, IdentifyOptions, ModelBody, ModelFile, ModelKind, PartSvr, Plausibility, identify,
};
use svm::{InputScaling, Kernel, SvrModel};

const OMEGA7: DeviceEnvelope = DeviceEnvelope {
    max_force_n: 12.0,
    stroke_m: 0.16,
};

fn capture(path: &str, kind: CaptureKind) -> Capture {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../assets/captures");
    Capture::read_file(root.join(path), kind).expect("a committed capture")
}

fn fitted(path: &str, kind: CaptureKind, model: ModelKind) -> ModelFile {
    identify(&capture(path, kind), None, &IdentifyOptions::new(model))
        .expect("identifies")
        .model
}

/// The Li & Bi phase model with one cutting law replaced by an SVR at the support-vector cap.
fn widest(mut m: ModelFile) -> ModelFile {
    let n = Plausibility::MAX_SUPPORT_VECTORS;
    if let ModelBody::Phases(p) = &mut m.body {
        p.layers[0].after.svr = Some(PartSvr {
            scaling: InputScaling {
                offset: vec![0.0, 0.0],
                scale: vec![0.045, 0.01],
            },
            svr: SvrModel {
                kernel: Kernel::Rbf { gamma: 30.0 },
                dim: 2,
                support_vectors: (0..n).flat_map(|i| [i as f64 / n as f64, 1.0]).collect(),
                coefficients: (0..n).map(|i| if i % 2 == 0 { 1e-3 } else { -1e-3 }).collect(),
                bias: 0.5,
                weights: None,
            },
        });
    }
    m
}

fn median_ms(mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..15)
        .map(|_| {
            let started = Instant::now();
            f();
            started.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

fn grid(m: &ModelFile) -> f64 {
    let n = 33;
    let r = &m.input_range;
    let at = |k: usize, i: usize| r[k][0] + (r[k][1] - r[k][0]) * i as f64 / (n - 1) as f64;
    let mut peak: f64 = 0.0;
    for i in 0..n {
        for j in 0..n {
            let x: Vec<f64> = if r.len() == 1 {
                vec![at(0, i)]
            } else {
                vec![at(0, i), at(1, j)]
            };
            peak = peak.max(m.predict(&x).abs());
        }
    }
    peak
}

#[allow(clippy::print_stdout)]
fn main() {
    let li_bi = fitted(
        "li_bi/needle_train.csv",
        CaptureKind::Insertion,
        ModelKind::NeedlePhases,
    );
    let models = [
        ("li_bi needle, phases", li_bi.clone()),
        (
            "li_bi needle, smooth",
            fitted(
                "li_bi/needle_train.csv",
                CaptureKind::Insertion,
                ModelKind::NeedlePuncture,
            ),
        ),
        (
            "li_bi hard contact",
            fitted(
                "li_bi/hard_contact_train.csv",
                CaptureKind::Rubbing,
                ModelKind::HardFriction,
            ),
        ),
        (
            "li_bi soft contact",
            fitted(
                "li_bi/soft_contact_train.csv",
                CaptureKind::Rubbing,
                ModelKind::SoftFriction,
            ),
        ),
        (
            "close_layers, phases",
            fitted(
                "needle_corpus/close_layers_train.csv",
                CaptureKind::Insertion,
                ModelKind::NeedlePhases,
            ),
        ),
        (
            "lumen, phases",
            fitted(
                "needle_corpus/lumen_train.csv",
                CaptureKind::Insertion,
                ModelKind::NeedlePhases,
            ),
        ),
        (
            "digitized, smooth",
            fitted(
                "needle_corpus/digitized_train.csv",
                CaptureKind::Insertion,
                ModelKind::NeedlePuncture,
            ),
        ),
        ("50,000-SV cutting law", widest(li_bi)),
    ];
    println!("model                     certify ms   work (kernel evals)   bound N   grid ms   certify/grid");
    for (name, m) in &models {
        let outcome = m.certify(&OMEGA7);
        let certify = median_ms(|| {
            let _ = black_box(m.certify(black_box(&OMEGA7)));
        });
        let reference = median_ms(|| {
            black_box(grid(black_box(m)));
        });
        let (work, bound) = match &outcome {
            Ok(c) => (c.work.to_string(), format!("{:.3}", c.bound_n)),
            Err(e) => ("-".into(), format!("refused: {e}")),
        };
        println!(
            "{name:<25} {certify:>10.2}   {work:>19}   {bound:>7}   {reference:>7.2}   {:>12.1}",
            certify / reference
        );
    }
}
