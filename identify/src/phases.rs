//! A phase-aware needle-puncture model: layers found in the data, each with its own loading,
//! puncture threshold and the force after it, and the state machine that renders them.
//!
//! One smooth surface over [depth, velocity] cannot hold a process with thresholds and memory:
//! the drop at a puncture is spread over the kernel's width, a layer whose drop is small is
//! smoothed away, and the same (depth, velocity) means "pushing an intact membrane" in one
//! stroke and "sliding through the hole" in the next. The model here follows the structure of
//! Okamura, Simone & O'Leary (IEEE TBME 51(10), 2004) — stiffness before a puncture, friction
//! and cutting after — with every part identified from the capture:
//!
//! | phase | force | fitted on |
//! |---|---|---|
//! | loading layer k (intact membrane, from its contact depth c_k) | `F_{k−1}(d, v⁺) + f0 + a1·u + a2·u² + b·v⁺`, `u = d − c_k` | advancing samples between the contact and the puncture |
//! | puncture of layer k | when `u ≥ u_k(v)`, a polynomial in speed through the detected events; the force falls to the next phase's within the tick | the events of the layer |
//! | cutting after layer k (advancing into uncut tissue) | `F_k(d, v) = g0 + g1·d + g2·v + g3·d·v` | advancing samples past the puncture's drop |
//! | withdrawal | `W(d, v)`, same form | withdrawing samples in tissue |
//! | re-insertion along the cut channel | `−W(d, −v)` (friction is odd in velocity) | — |
//! | held, or reversing (from the hold band on the last side moved to, to [`REVERSAL_MPS`] the other way) | linear in v between the two directions' laws at the band's ends | — |
//!
//! A term a phase's samples do not determine is left out ([`Varies`]: depth terms need 3 mm of
//! depth, speed terms several speeds), and a cutting or withdrawal law may be an ε-SVR
//! ([`PartSvr`]) where one predicted held-out strokes clearly better ([`crate::PartComparison`]).
//!
//! Layers and their events come from [`crate::detect_punctures`] and [`crate::group_layers`]
//! ([`crate::identify_phases`]);
//! each contact depth `c_k` is the one, among a grid between the layer before and the layer's
//! shallowest event, whose split of the advancing samples into "cutting before" and "loading"
//! fits both laws best (least squares, total squared error). Punctured layers stay punctured
//! until the tool leaves the tissue (depth ≤ 0): the holes stay where they are.
//!
//! **Known domain.** Every phase records the depths and velocities it was fitted on. Outside
//! them its law is evaluated at the nearest trained velocity (a faster surge feels the
//! friction of the fastest trained speed, not an extrapolated viscous term) and, past a margin
//! of a tenth of its depth range, at the nearest such depth (a linear depth term carried to the
//! end of a device's stroke turned a layer's resistance into a pull), and the step says it
//! left the domain so that the run can count it. The threshold likewise uses the nearest
//! trained speed; a membrane's deflection never exceeds its largest threshold.
//!
//! [`PhaseModel::step`] is allocation-free and the same code renders the model on the haptic
//! thread and evaluates it along a capture here ([`PhaseModel::simulate`]), so the identify
//! report measures exactly what a trainee will feel.

use serde::{Deserialize, Serialize};

use crate::baselines::{Rank, least_squares};
use crate::error::IdentifyError;
use crate::plausibility::check_svr_parts;
use faer::Mat;
use svm::{InputScaling, SvrModel};

/// Most layers a model holds.
pub const MAX_LAYERS: usize = 8;

/// Speed the tool must reach the other way for shaft friction to have fully reversed, m/s
/// (see [`PhaseModel::step`]). 2 mm/s, the speed over which the app regularises Coulomb
/// friction on surfaces too: a tool held by a hand under admittance control trembles at up to
/// about 1 mm/s, and a hard reversal inside that band flips ±0.4 N every few milliseconds;
/// spread over 2 mm/s, the 0.8 N between the two directions is a 400 N·s/m slope, which a
/// 0.8 kg virtual tool at 1 kHz renders stably.
pub const REVERSAL_MPS: f64 = 0.002;

/// Speed below which the tool reads as at rest where shaft friction reverses, m/s. A tool
/// held by a hand under admittance control creeps and trembles by a few tenths of a
/// millimetre per second at 1 kHz; read directly, that jitter crossed the reversal band's
/// slope (about 350 N·s/m) and made the held force chatter. The band reads
/// `sgn(v)·max(|v| − HOLD_JITTER_MPS, 0)`, and it is flat on the side the tool last moved to
/// (see [`PhaseModel::step`]): continuous, still within the jitter, and a real reversal still
/// passes the whole band, 0.5 mm/s later.
pub const HOLD_JITTER_MPS: f64 = 5e-4;

