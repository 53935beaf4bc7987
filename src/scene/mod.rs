//! Scenes: what a session contains, read from TOML.
//!
//! A scene lists objects (a mesh, a pose, a material), materials (each names the models it
//! needs: needle puncture, friction, a recognizable surface), where each model comes from (a
//! model file, or a capture and hyperparameters to identify it from), the device, the
//! recognizer, the haptic settings and the task a scripted trainee performs when nobody holds
//! the device. Paths are relative to the scene file. Loading validates everything once, so
//! every later stage can trust the scene; each error names the file, the key and the reason.

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

use haptics::{DeviceChoice, Registry};
use serde::Deserialize;

mod goal;
mod overrides;

pub use goal::{Goal, GoalMode, in_words};
pub use overrides::SceneOverride;

/// The scene `palpus run` starts when none is given.
pub const DEFAULT_SCENE: &str = "scenes/needle_liver.toml";

/// A scene, validated, with every path resolved against the scene file's folder.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Short name, used in reports.
    pub name: String,
    /// One line for the trainee.
    #[serde(default)]
    pub description: String,
    /// The haptic device.
    #[serde(default)]
    pub device: DeviceSection,
    /// Admittance rendering.
    #[serde(default)]
    pub haptics: HapticsSection,
    /// The camera.
    pub camera: CameraSection,
    /// What is drawn and touched.
    pub objects: Vec<Object>,
    /// Materials by name.
    pub materials: BTreeMap<String, Material>,
    /// Models by name; only those a material of a drawn object references are ever read.
    #[serde(default)]
    pub models: BTreeMap<String, ModelSource>,
    /// Live surface recognition, if the scene has one.
    pub recognizer: Option<RecognizerSection>,
    /// What the scripted trainee does in a headless run.
    pub task: Task,
    /// The file it was read from.
    #[serde(skip)]
    pub path: PathBuf,
}

/// `[device]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeviceSection {
    /// A device of the registry by name, without an option (`sim`, `omega7`; `palpus run
    /// --device` overrides it, with an option if it needs one). Its specs bound the scene.
    #[serde(default = "default_device")]
    pub kind: String,
    /// Haptic rate, Hz.
    #[serde(default = "default_rate")]
    pub rate_hz: f64,
}

fn default_device() -> String {
    "sim".into()
}

fn default_rate() -> f64 {
    1000.0
}

impl Default for DeviceSection {
    fn default() -> Self {
        Self {
            kind: default_device(),
            rate_hz: default_rate(),
        }
    }
}

/// `[haptics]`: the virtual tool the admittance renderer moves.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HapticsSection {
    /// Virtual mass, kg.
    #[serde(default = "default_mass")]
    pub virtual_mass_kg: f64,
    /// Virtual damping, N·s/m.
    #[serde(default = "default_damping")]
    pub virtual_damping_nspm: f64,
    /// The simulated hand's grip stiffness, N/m.
    #[serde(default = "default_grip")]
    pub grip_stiffness_npm: f64,
    /// Smallest loading peak the needle law takes for a membrane, N: an identified surface
    /// ripples by a few tenths of a newton near the surface, which must not read as a rupture.
    #[serde(default = "default_min_peak")]
    pub rupture_min_peak_n: f64,
}

fn default_min_peak() -> f64 {
    0.4
}

fn default_mass() -> f64 {
    0.8
}

fn default_damping() -> f64 {
    4.0
}

fn default_grip() -> f64 {
    300.0
}

impl Default for HapticsSection {
    fn default() -> Self {
        Self {
            virtual_mass_kg: default_mass(),
            virtual_damping_nspm: default_damping(),
            grip_stiffness_npm: default_grip(),
            rupture_min_peak_n: default_min_peak(),
        }
    }
}

/// `[camera]`.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSection {
    /// Eye position, m (scene frame: y up).
    pub eye_m: [f64; 3],
    /// Point looked at, m.
    pub target_m: [f64; 3],
    /// Vertical field of view, degrees.
    #[serde(default = "default_fov")]
    pub fov_deg: f64,
}

