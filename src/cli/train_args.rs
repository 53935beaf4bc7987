//! How to train a recognizer, as `recognize train`, `recognize cv` and `recognize categorize`
//! take it on the command line; [`TrainOptions::settings`] turns it into the library's
//! [`recognize::TrainSettings`].

use clap::{Args, ValueEnum};

use super::train_values::{CArg, parse_c, parse_nodes};
use recognize::{
    DECISION_WINDOW_S, FeatureSet, HOP_S, Histogram, LabelledCapture, Normalization, SvmC, TrainSettings,
};

/// A recognizer to train: its method and how (`train` and `cv`).
#[derive(Debug, Args)]
pub(crate) struct Training {
    /// Which recognizer.
    #[arg(long, value_enum)]
    pub(crate) method: Method,
    #[command(flatten)]
    pub(crate) options: TrainOptions,
}

impl Training {
    /// The library's settings for it, on captures shaped like `first` (see
    /// [`TrainOptions::settings`]).
    pub(crate) fn settings(&self, first: &LabelledCapture) -> TrainSettings {
        self.options.settings(self.method, first)
    }
}

/// How to train, besides the method: features and settings (`train`, `cv` and `categorize`
/// alike).
#[derive(Debug, Args)]
pub(crate) struct TrainOptions {
    /// Which features: nakano (rubbing windows), spectral (one histogram per scratch), both
    /// (rubbing windows with accelerometer columns: three axes, or a single-axis
    /// vibration_mps2) or vibration (knn, svm: each such window's vibration spectrum alone, 25
    /// bands of 8 Hz, windows of at least 0.125 s, to fuse with a nakano classifier in `eval
    /// --sequential --fuse`; with --windows-over-travel the bands are over travel too, see
    /// --travel-speed-mps) or nakano-spectrum (knn, svm: each rubbing window's nakano
    /// features followed by the same window's spectrum of the tip's height, which every device
    /// measures; decided at the window's last sample). Default: chosen by `train`; else both
    /// when the captures carry both and a window holds a histogram (1.92 s), else the method's
    /// own (som nakano, knn and svm spectral), else the set the capture carries.
    #[arg(
        long,
        value_enum,
        value_name = "nakano|spectral|both|vibration|nakano-spectrum"
    )]
    pub(super) features: Option<Features>,
    /// Windowed features (nakano, both): decision window, s (a decision is this old plus the
    /// filters' 0.27 s lookahead, none with --mirrored-end). Default: chosen by `train`, else 3.
    #[arg(long, value_name = "S")]
    pub(super) window_s: Option<f64>,
    /// Windowed features (nakano, both): window of the training vectors, s. Default: the
    /// decision window (--window-s), for every method, since a decision window is compared
    /// with what was learnt from training vectors and features of another length sit elsewhere.
    /// Nakano's thesis trains its map on 1 s windows (more of them from one short run per
    /// surface). Set apart from the decision window, training warns.
    #[arg(long, value_name = "S")]
    pub(super) train_window_s: Option<f64>,
    /// Windowed features (nakano, both): time between decisions (and between training
    /// windows), s.
    #[arg(long, default_value_t = HOP_S, value_name = "S")]
    hop_s: f64,
    /// Windowed features (nakano, both): decide each window the moment its last sample
    /// arrives, the filters' lookahead past it being its mirror image, instead of 0.27 s later;
    /// the training windows are computed the same way, so the classifier learns the guess.
    #[arg(long)]
    mirrored_end: bool,
    /// Windowed features (nakano, both): filter the friction over travel before the windows
    /// read it, undoing the time-domain low-pass of the rig's force observer (its cut-off from
    /// the captures' `observer.cutoff_radps`), so that it reads the same at any rubbing speed.
    #[arg(long)]
    friction_over_travel: bool,
    /// Windowed features (nakano, both): the roughness filters follow the measured speed down
    /// to this one, m/s, instead of the protocol's 0.005 (a longer lookahead below it).
    #[arg(long, value_name = "MPS")]
    slowest_speed_mps: Option<f64>,
    /// Windowed features (nakano, both), with --mirrored-end: each window spans the travel of
    /// --window-s at the protocol's 5 mm/s (1.25 mm for 0.25 s) instead of a fixed time, so a
    /// slower or faster stroke is decided on the same stretch of surface.
    #[arg(long, requires = "mirrored_end")]
    windows_over_travel: bool,
    /// With --windows-over-travel: the speed at which a window spans --window-s, m/s, instead
    /// of the protocol's 0.005: a rig's own sliding speed. With --features vibration it also
    /// sets the bands over travel: 25 bands over 0–200 Hz at this speed, in cycles per metre,
    /// so a texture lands in the same band however fast it is slid.
    #[arg(long, requires = "windows_over_travel", value_name = "MPS")]
    travel_speed_mps: Option<f64>,
    /// With --windows-over-travel and --features vibration or nakano-spectrum: the fastest
    /// stroke the spectra read, m/s. Their 25 bands over travel end at the Nyquist frequency
    /// at this speed (at 1 kHz and 0.025 m/s: wavelengths down to 50 µm), so every wavelength
    /// such a stroke still samples is read; a faster window is left out and counted. Default: bands of
    /// 0–200 Hz at the travel speed, readable up to 2.5 times it at 1 kHz.
    #[arg(long, requires = "windows_over_travel", value_name = "MPS")]
    fastest_speed_mps: Option<f64>,
    /// The vibration features' scaling (--features spectral|both|vibration): mean (each
    /// cell's or band's mean magnitude) or unit-sum (divided by their total: the spectrum's
    /// shape alone, whatever a sensor's gain or the sliding speed). Default: chosen by `train`
    /// (--search-budget-s), else mean.
    #[arg(long, value_enum, value_name = "mean|unit-sum")]
    pub(super) cells: Option<CellsArg>,
    /// The band of the histogram's 25 frequency bins (--features spectral|both): paper (0–200
    /// Hz, Sinapov's 400 Hz sensor) or nyquist (to the captures' Nyquist frequency: 44 Hz bins
    /// at 2.2 kHz, for surfaces that differ above 200 Hz). Default: chosen by `train`, else paper.
    #[arg(long, value_enum, value_name = "paper|nyquist")]
    pub(super) bands: Option<BandsArg>,
    /// `train`, `categorize --leave-surface-out`: what --features, --cells, --bands and
    /// --window-s leave unnamed is chosen by cross-validation by recording on the training
    /// captures (at most 5 folds; windows every 0.5 s, no posterior weight, an SVM over windows
    /// at C = 10) among every set the captures carry, each cell scaling and band, windows of 3
    /// and 2 s, skipping a candidate that would overrun this budget and stopping an SVM still
    /// solving when it runs out. The documented defaults
    /// stand unless beaten by two standard errors; the table is kept in the model file. 0: no
    /// search.
    #[arg(long, default_value_t = recognize::SEARCH_BUDGET_S, value_name = "S")]
    pub(super) search_budget_s: f64,
    /// som: nodes of each map (also --som-nodes). Default: over windows (nakano, both) the
    /// thesis's 12 for up to its 7 surfaces; beyond, the SOM Toolbox's 5·N^0.54321 for N
    /// training windows, at least two per class (presentations: 10 000, at least 500 per node);
    /// over whole scratches (spectral) three per class, at least 12. A node answers one class:
    /// training warns when a class owns none.
    #[arg(
        long = "nodes",
        visible_alias = "som-nodes",
        value_name = "N",
        value_parser = parse_nodes
    )]
    som_nodes: Option<usize>,
    /// som: seed of the map's initial vectors and presentation order.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// som over nakano features: how features are scaled before the map. log-within-class:
    /// scales on a log scale, each divided by its pooled within-surface spread, unit length
    /// (default); standardize: z-scores, unit length; thesis: Eq. 2.26, each feature divided
    /// by its column's norm.
    #[arg(long, value_enum, default_value = "log-within-class")]
    scaling: ScalingArg,

    /// knn: neighbours. Over windows, when every surface has captures of two runs or trials,
    /// the neighbours' votes are calibrated on windows held out by run (blended with the
    /// uniform distribution by the weight that fits them best), which also gives the
    /// reliability `eval --sequential --fuse` weighs the k-NN by.
    #[arg(long, default_value_t = 3)]
    k: usize,
    /// svm: the box constraint C, or `auto`: per behaviour, the most accurate of 1, 10, …, 10⁵
    /// under cross-validation by trial on the training captures (ties to the smaller C; a
    /// behaviour with fewer than two trials gets 10⁴). Over windows (--features nakano|both|…):
    /// one C, by cross-validation by run on windows 0.5 s apart, each candidate fitted at C
    /// times the windows each stands for (duplicated vectors weigh the loss as a larger C
    /// does), or 10 when a surface has a single run.
    #[arg(long, default_value = "auto", value_parser = parse_c, value_name = "auto|C")]
    c: CArg,
    /// knn, svm over windows: keep each window's weight in anytime decisions at hop / window
    /// instead of fitting it on recordings held out of training (the fit refits the recognizer
    /// once per fold; it needs two runs or trials of every surface).
    #[arg(long)]
    no_weight_fit: bool,
    /// knn, svm over windows: the posterior's memory the weight is fitted at, s: the one the
    /// recognizer will decide with (`eval --memory-s`, a scene's `recognizer.memory_s`). A
    /// window's weight and the memory trade against each other, and a recognizer used with
    /// another memory says so.
    #[arg(long, value_name = "S", default_value_t = recognize::DEFAULT_MEMORY_S, conflicts_with = "no_weight_fit")]
    weight_fit_memory_s: f64,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub(super) enum CellsArg {
    Mean,
    UnitSum,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub(super) enum BandsArg {
    Paper,
    Nyquist,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum ScalingArg {
    LogWithinClass,
    Standardize,
    Thesis,
}

/// `--method`.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub(crate) enum Method {
    Som,
    Knn,
    Svm,
}

impl From<Method> for recognize::Method {
    fn from(m: Method) -> Self {
        match m {
            Method::Som => Self::Som,
            Method::Knn => Self::Knn,
            Method::Svm => Self::Svm,
        }
    }
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub(super) enum Features {
    Nakano,
    Spectral,
    Both,
    Vibration,
    NakanoSpectrum,
}

impl From<Features> for FeatureSet {
    fn from(f: Features) -> Self {
        match f {
            Features::Nakano => Self::Nakano,
            Features::Spectral => Self::Spectral,
            Features::Both => Self::Both,
            Features::Vibration => Self::Vibration,
            Features::NakanoSpectrum => Self::NakanoSpectrum,
        }
    }
}

impl TrainOptions {
    /// The settings of a `method` recognizer on captures shaped like `first`: the features
    /// asked for, else those the method reads from such captures
    /// ([`recognize::Method::features_for`], said on stderr when it is not the method's own).
    /// Warns on stderr when training and decision windows were set apart.
    pub(crate) fn settings(&self, method: Method, first: &LabelledCapture) -> TrainSettings {
        let settings = self.settings_quietly(method, first);
        self.say_default_features(&settings, first);
        settings
    }

    /// [`TrainOptions::settings`] without saying which features were taken by default (a
    /// search that will choose them prints its own table); settings warnings are still said.
    pub(crate) fn settings_quietly(&self, method: Method, first: &LabelledCapture) -> TrainSettings {
        let method = recognize::Method::from(method);
        let window_s = self.window_s.unwrap_or(DECISION_WINDOW_S);
        let features = self.features.map_or_else(
            || {
                let shortest_s = self.train_window_s.map_or(window_s, |t| t.min(window_s));
                method.features_for(first, shortest_s)
            },
            FeatureSet::from,
        );
        let settings = TrainSettings {
            features,
            window_s,
            train_window_s: self.train_window_s,
            som_nodes: self.som_nodes,
            hop_s: self.hop_s,
            mirrored_end: self.mirrored_end,
            friction_over_travel: self.friction_over_travel,
            slowest_speed_mps: self.slowest_speed_mps,
            windows_over_travel: self.windows_over_travel,
            travel_speed_mps: self.travel_speed_mps,
            fastest_speed_mps: self.fastest_speed_mps,
            histogram: Histogram::new(self.named().cells.unwrap_or_default())
                .over(self.named().band.unwrap_or_default()),
            seed: self.seed,
            normalization: match self.scaling {
                ScalingArg::LogWithinClass => Normalization::LogWithinClass,
                ScalingArg::Standardize => Normalization::Standardize,
                ScalingArg::Thesis => Normalization::ThesisColumnNorm,
            },
            k: self.k,
            c: match self.c {
                CArg::Auto => SvmC::auto(),
                CArg::Fixed(c) => SvmC::Fixed(c),
            },
            fit_posterior_weight: !self.no_weight_fit,
            weight_fit_memory_s: self.weight_fit_memory_s,
            ..TrainSettings::new(method)
        };
        for warning in crate::training::settings_warnings(&settings, first) {
            eprintln!("{warning}");
        }
        settings
    }
}
