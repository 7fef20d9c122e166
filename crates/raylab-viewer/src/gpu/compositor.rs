//! Putting a window together on the GPU: the traced frame uploaded with `queue.write_texture` and drawn as a
//! full-target triangle (`shaders/frame.wgsl`), then the egui panels over it.
//!
//! egui's output is drawn into a texture of its own (the UI layer; its opaque base, the side panel's
//! background, filled without egui's shader, [`crate::gpu::ui_fill`]), which is laid over the frame where egui
//! drew (the cells its triangles touch, [`crate::gpu::ui_cover`]); its meshes are uploaded and drawn again only
//! when they changed. A redraw of the unchanged UI, the common case while frames stream in or the UI is asked
//! to redraw often, then costs a copy of the frame around the opaque base (which would hide it) and a blend of
//! the UI's pixels. It matters most on software Vulkan (lavapipe), where egui's fragment shader costs tens of
//! milliseconds of CPU per draw of a 1280x720 window with the panel, time taken from the tracer on the same
//! cores.

use crate::gpu::device::Gpu;
use crate::gpu::ui_cover::{PixelRect, drawn_rects};
use crate::gpu::ui_fill::{SolidBase, around, split_solid_base};

/// Format of the frame texture: display-ready 8-bit values.
pub const FRAME_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// Size of the uniform block of `frame.wgsl` (target size and padding).
const PARAMS_BYTES: u64 = 16;

