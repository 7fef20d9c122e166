//! Command-line arguments shared by the subcommands, with range checks that name the flag.

use clap::Args;
use glam::Vec3;
use raylab_core::kdtree::KdParams;
use raylab_core::render::RenderSettings;
use raylab_core::scene::{Camera, PointLight, Scene};
use raylab_core::shadow::{SampleBound, ShadowKind, Shadows};
use raylab_core::structures::StructureParams;
use raylab_scene::SceneSource;

/// Parses `X,Y,Z`.
pub fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != 3 {
        return Err(format!("expected X,Y,Z, got '{s}'"));
    }
    let mut v = [0f32; 3];
    for (out, p) in v.iter_mut().zip(&parts) {
        let x: f32 = p.trim().parse().map_err(|_| format!("'{p}' is not a number"))?;
        if !x.is_finite() {
            return Err(format!("'{p}' is not finite"));
        }
        *out = x;
    }
    Ok(Vec3::from_array(v))
}

/// Parses a SIMD backend name (`avx512`, `avx2`, `sse2` or `scalar`); refuses one this CPU cannot run.
pub fn parse_backend(s: &str) -> Result<raylab_simd::Backend, String> {
    let avail = raylab_simd::Backend::available();
    avail.iter().copied().find(|b| b.name() == s).ok_or_else(|| {
        let names: Vec<_> = avail.iter().map(|b| b.name()).collect();
        format!("unknown or unavailable backend '{s}' (available here: {})", names.join(", "))
    })
}

/// A clap value parser for integers in `lo..=hi`.
pub fn in_range(lo: u64, hi: u64) -> impl Fn(&str) -> Result<u64, String> + Clone + Send + Sync + 'static {
    move |s: &str| {
        let v: u64 = s.parse().map_err(|_| format!("'{s}' is not a whole number"))?;
        if (lo..=hi).contains(&v) { Ok(v) } else { Err(format!("{v} is out of range {lo}..={hi}")) }
    }
}

/// Parses a finite number of at least zero.
pub fn parse_non_negative(s: &str) -> Result<f32, String> {
    let v: f32 = s.parse().map_err(|_| format!("'{s}' is not a number"))?;
    if v.is_finite() && v >= 0.0 { Ok(v) } else { Err(format!("{v} must be finite and >= 0")) }
}

/// Parses a finite number greater than zero.
pub fn parse_positive(s: &str) -> Result<f32, String> {
    let v: f32 = s.parse().map_err(|_| format!("'{s}' is not a number"))?;
    if v.is_finite() && v > 0.0 { Ok(v) } else { Err(format!("{v} must be finite and > 0")) }
}

/// The scene, camera and light flags.
#[derive(Args, Clone, Debug)]
pub struct SceneArgs {
    /// Built-in scene name (atrium, arena, kitchen, forest) or path to an .obj file.
    #[arg(long, default_value = "atrium")]
    pub scene: String,
    /// Named view of the scene (defaults to its first).
    #[arg(long)]
    pub view: Option<String>,
    /// Camera position X,Y,Z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub eye: Option<Vec3>,
    /// Point looked at X,Y,Z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub target: Option<Vec3>,
    /// Up vector X,Y,Z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub up: Option<Vec3>,
    /// Vertical field of view in degrees, in (0, 180).
    #[arg(long, allow_hyphen_values = true)]
    pub fov: Option<f32>,
    /// Point light position X,Y,Z (defaults to the scene's light).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub light: Option<Vec3>,
    /// Radius of the spherical light for soft shadows, in world units (defaults to the scene's light).
    #[arg(long, value_parser = parse_non_negative, allow_hyphen_values = true)]
    pub light_radius: Option<f32>,
}

impl SceneArgs {
    /// The scene `name` with its own default view and light.
    pub fn named(name: &str) -> Self {
        Self {
            scene: name.to_string(),
            view: None,
            eye: None,
            target: None,
            up: None,
            fov: None,
            light: None,
            light_radius: None,
        }
    }

    /// Where the scene comes from.
    pub fn source(&self) -> SceneSource {
        SceneSource::parse(&self.scene)
    }

    /// The camera and light: the scene's own, overridden by the flags.
    pub fn camera_and_light(&self, scene: &Scene) -> Result<(Camera, PointLight), String> {
        let base = match &self.view {
            Some(name) => scene.view(name).map(|v| v.camera).ok_or_else(|| {
                let names: Vec<_> = scene.views.iter().map(|v| v.name.as_str()).collect();
                format!("--view: no view '{name}' in this scene (views: {})", names.join(", "))
            })?,
            None => scene.default_view().map(|v| v.camera).unwrap_or_else(|| default_camera(scene)),
        };
        let mut cam = base;
        cam.eye = self.eye.unwrap_or(cam.eye);
        cam.target = self.target.unwrap_or(cam.target);
        cam.up = self.up.unwrap_or(if self.eye.is_some() || self.target.is_some() { Vec3::Y } else { cam.up });
        cam.vfov_deg = self.fov.unwrap_or(if self.view.is_none() && self.eye.is_some() { 60.0 } else { cam.vfov_deg });
        cam.validate().map_err(|e| format!("camera (--eye/--target/--up/--fov): {e}"))?;
        let mut light = scene.lights.first().copied().unwrap_or_else(|| PointLight::at(default_light(scene)));
        if let Some(p) = self.light {
            light = PointLight { position: p, ..light };
        }
        if let Some(r) = self.light_radius {
            light.radius = r;
        }
        Ok((cam, light))
    }
}

