//! What the trainee sees: a scene's meshes and the haptic state turned into a
//! [`render::Frame`].
//!
//! The device works in its own frame (z up, the touched surface at
//! [`crate::session::SURFACE_Z_M`]); the scene is y up, metres. The device's origin is mapped
//! onto the object being worked on — the needle's entry point, or the centre of the rubbed
//! patch — so the tool appears where the haptic world puts it.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{DVec3, EulerRot, Mat4, Quat, Vec3};
use haptics::HapticSample;
use haptics::PunctureState;
use render::{Camera, Dimple, Frame, Material, MeshData, Object, Overlay, TissueState, Tool};

use crate::scene::Scene;
use crate::session::{SURFACE_Z_M, SegmentKind, SegmentRun};
use haptics::admittance_channel as c;

/// Why a scene's meshes could not be prepared.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    /// A mesh file is missing or invalid.
    #[error("object `{object}`: {source}")]
    Mesh {
        /// The object.
        object: String,
        /// Why.
        source: render::RenderError,
    },
    /// The `#node` named is not in the file.
    #[error("object `{object}`: {} has no node `{node}` (it has: {available})", file.display())]
    NoNode {
        /// The object.
        object: String,
        /// The mesh file.
        file: PathBuf,
        /// The node asked for.
        node: String,
        /// The nodes it has.
        available: String,
    },
}

/// One placed object with what the view needs to know about it.
#[derive(Debug, Clone)]
struct Placed {
    name: String,
    parts: Vec<Object>,
    /// Top centre of its bounds in the scene, m: where the device's origin maps when the tool
    /// works on it.
    anchor_m: Vec3,
}

/// A scene's meshes, loaded once, and the mapping from haptic state to frames.
#[derive(Debug, Clone)]
pub struct SceneView {
    camera: Camera,
    objects: Vec<Placed>,
    tool: Vec<Object>,
    /// Gaussian radius of the dimple under the needle, m.
    pub dimple_radius_m: f32,
    /// Opacity of the tissue once punctured.
    pub punctured_opacity: f32,
}

/// The haptic state a frame shows.
#[derive(Debug, Clone, Copy, Default)]
pub struct ViewState<'a> {
    /// The object being worked on (its name).
    pub object: Option<&'a str>,
    /// What it is.
    pub kind: Option<&'a SegmentKind>,
    /// The newest sample.
    pub sample: Option<&'a HapticSample>,
    /// Whether the tissue's surface has given in this stroke: a needle pressing a deeper layer
    /// then no longer dimples the surface.
    pub surface_given: bool,
}

fn rotation(deg: [f64; 3]) -> Quat {
    let r = |d: f64| d.to_radians() as f32;
    Quat::from_euler(EulerRot::XYZ, r(deg[0]), r(deg[1]), r(deg[2]))
}

fn material(m: &crate::scene::Material, tool: bool) -> Material {
    let rgb = [m.color[0] as f32, m.color[1] as f32, m.color[2] as f32];
    let mut out = if tool {
        Material {
            color: [rgb[0], rgb[1], rgb[2], 1.0],
            ..Material::metal()
        }
    } else if m.puncture.is_some() {
        Material::tissue(rgb)
    } else {
        Material::rough(rgb, m.roughness as f32)
    };
    out.color[3] = m.opacity as f32;
    if !tool && m.puncture.is_some() {
        out.roughness = m.roughness as f32;
    }
    out
}

impl SceneView {
    /// Loads every object's mesh (each file once).
    pub fn load(scene: &Scene) -> Result<Self, ViewError> {
        let mut files: BTreeMap<PathBuf, Vec<Arc<MeshData>>> = BTreeMap::new();
        let mut objects = Vec::new();
        let mut tool = Vec::new();
        for o in &scene.objects {
            let (file, node) = o.mesh_parts();
            let path = scene.resolve(Path::new(file));
            if !files.contains_key(&path) {
                let meshes = render::load_gltf(&path).map_err(|source| ViewError::Mesh {
                    object: o.name.clone(),
                    source,
                })?;
                files.insert(path.clone(), meshes.into_iter().map(Arc::new).collect());
            }
            let all = files.get(&path).cloned().unwrap_or_default();
            let meshes: Vec<Arc<MeshData>> = match node {
                Some(n) => {
                    let m: Vec<_> = all.iter().filter(|m| m.name == n).cloned().collect();
                    if m.is_empty() {
                        return Err(ViewError::NoNode {
                            object: o.name.clone(),
                            file: path,
                            node: n.into(),
                            available: all.iter().map(|m| m.name.as_str()).collect::<Vec<_>>().join(", "),
                        });
                    }
                    m
                }
                None => all,
            };
            let mat = material(&scene.materials[&o.material], o.tool);
            let position = Vec3::new(
                o.position_m[0] as f32,
                o.position_m[1] as f32,
                o.position_m[2] as f32,
            );
            let transform = Mat4::from_scale_rotation_translation(
                Vec3::splat(o.scale as f32),
                rotation(o.rotation_deg),
                position,
            );
            let deformable = {
                let m = &scene.materials[&o.material];
                m.puncture.is_some() || m.friction.is_some()
            };
            let parts: Vec<Object> = meshes
                .iter()
                .map(|mesh| {
                    let obj = Object::new(mesh.clone(), transform, mat);
                    if deformable && !o.tool {
                        obj.deformable()
                    } else {
                        obj
                    }
                })
                .collect();
            if o.tool {
                tool = parts;
            } else {
                let (lo, hi) = bounds(&meshes);
                let centre =
                    transform.transform_point3(Vec3::new((lo.x + hi.x) / 2.0, hi.y, (lo.z + hi.z) / 2.0));
                objects.push(Placed {
                    name: o.name.clone(),
                    parts,
                    anchor_m: centre,
                });
            }
        }
        let cam = scene.camera;
        let v = |a: [f64; 3]| Vec3::new(a[0] as f32, a[1] as f32, a[2] as f32);
        let mut camera = Camera::look_at(v(cam.eye_m), v(cam.target_m));
        camera.fov_y_rad = (cam.fov_deg as f32).to_radians();
        Ok(Self {
            camera,
            objects,
            tool,
            dimple_radius_m: 0.012,
            punctured_opacity: 0.35,
        })
    }

