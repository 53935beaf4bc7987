//! The interactive window: winit event loop, a wgpu surface drawn by the same [`Renderer`] code as
//! offscreen images, egui input, F12 screenshots, and an exit-after-N-frames mode for tests.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

use crate::error::RenderError;
use crate::frame::{Frame, Overlay, UiAction};
use crate::gpu::{Gpu, GpuOptions, no_adapter};
use crate::image::Image;
use crate::renderer::{OverlayInput, Renderer};

/// How the window opens and when it closes by itself.
#[derive(Debug, Clone, PartialEq)]
pub struct WindowConfig {
    pub title: String,
    /// Initial inner size, logical px.
    pub width: u32,
    pub height: u32,
    /// 1 or 4.
    pub msaa: u32,
    /// Where F12 writes `palpus-<unix ms>.png`.
    pub screenshot_dir: PathBuf,
    /// Close after this many drawn frames (for tests under Xvfb).
    pub exit_after_frames: Option<u32>,
    /// Write a screenshot of the last frame here when the window closes by itself
    /// (`exit_after_frames`, or the app's [`WindowApp::should_exit`]).
    pub screenshot_on_exit: Option<PathBuf>,
    pub gpu: GpuOptions,
}

impl Default for WindowConfig {
    fn default() -> Self {
        WindowConfig {
            title: "palpus".into(),
            width: 1280,
            height: 720,
            msaa: 4,
            screenshot_dir: PathBuf::from("screenshots"),
            exit_after_frames: None,
            screenshot_on_exit: None,
            gpu: GpuOptions::default(),
        }
    }
}

/// The overlay's data are taken from the app at most this often: its plots stay smooth, and the
/// panel (the costliest thing to paint on a software rasterizer) is repainted only then.
const OVERLAY_INTERVAL: Duration = Duration::from_millis(33);

/// How steadily the window drew: the time between successive frames.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameStats {
    /// Frames drawn.
    pub frames: u32,
    /// Median time between two frames, ms.
    pub p50_ms: f64,
    /// 99th percentile of the time between two frames, ms.
    pub p99_ms: f64,
    /// Longest time between two frames, ms.
    pub max_ms: f64,
}

impl FrameStats {
    fn from_intervals(frames: u32, mut intervals_ms: Vec<f64>) -> Self {
        intervals_ms.sort_by(f64::total_cmp);
        let at = |q: f64| {
            if intervals_ms.is_empty() {
                0.0
            } else {
                let i = ((intervals_ms.len() - 1) as f64 * q).round() as usize;
                intervals_ms[i.min(intervals_ms.len() - 1)]
            }
        };
        FrameStats {
            frames,
            p50_ms: at(0.5),
            p99_ms: at(0.99),
            max_ms: intervals_ms.last().copied().unwrap_or(0.0),
        }
    }
}

impl std::fmt::Display for FrameStats {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} frames, frame time p50 {:.1} ms, p99 {:.1} ms, max {:.1} ms",
            self.frames, self.p50_ms, self.p99_ms, self.max_ms
        )
    }
}

/// Keys the app may use to move the camera or the tool.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Key {
    Up,
    Down,
    Left,
    Right,
    W,
    A,
    S,
    D,
    Space,
}

impl Key {
    fn from_code(code: KeyCode) -> Option<Key> {
        Some(match code {
            KeyCode::ArrowUp => Key::Up,
            KeyCode::ArrowDown => Key::Down,
            KeyCode::ArrowLeft => Key::Left,
            KeyCode::ArrowRight => Key::Right,
            KeyCode::KeyW => Key::W,
            KeyCode::KeyA => Key::A,
            KeyCode::KeyS => Key::S,
            KeyCode::KeyD => Key::D,
            KeyCode::Space => Key::Space,
            _ => return None,
        })
    }
}

/// Input gathered since the previous frame, minus what the overlay consumed.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Input {
    /// Mouse movement with the left button held over the 3-D view, physical px.
    pub drag_delta_px: [f32; 2],
    /// Wheel movement in lines (positive away from the user).
    pub scroll_lines: f32,
    /// Keys held down now.
    pub keys_down: Vec<Key>,
    /// Keys pressed since the previous frame.
    pub keys_pressed: Vec<Key>,
    /// Drawable size, physical px.
    pub window_size_px: [u32; 2],
    /// Physical px per logical px.
    pub scale_factor: f32,
}

/// What the palpus binary implements to drive the window.
pub trait WindowApp {
    /// The frame to draw now; `dt_s` is the time since the previous one.
    fn frame(&mut self, input: &Input, dt_s: f32) -> Frame;
    /// A user request from the overlay.
    fn action(&mut self, action: UiAction);
    /// Whether the app is done (its session ended); the window then closes as if
    /// `exit_after_frames` had been reached.
    fn should_exit(&self) -> bool {
        false
    }
}

