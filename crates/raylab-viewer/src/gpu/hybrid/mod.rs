//! The hybrid render mode (seed 003, Stokes 2014): the GPU rasterises a G-buffer ([`gbuffer`]), it is read
//! back through double-buffered staging buffers ([`readback`]), and the CPU traces only the reflection rays of
//! reflective pixels (`raylab_core::render::hybrid`).

pub mod composite;
pub mod gbuffer;
pub mod readback;

use std::collections::VecDeque;
use std::sync::Arc;
use std::time::Instant;

use composite::CompositePass;
use gbuffer::GBufferPass;
use raylab_core::scene::Scene;
use raylab_scene::animation::Animation;
use readback::Readback;

use crate::gpu::compositor::Compositor;
use crate::gpu::device::Gpu;
use crate::lab::Lab;
use crate::loader::LoadedScene;
use crate::tracer::jobs::{HybridFrame, Job, ReflectionJob};

/// A rasterised G-buffer on its way back to the CPU.
struct InFlight {
    slot: usize,
    job: Job,
    raster_ms: f64,
    animation_time: Option<f64>,
}

/// The animation switch in hybrid mode: the rasteriser's own copy of the scene with its moving objects
/// (built exactly as the worker builds its copy, so triangle and material ids agree).
struct Moving {
    source: Arc<LoadedScene>,
    scene: Scene,
    anim: Animation,
    start: Instant,
    first_moving: usize,
}

/// The GPU side of the hybrid mode: raster pass, readback and composite, and the scene they were given.
pub struct HybridGpu {
    gbuffer: GBufferPass,
    readback: Readback,
    composite: CompositePass,
    scene: Option<Arc<LoadedScene>>,
    moving: Option<Moving>,
    in_flight: VecDeque<InFlight>,
}

impl HybridGpu {
    /// The passes, with no scene yet; an error naming the adapter when it cannot render into the G-buffer's
    /// 32-bit float targets (some OpenGL drivers cannot), so the mode is refused instead of failing.
    pub fn new(gpu: &Gpu) -> Result<Self, String> {
        let usages = gpu.adapter.get_texture_format_features(gbuffer::TARGET_FORMAT).allowed_usages;
        if !usages.contains(wgpu::TextureUsages::RENDER_ATTACHMENT) {
            return Err(format!(
                "hybrid mode needs a GPU that renders into {:?} targets, and {} cannot; staying in the CPU modes \
                 (with no GPU, Mesa's lavapipe Vulkan driver can: apt-get install mesa-vulkan-drivers libvulkan1)",
                gbuffer::TARGET_FORMAT,
                gpu.describe()
            ));
        }
        Ok(Self {
            gbuffer: GBufferPass::new(&gpu.device),
            readback: Readback::default(),
            composite: CompositePass::new(&gpu.device),
            scene: None,
            moving: None,
            in_flight: VecDeque::new(),
        })
    }

