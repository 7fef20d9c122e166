//! The G-buffer pass (`shaders/gbuffer.wgsl`): the scene's triangles in one vertex buffer, rasterised from
//! the CPU camera's projection into a position target and a normal target (both 32-bit float, with the
//! material id and, for reflective surfaces, the distance from the eye in their fourth channels) and a depth
//! buffer.

use raylab_core::scene::{Camera, Scene};

/// Floats per vertex: position, shading normal, face normal, material id and reflection weight.
const VERTEX_FLOATS: usize = 11;
/// Bytes of the camera uniform (a 4x4 matrix and the eye).
const CAMERA_BYTES: u64 = 80;
/// The targets' format.
pub const TARGET_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// The two G-buffer targets and the depth buffer of one size.
pub struct Targets {
    /// Position (w: material id + 1, 0 for the background).
    pub position: wgpu::Texture,
    /// Normal (w: distance from the eye where the material reflects, else 0): all the CPU reads back.
    pub normal: wgpu::Texture,
    depth: wgpu::TextureView,
    /// Width and height in pixels.
    pub size: (u32, u32),
}

/// The pipeline and the scene's vertices.
pub struct GBufferPass {
    pipeline: wgpu::RenderPipeline,
    camera: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    vertices: Option<wgpu::Buffer>,
    vertex_count: u32,
    targets: Option<Targets>,
}

impl GBufferPass {
    /// The pipeline, with no scene yet.
    pub fn new(device: &wgpu::Device) -> Self {
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("gbuffer.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("../../../../../shaders/gbuffer.wgsl").into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("gbuffer camera"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: wgpu::BufferSize::new(CAMERA_BYTES),
                },
                count: None,
            }],
        });
        let camera = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("gbuffer camera"),
            size: CAMERA_BYTES,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("gbuffer camera"),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: camera.as_entire_binding() }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("gbuffer"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let attributes = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3, 3 => Float32x2];
        let target =
            Some(wgpu::ColorTargetState { format: TARGET_FORMAT, blend: None, write_mask: wgpu::ColorWrites::ALL });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("gbuffer"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &shader,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: (VERTEX_FLOATS * 4) as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &attributes,
                })],
            },
            primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: wgpu::TextureFormat::Depth32Float,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &shader,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[target.clone(), target],
            }),
            multiview_mask: None,
            cache: None,
        });
        Self { pipeline, camera, bind_group, vertices: None, vertex_count: 0, targets: None }
    }

    /// Uploads `scene`'s triangles (replacing any earlier scene).
    pub fn set_scene(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, scene: &Scene) {
        let data = vertex_data(scene, 0);
        self.vertex_count = (data.len() / VERTEX_FLOATS) as u32;
        if data.is_empty() {
            self.vertices = None;
            return;
        }
        let bytes: Vec<u8> = data.iter().flat_map(|f| f.to_le_bytes()).collect();
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("gbuffer vertices"),
            size: bytes.len() as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        queue.write_buffer(&buffer, 0, &bytes);
        self.vertices = Some(buffer);
    }

    /// Re-uploads the triangles of `scene` from index `first` on (moved vertices; the same triangles as the
    /// scene given to [`GBufferPass::set_scene`]).
    pub fn update_triangles(&self, queue: &wgpu::Queue, scene: &Scene, first: usize) {
        let Some(buffer) = &self.vertices else { return };
        let data = vertex_data(scene, first);
        if data.len() / VERTEX_FLOATS + first * 3 > self.vertex_count as usize {
            return;
        }
        let bytes: Vec<u8> = data.iter().flat_map(|f| f.to_le_bytes()).collect();
        queue.write_buffer(buffer, (first * 3 * VERTEX_FLOATS * 4) as u64, &bytes);
    }

    /// The targets of the last pass.
    pub fn targets(&self) -> Option<&Targets> {
        self.targets.as_ref()
    }

    /// Records the pass for `camera` at `size` pixels into `encoder` (targets are made or resized as needed).
    /// `near` is the projection's near distance.
    pub fn record(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        camera: &Camera,
        size: (u32, u32),
        near: f32,
    ) {
        let (w, h) = (size.0.max(1), size.1.max(1));
        if self.targets.as_ref().is_none_or(|t| t.size != (w, h)) {
            self.targets = Some(make_targets(device, (w, h)));
        }
        let clip = camera.raster(w, h).clip_matrix(near);
        let mut uniform: Vec<u8> = clip.as_flattened().iter().flat_map(|f| f.to_le_bytes()).collect();
        uniform.extend([camera.eye.x, camera.eye.y, camera.eye.z, 1.0].iter().flat_map(|f| f.to_le_bytes()));
        queue.write_buffer(&self.camera, 0, &uniform);
        let Some(t) = &self.targets else { return };
        let (pv, nv) = (t.position.create_view(&Default::default()), t.normal.create_view(&Default::default()));
        let clear = |view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("gbuffer"),
            color_attachments: &[clear(&pv), clear(&nv)],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &t.depth,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Discard }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        if let Some(v) = &self.vertices {
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.bind_group, &[]);
            pass.set_vertex_buffer(0, v.slice(..));
            pass.draw(0..self.vertex_count, 0..1);
        }
    }
}

fn make_targets(device: &wgpu::Device, (w, h): (u32, u32)) -> Targets {
    let texture = |label, format, usage| {
        device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    };
    let usage =
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::TEXTURE_BINDING;
    let depth = texture("gbuffer depth", wgpu::TextureFormat::Depth32Float, wgpu::TextureUsages::RENDER_ATTACHMENT);
    Targets {
        position: texture("gbuffer position", TARGET_FORMAT, usage),
        normal: texture("gbuffer normal", TARGET_FORMAT, usage),
        depth: depth.create_view(&Default::default()),
        size: (w, h),
    }
}

/// Unindexed vertices of the triangles from index `first` on: position, shading normal (the vertex normal,
/// or the face normal when the scene has none), face normal, material id and reflection weight.
fn vertex_data(scene: &Scene, first: usize) -> Vec<f32> {
    let n = scene.triangle_count().saturating_sub(first);
    let mut out = Vec::with_capacity(n * 3 * VERTEX_FLOATS);
    let has_normals = !scene.normals.is_empty() && scene.normals.len() == scene.positions.len();
    for (i, t) in scene.triangles.iter().enumerate().skip(first) {
        let face = scene.geometric_normal_unnormalized(i);
        let m = &scene.materials[t.material as usize];
        let reflect = if m.kind.reflects() { m.reflect_blend.clamp(0.0, 1.0) } else { 0.0 };
        for &v in &t.v {
            let p = scene.positions[v as usize];
            let n = if has_normals { scene.normals[v as usize] } else { face };
            out.extend([p.x, p.y, p.z, n.x, n.y, n.z, face.x, face.y, face.z, t.material as f32, reflect]);
        }
    }
    out
}
