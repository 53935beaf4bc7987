//! Li & Bi's three identification experiments (IEEE/ASME T-Mech 2007, Sec. III-B–D), on their
//! 2-DOF rig: a "finger" carrying a 3-axis strain-gauge force sensor, driven along the surface
//! (motor 1, position via a planetary roller screw and an optical encoder) and pressed or
//! inserted along the normal (motor 2).
//!
//! The rig runs its controllers at 1 kHz; the logging rate and the number of logged samples
//! follow the paper: 31 (pressure, friction) pairs for hard contact, 40 pairs at each of ≥ 8
//! constant velocities for soft contact (the paper has 320 training data), and needle
//! insertions to 3 cm at several speeds up to 10 mm/s (the paper trains on 350 samples). Velocity
//! is estimated from the encoder by the paper's pseudo-differentiation (Eq. 13).

use std::f64::consts::PI;

use capture::kind::{
    AXIAL_FORCE_N, COMMANDED_VELOCITY_MPS, DEPTH_M, FRICTION_FORCE_N, NORMAL_FORCE_N, TANGENTIAL_POSITION_M,
    TANGENTIAL_VELOCITY_MPS, TIME_S, VELOCITY_MPS,
};
use capture::{Capture, CaptureError, CaptureErrorKind, CaptureKind, Metadata};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::columns::Columns;
use super::seed::{derive_seed, tag};
use super::split::Split;
use crate::world::friction::{HardContact, STANDARD_GRAVITY_MPS2, SoftContact, kgf_to_n};
use crate::world::needle::{NeedleSite, NeedleTissue};
use crate::world::sensor::{Encoder, ForceSensor, PseudoDifferentiator, round_to};

/// Device name written into these captures.
pub const DEVICE: &str = "sim-li-bi-rig";
/// Control rate of the rig, Hz.
pub const CONTROL_RATE_HZ: f64 = 1000.0;
/// Encoder quantum of the rig's "high-resolution optical encoder" (the paper gives no number;
/// 1 µm is our assumption).
pub const ENCODER_QUANTUM_M: f64 = 1e-6;
/// Time constant of the pseudo-differentiator (Eq. 13), s.
pub const PSEUDO_DIFF_TAU_S: f64 = 0.01;

/// Resolution at which the rig reports its velocity estimate, m/s.
pub const VELOCITY_QUANTUM_MPS: f64 = 1e-6;

const DT_S: f64 = 1.0 / CONTROL_RATE_HZ;

fn split_tag(split: Split) -> u64 {
    match split {
        Split::Train => 0,
        Split::Test => 1,
    }
}

/// The instruments of Li & Bi's rig: the screw's encoder and the force sensor, whose noise is
/// seeded per experiment and split.
struct Instruments {
    encoder: Encoder,
    sensor: ForceSensor,
    rng: ChaCha8Rng,
}

impl Instruments {
    fn new(seed: u64, experiment: u64, split: Split) -> Self {
        Self {
            encoder: Encoder {
                quantum_m: ENCODER_QUANTUM_M,
            },
            sensor: ForceSensor::li_bi(),
            rng: ChaCha8Rng::seed_from_u64(derive_seed(seed, &[experiment, split_tag(split)])),
        }
    }

    /// The force sensor's reading of `force_n`.
    fn force(&mut self, force_n: f64) -> f64 {
        self.sensor.read(force_n, &mut self.rng)
    }
}

/// Metadata every Li & Bi capture carries.
fn base_metadata(kind: CaptureKind, rate_hz: f64, protocol: &str, split: Split, seed: u64) -> Metadata {
    let sensor = ForceSensor::li_bi();
    Metadata::new(kind, DEVICE, rate_hz)
        .with("protocol", protocol)
        .with("split", split.as_str())
        .with("seed", seed)
        .with("source", "Li-Bi-2007-IEEE-ASME-TMech")
        .with("sensor.force_noise_std_n", sensor.noise_std_n)
        .with("sensor.force_lsb_n", sensor.lsb_n)
        .with("sensor.encoder_quantum_m", ENCODER_QUANTUM_M)
        .with("sensor.velocity", "pseudo-differentiation-Eq13")
        .with("sensor.pseudo_diff_tau_s", PSEUDO_DIFF_TAU_S)
}

