//! The wgpu device, found with a clear message when there is none.

/// What to install when no adapter is found.
pub const NO_ADAPTER_HELP: &str = "no GPU adapter found. raylab needs Vulkan, OpenGL ES or Metal; without a GPU, \
     install Mesa's software Vulkan driver (lavapipe): on Debian or Ubuntu `apt-get install mesa-vulkan-drivers \
     libvulkan1`";

/// Adapter, device and queue.
pub struct Gpu {
    /// The adapter in use.
    pub adapter: wgpu::Adapter,
    /// The logical device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
}

impl Gpu {
    /// An instance for `display` (a window system connection) or for offscreen use.
    pub fn instance(display: Option<Box<dyn wgpu::wgt::WgpuHasDisplayHandle>>) -> wgpu::Instance {
        let desc = match display {
            Some(d) => wgpu::InstanceDescriptor::new_with_display_handle_from_env(d),
            None => wgpu::InstanceDescriptor::new_without_display_handle_from_env(),
        };
        wgpu::Instance::new(desc)
    }

    /// Picks an adapter able to present to `surface` (any adapter when `None`) and opens a device with the
    /// lowest limits every backend supports.
    pub fn new(instance: &wgpu::Instance, surface: Option<&wgpu::Surface<'_>>) -> Result<Self, String> {
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: surface,
            ..Default::default()
        }))
        .map_err(|e| format!("{NO_ADAPTER_HELP} ({e})"))?;
        let limits = wgpu::Limits::downlevel_webgl2_defaults().using_resolution(adapter.limits());
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("raylab"),
            required_limits: limits,
            ..Default::default()
        }))
        .map_err(|e| format!("cannot open the GPU device ({}): {e}", adapter.get_info().name))?;
        Ok(Self { adapter, device, queue })
    }

    /// A line naming the adapter and backend, for the panel and the stats file.
    pub fn describe(&self) -> String {
        let i = self.adapter.get_info();
        format!("{} ({:?}, {:?})", i.name, i.backend, i.device_type)
    }
}
