#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

//! The simulated captures carry the physics they claim: each check reads captures back through
//! the capture format (as every consumer will) and compares what is in the data with the ground
//! truth written in the metadata.

use capture::{Capture, CaptureKind};
use sim::{CaptureSet, Split, generate, li_bi, nakano};
use sim::{SurfacePatch, nakano_surfaces};

fn truth(c: &Capture, key: &str) -> f64 {
    c.metadata()
        .get(key)
        .unwrap_or_else(|| panic!("no {key}"))
        .parse()
        .unwrap()
}

/// Least-squares line y = a·x + b; returns (a, b, residual std).
fn fit_line(x: &[f64], y: &[f64]) -> (f64, f64, f64) {
    let n = x.len() as f64;
    let mx = x.iter().sum::<f64>() / n;
    let my = y.iter().sum::<f64>() / n;
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
    let a = sxy / sxx;
    let b = my - a * mx;
    let rss: f64 = x.iter().zip(y).map(|(xi, yi)| (yi - a * xi - b).powi(2)).sum();
    (a, b, (rss / (n - 2.0)).sqrt())
}

#[test]
fn hard_contact_friction_is_linear_in_pressure_with_the_paper_law() {
    for split in [Split::Train, Split::Test] {
        let c = li_bi::hard_contact(1, split).unwrap();
        assert_eq!(c.len(), 31);
        let (slope, intercept, residual) = fit_line(
            c.column("normal_force_n").unwrap(),
            c.column("friction_force_n").unwrap(),
        );
        assert!((slope - truth(&c, "truth.slope")).abs() < 0.005, "slope {slope}");
        assert!(
            (intercept - truth(&c, "truth.intercept_n")).abs() < 0.02,
            "intercept {intercept}"
        );
        // Residuals are the sensor's noise and quantization, nothing systematic.
        let sensor = truth(&c, "sensor.force_noise_std_n");
        assert!(
            residual < 2.0 * sensor && residual > 0.5 * sensor,
            "residual {residual} vs {sensor}"
        );
        // Always sliding forward, as the paper's positive-velocity data.
        assert!(
            c.column("tangential_velocity_mps")
                .unwrap()
                .iter()
                .all(|&v| v > 0.0)
        );
    }
}

#[test]
fn soft_contact_has_per_speed_lines_whose_slope_varies_nonlinearly() {
    let c = li_bi::soft_contact(1, Split::Train).unwrap();
    assert!(c.len() >= 320);
    let commanded = c.column("commanded_velocity_mps").unwrap();
    let pressure = c.column("normal_force_n").unwrap();
    let friction = c.column("friction_force_n").unwrap();
    let law = sim::SoftContact::sponge();
    let speeds = li_bi::soft_contact_speeds_mmps(Split::Train);
    assert!(speeds.len() >= 8);
    let mut slopes = Vec::new();
    for &speed_mmps in speeds {
        let v = speed_mmps * 1e-3;
        let idx: Vec<usize> = (0..c.len()).filter(|&i| commanded[i] == v).collect();
        assert_eq!(idx.len(), 40);
        let x: Vec<f64> = idx.iter().map(|&i| pressure[i]).collect();
        let y: Vec<f64> = idx.iter().map(|&i| friction[i]).collect();
        let (w, m, _) = fit_line(&x, &y);
        assert!(
            (w - law.slope(v)).abs() < 0.01,
            "v={v}: w {w} vs {}",
            law.slope(v)
        );
        assert!(
            (m - law.intercept_n(v)).abs() < 0.05,
            "v={v}: m {m} vs {}",
            law.intercept_n(v)
        );
        slopes.push(w);
    }
    // Not monotonic in speed: it falls (Stribeck) before it rises.
    assert!(
        slopes[1] < slopes[0] && slopes[speeds.len() - 1] > slopes[1] + 0.1,
        "{slopes:?}"
    );
    // Held-out speeds are none of the training speeds.
    let test = li_bi::soft_contact_speeds_mmps(Split::Test);
    assert!(test.iter().all(|s| !speeds.contains(s)) && test.len() * 40 >= 320);
}

