//! Triangle meshes as the renderer takes them: what a glTF primitive holds once loaded.

/// One named triangle mesh in its own model frame (metres, y up).
///
/// Several of them make an asset: the tissue block's layers, the needle's shaft and hub, the
/// tray's patches. `positions`, `normals` and `colors` have one entry per vertex; `indices`
/// lists triangles counter-clockwise seen from outside.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshData {
    /// The glTF node's name (`skin`, `fat`, `muscle`, `liver`, `shaft`, `hub`, `patch_1`, …).
    pub name: String,
    /// Vertex positions, m.
    pub positions: Vec<[f32; 3]>,
    /// Unit vertex normals.
    pub normals: Vec<[f32; 3]>,
    /// Linear (not sRGB) RGBA vertex colours; the material's colour multiplies them.
    pub colors: Vec<[f32; 4]>,
    /// Triangle list.
    pub indices: Vec<u32>,
}
