//! The haptic loop's watchdog ending a stalled session, a part of one, or a loop benchmark.

use super::*;

/// Stops process `pid` (SIGSTOP) for `how_long`, then lets it go on (SIGCONT): every thread of
/// it, the haptic loop and its watchdog included, stalls at once.
fn stall(pid: u32, how_long: std::time::Duration) {
    let signal = |name: &str| {
        let sent = std::process::Command::new("kill")
            .args([name, &pid.to_string()])
            .status();
        assert!(sent.unwrap().success(), "kill {name} {pid}");
    };
    signal("-STOP");
    std::thread::sleep(how_long);
    signal("-CONT");
}

/// `palpus run --headless ARGS` without a display, stalled ([`stall`]) for 2 s once `after`
/// has passed since its first line: that line, the rest of its output, and how it ended.
fn stalled_headless_run(
    args: &[&str],
    cache: &Path,
    after: std::time::Duration,
) -> (String, String, std::process::Output) {
    use std::io::{BufRead, BufReader};
    use std::process::Stdio;
    let mut child = palpus_at_root("run", &[&["--headless"], args].concat(), cache)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdout = BufReader::new(child.stdout.take().unwrap());
    let mut first = String::new();
    stdout.read_line(&mut first).unwrap();
    std::thread::sleep(after);
    stall(child.id(), std::time::Duration::from_secs(2));
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut stdout, &mut rest).unwrap();
    (first, rest, child.wait_with_output().unwrap())
}

#[test]
fn a_part_the_watchdog_ended_ends_the_session_there() {
    let _one = serial();
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let scene = "scenes/friction_hard_soft.toml";
    // The models are identified and cached first, so that the stop below lands in the loop.
    run_unpaced(&[scene, "--duration", "0.2"], &dir.path().join("warm"), &cache);
    let report_dir = dir.path().join("report");
    // 1.5 s into the first part (the plate), of 4 s.
    let (first, rest, o) = stalled_headless_run(
        &[scene, "--duration", "4", "--report", report_dir.to_str().unwrap()],
        &cache,
        std::time::Duration::from_millis(1500),
    );
    assert!(first.contains("(2 parts)"), "{first}");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{first}{rest}{stderr}");
    assert!(
        rest.contains("part `plate` ended early: the session stops after 1 of 2 parts"),
        "{rest}"
    );
    let r = report(&report_dir);
    let segments = r["segments"].as_array().unwrap();
    assert_eq!(segments.len(), 1, "the sponge was not run: {r}");
    assert_eq!(segments[0]["object"], "plate");
}

#[test]
fn a_session_the_watchdog_ended_exits_3_and_names_its_recording() {
    let _one = serial();
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    // The model is identified and cached first, so that the stop below lands in the loop.
    run_unpaced(&["--duration", "0.2"], &dir.path().join("warm"), &cache);
    let target = dir.path().join("session.csv");
    // 2.5 s in, the scripted needle is in the liver, pressing on it.
    let report_dir = dir.path().join("report");
    let (first, rest, o) = stalled_headless_run(
        &[
            "--duration",
            "6",
            "--record",
            target.to_str().unwrap(),
            "--report",
            report_dir.to_str().unwrap(),
        ],
        &cache,
        std::time::Duration::from_millis(2500),
    );
    assert!(first.starts_with("running scene"), "{first}");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{first}{rest}{stderr}");
    let partial = format!("{}.partial", target.display());
    assert!(
        stderr.contains("stalled") && stderr.contains(&partial),
        "the error names the stall and the recording: {stderr}"
    );
    assert!(
        !target.exists(),
        "a session that ended early does not stand in for a whole one"
    );
    assert!(Path::new(&partial).exists());
    assert!(
        dir.path().join("report/report.json").exists(),
        "the report is written first"
    );
    // The simulated Omega.7's own watchdog, armed at the software watchdog's period (250 ms
    // for a simulator, held to the 255 × 125 µs an Omega.7's allows), saw the 2 s silence: the
    // report says what the device would have held, and for how long.
    let report: Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("report/report.json")).unwrap()).unwrap();
    let w = &report["segments"][0]["device_watchdog"];
    assert_eq!(w["period_ms"].as_f64(), Some(31.875), "{w}");
    assert!(w["trips"].as_u64().unwrap() >= 1, "{w}");
    assert!(w["longest_silence_ms"].as_f64().unwrap() > 1900.0, "{w}");
    assert!(
        w["held_force_n"].as_f64().unwrap() > 0.05,
        "in tissue, a force was held: {w}"
    );
    assert!(rest.contains("device watchdog armed at 31.875 ms"), "{rest}");
}

#[test]
fn a_loop_benchmark_the_watchdog_ended_exits_3() {
    let _one = serial();
    let child = common::palpus_command()
        .args(["bench", "loop", "--seconds", "4", "--no-realtime"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    stall(child.id(), std::time::Duration::from_millis(500));
    let o = child.wait_with_output().unwrap();
    let printed = text(&o);
    assert_eq!(o.status.code(), Some(3), "{printed}");
    assert!(
        printed.contains("ended early") && printed.contains("stalled"),
        "{printed}"
    );
}
