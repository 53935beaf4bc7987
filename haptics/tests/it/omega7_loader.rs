//! The Omega.7 backend against a fake `libdhd` built from `tests/fake_dhd/fake_dhd.c` with the
//! system C compiler (`$CC`, else `cc`): symbol lookup, availability flags, the C calling
//! convention in both directions, and the error paths.

#![allow(clippy::unwrap_used)]

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;

use glam::DVec3;
use haptics::HapticsError;
use haptics::rt::{self, LoopConfig, LoopIo, StopReason, ZeroForce};
use haptics::{DhdLibrary, Omega7};
use haptics::{ForceCommand, HapticDevice};

fn build(dir: &Path, name: &str, defines: &[&str]) -> PathBuf {
    let source = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fake_dhd/fake_dhd.c");
    let out = dir.join(name);
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let status = Command::new(&cc)
        .args(["-shared", "-fPIC", "-O1", "-o"])
        .arg(&out)
        .arg(&source)
        .args(defines)
        .status()
        .unwrap_or_else(|e| panic!("cannot run the C compiler `{cc}`: {e}"));
    assert!(status.success(), "{cc} failed to build the fake libdhd");
    out
}

/// Calls one of the fake's test controls.
fn control<'a, T>(lib: &'a libloading::Library, name: &str) -> libloading::Symbol<'a, T> {
    // SAFETY: each caller names the type of the C function it looks up.
    unsafe { lib.get(name.as_bytes()).unwrap() }
}

#[test]
fn the_sdk_is_loaded_by_name_and_drives_the_device() {
    let dir = tempfile::tempdir().unwrap();
    let path = build(dir.path(), "libdhd.so", &[]);
    let dhd = Arc::new(DhdLibrary::load(Some(&path)).unwrap());
    // SAFETY: the fake's own file, already loaded by the SDK loader; same handle.
    let fake = unsafe { libloading::Library::new(&path).unwrap() };
    let forces_enabled = control::<unsafe extern "C" fn() -> i32>(&fake, "fakeForcesEnabled");
    let last_force = control::<unsafe extern "C" fn(*mut f64)>(&fake, "fakeLastForce");
    let closed = control::<unsafe extern "C" fn() -> i32>(&fake, "fakeClosed");
    let read_force = || {
        let mut f = [0.0f64; 8];
        // SAFETY: an 8-double buffer, as fakeLastForce writes.
        unsafe { last_force(f.as_mut_ptr()) };
        f
    };

    assert_eq!(dhd.sdk_version().unwrap().to_string(), "3.17.6.42");
    assert!(dhd.available().iter().all(|&(_, present)| present));
    assert_eq!(dhd.device_count(), Some(1));

    let mut device = Omega7::open_with(dhd.clone()).unwrap();
    assert_eq!(device.system_name(), "omega.7 (fake)");
    // Opening leaves forces explicitly off.
    // SAFETY: no arguments.
    assert_eq!(unsafe { forces_enabled() }, 0);
    let s = device.read_state().unwrap();
    assert_eq!(s.position_m, DVec3::new(0.01, -0.02, 0.03));
    assert_eq!(s.velocity_mps, DVec3::new(0.1, 0.2, 0.3));
    assert_eq!((s.gripper_gap_m, s.buttons), (0.015, 1));
    device
        .command(&ForceCommand {
            force_n: DVec3::new(1.5, -2.25, 3.125),
            gripper_force_n: 0.5,
        })
        .unwrap();
    // Seven doubles and the device id arrive in order.
    assert_eq!(read_force(), [1.5, -2.25, 3.125, 0.0, 0.0, 0.0, 0.5, 0.0]);
    // The watchdog's path scales the last command from another thread.
    let o = device.force_override();
    std::thread::spawn(move || o.set_force_scale(0.5)).join().unwrap();
    assert_eq!(&read_force()[..3], &[0.75, -1.125, 1.5625]);
    device.force_override().set_force_scale(1.0);

    // Through the loop: forces are enabled for the run and off and zero afterwards. A run
    // with the software watchdog arms the device's own at its period, in 125 µs steps.
    let watchdog = control::<unsafe extern "C" fn() -> i32>(&fake, "fakeWatchdog");
    // SAFETY: no arguments.
    assert_eq!(unsafe { watchdog() }, -1);
    let config = LoopConfig {
        max_ticks: Some(10),
        ..LoopConfig::default()
    };
    let stall = config.watchdog.unwrap().stall;
    let outcome = rt::spawn(device, ZeroForce, LoopIo::default(), config)
        .unwrap()
        .join()
        .unwrap();
    assert_eq!(outcome.result.unwrap().reason, StopReason::TickLimit);
    // SAFETY: no arguments.
    assert_eq!(unsafe { watchdog() }, 32, "4 ms in 125 µs steps");
    let armed = outcome.device.hardware_watchdog().unwrap();
    assert_eq!((armed.period, armed.trips), (stall, None));
    // SAFETY: no arguments.
    assert_eq!(unsafe { forces_enabled() }, 0);
    assert_eq!(&read_force()[..7], &[0.0; 7]);
    drop(outcome.device);
    // SAFETY: no arguments.
    assert_eq!(unsafe { closed() }, 1);

    // A device that stops answering: a typed error naming the call.
    let fail_after = control::<unsafe extern "C" fn(i32)>(&fake, "fakeFailPositionAfter");
    let mut device = Omega7::open_with(dhd.clone()).unwrap();
    // SAFETY: plain int argument.
    unsafe { fail_after(0) };
    let e = device.read_state().unwrap_err();
    assert!(
        matches!(
            e,
            HapticsError::DeviceCall {
                call: "dhdGetPosition",
                code: -1,
                tick: None
            }
        ),
        "{e:?}"
    );
    // SAFETY: −1 turns the failure off.
    unsafe { fail_after(-1) };
    drop(device);

    // No device connected: the SDK says so and the error says what to do.
    let set_count = control::<unsafe extern "C" fn(i32)>(&fake, "fakeSetDeviceCount");
    let set_open = control::<unsafe extern "C" fn(i32)>(&fake, "fakeSetOpenResult");
    // SAFETY: plain int arguments.
    unsafe { set_count(0) };
    let e = Omega7::open_with(dhd.clone()).unwrap_err();
    assert!(matches!(e, HapticsError::NoDevice { .. }));
    assert!(e.to_string().contains("or run on the simulated device"), "{e}");
    // SAFETY: plain int arguments.
    unsafe {
        set_count(1);
        set_open(-1);
    }
    let e = Omega7::open_with(dhd).unwrap_err();
    assert!(e.to_string().contains("fake: no device found"), "{e}");
}

