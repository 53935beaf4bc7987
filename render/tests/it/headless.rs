//! Behaviour of the offscreen renderer beyond the golden pictures: sizes, MSAA, errors, sRGB
//! output, the overlay's actions.

#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use std::sync::Arc;

use glam::{Mat4, Vec3};
use render::egui;
use render::{Camera, Frame, Image, Material, Object, RenderError, Renderer, UiAction, shapes};
use render::{NeedleState, demo_overlay, tissue_scene};

fn plane_frame(color: [f32; 4]) -> Frame {
    let plane = Arc::new(shapes::tissue_box(
        "plane",
        [-1.0, -0.01, -1.0],
        [1.0, 0.0, 1.0],
        4,
        [1.0; 4],
    ));
    let mut frame = Frame::new(Camera::look_at(Vec3::new(0.0, 0.3, 0.0001), Vec3::ZERO));
    let material = Material {
        color,
        roughness: 0.0,
        specular: 0.0,
        ..Material::default()
    };
    frame.objects.push(Object::new(plane, Mat4::IDENTITY, material));
    frame
}

#[test]
fn image_has_requested_size_and_background() {
    let mut r = Renderer::headless(96, 64, 1).unwrap();
    let mut frame = Frame::new(Camera::look_at(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO));
    frame.clear_color = [0.5, 0.0, 0.0];
    let img = r.render(&frame).unwrap();
    assert_eq!((img.width, img.height), (96, 64));
    // Linear 0.5 stored in an sRGB target encodes to 188.
    let p = img.pixel(10, 10).unwrap();
    assert!(
        (i32::from(p[0]) - 188).abs() <= 1 && p[1] == 0 && p[2] == 0 && p[3] == 255,
        "{p:?}"
    );
}

#[test]
fn lighting_is_brighter_for_brighter_material_and_msaa_keeps_it() {
    let mut r1 = Renderer::headless(64, 64, 1).unwrap();
    let mut r4 = Renderer::headless(64, 64, 4).unwrap();
    assert!(r4.msaa() == 4 || r4.msaa() == 1);
    let dark = r1
        .render(&plane_frame([0.2, 0.2, 0.2, 1.0]))
        .unwrap()
        .pixel(32, 32)
        .unwrap();
    let bright = r1
        .render(&plane_frame([0.8, 0.8, 0.8, 1.0]))
        .unwrap()
        .pixel(32, 32)
        .unwrap();
    let bright4 = r4
        .render(&plane_frame([0.8, 0.8, 0.8, 1.0]))
        .unwrap()
        .pixel(32, 32)
        .unwrap();
    assert!(bright[0] > dark[0] + 40, "{dark:?} {bright:?}");
    // Interior pixels are the same with and without multisampling.
    assert!(bright4[0].abs_diff(bright[0]) <= 2, "{bright:?} {bright4:?}");
}

#[test]
fn rendering_is_deterministic() {
    let tissue: Vec<_> = shapes::tissue_block().into_iter().map(Arc::new).collect();
    let needle: Vec<_> = shapes::needle().into_iter().map(Arc::new).collect();
    let frame = tissue_scene(
        &tissue,
        &needle,
        NeedleState::Pressing {
            depth_m: 0.01,
            radius_m: 0.012,
        },
    );
    let mut r = Renderer::headless(128, 96, 4).unwrap();
    let a = r.render(&frame).unwrap();
    let b = r.render(&frame).unwrap();
    assert_eq!(a, b);
}

#[test]
fn bad_arguments_are_typed_errors() {
    assert!(matches!(
        Renderer::headless(0, 10, 1),
        Err(RenderError::BadSize { .. })
    ));
    assert!(matches!(
        Renderer::headless(10, 10, 3),
        Err(RenderError::BadMsaa(3))
    ));
    let mut r = Renderer::headless(16, 16, 1).unwrap();
    assert!(matches!(r.resize(100_000, 10), Err(RenderError::BadSize { .. })));
    r.resize(32, 8).unwrap();
    let img = r
        .render(&Frame::new(Camera::look_at(Vec3::Z, Vec3::ZERO)))
        .unwrap();
    assert_eq!((img.width, img.height), (32, 8));
}

