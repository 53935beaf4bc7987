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
    /// Where in `indices` the interior triangles start: faces that lie against another opaque
    /// mesh (a layer's top under the layer above, a vessel inside its organ) and so show only
    /// through see-through tissue. The renderer skips them while nothing in the frame is
    /// see-through. `None`: every triangle may be seen.
    pub interior_from: Option<usize>,
}

impl MeshData {
    /// The same mesh with the triangles `is_interior` picks (given their corners) moved, in
    /// order, behind the others and marked interior. Corners out of range count as outside.
    pub fn with_interior(mut self, is_interior: impl Fn([[f32; 3]; 3]) -> bool) -> Self {
        let corners = |t: &[u32]| -> Option<[[f32; 3]; 3]> {
            Some([
                *self.positions.get(t[0] as usize)?,
                *self.positions.get(t[1] as usize)?,
                *self.positions.get(t[2] as usize)?,
            ])
        };
        let (inside, outside): (Vec<&[u32]>, Vec<&[u32]>) = self
            .indices
            .chunks_exact(3)
            .partition(|t| corners(t).is_some_and(&is_interior));
        let start = 3 * outside.len();
        let indices: Vec<u32> = outside.into_iter().chain(inside).flatten().copied().collect();
        self.interior_from = (start < indices.len()).then_some(start);
        self.indices = indices;
        self
    }

    /// The triangles to draw while nothing is see-through.
    pub fn exterior_indices(&self) -> &[u32] {
        let end = self
            .interior_from
            .map_or(self.indices.len(), |k| k.min(self.indices.len()) / 3 * 3);
        &self.indices[..end]
    }

    /// The interior triangles (empty when there are none).
    pub fn interior_indices(&self) -> &[u32] {
        &self.indices[self.exterior_indices().len()..]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_triangles() -> MeshData {
        MeshData {
            name: "m".into(),
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 0.0, 1.0],
                [0.0, -1.0, 0.0],
            ],
            normals: vec![[0.0, 1.0, 0.0]; 4],
            colors: vec![[1.0; 4]; 4],
            indices: vec![0, 3, 1, 0, 2, 1],
            interior_from: None,
        }
    }

    #[test]
    fn interior_triangles_move_behind_in_order() {
        let m = two_triangles().with_interior(|c| c.iter().any(|p| p[1] < 0.0));
        assert_eq!(m.indices, [0, 2, 1, 0, 3, 1]);
        assert_eq!(m.interior_from, Some(3));
        assert_eq!(m.exterior_indices(), [0, 2, 1]);
        assert_eq!(m.interior_indices(), [0, 3, 1]);
    }

    #[test]
    fn no_interior_triangle_leaves_the_mesh_as_it_was() {
        let m = two_triangles().with_interior(|_| false);
        assert_eq!(m, two_triangles());
        assert_eq!(m.exterior_indices().len(), 6);
        assert!(m.interior_indices().is_empty());
    }

    #[test]
    fn an_interior_start_past_the_end_or_inside_a_triangle_is_clamped() {
        let mut m = two_triangles();
        m.interior_from = Some(99);
        assert_eq!(m.exterior_indices().len(), 6);
        m.interior_from = Some(4);
        assert_eq!(m.exterior_indices().len(), 3);
        assert_eq!(m.interior_indices().len(), 3);
    }
}
