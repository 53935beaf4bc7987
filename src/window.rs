//! The interactive session: the window draws the scene while the haptic thread renders the
//! models; the mouse and keyboard move the simulated hand (a real Omega.7 is moved by the
//! trainee's own hand).
//!
//! Controls: drag up/down or scroll to push the tool down/up, arrows or WASD to move it
//! sideways, Space for the next object of a rubbing scene, F12 for a screenshot. The overlay
//! switches scenes and sets the view's parameters.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::Instant;

use glam::DVec3;
use haptics::recognizer_channel as channel;
use haptics::{LiveFeed, LiveView, RecentSamples, live_channel};
use render::window::{Input, Key, WindowApp, WindowConfig};
use render::{Frame, Param, Recognition, UiAction};
use sim::LiveHand;

use crate::recognizer::SceneRecognizer;
use crate::scene::Scene;
use crate::session::guide::{LiveGuide, task_panel};
use crate::session::report::Recognition as Decision;
use crate::session::strokes::LiveAttempts;
use crate::session::{
    self, LiveLink, Segment, SegmentKind, SegmentRun, SessionError, SessionOptions, start_position_m,
};
use crate::view::{SceneView, ViewState, overlay_plots};

/// How far the hand may move from the workspace centre, m (the Omega.7's Ø 160 mm, less a
/// margin).
const REACH_M: f64 = 0.07;
/// Hand travel per pixel dragged, m.
const DRAG_M_PER_PX: f64 = 1e-4;
/// Hand travel per scroll line, m.
const SCROLL_M_PER_LINE: f64 = 1e-3;
/// Hand speed with a key held, m/s.
const KEY_SPEED_MPS: f64 = 0.02;
/// How much of the running segment the overlay plots, s.
const OVERLAY_S: f64 = 10.0;
/// Seconds of samples the live ring holds between two frames: far more than a frame, so a
/// window that stalls for a while still sees every sample.
const RING_S: f64 = 4.0;

/// What the window session produced.
#[derive(Debug, Default)]
pub struct WindowOutcome {
    /// Every segment run, in order.
    pub runs: Vec<SegmentRun>,
    /// The surface recognizer of the scene shown last, as the report names it.
    pub recognizer: Option<session::report::RecognizerLine>,
    /// Recognized-surface decisions.
    pub recognition: Vec<Decision>,
    /// The scene shown last (the overlay can switch).
    pub scene: Option<Scene>,
}

struct Session {
    scene: Scene,
    view: SceneView,
    segments: Vec<Segment>,
    current: usize,
    options: SessionOptions,
    cache_dir: PathBuf,
    /// The hand target the UI moves.
    hand: Arc<LiveHand>,
    /// Set to end the running segment.
    stop: Arc<AtomicBool>,
    /// The running segment's live view.
    live: LiveView,
    /// The last [`OVERLAY_S`] seconds of it, for the plots and the recognizer's decisions.
    recent: RecentSamples,
    worker: Option<JoinHandle<Result<SegmentRun, SessionError>>>,
    hand_m: DVec3,
    recognizer: Option<SceneRecognizer>,
    recognized: Option<Recognition>,
    /// The recognizer channel's decision count at the last sample read.
    decisions_seen: f64,
    outcome: WindowOutcome,
    scenes: Vec<PathBuf>,
    error: Option<anyhow::Error>,
    last_wall: Instant,
    last_ticks: u64,
    rate_hz: f32,
    /// The running attempt, as the overlay's task panel tells it.
    guide: LiveGuide,
    /// The segment's attempts, scored as each ends.
    attempts: LiveAttempts,
}

/// The live view of a segment at `rate_hz`, and the window's buffer for its plots.
fn live_view(rate_hz: f64) -> (LiveFeed, LiveView, RecentSamples) {
    let samples = |s: f64| (s * rate_hz.max(1.0)).ceil() as usize;
    let (feed, view) = live_channel(samples(RING_S));
    (feed, view, RecentSamples::new(samples(OVERLAY_S) + 1))
}