/// Hard contact (aluminium plate, Sec. III-B): the finger follows a sine-modulated trajectory
/// along the plate while motor 2 varies the normal force; 31 (pressure, friction) pairs are
/// logged, 0.2 s apart.
///
/// Train: `x = 10 mm/s·t + 1.2 mm·sin(2π·1 Hz·t)`, `P = 0.8 − 0.7·cos(2π t / 6 s)` kgf.
/// Test: `x = 8 mm/s·t + 1 mm·sin(2π·0.7 Hz·t)`, `P = 0.9 + 0.6·sin(2π t / 4.5 s)` kgf.
/// The sine's amplitude is small enough that the finger never stops (friction keeps its sign),
/// as in the paper's data, which are all for positive velocity.
pub fn hard_contact(seed: u64, split: Split) -> Result<Capture, CaptureError> {
    let (v0, amp, freq, p_mid, p_amp, p_period, p_phase) = match split {
        Split::Train => (0.010, 0.0012, 1.0, 0.8, 0.7, 6.0, -PI / 2.0),
        Split::Test => (0.008, 0.0010, 0.7, 0.9, 0.6, 4.5, 0.0),
    };
    let law = HardContact::li_bi();
    let mut rig = Instruments::new(seed, tag::HARD, split);
    let mut diff =
        PseudoDifferentiator::new(DT_S, PSEUDO_DIFF_TAU_S).with_initial_velocity(v0 + amp * 2.0 * PI * freq);
    let log_every = 200;
    let samples = 31;
    let mut cols = Columns::new(&[
        TIME_S,
        TANGENTIAL_POSITION_M,
        TANGENTIAL_VELOCITY_MPS,
        NORMAL_FORCE_N,
        FRICTION_FORCE_N,
    ]);
    for k in 0..=(samples - 1) * log_every {
        let t = k as f64 * DT_S;
        let x = v0 * t + amp * (2.0 * PI * freq * t).sin();
        let x_measured = rig.encoder.read(x);
        let v_measured = round_to(diff.update(x_measured), VELOCITY_QUANTUM_MPS);
        if k % log_every != 0 {
            continue;
        }
        let pressure_n = kgf_to_n(p_mid + p_amp * (2.0 * PI * t / p_period + p_phase).sin());
        let friction_n = law.friction_n(pressure_n);
        cols.push(&[
            k as f64 / CONTROL_RATE_HZ,
            x_measured,
            v_measured,
            rig.force(pressure_n),
            rig.force(friction_n),
        ]);
    }
    let meta = base_metadata(
        CaptureKind::Rubbing,
        CONTROL_RATE_HZ / log_every as f64,
        "li_bi_hard_contact",
        split,
        seed,
    )
    .with("surface", "aluminium_plate")
    .with("truth.law", "F=slope*P+intercept")
    .with("truth.slope", law.slope)
    .with("truth.intercept_n", law.intercept_n)
    .with("paper.eq", "12")
    .with("paper.units", "kgf")
    .with("paper.slope", HardContact::PAPER_SLOPE)
    .with("paper.intercept_kgf", HardContact::PAPER_INTERCEPT_KGF)
    .with("paper.c", "1e11")
    .with("paper.epsilon_kgf", 0.003)
    .with("kgf_n", STANDARD_GRAVITY_MPS2);
    cols.into_capture(meta)
}

/// Sliding speeds of the soft-contact protocol, mm/s: the test speeds interleave the training
/// ones.
pub fn soft_contact_speeds_mmps(split: Split) -> &'static [f64] {
    match split {
        Split::Train => &[2.0, 4.0, 6.0, 9.0, 13.0, 18.0, 24.0, 32.0, 40.0],
        Split::Test => &[3.0, 5.0, 7.5, 11.0, 15.5, 21.0, 28.0, 36.0],
    }
}

