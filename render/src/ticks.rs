//! Grid lines for meshes that need fine cells only where they bend: the shipped assets and the
//! procedural stand-ins are graded the same way, fine around the needle's entry point where the
//! renderer dimples them and coarse beyond, since every triangle costs a software rasterizer more
//! than the pixels it covers.

/// Sorted ticks covering [-half, half]: spacing `fine_step` for |t| ≤ `fine_half`, then equal
/// steps of at most `coarse_step` out to the ends. Symmetric by construction and contains 0; a
/// fine part reaching the ends leaves no tick twice.
pub(crate) fn graded(half: f64, fine_half: f64, fine_step: f64, coarse_step: f64) -> Vec<f64> {
    let mut fine_count = (fine_half.min(half) / fine_step).floor() as i64;
    if fine_count as f64 * fine_step >= half * (1.0 - 1e-9) {
        fine_count -= 1;
    }
    let fine_edge = fine_count as f64 * fine_step;
    let coarse_count = ((half - fine_edge) / coarse_step).ceil().max(1.0) as i64;
    let coarse = (half - fine_edge) / coarse_count as f64;
    let mut positive: Vec<f64> = (1..=fine_count).map(|k| k as f64 * fine_step).collect();
    positive.extend((1..coarse_count).map(|k| fine_edge + k as f64 * coarse));
    positive.push(half);
    let mut out: Vec<f64> = positive.iter().rev().map(|t| -t).collect();
    out.push(0.0);
    out.extend(positive);
    out
}

/// `count` evenly spaced ticks from `lo` to `hi` inclusive.
pub(crate) fn even(lo: f64, hi: f64, count: usize) -> Vec<f64> {
    let last = count.max(2) - 1;
    (0..=last)
        .map(|k| {
            if k == last {
                hi
            } else {
                lo + (hi - lo) * k as f64 / last as f64
            }
        })
        .collect()
}

/// Ticks on [-half, half] for a surface that a Gaussian dimple centred at 0 bends by
/// `depth·exp(-r²/radius²)`: every cell is as wide as keeps the triangles' straight-line
/// interpolation of the bent surface within `tol` of it, and at most `max_step` wide.
///
/// A triangle of a cell with sides a and b deviates from a surface whose curvature (the largest
/// eigenvalue of its Hessian) is at most κ by no more than κ·(a² + b²)/8. A column from x = c
/// outwards lies at r ≥ |c|, so with κ(c) the bound over r ≥ |c| and steps of √(4·tol/κ(c)) a
/// cell's error is at most min(κ(c), κ(c'))·(4·tol/κ(c) + 4·tol/κ(c'))/8 ≤ tol.
pub(crate) fn for_dimple(half: f64, depth: f64, radius: f64, tol: f64, max_step: f64) -> Vec<f64> {
    let mut positive = Vec::new();
    let mut at = 0.0;
    while at < half {
        let kappa = dimple_curvature_beyond(at, depth, radius);
        let step = if kappa > 0.0 {
            (4.0 * tol / kappa).sqrt().min(max_step)
        } else {
            max_step
        };
        at = if at + step >= half { half } else { at + step };
        positive.push(at);
    }
    let mut out: Vec<f64> = positive.iter().rev().map(|t| -t).collect();
    out.push(0.0);
    out.extend(positive);
    out
}

/// The largest Hessian eigenvalue of `depth·exp(-r²/radius²)` anywhere at r ≥ `r0`, with a margin
/// for sampling. With u = r²/radius² the eigenvalues are depth·e^(-u)·(4u − 2)/radius² (across the
/// rings) and -2·depth·e^(-u)/radius² (along them).
fn dimple_curvature_beyond(r0: f64, depth: f64, radius: f64) -> f64 {
    let u0 = (r0 / radius).powi(2);
    let peak = (0..=4000)
        .map(|k| u0 + f64::from(k) * 0.005)
        .map(|u| (4.0 * u - 2.0).abs().max(2.0) * (-u).exp())
        .fold(0.0, f64::max);
    1.01 * depth.abs() * peak / (radius * radius)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn increasing(t: &[f64]) -> bool {
        t.windows(2).all(|w| w[1] > w[0])
    }

    #[test]
    fn graded_ticks_are_fine_inside_coarse_outside_and_symmetric() {
        let t = graded(0.04, 0.015, 0.001, 0.005);
        assert!(increasing(&t));
        assert_eq!((t[0], *t.last().unwrap()), (-0.04, 0.04));
        assert!(t.contains(&0.0));
        for (a, b) in t.iter().zip(t.iter().rev()) {
            assert!((a + b).abs() < 1e-15);
        }
        for w in t.windows(2) {
            let step = w[1] - w[0];
            if w[1] <= 0.015 + 1e-12 && w[0] >= -0.015 - 1e-12 {
                assert!((step - 0.001).abs() < 1e-12, "{w:?}");
            } else {
                assert!(step <= 0.005 + 1e-12 && step > 0.001, "{w:?}");
            }
        }
    }

    #[test]
    fn a_fine_part_reaching_the_ends_repeats_no_tick() {
        for fine_half in [0.04, 0.05] {
            let t = graded(0.04, fine_half, 0.04 / 48.0, 0.005);
            assert!(increasing(&t), "{fine_half}");
            assert_eq!(t.len(), 97);
        }
        let e = even(-1.0, 1.0, 5);
        assert_eq!(e, vec![-1.0, -0.5, 0.0, 0.5, 1.0]);
    }

    /// Straight-line interpolation between the ticks, checked against the dimple itself on a
    /// fine sampling of each cell (in 1-D across the centre, where the curvature is largest).
    #[test]
    fn dimple_ticks_keep_interpolation_within_tolerance_and_coarsen_outwards() {
        let (half, depth, radius, tol) = (0.04, 0.015, 0.012, 5e-5);
        let t = for_dimple(half, depth, radius, tol, 0.01);
        assert!(increasing(&t));
        assert_eq!((t[0], *t.last().unwrap()), (-half, half));
        let g = |r: f64| depth * (-(r / radius).powi(2)).exp();
        let mut worst: f64 = 0.0;
        for w in t.windows(2) {
            for k in 1..100 {
                let s = f64::from(k) / 100.0;
                let x = w[0] + s * (w[1] - w[0]);
                worst = worst.max((g(w[0]) + s * (g(w[1]) - g(w[0])) - g(x)).abs());
            }
        }
        assert!(worst <= tol, "worst {worst}");
        // Well inside the tolerance would mean the cells could be coarser.
        assert!(worst > tol / 8.0, "worst {worst}");
        let centre_step = t[t.len() / 2 + 1] - t[t.len() / 2];
        let widest = t.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
        assert!(
            centre_step < 0.002 && widest > 4.0 * centre_step,
            "{centre_step} {widest}"
        );
        // A flat surface gets the widest cells; a deeper dimple more of them.
        assert_eq!(for_dimple(half, 0.0, radius, tol, 0.01).len(), 9);
        assert!(for_dimple(half, 2.0 * depth, radius, tol, 0.01).len() > t.len());
    }
}
