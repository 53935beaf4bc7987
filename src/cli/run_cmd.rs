//! `palpus run`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use clap::Args;

use super::device_arg::parse_device;
use crate::attempt;
use crate::exit::EndedEarly;
use crate::models;
use crate::scene::{DEFAULT_SCENE, Scene, SceneOverride};
use crate::session::report::{self, ModelLine, SessionReport};
use crate::session::{self, SessionOptions, analysis};
use haptics::DeviceChoice;
use haptics::partial_path;

/// Run a scene: identify or load the models it needs, render them on the haptic thread, show
/// the tissue, report.
///
/// With a display (and without --headless) a window opens: drag with the mouse or scroll to
/// move the simulated hand, the overlay shows live force, the recognized surface and the loop
/// rate. Without one, or with --headless, a scripted trainee performs the scene's task and a
/// report folder is written: force plots, a rendered frame, loop statistics, the recognized
/// surface timeline, and the summary printed here.
///
/// A part of the session that ended early still gets its report, the parts after it are not
/// run, and then palpus exits 3 when the haptic thread stalled and the watchdog released the
/// force, 4 when the device failed, 5 on another early end; with --record, the error names the
/// FILE.partial the part left.
#[derive(Debug, Args)]
pub(crate) struct RunArgs {
    /// The scene file.
    #[arg(default_value = DEFAULT_SCENE)]
    scene: PathBuf,
    /// The device: sim (the simulated Omega.7), omega7[:PATH] (a Force Dimension Omega.7, PATH
    /// its SDK library, default $PALPUS_DHD_LIBRARY, then libdhd.so), or replay:FILE (a capture
    /// played back as the device's motion). Default: the scene's `[device] kind`.
    #[arg(long, value_name = "NAME[:OPTION]", value_parser = parse_device)]
    device: Option<DeviceChoice>,
    /// No window: the scripted trainee performs the task.
    #[arg(long)]
    headless: bool,
    /// Stop each part of the task after this many seconds.
    #[arg(long, value_name = "S")]
    duration: Option<f64>,
    /// Record the session as a capture (rubbing scenes: one file per surface). Each file is
    /// written as FILE.partial and renamed to FILE when its part of the session ends: an
    /// existing FILE is replaced, as every palpus output is (no --force), but only by a
    /// finished recording. A session that fails or is killed leaves FILE as it was and what
    /// it recorded in FILE.partial.
    #[arg(long, value_name = "FILE")]
    record: Option<PathBuf>,
    /// Replace a value of the scene file for this run (repeatable): a dotted key and a TOML
    /// value, such as `--set task.depth_m=0.026` or `--set 'task.goal.stop_after="capsule"'`.
    /// The scene is validated with it as if the file said it.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<SceneOverride>,
    /// Who is training: each scored attempt (a scene with a `[task.goal]`) is stored in the
    /// history under this name (default: $USER).
    #[arg(long, value_name = "NAME")]
    trainee: Option<String>,
    /// The history database scored attempts are added to (default: $PALPUS_HISTORY, else
    /// history.sqlite under $XDG_DATA_HOME/palpus or ~/.local/share/palpus).
    #[arg(long, value_name = "FILE")]
    history: Option<PathBuf>,
    /// Where the report goes (default: out/run/SCENE).
    #[arg(long, value_name = "DIR")]
    report: Option<PathBuf>,
    /// Where identified models are cached (default: $PALPUS_CACHE_DIR, else ~/.cache/palpus).
    #[arg(long, value_name = "DIR")]
    cache_dir: Option<PathBuf>,
    /// Simulator only: run as fast as possible instead of in real time.
    #[arg(long)]
    unpaced: bool,
    /// In a window on the simulator: the scripted trainee performs the task instead of the
    /// mouse (a demonstration, and how the window is tested under Xvfb).
    #[arg(long)]
    autopilot: bool,
}

