//! The scene's surface recognizer: a recognizer file (or one trained from a folder of rubbing
//! captures), run over each rubbing segment's samples on the recorder thread, off the haptic
//! thread ([`SampleRecognizer`]); its decisions are read back from the samples' recognizer
//! channels.

use std::path::PathBuf;

use anyhow::Context;
#[cfg(doc)]
use haptics::SampleRecognizer;
use haptics::rt::HapticSample;
use haptics::{LiveRecognizer, decision_in, recognizer_channel as channel};
#[cfg(doc)]
use recognize::NakanoWindowing;
use recognize::{DEFAULT_MEMORY_S, DEFAULT_THRESHOLD};
use recognize::{
    DecisionTiming, FeatureNeeds, FeatureSet, LabelledCapture, Method, NamedDecision, RecognizerFile,
    TrainSettings,
};

use crate::scene::Scene;
use crate::session::report::{Recognition, RecognizerLine, SurfaceTiming, WindowWeightFrom};
use crate::session::{SegmentKind, SegmentRun};

/// A loaded recognizer and its live state.
#[derive(Debug)]
pub struct SceneRecognizer {
    live: LiveRecognizer,
    /// Where its windows' weight in the posterior came from, for the report.
    weight_from: Option<WindowWeightFrom>,
}

impl SceneRecognizer {
    /// The scene's recognizer, or None when it has none.
    pub fn for_scene(scene: &Scene) -> anyhow::Result<Option<Self>> {
        let Some(section) = &scene.recognizer else {
            return Ok(None);
        };
        // The scene checked the name when it was read.
        let method = Method::named(&section.method).unwrap_or(Method::Som);
        let memory_s = section.memory_s.unwrap_or(DEFAULT_MEMORY_S);
        let model = match (&section.file, &section.captures) {
            (Some(file), _) => {
                let path = scene.resolve(file);
                let model = RecognizerFile::load(&path)
                    .with_context(|| format!("loading recognizer {}", path.display()))?;
                if model.method() != section.method {
                    anyhow::bail!(
                        "{}: recognizer.method is {} but {} holds a {} recognizer",
                        scene.path.display(),
                        section.method,
                        path.display(),
                        model.method()
                    );
                }
                model
            }
            (None, Some(dir)) => train(&scene.resolve(dir), method, section.window_s, memory_s)?,
            (None, None) => return Ok(None),
        };
        let rate_hz = scene.device.rate_hz;
        let weight_from = WindowWeightFrom::of(&model);
        if let Some(note) = weight_memory_note(&model, memory_s) {
            eprintln!("warning: {}: recognizer: {note}", scene.path.display());
        }
        let live = match model.sequential_params(memory_s) {
            Some(params) => {
                let params = params.threshold(section.threshold.unwrap_or(DEFAULT_THRESHOLD));
                let params = match section.change_odds {
                    Some(0.0) => params.without_change_test(),
                    Some(odds) => params.change_log_odds(odds.ln()),
                    None => params,
                };
                let params = params.build().context("the recognizer's anytime settings")?;
                LiveRecognizer::with_params(&model, rate_hz, params)
            }
            None => LiveRecognizer::new(&model, rate_hz),
        }
        .context("starting the live recognizer")?;
        Ok(Some(Self { live, weight_from }))
    }

    /// A copy of the recognizer for one segment's haptic thread (allocated here, on the
    /// caller's thread; it is then moved into the tick).
    pub fn live(&self) -> LiveRecognizer {
        self.live.clone()
    }

    /// How the report names it.
    pub fn line(&self) -> RecognizerLine {
        line(&self.live, self.weight_from.clone())
    }

    /// The surfaces it names, in the order of its posterior.
    pub fn classes(&self) -> &[String] {
        self.live.classes()
    }

    /// The decisions a segment's haptic thread made, in order (none for other segments).
    pub fn recognize(&self, run: &SegmentRun) -> Vec<Recognition> {
        decisions(self.live.classes(), run)
    }
}

/// Why `model`'s window weight does not hold for a posterior keeping `memory_s` of evidence:
/// it was fitted at another memory. `None` when it holds, or when no weight was fitted.
pub fn weight_memory_note(model: &RecognizerFile, memory_s: f64) -> Option<String> {
    let fit = model
        .posterior_weight
        .as_ref()
        .filter(|p| !p.fitted_at_memory(memory_s))?;
    Some(format!(
        "its window weight was fitted over a memory of {} s and is used over {memory_s} s, outside \
         what the fit measured (train with --weight-fit-memory-s {memory_s} to fit it there)",
        fit.memory_s
    ))
}

