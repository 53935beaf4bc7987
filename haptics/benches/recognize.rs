//! Cost of one sample through the live recognizer (goal ≤ 2 µs): the streaming features on
//! every sample, a SOM decision every hop (100 samples) on the default 3 s windows, over a whole
//! simulated rubbing run; and the dearest sample alone, the one that completes a window and asks
//! the map.

// The measured call returns the recognizer's own result type, large by design (see haptics'
// lib.rs).
#![allow(clippy::result_large_err)]

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use haptics::live_recognizer::LiveRecognizer;
use haptics::sim::protocols::nakano::rubbing_run;
use haptics::sim::world::surface::{SurfacePatch, nakano_surfaces};
use recognize::{LabelledCapture, NakanoWindowing, RecognizerFile, SomParams};

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
    let model = RecognizerFile::train_som(&train, windowing, SomParams::default()).expect("train");
    let test = rubbing_run(&SurfacePatch::new(&surfaces[2]), 1, 1).expect("run");
    let x = test.column("tangential_position_m").expect("x").to_vec();
    let z = test.column("normal_position_m").expect("z").to_vec();
    let f = test.column("friction_force_n").expect("f").to_vec();
    let mut live = LiveRecognizer::new(&model, 1000.0).expect("som");
    let mut group = c.benchmark_group("live_recognizer");
    group.throughput(Throughput::Elements(x.len() as u64));
    group.bench_function("rubbing_run_per_sample", |b| {
        b.iter(|| {
            live.reset();
            let mut last = 0;
            for i in 0..x.len() {
                if let Ok(Some(d)) = live.push(black_box(x[i]), black_box(z[i]), black_box(f[i])) {
                    last = d.label;
                }
            }
            black_box(last)
        });
    });
    // The dearest sample: the one that completes a decision window and asks the map, with
    // every window full. The recognizer is fed up to just before it (untimed), then that sample
    // alone is timed.
    let decisions: Vec<usize> = {
        let mut probe = LiveRecognizer::new(&model, 1000.0).expect("som");
        (0..x.len())
            .filter(|&i| matches!(probe.push(x[i], z[i], f[i]), Ok(Some(_))))
            .collect()
    };
    let at = decisions[decisions.len() / 2];
    let mut before = LiveRecognizer::new(&model, 1000.0).expect("som");
    for i in 0..at {
        let _ = before.push(x[i], z[i], f[i]);
    }
    group.throughput(Throughput::Elements(1));
    group.bench_function("deciding_sample", |b| {
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
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
