//! The real window, run non-interactively: it draws a few frames, writes its exit screenshot and
//! closes. Needs an X display (run under `xvfb-run -a`); without one the test only checks that
//! opening fails with a typed error instead of a panic.

#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use render::bench::bench_frame;
use render::window::{Input, WindowApp, WindowConfig, run};
use render::{Frame, Image, RenderError, UiAction};

struct App {
    frames: u32,
    last_size: [u32; 2],
}

impl WindowApp for App {
    fn frame(&mut self, input: &Input, _dt_s: f32) -> Frame {
        self.frames += 1;
        self.last_size = input.window_size_px;
        // The benchmark scene with its overlay: layered tissue, the needle pressing.
        bench_frame(true)
    }

    fn action(&mut self, _action: UiAction) {}
}

#[test]
fn window_draws_frames_and_screenshots_on_exit() {
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("exit.png");
    let config = WindowConfig {
        width: 640,
        height: 400,
        msaa: 4,
        exit_after_frames: Some(5),
        screenshot_on_exit: Some(shot.clone()),
        screenshot_dir: dir.path().to_path_buf(),
        ..WindowConfig::default()
    };
    let mut app = App {
        frames: 0,
        last_size: [0, 0],
    };
    let has_display = std::env::var_os("DISPLAY").is_some();
    match run(config, &mut app) {
        Ok(stats) => {
            assert!(has_display);
            assert_eq!(app.frames, 5);
            assert_eq!(stats.frames, 5);
            assert!(stats.p50_ms > 0.0 && stats.p99_ms >= stats.p50_ms && stats.max_ms >= stats.p99_ms);
            let image = Image::load_png(&shot).unwrap();
            assert_eq!([image.width, image.height], app.last_size);
            assert!(
                image.width >= 640 && image.height >= 400,
                "{}x{}",
                image.width,
                image.height
            );
        }
        Err(e) => {
            assert!(!has_display, "window failed with a display: {e}");
            assert!(matches!(e, RenderError::Window(_)), "{e}");
        }
    }
}