/// How far behind the deepest point cut the tip still bears on uncut tissue, m: a tenth of a
/// millimetre, about a needle tip's bevel, and far more than a held hand creeps.
pub const TIP_CONTACT_M: f64 = 1e-4;

/// How far past a phase's trained range, as a fraction of its width or of its largest
/// magnitude (whichever is larger: a protocol at one speed has a range of almost no width), an
/// input still counts as inside it.
const DOMAIN_MARGIN: f64 = 0.1;

/// Share of the fitted samples' velocities left out at each end of a phase's velocity range:
/// a stroke's start and end pass through every speed below its own, too briefly to pin a
/// speed dependence there, so a law fitted at one withdrawal speed would otherwise be trusted
/// down to rest.
const VELOCITY_TAIL: f64 = 0.02;

/// Depths and velocities a phase was fitted on: the samples' depth range, and the range of
/// their velocities between the 2nd and the 98th percentile.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Domain {
    /// [min, max] depth, m.
    pub depth_m: [f64; 2],
    /// [min, max] velocity, m/s.
    pub velocity_mps: [f64; 2],
}

impl Domain {
    pub(crate) fn of(d: &[f64], v: &[f64]) -> Self {
        let span = d.iter().fold([f64::INFINITY, f64::NEG_INFINITY], |[lo, hi], &a| {
            [lo.min(a), hi.max(a)]
        });
        let mut sorted = v.to_vec();
        sorted.sort_by(f64::total_cmp);
        let at = |q: f64| {
            let i = (q * (sorted.len().saturating_sub(1)) as f64).round() as usize;
            sorted.get(i).copied().unwrap_or(f64::NAN)
        };
        Self {
            depth_m: span,
            velocity_mps: [at(VELOCITY_TAIL), at(1.0 - VELOCITY_TAIL)],
        }
    }

    /// `range` widened by the margin within which an input still counts as inside.
    fn widened(range: [f64; 2]) -> [f64; 2] {
        let m = DOMAIN_MARGIN * (range[1] - range[0]).max(range[0].abs().max(range[1].abs()));
        [range[0] - m, range[1] + m]
    }

    fn inside(range: [f64; 2], x: f64) -> bool {
        let [lo, hi] = Self::widened(range);
        x >= lo && x <= hi
    }

    /// The depths a shaft law is evaluated at: its trained range with the margin. Deeper or
    /// shallower, the law holds the nearest such depth (and the step says the input left the
    /// domain): a linear depth term fitted over 18 mm and carried to the end of a device's
    /// stroke turned the deepest layer's resistance into a 4 N pull.
    pub fn depth_held_m(&self) -> [f64; 2] {
        Self::widened(self.depth_m)
    }

    /// Whether (d, v) lies inside, with the margin.
    pub fn contains(&self, depth_m: f64, velocity_mps: f64) -> bool {
        Self::inside(self.depth_m, depth_m) && Self::inside(self.velocity_mps, velocity_mps)
    }

    fn clamp_velocity(&self, v: f64) -> f64 {
        v.clamp(self.velocity_mps[0], self.velocity_mps[1])
    }
}

/// An ε-SVR of [depth, velocity] standing in for a phase's linear law
/// ([`ShaftLaw::svr`]), inputs scaled as `scaling` says.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PartSvr {
    /// Input scaling applied before the SVR.
    pub scaling: InputScaling,
    /// The SVR.
    pub svr: SvrModel,
}

impl PartSvr {
    /// Allocation-free: the two scaled inputs live on the stack.
    pub(crate) fn eval(&self, d: f64, v: f64) -> f64 {
        let mut scaled = [0.0; 2];
        self.scaling.apply_into(&[d, v], &mut scaled);
        self.svr.predict(&scaled)
    }

    fn valid(&self) -> bool {
        let finite = |x: &[f64]| x.iter().all(|a| a.is_finite());
        self.svr.dim == 2
            && self.scaling.offset.len() == 2
            && self.scaling.scale.len() == 2
            && self.scaling.scale.iter().all(|s| s.is_finite() && *s > 0.0)
            && finite(&self.scaling.offset)
            && finite(&self.svr.coefficients)
            && finite(&self.svr.support_vectors)
            && self.svr.support_vectors.len() == 2 * self.svr.coefficients.len()
            && self.svr.bias.is_finite()
            && self.svr.weights.is_none()
    }
}

/// `F(d, v) = constant + per_depth·d + per_speed·v + per_depth_speed·d·v`: friction along the
/// inserted shaft (∝ d), cutting and Coulomb friction (constant), viscous friction (∝ v, ∝ d·v).
/// Where an ε-SVR of the same samples predicted held-out strokes clearly better, it replaces
/// these terms (`svr`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShaftLaw {
    /// N.
    pub constant_n: f64,
    /// N/m.
    pub per_depth_npm: f64,
    /// N·s/m.
    pub per_speed_nspm: f64,
    /// N·s/m².
    pub per_depth_speed_nspm2: f64,
    /// What it was fitted on.
    pub domain: Domain,
    /// The ε-SVR that replaces the linear terms, when it won ([`crate::PartComparison`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub svr: Option<PartSvr>,
}

