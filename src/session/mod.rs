//! A session: a scene's models rendered by the haptic thread on a device, with a scripted
//! trainee (headless) or the user's hand (window), recorded and summarised.
//!
//! A scene runs as one *segment* per thing the trainee works on: the needle's insertion site,
//! or each surface a rubbing task visits. Each segment has its own haptic loop, because moving
//! the tool from one patch to the next is a clutch (the workspace is re-centred on the next
//! object), exactly as a trainee indexes an Omega.7 across a tray wider than its 160 mm
//! workspace.

pub mod analysis;
pub mod guide;
pub mod report;
pub mod score;
pub mod script;
pub mod smoothness;
pub mod strokes;
pub mod truth_along;
pub mod truth_tissue;

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use capture::kind::{
    AXIAL_FORCE_N, DEPTH_M, FRICTION_FORCE_N, NORMAL_FORCE_N, NORMAL_POSITION_M, TANGENTIAL_POSITION_M,
    TANGENTIAL_VELOCITY_MPS, TIME_S, VELOCITY_MPS,
};
use capture::{CaptureKind, CaptureWriter, Metadata};
use glam::DVec3;
use haptics::HapticSample;
use haptics::LiveFeed;
use haptics::acquire::{self, CaptureOptions, Protocol};
use haptics::admittance_channel as channel;
use haptics::rt::{self, Controller, LoopConfig, LoopIo, Pacing, RateStats, RtStatus, WatchdogConfig};
use haptics::{Admittance, AdmittanceConfig, Direct};
use haptics::{DeviceChoice, Motion, OpenedDevice, SimSetup};
use haptics::{
    Environment, FrictionSurface, HardFriction, NeedleEnvironment, NeedleLaw, NeedleLawConfig,
    PhasedNeedleLaw, SoftFriction, hard_friction_model, needle_model, soft_friction_models,
};
use haptics::{LiveRecognizer, SampleRecognizer};
use haptics::{Recorder, RecorderConfig};
use haptics::{SimOmega7Config, SimWorld};
use identify::{ModelFile, ModelKind};
use sim::{HandImpedance, HandScript, LiveHand};

use crate::models::ResolvedModel;
use crate::scene::{ModelRole, Scene, Task};

/// Height of the tissue surface or of the rubbed surface in device coordinates (z up), m: a
/// little below the workspace centre, where the Omega.7 has room above and below.
pub const SURFACE_Z_M: f64 = -0.02;

/// Where on a simulated patch a session rubs, m: a track the recognizer's training captures
/// (offsets 10, 60 and 110 mm) never touched.
pub const LIVE_TRACK_OFFSET_M: f64 = 0.2;

/// How to run.
#[derive(Debug, Clone)]
pub struct SessionOptions {
    /// The device.
    pub device: DeviceChoice,
    /// Stop each segment after this long, s (None: when the task is done).
    pub duration_s: Option<f64>,
    /// Record the session into this capture (rubbing scenes: one file per surface, the
    /// object's name before the extension).
    pub record: Option<PathBuf>,
    /// Real time, or as fast as the simulator goes (tests of the whole chain).
    pub pacing: Pacing,
    /// Simulator in a window: the scripted trainee moves the hand instead of the mouse (demos).
    pub autopilot: bool,
}

/// What a segment works on.
#[derive(Debug, Clone)]
pub enum SegmentKind {
    /// Needle insertion into tissue rendered from a puncture model.
    Needle {
        /// The model.
        model: Box<ModelFile>,
        /// The simulated tissue it renders, when it renders one
        /// ([`truth_tissue`]): the report compares the session with it.
        truth: Option<sim::li_bi::NeedleTissueKind>,
    },
    /// Rubbing a surface rendered from a friction model.
    Friction {
        /// The model.
        model: Box<ModelFile>,
        /// Contact stiffness, N/m.
        stiffness_npm: f64,
    },
    /// Rubbing a simulated physical surface with Nakano's controller (recognition).
    Surface {
        /// One of Nakano's seven surfaces.
        surface: String,
    },
}

