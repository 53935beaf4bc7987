//! k-NN queries per second: the k-d tree ([`Knn::neighbours`]) against the exhaustive scan
//! ([`Knn::neighbours_exhaustive`]) and the original full sort of every distance, at 5-D
//! (Nakano's features) with 1 k, 10 k and 50 k training points and at 130-D (spectral
//! histograms) with 10 k, all in one run so the ratios compare like with like.
//!
//! The points are clustered like real features (20 classes, each a blob around its own
//! centre) and already in `[0, 1]`, so the classifier is fitted without scaling and the
//! full sort can be reproduced here on the same numbers.

use std::hint::black_box;
use std::time::Duration;

use capture::rng::SplitMix64;
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use recognize::{FeatureScaling, Knn, KnnParams};

/// Queries per measured iteration.
const QUERIES: usize = 200;
const CLASSES: usize = 20;

/// `n` points of `dim` values in 20 blobs, labels by blob, and `QUERIES` queries drawn the
/// same way.
fn data(n: usize, dim: usize, seed: u64) -> (Vec<Vec<f64>>, Vec<usize>, Vec<Vec<f64>>) {
    let mut rng = SplitMix64::new(seed);
    let centres: Vec<Vec<f64>> = (0..CLASSES)
        .map(|_| (0..dim).map(|_| 0.2 + 0.6 * rng.next_f64()).collect())
        .collect();
    let point = |c: usize, rng: &mut SplitMix64| -> Vec<f64> {
        centres[c]
            .iter()
            .map(|&m| (m + 0.15 * (rng.next_f64() + rng.next_f64() + rng.next_f64() - 1.5)).clamp(0.0, 1.0))
            .collect()
    };
    let labels: Vec<usize> = (0..n).map(|i| i % CLASSES).collect();
    let x = labels.iter().map(|&c| point(c, &mut rng)).collect();
    let queries = (0..QUERIES).map(|i| point(i % CLASSES, &mut rng)).collect();
    (x, labels, queries)
}

/// The search as first written: every squared distance, sorted by (distance, index).
fn full_sort(x: &[Vec<f64>], q: &[f64], k: usize) -> Vec<usize> {
    let mut dist: Vec<(f64, usize)> = x
        .iter()
        .enumerate()
        .map(|(i, p)| (p.iter().zip(q).map(|(a, b)| (a - b) * (a - b)).sum::<f64>(), i))
        .collect();
    dist.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    dist.into_iter().take(k).map(|(_, i)| i).collect()
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("knn_queries");
    group.throughput(Throughput::Elements(QUERIES as u64));
    group.sample_size(10);
    group.warm_up_time(Duration::from_millis(500));
    group.measurement_time(Duration::from_secs(2));
    for (dim, n) in [(5, 1_000), (5, 10_000), (5, 50_000), (130, 10_000)] {
        let (x, y, queries) = data(n, dim, 7 + n as u64 + dim as u64);
        let knn: Knn = KnnParams::default()
            .scaling(FeatureScaling::None)
            .fit(&x, &y, CLASSES)
            .expect("valid training set");
        // Same answers, or the timings mean nothing (and the tree is built before timing).
        for q in &queries {
            let want = full_sort(&x, q, 3);
            assert_eq!(knn.neighbours(q).expect("valid"), want);
            assert_eq!(knn.neighbours_exhaustive(q).expect("valid"), want);
        }
        let id = format!("{dim}d_{n}");
        group.bench_function(BenchmarkId::new("neighbours", &id), |b| {
            b.iter(|| {
                queries
                    .iter()
                    .map(|q| knn.neighbours(black_box(q)).map_or(0, |v| v[0]))
                    .sum::<usize>()
            })
        });
        group.bench_function(BenchmarkId::new("exhaustive_scan", &id), |b| {
            b.iter(|| {
                queries
                    .iter()
                    .map(|q| knn.neighbours_exhaustive(black_box(q)).map_or(0, |v| v[0]))
                    .sum::<usize>()
            })
        });
        group.bench_function(BenchmarkId::new("full_sort", &id), |b| {
            b.iter(|| {
                queries
                    .iter()
                    .map(|q| full_sort(&x, black_box(q), 3)[0])
                    .sum::<usize>()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