impl ShaftLaw {
    fn features(d: f64, v: f64) -> [f64; 4] {
        [1.0, d, v, d * v]
    }

    pub(crate) fn eval_raw(&self, d: f64, v: f64) -> f64 {
        if let Some(svr) = &self.svr {
            return svr.eval(d, v);
        }
        self.linear(d, v)
    }

    /// The linear terms alone.
    pub(crate) fn linear(&self, d: f64, v: f64) -> f64 {
        self.constant_n
            + self.per_depth_npm * d
            + self.per_speed_nspm * v
            + self.per_depth_speed_nspm2 * d * v
    }

    /// The force at (d, v) with v held to the trained velocities and d not held: as the
    /// identification fitted a membrane's loading on top of it.
    pub(crate) fn eval_extrapolated(&self, d: f64, v: f64) -> f64 {
        self.eval_raw(d, self.domain.clamp_velocity(v))
    }

    /// The force at (d, v), v held to the trained velocities and d to the trained depths with
    /// their margin ([`Domain::depth_held_m`]), and whether (d, v) was inside.
    pub fn eval(&self, d: f64, v: f64) -> (f64, bool) {
        let [lo, hi] = self.domain.depth_held_m();
        (
            self.eval_raw(d.clamp(lo, hi), self.domain.clamp_velocity(v)),
            self.domain.contains(d, v),
        )
    }

    /// Least squares over the terms the samples can determine (see [`Varies`]); the others
    /// are 0.
    /// Without the speed terms unless `with_speed`.
    pub(crate) fn fit_restricted(
        d: &[f64],
        v: &[f64],
        f: &[f64],
        with_speed: bool,
    ) -> Result<(Self, f64), IdentifyError> {
        let varies = Varies::of(d, v);
        let speed = with_speed && varies.speed;
        let keep = [true, varies.depth, speed, varies.depth && speed];
        let x = fit_terms(d.len(), |i| Self::features(d[i], v[i]), keep, f)?;
        let law = Self {
            constant_n: x[0],
            per_depth_npm: x[1],
            per_speed_nspm: x[2],
            per_depth_speed_nspm2: x[3],
            domain: Domain::of(d, v),
            svr: None,
        };
        let sse = (0..d.len())
            .map(|i| (f[i] - law.eval_raw(d[i], v[i])).powi(2))
            .sum();
        Ok((law, sse))
    }
}

/// The force an intact membrane adds while it deflects by `u = d − contact`:
/// `offset + a1·u + a2·u² + damping·v` (Okamura's `a1·u + a2·u²` with a viscous part, and an
/// offset for what changes at contact, e.g. cutting stopping while the membrane is pushed).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Loading {
    /// N.
    pub offset_n: f64,
    /// N/m.
    pub a1_npm: f64,
    /// N/m².
    pub a2_npm2: f64,
    /// N·s/m.
    pub damping_nspm: f64,
    /// What it was fitted on (depth of the tip, not the deflection).
    pub domain: Domain,
}

impl Loading {
    pub(crate) fn features(u: f64, v: f64) -> [f64; 4] {
        [1.0, u, u * u, v]
    }

    pub(crate) fn eval_raw(&self, u: f64, v: f64) -> f64 {
        self.offset_n + self.a1_npm * u + self.a2_npm2 * u * u + self.damping_nspm * v
    }
}

/// The deflection at which a membrane gives, as a polynomial in the insertion speed:
/// `u(v) = Σ coefficients[i]·vⁱ`, at speeds held to the events' range.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Threshold {
    /// Polynomial coefficients, constant first (m, m/(m/s), …); one to three of them.
    pub coefficients: Vec<f64>,
    /// [min, max] speed of the events it was fitted on, m/s.
    pub speed_mps: [f64; 2],
    /// RMS of the fit over the events, m.
    pub rms_m: f64,
}

impl Threshold {
    /// The largest deflection at puncture at any speed, m: the polynomial (degree ≤ 2) is
    /// largest at an end of its speed range or at its vertex.
    pub fn max_deflection_m(&self) -> f64 {
        self.extreme_deflection_m(f64::max)
    }

    /// The least deflection at puncture at any speed, m.
    pub fn min_deflection_m(&self) -> f64 {
        self.extreme_deflection_m(f64::min)
    }

