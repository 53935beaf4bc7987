//! Puncture events read from data: where an advancing needle's axial force falls sharply
//! (a membrane giving way), grouped into the tissue's layers by depth.
//!
//! An event is a **drop of the force while the needle advances**: from a peak, the force
//! falls by at least the threshold within [`PunctureParams::max_travel_m`] of further
//! travel. The threshold is `max(noise_multiple · σ, min_drop_n)`, with σ the force noise
//! estimated robustly from the signal itself: the median absolute second difference,
//! `σ = 1.4826 · MAD(Δ²f) / √6` (white noise of standard deviation σ has a second difference
//! of variance 6σ²; the second difference removes the loading's ramp, and the median ignores
//! the few samples at the punctures themselves). The detector reads the force with its
//! one- and two-sample excursions bridged (`outliers`: a logger's spike, a digitizing slip), so
//! a single low point neither makes a drop nor restarts a loading, and a single high one is
//! no peak. The samples may be as sparse and irregular as a digitized curve's: every length
//! is a travel of the tip or a time, never a count of samples. Samples that do not advance (held, withdrawn,
//! slower than [`PunctureParams::min_speed_mps`]) never take part in a drop, so a held
//! needle's relaxing friction and a withdrawal's reversal are not punctures. Two more checks
//! keep out drops that are no rupture:
//! - **a loading before it**: within [`PunctureParams::loading_travel_m`] before the peak
//!   (and since the previous drop) the force rose by at least the threshold. A step down with
//!   no rise before it (cutting that stops as the tip meets the next membrane) is not a
//!   puncture. What the force does after the drop does not matter: a membrane that opens into
//!   something softer (a lumen, a cavity, a softer layer) ends below the force the tip felt
//!   before touching it, and that loss of resistance is the puncture a trainee is taught to
//!   feel.
//! - **the speed kept**: over [`PunctureParams::speed_window_s`] after the bottom of the drop
//!   the tip advances on average at [`PunctureParams::min_speed_kept`] of its speed at the
//!   peak or more. A needle that slows
//!   down (a stroke ending) sheds its viscous friction and cutting; a needle through a
//!   membrane keeps its speed or surges forward.
//!
//! A recording holds several strokes (insert, withdraw, insert again): the stroke count rises
//! at each withdrawal that follows an advance. [`group_layers`] then puts events of all strokes
//! and speeds into layers: sorted by depth, a gap larger than the layer gap starts a new layer
//! (a membrane ruptures at a depth that moves with speed, by its deflection's rate dependence,
//! but far less than the distance between membranes). The gap comes from the data: a membrane
//! gives once per stroke, so two events of one stroke are two layers, and the layer gap is
//! [`PunctureParams::layer_gap_m`] or half the smallest distance between two events of one
//! stroke, whichever is smaller (layers 2 mm apart stay two layers).
//!
//! [`compare_punctures`] runs the same detector on a needle model's prediction along a
//! capture's own trajectory, so every puncture measured there gets the model's depth and
//! peak — or is reported as missed when the model smooths it away.

use capture::Capture;
use serde::Serialize;

use crate::error::{IdentifyError, check_series};
use crate::identification::model_column;
use crate::model_file::{ModelBody, ModelFile, ModelKind};
use crate::outliers::{force_noise_n, median};

/// The detector's parameters (see the module documentation for how they are used).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PunctureParams {
    /// A drop must exceed this many noise standard deviations. 10: the range of pure white
    /// noise over the ~100 samples of a millimetre's travel exceeds 10σ with a probability
    /// of about 1e-9 per window, so noise alone does not make events.
    pub noise_multiple: f64,
    /// Absolute floor of the drop, N, for clean signals (a model's prediction has no noise).
    /// 0.05 N is about the smallest change of a ~1 N axial force a hand tells apart (a Weber
    /// fraction of 5–10 %); a smaller fall is not felt as a puncture.
    pub min_drop_n: f64,
    /// The drop must be complete within this further travel of the tip past the peak, m.
    /// A membrane gives way within a fraction of a millimetre; a fall spread over more is the
    /// force easing off, not a puncture.
    pub max_travel_m: f64,
    /// Slowest speed that counts as advancing, m/s.
    pub min_speed_mps: f64,
    /// How far before the peak the loading is looked for, m. A soft membrane deflects by
    /// several millimetres before it gives way (Okamura et al. 2004: up to ~1 cm in liver).
    pub loading_travel_m: f64,
    /// Fraction of the peak's speed the tip must keep after the drop.
    pub min_speed_kept: f64,
    /// How long after the drop that speed is averaged, s (a few tens of milliseconds: long
    /// enough to see a stroke stop, short enough to end before the next event).
    pub speed_window_s: f64,
    /// Events further apart in depth than this belong to different layers, m (at most: the
    /// data can make it smaller, see [`group_layers`]).
    pub layer_gap_m: f64,
}

