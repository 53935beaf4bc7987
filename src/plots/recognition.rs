//! Plots of a recognizer's evaluation, written by `palpus recognize eval --plots DIR`.
//!
//! * `confusion.png`: the confusion matrix as a heat map, each row in percent of its true
//!   class's decisions, with the value in every cell.
//! * For a SOM recognizer, `som_map.png`: the 1-D map's nodes in line order coloured by their
//!   label, the U-distance between neighbouring reference vectors above them (a peak marks a
//!   boundary between clusters, thesis Fig. 4.12) and each node's training hits below them;
//!   `som_components.png`: the map for each feature value (thesis Fig. 4.12's component
//!   planes), each node's reference vector component by component, so a feature whose row
//!   changes smoothly and tracks the labels dominates and two rows that rise together are
//!   correlated; and `som_density.png`: per true class, on which nodes the evaluation windows
//!   landed (thesis Fig. 4.13, for the evaluation data).
//!
//! Everything is drawn in pixel coordinates so the map's cells, the U-distance points between
//! them and the density bars line up column for column.

use std::path::{Path, PathBuf};

use anyhow::Context;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use recognize::{LabelledCapture, RecognizerBody, RecognizerFile};

use super::{Area, FAMILY, PALETTE, PlotError, render};

/// A class's colour; classes beyond ten reuse them, which the names in the cells disambiguate.
fn class_colour(class: usize) -> RGBColor {
    PALETTE[class % PALETTE.len()]
}

/// Black or white, whichever reads better on `bg`.
fn ink_on(bg: RGBColor) -> RGBColor {
    let luma = 0.299 * f64::from(bg.0) + 0.587 * f64::from(bg.1) + 0.114 * f64::from(bg.2);
    if luma > 140.0 { BLACK } else { WHITE }
}

fn text_style(size: u32, colour: RGBColor, h: HPos, v: VPos) -> TextStyle<'static> {
    (FAMILY, size).into_font().color(&colour).pos(Pos::new(h, v))
}

/// Writes every plot for `model` evaluated on `captures` into `dir` (created if missing) and
/// returns the paths written. `window_s` overrides a SOM's window length, as in the evaluation.
pub fn write_eval_plots(
    dir: &Path,
    model: &RecognizerFile,
    captures: &[LabelledCapture],
    confusion_percent: &[Vec<f64>],
    window_s: Option<f64>,
) -> anyhow::Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let mut written = Vec::new();
    let path = dir.join("confusion.png");
    write_confusion(&path, &model.classes, confusion_percent)?;
    written.push(path);
    if let RecognizerBody::Som { windowing, som } = &model.body {
        let windowing = match window_s {
            Some(s) => windowing.with_window_s(s)?,
            None => *windowing,
        };
        // The evaluation reports labels, not nodes: find each decision window's node again
        // from its features (kept or computed), with the map's own winner rule.
        let mut density = vec![vec![0u64; som.node_labels().len()]; model.classes.len()];
        for c in captures {
            let path = &c.reference.path;
            let truth = model
                .classes
                .iter()
                .position(|l| *l == c.label)
                .with_context(|| {
                    format!(
                        "{}: surface `{}` is not one the recognizer knows",
                        path.display(),
                        c.label
                    )
                })?;
            let nodes = model
                .som_winners(c, Some(&windowing))?
                .with_context(|| format!("{}: not a map over Nakano's windows", path.display()))?;
            for node in nodes {
                if let Some(n) = density[truth].get_mut(node) {
                    *n += 1;
                }
            }
        }
        let hits: Vec<u64> = som.training_hits().iter().map(|&h| h as u64).collect();
        let path = dir.join("som_map.png");
        write_som_map(
            &path,
            &model.classes,
            som.node_labels(),
            som.reference_vectors(),
            &hits,
        )?;
        written.push(path);
        let path = dir.join("som_components.png");
        write_som_components(
            &path,
            &model.classes,
            &model.feature_names,
            som.node_labels(),
            som.reference_vectors(),
        )?;
        written.push(path);
        let path = dir.join("som_density.png");
        write_som_density(&path, &model.classes, som.node_labels(), &density)?;
        written.push(path);
    }
    Ok(written)
}

fn text(area: &Area<'_>, s: &str, at: (i32, i32), style: &TextStyle<'_>) -> Result<(), String> {
    area.draw(&Text::new(s.to_owned(), at, style.clone()))
        .map_err(|e| e.to_string())
}