/// Soft contact (sponge, Sec. III-C): for each constant sliding speed, motor 2 sweeps the
/// normal force through one cycle between 0.1 and 1.0 kgf while 40 pairs are logged at 20 Hz.
/// Each segment starts with 0.5 s of unlogged travel so the speed and the velocity estimate
/// have settled; `commanded_velocity_mps` names the segment.
pub fn soft_contact(seed: u64, split: Split) -> Result<Capture, CaptureError> {
    let law = SoftContact::sponge();
    let mut rig = Instruments::new(seed, tag::SOFT, split);
    let (p_lo, p_hi) = (kgf_to_n(0.1), kgf_to_n(1.0));
    let per_segment = 40;
    let log_every = 50;
    let settle = 500;
    let mut cols = Columns::new(&[
        TIME_S,
        TANGENTIAL_POSITION_M,
        TANGENTIAL_VELOCITY_MPS,
        COMMANDED_VELOCITY_MPS,
        NORMAL_FORCE_N,
        FRICTION_FORCE_N,
    ]);
    let mut clock = 0usize;
    let speeds = soft_contact_speeds_mmps(split);
    for &speed_mmps in speeds {
        let v = speed_mmps * 1e-3;
        let mut diff = PseudoDifferentiator::new(DT_S, PSEUDO_DIFF_TAU_S);
        // The screw's speed ripples by ±1 % at the roller pass frequency.
        let ripple_hz = 3.0 + speed_mmps * 0.2;
        let steps = settle + per_segment * log_every;
        let mut x = 0.0;
        for k in 0..steps {
            let t = k as f64 * DT_S;
            let v_true = v * (1.0 + 0.01 * (2.0 * PI * ripple_hz * t).sin());
            x += v_true * DT_S;
            let x_measured = rig.encoder.read(x);
            let v_measured = round_to(diff.update(x_measured), VELOCITY_QUANTUM_MPS);
            if k >= settle && (k - settle) % log_every == 0 {
                let phase = (k - settle) as f64 / (per_segment * log_every) as f64;
                let pressure_n = p_lo + (p_hi - p_lo) * 0.5 * (1.0 - (2.0 * PI * phase).cos());
                let friction_n = law.friction_n(v_true, pressure_n);
                cols.push(&[
                    (clock + k) as f64 / CONTROL_RATE_HZ,
                    x_measured,
                    v_measured,
                    v,
                    rig.force(pressure_n),
                    rig.force(friction_n),
                ]);
            }
        }
        clock += steps;
    }
    let speeds_list: Vec<String> = speeds.iter().map(|s| format!("{}", s * 1e-3)).collect();
    let mut meta = base_metadata(
        CaptureKind::Rubbing,
        CONTROL_RATE_HZ / log_every as f64,
        "li_bi_soft_contact",
        split,
        seed,
    )
    .with("surface", "sponge")
    .with("segments", speeds.len())
    .with("samples_per_segment", per_segment)
    .with("speeds_mps", speeds_list.join(";"))
    .with(
        "truth.law",
        "F=w(v)*P+m(v)|w=w0+w1*(1-exp(-v/v1))+w2*exp(-(v/v2)^2)|m=m0+m1*tanh(v/vm)",
    );
    for (name, value) in law.parameters() {
        meta.insert(format!("truth.{name}"), value);
    }
    cols.into_capture(meta)
}

/// Insertion speeds of the needle protocol, mm/s.
pub fn needle_speeds_mmps(split: Split) -> &'static [f64] {
    match split {
        Split::Train => &[1.0, 2.5, 5.0, 7.5, 10.0],
        Split::Test => &[1.5, 4.0, 6.0, 9.0],
    }
}

/// Which simulated tissue the needle goes into.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NeedleTissueKind {
    /// [`NeedleTissue::bovine_liver`]: capsule and a vessel wall (the paper's fresh liver).
    #[default]
    BovineLiver,
    /// [`NeedleTissue::layered_phantom`]: three membranes, other parameters.
    LayeredPhantom,
    /// [`NeedleTissue::lumbar_epidural`]: skin to dura along a lumbar epidural approach.
    LumbarEpidural,
}

