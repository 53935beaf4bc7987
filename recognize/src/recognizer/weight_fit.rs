//! The posterior's window weight, fitted on recordings held out of training.
//!
//! Anytime decisions raise each window's probabilities to a weight before multiplying them into
//! the posterior. `hop / window` counts every sample once, which is right only if windows that
//! do not overlap are independent evidence and the classifier's probabilities are calibrated
//! one window at a time. Neither is known on a rig we have not seen: a surface's texture
//! repeats, a hand sways slowly, and the same stretch of surface read twice says the same
//! thing twice. The exponent that calibrates the posterior depends on the rig, the surfaces and
//! the classifier, so it is measured: when every surface has captures in at least two
//! recordings (runs or trials), training refits the recognizer with each recording held out in
//! turn (at most [`WEIGHT_FIT_FOLDS`] folds, so that a fold's recognizer is nearly the final
//! one), runs the posterior over the held-out strokes at every weight of a grid around
//! `hop / window`, and keeps the weight with the least Brier score. The Brier score is a proper
//! scoring rule, least for a calibrated posterior; this is temperature scaling (Guo et al.,
//! ICML 2017) of the whole posterior rather than of one window. Without two recordings of every
//! surface there is nothing to hold out, and the weight stays `hop / window`.

use super::file::{RecognizerBody, RecognizerFile};
use super::labelled::class_index;
use super::posterior_weight::{
    HeldOutDecisions, PosteriorWeight, WEIGHT_FIT_FOLDS, WEIGHT_OCTAVES, WEIGHT_STEPS_PER_OCTAVE,
};
use super::sequential_eval::{SequentialRow, Stroke};
use super::train::every_class_in_two_groups;
use super::{LabelledCapture, recording_groups};
use crate::RecognizeError;
use crate::SettingError;
use crate::folds::group_folds;
#[cfg(doc)]
use crate::sequential::DEFAULT_MEMORY_S;
use crate::sequential::SequentialParamsBuilder;
use crate::svc::{FitEvent, Progress};
use rayon::prelude::*;

impl RecognizerFile {
    /// The weight of a window in this recognizer's anytime decisions, fitted on `captures`,
    /// the ones it was trained on: the weight of the grid ([`WEIGHT_OCTAVES`]) whose posterior
    /// (otherwise as [`RecognizerFile::sequential_params`] sets it, keeping `memory_s` of
    /// evidence: [`DEFAULT_MEMORY_S`] unless the recognizer is meant for another), run over
    /// each recording held out of a refit ([`WEIGHT_FIT_FOLDS`] at most), has the least Brier
    /// score; ties go to the smaller weight. `None` for a recognizer without window
    /// probabilities, or captures that cannot be cross-validated: a surface in fewer than two
    /// recordings, or a fold without which the refit fails or cannot stand for this recognizer
    /// (a warning to `progress` says why). `progress` is told of each fold's refit.
    pub fn fit_posterior_weight(
        &self,
        captures: &[LabelledCapture],
        memory_s: f64,
        progress: Progress<'_>,
    ) -> Result<Option<PosteriorWeight>, RecognizeError> {
        if !(memory_s.is_finite() && memory_s > 0.0) {
            return Err(RecognizeError::Setting(SettingError::Parameter {
                of: "setting",
                name: "the memory the posterior's weight is fitted at, s",
                value: memory_s,
                reason: "must be positive and finite",
            }));
        }
        let (Some(params), Some(hop_weight)) = (self.sequential_params(memory_s), self.hop_weight()) else {
            return Ok(None);
        };
        let base = params.weight(hop_weight);
        let groups = recording_groups(captures);
        let labels = captures
            .iter()
            .map(|c| class_index(&self.classes, c))
            .collect::<Result<Vec<_>, _>>()?;
        if !every_class_in_two_groups(&labels, &groups) {
            return Ok(None);
        }
        let (fold, folds) = group_folds(&groups, WEIGHT_FIT_FOLDS)?;
        progress(FitEvent::Step {
            what: "fitting the posterior's weight on held-out recordings",
            total: folds,
        });
        // The folds' refits on all cores (each also uses them where it can).
        let refits: Vec<Result<Result<Vec<Stroke>, String>, RecognizeError>> = (0..folds)
            .into_par_iter()
            .map(|f| {
                let kept: Vec<LabelledCapture> = captures
                    .iter()
                    .zip(&fold)
                    .filter(|(_, g)| **g != f)
                    .map(|(c, _)| c.clone())
                    .collect();
                let model = match self.refit(&kept) {
                    Ok(model) => model,
                    Err(why) => return Ok(Err(why)),
                };
                let sources = [(&model, model.windowing_with_probabilities()?, 1.0)];
                let mut short_of_travel = 0;
                // A held-out capture none of whose windows could be read (each slid too fast
                // for its bands) says nothing of the weight, as training left it out.
                let strokes = captures
                    .iter()
                    .zip(&fold)
                    .filter(|(_, g)| **g == f)
                    .filter_map(|(c, _)| match self.stroke(&sources, c, &mut short_of_travel) {
                        Err(e) if every_window_too_fast(&e) => None,
                        other => Some(other),
                    })
                    .collect::<Result<Vec<_>, _>>()?;
                progress(FitEvent::Advance);
                Ok(Ok(strokes))
            })
            .collect();
        let mut strokes = Vec::with_capacity(captures.len());
        for (f, refit) in refits.into_iter().enumerate() {
            match refit? {
                Ok(fold_strokes) => strokes.extend(fold_strokes),
                Err(why) => {
                    progress(FitEvent::Warning(format!(
                        "the posterior's weight stays hop / window: the refit without fold {} of {folds} \
                         cannot stand for the recognizer: {why}",
                        f + 1
                    )));
                    return Ok(None);
                }
            }
        }
        let windows = strokes.iter().map(|s| s.windows.len()).sum();
        if windows == 0 {
            return Ok(None);
        }
        let (weight, row, hop_brier) = self.least_brier_weight(&strokes, base, hop_weight)?;
        Ok(Some(PosteriorWeight {
            weight,
            hop_weight,
            folds,
            windows,
            brier: row.calibration.brier,
            hop_brier,
            memory_s,
            held_out: held_out_decisions(&row),
        }))
    }

