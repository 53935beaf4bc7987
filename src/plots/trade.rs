//! The figure of `palpus bench trade`: every measured fit as time per prediction against its
//! error, both on log scales (each spans decades), with the Pareto front drawn through the
//! points no other beats on both.

use std::path::Path;

use plotters::prelude::*;

use super::{Frame, PlotError, axes, padded_range, render};

/// Size of the figure, px.
pub const TRADE_SIZE: (u32, u32) = (900, 600);

const FRAME: Frame = Frame {
    title_px: 22,
    margin_px: 14,
};
const CLOUD: RGBColor = RGBColor(150, 150, 150);
const FRONT: RGBColor = RGBColor(200, 30, 40);

/// Draws `points` — (time per prediction in ns, error, on the front) — into a PNG at `path`,
/// the error axis described as `error_desc`. Points that are not positive and finite on both
/// axes have no place on log scales and are left out.
pub fn write_trade_plot(path: &Path, points: &[(f64, f64, bool)], error_desc: &str) -> Result<(), PlotError> {
    let logged: Vec<(f64, f64, bool)> = points
        .iter()
        .filter(|(x, y, _)| x.is_finite() && *x > 0.0 && y.is_finite() && *y > 0.0)
        .map(|&(x, y, on)| (x.log10(), y.log10(), on))
        .collect();
    let x = padded_range(logged.iter().map(|p| p.0), 0.08, 0.1);
    let y = padded_range(logged.iter().map(|p| p.1), 0.08, 0.1);
    let y_desc = format!("log10 {error_desc}");
    render(path, TRADE_SIZE, |root| {
        let mut chart = axes(
            root,
            "speed against accuracy (front in red)",
            FRAME,
            (x, "log10 time per prediction [ns]"),
            (y, &y_desc),
        )?;
        chart
            .draw_series(
                logged
                    .iter()
                    .filter(|p| !p.2)
                    .map(|&(x, y, _)| Circle::new((x, y), 3, CLOUD.filled())),
            )
            .map_err(|e| e.to_string())?;
        let mut front: Vec<(f64, f64)> = logged.iter().filter(|p| p.2).map(|&(x, y, _)| (x, y)).collect();
        front.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart
            .draw_series(LineSeries::new(front.iter().copied(), FRONT.stroke_width(2)))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(front.iter().map(|&p| Circle::new(p, 4, FRONT.filled())))
            .map_err(|e| e.to_string())?;
        Ok(())
    })
}