#[test]
fn needle_force_drops_at_the_truth_puncture_depth() {
    for split in [Split::Train, Split::Test] {
        let c = li_bi::needle_insertion(1, split).unwrap();
        assert!(c.len() >= 350);
        assert_eq!(c.metadata().kind(), CaptureKind::Insertion);
        let depth = c.column("depth_m").unwrap();
        let force = c.column("axial_force_n").unwrap();
        let time = c.time();
        let speeds = li_bi::needle_speeds_mmps(split);
        assert!(speeds.iter().any(|&s| s >= 10.0) || split == Split::Test);
        assert!(depth.iter().copied().fold(f64::MIN, f64::max) >= 0.0299);
        for k in 0..speeds.len() {
            let start = truth(&c, &format!("insertion.{k}.start_s"));
            let end = if k + 1 < speeds.len() {
                truth(&c, &format!("insertion.{}.start_s", k + 1))
            } else {
                f64::MAX
            };
            let punctures: Vec<f64> = c
                .metadata()
                .get(&format!("truth.insertion.{k}.puncture_depths_m"))
                .unwrap()
                .split(';')
                .map(|s| s.parse().unwrap())
                .collect();
            assert_eq!(punctures.len(), 2, "capsule and vessel wall");
            let window: Vec<usize> = (0..c.len())
                .filter(|&i| time[i] >= start && time[i] < end)
                .collect();
            // The largest sample-to-sample fall while inserting is the capsule puncture, at the
            // truth depth within one logging interval (plus the encoder quantum).
            let (at, fall) = window
                .windows(2)
                .map(|w| (depth[w[1]], force[w[0]] - force[w[1]]))
                .filter(|&(_, f)| f.is_finite())
                .fold((0.0, f64::MIN), |best, x| if x.1 > best.1 { x } else { best });
            let step = speeds[k] * 1e-3 * 0.01;
            assert!(
                (at - punctures[0]).abs() <= step + 2e-6,
                "insertion {k}: drop at {at}, truth {}",
                punctures[0]
            );
            assert!(fall > 0.8, "insertion {k}: drop only {fall} N");
            let peak = window.iter().map(|&i| force[i]).fold(f64::MIN, f64::max);
            assert!((1.0..=3.0).contains(&peak), "peak {peak}");
            // Withdrawal: friction only, so the force pulls the needle in (negative).
            let withdrawing: Vec<f64> = window
                .iter()
                .filter(|&&i| c.column("commanded_velocity_mps").unwrap()[i] < -0.009 && depth[i] > 0.005)
                .map(|&i| force[i])
                .collect();
            assert!(!withdrawing.is_empty() && withdrawing.iter().all(|&f| f < 0.0));
        }
    }
}

/// Mean absolute roughness (height minus a 2 mm moving average, a simple high-pass), and the
/// friction's mean and variance, over the whole run.
fn rubbing_features(c: &Capture) -> (f64, f64, f64) {
    let z = c.column("normal_position_m").unwrap();
    let f = c.column("friction_force_n").unwrap();
    let half = 200; // 2 mm at 5 mm/s and 1 kHz, each side
    let start = 400; // skip the speed ramp
    let n = z.len();
    let rough: Vec<f64> = (start + half..n - half)
        .map(|i| z[i] - z[i - half..=i + half].iter().sum::<f64>() / (2 * half + 1) as f64)
        .collect();
    let mean_abs = rough.iter().map(|r| r.abs()).sum::<f64>() / rough.len() as f64;
    let fr = &f[start..];
    let mean = fr.iter().sum::<f64>() / fr.len() as f64;
    let var = fr.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / fr.len() as f64;
    (mean_abs, mean, var)
}

