//! Reads glTF 2.0 (`.glb`, or `.gltf` with its buffers in files beside it or embedded as
//! `data:` URIs) and writes `.glb`, as lists of [`MeshData`].
//!
//! Loading flattens the scene: every node that carries a mesh becomes one `MeshData` in world
//! coordinates, its primitives merged. Writing produces one node and one mesh per `MeshData`,
//! byte-for-byte deterministic, so generated assets can be checked into the repository and
//! compared against a fresh generation.

use std::collections::HashSet;
use std::fs;
use std::io::{self, Write};
use std::path::Path;

use capture::write_atomically;
use glam::{Mat3, Mat4, Vec3};
use gltf::buffer::Source;
use gltf::mesh::Mode;
use serde_json::{Value, json};

use crate::error::RenderError;
use crate::mesh::MeshData;

/// Loads every node that has a mesh from a `.glb` or a `.gltf` (its buffers in files beside it
/// or embedded as base64 `data:` URIs), in scene order, with the node's world transform
/// applied (TRS or matrix, through its parents).
///
/// Missing normals are computed (area-weighted, smooth); a missing COLOR_0 reads as opaque white;
/// a primitive without indices reads as a plain triangle list. Texture coordinates, tangents and
/// materials are not read: the scene's material colours the mesh.
pub fn load_gltf(path: &Path) -> Result<Vec<MeshData>, RenderError> {
    let bytes = fs::read(path).map_err(|e| io_error(path, e))?;
    let gltf = gltf::Gltf::from_slice(&bytes).map_err(|e| explain_invalid(path, &bytes, e))?;
    let document = &gltf.document;

    let mut owned: Vec<Vec<u8>> = Vec::new();
    let mut sources: Vec<Option<usize>> = Vec::new();
    for buffer in document.buffers() {
        let (data, source) = match buffer.source() {
            Source::Bin => (None, gltf.blob.as_deref().unwrap_or(&[])),
            Source::Uri(uri) => {
                let data = buffer_from_uri(path, buffer.index(), uri)?;
                owned.push(data);
                (Some(owned.len() - 1), owned[owned.len() - 1].as_slice())
            }
        };
        if source.len() < buffer.length() {
            return Err(RenderError::TruncatedBuffer {
                path: path.to_path_buf(),
                buffer: buffer.index(),
                expected: buffer.length(),
                actual: source.len(),
            });
        }
        sources.push(data);
    }
    let blob = gltf.blob.as_deref().unwrap_or(&[]);
    let buffers: Vec<&[u8]> = sources
        .iter()
        .map(|s| s.map_or(blob, |i| owned[i].as_slice()))
        .collect();

    let mut out = Vec::new();
    for (node, world) in nodes_in_scene_order(document) {
        let Some(mesh) = node.mesh() else { continue };
        let name = node
            .name()
            .or_else(|| mesh.name())
            .map_or_else(|| format!("node_{}", node.index()), str::to_string);
        let mut data = read_mesh(path, &name, &mesh, &buffers)?;
        apply_transform(&mut data, world);
        out.push(data);
    }
    Ok(out)
}

/// Writes `meshes` as a binary glTF 2.0 file: one node and one single-primitive mesh per entry,
/// with f32 POSITION (with the min/max the spec requires), NORMAL, COLOR_0 (vec4) and u32 indices.
///
/// The file is written through [`capture::write_atomically`], so readers never see a
/// half-written file and a failed write keeps the previous one. The same input always yields the
/// same bytes.
pub fn write_glb(path: &Path, meshes: &[MeshData]) -> Result<(), RenderError> {
    let bytes = encode_glb(path, meshes)?;
    write_atomically(path, |out| out.write_all(&bytes)).map_err(|e| io_error(path, e))
}