fn default_fov() -> f64 {
    40.0
}

fn unit_scale() -> f64 {
    1.0
}

/// One `[[objects]]` entry.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Object {
    /// Name, unique in the scene.
    pub name: String,
    /// A glTF file (`.glb`, or `.gltf` with its buffers beside it or embedded), optionally
    /// `#node` to take one node of it.
    pub mesh: String,
    /// Position, m.
    #[serde(default)]
    pub position_m: [f64; 3],
    /// Rotation about x, y, z (applied in that order), degrees.
    #[serde(default)]
    pub rotation_deg: [f64; 3],
    /// A factor on the mesh's own units, applied before the rotation: glTF says metres, but
    /// many anatomy meshes are in millimetres (0.001) or centimetres (0.01).
    #[serde(default = "unit_scale")]
    pub scale: f64,
    /// A key of `[materials]`.
    pub material: String,
    /// The object is the tool the device moves (at most one per scene).
    #[serde(default)]
    pub tool: bool,
}

impl Object {
    /// The mesh file and, if given, the node.
    pub fn mesh_parts(&self) -> (&str, Option<&str>) {
        match self.mesh.split_once('#') {
            Some((file, node)) => (file, Some(node)),
            None => (self.mesh.as_str(), None),
        }
    }
}

/// One `[materials.NAME]` table.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Linear RGB colour multiplying the mesh's vertex colours.
    #[serde(default = "white")]
    pub color: [f64; 3],
    /// Opacity (tissue turns translucent after puncture whatever this says).
    #[serde(default = "one")]
    pub opacity: f64,
    /// Visual roughness 0–1 (surface detail in the renderer).
    #[serde(default)]
    pub roughness: f64,
    /// The needle-puncture model (a key of `[models]`).
    pub puncture: Option<String>,
    /// The friction model (a key of `[models]`).
    pub friction: Option<String>,
    /// A simulated physical surface (one of Nakano's seven) the recognizer should name.
    pub surface: Option<String>,
    /// Contact stiffness of a friction surface, N/m.
    #[serde(default = "default_contact_stiffness")]
    pub contact_stiffness_npm: f64,
}

fn white() -> [f64; 3] {
    [1.0; 3]
}

fn one() -> f64 {
    1.0
}

fn default_contact_stiffness() -> f64 {
    2000.0
}

/// Where a model comes from: `file = …`, or `kind`, `capture` and hyperparameters.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelSource {
    /// `needle`, `hard` or `soft`.
    pub kind: String,
    /// A model file written by `palpus identify --out`.
    pub file: Option<PathBuf>,
    /// A capture to identify the model from.
    pub capture: Option<PathBuf>,
    /// Regularisation constant C (defaults: the model kind's).
    pub c: Option<f64>,
    /// ε in the target's SI unit.
    pub epsilon: Option<f64>,
    /// RBF γ on the scaled inputs.
    pub gamma: Option<f64>,
    /// Needle: at most this many training samples (default [`DEFAULT_MAX_SAMPLES`]).
    pub max_samples: Option<usize>,
    /// `[models.NAME.budget]`: pick C, ε, γ and the training size from a measured trade
    /// instead of giving them.
    pub budget: Option<ModelBudget>,
}

/// The needle's training samples when a scene gives neither `max_samples` nor a budget.
pub const DEFAULT_MAX_SAMPLES: usize = identify::NEEDLE_SAMPLES;

impl ModelSource {
    /// The needle's training size the scene gives, else [`DEFAULT_MAX_SAMPLES`].
    pub fn max_samples(&self) -> usize {
        self.max_samples.unwrap_or(DEFAULT_MAX_SAMPLES)
    }
}

