//! Interior faces (where tissue layers meet, a vessel inside its organ) are skipped while the
//! tissue is opaque: the picture must not change, and they must show once it is see-through.

#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use std::path::Path;
use std::sync::Arc;

use glam::Vec3;
use render::{Camera, Frame, MeshData, Renderer, load_gltf, shapes};
use render::{NeedleState, tissue_scene};

fn asset(name: &str) -> Vec<MeshData> {
    load_gltf(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../assets/meshes")
            .join(name),
    )
    .unwrap()
}

/// The same meshes with their interior triangles drawn as ordinary ones.
fn all_outside(meshes: &[MeshData]) -> Vec<MeshData> {
    meshes
        .iter()
        .map(|m| MeshData {
            interior_from: None,
            ..m.clone()
        })
        .collect()
}

/// The same meshes without their interior triangles.
fn without_interior(meshes: &[MeshData]) -> Vec<MeshData> {
    meshes
        .iter()
        .map(|m| MeshData {
            indices: m.exterior_indices().to_vec(),
            interior_from: None,
            ..m.clone()
        })
        .collect()
}

fn frame(tissue: &[MeshData], state: NeedleState, camera: Option<Camera>) -> Frame {
    let tissue: Vec<_> = tissue.iter().cloned().map(Arc::new).collect();
    let needle: Vec<_> = shapes::needle().into_iter().map(Arc::new).collect();
    let mut frame = tissue_scene(&tissue, &needle, state);
    if let Some(camera) = camera {
        frame.camera = camera;
    }
    frame
}

fn tissues() -> Vec<(&'static str, Vec<MeshData>)> {
    vec![
        ("procedural block", shapes::tissue_block()),
        ("tissue_block.glb", asset("tissue_block.glb")),
        ("liver.glb", asset("liver.glb")),
        ("lumbar.glb", asset("lumbar.glb")),
    ]
}

#[test]
fn every_tissue_asset_has_interior_faces() {
    for (name, meshes) in tissues() {
        let interior: usize = meshes.iter().map(|m| m.interior_indices().len() / 3).sum();
        assert!(interior > 0, "{name}");
    }
    let liver = asset("liver.glb");
    let vessel = liver.iter().find(|m| m.name == "vessel").unwrap();
    assert_eq!(vessel.interior_from, Some(0), "the vessel lies inside the liver");
    assert!(
        liver
            .iter()
            .find(|m| m.name == "liver")
            .unwrap()
            .interior_from
            .is_none()
    );
}

#[test]
fn a_blocks_interior_faces_are_exactly_those_where_two_layers_meet() {
    for meshes in [shapes::tissue_block(), asset("tissue_block.glb")] {
        // Each layer's bottom is the next one's top.
        let mut bottoms: Vec<f32> = meshes
            .iter()
            .map(|m| m.positions.iter().map(|p| p[1]).fold(f32::MAX, f32::min))
            .collect();
        bottoms.pop();
        let on_interface = |m: &MeshData, t: &[u32]| {
            bottoms
                .iter()
                .any(|&y| t.iter().all(|&i| m.positions[i as usize][1] == y))
        };
        for m in &meshes {
            assert!(
                m.exterior_indices().chunks(3).all(|t| !on_interface(m, t)),
                "{}",
                m.name
            );
            assert!(
                m.interior_indices().chunks(3).all(|t| on_interface(m, t)),
                "{}",
                m.name
            );
        }
    }
}

#[test]
fn skipping_interior_faces_leaves_the_opaque_picture_unchanged() {
    let views = [
        None,
        // From below and behind: the block's and the liver's undersides.
        Some(Camera::look_at(
            Vec3::new(0.03, -0.09, -0.08),
            Vec3::new(0.0, -0.01, 0.0),
        )),
    ];
    let mut r = Renderer::headless(256, 192, 4).unwrap();
    for (name, meshes) in tissues() {
        for camera in views {
            let state = NeedleState::Pressing {
                depth_m: 0.008,
                radius_m: 0.012,
            };
            let skipped = r.render(&frame(&meshes, state, camera)).unwrap();
            let drawn = r.render(&frame(&all_outside(&meshes), state, camera)).unwrap();
            // Where two layers' edges meet, 4× MSAA samples can fall between them and on the
            // face between the layers: a few seam pixels may change, by little.
            let c = render::golden::compare(&skipped, &drawn, 16).unwrap();
            assert!(c.differing_pixels <= 8, "{name}, camera {camera:?}: {c:?}");
        }
    }
}

#[test]
fn interior_faces_show_through_see_through_tissue() {
    let mut r = Renderer::headless(256, 192, 1).unwrap();
    for (name, meshes) in tissues() {
        let state = NeedleState::Inserted { depth_m: 0.015 };
        let with = r.render(&frame(&meshes, state, None)).unwrap();
        let without = r.render(&frame(&without_interior(&meshes), state, None)).unwrap();
        let comparison = render::golden::compare(&with, &without, 8).unwrap();
        assert!(comparison.fraction() > 0.001, "{name}: {comparison:?}");
    }
}
