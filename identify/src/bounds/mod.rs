//! Certified bounds on the force a model file can ask of a device.
//!
//! Sampling a model on a grid misses what lies between the samples: a one-support-vector RBF
//! bump 45 µm wide passed a 33-point grid and asked a device for 289 N. Here every part a force
//! law evaluates gets an enclosure of its output over the whole box of inputs the law can give
//! it ([`enclosure`]), and a branch and bound ([`search`]) splits the box until the enclosures
//! prove the part within the device's limit, a point shows it is not, or a fixed amount of
//! work is spent. What cannot be proved safe is refused. Work is counted in kernel
//! evaluations, so the check's time grows with the model's size and not with its input range.
//!
//! Where physics fixes a sign it is checked the same way: the axial force on a needle
//! advancing into tissue resists it (it is not a pull), withdrawal friction opposes the
//! withdrawal (it is not a push), and a membrane must give within the device's stroke.

mod enclosure;
mod search;

use enclosure::{Bilinear, Bx, Part, Quadratic, SoftContact, Sum, Svr};
use search::{Broken, Outcome, Requirement, search};

use crate::model_file::{ModelBody, ModelFile, ScaledSvr};
use crate::phases::{PartSvr, PhaseModel, ShaftLaw, TIP_CONTACT_M};

/// Kernel evaluations one model's check may spend: about 0.1 s in a release build, whatever
/// the model (a part with more support vectors gets fewer, costlier enclosures).
pub const CHECK_WORK: usize = 4_000_000;

/// Pull (or, withdrawing, push) accepted as fitting noise where physics fixes the sign, N:
/// an identified law crosses zero by a few hundredths of a newton where the force it fits
/// starts from zero; half a newton is far above that and far below a pull a hand notices.
pub const SIGN_TOLERANCE_N: f64 = 0.5;

/// What a model is checked against.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeviceEnvelope {
    /// The largest force the device renders, N.
    pub max_force_n: f64,
    /// How deep the tool can go below a surface, m: the workspace's diameter.
    pub stroke_m: f64,
}

/// A model proved within a device's limit.
#[derive(Debug, Clone, PartialEq)]
pub struct ForceCertificate {
    /// Every force the model's law can give lies within ±this, N (proved, not sampled).
    pub bound_n: f64,
    /// Kernel evaluations spent proving it.
    pub work: usize,
}

/// Why a model cannot be rendered on a device, naming the model part (its field in the file).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BoundViolation {
    /// The part asks for more than the device gives.
    #[error("{part} asks for {force_n:.4} N at {at}, beyond the device's {limit_n} N")]
    Exceeds {
        /// The part's field.
        part: String,
        /// The force found, N.
        force_n: f64,
        /// Where, inputs named.
        at: String,
        /// The device's limit, N.
        limit_n: f64,
    },
    /// Neither proved safe nor shown unsafe within [`CHECK_WORK`].
    #[error(
        "{part}: cannot prove within the check's budget that its force stays {requirement} \
         (proved only within [{lo:.4}, {hi:.4}] N; the closest to breaking it found: {seen_n:.4} N at {at})"
    )]
    Unproved {
        /// The part's field.
        part: String,
        /// What was to be proved, in words.
        requirement: String,
        /// What was proved: the force lies in [lo, hi], N.
        lo: f64,
        /// Upper end, N.
        hi: f64,
        /// The force found closest to breaking the requirement, N.
        seen_n: f64,
        /// Where.
        at: String,
        /// The device's limit, N.
        limit_n: f64,
    },
    /// A force of the wrong sign beyond [`SIGN_TOLERANCE_N`].
    #[error("{part} gives {force_n:.4} N at {at}: {why}")]
    Sign {
        /// The part's field.
        part: String,
        /// The force found, N.
        force_n: f64,
        /// Where.
        at: String,
        /// What physics says.
        why: &'static str,
    },
    /// A membrane the device can never puncture.
    #[error(
        "{part}: the membrane at {contact_mm:.2} mm gives only {deflection_mm:.2} mm deeper, \
         beyond the {stroke_mm:.0} mm a device can push: it could never be punctured"
    )]
    NeverGives {
        /// The layer's field.
        part: String,
        /// Its contact depth, mm.
        contact_mm: f64,
        /// The least deflection at which it gives, mm.
        deflection_mm: f64,
        /// The device's stroke, mm.
        stroke_mm: f64,
    },
}

/// One part to prove: its field, the part, the box of inputs its law can see, the requirement.
struct Check<'a> {
    field: String,
    part: Box<dyn Part + 'a>,
    root: Bx,
    req: Requirement,
    /// What physics says of the sign, where the requirement has a floor or a ceiling.
    why: &'static str,
}

impl<'a> Check<'a> {
    /// A part held to the force limit alone.
    fn whole(field: &str, part: Box<dyn Part + 'a>, root: Bx, req: Requirement) -> Self {
        Self {
            field: field.into(),
            part,
            root,
            req,
            why: "",
        }
    }
}

