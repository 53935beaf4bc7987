//! Procedural, deterministic generation of the scene meshes: liver with a vessel, layered tissue
//! block, needle, the tray of rubbing surfaces, and the lumbar block (`lumbar`).
//!
//! Conventions: metres, y up, triangles counter-clockwise seen from outside, unit normals, linear
//! RGBA vertex colours. Every shape that encloses a volume is closed (each edge shared by exactly
//! two triangles once coincident positions are merged); hard edges use duplicated vertices so that
//! flat faces keep flat normals. All randomness comes from a hash of fixed seeds and lattice
//! coordinates, so regeneration reproduces the committed `.glb` files byte for byte.

use std::f64::consts::TAU;
use std::fs;
use std::path::{Path, PathBuf};

use crate::error::RenderError;
use crate::gltf_io::write_glb;
use crate::mesh::MeshData;
use crate::ticks;

mod lumbar;
use lumbar::lumbar_meshes;
pub use lumbar::{
    DURAL_SAC_RADIUS_M, INTERSPINOUS_HALF_GAP_M, LUMBAR_LAYER_TOPS_M, LUMBAR_SIZE_M, MIDLINE_HALF_WIDTH_M,
};

/// The needle's entry point on the liver and on the tissue block: the origin, surface normal +y.
pub const ENTRY_POINT_M: [f32; 3] = [0.0, 0.0, 0.0];

/// Radius of the vessel inside the liver, m.
pub const VESSEL_RADIUS_M: f32 = 0.003;
/// Depth of the vessel's upper wall below the entry point, m: the simulated tissue meets the
/// vessel wall 20 mm deeper than the capsule, so that is where the needle tip must touch it.
pub const VESSEL_WALL_DEPTH_M: f32 = 0.020;
/// Depth of the vessel's axis below the entry point, m (wall depth plus radius).
pub const VESSEL_CENTRE_DEPTH_M: f32 = VESSEL_WALL_DEPTH_M + VESSEL_RADIUS_M;
/// Half the vessel's length along x, m; the ends stay well inside the organ.
pub const VESSEL_HALF_LENGTH_M: f32 = 0.055;

/// Footprint of the tissue block (x and z), centred on the origin, m.
pub const BLOCK_SIZE_M: f32 = 0.080;
/// Skin thickness, m.
pub const SKIN_THICKNESS_M: f32 = 0.002;
/// Fat thickness, m.
pub const FAT_THICKNESS_M: f32 = 0.010;
/// Depth of the block's bottom (the muscle fills the rest), m.
pub const BLOCK_DEPTH_M: f32 = 0.050;

/// Needle shaft radius, m.
pub const NEEDLE_RADIUS_M: f32 = 0.0006;
/// Needle shaft length from tip to hub, m.
pub const NEEDLE_LENGTH_M: f32 = 0.100;
/// Length of the conical tip, m.
pub const NEEDLE_TIP_LENGTH_M: f32 = 0.002;
/// Hub radius, m.
pub const HUB_RADIUS_M: f32 = 0.004;
/// Hub length, m.
pub const HUB_LENGTH_M: f32 = 0.015;

