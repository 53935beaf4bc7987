//! The figure of `palpus identify --plot`: an identified model against the data it was fitted
//! on and tested on.
//!
//! - needle: axial force against depth, measured samples as points (training and test in two
//!   colours) and the model's prediction at every sample in a third;
//! - hard contact: friction against normal force, measured points and the fitted line;
//! - soft contact: friction against normal force, the samples coloured by speed band, and per
//!   band the model's line at the band's mean speed.

use std::path::Path;

use plotters::prelude::*;

use super::{Area, Frame, PlotError, axes, render};
use identify::{ModelFile, ModelKind};

/// Samples of one capture as the model sees them.
#[derive(Debug, Clone)]
pub struct FitSet {
    /// `train` or `test`.
    pub label: &'static str,
    /// Per input of the model (in the order of [`ModelFile::inputs`]), that column's values.
    pub inputs: Vec<Vec<f64>>,
    /// The measured output.
    pub measured: Vec<f64>,
    /// The model's output at each sample.
    pub predicted: Vec<f64>,
}

/// Soft contact: at most this many speed bands (fewer when the data hold fewer speeds).
const SPEED_BANDS: usize = 5;
/// Speed-band colours, slow to fast (viridis, its pale yellow end darkened to read on white).
const BANDS: [RGBColor; SPEED_BANDS] = [
    RGBColor(68, 1, 84),
    RGBColor(59, 82, 139),
    RGBColor(33, 145, 140),
    RGBColor(94, 180, 70),
    RGBColor(225, 160, 0),
];
/// Colours of the measured sets (training, test) and of the model.
const TRAIN: RGBColor = RGBColor(60, 110, 190);
const TEST: RGBColor = RGBColor(235, 140, 30);
const MODEL: RGBColor = RGBColor(200, 30, 40);

/// Draws `model` against `sets` into a `size` PNG at `path` (see the module documentation).
pub fn write_fit_plot(
    path: &Path,
    size: (u32, u32),
    model: &ModelFile,
    sets: &[FitSet],
) -> Result<(), PlotError> {
    render(path, size, |root| match model.kind {
        ModelKind::NeedlePuncture => needle(root, sets, "ε-SVR model at each sample"),
        ModelKind::NeedlePhases => needle(root, sets, "phase model along each stroke"),
        ModelKind::HardFriction => hard(root, model, sets),
        ModelKind::SoftFriction => soft(root, model, sets),
    })
}

const FRAME: Frame = Frame {
    title_px: 22,
    margin_px: 14,
};

/// A padded range over every finite value of `values`; a usable one when there is none.
fn range<'a>(values: impl IntoIterator<Item = &'a f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values
        .into_iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return -1.0..1.0;
    }
    let span = if hi > lo { hi - lo } else { lo.abs().max(1.0) };
    (lo - 0.05 * span)..(hi + 0.05 * span)
}

/// The colour a measured set is drawn in.
fn colour(set: &FitSet) -> RGBColor {
    if set.label == "test" { TEST } else { TRAIN }
}

fn err(e: impl ToString) -> String {
    e.to_string()
}

fn needle(root: &Area<'_>, sets: &[FitSet], model_label: &str) -> Result<(), String> {
    let depth_mm = |s: &FitSet| -> Vec<f64> { s.inputs[0].iter().map(|d| d * 1e3).collect() };
    let depth = range(sets.iter().flat_map(|s| &s.inputs[0]));
    let x = depth.start * 1e3..depth.end * 1e3;
    let y = range(sets.iter().flat_map(|s| s.measured.iter().chain(&s.predicted)));
    let title = "needle: axial force against depth";
    let mut chart = axes(root, title, FRAME, (x, "depth [mm]"), (y, "axial force [N]"))?;
    for set in sets {
        let c = colour(set);
        chart
            .draw_series(
                depth_mm(set)
                    .into_iter()
                    .zip(&set.measured)
                    .map(|(d, &f)| Circle::new((d, f), 2, c.filled())),
            )
            .map_err(err)?
            .label(format!("measured ({})", set.label))
            .legend(move |(x, y)| Circle::new((x + 10, y), 4, c.filled()));
    }
    for (k, set) in sets.iter().enumerate() {
        let series = chart
            .draw_series(
                depth_mm(set)
                    .into_iter()
                    .zip(&set.predicted)
                    .map(|(d, &f)| Circle::new((d, f), 1, MODEL.filled())),
            )
            .map_err(err)?;
        // One legend entry for the model, whichever sets it was evaluated on.
        if k == 0 {
            series
                .label(model_label)
                .legend(|(x, y)| Circle::new((x + 10, y), 4, MODEL.filled()));
        }
    }
    super::legend(&mut chart)
}

