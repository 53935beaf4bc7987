//! The figure of `palpus recognize eval --sequential`: the posterior's reliability diagram
//! (how often the most probable surface is right against how probable it was said to be), and
//! the trade the threshold sets between naming a surface soon and naming it right.

use std::path::Path;

use plotters::prelude::*;

use recognize::SequentialEvaluation;

use super::{Frame, PlotError, axes, render};

/// Size of the figure, px.
pub const SEQUENTIAL_SIZE: (u32, u32) = (1200, 540);

const FRAME: Frame = Frame {
    title_px: 20,
    margin_px: 14,
};
const IDEAL: RGBColor = RGBColor(150, 150, 150);
const MEASURED: RGBColor = RGBColor(30, 90, 200);
const TRADE: RGBColor = RGBColor(200, 30, 40);

/// Draws `e` into a PNG at `path`.
pub fn write_sequential_plot(path: &Path, e: &SequentialEvaluation) -> Result<(), PlotError> {
    render(path, SEQUENTIAL_SIZE, |root| {
        let (left, right) = root.split_horizontally(SEQUENTIAL_SIZE.0 / 2);
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
        Ok(())
    })
}
