//! `palpus bench needle-law`: what one haptic tick pays for the needle law.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use capture::{Capture, CaptureKind};
use clap::Args;
use haptics::{AxialLaw, NeedleLaw, NeedleLawConfig, PhasedNeedleLaw, needle_model};
use identify::{IdentifyOptions, ModelKind, identify, model_column};

/// Time per tick of the needle laws, phase-aware against Li & Bi's smooth SVR in the same run.
///
/// Both are identified from the capture with their defaults, then stepped along its own
/// trajectory (depth and velocity of every row, over and over, as the haptic thread steps them)
/// for `--ticks` ticks each. Ticks are timed in batches of 64 (a clock read costs about as
/// much as a phase-model tick), and the table gives the per-tick time's median, 99th
/// percentile and largest batch mean, and the ratio of the two laws' medians.
#[derive(Debug, Args)]
pub(crate) struct NeedleLawArgs {
    /// The insertion capture both laws are identified from and stepped along.
    #[arg(long, default_value = "assets/captures/li_bi/needle_train.csv")]
    capture: PathBuf,
    /// Ticks per law.
    #[arg(long, default_value_t = 2_000_000)]
    ticks: usize,
}

const BATCH: usize = 64;

/// Per-tick times (ns) of `law` over `ticks` ticks along (`depth`, `velocity`), one value a
/// batch.
fn time_law(law: &mut dyn AxialLaw, depth: &[f64], velocity: &[f64], ticks: usize) -> Vec<f64> {
    let n = depth.len();
    let mut out = Vec::with_capacity(ticks / BATCH + 1);
    let mut i = 0;
    let mut sink = 0.0;
    for _ in 0..ticks.div_ceil(BATCH) {
        let started = Instant::now();
        for _ in 0..BATCH {
            sink += law.step(depth[i], velocity[i]).axial_force_n;
            i = (i + 1) % n;
        }
        out.push(started.elapsed().as_secs_f64() * 1e9 / BATCH as f64);
    }
    std::hint::black_box(sink);
    out
}

fn quantile(sorted: &[f64], q: f64) -> f64 {
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

pub(crate) fn run(args: &NeedleLawArgs) -> anyhow::Result<()> {
    if args.ticks < BATCH {
        anyhow::bail!("--ticks must be at least {BATCH}");
    }
    let capture = Capture::read_file(&args.capture, CaptureKind::Insertion)
        .with_context(|| format!("reading {}", args.capture.display()))?;
    let depth = model_column(&capture, capture::kind::DEPTH_M)?;
    let velocity = model_column(&capture, capture::kind::VELOCITY_MPS)?;
    let fit = |kind| identify(&capture, None, &IdentifyOptions::new(kind)).map(|r| r.model);
    let phases = fit(ModelKind::NeedlePhases)?;
    let smooth = fit(ModelKind::NeedlePuncture)?;
    let config = NeedleLawConfig::default();
    let mut laws: Vec<(&str, Box<dyn AxialLaw>)> = vec![
        (
            "phase-aware",
            Box::new(PhasedNeedleLaw::from_file(&phases, config)?),
        ),
        (
            "smooth SVR (f32 fast path)",
            Box::new(NeedleLaw::new(needle_model(&smooth)?, config)),
        ),
    ];
    println!(
        "needle law per tick, {} ticks each along {} ({} rows), timed in batches of {BATCH}",
        args.ticks,
        args.capture.display(),
        depth.len()
    );
    println!(
        "  {:<28} {:>9} {:>9} {:>9}",
        "law", "p50 [ns]", "p99 [ns]", "max [ns]"
    );
    let mut medians = Vec::new();
    for (name, law) in &mut laws {
        let mut t = time_law(law.as_mut(), &depth, &velocity, args.ticks);
        t.sort_by(f64::total_cmp);
        let (p50, p99, max) = (quantile(&t, 0.5), quantile(&t, 0.99), quantile(&t, 1.0));
        println!("  {name:<28} {p50:>9.1} {p99:>9.1} {max:>9.1}");
        medians.push(p50);
    }
    println!("  phase-aware / smooth (medians): {:.3}", medians[0] / medians[1]);
    Ok(())
}
