//! Cost of one sample through the live recognizer (goal ≤ 2 µs): the streaming features on
//! every sample and a decision every hop, over a whole simulated rubbing run; and the dearest
//! sample alone, the one that completes a window and asks the classifier. Two recognizers: a
//! SOM on the default 3 s windows every 100 samples, and the committed SVM of `surfaces_nakano`
//! (0.25 s windows every 20 samples, window probabilities accumulated into a posterior; it
//! decides each window at its last sample, so that sample also computes the window's features
//! from the stroke's latest samples, with the filters' lookahead mirrored, instead of reading
//! them from the streaming sums). A recognizer that streams with a mirrored start has one more
//! dear sample a stroke, the one that pushes the mirror image through the filters.
//!
//! The height's spectrum: an SVM over windows over travel of Nakano's features alone and
//! followed by the spectrum of the window's heights (`nakano_spectrum`), both trained on run 0:
//! what the DFT adds to the sample that decides.
//!
//! Fusion: a k-NN over 0.25 s windows of Nakano's features decided at their last sample,
//! alone and with a k-NN over each window's vibration spectrum fused into its posterior
//! (`LiveRecognizer::fused`), on runs whose vibration is a tone per surface (the simulated
//! Omega.7 has no accelerometer): what the vibration sense adds per sample, and its dearest
//! sample, which completes windows of both.

// The measured call returns the recognizer's own result type, large by design (see haptics'
// lib.rs).
#![allow(clippy::result_large_err)]

use std::hint::black_box;
use std::path::Path;

use capture::Capture;
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use haptics::LiveRecognizer;
use recognize::DEFAULT_MEMORY_S;
use recognize::nakano::FrictionOverTravel;
use recognize::{CellScale, FeatureSet, LabelledCapture, NakanoWindowing, RecognizerFile, SomParams, SvmC};
use sim::nakano::rubbing_run;
use sim::{SurfacePatch, nakano_surfaces};

fn bench(c: &mut Criterion) {
    let surfaces = nakano_surfaces();
    let train: Vec<LabelledCapture> = surfaces
        .iter()
        .map(|s| {
            let capture = rubbing_run(&SurfacePatch::new(s), 0, 1).expect("run");
            LabelledCapture::new(capture, Path::new(s.name), String::new()).expect("labelled")
        })
        .collect();
    let windowing = NakanoWindowing::protocol(1000.0).expect("valid");
    let som = RecognizerFile::train_som(&train, windowing, SomParams::default()).expect("train");
    let svm_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/models/nakano_svm.json");
    let svm = RecognizerFile::load(&svm_path).expect("committed SVM recognizer");
    let test = rubbing_run(&SurfacePatch::new(&surfaces[2]), 1, 1).expect("run");
    let signals = ["tangential_position_m", "normal_position_m", "friction_force_n"]
        .map(|name| test.column(name).expect("rubbing column").to_vec());
    // The same SVM over windows of Nakano's features alone and followed by the height's
    // spectrum (a DFT of up to 625 samples on each deciding sample), trained on run 0.
    let over_travel = NakanoWindowing {
        mirrored_end: true,
        friction_over_travel: Some(FrictionOverTravel::protocol()),
        ..NakanoWindowing::new(0.25, 0.02, 1000.0)
            .and_then(|w| w.following_speeds_down_to(0.002))
            .expect("valid")
    }
    .over_travel()
    .and_then(|w| w.reading_spectra_up_to(0.025))
    .expect("valid");
    let [nakano, spectrum] = [FeatureSet::Nakano, FeatureSet::NakanoSpectrum].map(|features| {
        RecognizerFile::train_svm_windows(&train, over_travel, features, &SvmC::Fixed(10.0), CellScale::Mean)
            .expect("SVM")
    });
    let mut group = c.benchmark_group("live_recognizer");
    for (name, model) in [
        ("som", &som),
        ("svm", &svm),
        ("svm_nakano_run0", &nakano),
        ("svm_nakano_spectrum_run0", &spectrum),
    ] {
        bench_model(&mut group, name, model, &signals);
    }
    bench_fusion(&mut group, &surfaces);
    group.finish();
}

/// A capture with a `vibration_mps2` column: a tone at `tone_hz` with a deterministic jitter.
fn with_tone(capture: &Capture, tone_hz: f64) -> Capture {
    let rate_hz = capture.metadata().rate_hz();
    let tone = (0..capture.len()).map(|k| {
        let jitter = ((k * 7919) % 13) as f64 / 13.0 - 0.5;
        0.5 * (std::f64::consts::TAU * tone_hz * k as f64 / rate_hz).sin() + 0.1 * jitter
    });
    let mut columns = capture.columns().to_vec();
    columns.push("vibration_mps2".to_owned());
    let mut data = capture.data().to_vec();
    data.push(tone.collect());
    Capture::new(capture.metadata().clone(), columns, data).expect("capture")
}

