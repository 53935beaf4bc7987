//! The figure of `palpus recognize categorize`: the surfaces in their 2-D embedding, coloured
//! by leaf category, labelled without overlaps.

use std::path::Path;

use plotters::prelude::*;
use recognize::CategoryTree;

use super::{FAMILY, Frame, PlotError, axes, render};

/// Scatter of the embedded surfaces, labelled by name, coloured by leaf category.
pub fn write_scatter(
    path: &Path,
    names: &[String],
    points: &[[f64; 2]],
    tree: &CategoryTree,
    embedding: &str,
) -> Result<(), PlotError> {
    let mut leaf_of = vec![0usize; names.len()];
    for (leaf, members) in tree.leaves().iter().enumerate() {
        for &i in *members {
            if let Some(l) = leaf_of.get_mut(i) {
                *l = leaf;
            }
        }
    }
    let range = |axis: usize| {
        let (lo, hi) = points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p[axis]), b.max(p[axis]))
            });
        // Room for the labels right of the points, and a usable range when all points coincide.
        let span = if hi > lo { hi - lo } else { 1.0 };
        (lo - 0.08 * span)..(hi + 0.25 * span)
    };
    render(path, (1100, 900), |root| {
        let frame = Frame {
            title_px: 24,
            margin_px: 16,
        };
        let title = format!("surfaces by confusion similarity ({embedding})");
        let chart = axes(
            root,
            &title,
            frame,
            (range(0), "dimension 1"),
            (range(1), "dimension 2"),
        )?;
        let font = (FAMILY, 16).into_font().color(&BLACK);
        let at: Vec<(i32, i32)> = points
            .iter()
            .map(|p| chart.backend_coord(&(p[0], p[1])))
            .collect();
        for (i, &(x, y)) in at.iter().enumerate() {
            let color = Palette99::pick(leaf_of[i]).to_rgba();
            root.draw(&Circle::new((x, y), 6, color.filled()))
                .map_err(|e| e.to_string())?;
        }
        let sizes = names
            .iter()
            .map(|n| {
                root.estimate_text_size(n, &font)
                    .map(|(w, h)| (w as i32, h as i32))
                    .map_err(|e| e.to_string())
            })
            .collect::<Result<Vec<_>, String>>()?;
        let (plot_x, plot_y) = chart.plotting_area().get_pixel_range();
        for (i, (corner, leader)) in place_labels(&at, &sizes, (plot_x, plot_y))
            .into_iter()
            .enumerate()
        {
            if leader {
                let (w, h) = sizes[i];
                // To the nearest point of the label's box.
                let end = (
                    at[i].0.clamp(corner.0, corner.0 + w),
                    at[i].1.clamp(corner.1, corner.1 + h),
                );
                root.draw(&PathElement::new(vec![at[i], end], BLACK.mix(0.4)))
                    .map_err(|e| e.to_string())?;
            }
            root.draw(&Text::new(names[i].clone(), corner, font.clone()))
                .map_err(|e| e.to_string())?;
        }
        Ok(())
    })
}

/// Top-left corners for the labels of the points `at` (pixels), each of `sizes`, so that no
/// label covers another label or a point where that can be helped, and whether each needs a
/// leader line back to its point (when it had to move away from it).
///
/// Greedy, points in order: each label tries positions beside its point, then on rings further
/// out, and takes the first that overlaps nothing and stays inside `area`, else the one with
/// the least overlap. Similar surfaces sit on top of each other in the embedding, so labels
/// placed at one fixed offset would print over each other; no plotting crate places labels.
fn place_labels(
    at: &[(i32, i32)],
    sizes: &[(i32, i32)],
    area: (std::ops::Range<i32>, std::ops::Range<i32>),
) -> Vec<((i32, i32), bool)> {
    const POINT: i32 = 7;
    const GAP: i32 = 9;
    let overlap = |a: (i32, i32, i32, i32), b: (i32, i32, i32, i32)| -> i64 {
        let w = (a.2.min(b.2) - a.0.max(b.0)).max(0);
        let h = (a.3.min(b.3) - a.1.max(b.1)).max(0);
        i64::from(w) * i64::from(h)
    };
    let points: Vec<(i32, i32, i32, i32)> = at
        .iter()
        .map(|&(x, y)| (x - POINT, y - POINT, x + POINT, y + POINT))
        .collect();
    let mut placed: Vec<(i32, i32, i32, i32)> = Vec::with_capacity(at.len());
    let mut out = Vec::with_capacity(at.len());
    for (i, (&(x, y), &(w, h))) in at.iter().zip(sizes).enumerate() {
        let mut best: Option<(i64, (i32, i32), bool)> = None;
        'rings: for ring in 0..8 {
            let r = ring * (h + 4);
            let candidates = [
                (x + GAP + r, y - h / 2),
                (x - GAP - w - r, y - h / 2),
                (x - w / 2, y - GAP - h - r),
                (x - w / 2, y + GAP + r),
                (x + GAP + r, y - GAP - h - r),
                (x + GAP + r, y + GAP + r),
                (x - GAP - w - r, y - GAP - h - r),
                (x - GAP - w - r, y + GAP + r),
            ];
            for (cx, cy) in candidates {
                let b = (cx, cy, cx + w, cy + h);
                let outside =
                    b.0 < area.0.start || b.2 > area.0.end || b.1 < area.1.start || b.3 > area.1.end;
                let cost: i64 = placed.iter().map(|p| overlap(*p, b)).sum::<i64>()
                    + points
                        .iter()
                        .enumerate()
                        .filter(|(j, _)| *j != i)
                        .map(|(_, p)| overlap(*p, b))
                        .sum::<i64>()
                    + if outside {
                        i64::from(w) * i64::from(h) * 4
                    } else {
                        0
                    };
                if best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, (cx, cy), ring > 0));
                }
                if cost == 0 {
                    break 'rings;
                }
            }
        }
        let (_, corner, leader) = best.unwrap_or((0, (x + GAP, y - h / 2), false));
        placed.push((corner.0, corner.1, corner.0 + w, corner.1 + h));
        out.push((corner, leader));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_of_coinciding_points_do_not_overlap() {
        // Five surfaces on one spot and two close by, as similar surfaces land in the embedding.
        let at = [(300, 300); 5]
            .into_iter()
            .chain([(310, 305), (600, 200)])
            .collect::<Vec<_>>();
        let sizes = vec![(120, 16); at.len()];
        let placed = place_labels(&at, &sizes, (0..1000, 0..800));
        let boxes: Vec<_> = placed
            .iter()
            .zip(&sizes)
            .map(|(((x, y), _), (w, h))| (*x, *y, x + w, y + h))
            .collect();
        for (i, a) in boxes.iter().enumerate() {
            assert!(a.0 >= 0 && a.2 <= 1000 && a.1 >= 0 && a.3 <= 800, "{a:?}");
            for b in &boxes[i + 1..] {
                let apart = a.2 <= b.0 || b.2 <= a.0 || a.3 <= b.1 || b.3 <= a.1;
                assert!(apart, "{a:?} overlaps {b:?}");
            }
            for (j, p) in at.iter().enumerate() {
                let clear = p.0 + 7 <= a.0 || a.2 <= p.0 - 7 || p.1 + 7 <= a.1 || a.3 <= p.1 - 7;
                assert!(clear || j == i, "label {i} covers point {j}");
            }
        }
        // The lone point keeps its label beside it, without a leader.
        assert_eq!(placed[6], ((609, 192), false));
    }
}
