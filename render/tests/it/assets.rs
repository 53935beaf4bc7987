//! The generated assets: file round trip, reproducibility against the committed files, and the
//! geometric promises the renderer and the app rely on.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use render::assets_gen::{
    BLOCK_DEPTH_M, BLOCK_SIZE_M, BUMP_HEIGHT_EXAGGERATION, FAT_THICKNESS_M, HUB_LENGTH_M, HUB_RADIUS_M,
    LUMBAR_LAYER_TOPS_M, NEEDLE_LENGTH_M, NEEDLE_RADIUS_M, PATCH_CENTRES_M, PATCH_NAMES, PATCH_RQ_M,
    PATCH_SIZE_M, SKIN_THICKNESS_M, VESSEL_RADIUS_M, VESSEL_WALL_DEPTH_M, default_assets, patch_centre_m,
    write_default_assets,
};
use render::{MeshData, RenderError, load_gltf, write_glb};

fn committed_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/meshes")
}

fn asset(file: &str) -> Vec<MeshData> {
    default_assets()
        .into_iter()
        .find(|(name, _)| *name == file)
        .map(|(_, m)| m)
        .unwrap_or_else(|| panic!("no asset {file}"))
}

fn mesh<'a>(meshes: &'a [MeshData], name: &str) -> &'a MeshData {
    meshes
        .iter()
        .find(|m| m.name == name)
        .unwrap_or_else(|| panic!("no mesh {name}"))
}

fn bbox(m: &MeshData) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in &m.positions {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

/// Position key that merges coincident vertices (and +0.0 with -0.0).
fn key(p: [f32; 3]) -> [u32; 3] {
    [
        (p[0] + 0.0).to_bits(),
        (p[1] + 0.0).to_bits(),
        (p[2] + 0.0).to_bits(),
    ]
}

fn welded_triangles(m: &MeshData) -> Vec<[usize; 3]> {
    let mut ids: HashMap<[u32; 3], usize> = HashMap::new();
    let welded: Vec<usize> = m
        .positions
        .iter()
        .map(|&p| {
            let n = ids.len();
            *ids.entry(key(p)).or_insert(n)
        })
        .collect();
    m.indices
        .chunks_exact(3)
        .map(|t| {
            [
                welded[t[0] as usize],
                welded[t[1] as usize],
                welded[t[2] as usize],
            ]
        })
        .collect()
}

/// Every directed edge appears once and its reverse once: closed, manifold, consistently wound.
fn assert_watertight(m: &MeshData) {
    let mut edges: HashMap<(usize, usize), u32> = HashMap::new();
    for t in welded_triangles(m) {
        assert!(
            t[0] != t[1] && t[1] != t[2] && t[0] != t[2],
            "{}: degenerate triangle {t:?}",
            m.name
        );
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *edges.entry((a, b)).or_default() += 1;
        }
    }
    for (&(a, b), &count) in &edges {
        assert_eq!(count, 1, "{}: directed edge {a}->{b} used {count} times", m.name);
        assert_eq!(
            edges.get(&(b, a)),
            Some(&1),
            "{}: edge {a}-{b} has no opposite",
            m.name
        );
    }
}

fn signed_volume(m: &MeshData) -> f64 {
    m.indices
        .chunks_exact(3)
        .map(|t| {
            let p = |i: u32| m.positions[i as usize].map(f64::from);
            let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
            (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]))
                / 6.0
        })
        .sum()
}

/// Heights where the vertical line through (x, z) crosses the mesh, sorted ascending.
fn vertical_hits(m: &MeshData, x: f64, z: f64) -> Vec<f64> {
    let mut hits = Vec::new();
    for t in m.indices.chunks_exact(3) {
        let p = |i: u32| m.positions[i as usize].map(f64::from);
        let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
        let det = (b[0] - a[0]) * (c[2] - a[2]) - (c[0] - a[0]) * (b[2] - a[2]);
        if det.abs() < 1e-18 {
            continue;
        }
        let u = ((x - a[0]) * (c[2] - a[2]) - (c[0] - a[0]) * (z - a[2])) / det;
        let v = ((b[0] - a[0]) * (z - a[2]) - (x - a[0]) * (b[2] - a[2])) / det;
        if u >= -1e-9 && v >= -1e-9 && u + v <= 1.0 + 1e-9 {
            hits.push(a[1] + u * (b[1] - a[1]) + v * (c[1] - a[1]));
        }
    }
    hits.sort_by(f64::total_cmp);
    // A line through a shared vertex or edge hits several triangles at the same height.
    hits.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    hits
}

