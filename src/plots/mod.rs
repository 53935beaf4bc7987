//! Every figure palpus draws, with plotters on a bitmap: a session's forces ([`session`]), a
//! recognizer's evaluation ([`recognition`]) and the surfaces' categories ([`categories`]).
//!
//! The shared primitives live here: the bundled font ([`font`]), drawing into an RGB buffer
//! and writing it as PNG ([`render`], [`write_png_rgb`]), and [`PlotError`].

pub mod categories;
pub mod recognition;
pub mod session;

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;

pub use categories::write_scatter;
pub use recognition::{
    confusion_size, som_components_size, som_density_size, som_map_size, write_confusion, write_eval_plots,
    write_som_components, write_som_density, write_som_map,
};
pub use session::write_force_plot;

/// A drawing area of the bitmap backend, in pixels.
pub type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;

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
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        );
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
