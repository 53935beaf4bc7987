//! A headless render on a machine without a desktop session (no XDG_RUNTIME_DIR, no display, as
//! in CI, over ssh, in containers) prints nothing that reads as a failure when it succeeds.
#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use std::path::PathBuf;

#[test]
fn headless_render_without_a_session_is_quiet() {
    let dir = tempfile::tempdir().unwrap();
    // The child's own temporary folder, to see that it leaves nothing behind there.
    let tmp = dir.path().join("tmp");
    std::fs::create_dir(&tmp).unwrap();
    let out = dir.path().join("frame.png");
    let o = crate::common::palpus_command()
        .args([
            "render",
            "scenes/needle_liver.toml",
            "--out",
            out.to_str().unwrap(),
            "--size",
            "160x120",
            "--msaa",
            "1",
        ])
        .current_dir(PathBuf::from(env!("CARGO_MANIFEST_DIR")))
        .env("PALPUS_CACHE_DIR", dir.path().join("cache"))
        .env("TMPDIR", &tmp)
        .env_remove("XDG_RUNTIME_DIR")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .env_remove("DISPLAY")
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "render failed:\n{stdout}\nstderr:\n{stderr}");
    let image = render::Image::load_png(&out).unwrap();
    assert_eq!((image.width, image.height), (160, 120));
    let noise: Vec<&str> = stderr
        .lines()
        .filter(|line| line.contains("XDG_RUNTIME_DIR") || line.contains("error:"))
        .collect();
    assert!(
        noise.is_empty(),
        "a successful render printed {noise:?}; stderr:\n{stderr}"
    );
    let left: Vec<_> = std::fs::read_dir(&tmp)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert!(left.is_empty(), "left in the temporary folder: {left:?}");
}

#[test]
fn runtime_directories_are_not_left_behind() {
    let dir = tempfile::tempdir().unwrap();
    let tmp = dir.path();
    let palpus = |args: &[&str]| {
        crate::common::palpus_command()
            .args(args)
            .env("TMPDIR", tmp)
            .env("PALPUS_CACHE_DIR", tmp.join("cache"))
            .env_remove("XDG_RUNTIME_DIR")
            .output()
            .unwrap()
    };
    let left = || -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(tmp)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with("palpus-runtime-"))
            .collect();
        names.sort();
        names
    };
    // clap ends the process itself on --help and on bad arguments.
    assert!(palpus(&["--help"]).status.success());
    assert!(!palpus(&["--no-such-option"]).status.success());
    assert_eq!(left(), Vec::<String>::new());

    // One left by a process that died without cleaning up, one of a live process (this one).
    let mut child = crate::common::palpus_command().arg("--version").spawn().unwrap();
    let dead_pid = child.id();
    child.wait().unwrap();
    let dead = format!("palpus-runtime-{dead_pid}-0");
    let live = format!("palpus-runtime-{}-0", std::process::id());
    std::fs::create_dir(tmp.join(&dead)).unwrap();
    std::fs::create_dir(tmp.join(&live)).unwrap();
    let o = palpus(&["identify", "no-such-capture.csv", "--model", "needle"]);
    assert!(!o.status.success());
    if std::path::Path::new("/proc/self").exists() {
        assert_eq!(left(), vec![live]);
    }
}
