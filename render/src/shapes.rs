//! Procedural meshes for tests, demos and benchmarks: stand-ins that follow the asset
//! conventions (metres, y up, tissue top at y = 0, needle tip at the origin with the shaft along
//! +y, tray patches on y = 0 along x).

use crate::mesh::MeshData;

struct Builder {
    mesh: MeshData,
}

impl Builder {
    fn new(name: &str) -> Self {
        Builder {
            mesh: MeshData {
                name: name.into(),
                positions: Vec::new(),
                normals: Vec::new(),
                colors: Vec::new(),
                indices: Vec::new(),
            },
        }
    }

    fn vertex(&mut self, p: [f32; 3], n: [f32; 3], c: [f32; 4]) -> u32 {
        let i = self.mesh.positions.len() as u32;
        self.mesh.positions.push(p);
        self.mesh.normals.push(n);
        self.mesh.colors.push(c);
        i
    }

    /// A grid of (nu+1)×(nv+1) vertices at `origin + u·s + v·t`, s,t in 0..1; triangles wound
    /// counter-clockwise seen from the side `u × v` points to.
    fn grid(&mut self, origin: [f32; 3], u: [f32; 3], v: [f32; 3], nu: u32, nv: u32, color: [f32; 4]) {
        let n = normalize(cross(u, v));
        let base = self.mesh.positions.len() as u32;
        for j in 0..=nv {
            for i in 0..=nu {
                let (s, t) = (i as f32 / nu as f32, j as f32 / nv as f32);
                let p = [0, 1, 2].map(|k| origin[k] + u[k] * s + v[k] * t);
                self.vertex(p, n, color);
            }
        }
        let row = nu + 1;
        for j in 0..nv {
            for i in 0..nu {
                let a = base + j * row + i;
                let (b, c, d) = (a + 1, a + row, a + row + 1);
                self.mesh.indices.extend_from_slice(&[a, b, d, a, d, c]);
            }
        }
    }
}

fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn normalize(a: [f32; 3]) -> [f32; 3] {
    let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt().max(1e-12);
    [a[0] / l, a[1] / l, a[2] / l]
}

/// An axis-aligned box from `min` to `max` (m) whose top face is a `top_cells`² grid, fine enough
/// for a dimple to bend smoothly; the sides are split to match at the top edge.
pub fn tissue_box(name: &str, min: [f32; 3], max: [f32; 3], top_cells: u32, color: [f32; 4]) -> MeshData {
    let n = top_cells.max(1);
    let [x0, y0, z0] = min;
    let [x1, y1, z1] = max;
    let (dx, dy, dz) = (x1 - x0, y1 - y0, z1 - z0);
    let mut b = Builder::new(name);
    // Top (+y): u along +z, v along +x gives normal +y.
    b.grid([x0, y1, z0], [0.0, 0.0, dz], [dx, 0.0, 0.0], n, n, color);
    // Bottom (-y).
    b.grid([x0, y0, z0], [dx, 0.0, 0.0], [0.0, 0.0, dz], 1, 1, color);
    // Front (+z) and back (-z).
    b.grid([x0, y0, z1], [dx, 0.0, 0.0], [0.0, dy, 0.0], n, 4, color);
    b.grid([x1, y0, z0], [-dx, 0.0, 0.0], [0.0, dy, 0.0], n, 4, color);
    // Right (+x) and left (-x).
    b.grid([x1, y0, z1], [0.0, 0.0, -dz], [0.0, dy, 0.0], n, 4, color);
    b.grid([x0, y0, z0], [0.0, 0.0, dz], [0.0, dy, 0.0], n, 4, color);
    b.mesh
}

/// A closed cylinder of `radius_m` along +y from `y0_m` to `y1_m`; with `tip_m > 0` the lower end
/// is a bevelled point `tip_m` long ending at (0, `y0_m`, 0) instead of a flat cap.
pub fn cylinder(
    name: &str,
    radius_m: f32,
    y0_m: f32,
    y1_m: f32,
    tip_m: f32,
    segments: u32,
    color: [f32; 4],
) -> MeshData {
    let seg = segments.max(3);
    let mut b = Builder::new(name);
    let side_y0 = y0_m + tip_m.max(0.0);
    let ring = |b: &mut Builder, y: f32, radial_ny: f32| -> u32 {
        let first = b.mesh.positions.len() as u32;
        for i in 0..=seg {
            let a = i as f32 / seg as f32 * std::f32::consts::TAU;
            let (s, c) = a.sin_cos();
            let n = normalize([c, radial_ny, s]);
            b.vertex([radius_m * c, y, radius_m * s], n, color);
        }
        first
    };
    let lo = ring(&mut b, side_y0, 0.0);
    let hi = ring(&mut b, y1_m, 0.0);
    for i in 0..seg {
        let (a, c) = (lo + i, hi + i);
        b.mesh.indices.extend_from_slice(&[a, c, a + 1, a + 1, c, c + 1]);
    }
    // Top cap.
    let centre = b.vertex([0.0, y1_m, 0.0], [0.0, 1.0, 0.0], color);
    let first = b.mesh.positions.len() as u32;
    for i in 0..=seg {
        let a = i as f32 / seg as f32 * std::f32::consts::TAU;
        b.vertex(
            [radius_m * a.cos(), y1_m, radius_m * a.sin()],
            [0.0, 1.0, 0.0],
            color,
        );
    }
    for i in 0..seg {
        b.mesh
            .indices
            .extend_from_slice(&[centre, first + i + 1, first + i]);
    }
    // Bottom: a cone to the tip, or a flat cap.
    let tip = tip_m > 0.0;
    let slope = if tip { radius_m / tip_m } else { 0.0 };
    let bottom = b.vertex([0.0, y0_m, 0.0], [0.0, -1.0, 0.0], color);
    let first = b.mesh.positions.len() as u32;
    for i in 0..=seg {
        let a = i as f32 / seg as f32 * std::f32::consts::TAU;
        let (s, c) = a.sin_cos();
        let n = if tip {
            normalize([c, -slope, s])
        } else {
            [0.0, -1.0, 0.0]
        };
        b.vertex([radius_m * c, side_y0, radius_m * s], n, color);
    }
    for i in 0..seg {
        b.mesh
            .indices
            .extend_from_slice(&[bottom, first + i, first + i + 1]);
    }
    b.mesh
}

