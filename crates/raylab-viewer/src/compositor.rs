//! Putting a window together on the GPU: the traced frame uploaded with `queue.write_texture` and drawn as a
//! full-target triangle (`shaders/frame.wgsl`), then the egui panels over it.

use std::time::{Duration, Instant};

/// Format of the frame texture: display-ready 8-bit values.
pub const FRAME_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// Size of the uniform block of `frame.wgsl` (target size and padding).
const PARAMS_BYTES: u64 = 16;

/// A pipeline drawing one full-target triangle (`vs_main`, no vertex buffers) shaded by `fs_main` into one
/// `format` target, with `layout` as bind group 0: the frame view and the hybrid mode's composite pass.
pub fn fullscreen_pipeline(
    device: &wgpu::Device,
    label: &str,
    shader: &wgpu::ShaderModule,
    layout: &wgpu::BindGroupLayout,
    format: wgpu::TextureFormat,
) -> wgpu::RenderPipeline {
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module: shader,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module: shader,
            entry_point: Some("fs_main"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState { format, blend: None, write_mask: wgpu::ColorWrites::ALL })],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// The uploaded frame.
struct FrameTexture {
    texture: wgpu::Texture,
    bind_group: wgpu::BindGroup,
    size: (u32, u32),
}

/// The drawing pipeline of one target format.
pub struct Compositor {
    /// The colour format of every target drawn to (gamma-space, not sRGB).
    pub format: wgpu::TextureFormat,
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    frame: Option<FrameTexture>,
    /// egui's renderer.
    pub egui: egui_wgpu::Renderer,
}

impl Compositor {
    /// Pipelines for targets of `format`.
    pub fn new(device: &wgpu::Device, format: wgpu::TextureFormat) -> Self {
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("frame.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("../../../shaders/frame.wgsl").into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("frame"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: wgpu::BufferSize::new(PARAMS_BYTES),
                    },
                    count: None,
                },
            ],
        });
        let pipeline = fullscreen_pipeline(device, "frame", &shader, &layout, format);
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame params"),
            size: PARAMS_BYTES,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let options = egui_wgpu::RendererOptions { dithering: false, ..Default::default() };
        let egui = egui_wgpu::Renderer::new(device, format, options);
        Self { format, pipeline, layout, params, frame: None, egui }
    }

    /// Uploads a traced frame of `width x height` RGBA8 pixels; returns the time the CPU spent on it.
    pub fn upload(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        width: u32,
        height: u32,
        rgba: &[[u8; 4]],
    ) -> Duration {
        let t0 = Instant::now();
        if rgba.len() != (width as usize) * (height as usize) || width == 0 || height == 0 {
            return t0.elapsed();
        }
        self.ensure_frame(device, (width, height));
        if let Some(f) = &self.frame {
            let bytes: &[u8] = rgba.as_flattened();
            queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &f.texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d::ZERO,
                    aspect: wgpu::TextureAspect::All,
                },
                bytes,
                wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(4 * width), rows_per_image: Some(height) },
                wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            );
        }
        t0.elapsed()
    }

    /// The frame texture as a render target of `size` pixels (made or resized as needed): the hybrid mode's
    /// composite pass draws into it instead of uploading a traced frame.
    pub fn frame_target(&mut self, device: &wgpu::Device, size: (u32, u32)) -> wgpu::TextureView {
        let size = (size.0.max(1), size.1.max(1));
        self.ensure_frame(device, size);
        match &self.frame {
            Some(f) => f.texture.create_view(&wgpu::TextureViewDescriptor::default()),
            None => unreachable!("ensure_frame made the frame texture"),
        }
    }

    /// Makes the frame texture (and its bind group) when there is none of `size` pixels.
    fn ensure_frame(&mut self, device: &wgpu::Device, (width, height): (u32, u32)) {
        if self.frame.as_ref().is_some_and(|f| f.size == (width, height)) {
            return;
        }
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("traced frame"),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: FRAME_FORMAT,
            usage: wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_DST
                | wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("traced frame"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&view) },
                wgpu::BindGroupEntry { binding: 1, resource: self.params.as_entire_binding() },
            ],
        });
        self.frame = Some(FrameTexture { texture, bind_group, size: (width, height) });
    }

    /// Applies egui's texture changes of a UI frame: new and updated textures now, and returns the ones to
    /// free once the frame was submitted (see [`Compositor::free_egui`]).
    pub fn apply_egui_textures(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        mut textures: egui::TexturesDelta,
    ) -> Vec<egui::TextureId> {
        for (id, deltas) in &textures.set {
            for delta in deltas {
                self.egui.update_texture(device, queue, *id, delta);
            }
        }
        let free = std::mem::take(&mut textures.free).into_iter().collect();
        textures.clear();
        free
    }

    /// Hands this frame's egui meshes to the GPU; returns command buffers to submit before the draw's.
    pub fn prepare_egui(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        jobs: &[egui::ClippedPrimitive],
        screen: &egui_wgpu::ScreenDescriptor,
    ) -> Vec<wgpu::CommandBuffer> {
        self.egui.update_buffers(device, queue, encoder, jobs, screen)
    }

    /// Frees the textures egui no longer needs; call after the UI frame was submitted.
    pub fn free_egui(&mut self, free: &[egui::TextureId]) {
        for id in free {
            self.egui.free_texture(id);
        }
    }

    /// Draws the latest frame and the UI into `target` (of `size` pixels and of this compositor's format).
    pub fn draw(
        &self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        size: (u32, u32),
        jobs: &[egui::ClippedPrimitive],
        screen: &egui_wgpu::ScreenDescriptor,
    ) {
        let mut params = [0u8; PARAMS_BYTES as usize];
        params[0..4].copy_from_slice(&(size.0 as f32).to_le_bytes());
        params[4..8].copy_from_slice(&(size.1 as f32).to_le_bytes());
        queue.write_buffer(&self.params, 0, &params);
        let pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("window"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color { r: 0.08, g: 0.08, b: 0.09, a: 1.0 }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let mut pass = pass.forget_lifetime();
        if let Some(f) = &self.frame {
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &f.bind_group, &[]);
            pass.draw(0..3, 0..1);
        }
        self.egui.render(&mut pass, jobs, screen);
    }
}
