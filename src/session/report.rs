//! The session report: a folder with the summary (text and JSON), force plots (PNG), a
//! rendered frame (or why none could be made) and the recognized-surface timeline.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use plotters::prelude::*;
use serde::Serialize;

use super::analysis::SegmentSummary;
use super::{SegmentKind, SegmentRun};
use crate::models::{Origin, ResolvedModel};

/// Why a report could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A file could not be written.
    #[error("writing {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// Drawing a plot failed.
    #[error("drawing {}: {reason}", path.display())]
    Plot {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
}

/// One recognized-surface decision.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Recognition {
    /// The object being rubbed.
    pub object: String,
    /// The surface it really is.
    pub truth: String,
    /// Loop time of the decision within the segment, s.
    pub time_s: f64,
    /// The recognized surface.
    pub label: String,
    /// Confidence 0–1.
    pub confidence: f64,
}

/// A model as the report lists it.
#[derive(Debug, Clone, Serialize)]
pub struct ModelLine {
    /// The scene's name for it.
    pub name: String,
    /// Its role.
    pub role: String,
    /// `file`, `cache` or `identified`.
    pub origin: String,
    /// The file it came from or was cached to.
    pub path: PathBuf,
    /// Fitting time when identified now, s.
    pub fit_s: Option<f64>,
    /// Support vectors.
    pub training_samples: usize,
}

impl ModelLine {
    /// From a resolved model.
    pub fn new(m: &ResolvedModel) -> Self {
        let (origin, path, fit_s) = match &m.origin {
            Origin::File(p) => ("file", p.clone(), None),
            Origin::Cached(p) => ("cache", p.clone(), None),
            Origin::Identified { cached, seconds } => ("identified", cached.clone(), Some(*seconds)),
        };
        Self {
            name: m.name.clone(),
            role: m.role.to_string(),
            origin: origin.into(),
            path,
            fit_s,
            training_samples: m.model.n_train,
        }
    }
}

/// The whole report (`report.json`).
#[derive(Debug, Clone, Serialize)]
pub struct SessionReport {
    /// The scene's name.
    pub scene: String,
    /// The scene file.
    pub scene_file: PathBuf,
    /// The device.
    pub device: String,
    /// Models used.
    pub models: Vec<ModelLine>,
    /// Per segment.
    pub segments: Vec<SegmentSummary>,
    /// Recognized-surface decisions.
    pub recognition: Vec<Recognition>,
    /// Fraction of decisions that named the right surface.
    pub recognition_accuracy: Option<f64>,
    /// The rendered frame, or why there is none.
    pub frame: Result<PathBuf, String>,
    /// Captures recorded.
    pub recorded: Vec<(PathBuf, u64)>,
    /// Wall-clock time from start to report, s.
    pub wall_s: f64,
}

impl SessionReport {
    /// The summary printed to the terminal and written to `summary.txt`.
    pub fn to_text(&self) -> String {
        let mut t = String::new();
        let _ = writeln!(
            t,
            "scene {} ({}) on {}",
            self.scene,
            self.scene_file.display(),
            self.device
        );
        for m in &self.models {
            let how = match m.fit_s {
                Some(s) => format!("identified in {s:.2} s, cached at {}", m.path.display()),
                None => format!("{} {}", m.origin, m.path.display()),
            };
            let _ = writeln!(
                t,
                "  model {} ({}): {} training samples, {how}",
                m.name, m.role, m.training_samples
            );
        }
        for s in &self.segments {
            let _ = writeln!(
                t,
                "  {} [{}]: {:.2} s, {} ticks, mean rate {:.2} Hz ({:+.3} %), period error p99 {:.0} µs, {} ticks > 2 ms late",
                s.object,
                s.kind,
                s.duration_s,
                s.ticks,
                s.mean_rate_hz,
                100.0 * (s.mean_rate_hz - s.nominal_rate_hz) / s.nominal_rate_hz.max(1e-9),
                s.period_error_p99_us,
                s.late_over_2ms
            );
            let _ = writeln!(
                t,
                "    force sent ≤ {:.2} N (limit {:.0} N), {} non-finite, {} safety events, {} model clamps; ended: {}",
                s.max_command_n,
                s.device_limit_n,
                s.non_finite_commands,
                s.safety_events,
                s.model_clamps,
                s.outcome
            );
            for (i, p) in s.punctures.iter().enumerate() {
                let truth = p
                    .truth_depth_m
                    .map_or("-".to_owned(), |d| format!("{:.1} mm", d * 1e3));
                let _ = writeln!(
                    t,
                    "    puncture {} at {:.2} s: depth {:.1} mm (simulated liver at {:.1} mm/s: {truth}), peak {:.2} N",
                    i + 1,
                    p.time_s,
                    p.depth_m * 1e3,
                    p.speed_mps * 1e3,
                    p.peak_force_n
                );
            }
            if let Some(d) = s.max_depth_m {
                let _ = writeln!(
                    t,
                    "    deepest {:.1} mm, largest axial force {:.2} N",
                    d * 1e3,
                    s.max_model_force_n
                );
            }
            if let Some(r) = s.mean_friction_ratio {
                let _ = writeln!(
                    t,
                    "    friction/normal while sliding {r:.3}, largest normal force {:.2} N",
                    s.max_model_force_n
                );
            }
        }
        if let Some(a) = self.recognition_accuracy {
            let _ = writeln!(
                t,
                "  recognition: {:.1} % of {} decisions right",
                a * 100.0,
                self.recognition.len()
            );
        }
        for (p, rows) in &self.recorded {
            let _ = writeln!(t, "  recorded {rows} rows to {}", p.display());
        }
        match &self.frame {
            Ok(p) => {
                let _ = writeln!(t, "  frame {}", p.display());
            }
            Err(why) => {
                let _ = writeln!(t, "  no frame: {why}");
            }
        }
        let _ = writeln!(t, "  start to report {:.1} s", self.wall_s);
        t
    }
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ReportError + '_ {
    move |source| ReportError::Io {
        path: path.to_owned(),
        source,
    }
}

