//! Screenshots of the whole window: the same draw as the window's, into an offscreen texture that is copied
//! to a buffer and read back (rows padded to wgpu's 256-byte copy alignment, BGRA swizzled to RGBA).

use crate::gpu::compositor::Compositor;
use crate::gpu::device::Gpu;

/// Draws the window's contents (the latest frame and the UI last handed to [`Compositor::prepare_egui`])
/// offscreen at `size` and returns them as an RGBA image.
pub fn capture(
    gpu: &Gpu,
    compositor: &mut Compositor,
    size: (u32, u32),
    screen: &egui_wgpu::ScreenDescriptor,
) -> Result<image::RgbaImage, String> {
    let (device, queue) = (&gpu.device, &gpu.queue);
    let (w, h) = (size.0.max(1), size.1.max(1));
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("screenshot"),
        size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: compositor.format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
    let row = (4 * w).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("screenshot readback"),
        size: u64::from(row) * u64::from(h),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("screenshot") });
    compositor.draw(gpu, &mut encoder, &view, (w, h), screen);
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture: &texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(row), rows_per_image: Some(h) },
        },
        wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
    );
    queue.submit([encoder.finish()]);
    let slice = buffer.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        // The receiver waits below; it cannot be gone.
        let _ = tx.send(r);
    });
    device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| format!("screenshot: GPU wait failed: {e}"))?;
    rx.recv()
        .map_err(|_| "screenshot: the GPU never answered".to_string())?
        .map_err(|e| format!("screenshot: cannot read the image back: {e}"))?;
    let bgra = matches!(compositor.format, wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb);
    let mut pixels = Vec::with_capacity((4 * w * h) as usize);
    {
        let data = slice.get_mapped_range().map_err(|e| format!("screenshot: cannot read the image back: {e}"))?;
        for y in 0..h as usize {
            let line = &data[y * row as usize..][..4 * w as usize];
            for px in line.chunks_exact(4) {
                if bgra {
                    pixels.extend_from_slice(&[px[2], px[1], px[0], px[3]]);
                } else {
                    pixels.extend_from_slice(px);
                }
            }
        }
    }
    buffer.unmap();
    image::RgbaImage::from_raw(w, h, pixels).ok_or_else(|| "screenshot: image size mismatch".to_string())
}