const PULL: &str = "an advancing needle meets resistance (a force ≥ 0), never a pull into the tissue";
const PUSH: &str = "friction on a withdrawing needle opposes the withdrawal (a force ≤ 0), never a push out";

impl ModelFile {
    /// Proves that every force this model's law can give lies within `device.max_force_n`
    /// (and, for a needle, that its signs and thresholds are physical), or says which part,
    /// where and why not. Bounded by [`CHECK_WORK`] kernel evaluations.
    pub fn certify(&self, device: &DeviceEnvelope) -> Result<ForceCertificate, BoundViolation> {
        let limit = device.max_force_n;
        let magnitude = Requirement {
            max_abs: limit,
            floor: None,
            ceiling: None,
        };
        let ranges = &self.input_range;
        let range = |k: usize| ranges.get(k).copied().unwrap_or([0.0, 0.0]);
        let full: Bx = [range(0), range(1)];
        let checks: Vec<Check<'_>> = match &self.body {
            ModelBody::Single(m) => vec![Check::whole(
                "body.single",
                Box::new(scaled_svr(m, full)),
                full,
                magnitude,
            )],
            ModelBody::TwoStage { slope, intercept } => {
                let part = SoftContact {
                    slope: scaled_svr(slope, full),
                    intercept: scaled_svr(intercept, full),
                    force_range: range(1),
                };
                vec![Check::whole("body", Box::new(part), full, magnitude)]
            }
            ModelBody::Phases(p) => {
                check_thresholds(p, device.stroke_m)?;
                phase_checks(p, device.stroke_m, limit)
            }
        };
        let dim = self.input_range.len().clamp(1, 2);
        let mut bound_n: f64 = 0.0;
        let mut work = 0;
        for check in checks {
            let (outcome, spent) = search(
                check.part.as_ref(),
                check.root,
                dim,
                check.req,
                CHECK_WORK.saturating_sub(work).max(1),
            );
            work += spent;
            let at = |x: [f64; 2]| self.describe_inputs(x);
            match outcome {
                Outcome::Proved { range } => bound_n = bound_n.max(range[0].abs()).max(range[1].abs()),
                Outcome::Broken {
                    how: Broken::Magnitude,
                    value,
                    at: x,
                } => {
                    return Err(BoundViolation::Exceeds {
                        part: check.field,
                        force_n: value,
                        at: at(x),
                        limit_n: limit,
                    });
                }
                Outcome::Broken { value, at: x, .. } => {
                    return Err(BoundViolation::Sign {
                        part: check.field,
                        force_n: value,
                        at: at(x),
                        why: check.why,
                    });
                }
                Outcome::Unproved { range, worst, at: x } => {
                    let mut requirement = format!("within ±{limit} N");
                    if let Some(f) = check.req.floor {
                        requirement += &format!(" and at least {f} N ({})", check.why);
                    }
                    if let Some(c) = check.req.ceiling {
                        requirement += &format!(" and at most {c} N ({})", check.why);
                    }
                    return Err(BoundViolation::Unproved {
                        part: check.field,
                        requirement,
                        lo: range[0],
                        hi: range[1],
                        seen_n: worst,
                        at: at(x),
                        limit_n: limit,
                    });
                }
            }
        }
        Ok(ForceCertificate { bound_n, work })
    }

    fn describe_inputs(&self, x: [f64; 2]) -> String {
        let names: Vec<&str> = match &self.body {
            ModelBody::Phases(_) => vec!["depth_m", "velocity_mps"],
            _ => self.inputs.iter().map(|q| q.name.as_str()).collect(),
        };
        names
            .iter()
            .zip(x)
            .map(|(name, v)| match name.rsplit_once('_') {
                Some((q, "m")) => format!("{q} {:.3} mm", 1e3 * v),
                Some((q, "mps")) => format!("{q} {:.2} mm/s", 1e3 * v),
                Some((q, "n")) => format!("{q} {v:.3} N"),
                _ => format!("{name} {v:.4e}"),
            })
            .collect::<Vec<_>>()
            .join(", ")
    }
}

fn two(v: &[f64], fill: f64) -> [f64; 2] {
    [
        v.first().copied().unwrap_or(fill),
        v.get(1).copied().unwrap_or(fill),
    ]
}

/// A model file's SVR; the law holds its inputs to the training range `clamp`.
fn scaled_svr(m: &ScaledSvr, clamp: Bx) -> Svr<'_> {
    Svr {
        model: &m.svr,
        offset: two(&m.scaling.offset, 0.0),
        scale: two(&m.scaling.scale, 1.0),
        output_scale: m.output_scale,
        clamp,
    }
}