fn dist(a: [f32; 3], b: [f32; 3]) -> f32 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Longest triangle edge among triangles whose corners all lie within `radius_m` of `centre`.
fn max_edge_near(m: &MeshData, centre: [f32; 3], radius_m: f32) -> (f32, usize) {
    let mut longest = 0.0f32;
    let mut count = 0;
    for t in m.indices.chunks_exact(3) {
        let p = [0, 1, 2].map(|k| m.positions[t[k] as usize]);
        if p.iter().all(|&q| dist(q, centre) <= radius_m) {
            count += 1;
            longest = longest
                .max(dist(p[0], p[1]))
                .max(dist(p[1], p[2]))
                .max(dist(p[2], p[0]));
        }
    }
    (longest, count)
}

#[test]
fn write_then_load_is_bit_exact() {
    let dir = tempfile::tempdir().unwrap();
    let odd = MeshData {
        name: "odd \"name\" é".into(),
        positions: vec![
            [-0.0, 1e-30, f32::MAX],
            [1.0 / 3.0, -7.25, 0.1],
            [f32::MIN_POSITIVE, 2.0, -3.5],
        ],
        normals: vec![[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]],
        colors: vec![
            [0.1, 0.2, 0.3, 0.4],
            [1.0, 1.0, 1.0, 1.0],
            [0.0, 0.5, 0.25, 0.125],
        ],
        indices: vec![0, 1, 2, 2, 1, 0],
        interior_from: None,
    };
    let mut cases: Vec<Vec<MeshData>> = default_assets().into_iter().map(|(_, m)| m).collect();
    cases.push(vec![odd]);
    for (n, meshes) in cases.iter().enumerate() {
        let path = dir.path().join(format!("case_{n}.glb"));
        write_glb(&path, meshes).unwrap();
        let loaded = load_gltf(&path).unwrap();
        assert_eq!(loaded.len(), meshes.len());
        for (a, b) in meshes.iter().zip(&loaded) {
            assert_eq!(a.name, b.name);
            assert_eq!(a.indices, b.indices, "{}", a.name);
            let bits3 = |v: &[[f32; 3]]| v.iter().flat_map(|p| p.map(f32::to_bits)).collect::<Vec<_>>();
            let bits4 = |v: &[[f32; 4]]| v.iter().flat_map(|p| p.map(f32::to_bits)).collect::<Vec<_>>();
            assert_eq!(bits3(&a.positions), bits3(&b.positions), "{}", a.name);
            assert_eq!(bits3(&a.normals), bits3(&b.normals), "{}", a.name);
            assert_eq!(bits4(&a.colors), bits4(&b.colors), "{}", a.name);
        }
    }
    // Nothing but the written files: the temporary sibling was renamed away.
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into())
        .collect();
    assert!(
        names
            .iter()
            .all(|n| n.starts_with("case_") && n.ends_with(".glb")),
        "{names:?}"
    );
}

#[test]
fn written_file_is_a_valid_glb_with_position_bounds() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("needle.glb");
    write_glb(&path, &asset("needle.glb")).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(&bytes[0..4], b"glTF");
    assert_eq!(u32::from_le_bytes(bytes[4..8].try_into().unwrap()), 2);
    assert_eq!(
        u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize,
        bytes.len()
    );
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    assert_eq!(json_len % 4, 0);
    let json: serde_json::Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    let accessor = &json["accessors"][0];
    assert_eq!(accessor["type"], "VEC3");
    let (lo, hi) = bbox(&asset("needle.glb")[0]);
    for k in 0..3 {
        assert_eq!(accessor["min"][k].as_f64().unwrap() as f32, lo[k]);
        assert_eq!(accessor["max"][k].as_f64().unwrap() as f32, hi[k]);
    }
    assert_eq!(json["nodes"][1]["name"], "hub");
}

