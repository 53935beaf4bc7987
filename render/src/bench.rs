//! Headless frame-rate benchmark: frames per second at a few sizes, MSAA 1 and 4, overlay off, on
//! (its data unchanged between frames, as between two refreshes of the window's plots) and live
//! (new data every frame, so its panel is repainted every frame), with a per-stage time
//! breakdown so it is clear where a frame's time goes. One more row draws the tissue block with
//! uniform fine cells instead of cells graded around the dimple: what the grading saves, and the
//! reference picture for every row's PSNR.

use std::fmt::Write as _;
use std::sync::Arc;
use std::time::Instant;

use crate::demo::{NeedleState, demo_overlay, tissue_scene};
use crate::error::RenderError;
use crate::frame::Frame;
use crate::gpu::GpuOptions;
use crate::renderer::{Renderer, StageTimes};
use crate::shapes;

/// Whether and how the overlay is shown in a benchmark row.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OverlayMode {
    Off,
    /// Shown with the same data every frame: the panel is painted once and copied.
    On,
    /// Shown with new plot data every frame: the panel is repainted every frame.
    Live,
}

impl OverlayMode {
    fn label(self) -> &'static str {
        match self {
            OverlayMode::Off => "off",
            OverlayMode::On => "on",
            OverlayMode::Live => "live",
        }
    }
}

/// Which tissue block a benchmark row draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TissueMesh {
    /// [`shapes::tissue_block`]: fine cells only where the dimple bends it.
    Graded,
    /// [`shapes::uniform_tissue_block`]: fine cells everywhere, the reference picture.
    Uniform,
}

impl TissueMesh {
    fn label(self) -> &'static str {
        match self {
            TissueMesh::Graded => "graded",
            TissueMesh::Uniform => "uniform",
        }
    }

    fn meshes(self) -> Vec<crate::mesh::MeshData> {
        match self {
            TissueMesh::Graded => shapes::tissue_block(),
            TissueMesh::Uniform => shapes::uniform_tissue_block(),
        }
    }
}

/// What to measure.
#[derive(Debug, Clone, PartialEq)]
pub struct BenchOptions {
    pub sizes: Vec<[u32; 2]>,
    pub msaa: Vec<u32>,
    pub overlay: Vec<OverlayMode>,
    /// Internal resolution scales below 1 to measure too (overlay on), each with its PSNR
    /// against the full-resolution picture.
    pub scales: Vec<f32>,
    /// Adds a row with the uniform block (overlay on), the reference for every row's PSNR.
    pub uniform_row: bool,
    /// Frames timed per configuration (after one warm-up frame).
    pub frames: u32,
    pub gpu: GpuOptions,
}

impl Default for BenchOptions {
    fn default() -> Self {
        BenchOptions {
            sizes: vec![[640, 480], [1280, 720]],
            msaa: vec![1, 4],
            overlay: vec![OverlayMode::Off, OverlayMode::On, OverlayMode::Live],
            scales: vec![0.75, 0.5],
            uniform_row: true,
            frames: 30,
            gpu: GpuOptions::default(),
        }
    }
}

/// One configuration's result. Stage times are means per frame from a second run that waits
/// for the GPU after each stage; `fps` comes from the unsplit run.
#[derive(Debug, Clone, PartialEq)]
pub struct BenchRow {
    pub width: u32,
    pub height: u32,
    pub msaa: u32,
    pub overlay: OverlayMode,
    pub mesh: TissueMesh,
    /// Internal resolution of the scene relative to the image.
    pub scale: f32,
    /// PSNR of the picture against the same frame with the uniform block at full resolution, dB
    /// (`None` for that frame itself).
    pub psnr_db: Option<f64>,
    pub fps: f64,
    pub frame_ms: f64,
    /// Scene (and overlay) passes: uniforms, encoding, submit and execution.
    pub draw_ms: f64,
    pub resolve_ms: f64,
    /// Overlay UI build and tessellation on the CPU.
    pub overlay_cpu_ms: f64,
    pub readback_ms: f64,
}

/// All rows and the adapter they ran on.
#[derive(Debug, Clone, PartialEq)]
pub struct BenchTable {
    pub adapter: String,
    pub rows: Vec<BenchRow>,
}