/// A chart's title, centred across a `width`-pixel image with its top at `y`.
fn title(area: &Area<'_>, s: &str, width: u32, y: i32) -> Result<(), String> {
    text(
        area,
        s,
        (width as i32 / 2, y),
        &text_style(22, BLACK, HPos::Center, VPos::Top),
    )
}

/// A straight line from `a` to `b`.
fn segment(area: &Area<'_>, a: (i32, i32), b: (i32, i32), colour: RGBColor) -> Result<(), String> {
    area.draw(&PathElement::new(vec![a, b], colour))
        .map_err(|e| e.to_string())
}

fn rect(area: &Area<'_>, a: (i32, i32), b: (i32, i32), style: ShapeStyle) -> Result<(), String> {
    area.draw(&Rectangle::new([a, b], style))
        .map_err(|e| e.to_string())
}

/// Confusion heat map geometry: a wide cell so a class name fits under its column.
const CM_CELL: (i32, i32) = (112, 48);
const CM_LEFT: i32 = 190;
const CM_TOP: i32 = 110;

/// The size of `confusion.png` for `classes` classes.
pub fn confusion_size(classes: usize) -> (u32, u32) {
    let n = classes.max(1) as i32;
    (
        (CM_LEFT + n * CM_CELL.0 + 30) as u32,
        (CM_TOP + n * CM_CELL.1 + 60) as u32,
    )
}

/// Draws the row-normalised confusion matrix (`percent[truth][predicted]`).
pub fn write_confusion(path: &Path, classes: &[String], percent: &[Vec<f64>]) -> Result<(), PlotError> {
    // Rows and columns in natural order of the names (`mat2` before `mat10`), as the text table.
    let mut order: Vec<usize> = (0..classes.len()).collect();
    order.sort_by(|&a, &b| recognize::natural_cmp(&classes[a], &classes[b]));
    let classes: Vec<&String> = order.iter().map(|&i| &classes[i]).collect();
    let percent: Vec<Vec<f64>> = order
        .iter()
        .map(|&t| {
            order
                .iter()
                .map(|&p| percent.get(t).and_then(|row| row.get(p)).copied().unwrap_or(0.0))
                .collect()
        })
        .collect();
    let size = confusion_size(classes.len());
    render(path, size, |root| {
        let (cw, ch) = CM_CELL;
        let n = classes.len() as i32;
        title(root, "confusion matrix (% of each true class)", size.0, 12)?;
        let axis = text_style(16, BLACK, HPos::Center, VPos::Center);
        text(root, "predicted", (CM_LEFT + n * cw / 2, 52), &axis)?;
        text(root, "true", (CM_LEFT / 2, CM_TOP - 20), &axis)?;
        let name_col = text_style(14, BLACK, HPos::Center, VPos::Bottom);
        let name_row = text_style(14, BLACK, HPos::Right, VPos::Center);
        for (i, name) in classes.iter().enumerate() {
            let i = i as i32;
            text(root, name, (CM_LEFT + i * cw + cw / 2, CM_TOP - 6), &name_col)?;
            text(root, name, (CM_LEFT - 10, CM_TOP + i * ch + ch / 2), &name_row)?;
        }
        for (t, row) in percent.iter().enumerate() {
            for (p, &v) in row.iter().enumerate() {
                let (x, y) = (CM_LEFT + p as i32 * cw, CM_TOP + t as i32 * ch);
                // White to dark blue, linear in percent.
                let f = (v / 100.0).clamp(0.0, 1.0);
                let lerp = |a: u8, b: u8| (f64::from(a) + f * (f64::from(b) - f64::from(a))).round() as u8;
                let bg = RGBColor(lerp(255, 8), lerp(255, 48), lerp(255, 107));
                rect(root, (x, y), (x + cw, y + ch), bg.filled())?;
                let label = if v > 0.0 {
                    format!("{v:.1}")
                } else {
                    "0".to_owned()
                };
                text(
                    root,
                    &label,
                    (x + cw / 2, y + ch / 2),
                    &text_style(16, ink_on(bg), HPos::Center, VPos::Center),
                )?;
            }
        }
        // Grid and frame, with the diagonal outlined so correct decisions stand out.
        let grey = RGBColor(160, 160, 160);
        for i in 0..=n {
            segment(
                root,
                (CM_LEFT + i * cw, CM_TOP),
                (CM_LEFT + i * cw, CM_TOP + n * ch),
                grey,
            )?;
            segment(
                root,
                (CM_LEFT, CM_TOP + i * ch),
                (CM_LEFT + n * cw, CM_TOP + i * ch),
                grey,
            )?;
        }
        for i in 0..n {
            let (x, y) = (CM_LEFT + i * cw, CM_TOP + i * ch);
            rect(
                root,
                (x + 1, y + 1),
                (x + cw - 1, y + ch - 1),
                RGBColor(220, 60, 40).stroke_width(2),
            )?;
        }
        Ok(())
    })
}