#[test]
fn nakano_surfaces_differ_as_designed() {
    let surfaces = nakano_surfaces();
    let mut features = Vec::new();
    for s in &surfaces {
        let patch = SurfacePatch::new(s);
        let runs: Vec<(f64, f64, f64)> = (0..nakano::RUNS)
            .map(|run| rubbing_features(&nakano::rubbing_run(&patch, run, 1).unwrap()))
            .collect();
        for (_, friction_mean, _) in &runs {
            assert!(
                (friction_mean / nakano::NORMAL_FORCE_N - s.friction_coefficient).abs() < 0.06,
                "{}",
                s.name
            );
        }
        features.push(runs);
    }
    let roughness = |i: usize| features[i].iter().map(|r| r.0).sum::<f64>() / 3.0;
    let friction = |i: usize| features[i].iter().map(|r| r.1).sum::<f64>() / 3.0;
    // Sandpapers 1-4: coarser grit, rougher. Styrol: rough > semi-rough > smooth.
    assert!(roughness(0) > roughness(1) && roughness(1) > roughness(2) && roughness(2) > roughness(3));
    assert!(roughness(6) > roughness(5) && roughness(5) > roughness(4));
    // #400 and smooth styrol: roughness within 30 % of each other, yet every run's friction
    // mean keeps them apart.
    assert!(
        (roughness(3) / roughness(4) - 1.0).abs() < 0.3,
        "{} {}",
        roughness(3),
        roughness(4)
    );
    let max_smooth = features[4].iter().map(|r| r.1).fold(f64::MIN, f64::max);
    let min_400 = features[3].iter().map(|r| r.1).fold(f64::MAX, f64::min);
    assert!(min_400 > max_smooth, "{min_400} {max_smooth}");
    assert!(friction(0) > friction(3));
    // Rough surfaces make friction vary more.
    assert!(features[0][0].2 > features[3][0].2 && features[6][0].2 > features[4][0].2);
}

#[test]
fn nakano_runs_follow_the_thesis_commands() {
    let patch = SurfacePatch::new(&nakano_surfaces()[0]);
    let c = nakano::rubbing_run(&patch, 1, 1).unwrap();
    assert_eq!(c.metadata().rate_hz(), 1000.0);
    assert_eq!(c.metadata().get("role"), Some("test"));
    let x = c.column("tangential_position_m").unwrap();
    let t = c.time();
    // 5 mm/s once up to speed, over the 30 mm stroke.
    let (i, j) = (1000, c.len() - 1);
    let speed = (x[j] - x[i]) / (t[j] - t[i]);
    assert!((speed - 0.005).abs() < 1e-4, "{speed}");
    assert!((x[j] - nakano::STROKE_M).abs() < 1e-4);
    let normal = c.column("normal_force_n").unwrap();
    let mean = normal.iter().sum::<f64>() / normal.len() as f64;
    assert!((mean - 0.3).abs() < 0.005);
    // Heights are encoder counts of 0.01 mm.
    assert!(
        c.column("normal_position_m")
            .unwrap()
            .iter()
            .all(|z| ((z * 1e5).round() - z * 1e5).abs() < 1e-6)
    );
}

#[test]
fn nakano_runs_at_another_speed_cover_the_same_stroke() {
    let patch = SurfacePatch::new(&nakano_surfaces()[2]);
    let thesis = nakano::rubbing_run(&patch, 1, 1).unwrap();
    assert_eq!(
        nakano::rubbing_run_at(&patch, 1, 1, nakano::SPEED_MPS).unwrap(),
        thesis
    );
    for speed_mps in [0.002, 0.02] {
        let c = nakano::rubbing_run_at(&patch, 1, 1, speed_mps).unwrap();
        assert_eq!(
            c.metadata().get("command.speed_mps"),
            Some(speed_mps.to_string().as_str())
        );
        let (x, t) = (c.column("tangential_position_m").unwrap(), c.time());
        // Up to speed after the 0.2 s ramp; the stroke's length whatever the speed.
        let (i, j) = (300, c.len() - 1);
        let speed = (x[j] - x[i]) / (t[j] - t[i]);
        assert!((speed / speed_mps - 1.0).abs() < 0.02, "{speed} at {speed_mps}");
        assert!((x[j] - nakano::STROKE_M).abs() < 1e-4, "{}", x[j]);
        let expected_s = nakano::STROKE_M / speed_mps + 0.1;
        assert!((t[j] - expected_s).abs() < 2e-3, "{} vs {expected_s}", t[j]);
    }
    for bad in [0.0, -0.005, f64::NAN, f64::INFINITY] {
        let err = nakano::rubbing_run_at(&patch, 1, 1, bad).unwrap_err();
        assert!(err.to_string().contains("command.speed_mps"), "{err}");
    }
}

