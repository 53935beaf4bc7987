//! `palpus run` end to end, one test binary apart from `tests/it` so that nothing else runs
//! beside its rate checks: the default needle scene in real time as README's first command runs
//! it and the record → identify → run loop (`needle`), the rubbing scenes (`rubbing`), the
//! window and `palpus render` (`rendering`), the watchdog ending a stalled session
//! (`watchdog`), and trainees' attempts, scores and history (`training`). The helpers below
//! run the binary and read what it wrote.
#![allow(clippy::unwrap_used)]

#[path = "../common/mod.rs"]
mod common;

mod needle;
mod rendering;
mod rubbing;
mod training;
mod watchdog;

use std::path::{Path, PathBuf};

use common::text;
use identify::ModelFile;
use serde_json::Value;

/// The tests here run haptic loops and renderers. Those that time something (a loop's rate
/// in real time, a watchdog's stall) run alone, so that the 1 % rate check measures the loop
/// and not a neighbouring test hogging the cores; those that run unpaced may share the cores
/// with each other.
static CORES: std::sync::RwLock<()> = std::sync::RwLock::new(());

/// The cores to this test alone.
fn serial() -> std::sync::RwLockWriteGuard<'static, ()> {
    CORES.write().unwrap_or_else(|e| e.into_inner())
}

/// The cores shared with other untimed tests, never with a timed one.
fn untimed() -> std::sync::RwLockReadGuard<'static, ()> {
    CORES.read().unwrap_or_else(|e| e.into_inner())
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// `palpus SUBCOMMAND ARGS` in the repository root, with a private model cache.
fn palpus_at_root(subcommand: &str, args: &[&str], cache: &Path) -> std::process::Command {
    let mut command = common::palpus_command();
    command
        .arg(subcommand)
        .args(args)
        .current_dir(root())
        .env("PALPUS_CACHE_DIR", cache);
    command
}

/// Runs `palpus run ARGS` with a private model cache and no display.
fn run(args: &[&str], cache: &Path) -> std::process::Output {
    palpus_at_root("run", args, cache)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap()
}

/// Runs `palpus run ARGS --headless --unpaced --report OUT` with a private model cache, checks
/// that it succeeded, and returns its report.
fn run_unpaced(args: &[&str], out: &Path, cache: &Path) -> Value {
    let report_args = ["--headless", "--unpaced", "--report", out.to_str().unwrap()];
    let o = run(&[args, &report_args[..]].concat(), cache);
    assert!(o.status.success(), "{}", text(&o));
    report(out)
}

/// The summary a run wrote.
fn printed_layers(dir: &Path) -> String {
    std::fs::read_to_string(dir.join("summary.txt")).unwrap()
}

/// The default scene, its paths absolute and without budgets, with `model_source` (a
/// `capture = …` or `file = …` line) in place of its model's capture, and without its goal: the
/// goal names the two membranes of the default model, and another model may find more.
fn needle_scene_with(model_source: &str) -> String {
    let text = std::fs::read_to_string(root().join("scenes/needle_liver.toml")).unwrap();
    let text = text.split("\n[task.goal]").next().unwrap_or_default();
    common::without_budgets(text)
        .replace("../", &format!("{}/", root().display()))
        .lines()
        .map(|l| {
            if l.starts_with("capture = ") {
                model_source.to_owned()
            } else {
                l.to_owned()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn report(dir: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap()
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// The report of a real-time run whose first segment kept the loop's rate within
/// `rate_tolerance`, measured again (up to five runs in all, seconds apart) while that segment
/// shows ticks over 2 ms late. A virtual machine is sometimes descheduled for a hundred
/// milliseconds or more, now and then for minutes on end: the loop then skips the slots it
/// missed, and its mean rate says what the machine did rather than what the loop did. Of the
/// runs measured, the one least disturbed is judged: the fewest late ticks, then the rate
/// closest to nominal.
///
/// An undisturbed run must hold its mean rate to the tolerance. When every run was disturbed,
/// the loop is judged on its own part, and the note says so: its deadlines (the ticks run plus
/// the slots skipped, over the same span) at the nominal rate within the tolerance, which a
/// loop that set each deadline from a late wake-up would miss; its own work per tick (p99)
/// within half a period, which a tick that blocked or computed too long would miss; and at
/// least nine slots in ten kept, without which the run measured nothing.
fn real_time_report(rate_tolerance: f64, attempt: impl Fn() -> Value) -> Value {
    // Gigabytes of build output may still be waiting to be written back: flush them first, so
    // the kernel's writeback does not compete with the loop being measured.
    let settle = || {
        let _ = std::process::Command::new("sync").status();
    };
    let disturbance = |r: &Value| {
        let seg = &r["segments"][0];
        (f(&seg["late_over_2ms"]), f(&seg["rate_error"]))
    };
    settle();
    let mut best = attempt();
    // A shared machine's slow spells last tens of seconds: five tries, seconds apart.
    for _ in 1..5 {
        let (late, rate_error) = disturbance(&best);
        if late == 0.0 {
            break;
        }
        eprintln!(
            "the machine stalled during the run ({late} ticks over 2 ms late, rate error {rate_error:.4} against {rate_tolerance}); measuring again"
        );
        std::thread::sleep(std::time::Duration::from_secs(5));
        settle();
        let r = attempt();
        if disturbance(&r) < disturbance(&best) {
            best = r;
        }
    }
    let seg = &best["segments"][0];
    if f(&seg["late_over_2ms"]) == 0.0 {
        assert!(f(&seg["rate_error"]) < rate_tolerance, "{seg}");
    } else {
        eprintln!(
            "every run was disturbed by the machine; the least disturbed ({} ticks over 2 ms late, {} slots skipped, mean rate error {:.4}) is judged on the loop's deadlines and work",
            seg["late_over_2ms"],
            seg["missed_slots"],
            f(&seg["rate_error"])
        );
        let period_us = 1e6 / f(&seg["nominal_rate_hz"]);
        assert!(f(&seg["deadline_rate_error"]) < rate_tolerance, "{seg}");
        assert!(f(&seg["compute_p99_us"]) < period_us / 2.0, "{seg}");
        assert!(f(&seg["rate_error"]) < 0.1, "{seg}");
    }
    best
}