/// How the report names `live` and the settings it decides with (its windows' weight taken
/// from `weight_from`).
fn line(live: &LiveRecognizer, weight_from: Option<WindowWeightFrom>) -> RecognizerLine {
    let w = live.windowing();
    let params = live.sequential_params();
    let hop_s = w.hop_samples as f64 / w.rate_hz;
    RecognizerLine {
        method: live.method().to_owned(),
        features: live.features().name().to_owned(),
        window_s: w.window_s(),
        hop_s,
        window_m: w.travel.map(|t| t.window_m),
        friction_cutoff_m: w.friction_over_travel.map(|f| f.cutoff_m),
        decided_after_s: w.lookahead_samples() as f64 / w.rate_hz,
        threshold: params.map(|p| p.threshold()),
        memory_s: params.map(|p| p.memory() as f64 * hop_s),
        change_odds: params.and_then(|p| p.change_log_odds()).map(f64::exp),
        window_weight: params.map(|p| p.weight()),
        window_weight_from: params.and(weight_from),
    }
}

/// The decisions in a surface segment's samples: one at every sample where the recognizer's
/// decision count steps, undecided ones included.
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
        if count > 0.0
            && let Some(r) = recognition(classes, &run.segment.object, surface, s)
        {
            out.push(r);
        }
    }
    out
}

/// The decision `sample`'s recognizer channels carry, as the report lists it; `None` before
/// the stroke's first.
pub fn recognition(
    classes: &[String],
    object: &str,
    truth: &str,
    sample: &HapticSample,
) -> Option<Recognition> {
    let d = decision_in(&sample.channels)?;
    let name = |i: usize| classes.get(i).cloned();
    Some(Recognition {
        object: object.to_owned(),
        truth: truth.to_owned(),
        time_s: sample.time_s,
        label: match d.label {
            Some(l) => Some(name(l)?),
            None => None,
        },
        best: name(d.best)?,
        confidence: d.confidence,
    })
}

/// How soon each surface segment's surface was named, from the start of its stroke (the first
/// rubbing tick, where the recognizer starts).
pub fn timings(runs: &[SegmentRun], recognition: &[Recognition]) -> Vec<SurfaceTiming> {
    runs.iter()
        .filter_map(|run| {
            let SegmentKind::Surface { surface } = &run.segment.kind else {
                return None;
            };
            let rubbing = haptics::RubbingPhase::Rub.code();
            let stroke_s = run
                .samples
                .iter()
                .find(|s| s.channels[haptics::rubbing_channel::PHASE] == rubbing)?
                .time_s;
            // The tool's path through the play from the stroke's start, by loop time, read from
            // the position the recognizer reads.
            let mut played = recognize::PlayedPath::new();
            let path: Vec<(f64, f64)> = run
                .samples
                .iter()
                .filter_map(|s| {
                    let [x_m, ..] = haptics::acquire::rubbing_signals(&s.state, &s.channels)?;
                    Some((s.time_s, played.push(x_m)))
                })
                .collect();
            let path_at = |t_s: f64| {
                let after = path.partition_point(|(time_s, _)| *time_s <= t_s);
                after.checked_sub(1).map(|i| path[i].1)
            };
            let named: Vec<NamedDecision> = recognition
                .iter()
                .filter(|r| r.object == run.segment.object && r.label.is_some())
                .map(|r| NamedDecision {
                    time_s: r.time_s - stroke_s,
                    travel_m: path_at(r.time_s),
                    right: r.label.as_deref() == Some(surface.as_str()),
                })
                .collect();
            Some(SurfaceTiming {
                object: run.segment.object.clone(),
                truth: surface.clone(),
                stroke_s,
                timing: DecisionTiming::of(&named),
            })
        })
        .collect()
}

/// Trains a `method` recognizer on Nakano's features of every `*.csv` rubbing capture in
/// `dir`, with the method's defaults ([`TrainSettings::new`]: the protocol's windows,
/// [`NakanoWindowing::protocol`]) but for the decision window `window_s` if given, its windows'
/// weight fitted (where the captures allow) over the scene's memory, `memory_s`. Each
/// capture is kept only as its training windows once read, so a folder of many long captures
/// holds one capture's samples at a time.
fn train(
    dir: &std::path::Path,
    method: Method,
    window_s: Option<f64>,
    memory_s: f64,
) -> anyhow::Result<RecognizerFile> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("reading recognizer captures in {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "csv"))
        .collect();
    paths.sort();
    let mut settings = TrainSettings::new(method);
    // The live stream computes Nakano's features only.
    settings.features = FeatureSet::Nakano;
    if let Some(w) = window_s {
        settings.window_s = w;
    }
    // Where the captures allow a fit, the windows' weight is fitted over the memory the scene
    // decides with.
    settings.weight_fit_memory_s = memory_s;
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
