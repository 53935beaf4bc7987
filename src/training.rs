//! Training a recognizer as the command line asks: with a progress bar, and with warnings
//! where the settings do not suit the captures.

use indicatif::{ProgressBar, ProgressStyle};
use recognize::FitEvent;
use recognize::{FeatureSet, LabelledCapture, RecognizerFile, TrainSettings};

/// Trains on `captures` as `settings` say, with a progress bar on stderr over the trainer's
/// long steps (an SVM's C search, machines and probability sigmoids; shown only on a terminal)
/// and its warnings (a candidate C left out) printed above the bar as they happen.
pub fn train_with_progress(
    settings: &TrainSettings,
    captures: &[LabelledCapture],
) -> anyhow::Result<RecognizerFile> {
    Ok(with_fit_progress(|progress| {
        settings.train_observed(captures, progress)
    })?)
}

/// Runs `work` with a progress bar on stderr that counts the units of the steps it reports
/// (shown only on a terminal), and prints its warnings above the bar as they happen.
pub fn with_fit_progress<T>(work: impl FnOnce(recognize::Progress<'_>) -> T) -> T {
    let bar = ProgressBar::new(0).with_style(
        ProgressStyle::with_template("{msg} {bar:30} {pos}/{len} {elapsed} (eta {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let progress = |event: FitEvent| match event {
        // Steps of behaviours trained in parallel share the bar: their units add up.
        FitEvent::Step { what, total } => {
            bar.inc_length(total as u64);
            bar.set_message(what);
        }
        FitEvent::Advance => bar.inc(1),
        FitEvent::SkippedC { c, error } => {
            bar.suspend(|| eprintln!("warning: C = {c:e} skipped: {error}"));
        }
        FitEvent::Warning(line) => bar.suspend(|| eprintln!("warning: {line}")),
    };
    let done = work(&progress);
    bar.finish_and_clear();
    done
}

/// What is doubtful in `settings` for captures shaped like `first`, one line each.
pub fn settings_warnings(settings: &TrainSettings, first: &LabelledCapture) -> Vec<String> {
    let mut warnings: Vec<String> = window_warning(settings).into_iter().collect();
    if settings.friction_over_travel
        && first.capture.has_column(recognize::nakano::FRICTION_COLUMN)
        && first
            .capture
            .metadata()
            .get(recognize::nakano::OBSERVER_CUTOFF_KEY)
            .is_none()
    {
        warnings.push(format!(
            "warning: {} has no `{}`: its friction is taken as measured by a force sensor and only low-passed over travel (add the key if an observer estimated it)",
            first.reference.path.display(),
            recognize::nakano::OBSERVER_CUTOFF_KEY
        ));
    }
    warnings
}

/// The warning for training windows set to another length than the decision windows: the
/// vectors decided on then differ from those trained on (a roughness variance over 1 s is not
/// one over 3 s), which can cost much accuracy. `None` when they agree, when the training
/// window was left to its default, or when the features are not windowed.
fn window_warning(settings: &TrainSettings) -> Option<String> {
    let train_s = settings.train_window_s?;
    let windowed = !matches!(settings.features, FeatureSet::Spectral);
    (windowed && (train_s - settings.window_s).abs() > 1e-9).then(|| {
        format!(
            "warning: training on {train_s} s windows but deciding on {} s ones (--train-window-s, --window-s): vectors of different lengths may not compare",
            settings.window_s
        )
    })
}