    fn extreme_deflection_m(&self, pick: fn(f64, f64) -> f64) -> f64 {
        let [v0, v1] = self.speed_mps;
        let vertex = match self.coefficients.as_slice() {
            [_, b, c] if *c != 0.0 => Some(-b / (2.0 * c)).filter(|v| (v0..=v1).contains(v)),
            _ => None,
        };
        let ends = pick(self.deflection_m(v0), self.deflection_m(v1));
        vertex.map_or(ends, |v| pick(ends, self.deflection_m(v)))
    }

    /// Deflection at puncture for a tip advancing at `speed_mps`, m (at least 0.1 mm).
    pub fn deflection_m(&self, speed_mps: f64) -> f64 {
        let v = speed_mps.clamp(self.speed_mps[0], self.speed_mps[1]);
        let mut u = 0.0;
        for &c in self.coefficients.iter().rev() {
            u = u * v + c;
        }
        u.max(1e-4)
    }
}

/// One layer: its membrane's contact, loading and threshold, and the cutting after it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LayerModel {
    /// Depth at which the tip meets the membrane, m.
    pub contact_depth_m: f64,
    /// Force the intact membrane adds.
    pub loading: Loading,
    /// When it gives.
    pub threshold: Threshold,
    /// Advancing into uncut tissue after it.
    pub after: ShaftLaw,
    /// Puncture events of the training capture in this layer.
    pub events: usize,
    /// Median measured peak of those events, N.
    pub peak_force_n: f64,
}

/// The phase-aware model (see the module documentation).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PhaseModel {
    /// The force in tissue above the first membrane (cutting and shaft friction of what lies
    /// over it), when the capture has any: a membrane under skin or fat is reached through
    /// tissue that already resists. Files without it: none (the first membrane at the
    /// surface).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub above: Option<ShaftLaw>,
    /// Layers, shallowest first.
    pub layers: Vec<LayerModel>,
    /// Withdrawal friction.
    pub withdrawal: ShaftLaw,
    /// Where [`PhaseModel::withdrawal`] comes from (files without the field: measured).
    #[serde(default)]
    pub withdrawal_source: WithdrawalSource,
    /// |v| below which the needle counts as held, m/s.
    pub hold_band_mps: f64,
}

/// Where a phase model's withdrawal law comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WithdrawalSource {
    /// Fitted on the capture's withdrawing samples in punctured tissue.
    #[default]
    Measured,
    /// The capture holds no withdrawal (an insertion-only record): the law is the shaft
    /// friction the insertion measured below the deepest layer, its depth term
    /// (`per_depth_npm` of that layer's cutting law, when positive) with the sign of the
    /// motion, `F = −k·d` pulling out; no cutting, no viscous term. It is bounded by what the
    /// insertion felt: `k·d` is at most the cutting law's own depth part over the inserted
    /// length, and 0 where the insertion measured no depth dependence.
    FromInsertion,
}

impl WithdrawalSource {
    /// `measured`, or what stands in for the law.
    pub fn describe(self) -> &'static str {
        match self {
            Self::Measured => "measured",
            Self::FromInsertion => {
                "not measured (no withdrawal in the capture): the insertion's shaft friction below the \
                 deepest layer, with the sign of the motion"
            }
        }
    }
}

/// Where a step finds the needle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Phase {
    /// Not in tissue, or above the first membrane.
    Air,
    /// Deflecting layer k's intact membrane.
    Loading(usize),
    /// Advancing into uncut tissue below layer k.
    Cutting(usize),
    /// Advancing along the channel cut before.
    Channel,
    /// Held.
    Held,
    /// Withdrawing.
    Withdrawal,
}

impl Phase {
    /// `loading layer 2`, `cutting below layer 1`, `channel`, `held`, `withdrawal`, `air`
    /// (layers counted from 1).
    pub fn describe(self) -> String {
        match self {
            Self::Air => "air".into(),
            Self::Loading(k) => format!("loading layer {}", k + 1),
            Self::Cutting(k) => format!("cutting below layer {}", k + 1),
            Self::Channel => "channel".into(),
            Self::Held => "held".into(),
            Self::Withdrawal => "withdrawal".into(),
        }
    }
}

/// Rows of a trajectory outside the domain of one phase ([`PhaseModel::domain_exits`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PhaseExit {
    /// Which phase ([`Phase::describe`]).
    pub phase: String,
    /// How many rows.
    pub rows: usize,
    /// Their share of the trajectory's rows in tissue.
    pub fraction: f64,
    /// [min, max] depth over them, m.
    pub depth_m: [f64; 2],
    /// [min, max] velocity over them, m/s.
    pub velocity_mps: [f64; 2],
}

/// The memory of one insertion site. `Default` is a fresh, intact site.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PhaseState {
    punctured: usize,
    deepest_m: f64,
    /// The last step it moved, it moved out.
    backward: bool,
}

impl PhaseState {
    /// Layers punctured so far.
    pub fn punctured(&self) -> usize {
        self.punctured
    }
}

