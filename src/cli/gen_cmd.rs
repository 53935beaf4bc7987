//! `palpus gen`.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use sim::{CaptureSet, Variant, generate, generate_variant};

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
    /// wall), `phantom` (three membranes at other depths, with other parameters: a second
    /// tissue for held-out tests) or `epidural` (a lumbar epidural approach, skin to dura,
    /// inserted to 55 mm).
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
    /// Write only the multi-stream sliding study with this many trials of each surface (1-99;
    /// default 10): a study of a real one's size, e.g. 25 to train and 25 to test.
    #[arg(long, value_name = "N", conflicts_with_all = ["rub_speed_mps", "two_patch"])]
    slide_trials: Option<u32>,
    /// Write only the multi-stream sliding study, each trial sliding this long at its steady
    /// speed (default 4 s; at most 60).
    #[arg(long, value_name = "S", conflicts_with_all = ["rub_speed_mps", "two_patch"])]
    slide_s: Option<f64>,
    /// Write only the multi-stream sliding study on a rig with this fault: resonance (the
    /// vibration sensor's mount rings at about 160 Hz whatever the speed), drift (the force
    /// sensor's offset starts up to 0.1 N off and drifts up to 0.03 N/s) or noise-only (the
    /// vibration channel carries noise only). Everything else each trial draws is unchanged.
    #[arg(long, value_enum, conflicts_with_all = ["rub_speed_mps", "two_patch"])]
    rig_effect: Option<RigEffectArg>,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum RigEffectArg {
    Resonance,
    Drift,
    NoiseOnly,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum NeedleTissueArg {
    Liver,
    Phantom,
    Epidural,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum NeedleSpeedArg {
    Constant,
    Varying,
}

/// The single set `args` asks for instead of the papers' full sets, if any.
fn variant(args: &GenArgs) -> Option<Variant> {
    use sim::li_bi::{NeedleProtocol, NeedleTissueKind, SpeedProfile};
    if args.needle_rate_hz.is_some() || args.needle_tissue.is_some() || args.needle_speed.is_some() {
        return Some(Variant::Needle(NeedleProtocol {
            log_rate_hz: args.needle_rate_hz.unwrap_or(100),
            rounds: args.needle_rounds,
            tissue: match args.needle_tissue {
                Some(NeedleTissueArg::Phantom) => NeedleTissueKind::LayeredPhantom,
                Some(NeedleTissueArg::Epidural) => NeedleTissueKind::LumbarEpidural,
                Some(NeedleTissueArg::Liver) | None => NeedleTissueKind::BovineLiver,
            },
            speed: match args.needle_speed {
                Some(NeedleSpeedArg::Varying) => SpeedProfile::Varying,
                _ => SpeedProfile::Constant,
            },
        }));
    }
    if args.two_patch {
        let speed_mps = args.rub_speed_mps.unwrap_or(sim::nakano::SPEED_MPS);
        return Some(Variant::TwoPatch { speed_mps });
    }
    if let Some(speed_mps) = args.rub_speed_mps {
        return Some(Variant::Rubbing { speed_mps });
    }
    if args.slide_speed_mps.is_none()
        && args.slide_trials.is_none()
        && args.slide_s.is_none()
        && args.rig_effect.is_none()
    {
        return None;
    }
    use sim::multistream::{RigEffect, SlidingStudy};
    let default = SlidingStudy::default();
    Some(Variant::Sliding(SlidingStudy {
        trials: args.slide_trials.unwrap_or(default.trials),
        speed_mps: args.slide_speed_mps.unwrap_or(default.speed_mps),
        slide_s: args.slide_s.unwrap_or(default.slide_s),
        rig: match args.rig_effect {
            None => RigEffect::None,
            Some(RigEffectArg::Resonance) => RigEffect::Resonance,
            Some(RigEffectArg::Drift) => RigEffect::Drift,
            Some(RigEffectArg::NoiseOnly) => RigEffect::NoiseOnly,
        },
    }))
}

pub(crate) fn run(args: &GenArgs) -> anyhow::Result<()> {
    if let Some(variant) = variant(args) {
        generate_variant(&args.out, args.seed, variant, &mut |file| {
            if !args.quiet {
                println!(
                    "wrote {} ({} rows)",
                    args.out.join(&file.path).display(),
                    file.rows
                );
            }
        })
        .with_context(|| format!("writing into {}", args.out.display()))?;
        return Ok(());
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
