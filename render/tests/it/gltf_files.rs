//! `.gltf` files as other tools write them: the layout of the Khronos sample models (a parent
//! node turning y-up into z-up by a `matrix`, a child with its own matrix, 16-bit indices,
//! POSITION and NORMAL only: no texture coordinates, tangents or colours), with the buffer in a
//! file beside it (its name percent-encoded in the URI) or embedded as a base64 `data:` URI.

use std::path::Path;

use base64::Engine as _;
use render::{RenderError, load_gltf};

/// A box of half-extents 0.5 × 1 × 1.5 (x, y, z), four vertices per face: the buffer (positions,
/// normals, then u16 indices) and the document for `uri`.
fn box_layout(uri: &str) -> (serde_json::Value, Vec<u8>) {
    let half = [0.5f32, 1.0, 1.5];
    let (mut positions, mut normals, mut indices) = (Vec::new(), Vec::new(), Vec::<u16>::new());
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let base = positions.len() as u16;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                let mut p = [0.0f32; 3];
                p[axis] = sign * half[axis];
                p[u] = a * half[u];
                p[v] = b * half[v];
                positions.push(p);
                let mut n = [0.0f32; 3];
                n[axis] = sign;
                normals.push(n);
            }
            indices.extend([0, 1, 2, 0, 2, 3].map(|k| base + k));
        }
    }
    let mut bin = Vec::new();
    for p in positions.iter().chain(&normals) {
        for c in p {
            bin.extend(c.to_le_bytes());
        }
    }
    let index_offset = bin.len();
    for i in &indices {
        bin.extend(i.to_le_bytes());
    }
    let json = serde_json::json!({
        "asset": { "generator": "COLLADA2GLTF", "version": "2.0" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [
            { "children": [1], "matrix": [1, 0, 0, 0, 0, 0, -1, 0, 0, 1, 0, 0, 0, 0, 0, 1] },
            { "mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1] }
        ],
        "meshes": [{
            "name": "Mesh",
            "primitives": [{ "attributes": { "NORMAL": 1, "POSITION": 0 }, "indices": 2, "mode": 4, "material": 0 }]
        }],
        "materials": [{ "pbrMetallicRoughness": { "baseColorFactor": [0.8, 0.0, 0.0, 1.0] } }],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 24, "type": "VEC3",
              "min": [-0.5, -1.0, -1.5], "max": [0.5, 1.0, 1.5] },
            { "bufferView": 0, "byteOffset": 288, "componentType": 5126, "count": 24, "type": "VEC3" },
            { "bufferView": 1, "componentType": 5123, "count": 36, "type": "SCALAR" }
        ],
        "bufferViews": [
            { "buffer": 0, "byteLength": 576, "target": 34962 },
            { "buffer": 0, "byteOffset": index_offset, "byteLength": 72, "target": 34963 }
        ],
        "buffers": [{ "byteLength": bin.len(), "uri": uri }]
    });
    (json, bin)
}

fn write(path: &Path, json: &serde_json::Value) {
    std::fs::write(path, serde_json::to_vec_pretty(json).unwrap()).unwrap();
}

fn bbox(positions: &[[f32; 3]]) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in positions {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

#[test]
fn a_gltf_loads_with_its_buffer_beside_it_or_embedded_and_its_node_matrices_applied() {
    let dir = tempfile::tempdir().unwrap();
    let (json, bin) = box_layout("box%20data.bin");
    std::fs::write(dir.path().join("box data.bin"), &bin).unwrap();
    let separate = dir.path().join("Box.gltf");
    write(&separate, &json);
    let data_uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bin)
    );
    let (json, _) = box_layout(&data_uri);
    let embedded = dir.path().join("BoxEmbedded.gltf");
    write(&embedded, &json);
    for path in [&separate, &embedded] {
        let meshes = load_gltf(path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(meshes.len(), 1, "{}", path.display());
        let m = &meshes[0];
        assert_eq!(
            (m.name.as_str(), m.positions.len(), m.indices.len()),
            ("Mesh", 24, 36)
        );
        // The parent's matrix takes (x, y, z) to (x, z, −y): the box's 3 along z becomes
        // 3 along y, its 2 along y becomes 2 along z.
        let (lo, hi) = bbox(&m.positions);
        for (k, half) in [0.5f32, 1.5, 1.0].iter().enumerate() {
            assert!(
                (hi[k] - half).abs() < 1e-6 && (lo[k] + half).abs() < 1e-6,
                "{lo:?} {hi:?}"
            );
        }
        // The normals turn with the box: the +z face (vertices 20–23) now faces +y.
        for k in 20..24 {
            assert!((m.positions[k][1] - 1.5).abs() < 1e-6, "{:?}", m.positions[k]);
            assert!((m.normals[k][1] - 1.0).abs() < 1e-6, "{:?}", m.normals[k]);
        }
        // No colours in the file: opaque white, for the scene's material to colour.
        assert!(m.colors.iter().all(|c| *c == [1.0; 4]));
    }
}

#[test]
fn a_gltf_buffer_that_cannot_be_read_is_a_typed_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("missing.bin", "reading"),
        (
            "https://example.com/box.bin",
            "only a file path relative to the .gltf",
        ),
        ("/etc/box.bin", "only a file path relative to the .gltf"),
        ("data:application/octet-stream;base64,@@@@", "does not decode"),
        ("data:application/octet-stream,raw", "not base64"),
    ];
    for (n, (uri, reason)) in cases.iter().enumerate() {
        let (json, _) = box_layout(uri);
        let path = dir.path().join(format!("bad_{n}.gltf"));
        write(&path, &json);
        let err = load_gltf(&path).expect_err(uri);
        assert!(
            matches!(err, RenderError::BufferUri { buffer: 0, .. }),
            "{uri}: {err:?}"
        );
        let text = err.to_string();
        assert!(
            text.contains(&format!("bad_{n}.gltf")) && text.contains(reason),
            "{uri}: {text}"
        );
    }
    // A buffer file shorter than the buffer it declares.
    let (json, bin) = box_layout("short.bin");
    std::fs::write(dir.path().join("short.bin"), &bin[..100]).unwrap();
    let path = dir.path().join("short.gltf");
    write(&path, &json);
    let err = load_gltf(&path).expect_err("short");
    assert!(
        matches!(
            err,
            RenderError::TruncatedBuffer {
                expected: 648,
                actual: 100,
                ..
            }
        ),
        "{err:?}"
    );
}
