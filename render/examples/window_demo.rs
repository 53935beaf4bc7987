//! Opens the palpus window on the tissue block with a needle the arrow keys push in and out.
//! Drag to orbit, scroll to zoom, Up/Down (or W/S) move the needle, F12 saves a screenshot.
//!
//! `cargo run -p render --example window_demo -- [--frames N] [--screenshot out.png]`

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;

use glam::Vec3;
use render::window::{Input, Key, WindowApp, WindowConfig};
use render::{Frame, MeshData, UiAction, load_gltf, shapes};
use render::{NeedleState, demo_overlay, tissue_scene};

/// Depth at which the simulated skin gives way, m.
const PUNCTURE_DEPTH_M: f32 = 0.010;

struct Demo {
    tissue: Vec<Arc<MeshData>>,
    needle: Vec<Arc<MeshData>>,
    /// Tip position below the surface (negative: above), m.
    tip_depth_m: f32,
    punctured: bool,
    yaw_rad: f32,
    pitch_rad: f32,
    distance_m: f32,
    time_s: f32,
    trace: Vec<[f32; 2]>,
    stiffness_n_per_m: f32,
}

fn load(file: &str, fallback: fn() -> Vec<MeshData>) -> Vec<Arc<MeshData>> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../assets/meshes")
        .join(file);
    let meshes = load_gltf(&path).unwrap_or_else(|e| {
        eprintln!("{e}; using procedural {file}");
        fallback()
    });
    meshes.into_iter().map(Arc::new).collect()
}

impl Demo {
    fn force_n(&self) -> f32 {
        if self.tip_depth_m <= 0.0 {
            0.0
        } else if self.punctured {
            0.4 + 30.0 * self.tip_depth_m
        } else {
            self.stiffness_n_per_m * self.tip_depth_m
        }
    }
}

impl WindowApp for Demo {
    fn frame(&mut self, input: &Input, dt_s: f32) -> Frame {
        self.time_s += dt_s;
        self.yaw_rad -= input.drag_delta_px[0] * 0.005;
        self.pitch_rad = (self.pitch_rad + input.drag_delta_px[1] * 0.005).clamp(0.05, 1.5);
        self.distance_m = (self.distance_m * (1.0 - 0.1 * input.scroll_lines)).clamp(0.05, 0.6);
        let down = input.keys_down.iter().any(|k| matches!(k, Key::Down | Key::S));
        let up = input.keys_down.iter().any(|k| matches!(k, Key::Up | Key::W));
        let speed_mps = 0.01;
        if down {
            self.tip_depth_m += speed_mps * dt_s;
        }
        if up {
            self.tip_depth_m -= speed_mps * dt_s;
        }
        self.tip_depth_m = self.tip_depth_m.clamp(-0.02, 0.04);
        if self.tip_depth_m > PUNCTURE_DEPTH_M {
            self.punctured = true;
        }
        if self.tip_depth_m < 0.0 {
            self.punctured = false;
        }
        let state = if self.punctured {
            NeedleState::Inserted {
                depth_m: self.tip_depth_m,
            }
        } else if self.tip_depth_m > 0.0 {
            NeedleState::Pressing {
                depth_m: self.tip_depth_m,
                radius_m: 0.012,
            }
        } else {
            NeedleState::Above {
                height_m: -self.tip_depth_m,
            }
        };
        let mut frame = tissue_scene(&self.tissue, &self.needle, state);
        let target = Vec3::new(0.0, -0.006, 0.0);
        let dir = Vec3::new(
            self.yaw_rad.sin() * self.pitch_rad.cos(),
            self.pitch_rad.sin(),
            self.yaw_rad.cos() * self.pitch_rad.cos(),
        );
        frame.camera.eye_m = target + dir * self.distance_m;
        frame.camera.target_m = target;
        let force_n = self.force_n();
        self.trace.push([self.time_s, force_n]);
        if self.trace.len() > 600 {
            self.trace.remove(0);
        }
        let mut overlay = demo_overlay();
        overlay.force_time = self.trace.clone();
        overlay.recognized = None;
        overlay.current_scene = Some(1);
        if let Some(p) = overlay.params.iter_mut().find(|p| p.name == "stiffness") {
            p.value = self.stiffness_n_per_m;
        }
        frame.overlay = Some(overlay);
        frame
    }

    fn action(&mut self, action: UiAction) {
        match action {
            UiAction::SetParam { name, value } if name == "stiffness" => self.stiffness_n_per_m = value,
            other => eprintln!("demo ignores {other:?}"),
        }
    }
}

fn main() -> ExitCode {
    // SAFETY: first thing in `main`, before any other thread exists.
    let _quiet = unsafe { render::QuietRuntimeDir::install() };
    let mut config = WindowConfig {
        title: "palpus window demo".into(),
        ..WindowConfig::default()
    };
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match (arg.as_str(), args.next()) {
            ("--frames", Some(n)) => config.exit_after_frames = n.parse().ok(),
            ("--screenshot", Some(p)) => config.screenshot_on_exit = Some(PathBuf::from(p)),
            _ => {
                eprintln!("usage: window_demo [--frames N] [--screenshot out.png]");
                return ExitCode::FAILURE;
            }
        }
    }
    let mut demo = Demo {
        tissue: load("tissue_block.glb", shapes::tissue_block),
        needle: load("needle.glb", shapes::needle),
        tip_depth_m: 0.007,
        punctured: false,
        yaw_rad: 0.0,
        pitch_rad: 0.5,
        distance_m: 0.14,
        time_s: 0.0,
        trace: Vec::new(),
        stiffness_n_per_m: 450.0,
    };
    match render::window::run(config, &mut demo) {
        Ok(stats) => {
            eprintln!("{stats}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
