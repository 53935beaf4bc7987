//! Golden images of the four reference views, drawn headless with the committed assets.
//! `PALPUS_BLESS=1 cargo test -p render --test it golden::` rewrites `assets/golden/*.png`; on a
//! mismatch the actual image and a diff land in `target/golden-failures/`.

#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use render::golden::{Tolerance, check};
use render::{Frame, Image, MeshData, Renderer, load_gltf};
use render::{NeedleState, demo_overlay, tissue_scene, tray_scene};

const WIDTH: u32 = 640;
const HEIGHT: u32 = 480;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn meshes(file: &str) -> Vec<Arc<MeshData>> {
    load_gltf(&root().join("assets/meshes").join(file))
        .unwrap()
        .into_iter()
        .map(Arc::new)
        .collect()
}

fn draw(frame: &Frame, width: u32, height: u32) -> Image {
    let mut renderer = Renderer::headless(width, height, 4).unwrap();
    renderer.render(frame).unwrap()
}

fn golden(name: &str, image: &Image) {
    let result = check(
        name,
        image,
        &root().join("assets/golden"),
        &root().join("target/golden-failures"),
        Tolerance::default(),
    );
    if let Err(e) = result {
        panic!("{e}");
    }
}

/// The tissue block's and the needle's committed meshes.
fn tissue_and_needle() -> (Vec<Arc<MeshData>>, Vec<Arc<MeshData>>) {
    (meshes("tissue_block.glb"), meshes("needle.glb"))
}

/// The tissue scene with the needle in `state`, drawn at the golden size.
fn tissue_view(tissue: &[Arc<MeshData>], needle: &[Arc<MeshData>], state: NeedleState) -> Image {
    draw(&tissue_scene(tissue, needle, state), WIDTH, HEIGHT)
}

/// Pixels of `a` and `b` that differ by more than a small tolerance.
fn differing_pixels(a: &Image, b: &Image) -> usize {
    render::golden::compare(a, b, 24).unwrap().differing_pixels
}

fn luma(p: [u8; 4]) -> f32 {
    0.299 * f32::from(p[0]) + 0.587 * f32::from(p[1]) + 0.114 * f32::from(p[2])
}

#[test]
fn tissue_at_rest() {
    let (tissue, needle) = tissue_and_needle();
    let image = tissue_view(&tissue, &needle, NeedleState::Above { height_m: 0.02 });
    // The block fills the middle of the picture: not the background colour.
    let centre = image.pixel(WIDTH / 2, HEIGHT * 3 / 5).unwrap();
    assert!(luma(centre) > 40.0, "{centre:?}");
    golden("tissue_at_rest", &image);
}

#[test]
fn needle_dimpling_surface() {
    let (tissue, needle) = tissue_and_needle();
    let rest = tissue_view(&tissue, &needle, NeedleState::Above { height_m: 0.0 });
    let pressed = tissue_view(
        &tissue,
        &needle,
        NeedleState::Pressing {
            depth_m: 0.010,
            radius_m: 0.012,
        },
    );
    // The dimple changes a sizeable area around the entry point, not just the needle.
    let changed = differing_pixels(&pressed, &rest);
    assert!(changed > 2000, "dimple changed only {changed} pixels");
    golden("needle_dimpling_surface", &pressed);
}

#[test]
fn needle_inserted() {
    let (tissue, needle) = tissue_and_needle();
    let inserted = tissue_view(&tissue, &needle, NeedleState::Inserted { depth_m: 0.025 });
    let mut opaque = tissue_scene(&tissue, &needle, NeedleState::Inserted { depth_m: 0.025 });
    opaque.tissue.punctured = false;
    let hidden = draw(&opaque, WIDTH, HEIGHT);
    // See-through tissue reveals the shaft below the surface: the two pictures differ there.
    let changed = differing_pixels(&inserted, &hidden);
    assert!(changed > 1000, "only {changed} pixels changed");
    golden("needle_inserted", &inserted);
}

#[test]
fn surface_tray_with_overlay() {
    let needle = meshes("needle.glb");
    let probe = needle.iter().find(|m| m.name == "shaft").cloned();
    let mut frame = tray_scene(&meshes("surface_tray.glb"), probe, 3, 0.002);
    frame.overlay = Some(demo_overlay());
    let image = draw(&frame, 960, 600);
    // The overlay panel on the right is dark and mostly opaque; the heading text is light.
    let panel = image.pixel(960 - 20, 590).unwrap();
    assert!(luma(panel) < 60.0, "{panel:?}");
    golden("surface_tray_with_overlay", &image);
}

/// Before the recognizer's posterior reaches its threshold the overlay says so, and shows the
/// most likely surface with its probability instead of naming it.
#[test]
fn surface_tray_with_an_undecided_recognizer() {
    let mut frame = tray_scene(&meshes("surface_tray.glb"), None, 3, 0.002);
    let mut overlay = demo_overlay();
    overlay.recognized = Some(render::Recognition {
        surface: "sandpaper_240".into(),
        confidence: 0.62,
        decided: false,
    });
    frame.overlay = Some(overlay);
    golden("surface_tray_undecided", &draw(&frame, 640, 400));
}