/// One segment of a session.
#[derive(Debug, Clone)]
pub struct Segment {
    /// The object worked on.
    pub object: String,
    /// What it is.
    pub kind: SegmentKind,
}

/// Why a session could not run.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// The scene needs a model that was not resolved (a bug in resolution).
    #[error("the scene's material `{material}` needs a {role} model that was not resolved")]
    MissingModel {
        /// The material.
        material: String,
        /// Its role.
        role: ModelRole,
    },
    /// A model cannot drive its force law.
    #[error("model `{model}`: {source}")]
    Model {
        /// The scene's name for it.
        model: String,
        /// Why.
        source: Box<haptics::HapticsError>,
    },
    /// The device could not be opened.
    #[error("opening the device: {0}")]
    Device(#[source] Box<haptics::HapticsError>),
    /// The replay capture is unreadable.
    #[error(transparent)]
    Replay(#[from] capture::CaptureError),
    /// The loop could not run, recording failed, or a simulated surface is unknown.
    #[error(transparent)]
    Haptics(Box<haptics::HapticsError>),
    /// The device cannot run this task.
    #[error("{0}")]
    Unsupported(String),
}

// Boxed: the haptics error carries the lower crates' errors and would make every session
// `Result` as large as the largest of them.
impl From<haptics::HapticsError> for SessionError {
    fn from(e: haptics::HapticsError) -> Self {
        Self::Haptics(Box::new(e))
    }
}

/// The segments of `scene` with the models resolved for it.
pub fn segments(scene: &Scene, models: &[ResolvedModel]) -> Result<Vec<Segment>, SessionError> {
    let model = |material: &str, role: ModelRole, name: &Option<String>| {
        name.as_ref()
            .and_then(|n| models.iter().find(|m| &m.name == n))
            .map(|m| Box::new(m.model.clone()))
            .ok_or(SessionError::MissingModel {
                material: material.into(),
                role,
            })
    };
    let mut out = Vec::new();
    match &scene.task {
        Task::Insertion { .. } => {
            for object in &scene.objects {
                if object.tool {
                    continue;
                }
                let material = &scene.materials[&object.material];
                if material.puncture.is_some() {
                    out.push(Segment {
                        object: object.name.clone(),
                        kind: {
                            let model = model(&object.material, ModelRole::Puncture, &material.puncture)?;
                            let capture = material
                                .puncture
                                .as_ref()
                                .and_then(|name| scene.models.get(name))
                                .and_then(|source| source.capture.as_ref())
                                .map(|c| scene.resolve(Path::new(c)));
                            let truth = truth_tissue::of_model(&model, capture.as_deref());
                            SegmentKind::Needle { model, truth }
                        },
                    });
                    break;
                }
            }
        }
        Task::Rub { .. } => {
            for object in scene.rubbed_objects() {
                let material = &scene.materials[&object.material];
                let kind = if material.friction.is_some() {
                    SegmentKind::Friction {
                        model: model(&object.material, ModelRole::Friction, &material.friction)?,
                        stiffness_npm: material.contact_stiffness_npm,
                    }
                } else {
                    SegmentKind::Surface {
                        surface: material.surface.clone().unwrap_or_default(),
                    }
                };
                out.push(Segment {
                    object: object.name.clone(),
                    kind,
                });
            }
        }
    }
    Ok(out)
}

/// What one segment produced.
#[derive(Debug)]
pub struct SegmentRun {
    /// The segment.
    pub segment: Segment,
    /// Every tick's sample, in order.
    pub samples: Vec<HapticSample>,
    /// Loop timing.
    pub stats: RateStats,
    /// Real-time scheduling granted.
    pub rt_status: Option<RtStatus>,
    /// How the loop ended.
    pub outcome: Result<String, haptics::EarlyEnd>,
    /// The capture written and its rows.
    pub recorded: Option<(PathBuf, u64)>,
    /// The device's force limit, N.
    pub max_force_n: f64,
    /// The device's name.
    pub device: String,
    /// The device's own watchdog, when the loop armed one.
    pub hardware_watchdog: Option<haptics::HardwareWatchdog>,
    /// Wall-clock time.
    pub elapsed: Duration,
}

/// The live connection between a running segment and a window: the window keeps the
/// [`haptics::LiveView`] that goes with `feed` and clones of `hand` and `stop`.
#[derive(Debug)]
pub struct LiveLink {
    /// The hand target the UI moves (simulator only).
    pub hand: Arc<LiveHand>,
    /// Set by the UI to end the segment.
    pub stop: Arc<AtomicBool>,
    /// The live view's writing ends: the newest sample from the haptic thread, the recent
    /// samples from the recorder thread, the loop's statistics about 50 times a second.
    pub feed: LiveFeed,
}

impl LiveLink {
    /// A link with the hand at `start_m` (device coordinates), writing into `feed`.
    pub fn new(start_m: DVec3, feed: LiveFeed) -> Self {
        let hand = LiveHand::new();
        hand.set(start_m, 0.01);
        Self {
            hand,
            stop: Arc::new(AtomicBool::new(false)),
            feed,
        }
    }
}

/// Where the tool starts for `segment` (device coordinates).
pub fn start_position_m(scene: &Scene) -> DVec3 {
    match scene.task {
        Task::Insertion { start_above_m, .. } => DVec3::new(0.0, 0.0, SURFACE_Z_M + start_above_m),
        Task::Rub { stroke_m, .. } => DVec3::new(-stroke_m / 2.0, 0.0, SURFACE_Z_M + 0.003),
    }
}

/// A sample's value in SI units.
pub type Trace = fn(&HapticSample) -> f64;

/// What a segment's force is plotted against, and the force: (position along the task's
/// direction m — needle depth or tangential x —, force on the tool N, the position's name).
/// The report's plots and the overlay read samples the same way; no segment reads as a needle.
pub fn traces(kind: Option<&SegmentKind>) -> (Trace, Trace, &'static str) {
    use haptics::rubbing_channel as rub;
    match kind {
        Some(SegmentKind::Needle { .. }) | None => (
            |s| SURFACE_Z_M - s.channels[channel::VIRTUAL_Z_M],
            |s| s.channels[channel::MODEL_FORCE_Z_N],
            "depth",
        ),
        Some(SegmentKind::Friction { .. }) => (
            |s| s.state.position_m.x,
            |s| -s.channels[channel::MODEL_FORCE_X_N],
            "position",
        ),
        Some(SegmentKind::Surface { .. }) => (
            |s| s.state.position_m.x,
            |s| s.channels[rub::FRICTION_N],
            "position",
        ),
    }
}

fn renderer<E: Environment + 'static>(env: E, scene: &Scene, direct: bool) -> Box<dyn Controller> {
    if direct {
        Box::new(Direct::new(env))
    } else {
        let h = scene.haptics;
        Box::new(Admittance::new(
            env,
            AdmittanceConfig {
                virtual_mass_kg: h.virtual_mass_kg,
                virtual_damping_nspm: h.virtual_damping_nspm,
                ..AdmittanceConfig::default()
            },
        ))
    }
}