#[test]
fn regenerated_assets_match_committed_files() {
    let dir = tempfile::tempdir().unwrap();
    let written = write_default_assets(dir.path()).unwrap();
    assert_eq!(written.len(), 5);
    let mut total = 0;
    for path in written {
        let name = path.file_name().unwrap();
        let fresh = std::fs::read(&path).unwrap();
        let committed = std::fs::read(committed_dir().join(name)).unwrap_or_else(|e| {
            panic!("{name:?}: {e}; run `cargo run -p render --example make_assets -- assets/meshes`")
        });
        assert!(
            fresh == committed,
            "{name:?} differs from the committed file; regenerate the assets"
        );
        assert!(fresh.len() < 1_500_000, "{name:?} is {} bytes", fresh.len());
        total += fresh.len();
    }
    assert!(total < 4_000_000, "assets total {total} bytes");
}

#[test]
fn normals_are_unit_and_indices_in_range() {
    for (file, meshes) in default_assets() {
        for m in &meshes {
            let n = m.positions.len();
            assert!(n > 0 && !m.indices.is_empty(), "{file}/{}", m.name);
            assert_eq!(m.normals.len(), n);
            assert_eq!(m.colors.len(), n);
            assert_eq!(m.indices.len() % 3, 0);
            assert!(m.indices.iter().all(|&i| (i as usize) < n), "{file}/{}", m.name);
            for v in &m.normals {
                let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                assert!((len - 1.0).abs() < 1e-5, "{file}/{}: normal length {len}", m.name);
            }
            for c in &m.colors {
                assert!(
                    c.iter().all(|v| (0.0..=1.0).contains(v)),
                    "{file}/{}: colour {c:?}",
                    m.name
                );
                assert_eq!(c[3], 1.0);
            }
        }
    }
}

#[test]
fn closed_meshes_are_watertight_and_outward() {
    let closed = [
        ("liver.glb", vec!["liver", "vessel"]),
        ("tissue_block.glb", vec!["skin", "fat", "muscle"]),
        ("needle.glb", vec!["shaft", "hub"]),
        (
            "lumbar.glb",
            vec![
                "skin",
                "subcutaneous_fat",
                "supraspinous_ligament",
                "interspinous_ligament",
                "spinous_process_upper",
                "muscle_left",
                "ligamentum_flavum",
                "epidural_space",
                "dural_sac",
            ],
        ),
        ("surface_tray.glb", vec!["tray", "patch_1", "patch_4", "patch_7"]),
    ];
    for (file, names) in closed {
        let meshes = asset(file);
        for name in names {
            let m = mesh(&meshes, name);
            assert_watertight(m);
            let (lo, hi) = bbox(m);
            let box_volume: f64 = (0..3).map(|k| f64::from(hi[k] - lo[k])).product();
            let volume = signed_volume(m);
            // Positive (outward winding) and a plausible fraction of the bounding box.
            assert!(
                volume > 0.1 * box_volume && volume <= 1.001 * box_volume,
                "{file}/{name}: {volume} vs {box_volume}"
            );
        }
    }
}

#[test]
fn layer_volumes_match_their_dimensions() {
    let meshes = asset("tissue_block.glb");
    let area = f64::from(BLOCK_SIZE_M).powi(2);
    for (name, thickness) in [
        ("skin", f64::from(SKIN_THICKNESS_M)),
        ("fat", f64::from(FAT_THICKNESS_M)),
        (
            "muscle",
            f64::from(BLOCK_DEPTH_M - SKIN_THICKNESS_M - FAT_THICKNESS_M),
        ),
    ] {
        let v = signed_volume(mesh(&meshes, name));
        assert!((v / (area * thickness) - 1.0).abs() < 1e-4, "{name}: {v}");
    }
}