/// A shaft law as [`ShaftLaw::eval`] evaluates it (velocity held to its domain, depth to its
/// domain with the margin), or with `extended` as the base under a loading membrane (depth
/// not held).
fn shaft(law: &ShaftLaw, extended: bool) -> Box<dyn Part + '_> {
    let free = [f64::NEG_INFINITY, f64::INFINITY];
    let d_range = if extended { free } else { law.domain.depth_held_m() };
    let v_range = law.domain.velocity_mps;
    match &law.svr {
        Some(PartSvr { scaling, svr }) => Box::new(Svr {
            model: svr,
            offset: two(&scaling.offset, 0.0),
            scale: two(&scaling.scale, 1.0),
            output_scale: 1.0,
            clamp: [d_range, v_range],
        }),
        None => Box::new(Bilinear {
            terms: [
                law.constant_n,
                law.per_depth_npm,
                law.per_speed_nspm,
                law.per_depth_speed_nspm2,
            ],
            d_range,
            v_range,
        }),
    }
}

/// Every law [`PhaseModel::step`] evaluates, over the depths and velocities it can evaluate it
/// at on a device that pushes at most `stroke_m` deep. Velocities: each law holds its own to
/// its trained range. Depths: the tissue above the first membrane acts above it; a membrane
/// loads from its contact on, up to its largest threshold (the step holds the deflection
/// there), over the law of the tissue above it at any depth; the cutting law after
/// layer k acts once layer k gave, where the tip bears on uncut tissue, no shallower than
/// [`TIP_CONTACT_M`] above where it gave, so above layer k's contact less that; withdrawal
/// friction (and, mirrored, friction along the cut channel) anywhere in the tissue. The
/// reversal and hold bands blend two of these with weights in [0, 1] and so stay within them.
fn phase_checks(p: &PhaseModel, stroke_m: f64, limit_n: f64) -> Vec<Check<'_>> {
    let resisting = Requirement {
        max_abs: limit_n,
        floor: Some(-SIGN_TOLERANCE_N),
        ceiling: None,
    };
    let stroke = stroke_m.max(0.0);
    let mut checks = Vec::new();
    if let (Some(above), Some(first)) = (&p.above, p.layers.first()) {
        checks.push(Check {
            field: "body.above".into(),
            part: shaft(above, false),
            root: [
                [0.0, first.contact_depth_m.min(stroke)],
                above.domain.velocity_mps,
            ],
            req: resisting,
            why: PULL,
        });
    }
    for (k, layer) in p.layers.iter().enumerate() {
        let from = layer.contact_depth_m.min(stroke);
        let l = &layer.loading;
        let membrane = Box::new(Quadratic {
            terms: [l.offset_n, l.a1_npm, l.a2_npm2, l.damping_nspm],
            contact_m: layer.contact_depth_m,
            max_u_m: layer.threshold.max_deflection_m(),
            v_range: l.domain.velocity_mps,
        });
        let base = match k.checked_sub(1) {
            Some(j) => Some(shaft(&p.layers[j].after, true)),
            None => p.above.as_ref().map(|l| shaft(l, true)),
        };
        let mut parts: Vec<Box<dyn Part + '_>> = vec![membrane];
        parts.extend(base);
        checks.push(Check {
            field: format!("body.layers[{k}].loading"),
            part: Box::new(Sum(parts)),
            // Deeper than its largest threshold the step holds both the membrane and the law
            // under it where they are there.
            root: [
                [
                    from,
                    (layer.contact_depth_m + layer.threshold.max_deflection_m()).clamp(from, stroke),
                ],
                l.domain.velocity_mps,
            ],
            req: resisting,
            why: PULL,
        });
        checks.push(Check {
            field: format!("body.layers[{k}].after"),
            part: shaft(&layer.after, false),
            root: [
                [(layer.contact_depth_m - TIP_CONTACT_M).clamp(0.0, stroke), stroke],
                layer.after.domain.velocity_mps,
            ],
            req: resisting,
            why: PULL,
        });
    }
    checks.push(Check {
        field: "body.withdrawal".into(),
        part: shaft(&p.withdrawal, false),
        root: [[0.0, stroke], p.withdrawal.domain.velocity_mps],
        req: Requirement {
            max_abs: limit_n,
            floor: None,
            ceiling: Some(SIGN_TOLERANCE_N),
        },
        why: PUSH,
    });
    checks
}

/// Refuses a layer whose membrane a device cannot reach and puncture: its contact plus the
/// least deflection its threshold gives at any speed lies beyond `stroke_m`.
fn check_thresholds(p: &PhaseModel, stroke_m: f64) -> Result<(), BoundViolation> {
    for (k, layer) in p.layers.iter().enumerate() {
        let least = layer.threshold.min_deflection_m();
        if layer.contact_depth_m + least > stroke_m {
            return Err(BoundViolation::NeverGives {
                part: format!("body.layers[{k}].threshold"),
                contact_mm: 1e3 * layer.contact_depth_m,
                deflection_mm: 1e3 * least,
                stroke_mm: 1e3 * stroke_m,
            });
        }
    }
    Ok(())
}
