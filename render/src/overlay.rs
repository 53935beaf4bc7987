//! The egui overlay: live plots, recognition and loop status, scene and parameter controls.
//! Built from [`Overlay`] data each frame, the same way for windows and offscreen images.
//!
//! egui's shapes are painted into a texture the size of the side panel only when they change, and
//! the texture is copied into each frame's panel strip. On a software rasterizer repainting the
//! panel costs more than the whole 3-D scene, while its content changes at the rate of the plots'
//! data (or of the user's input), not at the frame rate.

use egui::{Align2, Color32, FontId, Pos2, Rect, Sense, Shape, Stroke, StrokeKind, Vec2};

use crate::frame::{Overlay, TaskPanel, UiAction};
use crate::offscreen::texture_2d;

/// Width of the overlay's side panel, points.
pub const PANEL_WIDTH_PT: f32 = 290.0;
/// A haptic loop slower than this is shown in red.
const RATE_WARN_HZ: f32 = 950.0;

pub(crate) struct Painted {
    pub primitives: Vec<egui::ClippedPrimitive>,
    pub textures: egui::TexturesDelta,
    pub pixels_per_point: f32,
    pub actions: Vec<UiAction>,
    pub platform_output: egui::PlatformOutput,
}

pub(crate) struct OverlayLayer {
    ctx: egui::Context,
    renderer: egui_wgpu::Renderer,
    format: wgpu::TextureFormat,
    /// Last painted shapes, replayed for screenshots.
    last: Option<(Vec<egui::ClippedPrimitive>, f32)>,
    /// The panel strip as last painted, with what it was painted from.
    panel: Option<PanelTexture>,
    /// Panel repaints since creation (tests and benchmarks check that unchanged shapes are not
    /// painted again).
    repaints: u64,
    headless_frames: u64,
}

/// The overlay's pixels for the strip right of `x0_px`, kept between frames.
struct PanelTexture {
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    /// Where the strip starts in the frame, px, and the frame's size.
    x0_px: u32,
    frame_size: [u32; 2],
    clear: [f32; 3],
    /// The shapes it shows; `None` when it must be repainted (new egui textures).
    shapes: Option<(Vec<egui::ClippedPrimitive>, f32)>,
}

/// Where and over what the overlay is painted in one frame.
pub(crate) struct PanelTarget<'a> {
    /// The frame's colour texture; the strip is copied into it.
    pub texture: &'a wgpu::Texture,
    pub size: [u32; 2],
    /// The left edge of the strip the overlay owns, px; the scene is not drawn right of it.
    pub x0_px: u32,
    /// The frame's background (linear RGB), seen through the panel's translucent fill.
    pub clear: [f32; 3],
}

/// Whether two tessellations paint the same pixels (paint callbacks never compare equal). Floats
/// are compared by their bits: egui can emit NaN positions, which epaint refuses to compare.
fn same_shapes(a: &[egui::ClippedPrimitive], b: &[egui::ClippedPrimitive]) -> bool {
    let rect_bits = |r: &Rect| [r.min.x, r.min.y, r.max.x, r.max.y].map(f32::to_bits);
    let vertex_bits = |v: &egui::epaint::Vertex| {
        (
            [v.pos.x, v.pos.y, v.uv.x, v.uv.y].map(f32::to_bits),
            v.color.to_array(),
        )
    };
    a.len() == b.len()
        && a.iter().zip(b).all(|(a, b)| {
            rect_bits(&a.clip_rect) == rect_bits(&b.clip_rect)
                && match (&a.primitive, &b.primitive) {
                    (egui::epaint::Primitive::Mesh(a), egui::epaint::Primitive::Mesh(b)) => {
                        a.texture_id == b.texture_id
                            && a.indices == b.indices
                            && a.vertices.len() == b.vertices.len()
                            && a.vertices
                                .iter()
                                .zip(&b.vertices)
                                .all(|(x, y)| vertex_bits(x) == vertex_bits(y))
                    }
                    _ => false,
                }
        })
}

