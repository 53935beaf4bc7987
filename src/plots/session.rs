//! The figure of a session report: `force.png`, each segment's force against position or depth
//! and against time.

use std::path::Path;

use plotters::prelude::*;

use super::{Area, Frame, PlotError, axes, render};
use crate::session::{SegmentKind, SegmentRun, traces};

/// Draws `force.png`: per segment, force against depth (needle) or position (rubbing), and
/// against time.
pub fn write_force_plot(path: &Path, runs: &[SegmentRun]) -> Result<(), PlotError> {
    render(path, (1200, 420 * runs.len().max(1) as u32), |root| {
        let rows = root.split_evenly((runs.len().max(1), 2));
        for (i, run) in runs.iter().enumerate() {
            let (position, force, quantity) = traces(Some(&run.segment.kind));
            let what = match run.segment.kind {
                SegmentKind::Needle { .. } => "axial force",
                SegmentKind::Friction { .. } => "friction",
                SegmentKind::Surface { .. } => "friction (RFOB)",
            };
            let x_label = format!("{quantity} [mm]");
            let xs: Vec<f64> = run.samples.iter().map(|s| position(s) * 1e3).collect();
            let ys: Vec<f64> = run.samples.iter().map(force).collect();
            let title = format!("{}: {what} vs {quantity}", run.segment.object);
            let ts: Vec<f64> = run.samples.iter().map(|s| s.time_s).collect();
            line_chart(&rows[2 * i], &title, &x_label, &xs, &ys)?;
            let title_t = format!("{}: force vs time", run.segment.object);
            line_chart(&rows[2 * i + 1], &title_t, "time [s]", &ts, &ys)?;
        }
        Ok(())
    })
}

fn line_chart(area: &Area<'_>, title: &str, x_label: &str, xs: &[f64], ys: &[f64]) -> Result<(), String> {
    let range = |v: &[f64]| {
        let (lo, hi) = v
            .iter()
            .filter(|x| x.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        if lo.is_finite() && hi > lo {
            let pad = 0.05 * (hi - lo);
            (lo - pad)..(hi + pad)
        } else {
            -1.0..1.0
        }
    };
    let frame = Frame {
        title_px: 20,
        margin_px: 12,
    };
    let mut chart = axes(area, title, frame, (range(xs), x_label), (range(ys), "force [N]"))?;
    // A plot needs no more points than pixels across.
    let step = (xs.len() / 4000).max(1);
    chart
        .draw_series(LineSeries::new(
            xs.iter().zip(ys).step_by(step).map(|(&x, &y)| (x, y)),
            &RGBColor(180, 40, 40),
        ))
        .map_err(|e| e.to_string())?;
    Ok(())
}
