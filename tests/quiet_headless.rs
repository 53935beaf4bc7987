//! A headless render on a machine without a desktop session (no XDG_RUNTIME_DIR, no display, as
//! in CI, over ssh, in containers) prints nothing that reads as a failure when it succeeds.
#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use std::path::PathBuf;
use std::process::Command;

#[test]
fn headless_render_without_a_session_is_quiet() {
    let dir = tempfile::tempdir().unwrap();
    // The child's own temporary folder, to see that it leaves nothing behind there.
    let tmp = dir.path().join("tmp");
    std::fs::create_dir(&tmp).unwrap();
    let out = dir.path().join("frame.png");
    let o = Command::new(env!("CARGO_BIN_EXE_palpus"))
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