impl OverlayLayer {
    pub fn new(device: &wgpu::Device, format: wgpu::TextureFormat) -> Self {
        // Dithering off: golden images must not depend on a noise pattern.
        let renderer = egui_wgpu::Renderer::new(device, format, egui_wgpu::RendererOptions::PREDICTABLE);
        let ctx = egui::Context::default();
        ctx.set_visuals(egui::Visuals::dark());
        OverlayLayer {
            ctx,
            renderer,
            format,
            last: None,
            panel: None,
            repaints: 0,
            headless_frames: 0,
        }
    }

    pub fn context(&self) -> egui::Context {
        self.ctx.clone()
    }

    /// Input for an offscreen frame: a fixed clock advancing 1/60 s per frame keeps images
    /// reproducible.
    pub fn headless_input(
        &mut self,
        size: [u32; 2],
        pixels_per_point: f32,
        events: Vec<egui::Event>,
    ) -> egui::RawInput {
        let mut input = egui::RawInput {
            screen_rect: Some(Rect::from_min_size(
                Pos2::ZERO,
                Vec2::new(size[0] as f32, size[1] as f32) / pixels_per_point,
            )),
            time: Some(self.headless_frames as f64 / 60.0),
            predicted_dt: 1.0 / 60.0,
            events,
            focused: true,
            ..Default::default()
        };
        input
            .viewports
            .entry(egui::ViewportId::ROOT)
            .or_default()
            .native_pixels_per_point = Some(pixels_per_point);
        self.headless_frames += 1;
        input
    }

    /// Runs the UI code and tessellates it.
    pub fn run(&mut self, overlay: &Overlay, input: egui::RawInput) -> Painted {
        let mut actions = Vec::new();
        let full = self.ctx.run_ui(input, |ui| {
            // egui may run the closure twice in one frame; only the last pass's answers count.
            actions.clear();
            build(ui, overlay, &mut actions);
        });
        let primitives = self.ctx.tessellate(full.shapes, full.pixels_per_point);
        Painted {
            primitives,
            textures: full.textures_delta,
            pixels_per_point: full.pixels_per_point,
            actions,
            platform_output: full.platform_output,
        }
    }

    /// Uploads the frame's egui textures and paints `painted` into `target`: into the panel
    /// texture and copied when the target can be copied to, else directly over the frame.
    pub fn paint(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        target: &PanelTarget<'_>,
        painted: &mut Painted,
    ) {
        let new_textures = !painted.textures.set.is_empty();
        for (id, deltas) in &painted.textures.set {
            for delta in deltas {
                self.renderer.update_texture(device, queue, *id, delta);
            }
        }
        if new_textures && let Some(panel) = self.panel.as_mut() {
            panel.shapes = None;
        }
        let primitives = std::mem::take(&mut painted.primitives);
        self.show(device, queue, target, &primitives, painted.pixels_per_point);
        for id in &painted.textures.free {
            self.renderer.free_texture(id);
        }
        // epaint checks in debug builds that every delta was handled before it is dropped.
        painted.textures.clear();
        self.last = Some((primitives, painted.pixels_per_point));
    }

    pub fn last_pixels_per_point(&self) -> f32 {
        self.last.as_ref().map_or(1.0, |(_, ppp)| *ppp)
    }

    /// Paints the previous frame's shapes again.
    pub fn repaint_last(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, target: &PanelTarget<'_>) {
        if let Some((primitives, ppp)) = self.last.take() {
            self.show(device, queue, target, &primitives, ppp);
            self.last = Some((primitives, ppp));
        }
    }

    /// How many times the panel texture was painted.
    pub fn repaints(&self) -> u64 {
        self.repaints
    }

