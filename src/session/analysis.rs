//! What a segment's samples say: punctures and their depths against the simulated tissue's
//! truth, friction ratios, force extremes, loop rate.

use haptics::HapticSample;
use haptics::PunctureState;
use haptics::rubbing_channel as rub;
use serde::Serialize;
use sim::NeedleTissue;

use super::{SURFACE_Z_M, SegmentKind, SegmentRun};
use haptics::admittance_channel as c;

/// One detected capsule or membrane rupture.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Puncture {
    /// When, s.
    pub time_s: f64,
    /// Depth of the tool below the undeformed surface, m.
    pub depth_m: f64,
    /// Insertion speed of the tool at the loading peak just before, m/s.
    pub speed_mps: f64,
    /// Largest force of the loading before it, N.
    pub peak_force_n: f64,
    /// Depth at which the simulated liver the model was identified from ruptures at that
    /// speed, m (membrane by index).
    pub truth_depth_m: Option<f64>,
    /// That simulated liver's axial force just before the same rupture at that speed, N: the
    /// peak a trainee should feel.
    pub truth_peak_force_n: Option<f64>,
}

/// One membrane of the simulated tissue the needle model was identified from, and whether the
/// rendered force gave way there: the model's force is run through the same puncture detector
/// as recordings ([`identify::detect_punctures`]), so a membrane the model smooths away is
/// reported as missed rather than silently absent.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LayerFidelity {
    /// The membrane (`capsule`, `vessel_wall`).
    pub name: &'static str,
    /// `felt`, `missed`, or `not reached` (the needle never went as deep).
    pub status: &'static str,
    /// Speed of the tool as it crossed the membrane's depth (at the felt peak when felt), m/s.
    pub speed_mps: Option<f64>,
    /// Depth at which the simulated tissue ruptures at that speed, m.
    pub truth_depth_m: Option<f64>,
    /// The simulated tissue's force just before that rupture, N.
    pub truth_peak_force_n: Option<f64>,
    /// Depth of the rendered force's peak before the drop, m (when felt).
    pub felt_depth_m: Option<f64>,
    /// The rendered peak force, N (when felt).
    pub felt_peak_force_n: Option<f64>,
    /// How far the rendered force fell, N (when felt).
    pub felt_drop_n: Option<f64>,
}

/// The device's own watchdog over a segment ([`haptics::HapticDevice::arm_watchdog`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DeviceWatchdog {
    /// The period armed, ms.
    pub period_ms: f64,
    /// Silences longer than the period, each ended by the device releasing the force, where
    /// the device reports them (the simulated Omega.7 does).
    pub trips: Option<u32>,
    /// The longest silence between two commands, ms, where reported.
    pub longest_silence_ms: Option<f64>,
    /// The force the device held when that silence began, N: held for the silence, or for
    /// one period when the silence tripped the watchdog.
    pub held_force_n: Option<f64>,
}

impl From<haptics::HardwareWatchdog> for DeviceWatchdog {
    fn from(w: haptics::HardwareWatchdog) -> Self {
        Self {
            period_ms: w.period.as_secs_f64() * 1e3,
            trips: w.trips,
            longest_silence_ms: w.longest_gap.map(|(g, _)| g.as_secs_f64() * 1e3),
            held_force_n: w.longest_gap.map(|(_, f)| f),
        }
    }
}

impl std::fmt::Display for DeviceWatchdog {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "device watchdog armed at {:.3} ms", self.period_ms)?;
        match (self.trips, self.longest_silence_ms, self.held_force_n) {
            (Some(0), Some(gap), _) => write!(f, ", never reached (longest silence {gap:.1} ms)"),
            (Some(trips), Some(gap), Some(held)) => write!(
                f,
                "; {trips} silence(s) longer released the force: over the longest ({gap:.1} ms) the device \
                 held {held:.2} N for {:.3} ms, then let go (without it: for the whole {gap:.1} ms)",
                self.period_ms
            ),
            _ => Ok(()),
        }
    }
}