/// A two-patch stroke: the first surface's friction up to the seam halfway, the second's after
/// it, and metadata that say which and when, as a recognizer's evaluation reads them.
#[test]
fn a_two_patch_stroke_changes_surface_at_the_seam() {
    let surfaces = nakano_surfaces();
    // Sandpaper #80 (μ 0.60) onto smooth styrol (μ 0.42).
    let (first, second) = (SurfacePatch::new(&surfaces[0]), SurfacePatch::new(&surfaces[4]));
    let c = nakano::two_patch_run(&first, &second, 1, 1, nakano::SPEED_MPS).unwrap();
    let meta = c.metadata();
    assert_eq!(meta.get("surface"), Some("sandpaper_80"));
    assert_eq!(meta.get(recognize::SURFACE_AFTER_KEY), Some("styrol_smooth"));
    let change_s: f64 = meta
        .get(recognize::SURFACE_CHANGE_S_KEY)
        .unwrap()
        .parse()
        .unwrap();
    let (x, t) = (c.column("tangential_position_m").unwrap(), c.time());
    let at = t.iter().position(|&ti| ti >= change_s).unwrap();
    // The commanded position crosses 15 mm there (the encoder reads it to 0.01 mm).
    assert!((x[at] - nakano::TWO_PATCH_CHANGE_M).abs() < 2e-5, "{}", x[at]);
    assert!((change_s - (nakano::TWO_PATCH_CHANGE_M / nakano::SPEED_MPS + 0.1)).abs() < 2e-3);
    // Friction per unit normal force, away from the seam (the observer's low-pass settles in
    // a tenth of a second).
    let f = c.column("friction_force_n").unwrap();
    let mean = |r: std::ops::Range<usize>| {
        f[r.clone()].iter().sum::<f64>() / r.len() as f64 / nakano::NORMAL_FORCE_N
    };
    let (before, after) = (mean(at - 2000..at - 200), mean(at + 200..c.len()));
    assert!(
        (before - 0.60).abs() < 0.06 && (after - 0.42).abs() < 0.06,
        "{before} {after}"
    );
    // Its own noise: not the single-surface run's.
    let single = nakano::rubbing_run(&first, 1, 1).unwrap();
    assert_eq!(single.metadata().get(recognize::SURFACE_AFTER_KEY), None);
    assert_ne!(
        c.column("normal_force_n").unwrap()[..100],
        single.column("normal_force_n").unwrap()[..100]
    );
}

/// A faster two-patch stroke rubs its second patch as long as one at the thesis's speed does,
/// so that the time to follow the change is measured over the same span at every speed; a
/// slower one keeps the half stroke.
#[test]
fn a_two_patch_stroke_rubs_its_second_patch_long_enough_at_any_speed() {
    let surfaces = nakano_surfaces();
    let (first, second) = (SurfacePatch::new(&surfaces[1]), SurfacePatch::new(&surfaces[6]));
    for speed_mps in [0.002, nakano::SPEED_MPS, 0.02] {
        let c = nakano::two_patch_run(&first, &second, 2, 1, speed_mps).unwrap();
        let change_s: f64 = c
            .metadata()
            .get(recognize::SURFACE_CHANGE_S_KEY)
            .unwrap()
            .parse()
            .unwrap();
        let after_s = c.time().last().unwrap() - change_s;
        let half_stroke_s = (nakano::STROKE_M - nakano::TWO_PATCH_CHANGE_M) / speed_mps;
        let expected_s = half_stroke_s.max(nakano::TWO_PATCH_AFTER_S);
        assert!(
            (after_s - expected_s).abs() < 5e-3,
            "{speed_mps} m/s: {after_s} s after the seam"
        );
        assert!(after_s >= 3.0 - 5e-3, "{speed_mps} m/s: {after_s} s");
    }
}