/// `[models.NAME.budget]`: what a scene's model may cost and must achieve. Resolving the scene
/// picks, from `front` (the `trade.csv` that `palpus bench trade` wrote for the same capture),
/// the point with the least time per prediction among those that meet every limit given.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelBudget {
    /// The measured trade, relative to the scene file.
    pub front: PathBuf,
    /// Longest time per prediction, ns (what one haptic tick pays for the model).
    pub max_predict_ns: Option<f64>,
    /// Largest AISE, N² (held out where the trade measured a test capture, else
    /// cross-validated).
    pub max_aise: Option<f64>,
}

/// `[recognizer]`: a recognizer model file or captures to train one from.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecognizerSection {
    /// `som`, `knn` or `svm`: what a folder of captures trains, and what a file must hold.
    #[serde(default = "default_method")]
    pub method: String,
    /// A recognizer model file.
    pub file: Option<PathBuf>,
    /// A folder of rubbing captures to train from.
    pub captures: Option<PathBuf>,
    /// With `captures`: the decision window to train, s (the method's default otherwise).
    pub window_s: Option<f64>,
    /// A k-NN's or SVM's posterior at which a surface is named (default 0.9); until then the
    /// recognizer says "undecided". A SOM names a surface every window and takes none.
    pub threshold: Option<f64>,
    /// A k-NN's or SVM's span of windows whose evidence counts, s (default 3): a new surface
    /// under the tool is named within about this time. Over travel it is the travel of that
    /// span at the speed the windows were made for, at any speed.
    pub memory_s: Option<f64>,
    /// A k-NN's or SVM's change test: the likelihood ratio against the named surface at which
    /// the evidence before a change is dropped (default 99); 0 for none.
    pub change_odds: Option<f64>,
}

fn default_method() -> String {
    "som".into()
}

/// `[task]`: what the scripted trainee does.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Task {
    /// Insert the needle straight down at the entry point, hold, withdraw.
    Insertion {
        /// What an attempt must achieve (`[task.goal]`), scored after each attempt.
        #[serde(default)]
        goal: Option<Goal>,
        /// Start this far above the surface, m.
        start_above_m: f64,
        /// Insertion depth of the hand's target below the surface, m.
        depth_m: f64,
        /// Insertion speed, m/s.
        speed_mps: f64,
        /// Hold at depth, s.
        hold_s: f64,
        /// Withdrawal speed, m/s.
        withdraw_speed_mps: f64,
    },
    /// Rub each touchable object in turn along x, pressing down.
    Rub {
        /// Normal force the hand presses with, N.
        normal_force_n: f64,
        /// Stroke length, m.
        stroke_m: f64,
        /// Stroke speed, m/s.
        speed_mps: f64,
        /// Strokes (there and back counts two) on each object.
        strokes: u32,
    },
}

impl Task {
    /// The insertion's goal, if the scene states one.
    pub fn goal(&self) -> Option<&Goal> {
        match self {
            Task::Insertion { goal, .. } => goal.as_ref(),
            Task::Rub { .. } => None,
        }
    }

    /// Short name for reports.
    pub fn name(&self) -> &'static str {
        match self {
            Task::Insertion { .. } => "insertion",
            Task::Rub { .. } => "rub",
        }
    }
}

/// Which model a material needs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum ModelRole {
    /// `puncture = …`.
    Puncture,
    /// `friction = …`.
    Friction,
}

impl fmt::Display for ModelRole {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ModelRole::Puncture => "puncture",
            ModelRole::Friction => "friction",
        })
    }
}

/// Heaviest virtual tool, kg: far heavier than any instrument held in one hand, which the
/// trainee could no longer move against the device's 12 N.
const MAX_VIRTUAL_MASS_KG: f64 = 10.0;
/// Fastest scripted hand motion, m/s: deliberate surgical motions stay below ~0.1 m/s; 0.5 m/s
/// crosses the Omega.7's whole workspace in a third of a second.
const MAX_HAND_SPEED_MPS: f64 = 0.5;
/// Longest scripted task (holds, all strokes), s: an hour.
const MAX_TASK_S: f64 = 3600.0;
/// Longest scene name; the name becomes a folder of the default output path.
const MAX_NAME_LEN: usize = 64;