    /// Where the device's origin maps for `object`: the needle enters at the scene origin
    /// (assets put the entry point there); a rubbed object's top centre.
    fn anchor_m(&self, object: Option<&str>, kind: Option<&SegmentKind>) -> Vec3 {
        match kind {
            Some(SegmentKind::Needle { .. }) | None => Vec3::ZERO,
            _ => object
                .and_then(|name| self.objects.iter().find(|o| o.name == name))
                .map_or(Vec3::ZERO, |o| o.anchor_m),
        }
    }

    /// A device position (z up) in the scene (y up) for work on `object`.
    pub fn to_scene_m(&self, device_m: DVec3, object: Option<&str>, kind: Option<&SegmentKind>) -> Vec3 {
        let rel = device_m - DVec3::new(0.0, 0.0, SURFACE_Z_M);
        self.anchor_m(object, kind) + Vec3::new(rel.x as f32, rel.z as f32, -rel.y as f32)
    }

    /// The frame for `state` (no overlay).
    pub fn frame(&self, state: &ViewState<'_>) -> Frame {
        let mut frame = Frame::new(self.camera);
        frame.clear_color = [0.05, 0.06, 0.07];
        frame.objects = self
            .objects
            .iter()
            .flat_map(|o| o.parts.iter().cloned())
            .collect();
        frame.tissue = TissueState {
            punctured_opacity: self.punctured_opacity,
            ..TissueState::default()
        };
        let Some(s) = state.sample else {
            return frame;
        };
        // The tool is drawn where the virtual tool is (admittance), which is where the
        // trainee feels it; for Nakano's controller it is the device itself.
        let tool_device_m = match state.kind {
            Some(SegmentKind::Surface { .. }) | None => s.state.position_m,
            _ => DVec3::new(
                s.state.position_m.x,
                s.state.position_m.y,
                s.channels[c::VIRTUAL_Z_M],
            ),
        };
        let tip = self.to_scene_m(tool_device_m, state.object, state.kind);
        let surface = self.anchor_m(state.object, state.kind);
        let depth_m = surface.y - tip.y;
        match state.kind {
            Some(SegmentKind::Needle { .. }) => {
                let code = s.channels[c::ENV_STATE];
                if code == PunctureState::CapsuleLoading.code() && depth_m > 0.0 && !state.surface_given {
                    frame.tissue.dimples.push(Dimple {
                        centre_m: Vec3::new(tip.x, surface.y, tip.z),
                        normal: Vec3::Y,
                        depth_m,
                        radius_m: self.dimple_radius_m,
                    });
                } else if code != PunctureState::Approach.code() && depth_m > 0.0 {
                    frame.tissue.punctured = true;
                }
            }
            Some(SegmentKind::Friction { .. }) if depth_m > 0.0 => {
                frame.tissue.dimples.push(Dimple {
                    centre_m: Vec3::new(tip.x, surface.y, tip.z),
                    normal: Vec3::Y,
                    depth_m,
                    radius_m: 0.004,
                });
            }
            _ => {}
        }
        if !self.tool.is_empty() {
            frame.tool = Some(Tool {
                pose: Mat4::from_translation(tip),
                parts: self.tool.clone(),
            });
        }
        frame
    }
}

