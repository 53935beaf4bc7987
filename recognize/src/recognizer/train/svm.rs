//! The SVM's trainer: one C-SVC per behaviour over whole-scratch histograms, or one over
//! rubbing windows, C chosen by cross-validation.

use rayon::prelude::*;

use std::time::{Duration, Instant};

use super::{
    BehaviourHistograms, CV_FOLDS, ChosenC, Method, ScaledWindows, SvmC, TrainJob, TrainSettings, Trainer,
    every_class_in_two_groups, histograms_by_behaviour, scaled_training_windows, sparse_every,
};
use crate::RecognizeError;
#[cfg(doc)]
use crate::features::WindowScaling;
use crate::features::spectral::Histogram;
use crate::features::{FeatureSet, NakanoWindowing};
use crate::fusion::BehaviourData;
use crate::knn::FeatureScaling;
use crate::recognizer::labelled::class_list;
#[cfg(doc)]
use crate::recognizer::trial_groups;
use crate::recognizer::{BehaviourSvc, LabelledCapture, RecognizerBody, RecognizerFile};
use crate::svc::{
    CSearch, FitEvent, Progress, Svc, SvcParams, TrainingVectors, no_progress, repeat_weight,
    select_c_observed, select_c_sparse,
};
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

    fn train(&self, job: TrainJob<'_>) -> Result<RecognizerFile, RecognizeError> {
        let (captures, settings, progress) = (job.captures, job.settings, job.progress);
        match settings.features {
            FeatureSet::Spectral => RecognizerFile::train_svm_observed(
                captures,
                SvcParams {
                    time_budget: settings.time_budget,
                    ..SvcParams::default()
                },
                &settings.c,
                settings.histogram,
                progress,
            ),
            windowed => RecognizerFile::svm_windows(
                captures,
                settings.windowing(captures)?,
                windowed,
                WindowC::Choose(&settings.c),
                settings.histogram,
                settings.time_budget,
                progress,
            ),
        }
    }
}

impl SvmTrainer {
    /// The vectors an SVM over windows (`settings.features` nakano or both) is fitted on, as
    /// [`RecognizerFile::train_svm_windows`] builds and scales them, and its SVC parameters with
    /// C fixed at `c`: for comparing this SVC with another library's on the same problem.
    pub fn window_vectors(
        &self,
        captures: &[LabelledCapture],
        settings: &TrainSettings,
        c: f64,
    ) -> Result<(TrainingVectors, SvcParams), RecognizeError> {
        settings.features.check_columns(captures)?;
        let ScaledWindows {
            classes,
            x,
            y,
            groups,
            ..
        } = scaled_training_windows(
            captures,
            &settings.windowing(captures)?,
            settings.features,
            settings.histogram,
        )?;
        let params = SvcParams {
            c,
            ..window_svc_params(settings.features.dim())
        };
        Ok((
            TrainingVectors {
                classes,
                x,
                y,
                groups,
            },
            params,
        ))
    }
}

/// What an SVM recognizer calls the classifier that `name` (a behaviour, or none) trains, for
/// errors and warnings: the behaviour, or `(no behaviour)` for captures without one (or with
/// an empty one, which would read as "behaviour ``").
fn behaviour_label(name: Option<&str>) -> &str {
    name.filter(|n| !n.trim().is_empty()).unwrap_or("(no behaviour)")
}

/// What an SVM over windows of `features` is called in errors and warnings.
fn windows_label(features: FeatureSet) -> String {
    format!("{features} windows")
}

/// `progress`, with each [`FitEvent::SkippedC`] of the classifier `label` turned into a
/// one-line [`FitEvent::Warning`] that names the classes and the classifier.
fn naming_progress<'a>(
    progress: Progress<'a>,
    classes: &'a [String],
    label: &'a str,
) -> impl Fn(FitEvent) + Sync + 'a {
    move |event| match event {
        FitEvent::SkippedC { c, error } => progress(FitEvent::Warning(skipped_c_warning(
            c,
            error.with_class_names(classes),
            label,
        ))),
        other => progress(other),
    }
}