/// Whether a window can be opened here.
pub(crate) fn has_display() -> bool {
    ["DISPLAY", "WAYLAND_DISPLAY"]
        .iter()
        .any(|v| std::env::var_os(v).is_some_and(|x| !x.is_empty()))
}

pub(crate) fn run(args: &RunArgs) -> anyhow::Result<()> {
    let started = Instant::now();
    let scene = Scene::load_with(&args.scene, &args.set)?;
    if let Some(d) = args.duration
        && !(d.is_finite() && d > 0.0)
    {
        anyhow::bail!("--duration {d}: expected a positive number of seconds");
    }
    let device = match &args.device {
        Some(device) => device.clone(),
        None => scene.device_choice()?,
    };
    if args.unpaced && !device.backend().simulated {
        anyhow::bail!("--unpaced is for the simulator only: a real device runs in real time");
    }
    // Read before the session, so that a bad reference is reported before anyone practises.
    let reference = match scene.task.goal().and_then(|g| g.reference.as_ref()) {
        Some(file) => Some(
            attempt::read_reference(&scene.resolve(file))
                .with_context(|| format!("{}: task.goal.reference", scene.path.display()))?,
        ),
        None => None,
    };
    let cache_dir = args.cache_dir.clone().unwrap_or_else(models::default_cache_dir);
    let resolved = models::resolve_with_progress(&scene, &cache_dir)?;
    let options = SessionOptions {
        device,
        duration_s: args.duration,
        record: args.record.clone(),
        pacing: if args.unpaced {
            haptics::rt::Pacing::Unpaced
        } else {
            haptics::rt::Pacing::REALTIME
        },
        autopilot: args.autopilot,
    };
    let segments = session::segments(&scene, &resolved)?;
    attempt::check_goal_layers(&scene, &segments)?;
    let segment_count = segments.len();
    let headless = args.headless || !has_display();
    let dir = |scene: &Scene| {
        args.report
            .clone()
            .unwrap_or_else(|| Path::new("out").join("run").join(&scene.name))
    };
    let (scene, runs, recognition, recognizer_line) = if headless {
        println!(
            "running scene {} headless on {} ({} part{}) ...",
            scene.name,
            options.device.label(),
            segments.len(),
            if segments.len() == 1 { "" } else { "s" }
        );
        let mut runs = Vec::new();
        let mut recognition = Vec::new();
        let recognizer = crate::recognizer::SceneRecognizer::for_scene(&scene)?;
        for segment in &segments {
            let live = recognizer.as_ref().map(crate::recognizer::SceneRecognizer::live);
            let run = session::run_segment(&scene, segment, segments.len(), &options, None, live)
                .with_context(|| format!("running {}", segment.object))?;
            if let Some(r) = &recognizer {
                recognition.extend(r.recognize(&run));
            }
            let ended_early = run.outcome.is_err();
            runs.push(run);
            // A stall or a device fault ends the session: the parts after it would run on a
            // device that just failed, for a session that can no longer count.
            if ended_early && runs.len() < segments.len() {
                println!(
                    "part `{}` ended early: the session stops after {} of {} parts",
                    segment.object,
                    runs.len(),
                    segments.len()
                );
                break;
            }
        }
        let line = recognizer.as_ref().map(crate::recognizer::SceneRecognizer::line);
        (scene, runs, recognition, line)
    } else {
        println!(
            "running scene {} in a window on {}: drag or scroll to push the tool, arrows/WASD to move it, F12 for a screenshot",
            scene.name,
            options.device.label()
        );
        let screenshot = dir(&scene).join("window.png");
        std::fs::create_dir_all(dir(&scene))
            .with_context(|| format!("creating {}", dir(&scene).display()))?;
        let outcome = crate::window::run(
            scene.clone(),
            segments,
            options.clone(),
            cache_dir,
            Some(screenshot),
        )?;
        (
            outcome.scene.unwrap_or(scene),
            outcome.runs,
            outcome.recognition,
            outcome.recognizer,
        )
    };
    if runs.is_empty() {
        anyhow::bail!("the session ran no part of the scene");
    }
    let dir = dir(&scene);
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    crate::plots::write_force_plot(&dir.join("force.png"), &runs)?;
    let frame = crate::view::render_session_frame(&scene, &runs, &recognition, &dir.join("frame.png"));
    // A report folder holds one session: nothing of an earlier one may remain beside it.
    let stale: &[&str] = if frame.is_ok() {
        &["frame.txt"]
    } else {
        &["frame.png", "frame_inserted.png"]
    };
    for name in stale.iter().chain(if recognition.is_empty() {
        &["timeline.csv"][..]
    } else {
        &[][..]
    }) {
        let _ = std::fs::remove_file(dir.join(name));
    }
    if let Err(why) = &frame {
        let path = dir.join("frame.txt");
        capture::write_atomically(&path, |w| {
            use std::io::Write;
            writeln!(w, "no frame could be rendered: {why}")
        })
        .with_context(|| format!("writing {}", path.display()))?;
    }
    let named = recognition.iter().filter(|r| r.label.is_some()).count();
    let accuracy = (named > 0).then(|| {
        recognition
            .iter()
            .filter(|r: &&report::Recognition| r.label.as_ref() == Some(&r.truth))
            .count() as f64
            / named as f64
    });
    let timing = crate::recognizer::timings(&runs, &recognition);
    let segments: Vec<analysis::SegmentSummary> = runs.iter().map(analysis::summarize).collect();
    let attempts = attempt::attempts(&scene, &runs);
    attempt::write_plot(
        &dir.join("attempt.png"),
        &runs,
        attempts.last(),
        reference.as_ref(),
    )?;
    let report = SessionReport {
        scene: scene.name.clone(),
        scene_file: scene.path.clone(),
        device: runs
            .first()
            .map_or_else(|| options.device.label(), |r| r.device.clone()),
        models: resolved.iter().map(ModelLine::new).collect(),
        segments,
        recognizer: recognizer_line,
        recognition,
        recognition_accuracy: accuracy,
        recognition_timing: timing,
        recognition_unread_windows: runs
            .iter()
            .flat_map(|r| &r.samples)
            .filter(|s| s.flags & haptics::flag::RECOGNIZER_WINDOW_UNREAD != 0)
            .count(),
        frame,
        recorded: runs.iter().filter_map(|r| r.recorded.clone()).collect(),
        score: attempts.last().map(|a| a.score.clone()),
        attempts: attempts.into_iter().map(|a| a.score).collect(),
        wall_s: started.elapsed().as_secs_f64(),
    };
    report::write_summary(&dir, &report)?;
    print!("{}", report.to_text());
    println!("report in {}", dir.display());
    // An attempt the session cut short (a stall, a device fault) says nothing of the trainee.
    if !runs.iter().any(|r| r.outcome.is_err()) {
        let path = args.history.clone().unwrap_or_else(crate::history::default_path);
        let trainee = attempt::trainee(args.trainee.as_deref());
        for score in &report.attempts {
            let number = attempt::store(&path, &trainee, &scene, &resolved, &report.device, score)?;
            println!(
                "attempt {number} stored for {trainee} in {} (palpus history --trainee {trainee})",
                path.display()
            );
        }
    }
    match runs
        .iter()
        .find_map(|r| r.outcome.as_ref().err().map(|end| (r, end)))
    {
        Some((run, end)) => {
            let partial = options
                .record
                .as_ref()
                .map(|f| partial_path(&session::record_path(f, &run.segment.object, segment_count)))
                .filter(|p| p.exists());
            Err(EndedEarly::new(
                format!("the session's part `{}`", run.segment.object),
                end,
                partial.as_deref(),
            )
            .into())
        }
        None => Ok(()),
    }
}