#[test]
fn same_seed_same_bytes_other_seed_other_noise() {
    let a = tempfile::tempdir().unwrap();
    let b = tempfile::tempdir().unwrap();
    let c = tempfile::tempdir().unwrap();
    let sets = [CaptureSet::LiBi];
    let first = generate(a.path(), 7, &sets, &mut |_| {}).unwrap();
    generate(b.path(), 7, &sets, &mut |_| {}).unwrap();
    generate(c.path(), 8, &sets, &mut |_| {}).unwrap();
    assert_eq!(first.files.len(), 6);
    for g in &first.files {
        let x = std::fs::read(a.path().join(&g.path)).unwrap();
        assert_eq!(
            x,
            std::fs::read(b.path().join(&g.path)).unwrap(),
            "{}",
            g.path.display()
        );
        assert_ne!(
            x,
            std::fs::read(c.path().join(&g.path)).unwrap(),
            "{}",
            g.path.display()
        );
        // Written files read back as captures of the right kind.
        let kind = if g.protocol == "li_bi_needle" {
            CaptureKind::Insertion
        } else {
            CaptureKind::Rubbing
        };
        assert_eq!(
            Capture::read_file(a.path().join(&g.path), kind).unwrap().len(),
            g.rows
        );
    }
    let manifest = std::fs::read_to_string(a.path().join("MANIFEST.csv")).unwrap();
    assert_eq!(manifest.lines().count(), 7);
    assert!(manifest.contains("li_bi/needle_test.csv,li_bi_needle,bovine_liver,test,"));
}

/// RMS deviation of |a| from its 100-sample moving average (the first step of Sinapov's
/// features).
fn vibration_level(c: &Capture) -> f64 {
    let [x, y, z] = ["accel_x_mps2", "accel_y_mps2", "accel_z_mps2"].map(|k| c.column(k).unwrap());
    let m: Vec<f64> = (0..c.len())
        .map(|i| (x[i] * x[i] + y[i] * y[i] + z[i] * z[i]).sqrt())
        .collect();
    let dev: Vec<f64> = (100..m.len())
        .map(|i| m[i] - m[i - 100..i].iter().sum::<f64>() / 100.0)
        .collect();
    (dev.iter().map(|d| d * d).sum::<f64>() / dev.len() as f64).sqrt()
}

#[test]
fn sinapov_captures_are_labelled_accelerometer_recordings() {
    use sim::sinapov;
    use sim::{Behaviour, household_surfaces};
    let surfaces = household_surfaces();
    assert_eq!(surfaces.len(), 21);
    let by_name = |n: &str| surfaces.iter().find(|s| s.name == n).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let mut levels = Vec::new();
    for name in ["corduroy", "air"] {
        let c = sinapov::scratch_capture(by_name(name), Behaviour::MedialFast, 3, 5).unwrap();
        let path = dir.path().join(format!("{name}.csv"));
        c.write_file(&path).unwrap();
        let c = Capture::read_file(&path, CaptureKind::Rubbing).unwrap();
        let meta = c.metadata();
        assert_eq!(meta.rate_hz(), 400.0);
        assert_eq!(meta.get("surface"), Some(name));
        assert_eq!(meta.get("behaviour"), Some("medial_fast"));
        assert_eq!(meta.get("trial"), Some("3"));
        assert!(meta.get("truth.speed_mps").is_some());
        // About Table I's 4.6 s, give or take the trial's ±5 % speed.
        assert!((c.len() as f64 / 400.0 / 4.6 - 1.0).abs() < 0.06, "{}", c.len());
        levels.push(vibration_level(&c));
    }
    assert!(levels[0] > 5.0 * levels[1], "{levels:?}");
    assert_eq!(sinapov::TRIALS, 10);
    assert_eq!(Behaviour::ALL.len(), 5);
}
