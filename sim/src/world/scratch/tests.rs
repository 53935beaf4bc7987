use std::f64::consts::{PI, TAU};

use super::simulate::{ShearContact, rotation};
use super::stroke::Stroke;
use super::*;
use crate::world::profile::Band;

/// Sinapov Sec. IV-A: |a| minus its 100-sample moving average (centred, shortened at the ends).
fn magnitude_deviation(rec: &ScratchRecording) -> Vec<f64> {
    let [x, y, z] = &rec.accel_mps2;
    let m: Vec<f64> = x
        .iter()
        .zip(y)
        .zip(z)
        .map(|((a, b), c)| (a * a + b * b + c * c).sqrt())
        .collect();
    let mut prefix = vec![0.0; m.len() + 1];
    for (i, v) in m.iter().enumerate() {
        prefix[i + 1] = prefix[i] + v;
    }
    (0..m.len())
        .map(|i| {
            let lo = i.saturating_sub(50);
            let hi = (i + 50).min(m.len());
            m[i] - (prefix[hi] - prefix[lo]) / (hi - lo) as f64
        })
        .collect()
}

fn energy(d: &[f64]) -> f64 {
    d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64
}

/// Welch power spectrum of `d`: 256-sample Hann windows, hop 128, 129 bins (1.5625 Hz apart).
fn psd(d: &[f64]) -> Vec<f64> {
    const N: usize = 256;
    let fft = fft::forward_plan(N);
    let mut input = fft.make_input_vec();
    let mut output = fft.make_output_vec();
    let window: Vec<f64> = (0..N)
        .map(|i| 0.5 - 0.5 * (TAU * i as f64 / N as f64).cos())
        .collect();
    let mut power = vec![0.0; N / 2 + 1];
    let mut count = 0;
    let mut start = 0;
    while start + N <= d.len() {
        for (i, x) in input.iter_mut().enumerate() {
            *x = d[start + i] * window[i];
        }
        fft.process(&mut input, &mut output).unwrap();
        for (p, c) in power.iter_mut().zip(&output) {
            *p += c.norm_sqr();
        }
        count += 1;
        start += N / 2;
    }
    power.iter_mut().for_each(|p| *p /= count.max(1) as f64);
    power
}

const BIN_HZ: f64 = ACCEL_RATE_HZ / 256.0;

/// 25 equal bands of 5 bins over bins 3..128 (4.7–200 Hz), log10 power.
fn log_bands(power: &[f64]) -> Vec<f64> {
    (0..25)
        .map(|b| (power[3 + 5 * b..8 + 5 * b].iter().sum::<f64>() / 5.0 + 1e-9).log10())
        .collect()
}

fn feature(rec: &ScratchRecording) -> Vec<f64> {
    log_bands(&psd(&magnitude_deviation(rec)))
}

fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>().sqrt()
}

fn mean_of(features: &[Vec<f64>]) -> Vec<f64> {
    let n = features.len() as f64;
    (0..features[0].len())
        .map(|i| features.iter().map(|f| f[i]).sum::<f64>() / n)
        .collect()
}

/// Frequency of the largest bin between 4 and 200 Hz.
fn dominant_hz(power: &[f64]) -> f64 {
    let (i, _) = power.iter().enumerate().skip(3).fold(
        (0, f64::MIN),
        |best, (i, &p)| if p > best.1 { (i, p) } else { best },
    );
    i as f64 * BIN_HZ
}

fn surface(name: &str) -> ScratchSurface {
    household_surfaces().into_iter().find(|s| s.name == name).unwrap()
}

fn truth<'a>(rec: &'a ScratchRecording, key: &str) -> &'a str {
    let key = format!("truth.{key}");
    rec.truth
        .iter()
        .find(|(k, _)| *k == key)
        .map(|(_, v)| v.as_str())
        .unwrap()
}

fn truth_f64(rec: &ScratchRecording, key: &str) -> f64 {
    truth(rec, key).parse().unwrap()
}

/// Average PSD of the magnitude deviation over several trials.
fn mean_psd(s: &ScratchSurface, b: Behaviour, trials: std::ops::Range<u32>, seed: u64) -> Vec<f64> {
    let psds: Vec<Vec<f64>> = trials
        .map(|t| psd(&magnitude_deviation(&scratch_trial(s, b, t, seed))))
        .collect();
    mean_of(&psds)
}