impl Default for PunctureParams {
    fn default() -> Self {
        Self {
            noise_multiple: 10.0,
            min_drop_n: 0.05,
            max_travel_m: 1e-3,
            min_speed_mps: 2e-4,
            loading_travel_m: 10e-3,
            min_speed_kept: 0.5,
            speed_window_s: 0.05,
            layer_gap_m: 3e-3,
        }
    }
}

impl PunctureParams {
    /// The smallest drop that counts on a force whose white noise is `noise_n`:
    /// `max(noise_multiple · σ, min_drop_n)`.
    pub fn threshold_n(&self, noise_n: f64) -> f64 {
        (self.noise_multiple * noise_n).max(self.min_drop_n)
    }

    fn check(&self) -> Result<(), IdentifyError> {
        let positive = |name: &'static str, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(IdentifyError::InvalidParameter {
                    name,
                    value,
                    reason: "must be positive and finite",
                })
            }
        };
        positive("noise_multiple", self.noise_multiple)?;
        positive("min_drop_n", self.min_drop_n)?;
        positive("max_travel_m", self.max_travel_m)?;
        positive("min_speed_mps", self.min_speed_mps)?;
        positive("loading_travel_m", self.loading_travel_m)?;
        positive("min_speed_kept", self.min_speed_kept)?;
        positive("speed_window_s", self.speed_window_s)?;
        positive("layer_gap_m", self.layer_gap_m)
    }
}

/// One puncture: the peak before a drop.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PunctureEvent {
    /// Sample index of the peak.
    pub index: usize,
    /// Time of the peak, s.
    pub time_s: f64,
    /// Depth of the tip at the peak, m.
    pub depth_m: f64,
    /// Speed of the tip at the peak, m/s.
    pub speed_mps: f64,
    /// Force at the peak, N.
    pub peak_force_n: f64,
    /// Fall from the peak to the median force over the travel window after it, N.
    pub drop_n: f64,
    /// Depth of the tip at the bottom of the drop, where the next loading can start, m.
    pub bottom_depth_m: f64,
    /// Stroke (0-based; a withdrawal after an advance starts the next).
    pub stroke: usize,
}

/// What the detector found, with the threshold it used.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PunctureDetection {
    /// Events in time order.
    pub events: Vec<PunctureEvent>,
    /// Estimated force noise σ, N.
    pub noise_n: f64,
    /// Smallest drop that counted, N.
    pub threshold_n: f64,
}