/// A view of the whole scene from outside its box, for files that carry no view.
fn default_camera(scene: &Scene) -> Camera {
    let b = scene.bounds();
    let c = b.center();
    let eye = c + Vec3::new(0.6, 0.4, 1.0) * b.diagonal().max(1.0);
    Camera::look_at(eye, c, Vec3::Y, 60.0)
}

fn default_light(scene: &Scene) -> Vec3 {
    let b = scene.bounds();
    b.center() + Vec3::Y * b.extent().y.max(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vec3_parsing() {
        assert_eq!(parse_vec3("1,-2.5, 3"), Ok(Vec3::new(1.0, -2.5, 3.0)));
        assert!(parse_vec3("1,2").is_err());
        assert!(parse_vec3("1,2,x").unwrap_err().contains("'x'"));
        assert!(parse_vec3("1,2,inf").is_err());
    }

    #[test]
    fn ranges() {
        let p = in_range(1, 16);
        assert_eq!(p("4"), Ok(4));
        assert!(p("0").unwrap_err().contains("1..=16"));
        assert!(p("-1").is_err());
    }
}

/// Image-size flags shared by `render`, `trace` and `compare` (the harness's default 512x512).
#[derive(Args, Clone, Copy, Debug)]
pub struct ImageArgs {
    /// Image width in pixels.
    #[arg(long, default_value_t = 512, value_parser = in_range(1, 16384))]
    pub width: u64,
    /// Image height in pixels.
    #[arg(long, default_value_t = 512, value_parser = in_range(1, 16384))]
    pub height: u64,
}

impl ImageArgs {
    /// Width and height as pixel counts.
    pub fn size(&self) -> (u32, u32) {
        (self.width as u32, self.height as u32)
    }
}

/// kd-tree cost-model flags (thesis Eq. 2.1); the defaults are [`StructureParams::default`]'s.
#[derive(Args, Clone, Debug)]
pub struct KdArgs {
    /// Traversal cost C_traversal of the SAH [default: 12 for the trees of packet, frustum, mft, cone and
    /// mft-cone, whose leaf visits cost more than their node steps; 1, the thesis's, for every other method].
    #[arg(long, allow_hyphen_values = true)]
    pub kd_ctrav: Option<f32>,
    /// Intersection cost C_intersect of the SAH (the thesis uses 5 x C_traversal).
    #[arg(long, default_value_t = KdParams::default().c_isect, allow_hyphen_values = true)]
    pub kd_cisect: f32,
    /// Empty-space bonus in [0, 1).
    #[arg(long, default_value_t = KdParams::default().empty_bonus, allow_hyphen_values = true)]
    pub kd_empty_bonus: f32,
    /// Maximum tree depth (default: 8 + 1.3 log2 N).
    #[arg(long, value_parser = in_range(1, KdParams::DEPTH_LIMIT as u64))]
    pub kd_max_depth: Option<u64>,
}

impl KdArgs {
    /// The parameters of every structure: both kd-trees' cost models ([`StructureParams::default`]) with the
    /// flags' changes (`--kd-ctrav` sets both trees' `c_trav`); checked, and the error names the flag.
    pub fn structure_params(&self) -> Result<StructureParams, String> {
        let with_flags = |base: KdParams| KdParams {
            c_trav: self.kd_ctrav.unwrap_or(base.c_trav),
            c_isect: self.kd_cisect,
            empty_bonus: self.kd_empty_bonus,
            max_depth: self.kd_max_depth.map(|d| d as u32),
            ..base
        };
        let defaults = StructureParams::default();
        let p = StructureParams { kd: with_flags(defaults.kd), packet_kd: with_flags(defaults.packet_kd), ..defaults };
        p.validate().map_err(|m| format!("--kd-*: {m}"))?;
        Ok(p)
    }

    /// The parameters of the thesis's tree (the one that single rays and the thesis's tables use), with
    /// the flags' changes; checked, and the error names the flag.
    pub fn params(&self) -> Result<KdParams, String> {
        Ok(self.structure_params()?.kd)
    }
}

/// Traversal-method flags shared by `render` and `trace`.
#[derive(Args, Clone, Debug)]
pub struct MethodArgs {
    /// Traversal method: mono, packet, frustum, mft, cone, mft-cone, mbvh, mbvh-rs, dacrt or reference.
    #[arg(long, default_value = "mono")]
    pub method: raylab_core::method::Method,
    /// Tile edge in pixels: the frustum size of frustum methods, the ray group of mbvh-rs (16: 2^8 rays), the
    /// ray set of dacrt, the unit threads take for all.
    #[arg(long, default_value_t = 16, value_parser = in_range(1, 4096))]
    pub tile: u64,
    /// Turn packet/leaf culling off (frustum methods).
    #[arg(long)]
    pub no_cull: bool,
    /// SIMD backend of packet kernels: avx512 (4x4 packets, where the CPU has AVX-512F/VL), avx2 (4x2
    /// packets, where it has AVX2 and FMA), sse2 (2x2 packets, any x86-64) or scalar (2x2); default: the
    /// fastest this CPU runs.
    #[arg(long, value_parser = parse_backend)]
    pub backend: Option<raylab_simd::Backend>,
    /// Widest shadow bundle seen from the light (tangent of its half-angle) that frustum methods trace as a
    /// frustum (hard shadows and edge-width walks); wider ones go as 2x2 packets. 0 traces all shadow rays as
    /// packets.
    #[arg(long, default_value_t = raylab_core::trace::TraceOptions::SHADOW_SPREAD_LIMIT, value_parser = parse_non_negative)]
    pub shadow_spread_limit: f32,
    /// Walk MBVH RS child tasks in lane order instead of by accumulated hit length (to measure the ordering).
    #[arg(long)]
    pub no_stream_order: bool,
    /// How MBVH RS tests the rays reaching a leaf: blocks (two rays per eight-lane test against four-triangle
    /// blocks) or packets (the paper's four-ray packets against one triangle at a time).
    #[arg(long, default_value = "blocks")]
    pub stream_leaves: raylab_core::mbvh::StreamLeaves,
    /// DACRT: a node with at most this many rays is tested naively (below the division made at setup).
    #[arg(long, default_value_t = 8, value_parser = in_range(1, raylab_core::dacrt::DacrtParams::MAX_LEAF as u64))]
    pub dacrt_leaf_rays: u64,
    /// DACRT: a node with at most this many triangles is tested naively.
    #[arg(long, default_value_t = 8, value_parser = in_range(1, raylab_core::dacrt::DacrtParams::MAX_LEAF as u64))]
    pub dacrt_leaf_tris: u64,
    /// DACRT: how triangles are divided, sah (16 bins) or median.
    #[arg(long, default_value = "sah")]
    pub dacrt_split: raylab_core::dacrt::SplitRule,
}

/// Shadow-technique and recursion flags shared by `render`, `compare` and the viewer (thesis chapter 5,
/// section 4.1.9 and 4.2.1).
#[derive(Args, Clone, Debug)]
pub struct ShadeArgs {
    /// Shadow technique: none, hard, cached (hard with the shadow cache), edge (edge-width soft shadows), or
    /// ms4, ms8, ms16, ms32 (that many stratified samples on the spherical light).
    #[arg(long, default_value = "hard")]
    pub shadows: ShadowKind,
    /// How multi-sampled shadows bound each point's samples: packets, fitted (a pyramid fitted to them), or the
    /// pyramid or cone around the light.
    #[arg(long, default_value = "packets")]
    pub ms_bound: SampleBound,
    /// Edge width at which a point counts as fully shadowed, in world units (default: the light's radius).
    #[arg(long, value_parser = parse_non_negative, allow_hyphen_values = true)]
    pub edge_radius: Option<f32>,
    /// Pair edge-width crossings only on triangles that share a vertex (the light-leak fix).
    #[arg(long)]
    pub leak_fix: bool,
    /// Reflection and refraction depth after the primary hit (0: primary rays only).
    #[arg(long, default_value_t = RenderSettings::DEFAULT_DEPTH as u64,
          value_parser = in_range(0, RenderSettings::MAX_DEPTH as u64))]
    pub depth: u64,
}