    /// One UI frame's work: rasterise the view `lab` asks for (at most two G-buffers in flight), and hand the
    /// oldest G-buffer back from the GPU to the worker once it is idle (waiting for it with synchronous
    /// readback).
    pub fn step(&mut self, gpu: &Gpu, lab: &mut Lab) {
        let scene = &lab.scene_arc();
        let animate = lab.settings.animate;
        if self.moving.as_ref().is_some_and(|m| !animate || !Arc::ptr_eq(&m.source, scene)) {
            // The animation stopped (or the scene changed): upload the still scene again.
            self.moving = None;
            self.scene = None;
        }
        if animate && self.moving.is_none() {
            let (moving, anim) = Animation::add_movers(&scene.scene);
            self.gbuffer.set_scene(&gpu.device, &gpu.queue, &moving);
            self.composite.set_scene(&gpu.queue, &moving);
            let first_moving = scene.scene.triangle_count();
            self.moving =
                Some(Moving { source: Arc::clone(scene), scene: moving, anim, start: Instant::now(), first_moving });
            self.scene = Some(Arc::clone(scene));
            self.in_flight.clear();
        }
        if self.scene.as_ref().is_none_or(|s| !Arc::ptr_eq(s, scene)) {
            self.gbuffer.set_scene(&gpu.device, &gpu.queue, &scene.scene);
            self.composite.set_scene(&gpu.queue, &scene.scene);
            self.scene = Some(Arc::clone(scene));
            self.in_flight.clear();
        }
        if self.in_flight.len() < 2
            && let Some(job) = lab.hybrid_request()
        {
            let t0 = Instant::now();
            let mut animation_time = None;
            if let Some(m) = &mut self.moving {
                let t = m.start.elapsed().as_secs_f64();
                if let Err(e) = m.anim.apply(&mut m.scene, t as f32) {
                    lab.message(e, true);
                }
                self.gbuffer.update_triangles(&gpu.queue, &m.scene, m.first_moving);
                animation_time = Some(t);
            }
            let mut encoder =
                gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("gbuffer") });
            let near = 1e-4 * job.scene.scene.bounds().diagonal().max(f32::MIN_POSITIVE);
            self.gbuffer.record(&gpu.device, &gpu.queue, &mut encoder, &job.camera, job.size, near);
            let slot = self.gbuffer.targets().map(|t| self.readback.record(&gpu.device, &mut encoder, t));
            gpu.queue.submit([encoder.finish()]);
            if let Some(slot) = slot {
                self.readback.map(slot);
                let raster_ms = t0.elapsed().as_secs_f64() * 1e3;
                self.in_flight.push_back(InFlight { slot, job, raster_ms, animation_time });
            }
        }
        if lab.hybrid_idle()
            && let Some(f) = self.in_flight.front()
        {
            let wait = !f.job.settings.hybrid.async_readback;
            let t0 = Instant::now();
            match self.readback.take(&gpu.device, f.slot, wait) {
                Ok(Some(gbuffer)) => {
                    if let Some(f) = self.in_flight.pop_front() {
                        let readback_ms = t0.elapsed().as_secs_f64() * 1e3;
                        lab.trace_reflections(ReflectionJob {
                            job: f.job,
                            gbuffer,
                            raster_ms: f.raster_ms,
                            readback_ms,
                            animation_time: f.animation_time,
                        });
                    }
                }
                Ok(None) => {}
                Err(e) => {
                    self.in_flight.pop_front();
                    lab.message(e, true);
                }
            }
        }
        lab.set_hybrid_pending(!self.in_flight.is_empty());
    }

    /// Uploads `frame`'s R-buffer and composites it with the latest G-buffer into the compositor's frame
    /// texture; returns the CPU milliseconds of the upload and of the composite, or `None` when the G-buffer
    /// was resized since (the next frame catches up).
    pub fn show(
        &mut self,
        gpu: &Gpu,
        compositor: &mut Compositor,
        frame: &HybridFrame,
        lab: &Lab,
    ) -> Option<(f64, f64)> {
        let t0 = Instant::now();
        self.composite.upload(&gpu.device, &gpu.queue, frame.size, &frame.rbuffer);
        let upload_ms = t0.elapsed().as_secs_f64() * 1e3;
        let t1 = Instant::now();
        let targets = self.gbuffer.targets().filter(|t| t.size == frame.size)?;
        let out = compositor.frame_target(&gpu.device, frame.size);
        let mut encoder =
            gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("composite") });
        let light = lab.light();
        let drawn = self.composite.record(gpu, &mut encoder, targets, &light, frame.eye, &out);
        gpu.queue.submit([encoder.finish()]);
        drawn.then(|| (upload_ms, t1.elapsed().as_secs_f64() * 1e3))
    }
}

#[cfg(test)]
mod tests {
    use raylab_core::method::{Method, Purpose};
    use raylab_core::render::RenderSettings;
    use raylab_core::render::hybrid::{psnr, reference_reflections, reflection_ray, shade_reflections};
    use raylab_core::render::surface_epsilon;
    use raylab_core::structures::{StructureParams, Structures};
    use raylab_core::trace::{TraceOptions, Tracer};
    use raylab_scene::builtin::{self, Detail};