/// One rupture of a trajectory ([`PhaseModel::ruptures_along`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Rupture {
    /// The sample at which the model gives.
    pub index: usize,
    /// Which layer (0: the shallowest).
    pub layer: usize,
    /// Depth of the tip at the threshold, m.
    pub depth_m: f64,
    /// The force just before it, N.
    pub peak_force_n: f64,
    /// The force at the sample after it, N.
    pub force_after_n: f64,
}

/// What one step gives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhaseStep {
    /// Axial force, positive pushing the needle out, N.
    pub force_n: f64,
    /// The phase after the step.
    pub phase: Phase,
    /// A layer gave way at this step.
    pub ruptured: bool,
    /// (d, v) lay outside the trained domain of the phase's law.
    pub out_of_domain: bool,
}

impl PhaseModel {
    /// The force of the phase below `punctured` layers while advancing into uncut tissue
    /// (above the first layer: [`PhaseModel::above`], or 0).
    fn cutting(&self, punctured: usize, d: f64, v: f64) -> (f64, bool) {
        match punctured.checked_sub(1).and_then(|k| self.layers.get(k)) {
            Some(layer) => layer.after.eval(d, v),
            None => self.above.as_ref().map_or((0.0, true), |l| l.eval(d, v)),
        }
    }

    /// The law under a loading membrane below `punctured` layers, extended in depth as the
    /// identification fitted the loading on top of it (0 with no tissue above the first).
    fn base(&self, punctured: usize, d: f64, v: f64) -> f64 {
        match punctured.checked_sub(1).and_then(|k| self.layers.get(k)) {
            Some(layer) => layer.after.eval_extrapolated(d, v),
            None => self.above.as_ref().map_or(0.0, |l| l.eval_extrapolated(d, v)),
        }
    }

    /// Advances `state` with the tip at `depth_m` moving at `velocity_mps` (positive
    /// inserting). Allocation-free; non-finite inputs read as a tip at rest outside.
    pub fn step(&self, state: &mut PhaseState, depth_m: f64, velocity_mps: f64) -> PhaseStep {
        let d = if depth_m.is_finite() { depth_m } else { 0.0 };
        let v = if velocity_mps.is_finite() {
            velocity_mps
        } else {
            0.0
        };
        let out = |force_n: f64, phase: Phase, ruptured: bool, inside: bool| PhaseStep {
            force_n: if force_n.is_finite() { force_n } else { 0.0 },
            phase,
            ruptured,
            out_of_domain: !inside,
        };
        if d <= 0.0 {
            *state = PhaseState::default();
            return out(0.0, Phase::Air, false, true);
        }
        // What the reversal band reads: rest within the hold's jitter.
        let vp = v.signum() * (v.abs() - HOLD_JITTER_MPS).max(0.0);
        let band = self.hold_band_mps;
        let mut ruptured = false;
        if let Some(layer) = self.layers.get(state.punctured)
            && d > layer.contact_depth_m
        {
            let u = d - layer.contact_depth_m;
            // The membrane gives once the advancing tip deflects it to its threshold, at any
            // speed: a slow push ruptures it too (held to the hold band, a creeping hand
            // loaded it without end, past 50 N at 80 mm in the liver's model).
            if v > 0.0 && u >= layer.threshold.deflection_m(v) {
                state.punctured += 1;
                ruptured = true;
            } else {
                // Backing off an intact membrane unloads it elastically: no friction reversal.
                let ahead = v.max(0.0);
                let l = &layer.loading;
                let vl = l.domain.clamp_velocity(ahead);
                // A deflection past every threshold is reached only by a jump in depth (a tip
                // that moves continuously gives way first): the membrane's force stops growing
                // there, so it stays within what the force check proves.
                let max_u = layer.threshold.max_deflection_m();
                let u = u.min(max_u);
                // The loading was fitted on top of the law before it, extended to these depths
                // (to the deepest the membrane can be pushed), so only the loading's own domain
                // says whether the inputs are known.
                let base = self.base(state.punctured, d.min(layer.contact_depth_m + max_u), vl);
                let inside = v <= band || l.domain.contains(d, v);
                return out(
                    base + l.eval_raw(u, vl),
                    Phase::Loading(state.punctured),
                    false,
                    inside,
                );
            }
        }
        if state.punctured == 0 {
            // Above the first membrane: its tissue's law while advancing; held or backing out,
            // the force eases linearly to nothing at [`REVERSAL_MPS`] outwards (no friction
            // law was measured for it the other way).
            let Some(above) = &self.above else {
                return out(0.0, Phase::Air, false, true);
            };
            if vp > band {
                let (f, inside) = above.eval(d, v.max(band));
                return out(f, Phase::Air, false, inside);
            }
            let (f_hi, _) = above.eval(d, band);
            let w = ((vp + REVERSAL_MPS) / (band + REVERSAL_MPS)).clamp(0.0, 1.0);
            return out(w * f_hi, Phase::Air, false, true);
        }
        // Shaft friction reverses over a band, not at a point: between rest and
        // [`REVERSAL_MPS`] on the side the tool did not last move to, the force runs linearly
        // from one direction's law to the other's; from rest to the hold band on the side it
        // last moved to, it keeps that side's law. A held needle keeps most of the
        // force it had (static friction holds it), a tool trembling at rest does not flip
        // ±friction every tick (it chattered), and the force's slope in velocity stays one an
        // admittance loop renders stably. The band reads the velocity less the hold's jitter
        // ([`HOLD_JITTER_MPS`]); each direction's law reads the velocity itself.
        let reversal = REVERSAL_MPS.max(2.0 * band);
        let (lo, hi) = if state.backward {
            (-band, reversal)
        } else {
            (-reversal, band)
        };
        if vp > hi || ruptured {
            state.backward = false;
            let (f, phase, inside) = self.forward(state, d, v.max(hi), true);
            return out(f, phase, ruptured, inside);
        }
        if vp < lo {
            state.backward = true;
            let (f, inside) = self.withdrawal.eval(d, v.min(lo));
            return out(f, Phase::Withdrawal, false, inside);
        }
        let (f_lo, _) = self.withdrawal.eval(d, lo);
        let (f_hi, _, _) = self.forward(state, d, hi, false);
        // Flat on the side the tool last moved to: at rest and trembling within the jitter
        // it keeps that side's friction; the slope lies between rest and the other side.
        let w = if state.backward {
            (vp / hi).clamp(0.0, 1.0)
        } else {
            ((vp - lo) / -lo).clamp(0.0, 1.0)
        };
        out(f_lo + w * (f_hi - f_lo), Phase::Held, false, true)
    }