/// The warning for a candidate C left out of the search of classifier `label`.
fn skipped_c_warning(c: f64, error: RecognizeError, label: &str) -> String {
    format!("C = {c:e} skipped for the SVC of behaviour `{label}`: {error}; searching the other candidates")
}

/// Wraps an SVC's error with the classifier's name (`label`) and the classes' names.
fn svc_error<'a>(label: &'a str, classes: &'a [String]) -> impl Fn(RecognizeError) -> RecognizeError + 'a {
    move |e| RecognizeError::svc(Some(label))(e.with_class_names(classes))
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
        histogram: impl Into<Histogram>,
    ) -> Result<Self, RecognizeError> {
        let histogram = histogram.into();
        Self::train_svm_observed(captures, params, c, histogram, &no_progress)
    }

    /// [`RecognizerFile::train_svm`], telling `progress` of each behaviour's C search and
    /// machines, and warning of each candidate C left out (see [`select_c_observed`]).
    pub fn train_svm_observed(
        captures: &[LabelledCapture],
        params: SvcParams,
        c: &SvmC,
        histogram: impl Into<Histogram>,
        progress: Progress<'_>,
    ) -> Result<Self, RecognizeError> {
        let histogram = histogram.into();
        let classes = class_list(captures);
        let data = histograms_by_behaviour(captures, &classes, histogram)?;
        let fit_one =
            |(name, x, y, groups): &BehaviourHistograms<'_>| -> Result<BehaviourSvc, RecognizeError> {
                let label = behaviour_label(*name);
                let svc_error = svc_error(label, &classes);
                let progress = naming_progress(progress, &classes, label);
                let chosen = c
                    .choose(SvmC::FALLBACK, |grid| {
                        Some(search_c(params, grid, x, y, groups, classes.len(), &progress))
                    })
                    .map_err(&svc_error)?;
                let svc = Svc::fit_observed(
                    SvcParams {
                        c: chosen.c,
                        ..params
                    },
                    x,
                    y,
                    classes.len(),
                    &progress,
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
                histogram,
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
        histogram: impl Into<Histogram>,
    ) -> Result<Self, RecognizeError> {
        let histogram = histogram.into();
        Self::train_svm_windows_observed(captures, windowing, features, c, histogram, &no_progress)
    }

    /// [`RecognizerFile::train_svm_windows`], telling `progress` of the C search and the
    /// machines, and warning of each candidate C left out (see [`select_c_observed`]).
    pub fn train_svm_windows_observed(
        captures: &[LabelledCapture],
        windowing: NakanoWindowing,
        features: FeatureSet,
        c: &SvmC,
        histogram: impl Into<Histogram>,
        progress: Progress<'_>,
    ) -> Result<Self, RecognizeError> {
        let histogram = histogram.into();
        Self::svm_windows(
            captures,
            windowing,
            features,
            WindowC::Choose(c),
            histogram,
            None,
            progress,
        )
    }

    /// The SVM over windows of this recognizer's settings, refitted on `captures` with its own
    /// C and no search for one, and the Platt sigmoids of `probabilities` (the recognizer's
    /// own SVC, whose sigmoids were cross-validated on all its training windows; fitting them
    /// again cost five more fits a pair in each of twenty refits): a fold's model in
    /// [`RecognizerFile::fit_posterior_weight`]. The refit is over windows [`SPARSE_HOP_S`](super::SPARSE_HOP_S)
    /// apart, at the C that weighs their hinge loss as all the windows weigh it at the
    /// recognizer's C, so that its decision values are on the scale the sigmoids were fitted
    /// to. `None` inside when the refit's pairs are not the recognizer's.
    pub(crate) fn refit_svm_windows(
        captures: &[LabelledCapture],
        windowing: NakanoWindowing,
        features: FeatureSet,
        probabilities: &Svc,
        histogram: Histogram,
    ) -> Result<Option<Self>, RecognizeError> {
        let mut model = Self::svm_windows(
            captures,
            windowing,
            features,
            WindowC::Refit(probabilities.params().c),
            histogram,
            None,
            &no_progress,
        )?;
        if let RecognizerBody::SvmWindows { svc, .. } = &mut model.body {
            match svc.clone().with_sigmoids_of(probabilities) {
                Some(with) => *svc = with,
                None => return Ok(None),
            }
        }
        Ok(Some(model))
    }

    /// [`RecognizerFile::train_svm_windows_observed`], with its C come by as `c` says and its
    /// solves within `time_budget` ([`SvcParams::time_budget`]).
    ///
    /// C is cross-validated on windows [`SPARSE_HOP_S`](super::SPARSE_HOP_S) apart, each candidate fitted at C
    /// times all the windows over those: duplicating every vector k times weighs the hinge
    /// loss as multiplying C by k does, so windows that nearly repeat their neighbours are
    /// stood for by fewer at a larger C, and the C chosen is the one for all the windows.
    fn svm_windows(
        captures: &[LabelledCapture],
        windowing: NakanoWindowing,
        features: FeatureSet,
        c: WindowC<'_>,
        histogram: Histogram,
        time_budget: Option<(Instant, Duration)>,
        progress: Progress<'_>,
    ) -> Result<Self, RecognizeError> {
        let windows = scaled_training_windows(captures, &windowing, features, histogram)?;
        let (x, y, groups) = (&windows.x, &windows.y, &windows.groups);
        let params = SvcParams {
            time_budget,
            ..window_svc_params(features.dim())
        };
        let label = windows_label(features);
        // The recognizer takes `classes`; errors and warnings borrow their names meanwhile.
        let names = windows.classes.clone();
        let svc_error = svc_error(&label, &names);
        let progress = naming_progress(progress, &names, &label);
        let sparse = windows.sparse(
            sparse_every(windowing.hop_samples as f64 / windowing.rate_hz),
            names.len(),
        );
        let chosen = match c {
            WindowC::Choose(c) => c
                .choose(WINDOW_SVM_FALLBACK_C, |grid| {
                    every_class_in_two_groups(y, groups).then(|| {
                        let data = BehaviourData {
                            features: x,
                            labels: y,
                            groups,
                        };
                        select_c_sparse(params, grid, &data, &sparse, names.len(), CV_FOLDS, &progress)
                    })
                })
                .map_err(&svc_error)?,
            WindowC::Refit(c) => ChosenC { c, search: None },
        };
        let svc = match c {
            WindowC::Refit(c) => {
                let (sparse_x, sparse_y): (Vec<&[f64]>, Vec<usize>) = x
                    .iter()
                    .zip(y)
                    .zip(&sparse)
                    .filter(|(_, kept)| **kept)
                    .map(|((x, &y), _)| (x.as_slice(), y))
                    .unzip();
                Svc::fit_observed(
                    SvcParams {
                        c: c * repeat_weight(x.len(), sparse_x.len()),
                        probability: false,
                        ..params
                    },
                    &sparse_x,
                    &sparse_y,
                    names.len(),
                    &progress,
                )
            }
            WindowC::Choose(_) => Svc::fit_observed(
                SvcParams {
                    c: chosen.c,
                    probability: true,
                    ..params
                },
                x,
                y,
                names.len(),
                &progress,
            ),
        }
        .map_err(&svc_error)?;
        let n_vectors = x.len();
        Ok(Self::assemble(
            windows.classes,
            features.feature_names(),
            RecognizerBody::SvmWindows {
                features,
                windowing,
                histogram,
                scaling: windows.scaling,
                svc,
                c_search: chosen.search,
            },
            captures,
            n_vectors,
        ))
    }
}

