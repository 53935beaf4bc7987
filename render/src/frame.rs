//! The plain value the app fills each frame and the renderer draws: nothing here refers to GPU
//! state, so the app can build frames on any thread and tests can build them by hand.

use std::sync::Arc;

use glam::{Mat4, Vec3};

use crate::mesh::MeshData;

/// Most dimples the vertex shader evaluates at once; the uniform block has a fixed size.
pub const MAX_DIMPLES: usize = 4;

/// Everything one picture shows.
#[derive(Debug, Clone)]
pub struct Frame {
    pub camera: Camera,
    /// Scene objects (tissue, tray, patches), world poses.
    pub objects: Vec<Object>,
    /// The hand-held tool (needle, probe); its parts are posed relative to `tool.pose`.
    pub tool: Option<Tool>,
    pub tissue: TissueState,
    /// Background colour, linear RGB.
    pub clear_color: [f32; 3],
    /// The egui overlay's data; `None` draws the 3-D scene only.
    pub overlay: Option<Overlay>,
}

impl Frame {
    /// An empty scene seen by `camera`, with a dark neutral background and no overlay.
    pub fn new(camera: Camera) -> Self {
        Frame {
            camera,
            objects: Vec::new(),
            tool: None,
            tissue: TissueState::default(),
            clear_color: [0.02, 0.025, 0.03],
            overlay: None,
        }
    }
}

/// A perspective camera looking from `eye_m` at `target_m`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    pub eye_m: Vec3,
    pub target_m: Vec3,
    pub up: Vec3,
    /// Vertical field of view, rad.
    pub fov_y_rad: f32,
    pub near_m: f32,
    pub far_m: f32,
}

impl Camera {
    /// A camera at `eye_m` looking at `target_m` with y up, 45° vertical field of view.
    pub fn look_at(eye_m: Vec3, target_m: Vec3) -> Self {
        Camera {
            eye_m,
            target_m,
            up: Vec3::Y,
            fov_y_rad: 45f32.to_radians(),
            near_m: 0.005,
            far_m: 10.0,
        }
    }

    /// View-projection matrix (right-handed, wgpu depth range 0..1) for an image of this aspect.
    pub fn view_proj(&self, aspect: f32) -> Mat4 {
        let up = self.up.try_normalize().unwrap_or(Vec3::Y);
        let view = glam::camera::rh::view::look_at_mat4(self.eye_m, self.target_m, up);
        // Degenerate values from the app would give NaN matrices; keep them in range instead.
        let fov = self.fov_y_rad.clamp(0.01, 3.1);
        let near = self.near_m.max(1e-5);
        let far = self.far_m.max(near * 2.0);
        let proj = glam::camera::rh::proj::directx::perspective(fov, aspect.max(1e-3), near, far);
        proj * view
    }
}

/// One mesh placed in the world.
#[derive(Debug, Clone)]
pub struct Object {
    /// Shared so the renderer can keep one GPU copy per mesh across frames.
    pub mesh: Arc<MeshData>,
    /// Model to world (or, for tool parts, model to tool) transform; metres.
    pub transform: Mat4,
    pub material: Material,
    /// Whether the tissue dimples bend this object and puncture makes it see-through.
    pub deformable: bool,
}

impl Object {
    pub fn new(mesh: Arc<MeshData>, transform: Mat4, material: Material) -> Self {
        Object {
            mesh,
            transform,
            material,
            deformable: false,
        }
    }

    /// The same object marked as soft tissue.
    pub fn deformable(mut self) -> Self {
        self.deformable = true;
        self
    }
}

/// How a surface reflects light.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    /// Linear RGBA; multiplies the mesh's vertex colours. Alpha below 1 draws it translucent.
    pub color: [f32; 4],
    /// 0 = smooth; up to 1 adds procedural surface detail (bumps and mottling) of that strength.
    pub roughness: f32,
    /// Spatial period of the procedural detail, m.
    pub detail_period_m: f32,
    /// Strength of the specular highlight, 0..1.
    pub specular: f32,
    /// Blinn-Phong exponent; higher is a tighter highlight.
    pub shininess: f32,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            color: [1.0; 4],
            roughness: 0.0,
            detail_period_m: 0.004,
            specular: 0.2,
            shininess: 32.0,
        }
    }
}

impl Material {
    /// Moist soft tissue of the given linear colour.
    pub fn tissue(rgb: [f32; 3]) -> Self {
        Material {
            color: [rgb[0], rgb[1], rgb[2], 1.0],
            roughness: 0.15,
            detail_period_m: 0.006,
            specular: 0.35,
            shininess: 40.0,
        }
    }

    /// Polished steel.
    pub fn metal() -> Self {
        Material {
            color: [0.75, 0.76, 0.78, 1.0],
            roughness: 0.0,
            detail_period_m: 0.004,
            specular: 0.9,
            shininess: 90.0,
        }
    }

    /// A matte surface whose procedural detail grows with `roughness` (0..1).
    pub fn rough(rgb: [f32; 3], roughness: f32) -> Self {
        Material {
            color: [rgb[0], rgb[1], rgb[2], 1.0],
            roughness,
            detail_period_m: 0.003,
            specular: 0.1,
            shininess: 16.0,
        }
    }
}

/// The tool: its parts share one pose.
#[derive(Debug, Clone)]
pub struct Tool {
    /// Tool to world. For the needle: the tip is the model origin, the shaft runs along +y.
    pub pose: Mat4,
    pub parts: Vec<Object>,
}

