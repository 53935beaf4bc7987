//! CPU images: what headless rendering returns and screenshots store.

use std::fs::File;
use std::io::{BufReader, Write};
use std::path::Path;

use capture::write_atomically;

use crate::error::RenderError;

/// An RGBA8 image in sRGB encoding, rows top to bottom, no padding.
#[derive(Clone, PartialEq, Eq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    /// `width * height * 4` bytes.
    pub rgba: Vec<u8>,
}

impl std::fmt::Debug for Image {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Image")
            .field("width", &self.width)
            .field("height", &self.height)
            .finish()
    }
}

impl Image {
    /// Wraps pixel data, checking that its length matches the size.
    pub fn from_rgba(width: u32, height: u32, rgba: Vec<u8>) -> Result<Self, RenderError> {
        let expected = width as usize * height as usize * 4;
        if rgba.len() != expected {
            return Err(RenderError::PixelCount {
                what: "image".into(),
                got: rgba.len(),
                expected,
            });
        }
        Ok(Image { width, height, rgba })
    }

    /// The RGBA bytes of pixel (x, y), or `None` outside the image.
    pub fn pixel(&self, x: u32, y: u32) -> Option<[u8; 4]> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let i = (y as usize * self.width as usize + x as usize) * 4;
        let p = self.rgba.get(i..i + 4)?;
        Some([p[0], p[1], p[2], p[3]])
    }

    /// Writes a PNG (creating its directory) through [`write_atomically`], so a reader never
    /// sees a half-written image and a failed write keeps the previous one.
    pub fn save_png(&self, path: &Path) -> Result<(), RenderError> {
        let io_err = |reason: &str, source| RenderError::Io {
            path: path.to_path_buf(),
            reason: reason.into(),
            source,
        };
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| io_err("cannot create directory", e))?;
        }
        // Encoded in memory first so that encoder failures and file failures stay distinct.
        let bytes = self.encode_png(path)?;
        write_atomically(path, |out| out.write_all(&bytes)).map_err(|e| io_err("cannot write", e))
    }

    fn encode_png(&self, path: &Path) -> Result<Vec<u8>, RenderError> {
        let mut bytes = Vec::new();
        let mut encoder = png::Encoder::new(&mut bytes, self.width, self.height);
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        let enc_err = |e: png::EncodingError| RenderError::PngEncode {
            path: path.to_path_buf(),
            reason: e.to_string(),
        };
        let mut png_writer = encoder.write_header().map_err(enc_err)?;
        png_writer.write_image_data(&self.rgba).map_err(enc_err)?;
        png_writer.finish().map_err(enc_err)?;
        Ok(bytes)
    }

    /// Reads an 8-bit RGB or RGBA PNG (RGB gets opaque alpha).
    pub fn load_png(path: &Path) -> Result<Self, RenderError> {
        let file = File::open(path).map_err(|source| RenderError::Io {
            path: path.to_path_buf(),
            reason: "cannot open".into(),
            source,
        })?;
        let dec_err = |reason: String| RenderError::PngDecode {
            path: path.to_path_buf(),
            reason,
        };
        let mut decoder = png::Decoder::new(BufReader::new(file));
        decoder.set_transformations(png::Transformations::EXPAND);
        let mut reader = decoder.read_info().map_err(|e| dec_err(e.to_string()))?;
        let size = reader
            .output_buffer_size()
            .ok_or_else(|| dec_err("image too large".into()))?;
        let mut buf = vec![0; size];
        let info = reader.next_frame(&mut buf).map_err(|e| dec_err(e.to_string()))?;
        if info.bit_depth != png::BitDepth::Eight {
            return Err(dec_err(format!("bit depth {:?}, expected 8", info.bit_depth)));
        }
        buf.truncate(info.buffer_size());
        let rgba = match info.color_type {
            png::ColorType::Rgba => buf,
            png::ColorType::Rgb => buf
                .chunks_exact(3)
                .flat_map(|p| [p[0], p[1], p[2], 255])
                .collect(),
            png::ColorType::Grayscale => buf.iter().flat_map(|&g| [g, g, g, 255]).collect(),
            png::ColorType::GrayscaleAlpha => buf
                .chunks_exact(2)
                .flat_map(|p| [p[0], p[0], p[0], p[1]])
                .collect(),
            other => return Err(dec_err(format!("colour type {other:?} not supported"))),
        };
        Image::from_rgba(info.width, info.height, rgba).map_err(|e| dec_err(e.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_round_trip_keeps_pixels() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sub/x.png");
        let rgba: Vec<u8> = (0..3 * 2 * 4).map(|i| (i * 11) as u8).collect();
        let img = Image::from_rgba(3, 2, rgba).unwrap();
        img.save_png(&path).unwrap();
        let back = Image::load_png(&path).unwrap();
        assert_eq!(back, img);
        assert_eq!(back.pixel(2, 1), Some([220, 231, 242, 253]));
        assert_eq!(back.pixel(3, 0), None);
        let leftovers: Vec<_> = std::fs::read_dir(path.parent().unwrap()).unwrap().collect();
        assert_eq!(leftovers.len(), 1, "temporary file left behind");
    }

    #[test]
    fn wrong_pixel_count_is_an_error() {
        assert!(matches!(
            Image::from_rgba(2, 2, vec![0; 15]),
            Err(RenderError::PixelCount { expected: 16, .. })
        ));
    }

    #[test]
    fn loading_a_non_png_names_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.png");
        std::fs::write(&path, b"not a png").unwrap();
        let err = Image::load_png(&path).unwrap_err().to_string();
        assert!(err.contains("bad.png"), "{err}");
    }
}
