//! How far a tool has travelled along a surface, read through a play: the position moves a
//! point that lags it by up to half the play either way, and only that point's path counts.
//!
//! A hand that holds a tool still trembles, and an encoder flickers between two counts: summed
//! sample by sample, the path of a tool at rest grows by tens of micrometres a tremor cycle, so
//! a rest reads as slow rubbing and a slow stroke as a faster one. Through the play (the
//! backlash, or Krasnosel'skii–Pokrovskii "play", operator) a sway narrower than the play adds
//! at most its reach once (a stroke leaves the point half the play behind the tool, so a sway
//! onward drags it that far) and then nothing; a stroke in one direction adds exactly its
//! displacement once it has moved half the play; each turn back costs the play. The play is
//! [`WAVE_SMOOTHING_M`], the span the roughness features smooth over: a tool that stays within
//! it reads one spot of the surface.
//!
//! Hand-written: it is a few lines of state, and the windows offline and the live recognizer
//! must run the same ones to agree to the bit.

use super::nakano::WAVE_SMOOTHING_M;

/// The play a tool's path is read through, m ([`WAVE_SMOOTHING_M`]).
pub const TRAVEL_PLAY_M: f64 = WAVE_SMOOTHING_M;

/// A stroke's path through the play, fed one position at a time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlayedPath {
    /// The point the position drags; `None` before the stroke's first sample.
    point_m: Option<f64>,
    /// The point's path since the stroke's first sample, m.
    path_m: f64,
}

impl Default for PlayedPath {
    fn default() -> Self {
        Self::new()
    }
}

impl PlayedPath {
    /// A stroke not yet begun.
    pub const fn new() -> Self {
        Self {
            point_m: None,
            path_m: 0.0,
        }
    }

    /// Adds the stroke's next position, m; returns the path since its first, m (0 at the first,
    /// never decreasing).
    pub fn push(&mut self, position_m: f64) -> f64 {
        let half = 0.5 * TRAVEL_PLAY_M;
        let point = *self.point_m.get_or_insert(position_m);
        let dragged = position_m.clamp(point - half, point + half);
        // The point follows when the position leaves the play: it then sits half the play
        // behind it.
        let moved_to = point + (position_m - dragged);
        self.path_m += (moved_to - point).abs();
        self.point_m = Some(moved_to);
        self.path_m
    }

    /// Forgets the stroke.
    pub fn reset(&mut self) {
        *self = Self::new();
    }

    /// The path at each of `position_m` (one stroke from its first sample), m.
    pub fn series(position_m: &[f64]) -> Vec<f64> {
        let mut played = Self::new();
        position_m.iter().map(|&x| played.push(x)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stroke_in_one_direction_counts_its_displacement_past_half_the_play() {
        let half = 0.5 * TRAVEL_PLAY_M;
        let x: Vec<f64> = (0..2000).map(|k| 0.012 + 5e-6 * k as f64).collect();
        let path = PlayedPath::series(&x);
        for (k, (&p, &x_k)) in path.iter().zip(&x).enumerate() {
            let expected = (x_k - x[0] - half).max(0.0);
            assert!((p - expected).abs() < 1e-12, "sample {k}: {p} against {expected}");
        }
        // Backwards alike.
        let back: Vec<f64> = x.iter().map(|v| -v).collect();
        assert_eq!(PlayedPath::series(&back), path);
    }

    #[test]
    fn a_sway_within_the_play_adds_nothing() {
        // 30 µm of tremor at 9 Hz, read by a 10 µm encoder, for 2 s.
        let x: Vec<f64> = (0..2000)
            .map(|k| {
                let sway = 30e-6 * (2.0 * std::f64::consts::PI * 9.0 * k as f64 / 1e3).sin();
                ((0.02 + sway) / 1e-5).round() * 1e-5
            })
            .collect();
        let raw: f64 = x.windows(2).map(|p| (p[1] - p[0]).abs()).sum();
        assert!(raw > 2e-3, "the samples' own path: {raw}");
        assert!(PlayedPath::series(&x).iter().all(|&p| p == 0.0));
    }

    #[test]
    fn a_turn_back_costs_the_play_and_the_path_never_decreases() {
        // 3 mm out, 3 mm back.
        let x: Vec<f64> = (0..=600)
            .map(|k| 1e-5 * (if k <= 300 { k } else { 600 - k }) as f64)
            .collect();
        let path = PlayedPath::series(&x);
        assert!(path.windows(2).all(|p| p[1] >= p[0]));
        let total = path[path.len() - 1];
        let expected = 6e-3 - 0.5 * TRAVEL_PLAY_M - TRAVEL_PLAY_M;
        assert!((total - expected).abs() < 1e-12, "{total} against {expected}");
    }

    #[test]
    fn reset_starts_a_new_stroke_where_the_tool_is() {
        let mut played = PlayedPath::new();
        for k in 0..100 {
            played.push(1e-5 * k as f64);
        }
        played.reset();
        assert_eq!(played.push(5.0), 0.0);
        let path = played.push(5.0 + 0.5 * TRAVEL_PLAY_M + 1e-4);
        assert!((path - 1e-4).abs() < 1e-12, "{path}");
    }
}