/// SOM plot geometry: one column per node.
const SOM_CELL_W: i32 = 112;
const SOM_LEFT: i32 = 140;

fn som_width(nodes: usize) -> u32 {
    (SOM_LEFT + nodes.max(1) as i32 * SOM_CELL_W + 30) as u32
}

/// The size of `som_map.png` for a map of `nodes` nodes.
pub fn som_map_size(nodes: usize) -> (u32, u32) {
    (som_width(nodes), 560)
}

/// The size of `som_density.png` for `classes` classes and `nodes` nodes.
pub fn som_density_size(classes: usize, nodes: usize) -> (u32, u32) {
    (
        som_width(nodes),
        (DENSITY_TOP + classes.max(1) as i32 * DENSITY_ROW + 50) as u32,
    )
}

/// Euclidean distance between each pair of neighbouring reference vectors.
fn u_distances(reference: &[Vec<f64>]) -> Vec<f64> {
    reference
        .windows(2)
        .map(|p| {
            p[0].iter()
                .zip(&p[1])
                .map(|(a, b)| (a - b).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .collect()
}

/// Draws the topographic map: U-distance profile, labelled nodes, training hits, legend.
pub fn write_som_map(
    path: &Path,
    classes: &[String],
    labels: &[usize],
    reference: &[Vec<f64>],
    hits: &[u64],
) -> Result<(), PlotError> {
    let size = som_map_size(labels.len());
    let u = u_distances(reference);
    render(path, size, |root| {
        let cw = SOM_CELL_W;
        let n = labels.len() as i32;
        let right = SOM_LEFT + n * cw;
        let x_mid = |q: i32| SOM_LEFT + q * cw + cw / 2;
        title(
            root,
            &format!("SOM topographic map ({} nodes)", labels.len()),
            size.0,
            10,
        )?;
        let side = text_style(15, BLACK, HPos::Right, VPos::Center);
        let small = text_style(13, BLACK, HPos::Center, VPos::Bottom);

        // U-distance: one point on each boundary between neighbouring cells.
        let (u_top, u_bottom) = (60, 200);
        let u_max = u.iter().copied().fold(0.0_f64, f64::max).max(1e-12) * 1.15;
        rect(
            root,
            (SOM_LEFT, u_top),
            (right, u_bottom),
            RGBColor(120, 120, 120).into(),
        )?;
        text(root, "U-distance", (SOM_LEFT - 14, (u_top + u_bottom) / 2), &side)?;
        text(
            root,
            &format!("{u_max:.2}"),
            (SOM_LEFT - 4, u_top + 6),
            &text_style(12, BLACK, HPos::Right, VPos::Center),
        )?;
        text(
            root,
            "0",
            (SOM_LEFT - 4, u_bottom - 6),
            &text_style(12, BLACK, HPos::Right, VPos::Center),
        )?;
        let points: Vec<(i32, i32)> = u
            .iter()
            .enumerate()
            .map(|(i, &d)| {
                let y = u_bottom - ((d / u_max) * f64::from(u_bottom - u_top)).round() as i32;
                (SOM_LEFT + (i as i32 + 1) * cw, y)
            })
            .collect();
        let line = RGBColor(180, 40, 40);
        root.draw(&PathElement::new(points.clone(), line.stroke_width(2)))
            .map_err(|e| e.to_string())?;
        for (&(x, y), d) in points.iter().zip(&u) {
            root.draw(&Circle::new((x, y), 4, line.filled()))
                .map_err(|e| e.to_string())?;
            text(root, &format!("{d:.2}"), (x, y - 6), &small)?;
        }

        // Nodes, coloured by label.
        let (c_top, c_bottom) = (215, 305);
        text(root, "node label", (SOM_LEFT - 14, (c_top + c_bottom) / 2), &side)?;
        for (q, &label) in labels.iter().enumerate() {
            let q = q as i32;
            let bg = class_colour(label);
            let (x0, x1) = (SOM_LEFT + q * cw, SOM_LEFT + (q + 1) * cw);
            rect(root, (x0, c_top), (x1, c_bottom), bg.filled())?;
            rect(root, (x0, c_top), (x1, c_bottom), WHITE.stroke_width(2))?;
            let ink = ink_on(bg);
            text(
                root,
                &format!("node {q}"),
                (x_mid(q), c_top + 18),
                &text_style(13, ink, HPos::Center, VPos::Center),
            )?;
            let name = classes.get(label).map_or("?", String::as_str);
            text(
                root,
                name,
                (x_mid(q), c_top + 52),
                &text_style(14, ink, HPos::Center, VPos::Center),
            )?;
        }

        // Training hits per node.
        let (h_top, h_bottom) = (340, 460);
        let h_max = hits.iter().copied().max().unwrap_or(0).max(1) as f64;
        text(
            root,
            "training hits",
            (SOM_LEFT - 14, (h_top + h_bottom) / 2),
            &side,
        )?;
        segment(root, (SOM_LEFT, h_bottom), (right, h_bottom), BLACK)?;
        for (q, &h) in hits.iter().enumerate() {
            let q = q as i32;
            let top = h_bottom - ((h as f64 / h_max) * f64::from(h_bottom - h_top - 18)).round() as i32;
            let x0 = SOM_LEFT + q * cw + cw / 5;
            let x1 = SOM_LEFT + (q + 1) * cw - cw / 5;
            rect(root, (x0, top), (x1, h_bottom), RGBColor(90, 90, 90).filled())?;
            text(root, &h.to_string(), (x_mid(q), top - 3), &small)?;
        }

        legend(root, classes, 490, size.0 as i32)
    })
}

const COMPONENT_TOP: i32 = 90;
const COMPONENT_ROW: i32 = 56;

/// The size of `som_components.png` for `features` features and `nodes` nodes.
pub fn som_components_size(features: usize, nodes: usize) -> (u32, u32) {
    (
        som_width(nodes) + 140,
        (COMPONENT_TOP + features.max(1) as i32 * COMPONENT_ROW + 60) as u32,
    )
}

/// Diverging colour for `v` in `[-1, 1]`: blue below zero, white at zero, red above.
fn diverging(v: f64) -> RGBColor {
    let t = v.clamp(-1.0, 1.0);
    let fade = |c: u8| (255.0 - (255.0 - f64::from(c)) * t.abs()).round() as u8;
    if t < 0.0 {
        RGBColor(fade(33), fade(102), fade(172))
    } else {
        RGBColor(fade(178), fade(24), fade(43))
    }
}

/// Draws the component planes: one row per feature, one cell per node, coloured by the
/// reference vector's component (the map's scaled, unit-length space; each row on its own
/// scale, its largest magnitude printed at the right), node labels across the top.
pub fn write_som_components(
    path: &Path,
    classes: &[String],
    feature_names: &[String],
    labels: &[usize],
    reference: &[Vec<f64>],
) -> Result<(), PlotError> {
    let size = som_components_size(feature_names.len(), labels.len());
    let left = SOM_LEFT + 90;
    render(path, size, |root| {
        let cw = SOM_CELL_W;
        let n = labels.len() as i32;
        let x_mid = |q: i32| left + q * cw + cw / 2;
        title(
            root,
            "SOM map for each feature value (reference vector components)",
            size.0,
            10,
        )?;
        for (q, &label) in labels.iter().enumerate() {
            let q = q as i32;
            let bg = class_colour(label);
            rect(root, (left + q * cw, 50), (left + (q + 1) * cw, 80), bg.filled())?;
            text(
                root,
                classes.get(label).map_or("?", String::as_str),
                (x_mid(q), 65),
                &text_style(13, ink_on(bg), HPos::Center, VPos::Center),
            )?;
        }
        let side = text_style(14, BLACK, HPos::Right, VPos::Center);
        for (j, name) in feature_names.iter().enumerate() {
            let top = COMPONENT_TOP + j as i32 * COMPONENT_ROW;
            let bottom = top + COMPONENT_ROW - 6;
            let values: Vec<f64> = reference
                .iter()
                .map(|m| m.get(j).copied().unwrap_or(0.0))
                .collect();
            let scale = values.iter().fold(0.0_f64, |a, v| a.max(v.abs())).max(1e-12);
            text(root, name, (left - 10, (top + bottom) / 2), &side)?;
            for (q, v) in values.iter().enumerate() {
                let q = q as i32;
                let bg = diverging(v / scale);
                rect(
                    root,
                    (left + q * cw, top),
                    (left + (q + 1) * cw, bottom),
                    bg.filled(),
                )?;
                text(
                    root,
                    &format!("{v:+.2}"),
                    (x_mid(q), (top + bottom) / 2),
                    &text_style(14, ink_on(bg), HPos::Center, VPos::Center),
                )?;
            }
            text(
                root,
                &format!("±{scale:.2}"),
                (left + n * cw + 8, (top + bottom) / 2),
                &text_style(13, BLACK, HPos::Left, VPos::Center),
            )?;
        }
        let note_y = COMPONENT_TOP + feature_names.len() as i32 * COMPONENT_ROW + 20;
        text(
            root,
            "blue: negative component, red: positive; each row scaled to its largest magnitude (right)",
            (20, note_y),
            &text_style(14, BLACK, HPos::Left, VPos::Center),
        )
    })
}

/// One swatch and name per class, wrapped across rows from `top`.
fn legend(root: &Area<'_>, classes: &[String], top: i32, width: i32) -> Result<(), String> {
    let style = text_style(14, BLACK, HPos::Left, VPos::Center);
    let item_w = 170;
    let per_row = ((width - 40) / item_w).max(1);
    for (i, name) in classes.iter().enumerate() {
        let (r, c) = (i as i32 / per_row, i as i32 % per_row);
        let (x, y) = (20 + c * item_w, top + r * 24);
        rect(root, (x, y), (x + 16, y + 16), class_colour(i).filled())?;
        text(root, name, (x + 22, y + 8), &style)?;
    }
    Ok(())
}

const DENSITY_TOP: i32 = 50;
const DENSITY_ROW: i32 = 76;

/// Draws, per true class, how many evaluation windows each node won (`density[class][node]`).
/// Each row has its own scale (its largest count is printed); the node columns are tinted with
/// the node's label so a window landing on a node of another class stands out.
pub fn write_som_density(
    path: &Path,
    classes: &[String],
    labels: &[usize],
    density: &[Vec<u64>],
) -> Result<(), PlotError> {
    let size = som_density_size(classes.len(), labels.len());
    render(path, size, |root| {
        let cw = SOM_CELL_W;
        let n = labels.len() as i32;
        let right = SOM_LEFT + n * cw;
        title(root, "evaluation windows per node, by true class", size.0, 10)?;
        let name_style = text_style(14, BLACK, HPos::Right, VPos::Center);
        let small = text_style(12, BLACK, HPos::Center, VPos::Bottom);
        for (t, row) in density.iter().enumerate() {
            let top = DENSITY_TOP + t as i32 * DENSITY_ROW;
            let bottom = top + DENSITY_ROW - 6;
            // Faint tint of each node's label colour behind the bars.
            for (q, &label) in labels.iter().enumerate() {
                let c = class_colour(label);
                let tint = |v: u8| (255.0 - 0.25 * (255.0 - f64::from(v))).round() as u8;
                let x0 = SOM_LEFT + q as i32 * cw;
                rect(
                    root,
                    (x0, top),
                    (x0 + cw, bottom),
                    RGBColor(tint(c.0), tint(c.1), tint(c.2)).filled(),
                )?;
            }
            let name = classes.get(t).map_or("?", String::as_str);
            rect(
                root,
                (SOM_LEFT - 28, (top + bottom) / 2 - 7),
                (SOM_LEFT - 14, (top + bottom) / 2 + 7),
                class_colour(t).filled(),
            )?;
            text(root, name, (SOM_LEFT - 34, (top + bottom) / 2), &name_style)?;
            let max = row.iter().copied().max().unwrap_or(0).max(1) as f64;
            for (q, &count) in row.iter().enumerate() {
                if count == 0 {
                    continue;
                }
                let q = q as i32;
                let h = ((count as f64 / max) * f64::from(bottom - top - 18)).round() as i32;
                let (x0, x1) = (SOM_LEFT + q * cw + cw / 5, SOM_LEFT + (q + 1) * cw - cw / 5);
                rect(root, (x0, bottom - h), (x1, bottom), class_colour(t).filled())?;
                text(
                    root,
                    &count.to_string(),
                    (SOM_LEFT + q * cw + cw / 2, bottom - h - 2),
                    &small,
                )?;
            }
            segment(root, (SOM_LEFT, bottom), (right, bottom), BLACK)?;
        }
        // Node indices, coloured by the node's label.
        let y = DENSITY_TOP + classes.len() as i32 * DENSITY_ROW + 8;
        for (q, &label) in labels.iter().enumerate() {
            let x0 = SOM_LEFT + q as i32 * cw;
            let bg = class_colour(label);
            rect(root, (x0 + 2, y), (x0 + cw - 2, y + 24), bg.filled())?;
            text(
                root,
                &format!("node {q}"),
                (x0 + cw / 2, y + 12),
                &text_style(13, ink_on(bg), HPos::Center, VPos::Center),
            )?;
        }
        Ok(())
    })
}
