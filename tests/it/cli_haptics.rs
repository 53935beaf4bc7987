//! `palpus capture`, `palpus devices` and `palpus bench loop` as a user meets them.

#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use crate::common::{fails, palpus, text};

use capture::{Capture, CaptureKind};

/// Runs `palpus ARGS`, checks that it succeeded and printed each of `needles`; returns what it
/// printed.
fn succeeds_saying(args: &[&str], needles: &[&str]) -> String {
    let o = palpus(args);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    for needle in needles {
        assert!(t.contains(needle), "`{needle}` missing from:\n{t}");
    }
    t
}

#[test]
fn devices_reports_none_found_and_succeeds() {
    let t = succeeds_saying(
        &["devices"],
        &[
            "Haptic devices (--device NAME[:OPTION]):",
            "  sim      simulated Omega.7",
            "  omega7   Force Dimension Omega.7",
            "  replay   replay of a capture",
            "USB (vendor 1451)",
            "HID devices:",
        ],
    );
    // No hardware and no SDK here: each says so plainly.
    assert!(t.contains("none found") || t.contains("connected"), "{t}");
    assert!(t.contains("SDK: not found") || t.contains("SDK: "), "{t}");
    // An SDK named through the device's option is the one tried.
    let t = succeeds_saying(
        &["devices", "--device", "omega7:/nonexistent/libdhd.so"],
        &["SDK: not found", "/nonexistent/libdhd.so"],
    );
    assert!(!t.contains("libdhd.so.3"), "{t}");
}

#[test]
fn a_device_outside_the_registry_is_refused_naming_every_device() {
    for (device, reason) in [
        ("phantom", "no device of that name"),
        ("sim:fast", "this device takes no option"),
        ("replay", "this device needs its FILE"),
    ] {
        for command in [
            &["run", "--headless"][..],
            &["capture", "--protocol", "needle", "--out", "x.csv"][..],
        ] {
            let args = [command, &["--device", device]].concat();
            let t = fails(&args);
            assert!(
                t.contains(reason) && t.contains("sim, omega7[:PATH], replay:FILE"),
                "{args:?}: {t}"
            );
        }
    }
    let t = fails(&[
        "capture",
        "--device",
        "replay:x.csv",
        "--protocol",
        "needle",
        "--out",
        "x.csv",
    ]);
    assert!(t.contains("a protocol needs a device it can move"), "{t}");
}

#[test]
fn capture_on_the_simulator_writes_a_valid_capture() {
    let dir = tempfile::tempdir().unwrap();
    for (protocol, kind) in [
        ("needle", CaptureKind::Insertion),
        ("rubbing", CaptureKind::Rubbing),
    ] {
        let out = dir.path().join(format!("{protocol}.csv"));
        let o = palpus(&[
            "capture",
            "--device",
            "sim",
            "--protocol",
            protocol,
            "--out",
            out.to_str().unwrap(),
            "--unpaced",
        ]);
        assert!(o.status.success(), "{}", text(&o));
        assert!(text(&o).contains("rows to"), "{}", text(&o));
        let c = Capture::read_file(&out, kind).unwrap();
        assert!(c.len() > 1000);
        assert_eq!(c.metadata().get("force_source"), Some("rfob"));
    }
}

#[test]
fn capture_errors_are_clear() {
    let o = palpus(&[
        "capture",
        "--device",
        "omega7",
        "--protocol",
        "needle",
        "--out",
        "x.csv",
    ]);
    assert!(!o.status.success());
    let t = text(&o);
    assert!(
        t.starts_with("error: opening Force Dimension Omega.7")
            && t.contains("the Force Dimension SDK (libdhd, version 3 or newer) was not found")
            && t.contains("install it, or run on the simulated device (--device sim)"),
        "{t}"
    );
    for (choice, message) in [
        (&["--protocol", "stab"][..], "unknown protocol `stab`"),
        (
            &["--protocol", "rubbing", "--surface", "glass"][..],
            "unknown surface `glass`",
        ),
    ] {
        let args = [&["capture", "--device", "sim"], choice, &["--out", "x.csv"]].concat();
        let o = palpus(&args);
        assert!(!o.status.success());
        assert!(text(&o).contains(message), "{}", text(&o));
    }
}

#[test]
fn bench_loop_reports_the_figures() {
    let args = ["bench", "loop", "--seconds", "0.3"];
    let figures = [
        "mean rate:",
        "period error:",
        "p99.9",
        "overruns:",
        "tick compute:",
        "scheduling:",
    ];
    // A virtual machine is now and then descheduled for tens of milliseconds, and the loop's
    // watchdog then ends the benchmark (exit 3, its figures printed): measured again, seconds
    // apart, up to five runs in all, as `tests/run` measures its real-time sessions. A loop
    // that stalls on every run still fails here.
    let mut o = palpus(&args);
    for _ in 1..5 {
        if o.status.code() != Some(3) {
            break;
        }
        let t = text(&o);
        assert!(t.contains("ended early") && t.contains("stalled"), "{t}");
        eprintln!("the machine stalled during the loop benchmark; measuring again:\n{t}");
        std::thread::sleep(std::time::Duration::from_secs(5));
        o = palpus(&args);
    }
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    for figure in figures {
        assert!(t.contains(figure), "`{figure}` missing from:\n{t}");
    }
    let o = palpus(&["bench", "loop", "--seconds", "-1"]);
    assert!(!o.status.success());
}