/// The summary of one segment.
#[derive(Debug, Clone, Serialize)]
pub struct SegmentSummary {
    /// The object.
    pub object: String,
    /// `needle`, `friction` or `surface`.
    pub kind: &'static str,
    /// Ticks run.
    pub ticks: u64,
    /// Loop time covered, s.
    pub duration_s: f64,
    /// Mean loop rate, Hz.
    pub mean_rate_hz: f64,
    /// Nominal rate, Hz.
    pub nominal_rate_hz: f64,
    /// |mean − nominal| / nominal.
    pub rate_error: f64,
    /// Period error p99, µs.
    pub period_error_p99_us: f64,
    /// Ticks started over 2 ms late.
    pub late_over_2ms: u64,
    /// Deadlines skipped because their tick woke after the next one (force updates lost).
    pub missed_slots: u64,
    /// |rate of the deadlines kept or skipped − nominal| / nominal: near zero for a loop that
    /// keeps its grid of absolute deadlines, however often the machine makes it late.
    pub deadline_rate_error: f64,
    /// The loop's own work per tick, p99, µs.
    pub compute_p99_us: f64,
    /// Stalls of the loop it rode out (force ramped to zero, then back).
    pub stalls: u64,
    /// The longest of them, ms (0 without one).
    pub longest_stall_ms: f64,
    /// Largest force norm sent to the device, N.
    pub max_command_n: f64,
    /// The device's limit, N.
    pub device_limit_n: f64,
    /// Any NaN or infinite command.
    pub non_finite_commands: u64,
    /// Ticks the safety filter changed.
    pub safety_events: u64,
    /// Ticks where a model's inputs were clamped to its training box.
    pub model_clamps: u64,
    /// Where those ticks were (needle): per law state, how many, over which depths and
    /// velocities. Each was rendered by the law's bounded fallback (inputs held to the trained
    /// box), so together they explain `model_clamps`.
    pub out_of_domain: Vec<OutOfDomainTicks>,
    /// Ruptures (needle).
    pub punctures: Vec<Puncture>,
    /// Every membrane of the simulated tissue, felt or missed (needle).
    pub layers: Vec<LayerFidelity>,
    /// The rendered force against the simulated tissue's along the run (needle on the
    /// simulator): RMSE, the largest error and where, false and missed pops.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub truth_along: Option<super::truth_along::TruthAlong>,
    /// The simulated tissue the needle model renders (`liver`), which the punctures,
    /// layers and `truth_along` are compared with; `None` for a model of anything else (a
    /// rig's logs), compared with nothing ([`super::truth_tissue`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub truth_tissue: Option<String>,
    /// Deepest tool depth (needle), m.
    pub max_depth_m: Option<f64>,
    /// Largest model force (needle: axial; friction: normal), N.
    pub max_model_force_n: f64,
    /// Mean friction / normal force while sliding (friction and surface segments).
    pub mean_friction_ratio: Option<f64>,
    /// The device's own watchdog, when armed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub device_watchdog: Option<DeviceWatchdog>,
    /// How the loop ended.
    pub outcome: String,
}

/// Ticks of one law state whose inputs left the model's trained domain.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OutOfDomainTicks {
    /// The law state (`approach`, `capsule_loading`, `puncture`, `insertion`, `withdrawal`).
    pub state: &'static str,
    /// How many ticks.
    pub ticks: u64,
    /// [min, max] depth over them, m.
    pub depth_m: [f64; 2],
    /// [min, max] insertion velocity over them, m/s.
    pub velocity_mps: [f64; 2],
}

/// The needle's out-of-domain ticks grouped by law state.
fn out_of_domain(s: &[HapticSample], surface_z_m: f64) -> Vec<OutOfDomainTicks> {
    use haptics::flag;
    let states = [
        (PunctureState::Approach, "approach"),
        (PunctureState::CapsuleLoading, "capsule_loading"),
        (PunctureState::Puncture, "puncture"),
        (PunctureState::Insertion, "insertion"),
        (PunctureState::Withdrawal, "withdrawal"),
    ];
    states
        .iter()
        .filter_map(|&(state, name)| {
            let mut t = OutOfDomainTicks {
                state: name,
                ticks: 0,
                depth_m: [f64::INFINITY, f64::NEG_INFINITY],
                velocity_mps: [f64::INFINITY, f64::NEG_INFINITY],
            };
            for x in s.iter().filter(|x| {
                x.flags & flag::MODEL_INPUT_CLAMPED != 0 && x.channels[c::ENV_STATE] == state.code()
            }) {
                let d = surface_z_m - x.channels[c::VIRTUAL_Z_M];
                let v = -x.channels[c::VIRTUAL_VZ_MPS];
                t.ticks += 1;
                t.depth_m = [t.depth_m[0].min(d), t.depth_m[1].max(d)];
                t.velocity_mps = [t.velocity_mps[0].min(v), t.velocity_mps[1].max(v)];
            }
            (t.ticks > 0).then_some(t)
        })
        .collect()
}

/// Where the tissue's surface is in `run`'s device coordinates ([`surface_z_on`]).
pub fn surface_z_m(run: &SegmentRun) -> f64 {
    surface_z_on(&run.device)
}