/// Finds the puncture events in a recording (see the module documentation). The four series
/// must have equal lengths and finite values, and time must increase.
pub fn detect_punctures(
    time_s: &[f64],
    depth_m: &[f64],
    velocity_mps: &[f64],
    force_n: &[f64],
    params: &PunctureParams,
) -> Result<PunctureDetection, IdentifyError> {
    params.check()?;
    let n = time_s.len();
    check_series("time_s", time_s, n)?;
    check_series("depth_m", depth_m, n)?;
    check_series("velocity_mps", velocity_mps, n)?;
    check_series("force_n", force_n, n)?;
    if let Some(i) = (1..n).find(|&i| time_s[i] <= time_s[i - 1]) {
        return Err(IdentifyError::TimeNotIncreasing {
            index: i,
            time_s: time_s[i],
            previous_s: time_s[i - 1],
        });
    }
    let noise_n = force_noise_n(force_n);
    let threshold_n = params.threshold_n(noise_n);
    let bridged = crate::outliers::bridged(time_s, force_n, threshold_n);
    let force_n = &bridged[..];
    let advancing = |i: usize| velocity_mps[i] > params.min_speed_mps;

    let mut events = Vec::new();
    // Indices of the current advancing run within the travel window behind the sample, their
    // forces decreasing: the front is the window's peak.
    let mut window: std::collections::VecDeque<usize> = std::collections::VecDeque::new();
    let mut stroke = 0;
    let mut advanced_in_stroke = false;
    // A loading starts after the previous drop's bottom.
    let mut floor = 0;
    let mut j = 0;
    while j < n {
        if !advancing(j) {
            window.clear();
            if velocity_mps[j] < -params.min_speed_mps && advanced_in_stroke {
                stroke += 1;
                advanced_in_stroke = false;
            }
            j += 1;
            continue;
        }
        advanced_in_stroke = true;
        while window
            .front()
            .is_some_and(|&p| depth_m[j] - depth_m[p] > params.max_travel_m)
        {
            window.pop_front();
        }
        if let Some(&peak) = window.front()
            && force_n[peak] - force_n[j] >= threshold_n
        {
            // The bottom: the lowest force while still advancing within the travel window;
            // the drop: from the peak to the median force over that window after the peak,
            // which neither noise nor a single low sample pulls down.
            let mut bottom = j;
            let mut k = j + 1;
            while k < n && advancing(k) && depth_m[k] - depth_m[peak] <= params.max_travel_m {
                if force_n[k] < force_n[bottom] {
                    bottom = k;
                }
                k += 1;
            }
            let mut after_peak: Vec<f64> = force_n[peak + 1..k].to_vec();
            let drop_n = force_n[peak] - median(&mut after_peak);
            // The loading: the lowest force of the same advance within the loading travel
            // before the peak, since the previous drop.
            let mut low = force_n[peak];
            let mut k = peak;
            while k > floor && advancing(k - 1) && depth_m[peak] - depth_m[k - 1] <= params.loading_travel_m {
                k -= 1;
                low = low.min(force_n[k]);
            }
            let loaded = force_n[peak] - low >= threshold_n;
            let mut after = bottom;
            while after + 1 < n && time_s[after] < time_s[bottom] + params.speed_window_s {
                after += 1;
            }
            let speed_after = if after > bottom {
                (depth_m[after] - depth_m[bottom]) / (time_s[after] - time_s[bottom])
            } else {
                velocity_mps[bottom]
            };
            let kept_speed = speed_after >= params.min_speed_kept * velocity_mps[peak];
            if drop_n >= threshold_n && loaded && kept_speed {
                events.push(PunctureEvent {
                    index: peak,
                    time_s: time_s[peak],
                    depth_m: depth_m[peak],
                    speed_mps: velocity_mps[peak],
                    peak_force_n: force_n[peak],
                    drop_n,
                    bottom_depth_m: depth_m[bottom],
                    stroke,
                });
            }
            // The next event's peak comes after this drop's bottom, whether it was a puncture
            // or not.
            window.clear();
            window.push_back(bottom);
            floor = bottom;
            j = bottom + 1;
            continue;
        }
        while window.back().is_some_and(|&b| force_n[b] <= force_n[j]) {
            window.pop_back();
        }
        window.push_back(j);
        j += 1;
    }
    Ok(PunctureDetection {
        events,
        noise_n,
        threshold_n,
    })
}

/// Events at about one depth, across strokes and speeds: one membrane.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Layer {
    /// Median depth of its events, m.
    pub depth_m: f64,
    /// Shallowest event, m.
    pub min_depth_m: f64,
    /// Deepest event, m.
    pub max_depth_m: f64,
    /// Median peak force, N.
    pub peak_force_n: f64,
    /// Indices into the event list given to [`group_layers`], by depth.
    pub events: Vec<usize>,
}