fn hard(root: &Area<'_>, model: &ModelFile, sets: &[FitSet]) -> Result<(), String> {
    let x = range(sets.iter().flat_map(|s| &s.inputs[0]));
    let y = range(sets.iter().flat_map(|s| s.measured.iter().chain(&s.predicted)));
    let title = "hard contact: friction against normal force";
    let mut chart = axes(
        root,
        title,
        FRAME,
        (x.clone(), "normal force [N]"),
        (y, "friction force [N]"),
    )?;
    for set in sets {
        let c = colour(set);
        chart
            .draw_series(
                set.inputs[0]
                    .iter()
                    .zip(&set.measured)
                    .map(|(&p, &f)| Circle::new((p, f), 4, c.filled())),
            )
            .map_err(err)?
            .label(format!("measured ({})", set.label))
            .legend(move |(x, y)| Circle::new((x + 10, y), 4, c.filled()));
    }
    // The model is linear in P, but evaluating it along the axis shows it as the file computes.
    let line = (0..=100).map(|k| {
        let p = x.start + (x.end - x.start) * f64::from(k) / 100.0;
        (p, model.predict(&[p]))
    });
    chart
        .draw_series(LineSeries::new(line, MODEL.stroke_width(2)))
        .map_err(err)?
        .label("ε-SVR model")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], MODEL.stroke_width(2)));
    super::legend(&mut chart)
}

fn soft(root: &Area<'_>, model: &ModelFile, sets: &[FitSet]) -> Result<(), String> {
    // Bands of equal width over the measured speeds of every set, so that train and test
    // samples at the same speed share a colour.
    let (v_lo, v_hi) = sets
        .iter()
        .flat_map(|s| &s.inputs[0])
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let speeds = if v_hi > v_lo { v_lo..v_hi } else { range([&v_lo]) };
    let n_bands = SPEED_BANDS;
    let band = |v: f64| -> usize {
        let t = (v - speeds.start) / (speeds.end - speeds.start);
        ((t * n_bands as f64).floor().max(0.0) as usize).min(n_bands - 1)
    };
    let palette = |b: usize| BANDS[b % BANDS.len()];
    let x = range(sets.iter().flat_map(|s| &s.inputs[1]));
    let y = range(sets.iter().flat_map(|s| s.measured.iter().chain(&s.predicted)));
    let title = "soft contact: friction against normal force, by sliding speed";
    let mut chart = axes(
        root,
        title,
        FRAME,
        (x, "normal force [N]"),
        (y, "friction force [N]"),
    )?;
    for set in sets {
        // Training samples filled, test samples as rings.
        let filled = set.label != "test";
        chart
            .draw_series(
                set.inputs[0]
                    .iter()
                    .zip(&set.inputs[1])
                    .zip(&set.measured)
                    .map(|((&v, &p), &f)| {
                        let c = palette(band(v));
                        let style = if filled { c.filled() } else { c.stroke_width(1) };
                        Circle::new((p, f), 3, style)
                    }),
            )
            .map_err(err)?
            .label(format!(
                "measured ({}{})",
                set.label,
                if filled { ", filled" } else { ", rings" }
            ))
            .legend(move |(x, y)| {
                let style = if filled {
                    BLACK.filled()
                } else {
                    BLACK.stroke_width(1)
                };
                Circle::new((x + 10, y), 4, style)
            });
    }
    for b in 0..n_bands {
        let (mut n, mut v_sum, mut p_lo, mut p_hi) = (0usize, 0.0, f64::INFINITY, f64::NEG_INFINITY);
        for set in sets {
            for (&v, &p) in set.inputs[0].iter().zip(&set.inputs[1]) {
                if band(v) == b && v.is_finite() && p.is_finite() {
                    n += 1;
                    v_sum += v;
                    p_lo = p_lo.min(p);
                    p_hi = p_hi.max(p);
                }
            }
        }
        if n == 0 {
            continue;
        }
        let v = v_sum / n as f64;
        let c = palette(b);
        let lo = speeds.start + (speeds.end - speeds.start) * b as f64 / n_bands as f64;
        let hi = speeds.start + (speeds.end - speeds.start) * (b + 1) as f64 / n_bands as f64;
        let line = (0..=20).map(|k| {
            let p = p_lo + (p_hi - p_lo) * f64::from(k) / 20.0;
            (p, model.predict(&[v, p]))
        });
        chart
            .draw_series(LineSeries::new(line, c.stroke_width(2)))
            .map_err(err)?
            .label(format!(
                "model at {:.1} mm/s (band {:.1}–{:.1} mm/s)",
                v * 1e3,
                lo * 1e3,
                hi * 1e3
            ))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
    }
    super::legend(&mut chart)
}
