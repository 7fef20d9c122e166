//! The composite pass (`shaders/composite.wgsl`): the G-buffer lit with the CPU renderer's local model, mixed
//! with the uploaded R-buffer of CPU-traced reflections by each material's (Fresnel-weighted) reflection
//! weight, drawn into the compositor's frame texture.

use raylab_core::render::shade::{AMBIENT, DIRECT};
use raylab_core::scene::{MaterialKind, PointLight, Scene};

use super::gbuffer::{TARGET_FORMAT, Targets};
use crate::gpu::compositor::{FRAME_FORMAT, fullscreen_pipeline};
use crate::gpu::device::Gpu;

/// Materials the composite pass knows (later ones are drawn with the last).
pub const MATERIALS: usize = 256;
/// Bytes of one material record (three vec4).
const MATERIAL_BYTES: usize = 48;
/// Bytes of the parameter block (five vec4).
const PARAMS_BYTES: u64 = 80;

/// The pipeline, the R-buffer texture and the uniforms.
pub struct CompositePass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    materials: wgpu::Buffer,
    rbuffer: Option<(wgpu::Texture, (u32, u32))>,
}

impl CompositePass {
    /// The pipeline.
    pub fn new(device: &wgpu::Device) -> Self {
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("composite.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("../../../../../shaders/composite.wgsl").into()),
        });
        let texture = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        let uniform = |binding, size| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: wgpu::BufferSize::new(size),
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("composite"),
            entries: &[
                texture(0),
                texture(1),
                texture(2),
                uniform(3, PARAMS_BYTES),
                uniform(4, (MATERIALS * MATERIAL_BYTES) as u64),
            ],
        });
        let pipeline = fullscreen_pipeline(device, "composite", &shader, &layout, FRAME_FORMAT, None);
        let buffer = |label, size| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        Self {
            pipeline,
            layout,
            params: buffer("composite params", PARAMS_BYTES),
            materials: buffer("composite materials", (MATERIALS * MATERIAL_BYTES) as u64),
            rbuffer: None,
        }
    }

    /// Uploads `scene`'s materials.
    pub fn set_scene(&self, queue: &wgpu::Queue, scene: &Scene) {
        let mut bytes = vec![0u8; MATERIALS * MATERIAL_BYTES];
        for (i, m) in scene.materials.iter().take(MATERIALS).enumerate() {
            let reflect = if m.kind.reflects() { m.reflect_blend.clamp(0.0, 1.0) } else { 0.0 };
            let fresnel = if m.kind == MaterialKind::TransparentReflective { 1.0 } else { 0.0 };
            let spec = if m.kind.has_specular() { 1.0 } else { 0.0 };
            let c = m.base_color;
            let values =
                [c.x, c.y, c.z, spec, reflect, fresnel, m.ior, m.phong_exponent, m.specular_blend, 0.0, 0.0, 0.0];
            for (k, v) in values.iter().enumerate() {
                bytes[i * MATERIAL_BYTES + 4 * k..][..4].copy_from_slice(&v.to_le_bytes());
            }
        }
        queue.write_buffer(&self.materials, 0, &bytes);
    }

    /// Uploads an R-buffer of `size` pixels (linear colours, row-major); returns nothing when the size is wrong.
    pub fn upload(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, size: (u32, u32), colors: &[[f32; 4]]) {
        let (w, h) = size;
        if colors.len() != (w as usize) * (h as usize) || w == 0 || h == 0 {
            return;
        }
        if self.rbuffer.as_ref().is_none_or(|(_, s)| *s != size) {
            let texture = device.create_texture(&wgpu::TextureDescriptor {
                label: Some("R-buffer"),
                size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: TARGET_FORMAT,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            });
            self.rbuffer = Some((texture, size));
        }
        let Some((texture, _)) = &self.rbuffer else { return };
        // The colours' own bytes (little-endian f32 on every host wgpu runs on), with no copy.
        let bytes: &[u8] = bytemuck::cast_slice(colors);
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            bytes,
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(16 * w), rows_per_image: Some(h) },
            wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        );
    }

    /// Records the composite of `targets` and the R-buffer (which must have the targets' size) into `out`.
    pub fn record(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        targets: &Targets,
        light: &PointLight,
        eye: glam::Vec3,
        out: &wgpu::TextureView,
    ) -> bool {
        let Some((rbuffer, size)) = &self.rbuffer else { return false };
        if *size != targets.size {
            return false;
        }
        let l = light;
        let values = [
            [l.position.x, l.position.y, l.position.z, 1.0],
            [l.color.x, l.color.y, l.color.z, 1.0],
            [l.constant, l.linear, l.quadratic, 0.0],
            [eye.x, eye.y, eye.z, 1.0],
            [AMBIENT, DIRECT, 0.0, 0.0],
        ];
        let bytes: Vec<u8> = values.as_flattened().iter().flat_map(|f| f.to_le_bytes()).collect();
        gpu.queue.write_buffer(&self.params, 0, &bytes);
        let view = |t: &wgpu::Texture| t.create_view(&wgpu::TextureViewDescriptor::default());
        let (pv, nv, rv) = (view(&targets.position), view(&targets.normal), view(rbuffer));
        let bind_group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("composite"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&pv) },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&nv) },
                wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::TextureView(&rv) },
                wgpu::BindGroupEntry { binding: 3, resource: self.params.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 4, resource: self.materials.as_entire_binding() },
            ],
        });
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("composite"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: out,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.draw(0..3, 0..1);
        true
    }
}
