//! `palpus gen`.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use sim::protocols::{CaptureSet, generate};

/// Write a reproducible set of simulated captures.
///
/// Runs the papers' measurement protocols in the simulated world, with realistic sensor
/// models, and writes each recording as a capture (CSV with a metadata line that carries the
/// ground truth): Li & Bi's hard-contact, soft-contact and needle-insertion experiments (a
/// training and a held-out capture each), Nakano's rubbing of 7 surfaces × 3 runs, and
/// Sinapov-style scratching of 20 surfaces and air × 5 behaviours × 10 trials. A MANIFEST.csv
/// lists them. The same seed always gives the same bytes.
///
/// Only when asked for (`--only multistream`): a sliding study of the same 20 surfaces written
/// not as captures but as a rig logs it, one CSV per stream (force, position, velocity at about
/// 88 Hz on their own jittered clocks; a 2.2 kHz vibration channel packed 22 samples per 100 Hz
/// row), input for `palpus import`; multistream/README.md says how to import it.
#[derive(Debug, Args)]
pub(crate) struct GenArgs {
    /// Folder to write into (created if missing; existing captures are replaced).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Seed of every noise source and every trial's variation.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Only these sets (comma-separated): li_bi, nakano, sinapov (the default: all three), and
    /// multistream (never by default).
    #[arg(long, value_delimiter = ',', value_name = "SET")]
    only: Vec<CaptureSet>,
    /// Print nothing but errors.
    #[arg(long, short)]
    quiet: bool,
    /// Write only Li & Bi's needle captures, logged at this rate (a divisor of 1000 Hz; the
    /// paper's is 100 Hz): larger training sets for benchmarking the fit.
    #[arg(long, value_name = "HZ")]
    needle_rate_hz: Option<u32>,
    /// With --needle-rate-hz: insert at every speed this many times, each at a fresh site.
    #[arg(long, default_value_t = 1, requires = "needle_rate_hz")]
    needle_rounds: u32,
    /// Write only needle captures, into this tissue: `liver` (the paper's, capsule and vessel
    /// wall) or `phantom` (three membranes at other depths, with other parameters: a second
    /// tissue for held-out tests).
    #[arg(long, value_enum, value_name = "TISSUE")]
    needle_tissue: Option<NeedleTissueArg>,
    /// Write only needle captures, each stroke at `constant` speed (the paper's) or at a
    /// `varying` one (±60 % around the nominal speed within the stroke).
    #[arg(long, value_enum, value_name = "PROFILE")]
    needle_speed: Option<NeedleSpeedArg>,
    /// Write only Nakano's rubbing runs (into nakano/, same names), the tip sliding at this
    /// speed instead of the thesis's 0.005 m/s: strokes for checking that recognition does not
    /// depend on how fast the tool moves.
    #[arg(long, value_name = "M/S")]
    rub_speed_mps: Option<f64>,
    /// Write only two-patch rubbing strokes (into nakano_two_patch/): each of Nakano's surfaces
    /// rubbed onto the next one halfway through the stroke, runs 1 and 2, at --rub-speed-mps if
    /// given (a faster stroke rubs the second surface for 3 s, as one at 5 mm/s does); their
    /// metadata say when the surface changes, which `recognize eval --sequential` times.
    #[arg(long)]
    two_patch: bool,
    /// Write only the multi-stream sliding study (into multistream/, same names and README),
    /// the arm sliding at about this speed instead of 0.025 m/s: trials for checking that
    /// recognition does not depend on how fast the rig slides. Each trial draws what it does at
    /// 0.025 m/s (strip, load, placement, noise), only faster or slower.
    #[arg(long, value_name = "M/S", conflicts_with_all = ["rub_speed_mps", "two_patch"])]
    slide_speed_mps: Option<f64>,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum NeedleTissueArg {
    Liver,
    Phantom,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum NeedleSpeedArg {
    Constant,
    Varying,
}

/// `--needle-rate-hz`, `--needle-tissue`, `--needle-speed`: only the needle's training and
/// held-out captures, with that protocol.
fn needle_only(args: &GenArgs, log_rate_hz: u32) -> anyhow::Result<()> {
    use sim::protocols::Split;
    use sim::protocols::li_bi::{NeedleProtocol, NeedleTissueKind, SpeedProfile, needle_insertion_with};
    let protocol = NeedleProtocol {
        log_rate_hz,
        rounds: args.needle_rounds,
        tissue: match args.needle_tissue {
            Some(NeedleTissueArg::Phantom) => NeedleTissueKind::LayeredPhantom,
            _ => NeedleTissueKind::BovineLiver,
        },
        speed: match args.needle_speed {
            Some(NeedleSpeedArg::Varying) => SpeedProfile::Varying,
            _ => SpeedProfile::Constant,
        },
    };
    let dir = args.out.join("li_bi");
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    for split in [Split::Train, Split::Test] {
        let path = dir.join(format!("needle_{}.csv", split.as_str()));
        write_capture(args, &path, &needle_insertion_with(args.seed, split, protocol)?)?;
    }
    Ok(())
}

/// Writes one capture of a single-set run and, unless quiet, says so.
fn write_capture(args: &GenArgs, path: &std::path::Path, capture: &capture::Capture) -> anyhow::Result<()> {
    capture
        .write_file(path)
        .with_context(|| format!("writing {}", path.display()))?;
    if !args.quiet {
        println!("wrote {} ({} samples)", path.display(), capture.len());
    }
    Ok(())
}

/// `--two-patch`: only strokes from each Nakano surface onto the next, at `speed_mps`.
fn two_patch_only(args: &GenArgs, speed_mps: f64) -> anyhow::Result<()> {
    use sim::protocols::nakano::{RUNS, two_patch_file_name, two_patch_run};
    use sim::world::surface::{SurfacePatch, nakano_surfaces};
    let dir = args.out.join("nakano_two_patch");
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let surfaces = nakano_surfaces();
    let patches: Vec<SurfacePatch> = surfaces.iter().map(SurfacePatch::new).collect();
    for (i, first) in patches.iter().enumerate() {
        let second = &patches[(i + 1) % patches.len()];
        // Run 0 is the training run of the single-surface set; these are test strokes.
        for run in 1..RUNS {
            let path = dir.join(two_patch_file_name(first.surface(), second.surface(), run));
            write_capture(
                args,
                &path,
                &two_patch_run(first, second, run, args.seed, speed_mps)?,
            )?;
        }
    }
    Ok(())
}

/// `--rub-speed-mps`: only Nakano's rubbing runs, at that speed.
fn rubbing_only(args: &GenArgs, speed_mps: f64) -> anyhow::Result<()> {
    use sim::protocols::nakano::{RUNS, rubbing_run_at, run_file_name};
    use sim::world::surface::{SurfacePatch, nakano_surfaces};
    let dir = args.out.join("nakano");
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    for surface in nakano_surfaces() {
        let patch = SurfacePatch::new(&surface);
        for run in 0..RUNS {
            let path = dir.join(run_file_name(&surface, run));
            write_capture(args, &path, &rubbing_run_at(&patch, run, args.seed, speed_mps)?)?;
        }
    }
    Ok(())
}

/// `--slide-speed-mps`: only the multi-stream sliding study, at that speed.
fn sliding_only(args: &GenArgs, speed_mps: f64) -> anyhow::Result<()> {
    use sim::protocols::multistream::{SlidingStudy, write_logs};
    let study = SlidingStudy::default().at_speed(speed_mps)?;
    write_logs(&args.out, args.seed, study, &mut |file| {
        if !args.quiet {
            println!(
                "wrote {} ({} rows)",
                args.out.join(&file.path).display(),
                file.rows
            );
        }
    })
    .with_context(|| format!("writing the sliding study into {}", args.out.display()))
}

pub(crate) fn run(args: &GenArgs) -> anyhow::Result<()> {
    if args.needle_rate_hz.is_some() || args.needle_tissue.is_some() || args.needle_speed.is_some() {
        return needle_only(args, args.needle_rate_hz.unwrap_or(100));
    }
    if args.two_patch {
        let speed_mps = args.rub_speed_mps.unwrap_or(sim::protocols::nakano::SPEED_MPS);
        return two_patch_only(args, speed_mps);
    }
    if let Some(speed_mps) = args.rub_speed_mps {
        return rubbing_only(args, speed_mps);
    }
    if let Some(speed_mps) = args.slide_speed_mps {
        return sliding_only(args, speed_mps);
    }
    let sets = if args.only.is_empty() {
        CaptureSet::ALL.to_vec()
    } else {
        args.only.clone()
    };
    let started = Instant::now();
    let summary = generate(&args.out, args.seed, &sets, &mut |_| {})
        .with_context(|| format!("generating captures into {}", args.out.display()))?;
    let elapsed = started.elapsed();
    if args.quiet {
        return Ok(());
    }
    let mut by_protocol: BTreeMap<&str, (usize, usize, u64)> = BTreeMap::new();
    for g in &summary.files {
        let entry = by_protocol.entry(g.protocol).or_default();
        entry.0 += 1;
        entry.1 += g.rows;
        entry.2 += g.bytes;
    }
    println!("{:<22} {:>6} {:>10} {:>10}", "protocol", "files", "samples", "MB");
    for (protocol, (files, rows, bytes)) in &by_protocol {
        println!(
            "{protocol:<22} {files:>6} {rows:>10} {:>10.2}",
            *bytes as f64 / 1e6
        );
    }
    println!(
        "{:<22} {:>6} {:>10} {:>10.2}",
        "total",
        summary.files.len(),
        summary.total_rows(),
        summary.total_bytes() as f64 / 1e6
    );
    println!(
        "wrote {} (seed {}) in {:.2} s",
        args.out.display(),
        args.seed,
        elapsed.as_secs_f64()
    );
    Ok(())
}