/// Power-weighted mean frequency between 4.7 and 200 Hz.
fn centroid_hz(power: &[f64]) -> f64 {
    let band = &power[3..];
    let total: f64 = band.iter().sum();
    band.iter()
        .enumerate()
        .map(|(i, p)| (i + 3) as f64 * BIN_HZ * p)
        .sum::<f64>()
        / total
}

#[test]
fn the_table_has_sinapovs_surfaces_in_order_with_physical_parameters() {
    let surfaces = household_surfaces();
    let names: Vec<&str> = surfaces.iter().map(|s| s.name).collect();
    assert_eq!(
        names,
        [
            "thick_floor_mat",
            "thin_blue_mat",
            "soft_cloth",
            "leather_with_bumps",
            "thin_floor_mat",
            "bulletin_board",
            "corduroy",
            "leather_flat",
            "plastic_kitchen_mat",
            "table",
            "bed_sheet",
            "corduroy_back",
            "thin_floor_mat_back",
            "sparkly_cloth",
            "cotton_wool",
            "plastic_pattern",
            "paper_white",
            "paper_yellow",
            "bubble_wrap",
            "wood",
            "air",
        ]
    );
    assert_eq!(
        surfaces.iter().map(|s| s.id).collect::<Vec<_>>(),
        (1..=21).collect::<Vec<_>>()
    );
    assert!(surfaces[20].is_air() && surfaces[20].nominal_force_n() == 0.0);
    for s in &surfaces[..20] {
        let c = s.contact.as_ref().unwrap();
        assert!(
            (2.0..=4.0).contains(&s.nominal_force_n()),
            "{}: {}",
            s.name,
            s.nominal_force_n()
        );
        assert!((40.0..=250.0).contains(&c.normal_mode_hz), "{}", s.name);
        assert!((0.05..=0.7).contains(&c.damping_ratio), "{}", s.name);
        assert!(
            (0.2..=1.0).contains(&c.friction) && (0.0..=0.2).contains(&c.stick_slip),
            "{}",
            s.name
        );
        assert!((0.1e-3..=1e-3).contains(&c.contact_width_m), "{}", s.name);
        // Relief: three turning bands of roughness, one layer per texture, three envelope bands.
        assert_eq!(s.relief.layers.len(), 3 + c.textures.len() + 3, "{}", s.name);
    }
    // Two builds are the same world.
    assert!(household_surfaces()[6].relief == surfaces[6].relief);
}

#[test]
fn same_arguments_give_the_same_recording_and_anything_else_changes_it() {
    let a = surface("leather_with_bumps");
    let b = household_surfaces().swap_remove(3);
    let first = scratch_trial(&a, Behaviour::MedialFast, 3, 11);
    assert_eq!(first, scratch_trial(&b, Behaviour::MedialFast, 3, 11));
    for other in [
        scratch_trial(&a, Behaviour::MedialFast, 4, 11),
        scratch_trial(&a, Behaviour::MedialFast, 3, 12),
        scratch_trial(&a, Behaviour::MedialMedium, 3, 11),
    ] {
        let differing = first.accel_mps2[2]
            .iter()
            .zip(&other.accel_mps2[2])
            .filter(|(x, y)| x != y)
            .count();
        assert!(
            differing > first.time_s.len().min(other.time_s.len()) / 2,
            "{differing}"
        );
    }
}

#[test]
fn the_placement_is_shared_by_the_five_behaviours_of_a_round() {
    // Sinapov Sec. III-E: the surface was swapped only after all five behaviours, so the lateral
    // strokes of one round scratch the same strip, and the next round another one.
    let s = surface("bed_sheet");
    let start = |b, t| {
        let rec = scratch_trial(&s, b, t, 5);
        [
            truth_f64(&rec, "start_x_m"),
            truth_f64(&rec, "start_y_m"),
            truth_f64(&rec, "placement_rotation_rad"),
        ]
    };
    let fast = start(Behaviour::LateralFast, 2);
    let slow = start(Behaviour::LateralSlow, 2);
    let next = start(Behaviour::LateralFast, 3);
    assert!(
        (fast[0] - slow[0]).hypot(fast[1] - slow[1]) < 6e-3,
        "{fast:?} {slow:?}"
    );
    assert_eq!(fast[2], slow[2]);
    assert!(
        (fast[0] - next[0]).hypot(fast[1] - next[1]) > 6e-3,
        "{fast:?} {next:?}"
    );
}