    /// Advancing at `v` past `punctured` layers: cutting into tissue deeper than ever before
    /// (which then counts as cut when `advance`), else friction along the channel (withdrawal
    /// friction mirrored: friction is odd in velocity).
    fn forward(&self, state: &mut PhaseState, d: f64, v: f64, advance: bool) -> (f64, Phase, bool) {
        // The tip bears on the uncut tissue while it stays within [`TIP_CONTACT_M`] of the
        // deepest point cut, so a hand creeping by micrometres at the cut front does not flip
        // between cutting and channel friction every tick (it chattered by 0.05 N in a hold).
        if d > state.deepest_m - TIP_CONTACT_M {
            if advance {
                state.deepest_m = state.deepest_m.max(d);
            }
            let (f, inside) = self.cutting(state.punctured, d, v);
            return (f, Phase::Cutting(state.punctured - 1), inside);
        }
        let (f, inside) = self.withdrawal.eval(d, -v);
        (-f, Phase::Channel, inside)
    }

    /// The model run along a recorded trajectory from a fresh site: one step per sample.
    pub fn simulate(&self, depth_m: &[f64], velocity_mps: &[f64]) -> Vec<PhaseStep> {
        let mut state = PhaseState::default();
        depth_m
            .iter()
            .zip(velocity_mps)
            .map(|(&d, &v)| self.step(&mut state, d, v))
            .collect()
    }

    /// Every rupture along a recorded trajectory from a fresh site, where the model puts it:
    /// at the depth its threshold lies at the sample's speed and with the force just before
    /// it, which a sparse trajectory (a digitized curve) steps over between two samples.
    pub fn ruptures_along(&self, depth_m: &[f64], velocity_mps: &[f64]) -> Vec<Rupture> {
        let mut state = PhaseState::default();
        let mut out = Vec::new();
        for (i, (&d, &v)) in depth_m.iter().zip(velocity_mps).enumerate() {
            let before = state;
            let s = self.step(&mut state, d, v);
            let Some(layer) = s.ruptured.then(|| self.layers.get(before.punctured)).flatten() else {
                continue;
            };
            let at = (layer.contact_depth_m + layer.threshold.deflection_m(v)).min(d);
            // Just short of the threshold, from the state before: the membrane's peak.
            let peak = self.step(&mut before.clone(), at - 1e-9, v);
            out.push(Rupture {
                index: i,
                layer: before.punctured,
                depth_m: at,
                peak_force_n: peak.force_n,
                force_after_n: s.force_n,
            });
        }
        out
    }