/// The tissue's visible deformation.
#[derive(Debug, Clone, PartialEq)]
pub struct TissueState {
    /// Indentations of deformable objects; at most [`MAX_DIMPLES`] are drawn, extra ones ignored.
    pub dimples: Vec<Dimple>,
    /// Once the needle is through the surface deformable objects are drawn see-through, so the
    /// shaft inside shows.
    pub punctured: bool,
    /// Opacity of deformable objects after puncture, 0..1.
    pub punctured_opacity: f32,
}

impl Default for TissueState {
    fn default() -> Self {
        TissueState {
            dimples: Vec::new(),
            punctured: false,
            punctured_opacity: 0.2,
        }
    }
}

/// A Gaussian indentation: points at distance r from the axis through `centre_m` move by
/// `depth_m · exp(-(r/radius_m)²)` against `normal`, fading with depth below the surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dimple {
    /// Contact point on the undeformed surface, world m.
    pub centre_m: Vec3,
    /// Outward unit surface normal at the contact; the surface moves along `-normal`.
    pub normal: Vec3,
    pub depth_m: f32,
    pub radius_m: f32,
}

impl Dimple {
    /// The displacement (world m) of an undeformed point, the same formula the vertex shader uses.
    pub fn displacement_m(&self, point_m: Vec3) -> Vec3 {
        let rel = point_m - self.centre_m;
        let along = rel.dot(self.normal);
        let perp = rel - along * self.normal;
        let radius = self.radius_m.max(1e-6);
        let falloff =
            (-perp.length_squared() / (radius * radius)).exp() * (-(-along).max(0.0) / (2.0 * radius)).exp();
        -self.normal * (self.depth_m * falloff)
    }
}

/// The overlay's content: plots, status and controls.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Overlay {
    /// (depth m, force N) samples of the current insertion or press, oldest first.
    pub force_depth: Vec<[f32; 2]>,
    /// What the x of `force_depth` is, when not the needle's depth (rubbing: `position`).
    pub depth_label: Option<String>,
    /// (time s, force N) samples, oldest first.
    pub force_time: Vec<[f32; 2]>,
    pub recognized: Option<Recognition>,
    /// Measured haptic loop rate, Hz.
    pub haptic_rate_hz: Option<f32>,
    /// Haptic period error (e.g. the 99th percentile of |period − nominal|), s.
    pub period_error_s: Option<f32>,
    /// One line on the device, e.g. "simulator" or "Omega.7: forces enabled".
    pub device_status: String,
    pub scenes: Vec<String>,
    /// Index into `scenes` of the scene being shown.
    pub current_scene: Option<usize>,
    pub params: Vec<Param>,
    /// The task's panel: guidance, or an exam's silence.
    pub task: TaskPanel,
}

/// What the overlay says of the task in progress.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum TaskPanel {
    /// No task with a goal.
    #[default]
    None,
    /// Guidance lines, each `(text, warning)`.
    Guided(Vec<(String, bool)>),
    /// An exam: the force plots and every reading of the attempt are hidden until it ends;
    /// the line says so.
    Exam(String),
}

/// A surface the recognizer names, with its confidence 0..1.
#[derive(Debug, Clone, PartialEq)]
pub struct Recognition {
    /// The surface named, or while undecided the most probable one.
    pub surface: String,
    /// Its probability (or a SOM's confidence), 0–1.
    pub confidence: f32,
    /// Whether the recognizer has named it; `false` while its confidence is below the
    /// threshold, and the overlay says "undecided".
    pub decided: bool,
}

/// A user-adjustable named value with its range; the overlay shows a slider.
#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    pub name: String,
    pub value: f32,
    pub min: f32,
    pub max: f32,
    /// Unit shown after the value ("N/m", "mm"); may be empty.
    pub unit: String,
}

/// What the user asked for through the overlay; the app applies it.
#[derive(Debug, Clone, PartialEq)]
pub enum UiAction {
    /// Switch to the scene with this index into [`Overlay::scenes`].
    SelectScene { index: usize, name: String },
    /// Set parameter `name` to `value`.
    SetParam { name: String, value: f32 },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dimple_is_deepest_at_centre_and_fades_radially_and_below() {
        let d = Dimple {
            centre_m: Vec3::ZERO,
            normal: Vec3::Y,
            depth_m: 0.01,
            radius_m: 0.012,
        };
        let at_centre = d.displacement_m(Vec3::ZERO);
        assert!((at_centre.y + 0.01).abs() < 1e-7);
        let at_radius = d.displacement_m(Vec3::new(0.012, 0.0, 0.0));
        assert!((at_radius.y + 0.01 * (-1f32).exp()).abs() < 1e-7);
        let far = d.displacement_m(Vec3::new(0.05, 0.0, 0.0));
        assert!(far.y.abs() < 1e-9);
        let below = d.displacement_m(Vec3::new(0.0, -0.024, 0.0));
        assert!((below.y + 0.01 * (-1f32).exp()).abs() < 1e-7);
    }

    #[test]
    fn view_proj_maps_target_to_screen_centre() {
        let cam = Camera::look_at(Vec3::new(0.0, 0.1, 0.2), Vec3::ZERO);
        let clip = cam.view_proj(1.5) * glam::Vec4::new(0.0, 0.0, 0.0, 1.0);
        assert!((clip.x / clip.w).abs() < 1e-5 && (clip.y / clip.w).abs() < 1e-5);
        let z = clip.z / clip.w;
        assert!(z > 0.0 && z < 1.0);
    }
}