fn controller(
    scene: &Scene,
    segment: &Segment,
    direct: bool,
    surface_z_m: f64,
) -> Result<Box<dyn Controller>, SessionError> {
    let law_error = |source| SessionError::Model {
        model: segment.object.clone(),
        source: Box::new(source),
    };
    Ok(match &segment.kind {
        SegmentKind::Needle { model, .. } => {
            let config = NeedleLawConfig {
                min_peak_n: scene.haptics.rupture_min_peak_n,
                ..NeedleLawConfig::default()
            };
            if model.kind == ModelKind::NeedlePhases {
                let law = PhasedNeedleLaw::from_file(model, config).map_err(law_error)?;
                renderer(
                    NeedleEnvironment::new(law, surface_z_m, [0.0, 0.0]),
                    scene,
                    direct,
                )
            } else {
                let law = NeedleLaw::new(needle_model(model).map_err(law_error)?, config);
                renderer(
                    NeedleEnvironment::new(law, surface_z_m, [0.0, 0.0]),
                    scene,
                    direct,
                )
            }
        }
        SegmentKind::Friction { model, stiffness_npm } => match model.kind {
            ModelKind::SoftFriction => {
                let (w, m) = soft_friction_models(model).map_err(law_error)?;
                let max_normal = model.input_range.get(1).map_or(10.0, |r| r[1]);
                let mut env = FrictionSurface::new(SoftFriction::new(w, m, max_normal), surface_z_m);
                env.stiffness_npm = *stiffness_npm;
                renderer(env, scene, direct)
            }
            _ => {
                let law = HardFriction::new(hard_friction_model(model).map_err(law_error)?);
                let mut env = FrictionSurface::new(law, surface_z_m);
                env.stiffness_npm = *stiffness_npm;
                renderer(env, scene, direct)
            }
        },
        SegmentKind::Surface { .. } => acquire::controller(Protocol::Rubbing),
    })
}

