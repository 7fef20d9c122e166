//! Reading the G-buffer back to the CPU through staging buffers (seed 003's pixel-buffer objects): each frame
//! copies the targets into one of two buffer pairs and maps it; with asynchronous readback the CPU reads the
//! pair the GPU finished a frame earlier while the next copy goes into the other pair, so neither side waits
//! (at the price of one frame of latency); with synchronous readback it waits for this frame's copy.

use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};

use glam::Vec3;
use raylab_core::render::hybrid::GPixel;

use super::gbuffer::Targets;

/// Bytes per G-buffer texel (four 32-bit floats).
const TEXEL: u32 = 16;

/// Map state of a slot.
const IDLE: u8 = 0;
const PENDING: u8 = 1;
const MAPPED: u8 = 2;
const FAILED: u8 = 3;

/// A pair of staging buffers holding one frame's G-buffer.
struct Slot {
    position: wgpu::Buffer,
    normal: wgpu::Buffer,
    size: (u32, u32),
    row: u32,
    /// Both buffers' mapping, counted: PENDING until both callbacks ran.
    state: Arc<AtomicU8>,
    left: Arc<AtomicU8>,
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
            s.position.unmap();
            s.normal.unmap();
            s.state.store(IDLE, Ordering::Release);
        }
        let (w, h) = targets.size;
        if self.slots[i].as_ref().is_none_or(|s| s.size != (w, h)) {
            let row = (TEXEL * w).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
            let buffer = |label| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: u64::from(row) * u64::from(h),
                    usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                    mapped_at_creation: false,
                })
            };
            self.slots[i] = Some(Slot {
                position: buffer("gbuffer position readback"),
                normal: buffer("gbuffer normal readback"),
                size: (w, h),
                row,
                state: Arc::new(AtomicU8::new(IDLE)),
                left: Arc::new(AtomicU8::new(0)),
            });
        }
        let Some(s) = &self.slots[i] else { return i };
        for (texture, buffer) in [(&targets.position, &s.position), (&targets.normal, &s.normal)] {
            encoder.copy_texture_to_buffer(
                wgpu::TexelCopyTextureInfo {
                    texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d::ZERO,
                    aspect: wgpu::TextureAspect::All,
                },
                wgpu::TexelCopyBufferInfo {
                    buffer,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(s.row),
                        rows_per_image: Some(h),
                    },
                },
                wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
            );
        }
        i
    }

    /// Starts mapping slot `i` (after the copies recorded into it were submitted).
    pub fn map(&self, i: usize) {
        let Some(s) = &self.slots[i] else { return };
        s.state.store(PENDING, Ordering::Release);
        s.left.store(2, Ordering::Release);
        for buffer in [&s.position, &s.normal] {
            let (state, left) = (Arc::clone(&s.state), Arc::clone(&s.left));
            buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| {
                if r.is_err() {
                    state.store(FAILED, Ordering::Release);
                } else if left.fetch_sub(1, Ordering::AcqRel) == 1 {
                    let _ = state.compare_exchange(PENDING, MAPPED, Ordering::AcqRel, Ordering::Acquire);
                }
            });
        }
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
        let texel = |t: &[u8]| -> [f32; 4] {
            std::array::from_fn(|k| f32::from_le_bytes([t[4 * k], t[4 * k + 1], t[4 * k + 2], t[4 * k + 3]]))
        };
        // One pass over both mapped buffers, row by row (rows are padded to the copy alignment).
        let pixels = {
            let position = s.position.slice(..).get_mapped_range().map_err(|e| format!("G-buffer readback: {e}"))?;
            let normal = s.normal.slice(..).get_mapped_range().map_err(|e| format!("G-buffer readback: {e}"))?;
            let mut pixels = Vec::with_capacity((w * h) as usize);
            for y in 0..h as usize {
                let row = y * s.row as usize..y * s.row as usize + (w * TEXEL) as usize;
                let texels = position[row.clone()].chunks_exact(16).zip(normal[row].chunks_exact(16));
                pixels.extend(texels.map(|(p, n)| {
                    let (p, n) = (texel(p), texel(n));
                    let id = p[3].round();
                    GPixel {
                        position: Vec3::new(p[0], p[1], p[2]),
                        material: (id >= 1.0).then(|| id as u32 - 1),
                        normal: Vec3::new(n[0], n[1], n[2]),
                        reflect: if id >= 1.0 { n[3] } else { 0.0 },
                    }
                }));
            }
            pixels
        };
        s.position.unmap();
        s.normal.unmap();
        s.state.store(IDLE, Ordering::Release);
        Ok(Some(GBufferImage { width: w, height: h, pixels }))
    }
}

/// A G-buffer read back to the CPU.
#[derive(Clone, Debug)]
pub struct GBufferImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major pixels from the top left.
    pub pixels: Vec<GPixel>,
}