#[test]
fn time_base_lengths_and_quantization_follow_the_sensor_and_the_arm() {
    for name in ["corduroy", "bubble_wrap", "air"] {
        let s = surface(name);
        for b in Behaviour::ALL {
            let rec = scratch_trial(&s, b, 1, 3);
            let n = rec.time_s.len();
            let duration = truth_f64(&rec, "duration_s");
            // ±5 % speed around Table I.
            assert!(
                (duration / b.duration_s() - 1.0).abs() < 0.053,
                "{name} {}: {duration}",
                b.name()
            );
            assert_eq!(n, (duration * 400.0).floor() as usize + 1);
            assert!(rec.time_s.iter().enumerate().all(|(k, &t)| t == k as f64 / 400.0));
            assert!(
                [&rec.tangential_position_m, &rec.normal_force_n]
                    .iter()
                    .all(|c| c.len() == n)
            );
            assert!(rec.accel_mps2.iter().all(|c| c.len() == n));

            // The stroke: from 0 to 12 inches, never backwards, on the 10 µm encoder grid.
            let pos = &rec.tangential_position_m;
            assert_eq!(pos[0], 0.0);
            assert!((pos[n - 1] - STROKE_M).abs() < 1e-4, "{}", pos[n - 1]);
            assert!(pos.windows(2).all(|w| w[1] >= w[0]));
            assert!(pos.iter().all(|p| (p * 1e5 - (p * 1e5).round()).abs() < 1e-6));
            // In the middle the speed is the plateau speed the truth reports.
            let speed = truth_f64(&rec, "speed_mps");
            let (i, j) = (n / 4, 3 * n / 4);
            let measured = (pos[j] - pos[i]) / (rec.time_s[j] - rec.time_s[i]);
            assert!((measured / speed - 1.0).abs() < 0.01, "{measured} {speed}");
            let ramp = truth_f64(&rec, "ramp_s");
            assert!((speed * (duration - ramp) - STROKE_M).abs() < 1e-7);

            // Every reading is a 10-bit code at 7.8125 mg/LSB, inside ±4 g.
            for axis in &rec.accel_mps2 {
                for &a in axis {
                    let code = (a / Adxl345::LSB_MPS2).round();
                    assert!((a - code * Adxl345::LSB_MPS2).abs() <= 0.5e-4 + 1e-12, "{a}");
                    assert!((-512.0..=511.0).contains(&code), "{a}");
                }
            }
            // Gravity is in the readings: at rest, before the stroke gets going, each axis reads
            // the nail's orientation (from the truth, with the pitch drift at the start) through
            // this part's gain and offset errors.
            let pitch = truth_f64(&rec, "nail_pitch_rad") - 0.5 * truth_f64(&rec, "nail_pitch_drift_rad");
            let r = rotation(
                truth_f64(&rec, "nail_roll_rad"),
                pitch,
                truth_f64(&rec, "nail_yaw_rad"),
            );
            for (axis, column) in rec.accel_mps2.iter().enumerate() {
                let expected = r[2][axis] * STANDARD_GRAVITY_MPS2 * (1.0 + Adxl345::GAIN_ERROR[axis])
                    + Adxl345::OFFSET_G[axis] * STANDARD_GRAVITY_MPS2;
                // First 20 ms: the ramp's own acceleration is still below 0.07 m/s² there.
                let rest = column[..8].iter().sum::<f64>() / 8.0;
                assert!(
                    (rest - expected).abs() < 0.1,
                    "{name} axis {axis}: {rest} vs {expected}"
                );
            }
            // Vibration during the stroke only adds to |a| (by |a⊥|²/2g to first order).
            assert!(magnitude_mean(&rec, n) >= 0.99 * magnitude_mean(&rec, 20));

            // Contact force: zero in air, else around the trial's nominal force, never negative,
            // on the 1e-4 N grid.
            let f = &rec.normal_force_n;
            assert!(
                f.iter()
                    .all(|&x| x >= 0.0 && (x * 1e4 - (x * 1e4).round()).abs() < 1e-6)
            );
            let mean_f = f.iter().sum::<f64>() / n as f64;
            if s.is_air() {
                assert!(f.iter().all(|&x| x == 0.0));
            } else {
                let nominal = truth_f64(&rec, "normal_force_n");
                assert!((nominal / s.nominal_force_n() - 1.0).abs() <= 0.15 + 1e-9);
                assert!((mean_f / nominal - 1.0).abs() < 0.08, "{mean_f} {nominal}");
            }
        }
    }
}