#[test]
fn empty_and_broken_meshes_do_not_fail() {
    let mut r = Renderer::headless(32, 32, 1).unwrap();
    let mut frame = Frame::new(Camera::look_at(Vec3::Z, Vec3::ZERO));
    let empty = render::MeshData {
        name: "empty".into(),
        positions: vec![],
        normals: vec![],
        colors: vec![],
        indices: vec![],
        interior_from: None,
    };
    let broken = render::MeshData {
        name: "broken".into(),
        indices: vec![0, 1, 7],
        ..shapes::needle().remove(0)
    };
    frame
        .objects
        .push(Object::new(Arc::new(empty), Mat4::IDENTITY, Material::default()));
    frame
        .objects
        .push(Object::new(Arc::new(broken), Mat4::IDENTITY, Material::default()));
    r.render(&frame).unwrap();
}

#[test]
fn overlay_click_on_scene_returns_select_action() {
    let mut r = Renderer::headless(800, 600, 1).unwrap();
    let mut frame = Frame::new(Camera::look_at(Vec3::Z, Vec3::ZERO));
    let mut overlay = demo_overlay();
    overlay.current_scene = Some(2);
    frame.overlay = Some(overlay);
    // First frame lays the panel out; find the "tissue_block" button by scanning where egui put it
    // is not possible from pixels alone, so click along the scene row until an action comes back.
    r.render(&frame).unwrap();
    let mut found = None;
    'scan: for y in (380..480).step_by(6) {
        for x in (520..790).step_by(20) {
            let pos = egui::pos2(x as f32, y as f32);
            let press = vec![
                egui::Event::PointerMoved(pos),
                egui::Event::PointerButton {
                    pos,
                    button: egui::PointerButton::Primary,
                    pressed: true,
                    modifiers: Default::default(),
                },
            ];
            r.render_with_events(&frame, press).unwrap();
            let release = vec![egui::Event::PointerButton {
                pos,
                button: egui::PointerButton::Primary,
                pressed: false,
                modifiers: Default::default(),
            }];
            let (_, actions) = r.render_with_events(&frame, release).unwrap();
            if let Some(a) = actions
                .into_iter()
                .find(|a| matches!(a, UiAction::SelectScene { .. }))
            {
                found = Some(a);
                break 'scan;
            }
        }
    }
    match found {
        Some(UiAction::SelectScene { index, name }) => {
            assert_ne!(index, 2, "clicking the current scene must not ask to switch");
            assert_eq!(name, ["liver_puncture", "tissue_block", "surface_tray"][index]);
        }
        other => panic!("no scene action found: {other:?}"),
    }
}

#[test]
fn overlay_panel_is_repainted_only_when_its_shapes_change() {
    let mut r = Renderer::headless(480, 320, 1).unwrap();
    let mut frame = Frame::new(Camera::look_at(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO));
    frame.overlay = Some(demo_overlay());
    let first = r.render(&frame).unwrap();
    let painted = r.overlay_repaints();
    let again = r.render(&frame).unwrap();
    assert_eq!(r.overlay_repaints(), painted, "unchanged overlay painted again");
    assert_eq!(first.rgba, again.rgba);
    // New plot data: the panel is painted again, and shows them.
    if let Some(o) = frame.overlay.as_mut() {
        o.force_time.iter_mut().for_each(|p| p[1] += 0.5);
    }
    let changed = r.render(&frame).unwrap();
    assert_eq!(r.overlay_repaints(), painted + 1);
    assert_ne!(changed.rgba, again.rgba);
    // A fresh renderer painting the changed frame once gives the same picture.
    let mut fresh = Renderer::headless(480, 320, 1).unwrap();
    fresh.render(&frame).unwrap();
    assert_eq!(fresh.render(&frame).unwrap().rgba, changed.rgba);
}

#[test]
fn lower_internal_resolution_keeps_the_frame_size_and_costs_measured_quality() {
    let mut r = Renderer::headless(320, 240, 1).unwrap();
    let tissue: Vec<_> = shapes::tissue_block().into_iter().map(Arc::new).collect();
    let needle: Vec<_> = shapes::needle().into_iter().map(Arc::new).collect();
    let frame = tissue_scene(
        &tissue,
        &needle,
        NeedleState::Pressing {
            depth_m: 0.008,
            radius_m: 0.012,
        },
    );
    let full = r.render(&frame).unwrap();
    assert!(matches!(r.set_scale(0.1), Err(RenderError::BadScale(_))));
    assert!(matches!(r.set_scale(f32::NAN), Err(RenderError::BadScale(_))));
    r.set_scale(0.5).unwrap();
    let half = r.render(&frame).unwrap();
    assert_eq!((half.width, half.height), (320, 240));
    let psnr = render::golden::psnr_db(&half, &full).unwrap();
    // Softer, not different: the same scene in the same place.
    assert!(psnr.is_finite() && psnr > 20.0, "PSNR {psnr} dB");
    r.set_scale(1.0).unwrap();
    let again = r.render(&frame).unwrap();
    assert_eq!(render::golden::psnr_db(&again, &full), Some(f64::INFINITY));
}