/// The rubbing surfaces in patch order: `patch_1` is `PATCH_NAMES[0]`.
pub const PATCH_NAMES: [&str; 7] = [
    "sandpaper_80",
    "sandpaper_120",
    "sandpaper_240",
    "sandpaper_400",
    "styrol_smooth",
    "styrol_semi_rough",
    "styrol_rough",
];
/// RMS roughness Rq of each surface, m.
pub const PATCH_RQ_M: [f64; 7] = [40e-6, 28e-6, 20e-6, 13e-6, 11e-6, 27e-6, 55e-6];
/// Dominant roughness wavelength of each surface, m.
pub const PATCH_WAVELENGTH_M: [f64; 7] = [0.80e-3, 0.60e-3, 0.45e-3, 0.35e-3, 0.45e-3, 1.20e-3, 2.00e-3];
/// Patch footprint, x by z, m.
pub const PATCH_SIZE_M: [f32; 2] = [0.030, 0.040];
/// Distance between neighbouring patch centres along x, m (5 mm gaps).
pub const PATCH_PITCH_M: f32 = 0.035;
/// Patch thickness below y = 0, m; the tray's top sits at this depth.
pub const PATCH_THICKNESS_M: f32 = 0.004;
/// Centre of each patch's top surface (mean height y = 0), m.
pub const PATCH_CENTRES_M: [[f32; 3]; 7] = [
    [-3.0 * PATCH_PITCH_M, 0.0, 0.0],
    [-2.0 * PATCH_PITCH_M, 0.0, 0.0],
    [-PATCH_PITCH_M, 0.0, 0.0],
    [0.0, 0.0, 0.0],
    [PATCH_PITCH_M, 0.0, 0.0],
    [2.0 * PATCH_PITCH_M, 0.0, 0.0],
    [3.0 * PATCH_PITCH_M, 0.0, 0.0],
];
/// True micrometre roughness is invisible at viewing distance, so the patches' geometric bumps
/// are this many times Rq (RMS height of the top surface = factor × Rq).
pub const BUMP_HEIGHT_EXAGGERATION: f64 = 10.0;
/// …and their lateral scale (and the colour grain's) is this many times the real wavelength, so
/// that the ~0.70 mm vertex spacing can still carry it.
pub const BUMP_WAVELENGTH_EXAGGERATION: f64 = 3.0;

/// Centre of patch `index` (0-based: 0 is `patch_1`), or `None` past the last patch.
pub fn patch_centre_m(index: usize) -> Option<[f32; 3]> {
    PATCH_CENTRES_M.get(index).copied()
}

/// All generated assets as (file name, meshes), in a fixed order.
pub fn default_assets() -> Vec<(&'static str, Vec<MeshData>)> {
    vec![
        ("liver.glb", liver_meshes()),
        ("tissue_block.glb", tissue_block_meshes()),
        ("needle.glb", needle_meshes()),
        ("lumbar.glb", lumbar_meshes()),
        ("surface_tray.glb", surface_tray_meshes()),
    ]
}

/// Generates every asset and writes it into `dir` (created if missing); returns the paths written.
pub fn write_default_assets(dir: &Path) -> Result<Vec<PathBuf>, RenderError> {
    fs::create_dir_all(dir).map_err(|source| RenderError::Io {
        path: dir.to_path_buf(),
        reason: source.to_string(),
        source,
    })?;
    let mut written = Vec::new();
    for (file_name, meshes) in default_assets() {
        let path = dir.join(file_name);
        write_glb(&path, &meshes)?;
        written.push(path);
    }
    Ok(written)
}

// ---------------------------------------------------------------------------------------------
// Colours and noise