/// How [`RecognizerFile`]'s SVM over windows comes by its C.
#[derive(Clone, Copy)]
enum WindowC<'a> {
    /// As the settings say: the best of the candidates under cross-validation by recording
    /// where the captures allow one (even a single C given is cross-validated, as the file
    /// keeps that accuracy for the fusion's reliability weighting).
    Choose(&'a SvmC),
    /// This C, chosen already, and no sigmoids: a fold's refit needs no cross-validation of
    /// its own and takes the recognizer's sigmoids. Fitted on windows [`SPARSE_HOP_S`](super::SPARSE_HOP_S) apart.
    Refit(f64),
}

/// The C of `grid` that classifies `x` best under cross-validation over [`CV_FOLDS`] folds
/// that keep each group of `groups` whole ([`select_c_observed`]): the one C search both of the
/// SVM's trainers (per behaviour, over windows) make.
fn search_c<V: AsRef<[f64]>>(
    params: SvcParams,
    grid: &[f64],
    x: &[V],
    y: &[usize],
    groups: &[u64],
    classes: usize,
    progress: Progress<'_>,
) -> Result<CSearch, RecognizeError> {
    let data = BehaviourData {
        features: x,
        labels: y,
        groups,
    };
    select_c_observed(params, grid, &data, classes, CV_FOLDS, progress)
}

