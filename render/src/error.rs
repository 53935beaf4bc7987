//! The renderer's typed errors.

use std::path::PathBuf;

/// Why a picture could not be made or stored.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// No GPU adapter on any backend that was tried.
    #[error(
        "no GPU adapter found (tried {tried}). For software rendering install the Vulkan driver: \
         `apt-get install mesa-vulkan-drivers libvulkan1` (Debian/Ubuntu; `vulkaninfo --summary` \
         from `vulkan-tools` should then list llvmpipe). Details: {details}"
    )]
    NoAdapter {
        /// The backends in the order tried, e.g. "Vulkan, then GL".
        tried: String,
        /// What each backend reported.
        details: String,
    },
    #[error("could not open the GPU device on {adapter}: {source}")]
    RequestDevice {
        adapter: String,
        #[source]
        source: wgpu::RequestDeviceError,
    },
    #[error("image size {width}×{height} px is invalid (each side 1..={max} px)")]
    BadSize { width: u32, height: u32, max: u32 },
    #[error("MSAA sample count {0} is not supported; use 1 or 4")]
    BadMsaa(u32),
    #[error("the GPU reported an error: {0}")]
    Gpu(String),
    #[error("reading back the rendered image failed: {0}")]
    Readback(String),
    #[error("{path}: {reason}")]
    Io {
        path: PathBuf,
        reason: String,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: PNG encoding failed: {reason}")]
    PngEncode { path: PathBuf, reason: String },
    #[error("{path}: PNG decoding failed: {reason}")]
    PngDecode { path: PathBuf, reason: String },
    #[error("{what}: pixel data has {got} bytes, expected {expected}")]
    PixelCount {
        what: String,
        got: usize,
        expected: usize,
    },
    #[error("window: {0}")]
    Window(String),
}