/// Linear RGBA from an sRGB triple, so colours can be picked by eye from sRGB swatches.
fn srgb(r: f64, g: f64, b: f64) -> [f32; 4] {
    let lin = |c: f64| {
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    [lin(r) as f32, lin(g) as f32, lin(b) as f32, 1.0]
}

fn scale_rgb(c: [f32; 4], factor: f64) -> [f32; 4] {
    let s = |v: f32| (f64::from(v) * factor).clamp(0.0, 1.0) as f32;
    [s(c[0]), s(c[1]), s(c[2]), c[3]]
}

/// SplitMix64 finaliser: a well-mixed, platform-independent hash of lattice coordinates.
fn hash(seed: u64, ix: i64, iz: i64) -> u64 {
    let mut h = seed
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add((ix as u64).wrapping_mul(0xBF58_476D_1CE4_E5B9))
        .wrapping_add((iz as u64).wrapping_mul(0x94D0_49BB_1331_11EB));
    h ^= h >> 30;
    h = h.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    h ^= h >> 27;
    h = h.wrapping_mul(0x94D0_49BB_1331_11EB);
    h ^ (h >> 31)
}

/// Uniform in [-1, 1).
fn lattice(seed: u64, ix: i64, iz: i64) -> f64 {
    (hash(seed, ix, iz) >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// Smooth value noise with lattice spacing `cell`, roughly in [-1, 1].
fn value_noise(seed: u64, x: f64, z: f64, cell: f64) -> f64 {
    let (gx, gz) = (x / cell, z / cell);
    let (fx, fz) = (gx.floor(), gz.floor());
    let (ix, iz) = (fx as i64, fz as i64);
    let smooth = |t: f64| t * t * (3.0 - 2.0 * t);
    let (tx, tz) = (smooth(gx - fx), smooth(gz - fz));
    let a = lattice(seed, ix, iz);
    let b = lattice(seed, ix + 1, iz);
    let c = lattice(seed, ix, iz + 1);
    let d = lattice(seed, ix + 1, iz + 1);
    let top = a + (b - a) * tx;
    let bottom = c + (d - c) * tx;
    top + (bottom - top) * tz
}

/// Two octaves of value noise: the fundamental at `cell` plus half as much at half the size.
fn fractal_noise(seed: u64, x: f64, z: f64, cell: f64) -> f64 {
    value_noise(seed, x, z, cell) + 0.5 * value_noise(seed.wrapping_add(1), x, z, 0.5 * cell)
}

// ---------------------------------------------------------------------------------------------
// Mesh building

#[derive(Default)]
struct Builder {
    positions: Vec<[f64; 3]>,
    normals: Vec<[f64; 3]>,
    colors: Vec<[f32; 4]>,
    indices: Vec<u32>,
}

impl Builder {
    fn vertex(&mut self, p: [f64; 3], n: [f64; 3], c: [f32; 4]) -> u32 {
        self.positions.push(p);
        self.normals.push(normalize(n));
        self.colors.push(c);
        // Asset meshes stay far below u32::MAX vertices; saturating keeps this total.
        u32::try_from(self.positions.len() - 1).unwrap_or(u32::MAX)
    }

    /// Adds triangle (a, b, c), swapped if needed so its geometric normal agrees with `outward`.
    fn tri_facing(&mut self, a: u32, b: u32, c: u32, outward: [f64; 3]) {
        let p = |i: u32| self.positions[i as usize];
        let n = cross(sub(p(b), p(a)), sub(p(c), p(a)));
        if dot(n, outward) >= 0.0 {
            self.indices.extend_from_slice(&[a, b, c]);
        } else {
            self.indices.extend_from_slice(&[a, c, b]);
        }
    }

    fn finish(self, name: &str) -> MeshData {
        let cast = |v: &[f64; 3]| [v[0] as f32, v[1] as f32, v[2] as f32];
        MeshData {
            name: name.to_string(),
            positions: self.positions.iter().map(cast).collect(),
            normals: self.normals.iter().map(cast).collect(),
            colors: self.colors,
            indices: self.indices,
            interior_from: None,
        }
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn normalize(v: [f64; 3]) -> [f64; 3] {
    let len = dot(v, v).sqrt();
    if len > 0.0 {
        [v[0] / len, v[1] / len, v[2] / len]
    } else {
        [0.0, 1.0, 0.0]
    }
}

/// Up-facing triangles of a `nx` × `nz` vertex grid (vertex (i, j) at local index j·nx + i, x
/// growing with i and z with j). Diagonals radiate from the grid's centre so that the grid is
/// symmetric and no corner triangle has all three vertices on the border.
fn grid_triangles(nx: usize, nz: usize) -> Vec<[usize; 3]> {
    let mut out = Vec::with_capacity(2 * nx.saturating_sub(1) * nz.saturating_sub(1));
    for j in 0..nz.saturating_sub(1) {
        for i in 0..nx.saturating_sub(1) {
            let a = j * nx + i;
            let b = a + 1;
            let d = a + nx;
            let c = d + 1;
            let right = 2 * i + 1 >= nx - 1;
            let far = 2 * j + 1 >= nz - 1;
            if right == far {
                out.push([a, d, c]);
                out.push([a, c, b]);
            } else {
                out.push([a, d, b]);
                out.push([b, d, c]);
            }
        }
    }
    out
}

/// A closed slab: a height-field top over the grid `xs` × `zs` (heights and colours given per
/// grid vertex, row-major in z), vertical walls down to `bottom_y`, and a flat bottom fanned from
/// its centre. Top normals are smooth; walls and bottom are flat with hard edges.
fn heightfield_prism(
    name: &str,
    xs: &[f64],
    zs: &[f64],
    heights: &[f64],
    top_colors: &[[f32; 4]],
    bottom_y: f64,
    side_color: [f32; 4],
) -> MeshData {
    let (nx, nz) = (xs.len(), zs.len());
    let mut b = Builder::default();
    let top_pos: Vec<[f64; 3]> = (0..nx * nz)
        .map(|k| [xs[k % nx], heights[k], zs[k / nx]])
        .collect();
    let top_tris = grid_triangles(nx, nz);
    let top_normals = smooth_normals(&top_pos, &top_tris);
    for k in 0..nx * nz {
        b.vertex(top_pos[k], top_normals[k], top_colors[k]);
    }
    for t in &top_tris {
        b.indices.extend(t.iter().map(|&v| v as u32));
    }

    // Border vertex indices in counter-clockwise order seen from above, one list per side.
    let sides: [(Vec<usize>, [f64; 3]); 4] = [
        ((0..nx).collect(), [0.0, 0.0, -1.0]),
        ((0..nz).map(|j| j * nx + nx - 1).collect(), [1.0, 0.0, 0.0]),
        (
            (0..nx).rev().map(|i| (nz - 1) * nx + i).collect(),
            [0.0, 0.0, 1.0],
        ),
        ((0..nz).rev().map(|j| j * nx).collect(), [-1.0, 0.0, 0.0]),
    ];
    for (side, outward) in &sides {
        let mut prev: Option<(u32, u32)> = None;
        for &k in side {
            let p = top_pos[k];
            let t = b.vertex(p, *outward, side_color);
            let d = b.vertex([p[0], bottom_y, p[2]], *outward, side_color);
            if let Some((pt, pd)) = prev {
                b.tri_facing(pt, pd, t, *outward);
                b.tri_facing(t, pd, d, *outward);
            }
            prev = Some((t, d));
        }
    }
    let down = [0.0, -1.0, 0.0];
    let centre = [0.5 * (xs[0] + xs[nx - 1]), bottom_y, 0.5 * (zs[0] + zs[nz - 1])];
    let c = b.vertex(centre, down, side_color);
    let ring: Vec<usize> = sides
        .iter()
        .flat_map(|(side, _)| side[..side.len() - 1].iter().copied())
        .collect();
    let ring_ids: Vec<u32> = ring
        .iter()
        .map(|&k| b.vertex([top_pos[k][0], bottom_y, top_pos[k][2]], down, side_color))
        .collect();
    for w in 0..ring_ids.len() {
        b.tri_facing(c, ring_ids[w], ring_ids[(w + 1) % ring_ids.len()], down);
    }
    b.finish(name)
}

fn smooth_normals(positions: &[[f64; 3]], tris: &[[usize; 3]]) -> Vec<[f64; 3]> {
    let mut acc = vec![[0.0; 3]; positions.len()];
    for t in tris {
        let n = cross(
            sub(positions[t[1]], positions[t[0]]),
            sub(positions[t[2]], positions[t[0]]),
        );
        for &v in t {
            for k in 0..3 {
                acc[v][k] += n[k];
            }
        }
    }
    acc.into_iter().map(normalize).collect()
}

/// A closed solid of revolution about the y axis through the profile `(radius, y)` (y rising).
/// Each profile segment gets its own ring vertices (hard edges between segments); a zero radius
/// becomes an apex, a non-zero radius at either end is closed by a flat cap.
fn lathe(name: &str, profile: &[(f64, f64)], segments: usize, color: [f32; 4]) -> MeshData {
    let mut b = Builder::default();
    let angle = |s: usize| {
        let a = TAU * (s % segments) as f64 / segments as f64;
        (a.cos(), a.sin())
    };
    let point = |r: f64, y: f64, s: usize| {
        if r == 0.0 {
            // Exact zeros, so that an apex is one position whatever the angle.
            [0.0, y, 0.0]
        } else {
            let (c, sn) = angle(s);
            [r * c, y, r * sn]
        }
    };
    for w in profile.windows(2) {
        let ((r0, y0), (r1, y1)) = (w[0], w[1]);
        let (dr, dy) = (r1 - r0, y1 - y0);
        for s in 0..segments {
            let mid = |k: usize| {
                let (c, sn) = angle(k);
                [dy * c, -dr, dy * sn]
            };
            let a = b.vertex(point(r0, y0, s), mid(s), color);
            let bb = b.vertex(point(r0, y0, s + 1), mid(s + 1), color);
            let c = b.vertex(point(r1, y1, s + 1), mid(s + 1), color);
            let d = b.vertex(point(r1, y1, s), mid(s), color);
            let (cm, sm) = {
                let a = TAU * (s as f64 + 0.5) / segments as f64;
                (a.cos(), a.sin())
            };
            let outward = [dy * cm, -dr, dy * sm];
            // At an apex one of the quad's triangles collapses to a line; leave it out.
            if r0 != 0.0 {
                b.tri_facing(a, bb, c, outward);
            }
            if r1 != 0.0 {
                b.tri_facing(a, c, d, outward);
            }
        }
    }
    let ends = [
        (profile.first(), [0.0, -1.0, 0.0]),
        (profile.last(), [0.0, 1.0, 0.0]),
    ];
    for (end, normal) in ends {
        let Some(&(r, y)) = end else { continue };
        if r == 0.0 {
            continue;
        }
        let centre = b.vertex([0.0, y, 0.0], normal, color);
        let ring: Vec<u32> = (0..segments)
            .map(|s| b.vertex(point(r, y, s), normal, color))
            .collect();
        for s in 0..segments {
            b.tri_facing(centre, ring[s], ring[(s + 1) % segments], normal);
        }
    }
    b.finish(name)
}

// ---------------------------------------------------------------------------------------------
// Liver

const LIVER_HALF_X_M: f64 = 0.080;
const LIVER_HALF_Z_M: f64 = 0.050;
/// Height of the dome above the rim at the entry point; the rim sits this far below y = 0.
const LIVER_TOP_RISE_M: f64 = 0.030;
/// Depth of the visceral (lower) surface below the rim at the entry point.
const LIVER_BOTTOM_DROP_M: f64 = 0.030;

/// Smooth bump in p centred on the fissure between the left and right lobes; zero for
/// p ≥ −0.1, so nothing near the entry point (p = 0) moves.
fn lobe_fissure(p: f64) -> f64 {
    let t = (p + 0.3) / 0.2;
    let w = (1.0 - t * t).max(0.0);
    w * w
}

/// Maps the disk parameters (p, q), p² + q² ≤ 1, to the organ's footprint: stretched to
/// 160 × 100 mm, widened on the right lobe (+x), bent like a kidney bean and pinched at the
/// fissure. ∂z/∂q stays above 0.25·half-width, so the map never folds over.
fn liver_xz(p: f64, q: f64) -> (f64, f64) {
    let x = LIVER_HALF_X_M * p;
    let q5 = q * q * q * q * q;
    let z = LIVER_HALF_Z_M * (q * (1.0 + 0.15 * p) - 0.2 * p * p - 0.12 * q5 * lobe_fissure(p));
    (x, z)
}

/// Upper and lower surface heights at disk parameters (p, q); `s` is the lens profile
/// √(1 − p² − q²), zero on the rim. Every shape term is flat at p = q = 0 (cubic, quadratic or
/// the fissure, which vanishes there), so the dome's apex — the entry point — is exactly y = 0
/// with normal +y.
fn liver_heights(p: f64, q: f64, s: f64) -> (f64, f64) {
    let rim_y = -LIVER_TOP_RISE_M;
    let fissure = 1.0 - 0.12 * lobe_fissure(p);
    let top_shape = (1.0 + 0.3 * p * p * p - 0.2 * q * q) * fissure;
    let bottom_shape = (1.0 + 0.4 * p * p * p + 0.1 * q * q * p) * fissure;
    let top = rim_y + LIVER_TOP_RISE_M * s * top_shape;
    let bottom = rim_y - LIVER_BOTTOM_DROP_M * s.powf(0.7) * bottom_shape;
    (top, bottom)
}

fn liver_meshes() -> Vec<MeshData> {
    vec![liver_mesh(), vessel_mesh()]
}

fn liver_mesh() -> MeshData {
    // Square-to-disk grid, fine (≈0.9 mm) where it lands within ~23 mm of the entry point.
    let us = ticks::graded(1.0, 0.30, 0.9e-3 / LIVER_HALF_X_M, 0.05);
    let vs = ticks::graded(1.0, 0.47, 0.85e-3 / LIVER_HALF_Z_M, 0.05);
    let (nu, nv) = (us.len(), vs.len());
    let base = srgb(0.42, 0.12, 0.09);
    let mut positions: Vec<[f64; 3]> = Vec::with_capacity(2 * nu * nv);
    let mut colors: Vec<[f32; 4]> = Vec::with_capacity(2 * nu * nv);
    let mut bottom_index = vec![0usize; nu * nv];
    let mut bottoms: Vec<([f64; 3], [f32; 4])> = Vec::new();
    for (j, &v) in vs.iter().enumerate() {
        for (i, &u) in us.iter().enumerate() {
            // Elliptical grid mapping: the square's border lands exactly on the unit circle.
            let p = u * (1.0 - 0.5 * v * v).sqrt();
            let q = v * (1.0 - 0.5 * u * u).sqrt();
            let border = i == 0 || j == 0 || i == nu - 1 || j == nv - 1;
            let s = if border {
                0.0
            } else {
                (1.0 - p * p - q * q).max(0.0).sqrt()
            };
            let (x, z) = liver_xz(p, q);
            let (top, bottom) = liver_heights(p, q, s);
            let mottle = 1.0 + 0.12 * fractal_noise(11, x, z, 0.012);
            positions.push([x, top, z]);
            colors.push(scale_rgb(base, mottle));
            if !border {
                let under = 1.0 + 0.12 * fractal_noise(12, x, z, 0.012);
                bottoms.push(([x, bottom, z], scale_rgb(base, 0.85 * under)));
            }
        }
    }
    let top_count = positions.len();
    let mut next = top_count;
    for j in 0..nv {
        for i in 0..nu {
            let k = j * nu + i;
            let border = i == 0 || j == 0 || i == nu - 1 || j == nv - 1;
            // The rim is shared: upper and lower surfaces meet in the same vertices.
            bottom_index[k] = if border {
                k
            } else {
                next += 1;
                next - 1
            };
        }
    }
    for (p, c) in bottoms {
        positions.push(p);
        colors.push(c);
    }
    let mut tris: Vec<[usize; 3]> = Vec::new();
    for t in grid_triangles(nu, nv) {
        tris.push(t);
        tris.push([bottom_index[t[0]], bottom_index[t[2]], bottom_index[t[1]]]);
    }
    let normals = smooth_normals(&positions, &tris);
    let mut b = Builder::default();
    for k in 0..positions.len() {
        b.vertex(positions[k], normals[k], colors[k]);
    }
    for t in tris {
        b.indices.extend(t.iter().map(|&v| v as u32));
    }
    b.finish("liver")
}

fn vessel_mesh() -> MeshData {
    let radius = f64::from(VESSEL_RADIUS_M);
    let half = f64::from(VESSEL_HALF_LENGTH_M);
    let centre_y = -f64::from(VESSEL_CENTRE_DEPTH_M);
    // Inside the liver: seen only once the tissue turns see-through.
    tube_along_x("vessel", half, centre_y, radius, [24, 45], srgb(0.40, 0.12, 0.28)).with_interior(|_| true)
}

/// A closed tube along x from −`half` to `half`, its axis at height `centre_y` and z = 0, cut
/// into `[segments around, rings along]`, capped flat at both ends.
fn tube_along_x(
    name: &str,
    half: f64,
    centre_y: f64,
    radius: f64,
    cuts: [usize; 2],
    color: [f32; 4],
) -> MeshData {
    let [segments, ring_count] = cuts;
    let rings = ticks::even(-half, half, ring_count);
    let mut b = Builder::default();
    let around = |s: usize| {
        let a = TAU * (s % segments) as f64 / segments as f64;
        (a.cos(), a.sin())
    };
    let mut ids = Vec::with_capacity(rings.len() * segments);
    for &x in &rings {
        for s in 0..segments {
            let (c, sn) = around(s);
            ids.push(b.vertex([x, centre_y + radius * c, radius * sn], [0.0, c, sn], color));
        }
    }
    for r in 0..rings.len() - 1 {
        for s in 0..segments {
            let (a0, a1) = (ids[r * segments + s], ids[r * segments + (s + 1) % segments]);
            let (b0, b1) = (
                ids[(r + 1) * segments + s],
                ids[(r + 1) * segments + (s + 1) % segments],
            );
            let mid = TAU * (s as f64 + 0.5) / segments as f64;
            let outward = [0.0, mid.cos(), mid.sin()];
            b.tri_facing(a0, a1, b1, outward);
            b.tri_facing(a0, b1, b0, outward);
        }
    }
    for (x, normal) in [(-half, [-1.0, 0.0, 0.0]), (half, [1.0, 0.0, 0.0])] {
        let centre = b.vertex([x, centre_y, 0.0], normal, color);
        let ring: Vec<u32> = (0..segments)
            .map(|s| {
                let (c, sn) = around(s);
                b.vertex([x, centre_y + radius * c, radius * sn], normal, color)
            })
            .collect();
        for s in 0..segments {
            b.tri_facing(centre, ring[s], ring[(s + 1) % segments], normal);
        }
    }
    b.finish(name)
}

// ---------------------------------------------------------------------------------------------
// Tissue block

fn tissue_block_meshes() -> Vec<MeshData> {
    let half = 0.5 * f64::from(BLOCK_SIZE_M);
    let skin_bottom = -f64::from(SKIN_THICKNESS_M);
    let fat_bottom = skin_bottom - f64::from(FAT_THICKNESS_M);
    let block_bottom = -f64::from(BLOCK_DEPTH_M);
    // 1 mm spacing (diagonals 1.41 mm) out to 21 mm, where the renderer dimples the skin.
    let fine = ticks::graded(half, 0.021, 0.001, 0.005);
    let coarse = ticks::even(-half, half, 17);
    let layer = |name: &str, xs: &[f64], top: f64, bottom: f64, color: [f32; 4], seed: u64| {
        let (nx, nz) = (xs.len(), xs.len());
        let heights = vec![top; nx * nz];
        let colors: Vec<[f32; 4]> = (0..nx * nz)
            .map(|k| {
                scale_rgb(
                    color,
                    1.0 + 0.06 * fractal_noise(seed, xs[k % nx], xs[k / nx], 0.006),
                )
            })
            .collect();
        heightfield_prism(name, xs, xs, &heights, &colors, bottom, scale_rgb(color, 0.9))
    };
    // Where two layers meet the faces are interior: seen only through see-through tissue.
    let interfaces = [skin_bottom as f32, fat_bottom as f32];
    let on_interface = |c: [[f32; 3]; 3]| interfaces.iter().any(|&y| c.iter().all(|p| p[1] == y));
    [
        layer("skin", &fine, 0.0, skin_bottom, srgb(0.88, 0.66, 0.58), 21),
        layer(
            "fat",
            &coarse,
            skin_bottom,
            fat_bottom,
            srgb(0.95, 0.84, 0.52),
            22,
        ),
        layer(
            "muscle",
            &coarse,
            fat_bottom,
            block_bottom,
            srgb(0.62, 0.16, 0.15),
            23,
        ),
    ]
    .into_iter()
    .map(|m| m.with_interior(on_interface))
    .collect()
}

// ---------------------------------------------------------------------------------------------
// Needle

fn needle_meshes() -> Vec<MeshData> {
    let r = f64::from(NEEDLE_RADIUS_M);
    let tip = f64::from(NEEDLE_TIP_LENGTH_M);
    let length = f64::from(NEEDLE_LENGTH_M);
    let hub_r = f64::from(HUB_RADIUS_M);
    let hub_len = f64::from(HUB_LENGTH_M);
    let shaft = lathe(
        "shaft",
        &[(0.0, 0.0), (r, tip), (r, length)],
        24,
        srgb(0.75, 0.76, 0.78),
    );
    // Tapered nose gripping the shaft, a cylindrical barrel, a chamfered back rim.
    let hub_profile = [
        (2.0 * r, length),
        (0.6 * hub_r, length + 0.25 * hub_len),
        (hub_r, length + 0.35 * hub_len),
        (hub_r, length + 0.9 * hub_len),
        (0.85 * hub_r, length + hub_len),
    ];
    let hub = lathe("hub", &hub_profile, 32, srgb(0.20, 0.62, 0.36));
    vec![shaft, hub]
}

// ---------------------------------------------------------------------------------------------
// Surface tray

/// Vertices per patch along x and z: ≈0.70 mm spacing, which keeps the tray file under 1.5 MB.
const PATCH_GRID: [usize; 2] = [44, 58];

fn surface_tray_meshes() -> Vec<MeshData> {
    let patch_bottom = -f64::from(PATCH_THICKNESS_M);
    let tray_half_x = 0.5 * (6.0 * f64::from(PATCH_PITCH_M) + f64::from(PATCH_SIZE_M[0])) + 0.010;
    let tray_half_z = 0.5 * f64::from(PATCH_SIZE_M[1]) + 0.010;
    let tray_color = srgb(0.22, 0.24, 0.28);
    let tray = heightfield_prism(
        "tray",
        &[-tray_half_x, tray_half_x],
        &[-tray_half_z, tray_half_z],
        &[patch_bottom; 4],
        &[tray_color; 4],
        patch_bottom - 0.005,
        scale_rgb(tray_color, 0.8),
    );
    let mut out = vec![tray];
    for (index, name) in PATCH_NAMES.iter().enumerate() {
        out.push(patch_mesh(index, name, patch_bottom));
    }
    out
}

fn patch_base_color(name: &str) -> [f32; 4] {
    match name {
        "sandpaper_80" => srgb(0.52, 0.40, 0.27),
        "sandpaper_120" => srgb(0.58, 0.47, 0.34),
        "sandpaper_240" => srgb(0.46, 0.45, 0.43),
        "sandpaper_400" => srgb(0.32, 0.32, 0.33),
        "styrol_smooth" => srgb(0.95, 0.95, 0.93),
        "styrol_semi_rough" => srgb(0.92, 0.91, 0.88),
        _ => srgb(0.88, 0.87, 0.84),
    }
}

fn patch_mesh(index: usize, name: &str, bottom_y: f64) -> MeshData {
    let centre = PATCH_CENTRES_M[index];
    let (cx, cz) = (f64::from(centre[0]), f64::from(centre[2]));
    let (hx, hz) = (0.5 * f64::from(PATCH_SIZE_M[0]), 0.5 * f64::from(PATCH_SIZE_M[1]));
    let xs = ticks::even(cx - hx, cx + hx, PATCH_GRID[0]);
    let zs = ticks::even(cz - hz, cz + hz, PATCH_GRID[1]);
    let (nx, nz) = (xs.len(), zs.len());
    let rq = PATCH_RQ_M[index];
    let cell = BUMP_WAVELENGTH_EXAGGERATION * PATCH_WAVELENGTH_M[index];
    let seed = 100 + index as u64 * 10;

    let raw: Vec<f64> = (0..nx * nz)
        .map(|k| fractal_noise(seed, xs[k % nx], zs[k / nx], cell))
        .collect();
    let mean = raw.iter().sum::<f64>() / raw.len() as f64;
    let rms = (raw.iter().map(|h| (h - mean) * (h - mean)).sum::<f64>() / raw.len() as f64).sqrt();
    // Normalised so the exaggerated RMS height is exactly factor × Rq over the grid.
    let target = BUMP_HEIGHT_EXAGGERATION * rq;
    let gain = if rms > 0.0 { target / rms } else { 0.0 };
    let heights: Vec<f64> = raw.iter().map(|h| (h - mean) * gain).collect();

    // Colour grain: contrast grows with Rq (up to ±35 % for the roughest), grain size with the
    // wavelength; crests are lit a little brighter so the bumps read even in flat lighting.
    let base = patch_base_color(name);
    let contrast = 0.35 * rq / 55e-6;
    let sandpaper = name.starts_with("sandpaper");
    let colors: Vec<[f32; 4]> = (0..nx * nz)
        .map(|k| {
            let (x, z) = (xs[k % nx], zs[k / nx]);
            let grain = fractal_noise(seed + 5, x, z, 0.7 * cell);
            let crest = if target > 0.0 {
                heights[k] / (3.0 * target)
            } else {
                0.0
            };
            let mut factor = 1.0 + contrast * (grain + 0.5 * crest);
            // Abrasive grit: sparse light specks on sandpaper.
            if sandpaper
                && hash(seed + 7, (x * 1e5).round() as i64, (z * 1e5).round() as i64).is_multiple_of(11)
            {
                factor *= 1.0 + 1.5 * contrast;
            }
            scale_rgb(base, factor)
        })
        .collect();
    heightfield_prism(
        &format!("patch_{}", index + 1),
        &xs,
        &zs,
        &heights,
        &colors,
        bottom_y,
        scale_rgb(base, 0.8),
    )
}
