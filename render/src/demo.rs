//! Ready-made frames for the demo window, the benchmark and the golden tests: a tissue block with
//! a needle, and the surface tray. They take their meshes as arguments so the same scenes work
//! with procedural stand-ins and with loaded assets.

use std::sync::Arc;

use glam::{Mat4, Vec3};

use crate::assets_gen::PATCH_RQ_M;
use crate::frame::{Camera, Dimple, Frame, Material, Object, Overlay, Param, Recognition, TaskPanel, Tool};
use crate::mesh::MeshData;

/// Where the needle is in a tissue scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NeedleState {
    /// Tip this far above the surface, m; nothing touches.
    Above { height_m: f32 },
    /// Tip pressing the surface in a dimple of this depth and radius, m.
    Pressing { depth_m: f32, radius_m: f32 },
    /// Tip this far below the (punctured) surface, m.
    Inserted { depth_m: f32 },
}

/// The meshes carry their colours; materials add only how the surface reflects.
fn tissue_material(name: &str) -> Material {
    let white = [1.0, 1.0, 1.0];
    match name {
        "liver" => Material {
            roughness: 0.25,
            ..Material::tissue(white)
        },
        "muscle" => Material {
            roughness: 0.3,
            detail_period_m: 0.003,
            ..Material::tissue(white)
        },
        _ => Material::tissue(white),
    }
}

/// Camera used for the tissue scenes: from the front, above, looking at the entry point.
pub fn tissue_camera() -> Camera {
    Camera::look_at(Vec3::new(0.0, 0.055, 0.095), Vec3::new(0.0, -0.006, 0.0))
}

/// Tissue meshes (all deformable) at the origin with the needle over the entry point x = z = 0.
pub fn tissue_scene(tissue: &[Arc<MeshData>], needle: &[Arc<MeshData>], state: NeedleState) -> Frame {
    let mut frame = Frame::new(tissue_camera());
    frame.clear_color = [0.015, 0.02, 0.03];
    for mesh in tissue {
        frame
            .objects
            .push(Object::new(mesh.clone(), Mat4::IDENTITY, tissue_material(&mesh.name)).deformable());
    }
    let tip_y_m = match state {
        NeedleState::Above { height_m } => height_m,
        NeedleState::Pressing { depth_m, radius_m } => {
            frame.tissue.dimples.push(Dimple {
                centre_m: Vec3::ZERO,
                normal: Vec3::Y,
                depth_m,
                radius_m,
            });
            -depth_m
        }
        NeedleState::Inserted { depth_m } => {
            frame.tissue.punctured = true;
            -depth_m
        }
    };
    let parts = needle
        .iter()
        .map(|m| {
            let material = if m.name == "hub" {
                Material {
                    color: [0.15, 0.35, 0.85, 1.0],
                    specular: 0.4,
                    ..Material::default()
                }
            } else {
                Material::metal()
            };
            Object::new(m.clone(), Mat4::IDENTITY, material)
        })
        .collect();
    // Tilted a little so the shaft is seen as a line, not end-on.
    let pose = Mat4::from_translation(Vec3::new(0.0, tip_y_m, 0.0)) * Mat4::from_rotation_z(-0.25);
    frame.tool = Some(Tool { pose, parts });
    frame
}

/// The surface tray seen from above its front edge, with the probe (the needle's shaft, say)
/// pressing the centre of mesh `patch_<pressed>` by `depth_m`.
pub fn tray_scene(tray: &[Arc<MeshData>], probe: Option<Arc<MeshData>>, pressed: u32, depth_m: f32) -> Frame {
    let mut frame = Frame::new(Camera::look_at(
        Vec3::new(0.0, 0.2, 0.25),
        Vec3::new(0.0, -0.015, 0.0),
    ));
    for mesh in tray {
        let patch: Option<u32> = mesh.name.strip_prefix("patch_").and_then(|k| k.parse().ok());
        let material = match patch {
            // Detail strength follows the surface's measured RMS roughness (roughest = 1).
            Some(k) => {
                let rq_max_m = PATCH_RQ_M.iter().copied().fold(0.0, f64::max);
                let rq_m = PATCH_RQ_M
                    .get(k.saturating_sub(1) as usize)
                    .copied()
                    .unwrap_or(0.0);
                Material::rough([1.0, 1.0, 1.0], (rq_m / rq_max_m) as f32)
            }
            None => Material::rough([0.35, 0.36, 0.4], 0.05),
        };
        let mut object = Object::new(mesh.clone(), Mat4::IDENTITY, material);
        object.deformable = patch.is_some();
        frame.objects.push(object);
    }
    let name = format!("patch_{pressed}");
    let centre = tray
        .iter()
        .find(|m| m.name == name)
        .map_or(Vec3::ZERO, |m| footprint_centre(m));
    frame.tissue.dimples.push(Dimple {
        centre_m: centre,
        normal: Vec3::Y,
        depth_m,
        radius_m: 0.006,
    });
    if let Some(probe) = probe {
        let parts = vec![Object::new(probe, Mat4::IDENTITY, Material::metal())];
        let pose = Mat4::from_translation(centre - Vec3::Y * depth_m) * Mat4::from_rotation_z(-0.5);
        frame.tool = Some(Tool { pose, parts });
    }
    frame
}

/// Centre of a mesh's x–z footprint, at y = 0 (where surfaces lie by convention).
fn footprint_centre(mesh: &MeshData) -> Vec3 {
    let (lo, hi) = mesh
        .positions
        .iter()
        .fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), p| {
            (lo.min(Vec3::from(*p)), hi.max(Vec3::from(*p)))
        });
    if mesh.positions.is_empty() {
        Vec3::ZERO
    } else {
        Vec3::new((lo.x + hi.x) * 0.5, 0.0, (lo.z + hi.z) * 0.5)
    }
}

/// Overlay content with plausible live data: a puncture force curve peaking at 2.4 N near 9 mm.
pub fn demo_overlay() -> Overlay {
    let force_depth: Vec<[f32; 2]> = (0..=120)
        .map(|i| {
            let d_m = i as f32 * 0.0001;
            let f_n = if d_m < 0.009 {
                2.4 * (d_m / 0.009).powi(2)
            } else {
                0.6 + 40.0 * (d_m - 0.009)
            };
            [d_m, f_n]
        })
        .collect();
    let force_time: Vec<[f32; 2]> = (0..=200)
        .map(|i| {
            let t_s = i as f32 * 0.01;
            [t_s, 0.3 + 0.08 * (t_s * 9.0).sin() + 0.03 * (t_s * 31.0).sin()]
        })
        .collect();
    Overlay {
        force_depth,
        depth_label: None,
        force_time,
        recognized: Some(Recognition {
            surface: "sandpaper_240".into(),
            confidence: 0.87,
            decided: true,
        }),
        haptic_rate_hz: Some(999.6),
        period_error_s: Some(12.5e-6),
        device_status: "simulator".into(),
        scenes: vec![
            "liver_puncture".into(),
            "tissue_block".into(),
            "surface_tray".into(),
        ],
        current_scene: Some(2),
        params: vec![
            Param {
                name: "stiffness".into(),
                value: 450.0,
                min: 50.0,
                max: 2000.0,
                unit: "N/m".into(),
            },
            Param {
                name: "normal force".into(),
                value: 0.3,
                min: 0.0,
                max: 2.0,
                unit: "N".into(),
            },
        ],
        task: TaskPanel::None,
    }
}
