//! Nakano's features: batch against a sine's known statistics, streaming against batch (from the
//! first sample and with the mirrored start), the reaction-force observer, and bad input.

use super::*;
use crate::{InputError, SettingError, UsageError};

/// A rough, wavy, tilted profile with noisy friction, sampled like the thesis's rubbing.
fn signals(n: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let mut rng = capture::rng::SplitMix64::new(7u64);
    let mut noise = move || rng.next_f64() - 0.5;
    let step_m = 5e-6;
    let mut x = Vec::new();
    let mut z = Vec::new();
    let mut f = Vec::new();
    for i in 0..n {
        let xi = i as f64 * step_m;
        x.push(xi);
        let height = 20e-6 * (xi * std::f64::consts::TAU / 15e-3).sin()
            + 12e-6 * (xi * std::f64::consts::TAU / 0.5e-3).sin()
            + 1e-3 * xi
            + 0.1;
        z.push((height / 1e-5).round() * 1e-5 + 1e-6 * noise());
        f.push(0.15 + 0.01 * noise());
    }
    (x, z, f)
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs()) + 1e-300
}

#[test]
fn a_sine_roughness_gives_its_amplitude_wavelength_and_friction_statistics() {
    let n = 4000;
    let x: Vec<f64> = (0..n).map(|i| i as f64 * 5e-6).collect();
    // 10 µm amplitude, 0.5 mm wavelength on 20 µm of 15 mm waviness.
    let z: Vec<f64> = x
        .iter()
        .map(|&x| {
            10e-6 * (x * std::f64::consts::TAU / 0.5e-3).sin()
                + 20e-6 * (x * std::f64::consts::TAU / 15e-3).sin()
        })
        .collect();
    let f: Vec<f64> = (0..n).map(|i| if i % 2 == 0 { 0.2 } else { 0.1 }).collect();
    let sig = NakanoSignals::new(&x, &z, &f).expect("equal lengths");
    let p = sig
        .features(1000, 2000, &NakanoConfig::default())
        .expect("in range");
    // Mean |sin| = 2/π of the amplitude; variance = A²/2 (the 2.5 mm average leaves a few %).
    assert!(
        (p[0] / (10e-6 * 2.0 / std::f64::consts::PI) - 1.0).abs() < 0.05,
        "{p:?}"
    );
    assert!((p[1] / (10e-6f64.powi(2) / 2.0) - 1.0).abs() < 0.1, "{p:?}");
    // 10 mm of travel holds 20 waves.
    assert!((p[2] - 0.5e-3).abs() < 0.03e-3, "{p:?}");
    assert!(
        (p[3] - 0.15).abs() < 1e-12 && (p[4] - 0.0025).abs() < 1e-12,
        "{p:?}"
    );
}

#[test]
fn a_mirrored_start_streams_as_the_batch_over_the_mirrored_signals() {
    let (x, z, f) = signals(3000);
    let config = NakanoConfig::default();
    let pad = config.lookahead_samples();
    let sig = NakanoSignals::new(&x, &z, &f).expect("equal lengths");
    let (ex, ez, ef) = mirror_start(&sig, pad).expect("longer than the margin");
    assert_eq!(ex.len(), x.len() + pad);
    // Heights and positions reflected through the first sample; the stroke itself kept.
    assert_eq!(ez[pad - 1], 2.0 * z[0] - z[1]);
    assert_eq!(ex[0], 2.0 * x[0] - x[pad]);
    assert_eq!(ez[pad..], z[..]);
    let extended = NakanoSignals::new(&ex, &ez, &ef).expect("equal lengths");
    let len = 250;
    let mut stream = NakanoStream::new(config, len)
        .expect("valid")
        .with_mirrored_start();
    let mut fresh = stream.clone();
    let mut starts = Vec::new();
    for i in 0..x.len() {
        let Some(w) = stream.push(x[i], z[i], f[i]) else {
            continue;
        };
        // The window completed by sample i ends lookahead samples before it, counted from
        // the stroke's first sample.
        assert_eq!(w.start as usize + len - 1 + pad, i);
        let start = w.start as usize;
        assert_eq!(w.start_position_m, x[start]);
        let batch = extended.features(start + pad, len, &config).expect("in range");
        let floors = [0.0, 1e-12 * 1e-10, 0.0, 0.0, 1e-12 * batch[3].powi(2)];
        for (k, (a, b)) in w.features.iter().zip(&batch).enumerate() {
            assert!(
                close(*a, *b) || (a - b).abs() <= floors[k],
                "start {start} feature {k}: {a} vs {b}"
            );
        }
        starts.push(start);
    }
    // The first window starts at the stroke's first sample, not after the margin.
    assert_eq!(starts.first(), Some(&0));
    assert_eq!(starts.len(), x.len() - len - pad + 1);
    // Reset, the stream mirrors the next stroke's start again.
    stream.reset();
    let again: Vec<u64> = (0..x.len())
        .filter_map(|i| stream.push(x[i], z[i], f[i]).map(|w| w.start))
        .collect();
    let first: Vec<u64> = (0..x.len())
        .filter_map(|i| fresh.push(x[i], z[i], f[i]).map(|w| w.start))
        .collect();
    assert_eq!(again, first);
    assert!(
        mirror_start(
            &NakanoSignals::new(&x[..pad], &z[..pad], &f[..pad]).expect("equal"),
            pad
        )
        .is_none()
    );
}

