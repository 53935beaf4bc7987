//! Reading many captures while keeping of each only the features a command will read, so that
//! memory follows the feature vectors, not the samples.

use std::path::PathBuf;

use indicatif::{ProgressBar, ProgressStyle};
use recognize::{FeatureNeeds, LabelledCapture};

use super::mapped_captures::MappedCaptures;

/// Reads `paths` one at a time with `read` and keeps of each capture only the features `needs`
/// names, dropping its samples before the next is read. `needs` is asked once, with the first
/// capture (its rate, its columns), before anything is kept.
pub(crate) fn keeping_each(
    paths: &[PathBuf],
    mut read: impl FnMut(&PathBuf) -> anyhow::Result<Vec<LabelledCapture>>,
    mut needs: impl FnMut(&LabelledCapture) -> anyhow::Result<FeatureNeeds>,
) -> anyhow::Result<Vec<LabelledCapture>> {
    let bar = ProgressBar::new(paths.len() as u64).with_style(
        ProgressStyle::with_template("reading captures {bar:30} {pos}/{len} {elapsed} (eta {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut needed: Option<FeatureNeeds> = None;
    let mut captures = Vec::with_capacity(paths.len());
    for path in paths {
        for c in read(path)? {
            let wanted = match &needed {
                Some(n) => n,
                None => needed.insert(needs(&c)?),
            };
            captures.push(c.keep_features(wanted)?);
        }
        bar.inc(1);
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