/// Mean |a| over the first `n` samples.
fn magnitude_mean(rec: &ScratchRecording, n: usize) -> f64 {
    let [x, y, z] = &rec.accel_mps2;
    let n = n.min(x.len());
    x.iter()
        .zip(y)
        .zip(z)
        .take(n)
        .map(|((a, b), c)| (a * a + b * b + c * c).sqrt())
        .sum::<f64>()
        / n as f64
}

#[test]
fn stroke_ramps_are_smooth_and_the_plateau_covers_the_rest() {
    let stroke = Stroke::new(STROKE_M, 3.9);
    assert_eq!(stroke.ramp_s, RAMP_S);
    assert!((stroke.speed_mps - STROKE_M / (3.9 - RAMP_S)).abs() < 1e-15);
    assert_eq!(stroke.at(0.0), (0.0, 0.0, 0.0));
    let (s_end, v_end, _) = stroke.at(3.9);
    assert!((s_end - STROKE_M).abs() < 1e-12 && v_end.abs() < 1e-12);
    // Continuous position, speed and acceleration across both ramp joints.
    for t in [RAMP_S, 3.9 - RAMP_S] {
        let (a, b) = (stroke.at(t - 1e-9), stroke.at(t + 1e-9));
        assert!(
            (a.0 - b.0).abs() < 1e-9 && (a.1 - b.1).abs() < 1e-6 && (a.2 - b.2).abs() < 1e-6,
            "{a:?} {b:?}"
        );
    }
    // Peak acceleration of a half-cosine ramp: π v / (2 T_ramp), at its middle.
    let (_, v, a) = stroke.at(RAMP_S / 2.0);
    assert!((v - stroke.speed_mps / 2.0).abs() < 1e-12);
    assert!((a - PI * stroke.speed_mps / (2.0 * RAMP_S)).abs() < 1e-12);
}

#[test]
fn stick_slip_period_is_two_delta_mu_f_over_k_v() {
    // Relaxation oscillation: the force climbs at k·w and drops by 2·Δμ·F at μ_s·F.
    let (k, w, f, mu, d_mu, dt) = (4000.0, 0.04, 3.0, 0.5, 0.05, 1.0 / SIM_RATE_HZ);
    let mut contact = ShearContact {
        stiffness_n_per_m: k,
        stretch_m: 0.0,
    };
    let mut previous = 0.0;
    let mut drops = Vec::new();
    for step in 0..80_000 {
        let force = contact.step(w, mu, d_mu, f, dt);
        assert!(force <= (mu + d_mu) * f + 1e-12);
        if force < previous - 0.1 {
            drops.push(step);
        }
        previous = force;
    }
    let period_s = (drops[drops.len() - 1] - drops[1]) as f64 * dt / (drops.len() - 2) as f64;
    let expected = 2.0 * d_mu * f / (k * w);
    assert!((period_s / expected - 1.0).abs() < 0.01, "{period_s} {expected}");
    // Without a static excess the contact slides at exactly μ_k·F.
    let mut smooth = ShearContact {
        stiffness_n_per_m: k,
        stretch_m: 0.0,
    };
    let last = (0..10_000)
        .map(|_| smooth.step(w, mu, 0.0, f, dt))
        .last()
        .unwrap();
    assert!((last - mu * f).abs() < 1e-12);
}

