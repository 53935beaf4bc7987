//! The renderer: one drawing path for windows and offscreen images. A frame is drawn into a
//! colour texture (a swap-chain image or an offscreen texture); the overlay's panel is copied
//! into the strip the scene leaves free (see [`crate::overlay`]); headless rendering then copies
//! the texture back to the CPU.

use std::collections::HashMap;
use std::sync::{Arc, Weak};
use std::time::{Duration, Instant};

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};
use wgpu::util::DeviceExt;

use crate::error::RenderError;
use crate::frame::{Frame, MAX_DIMPLES, Object, UiAction};
use crate::gpu::{DEPTH_FORMAT, Gpu, GpuOptions, opaque_colour, wait};
use crate::image::Image;
use crate::mesh::MeshData;
use crate::offscreen::Offscreen;
use crate::overlay::{OverlayLayer, PanelTarget};
use crate::upscale::Upscaler;

/// Offscreen images: 8-bit sRGB so lighting computed in linear space is encoded on store.
pub const HEADLESS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// Uniform slots must start at multiples of the device's offset alignment (256 on every backend).
const OBJECT_SLOT_BYTES: u64 = 256;
/// Largest image side accepted; lavapipe and most GPUs allow 8192 or more.
const MAX_SIDE_PX: u32 = 8192;
/// Smallest internal resolution scale accepted: below it the picture is a blur.
const MIN_SCALE: f32 = 0.25;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GlobalsUniform {
    view_proj: [[f32; 4]; 4],
    eye_m: [f32; 4],
    key_dir: [f32; 4],
    dimple_centre: [[f32; 4]; MAX_DIMPLES],
    dimple_normal: [[f32; 4]; MAX_DIMPLES],
    counts: [u32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ObjectUniform {
    model: [[f32; 4]; 4],
    normal_model: [[f32; 4]; 4],
    color: [f32; 4],
    surface: [f32; 4],
    flags: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Vertex {
    position: [f32; 3],
    normal: [f32; 3],
    color: [f32; 4],
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Pass {
    Opaque,
    Translucent,
    /// The tool's hidden parts, over see-through tissue.
    Xray,
}

struct GpuMesh {
    /// Detects a freed mesh whose address was reused by a new one.
    source: Weak<MeshData>,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
    /// The first indices, those of the triangles outside ([`MeshData::interior_from`]).
    exterior_count: u32,
    /// Corners of the model-space bounding box, m (zero for an empty mesh).
    bounds_m: [Vec3; 2],
}

struct Attachments {
    /// The frame's size and the width of the scene's part of it, px.
    size: [u32; 2],
    scene_width: u32,
    msaa_view: Option<wgpu::TextureView>,
    /// The same samples viewed without sRGB, for the opaque pass when it encodes them itself.
    encoded_view: Option<wgpu::TextureView>,
    depth_view: wgpu::TextureView,
    /// The scene at the internal resolution, when it is lower than the frame's.
    low: Option<(wgpu::TextureView, wgpu::BindGroup)>,
    /// With MSAA beside the overlay's panel, the scene's strip resolved, then copied into the
    /// frame: multisampled attachments only as wide as the scene.
    strip: Option<(wgpu::Texture, wgpu::TextureView)>,
}

/// Wall-clock time per stage of one frame, measured by waiting for the GPU after each stage.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StageTimes {
    /// Uploading uniforms, encoding and executing the scene pass (and the overlay pass).
    pub draw: Duration,
    /// Resolving the multisampled image into the single-sample target (and copying the scene's
    /// strip into the frame beside the overlay).
    pub resolve: Duration,
    /// Building the overlay's UI and tessellating it (CPU).
    pub overlay_cpu: Duration,
    /// Copying the image to a CPU buffer and unpadding it.
    pub readback: Duration,
}

/// How the overlay is produced for a drawn frame.
pub(crate) enum OverlayInput {
    /// Run the UI with this input (a new frame).
    Run(egui::RawInput),
    /// Paint the previous frame's shapes again (a screenshot must not consume input twice).
    Replay { pixels_per_point: f32 },
}

impl OverlayInput {
    fn pixels_per_point(&self) -> f32 {
        match self {
            OverlayInput::Run(input) => input
                .viewports
                .get(&egui::ViewportId::ROOT)
                .and_then(|v| v.native_pixels_per_point)
                .unwrap_or(1.0),
            OverlayInput::Replay { pixels_per_point } => *pixels_per_point,
        }
    }
}

/// What one drawn frame returns besides pixels.
#[derive(Default)]
pub(crate) struct DrawOutput {
    pub actions: Vec<UiAction>,
    pub platform_output: Option<egui::PlatformOutput>,
}

/// Draws [`Frame`]s. Create it with [`Renderer::headless`] for images; the window module creates
/// one for its surface.
pub struct Renderer {
    gpu: Gpu,
    format: wgpu::TextureFormat,
    msaa: u32,
    /// On a software rasterizer, opaque surfaces are drawn in a pass of their own into the
    /// multisampled target viewed without sRGB, their colour encoded by the fragment shader:
    /// lavapipe encodes to sRGB in software on every store, so with 4 samples it encoded each
    /// pixel four times. See-through layers, which must blend in linear light, follow in a pass
    /// with the sRGB view, and the resolve averages the samples decoded, as before; the picture
    /// is the same.
    encoded_opaque: bool,
    opaque: wgpu::RenderPipeline,
    translucent: wgpu::RenderPipeline,
    xray: wgpu::RenderPipeline,
    globals: wgpu::Buffer,
    globals_group: wgpu::BindGroup,
    object_layout: wgpu::BindGroupLayout,
    objects: wgpu::Buffer,
    objects_group: wgpu::BindGroup,
    object_slots: u64,
    meshes: HashMap<usize, GpuMesh>,
    attachments: Option<Attachments>,
    offscreen: Option<Offscreen>,
    overlay: OverlayLayer,
    /// Internal resolution of the scene relative to the frame (1 = full).
    scale: f32,
    upscaler: Option<Upscaler>,
}

impl std::fmt::Debug for Renderer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Renderer")
            .field("adapter", &self.gpu.adapter_description())
            .field("format", &self.format)
            .field("msaa", &self.msaa)
            .field("meshes", &self.meshes.len())
            .finish()
    }
}

fn check_size(width: u32, height: u32) -> Result<(), RenderError> {
    if width == 0 || height == 0 || width > MAX_SIDE_PX || height > MAX_SIDE_PX {
        return Err(RenderError::BadSize {
            width,
            height,
            max: MAX_SIDE_PX,
        });
    }
    Ok(())
}

impl Renderer {
    /// An offscreen renderer of `width`×`height` px with `msaa` samples (1 or 4; 4 falls back to
    /// 1 where the adapter lacks it — see [`Renderer::msaa`]). Tries Vulkan, then GL.
    pub fn headless(width: u32, height: u32, msaa: u32) -> Result<Self, RenderError> {
        Self::headless_with(width, height, msaa, &GpuOptions::default())
    }

    /// [`Renderer::headless`] on the backends of `options`.
    pub fn headless_with(
        width: u32,
        height: u32,
        msaa: u32,
        options: &GpuOptions,
    ) -> Result<Self, RenderError> {
        check_size(width, height)?;
        if msaa != 1 && msaa != 4 {
            return Err(RenderError::BadMsaa(msaa));
        }
        let gpu = Gpu::headless(options)?;
        let mut renderer = Self::new(gpu, HEADLESS_FORMAT, msaa)?;
        renderer.ensure_offscreen([width, height]);
        Ok(renderer)
    }

    pub(crate) fn new(gpu: Gpu, format: wgpu::TextureFormat, msaa: u32) -> Result<Self, RenderError> {
        // A GPU encodes sRGB on store in hardware, for free: there the second pass would only
        // cost.
        let software = gpu.is_software();
        Self::with_encoding(gpu, format, msaa, software)
    }

    /// [`Renderer::new`], the opaque pass encoding its own sRGB only if `allow_encoded` (and
    /// the adapter can; see `encoded_opaque`).
    fn with_encoding(
        gpu: Gpu,
        format: wgpu::TextureFormat,
        msaa: u32,
        allow_encoded: bool,
    ) -> Result<Self, RenderError> {
        if msaa != 1 && msaa != 4 {
            return Err(RenderError::BadMsaa(msaa));
        }
        let msaa = gpu.supported_msaa(format, msaa);
        let encoded_opaque = allow_encoded && msaa > 1 && format.is_srgb() && gpu.srgb_views();
        let device = &gpu.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("scene.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("scene.wgsl").into()),
        });
        let uniform_entry = |dynamic: bool, size: u64| wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: dynamic,
                min_binding_size: wgpu::BufferSize::new(size),
            },
            count: None,
        };
        let globals_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("globals"),
            entries: &[uniform_entry(false, size_of::<GlobalsUniform>() as u64)],
        });
        let object_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("object"),
            entries: &[uniform_entry(true, size_of::<ObjectUniform>() as u64)],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("scene"),
            bind_group_layouts: &[Some(&globals_layout), Some(&object_layout)],
            immediate_size: 0,
        });
        let pipeline = |kind: Pass| {
            let translucent = kind != Pass::Opaque;
            let encoded = encoded_opaque && kind == Pass::Opaque;
            let attributes = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x4];
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(match kind {
                    Pass::Opaque => "scene opaque",
                    Pass::Translucent => "scene translucent",
                    Pass::Xray => "tool x-ray",
                }),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &shader,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: size_of::<Vertex>() as u64,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &attributes,
                    })],
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    front_face: wgpu::FrontFace::Ccw,
                    cull_mode: Some(wgpu::Face::Back),
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    // See-through layers are drawn after everything opaque, back to front, so
                    // writing depth hides nothing already drawn; it lets the x-ray pass find
                    // where tissue covers the tool.
                    depth_write_enabled: Some(kind != Pass::Xray),
                    depth_compare: Some(if kind == Pass::Xray {
                        wgpu::CompareFunction::Greater
                    } else {
                        wgpu::CompareFunction::LessEqual
                    }),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: wgpu::MultisampleState {
                    count: msaa,
                    mask: !0,
                    alpha_to_coverage_enabled: false,
                },
                fragment: Some(wgpu::FragmentState {
                    module: &shader,
                    entry_point: Some(match kind {
                        Pass::Xray => "fs_xray",
                        _ if encoded => "fs_encoded",
                        _ => "fs_main",
                    }),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: if encoded {
                            format.remove_srgb_suffix()
                        } else {
                            format
                        },
                        blend: Some(if translucent {
                            wgpu::BlendState::ALPHA_BLENDING
                        } else {
                            wgpu::BlendState::REPLACE
                        }),
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let opaque = pipeline(Pass::Opaque);
        let translucent = pipeline(Pass::Translucent);
        let xray = pipeline(Pass::Xray);
        let globals = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("globals"),
            size: size_of::<GlobalsUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let globals_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("globals"),
            layout: &globals_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: globals.as_entire_binding(),
            }],
        });
        let object_slots = 16;
        let (objects, objects_group) = make_object_buffer(device, &object_layout, object_slots);
        if let Some(err) = pollster::block_on(scope.pop()) {
            return Err(RenderError::Gpu(err.to_string()));
        }
        let overlay = OverlayLayer::new(device, format);
        Ok(Renderer {
            gpu,
            format,
            msaa,
            encoded_opaque,
            opaque,
            translucent,
            xray,
            globals,
            globals_group,
            object_layout,
            objects,
            objects_group,
            object_slots,
            meshes: HashMap::new(),
            attachments: None,
            offscreen: None,
            overlay,
            scale: 1.0,
            upscaler: None,
        })
    }

    /// Draws the 3-D scene at `scale` (0.25..=1) times the frame's resolution and stretches it
    /// over the frame: fewer pixels to shade for a softer picture (the overlay stays sharp).
    /// 1 draws at full resolution.
    pub fn set_scale(&mut self, scale: f32) -> Result<(), RenderError> {
        if !(MIN_SCALE..=1.0).contains(&scale) {
            return Err(RenderError::BadScale(scale));
        }
        self.scale = scale;
        self.attachments = None;
        Ok(())
    }

    /// The internal resolution scale (see [`Renderer::set_scale`]).
    pub fn scale(&self) -> f32 {
        self.scale
    }

    fn ensure_upscaler(&mut self) {
        let (device, format) = (&self.gpu.device, self.format);
        self.upscaler.get_or_insert_with(|| Upscaler::new(device, format));
    }

    /// The MSAA sample count in use (1 or 4).
    pub fn msaa(&self) -> u32 {
        self.msaa
    }

    /// The offscreen image size, px.
    pub fn size(&self) -> Option<[u32; 2]> {
        self.offscreen.as_ref().map(|o| o.size)
    }

    /// The adapter, e.g. "llvmpipe (LLVM 19.1.7, 256 bits) on Vulkan (Cpu)".
    pub fn adapter_description(&self) -> String {
        self.gpu.adapter_description()
    }

    /// Changes the offscreen image size.
    pub fn resize(&mut self, width: u32, height: u32) -> Result<(), RenderError> {
        check_size(width, height)?;
        self.ensure_offscreen([width, height]);
        Ok(())
    }

    pub(crate) fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    pub(crate) fn egui_context(&self) -> egui::Context {
        self.overlay.context()
    }

    /// Draws `frame` offscreen and returns the picture (overlay included when the frame has one).
    pub fn render(&mut self, frame: &Frame) -> Result<Image, RenderError> {
        self.render_timed(frame, None).map(|(image, _)| image)
    }

    /// Like [`Renderer::render`], feeding `events` (pointer moves, clicks) to the overlay first
    /// and returning what the user asked for.
    pub fn render_with_events(
        &mut self,
        frame: &Frame,
        events: Vec<egui::Event>,
    ) -> Result<(Image, Vec<UiAction>), RenderError> {
        let size = self.offscreen_size()?;
        let input = self.overlay.headless_input(size, 1.0, events);
        let texture = self.offscreen_texture()?;
        let out = self.draw(frame, &texture, OverlayInput::Run(input), None)?;
        let image = self.read_back(None)?;
        Ok((image, out.actions))
    }

    /// Draws and reads back with a time per stage when `timer` is given (the GPU is waited for
    /// after each stage, which costs some throughput).
    pub(crate) fn render_timed(
        &mut self,
        frame: &Frame,
        mut timer: Option<&mut StageTimes>,
    ) -> Result<(Image, Vec<UiAction>), RenderError> {
        let size = self.offscreen_size()?;
        let input = self.overlay.headless_input(size, 1.0, Vec::new());
        let texture = self.offscreen_texture()?;
        let out = self.draw(frame, &texture, OverlayInput::Run(input), timer.as_deref_mut())?;
        let image = self.read_back(timer)?;
        Ok((image, out.actions))
    }

    fn offscreen_size(&self) -> Result<[u32; 2], RenderError> {
        self.offscreen
            .as_ref()
            .map(|o| o.size)
            .ok_or_else(|| RenderError::Gpu("no offscreen target".into()))
    }

    fn offscreen_texture(&self) -> Result<wgpu::Texture, RenderError> {
        self.offscreen
            .as_ref()
            .map(|o| o.texture.clone())
            .ok_or_else(|| RenderError::Gpu("no offscreen target".into()))
    }

    /// How many times the overlay's panel was painted (it is reused while its shapes stay the
    /// same).
    pub fn overlay_repaints(&self) -> u64 {
        self.overlay.repaints()
    }

    pub(crate) fn ensure_offscreen(&mut self, size: [u32; 2]) {
        if self.offscreen.as_ref().is_some_and(|o| o.size == size) {
            return;
        }
        self.offscreen = Some(Offscreen::new(&self.gpu.device, self.format, size));
    }

    /// Attachments for a frame of `size` px whose scene fills its left `scene_width` px, drawn
    /// at `scale` (into a texture of its own below 1, as wide as the scene alone). `strip` sizes
    /// the multisampled attachments to the scene alone when its resolved image can be copied
    /// into the frame: lavapipe clears and resolves every sample of them each frame, the part
    /// the overlay's panel then covers too.
    fn ensure_attachments(&mut self, size: [u32; 2], scene_width: u32, strip: bool) {
        let strip = strip && self.msaa > 1 && self.scale >= 1.0 && scene_width < size[0];
        if self
            .attachments
            .as_ref()
            .is_some_and(|a| a.size == size && a.scene_width == scene_width && a.strip.is_some() == strip)
        {
            return;
        }
        let low_size = self.internal_size([scene_width, size[1]]);
        if self.scale < 1.0 {
            self.ensure_upscaler();
        }
        let low = self
            .upscaler
            .as_ref()
            .filter(|_| self.scale < 1.0)
            .map(|up| up.target(&self.gpu.device, self.format, low_size));
        let device = &self.gpu.device;
        let extent = wgpu::Extent3d {
            width: if strip || self.scale < 1.0 {
                low_size[0]
            } else {
                size[0]
            },
            height: low_size[1],
            depth_or_array_layers: 1,
        };
        let encoded = [self.format.remove_srgb_suffix()];
        let make = |label, format, samples, usage, view_formats| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: extent,
                mip_level_count: 1,
                sample_count: samples,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats,
            })
        };
        let attachment = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let view = |t: wgpu::Texture| t.create_view(&Default::default());
        let samples_views: &[wgpu::TextureFormat] = if self.encoded_opaque { &encoded } else { &[] };
        let samples =
            (self.msaa > 1).then(|| make("msaa colour", self.format, self.msaa, attachment, samples_views));
        let encoded_view = samples.as_ref().filter(|_| self.encoded_opaque).map(|t| {
            t.create_view(&wgpu::TextureViewDescriptor {
                format: Some(encoded[0]),
                ..Default::default()
            })
        });
        let msaa_view = samples.map(view);
        let depth_view = view(make("depth", DEPTH_FORMAT, self.msaa, attachment, &[]));
        let strip = strip.then(|| {
            let texture = make(
                "scene strip",
                self.format,
                1,
                attachment | wgpu::TextureUsages::COPY_SRC,
                &[],
            );
            let view = texture.create_view(&Default::default());
            (texture, view)
        });
        self.attachments = Some(Attachments {
            size,
            scene_width,
            msaa_view,
            encoded_view,
            depth_view,
            low,
            strip,
        });
    }

    /// The scene's size in px at the internal resolution.
    fn internal_size(&self, size: [u32; 2]) -> [u32; 2] {
        size.map(|s| ((s as f32 * self.scale).round() as u32).clamp(1, s.max(1)))
    }

    fn upload_mesh(&mut self, mesh: &Arc<MeshData>) -> usize {
        let key = Arc::as_ptr(mesh) as usize;
        if let Some(m) = self.meshes.get(&key)
            && m.source.upgrade().is_some_and(|s| Arc::ptr_eq(&s, mesh))
        {
            return key;
        }
        let vertices: Vec<Vertex> = (0..mesh.positions.len())
            .map(|i| Vertex {
                position: mesh.positions[i],
                normal: mesh.normals.get(i).copied().unwrap_or([0.0, 1.0, 0.0]),
                color: mesh.colors.get(i).copied().unwrap_or([1.0; 4]),
            })
            .collect();
        // Out-of-range indices would be a validation error on the GPU; such triangles are dropped.
        let count = vertices.len() as u32;
        let valid = |indices: &[u32]| -> Vec<u32> {
            indices
                .chunks_exact(3)
                .filter(|t| t.iter().all(|&i| i < count))
                .flatten()
                .copied()
                .collect()
        };
        let mut indices = valid(mesh.exterior_indices());
        let exterior_count = indices.len() as u32;
        indices.extend(valid(mesh.interior_indices()));
        let (lo, hi) = mesh
            .positions
            .iter()
            .fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), p| {
                (lo.min(Vec3::from(*p)), hi.max(Vec3::from(*p)))
            });
        let bounds_m = if mesh.positions.is_empty() {
            [Vec3::ZERO; 2]
        } else {
            [lo, hi]
        };
        let device = &self.gpu.device;
        // Zero-sized buffers are not allowed; an empty mesh still gets a tiny one and draws nothing.
        let vertex_bytes: &[u8] = if vertices.is_empty() {
            &[0; 40]
        } else {
            bytemuck::cast_slice(&vertices)
        };
        let index_bytes: &[u8] = if indices.is_empty() {
            &[0; 4]
        } else {
            bytemuck::cast_slice(&indices)
        };
        let gpu_mesh = GpuMesh {
            source: Arc::downgrade(mesh),
            vertices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(&mesh.name),
                contents: vertex_bytes,
                usage: wgpu::BufferUsages::VERTEX,
            }),
            indices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(&mesh.name),
                contents: index_bytes,
                usage: wgpu::BufferUsages::INDEX,
            }),
            index_count: indices.len() as u32,
            exterior_count,
            bounds_m,
        };
        self.meshes.insert(key, gpu_mesh);
        key
    }

    /// Draws `frame` into `target` and puts the overlay over it.
    pub(crate) fn draw(
        &mut self,
        frame: &Frame,
        target: &wgpu::Texture,
        overlay_input: OverlayInput,
        mut timer: Option<&mut StageTimes>,
    ) -> Result<DrawOutput, RenderError> {
        let start = Instant::now();
        let size = [target.width(), target.height()];
        let view = &target.create_view(&wgpu::TextureViewDescriptor {
            format: Some(self.format),
            ..Default::default()
        });
        // With the overlay on, the scene is framed in the part of the image the panel leaves free.
        let scene_width = match &frame.overlay {
            Some(_) => {
                let ppp = overlay_input.pixels_per_point();
                let panel_px = (crate::overlay::PANEL_WIDTH_PT * ppp).round() as u32;
                size[0].saturating_sub(panel_px).max(size[0] / 3).max(1)
            }
            None => size[0],
        };
        // The strip is copied into the frame, as the overlay's panel is.
        let copyable = target.usage().contains(wgpu::TextureUsages::COPY_DST)
            && target.format().remove_srgb_suffix() == self.format.remove_srgb_suffix();
        self.ensure_attachments(size, scene_width, copyable);
        // Forget meshes the app no longer holds.
        self.meshes.retain(|_, m| m.source.strong_count() > 0);

        struct Item {
            mesh: usize,
            translucent: bool,
            tool: bool,
            distance_m: f32,
            /// World-space bounding box, m.
            bounds_m: [Vec3; 2],
        }
        let punctured = frame.tissue.punctured;
        let see_through = frame.tissue.punctured_opacity.clamp(0.0, 1.0);
        let mut uniforms = Vec::new();
        let mut items = Vec::new();
        let tool_parts = frame
            .tool
            .iter()
            .flat_map(|t| t.parts.iter().map(move |p| (t.pose, p, true)));
        let all: Vec<(Mat4, &Object, bool)> = frame
            .objects
            .iter()
            .map(|o| (Mat4::IDENTITY, o, false))
            .chain(tool_parts)
            .collect();
        for (parent, object, tool) in all {
            let key = self.upload_mesh(&object.mesh);
            let model = parent * object.transform;
            let mut color = object.material.color;
            if object.deformable && punctured {
                color[3] = color[3].min(see_through);
            }
            let m = &object.material;
            uniforms.push(ObjectUniform {
                model: model.to_cols_array_2d(),
                normal_model: model.inverse().transpose().to_cols_array_2d(),
                color,
                surface: [
                    m.roughness.clamp(0.0, 1.0),
                    m.detail_period_m,
                    m.specular,
                    m.shininess.max(1.0),
                ],
                flags: [if object.deformable { 1.0 } else { 0.0 }, 0.0, 0.0, 0.0],
            });
            let [lo, hi] = self.meshes.get(&key).map_or([Vec3::ZERO; 2], |g| g.bounds_m);
            let distance_m = model
                .transform_point3((lo + hi) * 0.5)
                .distance(frame.camera.eye_m);
            let corners = (0..8).map(|k| {
                let pick = |bit: u32, l: f32, h: f32| if k & bit == 0 { l } else { h };
                model.transform_point3(Vec3::new(
                    pick(1, lo.x, hi.x),
                    pick(2, lo.y, hi.y),
                    pick(4, lo.z, hi.z),
                ))
            });
            let bounds_m = corners.fold([Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)], |[l, h], c| {
                [l.min(c), h.max(c)]
            });
            items.push(Item {
                mesh: key,
                translucent: color[3] < 0.999,
                tool,
                distance_m,
                bounds_m,
            });
        }
        self.write_uniforms(frame, [scene_width, size[1]], &uniforms);

        let order: Vec<(usize, Pass)> = {
            let mut order: Vec<(usize, Pass)> = (0..items.len())
                .filter(|&i| !items[i].translucent)
                .map(|i| (i, Pass::Opaque))
                .collect();
            let clear: Vec<usize> = (0..items.len()).filter(|&i| items[i].translucent).collect();
            // See-through objects write depth (the x-ray pass needs it), so one inside another (a
            // vessel in its organ) goes first, or the organ's nearer surface would hide it.
            // Otherwise back to front, so nearer see-through layers blend over farther ones.
            let inside = |a: usize, b: usize| {
                let ([la, ha], [lb, hb]) = (items[a].bounds_m, items[b].bounds_m);
                a != b && lb.cmple(la).all() && ha.cmple(hb).all()
            };
            let nesting = |a: usize| clear.iter().filter(|&&b| inside(a, b)).count();
            let mut clear: Vec<(usize, usize)> = clear.iter().map(|&i| (nesting(i), i)).collect();
            clear.sort_by(|&(na, a), &(nb, b)| {
                nb.cmp(&na)
                    .then(items[b].distance_m.total_cmp(&items[a].distance_m))
            });
            order.extend(clear.into_iter().map(|(_, i)| (i, Pass::Translucent)));
            if punctured {
                order.extend(
                    (0..items.len())
                        .filter(|&i| items[i].tool && !items[i].translucent)
                        .map(|i| (i, Pass::Xray)),
                );
            }
            order
        };
        // Interior faces can only be seen through something see-through.
        let see_through_anything = items.iter().any(|i| i.translucent);

        let device = &self.gpu.device;
        let queue = &self.gpu.queue;
        let Some(att) = self.attachments.as_ref() else {
            return Err(RenderError::Gpu("attachments missing".into()));
        };
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let split_resolve = timer.is_some() && att.msaa_view.is_some();
        // Below full resolution the scene goes to its own texture, stretched over the frame
        // afterwards; beside the panel with MSAA, to its strip, copied into the frame.
        let scene_view = match (&att.low, &att.strip) {
            (Some((low, _)), _) => low,
            (None, Some((_, strip))) => strip,
            (None, None) => view,
        };
        let mut encoder =
            device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("scene") });
        let clear = opaque_colour(frame.clear_color);
        // The opaque pass encodes its own colour into the samples viewed without sRGB; the
        // see-through pass, which blends, and the resolve use the sRGB view (`encoded_opaque`).
        let first_see_through = order
            .iter()
            .position(|&(_, kind)| kind != Pass::Opaque)
            .unwrap_or(order.len());
        let passes: Vec<(&wgpu::TextureView, &[(usize, Pass)])> = match (&att.encoded_view, &att.msaa_view) {
            (Some(encoded), Some(msaa)) => vec![
                (encoded, &order[..first_see_through]),
                (msaa, &order[first_see_through..]),
            ],
            (None, Some(msaa)) => vec![(msaa, &order[..])],
            (_, None) => vec![(scene_view, &order[..])],
        };
        // The scene's part of the frame, or the whole of its own texture below full resolution.
        let [scene_w, scene_h] = self.internal_size([scene_width, size[1]]);
        let last = passes.len() - 1;
        for (p, (color_view, pass_items)) in passes.into_iter().enumerate() {
            let resolve_target =
                (p == last && att.msaa_view.is_some() && !split_resolve).then_some(scene_view);
            // The see-through pass goes on from the opaque pass's samples and depth.
            let (color_load, depth_load) = if p == 0 {
                // The view without sRGB stores the clear colour as given.
                let clear = if att.encoded_view.is_some() {
                    srgb_encoded(clear)
                } else {
                    clear
                };
                (wgpu::LoadOp::Clear(clear), wgpu::LoadOp::Clear(1.0))
            } else {
                (wgpu::LoadOp::Load, wgpu::LoadOp::Load)
            };
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(if p == 0 { "scene" } else { "scene see-through" }),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: color_view,
                    depth_slice: None,
                    resolve_target,
                    ops: wgpu::Operations {
                        load: color_load,
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &att.depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: depth_load,
                        store: if p == last {
                            wgpu::StoreOp::Discard
                        } else {
                            wgpu::StoreOp::Store
                        },
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_viewport(0.0, 0.0, scene_w as f32, scene_h as f32, 0.0, 1.0);
            pass.set_bind_group(0, &self.globals_group, &[]);
            for &(i, kind) in pass_items {
                let item = &items[i];
                let Some(mesh) = self.meshes.get(&item.mesh) else {
                    continue;
                };
                let index_count = if see_through_anything {
                    mesh.index_count
                } else {
                    mesh.exterior_count
                };
                if index_count == 0 {
                    continue;
                }
                pass.set_pipeline(match kind {
                    Pass::Opaque => &self.opaque,
                    Pass::Translucent => &self.translucent,
                    Pass::Xray => &self.xray,
                });
                pass.set_bind_group(1, &self.objects_group, &[(i as u64 * OBJECT_SLOT_BYTES) as u32]);
                pass.set_vertex_buffer(0, mesh.vertices.slice(..));
                pass.set_index_buffer(mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..index_count, 0, 0..1);
            }
        }
        queue.submit([encoder.finish()]);
        if let Some(t) = timer.as_deref_mut() {
            wait(device)?;
            t.draw += start.elapsed();
        }
        if split_resolve && let Some(msaa) = &att.msaa_view {
            let start = Instant::now();
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("resolve"),
            });
            encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("resolve"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: msaa,
                    depth_slice: None,
                    resolve_target: Some(scene_view),
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Discard,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            queue.submit([encoder.finish()]);
            wait(device)?;
            if let Some(t) = timer.as_deref_mut() {
                t.resolve += start.elapsed();
            }
        }

        if let Some((strip, _)) = &att.strip {
            let start = Instant::now();
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("scene strip copy"),
            });
            encoder.copy_texture_to_texture(strip.as_image_copy(), target.as_image_copy(), strip.size());
            queue.submit([encoder.finish()]);
            if let Some(t) = timer.as_deref_mut() {
                wait(device)?;
                t.resolve += start.elapsed();
            }
        }

        if let (Some((_, group)), Some(up)) = (&att.low, &self.upscaler) {
            let start = Instant::now();
            up.draw(device, queue, view, group, [scene_width, size[1]]);
            if let Some(t) = timer.as_deref_mut() {
                wait(device)?;
                t.draw += start.elapsed();
            }
        }

        let mut out = DrawOutput::default();
        let panel = PanelTarget {
            texture: target,
            size,
            x0_px: scene_width,
            clear: frame.clear_color,
        };
        if let (Some(_), OverlayInput::Replay { .. }) = (&frame.overlay, &overlay_input) {
            self.overlay.repaint_last(device, queue, &panel);
        } else if let (Some(overlay), OverlayInput::Run(overlay_input)) = (&frame.overlay, overlay_input) {
            let cpu_start = Instant::now();
            let mut painted = self.overlay.run(overlay, overlay_input);
            if let Some(t) = timer.as_deref_mut() {
                t.overlay_cpu += cpu_start.elapsed();
            }
            let gpu_start = Instant::now();
            self.overlay.paint(device, queue, &panel, &mut painted);
            out.actions = std::mem::take(&mut painted.actions);
            out.platform_output = Some(std::mem::take(&mut painted.platform_output));
            if let Some(t) = timer {
                wait(device)?;
                t.draw += gpu_start.elapsed();
            }
        }
        if let Some(err) = pollster::block_on(scope.pop()) {
            return Err(RenderError::Gpu(err.to_string()));
        }
        if let Some(err) = self.gpu.take_uncaptured_error() {
            return Err(RenderError::Gpu(err));
        }
        Ok(out)
    }

    fn write_uniforms(&mut self, frame: &Frame, size: [u32; 2], uniforms: &[ObjectUniform]) {
        let aspect = size[0] as f32 / size[1].max(1) as f32;
        let mut globals = GlobalsUniform::zeroed();
        globals.view_proj = frame.camera.view_proj(aspect).to_cols_array_2d();
        globals.eye_m = frame.camera.eye_m.extend(1.0).to_array();
        // Key light from above, slightly behind the viewer's right shoulder.
        let key = Vec3::new(0.45, 1.0, 0.35).normalize();
        globals.key_dir = key.extend(0.22).to_array();
        let dimples: Vec<_> = frame.tissue.dimples.iter().take(MAX_DIMPLES).collect();
        for (i, d) in dimples.iter().enumerate() {
            let normal = d.normal.try_normalize().unwrap_or(Vec3::Y);
            globals.dimple_centre[i] = d.centre_m.extend(d.radius_m.max(1e-6)).to_array();
            globals.dimple_normal[i] = normal.extend(d.depth_m).to_array();
        }
        globals.counts[0] = dimples.len() as u32;
        self.gpu
            .queue
            .write_buffer(&self.globals, 0, bytemuck::bytes_of(&globals));

        let needed = uniforms.len().max(1) as u64;
        if needed > self.object_slots {
            let slots = needed.next_power_of_two();
            let (buffer, group) = make_object_buffer(&self.gpu.device, &self.object_layout, slots);
            self.objects = buffer;
            self.objects_group = group;
            self.object_slots = slots;
        }
        let mut bytes = vec![0u8; uniforms.len() * OBJECT_SLOT_BYTES as usize];
        for (i, u) in uniforms.iter().enumerate() {
            let at = i * OBJECT_SLOT_BYTES as usize;
            bytes[at..at + size_of::<ObjectUniform>()].copy_from_slice(bytemuck::bytes_of(u));
        }
        if !bytes.is_empty() {
            self.gpu.queue.write_buffer(&self.objects, 0, &bytes);
        }
    }

    /// Copies the offscreen texture to the CPU.
    fn read_back(&mut self, timer: Option<&mut StageTimes>) -> Result<Image, RenderError> {
        let start = Instant::now();
        let Some(off) = self.offscreen.as_ref() else {
            return Err(RenderError::Readback("no offscreen target".into()));
        };
        let image = off.read(&self.gpu.device, &self.gpu.queue)?;
        if let Some(t) = timer {
            t.readback += start.elapsed();
        }
        Ok(image)
    }

    /// Draws `frame` offscreen at `size` with the overlay shapes of the window's last frame
    /// replayed (used for window screenshots, which must not consume input twice).
    pub(crate) fn capture(&mut self, frame: &Frame, size: [u32; 2]) -> Result<Image, RenderError> {
        check_size(size[0], size[1])?;
        self.ensure_offscreen(size);
        let texture = self.offscreen_texture()?;
        let pixels_per_point = self.overlay.last_pixels_per_point();
        self.draw(frame, &texture, OverlayInput::Replay { pixels_per_point }, None)?;
        self.read_back(None)
    }
}

