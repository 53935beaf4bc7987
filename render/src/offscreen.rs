//! The offscreen target of headless rendering: a colour texture frames are drawn into, and its
//! copy back to the CPU as an [`Image`] (rows unpadded from wgpu's 256-byte copy alignment,
//! BGRA swapped to RGBA).

use crate::error::RenderError;
use crate::image::Image;

/// A colour texture of one size and the buffer it is read back through.
pub(crate) struct Offscreen {
    /// Width and height, px.
    pub(crate) size: [u32; 2],
    /// What frames are drawn into.
    pub(crate) texture: wgpu::Texture,
    readback: wgpu::Buffer,
    padded_row_bytes: u32,
}

/// A single-sampled 2-D texture of `size` px without mipmaps, as every target here is.
pub(crate) fn texture_2d(
    device: &wgpu::Device,
    label: &str,
    size: [u32; 2],
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: size[0],
            height: size[1],
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

impl Offscreen {
    /// A target of `size` px in `format`.
    pub(crate) fn new(device: &wgpu::Device, format: wgpu::TextureFormat, size: [u32; 2]) -> Self {
        // COPY_DST: the overlay's panel is copied in.
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::COPY_DST;
        let texture = texture_2d(device, "offscreen colour", size, format, usage);
        let padded_row_bytes = (size[0] * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: u64::from(padded_row_bytes) * u64::from(size[1]),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        Self {
            size,
            texture,
            readback,
            padded_row_bytes,
        }
    }

    /// Copies the texture to the CPU, waiting for the GPU.
    pub(crate) fn read(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<Image, RenderError> {
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("readback"),
        });
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &self.texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &self.readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(self.padded_row_bytes),
                    rows_per_image: Some(self.size[1]),
                },
            },
            wgpu::Extent3d {
                width: self.size[0],
                height: self.size[1],
                depth_or_array_layers: 1,
            },
        );
        queue.submit([encoder.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        let slice = self.readback.slice(..);
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        crate::gpu::wait(device)?;
        rx.recv()
            .map_err(|e| RenderError::Readback(e.to_string()))?
            .map_err(|e| RenderError::Readback(e.to_string()))?;
        let row_bytes = self.size[0] as usize * 4;
        let mut rgba = Vec::with_capacity(row_bytes * self.size[1] as usize);
        {
            let mapped = slice
                .get_mapped_range()
                .map_err(|e| RenderError::Readback(e.to_string()))?;
            if self.padded_row_bytes as usize == row_bytes {
                // Rows need no unpadding (widths that are multiples of 64 px): one copy.
                rgba.extend_from_slice(&mapped[..row_bytes * self.size[1] as usize]);
            } else {
                for row in mapped
                    .chunks(self.padded_row_bytes as usize)
                    .take(self.size[1] as usize)
                {
                    rgba.extend_from_slice(&row[..row_bytes]);
                }
            }
        }
        self.readback.unmap();
        if matches!(
            self.texture.format(),
            wgpu::TextureFormat::Bgra8UnormSrgb | wgpu::TextureFormat::Bgra8Unorm
        ) {
            for px in rgba.chunks_exact_mut(4) {
                px.swap(0, 2);
            }
        }
        Image::from_rgba(self.size[0], self.size[1], rgba)
    }
}