#[test]
fn air_is_much_quieter_than_every_surface_and_speed_raises_the_level() {
    let surfaces = household_surfaces();
    let level = |s: &ScratchSurface, b| {
        (0..2)
            .map(|t| energy(&magnitude_deviation(&scratch_trial(s, b, t, 21))))
            .sum::<f64>()
            / 2.0
    };
    for b in Behaviour::ALL {
        let air = level(&surfaces[20], b);
        // Air is the sensor's noise floor plus arm hum: 5-15 mg RMS.
        let air_mg = air.sqrt() / STANDARD_GRAVITY_MPS2 * 1e3;
        assert!((5.0..15.0).contains(&air_mg), "{}: {air_mg} mg", b.name());
        // Slow strokes on the smoothest surfaces are the closest to air, but still well above.
        let factor = if b == Behaviour::LateralSlow { 2.0 } else { 10.0 };
        for s in &surfaces[..20] {
            let e = level(s, b);
            assert!(e > factor * air, "{} {}: {e} vs air {air}", s.name, b.name());
        }
    }
    // Temporal frequency and amplitude both grow with speed: fast beats slow everywhere.
    for s in &surfaces[..20] {
        let (fast, slow) = (level(s, Behaviour::LateralFast), level(s, Behaviour::LateralSlow));
        assert!(fast > 4.0 * slow, "{}: {fast} vs {slow}", s.name);
    }
}

#[test]
fn faster_strokes_move_corduroys_rib_frequency_up() {
    let s = surface("corduroy");
    let mut centroids = Vec::new();
    for b in [
        Behaviour::LateralSlow,
        Behaviour::LateralMedium,
        Behaviour::LateralFast,
    ] {
        let p = mean_psd(&s, b, 0..3, 9);
        // The ribs (3 mm apart, crossed at ~7°) at the stroke's speed dominate the spectrum.
        let rec = scratch_trial(&s, b, 0, 9);
        let rib_m: f64 = truth(&rec, "texture_wavelength_along_stroke_m")
            .split(';')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        let expected = truth_f64(&rec, "speed_mps") / rib_m;
        let dominant = dominant_hz(&p);
        assert!(
            (dominant - expected).abs() < BIN_HZ + 0.08 * expected,
            "{}: {dominant} vs {expected}",
            b.name()
        );
        centroids.push(centroid_hz(&p));
    }
    assert!(
        centroids[0] < centroids[1] && centroids[1] < centroids[2],
        "{centroids:?}"
    );
}

#[test]
fn direction_matters_on_corduroy_but_not_on_isotropic_cotton_wool() {
    let distance_between_directions = |name: &str| {
        let s = surface(name);
        let lateral: Vec<Vec<f64>> = (0..4)
            .map(|t| feature(&scratch_trial(&s, Behaviour::LateralMedium, t, 4)))
            .collect();
        let medial: Vec<Vec<f64>> = (0..4)
            .map(|t| feature(&scratch_trial(&s, Behaviour::MedialMedium, t, 4)))
            .collect();
        let (cl, cm) = (mean_of(&lateral), mean_of(&medial));
        let spread = lateral.iter().map(|f| distance(f, &cl)).sum::<f64>() / 4.0;
        (distance(&cl, &cm), spread)
    };
    let (corduroy, corduroy_spread) = distance_between_directions("corduroy");
    let (cotton, cotton_spread) = distance_between_directions("cotton_wool");
    assert!(corduroy > 4.0 * corduroy_spread, "{corduroy} {corduroy_spread}");
    assert!(cotton < 2.0 * cotton_spread, "{cotton} {cotton_spread}");
    assert!(corduroy > 3.0 * cotton, "{corduroy} {cotton}");
    // Lateral strokes cross the ribs: a strong line at speed / 3 mm; medial ones run along them.
    let s = surface("corduroy");
    let (lat, med) = (
        mean_psd(&s, Behaviour::LateralMedium, 0..3, 4),
        mean_psd(&s, Behaviour::MedialMedium, 0..3, 4),
    );
    let rib = (0.0426 / 3.02e-3 / BIN_HZ).round() as usize;
    let line = |p: &[f64]| p[rib - 1..=rib + 1].iter().sum::<f64>();
    assert!(line(&lat) > 10.0 * line(&med), "{} {}", line(&lat), line(&med));
}

