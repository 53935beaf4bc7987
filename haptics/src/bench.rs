//! The loop benchmark behind `palpus bench loop`: the full haptic path at 1 kHz — simulated
//! Omega.7 with a hand inserting a needle over and over, observers, the needle law through
//! admittance control, safety, the recorder ring drained to a capture writer — with or
//! without competing CPU load on every core.

use std::hint::black_box;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use capture::kind::{AXIAL_FORCE_N, DEPTH_M, TIME_S};
use capture::{CaptureKind, CaptureWriter, Metadata};
use glam::DVec3;

use crate::control::{Admittance, AdmittanceConfig};
use crate::device::sim_omega7::{SimOmega7, SimOmega7Config, SimWorld};
use crate::error::{EarlyEnd, HapticsError};
use crate::law::{NeedleEnvironment, NeedleLaw, NeedleLawConfig, NeedleQuasiStatic};
use crate::recorder::{Recorder, RecorderConfig};
use crate::rt::{HapticSample, LoopConfig, LoopIo, RateStats, RtStatus, StopReason, core_count, spawn};
use sim::NeedleTissue;
use sim::{HandImpedance, Waypoints};

/// What to benchmark.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BenchConfig {
    /// How long, s.
    pub seconds: f64,
    /// Run a busy thread on every core beside the loop.
    pub load: bool,
    /// The loop's settings.
    pub loop_config: LoopConfig,
}

/// What the benchmark measured.
#[derive(Debug, Clone)]
pub struct BenchReport {
    /// Timing.
    pub stats: RateStats,
    /// Scheduling granted.
    pub rt_status: Option<RtStatus>,
    /// Busy threads run beside the loop.
    pub load_threads: usize,
    /// How the loop ended (stalls beyond the watchdog's rules or a device error end it early;
    /// stalls it survived are in `stats`).
    pub outcome: Result<StopReason, EarlyEnd>,
    /// Rows the recorder wrote.
    pub recorded_rows: u64,
    /// Wall-clock duration.
    pub elapsed: Duration,
}

/// A hand inserting to 20 mm at 5 mm/s and withdrawing at 10 mm/s, every 8 s, for `seconds`.
pub fn insertion_hand(surface_z_m: f64, seconds: f64) -> Waypoints {
    let top = surface_z_m + 0.003;
    let bottom = surface_z_m - 0.020;
    let mut points = Vec::new();
    let mut t = 0.0;
    while t <= seconds + 8.0 {
        points.push((t, DVec3::new(0.0, 0.0, top)));
        points.push((t + 0.5, DVec3::new(0.0, 0.0, top)));
        points.push((t + 0.5 + 0.023 / 0.005, DVec3::new(0.0, 0.0, bottom)));
        points.push((t + 5.6, DVec3::new(0.0, 0.0, bottom)));
        points.push((t + 5.6 + 0.023 / 0.010, DVec3::new(0.0, 0.0, top)));
        t += 8.0;
    }
    Waypoints::new(&points)
}

/// Runs the benchmark.
pub fn loop_bench(config: &BenchConfig) -> Result<BenchReport, HapticsError> {
    let surface_z_m = -0.02;
    let period_s = 1.0 / config.loop_config.rate_hz;
    let device = SimOmega7::new(
        SimOmega7Config {
            period_s,
            start_m: DVec3::new(0.0, 0.0, surface_z_m + 0.003),
            ..SimOmega7Config::default()
        },
        SimWorld::Free,
    )
    .with_hand(
        HandImpedance::default(),
        Box::new(insertion_hand(surface_z_m, config.seconds)),
    );
    let law = NeedleLaw::new(
        NeedleQuasiStatic::new(NeedleTissue::bovine_liver()),
        NeedleLawConfig::default(),
    );
    let controller = Admittance::new(
        NeedleEnvironment::new(law, surface_z_m, [0.0, 0.0]),
        AdmittanceConfig::default(),
    );
    let meta = Metadata::new(CaptureKind::Insertion, "sim-omega7", config.loop_config.rate_hz)
        .with("protocol", "palpus_bench_loop");
    let writer = CaptureWriter::new(std::io::sink(), &meta, &[TIME_S, DEPTH_M, AXIAL_FORCE_N])?;
    let (producer, recorder) = Recorder::spawn(
        writer,
        move |s: &HapticSample, row: &mut Vec<f64>| {
            row.extend([s.time_s, surface_z_m - s.state.position_m.z, s.channels[1]]);
            true
        },
        RecorderConfig::default(),
    )?;

    let stop_load = Arc::new(AtomicBool::new(false));
    let load_threads = if config.load { core_count() } else { 0 };
    let loads: Vec<_> = (0..load_threads)
        .map(|_| {
            let stop = stop_load.clone();
            std::thread::spawn(move || {
                let mut x = 1.0f64;
                while !stop.load(Ordering::Relaxed) {
                    for _ in 0..10_000 {
                        x = black_box((x * 1.000_001).sin() + 1.5);
                    }
                }
                x
            })
        })
        .collect();

    let started = Instant::now();
    let mut loop_config = config.loop_config;
    loop_config.max_ticks = Some((config.seconds * config.loop_config.rate_hz).round() as u64);
    let io = LoopIo {
        samples: Some(producer),
        live: None,
    };
    let handle = spawn(device, controller, io, loop_config)?;
    while !handle.is_finished() {
        std::thread::sleep(Duration::from_millis(50));
    }
    let stats = handle.stats();
    let rt_status = handle.shared().rt_status();
    let outcome = handle.join()?;
    let elapsed = started.elapsed();
    stop_load.store(true, Ordering::Relaxed);
    for l in loads {
        let _ = l.join();
    }
    drop(outcome.io);
    let recorded_rows = recorder.finish().map(|(_, s)| s.rows).unwrap_or(0);
    Ok(BenchReport {
        stats,
        rt_status,
        load_threads,
        outcome: outcome.result.map(|r| r.reason).map_err(|e| EarlyEnd::from(&e)),
        recorded_rows,
        elapsed,
    })
}
