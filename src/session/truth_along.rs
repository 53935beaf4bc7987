//! The rendered needle force against the simulated tissue's own force along the same
//! trajectory: what a report of the peaks alone cannot see (a pop the tissue does not have
//! between two membranes, a drop it has that the render smooths away, an offset during the
//! hold).
//!
//! The simulated tissue the model renders (the bovine liver for the default capture; see
//! [`super::truth_tissue`]) is stepped at every tick's depth and velocity of the virtual tool, from a
//! fresh site, exactly as the simulated rig stepped it when it recorded; its force is then the
//! force the tissue would have given the trainee. A drop is a fall of more than [`POP_N`]
//! within [`POP_TRAVEL_M`] of travel while the needle is not withdrawn (the detector's travel,
//! with no loading asked for: a false pop need not follow one; a needle slowing to a stop
//! counts, since tissue stops cutting then); a drop of one series with none of the other within
//! [`POP_MATCH_M`] is a false pop (rendered only) or a missed one (tissue only).

use haptics::HapticSample;
use haptics::admittance_channel as c;
use serde::Serialize;
use sim::{NeedleSite, NeedleTissue};

/// Smallest fall that counts as a pop, N: about the smallest change of a ~1 N axial force a
/// hand tells apart.
pub const POP_N: f64 = 0.1;
/// The travel a pop's fall is complete within, m.
pub const POP_TRAVEL_M: f64 = 1e-3;
/// A rendered and a tissue pop this close in depth are the same one, m.
pub const POP_MATCH_M: f64 = 1e-3;
/// Fastest withdrawal at which a fall still counts, m/s: a drop as the needle slows to a stop
/// is the tissue's too (cutting stops), at whatever speed each of them lets go of it.
const NOT_WITHDRAWING_MPS: f64 = -2e-4;

/// One fall of the force while advancing.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Pop {
    /// When the fall began, s.
    pub time_s: f64,
    /// Depth where it began, m.
    pub depth_m: f64,
    /// How far the force fell, N.
    pub drop_n: f64,
}

/// The rendered force against the tissue's along the run ([`along`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TruthAlong {
    /// Ticks compared: those with the tool in the tissue.
    pub ticks: usize,
    /// RMS of rendered − tissue force over them, N.
    pub rmse_n: f64,
    /// The largest |rendered − tissue|, N.
    pub max_error_n: f64,
    /// Where it was: depth, m.
    pub max_error_depth_m: f64,
    /// And when, s.
    pub max_error_time_s: f64,
    /// Pops of the rendered force the tissue does not have.
    pub false_pops: Vec<Pop>,
    /// Pops of the tissue the rendered force does not have.
    pub missed_pops: Vec<Pop>,
    /// Ticks held in the tissue: the tool within [`HELD_SPAN_M`] and slower than
    /// [`identify::HOLD_JITTER_MPS`] over the [`RIPPLE_WINDOW`] ticks around.
    pub held_ticks: usize,
    /// Chatter of the rendered force while held: over the [`RIPPLE_WINDOW`] ticks around a
    /// held tick, how far the force went back and forth (half its total variation less its net
    /// change, so a steady ramp, a reversal's, counts nothing), the largest, N.
    pub held_ripple_n: f64,
}

/// Most depth the tool may cover over [`RIPPLE_WINDOW`] ticks and count as held, m: a hand
/// holding still creeps and trembles by less, a stroke at 1 mm/s covers twice that, and a
/// rebound that turns in place lasts less than the window. Depth, not speed: an oscillation of
/// the tool in place is a hold, at whatever speed it trembles.
pub const HELD_SPAN_M: f64 = 0.1e-3;
/// Ticks (centred) over which a held force's chatter is measured: 0.2 s at 1 kHz.
pub const RIPPLE_WINDOW: usize = 201;

/// `tissue`'s force at every sample, the tool at `surface_z_m − z`.
pub fn tissue_force(samples: &[HapticSample], surface_z_m: f64, tissue: &NeedleTissue) -> Vec<f64> {
    let mut site = NeedleSite::new(tissue.clone());
    let mut previous_s: Option<f64> = None;
    samples
        .iter()
        .map(|s| {
            let depth_m = surface_z_m - s.channels[c::VIRTUAL_Z_M];
            let velocity_mps = -s.channels[c::VIRTUAL_VZ_MPS];
            let dt_s = previous_s.map_or(1e-3, |p| (s.time_s - p).max(0.0));
            previous_s = Some(s.time_s);
            if depth_m <= 0.0 {
                site = NeedleSite::new(tissue.clone());
                return 0.0;
            }
            site.step(depth_m, velocity_mps, dt_s).axial_force_n
        })
        .collect()
}

