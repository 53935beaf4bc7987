//! Every figure palpus draws, with plotters on a bitmap: a session's forces ([`session`]), a
//! recognizer's evaluation ([`recognition`]) and its anytime decisions ([`sequential`]), the
//! surfaces' categories ([`categories`]), an identified model against its data ([`fit`]) and
//! the speed/accuracy trade of its fits ([`trade`]) and the ε-SVR's fit time against n
//! ([`scaling`]).
//!
//! The shared primitives live here: the bundled font ([`font`]), drawing into an RGB buffer
//! and writing it as PNG ([`render()`], [`write_png_rgb`]), and [`PlotError`].

pub mod attempt;
pub mod categories;
pub mod fit;
pub mod history;
pub mod recognition;
pub mod scaling;
pub mod sequential;
pub mod session;
pub mod trade;

use std::path::{Path, PathBuf};

use std::ops::Range;

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::FontStyle;

pub use attempt::{ATTEMPT_SIZE, ForceDepth, write_attempt_plot};
pub use categories::write_scatter;
pub use fit::{FitSet, write_fit_plot};
pub use history::write_learning_curve;
pub use recognition::{
    confusion_size, som_components_size, som_density_size, som_map_size, write_confusion, write_eval_plots,
    write_som_components, write_som_density, write_som_map,
};
pub use scaling::{ScalingSeries, write_scaling_plot};
pub use sequential::{SEQUENTIAL_SIZE, write_sequential_plot};
pub use session::write_force_plot;
pub use trade::{TRADE_SIZE, write_trade_plot};

/// A drawing area of the bitmap backend, in pixels.
pub type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;

/// A chart of `f64` against `f64` on the bitmap backend.
pub type Chart<'a, 'b> = ChartContext<'a, BitMapBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// The font family every figure writes in (see [`font`]).
pub const FAMILY: &str = "sans-serif";

/// Title size and margin of a chart, px.
#[derive(Debug, Clone, Copy)]
pub struct Frame {
    /// Size of the title.
    pub title_px: u32,
    /// Margin around the chart.
    pub margin_px: u32,
}

/// A titled chart over `x` and `y` on `area`, its axes labelled `x_desc` and `y_desc`, with
/// the axis label areas every figure uses.
pub fn axes<'a, 'b>(
    area: &'a Area<'b>,
    title: &str,
    frame: Frame,
    (x, x_desc): (Range<f64>, &str),
    (y, y_desc): (Range<f64>, &str),
) -> Result<Chart<'a, 'b>, String> {
    let mut chart = ChartBuilder::on(area)
        .caption(title, (FAMILY, frame.title_px))
        .margin(frame.margin_px)
        .x_label_area_size(36)
        .y_label_area_size(52)
        .build_cartesian_2d(x, y)
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .draw()
        .map_err(|e| e.to_string())?;
    Ok(chart)
}

/// Why a figure could not be written.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The file could not be written.
    #[error("writing {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// Drawing failed.
    #[error("drawing {}: {reason}", path.display())]
    Plot {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
}

/// Registers the bundled font with plotters once (the bitmap backend has no system fonts); the
/// font is egui's Ubuntu Light, as `sans-serif`.
pub fn font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let _ = plotters::style::register_font(FAMILY, FontStyle::Normal, epaint_default_fonts::UBUNTU_LIGHT);
    });
}

/// Renders `w`×`h` pixels on white with `draw` and writes them as PNG to `path`.
pub fn render(
    path: &Path,
    (w, h): (u32, u32),
    draw: impl FnOnce(&Area<'_>) -> Result<(), String>,
) -> Result<(), PlotError> {
    font();
    let plot_err = |reason: String| PlotError::Plot {
        path: path.to_owned(),
        reason,
    };
    let mut rgb = vec![255u8; (w as usize) * (h as usize) * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(e.to_string()))?;
        draw(&root).map_err(plot_err)?;
        root.present().map_err(|e| plot_err(e.to_string()))?;
    }
    write_png_rgb(path, w, h, &rgb)
}

/// Writes an RGB8 image as PNG, through a temporary file.
pub fn write_png_rgb(path: &Path, w: u32, h: u32, rgb: &[u8]) -> Result<(), PlotError> {
    capture::write_atomically(path, |out| {
        let mut encoder = png::Encoder::new(out, w, h);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
        writer.write_image_data(rgb).map_err(std::io::Error::other)?;
        writer.finish().map_err(std::io::Error::other)
    })
    .map_err(|source| PlotError::Io {
        path: path.to_owned(),
        source,
    })
}

/// The chart's series labels, upper left, in the plots' font.
pub(crate) fn legend<'a, 'b: 'a>(chart: &mut Chart<'a, 'b>) -> Result<(), String> {
    legend_at(chart, SeriesLabelPosition::UpperLeft)
}

/// The chart's series labels at `position`, in the plots' font.
pub(crate) fn legend_at<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    position: SeriesLabelPosition,
) -> Result<(), String> {
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FAMILY, 15))
        .position(position)
        .draw()
        .map_err(|e| e.to_string())
}

/// The range from the least to the largest of `values`, widened on each side by `share` of
/// its span (at least `least_pad`); `0..1` when there is none.
pub(crate) fn padded_range(values: impl Iterator<Item = f64>, share: f64, least_pad: f64) -> Range<f64> {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    if lo.is_finite() {
        let pad = ((hi - lo) * share).max(least_pad);
        (lo - pad)..(hi + pad)
    } else {
        0.0..1.0
    }
}

/// Colours (Tableau 10), distinguishable on screen and in print; a figure with more than ten
/// series reuses them.
pub(crate) const PALETTE: [RGBColor; 10] = [
    RGBColor(78, 121, 167),
    RGBColor(242, 142, 43),
    RGBColor(225, 87, 89),
    RGBColor(118, 183, 178),
    RGBColor(89, 161, 79),
    RGBColor(237, 201, 72),
    RGBColor(176, 122, 161),
    RGBColor(255, 157, 167),
    RGBColor(156, 117, 95),
    RGBColor(186, 176, 172),
];
