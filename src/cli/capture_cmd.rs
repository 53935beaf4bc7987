//! `palpus capture`.

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::Args;
use haptics::acquire::{CaptureOptions, Protocol, run_capture, sim_setup};
use haptics::partial_path;
use haptics::rt::Pacing;
use haptics::{DeviceChoice, Motion};

use super::device_arg::parse_device;

/// Record a capture through a haptic device.
///
/// Runs a measurement protocol on the device in the 1 kHz haptic loop and records what the
/// device measured and what its observers estimated, in the capture format `palpus gen`
/// writes (the Omega.7 has no force sensor: forces come from its reaction-force observer).
/// Protocols: needle (insertions at 2, 5 and 10 mm/s into fresh sites), hard (strokes on a
/// hard plate under a varying load), soft (strokes at 2–40 mm/s on a sponge), rubbing (one
/// 30 mm stroke at 5 mm/s under 0.3 N, Nakano's Table 3.2). On the simulator the world is the
/// simulated one; on an Omega.7 the device moves by itself: keep hands clear and place the
/// sample under the tip.
#[derive(Debug, Args)]
pub(crate) struct CaptureArgs {
    /// The device: sim (the simulated Omega.7) or omega7[:PATH] (a Force Dimension Omega.7,
    /// PATH its SDK library, default $PALPUS_DHD_LIBRARY, then libdhd.so).
    #[arg(long, value_name = "NAME[:OPTION]", value_parser = parse_device)]
    device: DeviceChoice,
    /// What to capture: needle, hard, soft or rubbing.
    #[arg(long, value_parser = parse_protocol)]
    protocol: Protocol,
    /// The capture file to write. Rows go to FILE.partial while the capture runs, and it is
    /// renamed to FILE when the capture completes: an existing FILE is replaced, as every
    /// palpus output is (no --force), but only by a finished capture. A capture that fails or
    /// is killed leaves FILE as it was and what it recorded in FILE.partial.
    #[arg(long, value_name = "FILE")]
    out: PathBuf,
    /// For `rubbing` on the simulator: which of Nakano's seven surfaces.
    #[arg(long, default_value = "sandpaper_120")]
    surface: String,
    /// For `rubbing` on the simulator: where on the patch the stroke starts, mm (another
    /// offset rubs another track of the same surface).
    #[arg(long, default_value_t = 10.0, value_name = "MM")]
    track_offset_mm: f64,
    /// Simulator only: run as fast as possible instead of in real time (same capture, its
    /// clock is the tick count).
    #[arg(long)]
    unpaced: bool,
    /// Print nothing but errors.
    #[arg(long, short)]
    quiet: bool,
}

fn parse_protocol(s: &str) -> Result<Protocol, String> {
    s.parse()
}

pub(crate) fn run(args: &CaptureArgs) -> anyhow::Result<()> {
    let mut options = CaptureOptions::new(args.protocol);
    options.surface = args.surface.clone();
    if !(args.track_offset_mm.is_finite() && (0.0..=280.0).contains(&args.track_offset_mm)) {
        bail!(
            "--track-offset-mm {}: expected 0–280 mm (the patch is 330 mm long)",
            args.track_offset_mm
        );
    }
    options.track_offset_m = args.track_offset_mm * 1e-3;
    if args.unpaced {
        options.pacing = Pacing::Unpaced;
    }
    let backend = args.device.backend();
    if backend.motion == Motion::Recorded {
        bail!(
            "`{}` plays recorded motion: a protocol needs a device it can move",
            backend.name
        );
    }
    if args.unpaced && !backend.simulated {
        bail!("--unpaced is for the simulator only: a real device runs in real time");
    }
    let period_s = 1.0 / options.loop_config.rate_hz;
    let device = args
        .device
        .open(period_s, sim_setup(&options)?, options.protocol.kind())
        .with_context(|| format!("opening {}", args.device.label()))?
        .device;
    if !args.quiet && options.pacing != Pacing::Unpaced {
        println!(
            "capturing `{}` on {} in real time into {} ...",
            args.protocol,
            device.name(),
            args.out.display()
        );
    }
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let report = run_capture(device, &args.out, &options, &mut |_| {}).with_context(|| {
        let partial = partial_path(&args.out);
        let kept = if partial.exists() {
            format!(" (what was recorded is in {})", partial.display())
        } else {
            String::new()
        };
        format!("capturing `{}` into {}{kept}", args.protocol, args.out.display())
    })?;
    if args.quiet {
        return Ok(());
    }
    let s = &report.stats;
    println!(
        "wrote {} rows to {} in {:.2} s",
        report.recorder.rows,
        report.path.display(),
        report.elapsed.as_secs_f64()
    );
    if options.pacing != Pacing::Unpaced {
        println!(
            "loop: {} ticks, mean rate {:.3} Hz, period error p99 {:?}, overruns {}, dropped samples {}",
            s.ticks, s.mean_rate_hz, s.period_error.p99, s.overruns, s.dropped_samples
        );
        if let Some(rt) = report.rt_status {
            println!("scheduling: {rt}");
        }
    }
    Ok(())
}