impl Session {
    fn new(
        scene: Scene,
        segments: Vec<Segment>,
        options: SessionOptions,
        cache_dir: PathBuf,
    ) -> anyhow::Result<Self> {
        let view = SceneView::load(&scene)?;
        let recognizer = SceneRecognizer::for_scene(&scene)?;
        let mut scenes: Vec<PathBuf> = std::fs::read_dir(scene.base_dir())
            .map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).collect())
            .unwrap_or_default();
        scenes.retain(|p| p.extension().is_some_and(|e| e == "toml"));
        scenes.sort();
        let start = start_position_m(&scene);
        let (_, live, recent) = live_view(scene.device.rate_hz);
        let mut s = Self {
            scene,
            view,
            segments,
            current: 0,
            options,
            cache_dir,
            hand: LiveHand::new(),
            stop: Arc::new(AtomicBool::new(false)),
            live,
            recent,
            worker: None,
            hand_m: start,
            recognizer,
            recognized: None,
            decisions_seen: 0.0,
            outcome: WindowOutcome::default(),
            scenes,
            error: None,
            last_wall: Instant::now(),
            last_ticks: 0,
            rate_hz: 0.0,
            guide: LiveGuide::new(),
            attempts: LiveAttempts::new(),
        };
        s.start();
        Ok(s)
    }

    fn start(&mut self) {
        let Some(segment) = self.segments.get(self.current).cloned() else {
            return;
        };
        self.hand_m = start_position_m(&self.scene);
        let (feed, live, recent) = live_view(self.scene.device.rate_hz);
        let link = LiveLink::new(self.hand_m, feed);
        self.hand = link.hand.clone();
        self.stop = link.stop.clone();
        self.live = live;
        self.recent = recent;
        self.last_ticks = 0;
        self.guide = LiveGuide::new();
        self.attempts = LiveAttempts::new();
        self.recognized = None;
        self.decisions_seen = 0.0;
        let (scene, options, n, recognizer) = (
            self.scene.clone(),
            self.options.clone(),
            self.segments.len(),
            self.recognizer.as_ref().map(SceneRecognizer::live),
        );
        self.worker = Some(std::thread::spawn(move || {
            session::run_segment(&scene, &segment, n, &options, Some(link), recognizer)
        }));
    }

    fn stop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(w) = self.worker.take() {
            match w.join() {
                Ok(Ok(run)) => self.outcome.runs.push(run),
                Ok(Err(e)) => self.error = Some(e.into()),
                Err(_) => self.error = Some(anyhow::anyhow!("the session thread panicked")),
            }
        }
    }

    fn switch_scene(&mut self, path: &Path) -> anyhow::Result<()> {
        let scene = Scene::load(path)?;
        let models = crate::models::resolve_with_progress(&scene, &self.cache_dir)?;
        let segments = session::segments(&scene, &models)?;
        let view = SceneView::load(&scene)?;
        let recognizer = SceneRecognizer::for_scene(&scene)?;
        self.stop();
        self.scene = scene;
        self.segments = segments;
        self.view = view;
        self.recognizer = recognizer;
        self.current = 0;
        self.start();
        Ok(())
    }

    fn move_hand(&mut self, input: &Input, dt_s: f32) {
        let dt = f64::from(dt_s.clamp(0.0, 0.1));
        let mut d = DVec3::ZERO;
        d.z -= f64::from(input.drag_delta_px[1]) * DRAG_M_PER_PX;
        d.z -= f64::from(input.scroll_lines) * SCROLL_M_PER_LINE;
        for k in &input.keys_down {
            let step = KEY_SPEED_MPS * dt;
            match k {
                Key::Left | Key::A => d.x -= step,
                Key::Right | Key::D => d.x += step,
                Key::Up | Key::W => d.y += step,
                Key::Down | Key::S => d.y -= step,
                Key::Space => {}
            }
        }
        let p = self.hand_m + d;
        self.hand_m = if p.length() > REACH_M {
            p * (REACH_M / p.length())
        } else {
            p
        };
        self.hand.set(self.hand_m, 0.01);
    }
}