#[test]
fn texture_above_the_nyquist_frequency_aliases_as_in_the_real_sensor() {
    // A hard surface with one fine, almost periodic texture that the fast lateral stroke meets
    // at ~300 Hz: with no anti-aliasing filter it shows up at 400 − 300 ≈ 100 Hz.
    let contact = Contact {
        roughness: Band {
            rms_m: 0.0,
            wavelength_m: 1e-3,
            log_width: 1.0,
        },
        textures: vec![Texture {
            band: Band {
                rms_m: 0.3e-6,
                wavelength_m: 0.29e-3,
                log_width: 0.01,
            },
            orientation_rad: 0.0,
        }],
        thickness_m: 0.0,
        normal_mode_hz: 400.0,
        damping_ratio: 0.1,
        friction: 0.3,
        stick_slip: 0.0,
        friction_variation: 0.0,
        contact_width_m: 0.05e-3,
        placement_variation: 0.0,
        patchiness: 0.0,
        shear_stiffness_n_per_m: 1e4,
    };
    let s = ScratchSurface::new(99, "fine_grating", Some(contact));
    for trial in 0..3 {
        let rec = scratch_trial(&s, Behaviour::LateralFast, trial, 1);
        let wavelength: f64 = truth(&rec, "texture_wavelength_along_stroke_m").parse().unwrap();
        let true_hz = truth_f64(&rec, "speed_mps") / wavelength;
        assert!(true_hz > 250.0 && true_hz < 350.0, "{true_hz}");
        let dominant = dominant_hz(&psd(&magnitude_deviation(&rec)));
        assert!(
            // Within the bin resolution and the texture's 1 % band.
            (dominant - (ACCEL_RATE_HZ - true_hz)).abs() < 1.5 * BIN_HZ + 0.01 * true_hz,
            "{dominant} vs {true_hz}"
        );
    }
}

#[test]
fn similar_surfaces_are_close_and_recognition_is_good_but_not_trivial() {
    // Sinapov's pipeline, simplified: the 25-band log spectrum of the magnitude deviation, and a
    // nearest-centroid classifier trained on trials 0-4 and tested on trials 5-9 (lateral fast).
    let surfaces = household_surfaces();
    let feats: Vec<Vec<Vec<f64>>> = surfaces
        .iter()
        .map(|s| {
            (0..10)
                .map(|t| feature(&scratch_trial(s, Behaviour::LateralFast, t, 7)))
                .collect()
        })
        .collect();
    let centroids: Vec<Vec<f64>> = feats.iter().map(|f| mean_of(&f[..5])).collect();
    let index = |name: &str| surfaces.iter().position(|s| s.name == name).unwrap();
    let d = |a: &str, b: &str| distance(&centroids[index(a)], &centroids[index(b)]);
    let nearest_other = |a: &str| {
        let i = index(a);
        (0..surfaces.len()).filter(|&j| j != i).min_by(|&x, &y| {
            distance(&centroids[i], &centroids[x]).total_cmp(&distance(&centroids[i], &centroids[y]))
        })
    };
    let spread = |a: &str| {
        feats[index(a)][..5]
            .iter()
            .map(|x| distance(x, &centroids[index(a)]))
            .sum::<f64>()
            / 5.0
    };

    let mut between: Vec<f64> = Vec::new();
    for i in 0..surfaces.len() {
        for j in i + 1..surfaces.len() {
            between.push(distance(&centroids[i], &centroids[j]));
        }
    }
    between.sort_by(f64::total_cmp);
    let median = between[between.len() / 2];

    // The papers are each other's nearest neighbours, much closer than paper and bubble wrap,
    // and barely further apart than two trials on one of them: similar, not trivially separable.
    assert_eq!(nearest_other("paper_white"), Some(index("paper_yellow")));
    assert_eq!(nearest_other("paper_yellow"), Some(index("paper_white")));
    assert!(d("paper_white", "paper_yellow") < 0.25 * d("paper_white", "bubble_wrap"));
    assert!(d("paper_white", "paper_yellow") < 3.0 * spread("paper_white").max(spread("paper_yellow")));
    // The other pairs built alike (the two doormats; two soft fibrous cloths) are close too.
    for (a, b) in [
        ("thin_floor_mat", "thick_floor_mat"),
        ("cotton_wool", "soft_cloth"),
    ] {
        assert!(d(a, b) < 0.4 * median, "{a} {b}: {} vs median {median}", d(a, b));
    }

    // Within-surface scatter is small next to the distance to other surfaces for most of them.
    let compact = surfaces.iter().filter(|s| spread(s.name) < median / 3.0).count();
    assert!(compact >= 18, "{compact}");

    let mut correct = 0;
    for (i, f) in feats.iter().enumerate() {
        for x in &f[5..] {
            let best = (0..centroids.len())
                .min_by(|&a, &b| distance(x, &centroids[a]).total_cmp(&distance(x, &centroids[b])));
            correct += usize::from(best == Some(i));
        }
    }
    let accuracy = correct as f64 / 105.0;
    assert!(accuracy >= 0.8, "{accuracy}");
}

