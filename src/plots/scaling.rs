//! The figure of `palpus bench svr-scale-plot`: the ε-SVR's fit time against n on each
//! problem of a sweep, ours beside libsvm's, on log scales (both span decades), one panel a
//! problem, each of our fits marked by the path the solver took.

use std::path::Path;

use plotters::prelude::*;

use super::{Area, Frame, PALETTE, PlotError, axes, legend_at, padded_range, render};

/// One problem's sweep: our fits (n, seconds, solver path) and libsvm's (n, seconds).
#[derive(Debug, Clone, PartialEq)]
pub struct ScalingSeries {
    /// The problem, as the panel's title.
    pub name: String,
    /// Our fits.
    pub ours: Vec<(f64, f64, String)>,
    /// libsvm's fits of the same samples.
    pub libsvm: Vec<(f64, f64)>,
}

const FRAME: Frame = Frame {
    title_px: 18,
    margin_px: 10,
};
const LIBSVM: RGBColor = RGBColor(120, 120, 120);
/// Draws every series into a PNG at `path`, two panels a row. Points not positive and finite
/// have no place on log scales and are left out.
pub fn write_scaling_plot(path: &Path, series: &[ScalingSeries]) -> Result<(), PlotError> {
    let mut paths: Vec<&str> = Vec::new();
    for s in series {
        for (_, _, p) in &s.ours {
            if !paths.contains(&p.as_str()) {
                paths.push(p);
            }
        }
    }
    let rows = series.len().div_ceil(2).max(1);
    render(path, (1200, 380 * rows as u32), |root| {
        let panels = root.split_evenly((rows, 2));
        for (s, area) in series.iter().zip(&panels) {
            panel(area, s, &paths)?;
        }
        Ok(())
    })
}

fn logged(points: impl Iterator<Item = (f64, f64)>) -> Vec<(f64, f64)> {
    points
        .filter(|(n, s)| n.is_finite() && *n > 0.0 && s.is_finite() && *s > 0.0)
        .map(|(n, s)| (n.log10(), s.log10()))
        .collect()
}

fn panel(area: &Area<'_>, s: &ScalingSeries, paths: &[&str]) -> Result<(), String> {
    let ours = logged(s.ours.iter().map(|(n, t, _)| (*n, *t)));
    let libsvm = logged(s.libsvm.iter().copied());
    let all = || ours.iter().chain(&libsvm);
    let span = |get: fn(&(f64, f64)) -> f64| padded_range(all().map(get), 0.06, 0.1);
    let mut chart = axes(
        area,
        &s.name,
        FRAME,
        (span(|p| p.0), "log10 n"),
        (span(|p| p.1), "log10 fit time [s]"),
    )?;
    chart
        .draw_series(LineSeries::new(libsvm.iter().copied(), LIBSVM.stroke_width(2)))
        .map_err(|e| e.to_string())?
        .label("libsvm")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], LIBSVM.stroke_width(2)));
    chart
        .draw_series(LineSeries::new(ours.iter().copied(), BLACK.stroke_width(1)))
        .map_err(|e| e.to_string())?;
    for (k, name) in paths.iter().enumerate() {
        let colour = PALETTE[k % PALETTE.len()];
        let points: Vec<(f64, f64)> = logged(
            s.ours
                .iter()
                .filter(|(_, _, p)| p == name)
                .map(|(n, t, _)| (*n, *t)),
        );
        if points.is_empty() {
            continue;
        }
        chart
            .draw_series(points.iter().map(|&p| Circle::new(p, 4, colour.filled())))
            .map_err(|e| e.to_string())?
            .label(format!("ours: {name}"))
            .legend(move |(x, y)| Circle::new((x + 8, y), 4, colour.filled()));
    }
    // Time grows with n: the lower right is where the curves are not.
    legend_at(&mut chart, SeriesLabelPosition::LowerRight)
}