    fn show(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        target: &PanelTarget<'_>,
        primitives: &[egui::ClippedPrimitive],
        pixels_per_point: f32,
    ) {
        let [width, height] = target.size;
        let x0_px = target.x0_px.min(width.saturating_sub(1));
        let copyable = target.texture.usage().contains(wgpu::TextureUsages::COPY_DST)
            && target.texture.format().remove_srgb_suffix() == self.format.remove_srgb_suffix();
        if !copyable {
            // A swap chain that cannot be copied to: paint over the frame every time.
            let view = target.texture.create_view(&wgpu::TextureViewDescriptor {
                format: Some(self.format),
                ..Default::default()
            });
            self.repaints += 1;
            self.paint_primitives(
                device,
                queue,
                &view,
                None,
                target.size,
                primitives,
                pixels_per_point,
            );
            return;
        }
        let strip = [width - x0_px, height];
        let reusable = self.panel.as_ref().is_some_and(|p| {
            p.x0_px == x0_px
                && p.frame_size == target.size
                && p.clear == target.clear
                && p.shapes
                    .as_ref()
                    .is_some_and(|(s, ppp)| *ppp == pixels_per_point && same_shapes(s, primitives))
        });
        if !reusable {
            if !self
                .panel
                .as_ref()
                .is_some_and(|p| p.x0_px == x0_px && p.frame_size == target.size)
            {
                let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
                let texture = texture_2d(device, "overlay panel", strip, self.format, usage);
                let view = texture.create_view(&Default::default());
                self.panel = Some(PanelTexture {
                    texture,
                    view,
                    x0_px,
                    frame_size: target.size,
                    clear: target.clear,
                    shapes: None,
                });
            }
            // egui works in frame coordinates; the strip's texture starts at x0.
            let dx_pt = x0_px as f32 / pixels_per_point.max(1e-3);
            let shifted: Vec<egui::ClippedPrimitive> = primitives
                .iter()
                .map(|p| {
                    let mut p = p.clone();
                    p.clip_rect = p.clip_rect.translate(Vec2::new(-dx_pt, 0.0));
                    if let egui::epaint::Primitive::Mesh(mesh) = &mut p.primitive {
                        mesh.translate(Vec2::new(-dx_pt, 0.0));
                    }
                    p
                })
                .collect();
            if let Some(panel) = self.panel.take() {
                let clear = crate::gpu::opaque_colour(target.clear);
                self.repaints += 1;
                self.paint_primitives(
                    device,
                    queue,
                    &panel.view,
                    Some(clear),
                    strip,
                    &shifted,
                    pixels_per_point,
                );
                self.panel = Some(PanelTexture {
                    clear: target.clear,
                    shapes: Some((primitives.to_vec(), pixels_per_point)),
                    ..panel
                });
            }
        }
        let Some(panel) = self.panel.as_ref() else {
            return;
        };
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("overlay copy"),
        });
        encoder.copy_texture_to_texture(
            panel.texture.as_image_copy(),
            wgpu::TexelCopyTextureInfo {
                texture: target.texture,
                mip_level: 0,
                origin: wgpu::Origin3d { x: x0_px, y: 0, z: 0 },
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::Extent3d {
                width: strip[0],
                height: strip[1],
                depth_or_array_layers: 1,
            },
        );
        queue.submit([encoder.finish()]);
    }

    /// Paints `primitives` into `view` (`size` px), over its content or over `clear`.
    #[allow(clippy::too_many_arguments)] // The GPU handles, the target and what to paint.
    fn paint_primitives(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        view: &wgpu::TextureView,
        clear: Option<wgpu::Color>,
        size: [u32; 2],
        primitives: &[egui::ClippedPrimitive],
        pixels_per_point: f32,
    ) {
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: size,
            pixels_per_point,
        };
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("overlay"),
        });
        let mut commands = self
            .renderer
            .update_buffers(device, queue, &mut encoder, primitives, &screen);
        {
            let pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("overlay"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: clear.map_or(wgpu::LoadOp::Load, wgpu::LoadOp::Clear),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let mut pass = pass.forget_lifetime();
            self.renderer.render(&mut pass, primitives, &screen);
        }
        commands.push(encoder.finish());
        queue.submit(commands);
    }
}

