//! `palpus bench loop` and `palpus bench render`.

use std::time::Duration;

use clap::Args;
use haptics::rt::{LoopConfig, Percentiles, RtRequest};
use haptics::{BenchConfig, loop_bench};
use indicatif::{ProgressBar, ProgressStyle};

use crate::exit::EndedEarly;

/// Frames per second of the renderer, headless, with where a frame's time goes.
///
/// Draws the needle-in-tissue demo frame at 640×480 and 1280×720, MSAA 1 and 4, with the
/// overlay off, on (the same data every frame, as between two refreshes of the window's plots:
/// its panel is painted once and copied) and live (new plot data every frame: the panel is
/// repainted every frame), on the first adapter found (Vulkan, then GL; lavapipe where there is
/// no GPU). A second pass waits for the device after each stage to split a frame into drawing,
/// MSAA resolve, overlay CPU work and readback.
#[derive(Debug, Args)]
pub(crate) struct RenderArgs {
    /// Frames timed per configuration.
    #[arg(long, default_value_t = 30)]
    frames: u32,
    /// Print the table as Markdown (docs/rendering.md's table).
    #[arg(long)]
    markdown: bool,
}

/// Run the haptic loop at 1 kHz and report its timing.
///
/// The full haptic path runs: a simulated Omega.7 with a hand inserting a needle over and
/// over, observers, the needle law through admittance control, the safety filter and the
/// recorder. Reports the mean rate, period-error and lateness percentiles, overruns and the
/// tick compute time, against the goals (rate within 0.1 %, p99.9 period error ≤ 100 µs, no
/// tick more than 2 ms late, compute p99 ≤ 20 µs). `--load` runs a busy thread on every core
/// beside the loop, as a renderer would.
///
/// A stall (a tick more than 4 ms after the one before) is reported, not fatal: the force goes
/// to zero and comes back over 100 ms. The run ends early only on a stall over 100 ms or more
/// than 5 stalls within a second.
#[derive(Debug, Args)]
pub(crate) struct LoopArgs {
    /// How long to run, s.
    #[arg(long, default_value_t = 10.0)]
    seconds: f64,
    /// Compete with a busy thread on every core.
    #[arg(long)]
    load: bool,
    /// Do not ask for SCHED_FIFO or core pinning.
    #[arg(long)]
    no_realtime: bool,
    /// Run without the watchdog: stalls are still counted, but the force is not ramped down
    /// and no stall ends the run.
    #[arg(long)]
    no_watchdog: bool,
}

fn us(d: Duration) -> String {
    format!("{:.1} µs", d.as_secs_f64() * 1e6)
}

/// `p50 …  p99 …  p99.9 …  max …`, in µs.
fn quantiles(p: &Percentiles) -> String {
    format!(
        "p50 {}  p99 {}  p99.9 {}  max {}",
        us(p.p50),
        us(p.p99),
        us(p.p999),
        us(p.max)
    )
}

/// `palpus bench render`.
pub(crate) fn run_render(args: &RenderArgs) -> anyhow::Result<()> {
    if args.frames == 0 {
        anyhow::bail!("--frames must be at least 1");
    }
    let options = render::bench::BenchOptions {
        frames: args.frames,
        ..render::bench::BenchOptions::default()
    };
    let bar = ProgressBar::new(render::bench::row_count(&options) as u64).with_style(
        ProgressStyle::with_template("drawing {bar:30} {pos}/{len} configurations {elapsed} (eta {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let table = render::bench::run_reporting(&options, |done, _| bar.set_position(done as u64));
    bar.finish_and_clear();
    let table = table?;
    if args.markdown {
        print!("{}", table.to_markdown());
    } else {
        print!("{}", table.to_text());
    }
    Ok(())
}

/// `palpus bench loop`.
pub(crate) fn run_loop(args: &LoopArgs) -> anyhow::Result<()> {
    if !(args.seconds.is_finite() && args.seconds > 0.0 && args.seconds <= 86_400.0) {
        anyhow::bail!("--seconds must be in (0, 86400], not {}", args.seconds);
    }
    let mut loop_config = LoopConfig::default();
    if args.no_realtime {
        loop_config.rt = RtRequest::NONE;
    }
    if args.no_watchdog {
        loop_config.watchdog = None;
    }
    let report = loop_bench(&BenchConfig {
        seconds: args.seconds,
        load: args.load,
        loop_config,
    })?;
    let s = &report.stats;
    let load = if report.load_threads > 0 {
        format!("with {} busy threads", report.load_threads)
    } else {
        "no competing load".into()
    };
    println!("haptic loop, {:.0} s at 1 kHz, {load}", args.seconds);
    if let Some(rt) = report.rt_status {
        println!("scheduling:       {rt}");
    }
    match &report.outcome {
        Ok(reason) => println!("ended:            {reason:?} after {} ticks", s.ticks),
        Err(e) => println!("ended early:      {e}"),
    }
    let yes = |ok: bool| if ok { "meets goal" } else { "MISSES goal" };
    println!(
        "mean rate:        {:.3} Hz ({:+.4} %)  {}",
        s.mean_rate_hz,
        (s.mean_rate_hz / s.nominal_rate_hz - 1.0) * 100.0,
        yes(s.rate_error() <= 0.001)
    );
    println!(
        "period error:     {}  {}",
        quantiles(&s.period_error),
        yes(s.period_error.p999 <= Duration::from_micros(100))
    );
    println!("lateness:         {}", quantiles(&s.lateness));
    println!(
        "overruns:         {} ticks a period late, {} slots skipped, {} ticks > 2 ms late  {}",
        s.overruns,
        s.missed_slots,
        s.late_over_2ms,
        yes(s.late_over_2ms == 0)
    );
    println!(
        "stalls:           {} (longest {:.1} ms){}",
        s.stalls,
        s.longest_stall.as_secs_f64() * 1e3,
        if s.stalls == 0 {
            ""
        } else if args.no_watchdog {
            "; force left alone (no watchdog)"
        } else {
            "; force ramped to zero and back over 100 ms each time"
        }
    );
    println!(
        "tick compute:     {}  {}",
        quantiles(&s.compute),
        yes(s.compute.p99 <= Duration::from_micros(20))
    );
    println!(
        "recorder:         {} rows, {} samples dropped",
        report.recorded_rows, s.dropped_samples
    );
    match &report.outcome {
        Ok(_) => Ok(()),
        Err(end) => Err(EndedEarly::new("the loop benchmark", end, None).into()),
    }
}
