//! What becomes of an insertion attempt at a scene with a goal: its score, its force against
//! depth drawn over the expert's, and its row in the trainees' history.

use std::ops::Range;
use std::path::Path;

use haptics::admittance_channel as c;

use crate::history::{History, HistoryError};
use crate::models::ResolvedModel;
use crate::plots::{ForceDepth, PlotError};
use crate::scene::Scene;
use crate::session::analysis;
use crate::session::score::Score;
use crate::session::strokes::{score_stroke, strokes};
use crate::session::{Segment, SegmentKind, SegmentRun};

/// A goal names the layers of a phase model one by one: as many names as the model renders
/// membranes, or a score would call a membrane by another's name.
pub fn check_goal_layers(scene: &Scene, segments: &[Segment]) -> anyhow::Result<()> {
    let Some(goal) = scene.task.goal() else {
        return Ok(());
    };
    for segment in segments {
        if let SegmentKind::Needle { model, .. } = &segment.kind
            && let identify::ModelBody::Phases(phases) = &model.body
            && phases.layers.len() != goal.layers.len()
        {
            anyhow::bail!(
                "{}: `task.goal.layers` names {} layer{} ({}), but the model of `{}` renders {} \
                 membrane{}: name each, shallowest first",
                scene.path.display(),
                goal.layers.len(),
                if goal.layers.len() == 1 { "" } else { "s" },
                goal.layers.join(", "),
                segment.object,
                phases.layers.len(),
                if phases.layers.len() == 1 { "" } else { "s" },
            );
        }
    }
    Ok(())
}

/// One scored stroke of the needle segment.
#[derive(Debug, Clone)]
pub struct Attempt {
    /// Its samples in the needle segment's run.
    pub samples: Range<usize>,
    /// Its score.
    pub score: Score,
}

/// The needle segment's attempts, each stroke into the tissue and out scored against the
/// scene's goal ([`crate::session::strokes`]); none without a goal or a needle segment.
pub fn attempts(scene: &Scene, runs: &[SegmentRun]) -> Vec<Attempt> {
    let (Some(goal), Some(run)) = (scene.task.goal(), needle_run(runs)) else {
        return Vec::new();
    };
    let surface_z_m = analysis::surface_z_m(run);
    strokes(&run.samples, surface_z_m)
        .into_iter()
        .map(|range| Attempt {
            score: score_stroke(
                &run.samples[range.clone()],
                goal,
                surface_z_m,
                scene.device.rate_hz,
            ),
            samples: range,
        })
        .collect()
}

fn needle_run(runs: &[SegmentRun]) -> Option<&SegmentRun> {
    runs.iter()
        .find(|r| matches!(r.segment.kind, SegmentKind::Needle { .. }))
}

/// Draws `path` (`attempt.png`) for the last scored attempt, over `reference`; without one,
/// removes one an earlier session left, since a report folder holds one session.
pub fn write_plot(
    path: &Path,
    runs: &[SegmentRun],
    last: Option<&Attempt>,
    reference: Option<&ForceDepth>,
) -> Result<(), PlotError> {
    let (Some(last), Some(run)) = (last, needle_run(runs)) else {
        let _ = std::fs::remove_file(path);
        return Ok(());
    };
    let surface_z_m = analysis::surface_z_m(run);
    // The approach before it and the air after it belong to no stroke but draw the full motion.
    let from = run.samples[..last.samples.start]
        .iter()
        .rposition(|s| surface_z_m - s.channels[c::VIRTUAL_Z_M] > 0.0)
        .map_or(0, |i| i + 1);
    let samples = &run.samples[from..];
    let attempt = ForceDepth {
        depth_m: samples
            .iter()
            .map(|s| surface_z_m - s.channels[c::VIRTUAL_Z_M])
            .collect(),
        force_n: samples.iter().map(|s| s.channels[c::MODEL_FORCE_Z_N]).collect(),
    };
    crate::plots::write_attempt_plot(path, &attempt, reference, &last.score)
}

/// Who the history stores an attempt under: `named`, else `$USER`, else `trainee`.
pub fn trainee(named: Option<&str>) -> String {
    named
        .map(str::to_owned)
        .or_else(|| std::env::var("USER").ok().filter(|u| !u.is_empty()))
        .unwrap_or_else(|| "trainee".to_owned())
}

/// Adds the attempt to the history at `path` (made when missing); returns its number.
pub fn store(
    path: &Path,
    trainee: &str,
    scene: &Scene,
    resolved: &[ResolvedModel],
    device: &str,
    score: &Score,
) -> Result<i64, HistoryError> {
    History::open_or_create(path)?.add(trainee, &scene.name, &models_sha256(resolved), device, score)
}

/// SHA-256 of the models a session rendered, as stored: attempts on different models are
/// told apart in the history.
fn models_sha256(resolved: &[ResolvedModel]) -> String {
    use sha2::{Digest, Sha256};
    let mut hash = Sha256::new();
    for m in resolved {
        hash.update(m.name.as_bytes());
        hash.update(serde_json::to_vec(&m.model).unwrap_or_default());
    }
    hash.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

/// The force against depth of an insertion capture (an expert's recorded attempt).
pub fn read_reference(path: &Path) -> anyhow::Result<ForceDepth> {
    let capture = capture::Capture::read_file(path, capture::CaptureKind::Insertion)?;
    Ok(ForceDepth {
        depth_m: capture.column(capture::kind::DEPTH_M)?.to_vec(),
        force_n: capture.column(capture::kind::AXIAL_FORCE_N)?.to_vec(),
    })
}
