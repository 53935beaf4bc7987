//! Command-line interface.

// The command line is where palpus talks to its user.
#![allow(clippy::print_stdout)]

mod bench_cmd;
mod bench_needle;
mod bench_svr;
mod bench_svr_plot;
mod bench_trade;
mod capture_cmd;
mod categorize_cmd;
mod chosen_training;
mod device_arg;
mod devices_cmd;
mod gen_cmd;
mod history_cmd;
mod identify_cmd;
mod import_cmd;
mod kept_reading;
mod mapped_captures;
mod meta_arg;
mod model_arg;
mod recognize_cv_cmd;
mod recognize_eval_cmd;
mod recognize_train_cmd;
mod render_cmd;
mod run_cmd;
mod train_args;
mod train_values;

use clap::{Args, Parser, Subcommand};

/// palpus — haptic VR training on identified dynamics.
///
/// Trainees puncture virtual tissue and rub virtual surfaces through a Force Dimension Omega.7
/// (or its simulator) and feel forces identified from measured data. Without an Omega.7 the
/// simulated world measures: `palpus gen` writes the papers' experiments as captures, and
/// `palpus run` starts a scene (default: a needle into virtual liver).
#[derive(Debug, Parser)]
#[command(name = "palpus", version, about, long_about)]
pub struct Cli {
    /// Worker threads for the solvers' parallel parts (kernel rows, the low-rank factor, the
    /// certificate, the exact finish, the C-SVC's pairs and cross-validation folds); default:
    /// one per core. `--threads 1` times them beside single-threaded libraries such as libsvm.
    #[arg(long, global = true, value_name = "N")]
    threads: Option<std::num::NonZeroUsize>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    Run(run_cmd::RunArgs),
    Render(render_cmd::RenderArgs),
    Gen(gen_cmd::GenArgs),
    Identify(identify_cmd::IdentifyArgs),
    Capture(capture_cmd::CaptureArgs),
    Devices(devices_cmd::DevicesArgs),
    Bench(BenchArgs),
    Recognize(RecognizeArgs),
    // `palpus import`: its help is `ImportArgs`' doc comment (a `///` here would replace it).
    Import(import_cmd::ImportArgs),
    History(history_cmd::HistoryArgs),
}

/// Measure performance.
#[derive(Debug, Args)]
struct BenchArgs {
    #[command(subcommand)]
    what: BenchWhat,
}

#[derive(Debug, Subcommand)]
enum BenchWhat {
    Loop(bench_cmd::LoopArgs),
    Svr(bench_svr::SvrArgs),
    SvrScale(bench_svr::SvrScaleArgs),
    SvrScalePlot(bench_svr_plot::SvrScalePlotArgs),
    Trade(bench_trade::TradeArgs),
    NeedleLaw(bench_needle::NeedleLawArgs),
    Render(bench_cmd::RenderArgs),
}

/// Train and evaluate surface recognizers.
///
/// A capture's class is the `surface` in its metadata (and, for scratches, its `behaviour`
/// picks which classifier answers), so `palpus gen` captures are used as they are.
#[derive(Debug, Args)]
struct RecognizeArgs {
    #[command(subcommand)]
    what: RecognizeWhat,
}

#[derive(Debug, Subcommand)]
enum RecognizeWhat {
    Train(recognize_train_cmd::TrainArgs),
    Eval(recognize_eval_cmd::EvalArgs),
    Cv(recognize_cv_cmd::CvArgs),
    Categorize(categorize_cmd::CategorizeArgs),
}

/// Runs the parsed command line.
/// The whole chain of `error` on one line: what was being done, then why it failed. Many
/// errors already quote their cause in their own message (`…: {source}`), so a cause whose text
/// is already there is not repeated.
pub fn describe(error: &anyhow::Error) -> String {
    let mut text = error.to_string();
    for cause in error.chain().skip(1) {
        let cause = cause.to_string();
        if !text.contains(&cause) {
            text.push_str(": ");
            text.push_str(&cause);
        }
    }
    // The device library speaks of devices, the command line of its options: how to run on
    // the simulated device is said here.
    let no_device = error.chain().any(|e| {
        matches!(
            e.downcast_ref::<haptics::HapticsError>(),
            Some(
                haptics::HapticsError::SdkMissing { .. }
                    | haptics::HapticsError::SymbolMissing { .. }
                    | haptics::HapticsError::NoDevice { .. }
            )
        )
    });
    if no_device {
        text.push_str(" (--device sim)");
    }
    text
}

/// An image size `WIDTHxHEIGHT`, each side 16–8192 px (what every PNG the CLI draws accepts).
fn parse_size(s: &str) -> Result<[u32; 2], String> {
    let (w, h) = s
        .split_once('x')
        .ok_or_else(|| format!("`{s}`: expected WIDTHxHEIGHT"))?;
    let n = |v: &str| {
        v.parse::<u32>()
            .ok()
            .filter(|v| (16..=8192).contains(v))
            .ok_or_else(|| format!("`{s}`: each side must be 16–8192 px"))
    };
    Ok([n(w)?, n(h)?])
}

pub fn run(cli: Cli) -> anyhow::Result<()> {
    if let Some(threads) = cli.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads.get())
            .build_global()
            .map_err(|e| anyhow::anyhow!("--threads {threads}: {e}"))?;
    }
    match cli.command {
        Command::Run(args) => run_cmd::run(&args),
        Command::Render(args) => render_cmd::run(&args),
        Command::Gen(args) => gen_cmd::run(&args),
        Command::Identify(args) => identify_cmd::run(&args),
        Command::Capture(args) => capture_cmd::run(&args),
        Command::Devices(args) => devices_cmd::run(&args),
        Command::Bench(args) => match &args.what {
            BenchWhat::Loop(args) => bench_cmd::run_loop(args),
            BenchWhat::Svr(args) => bench_svr::run(args),
            BenchWhat::SvrScale(args) => bench_svr::run_scale(args),
            BenchWhat::SvrScalePlot(args) => bench_svr_plot::run(args),
            BenchWhat::Trade(args) => bench_trade::run(args),
            BenchWhat::NeedleLaw(args) => bench_needle::run(args),
            BenchWhat::Render(args) => bench_cmd::run_render(args),
        },
        Command::Recognize(args) => match &args.what {
            RecognizeWhat::Train(args) => recognize_train_cmd::run(args),
            RecognizeWhat::Eval(args) => recognize_eval_cmd::run(args),
            RecognizeWhat::Cv(args) => recognize_cv_cmd::run(args),
            RecognizeWhat::Categorize(args) => categorize_cmd::run(args),
        },
        Command::Import(args) => import_cmd::run(&args),
        Command::History(args) => history_cmd::run(&args),
    }
}

#[cfg(test)]
mod tests {
    use super::describe;

    #[derive(Debug, thiserror::Error)]
    #[error("model `m`: {source}")]
    struct Quoting {
        source: std::io::Error,
    }

    #[derive(Debug, thiserror::Error)]
    #[error("model `m`")]
    struct Silent {
        source: std::io::Error,
    }

    #[test]
    fn a_cause_is_told_once_whether_or_not_the_message_quotes_it() {
        let io = || std::io::Error::other("disk on fire");
        let quoting = anyhow::Error::new(Quoting { source: io() }).context("resolving");
        assert_eq!(describe(&quoting), "resolving: model `m`: disk on fire");
        let silent = anyhow::Error::new(Silent { source: io() }).context("resolving");
        assert_eq!(describe(&silent), "resolving: model `m`: disk on fire");
    }
}
