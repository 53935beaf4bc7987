//! `attempt.png`: an insertion attempt's axial force against depth over the scene's expert
//! reference attempt, with where the target layer gave and the overshoot the goal allows.

use std::path::Path;

use plotters::prelude::*;

use super::{Frame, PlotError, axes, legend, render};
use crate::session::score::Score;

/// A force-against-depth trace: depths m, forces N.
#[derive(Debug, Clone, Default)]
pub struct ForceDepth {
    /// Depth below the surface, m.
    pub depth_m: Vec<f64>,
    /// Axial force on the needle, N.
    pub force_n: Vec<f64>,
}

/// Size of `attempt.png`, px.
pub const ATTEMPT_SIZE: (u32, u32) = (1000, 560);

/// Draws `attempt` (red) over `reference` (grey, when the scene names one), the depth where the
/// target gave and the band past it the goal allows (green), titled with the verdict.
pub fn write_attempt_plot(
    path: &Path,
    attempt: &ForceDepth,
    reference: Option<&ForceDepth>,
    score: &Score,
) -> Result<(), PlotError> {
    render(path, ATTEMPT_SIZE, |root| {
        let mm = |v: &[f64]| v.iter().map(|d| d * 1e3).collect::<Vec<_>>();
        // The reference first, so that the attempt is drawn over it.
        let traces: Vec<(&ForceDepth, Vec<f64>, bool)> = reference
            .into_iter()
            .map(|t| (t, mm(&t.depth_m), false))
            .chain(std::iter::once((attempt, mm(&attempt.depth_m), true)))
            .collect();
        let finite = |v: &mut dyn Iterator<Item = f64>| {
            v.filter(|x| x.is_finite())
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                    (a.min(x), b.max(x))
                })
        };
        let (x_lo, x_hi) = finite(&mut traces.iter().flat_map(|(_, d, _)| d.iter().copied()));
        let (y_lo, y_hi) = finite(&mut traces.iter().flat_map(|(t, _, _)| t.force_n.iter().copied()));
        let x = if x_lo.is_finite() && x_hi > x_lo {
            x_lo.min(0.0)..x_hi + 0.05 * (x_hi - x_lo)
        } else {
            0.0..1.0
        };
        let y = if y_lo.is_finite() && y_hi > y_lo {
            let pad = 0.08 * (y_hi - y_lo);
            y_lo.min(0.0) - pad..y_hi + pad
        } else {
            -0.1..1.0
        };
        let title = format!(
            "{}: {}",
            if score.passed { "passed" } else { "failed" },
            score.verdict
        );
        let frame = Frame {
            title_px: 17,
            margin_px: 14,
        };
        let mut chart = axes(
            root,
            &title,
            frame,
            (x, "depth [mm]"),
            (y.clone(), "axial force [N]"),
        )?;
        let green = RGBColor(40, 150, 60);
        if let Some(d) = score.target_depth_m {
            let (a, b) = (d * 1e3, (d + score.allowed_overshoot_m) * 1e3);
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [(a, y.start), (b, y.end)],
                    green.mix(0.15).filled(),
                )))
                .map_err(|e| e.to_string())?
                .label(format!(
                    "{} gave; allowed past it",
                    crate::scene::in_words(&score.target)
                ))
                .legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 16, y + 6)], green.mix(0.3).filled()));
        }
        let grey = RGBColor(120, 120, 120);
        let red = RGBColor(180, 40, 40);
        for (trace, depth_mm, own) in &traces {
            let (colour, name) = if *own {
                (red, "this attempt")
            } else {
                (grey, "expert reference")
            };
            let step = (depth_mm.len() / 4000).max(1);
            chart
                .draw_series(LineSeries::new(
                    depth_mm
                        .iter()
                        .zip(&trace.force_n)
                        .step_by(step)
                        .map(|(&x, &y)| (x, y)),
                    colour.stroke_width(if *own { 2 } else { 4 }),
                ))
                .map_err(|e| e.to_string())?
                .label(name)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2)));
        }
        legend(&mut chart)
    })
}
