//! `palpus history`.

use std::path::PathBuf;

use clap::Args;

use crate::history::{self, History};

/// Show scored attempts from the trainees' history: a table (one row per attempt, oldest first)
/// and a learning-curve PNG (overshoot after the target layer gave, peak force and time to the
/// target against attempt number, one line per trainee and scene; failed attempts hollow).
#[derive(Debug, Args)]
pub(crate) struct HistoryArgs {
    /// Only this trainee's attempts.
    #[arg(long, value_name = "NAME")]
    trainee: Option<String>,
    /// Only attempts at this scene (its name, as the run report gives it).
    #[arg(long, value_name = "SCENE")]
    scene: Option<String>,
    /// The history database (default: $PALPUS_HISTORY, else history.sqlite under
    /// $XDG_DATA_HOME/palpus or ~/.local/share/palpus).
    #[arg(long, value_name = "FILE")]
    history: Option<PathBuf>,
    /// Where the learning curve is drawn.
    #[arg(long, value_name = "PNG", default_value = "out/history/learning_curve.png")]
    plot: PathBuf,
    /// Print the attempts as JSON instead of the table.
    #[arg(long)]
    json: bool,
}

pub(crate) fn run(args: &HistoryArgs) -> anyhow::Result<()> {
    let path = args.history.clone().unwrap_or_else(history::default_path);
    let attempts = History::open(&path)?.attempts(args.trainee.as_deref(), args.scene.as_deref())?;
    if attempts.is_empty() {
        anyhow::bail!(
            "{}: no attempts{}{}",
            path.display(),
            args.trainee
                .as_ref()
                .map_or(String::new(), |t| format!(" by {t}")),
            args.scene.as_ref().map_or(String::new(), |s| format!(" at {s}"))
        );
    }
    if let Some(dir) = args.plot.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    crate::plots::write_learning_curve(&args.plot, &attempts)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&attempts)?);
        eprintln!("wrote {}", args.plot.display());
        return Ok(());
    }
    println!(
        "{} attempt{} in {}",
        attempts.len(),
        if attempts.len() == 1 { "" } else { "s" },
        path.display()
    );
    println!(
        "{:>4}  {:<24}  {:<12}  {:<16}  {:<6}  {:>9}  {:>8}  {:>8}  {:>5}  {:>6}  {:>6}",
        "#",
        "when (UTC)",
        "trainee",
        "scene",
        "result",
        "overshoot",
        "peak",
        "to target",
        "withd",
        "reins",
        "SPARC"
    );
    for a in &attempts {
        let s = &a.score;
        let opt = |v: Option<f64>, f: &dyn Fn(f64) -> String| v.map_or("—".to_owned(), f);
        println!(
            "{:>4}  {:<24}  {:<12}  {:<16}  {:<6}  {:>9}  {:>6.2} N  {:>8}  {:>5}  {:>6}  {:>6}",
            a.id,
            a.at,
            a.trainee,
            a.scene,
            if s.passed { "passed" } else { "failed" },
            opt(s.overshoot_m, &|m| format!("{:.1} mm", m * 1e3)),
            s.peak_force_n,
            opt(s.time_to_target_s, &|t| format!("{t:.2} s")),
            s.withdrawals,
            s.reinsertions,
            opt(s.smoothness_sparc, &|v| format!("{v:.2}")),
        );
    }
    let passed = attempts.iter().filter(|a| a.score.passed).count();
    println!("passed {passed} of {}", attempts.len());
    println!("wrote {}", args.plot.display());
    Ok(())
}
