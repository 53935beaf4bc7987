//! Draws a plain [`Frame`] value — camera, meshes with poses and materials, the tool, the tissue's
//! deformation and the overlay's data — to a window or to an offscreen image. Knows nothing of
//! haptics: the app fills the frame.
//!
//! This file is the crate's door: other crates name what they use as `render::X`, or through
//! one of its namespaces: [`window`] (`window::run` opens a window), [`golden`] (image
//! comparison), [`bench`] (frames per second), [`shapes`] (procedural meshes) and
//! [`assets_gen`] (the default assets and their dimensions).
//!
//! - [`Renderer::headless`] + [`Renderer::render`] give an [`Image`]; [`window::run`] opens a
//!   window that draws through the same code.
//! - Dimples bend objects marked deformable in the vertex shader; after puncture they are drawn
//!   see-through so the shaft inside shows.
//! - [`golden`] compares images with a tolerance; [`bench`] measures frames per second.
//! - [`QuietRuntimeDir`] keeps a headless binary's stderr free of a spurious Wayland error.
//! - Every fallible call returns [`RenderError`]: GPU and window failures, image and mesh files,
//!   golden mismatches, each naming the file involved.

pub mod assets_gen;
pub mod bench;
mod demo;
mod error;
mod frame;
mod gltf_io;
pub mod golden;
mod gpu;
mod image;
mod mesh;
mod offscreen;
mod overlay;
mod quiet_runtime;
mod renderer;
pub mod shapes;
mod ticks;
mod upscale;
pub mod window;

pub use assets_gen::{PATCH_CENTRES_M, PATCH_NAMES, default_assets, patch_centre_m, write_default_assets};
/// egui is part of the API: [`Renderer::render_with_events`] takes its input events.
pub use demo::{NeedleState, demo_overlay, tissue_scene, tray_scene};
pub use egui;
pub use error::RenderError;
pub use frame::{
    Camera, Dimple, Frame, MAX_DIMPLES, Material, Object, Overlay, Param, Recognition, TaskPanel,
    TissueState, Tool, UiAction,
};
pub use gltf_io::{compute_normals, load_gltf, write_glb};
pub use gpu::{Backend, GpuOptions};
pub use image::Image;
pub use mesh::MeshData;
pub use overlay::PANEL_WIDTH_PT;
pub use quiet_runtime::QuietRuntimeDir;
pub use renderer::{HEADLESS_FORMAT, Renderer, StageTimes};
