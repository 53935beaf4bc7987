//! Captures recorded through a haptic device: what `palpus capture` runs.
//!
//! Each protocol is a controller run by the real-time loop ([`crate::rt`]) on a device — the
//! simulated Omega.7 or the real one — with the recorder ([`crate::recorder`]) writing what the
//! device measured and what the observers estimated, in the same columns as the papers'
//! captures, so identification treats them alike:
//! - `needle`: insertions at 2, 5 and 10 mm/s into fresh sites (Li & Bi Sec. III-D);
//! - `hard`: back-and-forth strokes at 10 mm/s on a hard plate under a slowly varying load
//!   (Li & Bi Sec. III-B);
//! - `soft`: strokes at 2–40 mm/s on a sponge under a varying load (Li & Bi Sec. III-C);
//! - `rubbing`: one 30 mm stroke at 5 mm/s under 0.3 N on one of Nakano's surfaces (Table 3.2).

pub(crate) mod needle;

use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::{Duration, Instant};

use capture::kind::{
    AXIAL_FORCE_N, COMMANDED_VELOCITY_MPS, DEPTH_M, FRICTION_FORCE_N, NORMAL_FORCE_N, NORMAL_POSITION_M,
    TANGENTIAL_POSITION_M, TANGENTIAL_VELOCITY_MPS, TIME_S, VELOCITY_MPS,
};
use capture::{CaptureKind, Metadata};

use crate::control::{MotionGains, RubbingController, RubbingPlan};
use crate::device::sim_omega7::{SimOmega7, SimOmega7Config, SimWorld, Texture};
use crate::device::{HapticDevice, SimSetup};
use crate::error::HapticsError;
use crate::recorder::{RecorderConfig, RecorderSummary, record_to_file};
use crate::rt::{
    self, CHANNELS, Controller, HapticSample, LoopConfig, LoopIo, LoopOutcome, Pacing, RateStats, RtStatus,
};
pub use needle::{InsertionController, InsertionPhase, InsertionPlan};
use sim::NeedleTissue;
use sim::{HardContact, SoftContact};
use sim::{SurfacePatch, nakano_surfaces};

/// What to capture.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Protocol {
    /// Needle insertions.
    Needle,
    /// Hard-contact friction.
    Hard,
    /// Soft-contact friction.
    Soft,
    /// Nakano's surface rubbing.
    Rubbing,
}

impl Protocol {
    /// Every protocol.
    pub const ALL: [Protocol; 4] = [Self::Needle, Self::Hard, Self::Soft, Self::Rubbing];

    /// Name on the command line and in metadata.
    pub fn name(self) -> &'static str {
        match self {
            Self::Needle => "needle",
            Self::Hard => "hard",
            Self::Soft => "soft",
            Self::Rubbing => "rubbing",
        }
    }

    /// The capture kind it writes.
    pub fn kind(self) -> CaptureKind {
        match self {
            Self::Needle => CaptureKind::Insertion,
            _ => CaptureKind::Rubbing,
        }
    }

    /// Columns it writes.
    pub fn columns(self) -> &'static [&'static str] {
        match self {
            Self::Needle => &[
                TIME_S,
                DEPTH_M,
                VELOCITY_MPS,
                COMMANDED_VELOCITY_MPS,
                AXIAL_FORCE_N,
            ],
            _ => &[
                TIME_S,
                TANGENTIAL_POSITION_M,
                TANGENTIAL_VELOCITY_MPS,
                COMMANDED_VELOCITY_MPS,
                NORMAL_POSITION_M,
                NORMAL_FORCE_N,
                FRICTION_FORCE_N,
            ],
        }
    }
}

impl fmt::Display for Protocol {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Protocol {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| format!("unknown protocol `{s}` (expected one of: needle, hard, soft, rubbing)"))
    }
}

const HARD_PLAN: RubbingPlan = RubbingPlan {
    stroke_speeds_mps: &[0.01, 0.01, 0.01, 0.01],
    stroke_m: 0.03,
    ramp_s: 0.2,
    normal_force_n: 2.5,
    normal_force_amplitude_n: 2.0,
    normal_force_period_s: 6.0,
};

