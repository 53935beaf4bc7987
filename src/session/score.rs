//! How an insertion attempt did against its scene's goal ([`crate::scene::Goal`]): passed or
//! failed and why, the overshoot after the target layer gave, the peak force, the time to the
//! target, withdrawals and re-insertions, and how smooth the insertion was. These are what
//! needle-insertion training is judged by (loss-of-resistance tasks are scored on the overshoot
//! after the pop, the force, the time and the number of re-insertions).

use haptics::HapticSample;
use haptics::admittance_channel as c;
use serde::Serialize;

use super::analysis::Puncture;
use super::smoothness::sparc;
use crate::scene::{Goal, in_words};

/// Backing off or advancing again by less than this inside the tissue is a tremor, not a
/// withdrawal or a re-insertion, m.
pub const REVERSAL_M: f64 = 0.001;

/// One attempt's score.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Score {
    /// Whether the attempt met the goal.
    pub passed: bool,
    /// Why, in words: what it achieved, or every reason it failed.
    pub verdict: String,
    /// The layer after whose giving the tip had to stop.
    pub target: String,
    /// The layers that gave, in the order they gave (named as the goal names them; a layer past
    /// the goal's list is `layer N`).
    pub layers_given: Vec<String>,
    /// Depth at which the target gave, m.
    pub target_depth_m: Option<f64>,
    /// How far past that depth the tip went, m.
    pub overshoot_m: Option<f64>,
    /// How far past it the goal allows, m.
    pub allowed_overshoot_m: f64,
    /// The largest axial force on the needle, N.
    pub peak_force_n: f64,
    /// From first contact to the target giving, s.
    pub time_to_target_s: Option<f64>,
    /// Times the tip backed off by at least [`REVERSAL_M`] inside the tissue (the final
    /// withdrawal out of it not counted).
    pub withdrawals: u32,
    /// Times it advanced again by at least [`REVERSAL_M`] after backing off.
    pub reinsertions: u32,
    /// SPARC of the tip's speed from first contact to its deepest point (about −1.4 for one
    /// smooth push; more negative with pauses and corrections).
    pub smoothness_sparc: Option<f64>,
    /// Deepest tip depth, m.
    pub deepest_m: f64,
}

/// Scores the needle segment's `samples` (tissue surface at `surface_z_m`, ruptures
/// `punctures` in order, loop at `rate_hz`) against `goal`.
pub fn score(
    samples: &[HapticSample],
    punctures: &[Puncture],
    goal: &Goal,
    surface_z_m: f64,
    rate_hz: f64,
) -> Score {
    let depth = |s: &HapticSample| surface_z_m - s.channels[c::VIRTUAL_Z_M];
    let target = goal.layer_index(&goal.stop_after).unwrap_or(0);
    let name = |k: usize| {
        goal.layers
            .get(k)
            .cloned()
            .unwrap_or_else(|| format!("layer {}", k + 1))
    };
    let layers_given: Vec<String> = (0..punctures.len()).map(name).collect();
    let gave = punctures.get(target);
    let first_contact = samples.iter().position(|s| depth(s) > 0.0);
    let deepest = samples.iter().map(depth).fold(f64::NEG_INFINITY, f64::max);
    let deepest_m = if deepest.is_finite() { deepest } else { 0.0 };
    let peak_force_n = samples
        .iter()
        .map(|s| s.channels[c::MODEL_FORCE_Z_N])
        .filter(|f| f.is_finite())
        .fold(0.0, f64::max);
    let overshoot_m = gave.map(|p| {
        let after = samples.iter().filter(|s| s.time_s >= p.time_s).map(depth);
        (after.fold(f64::NEG_INFINITY, f64::max) - p.depth_m).max(0.0)
    });
    let time_to_target_s = match (gave, first_contact) {
        (Some(p), Some(k)) => Some(p.time_s - samples[k].time_s),
        _ => None,
    };
    let (withdrawals, reinsertions) = reversals(samples.iter().map(depth));
    let smoothness_sparc = first_contact.and_then(|k| {
        let end = samples
            .iter()
            .enumerate()
            .skip(k)
            .max_by(|a, b| depth(a.1).total_cmp(&depth(b.1)))
            .map_or(k, |(i, _)| i);
        let speed: Vec<f64> = samples[k..=end]
            .iter()
            .map(|s| s.channels[c::VIRTUAL_VZ_MPS].abs())
            .collect();
        sparc(&speed, rate_hz)
    });

    let mm = |m: f64| m * 1e3;
    let mut failures = Vec::new();
    for layer in &goal.must_not_puncture {
        if layers_given.contains(layer) {
            failures.push(format!("punctured the {}", in_words(layer)));
        }
    }
    if let Some(limit) = goal.max_force_n
        && peak_force_n > limit
    {
        failures.push(format!(
            "the axial force reached {peak_force_n:.2} N, over the limit of {limit:.2} N"
        ));
    }
    match (gave, overshoot_m) {
        (None, _) => failures.push(format!(
            "the {} never gave (deepest {:.1} mm, {} layer{} gave)",
            in_words(&goal.stop_after),
            mm(deepest_m),
            layers_given.len(),
            if layers_given.len() == 1 { "" } else { "s" }
        )),
        (Some(p), Some(over)) if over > goal.within_m => failures.push(format!(
            "went {:.1} mm past where the {} gave at {:.1} mm (allowed {:.1} mm)",
            mm(over),
            in_words(&goal.stop_after),
            mm(p.depth_m),
            mm(goal.within_m)
        )),
        _ => {}
    }
    if let (Some(limit), Some(t)) = (goal.time_limit_s, time_to_target_s)
        && t > limit
    {
        failures.push(format!(
            "the {} gave after {t:.1} s, over the limit of {limit:.1} s",
            in_words(&goal.stop_after)
        ));
    }
    let passed = failures.is_empty();
    let verdict = if passed {
        format!(
            "stopped {:.1} mm past where the {} gave at {:.1} mm (allowed {:.1} mm)",
            mm(overshoot_m.unwrap_or(0.0)),
            in_words(&goal.stop_after),
            mm(gave.map_or(0.0, |p| p.depth_m)),
            mm(goal.within_m)
        )
    } else {
        failures.join("; ")
    };
    Score {
        passed,
        verdict,
        target: goal.stop_after.clone(),
        layers_given,
        target_depth_m: gave.map(|p| p.depth_m),
        overshoot_m,
        allowed_overshoot_m: goal.within_m,
        peak_force_n,
        time_to_target_s,
        withdrawals,
        reinsertions,
        smoothness_sparc,
        deepest_m,
    }
}