/// Groups `events` into layers by depth: sorted by depth, a gap over the layer gap starts a
/// new layer, and so does an event whose stroke the layer already holds (a membrane gives once
/// per stroke). The layer gap is `gap_m`, or half the smallest distance between two events of
/// one stroke when that is smaller. Layers come shallowest first.
pub fn group_layers(events: &[PunctureEvent], gap_m: f64) -> Vec<Layer> {
    let gap_m = gap_m.min(0.5 * smallest_spacing_in_a_stroke(events));
    let mut order: Vec<usize> = (0..events.len()).collect();
    order.sort_by(|&a, &b| events[a].depth_m.total_cmp(&events[b].depth_m));
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for i in order {
        match groups.last_mut() {
            Some(g)
                if events[i].depth_m - events[g[g.len() - 1]].depth_m <= gap_m
                    && g.iter().all(|&e| events[e].stroke != events[i].stroke) =>
            {
                g.push(i)
            }
            _ => groups.push(vec![i]),
        }
    }
    groups
        .into_iter()
        .map(|g| {
            let mut depths: Vec<f64> = g.iter().map(|&i| events[i].depth_m).collect();
            let mut peaks: Vec<f64> = g.iter().map(|&i| events[i].peak_force_n).collect();
            Layer {
                min_depth_m: depths[0],
                max_depth_m: depths[depths.len() - 1],
                depth_m: median(&mut depths),
                peak_force_n: median(&mut peaks),
                events: g,
            }
        })
        .collect()
}

/// The smallest depth between two consecutive events of one stroke, m (∞ with none).
fn smallest_spacing_in_a_stroke(events: &[PunctureEvent]) -> f64 {
    events
        .windows(2)
        .filter(|w| w[0].stroke == w[1].stroke)
        .map(|w| (w[1].depth_m - w[0].depth_m).abs())
        .fold(f64::INFINITY, f64::min)
}

/// One puncture measured in a capture beside the model's along the same stroke.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PunctureComparison {
    /// Stroke of the capture.
    pub stroke: usize,
    /// Speed of the tip at the measured peak, m/s.
    pub speed_mps: f64,
    /// Measured depth of the peak, m.
    pub measured_depth_m: f64,
    /// Measured peak force, N.
    pub measured_peak_force_n: f64,
    /// Measured drop, N.
    pub measured_drop_n: f64,
    /// The model's force at the measured peak's sample, N.
    pub model_force_at_measured_n: f64,
    /// Depth of the model's puncture in that stroke within the layer gap of the measured one,
    /// m; `None` when the model renders no drop there (missed).
    pub predicted_depth_m: Option<f64>,
    /// The model's peak force there, N (`None` when missed).
    pub predicted_peak_force_n: Option<f64>,
    /// The model's drop there, N (`None` when missed).
    pub predicted_drop_n: Option<f64>,
}

/// Every puncture detected in `capture` (an insertion capture), each beside the puncture the
/// needle `model` renders along the same trajectory: the model is evaluated on the capture's
/// own depth and velocity (0 N in air, where the model describes nothing) and the same
/// detector is run on that prediction (a phase-aware model reports its own ruptures instead:
/// its force is clean, and the detector's drops on a clean force that varies with speed are
/// not what a trainee feels as a puncture). A measured puncture is matched with the model's nearest
/// event of the same stroke within `params.layer_gap_m`.
pub fn compare_punctures(
    model: &ModelFile,
    capture: &Capture,
    params: &PunctureParams,
) -> Result<Vec<PunctureComparison>, IdentifyError> {
    if !matches!(model.kind, ModelKind::NeedlePuncture | ModelKind::NeedlePhases) {
        return Err(IdentifyError::Data {
            path: capture.source().to_owned(),
            reason: format!(
                "puncture comparison needs a needle model, not a {} model",
                model.kind.short_name()
            ),
        });
    }
    let depth = model_column(capture, capture::kind::DEPTH_M)?;
    let velocity = model_column(capture, capture::kind::VELOCITY_MPS)?;
    let force = capture.column(capture::kind::AXIAL_FORCE_N)?;
    let inputs: Vec<Vec<f64>> = model
        .inputs
        .iter()
        .map(|q| model_column(capture, &q.name))
        .collect::<Result<_, _>>()?;
    let mut x = vec![0.0; inputs.len()];
    // A model with memory runs along the trajectory; a smooth one is evaluated per sample.
    let along = match &model.body {
        ModelBody::Phases(p) => Some(p.simulate(&depth, &velocity)),
        _ => None,
    };
    let predicted: Vec<f64> = (0..capture.len())
        .map(|i| {
            if depth[i] <= 0.0 {
                return 0.0;
            }
            if let Some(steps) = &along {
                return steps[i].force_n;
            }
            for (slot, column) in x.iter_mut().zip(&inputs) {
                *slot = column[i];
            }
            model.predict(&x)
        })
        .collect();
    let time = capture.time();
    let measured = detect_punctures(time, &depth, &velocity, force, params)?;
    // A model with memory says itself where each layer gave: those are the punctures a
    // trainee feels. A smooth model's are found in its force by the detector.
    let rendered = match &model.body {
        ModelBody::Phases(p) => ruptures(p, time, &depth, &velocity, params),
        _ => detect_punctures(time, &depth, &velocity, &predicted, params)?.events,
    };
    Ok(measured
        .events
        .iter()
        .map(|m| {
            let matched = rendered
                .iter()
                .filter(|p| p.stroke == m.stroke && (p.depth_m - m.depth_m).abs() <= params.layer_gap_m)
                .min_by(|a, b| {
                    (a.depth_m - m.depth_m)
                        .abs()
                        .total_cmp(&(b.depth_m - m.depth_m).abs())
                });
            PunctureComparison {
                stroke: m.stroke,
                speed_mps: m.speed_mps,
                measured_depth_m: m.depth_m,
                measured_peak_force_n: m.peak_force_n,
                measured_drop_n: m.drop_n,
                model_force_at_measured_n: predicted[m.index],
                predicted_depth_m: matched.map(|p| p.depth_m),
                predicted_peak_force_n: matched.map(|p| p.peak_force_n),
                predicted_drop_n: matched.map(|p| p.drop_n),
            }
        })
        .collect())
}

