//! Nakano's features of a window decided the moment it is complete (see [`EdgeWindow`]).

use super::{FEATURES, FeatureBuffers, NakanoConfig, window_features};
use crate::RecognizeError;
use crate::{SettingError, UsageError};

/// Nakano's features of the window that ends at the latest sample, as known at that sample:
/// the filters' lookahead past it is the signals' mirror image through it, so the window is
/// decided the moment it is complete instead of a lookahead later.
///
/// Heights and positions are reflected through the last sample (`2·v_last − v`, continuing a
/// slope straight on, as [`super::mirror_start`] does at a stroke's first sample), the friction as its
/// plain mirror (it is never filtered). Before the stroke's first sample, when the window starts
/// within a margin of it, the signals are reflected through that sample in the same way, and a
/// reflection that falls outside the known samples is reflected again, so a window is decided on
/// what was measured up to its end and nothing later.
///
/// Compared with a window decided a lookahead later, the last quarter-second of roughness is a
/// guess, so the features are noisier; a classifier trained on windows computed this same way
/// ([`crate::NakanoWindowing::mirrored_end`]) learns that noise.
#[derive(Debug)]
pub struct EdgeWindow {
    config: NakanoConfig,
    len: usize,
    margin: usize,
    position_m: Vec<f64>,
    height_m: Vec<f64>,
    friction_n: Vec<f64>,
    buffers: FeatureBuffers,
}

/// Reflections [`reflected`] makes at most before it gives up: each reaches one window's
/// length further past an edge.
const MAX_REFLECTIONS: usize = 7;

impl EdgeWindow {
    /// Whether a window of `len` samples can be decided at a stroke's first window, where
    /// nothing before it is known: the mirror has to reach the filters' `margin` past both of
    /// its edges within [`MAX_REFLECTIONS`]. Recognizer settings are checked against this, so
    /// that no reader meets a window it cannot read.
    pub fn mirror_reaches(len: usize, margin: usize) -> bool {
        len >= 2 && margin as u128 <= MAX_REFLECTIONS as u128 * (len as u128 - 1)
    }

    /// Windows of `len` samples (at least 2) under `config`'s filters; all memory is taken
    /// here.
    pub fn new(config: NakanoConfig, len: usize) -> Result<Self, RecognizeError> {
        config.check()?;
        if len < 2 {
            return Err(RecognizeError::Setting(SettingError::WindowTooShort { len }));
        }
        Ok(Self::with_room(config, len))
    }

    /// All buffers made for `len` and `config`'s margin (both checked).
    fn with_room(config: NakanoConfig, len: usize) -> Self {
        let margin = config.lookahead_samples();
        let span = len + 2 * margin;
        Self {
            config,
            len,
            margin,
            position_m: Vec::with_capacity(span),
            height_m: Vec::with_capacity(span),
            friction_n: Vec::with_capacity(span),
            buffers: FeatureBuffers::with_capacity(len, margin),
        }
    }

    /// Samples of history a window needs once the stroke is longer than that: the window and
    /// the filters' margin before it.
    pub fn history_samples(&self) -> usize {
        self.len + self.margin
    }

    /// The first sample of the stroke the window starting at `window_start` is computed from:
    /// the filters' margin before it, or the stroke's first sample when the window starts
    /// within a margin of it.
    pub fn history_start(&self, window_start: usize) -> usize {
        window_start.saturating_sub(self.margin)
    }

    /// The features of the window of `len` samples starting at the stroke's sample
    /// `window_start`, from `position_m`, `height_m` and `friction_n` (equally long) that end
    /// with the window's last sample and begin at [`EdgeWindow::history_start`] (or earlier,
    /// once the window starts a margin past the stroke's start: those are ignored). Allocates
    /// nothing.
    pub fn features(
        &mut self,
        window_start: usize,
        position_m: &[f64],
        height_m: &[f64],
        friction_n: &[f64],
    ) -> Result<[f64; FEATURES], RecognizeError> {
        self.features_of(window_start, self.len, position_m, height_m, friction_n)
    }

    /// [`EdgeWindow::features`] of a window of `len` samples (at least 2, at most
    /// the length it was made for) starting at the stroke's sample `window_start`.
    pub fn features_of(
        &mut self,
        window_start: usize,
        len: usize,
        position_m: &[f64],
        height_m: &[f64],
        friction_n: &[f64],
    ) -> Result<[f64; FEATURES], RecognizeError> {
        if len < 2 {
            return Err(RecognizeError::Setting(SettingError::WindowTooShort { len }));
        }
        let n = position_m.len();
        if height_m.len() != n || friction_n.len() != n {
            return Err(RecognizeError::Usage(UsageError::SignalLengths {
                position: n,
                height: height_m.len(),
                friction: friction_n.len(),
            }));
        }
        let margin = self.margin;
        let too_short = || {
            RecognizeError::Usage(UsageError::WindowOutOfRange {
                start: window_start,
                len,
                margin,
                samples: n,
            })
        };
        // The samples from the history's start to the window's end are known; before the
        // stroke's first sample nothing is.
        let needed = window_start + len - self.history_start(window_start);
        if len > self.len || n < needed || (window_start < margin && n != needed) {
            return Err(too_short());
        }
        let known = n - needed..n;
        // Indices relative to the first known sample; the window is the last `len` of them.
        let e = known.len() as i64;
        let window_start = e - len as i64;
        let (lo, hi) = (window_start - margin as i64, e + margin as i64);
        for (out, v, odd) in [
            (&mut self.position_m, position_m, true),
            (&mut self.height_m, height_m, true),
            (&mut self.friction_n, friction_n, false),
        ] {
            let v = &v[known.clone()];
            out.clear();
            // Before the stroke (only from its start), then the known samples as they are, then
            // the mirror past the last; the general reflection only where one is not enough.
            for i in lo..0 {
                out.push(reflected(v, odd, i).ok_or_else(too_short)?);
            }
            out.extend_from_slice(&v[lo.max(0) as usize..]);
            let last = v[v.len() - 1];
            for i in e..hi {
                let inner = 2 * (e - 1) - i;
                let value = if inner >= 0 {
                    let w = v[inner as usize];
                    if odd { 2.0 * last - w } else { w }
                } else {
                    reflected(v, odd, i).ok_or_else(too_short)?
                };
                out.push(value);
            }
        }
        window_features(
            &self.position_m,
            &self.height_m,
            &self.friction_n,
            margin,
            len,
            &self.config,
            &mut self.buffers,
        )
    }
}

impl Clone for EdgeWindow {
    /// A copy with all its buffers' room, as the original was made: a derived clone would
    /// keep only what is in them and grow (allocate) on the haptic thread.
    fn clone(&self) -> Self {
        Self::with_room(self.config, self.len)
    }
}

/// The value at index `i` of `v` extended past both ends by its mirror image through the end
/// sample (odd: `2·v_end − v`, even: `v`), reflecting again while outside; `None` after a few
/// reflections (a stroke too short for the margin).
fn reflected(v: &[f64], odd: bool, mut i: i64) -> Option<f64> {
    let last = v.len() as i64 - 1;
    if last < 1 {
        return None;
    }
    // value = offset + sign · v[i]
    let (mut offset, mut sign) = (0.0, 1.0);
    for _ in 0..=MAX_REFLECTIONS {
        let end = if i > last {
            i = 2 * last - i;
            v[last as usize]
        } else if i < 0 {
            i = -i;
            v[0]
        } else {
            return Some(offset + sign * v[i as usize]);
        };
        if odd {
            offset += sign * 2.0 * end;
            sign = -sign;
        }
    }
    None
}
