//! The model `palpus identify` and `palpus bench trade` fit, as the command line names it, and
//! its fit along a capture (what `--predictions`, `--plot` and the trade's peak error read).

use capture::{Capture, CaptureKind};
use clap::ValueEnum;
use identify::{ModelBody, ModelFile, ModelKind};

use crate::plots::FitSet;

#[derive(Debug, Clone, Copy, ValueEnum)]
pub(crate) enum ModelArg {
    Hard,
    Soft,
    Needle,
    /// The phase-aware needle model: layers, puncture thresholds and the force after each.
    NeedlePhases,
}

impl ModelArg {
    /// The model it names.
    pub(crate) fn kind(self) -> ModelKind {
        match self {
            Self::Hard => ModelKind::HardFriction,
            Self::Soft => ModelKind::SoftFriction,
            Self::Needle => ModelKind::NeedlePuncture,
            Self::NeedlePhases => ModelKind::NeedlePhases,
        }
    }

    /// The kind of capture the model is identified from.
    pub(crate) fn capture_kind(self) -> CaptureKind {
        match self {
            Self::Needle | Self::NeedlePhases => CaptureKind::Insertion,
            Self::Hard | Self::Soft => CaptureKind::Rubbing,
        }
    }
}

/// The rows of `capture` the model describes, its inputs as the model reads them, and the
/// model's output at each: every row for the friction models, the rows in tissue (depth > 0)
/// for the needle, as `identify` selects them.
pub(crate) fn fit_set(label: &'static str, capture: &Capture, model: &ModelFile) -> anyhow::Result<FitSet> {
    let column = |name: &str| -> anyhow::Result<Vec<f64>> { Ok(identify::model_column(capture, name)?) };
    let all_inputs = model
        .inputs
        .iter()
        .map(|q| column(&q.name))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let all_measured = column(&model.output.name)?;
    let rows = identify::model_rows(model.kind, capture)?;
    let inputs: Vec<Vec<f64>> = all_inputs
        .iter()
        .map(|col| rows.iter().map(|&i| col[i]).collect())
        .collect();
    let predicted = match &model.body {
        // A model with memory is run along the whole trajectory, as the haptic thread runs it.
        ModelBody::Phases(p) => {
            let steps = p.simulate(&all_inputs[0], &all_inputs[1]);
            rows.iter().map(|&i| steps[i].force_n).collect()
        }
        _ => (0..rows.len())
            .map(|r| {
                let x: Vec<f64> = inputs.iter().map(|col| col[r]).collect();
                model.predict(&x)
            })
            .collect(),
    };
    Ok(FitSet {
        label,
        inputs,
        measured: rows.iter().map(|&i| all_measured[i]).collect(),
        predicted,
    })
}