/// Writes `summary.txt`, `report.json` and, if there are decisions, `timeline.csv`.
pub fn write_summary(dir: &Path, report: &SessionReport) -> Result<(), ReportError> {
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let text = dir.join("summary.txt");
    capture::write_atomically(&text, |w| w.write_all(report.to_text().as_bytes())).map_err(io(&text))?;
    let json = dir.join("report.json");
    capture::write_atomically(&json, |w| {
        serde_json::to_writer_pretty(&mut *w, report).map_err(std::io::Error::other)
    })
    .map_err(io(&json))?;
    if !report.recognition.is_empty() {
        let csv = dir.join("timeline.csv");
        capture::write_atomically(&csv, |w| {
            writeln!(w, "object,truth,time_s,label,confidence")?;
            for r in &report.recognition {
                writeln!(
                    w,
                    "{},{},{},{},{}",
                    r.object, r.truth, r.time_s, r.label, r.confidence
                )?;
            }
            Ok(())
        })
        .map_err(io(&csv))?;
    }
    Ok(())
}

use std::io::Write;

/// Registers the bundled font with plotters once.
pub(crate) fn font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        );
    });
}

/// Draws `force.png`: per segment, force against depth (needle) or position (rubbing), and
/// against time.
pub fn write_force_plot(path: &Path, runs: &[SegmentRun]) -> Result<(), ReportError> {
    font();
    let (w, h) = (1200u32, 420 * runs.len().max(1) as u32);
    let mut rgb = vec![255u8; (w * h * 3) as usize];
    let plot_err = |e: String| ReportError::Plot {
        path: path.to_owned(),
        reason: e,
    };
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(e.to_string()))?;
        let rows = root.split_evenly((runs.len().max(1), 2));
        for (i, run) in runs.iter().enumerate() {
            let (position, force, quantity) = super::traces(Some(&run.segment.kind));
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
            line_chart(&rows[2 * i], &title, &x_label, &xs, &ys).map_err(plot_err)?;
            let title_t = format!("{}: force vs time", run.segment.object);
            line_chart(&rows[2 * i + 1], &title_t, "time [s]", &ts, &ys).map_err(plot_err)?;
        }
        root.present().map_err(|e| plot_err(e.to_string()))?;
    }
    write_png_rgb(path, w, h, &rgb)
}

fn line_chart(
    area: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    title: &str,
    x_label: &str,
    xs: &[f64],
    ys: &[f64],
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
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(52)
        .build_cartesian_2d(range(xs), range(ys))
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc("force [N]")
        .draw()
        .map_err(|e| e.to_string())?;
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

/// Writes an RGB8 image as PNG, through a temporary file.
pub fn write_png_rgb(path: &Path, w: u32, h: u32, rgb: &[u8]) -> Result<(), ReportError> {
    capture::write_atomically(path, |out| {
        let mut encoder = png::Encoder::new(out, w, h);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
        writer.write_image_data(rgb).map_err(std::io::Error::other)?;
        writer.finish().map_err(std::io::Error::other)
    })
    .map_err(io(path))
}
