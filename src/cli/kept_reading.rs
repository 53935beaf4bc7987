//! Reading many captures while keeping of each only the features a command will read, so that
//! memory follows the feature vectors, not the samples.

use std::path::PathBuf;

use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use recognize::{FeatureNeeds, LabelledCapture};

use super::mapped_captures::MappedCaptures;

/// Reads `paths` with `read` and keeps of each capture only the features `needs` names,
/// dropping its samples as soon as they are computed. `needs` is asked once, with the first
/// capture (its rate, its columns), before anything is kept; the other paths are then read on
/// all cores, each core holding one capture's samples at a time. The captures come back in
/// the order of `paths`, and the first error (in that order) is the one returned.
pub(crate) fn keeping_each(
    paths: &[PathBuf],
    read: impl Fn(&PathBuf) -> anyhow::Result<Vec<LabelledCapture>> + Sync,
    mut needs: impl FnMut(&LabelledCapture) -> anyhow::Result<FeatureNeeds>,
) -> anyhow::Result<Vec<LabelledCapture>> {
    let bar = ProgressBar::new(paths.len() as u64).with_style(
        ProgressStyle::with_template("reading captures {bar:30} {pos}/{len} {elapsed} (eta {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut needed: Option<FeatureNeeds> = None;
    let mut captures = Vec::with_capacity(paths.len());
    let mut rest = paths;
    // Paths are read one by one until one gives a capture to ask `needs` with.
    while needed.is_none() {
        let Some((path, after)) = rest.split_first() else {
            break;
        };
        rest = after;
        for c in read(path)? {
            let wanted = match &needed {
                Some(n) => n,
                None => needed.insert(needs(&c)?),
            };
            captures.push(c.keep_features(wanted)?);
        }
        bar.inc(1);
    }
    if let Some(wanted) = &needed {
        // Collected whole, so that the error returned is the first in order, not the first
        // a core happened to meet.
        let kept: Vec<anyhow::Result<Vec<LabelledCapture>>> = rest
            .par_iter()
            .map(|path| {
                let kept = read(path)?
                    .into_iter()
                    .map(|c| c.keep_features(wanted))
                    .collect::<Result<Vec<_>, _>>()?;
                bar.inc(1);
                Ok(kept)
            })
            .collect();
        for each in kept {
            captures.extend(each?);
        }
    }
    bar.finish_and_clear();
    Ok(captures)
}

/// Reads `paths` one at a time and keeps of each only the features `needs` lists (asked once,
/// with the first capture), dropping its samples before the next is read: memory holds one
/// capture's samples at a time however many captures there are, and the results are those of
/// the whole captures. A bar on stderr counts the captures read (only on a terminal).
pub(crate) fn read_keeping(
    input: &MappedCaptures,
    paths: &[PathBuf],
    default_rate_hz: Option<f64>,
    needs: impl FnMut(&LabelledCapture) -> anyhow::Result<FeatureNeeds>,
) -> anyhow::Result<Vec<LabelledCapture>> {
    keeping_each(
        paths,
        |path| input.read(std::slice::from_ref(path), default_rate_hz),
        needs,
    )
}
