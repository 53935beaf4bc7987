//! The figure of `palpus recognize eval --sequential`: the posterior's reliability diagram
//! (how often the most probable surface is right against how probable it was said to be), the
//! trade the threshold sets between naming a surface soon and naming it right, and how much of
//! each surface the first threshold's decisions took (the path, which a slower or faster stroke
//! needs about as much of, or the time where the captures have no positions).

use std::path::Path;

use plotters::prelude::*;

use recognize::{SequentialEvaluation, SequentialRow, SurfaceWait};

use super::{Frame, PlotError, axes, render};

/// Size of the figure, px.
pub const SEQUENTIAL_SIZE: (u32, u32) = (1800, 540);

const FRAME: Frame = Frame {
    title_px: 20,
    margin_px: 14,
};
const IDEAL: RGBColor = RGBColor(150, 150, 150);
const MEASURED: RGBColor = RGBColor(30, 90, 200);
const TRADE: RGBColor = RGBColor(200, 30, 40);
const WAIT: RGBColor = RGBColor(90, 150, 90);

/// Draws `e` into a PNG at `path`.
pub fn write_sequential_plot(path: &Path, e: &SequentialEvaluation) -> Result<(), PlotError> {
    render(path, SEQUENTIAL_SIZE, |root| {
        let (left, rest) = root.split_horizontally(SEQUENTIAL_SIZE.0 / 3);
        let (right, surfaces) = rest.split_horizontally(SEQUENTIAL_SIZE.0 / 3);
        let title = format!(
            "reliability at {} (Brier {:.3}, ECE {:.1} %)",
            e.params.threshold(),
            e.calibration.brier,
            100.0 * e.calibration.ece
        );
        let mut chart = axes(
            &left,
            &title,
            FRAME,
            (0.0..1.0, "posterior of the most probable surface"),
            (0.0..1.0, "fraction right"),
        )?;
        chart
            .draw_series(LineSeries::new([(0.0, 0.0), (1.0, 1.0)], IDEAL.stroke_width(1)))
            .map_err(|e| e.to_string())?;
        let bins: Vec<(f64, f64)> = e
            .calibration
            .bins
            .iter()
            .map(|b| (b.mean_probability, b.accuracy))
            .collect();
        chart
            .draw_series(LineSeries::new(bins.iter().copied(), MEASURED.stroke_width(2)))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(bins.iter().map(|&p| Circle::new(p, 4, MEASURED.filled())))
            .map_err(|e| e.to_string())?;

        let points: Vec<(f64, f64, f64)> = e
            .rows
            .iter()
            .filter_map(|r| Some((r.time_to_stable_correct_s?, 100.0 * r.accuracy()?, r.threshold)))
            .collect();
        let t_max = points.iter().map(|p| p.0).fold(1.0f64, f64::max) * 1.1;
        let a_min = points.iter().map(|p| p.1).fold(100.0f64, f64::min);
        let a_lo = (a_min - 5.0).clamp(0.0, 95.0);
        let mut chart = axes(
            &right,
            "threshold: sooner against right",
            FRAME,
            (
                0.0..t_max,
                "mean time from contact to the stable right surface [s]",
            ),
            (a_lo..100.5, "named windows right [%]"),
        )?;
        chart
            .draw_series(LineSeries::new(
                points.iter().map(|p| (p.0, p.1)),
                TRADE.stroke_width(2),
            ))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(points.iter().map(|&(t, a, threshold)| {
                EmptyElement::at((t, a))
                    + Circle::new((0, 0), 4, TRADE.filled())
                    + Text::new(format!("{threshold}"), (6, -14), (super::FAMILY, 14))
            }))
            .map_err(|e| e.to_string())?;
        match e.rows.first() {
            Some(row) => draw_surface_waits(&surfaces, row),
            None => Ok(()),
        }
    })
}

/// One bar per surface of `row`: the mean path to its stable right surface, or the mean time
/// where some capture had no positions; a surface no stroke of which ended right has none.
fn draw_surface_waits(area: &super::Area<'_>, row: &SequentialRow) -> Result<(), String> {
    let in_travel = row
        .surfaces
        .iter()
        .all(|w| w.stable == 0 || w.stable_right_m.is_some());
    let wait = |w: &SurfaceWait| {
        if in_travel {
            w.stable_right_m.map(|m| 1e3 * m)
        } else {
            w.stable_right_s
        }
    };
    // Room right of the longest bar for its label.
    let longest = row.surfaces.iter().filter_map(wait).fold(1.0f64, f64::max) * 1.9;
    let n = row.surfaces.len().max(1) as f64;
    let (title, x_desc) = if in_travel {
        (
            format!("how much of each surface it took, at {}", row.threshold),
            "mean path from contact to the stable right surface [mm]",
        )
    } else {
        (
            format!("how long each surface took, at {}", row.threshold),
            "mean time from contact to the stable right surface [s]",
        )
    };
    // The surfaces name their bars, so the y axis carries no numbers.
    let mut chart = ChartBuilder::on(area)
        .caption(title, (super::FAMILY, FRAME.title_px))
        .margin(FRAME.margin_px)
        .x_label_area_size(36)
        .y_label_area_size(8)
        .build_cartesian_2d(0.0..longest, -0.5..n - 0.5)
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_labels(0)
        .disable_y_mesh()
        .draw()
        .map_err(|e| e.to_string())?;
    for (i, w) in row.surfaces.iter().enumerate() {
        let y = n - 1.0 - i as f64;
        let label = match (wait(w), w.stable_right_s) {
            (Some(v), Some(s)) if in_travel => format!("{} {v:.1} mm, {s:.2} s", w.surface),
            (Some(v), _) => format!("{} {v:.2} s", w.surface),
            _ => format!("{}: no stroke ended right", w.surface),
        };
        let end = wait(w).unwrap_or(0.0);
        chart
            .draw_series([Rectangle::new([(0.0, y - 0.3), (end, y + 0.3)], WAIT.filled())])
            .map_err(|e| e.to_string())?;
        chart
            .draw_series([EmptyElement::at((end, y)) + Text::new(label, (6, -7), (super::FAMILY, 13))])
            .map_err(|e| e.to_string())?;
    }
    Ok(())
}
