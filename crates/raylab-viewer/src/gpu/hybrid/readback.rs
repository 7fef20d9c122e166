//! Reading the G-buffer back to the CPU through staging buffers (seed 003's pixel-buffer objects): each frame
//! copies the normal target (normal and, for reflective pixels, distance from the eye: all the CPU needs,
//! 16 bytes a pixel) into one of two buffers and maps it; with asynchronous readback the CPU reads the buffer
//! the GPU finished a frame earlier while the next copy goes into the other, so neither side waits (at the
//! price of one frame of latency); with synchronous readback it waits for this frame's copy. Reading
//! host-visible memory the GPU wrote is slow on discrete GPUs (about 2 GB/s on an H100 machine), so the
//! fewer bytes the better, and the mapped buffer is read once: only the reflective pixels are kept.

use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};

use glam::Vec3;
use raylab_core::render::hybrid::GPixel;
use raylab_core::scene::CameraRaster;

use super::gbuffer::Targets;

/// Bytes per G-buffer texel (four 32-bit floats).
const TEXEL: u32 = 16;

/// Map state of a slot.
const IDLE: u8 = 0;
const PENDING: u8 = 1;
const MAPPED: u8 = 2;
const FAILED: u8 = 3;

/// A staging buffer holding one frame's normal target.
struct Slot {
    buffer: wgpu::Buffer,
    size: (u32, u32),
    row: u32,
    /// The buffer's mapping: PENDING until its callback ran.
    state: Arc<AtomicU8>,
}

/// Two staging slots used in turn.
#[derive(Default)]
pub struct Readback {
    slots: [Option<Slot>; 2],
    next: usize,
}

impl Readback {
    /// Records copies of `targets` into the next free slot and returns its index. A slot still being read
    /// (asynchronous readback that fell behind) is waited for first.
    pub fn record(&mut self, device: &wgpu::Device, encoder: &mut wgpu::CommandEncoder, targets: &Targets) -> usize {
        let i = self.next;
        self.next = (self.next + 1) % 2;
        if let Some(s) = &self.slots[i]
            && s.state.load(Ordering::Acquire) != IDLE
        {
            // Drop what the CPU never read: wait for the mapping to finish, then release it.
            while s.state.load(Ordering::Acquire) == PENDING {
                let _ = device.poll(wgpu::PollType::wait_indefinitely());
            }
            s.buffer.unmap();
            s.state.store(IDLE, Ordering::Release);
        }
        let (w, h) = targets.size;
        if self.slots[i].as_ref().is_none_or(|s| s.size != (w, h)) {
            let row = (TEXEL * w).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("gbuffer normal readback"),
                size: u64::from(row) * u64::from(h),
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            });
            self.slots[i] = Some(Slot { buffer, size: (w, h), row, state: Arc::new(AtomicU8::new(IDLE)) });
        }
        let Some(s) = &self.slots[i] else { return i };
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &targets.normal,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &s.buffer,
                layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(s.row), rows_per_image: Some(h) },
            },
            wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        );
        i
    }

    /// Starts mapping slot `i` (after the copies recorded into it were submitted).
    pub fn map(&self, i: usize) {
        let Some(s) = &self.slots[i] else { return };
        s.state.store(PENDING, Ordering::Release);
        let state = Arc::clone(&s.state);
        s.buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            state.store(if r.is_err() { FAILED } else { MAPPED }, Ordering::Release);
        });
    }

    /// The G-buffer of slot `i` once it is mapped: waiting for it when `wait`, else `Ok(None)` while the GPU
    /// is not done. The slot is unmapped and free again afterwards.
    pub fn take(&mut self, device: &wgpu::Device, i: usize, wait: bool) -> Result<Option<GBufferImage>, String> {
        let Some(s) = &self.slots[i] else { return Ok(None) };
        let poll = if wait { wgpu::PollType::wait_indefinitely() } else { wgpu::PollType::Poll };
        loop {
            device.poll(poll.clone()).map_err(|e| format!("G-buffer readback: GPU wait failed: {e}"))?;
            match s.state.load(Ordering::Acquire) {
                MAPPED => break,
                FAILED => {
                    s.state.store(IDLE, Ordering::Release);
                    return Err("G-buffer readback: the GPU refused to map the staging buffer".into());
                }
                PENDING if wait => continue,
                _ => return Ok(None),
            }
        }
        let (w, h) = s.size;
        // One pass over the mapped rows (padded to the copy alignment; little-endian f32 texels, as the
        // host's), keeping the reflective pixels.
        let reflective = {
            let mapped = s.buffer.slice(..).get_mapped_range().map_err(|e| format!("G-buffer readback: {e}"))?;
            let mut reflective = Vec::new();
            for y in 0..h as usize {
                let row = &mapped[y * s.row as usize..y * s.row as usize + (w * TEXEL) as usize];
                let row: &[[f32; 4]] = bytemuck::try_cast_slice(row)
                    .map_err(|e| format!("G-buffer readback: unaligned staging buffer ({e})"))?;
                let first = (y * w as usize) as u32;
                reflective.extend((first..).zip(row).filter(|(_, t)| t[3] > 0.0).map(|(i, t)| GTexel {
                    index: i,
                    normal: Vec3::new(t[0], t[1], t[2]),
                    distance: t[3],
                }));
            }
            reflective
        };
        s.buffer.unmap();
        s.state.store(IDLE, Ordering::Release);
        Ok(Some(GBufferImage { width: w, height: h, reflective }))
    }
}

/// A reflective pixel of the G-buffer as read back.
#[derive(Clone, Copy, Debug)]
pub struct GTexel {
    /// Row-major index of the pixel from the top left.
    pub index: u32,
    /// Unit shading normal, turned toward the viewer.
    pub normal: Vec3,
    /// Distance from the eye along the pixel's primary ray.
    pub distance: f32,
}

/// A G-buffer read back to the CPU: its reflective pixels, the only ones the CPU traces.
#[derive(Clone, Debug)]
pub struct GBufferImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The reflective pixels in row-major order.
    pub reflective: Vec<GTexel>,
}

impl GBufferImage {
    /// Pixel `texel` as the CPU traces it, for the camera whose `raster` (of this image's size) drew the
    /// G-buffer: it lies on its primary ray at the distance the GPU wrote.
    pub fn pixel(&self, raster: &CameraRaster, texel: &GTexel) -> GPixel {
        let w = self.width.max(1);
        let ray = raster.primary(texel.index % w, texel.index / w);
        GPixel { position: ray.origin + ray.dir * texel.distance, normal: texel.normal, reflective: true }
    }
}