/// Recording layout of a segment: capture kind, columns and the row of a sample.
fn recording(segment: &Segment) -> (CaptureKind, &'static [&'static str]) {
    match segment.kind {
        SegmentKind::Needle { .. } => (
            CaptureKind::Insertion,
            &[TIME_S, DEPTH_M, VELOCITY_MPS, AXIAL_FORCE_N],
        ),
        SegmentKind::Friction { .. } => (
            CaptureKind::Rubbing,
            &[
                TIME_S,
                TANGENTIAL_POSITION_M,
                TANGENTIAL_VELOCITY_MPS,
                NORMAL_POSITION_M,
                NORMAL_FORCE_N,
                FRICTION_FORCE_N,
            ],
        ),
        SegmentKind::Surface { .. } => (CaptureKind::Rubbing, Protocol::Rubbing.columns()),
    }
}

/// The capture row of a sample. Needle and friction rows hold the virtual tool's motion and
/// the model's force on it: what the trainee felt, in the columns identification reads.
fn row(kind: &SegmentKind, surface_z_m: f64, s: &HapticSample, row: &mut Vec<f64>) -> bool {
    use channel as c;
    match kind {
        SegmentKind::Needle { .. } => {
            let depth_m = surface_z_m - s.channels[c::VIRTUAL_Z_M];
            // Only contact is a capture of the tissue; the approach in air is not.
            if depth_m <= 0.0 {
                return false;
            }
            row.extend([
                s.time_s,
                depth_m,
                -s.channels[c::VIRTUAL_VZ_MPS],
                s.channels[c::MODEL_FORCE_Z_N],
            ]);
            true
        }
        SegmentKind::Friction { .. } => {
            let normal_n = s.channels[c::MODEL_FORCE_Z_N];
            if normal_n <= 0.05 {
                return false;
            }
            row.extend([
                s.time_s,
                s.state.position_m.x,
                s.state.velocity_mps.x,
                s.state.position_m.z - surface_z_m,
                normal_n,
                // Positive opposing the motion, as the capture format says.
                -s.channels[c::MODEL_FORCE_X_N] * s.state.velocity_mps.x.signum(),
            ]);
            true
        }
        SegmentKind::Surface { .. } => acquire::row(Protocol::Rubbing, s, row),
    }
}

/// The file a segment records into: `record` itself for a single segment, else the object's
/// name before the extension.
pub fn record_path(record: &Path, object: &str, segments: usize) -> PathBuf {
    if segments <= 1 {
        return record.to_owned();
    }
    let stem = record
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = record
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_else(|| "csv".into());
    record.with_file_name(format!("{stem}.{object}.{ext}"))
}