impl WindowApp for Session {
    fn frame(&mut self, input: &Input, dt_s: f32) -> Frame {
        if input.keys_pressed.contains(&Key::Space) && self.segments.len() > 1 {
            self.stop();
            self.current = (self.current + 1) % self.segments.len();
            self.start();
        }
        self.move_hand(input, dt_s);
        let segment = self.segments.get(self.current);
        let kind = segment.map(|s| &s.kind);
        let object = segment.map(|s| s.object.as_str());
        // The recorder thread decides on the samples before handing them on; each sample where
        // the decision count steps carries a new decision.
        let surface = match (&self.recognizer, kind) {
            (Some(r), Some(SegmentKind::Surface { surface })) => Some((r, surface)),
            _ => None,
        };
        let (recent, recognized, decisions_seen, recognition, guide, attempts) = (
            &mut self.recent,
            &mut self.recognized,
            &mut self.decisions_seen,
            &mut self.outcome.recognition,
            &mut self.guide,
            &mut self.attempts,
        );
        let needle = matches!(kind, Some(SegmentKind::Needle { .. }));
        let surface_z_m = session::analysis::surface_z_on(&self.options.device.label());
        let (goal, rate_hz) = (self.scene.task.goal(), self.scene.device.rate_hz);
        self.live.drain(|s| {
            if needle {
                guide.push(s, surface_z_m);
                if let Some(goal) = goal
                    && let Some(score) = attempts.push(s, goal, surface_z_m, rate_hz).cloned()
                {
                    guide.attempt_ended(attempts.scored().len(), score);
                }
            }
            recent.push(s);
            let Some((r, truth)) = surface else {
                return;
            };
            let count = s.channels[channel::DECISIONS];
            if count == *decisions_seen {
                return;
            }
            *decisions_seen = count;
            if count > 0.0
                && let Some(d) =
                    crate::recognizer::recognition(r.classes(), object.unwrap_or_default(), truth, s)
            {
                *recognized = Some(Recognition {
                    surface: d.label.clone().unwrap_or_else(|| d.best.clone()),
                    confidence: d.confidence as f32,
                    decided: d.label.is_some(),
                });
                recognition.push(d);
            }
        });
        let last = self.live.newest();
        let mut overlay = overlay_plots(self.recent.as_slice(), kind, OVERLAY_S, 600);
        let ticks = last.map_or(0, |s| s.tick + 1);
        let wall = self.last_wall.elapsed().as_secs_f32();
        if wall >= 0.5 {
            self.rate_hz = ticks.saturating_sub(self.last_ticks) as f32 / wall;
            self.last_wall = Instant::now();
            self.last_ticks = ticks;
        }
        let state = ViewState {
            object,
            kind,
            sample: last.as_ref(),
            surface_given: self.guide.layers_given() > 0,
        };
        let mut frame = self.view.frame(&state);
        overlay.haptic_rate_hz = Some(self.rate_hz);
        overlay.period_error_s = self.live.stats().map(|s| s.period_error.p99.as_secs_f32());
        let running = self.worker.as_ref().is_some_and(|w| !w.is_finished());
        overlay.device_status = format!(
            "{} · {} · {}{}",
            self.options.device.label(),
            object.unwrap_or("-"),
            if running { "running" } else { "stopped" },
            if self.segments.len() > 1 {
                " · Space: next object"
            } else {
                ""
            }
        );
        overlay.recognized = self.recognized.clone();
        overlay.task = task_panel(self.scene.task.goal(), kind, &self.guide);
        overlay.scenes = self
            .scenes
            .iter()
            .map(|p| {
                p.file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default()
            })
            .collect();
        overlay.current_scene = self.scenes.iter().position(|p| {
            p.file_stem().map(|s| s.to_string_lossy())
                == self.scene.path.file_stem().map(|s| s.to_string_lossy())
        });
        overlay.params = vec![
            Param {
                name: "dimple radius".into(),
                value: self.view.dimple_radius_m * 1e3,
                min: 4.0,
                max: 25.0,
                unit: "mm".into(),
            },
            Param {
                name: "opacity after puncture".into(),
                value: self.view.punctured_opacity,
                min: 0.1,
                max: 1.0,
                unit: String::new(),
            },
        ];
        frame.overlay = Some(overlay);
        frame
    }

    fn action(&mut self, action: UiAction) {
        match action {
            UiAction::SetParam { name, value } => match name.as_str() {
                "dimple radius" => self.view.dimple_radius_m = value.clamp(4.0, 25.0) * 1e-3,
                "opacity after puncture" => self.view.punctured_opacity = value.clamp(0.1, 1.0),
                _ => {}
            },
            UiAction::SelectScene { index, .. } => {
                if let Some(path) = self.scenes.get(index).cloned()
                    && path != self.scene.path
                    && let Err(e) = self.switch_scene(&path)
                {
                    self.error = Some(e);
                }
            }
        }
    }

    fn should_exit(&self) -> bool {
        // A session with --duration ends when its haptic thread does.
        self.options.duration_s.is_some() && self.worker.as_ref().is_some_and(JoinHandle::is_finished)
    }
}

/// Runs the scene in a window until it is closed; `screenshot` is written on exit.
pub fn run(
    scene: Scene,
    segments: Vec<Segment>,
    options: SessionOptions,
    cache_dir: PathBuf,
    screenshot: Option<PathBuf>,
) -> anyhow::Result<WindowOutcome> {
    let title = format!("palpus — {}", scene.name);
    let mut session = Session::new(scene, segments, options, cache_dir)?;
    let config = WindowConfig {
        title,
        screenshot_on_exit: screenshot,
        ..WindowConfig::default()
    };
    let shown = render::window::run(config, &mut session);
    session.stop();
    if let Some(e) = session.error.take() {
        return Err(e);
    }
    let stats = shown?;
    // One line beside the CLI's own, which announced the window: how steadily it drew.
    #[allow(clippy::print_stdout)]
    {
        println!("window: {stats}");
    }
    let mut outcome = std::mem::take(&mut session.outcome);
    outcome.scene = Some(session.scene.clone());
    outcome.recognizer = session.recognizer.as_ref().map(SceneRecognizer::line);
    Ok(outcome)
}
