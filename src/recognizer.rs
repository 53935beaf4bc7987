//! The scene's surface recognizer: a recognizer file (or one trained from a folder of rubbing
//! captures), fed every sample of a rubbing segment in tick order through the same
//! allocation-free [`LiveRecognizer`] the haptic side uses.

use std::path::PathBuf;

use anyhow::Context;
use haptics::acquire::{self, Protocol};
use haptics::recognize::LiveRecognizer;
use identify::recognition::model::{LabelledCapture, NakanoWindowing, RecognizerFile};
use identify::recognition::som::SomParams;

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

    /// The decisions over a rubbing segment, in order (none for other segments).
    pub fn recognize(&mut self, run: &SegmentRun) -> anyhow::Result<Vec<Recognition>> {
        let SegmentKind::Surface { surface } = &run.segment.kind else {
            return Ok(Vec::new());
        };
        self.live.reset();
        let mut out = Vec::new();
        let mut row = Vec::with_capacity(8);
        for s in &run.samples {
            row.clear();
            // The same rows the captures it was trained on hold: rubbing phase only, at the
            // device's resolution.
            if !acquire::row(Protocol::Rubbing, s, &mut row) {
                continue;
            }
            if let Some(d) = self.live.push(row[1], row[4], row[6])? {
                out.push(Recognition {
                    object: run.segment.object.clone(),
                    truth: surface.clone(),
                    time_s: s.time_s,
                    label: self.live.classes().get(d.label).cloned().unwrap_or_default(),
                    confidence: d.confidence,
                });
            }
        }
        Ok(out)
    }
}

/// Trains Nakano's SOM on every `*.csv` rubbing capture in `dir` (1 s windows every 0.1 s).
fn train(dir: &std::path::Path) -> anyhow::Result<RecognizerFile> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("reading recognizer captures in {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "csv"))
        .collect();
    paths.sort();
    let captures = paths
        .iter()
        .map(|p| LabelledCapture::read(p).with_context(|| format!("reading {}", p.display())))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let rate_hz = captures
        .first()
        .map(|c| c.capture.metadata().rate_hz())
        .with_context(|| format!("no captures in {}", dir.display()))?;
    let windowing = NakanoWindowing::new(1.0, 0.1, rate_hz)?;
    Ok(RecognizerFile::train_som(
        &captures,
        windowing,
        SomParams::default(),
    )?)
}