#[test]
fn the_lumbar_layers_lie_where_the_simulated_spine_has_them() {
    let meshes = asset("lumbar.glb");
    let top_of = |name: &str| bbox(mesh(&meshes, name)).1[1];
    for (name, depth) in LUMBAR_LAYER_TOPS_M {
        // The dura is the dural sac's top.
        let name = if name == "dura" { "dural_sac" } else { name };
        assert!(
            (top_of(name) + depth).abs() < 1e-7,
            "{name}: top {} for {depth}",
            top_of(name)
        );
    }
    // Straight down the entry point the needle meets skin, fat, the supraspinous and the
    // interspinous ligament, the flavum, the epidural fat and the sac, in that order.
    let entry: Vec<(&str, f64)> = meshes
        .iter()
        .filter_map(|m| {
            let hits = vertical_hits(m, 0.0, 0.0);
            hits.last().map(|&y| (m.name.as_str(), y))
        })
        .collect();
    let mut order = entry.clone();
    order.sort_by(|a, b| b.1.total_cmp(&a.1));
    let names: Vec<&str> = order.iter().map(|e| e.0).collect();
    assert_eq!(
        names,
        [
            "skin",
            "subcutaneous_fat",
            "supraspinous_ligament",
            "interspinous_ligament",
            "ligamentum_flavum",
            "epidural_space",
            "dural_sac"
        ],
        "{entry:?}"
    );
    let (longest, count) = max_edge_near(mesh(&meshes, "skin"), [0.0; 3], 0.020);
    assert!(
        count > 1000 && longest <= 1.5e-3,
        "{count} triangles, edge {longest} m"
    );
}

#[test]
fn liver_entry_point_is_finely_tessellated_at_y0_with_up_normal() {
    let meshes = asset("liver.glb");
    let liver = mesh(&meshes, "liver");
    let origin = liver
        .positions
        .iter()
        .position(|p| p[0] == 0.0 && p[2] == 0.0 && p[1] > -0.01)
        .unwrap();
    assert!(liver.positions[origin][1].abs() <= 1e-4);
    assert!(liver.normals[origin][1] > 0.9999, "{:?}", liver.normals[origin]);
    let hits = vertical_hits(liver, 0.0, 0.0);
    assert_eq!(hits.len(), 2, "{hits:?}");
    assert!(hits[1].abs() <= 1e-4);
    // The dome's apex: nothing of the organ rises above the entry point.
    assert!(bbox(liver).1[1] <= 1e-6);
    let (longest, count) = max_edge_near(liver, [0.0; 3], 0.020);
    assert!(count > 1000, "only {count} triangles near the entry point");
    assert!(longest <= 1.5e-3, "edge {longest} m near the entry point");
    let (lo, hi) = bbox(liver);
    let size = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
    assert!((0.14..=0.18).contains(&size[0]), "{size:?}");
    assert!((0.05..=0.075).contains(&size[1]), "{size:?}");
    assert!((0.09..=0.125).contains(&size[2]), "{size:?}");
}

#[test]
fn vessel_runs_along_x_20mm_below_the_entry_point_inside_the_liver() {
    let meshes = asset("liver.glb");
    let (liver, vessel) = (mesh(&meshes, "liver"), mesh(&meshes, "vessel"));
    let (lo, hi) = bbox(vessel);
    assert!((hi[1] + VESSEL_WALL_DEPTH_M).abs() < 1e-6, "wall top {}", hi[1]);
    assert!(((hi[1] - lo[1]) - 2.0 * VESSEL_RADIUS_M).abs() < 1e-6);
    assert!((hi[2] + lo[2]).abs() < 1e-6 && hi[0] - lo[0] > 0.1);
    let surface = vertical_hits(liver, 0.0, 0.0)[1];
    let centre = 0.5 * f64::from(hi[1] + lo[1]);
    assert!(((surface - centre) - f64::from(VESSEL_WALL_DEPTH_M + VESSEL_RADIUS_M)).abs() < 1e-5);
    for p in vessel.positions.iter().step_by(7) {
        let hits = vertical_hits(liver, f64::from(p[0]), f64::from(p[2]));
        let (below, above) = (hits[0], hits[hits.len() - 1]);
        let y = f64::from(p[1]);
        assert!(
            below + 0.002 < y && y + 0.002 < above,
            "vessel point {p:?} outside liver {below}..{above}"
        );
    }
}