fn build(ui: &mut egui::Ui, o: &Overlay, actions: &mut Vec<UiAction>) {
    let frame = egui::Frame::side_top_panel(ui.style())
        .fill(Color32::from_rgba_unmultiplied(18, 20, 24, 225))
        .inner_margin(8.0);
    egui::Panel::right("palpus_overlay")
        .exact_size(PANEL_WIDTH_PT)
        .resizable(false)
        .frame(frame)
        .show(ui, |ui| {
            status(ui, o);
            ui.separator();
            match &o.task {
                TaskPanel::None => {}
                TaskPanel::Guided(lines) => {
                    for (text, warning) in lines {
                        let colour = if *warning {
                            Color32::from_rgb(255, 110, 90)
                        } else {
                            Color32::from_rgb(150, 230, 150)
                        };
                        ui.label(egui::RichText::new(text).color(colour));
                    }
                    ui.separator();
                }
                TaskPanel::Exam(line) => {
                    // An exam shows no reading of the attempt: neither guidance nor the forces.
                    ui.label(egui::RichText::new(line).color(Color32::from_rgb(230, 200, 120)));
                    ui.separator();
                    controls(ui, o, actions);
                    return;
                }
            }
            let quantity = o.depth_label.as_deref().unwrap_or("depth");
            plot(
                ui,
                &format!("Force vs {quantity}"),
                &format!("{quantity} mm"),
                &o.force_depth,
                1000.0,
                Color32::from_rgb(255, 170, 60),
            );
            ui.add_space(4.0);
            plot(
                ui,
                "Force vs time",
                "time s",
                &o.force_time,
                1.0,
                Color32::from_rgb(90, 200, 255),
            );
            ui.separator();
            controls(ui, o, actions);
        });
}

fn status(ui: &mut egui::Ui, o: &Overlay) {
    ui.heading("palpus");
    ui.label(format!(
        "Device: {}",
        if o.device_status.is_empty() {
            "—"
        } else {
            &o.device_status
        }
    ));
    let rate = match o.haptic_rate_hz {
        Some(hz) => {
            let color = if hz < RATE_WARN_HZ {
                Color32::from_rgb(255, 90, 80)
            } else {
                Color32::from_rgb(120, 220, 120)
            };
            egui::RichText::new(format!("{hz:.1} Hz")).color(color)
        }
        None => egui::RichText::new("—"),
    };
    ui.horizontal(|ui| {
        ui.label("Haptic rate:");
        ui.label(rate);
    });
    let err = o
        .period_error_s
        .map_or("—".to_string(), |e| format!("{:.1} µs", e * 1e6));
    ui.label(format!("Period error: {err}"));
    match &o.recognized {
        Some(r) if r.decided => {
            ui.label(format!("Surface: {}", r.surface));
            let c = r.confidence.clamp(0.0, 1.0);
            ui.add(egui::ProgressBar::new(c).text(format!("confidence {:.0} %", c * 100.0)));
        }
        Some(r) => {
            ui.label("Surface: undecided");
            let c = r.confidence.clamp(0.0, 1.0);
            ui.add(egui::ProgressBar::new(c).text(format!("most likely {}: {:.0} %", r.surface, c * 100.0)));
        }
        None => {
            ui.label("Surface: —");
        }
    }
}

