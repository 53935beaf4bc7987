//! `palpus capture --out FILE` killed mid-recording keeps the FILE it was to replace, and what it
//! recorded is in FILE.partial, readable as a capture.

#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use std::process::Stdio;
use std::time::{Duration, Instant};

use crate::common::{succeeds, text};
use capture::{Capture, CaptureKind};
use haptics::{partial_path, read_recording};

#[test]
fn a_killed_capture_keeps_the_old_file_and_leaves_a_readable_partial_one() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("needle.csv");
    let out_arg = out.to_str().unwrap();
    let capture = [
        "capture",
        "--device",
        "sim",
        "--protocol",
        "needle",
        "--out",
        out_arg,
    ];
    succeeds(&[&capture[..], &["--unpaced", "--quiet"]].concat());
    let old = std::fs::read(&out).unwrap();
    let old_rows = Capture::read_file(&out, CaptureKind::Insertion).unwrap().len();

    // The same capture in real time, killed (SIGKILL) once it has been recording for a while.
    // On a shared machine the haptic thread's watchdog can end a real-time capture on its own
    // (the loop descheduled several times in a second); that run says nothing about a kill, so
    // it is tried again, a few times at most.
    let partial = partial_path(&out);
    let mut attempts = 0;
    while let Err(stalled) = record_then_kill(&capture, &partial) {
        attempts += 1;
        assert!(
            attempts < 3 && stalled.contains("the haptic thread stalled"),
            "the capture ended before it was killed: {stalled}"
        );
    }

    assert_eq!(std::fs::read(&out).unwrap(), old, "the old capture changed");
    let bytes = std::fs::read(&partial).unwrap();
    assert_eq!(
        bytes.last(),
        Some(&b'\n'),
        "the partial capture ends on a whole line"
    );
    let recording = read_recording(&partial).unwrap();
    assert!(!recording.truncated);
    let killed = Capture::read_file(&partial, CaptureKind::Insertion).unwrap();
    assert!(
        !killed.is_empty() && killed.len() < old_rows,
        "{} rows in the partial capture, {old_rows} in the whole one",
        killed.len()
    );
    assert_eq!(killed.metadata().get("force_source"), Some("rfob"));

    // Running it again to the end replaces the old capture and leaves no partial file.
    succeeds(&[&capture[..], &["--unpaced", "--quiet"]].concat());
    assert!(!partial.exists());
    assert_eq!(
        Capture::read_file(&out, CaptureKind::Insertion).unwrap().len(),
        old_rows
    );
}

/// Runs `capture` in real time and kills it (SIGKILL) once its partial file has held rows for a
/// second; `Err` with its output when it ended on its own first.
fn record_then_kill(capture: &[&str], partial: &std::path::Path) -> Result<(), String> {
    // A stalled attempt's partial file would show rows before this run has recorded any.
    let _ = std::fs::remove_file(partial);
    let mut child = crate::common::palpus_command()
        .args(capture)
        .arg("--quiet")
        .env_remove("PALPUS_DHD_LIBRARY")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let started = Instant::now();
    let mut rows_seen_at = None;
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            let o = child.wait_with_output().unwrap();
            return Err(format!("({status}) {}", text(&o)));
        }
        let rows = read_recording(partial).map_or(0, |r| r.rows.len());
        if rows > 0 && rows_seen_at.is_none() {
            rows_seen_at = Some(Instant::now());
        }
        if rows_seen_at.is_some_and(|t| t.elapsed() >= Duration::from_secs(1)) {
            break;
        }
        assert!(
            started.elapsed() < Duration::from_secs(60),
            "no rows recorded in 60 s"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    Ok(())
}