impl NeedleTissueKind {
    /// The tissue.
    pub fn tissue(self) -> NeedleTissue {
        match self {
            Self::BovineLiver => NeedleTissue::bovine_liver(),
            Self::LayeredPhantom => NeedleTissue::layered_phantom(),
            Self::LumbarEpidural => NeedleTissue::lumbar_epidural(),
        }
    }

    /// Its name in capture metadata.
    pub fn name(self) -> &'static str {
        match self {
            Self::BovineLiver => "bovine_liver",
            Self::LayeredPhantom => "layered_phantom",
            Self::LumbarEpidural => "lumbar_epidural",
        }
    }

    /// How a report names it ("the simulated liver").
    pub fn words(self) -> &'static str {
        match self {
            Self::BovineLiver => "liver",
            Self::LayeredPhantom => "layered phantom",
            Self::LumbarEpidural => "lumbar spine",
        }
    }

    /// The tissue a capture's metadata names ([`NeedleTissueKind::name`]); `None` for any
    /// other name.
    pub fn named(name: &str) -> Option<Self> {
        [Self::BovineLiver, Self::LayeredPhantom, Self::LumbarEpidural]
            .into_iter()
            .find(|k| k.name() == name)
    }

    /// How deep the protocol inserts, m: 30 mm into the liver and the phantom (the paper's), 55
    /// mm into the lumbar spine, past the dura, so that a capture shows every layer give.
    pub fn insertion_depth_m(self) -> f64 {
        match self {
            Self::BovineLiver | Self::LayeredPhantom => 0.030,
            Self::LumbarEpidural => 0.055,
        }
    }
}

/// How the insertion speed behaves within one stroke.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SpeedProfile {
    /// The nominal speed throughout (the paper's protocol).
    #[default]
    Constant,
    /// The nominal speed modulated by ±60 % with a 1.3 s period, as a hand varies it: every
    /// membrane is loaded and ruptured at a speed of its own.
    Varying,
}

impl SpeedProfile {
    /// Factor on the nominal speed `t_s` into the stroke.
    fn factor(self, t_s: f64) -> f64 {
        match self {
            Self::Constant => 1.0,
            Self::Varying => 1.0 + 0.6 * (std::f64::consts::TAU * t_s / 1.3).sin(),
        }
    }
}

/// How the needle protocol logs, how often it repeats its insertions, into what and how fast.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NeedleProtocol {
    /// Logging rate, Hz: a divisor of [`CONTROL_RATE_HZ`] (the paper's rig logs at 100 Hz).
    pub log_rate_hz: u32,
    /// Times the whole set of speeds is inserted, each insertion at a fresh site.
    pub rounds: u32,
    /// The tissue.
    pub tissue: NeedleTissueKind,
    /// The speed within each stroke.
    pub speed: SpeedProfile,
}

impl Default for NeedleProtocol {
    /// The paper's protocol: 100 Hz, one insertion per speed into the liver, each at
    /// constant speed.
    fn default() -> Self {
        Self {
            log_rate_hz: 100,
            rounds: 1,
            tissue: NeedleTissueKind::BovineLiver,
            speed: SpeedProfile::Constant,
        }
    }
}

impl NeedleProtocol {
    /// Control ticks per logged sample; `None` unless the rate divides [`CONTROL_RATE_HZ`].
    pub fn log_every(&self) -> Option<usize> {
        let control = CONTROL_RATE_HZ as u32;
        (self.log_rate_hz > 0 && control.is_multiple_of(self.log_rate_hz))
            .then(|| (control / self.log_rate_hz) as usize)
    }
}

/// Needle puncture (Sec. III-D, fresh liver): for each speed, a fresh insertion site; the tip
/// starts 2 mm above the surface, accelerates over 50 ms, inserts to 30 mm (the tissue's
/// [`NeedleTissueKind::insertion_depth_m`] for another tissue), holds 1 s and
/// withdraws at 10 mm/s to where it started. Logged at 100 Hz.
pub fn needle_insertion(seed: u64, split: Split) -> Result<Capture, CaptureError> {
    needle_insertion_with(seed, split, NeedleProtocol::default())
}

