//! `palpus capture` on the simulated Omega.7: each protocol's capture reads back as a valid
//! capture of its kind, with what the device measured and what its observers estimated
//! matching the world's ground truth.

#![allow(clippy::unwrap_used)]

use crate::common::run_unpaced;
use capture::Capture;
use haptics::acquire::{CaptureOptions, Protocol, controller, run_capture, sim_device};
use haptics::rt::Pacing;
use sim::HardContact;
use sim::NeedleTissue;
use sim::nakano_surfaces;

fn capture(protocol: Protocol) -> Capture {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(format!("{protocol}.csv"));
    let mut options = CaptureOptions::new(protocol);
    options.pacing = Pacing::Unpaced;
    let device = sim_device(&options).unwrap();
    let report = run_capture(Box::new(device), &path, &options, &mut |_| {}).unwrap();
    assert_eq!(report.recorder.rejected, 0);
    assert_eq!(report.stats.dropped_samples, 0);
    let c = Capture::read_file(&path, protocol.kind()).unwrap();
    assert_eq!(c.len() as u64, report.recorder.rows);
    assert_eq!(c.metadata().device(), "sim-omega7");
    assert_eq!(c.metadata().rate_hz(), 1000.0);
    c
}

fn col<'a>(c: &'a Capture, name: &str) -> &'a [f64] {
    c.column(name).unwrap()
}

#[test]
fn needle_capture_shows_each_puncture_at_the_truths_force() {
    let c = capture(Protocol::Needle);
    let depth = col(&c, "depth_m");
    let force = col(&c, "axial_force_n");
    let command = col(&c, "commanded_velocity_mps");
    // Encoder counts of 10 µm.
    assert!(depth.iter().all(|d| ((d * 1e5).round() - d * 1e5).abs() < 1e-6));
    assert!(depth.iter().copied().fold(f64::MIN, f64::max) > 0.024);
    // Split into insertions by the commanded speed; each peak is the capsule's puncture.
    let tissue = NeedleTissue::bovine_liver();
    for speed in [0.002, 0.005, 0.010] {
        let peak = command
            .iter()
            .zip(force)
            .filter(|(v, _)| (**v - speed).abs() < 1e-12)
            .map(|(_, f)| *f)
            .fold(f64::MIN, f64::max);
        let m = &tissue.membranes[0];
        let truth = m.puncture_force_at(speed) + m.damping_nspm * speed;
        println!("{speed} m/s: peak {peak:.3} N, truth {truth:.3} N");
        assert!((peak - truth).abs() < 0.25, "{speed}: {peak} vs {truth}");
    }
}

fn fit_line(x: &[f64], y: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    let slope = sxy / sxx;
    (slope, my - slope * mx)
}

#[test]
fn hard_contact_capture_recovers_the_friction_law() {
    let c = capture(Protocol::Hard);
    let v = col(&c, "tangential_velocity_mps");
    let keep: Vec<usize> = (0..c.len()).filter(|&i| v[i].abs() > 0.008).collect();
    let normal: Vec<f64> = keep.iter().map(|&i| col(&c, "normal_force_n")[i]).collect();
    let friction: Vec<f64> = keep.iter().map(|&i| col(&c, "friction_force_n")[i]).collect();
    let (slope, intercept) = fit_line(&normal, &friction);
    let law = HardContact::li_bi();
    println!(
        "hard: slope {slope:.4} (truth {:.4}), intercept {intercept:.4} N (truth {:.4})",
        law.slope, law.intercept_n
    );
    assert!((slope - law.slope).abs() < 0.02, "{slope}");
    assert!((intercept - law.intercept_n).abs() < 0.05, "{intercept}");
    let n_min = normal.iter().copied().fold(f64::MAX, f64::min);
    let n_max = normal.iter().copied().fold(f64::MIN, f64::max);
    assert!(n_min < 1.0 && n_max > 4.0, "{n_min} {n_max}");
}

#[test]
fn soft_and_rubbing_captures_measure_friction_against_load() {
    let c = capture(Protocol::Soft);
    let v = col(&c, "tangential_velocity_mps");
    assert!(v.iter().any(|v| v.abs() > 0.035), "the 40 mm/s stroke is missing");
    assert!(col(&c, "friction_force_n").iter().all(|f| f.is_finite()));

    let c = capture(Protocol::Rubbing);
    let normal = col(&c, "normal_force_n");
    let friction = col(&c, "friction_force_n");
    let v = col(&c, "tangential_velocity_mps");
    let steady: Vec<usize> = (0..c.len()).filter(|&i| (v[i] - 0.005).abs() < 0.002).collect();
    let mean = |xs: &[f64]| steady.iter().map(|&i| xs[i]).sum::<f64>() / steady.len() as f64;
    let mu = nakano_surfaces()[1].friction_coefficient;
    println!(
        "rubbing: normal {:.3} N, friction {:.3} N, ratio {:.3} (mu {mu})",
        mean(normal),
        mean(friction),
        mean(friction) / mean(normal)
    );
    assert!((mean(normal) - 0.3).abs() < 0.03);
    // At least Coulomb's μN; more, because a stiff tip climbing asperities presses harder on
    // the rising flanks (the world's F = N·(μ + h′) with N and h′ correlated), which the next
    // test checks the observer reports faithfully.
    let ratio = mean(friction) / mean(normal);
    assert!(ratio > mu - 0.05 && ratio < 1.0, "{ratio}");
    // The tip's height follows the surface: roughness of tens of micrometres.
    let z = col(&c, "normal_position_m");
    let zm = mean(z);
    let rms = (steady.iter().map(|&i| (z[i] - zm).powi(2)).sum::<f64>() / steady.len() as f64).sqrt();
    println!("rubbing: height rms {:.1} µm", rms * 1e6);
    assert!(rms > 5e-6 && rms < 2e-4, "{rms}");
}

/// The friction and normal force in a rubbing capture are the RFOB's estimates; they match the
/// forces the simulated world actually applied to the tip.
#[test]
fn rubbing_observers_report_the_forces_the_world_applied() {
    let mut options = CaptureOptions::new(Protocol::Rubbing);
    options.pacing = Pacing::Unpaced;
    let mut device = sim_device(&options).unwrap().with_trace(10_000);
    let mut c = controller(Protocol::Rubbing);
    let samples = run_unpaced(&mut device, &mut c, 10_000);
    let trace = device.trace();
    use haptics::rubbing_channel as channel;
    let rubbing: Vec<usize> = (0..trace.len().min(samples.len()))
        .filter(|&i| samples[i].channels[channel::PHASE] == haptics::RubbingPhase::Rub.code())
        .filter(|&i| (trace[i].velocity_mps.x - 0.005).abs() < 0.002)
        .collect();
    assert!(rubbing.len() > 1000);
    let mean = |f: &dyn Fn(usize) -> f64| rubbing.iter().map(|&i| f(i)).sum::<f64>() / rubbing.len() as f64;
    let world_friction = mean(&|i| -trace[i].world_force_n.x);
    let world_normal = mean(&|i| trace[i].world_force_n.z);
    let est_friction = mean(&|i| samples[i].channels[channel::FRICTION_N]);
    let est_normal = mean(&|i| samples[i].channels[channel::NORMAL_FORCE_N]);
    println!(
        "world friction {world_friction:.4} N normal {world_normal:.4} N; RFOB {est_friction:.4} N, {est_normal:.4} N"
    );
    assert!((est_friction - world_friction).abs() < 0.015);
    assert!((est_normal - world_normal).abs() < 0.015);
}