#[test]
fn streaming_equals_batch_on_every_window() {
    let (x, z, f) = signals(5000);
    let config = NakanoConfig::default();
    let sig = NakanoSignals::new(&x, &z, &f).expect("equal lengths");
    for len in [2, 500, 1000] {
        let mut stream = NakanoStream::new(config, len).expect("valid");
        let mut compared = 0;
        for i in 0..x.len() {
            let Some(w) = stream.push(x[i], z[i], f[i]) else {
                continue;
            };
            // The window completed by sample i ends lookahead samples before it.
            assert_eq!(w.start as usize + len - 1 + config.lookahead_samples(), i);
            let start = w.start as usize;
            if start < config.lookahead_samples() {
                continue; // the batch needs a margin before the window
            }
            let batch = sig.features(start, len, &config).expect("in range");
            // Variances to 1e-9 relative, or to 1e-12 of the squared level the signal varies
            // about — (10 µm)² for the roughness, the mean² for friction: the running sums'
            // rounding is of order ε × that level, which only shows in a nearly constant
            // window of two samples.
            let floors = [0.0, 1e-12 * 1e-10, 0.0, 0.0, 1e-12 * batch[3].powi(2)];
            for (k, (a, b)) in w.features.iter().zip(&batch).enumerate() {
                assert!(
                    close(*a, *b) || (a - b).abs() <= floors[k],
                    "len {len} start {start} feature {k}: {a} vs {b}"
                );
            }
            compared += 1;
        }
        assert!(compared > 2000, "{compared}");
    }
}

#[test]
fn bad_windows_and_signals_are_errors() {
    let (x, z, f) = signals(1000);
    let sig = NakanoSignals::new(&x, &z, &f).expect("equal lengths");
    let config = NakanoConfig::default();
    assert!(matches!(
        sig.features(100, 200, &config),
        Err(RecognizeError::Usage(UsageError::WindowOutOfRange {
            margin: 270,
            ..
        }))
    ));
    assert!(matches!(
        sig.features(600, 200, &config),
        Err(RecognizeError::Usage(UsageError::WindowOutOfRange { .. }))
    ));
    assert!(sig.features(270, 460, &config).is_ok());
    assert!(matches!(
        sig.features(300, 1, &config),
        Err(RecognizeError::Setting(SettingError::WindowTooShort { len: 1 }))
    ));
    assert!(matches!(
        sig.features(usize::MAX, 2, &config),
        Err(RecognizeError::Usage(UsageError::WindowOutOfRange { .. }))
    ));
    assert!(matches!(
        NakanoSignals::new(&x, &z[1..], &f),
        Err(RecognizeError::Usage(UsageError::SignalLengths {
            height: 999,
            ..
        }))
    ));
    assert!(NakanoStream::new(config, 1).is_err());
    assert!(NakanoConfig::from_wavelengths(0.0, 1e-4, 5e-3, 1e3).is_err());
    assert_eq!(
        NakanoConfig::at_rate(1e3).expect("valid"),
        NakanoConfig::default()
    );
    let slow = NakanoConfig::at_rate(100.0).expect("valid");
    assert_eq!((slow.highpass_half_width, slow.smoothing_half_width), (25, 2));
    let fast = NakanoConfig::at_rate(1e4).expect("valid");
    assert_eq!((fast.highpass_half_width, fast.smoothing_half_width), (2500, 200));
    let c = NakanoConfig::from_wavelengths(2.5e-3, 0.2e-3, 5e-3, 1e3).expect("valid");
    assert_eq!((c.highpass_half_width, c.smoothing_half_width), (250, 20));
}

