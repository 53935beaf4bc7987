//! `palpus recognize cv`.

use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, ValueEnum};
use recognize::FeatureNeeds;
use recognize::protocol::{self, SINAPOV_FOLDS, Split};

use super::kept_reading::read_keeping;
use super::mapped_captures::MappedCaptures;
use super::train_args::{Method, Training};
use crate::tables::recognition::warn_windowless;
use crate::tables::recognition_cv::{cv_json, print_cv};

/// Run a paper's protocol: train and evaluate again and again on captures split by recording,
/// and pool the decisions.
///
/// Recordings are the captures' `trial` (else `run`, else each capture alone), dealt into
/// --folds folds in numeric order. k-fold (Sinapov): each fold is held out once while the
/// others train — with `palpus gen --only sinapov` and 10 folds, fold t is trial t of every
/// surface. train-on-one (Nakano): each fold trains once and the others are held out — with
/// Nakano's three runs per surface, one run trains and two test. --seeds trains that many maps
/// per fold (Fig. 4.15 pools 10). Each round trains exactly as `recognize train` would.
///
/// For knn and svm over scratches it also scores each behaviour alone (Table II) and every
/// combination of n behaviours fused, for each n (Fig. 6).
#[derive(Debug, Args)]
pub(crate) struct CvArgs {
    /// All the captures: every recording of every surface.
    #[arg(required = true)]
    captures: Vec<PathBuf>,
    /// How the recordings are split.
    #[arg(long, value_enum, default_value = "k-fold")]
    split: SplitArg,
    /// Folds. Default: 10 for k-fold; one per recording for train-on-one.
    #[arg(long)]
    folds: Option<usize>,
    /// Run only this fold (from 1): with train-on-one, `--fold 1 --seeds 10` is Nakano's own
    /// protocol (the first run trains, 10 maps).
    #[arg(long)]
    fold: Option<usize>,
    /// som: maps trained per fold, seeds --seed, --seed + 1, … (their decisions pooled).
    #[arg(long, default_value_t = 1)]
    seeds: u64,
    /// Print one JSON object instead of the tables.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    training: Training,
    #[command(flatten)]
    input: MappedCaptures,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum SplitArg {
    KFold,
    TrainOnOne,
}

pub(crate) fn run(args: &CvArgs) -> anyhow::Result<()> {
    if args.seeds > 1 && !matches!(args.training.method, Method::Som) {
        anyhow::bail!(
            "--seeds {} applies to som only: knn and svm train the same way every time",
            args.seeds
        );
    }
    let mut settings = None;
    let captures = read_keeping(&args.input, &args.captures, None, |first| {
        // Each round's recognizer is scored window by window, which the posterior's weight
        // does not touch: fitting it would only refit every round once per fold.
        let settings = settings.insert(recognize::TrainSettings {
            fit_posterior_weight: false,
            ..args.training.settings(first)
        });
        Ok(FeatureNeeds::training_and_decisions(
            settings,
            first.capture.metadata().rate_hz(),
        )?)
    })?;
    let settings = settings.context("no captures to cross-validate on")?;
    let split = match (args.split, args.folds) {
        (SplitArg::KFold, folds) => Split::KFold {
            folds: folds.unwrap_or(SINAPOV_FOLDS),
        },
        (SplitArg::TrainOnOne, Some(folds)) => Split::TrainOnOne { folds },
        (SplitArg::TrainOnOne, None) => Split::TrainOnOne {
            folds: protocol::recordings(&captures),
        },
    };
    let start = std::time::Instant::now();
    let result = protocol::run(&captures, split, args.seeds, args.fold, |train, seed| {
        let settings = recognize::TrainSettings {
            seed: settings.seed + seed,
            ..settings.clone()
        };
        recognize::train(train, &settings).map_err(Box::new)
    })?;
    let elapsed_s = start.elapsed().as_secs_f64();
    warn_windowless(&result.evaluation);
    if args.json {
        let json = cv_json(&result, &settings, split, args.fold);
        println!("{}", serde_json::to_string_pretty(&json)?);
    } else {
        print_cv(&result, &settings, split, args.fold, elapsed_s);
    }
    Ok(())
}