/// Where the tissue's surface is on the device named `device`: a replayed capture's depths
/// are measured from it already.
pub fn surface_z_on(device: &str) -> f64 {
    if device.starts_with("replay") {
        0.0
    } else {
        SURFACE_Z_M
    }
}

/// Summarises a segment.
pub fn summarize(run: &SegmentRun) -> SegmentSummary {
    let s = &run.samples;
    let mut max_command_n: f64 = 0.0;
    let mut non_finite = 0;
    for x in s {
        let f = x.command.force_n;
        if f.is_finite() {
            max_command_n = max_command_n.max(f.length());
        } else {
            non_finite += 1;
        }
    }
    let mut layers = Vec::new();
    let mut outside = Vec::new();
    let mut truth_along = None;
    let mut truth_tissue = None;
    let (kind, punctures, max_depth_m, max_model_force_n, ratio) = match &run.segment.kind {
        SegmentKind::Needle { truth, .. } => {
            let surface_z_m = surface_z_m(run);
            let tissue = truth.map(sim::li_bi::NeedleTissueKind::tissue);
            let punctures = punctures(s, tissue.as_ref());
            if let Some(tissue) = &tissue {
                layers = layer_fidelity(s, surface_z_m, tissue);
                if !run.device.starts_with("replay") {
                    truth_along = Some(super::truth_along::along(s, surface_z_m, tissue));
                }
            }
            truth_tissue = truth.map(|t| t.words().to_owned());
            outside = out_of_domain(s, surface_z_m);
            let depth = s
                .iter()
                .map(|x| surface_z_m - x.channels[c::VIRTUAL_Z_M])
                .fold(f64::NEG_INFINITY, f64::max);
            let force = s
                .iter()
                .map(|x| x.channels[c::MODEL_FORCE_Z_N])
                .fold(0.0, f64::max);
            (
                "needle",
                punctures,
                depth.is_finite().then_some(depth),
                force,
                None,
            )
        }
        SegmentKind::Friction { .. } => {
            let (mut sum, mut n) = (0.0, 0usize);
            for x in s {
                let normal = x.channels[c::MODEL_FORCE_Z_N];
                if normal > 0.2 && x.state.velocity_mps.x.abs() > 0.003 {
                    sum += x.channels[c::MODEL_FORCE_X_N].abs() / normal;
                    n += 1;
                }
            }
            let force = s
                .iter()
                .map(|x| x.channels[c::MODEL_FORCE_Z_N])
                .fold(0.0, f64::max);
            (
                "friction",
                Vec::new(),
                None,
                force,
                (n > 0).then(|| sum / n as f64),
            )
        }
        SegmentKind::Surface { .. } => {
            let (mut sum, mut n) = (0.0, 0usize);
            for x in s {
                let normal = x.channels[rub::NORMAL_FORCE_N];
                if x.channels[rub::PHASE] == haptics::RubbingPhase::Rub.code() && normal > 0.1 {
                    sum += x.channels[rub::FRICTION_N] / normal;
                    n += 1;
                }
            }
            let force = s
                .iter()
                .map(|x| x.channels[rub::NORMAL_FORCE_N])
                .fold(0.0, f64::max);
            (
                "surface",
                Vec::new(),
                None,
                force,
                (n > 0).then(|| sum / n as f64),
            )
        }
    };
    let st = &run.stats;
    SegmentSummary {
        object: run.segment.object.clone(),
        kind,
        ticks: st.ticks,
        duration_s: s.last().map_or(0.0, |x| x.time_s),
        mean_rate_hz: st.mean_rate_hz,
        nominal_rate_hz: st.nominal_rate_hz,
        rate_error: st.rate_error(),
        period_error_p99_us: st.period_error.p99.as_secs_f64() * 1e6,
        late_over_2ms: st.late_over_2ms,
        missed_slots: st.missed_slots,
        deadline_rate_error: st.deadline_rate_error(),
        compute_p99_us: st.compute.p99.as_secs_f64() * 1e6,
        stalls: st.stalls,
        longest_stall_ms: st.longest_stall.as_secs_f64() * 1e3,
        max_command_n,
        device_limit_n: run.max_force_n,
        non_finite_commands: non_finite,
        safety_events: st.safety_events,
        model_clamps: st.model_clamps,
        out_of_domain: outside,
        punctures,
        layers,
        truth_along,
        truth_tissue,
        max_depth_m,
        max_model_force_n,
        mean_friction_ratio: ratio,
        device_watchdog: run.hardware_watchdog.map(DeviceWatchdog::from),
        outcome: match &run.outcome {
            Ok(r) => r.clone(),
            Err(e) => format!("error: {e}"),
        },
    }
}