#[test]
fn the_rfob_recovers_friction_from_the_commanded_force() {
    use capture::{CaptureKind, Metadata};
    // Accelerating sinusoidally on top of 5 mm/s against a friction of 0.15 + 0.02 sin N.
    let n = 3000;
    let dt = 1e-3;
    let mass_kg = 0.3;
    let t: Vec<f64> = (0..n).map(|k| k as f64 * dt).collect();
    let w = std::f64::consts::TAU * 2.0;
    let x: Vec<f64> = t.iter().map(|t| 5e-3 * t + 1e-4 * (w * t).sin()).collect();
    let v: Vec<f64> = t.iter().map(|t| 5e-3 + 1e-4 * w * (w * t).cos()).collect();
    let friction: Vec<f64> = t.iter().map(|t| 0.15 + 0.02 * (3.0 * t).sin()).collect();
    let command: Vec<f64> = t
        .iter()
        .zip(&friction)
        .map(|(t, f)| mass_kg * (-1e-4 * w * w * (w * t).sin()) + f)
        .collect();
    let columns = [
        "time_s",
        "tangential_position_m",
        "normal_force_n",
        "tangential_velocity_mps",
    ];
    let columns: Vec<String> = columns.iter().map(|c| (*c).to_owned()).collect();
    let meta = Metadata::new(CaptureKind::Rubbing, "test", 1000.0);
    let mut data = vec![t.clone(), x.clone(), vec![0.3; n], v];
    let no_command = Capture::new(meta.clone(), columns.clone(), data.clone()).expect("valid");
    assert!(matches!(
        NakanoSignals::from_capture(&no_command),
        Err(RecognizeError::Input(InputError::NakanoColumn(_)))
    ));
    let mut columns = columns;
    columns.push("tangential_command_force_n".into());
    data.push(command);
    let capture = Capture::new(meta, columns, data).expect("valid");
    // Within `tolerance` N of the friction from sample `from` on.
    let assert_tracks = |capture: &Capture, from: usize, tolerance: f64| {
        let estimate = Rfob::default().friction_n(capture).expect("columns");
        for k in from..n {
            assert!(
                (estimate[k] - friction[k]).abs() < tolerance,
                "{k}: {} vs {}",
                estimate[k],
                friction[k]
            );
        }
    };
    // After the observer's transient (5 time constants of 20 ms) it lags the slow friction
    // by ~20 ms: 3 rad/s × 0.02 N × 0.02 s ≈ 1.2 mN.
    assert_tracks(&capture, 100, 3e-3);
    // Without a velocity column it pseudo-differentiates the position.
    let mut columns = capture.columns().to_vec();
    let mut data = capture.data().to_vec();
    columns.remove(3);
    data.remove(3);
    let capture = Capture::new(capture.metadata().clone(), columns, data).expect("valid");
    assert_tracks(&capture, 200, 5e-3);
}

#[test]
fn a_flat_surface_counts_no_waves() {
    let n = 2000;
    let x: Vec<f64> = (0..n).map(|i| i as f64 * 5e-6).collect();
    let z = vec![0.123; n];
    let f = vec![0.2; n];
    let sig = NakanoSignals::new(&x, &z, &f).expect("equal lengths");
    let p = sig
        .features(500, 1000, &NakanoConfig::default())
        .expect("in range");
    assert!(p[0] < 1e-15 && p[1] < 1e-30, "{p:?}");
    assert!((p[2] - 999.0 * 5e-6).abs() < 1e-12, "{p:?}");
    let mut stream = NakanoStream::new(NakanoConfig::default(), 1000).expect("valid");
    let last = (0..n)
        .filter_map(|i| stream.push(x[i], z[i], f[i]))
        .last()
        .expect("windows");
    assert!((last.features[2] - 999.0 * 5e-6).abs() < 1e-12, "{last:?}");
}