/// Every fall of `force_n` by more than [`POP_N`] within [`POP_TRAVEL_M`] of advancing travel.
fn pops(time_s: &[f64], depth_m: &[f64], velocity_mps: &[f64], force_n: &[f64]) -> Vec<Pop> {
    let advancing = |i: usize| velocity_mps[i] > NOT_WITHDRAWING_MPS && depth_m[i] > 0.0;
    let mut out = Vec::new();
    // The current advance's samples within the travel window behind the sample, their forces
    // decreasing: the front is the window's highest.
    let mut window: std::collections::VecDeque<usize> = std::collections::VecDeque::new();
    let mut i = 0;
    while i < force_n.len() {
        if !advancing(i) {
            window.clear();
            i += 1;
            continue;
        }
        while window
            .front()
            .is_some_and(|&p| depth_m[i] - depth_m[p] > POP_TRAVEL_M)
        {
            window.pop_front();
        }
        if let Some(&p) = window.front()
            && force_n[p] - force_n[i] > POP_N
        {
            // The bottom: the lowest force within the travel after the peak.
            let mut bottom = i;
            let mut k = i;
            while k < force_n.len() && advancing(k) && depth_m[k] - depth_m[p] <= POP_TRAVEL_M {
                if force_n[k] < force_n[bottom] {
                    bottom = k;
                }
                k += 1;
            }
            out.push(Pop {
                time_s: time_s[p],
                depth_m: depth_m[p],
                drop_n: force_n[p] - force_n[bottom],
            });
            window.clear();
            i = bottom + 1;
            continue;
        }
        while window.back().is_some_and(|&b| force_n[b] <= force_n[i]) {
            window.pop_back();
        }
        window.push_back(i);
        i += 1;
    }
    out
}

/// The run's rendered force (`MODEL_FORCE_Z_N`) against `tissue`'s along its samples.
pub fn along(samples: &[HapticSample], surface_z_m: f64, tissue: &NeedleTissue) -> TruthAlong {
    let tissue = tissue_force(samples, surface_z_m, tissue);
    let time: Vec<f64> = samples.iter().map(|s| s.time_s).collect();
    let depth: Vec<f64> = samples
        .iter()
        .map(|s| surface_z_m - s.channels[c::VIRTUAL_Z_M])
        .collect();
    let velocity: Vec<f64> = samples.iter().map(|s| -s.channels[c::VIRTUAL_VZ_MPS]).collect();
    let rendered: Vec<f64> = samples.iter().map(|s| s.channels[c::MODEL_FORCE_Z_N]).collect();
    let (mut sum, mut ticks, mut worst) = (0.0, 0usize, (0.0f64, 0usize));
    for i in (0..samples.len()).filter(|&i| depth[i] > 0.0) {
        let e = rendered[i] - tissue[i];
        if !e.is_finite() {
            continue;
        }
        sum += e * e;
        ticks += 1;
        if e.abs() > worst.0 {
            worst = (e.abs(), i);
        }
    }
    let rendered_pops = pops(&time, &depth, &velocity, &rendered);
    let tissue_pops = pops(&time, &depth, &velocity, &tissue);
    let unmatched = |of: &[Pop], against: &[Pop]| -> Vec<Pop> {
        of.iter()
            .filter(|p| {
                !against
                    .iter()
                    .any(|q| (q.depth_m - p.depth_m).abs() <= POP_MATCH_M)
            })
            .copied()
            .collect()
    };
    let half = RIPPLE_WINDOW / 2;
    let held: Vec<usize> = (half..samples.len().saturating_sub(half))
        .filter(|&i| {
            let window = &depth[i - half..=i + half];
            let (lo, hi) = window
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                    (a.min(x), b.max(x))
                });
            // At rest by the model's own reading too: a reversal starting is no hold.
            lo > 0.0
                && hi - lo <= HELD_SPAN_M
                && velocity[i - half..=i + half]
                    .iter()
                    .all(|v| v.abs() <= identify::HOLD_JITTER_MPS)
        })
        .collect();
    let held_ripple_n = held
        .iter()
        .map(|&i| {
            let window = &rendered[i - half..=i + half];
            let travel: f64 = window.windows(2).map(|w| (w[1] - w[0]).abs()).sum();
            0.5 * (travel - (window[window.len() - 1] - window[0]).abs())
        })
        .fold(0.0, f64::max);
    TruthAlong {
        held_ticks: held.len(),
        held_ripple_n,
        ticks,
        rmse_n: if ticks > 0 {
            (sum / ticks as f64).sqrt()
        } else {
            0.0
        },
        max_error_n: worst.0,
        max_error_depth_m: depth.get(worst.1).copied().unwrap_or(0.0),
        max_error_time_s: time.get(worst.1).copied().unwrap_or(0.0),
        false_pops: unmatched(&rendered_pops, &tissue_pops),
        missed_pops: unmatched(&tissue_pops, &rendered_pops),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_fall_while_advancing_is_a_pop_and_a_slow_ramp_down_is_not() {
        let n = 400;
        let time: Vec<f64> = (0..n).map(|i| i as f64 * 1e-3).collect();
        let depth: Vec<f64> = (0..n).map(|i| i as f64 * 1e-5).collect();
        let velocity = vec![0.01; n];
        // Rising to 1 N, a fall of 0.5 N within 0.05 mm at sample 200, then a slow ramp down
        // of 0.1 N over the remaining 1.95 mm (never 0.1 N within 1 mm).
        let force: Vec<f64> = (0..n)
            .map(|i| match i {
                0..200 => i as f64 / 200.0,
                200..205 => 1.0 - 0.1 * (i - 199) as f64,
                _ => 0.5 - 0.1 * (i - 205) as f64 / 195.0,
            })
            .collect();
        let p = pops(&time, &depth, &velocity, &force);
        assert_eq!(p.len(), 1, "{p:?}");
        assert!(
            (p[0].depth_m - 199e-5).abs() < 2e-5 && p[0].drop_n > 0.5 && p[0].drop_n < 0.56,
            "{p:?}"
        );
        // Withdrawing, the same fall is no pop.
        assert!(pops(&time, &depth, &vec![-0.01; n], &force).is_empty());
    }
}