#[test]
fn tissue_block_layers_stack_with_fine_skin_top() {
    let meshes = asset("tissue_block.glb");
    let layers = [
        ("skin", 0.0, -SKIN_THICKNESS_M),
        ("fat", -SKIN_THICKNESS_M, -SKIN_THICKNESS_M - FAT_THICKNESS_M),
        ("muscle", -SKIN_THICKNESS_M - FAT_THICKNESS_M, -BLOCK_DEPTH_M),
    ];
    for (name, top, bottom) in layers {
        let (lo, hi) = bbox(mesh(&meshes, name));
        assert!(
            (hi[1] - top).abs() < 1e-7 && (lo[1] - bottom).abs() < 1e-7,
            "{name}: {lo:?} {hi:?}"
        );
        for k in [0, 2] {
            assert!((hi[k] - 0.5 * BLOCK_SIZE_M).abs() < 1e-7 && (lo[k] + 0.5 * BLOCK_SIZE_M).abs() < 1e-7);
        }
    }
    let skin = mesh(&meshes, "skin");
    let (longest, count) = max_edge_near(skin, [0.0; 3], 0.020);
    assert!(
        count > 1000 && longest <= 1.5e-3,
        "{count} triangles, longest {longest}"
    );
}

#[test]
fn needle_tip_is_at_the_origin_with_shaft_along_y() {
    let meshes = asset("needle.glb");
    let (shaft, hub) = (mesh(&meshes, "shaft"), mesh(&meshes, "hub"));
    let (lo, hi) = bbox(shaft);
    assert_eq!(lo[1], 0.0);
    assert!((hi[1] - NEEDLE_LENGTH_M).abs() < 1e-7);
    let lowest: Vec<_> = shaft.positions.iter().filter(|p| p[1] == 0.0).collect();
    assert!(
        !lowest.is_empty() && lowest.iter().all(|p| p[0] == 0.0 && p[2] == 0.0),
        "{lowest:?}"
    );
    let radius = shaft
        .positions
        .iter()
        .map(|p| p[0].hypot(p[2]))
        .fold(0.0, f32::max);
    assert!((radius - NEEDLE_RADIUS_M).abs() < 1e-7);
    let (hlo, hhi) = bbox(hub);
    assert!(
        (hlo[1] - NEEDLE_LENGTH_M).abs() < 1e-7 && (hhi[1] - NEEDLE_LENGTH_M - HUB_LENGTH_M).abs() < 1e-7
    );
    let hub_radius = hub.positions.iter().map(|p| p[0].hypot(p[2])).fold(0.0, f32::max);
    assert!((hub_radius - HUB_RADIUS_M).abs() < 1e-7);
    assert_ne!(shaft.colors[0], hub.colors[0]);
}

/// Top-surface heights of a patch: the only vertices with upward-tilted normals (walls are
/// horizontal-facing, the bottom faces down).
fn patch_top_heights(m: &MeshData) -> Vec<f64> {
    m.positions
        .iter()
        .zip(&m.normals)
        .filter(|(_, n)| n[1] > 0.0)
        .map(|(p, _)| f64::from(p[1]))
        .collect()
}

