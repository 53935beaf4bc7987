//! A recording process killed with SIGKILL loses nothing it had flushed.
//!
//! The test runs this very test binary again as a child (`recorder_child`, which does nothing
//! unless `PALPUS_RECORDER_CHILD` names a file): the child records a 1 kHz haptic loop and
//! prints how many rows the recorder has flushed; the parent kills it mid-run and reads the
//! partial file back.

#![allow(clippy::unwrap_used)]

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use capture::{CaptureKind, Metadata};
use haptics::rt::{self, HapticSample, LoopConfig, LoopIo, RtRequest, ZeroForce};
use haptics::{RecorderConfig, partial_path, read_recording, record_to_file};
use haptics::{SimOmega7, SimOmega7Config, SimWorld};

const CHILD_ENV: &str = "PALPUS_RECORDER_CHILD";

/// `name`, a test of this module, as the harness names it: the module path less the binary's.
fn own_test(name: &str) -> String {
    let path = module_path!();
    format!(
        "{}::{name}",
        path.split_once("::").map_or(path, |(_, module)| module)
    )
}

fn row(s: &HapticSample, row: &mut Vec<f64>) -> bool {
    // The tick in two columns so a reader can check that no row is missing or altered.
    row.extend([s.time_s, s.tick as f64 * 1e-6, (s.tick % 7) as f64]);
    true
}

#[test]
fn recorder_child() {
    let Ok(path) = std::env::var(CHILD_ENV) else {
        return;
    };
    let meta =
        Metadata::new(CaptureKind::Insertion, "sim-omega7", 1000.0).with("protocol", "recorder_kill_test");
    let (producer, recorder) = record_to_file(
        path.as_ref(),
        &meta,
        &["time_s", "depth_m", "axial_force_n"],
        row,
        RecorderConfig::default(),
    )
    .unwrap();
    let io = LoopIo {
        samples: Some(producer),
        live: None,
    };
    let config = LoopConfig {
        rt: RtRequest::NONE,
        watchdog: None,
        ..LoopConfig::default()
    };
    let _handle = rt::spawn(
        SimOmega7::new(SimOmega7Config::default(), SimWorld::Free),
        ZeroForce,
        io,
        config,
    )
    .unwrap();
    loop {
        std::thread::sleep(Duration::from_millis(10));
        println!("flushed {}", recorder.stats().rows_flushed());
    }
}

#[test]
fn every_flushed_sample_survives_sigkill() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("killed.csv");
    let mut child = Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            &own_test("recorder_child"),
            "--nocapture",
            "--test-threads=1",
        ])
        .env(CHILD_ENV, &path)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let stdout = child.stdout.take().unwrap();
    let started = Instant::now();
    let mut flushed = 0u64;
    for line in BufReader::new(stdout).lines() {
        let line = line.unwrap();
        if let Some(n) = line.strip_prefix("flushed ") {
            flushed = n.trim().parse().unwrap();
        }
        if flushed >= 700 || started.elapsed() > Duration::from_secs(60) {
            break;
        }
    }
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    assert!(flushed >= 700, "the child flushed only {flushed} rows");

    // A killed recording never reached its target: its rows are under the partial name.
    let recording = read_recording(&partial_path(&path)).unwrap();
    let rows = &recording.rows;
    println!(
        "child killed after {flushed} flushed rows; {} whole rows in the file{}",
        rows.len(),
        if recording.truncated {
            ", last line cut"
        } else {
            ""
        }
    );
    assert!(rows.len() as u64 >= flushed);
    assert_eq!(recording.metadata.get("protocol"), Some("recorder_kill_test"));
    for (k, r) in rows.iter().enumerate() {
        assert_eq!(r[1], k as f64 * 1e-6, "row {k}");
        assert_eq!(r[2], (k % 7) as f64, "row {k}");
        assert!((r[0] - k as f64 * 1e-3).abs() < 1e-9, "row {k}");
    }
}
