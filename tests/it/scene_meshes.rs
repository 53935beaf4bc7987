//! A teacher's own mesh in a scene: a `.gltf` as another tool wrote it (buffer in a file
//! beside it, a node matrix, no texture coordinates), in millimetres, placed at `scale = 0.001`.

use std::path::Path;

use palpus::scene::Scene;
use palpus::view::{SceneView, ViewState};

/// A 100 × 40 mm plate (x, z once its node's matrix turns it y-up) in millimetres: the `.gltf`
/// and its buffer, written into `dir`.
fn plate_in_millimetres(dir: &Path) {
    let positions: [[f32; 3]; 4] = [
        [-50.0, 0.0, -20.0],
        [50.0, 0.0, -20.0],
        [50.0, 0.0, 20.0],
        [-50.0, 0.0, 20.0],
    ];
    let mut bin: Vec<u8> = positions.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    bin.extend([0u16, 2, 1, 0, 3, 2].iter().flat_map(|i| i.to_le_bytes()));
    std::fs::write(dir.join("plate.bin"), &bin).unwrap();
    let json = serde_json::json!({
        "asset": { "version": "2.0" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0, "name": "plate",
                    "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 10, 0, 1] }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 }, "indices": 1 }] }],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
              "min": [-50.0, 0.0, -20.0], "max": [50.0, 0.0, 20.0] },
            { "bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR" }
        ],
        "bufferViews": [
            { "buffer": 0, "byteLength": 48 },
            { "buffer": 0, "byteOffset": 48, "byteLength": 12 }
        ],
        "buffers": [{ "byteLength": bin.len(), "uri": "plate.bin" }]
    });
    std::fs::write(dir.join("plate.gltf"), serde_json::to_vec_pretty(&json).unwrap()).unwrap();
}

fn scene_text(scale: &str) -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("scenes/needle_liver.toml")).unwrap();
    let text = text.replace("../assets/", &format!("{}/assets/", root.display()));
    text.replace(
        &format!("mesh = \"{}/assets/meshes/liver.glb#liver\"", root.display()),
        &format!("mesh = \"plate.gltf\"\nscale = {scale}"),
    )
}

#[test]
fn a_gltf_in_millimetres_loads_at_its_stated_scale() {
    let dir = tempfile::tempdir().unwrap();
    plate_in_millimetres(dir.path());
    let path = dir.path().join("scene.toml");
    std::fs::write(&path, scene_text("0.001")).unwrap();
    let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let view = SceneView::load(&scene).unwrap_or_else(|e| panic!("{e}"));
    let frame = view.frame(&ViewState::default());
    let plate = &frame.objects[0];
    let corners: Vec<_> = plate
        .mesh
        .positions
        .iter()
        .map(|p| plate.transform.transform_point3(glam::Vec3::from(*p)))
        .collect();
    let extent = |k: usize| {
        let (lo, hi) = corners
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p[k]), hi.max(p[k]))
            });
        (lo, hi)
    };
    // 100 mm × 40 mm, lifted 10 mm by its node's matrix: 0.1 m × 0.04 m at y = 0.01 m.
    let (x, y, z) = (extent(0), extent(1), extent(2));
    assert!((x.1 - x.0 - 0.1).abs() < 1e-6, "{x:?}");
    assert!((z.1 - z.0 - 0.04).abs() < 1e-6, "{z:?}");
    assert!((y.0 - 0.01).abs() < 1e-6 && (y.1 - 0.01).abs() < 1e-6, "{y:?}");

    for bad in ["0.0", "-1.0", "1e9", "nan"] {
        std::fs::write(&path, scene_text(bad)).unwrap();
        let err = Scene::load(&path).expect_err(bad).to_string();
        assert!(err.contains("objects[0].scale"), "{bad}: {err}");
    }
}

/// The lumbar block draws each membrane where the simulated spine has it, so the needle's tip
/// is drawn meeting a layer where the trainee feels it.
#[test]
fn the_lumbar_mesh_and_the_simulated_spine_agree_on_every_membrane() {
    let tissue = sim::NeedleTissue::lumbar_epidural();
    let drawn = render::assets_gen::LUMBAR_LAYER_TOPS_M;
    for m in &tissue.membranes {
        let (_, top) = drawn
            .iter()
            .find(|(name, _)| *name == m.name)
            .unwrap_or_else(|| panic!("{} is not drawn", m.name));
        assert!(
            (f64::from(*top) - m.depth_m).abs() < 1e-7,
            "{}: {top} vs {}",
            m.name,
            m.depth_m
        );
    }
}