    /// The same recognizer trained on `captures` with this one's settings (an SVM's C as
    /// chosen and its sigmoids, a k-NN's vote calibration; no search), or why its
    /// probabilities would not stand for this recognizer's: the
    /// refit failed, lost a surface, or lost (or gained) a k-NN's vote calibration.
    fn refit(&self, captures: &[LabelledCapture]) -> Result<RecognizerFile, String> {
        let chain = |e: RecognizeError| e.chain();
        let model = match &self.body {
            RecognizerBody::SvmWindows {
                features,
                windowing,
                histogram,
                svc,
                ..
            } => Self::refit_svm_windows(captures, *windowing, *features, svc, *histogram)
                .map_err(chain)?
                .ok_or("its machines' pairs are not the recognizer's")?,
            RecognizerBody::KnnWindows {
                features,
                windowing,
                histogram,
                knn,
                calibration: Some(calibration),
                ..
            } => Self::refit_knn_windows(captures, *windowing, *features, knn.k(), *histogram, *calibration)
                .map_err(chain)?,
            RecognizerBody::KnnWindows {
                features,
                windowing,
                histogram,
                knn,
                calibration: None,
                ..
            } => Self::train_knn_windows(captures, *windowing, *features, knn.k(), *histogram)
                .map_err(chain)?,
            _ => return Err(format!("a {} gives no window probabilities", self.method())),
        };
        let calibrated = |m: &RecognizerFile| {
            matches!(
                m.body,
                RecognizerBody::KnnWindows {
                    calibration: Some(_),
                    ..
                }
            )
        };
        if model.classes != self.classes {
            return Err(format!(
                "its captures hold {} of the {} surfaces",
                model.classes.len(),
                self.classes.len()
            ));
        }
        if calibrated(&model) != calibrated(self) {
            return Err("its k-NN's votes could not be calibrated as this one's were".into());
        }
        Ok(model)
    }

    /// The weight of the grid ([`WEIGHT_OCTAVES`] around `hop_weight`) at which the posterior
    /// over `strokes`, otherwise as `base` sets it, has the least mean Brier score (ties to
    /// the smaller weight): `(weight, the decisions at it, the Brier score at hop_weight)`.
    pub(super) fn least_brier_weight(
        &self,
        strokes: &[Stroke],
        base: SequentialParamsBuilder,
        hop_weight: f64,
    ) -> Result<(f64, SequentialRow, f64), RecognizeError> {
        let row_at = |w: f64| self.sequential_row(strokes, base.weight(w).build()?);
        let mut best = (hop_weight, row_at(hop_weight)?);
        let hop_brier = best.1.calibration.brier;
        let (low, high) = WEIGHT_OCTAVES;
        for step in low * WEIGHT_STEPS_PER_OCTAVE..=high * WEIGHT_STEPS_PER_OCTAVE {
            if step == 0 {
                continue;
            }
            let w = (hop_weight * 2f64.powf(f64::from(step) / f64::from(WEIGHT_STEPS_PER_OCTAVE))).min(1.0);
            let row = row_at(w)?;
            let (b, brier) = (row.calibration.brier, best.1.calibration.brier);
            if b < brier || (b == brier && w < best.0) {
                best = (w, row);
            }
        }
        Ok((best.0, best.1, hop_brier))
    }
}

/// Whether `e` says that none of a capture's windows could be read, every one having slid too
/// fast for its bands ([`crate::features::WindowVectors::decidable`]).
fn every_window_too_fast(e: &RecognizeError) -> bool {
    matches!(
        e,
        RecognizeError::Features { source, .. }
            if matches!(**source, RecognizeError::Setting(SettingError::TooFastForBands { .. }))
    )
}

/// What the anytime decisions of `row`, over the strokes held out of the weight's fit, needed;
/// `None` when no stroke of one surface ends named right.
fn held_out_decisions(row: &SequentialRow) -> Option<HeldOutDecisions> {
    // The slowest surface is the one that takes the longest path where paths are known: that
    // is what stays about the same at another speed.
    let slowest = row
        .worst_surface_travel
        .as_ref()
        .or(row.worst_surface.as_ref())
        .and_then(|(name, _)| row.surfaces.iter().find(|w| w.surface == *name))?;
    Some(HeldOutDecisions {
        threshold: row.threshold,
        strokes: row.surfaces.iter().map(|w| w.strokes).sum(),
        not_stable: row.not_stable,
        named_right: row.accuracy().unwrap_or(0.0),
        stable_right_s: row.time_to_stable_correct_s?,
        stable_right_m: row.travel_to_stable_correct_m,
        slowest_surface: slowest.surface.clone(),
        slowest_surface_s: slowest.stable_right_s?,
        slowest_surface_m: slowest.stable_right_m,
    })
}
