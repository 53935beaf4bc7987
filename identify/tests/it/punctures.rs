//! The puncture detector on signals with known drops and noise, and on the committed needle
//! captures against the depths their generator recorded in the metadata.

#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use std::path::Path;

use capture::{Capture, CaptureKind};
use identify::{PunctureParams, detect_punctures, force_noise_n, group_layers};

/// A deterministic standard normal sequence (`capture::rng` + Box–Muller), so the tests need no
/// RNG crate and give the same noise every run.
fn normals(seed: u64, n: usize) -> Vec<f64> {
    let mut rng = capture::rng::SplitMix64::new(seed);
    // Half a step above 0 so that the logarithm below is finite.
    let mut next = move || ((rng.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
    (0..n)
        .map(|_| {
            let (u1, u2) = (next(), next());
            (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
        })
        .collect()
}

/// One insertion at `speed` to 30 mm sampled at `rate_hz`: force ramps up to `peak` at each
/// of `membranes` (depth, peak, drop), falls by `drop` at once, plus white noise `sigma`.
fn synthetic(
    speed: f64,
    rate_hz: f64,
    membranes: &[(f64, f64, f64)],
    sigma: f64,
    seed: u64,
) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
    let n = (0.03 / speed * rate_hz) as usize;
    let noise = normals(seed, n);
    let mut t = Vec::with_capacity(n);
    let mut d = Vec::with_capacity(n);
    let mut f = Vec::with_capacity(n);
    for (i, e) in noise.iter().enumerate() {
        let time = i as f64 / rate_hz;
        let depth = speed * time;
        // Loading: a quadratic rise over the 8 mm before each membrane, then the residue.
        let mut force = 0.0;
        let mut base = 0.0;
        for &(at, peak, drop) in membranes {
            if depth < at {
                let u = (depth - (at - 0.008)).max(0.0) / 0.008;
                force = base + (peak - base) * u * u;
                break;
            }
            base = peak - drop;
            force = base;
        }
        t.push(time);
        d.push(depth);
        f.push(force + sigma * e);
    }
    let v = vec![speed; n];
    (t, d, v, f)
}

#[test]
fn finds_known_drops_in_noise_within_tolerance() {
    let membranes = [(0.012, 1.6, 1.2), (0.023, 0.75, 0.33)];
    for (k, &(speed, rate, sigma)) in [
        (0.0015, 100.0, 0.015),
        (0.009, 100.0, 0.015),
        (0.005, 1000.0, 0.02),
    ]
    .iter()
    .enumerate()
    {
        let (t, d, v, f) = synthetic(speed, rate, &membranes, sigma, k as u64 + 1);
        let found = detect_punctures(&t, &d, &v, &f, &PunctureParams::default()).unwrap();
        // The noise estimate is within 15 % of the noise put in.
        assert!(
            (found.noise_n / sigma - 1.0).abs() < 0.15,
            "noise {} for {sigma}",
            found.noise_n
        );
        assert_eq!(
            found.events.len(),
            2,
            "{speed} m/s at {rate} Hz: {:?}",
            found.events
        );
        for (e, &(at, peak, drop)) in found.events.iter().zip(&membranes) {
            // Depth within two samples' travel or 0.1 mm (near the peak the loading is flat
            // to within the noise, so the noisiest of the last few samples wins), peak and
            // drop (the noisy peak less the median after it) within 4σ.
            let tolerance_m = (2.0 * speed / rate).max(1e-4);
            assert!((e.depth_m - at).abs() <= tolerance_m, "{e:?}");
            assert!((e.peak_force_n - peak).abs() < 4.0 * sigma, "{e:?}");
            assert!((e.drop_n - drop).abs() < 4.0 * sigma, "{e:?}");
            assert_eq!(e.stroke, 0);
        }
    }
}

#[test]
fn pure_noise_and_a_slow_decline_give_no_events() {
    // SNR: a 1 N loading ramp under σ = 0.02 N of noise, 30 000 samples; no drop at all.
    let sigma = 0.02;
    let n = 30_000;
    let noise = normals(7, n);
    let t: Vec<f64> = (0..n).map(|i| i as f64 * 1e-3).collect();
    let d: Vec<f64> = t.iter().map(|t| 0.001 * t).collect();
    let v = vec![0.001; n];
    let f: Vec<f64> = (0..n).map(|i| i as f64 / n as f64 + sigma * noise[i]).collect();
    let found = detect_punctures(&t, &d, &v, &f, &PunctureParams::default()).unwrap();
    assert!(
        found.events.is_empty(),
        "{:?}",
        &found.events[..found.events.len().min(3)]
    );
    // A fall of 0.5 N spread over 5 mm of travel is force easing off, not a puncture.
    let f: Vec<f64> = (0..n)
        .map(|i| 1.0 - 0.5 * i as f64 / n as f64 + sigma * noise[i])
        .collect();
    let d20: Vec<f64> = t.iter().map(|t| 0.02 * t / 30.0).collect();
    let found = detect_punctures(&t, &d20, &v, &f, &PunctureParams::default()).unwrap();
    assert!(found.events.is_empty(), "{:?}", found.events);
}

#[test]
fn drops_while_held_or_withdrawing_are_not_punctures_and_strokes_are_counted() {
    // Advance with a drop, hold while the force relaxes by 1 N, withdraw (force reverses),
    // then advance again into a second drop, loaded from 0.2 N.
    let mut t = Vec::new();
    let mut d = Vec::new();
    let mut v = Vec::new();
    let mut f = Vec::new();
    let mut push = |depth: f64, vel: f64, force: f64| {
        t.push(t.len() as f64 * 0.01);
        d.push(depth);
        v.push(vel);
        f.push(force);
    };
    for i in 0..200 {
        let depth = i as f64 * 1e-4;
        push(depth, 0.01, if i < 100 { i as f64 * 0.01 } else { 0.3 });
    }
    for i in 0..100 {
        push(0.02, 0.0, 1.3 - i as f64 * 0.01);
    }
    for i in 0..100 {
        push(0.02 - i as f64 * 1e-4, -0.01, -0.5);
    }
    for i in 0..150 {
        let depth = 0.01 + i as f64 * 1e-4;
        push(depth, 0.01, if i < 120 { 0.2 + 0.006 * i as f64 } else { 0.5 });
    }
    let found = detect_punctures(&t, &d, &v, &f, &PunctureParams::default()).unwrap();
    let at: Vec<(usize, f64)> = found.events.iter().map(|e| (e.stroke, e.depth_m)).collect();
    assert_eq!(found.events.len(), 2, "{at:?}");
    assert_eq!(found.events[0].stroke, 0);
    assert!((found.events[0].depth_m - 0.0099).abs() < 1e-9, "{at:?}");
    assert!(
        (found.events[0].drop_n - 0.69).abs() < 1e-9,
        "{:?}",
        found.events[0]
    );
    assert_eq!(found.events[1].stroke, 1);
    assert!((found.events[1].depth_m - 0.0219).abs() < 1e-9, "{at:?}");
}

/// The generator's puncture depths per insertion: `truth.insertion.<k>.puncture_depths_m`.
fn truth_depths(c: &Capture) -> Vec<Vec<f64>> {
    (0..)
        .map_while(|k| {
            c.metadata()
                .get(&format!("truth.insertion.{k}.puncture_depths_m"))
        })
        .map(|s| s.split(';').map(|x| x.parse::<f64>().unwrap()).collect())
        .collect()
}

#[test]
fn detected_layers_match_the_generated_captures_metadata() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/captures/li_bi");
    for name in ["needle_train.csv", "needle_test.csv"] {
        let c = Capture::read_file(root.join(name), CaptureKind::Insertion).unwrap();
        let truth = truth_depths(&c);
        assert!(!truth.is_empty(), "{name}: no truth in the metadata");
        let found = detect_punctures(
            c.time(),
            c.column("depth_m").unwrap(),
            c.column("velocity_mps").unwrap(),
            c.column("axial_force_n").unwrap(),
            &PunctureParams::default(),
        )
        .unwrap();
        // Every stroke's punctures, in order, within 1 mm of the generator's.
        for (k, depths) in truth.iter().enumerate() {
            let got: Vec<f64> = found
                .events
                .iter()
                .filter(|e| e.stroke == k)
                .map(|e| e.depth_m)
                .collect();
            assert_eq!(
                got.len(),
                depths.len(),
                "{name} stroke {k}: {got:?} vs {depths:?}"
            );
            for (g, want) in got.iter().zip(depths) {
                assert!((g - want).abs() < 1e-3, "{name} stroke {k}: {g} vs {want}");
            }
        }
        // Layers: as many as membranes, each spanning the generator's depths within 1 mm.
        let layers = group_layers(&found.events, PunctureParams::default().layer_gap_m);
        let n_membranes = truth[0].len();
        assert_eq!(layers.len(), n_membranes, "{name}: {layers:?}");
        for (m, layer) in layers.iter().enumerate() {
            let want: Vec<f64> = truth.iter().map(|d| d[m]).collect();
            let lo = want.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = want.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            assert!(
                (layer.min_depth_m - lo).abs() < 1e-3 && (layer.max_depth_m - hi).abs() < 1e-3,
                "{name} layer {m}: {layer:?} vs {lo}..{hi}"
            );
            assert_eq!(layer.events.len(), truth.len());
        }
        // The sensor's stated noise is what the estimate finds (within 30 %: quantisation).
        let stated: f64 = c
            .metadata()
            .get("sensor.force_noise_std_n")
            .unwrap()
            .parse()
            .unwrap();
        let est = force_noise_n(c.column("axial_force_n").unwrap());
        assert!(
            (est / stated - 1.0).abs() < 0.3,
            "{name}: noise {est} vs {stated}"
        );
    }
}

#[test]
fn the_needle_report_sets_every_measured_puncture_beside_the_model() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/captures/li_bi");
    let train = Capture::read_file(root.join("needle_train.csv"), CaptureKind::Insertion).unwrap();
    let test = Capture::read_file(root.join("needle_test.csv"), CaptureKind::Insertion).unwrap();
    let identified = identify::identify(
        &train,
        Some(&test),
        &identify::IdentifyOptions::new(identify::ModelKind::NeedlePuncture),
    )
    .unwrap();
    let rows = &identified.report.punctures;
    let truth = truth_depths(&test);
    assert_eq!(rows.len(), truth.iter().map(Vec::len).sum::<usize>(), "{rows:?}");
    let depth = test.column("depth_m").unwrap();
    let velocity = test.column("velocity_mps").unwrap();
    for row in rows {
        let want = &truth[row.stroke];
        assert!(
            want.iter().any(|d| (d - row.measured_depth_m).abs() < 1e-3),
            "{row:?} vs {want:?}"
        );
        // The model's force at the measured peak is the model evaluated there.
        let i = (0..test.len())
            .find(|&i| depth[i] == row.measured_depth_m && (velocity[i] - row.speed_mps).abs() < 1e-15)
            .unwrap();
        let at = identified.model.predict(&[depth[i], velocity[i]]);
        assert!((row.model_force_at_measured_n - at).abs() < 1e-12, "{row:?}");
        // A matched puncture lies within the layer gap; a missed one has no model values.
        match row.predicted_depth_m {
            Some(d) => assert!((d - row.measured_depth_m).abs() <= PunctureParams::default().layer_gap_m),
            None => assert!(row.predicted_peak_force_n.is_none() && row.predicted_drop_n.is_none()),
        }
    }
    // A friction model cannot be compared.
    let mut friction = identified.model.clone();
    friction.kind = identify::ModelKind::HardFriction;
    assert!(identify::compare_punctures(&friction, &test, &PunctureParams::default()).is_err());
}