/// Ruptures: the law's state entering `Puncture`.
pub(crate) fn punctures(s: &[HapticSample], tissue: Option<&NeedleTissue>) -> Vec<Puncture> {
    let loading = PunctureState::CapsuleLoading.code();
    let puncture = PunctureState::Puncture.code();
    let mut out: Vec<Puncture> = Vec::new();
    let mut peak: f64 = 0.0;
    // The loading speed at the peak: after it the tool surges forward as the force gives.
    let mut peak_speed_mps = 0.0;
    for w in s.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        if (a.channels[c::ENV_STATE] == loading
            || a.channels[c::ENV_STATE] == PunctureState::Insertion.code())
            && a.channels[c::MODEL_FORCE_Z_N] > peak
        {
            peak = a.channels[c::MODEL_FORCE_Z_N];
            peak_speed_mps = -a.channels[c::VIRTUAL_VZ_MPS];
        }
        if b.channels[c::ENV_STATE] == puncture && a.channels[c::ENV_STATE] != puncture {
            let speed_mps = peak_speed_mps;
            let index = out.len();
            out.push(Puncture {
                time_s: b.time_s,
                depth_m: b.channels[c::ENV_INPUT],
                speed_mps,
                peak_force_n: peak,
                truth_depth_m: tissue.and_then(|t| t.puncture_depth_m(index, speed_mps.max(0.0))),
                truth_peak_force_n: tissue.and_then(|t| t.puncture_peak_force_n(index, speed_mps.max(0.0))),
            });
            peak = 0.0;
        }
    }
    out
}

/// Every membrane of the simulated liver against the drops of the rendered axial force (see
/// [`LayerFidelity`]). A detected drop belongs to the membrane whose rupture depth at the
/// drop's speed is nearest, within the detector's layer gap.
fn layer_fidelity(s: &[HapticSample], surface_z_m: f64, tissue: &NeedleTissue) -> Vec<LayerFidelity> {
    let time: Vec<f64> = s.iter().map(|x| x.time_s).collect();
    let depth: Vec<f64> = s
        .iter()
        .map(|x| surface_z_m - x.channels[c::VIRTUAL_Z_M])
        .collect();
    let velocity: Vec<f64> = s.iter().map(|x| -x.channels[c::VIRTUAL_VZ_MPS]).collect();
    let force: Vec<f64> = s.iter().map(|x| x.channels[c::MODEL_FORCE_Z_N]).collect();
    let params = identify::PunctureParams::default();
    // A run that is not a clean series (a stalled clock repeating a time) detects nothing
    // rather than failing the report; every membrane then reads as missed or not reached.
    let events = identify::detect_punctures(&time, &depth, &velocity, &force, &params)
        .map(|d| d.events)
        .unwrap_or_default();
    let max_depth_m = depth.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (0..tissue.membranes.len())
        .map(|k| {
            let membrane = &tissue.membranes[k];
            let felt = events
                .iter()
                .filter_map(|e| {
                    let truth = tissue.puncture_depth_m(k, e.speed_mps.max(0.0))?;
                    let off = (e.depth_m - truth).abs();
                    (off <= params.layer_gap_m).then_some((off, e))
                })
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .map(|(_, e)| *e);
            // The speed at the membrane: at the felt peak, else where the advancing tool first
            // met the membrane's resting depth.
            let speed_mps = felt.map(|e| e.speed_mps).or_else(|| {
                let i = (0..s.len()).find(|&i| depth[i] >= membrane.depth_m && velocity[i] > 0.0)?;
                Some(velocity[i])
            });
            let truth_depth_m = speed_mps.and_then(|v| tissue.puncture_depth_m(k, v.max(0.0)));
            // The simulated tissue would have given way had the tool gone that deep.
            let reached = truth_depth_m.is_some_and(|d| max_depth_m >= d);
            LayerFidelity {
                name: membrane.name,
                status: if felt.is_some() {
                    "felt"
                } else if reached {
                    "missed"
                } else {
                    "not reached"
                },
                speed_mps,
                truth_depth_m,
                truth_peak_force_n: speed_mps.and_then(|v| tissue.puncture_peak_force_n(k, v.max(0.0))),
                felt_depth_m: felt.map(|e| e.depth_m),
                felt_peak_force_n: felt.map(|e| e.peak_force_n),
                felt_drop_n: felt.map(|e| e.drop_n),
            }
        })
        .collect()
}