    /// The force of a fresh site at depth `d` reached at constant speed `v` (v ≤ 0: on the
    /// way out after an insertion deeper than `d`): the model without a trajectory, for
    /// plotting and for bounding its output.
    pub fn steady(&self, depth_m: f64, velocity_mps: f64) -> f64 {
        let mut state = PhaseState::default();
        if velocity_mps > self.hold_band_mps {
            // In at that speed: each membrane shallower than `depth_m` gives at its threshold,
            // in order, and nothing else on the way changes the state. One step per layer, so
            // the time does not grow with the depth.
            let mut past_m: f64 = 0.0;
            for layer in &self.layers {
                let gives_m = layer.contact_depth_m + layer.threshold.deflection_m(velocity_mps);
                // A hair past it, so that rounding cannot leave the deflection just short (and
                // never behind the tip: a layer whose threshold the last one's passed gives at
                // once).
                past_m = past_m.max(gives_m + 1e-12 * (1.0 + gives_m.abs()));
                if past_m >= depth_m || !self.step(&mut state, past_m, velocity_mps).ruptured {
                    break;
                }
            }
            self.step(&mut state, depth_m, velocity_mps).force_n
        } else {
            state.punctured = self.layers.len();
            state.deepest_m = depth_m.max(0.0) + 1.0;
            self.step(&mut state, depth_m, velocity_mps).force_n
        }
    }

    /// The rows of a trajectory (in tissue) whose depth or velocity left the domain of the
    /// phase they were in, grouped by phase, in order of first appearance.
    pub fn domain_exits(&self, depth_m: &[f64], velocity_mps: &[f64]) -> Vec<PhaseExit> {
        let steps = self.simulate(depth_m, velocity_mps);
        let inside_rows = depth_m.iter().filter(|&&d| d > 0.0).count();
        let mut out: Vec<PhaseExit> = Vec::new();
        for ((s, &d), &v) in steps.iter().zip(depth_m).zip(velocity_mps) {
            if !s.out_of_domain || d <= 0.0 {
                continue;
            }
            let name = s.phase.describe();
            let exit = match out.iter_mut().find(|e| e.phase == name) {
                Some(e) => e,
                None => {
                    out.push(PhaseExit {
                        phase: name,
                        rows: 0,
                        fraction: 0.0,
                        depth_m: [f64::INFINITY, f64::NEG_INFINITY],
                        velocity_mps: [f64::INFINITY, f64::NEG_INFINITY],
                    });
                    let last = out.len() - 1;
                    &mut out[last]
                }
            };
            exit.rows += 1;
            exit.fraction = exit.rows as f64 / inside_rows.max(1) as f64;
            exit.depth_m = [exit.depth_m[0].min(d), exit.depth_m[1].max(d)];
            exit.velocity_mps = [exit.velocity_mps[0].min(v), exit.velocity_mps[1].max(v)];
        }
        out
    }

    /// Checks what a hand-edited or truncated file could break: `Err((field, reason))`.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let bad = |field: String, reason: &str| Err((field, reason.to_owned()));
        if self.layers.is_empty() || self.layers.len() > MAX_LAYERS {
            return bad("body.layers".into(), "must hold 1 to 8 layers");
        }
        if !(self.hold_band_mps.is_finite() && self.hold_band_mps >= 0.0) {
            return bad("body.hold_band_mps".into(), "must be finite and ≥ 0");
        }
        let finite = |x: &[f64]| x.iter().all(|a| a.is_finite());
        let law_ok = |l: &ShaftLaw| {
            finite(&[
                l.constant_n,
                l.per_depth_npm,
                l.per_speed_nspm,
                l.per_depth_speed_nspm2,
            ]) && domain_ok(&l.domain)
                && l.svr.as_ref().is_none_or(PartSvr::valid)
        };
        // A part's SVR is held to what a smooth model's is (the support-vector cap included):
        // the haptic thread evaluates both, and the force check's time grows with its size.
        let svr_ok = |label: &str, l: &ShaftLaw| match &l.svr {
            Some(p) => check_svr_parts(
                label,
                &p.scaling,
                1.0,
                &p.svr,
                2,
                &[l.domain.depth_m, l.domain.velocity_mps],
            ),
            None => Ok(()),
        };
        if !law_ok(&self.withdrawal) {
            return bad("body.withdrawal".into(), "coefficients and domain must be finite");
        }
        svr_ok("withdrawal", &self.withdrawal)?;
        if !self.above.as_ref().is_none_or(law_ok) {
            return bad("body.above".into(), "coefficients and domain must be finite");
        }
        if let Some(above) = &self.above {
            svr_ok("above", above)?;
        }
        let mut previous = f64::NEG_INFINITY;
        for (k, layer) in self.layers.iter().enumerate() {
            let field = |name: &str| format!("body.layers[{k}].{name}");
            if !(layer.contact_depth_m.is_finite()
                && layer.contact_depth_m >= 0.0
                && layer.contact_depth_m > previous)
            {
                return bad(
                    field("contact_depth_m"),
                    "must be finite, ≥ 0 and deeper than the layer before",
                );
            }
            previous = layer.contact_depth_m;
            let l = &layer.loading;
            if !(finite(&[l.offset_n, l.a1_npm, l.a2_npm2, l.damping_nspm]) && domain_ok(&l.domain)) {
                return bad(field("loading"), "coefficients and domain must be finite");
            }
            let t = &layer.threshold;
            if t.coefficients.is_empty()
                || t.coefficients.len() > 3
                || !finite(&t.coefficients)
                || !finite(&t.speed_mps)
                || t.speed_mps[0] > t.speed_mps[1]
            {
                return bad(
                    field("threshold"),
                    "1 to 3 finite coefficients and an ordered speed range",
                );
            }
            if !law_ok(&layer.after) {
                return bad(field("after"), "coefficients and domain must be finite");
            }
            svr_ok(&format!("layers[{k}].after"), &layer.after)?;
        }
        Ok(())
    }

    /// Every depth and velocity the model was fitted over, as one [min, max] box.
    pub fn input_range(&self) -> Vec<[f64; 2]> {
        let domains = self
            .layers
            .iter()
            .flat_map(|l| [l.loading.domain, l.after.domain])
            .chain([self.withdrawal.domain])
            .chain(self.above.as_ref().map(|l| l.domain));
        let mut d = [f64::INFINITY, f64::NEG_INFINITY];
        let mut v = d;
        for dom in domains {
            d = [d[0].min(dom.depth_m[0]), d[1].max(dom.depth_m[1])];
            v = [v[0].min(dom.velocity_mps[0]), v[1].max(dom.velocity_mps[1])];
        }
        vec![d, v]
    }
}

