//! A needle session as attempts: each stroke into the tissue and out of it again is one attempt,
//! scored on its own. A window session holds as many as the trainee makes; the model starts
//! every stroke at a fresh site (the tissue is intact again once the tip is out), so every
//! stroke is scored as the first.

use std::ops::Range;

use haptics::HapticSample;
use haptics::admittance_channel as c;

use super::score::{REVERSAL_M, Score, score};
use crate::scene::Goal;

/// Follows the tip's depth sample by sample and says where each stroke begins and ends. A
/// stroke begins at the first sample in the tissue (depth > 0) and ends at the first sample out
/// of it again, which it includes; one that never went [`REVERSAL_M`] deep is a touch at the
/// surface, not an attempt.
#[derive(Debug, Clone, Copy, Default)]
struct Splitter {
    start: Option<usize>,
    deepest_m: f64,
}

impl Splitter {
    /// Takes sample `index` at `depth_m`; returns the stroke it ends, if any.
    fn step(&mut self, index: usize, depth_m: f64) -> Option<Range<usize>> {
        match self.start {
            None if depth_m > 0.0 => {
                self.start = Some(index);
                self.deepest_m = depth_m;
                None
            }
            None => None,
            Some(_) if depth_m > 0.0 => {
                self.deepest_m = self.deepest_m.max(depth_m);
                None
            }
            Some(start) => {
                self.start = None;
                (self.deepest_m >= REVERSAL_M).then_some(start..index + 1)
            }
        }
    }

    /// The stroke still in the tissue when the samples end (`len` of them), if an attempt.
    fn finish(self, len: usize) -> Option<Range<usize>> {
        self.start
            .filter(|_| self.deepest_m >= REVERSAL_M)
            .map(|start| start..len)
    }
}

/// The strokes of a needle segment's `samples` (tissue surface at `surface_z_m`), in order.
pub fn strokes(samples: &[HapticSample], surface_z_m: f64) -> Vec<Range<usize>> {
    let mut splitter = Splitter::default();
    let mut out: Vec<Range<usize>> = samples
        .iter()
        .enumerate()
        .filter_map(|(i, s)| splitter.step(i, surface_z_m - s.channels[c::VIRTUAL_Z_M]))
        .collect();
    out.extend(splitter.finish(samples.len()));
    out
}

/// One stroke's `samples` scored against `goal`: its ruptures are the law's, read from the
/// samples as the session's analysis reads them.
pub fn score_stroke(samples: &[HapticSample], goal: &Goal, surface_z_m: f64, rate_hz: f64) -> Score {
    let punctures = super::analysis::punctures(samples, None);
    score(samples, &punctures, goal, surface_z_m, rate_hz)
}

/// A window session's attempts as they happen: keeps the stroke in progress and scores it the
/// moment the tip leaves the tissue, as the session's report will.
#[derive(Debug, Default)]
pub struct LiveAttempts {
    splitter: Splitter,
    stroke: Vec<HapticSample>,
    scored: Vec<Score>,
}

impl LiveAttempts {
    /// No attempt yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Takes the next sample; returns the score of the attempt it ends, if any.
    pub fn push(
        &mut self,
        sample: &HapticSample,
        goal: &Goal,
        surface_z_m: f64,
        rate_hz: f64,
    ) -> Option<&Score> {
        let depth_m = surface_z_m - sample.channels[c::VIRTUAL_Z_M];
        let inside = self.splitter.start.is_some() || depth_m > 0.0;
        if inside {
            self.stroke.push(*sample);
        }
        let index = self.stroke.len().saturating_sub(1);
        let ended = self.splitter.step(index, depth_m);
        if self.splitter.start.is_none() {
            let stroke = std::mem::take(&mut self.stroke);
            if ended.is_some() {
                self.scored
                    .push(score_stroke(&stroke, goal, surface_z_m, rate_hz));
                return self.scored.last();
            }
        }
        None
    }

    /// The attempts scored so far, in order.
    pub fn scored(&self) -> &[Score] {
        &self.scored
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use haptics::PunctureState;

    fn goal() -> Goal {
        Goal::guided_through(&["capsule"], 0.003)
    }

    /// A trace through `depths_mm`, 1 ms apart; the capsule gives where the depth first passes
    /// `gives_mm` in each stroke.
    fn trace(depths_mm: &[f64], gives_mm: f64) -> Vec<HapticSample> {
        let mut given = false;
        depths_mm
            .iter()
            .enumerate()
            .map(|(i, &d)| {
                let mut s = HapticSample {
                    time_s: i as f64 * 1e-3,
                    ..HapticSample::default()
                };
                s.channels[c::VIRTUAL_Z_M] = -d * 1e-3;
                let state = if d <= 0.0 {
                    given = false;
                    PunctureState::Approach
                } else if !given && d >= gives_mm {
                    given = true;
                    PunctureState::Puncture
                } else if given {
                    PunctureState::Insertion
                } else {
                    PunctureState::CapsuleLoading
                };
                s.channels[c::ENV_STATE] = state.code();
                s.channels[c::ENV_INPUT] = d * 1e-3;
                s
            })
            .collect()
    }

    fn ramp(from_mm: f64, to_mm: f64, steps: usize) -> Vec<f64> {
        (0..=steps)
            .map(|k| from_mm + (to_mm - from_mm) * k as f64 / steps as f64)
            .collect()
    }

    #[test]
    fn each_stroke_in_and_out_is_an_attempt_and_a_touch_is_not() {
        // Touch 0.5 mm and back; in to 12 mm and out; in to 8 mm and stay.
        let mut depths = ramp(-1.0, 0.5, 15);
        depths.extend(ramp(0.5, -1.0, 15));
        depths.extend(ramp(-1.0, 12.0, 130));
        depths.extend(ramp(12.0, -1.0, 130));
        depths.extend(ramp(-1.0, 8.0, 90));
        let samples = trace(&depths, 10.0);
        let found = strokes(&samples, 0.0);
        assert_eq!(found.len(), 2, "{found:?}");
        let (first, second) = (&found[0], &found[1]);
        assert!(samples[first.start].channels[c::VIRTUAL_Z_M] < 0.0);
        assert!(
            samples[first.end - 1].channels[c::VIRTUAL_Z_M] >= 0.0,
            "a stroke ends out of the tissue"
        );
        assert_eq!(second.end, samples.len(), "the last stroke never left");

        // The live watcher scores the same strokes the same way, the moment each ends.
        let mut live = LiveAttempts::new();
        let ended: Vec<Score> = samples
            .iter()
            .filter_map(|s| live.push(s, &goal(), 0.0, 1000.0).cloned())
            .collect();
        assert_eq!(ended.len(), 1, "the second stroke has not ended");
        let batch = score_stroke(&samples[first.clone()], &goal(), 0.0, 1000.0);
        assert_eq!(ended[0], batch);
        // 12 mm deep after the capsule gave at 10 mm: 2 mm past it, within the 3 mm allowed.
        assert!(batch.passed, "{}", batch.verdict);
        assert!((batch.overshoot_m.unwrap() - 0.002).abs() < 1e-9);
        let unfinished = score_stroke(&samples[second.clone()], &goal(), 0.0, 1000.0);
        assert!(
            !unfinished.passed && unfinished.verdict.contains("never gave"),
            "{}",
            unfinished.verdict
        );
        assert_eq!(live.scored().len(), 1);
    }
}
