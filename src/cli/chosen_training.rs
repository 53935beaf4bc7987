//! Reading the captures of a training whose unnamed defaults are chosen on them
//! ([`recognize::DefaultSearch`]): once keeping every candidate's features, to score them, then
//! again keeping the chosen one's, to train it. Reading twice keeps memory at the features
//! either pass needs; the second read is the one a training without a search does anyway.

use anyhow::Context;
use recognize::{
    CellScale, DECISION_WINDOW_S, DefaultChoice, DefaultSearch, FeatureNeeds, FeatureSet, HistogramBand,
    LabelledCapture, Named, RecognizeError, TrainSettings,
};

use super::train_args::{BandsArg, CellsArg, Method, TrainOptions};
use crate::tables::recognition::print_default_choice;
use crate::training::with_fit_progress;

/// Reads captures, keeping of each what the `needs` it is given at the first capture lists.
pub(crate) type Reader<'a> = dyn Fn(
        &mut dyn FnMut(&LabelledCapture) -> anyhow::Result<FeatureNeeds>,
    ) -> anyhow::Result<Vec<LabelledCapture>>
    + 'a;

/// The captures, read for the settings chosen, and how they were chosen.
pub(crate) struct ChosenTraining {
    /// What to train.
    pub settings: TrainSettings,
    /// The captures, keeping what `needs` lists for `settings`.
    pub captures: Vec<LabelledCapture>,
    /// The table the settings were chosen from; `None` when nothing was left to choose.
    pub choice: Option<DefaultChoice>,
}

/// Reads the captures with `read` and settles what `options` leave unnamed: by the search
/// when there is anything to choose (printing its table), else the documented defaults.
/// `adjust` is applied to the settings before anything is read (e.g. no posterior weight);
/// `needs` says what the chosen settings read from captures at a rate.
pub(crate) fn read_and_choose(
    options: &TrainOptions,
    method: Method,
    read: &Reader<'_>,
    adjust: &dyn Fn(TrainSettings) -> TrainSettings,
    needs: &dyn Fn(&TrainSettings, f64) -> Result<FeatureNeeds, RecognizeError>,
) -> anyhow::Result<ChosenTraining> {
    let mut base = None;
    let mut search = None;
    let mut rate_hz = 0.0;
    let captures = read(&mut |first| {
        let settings = base.insert(adjust(options.settings_quietly(method, first)));
        rate_hz = first.capture.metadata().rate_hz();
        Ok(match options.search(settings, first) {
            Some(s) => search.insert(s).needs(rate_hz),
            None => {
                options.say_default_features(settings, first);
                needs(settings, rate_hz)?
            }
        })
    })?;
    let base = base.context("no captures to train on")?;
    let Some(search) = search else {
        return Ok(ChosenTraining {
            settings: base,
            captures,
            choice: None,
        });
    };
    let choice = with_fit_progress(|progress| search.run(&captures, progress));
    drop(captures);
    print_default_choice(&choice);
    let settings = choice.chosen().settings(&base);
    let wanted = needs(&settings, rate_hz)?;
    let captures = read(&mut |_| Ok(wanted.clone()))?;
    Ok(ChosenTraining {
        settings,
        captures,
        choice: Some(choice),
    })
}

impl TrainOptions {
    /// Says on stderr when the features of `settings` were taken by default and are not the
    /// method's own.
    pub(crate) fn say_default_features(&self, settings: &TrainSettings, first: &LabelledCapture) {
        if self.features.is_none() && settings.features != settings.method.default_features() {
            eprintln!(
                "{} over {} features: {} has the columns of both sets (--features picks one)",
                settings.method.name(),
                settings.features,
                first.reference.path.display()
            );
        }
    }

    /// What the user named of what `train` would otherwise choose.
    pub(crate) fn named(&self) -> Named {
        Named {
            features: self.features.map(FeatureSet::from),
            cells: self.cells.map(|c| match c {
                CellsArg::Mean => CellScale::Mean,
                CellsArg::UnitSum => CellScale::UnitSum,
            }),
            band: self.bands.map(|b| match b {
                BandsArg::Paper => HistogramBand::Paper,
                BandsArg::Nyquist => HistogramBand::Nyquist,
            }),
            // A training window set apart ties the decision window to its default.
            window_s: self.window_s.or(self.train_window_s.map(|_| DECISION_WINDOW_S)),
        }
    }

    /// The search for what the user left unnamed, around `base` (the settings with the
    /// documented defaults), on captures shaped like `first`; `None` when there is nothing to
    /// choose or --search-budget-s is 0.
    pub(crate) fn search(&self, base: &TrainSettings, first: &LabelledCapture) -> Option<DefaultSearch> {
        if self.search_budget_s <= 0.0 {
            return None;
        }
        let search = DefaultSearch::new(base.clone(), self.named(), first, self.search_budget_s);
        search.has_choice().then_some(search)
    }
}