const SOFT_PLAN: RubbingPlan = RubbingPlan {
    stroke_speeds_mps: &[0.002, 0.005, 0.01, 0.02, 0.04],
    stroke_m: 0.03,
    ramp_s: 0.2,
    normal_force_n: 2.0,
    normal_force_amplitude_n: 1.5,
    normal_force_period_s: 2.0,
};

/// Height of the simulated surfaces and tissue in device coordinates, m.
const SURFACE_Z_M: f64 = -0.02;

/// Options of a capture.
#[derive(Debug, Clone, PartialEq)]
pub struct CaptureOptions {
    /// The protocol.
    pub protocol: Protocol,
    /// For `rubbing`: which of Nakano's surfaces (simulator only).
    pub surface: String,
    /// For `rubbing`: where along the simulated patch the stroke starts, m (each track of a
    /// 0.33 m patch is different, like rubbing another spot of the same sample).
    pub track_offset_m: f64,
    /// Real time, or as fast as possible (simulator only).
    pub pacing: Pacing,
    /// Loop settings besides pacing.
    pub loop_config: LoopConfig,
}

impl CaptureOptions {
    /// Real-time capture of `protocol` (sandpaper #120 for rubbing).
    pub fn new(protocol: Protocol) -> Self {
        Self {
            protocol,
            surface: "sandpaper_120".into(),
            track_offset_m: 0.01,
            pacing: Pacing::REALTIME,
            loop_config: LoopConfig::default(),
        }
    }
}

/// Names of Nakano's surfaces.
pub fn surface_names() -> Vec<&'static str> {
    nakano_surfaces().iter().map(|s| s.name).collect()
}

/// The simulated Omega.7 set up for `options`: the world the protocol needs, the tip above it.
pub fn sim_device(options: &CaptureOptions) -> Result<SimOmega7, HapticsError> {
    let SimSetup { config, world, .. } = sim_setup(options)?;
    Ok(SimOmega7::new(config, world))
}

/// What a simulated device needs for `options`: the world the protocol needs, the tip above
/// it, no hand (the protocol moves the device).
pub fn sim_setup(options: &CaptureOptions) -> Result<SimSetup, HapticsError> {
    let start_m = glam::DVec3::new(0.0, 0.0, SURFACE_Z_M + 0.003);
    let world = match options.protocol {
        Protocol::Needle => SimWorld::needle_block(
            &NeedleTissue::bovine_liver(),
            InsertionPlan::DEFAULT.speeds_mps.len() + 1,
            InsertionPlan::DEFAULT.site_spacing_m,
            InsertionPlan::DEFAULT.surface_z_m,
        ),
        Protocol::Hard => SimWorld::surface(Texture::Hard(HardContact::li_bi()), SURFACE_Z_M),
        Protocol::Soft => match SimWorld::surface(Texture::Soft(SoftContact::sponge()), SURFACE_Z_M) {
            SimWorld::Surface {
                surface_z_m, texture, ..
            } => SimWorld::Surface {
                surface_z_m,
                // Foam is soft: a tenth of the plate's contact stiffness, more damping.
                stiffness_npm: 300.0,
                damping_nspm: 6.0,
                texture,
            },
            other => other,
        },
        Protocol::Rubbing => {
            let surface = nakano_surfaces()
                .into_iter()
                .find(|s| s.name == options.surface)
                .ok_or_else(|| HapticsError::UnknownSurface {
                    name: options.surface.clone(),
                    expected: surface_names().join(", "),
                })?;
            SimWorld::surface(
                Texture::Patch {
                    patch: Box::new(SurfacePatch::new(&surface)),
                    offset_m: options.track_offset_m,
                },
                SURFACE_Z_M,
            )
        }
    };
    Ok(SimSetup {
        config: SimOmega7Config {
            period_s: 1.0 / options.loop_config.rate_hz,
            start_m,
            ..SimOmega7Config::default()
        },
        world,
        hand: None,
    })
}

/// What a capture produced.
#[derive(Debug)]
pub struct CaptureReport {
    /// The file written.
    pub path: PathBuf,
    /// Rows written and rejections.
    pub recorder: RecorderSummary,
    /// Loop timing.
    pub stats: RateStats,
    /// Real-time scheduling granted.
    pub rt_status: Option<RtStatus>,
    /// Wall-clock duration.
    pub elapsed: Duration,
}