/// Column names and the text table's widths.
const COLUMNS: [(&str, usize); 12] = [
    ("size", 9),
    ("MSAA", 4),
    ("overlay", 7),
    ("mesh", 7),
    ("scale", 5),
    ("PSNR dB", 7),
    ("fps", 6),
    ("frame ms", 8),
    ("draw ms", 7),
    ("resolve ms", 10),
    ("overlay CPU ms", 14),
    ("readback ms", 11),
];

/// One row's cells, as both tables print them ("—" where a stage does not apply).
fn cells(r: &BenchRow) -> [String; 12] {
    let stage = |v: f64| if v > 0.0 { format!("{v:.2}") } else { "—".into() };
    [
        format!("{}×{}", r.width, r.height),
        r.msaa.to_string(),
        r.overlay.label().into(),
        r.mesh.label().into(),
        r.scale.to_string(),
        r.psnr_db.map_or("—".to_string(), |p| format!("{p:.1}")),
        format!("{:.1}", r.fps),
        format!("{:.1}", r.frame_ms),
        format!("{:.1}", r.draw_ms),
        stage(r.resolve_ms),
        stage(r.overlay_cpu_ms),
        format!("{:.2}", r.readback_ms),
    ]
}

impl BenchTable {
    /// A fixed-width text table.
    pub fn to_text(&self) -> String {
        let line = |cells: &mut dyn Iterator<Item = String>| -> String {
            let padded: Vec<String> = cells.zip(COLUMNS).map(|(c, (_, w))| format!("{c:>w$}")).collect();
            padded.join(" ")
        };
        let mut s = format!("headless render benchmark on {}\n", self.adapter);
        let _ = writeln!(
            s,
            "{}",
            line(&mut COLUMNS.iter().map(|(name, _)| name.to_string()))
        );
        for r in &self.rows {
            let _ = writeln!(s, "{}", line(&mut cells(r).into_iter()));
        }
        s
    }

    /// The same table in Markdown, as docs/rendering.md shows it.
    pub fn to_markdown(&self) -> String {
        let names: Vec<&str> = COLUMNS.iter().map(|(name, _)| *name).collect();
        let mut s = format!("| {} |\n|{}\n", names.join(" | "), "---|".repeat(COLUMNS.len()));
        for r in &self.rows {
            let _ = writeln!(s, "| {} |", cells(r).join(" | "));
        }
        s
    }
}

/// The benchmark scene: the tissue block (three layers) with the needle pressing.
pub fn bench_frame(overlay: bool) -> Frame {
    frame_with(TissueMesh::Graded, overlay)
}

/// The benchmark scene drawn with either tissue block.
pub fn frame_with(mesh: TissueMesh, overlay: bool) -> Frame {
    let tissue: Vec<_> = mesh.meshes().into_iter().map(Arc::new).collect();
    let needle: Vec<_> = shapes::needle().into_iter().map(Arc::new).collect();
    let mut frame = tissue_scene(
        &tissue,
        &needle,
        NeedleState::Pressing {
            depth_m: 0.008,
            radius_m: 0.012,
        },
    );
    frame.overlay = overlay.then(demo_overlay);
    frame
}

/// The benchmark frame for frame number `i`: in [`OverlayMode::Live`] the force-time plot has
/// scrolled by one sample and the loop rate has changed, as in a running session.
fn frame_at(base: &Frame, mode: OverlayMode, i: u32) -> Frame {
    let mut frame = base.clone();
    if mode == OverlayMode::Live
        && let Some(overlay) = frame.overlay.as_mut()
    {
        let shift_s = i as f32 * 0.01;
        for p in &mut overlay.force_time {
            p[0] += shift_s;
            p[1] += 0.05 * (p[0] * 5.0).sin();
        }
        overlay.haptic_rate_hz = Some(999.0 + (i % 10) as f32 * 0.1);
    }
    frame
}

/// Runs every configuration of `options`.
pub fn run(options: &BenchOptions) -> Result<BenchTable, RenderError> {
    run_reporting(options, |_, _| {})
}

/// The number of rows [`run`] measures for `options`.
pub fn row_count(options: &BenchOptions) -> usize {
    let per_renderer = options.overlay.len() + options.scales.len() + usize::from(options.uniform_row);
    options.sizes.len() * options.msaa.len() * per_renderer
}