struct Surface {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    renderer: Renderer,
    egui: egui_winit::State,
}

struct App<'a> {
    config: WindowConfig,
    app: &'a mut dyn WindowApp,
    surface: Option<Surface>,
    error: Option<RenderError>,
    input: Input,
    dragging: bool,
    last_cursor: Option<[f32; 2]>,
    screenshot_requested: bool,
    last_frame_at: Option<Instant>,
    frames_drawn: u32,
    /// Time between successive frames, ms.
    intervals_ms: Vec<f64>,
    /// The overlay data shown, and when they were taken from the app.
    overlay_shown: Option<(Overlay, Instant)>,
    /// The user changed something through the overlay: show the app's answer at once.
    overlay_stale: bool,
}

/// Opens the window and runs until it is closed (or `exit_after_frames` frames are drawn);
/// returns how steadily it drew.
pub fn run(config: WindowConfig, app: &mut dyn WindowApp) -> Result<FrameStats, RenderError> {
    if config.msaa != 1 && config.msaa != 4 {
        return Err(RenderError::BadMsaa(config.msaa));
    }
    let mut builder = EventLoop::builder();
    // Tests and tools may open the window from a thread other than the process's first.
    #[cfg(target_os = "linux")]
    winit::platform::x11::EventLoopBuilderExtX11::with_any_thread(&mut builder, true);
    let event_loop = builder
        .build()
        .map_err(|e| RenderError::Window(format!("cannot open the display: {e}")))?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let mut state = App {
        config,
        app,
        surface: None,
        error: None,
        input: Input::default(),
        dragging: false,
        last_cursor: None,
        screenshot_requested: false,
        last_frame_at: None,
        frames_drawn: 0,
        intervals_ms: Vec::new(),
        overlay_shown: None,
        overlay_stale: false,
    };
    event_loop
        .run_app(&mut state)
        .map_err(|e| RenderError::Window(e.to_string()))?;
    match state.error {
        Some(e) => Err(e),
        None => Ok(FrameStats::from_intervals(state.frames_drawn, state.intervals_ms)),
    }
}