fn bounds(meshes: &[Arc<MeshData>]) -> (Vec3, Vec3) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for m in meshes {
        for p in &m.positions {
            let p = Vec3::from_array(*p);
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    if lo.is_finite() && hi.is_finite() {
        (lo, hi)
    } else {
        (Vec3::ZERO, Vec3::ZERO)
    }
}

/// The overlay's plots from a segment's samples: the last `window_s` seconds, at most about
/// `points` points each.
pub fn overlay_plots(
    samples: &[HapticSample],
    kind: Option<&SegmentKind>,
    window_s: f64,
    points: usize,
) -> Overlay {
    let t_end = samples.last().map_or(0.0, |s| s.time_s);
    let start = samples.partition_point(|s| s.time_s < t_end - window_s);
    let recent = &samples[start..];
    let step = (recent.len() / points.max(1)).max(1);
    let (x, force, quantity) = crate::session::traces(kind);
    Overlay {
        depth_label: (quantity != "depth").then(|| quantity.to_owned()),
        force_depth: recent
            .iter()
            .step_by(step)
            .map(|s| [x(s) as f32, force(s) as f32])
            .collect(),
        force_time: recent
            .iter()
            .step_by(step)
            .map(|s| [s.time_s as f32, force(s) as f32])
            .collect(),
        ..Overlay::default()
    }
}

/// Renders the session's moments of interest into the report folder: `frame.png` (the needle
/// dimpling the capsule at its peak load, or mid-stroke on the last rubbed surface, with the
/// overlay) and, for a needle, `frame_inserted.png` (deepest). Returns the first path, or why
/// nothing could be drawn.
pub fn render_session_frame(
    scene: &Scene,
    runs: &[SegmentRun],
    recognition: &[crate::session::report::Recognition],
    out: &Path,
) -> Result<PathBuf, String> {
    let view = SceneView::load(scene).map_err(|e| e.to_string())?;
    let Some(run) = runs.last() else {
        return Err("the session ran no segment".into());
    };
    if run.samples.is_empty() {
        return Err("the session recorded no sample".into());
    }
    let mut renderer = render::Renderer::headless(1280, 720, 4).map_err(|e| e.to_string())?;
    let moments: Vec<(usize, PathBuf)> = match run.segment.kind {
        SegmentKind::Needle { .. } => {
            let loading = PunctureState::CapsuleLoading.code();
            let peak = (0..run.samples.len())
                .filter(|&i| run.samples[i].channels[c::ENV_STATE] == loading)
                .max_by(|&a, &b| {
                    run.samples[a].channels[c::MODEL_FORCE_Z_N]
                        .total_cmp(&run.samples[b].channels[c::MODEL_FORCE_Z_N])
                });
            let deepest = (0..run.samples.len()).min_by(|&a, &b| {
                run.samples[a].channels[c::VIRTUAL_Z_M].total_cmp(&run.samples[b].channels[c::VIRTUAL_Z_M])
            });
            let mut m = Vec::new();
            if let Some(i) = peak {
                m.push((i, out.to_owned()));
            }
            if let Some(i) = deepest {
                let path = out.with_file_name("frame_inserted.png");
                if m.is_empty() {
                    m.push((i, out.to_owned()));
                } else {
                    m.push((i, path));
                }
            }
            m
        }
        _ => vec![(run.samples.len() / 2, out.to_owned())],
    };
    for (i, path) in &moments {
        let sample = &run.samples[*i];
        // What the trainee's overlay said at that moment.
        let mut guide = crate::session::guide::LiveGuide::new();
        let surface_z_m = crate::session::analysis::surface_z_m(run);
        for s in &run.samples[..=*i] {
            guide.push(s, surface_z_m);
        }
        let state = ViewState {
            object: Some(&run.segment.object),
            kind: Some(&run.segment.kind),
            sample: Some(sample),
            surface_given: guide.layers_given() > 0,
        };
        let mut frame = view.frame(&state);
        let mut overlay = overlay_plots(&run.samples[..=*i], Some(&run.segment.kind), 10.0, 800);
        overlay.haptic_rate_hz = Some(run.stats.mean_rate_hz as f32);
        overlay.period_error_s = Some(run.stats.period_error.p99.as_secs_f32());
        overlay.device_status = format!("{} — {} (headless report)", run.device, scene.name);
        overlay.recognized = recognition
            .iter()
            .rfind(|r| r.object == run.segment.object && r.time_s <= sample.time_s)
            .map(|r| render::Recognition {
                surface: r.label.clone().unwrap_or_else(|| r.best.clone()),
                confidence: r.confidence as f32,
                decided: r.label.is_some(),
            });
        overlay.task = crate::session::guide::task_panel(scene.task.goal(), Some(&run.segment.kind), &guide);
        frame.overlay = Some(overlay);
        let image = renderer.render(&frame).map_err(|e| e.to_string())?;
        image.save_png(path).map_err(|e| e.to_string())?;
    }
    moments
        .first()
        .map(|(_, p)| p.clone())
        .ok_or_else(|| "no moment to draw".to_owned())
}