    use super::gbuffer::GBufferPass;
    use super::readback::Readback;
    use crate::gpu::device::Gpu;

    /// The GPU's G-buffer (under lavapipe in CI) gives reflections within 35 dB of the CPU Whitted renderer's
    /// first reflections over the pixels both see as reflective, and flags nearly the same pixels.
    #[test]
    fn hybrid_reflections_match_the_cpu_renderer() {
        let gpu = Gpu::new(&Gpu::instance(None), None).expect("a GPU adapter (lavapipe in CI)");
        super::HybridGpu::new(&gpu).expect("an adapter that renders float targets (lavapipe in CI)");
        let scene = builtin::build("atrium", Detail::Test).unwrap();
        let params = StructureParams::default();
        let structures = Structures::build(&scene, &[Method::Mono], Purpose::Frames, &params).unwrap();
        let tracer = Tracer::new(&structures, TraceOptions::default()).unwrap();
        let cam = scene.default_view().unwrap().camera;
        let light = scene.lights[0];
        let (w, h) = (160u32, 120u32);
        let mut pass = GBufferPass::new(&gpu.device);
        pass.set_scene(&gpu.device, &gpu.queue, &scene);
        let mut readback = Readback::default();
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let near = 1e-4 * scene.bounds().diagonal();
        pass.record(&gpu.device, &gpu.queue, &mut encoder, &cam, (w, h), near);
        let slot = readback.record(&gpu.device, &mut encoder, pass.targets().unwrap());
        gpu.queue.submit([encoder.finish()]);
        readback.map(slot);
        let g = readback.take(&gpu.device, slot, true).unwrap().expect("a mapped G-buffer");
        assert_eq!((g.width, g.height), (w, h));
        let raster = cam.raster(w, h);
        let mut pixels = vec![None; (w * h) as usize];
        for t in &g.reflective {
            pixels[t.index as usize] = Some(g.pixel(&raster, t));
        }
        let settings = RenderSettings { width: w, height: h, ..RenderSettings::default() };
        let want = reference_reflections(&scene, &tracer, &cam, light, &settings);
        let eps = surface_epsilon(&scene);
        let rays: Vec<_> = pixels.iter().map(|p| p.and_then(|p| reflection_ray(cam.eye, &p, eps))).collect();
        let (got, _, _) = shade_reflections(&scene, &tracer, &cam, light, &settings, &rays);
        let (cpu, gpu_flags) =
            (want.iter().filter(|c| c.is_some()).count(), rays.iter().filter(|r| r.is_some()).count());
        let both: Vec<_> =
            rays.iter().zip(&got).zip(&want).filter_map(|((r, g), w)| r.and(*w).map(|w| (*g, w))).collect();
        assert!(cpu > 200, "{cpu} reflective pixels");
        // Rasterisation and ray casting may disagree on a mirror's silhouette pixels only.
        assert!(
            both.len() * 100 >= cpu.max(gpu_flags) * 95,
            "{} of {cpu} CPU / {gpu_flags} GPU pixels agree",
            both.len()
        );
        let db = psnr(both).unwrap();
        assert!(db >= 35.0, "hybrid reflections {db:.1} dB from the CPU renderer's");
        // The reflective pixels' positions, put on their primary rays at the distance the GPU wrote, are the
        // CPU's hit points to rounding, and their normals the CPU's shading normals.
        let cpu_g = raylab_core::render::hybrid::cpu_gbuffer(&scene, &tracer, &cam, w, h);
        let both: Vec<_> =
            pixels.iter().zip(&cpu_g).filter_map(|(a, b)| a.filter(|_| b.reflective).map(|a| (a, b))).collect();
        let close = both
            .iter()
            .filter(|(a, b)| (a.position - b.position).length() <= 1e-3 * scene.bounds().diagonal())
            .filter(|(a, b)| a.normal.dot(b.normal) >= 0.999)
            .count();
        let covered = cpu_g.iter().filter(|p| p.reflective).count();
        assert!(close * 100 >= covered * 95, "{close} of {covered} reflective positions and normals match");
    }
}