impl ShadeArgs {
    /// The shadow technique for a scene lit by `light` (whose radius is the default edge radius).
    pub fn shadows(&self, light: &PointLight) -> Shadows {
        self.shadows.with(self.edge_radius.unwrap_or(light.radius), self.leak_fix, self.ms_bound)
    }
}

impl MethodArgs {
    /// The tracer options these flags select.
    pub fn options(&self) -> raylab_core::trace::TraceOptions {
        raylab_core::trace::TraceOptions {
            method: self.method,
            cull: !self.no_cull,
            backend: self.backend.unwrap_or_else(raylab_simd::Backend::detect),
            shadow_spread_limit: self.shadow_spread_limit,
            stream_order: !self.no_stream_order,
            stream_leaves: self.stream_leaves,
            dacrt: raylab_core::dacrt::DacrtParams {
                leaf_rays: self.dacrt_leaf_rays as usize,
                leaf_tris: self.dacrt_leaf_tris as usize,
                split: self.dacrt_split,
            },
            stream_group: None,
        }
    }
}

/// Parses an MBVH RS ray-group size: a power of two in 2^4..=2^12 (the MBVH RS paper's range).
pub fn parse_group(s: &str) -> Result<u64, String> {
    let g: u64 = s.parse().map_err(|_| format!("'{s}' is not a whole number"))?;
    if g.is_power_of_two() && (16..=4096).contains(&g) {
        Ok(g)
    } else {
        Err(format!("{g} is not a power of two from 16 to 4096"))
    }
}