#[test]
fn patches_lie_side_by_side_on_y0_and_rank_by_roughness() {
    let meshes = asset("surface_tray.glb");
    assert_eq!(meshes.len(), 8);
    assert_eq!(meshes[0].name, "tray");
    let mut previous_max_x = f32::NEG_INFINITY;
    let mut rms = Vec::new();
    for (i, name) in PATCH_NAMES.iter().enumerate() {
        let patch = &meshes[i + 1];
        assert_eq!(patch.name, format!("patch_{}", i + 1), "{name}");
        let (lo, hi) = bbox(patch);
        assert!(
            lo[0] > previous_max_x,
            "patch_{} overlaps its left neighbour",
            i + 1
        );
        previous_max_x = hi[0];
        assert!(
            (hi[0] - lo[0] - PATCH_SIZE_M[0]).abs() < 1e-6 && (hi[2] - lo[2] - PATCH_SIZE_M[1]).abs() < 1e-6
        );
        let centre = patch_centre_m(i).unwrap();
        assert_eq!(centre, PATCH_CENTRES_M[i]);
        assert!(
            (0.5 * (hi[0] + lo[0]) - centre[0]).abs() < 1e-6
                && (0.5 * (hi[2] + lo[2]) - centre[2]).abs() < 1e-6
        );
        let heights = patch_top_heights(patch);
        assert_eq!(heights.len(), 44 * 58);
        let mean = heights.iter().sum::<f64>() / heights.len() as f64;
        let r = (heights.iter().map(|h| (h - mean).powi(2)).sum::<f64>() / heights.len() as f64).sqrt();
        let bump = BUMP_HEIGHT_EXAGGERATION * PATCH_RQ_M[i];
        assert!(mean.abs() < 1e-7, "{name}: mean {mean}");
        assert!((r / bump - 1.0).abs() < 1e-3, "{name}: rms {r} vs {bump}");
        assert!(heights.iter().all(|h| h.abs() < 6.0 * bump), "{name}: outlier");
        // The bumps never reach down to the patch's bottom face.
        assert!(
            heights.iter().all(|&h| h > f64::from(lo[1]) + 0.001),
            "{name}: top reaches the bottom"
        );
        // Colour grain: stronger for rougher surfaces.
        let lum: Vec<f64> = patch.colors[..heights.len()]
            .iter()
            .map(|c| f64::from(c[0] + c[1] + c[2]))
            .collect();
        let lm = lum.iter().sum::<f64>() / lum.len() as f64;
        let contrast = (lum.iter().map(|l| (l - lm).powi(2)).sum::<f64>() / lum.len() as f64).sqrt() / lm;
        assert!(contrast > 0.01, "{name}: no visible grain ({contrast})");
        rms.push((r, PATCH_RQ_M[i], contrast));
    }
    assert!(patch_centre_m(7).is_none());
    let rank = |f: &dyn Fn(&(f64, f64, f64)) -> f64| {
        let mut order: Vec<usize> = (0..rms.len()).collect();
        order.sort_by(|&a, &b| f(&rms[a]).total_cmp(&f(&rms[b])));
        order
    };
    assert_eq!(rank(&|t| t.0), rank(&|t| t.1), "measured RMS {rms:?}");
    let (tray_lo, tray_hi) = bbox(&meshes[0]);
    assert!(tray_lo[0] < bbox(&meshes[1]).0[0] && tray_hi[0] > previous_max_x);
    assert!(
        tray_hi[1] <= bbox(&meshes[1]).0[1] + 1e-7,
        "tray pokes through the patches"
    );
}

#[test]
fn missing_file_is_not_found() {
    let path = Path::new("/nonexistent/dir/liver.glb");
    match load_gltf(path) {
        Err(RenderError::NotFound { path: p }) => assert_eq!(p, path),
        other => panic!("{other:?}"),
    }
}

#[test]
fn garbage_bytes_are_not_gltf() {
    let dir = tempfile::tempdir().unwrap();
    for (n, bytes) in [
        b"\x00\x01garbage bytes".to_vec(),
        b"glTF\x02\x00\x00\x00\xff\xff".to_vec(),
    ]
    .iter()
    .enumerate()
    {
        let path = dir.path().join(format!("bad_{n}.glb"));
        let err = load_error(&path, bytes);
        assert!(matches!(err, RenderError::NotGltf { .. }), "{err:?}");
        assert!(err.to_string().contains(&format!("bad_{n}.glb")), "{err}");
    }
}

/// Writes `bytes` to `path` and returns why loading them fails; a successful load fails the test.
fn load_error(path: &Path, bytes: &[u8]) -> RenderError {
    std::fs::write(path, bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    match load_gltf(path) {
        Err(e) => e,
        Ok(meshes) => panic!("{} loaded: {meshes:?}", path.display()),
    }
}

fn glb_from_json(json: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut j = serde_json::to_vec(json).unwrap_or_else(|e| panic!("{e}"));
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while !b.len().is_multiple_of(4) {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + if b.is_empty() { 0 } else { 8 + b.len() };
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((j.len() as u32).to_le_bytes());
    out.extend(0x4E4F_534Au32.to_le_bytes());
    out.extend(j);
    if !b.is_empty() {
        out.extend((b.len() as u32).to_le_bytes());
        out.extend(0x004E_4942u32.to_le_bytes());
        out.extend(b);
    }
    out
}

#[test]
fn gltf_without_positions_is_a_typed_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("no_positions.glb");
    let bin: Vec<u8> = [0.0f32, 1.0, 0.0]
        .iter()
        .cycle()
        .take(9)
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let json = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "blob", "mesh": 0}],
        "meshes": [{"name": "blob", "primitives": [{"attributes": {"NORMAL": 0}}]}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "buffers": [{"byteLength": 36}],
    });
    let err = load_error(&path, &glb_from_json(&json, &bin));
    assert!(
        matches!(&err, RenderError::MissingPositions { mesh, .. } if mesh == "blob"),
        "{err:?}"
    );
}

