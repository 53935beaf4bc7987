//! Cross-validation groups: which captures are held out together (a trial's scratches, a
//! recording's windows).

use std::borrow::Borrow;
use std::collections::BTreeSet;

use super::LabelledCapture;

/// Metadata key of a scratch's trial: the scratches of one object by several behaviours share
/// its surface and trial (`palpus gen --only sinapov` writes `trial=0…9`).
pub const TRIAL_KEY: &str = "trial";

/// A capture's trial (metadata [`TRIAL_KEY`]), if it has a non-empty one.
pub(crate) fn trial_of(c: &LabelledCapture) -> Option<&str> {
    c.capture.metadata().get(TRIAL_KEY).filter(|t| !t.is_empty())
}

/// Cross-validation group of each capture inside training: its trial, so that the folds of
/// [`crate::folds::group_folds`] hold out trial `t` of every surface together — a scratch is
/// never on both sides of a split, and every fold keeps about the same share of each surface.
/// Groups are numbered in the trials' numeric order (shorter strings first); captures without
/// a trial are a group each, after them.
pub fn trial_groups(captures: &[&LabelledCapture]) -> Vec<u64> {
    groups_by(captures, trial_of)
}

/// Recording of each capture: its `trial`, else its `run` (both in numeric order), else a
/// recording of its own — numbered densely from 0 — so that all windows of one recording, and
/// all recordings of one run or trial, are held out together.
pub fn recording_groups(captures: &[LabelledCapture]) -> Vec<u64> {
    groups_by(captures, recording_of)
}

/// A capture's recording: its trial, else its `run`.
fn recording_of(c: &LabelledCapture) -> Option<&str> {
    trial_of(c).or_else(|| c.capture.metadata().get("run").filter(|r| !r.is_empty()))
}

/// Numbers captures by `key`, densely from 0 in the keys' numeric order (shorter strings
/// first, so trial 10 follows 9); a capture without a key is a group of its own, after them.
fn groups_by<C: Borrow<LabelledCapture>>(
    captures: &[C],
    key: fn(&LabelledCapture) -> Option<&str>,
) -> Vec<u64> {
    let keys: BTreeSet<(usize, &str)> = captures
        .iter()
        .filter_map(|c| key(c.borrow()))
        .map(|k| (k.len(), k))
        .collect();
    let keys: Vec<(usize, &str)> = keys.into_iter().collect();
    let mut alone = keys.len() as u64;
    captures
        .iter()
        .map(|c| match key(c.borrow()) {
            Some(k) => keys.binary_search(&(k.len(), k)).map_or(0, |r| r as u64),
            None => {
                alone += 1;
                alone - 1
            }
        })
        .collect()
}
