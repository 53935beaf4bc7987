//! Finding a GPU: Vulkan first (Mesa lavapipe renders in software when there is no GPU), then GL.

use std::sync::{Arc, Mutex};

use crate::error::RenderError;

/// The depth buffer's format: every render pass and the adapter check share it.
pub(crate) const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// A graphics API wgpu may use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Backend {
    Vulkan,
    Gl,
}

impl Backend {
    pub(crate) fn wgpu(self) -> wgpu::Backends {
        match self {
            Backend::Vulkan => wgpu::Backends::VULKAN,
            Backend::Gl => wgpu::Backends::GL,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Backend::Vulkan => "Vulkan",
            Backend::Gl => "GL",
        }
    }
}

/// Which backends to try, in order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GpuOptions {
    pub backends: Vec<Backend>,
}

impl Default for GpuOptions {
    fn default() -> Self {
        GpuOptions {
            backends: vec![Backend::Vulkan, Backend::Gl],
        }
    }
}

/// An open device and what it runs on.
#[derive(Debug, Clone)]
pub struct Gpu {
    pub(crate) adapter: wgpu::Adapter,
    pub(crate) device: wgpu::Device,
    pub(crate) queue: wgpu::Queue,
    /// Errors outside any error scope (out of memory, device lost). wgpu's default handler
    /// panics; these are kept and returned by the next draw instead.
    uncaptured: Arc<Mutex<Option<String>>>,
}

impl Gpu {
    /// Opens the first adapter found on the backends of `options`, for offscreen rendering.
    pub fn headless(options: &GpuOptions) -> Result<Self, RenderError> {
        Self::open(Self::headless_adapter(options)?)
    }

    fn headless_adapter(options: &GpuOptions) -> Result<wgpu::Adapter, RenderError> {
        let mut tried = Vec::new();
        let mut details = Vec::new();
        for &backend in &options.backends {
            tried.push(backend.name());
            let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
            desc.backends = backend.wgpu();
            let instance = wgpu::Instance::new(desc);
            let request = wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                force_fallback_adapter: false,
                compatible_surface: None,
                apply_limit_buckets: false,
            };
            match pollster::block_on(instance.request_adapter(&request)) {
                Ok(adapter) => return Ok(adapter),
                Err(e) => details.push(format!("{}: {e}", backend.name())),
            }
        }
        Err(no_adapter(&tried, &details))
    }

    /// Opens the device on an adapter already chosen (the window picks one that can present).
    pub(crate) fn open(adapter: wgpu::Adapter) -> Result<Self, RenderError> {
        let info = adapter.get_info();
        // Downlevel limits raised to what the adapter allows keep the GL fallback usable while
        // still permitting large images on Vulkan.
        let required_limits = wgpu::Limits::downlevel_webgl2_defaults().using_resolution(adapter.limits());
        let desc = wgpu::DeviceDescriptor {
            label: Some("palpus"),
            required_features: wgpu::Features::empty(),
            required_limits,
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&desc)).map_err(|source| {
            RenderError::RequestDevice {
                adapter: format!("{} ({:?})", info.name, info.backend),
                source,
            }
        })?;
        let uncaptured = Arc::new(Mutex::new(None));
        let sink = Arc::clone(&uncaptured);
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut slot) = sink.lock() {
                slot.get_or_insert_with(|| e.to_string());
            }
        }));
        Ok(Gpu {
            adapter,
            device,
            queue,
            uncaptured,
        })
    }

    /// The first error reported outside an error scope since the last call, if any.
    pub(crate) fn take_uncaptured_error(&self) -> Option<String> {
        self.uncaptured.lock().ok().and_then(|mut slot| slot.take())
    }

    pub(crate) fn device_ref(&self) -> &wgpu::Device {
        &self.device
    }

    pub(crate) fn queue_ref(&self) -> &wgpu::Queue {
        &self.queue
    }

    /// "llvmpipe (LLVM …) on Vulkan" and the like.
    pub fn adapter_description(&self) -> String {
        let info = self.adapter.get_info();
        format!("{} on {:?} ({:?})", info.name, info.backend, info.device_type)
    }

    /// The largest MSAA sample count (1 or 4) not above `requested` that `format` supports here.
    pub(crate) fn supported_msaa(&self, format: wgpu::TextureFormat, requested: u32) -> u32 {
        let flags = self.adapter.get_texture_format_features(format).flags;
        let depth = self.adapter.get_texture_format_features(DEPTH_FORMAT).flags;
        if requested >= 4 && flags.sample_count_supported(4) && depth.sample_count_supported(4) {
            4
        } else {
            1
        }
    }

    /// Whether the adapter rasterizes on the CPU (lavapipe, llvmpipe).
    pub(crate) fn is_software(&self) -> bool {
        self.adapter.get_info().device_type == wgpu::DeviceType::Cpu
    }

    /// Whether a texture can be viewed both with and without its sRGB format.
    pub(crate) fn srgb_views(&self) -> bool {
        self.adapter
            .get_downlevel_capabilities()
            .flags
            .contains(wgpu::DownlevelFlags::VIEW_FORMATS)
    }
}

/// A clear colour from linear RGB, opaque.
pub(crate) fn opaque_colour([r, g, b]: [f32; 3]) -> wgpu::Color {
    wgpu::Color {
        r: f64::from(r),
        g: f64::from(g),
        b: f64::from(b),
        a: 1.0,
    }
}

pub(crate) fn no_adapter(tried: &[&str], details: &[String]) -> RenderError {
    let tried = if tried.is_empty() {
        "no backends".to_string()
    } else {
        tried.join(", then ")
    };
    let details = if details.is_empty() {
        "none".to_string()
    } else {
        details.join("; ")
    };
    RenderError::NoAdapter { tried, details }
}

/// Waits until the GPU has finished all submitted work.
pub(crate) fn wait(device: &wgpu::Device) -> Result<(), RenderError> {
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map(|_| ())
        .map_err(|e| RenderError::Gpu(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_adapter_message_names_packages_and_backends() {
        let msg = no_adapter(&["Vulkan", "GL"], &["Vulkan: none".into()]).to_string();
        assert!(msg.contains("mesa-vulkan-drivers"), "{msg}");
        assert!(msg.contains("libvulkan1"), "{msg}");
        assert!(msg.contains("Vulkan, then GL"), "{msg}");
    }
}