/// As [`run`], calling `progress(rows done, rows in all)` after each row (a run takes about a
/// minute on a software rasterizer).
pub fn run_reporting(
    options: &BenchOptions,
    mut progress: impl FnMut(usize, usize),
) -> Result<BenchTable, RenderError> {
    let total = row_count(options);
    let frames = options.frames.max(1);
    let mut rows = Vec::new();
    let mut adapter = String::new();
    for &[width, height] in &options.sizes {
        for &msaa in &options.msaa {
            let mut renderer = Renderer::headless_with(width, height, msaa, &options.gpu)?;
            adapter = renderer.adapter_description();
            let mut configs: Vec<(OverlayMode, f32, TissueMesh)> = options
                .overlay
                .iter()
                .map(|&o| (o, 1.0, TissueMesh::Graded))
                .collect();
            configs.extend(
                options
                    .scales
                    .iter()
                    .map(|&s| (OverlayMode::On, s, TissueMesh::Graded)),
            );
            if options.uniform_row {
                configs.push((OverlayMode::On, 1.0, TissueMesh::Uniform));
            }
            for (overlay, scale, mesh) in configs {
                let reference = if mesh == TissueMesh::Uniform && scale == 1.0 {
                    None
                } else {
                    renderer.set_scale(1.0)?;
                    let frame = frame_with(TissueMesh::Uniform, overlay != OverlayMode::Off);
                    Some(renderer.render(&frame_at(&frame, overlay, 0))?)
                };
                renderer.set_scale(scale)?;
                let base = frame_with(mesh, overlay != OverlayMode::Off);
                let first = renderer.render(&frame_at(&base, overlay, 0))?;
                let psnr_db = reference.and_then(|r| crate::golden::psnr_db(&first, &r));
                // Frames are made before timing: only drawing is measured.
                let timed: Vec<Frame> = (1..=frames).map(|i| frame_at(&base, overlay, i)).collect();
                let start = Instant::now();
                for frame in &timed {
                    renderer.render(frame)?;
                }
                let frame_s = start.elapsed().as_secs_f64() / f64::from(frames);
                let split: Vec<Frame> = (1..=frames)
                    .map(|i| frame_at(&base, overlay, frames + i))
                    .collect();
                let mut stages = StageTimes::default();
                for frame in &split {
                    renderer.render_timed(frame, Some(&mut stages))?;
                }
                let per = |d: std::time::Duration| d.as_secs_f64() * 1e3 / f64::from(frames);
                rows.push(BenchRow {
                    width,
                    height,
                    msaa: renderer.msaa(),
                    overlay,
                    mesh,
                    scale,
                    psnr_db,
                    fps: 1.0 / frame_s,
                    frame_ms: frame_s * 1e3,
                    draw_ms: per(stages.draw),
                    resolve_ms: per(stages.resolve),
                    overlay_cpu_ms: per(stages.overlay_cpu),
                    readback_ms: per(stages.readback),
                });
                progress(rows.len(), total);
            }
        }
    }
    Ok(BenchTable { adapter, rows })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_text_has_a_line_per_row() {
        let row = BenchRow {
            width: 640,
            height: 480,
            msaa: 4,
            overlay: OverlayMode::On,
            mesh: TissueMesh::Graded,
            scale: 1.0,
            psnr_db: None,
            fps: 50.0,
            frame_ms: 20.0,
            draw_ms: 12.0,
            resolve_ms: 3.0,
            overlay_cpu_ms: 1.0,
            readback_ms: 4.0,
        };
        let table = BenchTable {
            adapter: "test".into(),
            rows: vec![
                row.clone(),
                BenchRow {
                    overlay: OverlayMode::Off,
                    mesh: TissueMesh::Uniform,
                    ..row.clone()
                },
                BenchRow {
                    overlay: OverlayMode::Live,
                    scale: 0.5,
                    psnr_db: Some(31.25),
                    ..row
                },
            ],
        };
        let markdown = table.to_markdown();
        assert_eq!(markdown.lines().count(), 5);
        assert!(
            markdown
                .contains("| 640×480 | 4 | on | graded | 1 | — | 50.0 | 20.0 | 12.0 | 3.00 | 1.00 | 4.00 |")
        );
        assert!(markdown.contains("| live | graded | 0.5 | 31.2 |"));
        let text = table.to_text();
        assert_eq!(text.lines().count(), 5);
        assert!(
            text.contains("640×480")
                && text.contains("50.0")
                && text.contains(" on ")
                && text.contains(" off ")
                && text.contains(" live ")
                && text.contains("31.2")
                && text.contains(" 0.5 ")
                && text.contains(" graded ")
                && text.contains(" uniform ")
        );
    }
}