fn bench_fusion(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    surfaces: &[sim::RubbingSurface],
) {
    let tone_hz = |i: usize| 40.0 + 32.0 * (i / 2) as f64;
    let train: Vec<LabelledCapture> = surfaces
        .iter()
        .enumerate()
        .flat_map(|(i, s)| {
            (0..2).map(move |run| {
                let capture = rubbing_run(&SurfacePatch::new(s), run, 1).expect("run");
                LabelledCapture::new(with_tone(&capture, tone_hz(i)), Path::new(s.name), String::new())
                    .expect("labelled")
            })
        })
        .collect();
    let windowing = NakanoWindowing {
        mirrored_end: true,
        ..NakanoWindowing::new(0.25, 0.1, 1000.0).expect("valid")
    };
    let knn = |features| {
        RecognizerFile::train_knn_windows(&train, windowing, features, 5, CellScale::Mean).expect("k-NN")
    };
    let (nakano, vibration) = (knn(FeatureSet::Nakano), knn(FeatureSet::Vibration));
    let params = nakano
        .fused_sequential_params(&[&vibration], DEFAULT_MEMORY_S)
        .expect("fusable")
        .build()
        .expect("valid");
    let test = with_tone(
        &rubbing_run(&SurfacePatch::new(&surfaces[2]), 2, 1).expect("run"),
        tone_hz(2),
    );
    let [x, z, f, v] = [
        "tangential_position_m",
        "normal_position_m",
        "friction_force_n",
        "vibration_mps2",
    ]
    .map(|name| test.column(name).expect("rubbing column").to_vec());
    let alone = LiveRecognizer::new(&nakano, 1000.0).expect("live recognizer");
    let fused = LiveRecognizer::fused(&nakano, &[&vibration], 1000.0, params).expect("fused");
    group.throughput(Throughput::Elements(x.len() as u64));
    for (name, mut live) in [("knn", alone), ("knn_vibration_fused", fused)] {
        group.bench_function(format!("{name}/rubbing_run_per_sample"), |b| {
            b.iter(|| {
                live.reset();
                let mut last = 0;
                for i in 0..x.len() {
                    let pushed = live.push_with_vibration(
                        black_box(x[i]),
                        black_box(z[i]),
                        black_box(f[i]),
                        black_box(v[i]),
                    );
                    if let Ok(Some(d)) = pushed {
                        last = d.best;
                    }
                }
                black_box(last)
            });
        });
    }
    // The dearest sample: one that completes windows of both senses, in the middle of the run.
    let mut probe = LiveRecognizer::fused(&nakano, &[&vibration], 1000.0, params).expect("fused");
    let decisions: Vec<usize> = (0..x.len())
        .filter(|&i| matches!(probe.push_with_vibration(x[i], z[i], f[i], v[i]), Ok(Some(_))))
        .collect();
    let at = decisions[decisions.len() / 2];
    let mut before = LiveRecognizer::fused(&nakano, &[&vibration], 1000.0, params).expect("fused");
    for i in 0..at {
        let _ = before.push_with_vibration(x[i], z[i], f[i], v[i]);
    }
    group.throughput(Throughput::Elements(1));
    group.bench_function("knn_vibration_fused/deciding_sample", |b| {
        b.iter_batched_ref(
            || before.clone(),
            |r| {
                black_box(r.push_with_vibration(
                    black_box(x[at]),
                    black_box(z[at]),
                    black_box(f[at]),
                    black_box(v[at]),
                ))
            },
            criterion::BatchSize::LargeInput,
        );
    });
}

fn bench_model(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    name: &str,
    model: &RecognizerFile,
    [x, z, f]: &[Vec<f64>; 3],
) {
    let mut live = LiveRecognizer::new(model, 1000.0).expect("live recognizer");
    group.throughput(Throughput::Elements(x.len() as u64));
    group.bench_function(format!("{name}/rubbing_run_per_sample"), |b| {
        b.iter(|| {
            live.reset();
            let mut last = 0;
            for i in 0..x.len() {
                if let Ok(Some(d)) = live.push(black_box(x[i]), black_box(z[i]), black_box(f[i])) {
                    last = d.best;
                }
            }
            black_box(last)
        });
    });
    // The dearest sample: the one that completes a decision window and asks the classifier,
    // with every window full. The recognizer is fed up to just before it (untimed), then that
    // sample alone is timed.
    let decisions: Vec<usize> = {
        let mut probe = LiveRecognizer::new(model, 1000.0).expect("live recognizer");
        (0..x.len())
            .filter(|&i| matches!(probe.push(x[i], z[i], f[i]), Ok(Some(_))))
            .collect()
    };
    let at = decisions[decisions.len() / 2];
    let mut before = LiveRecognizer::new(model, 1000.0).expect("live recognizer");
    for i in 0..at {
        let _ = before.push(x[i], z[i], f[i]);
    }
    group.throughput(Throughput::Elements(1));
    // With a mirrored start, the sample that completes the held start pushes the mirror image
    // and the held samples through the filters at once, once a stroke.
    if live.windowing().mirrored_start && !live.windowing().mirrored_end {
        let held = live.windowing().filters.lookahead_samples();
        let mut start = LiveRecognizer::new(model, 1000.0).expect("live recognizer");
        for i in 0..held {
            let _ = start.push(x[i], z[i], f[i]);
        }
        group.bench_function(format!("{name}/mirroring_sample"), |b| {
            b.iter_batched_ref(
                || start.clone(),
                |r| black_box(r.push(black_box(x[held]), black_box(z[held]), black_box(f[held]))),
                criterion::BatchSize::LargeInput,
            );
        });
    }
    group.bench_function(format!("{name}/deciding_sample"), |b| {
        b.iter_batched_ref(
            || before.clone(),
            |r| {
                let d = r.push(black_box(x[at]), black_box(z[at]), black_box(f[at]));
                assert!(matches!(d, Ok(Some(_))));
                black_box(d)
            },
            criterion::BatchSize::LargeInput,
        );
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