/// A line plot drawn with the painter: y is force in N, x is scaled by `x_scale` for display.
fn plot(ui: &mut egui::Ui, title: &str, x_label: &str, points: &[[f32; 2]], x_scale: f32, color: Color32) {
    let width = ui.available_width();
    let (response, painter) = ui.allocate_painter(Vec2::new(width, 118.0), Sense::hover());
    let rect = response.rect;
    painter.rect_filled(rect, 3.0, Color32::from_gray(10));
    painter.rect_stroke(
        rect,
        3.0,
        Stroke::new(1.0, Color32::from_gray(60)),
        StrokeKind::Inside,
    );
    let font = FontId::proportional(11.0);
    let text = Color32::from_gray(200);
    painter.text(
        rect.left_top() + Vec2::new(6.0, 3.0),
        Align2::LEFT_TOP,
        title,
        font.clone(),
        text,
    );
    let area = Rect::from_min_max(
        rect.left_top() + Vec2::new(40.0, 18.0),
        rect.right_bottom() - Vec2::new(8.0, 18.0),
    );
    let finite: Vec<[f32; 2]> = points
        .iter()
        .filter(|p| p[0].is_finite() && p[1].is_finite())
        .map(|p| [p[0] * x_scale, p[1]])
        .collect();
    let (mut x0, mut x1) = finite
        .iter()
        .fold((f32::MAX, f32::MIN), |(a, b), p| (a.min(p[0]), b.max(p[0])));
    let (mut y0, mut y1) = finite
        .iter()
        .fold((0.0f32, f32::MIN), |(a, b), p| (a.min(p[1]), b.max(p[1])));
    if finite.is_empty() || x1 - x0 <= f32::EPSILON {
        x0 = x0.clamp(-1e6, 0.0);
        x1 = x0 + 1.0;
    }
    if finite.is_empty() || y1 - y0 <= f32::EPSILON {
        y0 = 0.0;
        y1 = 1.0;
    } else {
        y1 += 0.08 * (y1 - y0);
    }
    let axis = Stroke::new(1.0, Color32::from_gray(110));
    painter.line_segment([area.left_bottom(), area.right_bottom()], axis);
    painter.line_segment([area.left_bottom(), area.left_top()], axis);
    let small = FontId::proportional(10.0);
    painter.text(
        area.left_top() - Vec2::new(4.0, 0.0),
        Align2::RIGHT_TOP,
        format!("{y1:.1}"),
        small.clone(),
        text,
    );
    painter.text(
        area.left_bottom() - Vec2::new(4.0, 0.0),
        Align2::RIGHT_BOTTOM,
        format!("{y0:.1}"),
        small.clone(),
        text,
    );
    painter.text(
        area.left_center() - Vec2::new(4.0, 0.0),
        Align2::RIGHT_CENTER,
        "N",
        small.clone(),
        text,
    );
    let below = area.left_bottom() + Vec2::new(0.0, 2.0);
    painter.text(below, Align2::LEFT_TOP, format!("{x0:.1}"), small.clone(), text);
    painter.text(
        area.right_bottom() + Vec2::new(0.0, 2.0),
        Align2::RIGHT_TOP,
        format!("{x1:.1}"),
        small.clone(),
        text,
    );
    painter.text(
        area.center_bottom() + Vec2::new(0.0, 2.0),
        Align2::CENTER_TOP,
        x_label,
        small,
        text,
    );
    if finite.len() >= 2 {
        let to_screen = |p: &[f32; 2]| {
            Pos2::new(
                area.left() + (p[0] - x0) / (x1 - x0) * area.width(),
                area.bottom() - (p[1] - y0) / (y1 - y0) * area.height(),
            )
        };
        let line: Vec<Pos2> = finite.iter().map(to_screen).collect();
        painter.add(Shape::line(line, Stroke::new(1.5, color)));
    }
}

fn controls(ui: &mut egui::Ui, o: &Overlay, actions: &mut Vec<UiAction>) {
    if !o.scenes.is_empty() {
        ui.label("Scene");
        ui.horizontal_wrapped(|ui| {
            for (index, name) in o.scenes.iter().enumerate() {
                let selected = o.current_scene == Some(index);
                if ui.selectable_label(selected, name.as_str()).clicked() && !selected {
                    actions.push(UiAction::SelectScene {
                        index,
                        name: name.clone(),
                    });
                }
            }
        });
    }
    for p in &o.params {
        let (lo, hi) = if p.min <= p.max {
            (p.min, p.max)
        } else {
            (p.max, p.min)
        };
        let mut value = p.value;
        let mut slider = egui::Slider::new(&mut value, lo..=hi).text(p.name.as_str());
        if !p.unit.is_empty() {
            slider = slider.suffix(format!(" {}", p.unit));
        }
        if ui.add(slider).changed() && value != p.value {
            actions.push(UiAction::SetParam {
                name: p.name.clone(),
                value,
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn primitive(x: f32, color: Color32) -> egui::ClippedPrimitive {
        let mut mesh = egui::epaint::Mesh::default();
        mesh.colored_vertex(Pos2::new(x, 1.0), color);
        mesh.colored_vertex(Pos2::new(2.0, f32::NAN), color);
        mesh.add_triangle(0, 1, 0);
        egui::ClippedPrimitive {
            clip_rect: Rect::from_min_max(Pos2::ZERO, Pos2::new(10.0, 10.0)),
            primitive: egui::epaint::Primitive::Mesh(mesh),
        }
    }

    #[test]
    fn shapes_with_nan_positions_compare_by_bits() {
        let a = vec![primitive(1.0, Color32::RED)];
        assert!(same_shapes(&a, &a.clone()));
        assert!(!same_shapes(&a, &[primitive(1.5, Color32::RED)]));
        assert!(!same_shapes(&a, &[primitive(1.0, Color32::BLUE)]));
        assert!(!same_shapes(&a, &[]));
    }
}