/// Runs one segment to its end (the task's, `duration_s`, or the UI's stop). A surface
/// segment given a `recognizer` runs it over the loop's samples on the recorder thread, off the
/// haptic thread ([`SampleRecognizer`]): its decisions ride in every sample's
/// [`haptics::recognizer_channel`]s.
///
/// The segment's samples are kept by the recorder thread, off the haptic thread; a window
/// reads the running segment through `live`, whose writers never wait.
pub fn run_segment(
    scene: &Scene,
    segment: &Segment,
    segments: usize,
    options: &SessionOptions,
    live: Option<LiveLink>,
    recognizer: Option<LiveRecognizer>,
) -> Result<SegmentRun, SessionError> {
    let started = Instant::now();
    let rate_hz = scene.device.rate_hz;
    let period_s = 1.0 / rate_hz;
    let backend = options.device.backend();
    let (sim, recording_kind) = match &segment.kind {
        SegmentKind::Surface { surface } => {
            if !backend.simulated {
                return Err(SessionError::Unsupported(format!(
                    "the surfaces of a recognition scene are simulated; `{}` touches a real one: run \
                     it with a simulated device (--device sim)",
                    backend.name
                )));
            }
            let mut capture = CaptureOptions::new(Protocol::Rubbing);
            capture.surface = surface.clone();
            capture.track_offset_m = LIVE_TRACK_OFFSET_M;
            capture.loop_config.rate_hz = rate_hz;
            (acquire::sim_setup(&capture)?, CaptureKind::Rubbing)
        }
        _ => {
            let impedance = HandImpedance {
                stiffness_npm: scene.haptics.grip_stiffness_npm,
                ..HandImpedance::default()
            };
            let hand: (Box<dyn HandScript>, Option<f64>) = match &live {
                Some(link) if !options.autopilot => (Box::new(link.hand.clone()), None),
                _ => {
                    let w = script::trainee(&scene.task, SURFACE_Z_M, impedance.stiffness_npm);
                    let end_s = w.end_s();
                    (Box::new(w), Some(end_s))
                }
            };
            let setup = SimSetup {
                config: SimOmega7Config {
                    period_s,
                    start_m: start_position_m(scene),
                    ..SimOmega7Config::default()
                },
                world: SimWorld::Free,
                hand: Some((impedance, hand.0, hand.1)),
            };
            (setup, CaptureKind::Insertion)
        }
    };
    let OpenedDevice { device, script_end_s } =
        options
            .device
            .open(period_s, sim, recording_kind)
            .map_err(|e| match e {
                haptics::HapticsError::Capture(e) => SessionError::Replay(e),
                e => SessionError::Device(Box::new(e)),
            })?;
    // A recording moves the tool: the law is rendered straight from the played position, and a
    // replayed insertion's depth runs along −z from 0.
    let direct = backend.motion == Motion::Recorded;
    let surface_z_m = if direct { 0.0 } else { SURFACE_Z_M };
    let device_name = device.name().to_owned();
    let max_force_n = backend.specs.max_force_n;
    let controller = controller(scene, segment, direct, surface_z_m)?;
    let mut recognizer = match (recognizer, &segment.kind) {
        (Some(r), SegmentKind::Surface { .. }) => Some(SampleRecognizer::new(r)),
        _ => None,
    };

    let (stop, newest, mut recent, mut live_stats) = match live {
        Some(LiveLink {
            stop,
            feed:
                LiveFeed {
                    newest,
                    recent,
                    stats,
                },
            ..
        }) => (Some(stop), Some(newest), Some(recent), Some(stats)),
        None => (None, None, None, None),
    };
    let kind = segment.kind.clone();
    let (capture_kind, columns) = recording(segment);
    let record = options
        .record
        .as_ref()
        .map(|r| record_path(r, &segment.object, segments));
    let mut meta = match &segment.kind {
        SegmentKind::Surface { surface } => {
            let mut capture = CaptureOptions::new(Protocol::Rubbing);
            capture.surface = surface.clone();
            capture.track_offset_m = LIVE_TRACK_OFFSET_M;
            acquire::metadata(Protocol::Rubbing, &device_name, rate_hz, &capture)
        }
        _ => Metadata::new(capture_kind, &device_name, rate_hz)
            .with("protocol", "palpus_run")
            .with("force_source", "model"),
    };
    meta.insert("scene", &scene.name);
    meta.insert("object", &segment.object);
    // A model of a simulated tissue renders that tissue: a model identified from this
    // recording is compared with it too.
    if let SegmentKind::Needle { truth: Some(t), .. } = &segment.kind {
        meta.insert(truth_tissue::TRUTH_KEY, t.name());
    }
    // The recorder thread sees every sample, in order: the recognizer decides on them there,
    // then it hands them on to the window's ring (never waiting: a window that falls behind
    // misses samples for its plots, not the report) and keeps them for the report.
    let annotate = move |s: &mut HapticSample| {
        if let Some(r) = recognizer.as_mut() {
            r.annotate(s);
        }
    };
    let map = move |s: &HapticSample, r: &mut Vec<f64>| {
        if let Some(recent) = recent.as_mut() {
            recent.push(s);
        }
        row(&kind, surface_z_m, s, r)
    };
    let map = haptics::annotate_then(annotate, map);
    let ring = RecorderConfig {
        capacity: 1 << 16,
        keep_samples: true,
        ..RecorderConfig::default()
    };
    enum AnyRecorder {
        File(Recorder<std::fs::File>),
        Sink(Recorder<std::io::Sink>),
    }
    let (producer, recorder) = match &record {
        Some(path) => {
            let (p, r) = haptics::record_to_file(path, &meta, columns, map, ring)?;
            (p, AnyRecorder::File(r))
        }
        None => {
            let writer =
                CaptureWriter::new(std::io::sink(), &meta, columns).map_err(haptics::HapticsError::from)?;
            let (p, r) = Recorder::spawn(writer, map, ring)?;
            (p, AnyRecorder::Sink(r))
        }
    };

    let mut config = LoopConfig {
        rate_hz,
        pacing: options.pacing,
        ..LoopConfig::default()
    };
    if options.pacing == Pacing::Unpaced {
        config.watchdog = None;
    } else if backend.simulated {
        // A simulated device cannot hurt a hand, and a busy or virtual machine stalls a thread
        // for tens of milliseconds now and then: the simulator's watchdog only ends a session
        // that has really hung. A real device keeps the default 4 ms bound.
        config.watchdog = Some(WatchdogConfig {
            stall: Duration::from_millis(250),
            ..WatchdogConfig::default()
        });
    }
    let until_s = match (options.duration_s, script_end_s) {
        (Some(d), Some(e)) => Some(d.min(e + 0.2)),
        (Some(d), None) => Some(d),
        (None, Some(e)) => Some(e + 0.2),
        (None, None) => None,
    };
    config.max_ticks = until_s.map(|s| (s * rate_hz).round().max(1.0) as u64);
    let io = LoopIo {
        samples: Some(producer),
        live: newest,
    };
    let handle = rt::spawn(device, controller, io, config)?;
    while !handle.is_finished() {
        if stop.as_ref().is_some_and(|s| s.load(Ordering::Relaxed)) {
            handle.stop();
        }
        if let Some(out) = live_stats.as_mut() {
            out.publish(handle.stats());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let stats = handle.stats();
    let rt_status = handle.shared().rt_status();
    let outcome = handle.join()?;
    let mut device = outcome.device;
    let hardware_watchdog = device.hardware_watchdog();
    drop(outcome.io);
    let _ = device.close();
    let result = outcome
        .result
        .map(|r| format!("{:?}", r.reason))
        .map_err(|e| haptics::EarlyEnd::from(&e));
    let (recorded, samples) = match recorder {
        // A run that failed keeps its rows beside the target, under the partial name, and
        // leaves a file already there untouched.
        AnyRecorder::File(r) if result.is_err() => (None, r.abandon().1),
        AnyRecorder::File(r) => {
            let (result, samples) = r.finish_with_samples();
            let (_, summary) = result?;
            (record.map(|p| (p, summary.rows)), samples)
        }
        AnyRecorder::Sink(r) => {
            // An empty sink (a segment that never touched) is not an error without a file.
            let (_, samples) = r.finish_with_samples();
            (None, samples)
        }
    };
    if let Some(out) = live_stats.as_mut() {
        out.publish(stats);
    }
    Ok(SegmentRun {
        segment: segment.clone(),
        samples,
        stats,
        rt_status,
        outcome: result,
        recorded,
        max_force_n,
        device: device_name,
        hardware_watchdog,
        elapsed: started.elapsed(),
    })
}
