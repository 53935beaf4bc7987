//! The window under Xvfb and `palpus render`'s images of every default scene.

use super::*;

#[test]
fn the_window_opens_under_xvfb_and_shows_the_needle() {
    let _serial = serial();
    if std::process::Command::new("xvfb-run")
        .arg("--help")
        .output()
        .is_err()
    {
        // `.ci/run` installs Xvfb; without it there is no display to test against.
        eprintln!("xvfb-run not installed: the window test needs it (apt-get install xvfb xauth)");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("report");
    let attempt = || {
        let o = std::process::Command::new("xvfb-run")
            .args([
                "-a",
                "-s",
                "-screen 0 1280x720x24",
                env!("CARGO_BIN_EXE_palpus"),
                "run",
            ])
            .args([
                "--autopilot",
                "--duration",
                "2.5",
                "--report",
                out.to_str().unwrap(),
            ])
            .current_dir(root())
            .env("PALPUS_CACHE_DIR", dir.path().join("cache"))
            .output()
            .unwrap();
        let printed = text(&o);
        assert!(o.status.success(), "{printed}");
        assert!(printed.contains("in a window"), "{printed}");
        report(&out)
    };
    // At the nominal rate within 2 % while the window draws.
    let r = real_time_report(0.02, attempt);
    let shot = render::Image::load_png(&out.join("window.png")).unwrap();
    assert_eq!((shot.width, shot.height), (1280, 720));
    // The scripted trainee pushed the needle into the capsule while the window drew.
    let seg = &r["segments"][0];
    assert!(f(&seg["max_model_force_n"]) > 0.5, "{seg}");
}

#[test]
fn palpus_render_draws_each_default_scene_and_the_dimple() {
    let _shared = untimed();
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let render_ = |args: &[&str]| palpus_at_root("render", args, &cache).output().unwrap();
    for scene in ["needle_liver", "surfaces_nakano", "friction_hard_soft"] {
        let out = dir.path().join(format!("{scene}.png"));
        let o = render_(&[
            &format!("scenes/{scene}.toml"),
            "--out",
            out.to_str().unwrap(),
            "--size",
            "320x240",
            "--msaa",
            "1",
        ]);
        assert!(o.status.success(), "{}", text(&o));
        let image = render::Image::load_png(&out).unwrap();
        assert_eq!((image.width, image.height), (320, 240));
        // Something besides the background was drawn.
        let background = image.pixel(0, 0).unwrap();
        let drawn = image.rgba.chunks(4).filter(|p| p[..3] != background[..3]).count();
        assert!(drawn > 320 * 240 / 20, "{scene}: {drawn} pixels drawn");
    }
    let state = dir.path().join("state.json");
    std::fs::write(
        &state,
        r#"{"object": "liver", "tool_position_m": [0, 0, -0.03], "law_state": "capsule_loading"}"#,
    )
    .unwrap();
    let pressed = dir.path().join("pressed.png");
    let o = render_(&[
        "scenes/needle_liver.toml",
        "--out",
        pressed.to_str().unwrap(),
        "--size",
        "320x240",
        "--msaa",
        "1",
        "--state",
        state.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let rest = render::Image::load_png(&dir.path().join("needle_liver.png")).unwrap();
    let pressed = render::Image::load_png(&pressed).unwrap();
    let changed = rest
        .rgba
        .chunks(4)
        .zip(pressed.rgba.chunks(4))
        .filter(|(a, b)| a != b)
        .count();
    assert!(changed > 200, "a 10 mm dimple changed only {changed} pixels");

    std::fs::write(
        &state,
        r#"{"tool_position_m": [0, 0, -0.03], "law_state": "squeezed"}"#,
    )
    .unwrap();
    let o = render_(&[
        "scenes/needle_liver.toml",
        "--out",
        dir.path().join("x.png").to_str().unwrap(),
        "--state",
        state.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(
        text(&o).contains("state.json") && text(&o).contains("squeezed"),
        "{}",
        text(&o)
    );
}