/// A scene's name names its report folder, so it must be one plain path component: letters,
/// digits, `_`, `-` and `.`, not starting with `.` (no `..`, no hidden folder, no separator).
fn check_name(name: &str) -> Result<(), String> {
    if name.is_empty() || name.len() > MAX_NAME_LEN {
        return Err(format!("`{name}`: must be 1–{MAX_NAME_LEN} characters"));
    }
    if name.starts_with('.') {
        return Err(format!("`{name}`: must not start with `.`"));
    }
    if let Some(c) = name
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.')))
    {
        return Err(format!(
            "`{name}`: `{c}` is not allowed (letters, digits, `_`, `-`, `.`)"
        ));
    }
    Ok(())
}

/// Why a scene cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("{file}: {source}")]
    Io {
        /// The scene file.
        file: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// Not TOML, or a key of the wrong type, missing or unknown.
    #[error("{file}: {message}")]
    Parse {
        /// The scene file.
        file: PathBuf,
        /// The parser's message (with line and column).
        message: String,
    },
    /// A value that parses but makes no sense.
    #[error("{file}: `{key}`: {reason}")]
    Invalid {
        /// The scene file.
        file: PathBuf,
        /// The key, dotted (`materials.liver.puncture`).
        key: String,
        /// Why.
        reason: String,
    },
}