/// A pipeline drawing one full-target triangle (`vs_main`, no vertex buffers) shaded by `fs_main` into one
/// `format` target, with `layout` as bind group 0 and `blend` (none: replace): the frame view, the UI layer
/// and the hybrid mode's composite pass.
pub fn fullscreen_pipeline(
    device: &wgpu::Device,
    label: &str,
    shader: &wgpu::ShaderModule,
    layout: &wgpu::BindGroupLayout,
    format: wgpu::TextureFormat,
    blend: Option<wgpu::BlendState>,
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
            targets: &[Some(wgpu::ColorTargetState { format, blend, write_mask: wgpu::ColorWrites::ALL })],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// The texture [`Compositor`] fills the UI's solid base from, and the colour it holds.
struct BaseFill {
    texture: wgpu::Texture,
    bind_group: wgpu::BindGroup,
    color: Option<[u8; 4]>,
}

/// The uploaded frame.
struct FrameTexture {
    texture: wgpu::Texture,
    bind_group: wgpu::BindGroup,
    size: (u32, u32),
}

/// egui's output drawn into a texture of the target's size, with what was drawn.
struct UiLayer {
    view: wgpu::TextureView,
    bind_group: wgpu::BindGroup,
    size: (u32, u32),
    pixels_per_point: f32,
    /// The pixels egui drew, as disjoint rectangles (see [`drawn_rects`]).
    rects: Vec<PixelRect>,
    /// Where the layer is opaque (its solid base, see [`crate::gpu::ui_fill`]): the frame below is hidden there.
    opaque: Option<PixelRect>,
}

/// True when two UI frames' meshes draw the same pixels: the same clip rectangles and meshes, in order (a
/// paint callback never compares equal: it may draw anything).
fn same_jobs(a: &[egui::ClippedPrimitive], b: &[egui::ClippedPrimitive]) -> bool {
    use egui::epaint::Primitive;
    a.len() == b.len()
        && a.iter().zip(b).all(|(x, y)| {
            x.clip_rect == y.clip_rect
                && matches!((&x.primitive, &y.primitive), (Primitive::Mesh(m), Primitive::Mesh(n)) if m == n)
        })
}

/// The drawing pipeline of one target format.
pub struct Compositor {
    /// The colour format of every target drawn to (gamma-space, not sRGB).
    pub format: wgpu::TextureFormat,
    pipeline: wgpu::RenderPipeline,
    /// Lays the UI layer (premultiplied alpha, as egui draws it) over the target.
    layer_pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    frame: Option<FrameTexture>,
    ui: Option<UiLayer>,
    /// The meshes and screen (size in pixels, pixels per point) last handed to [`Compositor::prepare_egui`].
    ui_jobs: Vec<egui::ClippedPrimitive>,
    /// Their solid base, which the compositor fills itself ([`crate::gpu::ui_fill`]), and the meshes egui's
    /// renderer draws: the rest.
    ui_base: Option<SolidBase>,
    ui_drawn: Vec<egui::ClippedPrimitive>,
    /// A one-texel texture of the base's colour, drawn through `frame.wgsl`.
    base_fill: Option<BaseFill>,
    ui_screen: Option<([u32; 2], f32)>,
    /// egui's output (meshes, screen or textures) changed since the UI layer was drawn.
    ui_stale: bool,
    /// Times the UI layer was drawn.
    pub ui_draws: u64,
    /// egui's renderer.
    pub egui: egui_wgpu::Renderer,
}

impl Compositor {
    /// Pipelines for targets of `format`.
    pub fn new(device: &wgpu::Device, format: wgpu::TextureFormat) -> Self {
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("frame.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("../../../../shaders/frame.wgsl").into()),
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
        let pipeline = fullscreen_pipeline(device, "frame", &shader, &layout, format, None);
        let over = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
            operation: wgpu::BlendOperation::Add,
        };
        let blend = wgpu::BlendState { color: over, alpha: over };
        let layer_pipeline = fullscreen_pipeline(device, "ui layer", &shader, &layout, format, Some(blend));
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame params"),
            size: PARAMS_BYTES,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let options = egui_wgpu::RendererOptions { dithering: false, ..Default::default() };
        let egui = egui_wgpu::Renderer::new(device, format, options);
        Self {
            format,
            pipeline,
            layer_pipeline,
            layout,
            params,
            frame: None,
            ui: None,
            ui_jobs: Vec::new(),
            ui_base: None,
            ui_drawn: Vec::new(),
            base_fill: None,
            ui_screen: None,
            ui_stale: false,
            ui_draws: 0,
            egui,
        }
    }

    /// Uploads a traced frame of `width x height` RGBA8 pixels.
    pub fn upload(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, width: u32, height: u32, rgba: &[[u8; 4]]) {
        if rgba.len() != (width as usize) * (height as usize) || width == 0 || height == 0 {
            return;
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
        let bind_group = self.bind_texture(device, "traced frame", &texture);
        self.frame = Some(FrameTexture { texture, bind_group, size: (width, height) });
    }

    /// A bind group of `frame.wgsl` reading `texture`.
    fn bind_texture(&self, device: &wgpu::Device, label: &str, texture: &wgpu::Texture) -> wgpu::BindGroup {
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&view) },
                wgpu::BindGroupEntry { binding: 1, resource: self.params.as_entire_binding() },
            ],
        })
    }

    /// Makes the UI layer when there is none of `size` pixels; true when it made one.
    fn ensure_ui_layer(&mut self, device: &wgpu::Device, size: (u32, u32), pixels_per_point: f32) -> bool {
        if self.ui.as_ref().is_some_and(|l| l.size == size && l.pixels_per_point == pixels_per_point) {
            return false;
        }
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("ui layer"),
            size: wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: self.format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        let bind_group = self.bind_texture(device, "ui layer", &texture);
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        self.ui = Some(UiLayer { view, bind_group, size, pixels_per_point, rects: Vec::new(), opaque: None });
        true
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
        self.ui_stale |= !textures.set.is_empty() || !textures.free.is_empty();
        let free = std::mem::take(&mut textures.free).into_iter().collect();
        textures.clear();
        free
    }

    /// Hands this frame's egui meshes to the GPU when they differ from the last ones (the UI layer is then
    /// drawn again, see [`Compositor::draw`]); returns command buffers to submit before the draw's.
    pub fn prepare_egui(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        jobs: &[egui::ClippedPrimitive],
        screen: &egui_wgpu::ScreenDescriptor,
    ) -> Vec<wgpu::CommandBuffer> {
        let key = (screen.size_in_pixels, screen.pixels_per_point);
        if !self.ui_stale && self.ui_screen == Some(key) && same_jobs(&self.ui_jobs, jobs) {
            return Vec::new();
        }
        self.ui_stale = true;
        self.ui_screen = Some(key);
        self.ui_jobs = jobs.to_vec();
        let size = (screen.size_in_pixels[0], screen.size_in_pixels[1]);
        (self.ui_base, self.ui_drawn) = split_solid_base(jobs, screen.pixels_per_point, size);
        self.egui.update_buffers(device, queue, encoder, &self.ui_drawn, screen)
    }

    /// The one-texel texture of `color` (made on first use, rewritten when the colour changes).
    fn base_fill(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, color: [u8; 4]) {
        if self.base_fill.is_none() {
            let texture = device.create_texture(&wgpu::TextureDescriptor {
                label: Some("ui base fill"),
                size: wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: FRAME_FORMAT,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            });
            let bind_group = self.bind_texture(device, "ui base fill", &texture);
            self.base_fill = Some(BaseFill { texture, bind_group, color: None });
        }
        if let Some(fill) = self.base_fill.as_mut().filter(|f| f.color != Some(color)) {
            queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &fill.texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d::ZERO,
                    aspect: wgpu::TextureAspect::All,
                },
                &color,
                wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(4), rows_per_image: Some(1) },
                wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: 1 },
            );
            fill.color = Some(color);
        }
    }

    /// Frees the textures egui no longer needs; call after the UI frame was submitted.
    pub fn free_egui(&mut self, free: &[egui::TextureId]) {
        for id in free {
            self.egui.free_texture(id);
        }
    }

    /// Draws the latest frame and the UI into `target` (of `size` pixels and of this compositor's format): the
    /// meshes last handed to [`Compositor::prepare_egui`]. The UI layer is drawn again first when
    /// egui's output or the target's size changed.
    pub fn draw(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        size: (u32, u32),
        screen: &egui_wgpu::ScreenDescriptor,
    ) {
        let (device, queue) = (&gpu.device, &gpu.queue);
        let size = (size.0.max(1), size.1.max(1));
        let mut params = [0u8; PARAMS_BYTES as usize];
        params[0..4].copy_from_slice(&(size.0 as f32).to_le_bytes());
        params[4..8].copy_from_slice(&(size.1 as f32).to_le_bytes());
        queue.write_buffer(&self.params, 0, &params);
        let made = self.ensure_ui_layer(device, size, screen.pixels_per_point);
        let redraw = made || self.ui_stale;
        if let Some(base) = self.ui_base.filter(|_| redraw) {
            self.base_fill(device, queue, base.color);
        }
        if let Some(layer) = self.ui.as_mut().filter(|_| redraw) {
            let mut pass = target_pass(encoder, "ui layer", &layer.view, wgpu::Color::TRANSPARENT);
            // The base first (nothing of egui's lies below it), then the rest of egui's output over it.
            layer.opaque = None;
            if let (Some(base), Some(fill)) = (self.ui_base, &self.base_fill) {
                let [x, y, w, h] = base.rect;
                let (x, y) = (x.min(size.0), y.min(size.1));
                let (w, h) = (w.min(size.0 - x), h.min(size.1 - y));
                if w > 0 && h > 0 {
                    pass.set_pipeline(&self.pipeline);
                    pass.set_bind_group(0, &fill.bind_group, &[]);
                    pass.set_scissor_rect(x, y, w, h);
                    pass.draw(0..3, 0..1);
                    layer.opaque = Some([x, y, w, h]);
                }
            }
            self.egui.render(&mut pass, &self.ui_drawn, screen);
            layer.rects = drawn_rects(&self.ui_jobs, screen.pixels_per_point, size);
            self.ui_stale = false;
            self.ui_draws += 1;
        }
        let mut pass = target_pass(encoder, "window", target, wgpu::Color { r: 0.08, g: 0.08, b: 0.09, a: 1.0 });
        if let Some(f) = &self.frame {
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &f.bind_group, &[]);
            // The layer's opaque base, laid over the frame below, would hide the frame there: skip it. Its
            // rectangles (cells egui's triangles touch, the base's among them) cover the base.
            let hidden = self.ui.as_ref().filter(|l| !l.rects.is_empty()).and_then(|l| l.opaque);
            match hidden {
                Some(opaque) => {
                    for [x, y, w, h] in around(opaque, size) {
                        pass.set_scissor_rect(x, y, w, h);
                        pass.draw(0..3, 0..1);
                    }
                }
                None => pass.draw(0..3, 0..1),
            }
        }
        if let Some(layer) = self.ui.as_ref().filter(|l| !l.rects.is_empty()) {
            pass.set_pipeline(&self.layer_pipeline);
            pass.set_bind_group(0, &layer.bind_group, &[]);
            for &[x, y, w, h] in &layer.rects {
                pass.set_scissor_rect(x, y, w, h);
                pass.draw(0..3, 0..1);
            }
        }
    }
}