#[cfg(test)]
mod tests {
    use super::super::{sparse_every, train};
    use super::*;
    use crate::SolverError;
    use crate::recognizer::tests::{short_windows, with_tones};

    #[test]
    fn errors_and_warnings_name_the_classes_and_the_behaviour() {
        let classes: Vec<String> = ["felt", "sandpaper_80", "styrol_rough"]
            .map(String::from)
            .to_vec();
        let failed = |c| {
            RecognizeError::Solver(SolverError::NotConverged {
                iterations: 10_000_000,
                c,
                first: 1,
                second: 2,
                violation: 0.25,
                stop: 1e-3,
            })
        };
        let e = svc_error("lateral scratch", &classes)(failed(1e5));
        assert_eq!(
            e.chain(),
            "SVC of behaviour `lateral scratch`: SMO did not converge in 10000000 iterations at C = 1e5 \
             (classes `sandpaper_80` and `styrol_rough`): its largest KKT violation was 2.500e-1, over \
             its stop 1.0e-3"
        );
        // Every candidate failed: each listed, by class name.
        let label = windows_label(FeatureSet::Nakano);
        let e = svc_error(&label, &classes)(RecognizeError::Solver(SolverError::EveryCFailed {
            failures: vec![(1e4, failed(1e4)), (1e5, failed(1e5))],
        }));
        let text = e.chain();
        assert!(
            text.starts_with("SVC of behaviour `nakano windows`: every candidate C failed: C = 1e4: ")
                && text.contains("C = 1e5: SMO did not converge")
                && !text.contains("classes 1, 2")
                && text.matches("`sandpaper_80` and `styrol_rough`").count() == 2,
            "{text}"
        );
        // Captures without a behaviour still name their classifier.
        assert_eq!(behaviour_label(None), "(no behaviour)");
        assert_eq!(behaviour_label(Some("")), "(no behaviour)");
        assert_eq!(behaviour_label(Some("poke")), "poke");
        let e = svc_error(behaviour_label(None), &classes)(failed(1.0));
        assert!(
            e.chain().starts_with("SVC of behaviour `(no behaviour)`: "),
            "{}",
            e.chain()
        );

        // A skipped candidate reaches the caller as one warning line in the recognizer's terms.
        let lines = std::sync::Mutex::new(Vec::new());
        let sink = |e: FitEvent| {
            if let FitEvent::Warning(line) = e {
                lines.lock().expect("lines").push(line);
            }
        };
        {
            let progress = naming_progress(&sink, &classes, "poke");
            progress(FitEvent::SkippedC {
                c: 1e5,
                error: failed(1e5),
            });
            progress(FitEvent::Advance);
        }
        let lines = lines.into_inner().expect("lines");
        assert_eq!(
            lines,
            [
                "C = 1e5 skipped for the SVC of behaviour `poke`: SMO did not converge in 10000000 \
                 iterations at C = 1e5 (classes `sandpaper_80` and `styrol_rough`): its largest KKT \
                 violation was 2.500e-1, over its stop 1.0e-3; searching the other candidates"
            ]
        );
    }

