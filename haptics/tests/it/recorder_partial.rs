//! A recording into an existing file replaces it only when it finishes: until then the rows
//! go to the partial file beside it, and a recording that never finishes leaves the old file
//! as it was.

#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use std::path::Path;
use std::time::{Duration, Instant};

use capture::kind::{AXIAL_FORCE_N, DEPTH_M, TIME_S};
use capture::{Capture, CaptureErrorKind, CaptureKind, Metadata};
use haptics::HapticsError;
use haptics::rt::HapticSample;
use haptics::{RecorderConfig, partial_path, read_recording, record_to_file};

const COLUMNS: &[&str] = &[TIME_S, DEPTH_M, AXIAL_FORCE_N];

fn meta(run: &str) -> Metadata {
    Metadata::new(CaptureKind::Insertion, "sim-omega7", 1000.0).with("protocol", run)
}

fn row(s: &HapticSample, row: &mut Vec<f64>) -> bool {
    row.extend([s.time_s, s.tick as f64 * 1e-6, (s.tick % 7) as f64]);
    true
}

fn sample(tick: u64) -> HapticSample {
    HapticSample {
        tick,
        time_s: tick as f64 * 1e-3,
        ..HapticSample::default()
    }
}

/// Writes a finished recording of `rows` rows to `path` and returns its bytes.
fn good_recording(path: &Path, rows: u64) -> Vec<u8> {
    let (mut producer, recorder) =
        record_to_file(path, &meta("old"), COLUMNS, row, RecorderConfig::default()).unwrap();
    for tick in 0..rows {
        while producer.push(sample(tick)).is_err() {
            std::thread::yield_now();
        }
    }
    drop(producer);
    assert_eq!(recorder.finish().unwrap().1.rows, rows);
    std::fs::read(path).unwrap()
}

/// The names in `dir`, sorted.
fn entries(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn the_partial_file_is_named_after_the_target() {
    assert_eq!(
        partial_path(Path::new("out/run.csv")),
        Path::new("out/run.csv.partial")
    );
}

#[test]
fn a_finished_recording_replaces_the_target_and_leaves_no_partial_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.csv");
    let old = good_recording(&path, 300);
    assert_eq!(entries(dir.path()), ["run.csv"]);

    let new = good_recording(&path, 120);
    assert_ne!(new, old);
    assert_eq!(entries(dir.path()), ["run.csv"]);
    let c = Capture::read_file(&path, CaptureKind::Insertion).unwrap();
    assert_eq!(c.len(), 120);
}

/// The process dies mid-recording: the recorder is never finished (its handle forgotten, as a
/// kill leaves it) while its thread has flushed what it got.
#[test]
fn an_unfinished_recording_keeps_the_old_file_and_leaves_a_readable_partial_one() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.csv");
    let old = good_recording(&path, 300);

    let (mut producer, recorder) =
        record_to_file(&path, &meta("new"), COLUMNS, row, RecorderConfig::default()).unwrap();
    // The old file is untouched from the very start of the new recording.
    assert_eq!(std::fs::read(&path).unwrap(), old);
    for tick in 0..500 {
        while producer.push(sample(tick)).is_err() {
            std::thread::yield_now();
        }
    }
    let started = Instant::now();
    while recorder.stats().rows_flushed() < 500 {
        assert!(
            started.elapsed() < Duration::from_secs(30),
            "the recorder never flushed"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    std::mem::forget(recorder);

    // What a kill now would leave: the old file as it was, the new rows under the partial name.
    assert_eq!(std::fs::read(&path).unwrap(), old);
    let partial = partial_path(&path);
    assert_eq!(entries(dir.path()), ["run.csv", "run.csv.partial"]);
    let bytes = std::fs::read(&partial).unwrap();
    assert_eq!(
        bytes.last(),
        Some(&b'\n'),
        "the partial file ends on a whole line"
    );
    let r = read_recording(&partial).unwrap();
    assert!(!r.truncated);
    assert_eq!(r.rows.len(), 500);
    assert_eq!(r.metadata.get("protocol"), Some("new"));
    let c = Capture::read_file(&partial, CaptureKind::Insertion).unwrap();
    assert_eq!(c.len(), 500);

    // The haptic side going away ends the thread, which still does not touch the target.
    drop(producer);
    // The thread drains, flushes and finishes the file within a few milliseconds.
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(std::fs::read(&path).unwrap(), old);
    assert_eq!(entries(dir.path()), ["run.csv", "run.csv.partial"]);
    assert_eq!(
        Capture::read_file(&partial, CaptureKind::Insertion)
            .unwrap()
            .len(),
        500
    );
}

#[test]
fn a_recording_of_no_rows_fails_and_leaves_nothing_but_the_old_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.csv");
    let old = good_recording(&path, 10);
    let (producer, recorder) =
        record_to_file(&path, &meta("empty"), COLUMNS, row, RecorderConfig::default()).unwrap();
    drop(producer);
    let e = recorder.finish().unwrap_err();
    assert!(
        matches!(&e, HapticsError::Capture(c) if matches!(c.kind, CaptureErrorKind::NoSamples)),
        "{e}"
    );
    assert_eq!(std::fs::read(&path).unwrap(), old);
    assert_eq!(entries(dir.path()), ["run.csv"]);
}

#[test]
fn a_directory_target_is_refused_before_recording() {
    let dir = tempfile::tempdir().unwrap();
    let e = record_to_file(dir.path(), &meta("dir"), COLUMNS, row, RecorderConfig::default()).unwrap_err();
    assert!(e.to_string().contains("cannot create"), "{e}");
    assert!(entries(dir.path()).is_empty());
}

#[test]
fn an_abandoned_recording_keeps_the_old_file_and_all_its_rows_beside_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.csv");
    let old = good_recording(&path, 300);

    let (mut producer, recorder) =
        record_to_file(&path, &meta("failed"), COLUMNS, row, RecorderConfig::default()).unwrap();
    for tick in 0..200 {
        while producer.push(sample(tick)).is_err() {
            std::thread::yield_now();
        }
    }
    drop(producer);
    let (result, _) = recorder.abandon();
    assert_eq!(result.unwrap().1.rows, 200);
    assert_eq!(std::fs::read(&path).unwrap(), old);
    assert_eq!(entries(dir.path()), ["run.csv", "run.csv.partial"]);
    let partial = Capture::read_file(partial_path(&path), CaptureKind::Insertion).unwrap();
    assert_eq!(partial.len(), 200);
}
