//! `palpus history`'s learning curve: each trainee's attempts at each scene, in order.

use std::collections::BTreeMap;
use std::path::Path;

use plotters::prelude::*;

use super::{Area, Frame, PlotError, axes, render};
use crate::history::Attempt;

/// Three panels against attempt number (each trainee's and scene's own count): the overshoot
/// past where the target gave (with the goal's allowance dashed), the peak force, and the time
/// to the target. Passed attempts are filled dots, failed ones hollow.
pub fn write_learning_curve(path: &Path, attempts: &[Attempt]) -> Result<(), PlotError> {
    let mut series: BTreeMap<(String, String), Vec<&Attempt>> = BTreeMap::new();
    for a in attempts {
        series
            .entry((a.trainee.clone(), a.scene.clone()))
            .or_default()
            .push(a);
    }
    render(path, (1000, 900), |root| {
        let rows = root.split_evenly((3, 1));
        type Get = fn(&Attempt) -> Option<f64>;
        let panels: [(&str, &str, Get); 3] = [
            ("overshoot past the target layer", "overshoot [mm]", |a| {
                a.score.overshoot_m.map(|m| m * 1e3)
            }),
            ("peak axial force", "force [N]", |a| Some(a.score.peak_force_n)),
            ("time from first contact to the target", "time [s]", |a| {
                a.score.time_to_target_s
            }),
        ];
        for (k, (title, y_desc, get)) in panels.iter().enumerate() {
            panel(&rows[k], title, y_desc, *get, &series, k == 0)?;
        }
        Ok(())
    })
}

fn panel(
    area: &Area<'_>,
    title: &str,
    y_desc: &str,
    get: fn(&Attempt) -> Option<f64>,
    series: &BTreeMap<(String, String), Vec<&Attempt>>,
    allowance: bool,
) -> Result<(), String> {
    let longest = series.values().map(Vec::len).max().unwrap_or(1);
    let values: Vec<f64> = series.values().flatten().filter_map(|a| get(a)).collect();
    let allowed: Vec<f64> = series
        .values()
        .flatten()
        .map(|a| a.score.allowed_overshoot_m * 1e3)
        .collect();
    let hi = values
        .iter()
        .chain(if allowance { allowed.as_slice() } else { &[] })
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let frame = Frame {
        title_px: 17,
        margin_px: 10,
    };
    let mut chart = axes(
        area,
        title,
        frame,
        (0.5..longest as f64 + 0.5, "attempt"),
        (0.0..if hi > 0.0 { 1.15 * hi } else { 1.0 }, y_desc),
    )?;
    for (i, ((trainee, scene), list)) in series.iter().enumerate() {
        let colour = Palette99::pick(i).to_rgba();
        let points: Vec<(f64, f64, bool)> = list
            .iter()
            .enumerate()
            .filter_map(|(n, a)| get(a).map(|v| ((n + 1) as f64, v, a.score.passed)))
            .collect();
        chart
            .draw_series(LineSeries::new(
                points.iter().map(|&(x, y, _)| (x, y)),
                colour.stroke_width(2),
            ))
            .map_err(|e| e.to_string())?
            .label(format!("{trainee} at {scene}"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2)));
        chart
            .draw_series(points.iter().map(|&(x, y, passed)| {
                let style = if passed {
                    colour.filled()
                } else {
                    colour.stroke_width(2)
                };
                Circle::new((x, y), 5, style)
            }))
            .map_err(|e| e.to_string())?;
        if allowance && let Some(first) = list.first() {
            let allowed = first.score.allowed_overshoot_m * 1e3;
            chart
                .draw_series(DashedLineSeries::new(
                    [(0.5, allowed), (longest as f64 + 0.5, allowed)],
                    6,
                    4,
                    colour.mix(0.6).stroke_width(1),
                ))
                .map_err(|e| e.to_string())?;
        }
    }
    // Upper right: attempts start at the upper left, where a first attempt's overshoot is.
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((super::FAMILY, 15))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| e.to_string())
}
