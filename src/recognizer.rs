//! The scene's surface recognizer: a recognizer file (or one trained from a folder of rubbing
//! captures), run by the haptic thread inside each rubbing tick ([`Recognizing`]); its
//! decisions are read back from the samples' recognizer channels.

use std::path::PathBuf;

use anyhow::Context;
#[cfg(doc)]
use haptics::live_recognizer::Recognizing;
use haptics::live_recognizer::{LiveRecognizer, channel, decision_in};
#[cfg(doc)]
use recognize::NakanoWindowing;
use recognize::{FeatureNeeds, LabelledCapture, Method, RecognizerFile, TrainSettings};

use crate::scene::Scene;
use crate::session::report::Recognition;
use crate::session::{SegmentKind, SegmentRun};

/// A loaded recognizer and its live state.
#[derive(Debug)]
pub struct SceneRecognizer {
    live: LiveRecognizer,
}

impl SceneRecognizer {
    /// The scene's recognizer, or None when it has none.
    pub fn for_scene(scene: &Scene) -> anyhow::Result<Option<Self>> {
        let Some(section) = &scene.recognizer else {
            return Ok(None);
        };
        let model = match (&section.file, &section.captures) {
            (Some(file), _) => {
                let path = scene.resolve(file);
                RecognizerFile::load(&path)
                    .with_context(|| format!("loading recognizer {}", path.display()))?
            }
            (None, Some(dir)) => train(&scene.resolve(dir))?,
            (None, None) => return Ok(None),
        };
        let live =
            LiveRecognizer::new(&model, scene.device.rate_hz).context("starting the live recognizer")?;
        Ok(Some(Self { live }))
    }

    /// A copy of the recognizer for one segment's haptic thread (allocated here, on the
    /// caller's thread; it is then moved into the tick).
    pub fn live(&self) -> LiveRecognizer {
        self.live.clone()
    }

    /// The decisions a segment's haptic thread made, in order (none for other segments).
    pub fn recognize(&self, run: &SegmentRun) -> Vec<Recognition> {
        decisions(self.live.classes(), run)
    }
}

/// The decisions in a surface segment's samples: one at every sample where the recognizer's
/// decision count steps.
pub fn decisions(classes: &[String], run: &SegmentRun) -> Vec<Recognition> {
    let SegmentKind::Surface { surface } = &run.segment.kind else {
        return Vec::new();
    };
    let mut out = Vec::new();
    let mut made = 0.0;
    for s in &run.samples {
        let count = s.channels[channel::DECISIONS];
        if count == made {
            continue;
        }
        made = count;
        if let Some((label, confidence)) = decision_in(&s.channels)
            && count > 0.0
        {
            out.push(Recognition {
                object: run.segment.object.clone(),
                truth: surface.clone(),
                time_s: s.time_s,
                label: classes.get(label).cloned().unwrap_or_default(),
                confidence,
            });
        }
    }
    out
}

/// Trains Nakano's SOM on every `*.csv` rubbing capture in `dir`, with the method's defaults
/// ([`TrainSettings::new`]: the protocol's windows, [`NakanoWindowing::protocol`]). Each
/// capture is kept only as its training windows once read, so a folder of many long captures
/// holds one capture's samples at a time.
fn train(dir: &std::path::Path) -> anyhow::Result<RecognizerFile> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("reading recognizer captures in {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "csv"))
        .collect();
    paths.sort();
    let settings = TrainSettings::new(Method::Som);
    let mut needs: Option<FeatureNeeds> = None;
    let mut captures = Vec::with_capacity(paths.len());
    for p in &paths {
        let c = LabelledCapture::read(p).with_context(|| format!("reading {}", p.display()))?;
        let needs = match &needs {
            Some(n) => n,
            None => needs.insert(FeatureNeeds::training(&settings, c.capture.metadata().rate_hz())?),
        };
        captures.push(c.keep_features(needs)?);
    }
    if captures.is_empty() {
        anyhow::bail!("no captures in {}", dir.display());
    }
    Ok(recognize::train(&captures, &settings)?)
}