/// Metadata of a capture of `protocol` on `device` at `rate_hz`.
pub fn metadata(protocol: Protocol, device: &str, rate_hz: f64, options: &CaptureOptions) -> Metadata {
    let g = MotionGains::NAKANO;
    let mut meta = Metadata::new(protocol.kind(), device, rate_hz)
        .with("protocol", format!("palpus_capture_{}", protocol.name()))
        .with("force_source", "rfob")
        .with(recognize::nakano::OBSERVER_CUTOFF_KEY, g.g_reac_radps)
        .with("control.kp_per_s2", g.kp_per_s2)
        .with("control.kv_per_s", g.kv_per_s)
        .with("control.kf", g.kf)
        .with("control.mass_n_kg", g.mass_n_kg)
        .with("sensor.encoder_quantum_m", sim::Encoder::OMEGA7_QUANTUM_M)
        .with("sensor.velocity", "pseudo-differentiation")
        .with(
            "pacing",
            if options.pacing == Pacing::Unpaced {
                "unpaced"
            } else {
                "realtime"
            },
        );
    match protocol {
        Protocol::Needle => {
            let p = InsertionPlan::DEFAULT;
            let speeds: Vec<String> = p.speeds_mps.iter().map(|s| s.to_string()).collect();
            meta = meta
                .with("tissue", "bovine_liver")
                .with("speeds_mps", speeds.join(";"))
                .with("target_depth_m", p.target_depth_m)
                .with("withdraw_speed_mps", p.withdraw_mps);
            if device.starts_with("sim") {
                for (k, v) in NeedleTissue::bovine_liver().parameters() {
                    meta.insert(format!("truth.{k}"), v);
                }
            }
        }
        Protocol::Hard | Protocol::Soft | Protocol::Rubbing => {
            let plan = rubbing_plan(protocol);
            let speeds: Vec<String> = plan.stroke_speeds_mps.iter().map(|s| s.to_string()).collect();
            meta = meta
                .with("stroke_speeds_mps", speeds.join(";"))
                .with("stroke_m", plan.stroke_m)
                .with("command.normal_force_n", plan.normal_force_n)
                .with("command.normal_force_amplitude_n", plan.normal_force_amplitude_n)
                .with("command.normal_force_period_s", plan.normal_force_period_s);
            if device.starts_with("sim") {
                match protocol {
                    Protocol::Hard => {
                        let law = HardContact::li_bi();
                        meta = meta
                            .with("surface", "aluminium_plate")
                            .with("truth.slope", law.slope)
                            .with("truth.intercept_n", law.intercept_n);
                    }
                    Protocol::Soft => {
                        meta = meta.with("surface", "sponge");
                        for (k, v) in SoftContact::sponge().parameters() {
                            meta.insert(format!("truth.{k}"), v);
                        }
                    }
                    _ => {
                        meta = meta
                            .with("surface", &options.surface)
                            .with("track_offset_m", options.track_offset_m);
                    }
                }
            }
        }
    }
    meta
}

fn rubbing_plan(protocol: Protocol) -> RubbingPlan {
    match protocol {
        Protocol::Hard => HARD_PLAN,
        Protocol::Soft => SOFT_PLAN,
        _ => RubbingPlan::NAKANO,
    }
}

/// The controller of `protocol`.
pub fn controller(protocol: Protocol) -> Box<dyn Controller> {
    match protocol {
        Protocol::Needle => Box::new(InsertionController::new(InsertionPlan::DEFAULT)),
        other => Box::new(RubbingController::new(rubbing_plan(other))),
    }
}