/// Beside the overlay's panel the lowered scene is drawn only as wide as its own part of the
/// frame and stretched over that part alone: the panel is the full-resolution frame's, pixel for
/// pixel, and the scene stands where it stands at full resolution.
#[test]
fn lower_internal_resolution_beside_the_panel_keeps_both_in_place() {
    use render::bench::{TissueMesh, frame_with};
    let (width, height) = (640, 480);
    let frame = frame_with(TissueMesh::Graded, true);
    let scene_px = width - render::PANEL_WIDTH_PT as u32;
    let crop = |image: &Image, x0: u32, x1: u32| {
        let rgba = (0..height)
            .flat_map(|y| (x0..x1).flat_map(move |x| image.pixel(x, y).unwrap()))
            .collect();
        Image::from_rgba(x1 - x0, height, rgba).unwrap()
    };
    for msaa in [1, 4] {
        let mut r = Renderer::headless(width, height, msaa).unwrap();
        let full = r.render(&frame).unwrap();
        r.set_scale(0.5).unwrap();
        let half = r.render(&frame).unwrap();
        assert_eq!(
            crop(&half, scene_px, width).rgba,
            crop(&full, scene_px, width).rgba,
            "MSAA {msaa}: the panel changed"
        );
        let psnr = render::golden::psnr_db(&crop(&half, 0, scene_px), &crop(&full, 0, scene_px)).unwrap();
        // 33 dB here; stretched over the whole frame's width it was 25 dB.
        assert!(psnr > 30.0, "MSAA {msaa}: scene PSNR {psnr} dB");
    }
}

/// The block cut by its dimple draws what the uniformly fine block draws: a handful of pixels
/// on edges may land differently, nothing more.
#[test]
fn the_graded_block_looks_like_the_uniform_one() {
    use render::bench::{TissueMesh, frame_with};
    let mut r = Renderer::headless(640, 480, 4).unwrap();
    let graded = r.render(&frame_with(TissueMesh::Graded, true)).unwrap();
    let uniform = r.render(&frame_with(TissueMesh::Uniform, true)).unwrap();
    let cmp = render::golden::compare(&graded, &uniform, 8).unwrap();
    assert!(
        cmp.fraction() < 1e-4,
        "{} of {} pixels differ",
        cmp.differing_pixels,
        cmp.total_pixels
    );
    let psnr = render::golden::psnr_db(&graded, &uniform).unwrap();
    assert!(psnr > 50.0, "PSNR {psnr} dB");
    let triangles = |m: TissueMesh| -> usize {
        frame_with(m, false)
            .objects
            .iter()
            .map(|o| o.mesh.indices.len() / 3)
            .sum()
    };
    assert!(4 * triangles(TissueMesh::Graded) < triangles(TissueMesh::Uniform));
}

/// The benchmark measures as many rows as it says, reports each, and scores every row but the
/// uniform reference against that reference.
#[test]
fn the_benchmark_reports_each_row_and_scores_against_the_uniform_block() {
    use render::bench::{BenchOptions, OverlayMode, TissueMesh, row_count, run_reporting};
    let options = BenchOptions {
        sizes: vec![[96, 64]],
        msaa: vec![1],
        overlay: vec![OverlayMode::Off],
        scales: vec![0.5],
        uniform_row: true,
        frames: 1,
        ..BenchOptions::default()
    };
    let mut seen = Vec::new();
    let table = run_reporting(&options, |done, total| seen.push((done, total))).unwrap();
    assert_eq!(row_count(&options), 3);
    assert_eq!(seen, vec![(1, 3), (2, 3), (3, 3)]);
    assert_eq!(table.rows.len(), 3);
    for row in &table.rows {
        assert!(row.fps.is_finite() && row.fps > 0.0);
        match row.mesh {
            TissueMesh::Uniform => assert_eq!(row.psnr_db, None),
            TissueMesh::Graded => assert!(row.psnr_db.is_some_and(|p| p > 20.0), "{row:?}"),
        }
    }
}