/// The tissue block's three layers, each 40 mm wide: `skin` (2 mm), `fat` (8 mm), `muscle`
/// (20 mm) with the skin's top at y = 0.
pub fn tissue_block() -> Vec<MeshData> {
    let h = 0.04;
    // Name, bottom and top y, cells along the top's edge, colour.
    [
        ("skin", -0.002, 0.0, 96, [0.93, 0.70, 0.60, 1.0]),
        ("fat", -0.010, -0.002, 64, [0.95, 0.85, 0.45, 1.0]),
        ("muscle", -0.030, -0.010, 32, [0.55, 0.12, 0.10, 1.0]),
    ]
    .into_iter()
    .map(|(name, bottom, top, cells, color)| tissue_box(name, [-h, bottom, -h], [h, top, h], cells, color))
    .collect()
}

/// A needle 80 mm long, 1.2 mm across, tip at the origin, with a 15 mm hub: `shaft`, `hub`.
pub fn needle() -> Vec<MeshData> {
    vec![
        cylinder("shaft", 0.0006, 0.0, 0.080, 0.004, 24, [1.0; 4]),
        cylinder("hub", 0.003, 0.080, 0.095, 0.0, 24, [0.2, 0.45, 0.9, 1.0]),
    ]
}

/// A tray (`tray`) and seven 30 mm square patches (`patch_1`..`patch_7`) on y = 0 spaced 40 mm
/// along x; patch k carries bumps whose height and spacing grow with k.
pub fn surface_tray() -> Vec<MeshData> {
    let mut meshes = vec![tissue_box(
        "tray",
        [-0.16, -0.006, -0.03],
        [0.16, -0.001, 0.03],
        8,
        [0.3, 0.3, 0.32, 1.0],
    )];
    for k in 1..=7u32 {
        let cx = (k as f32 - 4.0) * 0.04;
        let mut b = Builder::new(&format!("patch_{k}"));
        let cells = 60;
        let half = 0.015;
        let amp_m = 0.00002 * (k * k) as f32;
        let period_m = 0.001 + 0.0005 * k as f32;
        let hue = k as f32 / 7.0;
        let base_color = [0.55 + 0.4 * hue, 0.6 - 0.2 * hue, 0.45 + 0.1 * (1.0 - hue), 1.0];
        let row = cells + 1;
        let w = std::f32::consts::TAU / period_m;
        for j in 0..=cells {
            for i in 0..=cells {
                let x = -half + 2.0 * half * i as f32 / cells as f32;
                let z = -half + 2.0 * half * j as f32 / cells as f32;
                let y = amp_m * (w * x).sin() * (w * z).sin();
                let dydx = amp_m * w * (w * x).cos() * (w * z).sin();
                let dydz = amp_m * w * (w * x).sin() * (w * z).cos();
                let shade = 0.85 + 0.15 * ((w * x).sin() * (w * z).sin());
                let c = [
                    base_color[0] * shade,
                    base_color[1] * shade,
                    base_color[2] * shade,
                    1.0,
                ];
                b.vertex([cx + x, y, z], normalize([-dydx, 1.0, -dydz]), c);
            }
        }
        for j in 0..cells {
            for i in 0..cells {
                let a = j * row + i;
                b.mesh
                    .indices
                    .extend_from_slice(&[a, a + row + 1, a + 1, a, a + row, a + row + 1]);
            }
        }
        meshes.push(b.mesh);
    }
    meshes
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check_mesh(m: &MeshData) {
        assert_eq!(m.positions.len(), m.normals.len());
        assert_eq!(m.positions.len(), m.colors.len());
        assert_eq!(m.indices.len() % 3, 0);
        assert!(
            m.indices.iter().all(|&i| (i as usize) < m.positions.len()),
            "{}",
            m.name
        );
    }

    /// Counter-clockwise winding seen from outside: each face normal agrees with its vertex normals.
    fn check_winding(m: &MeshData) {
        for t in m.indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| glam::Vec3::from(m.positions[i as usize]));
            let face = (b - a).cross(c - a);
            if face.length() < 1e-12 {
                continue;
            }
            let n = glam::Vec3::from(m.normals[t[0] as usize]);
            assert!(face.dot(n) > 0.0, "{} triangle {t:?} wound inward", m.name);
        }
    }

    #[test]
    fn meshes_are_consistent_and_wound_outward() {
        for m in tissue_block().iter().chain(&needle()).chain(&surface_tray()) {
            check_mesh(m);
            check_winding(m);
        }
    }

    #[test]
    fn conventions_hold() {
        let skin = &tissue_block()[0];
        let top = skin.positions.iter().map(|p| p[1]).fold(f32::MIN, f32::max);
        assert!(top.abs() < 1e-7);
        let shaft = &needle()[0];
        let lowest = shaft.positions.iter().map(|p| p[1]).fold(f32::MAX, f32::min);
        assert!(lowest.abs() < 1e-7);
        assert!(shaft.positions.iter().any(|p| p == &[0.0, 0.0, 0.0]));
        let names: Vec<String> = surface_tray().into_iter().map(|m| m.name).collect();
        assert_eq!(names.len(), 8);
        assert_eq!(names[7], "patch_7");
    }
}