/// Maps a sample to a capture row of `protocol` (false outside the recorded phases).
///
/// Values are written at the resolution the device reports them, as a device log would:
/// time to 1 µs, positions to the encoder's 10 µm, velocities to 1 µm/s, observer forces to
/// 0.1 mN.
pub fn row(protocol: Protocol, s: &HapticSample, row: &mut Vec<f64>) -> bool {
    use crate::control::rubbing::channel as rub;
    use sim::{Encoder, round_to};
    let time = round_to(s.time_s, 1e-6);
    let position = |x: f64| round_to(x, Encoder::OMEGA7_QUANTUM_M);
    let velocity = |v: f64| round_to(v, 1e-6);
    let force = |f: f64| round_to(f, 1e-4);
    match protocol {
        Protocol::Needle => {
            use needle::channel as n;
            row.extend([
                time,
                position(s.channels[n::DEPTH_M]),
                velocity(-s.state.velocity_mps.z),
                velocity(s.channels[n::COMMANDED_VELOCITY_MPS]),
                force(s.channels[n::AXIAL_FORCE_N]),
            ]);
            s.channels[n::RECORDING] > 0.0
        }
        _ => {
            row.extend([
                time,
                position(s.state.position_m.x),
                velocity(s.state.velocity_mps.x),
                velocity(s.channels[rub::COMMANDED_VELOCITY_MPS]),
                position(s.state.position_m.z),
                force(s.channels[rub::NORMAL_FORCE_N]),
                force(s.channels[rub::FRICTION_N]),
            ]);
            s.channels[rub::PHASE] == crate::control::RubbingPhase::Rub.code()
        }
    }
}

/// What a rubbing recognizer reads from one tick of [`RubbingController`], exactly as a rubbing
/// capture records it ([`row`]'s columns 1, 4 and 6: position along x and height at the
/// encoder's resolution, the RFOB's friction to 0.1 mN): `[x_m, z_m, friction_n]`, or `None`
/// outside the rubbing phase. No allocation, so the haptic thread can call it.
pub fn rubbing_signals(state: &crate::device::DeviceState, channels: &[f64; CHANNELS]) -> Option<[f64; 3]> {
    use crate::control::rubbing::channel as rub;
    use sim::{Encoder, round_to};
    (channels[rub::PHASE] == crate::control::RubbingPhase::Rub.code()).then(|| {
        [
            round_to(state.position_m.x, Encoder::OMEGA7_QUANTUM_M),
            round_to(state.position_m.z, Encoder::OMEGA7_QUANTUM_M),
            round_to(channels[rub::FRICTION_N], 1e-4),
        ]
    })
}

/// Runs `options.protocol` on `device`, recording to `out`. `progress` is called about ten
/// times a second with the loop's statistics.
pub fn run_capture(
    device: Box<dyn HapticDevice>,
    out: &Path,
    options: &CaptureOptions,
    progress: &mut dyn FnMut(&RateStats),
) -> Result<CaptureReport, HapticsError> {
    let started = Instant::now();
    let mut config = options.loop_config;
    config.pacing = options.pacing;
    if options.pacing == Pacing::Unpaced {
        config.watchdog = None;
    }
    let protocol = options.protocol;
    let meta = metadata(protocol, device.name(), config.rate_hz, options);
    let (producer, recorder) = record_to_file(
        out,
        &meta,
        protocol.columns(),
        move |s: &HapticSample, r: &mut Vec<f64>| row(protocol, s, r),
        RecorderConfig {
            // Unpaced runs produce samples far faster than real time: a larger ring.
            capacity: if options.pacing == Pacing::Unpaced {
                1 << 16
            } else {
                4096
            },
            ..RecorderConfig::default()
        },
    )?;
    let io = LoopIo {
        samples: Some(producer),
        live: None,
    };
    let handle = rt::spawn(device, controller(protocol), io, config)?;
    while !handle.is_finished() {
        std::thread::sleep(Duration::from_millis(100));
        progress(&handle.stats());
    }
    let stats = handle.stats();
    let rt_status = handle.shared().rt_status();
    let outcome = handle.join()?;
    let LoopOutcome {
        mut device,
        io,
        result,
        ..
    } = outcome;
    drop(io);
    let _ = device.close();
    // A failed run keeps its rows under the partial name and leaves the target as it was.
    if let Err(e) = result {
        let _ = recorder.abandon();
        return Err(e);
    }
    let (_, summary) = recorder.finish()?;
    Ok(CaptureReport {
        path: out.to_owned(),
        recorder: summary,
        stats,
        rt_status,
        elapsed: started.elapsed(),
    })
}