#[test]
fn an_sdk_without_a_watchdog_runs_on_the_software_watchdog_alone() {
    let dir = tempfile::tempdir().unwrap();
    let path = build(dir.path(), "libdhd_old.so", &["-DOMIT_WATCHDOG"]);
    let dhd = Arc::new(DhdLibrary::load(Some(&path)).unwrap());
    assert!(!dhd.has("dhdSetWatchdog"));
    let mut device = Omega7::open_with(dhd).unwrap();
    assert_eq!(
        device.arm_watchdog(std::time::Duration::from_millis(4)).unwrap(),
        None
    );
    assert_eq!(device.hardware_watchdog(), None);
}

#[test]
fn a_library_without_a_required_function_is_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let path = build(dir.path(), "libdhd_novelocity.so", &["-DOMIT_VELOCITY"]);
    let e = DhdLibrary::load(Some(&path)).unwrap_err();
    match &e {
        HapticsError::SymbolMissing { symbol, library, .. } => {
            assert_eq!(*symbol, "dhdGetLinearVelocity");
            assert!(library.ends_with("libdhd_novelocity.so"));
        }
        other => panic!("{other:?}"),
    }
    assert!(e.to_string().contains("or run on the simulated device"), "{e}");
    // Not a shared library at all.
    let junk = dir.path().join("libdhd.so");
    std::fs::write(&junk, b"not an ELF file").unwrap();
    assert!(matches!(
        DhdLibrary::load(Some(&junk)),
        Err(HapticsError::SdkMissing { .. })
    ));
}
