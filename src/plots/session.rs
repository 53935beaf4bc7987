//! The figure of a session report: `force.png`, each segment's force against position or depth
//! and against time.

use std::path::Path;

use plotters::prelude::*;

use super::{Area, Frame, PlotError, axes, render};
use crate::session::{SURFACE_Z_M, SegmentKind, SegmentRun, traces};

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
            // A needle model of a simulated tissue, on the simulator: that tissue's own force
            // along the same trajectory beside the rendered one.
            let truth = match &run.segment.kind {
                SegmentKind::Needle { truth: Some(t), .. } if !run.device.starts_with("replay") => Some(*t),
                _ => None,
            };
            let tissue = truth.map(|t| {
                (
                    crate::session::truth_along::tissue_force(&run.samples, SURFACE_Z_M, &t.tissue()),
                    format!("simulated {}", t.words()),
                )
            });
            let tissue = tissue.as_ref().map(|(f, label)| (f.as_slice(), label.as_str()));
            line_chart(&rows[2 * i], &title, &x_label, &xs, &ys, tissue)?;
            let title_t = format!("{}: force vs time", run.segment.object);
            line_chart(&rows[2 * i + 1], &title_t, "time [s]", &ts, &ys, tissue)?;
        }
        Ok(())
    })
}

/// `ys` against `xs` in red, and `tissue` (a simulated tissue's force at the same samples, and
/// its legend) in grey behind it, with a legend, when given.
fn line_chart(
    area: &Area<'_>,
    title: &str,
    x_label: &str,
    xs: &[f64],
    ys: &[f64],
    tissue: Option<(&[f64], &str)>,
) -> Result<(), String> {
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
    let all: Vec<f64> = ys
        .iter()
        .chain(tissue.map_or(&[][..], |(f, _)| f))
        .copied()
        .collect();
    let mut chart = axes(
        area,
        title,
        frame,
        (range(xs), x_label),
        (range(&all), "force [N]"),
    )?;
    // A plot needs no more points than pixels across.
    let step = (xs.len() / 4000).max(1);
    let grey = RGBColor(120, 120, 120);
    let red = RGBColor(180, 40, 40);
    if let Some((tissue, label)) = tissue {
        chart
            .draw_series(LineSeries::new(
                xs.iter().zip(tissue).step_by(step).map(|(&x, &y)| (x, y)),
                grey.stroke_width(2),
            ))
            .map_err(|e| e.to_string())?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], grey.stroke_width(2)));
    }
    let rendered = chart
        .draw_series(LineSeries::new(
            xs.iter().zip(ys).step_by(step).map(|(&x, &y)| (x, y)),
            &red,
        ))
        .map_err(|e| e.to_string())?;
    if tissue.is_some() {
        rendered
            .label("rendered")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], red));
        super::legend(&mut chart)?;
    }
    Ok(())
}
