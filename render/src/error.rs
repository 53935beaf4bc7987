//! The renderer's one error type: GPU and window failures, image and mesh files, golden checks.

use std::path::PathBuf;

/// Environment variable that, set to `1`, makes [`crate::golden::check`] rewrite the golden
/// instead of comparing. Defined here because the missing-golden message names it.
pub const BLESS_ENV: &str = "PALPUS_BLESS";

/// Why a picture or a mesh could not be made, read or stored, or why a golden check failed.
/// Every variant that involves a file names it.
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
    /// The adapter was found but refused to open a device.
    #[error("could not open the GPU device on {adapter}: {source}")]
    RequestDevice {
        /// The adapter's name and backend.
        adapter: String,
        /// What wgpu reported.
        #[source]
        source: wgpu::RequestDeviceError,
    },
    /// A requested image size is zero or larger than the device allows.
    #[error("image size {width}×{height} px is invalid (each side 1..={max} px)")]
    BadSize {
        /// Requested width, px.
        width: u32,
        /// Requested height, px.
        height: u32,
        /// The largest side the device supports, px.
        max: u32,
    },
    /// An MSAA sample count other than 1 or 4.
    #[error("MSAA sample count {0} is not supported; use 1 or 4")]
    BadMsaa(u32),
    /// An internal resolution scale outside 0.25..=1.
    #[error("render scale {0} is not supported; use a value from 0.25 to 1")]
    BadScale(f32),
    /// A validation or out-of-memory error caught from the GPU.
    #[error("the GPU reported an error: {0}")]
    Gpu(String),
    /// Mapping the rendered image back to the CPU failed.
    #[error("reading back the rendered image failed: {0}")]
    Readback(String),
    /// The file does not exist.
    #[error("{path}: file not found")]
    NotFound {
        /// The file.
        path: PathBuf,
    },
    /// Any other I/O failure while reading or writing a file or creating its directory.
    #[error("{path}: {reason}")]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// What was being done, or what the system reported.
        reason: String,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The PNG encoder failed.
    #[error("{path}: PNG encoding failed: {reason}")]
    PngEncode {
        /// The file being written.
        path: PathBuf,
        /// What the encoder reported.
        reason: String,
    },
    /// The file is not an 8-bit PNG this crate can read.
    #[error("{path}: PNG decoding failed: {reason}")]
    PngDecode {
        /// The file.
        path: PathBuf,
        /// What the decoder reported.
        reason: String,
    },
    /// Pixel data whose length does not match the image size.
    #[error("{what}: pixel data has {got} bytes, expected {expected}")]
    PixelCount {
        /// Whose pixels.
        what: String,
        /// Bytes given.
        got: usize,
        /// `width * height * 4`.
        expected: usize,
    },
    /// The window or its event loop failed.
    #[error("window: {0}")]
    Window(String),
    /// The bytes are not a valid glTF document.
    #[error("{path}: not a valid glTF file: {reason}")]
    NotGltf {
        /// The file.
        path: PathBuf,
        /// What the parser or validator reported.
        reason: String,
    },
    /// A buffer's URI cannot be read: not a relative file path or a base64 `data:` URI, its
    /// file is missing or unreadable, or its data does not decode.
    #[error("{path}: buffer {buffer} ({uri}): {reason}")]
    BufferUri {
        /// The file.
        path: PathBuf,
        /// The buffer's index.
        buffer: usize,
        /// The buffer's URI (a `data:` URI cut after its header).
        uri: String,
        /// Why it cannot be read.
        reason: String,
    },
    /// The binary chunk (or the buffer's file or data) is missing or shorter than the buffer
    /// it must hold.
    #[error("{path}: buffer {buffer} holds {actual} bytes, it declares {expected}")]
    TruncatedBuffer {
        /// The file.
        path: PathBuf,
        /// The buffer's index.
        buffer: usize,
        /// Bytes the buffer declares.
        expected: usize,
        /// Bytes present.
        actual: usize,
    },
    /// A primitive has no POSITION attribute.
    #[error("{path}: mesh '{mesh}' has a primitive without POSITION")]
    MissingPositions {
        /// The file.
        path: PathBuf,
        /// The node or mesh name.
        mesh: String,
    },
    /// An attribute's accessor cannot be read as the expected type or lies outside its buffer.
    #[error("{path}: mesh '{mesh}': attribute {attribute} cannot be read")]
    BadAccessor {
        /// The file.
        path: PathBuf,
        /// The node or mesh name.
        mesh: String,
        /// The attribute (`POSITION`, `NORMAL`, `COLOR_0`, `indices`).
        attribute: &'static str,
    },
    /// An attribute's vertex count differs from POSITION's.
    #[error("{path}: mesh '{mesh}': {attribute} has {actual} entries, POSITION has {expected}")]
    AttributeCount {
        /// The file.
        path: PathBuf,
        /// The node or mesh name.
        mesh: String,
        /// The attribute.
        attribute: &'static str,
        /// POSITION's count.
        expected: usize,
        /// The attribute's count.
        actual: usize,
    },
    /// A primitive is not a triangle list.
    #[error("{path}: mesh '{mesh}' has a {mode} primitive; only triangle lists are supported")]
    NonTriangle {
        /// The file.
        path: PathBuf,
        /// The node or mesh name.
        mesh: String,
        /// The primitive's mode, e.g. `Lines`.
        mode: String,
    },
    /// The index count is not a multiple of three.
    #[error("{path}: mesh '{mesh}' has {count} indices, not a multiple of 3")]
    PartialTriangle {
        /// The file.
        path: PathBuf,
        /// The node or mesh name.
        mesh: String,
        /// The number of indices.
        count: usize,
    },
    /// An index points past the last vertex.
    #[error("{path}: mesh '{mesh}': index {index} out of range for {vertex_count} vertices")]
    IndexOutOfRange {
        /// The file.
        path: PathBuf,
        /// The node or mesh name.
        mesh: String,
        /// The offending index.
        index: u32,
        /// The number of vertices.
        vertex_count: usize,
    },
    /// A mesh to be written has no vertices or no triangles (glTF accessors need count ≥ 1).
    #[error("{path}: mesh '{mesh}' is empty")]
    EmptyMesh {
        /// The file.
        path: PathBuf,
        /// The mesh name.
        mesh: String,
    },
    /// A mesh to be written holds NaN or infinite values.
    #[error("{path}: mesh '{mesh}': {attribute} holds a non-finite value")]
    NonFinite {
        /// The file.
        path: PathBuf,
        /// The mesh name.
        mesh: String,
        /// The attribute.
        attribute: &'static str,
    },
    /// The meshes do not fit the 32-bit sizes glTF uses.
    #[error("{path}: meshes too large for a .glb file")]
    TooLarge {
        /// The file.
        path: PathBuf,
    },
    /// Too many pixels differ from the golden image.
    #[error(
        "{name}: {differing} of {total} pixels ({percent:.3} %) differ by more than {threshold} \
         (allowed {allowed:.3} %); actual and diff written to {dir}"
    )]
    GoldenMismatch {
        /// The golden's name.
        name: String,
        /// Pixels over the threshold.
        differing: usize,
        /// Pixels compared.
        total: usize,
        /// `differing / total` in percent.
        percent: f64,
        /// The per-channel threshold.
        threshold: u8,
        /// The allowed percentage.
        allowed: f64,
        /// Where the actual image and the diff went.
        dir: PathBuf,
    },
    /// The image and its golden differ in size.
    #[error(
        "{name}: size {actual_w}×{actual_h} differs from golden {golden_w}×{golden_h}; actual written to {dir}"
    )]
    GoldenSizeMismatch {
        /// The golden's name.
        name: String,
        /// The image's width, px.
        actual_w: u32,
        /// The image's height, px.
        actual_h: u32,
        /// The golden's width, px.
        golden_w: u32,
        /// The golden's height, px.
        golden_h: u32,
        /// Where the actual image went.
        dir: PathBuf,
    },
    /// There is no golden image to compare with.
    #[error("golden {path} is missing; run with {BLESS_ENV}=1 to create it (actual written to {dir})")]
    GoldenMissing {
        /// The golden that should exist.
        path: PathBuf,
        /// Where the actual image went.
        dir: PathBuf,
    },
}