fn domain_ok(d: &Domain) -> bool {
    d.depth_m.iter().chain(&d.velocity_mps).all(|x| x.is_finite())
        && d.depth_m[0] <= d.depth_m[1]
        && d.velocity_mps[0] <= d.velocity_mps[1]
}

/// Which inputs vary enough over a phase's samples for a law to be fitted in them. A term in
/// an input the samples barely move is pinned by noise and transients alone, and extrapolates
/// wildly (a withdrawal recorded at one speed fitted −26 N of constant against +26 N of
/// velocity terms): depth terms need [`MIN_DEPTH_SPAN_M`] of depth, speed terms speeds whose
/// middle 80 % span at least a factor [`MIN_SPEED_RATIO`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct Varies {
    pub(crate) depth: bool,
    pub(crate) speed: bool,
}

/// Depth a phase's samples must span for a depth term, m.
pub(crate) const MIN_DEPTH_SPAN_M: f64 = 3e-3;
/// Ratio of the 90th to the 10th percentile of |v| a phase's samples must reach for a speed
/// term.
pub(crate) const MIN_SPEED_RATIO: f64 = 1.5;

impl Varies {
    pub(crate) fn of(d: &[f64], v: &[f64]) -> Self {
        let span = d.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            - d.iter().copied().fold(f64::INFINITY, f64::min);
        let mut speeds: Vec<f64> = v.iter().map(|x| x.abs()).collect();
        speeds.sort_by(f64::total_cmp);
        let at = |q: f64| {
            speeds
                .get((q * speeds.len().saturating_sub(1) as f64).round() as usize)
                .copied()
        };
        let speed = match (at(0.1), at(0.9)) {
            (Some(lo), Some(hi)) => hi >= MIN_SPEED_RATIO * lo,
            _ => false,
        };
        Self {
            depth: span >= MIN_DEPTH_SPAN_M,
            speed,
        }
    }
}

/// [`fit_linear`] over the `keep` columns of four features; the others get 0.
pub(crate) fn fit_terms(
    n: usize,
    row: impl Fn(usize) -> [f64; 4],
    keep: [bool; 4],
    target: &[f64],
) -> Result<[f64; 4], IdentifyError> {
    let x = fit_linear(
        n,
        |i| {
            let r = row(i);
            (0..4).filter(|&j| keep[j]).map(|j| r[j]).collect()
        },
        target,
    )?;
    let mut out = [0.0; 4];
    let mut k = 0;
    for (j, slot) in out.iter_mut().enumerate() {
        if keep[j] {
            *slot = x[k];
            k += 1;
        }
    }
    Ok(out)
}

/// Least squares over `n` rows of `row(i)` features against `target`; the minimum-norm
/// solution when a feature does not vary (one speed only: velocity is then a constant).
pub(crate) fn fit_linear(
    n: usize,
    row: impl Fn(usize) -> Vec<f64>,
    target: &[f64],
) -> Result<Vec<f64>, IdentifyError> {
    let rows: Vec<Vec<f64>> = (0..n).map(row).collect();
    let cols = rows.first().map_or(0, Vec::len);
    let a = Mat::from_fn(n, cols, |i, j| rows[i][j]);
    least_squares(a, target, Rank::MinimumNorm)
}