/// Area-weighted smooth vertex normals of a triangle list; vertices in no (or only degenerate)
/// triangles get +y so that every normal stays unit length.
pub fn compute_normals(positions: &[[f32; 3]], indices: &[u32]) -> Vec<[f32; 3]> {
    let mut acc = vec![[0.0f64; 3]; positions.len()];
    for tri in indices.chunks_exact(3) {
        let [a, b, c] = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
        let (Some(pa), Some(pb), Some(pc)) = (positions.get(a), positions.get(b), positions.get(c)) else {
            continue;
        };
        let e1 = sub64(*pb, *pa);
        let e2 = sub64(*pc, *pa);
        // The un-normalised cross product is twice the area times the unit normal: area weighting.
        let n = cross64(e1, e2);
        for v in [a, b, c] {
            for k in 0..3 {
                acc[v][k] += n[k];
            }
        }
    }
    acc.iter()
        .map(|n| {
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            if len > 0.0 && len.is_finite() {
                [(n[0] / len) as f32, (n[1] / len) as f32, (n[2] / len) as f32]
            } else {
                [0.0, 1.0, 0.0]
            }
        })
        .collect()
}

fn sub64(a: [f32; 3], b: [f32; 3]) -> [f64; 3] {
    [
        f64::from(a[0]) - f64::from(b[0]),
        f64::from(a[1]) - f64::from(b[1]),
        f64::from(a[2]) - f64::from(b[2]),
    ]
}