#[test]
fn an_edge_window_is_the_batch_window_of_the_mirrored_known_signals() {
    let (x, z, f) = signals(3000);
    let config = NakanoConfig::default();
    let pad = config.lookahead_samples();
    let len = 250;
    let mut edge = EdgeWindow::new(config, len).expect("valid");
    assert_eq!(edge.history_samples(), len + pad);
    // Far from the start: the window and the margin before it are known, the margin after it
    // is the mirror image, bit for bit the batch features of that construction.
    for e in [len + pad, 1200, 3000] {
        let known = e - len - pad..e;
        let got = edge
            .features(e - len, &x[known.clone()], &z[known.clone()], &f[known])
            .expect("enough history");
        let (ex, ez, ef) = (
            extended_by_hand(&x, e, pad, true, 0),
            extended_by_hand(&z, e, pad, true, 0),
            extended_by_hand(&f, e, pad, false, 0),
        );
        let batch = NakanoSignals::new(&ex, &ez, &ef)
            .expect("equal lengths")
            .features(e - len, len, &config)
            .expect("in range");
        assert_eq!(got, batch, "window ending at {e}");
        // Only the lookahead differs from the window decided later, so its friction
        // statistics are the same.
        let later = NakanoSignals::new(&x, &z, &f)
            .expect("equal lengths")
            .features(e - len, len, &config);
        if let Ok(later) = later {
            assert_eq!(got[3..], later[3..]);
        }
    }
    // From the stroke's start, both ends mirrored: the first window, and one whose margin
    // reaches before the start.
    for e in [len, len + 100] {
        let s = e - len;
        let got = edge
            .features(e - len, &x[..e], &z[..e], &f[..e])
            .expect("whole stroke");
        let before = pad - s;
        let (ex, ez, ef) = (
            extended_by_hand(&x, e, pad, true, before),
            extended_by_hand(&z, e, pad, true, before),
            extended_by_hand(&f, e, pad, false, before),
        );
        let batch = NakanoSignals::new(&ex, &ez, &ef)
            .expect("equal lengths")
            .features(pad, len, &config)
            .expect("in range");
        for (k, (a, b)) in got.iter().zip(&batch).enumerate() {
            assert!(close(*a, *b), "window ending at {e}, feature {k}: {a} vs {b}");
        }
    }
    // Too little history, or signals of different lengths, are errors, not guesses.
    assert!(matches!(
        edge.features(
            1000,
            &x[..len + pad - 1],
            &z[..len + pad - 1],
            &f[..len + pad - 1]
        ),
        Err(RecognizeError::Usage(UsageError::WindowOutOfRange { .. }))
    ));
    assert!(matches!(
        edge.features(0, &x[..len - 1], &z[..len - 1], &f[..len - 1]),
        Err(RecognizeError::Usage(UsageError::WindowOutOfRange { .. }))
    ));
    assert!(matches!(
        edge.features(0, &x[..len], &z[..len], &f[..len - 1]),
        Err(RecognizeError::Usage(UsageError::SignalLengths { .. }))
    ));
    assert!(matches!(
        EdgeWindow::new(config, 1),
        Err(RecognizeError::Setting(SettingError::WindowTooShort { len: 1 }))
    ));
}

#[test]
fn a_strokes_first_window_reads_exactly_when_its_mirror_reaches_the_margin() {
    let (x, z, f) = signals(3000);
    let config = NakanoConfig::default();
    let margin = config.lookahead_samples();
    // Around the boundary 7·(len − 1) = margin, and far on each side of it.
    let boundary = margin.div_ceil(7) + 1;
    let mut reached = (0, 0);
    for len in (2..=8).chain(boundary - 3..=boundary + 3).chain([250, 1000]) {
        let mut edge = EdgeWindow::new(config, len).expect("valid");
        let first = edge.features(0, &x[..len], &z[..len], &f[..len]);
        let reaches = EdgeWindow::mirror_reaches(len, margin);
        assert_eq!(
            first.is_ok(),
            reaches,
            "a window of {len} samples, margin {margin}: {first:?}"
        );
        if reaches {
            reached.0 += 1;
        } else {
            reached.1 += 1;
        }
    }
    assert!(reached.0 > 3 && reached.1 > 3, "both sides tried: {reached:?}");
}

/// The signals known at sample `e` (exclusive) continued by definition: past sample `e − 1`
/// as `g(e − 1 + k) = 2·v(e − 1) − g(e − 1 − k)`, before sample 0 as `g(−k) = 2·v(0) − g(k)`
/// (plain mirrors for friction), from `before` samples before the start to `pad` after the end.
fn extended_by_hand(v: &[f64], e: usize, pad: usize, odd: bool, before: usize) -> Vec<f64> {
    fn g(v: &[f64], e: i64, odd: bool, i: i64) -> f64 {
        let mirror = |end: f64, inner: f64| if odd { 2.0 * end - inner } else { inner };
        if i >= e {
            mirror(v[e as usize - 1], g(v, e, odd, 2 * (e - 1) - i))
        } else if i < 0 {
            mirror(v[0], g(v, e, odd, -i))
        } else {
            v[i as usize]
        }
    }
    let (e_i, before_i) = (e as i64, before as i64);
    (-before_i..e_i + pad as i64).map(|i| g(v, e_i, odd, i)).collect()
}