/// A render pass into `view`, cleared to `clear` first.
fn target_pass(
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    view: &wgpu::TextureView,
    clear: wgpu::Color,
) -> wgpu::RenderPass<'static> {
    encoder
        .begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(label),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Clear(clear), store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        })
        .forget_lifetime()
}

#[cfg(test)]
mod tests {
    use egui::epaint::{Mesh, Primitive};
    use egui::{ClippedPrimitive, Color32, Rect, pos2};

    use super::*;

    /// A job drawing one rectangle (in points), clipped to `clip`.
    fn job(r: [f32; 4], clip: [f32; 4]) -> ClippedPrimitive {
        let mut mesh = Mesh::default();
        mesh.add_colored_rect(Rect::from_min_max(pos2(r[0], r[1]), pos2(r[2], r[3])), Color32::WHITE);
        ClippedPrimitive {
            clip_rect: Rect::from_min_max(pos2(clip[0], clip[1]), pos2(clip[2], clip[3])),
            primitive: Primitive::Mesh(mesh),
        }
    }

    const WHOLE: [f32; 4] = [0.0, 0.0, 1000.0, 1000.0];

    #[test]
    fn same_jobs_compares_meshes_and_clips() {
        let a = [job([0.0, 0.0, 10.0, 10.0], WHOLE)];
        assert!(same_jobs(&a, &a.clone()));
        assert!(!same_jobs(&a, &[job([0.0, 0.0, 10.0, 11.0], WHOLE)]), "a moved vertex");
        assert!(!same_jobs(&a, &[job([0.0, 0.0, 10.0, 10.0], [0.0, 0.0, 5.0, 5.0])]), "another clip");
        assert!(!same_jobs(&a, &[]), "nothing drawn");
        assert!(same_jobs(&[], &[]));
    }
}