fn cross64(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn io_error(path: &Path, e: io::Error) -> RenderError {
    if e.kind() == io::ErrorKind::NotFound {
        RenderError::NotFound {
            path: path.to_path_buf(),
        }
    } else {
        RenderError::Io {
            path: path.to_path_buf(),
            reason: e.to_string(),
            source: e,
        }
    }
}

/// The validator reports a primitive without POSITION as a generic schema error; re-parse without
/// validation to name that common case precisely.
fn explain_invalid(path: &Path, bytes: &[u8], error: gltf::Error) -> RenderError {
    if let gltf::Error::Validation(_) = error
        && let Ok(unchecked) = gltf::Gltf::from_slice_without_validation(bytes)
    {
        // Raw JSON only: the unchecked document's accessors may dangle, and its helpers would panic.
        let positions = gltf::json::validation::Checked::Valid(gltf::json::mesh::Semantic::Positions);
        for (index, mesh) in unchecked.document.as_json().meshes.iter().enumerate() {
            if mesh
                .primitives
                .iter()
                .any(|p| !p.attributes.contains_key(&positions))
            {
                let name = mesh.name.clone().unwrap_or_else(|| format!("mesh_{index}"));
                return RenderError::MissingPositions {
                    path: path.to_path_buf(),
                    mesh: name,
                };
            }
        }
    }
    RenderError::NotGltf {
        path: path.to_path_buf(),
        reason: error.to_string(),
    }
}

/// Depth-first walk of the default scene (or of every scene, or — for scene-less files — of every
/// node nobody lists as a child), pairing each node with its world matrix.
fn nodes_in_scene_order(document: &gltf::Document) -> Vec<(gltf::Node<'_>, Mat4)> {
    let roots: Vec<gltf::Node<'_>> = if let Some(scene) = document.default_scene() {
        scene.nodes().collect()
    } else if document.scenes().len() > 0 {
        document.scenes().flat_map(|s| s.nodes()).collect()
    } else {
        let children: HashSet<usize> = document
            .nodes()
            .flat_map(|n| n.children().map(|c| c.index()))
            .collect();
        document
            .nodes()
            .filter(|n| !children.contains(&n.index()))
            .collect()
    };
    let mut out = Vec::new();
    // Validation rejects cyclic hierarchies, but a visited set keeps a malformed file from looping.
    let mut visited = HashSet::new();
    let mut stack: Vec<(gltf::Node<'_>, Mat4)> =
        roots.into_iter().rev().map(|n| (n, Mat4::IDENTITY)).collect();
    while let Some((node, parent)) = stack.pop() {
        if !visited.insert(node.index()) {
            continue;
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        let children: Vec<_> = node.children().collect();
        out.push((node, world));
        for child in children.into_iter().rev() {
            stack.push((child, world));
        }
    }
    out
}

fn read_mesh(
    path: &Path,
    name: &str,
    mesh: &gltf::Mesh<'_>,
    buffers: &[&[u8]],
) -> Result<MeshData, RenderError> {
    let mut data = MeshData {
        name: name.to_string(),
        positions: Vec::new(),
        normals: Vec::new(),
        colors: Vec::new(),
        indices: Vec::new(),
        interior_from: None,
    };
    let bad = |attribute| RenderError::BadAccessor {
        path: path.to_path_buf(),
        mesh: name.to_string(),
        attribute,
    };
    let count_mismatch = |attribute, expected, actual| RenderError::AttributeCount {
        path: path.to_path_buf(),
        mesh: name.to_string(),
        attribute,
        expected,
        actual,
    };
    let mut parts = Vec::new();
    for primitive in mesh.primitives() {
        if primitive.mode() != Mode::Triangles {
            return Err(RenderError::NonTriangle {
                path: path.to_path_buf(),
                mesh: name.to_string(),
                mode: format!("{:?}", primitive.mode()),
            });
        }
        if primitive.get(&gltf::Semantic::Positions).is_none() {
            return Err(RenderError::MissingPositions {
                path: path.to_path_buf(),
                mesh: name.to_string(),
            });
        }
        let reader = primitive.reader(|b| buffers.get(b.index()).copied());
        let positions: Vec<[f32; 3]> = reader.read_positions().ok_or_else(|| bad("POSITION"))?.collect();
        let n = positions.len();
        let normals: Option<Vec<[f32; 3]>> = match primitive.get(&gltf::Semantic::Normals) {
            Some(_) => Some(reader.read_normals().ok_or_else(|| bad("NORMAL"))?.collect()),
            None => None,
        };
        let colors: Vec<[f32; 4]> = match primitive.get(&gltf::Semantic::Colors(0)) {
            Some(_) => reader
                .read_colors(0)
                .ok_or_else(|| bad("COLOR_0"))?
                .into_rgba_f32()
                .collect(),
            None => vec![[1.0; 4]; n],
        };
        let indices: Vec<u32> = match primitive.indices() {
            Some(_) => reader
                .read_indices()
                .ok_or_else(|| bad("indices"))?
                .into_u32()
                .collect(),
            None => (0..u32::try_from(n).map_err(|_| RenderError::TooLarge {
                path: path.to_path_buf(),
            })?)
                .collect(),
        };
        if let Some(normals) = &normals
            && normals.len() != n
        {
            return Err(count_mismatch("NORMAL", n, normals.len()));
        }
        if colors.len() != n {
            return Err(count_mismatch("COLOR_0", n, colors.len()));
        }
        if !indices.len().is_multiple_of(3) {
            return Err(RenderError::PartialTriangle {
                path: path.to_path_buf(),
                mesh: name.to_string(),
                count: indices.len(),
            });
        }
        if let Some(&index) = indices.iter().find(|&&i| i as usize >= n) {
            return Err(RenderError::IndexOutOfRange {
                path: path.to_path_buf(),
                mesh: name.to_string(),
                index,
                vertex_count: n,
            });
        }
        // Primitives that name the same vertex accessors (normals included) share vertices.
        let shared = normals.is_some().then(|| {
            [
                gltf::Semantic::Positions,
                gltf::Semantic::Normals,
                gltf::Semantic::Colors(0),
            ]
            .map(|s| primitive.get(&s).map(|a| a.index()))
        });
        let interior = primitive
            .extras()
            .as_ref()
            .and_then(|raw| serde_json::from_str::<Value>(raw.get()).ok())
            .is_some_and(|extras| extras[INTERIOR_EXTRA] == Value::Bool(true));
        parts.push((shared, positions, normals, colors, indices, interior));
    }
    let mut offsets: Vec<([Option<usize>; 3], u32)> = Vec::new();
    let (mut outside, mut inside) = (Vec::new(), Vec::new());
    for (shared, positions, normals, colors, indices, interior) in parts {
        let known = shared.and_then(|key| offsets.iter().find(|(k, _)| *k == key).map(|(_, o)| *o));
        let offset = match known {
            Some(offset) => offset,
            None => {
                let offset = u32::try_from(data.positions.len()).map_err(|_| RenderError::TooLarge {
                    path: path.to_path_buf(),
                })?;
                // Per primitive, so that computed smoothing never blends across primitive borders.
                let normals = normals.unwrap_or_else(|| compute_normals(&positions, &indices));
                data.positions.extend_from_slice(&positions);
                data.normals.extend_from_slice(&normals);
                data.colors.extend_from_slice(&colors);
                if let Some(key) = shared {
                    offsets.push((key, offset));
                }
                offset
            }
        };
        let target = if interior { &mut inside } else { &mut outside };
        for i in indices {
            let shifted = i.checked_add(offset).ok_or_else(|| RenderError::TooLarge {
                path: path.to_path_buf(),
            })?;
            target.push(shifted);
        }
    }
    data.interior_from = (!inside.is_empty()).then_some(outside.len());
    data.indices = outside;
    data.indices.extend(inside);
    Ok(data)
}

fn apply_transform(data: &mut MeshData, world: Mat4) {
    // Skipping the identity keeps loads bit-exact (a multiply-add would turn -0.0 into +0.0).
    if world == Mat4::IDENTITY {
        return;
    }
    for p in &mut data.positions {
        *p = world.transform_point3(Vec3::from(*p)).to_array();
    }
    let linear = Mat3::from_mat4(world);
    let normal_matrix = linear.inverse().transpose();
    for n in &mut data.normals {
        let t = normal_matrix * Vec3::from(*n);
        *n = t.try_normalize().unwrap_or(Vec3::Y).to_array();
    }
    // A mirroring transform turns counter-clockwise triangles clockwise; swap two corners back.
    if linear.determinant() < 0.0 {
        for tri in data.indices.chunks_exact_mut(3) {
            tri.swap(1, 2);
        }
    }
}

const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const COMPONENT_FLOAT: u32 = 5126;
const COMPONENT_UNSIGNED_INT: u32 = 5125;
const MODE_TRIANGLES: u32 = 4;
/// The key in a primitive's `extras` that marks its triangles interior.
const INTERIOR_EXTRA: &str = "interior";

/// The bytes of buffer `index` of the `.gltf` at `path`, from its URI: a base64 `data:` URI, or
/// a file path relative to the `.gltf`'s folder (percent-encoded, as URIs are). URIs with a
/// scheme (`http:`, `file:`) and absolute paths are refused: an asset reads only what travels
/// with it.
// By hand rather than through the gltf crate's `import` feature, which also brings image
// decoders for textures that are never read here.
fn buffer_from_uri(path: &Path, index: usize, uri: &str) -> Result<Vec<u8>, RenderError> {
    use base64::Engine as _;
    let refuse = |reason: String| RenderError::BufferUri {
        path: path.to_path_buf(),
        buffer: index,
        uri: uri
            .split_once(',')
            .map_or(uri, |(head, _)| head)
            .chars()
            .take(200)
            .collect(),
        reason,
    };
    if let Some(rest) = uri.strip_prefix("data:") {
        let (header, data) = rest
            .split_once(',')
            .ok_or_else(|| refuse("a data URI without a comma before its data".into()))?;
        if !header.ends_with(";base64") {
            return Err(refuse("a data URI that is not base64".into()));
        }
        return base64::engine::general_purpose::STANDARD
            .decode(data.trim())
            .map_err(|e| refuse(format!("its base64 data does not decode: {e}")));
    }
    let has_scheme = uri.split_once(':').is_some_and(|(scheme, _)| {
        scheme.len() > 1
            && scheme
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
    });
    let decoded = percent_encoding::percent_decode_str(uri)
        .decode_utf8()
        .map_err(|_| refuse("not UTF-8 once percent-decoded".into()))?;
    let relative = Path::new(decoded.as_ref());
    if has_scheme || relative.is_absolute() || decoded.is_empty() {
        return Err(refuse(
            "only a file path relative to the .gltf, or a base64 data: URI, is read".into(),
        ));
    }
    let file = path.parent().unwrap_or(Path::new(".")).join(relative);
    fs::read(&file).map_err(|e| refuse(format!("reading {}: {e}", file.display())))
}

/// Builds the whole `.glb` in memory.
///
/// The JSON is built with `serde_json` rather than `gltf-json`: the writer needs a dozen fields,
/// `json!` states them in the shape the spec documents, and serde_json's sorted maps make the
/// output byte-stable without depending on another crate's struct layout and skip rules.
fn encode_glb(path: &Path, meshes: &[MeshData]) -> Result<Vec<u8>, RenderError> {
    let too_large = || RenderError::TooLarge {
        path: path.to_path_buf(),
    };
    let mut bin: Vec<u8> = Vec::new();
    let mut views: Vec<Value> = Vec::new();
    let mut accessors: Vec<Value> = Vec::new();
    let mut json_meshes: Vec<Value> = Vec::new();
    let mut nodes: Vec<Value> = Vec::new();

    for mesh in meshes {
        validate_for_write(path, mesh)?;
        let n = mesh.positions.len();
        let mut push_view = |bytes: Vec<u8>, target: u32| -> usize {
            let offset = bin.len();
            bin.extend_from_slice(&bytes);
            // Every element type here is 4 bytes wide, so views stay aligned without padding.
            views.push(json!({
                "buffer": 0,
                "byteOffset": offset,
                "byteLength": bytes.len(),
                "target": target,
            }));
            views.len() - 1
        };
        let pos_view = push_view(floats_le(mesh.positions.iter().flatten()), ARRAY_BUFFER);
        let nrm_view = push_view(floats_le(mesh.normals.iter().flatten()), ARRAY_BUFFER);
        let col_view = push_view(floats_le(mesh.colors.iter().flatten()), ARRAY_BUFFER);
        let idx_view = push_view(
            mesh.indices.iter().flat_map(|i| i.to_le_bytes()).collect(),
            ELEMENT_ARRAY_BUFFER,
        );

        let (min, max) = bounds(&mesh.positions);
        let base = accessors.len();
        accessors.push(json!({
            "bufferView": pos_view, "componentType": COMPONENT_FLOAT, "count": n, "type": "VEC3",
            "min": min, "max": max,
        }));
        accessors.push(json!({
            "bufferView": nrm_view, "componentType": COMPONENT_FLOAT, "count": n, "type": "VEC3",
        }));
        accessors.push(json!({
            "bufferView": col_view, "componentType": COMPONENT_FLOAT, "count": n, "type": "VEC4",
        }));
        // Interior triangles (see `MeshData::interior_from`) go in a second primitive over the
        // same vertices, marked in its extras; other viewers simply draw it.
        let outside = mesh.exterior_indices().len();
        let mut primitives = Vec::new();
        for (start, count, interior) in [(0, outside, false), (outside, mesh.indices.len() - outside, true)] {
            if count == 0 {
                continue;
            }
            let mut accessor = json!({
                "bufferView": idx_view, "componentType": COMPONENT_UNSIGNED_INT,
                "count": count, "type": "SCALAR",
            });
            let mut primitive = json!({
                "attributes": { "POSITION": base, "NORMAL": base + 1, "COLOR_0": base + 2 },
                "indices": accessors.len(),
                "mode": MODE_TRIANGLES,
            });
            if interior {
                accessor["byteOffset"] = json!(4 * start);
                primitive["extras"] = json!({ INTERIOR_EXTRA: true });
            }
            accessors.push(accessor);
            primitives.push(primitive);
        }
        json_meshes.push(json!({ "name": mesh.name, "primitives": primitives }));
        nodes.push(json!({ "name": mesh.name, "mesh": json_meshes.len() - 1 }));
    }

    let mut root = json!({
        "asset": { "version": "2.0", "generator": "palpus render" },
        "scene": 0,
        "scenes": [{ "nodes": (0..nodes.len()).collect::<Vec<_>>() }],
        "nodes": nodes,
        "meshes": json_meshes,
        "accessors": accessors,
        "bufferViews": views,
    });
    if !bin.is_empty()
        && let Some(obj) = root.as_object_mut()
    {
        obj.insert("buffers".into(), json!([{ "byteLength": bin.len() }]));
    }
    let mut json_bytes = serde_json::to_vec(&root).map_err(|e| RenderError::Io {
        path: path.to_path_buf(),
        reason: e.to_string(),
        source: io::Error::other(e),
    })?;
    // Chunks must be 4-byte aligned: JSON pads with spaces, BIN with zeros (glTF 2.0 §4.4.3).
    while !json_bytes.len().is_multiple_of(4) {
        json_bytes.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let bin_chunk_len = if bin.is_empty() { 0 } else { 8 + bin.len() };
    let total = 12 + 8 + json_bytes.len() + bin_chunk_len;
    let total_u32 = u32::try_from(total).map_err(|_| too_large())?;
    let json_len = u32::try_from(json_bytes.len()).map_err(|_| too_large())?;
    let bin_len = u32::try_from(bin.len()).map_err(|_| too_large())?;

    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(GLB_MAGIC);
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total_u32.to_le_bytes());
    out.extend_from_slice(&json_len.to_le_bytes());
    out.extend_from_slice(&CHUNK_JSON.to_le_bytes());
    out.extend_from_slice(&json_bytes);
    if !bin.is_empty() {
        out.extend_from_slice(&bin_len.to_le_bytes());
        out.extend_from_slice(&CHUNK_BIN.to_le_bytes());
        out.extend_from_slice(&bin);
    }
    Ok(out)
}

fn validate_for_write(path: &Path, mesh: &MeshData) -> Result<(), RenderError> {
    let n = mesh.positions.len();
    if n == 0 || mesh.indices.is_empty() {
        return Err(RenderError::EmptyMesh {
            path: path.to_path_buf(),
            mesh: mesh.name.clone(),
        });
    }
    let mismatch = |attribute, actual| RenderError::AttributeCount {
        path: path.to_path_buf(),
        mesh: mesh.name.clone(),
        attribute,
        expected: n,
        actual,
    };
    if mesh.normals.len() != n {
        return Err(mismatch("NORMAL", mesh.normals.len()));
    }
    if mesh.colors.len() != n {
        return Err(mismatch("COLOR_0", mesh.colors.len()));
    }
    if !mesh.indices.len().is_multiple_of(3) {
        return Err(RenderError::PartialTriangle {
            path: path.to_path_buf(),
            mesh: mesh.name.clone(),
            count: mesh.indices.len(),
        });
    }
    if let Some(&index) = mesh.indices.iter().find(|&&i| i as usize >= n) {
        return Err(RenderError::IndexOutOfRange {
            path: path.to_path_buf(),
            mesh: mesh.name.clone(),
            index,
            vertex_count: n,
        });
    }
    let non_finite = |attribute| RenderError::NonFinite {
        path: path.to_path_buf(),
        mesh: mesh.name.clone(),
        attribute,
    };
    if mesh.positions.iter().flatten().any(|v| !v.is_finite()) {
        return Err(non_finite("POSITION"));
    }
    if mesh.normals.iter().flatten().any(|v| !v.is_finite()) {
        return Err(non_finite("NORMAL"));
    }
    if mesh.colors.iter().flatten().any(|v| !v.is_finite()) {
        return Err(non_finite("COLOR_0"));
    }
    Ok(())
}

fn floats_le<'a>(values: impl Iterator<Item = &'a f32>) -> Vec<u8> {
    values.flat_map(|v| v.to_le_bytes()).collect()
}

fn bounds(positions: &[[f32; 3]]) -> ([f32; 3], [f32; 3]) {
    let mut min = [f32::INFINITY; 3];
    let mut max = [f32::NEG_INFINITY; 3];
    for p in positions {
        for k in 0..3 {
            min[k] = min[k].min(p[k]);
            max[k] = max[k].max(p[k]);
        }
    }
    (min, max)
}