fn make_object_buffer(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    slots: u64,
) -> (wgpu::Buffer, wgpu::BindGroup) {
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("objects"),
        size: slots * OBJECT_SLOT_BYTES,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("objects"),
        layout,
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer: &buffer,
                offset: 0,
                size: wgpu::BufferSize::new(size_of::<ObjectUniform>() as u64),
            }),
        }],
    });
    (buffer, group)
}

/// `colour`'s linear RGB through the sRGB transfer function (as `encode_srgb` in scene.wgsl).
fn srgb_encoded(colour: wgpu::Color) -> wgpu::Color {
    let encode = |c: f64| {
        let c = c.clamp(0.0, 1.0);
        if c <= 0.0031308 {
            12.92 * c
        } else {
            1.055 * c.powf(1.0 / 2.4) - 0.055
        }
    };
    wgpu::Color {
        r: encode(colour.r),
        g: encode(colour.g),
        b: encode(colour.b),
        a: colour.a,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::{NeedleState, tissue_scene};
    use crate::shapes;

    /// The opaque pass that encodes its own sRGB draws the picture the sRGB target draws, up to
    /// rounding, with and without see-through layers after it.
    #[test]
    fn encoded_opaque_pass_draws_the_same_picture() {
        let tissue: Vec<_> = shapes::tissue_block().into_iter().map(Arc::new).collect();
        let needle: Vec<_> = shapes::needle().into_iter().map(Arc::new).collect();
        let renderer = |allow_encoded| {
            let gpu = Gpu::headless(&GpuOptions::default()).unwrap();
            let mut r = Renderer::with_encoding(gpu, HEADLESS_FORMAT, 4, allow_encoded).unwrap();
            r.ensure_offscreen([320, 240]);
            r
        };
        let (mut encoded, mut plain) = (renderer(true), renderer(false));
        assert!(encoded.encoded_opaque && !plain.encoded_opaque);
        let states = [
            NeedleState::Pressing {
                depth_m: 0.008,
                radius_m: 0.012,
            },
            NeedleState::Inserted { depth_m: 0.03 },
        ];
        for state in states {
            let frame = tissue_scene(&tissue, &needle, state);
            let a = encoded.render(&frame).unwrap();
            let b = plain.render(&frame).unwrap();
            let c = crate::golden::compare(&a, &b, 1).unwrap();
            assert_eq!(
                c.differing_pixels, 0,
                "{state:?}: {} pixels differ by more than 1",
                c.differing_pixels
            );
            // Not vacuous: the tissue covers much of the picture in both.
            let lit = (0..240)
                .filter(|&y| a.pixel(160, y).is_some_and(|p| p[0] > 60))
                .count();
            assert!(lit > 60, "{state:?}: {lit} rows lit");
        }
    }
}
