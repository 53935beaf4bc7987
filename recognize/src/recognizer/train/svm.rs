//! The SVM's trainer: one C-SVC per behaviour over whole-scratch histograms, or one over
//! rubbing windows, C chosen by cross-validation.

use rayon::prelude::*;

use super::{
    BehaviourHistograms, CV_FOLDS, Method, ScaledWindows, SvmC, TrainSettings, Trainer,
    every_class_in_two_groups, histograms_by_behaviour, scaled_training_windows,
};
use crate::RecognizeError;
#[cfg(doc)]
use crate::features::WindowScaling;
use crate::features::spectral::CellScale;
use crate::features::{FeatureSet, NakanoWindowing};
use crate::knn::FeatureScaling;
use crate::recognizer::labelled::class_list;
#[cfg(doc)]
use crate::recognizer::trial_groups;
use crate::recognizer::{BehaviourSvc, LabelledCapture, RecognizerBody, RecognizerFile};
use crate::svc::{CSearch, Svc, SvcParams, select_c};
use svm::Kernel;

/// Trains SVM recognizers with `settings.c`: one SVC per behaviour over whole-scratch
/// histograms ([`RecognizerFile::train_svm`], [`SvcParams::default`]), or one over rubbing
/// windows ([`RecognizerFile::train_svm_windows`], [`window_svc_params`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct SvmTrainer;

impl Trainer for SvmTrainer {
    fn method(&self) -> Method {
        Method::Svm
    }

    fn train(
        &self,
        captures: &[LabelledCapture],
        settings: &TrainSettings,
    ) -> Result<RecognizerFile, RecognizeError> {
        match settings.features {
            FeatureSet::Spectral => {
                RecognizerFile::train_svm(captures, SvcParams::default(), &settings.c, settings.cell_scale)
            }
            windowed => RecognizerFile::train_svm_windows(
                captures,
                settings.windowing(captures)?,
                windowed,
                &settings.c,
                settings.cell_scale,
            ),
        }
    }
}

/// The SVC of a k-NN/SVM over windows: degree-2 polynomial `(γ a·b + 1)²` with γ = 1/dim (1/5
/// for Nakano's features, 1/130 for both), as the scratch SVM's γ = 1/125 for its 125 cells: the
/// scaled features are O(1) each, so `γ a·b` is O(1) too. No scaling inside (the windows arrive
/// scaled by [`WindowScaling`]).
pub fn window_svc_params(dim: usize) -> SvcParams {
    SvcParams {
        kernel: Kernel::Polynomial {
            gamma: 1.0 / dim.max(1) as f64,
            coef0: 1.0,
            degree: 2,
        },
        scaling: FeatureScaling::None,
        ..SvcParams::default()
    }
}

/// C of an SVM over windows whose training captures cannot be cross-validated (each surface
/// needs captures in at least two runs or trials, e.g. not when trained on run 0 alone): 10, a
/// soft margin. Windows of different surfaces overlap (a 1 s window of one surface can look like
/// another's), so the hard-margin machine of the scratch SVM's fallback (10⁴) would bend its
/// boundaries around single windows; with every feature in units of its within-surface spread,
/// a moderate C keeps the margin wide. `--c` overrides it.
pub const WINDOW_SVM_FALLBACK_C: f64 = 10.0;

impl RecognizerFile {
    /// Trains one SVC per behaviour on one histogram per capture, with `params` but the C of
    /// `c`; each behaviour's C and reliability weight come from cross-validation by trial on
    /// its training captures (see [`trial_groups`]).
    ///
    /// C is chosen per behaviour: each behaviour has its own classifier over its own
    /// histograms (a fast lateral scratch and a slow poke differ in level and spread), and
    /// its reliability weight is the same cross-validation's accuracy at the chosen C. A
    /// behaviour with fewer than two trials cannot be cross-validated: it gets
    /// [`SvmC::FALLBACK`] (or the fixed C) and no weight.
    pub fn train_svm(
        captures: &[LabelledCapture],
        params: SvcParams,
        c: &SvmC,
        cell_scale: CellScale,
    ) -> Result<Self, RecognizeError> {
        let classes = class_list(captures);
        let data = histograms_by_behaviour(captures, &classes, cell_scale)?;
        let fit_one =
            |(name, x, y, groups): &BehaviourHistograms<'_>| -> Result<BehaviourSvc, RecognizeError> {
                let svc_error = RecognizeError::svc(*name);
                let chosen = c
                    .choose(SvmC::FALLBACK, |grid| {
                        Some(select_c(params, grid, x, y, groups, classes.len(), CV_FOLDS))
                    })
                    .map_err(&svc_error)?;
                let svc = Svc::fit(
                    SvcParams {
                        c: chosen.c,
                        ..params
                    },
                    x,
                    y,
                    classes.len(),
                )
                .map_err(&svc_error)?;
                Ok(BehaviourSvc {
                    behaviour: name.map(str::to_owned),
                    svc,
                    reliability: chosen.search.as_ref().and_then(CSearch::accuracy),
                    c_search: chosen.search,
                })
            };
        // One behaviour per task; collected in the behaviours' order.
        let behaviours: Vec<BehaviourSvc> = data.par_iter().map(fit_one).collect::<Result<_, _>>()?;
        Self::assemble_scratches(
            classes,
            behaviours.len(),
            RecognizerBody::Svm {
                cell_scale,
                behaviours,
            },
            captures,
        )
    }

    /// C-SVC over rubbing windows (see [`RecognizerFile::train_knn_windows`] and
    /// [`window_svc_params`]). With [`SvmC::Auto`], C is chosen by cross-validation grouped by
    /// run (or trial; the windows of one capture never straddle folds) when every surface has
    /// captures in at least two runs; otherwise C is [`WINDOW_SVM_FALLBACK_C`].
    pub fn train_svm_windows(
        captures: &[LabelledCapture],
        windowing: NakanoWindowing,
        features: FeatureSet,
        c: &SvmC,
        cell_scale: CellScale,
    ) -> Result<Self, RecognizeError> {
        let ScaledWindows {
            classes,
            scaling,
            x,
            y,
            groups,
        } = scaled_training_windows(captures, &windowing, features, cell_scale)?;
        let params = window_svc_params(features.dim());
        let svc_error = RecognizeError::svc(None);
        let chosen = c
            .choose(WINDOW_SVM_FALLBACK_C, |grid| {
                every_class_in_two_groups(&y, &groups)
                    .then(|| select_c(params, grid, &x, &y, &groups, classes.len(), CV_FOLDS))
            })
            .map_err(&svc_error)?;
        let svc = Svc::fit(
            SvcParams {
                c: chosen.c,
                ..params
            },
            &x,
            &y,
            classes.len(),
        )
        .map_err(&svc_error)?;
        Ok(Self::assemble(
            classes,
            features.feature_names(),
            RecognizerBody::SvmWindows {
                features,
                windowing,
                cell_scale,
                scaling,
                svc,
                c_search: chosen.search,
            },
            captures,
            x.len(),
        ))
    }
}