/// The phase model's own ruptures along a trajectory, as events: the peak is the model's force
/// just before its threshold ([`crate::PhaseModel::ruptures_along`]), the drop the fall to the
/// sample after it; strokes are counted as the detector counts them (a withdrawal after an
/// advance starts the next).
fn ruptures(
    model: &crate::PhaseModel,
    time_s: &[f64],
    depth_m: &[f64],
    velocity_mps: &[f64],
    params: &PunctureParams,
) -> Vec<PunctureEvent> {
    let mut stroke_of = Vec::with_capacity(depth_m.len());
    let mut stroke = 0;
    let mut advanced = false;
    for &v in velocity_mps {
        if v > params.min_speed_mps {
            advanced = true;
        } else if v < -params.min_speed_mps && advanced {
            stroke += 1;
            advanced = false;
        }
        stroke_of.push(stroke);
    }
    model
        .ruptures_along(depth_m, velocity_mps)
        .into_iter()
        .map(|r| {
            let i = r.index;
            PunctureEvent {
                index: i.saturating_sub(1),
                time_s: time_s[i],
                depth_m: r.depth_m,
                speed_mps: velocity_mps[i],
                peak_force_n: r.peak_force_n,
                drop_n: r.peak_force_n - r.force_after_n,
                bottom_depth_m: depth_m[i],
                stroke: stroke_of[i],
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_estimate_ignores_a_ramp() {
        // A pure ramp has zero second difference.
        let ramp: Vec<f64> = (0..100).map(|i| 0.01 * i as f64).collect();
        assert!(force_noise_n(&ramp) < 1e-12);
    }

    #[test]
    fn bad_parameters_and_series_are_refused() {
        let t = [0.0, 1.0, 2.0];
        let z = [0.0; 3];
        let p = PunctureParams {
            max_travel_m: 0.0,
            ..PunctureParams::default()
        };
        assert!(matches!(
            detect_punctures(&t, &z, &z, &z, &p),
            Err(IdentifyError::InvalidParameter {
                name: "max_travel_m",
                ..
            })
        ));
        let d = PunctureParams::default();
        assert!(matches!(
            detect_punctures(&t, &z[..2], &z, &z, &d),
            Err(IdentifyError::LengthMismatch { name: "depth_m", .. })
        ));
        assert!(matches!(
            detect_punctures(&[0.0, 0.0, 1.0], &z, &z, &z, &d),
            Err(IdentifyError::TimeNotIncreasing { index: 1, .. })
        ));
        assert!(matches!(
            detect_punctures(&t, &z, &z, &[0.0, f64::NAN, 0.0], &d),
            Err(IdentifyError::NonFinite {
                name: "force_n",
                index: 1,
                ..
            })
        ));
    }
}