#[test]
fn truth_describes_the_trial_without_whitespace() {
    let s = surface("wood");
    let rec = scratch_trial(&s, Behaviour::MedialMedium, 7, 99);
    assert!(
        rec.truth
            .iter()
            .all(|(k, v)| k.starts_with("truth.") && !v.is_empty() && !v.contains(char::is_whitespace))
    );
    let keys: std::collections::HashSet<&str> = rec.truth.iter().map(|(k, _)| k.as_str()).collect();
    assert_eq!(keys.len(), rec.truth.len(), "duplicate keys");
    // A surface without textures says so rather than leaving the value empty.
    let cotton = scratch_trial(&surface("cotton_wool"), Behaviour::LateralFast, 0, 99);
    assert_eq!(truth(&cotton, "texture_rms_m"), "none");
    assert_eq!(truth(&rec, "contact"), "true");
    assert!((truth_f64(&rec, "direction_rad") - FRAC_PI_2).abs() < 0.05);
    assert!((truth_f64(&rec, "speed_mps") - 0.305 / (7.9 - RAMP_S)).abs() < 0.06 * 0.305 / 7.9);
    // Wood grain runs left to right, so medial strokes cross it at about its 1.2 mm pitch.
    let along: f64 = truth(&rec, "texture_wavelength_along_stroke_m").parse().unwrap();
    assert!((along / 1.2e-3 - 1.0).abs() < 0.01, "{along}");
    let air = scratch_trial(&surface("air"), Behaviour::LateralFast, 0, 99);
    assert_eq!(truth(&air, "contact"), "false");
    assert_eq!(truth_f64(&air, "normal_force_n"), 0.0);
}

#[test]
fn edited_parameters_are_honoured_even_though_the_relief_is_cached() {
    let original = surface("corduroy");
    let mut edited = original.clone();
    if let Some(c) = edited.contact.as_mut() {
        c.textures.clear();
    }
    let fresh = ScratchSurface::new(original.id, original.name, edited.contact.clone());
    let from_edited = scratch_trial(&edited, Behaviour::LateralFast, 0, 2);
    assert_eq!(from_edited, scratch_trial(&fresh, Behaviour::LateralFast, 0, 2));
    assert_ne!(
        from_edited,
        scratch_trial(&original, Behaviour::LateralFast, 0, 2)
    );
    // Without its ribs corduroy is much quieter.
    let level = |r: &ScratchRecording| energy(&magnitude_deviation(r));
    assert!(level(&from_edited) < 0.3 * level(&scratch_trial(&original, Behaviour::LateralFast, 0, 2)));
}

#[test]
#[ignore = "reports the time of the whole set; run with --release -- --ignored --nocapture"]
fn all_1050_trials_have_the_protocol_sample_count() {
    let start = std::time::Instant::now();
    let surfaces = household_surfaces();
    let built = start.elapsed().as_secs_f64();
    let mut samples = 0;
    for s in &surfaces {
        for b in Behaviour::ALL {
            for t in 0..10 {
                samples += scratch_trial(s, b, t, 42).time_s.len();
            }
        }
    }
    let total = start.elapsed().as_secs_f64();
    println!("household_surfaces {built:.3} s; 1050 trials {total:.3} s; {samples} samples");
    // 21 surfaces × 10 trials × (3.9 + 7.5 + 14.7 + 4.6 + 7.9) s × 400 Hz, ±5 % speed.
    assert!((samples as f64 / 3_242_400.0 - 1.0).abs() < 0.02, "{samples}");
}