/// [`needle_insertion`] logged at another rate and with the speeds repeated: larger training
/// sets from the same tissue and rig (benchmarks of the fit at tens of thousands of samples).
/// The default protocol gives [`needle_insertion`]'s capture, byte for byte.
///
/// # Errors
/// A log rate that does not divide the control rate, or zero rounds, is
/// [`CaptureErrorKind::BadMetadata`]; otherwise as [`needle_insertion`].
pub fn needle_insertion_with(
    seed: u64,
    split: Split,
    protocol: NeedleProtocol,
) -> Result<Capture, CaptureError> {
    let tissue = protocol.tissue.tissue();
    let mut rig = Instruments::new(seed, tag::NEEDLE, split);
    let Some(log_every) = protocol.log_every().filter(|_| protocol.rounds > 0) else {
        return Err(CaptureError::without_file(CaptureErrorKind::BadMetadata(
            format!(
                "needle protocol: log rate {} Hz must divide the {CONTROL_RATE_HZ} Hz control rate and rounds ({}) must be at least 1",
                protocol.log_rate_hz, protocol.rounds
            ),
        )));
    };
    let target_m = protocol.tissue.insertion_depth_m();
    let (start_m, withdraw_mps, ramp_s, hold_s, rest_s) = (-0.002, 0.010, 0.05, 1.0, 0.3);
    let mut cols = Columns::new(&[
        TIME_S,
        DEPTH_M,
        VELOCITY_MPS,
        COMMANDED_VELOCITY_MPS,
        AXIAL_FORCE_N,
    ]);
    let mut per_insertion: Vec<(String, String)> = Vec::new();
    let mut clock = 0usize;
    let speeds = needle_speeds_mmps(split);
    let rounds = speeds
        .iter()
        .cycle()
        .take(speeds.len() * protocol.rounds as usize);
    for (index, &speed_mmps) in rounds.enumerate() {
        let speed = speed_mmps * 1e-3;
        let mut site = NeedleSite::new(tissue.clone());
        let mut diff = PseudoDifferentiator::new(DT_S, PSEUDO_DIFF_TAU_S);
        let mut depth = start_m;
        let mut phase = Phase::Rest(0.0);
        let mut k = 0usize;
        per_insertion.push((format!("insertion.{index}.speed_mps"), speed.to_string()));
        per_insertion.push((
            format!("insertion.{index}.start_s"),
            (clock as f64 / CONTROL_RATE_HZ).to_string(),
        ));
        loop {
            // The commanded velocity: rest, smooth ramp up, cruise, hold, withdraw.
            let command = match phase {
                Phase::Rest(t) if t < rest_s => 0.0,
                Phase::Rest(_) => {
                    phase = Phase::Insert(0.0);
                    continue;
                }
                Phase::Insert(t) if depth < target_m => {
                    speed * smooth_ramp(t / ramp_s) * protocol.speed.factor(t)
                }
                Phase::Insert(_) => {
                    phase = Phase::Hold(0.0);
                    continue;
                }
                Phase::Hold(t) if t < hold_s => 0.0,
                Phase::Hold(_) => {
                    phase = Phase::Withdraw(0.0);
                    continue;
                }
                Phase::Withdraw(t) if depth > start_m => -withdraw_mps * smooth_ramp(t / ramp_s),
                Phase::Withdraw(_) => break,
            };
            depth += command * DT_S;
            let force = site.step(depth, command, DT_S);
            let depth_measured = rig.encoder.read(depth);
            let v_measured = round_to(diff.update(depth_measured), VELOCITY_QUANTUM_MPS);
            if k.is_multiple_of(log_every) {
                cols.push(&[
                    (clock + k) as f64 / CONTROL_RATE_HZ,
                    depth_measured,
                    v_measured,
                    command,
                    rig.force(force.axial_force_n),
                ]);
            }
            phase = phase.advance(DT_S);
            k += 1;
        }
        let punctures: Vec<String> = site.puncture_depths_m().iter().map(|d| format!("{d}")).collect();
        per_insertion.push((
            format!("truth.insertion.{index}.puncture_depths_m"),
            punctures.join(";"),
        ));
        clock += k + 500;
    }
    let speeds_list: Vec<String> = speeds.iter().map(|s| format!("{}", s * 1e-3)).collect();
    let mut full = base_metadata(CaptureKind::Insertion, CONTROL_RATE_HZ / log_every as f64, "li_bi_needle", split, seed)
        .with("tissue", protocol.tissue.name())
        .with("insertions", speeds.len() * protocol.rounds as usize)
        .with("speeds_mps", speeds_list.join(";"))
        .with("target_depth_m", target_m)
        .with("withdraw_speed_mps", withdraw_mps)

        .with("truth.model", "Okamura-2004:stiffness(a1*u+a2*u^2)+cutting+Karnopp-friction|Mahvash-Dupont-2010:rate-dependent-puncture");
    // Only a varying profile says so: the paper's protocol keeps its bytes.
    if protocol.speed == SpeedProfile::Varying {
        full.insert("speed_profile", "varying(1+0.6*sin(2*pi*t/1.3s))");
    }
    for (name, value) in tissue.parameters() {
        full.insert(format!("truth.{name}"), value);
    }
    for (key, value) in per_insertion {
        full.insert(key, value);
    }
    cols.into_capture(full)
}