impl Scene {
    /// Reads and validates a scene file.
    pub fn load(path: &Path) -> Result<Self, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            file: path.to_owned(),
            source,
        })?;
        Self::parse(&text, path)
    }

    /// Reads a scene file with some of its values replaced (`palpus run --set`), then
    /// validates it as if the file said them.
    pub fn load_with(path: &Path, overrides: &[SceneOverride]) -> Result<Self, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            file: path.to_owned(),
            source,
        })?;
        Self::parse_with(&text, path, overrides)
    }

    /// Parses and validates scene text; `path` names it and anchors its relative paths.
    pub fn parse(text: &str, path: &Path) -> Result<Self, SceneError> {
        Self::parse_with(text, path, &[])
    }

    /// [`Scene::parse`] with `overrides` applied to the text's values first.
    pub fn parse_with(text: &str, path: &Path, overrides: &[SceneOverride]) -> Result<Self, SceneError> {
        let parse_error = |e: toml::de::Error| SceneError::Parse {
            file: path.to_owned(),
            message: e.to_string().trim_end().replace('\n', " | "),
        };
        let mut scene: Scene = if overrides.is_empty() {
            toml::from_str(text).map_err(parse_error)?
        } else {
            let mut table: toml::Table = toml::from_str(text).map_err(parse_error)?;
            for o in overrides {
                o.apply(&mut table).map_err(|reason| SceneError::Invalid {
                    file: path.to_owned(),
                    key: o.key.clone(),
                    reason,
                })?;
            }
            toml::Value::Table(table).try_into().map_err(parse_error)?
        };
        scene.path = path.to_owned();
        scene.validate()?;
        Ok(scene)
    }

    /// The folder relative paths start from.
    pub fn base_dir(&self) -> &Path {
        self.path.parent().unwrap_or(Path::new("."))
    }

    /// `relative` against the scene file's folder.
    pub fn resolve(&self, relative: &Path) -> PathBuf {
        if relative.is_absolute() {
            relative.to_owned()
        } else {
            self.base_dir().join(relative)
        }
    }

    fn invalid(&self, key: impl Into<String>, reason: impl Into<String>) -> SceneError {
        SceneError::Invalid {
            file: self.path.clone(),
            key: key.into(),
            reason: reason.into(),
        }
    }

    /// The tool object, if any.
    pub fn tool(&self) -> Option<&Object> {
        self.objects.iter().find(|o| o.tool)
    }

    /// The models the drawn objects' materials need: (model name, role, material name), each
    /// model once, in a fixed order. Nothing else in `[models]` is ever read.
    pub fn referenced_models(&self) -> Vec<(String, ModelRole, String)> {
        let mut out: Vec<(String, ModelRole, String)> = Vec::new();
        for object in &self.objects {
            let Some(material) = self.materials.get(&object.material) else {
                continue;
            };
            for (role, name) in [
                (ModelRole::Puncture, &material.puncture),
                (ModelRole::Friction, &material.friction),
            ] {
                if let Some(name) = name
                    && !out.iter().any(|(n, _, _)| n == name)
                {
                    out.push((name.clone(), role, object.material.clone()));
                }
            }
        }
        out
    }

    /// The scene's device, from the registry.
    pub fn device_choice(&self) -> Result<DeviceChoice, SceneError> {
        let kind = &self.device.kind;
        let choice = Registry::builtin()
            .choose(kind)
            .map_err(|e| self.invalid("device.kind", e.to_string()))?;
        if choice.option().is_some() {
            return Err(self.invalid(
                "device.kind",
                format!("`{kind}`: a scene names its device; an option goes on the command line (--device)"),
            ));
        }
        Ok(choice)
    }

    /// The specs of the device the scene names (validation refused a name no backend has,
    /// so the simulated Omega.7's stand only for a scene built without it).
    pub fn device_specs(&self) -> haptics::DeviceSpecs {
        self.device_choice()
            .map_or(haptics::DeviceSpecs::OMEGA7, |c| c.backend().specs)
    }

    fn validate(&self) -> Result<(), SceneError> {
        if let Err(reason) = check_name(&self.name) {
            return Err(self.invalid("name", reason));
        }
        let device = self.device_choice()?.backend().specs;
        let rate = self.device.rate_hz;
        if !(rate.is_finite() && (100.0..=10_000.0).contains(&rate)) {
            return Err(self.invalid("device.rate_hz", format!("{rate}: expected 100–10000 Hz")));
        }
        let h = self.haptics;
        for (key, value, max, why) in [
            (
                "haptics.virtual_mass_kg",
                h.virtual_mass_kg,
                MAX_VIRTUAL_MASS_KG,
                "a tool held in one hand",
            ),
            (
                "haptics.virtual_damping_nspm",
                h.virtual_damping_nspm,
                device.max_damping_nspm,
                "the Omega.7's largest stable damping",
            ),
            (
                "haptics.grip_stiffness_npm",
                h.grip_stiffness_npm,
                device.max_stiffness_npm,
                "the Omega.7's stiffest stable spring",
            ),
            (
                "haptics.rupture_min_peak_n",
                h.rupture_min_peak_n,
                device.max_force_n,
                "the Omega.7's largest force",
            ),
        ] {
            self.in_range(key, value, max, why)?;
        }
        let c = self.camera;
        if c.eye_m.iter().chain(&c.target_m).any(|v| !v.is_finite()) || c.eye_m == c.target_m {
            return Err(self.invalid("camera", "eye_m and target_m must be finite and distinct"));
        }
        if !(c.fov_deg.is_finite() && c.fov_deg > 1.0 && c.fov_deg < 170.0) {
            return Err(self.invalid("camera.fov_deg", format!("{}: expected 1–170°", c.fov_deg)));
        }
        if self.objects.is_empty() {
            return Err(self.invalid("objects", "a scene needs at least one object"));
        }
        let mut tools = 0;
        for (i, o) in self.objects.iter().enumerate() {
            let key = |field: &str| format!("objects[{i}].{field}");
            if self.objects[..i].iter().any(|p| p.name == o.name) {
                return Err(self.invalid(key("name"), format!("`{}` is used twice", o.name)));
            }
            let (file, node) = o.mesh_parts();
            let extension = Path::new(file)
                .extension()
                .and_then(|e| e.to_str())
                .map(str::to_ascii_lowercase);
            if !matches!(extension.as_deref(), Some("glb" | "gltf")) {
                return Err(self.invalid(
                    key("mesh"),
                    format!("`{}`: expected a glTF file (.glb or .gltf)", o.mesh),
                ));
            }
            if !(o.scale.is_finite() && (1e-6..=1e6).contains(&o.scale)) {
                return Err(self.invalid(
                    key("scale"),
                    format!(
                        "{}: expected a factor from 1e-6 to 1e6 on the mesh's units",
                        o.scale
                    ),
                ));
            }
            if node.is_some_and(str::is_empty) {
                return Err(self.invalid(key("mesh"), "empty node name after `#`"));
            }
            if o.position_m.iter().chain(&o.rotation_deg).any(|v| !v.is_finite()) {
                return Err(self.invalid(key("position_m"), "pose values must be finite"));
            }
            if !self.materials.contains_key(&o.material) {
                return Err(self.invalid(key("material"), format!("`{}` is not in [materials]", o.material)));
            }
            tools += usize::from(o.tool);
        }
        if tools > 1 {
            return Err(self.invalid("objects", "at most one object can be the tool"));
        }
        for (name, m) in &self.materials {
            let key = |field: &str| format!("materials.{name}.{field}");
            if m.color
                .iter()
                .any(|v| !(v.is_finite() && (0.0..=1.0).contains(v)))
            {
                return Err(self.invalid(key("color"), "components must lie in 0–1"));
            }
            if !(m.opacity.is_finite() && (0.0..=1.0).contains(&m.opacity)) {
                return Err(self.invalid(key("opacity"), "must lie in 0–1"));
            }
            if !(m.roughness.is_finite() && (0.0..=1.0).contains(&m.roughness)) {
                return Err(self.invalid(key("roughness"), "must lie in 0–1"));
            }
            self.in_range(
                &key("contact_stiffness_npm"),
                m.contact_stiffness_npm,
                device.max_stiffness_npm,
                "the Omega.7's stiffest stable spring",
            )?;
            // The virtual tool is integrated semi-implicitly (haptics::admittance): a
            // spring K on mass M is stable only for T < 2·√(M/K). Asking for T ≤ √(M/K), half
            // that, keeps every contact resolved by at least 2π ticks per period.
            let stiffness_npm = m.contact_stiffness_npm + h.grip_stiffness_npm;
            let period_s = 1.0 / rate;
            if period_s > (h.virtual_mass_kg / stiffness_npm).sqrt() {
                return Err(self.invalid(
                    key("contact_stiffness_npm"),
                    format!(
                        "{} N/m with the grip's {} N/m on a {} kg virtual tool oscillates faster than \
                         {rate} Hz can follow (needs virtual_mass_kg ≥ {:.4} kg, or a softer contact)",
                        m.contact_stiffness_npm,
                        h.grip_stiffness_npm,
                        h.virtual_mass_kg,
                        stiffness_npm * period_s * period_s
                    ),
                ));
            }
            for (field, model, kinds) in [
                ("puncture", &m.puncture, &["needle", "needle_phases"][..]),
                ("friction", &m.friction, &["hard", "soft"][..]),
            ] {
                let Some(model) = model else { continue };
                let Some(source) = self.models.get(model) else {
                    return Err(self.invalid(key(field), format!("model `{model}` is not in [models]")));
                };
                if !kinds.contains(&source.kind.as_str()) {
                    return Err(self.invalid(
                        key(field),
                        format!(
                            "model `{model}` is a {} model; expected {}",
                            source.kind,
                            kinds.join(" or ")
                        ),
                    ));
                }
            }
            if let Some(surface) = &m.surface
                && !haptics::acquire::surface_names().contains(&surface.as_str())
            {
                return Err(self.invalid(
                    key("surface"),
                    format!(
                        "`{surface}` is not one of the simulated surfaces ({})",
                        haptics::acquire::surface_names().join(", ")
                    ),
                ));
            }
        }
        for (name, s) in &self.models {
            let key = |field: &str| format!("models.{name}.{field}");
            if !matches!(s.kind.as_str(), "needle" | "needle_phases" | "hard" | "soft") {
                return Err(self.invalid(
                    key("kind"),
                    format!("`{}`: expected needle, needle_phases, hard or soft", s.kind),
                ));
            }
            match (&s.file, &s.capture) {
                (Some(_), Some(_)) => {
                    return Err(self.invalid(key("file"), "give either `file` or `capture`, not both"));
                }
                (None, None) => {
                    return Err(
                        self.invalid(name.clone(), "needs `file` (a model) or `capture` (to identify)")
                    );
                }
                _ => {}
            }
            if let Err((field, v, reason)) =
                identify::Plausibility::check_hyperparameters(s.c, s.epsilon, s.gamma)
            {
                return Err(self.invalid(key(field), format!("{v:e}: {reason}")));
            }
            if s.max_samples.is_some_and(|n| n < 10) {
                return Err(self.invalid(key("max_samples"), "at least 10"));
            }
            if let Some(b) = &s.budget {
                if s.kind == "needle_phases" {
                    return Err(self.invalid(
                        key("budget"),
                        "a budget picks an SVR's hyperparameters from its measured trade; the \
                         phase-aware needle model has none (use kind = \"needle\")",
                    ));
                }
                if s.capture.is_none() {
                    return Err(self.invalid(
                        key("budget"),
                        "a budget picks hyperparameters to identify with: it needs `capture`, not `file`",
                    ));
                }
                let given = [
                    ("c", s.c.is_some()),
                    ("epsilon", s.epsilon.is_some()),
                    ("gamma", s.gamma.is_some()),
                    ("max_samples", s.max_samples.is_some()),
                ];
                if let Some((field, _)) = given.iter().find(|(_, g)| *g) {
                    return Err(self.invalid(
                        key(field),
                        "the budget picks it from the measured trade: give one or the other",
                    ));
                }
                let limits = [
                    ("budget.max_predict_ns", b.max_predict_ns),
                    ("budget.max_aise", b.max_aise),
                ];
                if limits.iter().all(|(_, v)| v.is_none()) {
                    return Err(self.invalid(key("budget"), "give max_predict_ns, max_aise or both"));
                }
                for (field, value) in limits {
                    if let Some(v) = value
                        && !(v.is_finite() && v > 0.0)
                    {
                        return Err(self.invalid(key(field), format!("{v}: must be a positive number")));
                    }
                }
            }
        }
        if let Some(r) = &self.recognizer {
            let key = |field: &str| format!("recognizer.{field}");
            if recognize::Method::named(&r.method).is_none() {
                return Err(self.invalid(
                    "recognizer.method",
                    format!("`{}`: expected som, knn or svm", r.method),
                ));
            }
            if r.file.is_some() == r.captures.is_some() {
                return Err(self.invalid("recognizer", "give exactly one of `file` and `captures`"));
            }
            if r.method == "som" {
                for (field, v) in [
                    ("threshold", r.threshold),
                    ("memory_s", r.memory_s),
                    ("change_odds", r.change_odds),
                ] {
                    if v.is_some() {
                        return Err(self.invalid(
                            key(field),
                            "a som names a surface every window and has no posterior: only a knn or svm takes it",
                        ));
                    }
                }
            }
            if let Some(p) = r.threshold
                && !(p > 0.0 && p < 1.0)
            {
                return Err(self.invalid("recognizer.threshold", format!("{p}: must be in (0, 1)")));
            }
            for (field, v) in [("memory_s", r.memory_s), ("window_s", r.window_s)] {
                if let Some(v) = v
                    && !(v.is_finite() && v > 0.0)
                {
                    return Err(
                        self.invalid(key(field), format!("{v}: must be a positive number of seconds"))
                    );
                }
            }
            if let Some(odds) = r.change_odds
                && !(odds == 0.0 || (odds.is_finite() && odds > 1.0))
            {
                return Err(self.invalid(
                    "recognizer.change_odds",
                    format!("{odds}: a likelihood ratio above 1, or 0 for no change test"),
                ));
            }
            if r.window_s.is_some() && r.captures.is_none() {
                return Err(self.invalid(
                    "recognizer.window_s",
                    "sets the window a folder of captures trains; a file has its own",
                ));
            }
        }
        self.validate_task()
    }

    /// `value` must be a number in (0, `max`]; `why` says where the bound comes from.
    fn in_range(&self, key: &str, value: f64, max: f64, why: &str) -> Result<(), SceneError> {
        if !(value.is_finite() && value > 0.0) {
            return Err(self.invalid(key, format!("{value}: must be a positive number")));
        }
        if value > max {
            return Err(self.invalid(key, format!("{value}: above {max} ({why})")));
        }
        Ok(())
    }

    fn validate_task(&self) -> Result<(), SceneError> {
        let speed = |key: &str, v: f64| {
            self.in_range(
                &format!("task.{key}"),
                v,
                MAX_HAND_SPEED_MPS,
                "a deliberate hand motion",
            )
        };
        let positive = |key: &str, v: f64| self.in_range(&format!("task.{key}"), v, f64::MAX, "");
        match self.task {
            Task::Insertion {
                start_above_m,
                depth_m,
                speed_mps,
                hold_s,
                withdraw_speed_mps,
                ref goal,
            } => {
                if let Some(goal) = goal {
                    self.validate_goal(goal)?;
                }
                positive("start_above_m", start_above_m)?;
                positive("depth_m", depth_m)?;
                speed("speed_mps", speed_mps)?;
                speed("withdraw_speed_mps", withdraw_speed_mps)?;
                if !(hold_s.is_finite() && (0.0..=MAX_TASK_S).contains(&hold_s)) {
                    return Err(self.invalid("task.hold_s", format!("{hold_s}: expected 0–{MAX_TASK_S} s")));
                }
                if depth_m + start_above_m > 0.07 {
                    return Err(self.invalid(
                        "task.depth_m",
                        "the stroke leaves the Omega.7's workspace (at most 70 mm in all)",
                    ));
                }
                if self.tool().is_none() {
                    return Err(self.invalid("task", "an insertion needs a tool object (`tool = true`)"));
                }
                if !self.materials.values().any(|m| m.puncture.is_some()) {
                    return Err(self.invalid("task", "an insertion needs a material with `puncture`"));
                }
            }
            Task::Rub {
                normal_force_n,
                stroke_m,
                speed_mps,
                strokes,
            } => {
                positive("normal_force_n", normal_force_n)?;
                self.in_range(
                    "task.stroke_m",
                    stroke_m,
                    2.0 * self.device_choice()?.backend().specs.workspace_radius_m,
                    "the Omega.7's workspace diameter",
                )?;
                speed("speed_mps", speed_mps)?;
                if strokes == 0 {
                    return Err(self.invalid("task.strokes", "at least one"));
                }
                // The stroke plan is built before the run starts, so its length bounds memory.
                let planned_s =
                    f64::from(strokes) * stroke_m / speed_mps * self.rubbed_objects().len().max(1) as f64;
                if planned_s > MAX_TASK_S {
                    return Err(self.invalid(
                        "task.strokes",
                        format!("{strokes} strokes take {planned_s:.3e} s; at most {MAX_TASK_S} s in all"),
                    ));
                }
                if normal_force_n > 10.0 {
                    return Err(self.invalid("task.normal_force_n", "above the Omega.7's 12 N less margin"));
                }
                if self.rubbed_objects().is_empty() {
                    return Err(self.invalid(
                        "task",
                        "rubbing needs objects whose material has `friction` or `surface`",
                    ));
                }
            }
        }
        Ok(())
    }

    /// Objects a rubbing task visits, in scene order.
    pub fn rubbed_objects(&self) -> Vec<&Object> {
        self.objects
            .iter()
            .filter(|o| {
                !o.tool
                    && self
                        .materials
                        .get(&o.material)
                        .is_some_and(|m| m.friction.is_some() || m.surface.is_some())
            })
            .collect()
    }
}

#[cfg(test)]
mod tests;