/// A hand-written file: nested node transforms, no normals, no colours, u16 indices, one index
/// past the end in the second case, lines in the third.
#[test]
fn loader_applies_transforms_fills_defaults_and_rejects_bad_primitives() {
    let dir = tempfile::tempdir().unwrap();
    let mut bin: Vec<u8> = [[0.0f32, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let good_indices = [0u16, 1, 2];
    bin.extend(good_indices.iter().flat_map(|i| i.to_le_bytes()));
    let doc = |index_max: u16, mode: u32| {
        let mut b = bin.clone();
        b.truncate(36);
        b.extend([0u16, 1, index_max].iter().flat_map(|i| i.to_le_bytes()));
        let json = serde_json::json!({
            "asset": {"version": "2.0"},
            "scene": 0, "scenes": [{"nodes": [0]}],
            "nodes": [
                {"name": "parent", "translation": [0.0, 2.0, 0.0], "children": [1]},
                {"name": "child", "mesh": 0, "scale": [2.0, 1.0, 1.0]}
            ],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": mode}]}],
            "accessors": [
                {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [0.0, 0.0, 0.0], "max": [1.0, 0.0, 1.0]},
                {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}
            ],
            "bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
            "buffers": [{"byteLength": 42}],
        });
        glb_from_json(&json, &b)
    };
    let path = dir.path().join("nested.glb");
    std::fs::write(&path, doc(2, 4)).unwrap();
    let loaded = load_gltf(&path).unwrap();
    assert_eq!(loaded.len(), 1);
    let m = &loaded[0];
    assert_eq!(m.name, "child");
    assert_eq!(
        m.positions,
        vec![[0.0, 2.0, 0.0], [0.0, 2.0, 1.0], [2.0, 2.0, 0.0]]
    );
    assert_eq!(m.indices, vec![0, 1, 2]);
    assert!(m.normals.iter().all(|n| *n == [0.0, 1.0, 0.0]), "{:?}", m.normals);
    assert!(m.colors.iter().all(|c| *c == [1.0; 4]));

    let err = load_error(&path, &doc(3, 4));
    assert!(
        matches!(
            err,
            RenderError::IndexOutOfRange {
                index: 3,
                vertex_count: 3,
                ..
            }
        ),
        "{err:?}"
    );
    let err = load_error(&path, &doc(2, 1));
    assert!(
        matches!(&err, RenderError::NonTriangle { mode, .. } if mode == "Lines"),
        "{err:?}"
    );
}

#[test]
fn writer_rejects_inconsistent_meshes() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.glb");
    let good = MeshData {
        name: "t".into(),
        positions: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
        normals: vec![[0.0, 1.0, 0.0]; 3],
        colors: vec![[1.0; 4]; 3],
        indices: vec![0, 2, 1],
        interior_from: None,
    };
    let mut out_of_range = good.clone();
    out_of_range.indices[2] = 3;
    assert!(matches!(
        write_glb(&path, &[out_of_range]),
        Err(RenderError::IndexOutOfRange { index: 3, .. })
    ));
    let mut short_normals = good.clone();
    short_normals.normals.pop();
    assert!(matches!(
        write_glb(&path, &[short_normals]),
        Err(RenderError::AttributeCount { .. })
    ));
    let mut nan = good.clone();
    nan.positions[0][1] = f32::NAN;
    assert!(matches!(
        write_glb(&path, &[nan]),
        Err(RenderError::NonFinite { .. })
    ));
    assert!(!path.exists(), "a rejected mesh must leave no file");
    write_glb(&path, &[good]).unwrap();
    assert!(path.exists());
}