#[derive(Debug, Clone, Copy)]
enum Phase {
    Rest(f64),
    Insert(f64),
    Hold(f64),
    Withdraw(f64),
}

impl Phase {
    fn advance(self, dt: f64) -> Self {
        match self {
            Self::Rest(t) => Self::Rest(t + dt),
            Self::Insert(t) => Self::Insert(t + dt),
            Self::Hold(t) => Self::Hold(t + dt),
            Self::Withdraw(t) => Self::Withdraw(t + dt),
        }
    }
}

/// 0 → 1 with zero slope at both ends (smoothstep), saturating at 1.
fn smooth_ramp(u: f64) -> f64 {
    let u = u.clamp(0.0, 1.0);
    u * u * (3.0 - 2.0 * u)
}

#[cfg(test)]
mod needle_protocol_tests {
    use super::*;

    #[test]
    fn a_faster_log_and_more_rounds_give_proportionally_more_samples() {
        let paper = needle_insertion(3, Split::Train).unwrap();
        let same = needle_insertion_with(3, Split::Train, NeedleProtocol::default()).unwrap();
        assert_eq!(paper.len(), same.len());
        assert_eq!(
            paper.column(AXIAL_FORCE_N).unwrap(),
            same.column(AXIAL_FORCE_N).unwrap()
        );
        let dense = NeedleProtocol {
            log_rate_hz: 500,
            rounds: 2,
            ..NeedleProtocol::default()
        };
        let big = needle_insertion_with(3, Split::Train, dense).unwrap();
        // 5× the rate, 2× the insertions: every control tick that was logged at 100 Hz and the
        // four between, twice over (± one sample per insertion at the ends).
        let ratio = big.len() as f64 / paper.len() as f64;
        assert!(
            (ratio - 10.0).abs() < 0.05,
            "{} / {} = {ratio}",
            big.len(),
            paper.len()
        );
        assert_eq!(big.metadata().get("insertions"), Some("10"));
        let time = big.time();
        assert!(time.windows(2).all(|w| w[1] > w[0]), "time must increase");
        for bad in [
            NeedleProtocol {
                log_rate_hz: 300,
                rounds: 1,
                ..NeedleProtocol::default()
            },
            NeedleProtocol {
                log_rate_hz: 100,
                rounds: 0,
                ..NeedleProtocol::default()
            },
        ] {
            let e = needle_insertion_with(3, Split::Train, bad).unwrap_err();
            assert!(e.to_string().contains("needle protocol"), "{e}");
        }
    }
}
