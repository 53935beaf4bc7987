//! The lumbar block of the epidural scene: layers where the simulated spine has its membranes.

use super::{fractal_noise, heightfield_prism, scale_rgb, srgb, tube_along_x};
use crate::mesh::MeshData;
use crate::ticks;

/// Footprint of the lumbar block (x along the spine, z across it), centred on the origin, m.
pub const LUMBAR_SIZE_M: f32 = 0.080;
/// Depths (m, below the skin at the entry point) where the lumbar block's layers start, top to
/// bottom: skin, subcutaneous fat, supraspinous ligament, interspinous ligament, ligamentum
/// flavum, epidural space, dura. The membranes among them (skin, supraspinous ligament,
/// ligamentum flavum, dura) sit where the simulated lumbar tissue has them
/// (`sim::NeedleTissue::lumbar_epidural`), so the needle's tip is drawn meeting each layer
/// where the trainee feels it.
pub const LUMBAR_LAYER_TOPS_M: [(&str, f32); 7] = [
    ("skin", 0.0),
    ("subcutaneous_fat", 0.003),
    ("supraspinous_ligament", 0.016),
    ("interspinous_ligament", 0.019),
    ("ligamentum_flavum", 0.037),
    ("epidural_space", 0.041),
    ("dura", 0.046),
];
/// Radius of the dural sac, a tube along the spine whose top is the dura, m.
pub const DURAL_SAC_RADIUS_M: f32 = 0.007;
/// Half the width (across the spine) of the midline ligaments and spinous processes, m.
pub const MIDLINE_HALF_WIDTH_M: f32 = 0.004;
/// Half the gap along the spine between two spinous processes, where the interspinous ligament
/// lies, m.
pub const INTERSPINOUS_HALF_GAP_M: f32 = 0.008;

/// A lumbar block for the epidural approach, entry point on the midline between two spinous
/// processes: skin and subcutaneous fat over the whole footprint; the supraspinous ligament over
/// the midline; beneath it two spinous processes with the interspinous ligament between them,
/// paraspinal muscle either side; the ligamentum flavum and the epidural space's fat across the
/// canal; the dural sac, a tube along the spine, whose top is the dura. The cut faces show each
/// layer where the block's sides are seen; where layers meet, faces are interior.
pub(super) fn lumbar_meshes() -> Vec<MeshData> {
    let half = 0.5 * f64::from(LUMBAR_SIZE_M);
    let top = |name: &str| {
        -f64::from(
            LUMBAR_LAYER_TOPS_M
                .iter()
                .find(|(n, _)| *n == name)
                .map_or(0.0, |(_, d)| *d),
        )
    };
    let (skin, fat, supra, inter, flavum, epidural, dura) = (
        top("skin"),
        top("subcutaneous_fat"),
        top("supraspinous_ligament"),
        top("interspinous_ligament"),
        top("ligamentum_flavum"),
        top("epidural_space"),
        top("dura"),
    );
    let mid = f64::from(MIDLINE_HALF_WIDTH_M);
    let gap = f64::from(INTERSPINOUS_HALF_GAP_M);
    let sac_r = f64::from(DURAL_SAC_RADIUS_M);
    let bottom = dura - 2.0 * sac_r - 0.004;
    // The skin is dimpled at the entry point: 1 mm cells out to 21 mm, as the tissue block's.
    let fine = ticks::graded(half, 0.021, 0.001, 0.005);
    let coarse = ticks::even(-half, half, 9);
    let slab = |name: &str, xs: &[f64], zs: &[f64], y: [f64; 2], color: [f32; 4], seed: u64| {
        let (nx, nz) = (xs.len(), zs.len());
        let colors: Vec<[f32; 4]> = (0..nx * nz)
            .map(|k| {
                scale_rgb(
                    color,
                    1.0 + 0.06 * fractal_noise(seed, xs[k % nx], zs[k / nx], 0.006),
                )
            })
            .collect();
        heightfield_prism(
            name,
            xs,
            zs,
            &vec![y[0]; nx * nz],
            &colors,
            y[1],
            scale_rgb(color, 0.9),
        )
    };
    let midline = [-mid, mid];
    let ligament = srgb(0.90, 0.88, 0.80);
    let bone = srgb(0.86, 0.82, 0.70);
    let muscle = srgb(0.62, 0.16, 0.15);
    let mut meshes = vec![
        slab("skin", &fine, &fine, [skin, fat], srgb(0.88, 0.66, 0.58), 31),
        slab(
            "subcutaneous_fat",
            &coarse,
            &coarse,
            [fat, supra],
            srgb(0.95, 0.84, 0.52),
            32,
        ),
        slab(
            "supraspinous_ligament",
            &coarse,
            &midline,
            [supra, inter],
            ligament,
            33,
        ),
        slab(
            "interspinous_ligament",
            &[-gap, gap],
            &midline,
            [inter, flavum],
            scale_rgb(ligament, 0.92),
            34,
        ),
        slab(
            "spinous_process_upper",
            &[-half, -gap],
            &midline,
            [inter, flavum],
            bone,
            35,
        ),
        slab(
            "spinous_process_lower",
            &[gap, half],
            &midline,
            [inter, flavum],
            bone,
            36,
        ),
        slab(
            "muscle_left",
            &coarse,
            &[-half, -mid],
            [supra, flavum],
            muscle,
            37,
        ),
        slab("muscle_right", &coarse, &[mid, half], [supra, flavum], muscle, 38),
        slab(
            "ligamentum_flavum",
            &coarse,
            &coarse,
            [flavum, epidural],
            srgb(0.93, 0.80, 0.30),
            39,
        ),
        slab(
            "epidural_space",
            &coarse,
            &coarse,
            [epidural, bottom],
            srgb(0.96, 0.90, 0.62),
            40,
        ),
    ];
    let interfaces = [fat, supra, inter, flavum, epidural].map(|y| y as f32);
    meshes = meshes
        .into_iter()
        .map(|m| m.with_interior(|c| interfaces.iter().any(|&y| c.iter().all(|p| p[1] == y))))
        .collect();
    meshes.push(dural_sac_mesh(half, dura - sac_r, sac_r));
    meshes
}

/// The dural sac: a tube along x, inside the epidural fat; seen only once the tissue turns
/// see-through.
fn dural_sac_mesh(half: f64, centre_y: f64, radius: f64) -> MeshData {
    tube_along_x(
        "dural_sac",
        half,
        centre_y,
        radius,
        [32, 17],
        srgb(0.80, 0.78, 0.85),
    )
    .with_interior(|_| true)
}