/// Withdrawals and re-insertions of a depth trace: reversals of at least [`REVERSAL_M`] while
/// inside the tissue (depth > 0). A withdrawal that takes the tip out of the tissue, as every
/// attempt ends, is not counted unless the tip goes back in.
fn reversals(depths: impl Iterator<Item = f64>) -> (u32, u32) {
    let (mut withdrawals, mut reinsertions) = (0u32, 0u32);
    // Advancing: the deepest point since the last reversal; backing off: the shallowest.
    let mut advancing = true;
    let mut extreme = f64::NEG_INFINITY;
    // A back-off not yet counted: it counts once the tip advances again or stays in.
    let mut pending = false;
    for d in depths {
        if d <= 0.0 {
            // Out of the tissue: a pending back-off was the attempt's end.
            pending = false;
            advancing = true;
            extreme = f64::NEG_INFINITY;
            continue;
        }
        if advancing {
            extreme = extreme.max(d);
            if d < extreme - REVERSAL_M {
                advancing = false;
                pending = true;
                extreme = d;
            }
        } else {
            extreme = extreme.min(d);
            if d > extreme + REVERSAL_M {
                advancing = true;
                if pending {
                    withdrawals += 1;
                    pending = false;
                }
                reinsertions += 1;
                extreme = d;
            }
        }
    }
    // Ending inside the tissue after backing off: that back-off was a withdrawal.
    (withdrawals + u32::from(pending), reinsertions)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reversals_count_back_offs_and_advances_past_the_tremor_band() {
        let mm = |v: &[f64]| v.iter().map(|d| d * 1e-3).collect::<Vec<_>>();
        // In to 20 mm, out of the tissue: no withdrawal, no re-insertion.
        let once = mm(&[-2.0, 0.0, 5.0, 10.0, 20.0, 10.0, 0.0, -2.0]);
        assert_eq!(reversals(once.into_iter()), (0, 0));
        // Back off 3 mm and push again, then out: one each.
        let again = mm(&[-1.0, 5.0, 15.0, 12.0, 18.0, 5.0, -1.0]);
        assert_eq!(reversals(again.into_iter()), (1, 1));
        // A 0.5 mm tremor is neither.
        let tremor = mm(&[-1.0, 5.0, 10.0, 9.5, 10.0, 9.6, 12.0, -1.0]);
        assert_eq!(reversals(tremor.into_iter()), (0, 0));
        // Ending inside after backing off: a withdrawal without a re-insertion.
        let stays = mm(&[-1.0, 5.0, 20.0, 15.0]);
        assert_eq!(reversals(stays.into_iter()), (1, 0));
        // Twice back and forth, then out.
        let twice = mm(&[-1.0, 10.0, 7.0, 12.0, 9.0, 14.0, -1.0]);
        assert_eq!(reversals(twice.into_iter()), (2, 2));
    }
}
