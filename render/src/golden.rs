//! Golden-image comparison with a tolerance: software rasterizers differ in the last bit across
//! CPU SIMD widths, so a test counts the pixels that differ noticeably instead of demanding
//! identical bytes.

use std::path::Path;

pub use crate::error::BLESS_ENV;
use crate::error::RenderError;
use crate::image::Image;

/// How different two images may be.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerance {
    /// A pixel differs when any channel differs by more than this.
    pub channel_threshold: u8,
    /// The comparison fails when more than this fraction (0..1) of pixels differ.
    pub max_fraction: f64,
}

impl Default for Tolerance {
    fn default() -> Self {
        Tolerance {
            channel_threshold: 24,
            max_fraction: 0.005,
        }
    }
}

/// The result of comparing two images of the same size.
#[derive(Debug, Clone, PartialEq)]
pub struct Comparison {
    pub differing_pixels: usize,
    pub total_pixels: usize,
    pub max_channel_diff: u8,
    /// A visualisation: differing pixels red, others a dimmed copy of the expected image.
    pub diff: Image,
}

impl Comparison {
    pub fn fraction(&self) -> f64 {
        self.differing_pixels as f64 / self.total_pixels.max(1) as f64
    }
}

/// Peak signal-to-noise ratio of `actual` against `reference` over the RGB channels, dB
/// (infinite for identical images); `None` when the sizes differ.
pub fn psnr_db(actual: &Image, reference: &Image) -> Option<f64> {
    if actual.width != reference.width || actual.height != reference.height {
        return None;
    }
    let (sum, n) = actual
        .rgba
        .chunks_exact(4)
        .zip(reference.rgba.chunks_exact(4))
        .flat_map(|(a, r)| a[..3].iter().zip(&r[..3]))
        .fold((0.0f64, 0usize), |(s, n), (a, r)| {
            let d = f64::from(*a) - f64::from(*r);
            (s + d * d, n + 1)
        });
    let mse = sum / n.max(1) as f64;
    Some(if mse == 0.0 {
        f64::INFINITY
    } else {
        10.0 * (255.0f64 * 255.0 / mse).log10()
    })
}

/// Compares two images pixel by pixel; `None` when their sizes differ.
pub fn compare(actual: &Image, expected: &Image, channel_threshold: u8) -> Option<Comparison> {
    if actual.width != expected.width || actual.height != expected.height {
        return None;
    }
    let mut differing = 0;
    let mut max_diff = 0u8;
    let mut diff = Vec::with_capacity(expected.rgba.len());
    for (a, e) in actual.rgba.chunks_exact(4).zip(expected.rgba.chunks_exact(4)) {
        let d = a.iter().zip(e).map(|(x, y)| x.abs_diff(*y)).max().unwrap_or(0);
        max_diff = max_diff.max(d);
        if d > channel_threshold {
            differing += 1;
            diff.extend_from_slice(&[255, 0, 0, 255]);
        } else {
            diff.extend_from_slice(&[e[0] / 4, e[1] / 4, e[2] / 4, 255]);
        }
    }
    let diff = Image {
        width: expected.width,
        height: expected.height,
        rgba: diff,
    };
    Some(Comparison {
        differing_pixels: differing,
        total_pixels: expected.width as usize * expected.height as usize,
        max_channel_diff: max_diff,
        diff,
    })
}

/// Whether the bless variable asks for goldens to be rewritten.
pub fn bless_requested() -> bool {
    std::env::var(BLESS_ENV).is_ok_and(|v| v == "1")
}

/// Compares `actual` with `golden_dir/name.png`. With [`BLESS_ENV`]`=1` it writes the golden
/// instead. On failure `name.actual.png` and `name.diff.png` go to `failure_dir`.
pub fn check(
    name: &str,
    actual: &Image,
    golden_dir: &Path,
    failure_dir: &Path,
    tolerance: Tolerance,
) -> Result<Option<Comparison>, RenderError> {
    let golden_path = golden_dir.join(format!("{name}.png"));
    if bless_requested() {
        actual.save_png(&golden_path)?;
        return Ok(None);
    }
    let actual_path = failure_dir.join(format!("{name}.actual.png"));
    if !golden_path.exists() {
        actual.save_png(&actual_path)?;
        return Err(RenderError::GoldenMissing {
            path: golden_path,
            dir: failure_dir.to_path_buf(),
        });
    }
    let expected = Image::load_png(&golden_path)?;
    let Some(cmp) = compare(actual, &expected, tolerance.channel_threshold) else {
        actual.save_png(&actual_path)?;
        return Err(RenderError::GoldenSizeMismatch {
            name: name.into(),
            actual_w: actual.width,
            actual_h: actual.height,
            golden_w: expected.width,
            golden_h: expected.height,
            dir: failure_dir.to_path_buf(),
        });
    };
    if cmp.fraction() > tolerance.max_fraction {
        actual.save_png(&actual_path)?;
        cmp.diff.save_png(&failure_dir.join(format!("{name}.diff.png")))?;
        return Err(RenderError::GoldenMismatch {
            name: name.into(),
            differing: cmp.differing_pixels,
            total: cmp.total_pixels,
            percent: cmp.fraction() * 100.0,
            threshold: tolerance.channel_threshold,
            allowed: tolerance.max_fraction * 100.0,
            dir: failure_dir.to_path_buf(),
        });
    }
    Ok(Some(cmp))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn solid(w: u32, h: u32, v: u8) -> Image {
        Image::from_rgba(w, h, vec![v; (w * h * 4) as usize]).unwrap()
    }

    #[test]
    fn counts_pixels_over_threshold_only() {
        let a = solid(4, 4, 100);
        let mut b = solid(4, 4, 100);
        b.rgba[0] = 110; // within threshold 24
        b.rgba[5] = 200; // pixel 1 differs
        b.rgba[10] = 0; // pixel 2 differs
        let cmp = compare(&a, &b, 24).unwrap();
        assert_eq!(cmp.differing_pixels, 2);
        assert_eq!(cmp.max_channel_diff, 100);
        assert!((cmp.fraction() - 2.0 / 16.0).abs() < 1e-12);
        assert_eq!(cmp.diff.pixel(1, 0), Some([255, 0, 0, 255]));
        assert_eq!(cmp.diff.pixel(0, 0), Some([27, 25, 25, 255]));
    }

    #[test]
    fn size_mismatch_is_none() {
        assert!(compare(&solid(2, 2, 0), &solid(2, 3, 0), 0).is_none());
    }

    #[test]
    fn mismatch_writes_actual_and_diff() {
        let dir = tempfile::tempdir().unwrap();
        let golden = dir.path().join("golden");
        let fail = dir.path().join("fail");
        solid(8, 8, 0).save_png(&golden.join("x.png")).unwrap();
        if bless_requested() {
            return;
        }
        let err = check("x", &solid(8, 8, 255), &golden, &fail, Tolerance::default()).unwrap_err();
        assert!(
            matches!(err, RenderError::GoldenMismatch { differing: 64, .. }),
            "{err}"
        );
        assert!(fail.join("x.actual.png").exists() && fail.join("x.diff.png").exists());
        let ok = check("x", &solid(8, 8, 10), &golden, &fail, Tolerance::default()).unwrap();
        assert_eq!(ok.unwrap().differing_pixels, 0);
    }
}