impl App<'_> {
    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<Surface, RenderError> {
        let attributes = Window::default_attributes()
            .with_title(self.config.title.clone())
            .with_inner_size(winit::dpi::LogicalSize::new(
                self.config.width,
                self.config.height,
            ));
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .map_err(|e| RenderError::Window(e.to_string()))?,
        );
        let mut tried = Vec::new();
        let mut details = Vec::new();
        let mut found = None;
        for backend in &self.config.gpu.backends {
            let name = match backend {
                crate::gpu::Backend::Vulkan => "Vulkan",
                crate::gpu::Backend::Gl => "GL",
            };
            tried.push(name);
            let mut desc = wgpu::InstanceDescriptor::new_with_display_handle(Box::new(
                event_loop.owned_display_handle(),
            ));
            desc.backends = backend.wgpu();
            let instance = wgpu::Instance::new(desc);
            let surface = match instance.create_surface(window.clone()) {
                Ok(s) => s,
                Err(e) => {
                    details.push(format!("{name}: surface: {e}"));
                    continue;
                }
            };
            let request = wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                force_fallback_adapter: false,
                compatible_surface: Some(&surface),
                apply_limit_buckets: false,
            };
            match pollster::block_on(instance.request_adapter(&request)) {
                Ok(adapter) => {
                    found = Some((adapter, surface));
                    break;
                }
                Err(e) => details.push(format!("{name}: {e}")),
            }
        }
        let Some((adapter, surface)) = found else {
            return Err(no_adapter(&tried, &details));
        };
        let gpu = Gpu::open(adapter)?;
        let caps = surface.get_capabilities(&gpu.adapter);
        // Lighting is linear; an sRGB swap chain encodes it like the offscreen target does.
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| f.is_srgb())
            .or_else(|| caps.formats.first().copied())
            .ok_or_else(|| RenderError::Window("the surface offers no formats".into()))?;
        let size = window.inner_size();
        // Copying into the swap-chain image lets the overlay's panel be painted only when it
        // changes; without it the overlay is painted over every frame.
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | (caps.usages & wgpu::TextureUsages::COPY_DST);
        let config = wgpu::SurfaceConfiguration {
            usage,
            format,
            color_space: Default::default(),
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps
                .alpha_modes
                .first()
                .copied()
                .unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: vec![],
        };
        surface.configure(&gpu.device, &config);
        let max_texture_side = gpu.device.limits().max_texture_dimension_2d as usize;
        let renderer = Renderer::new(gpu, format, self.config.msaa)?;
        let egui = egui_winit::State::new(
            renderer.egui_context(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(max_texture_side),
        );
        Ok(Surface {
            window,
            surface,
            config,
            renderer,
            egui,
        })
    }

    fn redraw(&mut self, event_loop: &ActiveEventLoop) -> Result<(), RenderError> {
        let Some(s) = self.surface.as_mut() else {
            return Ok(());
        };
        let now = Instant::now();
        let dt_s = self.last_frame_at.map_or(0.0, |t| (now - t).as_secs_f32());
        if let Some(t) = self.last_frame_at {
            self.intervals_ms.push((now - t).as_secs_f64() * 1e3);
        }
        self.last_frame_at = Some(now);
        let size = [s.config.width, s.config.height];
        self.input.window_size_px = size;
        self.input.scale_factor = s.window.scale_factor() as f32;
        let input = std::mem::take(&mut self.input);
        self.input.keys_down = input.keys_down.clone();
        let mut frame = self.app.frame(&input, dt_s);
        // Between refreshes the overlay shows the data it showed last, so its panel is not
        // repainted; egui still sees every input event.
        match (&mut frame.overlay, &self.overlay_shown) {
            (Some(overlay), Some((shown, at)))
                if now.duration_since(*at) < OVERLAY_INTERVAL && !self.overlay_stale =>
            {
                overlay.clone_from(shown);
            }
            (Some(overlay), _) => {
                self.overlay_shown = Some((overlay.clone(), now));
                self.overlay_stale = false;
            }
            (None, _) => self.overlay_shown = None,
        }
        let raw = s.egui.take_egui_input(&s.window);
        let texture = match s.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                s.surface.configure(s.renderer.gpu().device_ref(), &s.config);
                return Ok(());
            }
            // Occluded, timed out: try again next frame.
            _ => return Ok(()),
        };
        let out = s
            .renderer
            .draw(&frame, &texture.texture, OverlayInput::Run(raw), None)?;
        s.window.pre_present_notify();
        s.renderer.gpu().queue_ref().present(texture);
        if let Some(platform) = out.platform_output {
            s.egui.handle_platform_output(&s.window, platform);
        }
        self.overlay_stale |= !out.actions.is_empty();
        for action in out.actions {
            self.app.action(action);
        }
        self.frames_drawn += 1;
        if std::mem::take(&mut self.screenshot_requested) {
            let millis = SystemTime::now()
                .duration_since(UNIX_EPOCH)
                .map_or(0, |d| d.as_millis());
            let path = self.config.screenshot_dir.join(format!("palpus-{millis}.png"));
            let image: Image = s.renderer.capture(&frame, size)?;
            image.save_png(&path)?;
        }
        if self
            .config
            .exit_after_frames
            .is_some_and(|n| self.frames_drawn >= n)
            || self.app.should_exit()
        {
            if let Some(path) = &self.config.screenshot_on_exit {
                s.renderer.capture(&frame, size)?.save_png(path)?;
            }
            event_loop.exit();
        }
        Ok(())
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, error: RenderError) {
        self.error = Some(error);
        event_loop.exit();
    }
}

impl ApplicationHandler for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.surface.is_some() {
            return;
        }
        match self.open(event_loop) {
            Ok(s) => {
                s.window.request_redraw();
                self.surface = Some(s);
            }
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(s) = self.surface.as_mut() else { return };
        let consumed = s.egui.on_window_event(&s.window, &event).consumed;
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) if size.width > 0 && size.height > 0 => {
                s.config.width = size.width;
                s.config.height = size.height;
                s.surface.configure(s.renderer.gpu().device_ref(), &s.config);
            }
            WindowEvent::KeyboardInput { event, .. } => {
                if consumed {
                    return;
                }
                let PhysicalKey::Code(code) = event.physical_key else {
                    return;
                };
                let pressed = event.state == ElementState::Pressed;
                if code == KeyCode::F12 && pressed && !event.repeat {
                    self.screenshot_requested = true;
                }
                if let Some(key) = Key::from_code(code) {
                    self.input.keys_down.retain(|k| *k != key);
                    if pressed {
                        self.input.keys_down.push(key);
                        if !event.repeat {
                            self.input.keys_pressed.push(key);
                        }
                    }
                }
            }
            WindowEvent::MouseInput {
                state,
                button: MouseButton::Left,
                ..
            } => {
                self.dragging = state == ElementState::Pressed && !consumed;
            }
            WindowEvent::CursorMoved { position, .. } => {
                let p = [position.x as f32, position.y as f32];
                if let Some(last) = self.last_cursor
                    && self.dragging
                {
                    self.input.drag_delta_px[0] += p[0] - last[0];
                    self.input.drag_delta_px[1] += p[1] - last[1];
                }
                self.last_cursor = Some(p);
            }
            WindowEvent::MouseWheel { delta, .. } if !consumed => {
                self.input.scroll_lines += match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
            }
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.redraw(event_loop) {
                    self.fail(event_loop, e);
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(s) = &self.surface {
            s.window.request_redraw();
        }
    }
}
