//! Files an identification writes beside its model: the fit along the captures as CSV, and
//! the SVRs in libsvm's model format.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::Context;
use identify::{ModelBody, ModelFile, ScaledSvr};
use svm::write_libsvm_model;

use crate::plots::FitSet;

/// Writes `sets` as CSV: `set`, the model's inputs and output under their capture column
/// names, `predicted_<output>` and `residual_<unit>` (measured − predicted), numbers in full
/// precision so that a reader recomputes the model's outputs exactly.
pub fn write_predictions(path: &Path, model: &ModelFile, sets: &[FitSet]) -> anyhow::Result<()> {
    let output = &model.output.name;
    // Column names end in their unit (`axial_force_n`).
    let unit = output.rsplit_once('_').map_or(output.as_str(), |(_, u)| u);
    capture::write_atomically(path, |w| -> std::io::Result<()> {
        write!(w, "set")?;
        for q in &model.inputs {
            write!(w, ",{}", q.name)?;
        }
        writeln!(w, ",{output},predicted_{output},residual_{unit}")?;
        for set in sets {
            for (r, (&measured, &predicted)) in set.measured.iter().zip(&set.predicted).enumerate() {
                write!(w, "{}", set.label)?;
                for col in &set.inputs {
                    write!(w, ",{}", col[r])?;
                }
                writeln!(w, ",{measured},{predicted},{}", measured - predicted)?;
            }
        }
        Ok(())
    })
    .with_context(|| format!("writing {}", path.display()))
}

/// Writes the SVRs of `body` to `path` in libsvm's format: a two-stage model's two SVRs to
/// `path.slope` and `path.intercept`. The phase-aware needle model holds none: an error.
pub fn write_libsvm_models(body: &ModelBody, path: &Path) -> anyhow::Result<()> {
    match body {
        ModelBody::Single(m) => write_libsvm(m, path)?,
        ModelBody::TwoStage { slope, intercept } => {
            write_libsvm(slope, &with_suffix(path, "slope"))?;
            write_libsvm(intercept, &with_suffix(path, "intercept"))?;
        }
        ModelBody::Phases(_) => anyhow::bail!("--libsvm: the phase-aware needle model holds no SVR"),
    }
    Ok(())
}

fn with_suffix(path: &Path, suffix: &str) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(".");
    s.push(suffix);
    PathBuf::from(s)
}

fn write_libsvm(m: &ScaledSvr, path: &Path) -> anyhow::Result<()> {
    capture::write_atomically(path, |w| {
        write_libsvm_model(&m.svr, w).map_err(|e| std::io::Error::other(e.to_string()))
    })
    .with_context(|| format!("writing {}", path.display()))
}