    /// The windows that stand for all of a recording's are every k-th of each capture, from its
    /// first; where one class would be left without any, all of them.
    #[test]
    fn sparse_windows_are_every_kth_of_each_capture_and_keep_every_class() {
        assert_eq!(sparse_every(0.1), 5);
        assert_eq!(sparse_every(0.25), 2);
        assert_eq!(sparse_every(0.5), 1);
        assert_eq!(sparse_every(2.0), 1);
        let captures = with_tones(0..2, 3.0);
        let settings = short_windows(Method::Svm, FeatureSet::Vibration);
        let windowing = settings.windowing(&captures).expect("windowing");
        let w = scaled_training_windows(&captures, &windowing, FeatureSet::Vibration, Histogram::default())
            .expect("windows");
        let kept = w.sparse(5, 3);
        let count = kept.iter().filter(|&&k| k).count();
        assert!(
            count * 4 < w.x.len() && count * 6 > w.x.len(),
            "{count} of {}",
            w.x.len()
        );
        for (i, &k) in kept.iter().enumerate() {
            assert_eq!(k, w.place[i].is_multiple_of(5));
        }
        // Each capture's places run 0, 1, 2, …: its first window is kept.
        assert_eq!(w.place.iter().filter(|&&p| p == 0).count(), captures.len());
        for pair in w.place.windows(2) {
            assert!(pair[1] == pair[0] + 1 || pair[1] == 0, "{pair:?}");
        }
        // A fourth class no window belongs to cannot be kept: every window is.
        assert!(w.sparse(5, 4).iter().all(|&k| k));
    }

    /// The SVM over windows cross-validates C on windows 0.5 s apart, each candidate at C times
    /// the windows it stands for, and reports the grid in the Cs of the full fit; the fit itself
    /// is at the C chosen, on every window.
    #[test]
    fn the_svms_c_is_searched_on_sparse_windows_at_the_weight_they_stand_for() {
        let captures = with_tones(0..3, 3.0);
        let settings = TrainSettings {
            c: SvmC::Auto(vec![1.0, 10.0, 100.0]),
            fit_posterior_weight: false,
            ..short_windows(Method::Svm, FeatureSet::Vibration)
        };
        let model = train(&captures, &settings).expect("trains");
        let RecognizerBody::SvmWindows { svc, c_search, .. } = &model.body else {
            panic!("an SVM over windows");
        };
        let search = c_search.as_ref().expect("three trials: searched");
        let weight = search.vector_weight.expect("windows every 0.1 s: sparse");
        assert!(weight > 4.0 && weight <= 5.0, "{weight}");
        let cs: Vec<f64> = search.grid.iter().map(|p| p.c).collect();
        assert_eq!(cs, [1.0, 10.0, 100.0]);
        assert_eq!(svc.params().c, search.chosen_c);
        assert!(svc.params().probability);
        search.check().expect("valid");
        // A stored weight below 1 cannot be.
        let mut bad = search.clone();
        bad.vector_weight = Some(0.5);
        assert_eq!(bad.check().expect_err("bad").0, "vector_weight");
    }

    /// An SVM given a time budget that has run out fails with an error that says so; the search
    /// tells such a candidate from one that cannot be trained.
    #[test]
    fn an_svm_past_its_time_budget_fails_with_the_budget_error() {
        let captures = with_tones(0..3, 3.0);
        let settings = TrainSettings {
            c: SvmC::Unscored(10.0),
            fit_posterior_weight: false,
            time_budget: Some((Instant::now(), Duration::from_nanos(1))),
            ..short_windows(Method::Svm, FeatureSet::Vibration)
        };
        let err = train(&captures, &settings).expect_err("out of time");
        assert!(err.ran_out_of_time(), "{}", err.chain());
        // Unscored: no cross-validation, so no C search is kept.
        let model = train(
            &captures,
            &TrainSettings {
                time_budget: None,
                ..settings.clone()
            },
        )
        .expect("no budget");
        let RecognizerBody::SvmWindows { svc, c_search, .. } = &model.body else {
            panic!("an SVM over windows");
        };
        assert_eq!((svc.params().c, c_search.is_none()), (10.0, true));
        let other = train(
            &captures,
            &TrainSettings {
                window_s: 100.0,
                train_window_s: None,
                time_budget: None,
                ..settings
            },
        )
        .expect_err("no window");
        assert!(!other.ran_out_of_time(), "{}", other.chain());
    }
}
