// The hybrid mode's composite pass (seed 003, Stokes 2014, section 3.4): lights each G-buffer pixel with the
// CPU renderer's local model (ambient plus N.L diffuse with the light's attenuation, Phong highlight; the
// raster pass has no shadows) and mixes in the CPU-traced reflection of the R-buffer with the material's
// weight: the reflection blend, Fresnel-weighted (Schlick) for transparent-reflective materials. Writes
// display-ready 8-bit values (gamma 2.2), as the CPU frames are.

struct Params {
    light_position: vec4<f32>,
    // rgb: light colour.
    light_color: vec4<f32>,
    // Constant, linear and quadratic attenuation.
    attenuation: vec4<f32>,
    eye: vec4<f32>,
    // Ambient and direct shares of the local model.
    shading: vec4<f32>,
}

struct Material {
    // rgb: base colour; w: 1 for the kinds with a Phong highlight.
    base: vec4<f32>,
    // Reflection weight (0: no reflection), 1 to weight it by Fresnel, index of refraction, Phong exponent.
    reflection: vec4<f32>,
    // x: specular blend.
    specular: vec4<f32>,
}

const MATERIALS: u32 = 256u;

@group(0) @binding(0) var position_tex: texture_2d<f32>;
@group(0) @binding(1) var normal_tex: texture_2d<f32>;
@group(0) @binding(2) var rbuffer: texture_2d<f32>;
@group(0) @binding(3) var<uniform> params: Params;
@group(0) @binding(4) var<uniform> materials: array<Material, MATERIALS>;

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let x = f32((i << 1u) & 2u);
    let y = f32(i & 2u);
    return vec4<f32>(x * 2.0 - 1.0, y * 2.0 - 1.0, 0.0, 1.0);
}

fn attenuate(d: f32) -> f32 {
    let a = params.attenuation;
    let denom = a.x + a.y * d + a.z * d * d;
    return select(1.0, 1.0 / denom, denom > 1.0);
}

// Schlick's approximation from outside (air) into a medium of index `ior`.
fn schlick(cos_i: f32, ior: f32) -> f32 {
    let r0 = pow((1.0 - ior) / (1.0 + ior), 2.0);
    return r0 + (1.0 - r0) * pow(1.0 - clamp(cos_i, 0.0, 1.0), 5.0);
}

@fragment
fn fs_main(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let texel = vec2<i32>(frag.xy);
    let p = textureLoad(position_tex, texel, 0);
    if (p.w < 0.5) {
        return vec4<f32>(0.0, 0.0, 0.0, 1.0);
    }
    let m = materials[min(u32(p.w - 0.5), MATERIALS - 1u)];
    let n = textureLoad(normal_tex, texel, 0).xyz;
    let to_light = params.light_position.xyz - p.xyz;
    let dist = length(to_light);
    let l = select(n, to_light / dist, dist > 0.0);
    let ndl = max(dot(n, l), 0.0);
    let lit = attenuate(dist);
    var c = m.base.rgb * (params.shading.x + params.shading.y * (ndl * lit) * params.light_color.rgb);
    let view = normalize(p.xyz - params.eye.xyz);
    if (m.base.w > 0.5 && ndl > 0.0 && lit > 0.0) {
        let r = reflect(-l, n);
        let highlight = pow(max(dot(r, -view), 0.0), m.reflection.w);
        c += params.light_color.rgb * (m.specular.x * highlight * lit);
    }
    var w = m.reflection.x;
    if (m.reflection.y > 0.5) {
        w = w + (1.0 - w) * schlick(dot(-view, n), m.reflection.z);
    }
    let reflected = textureLoad(rbuffer, texel, 0).rgb;
    let color = mix(c, reflected, clamp(w, 0.0, 1.0));
    return vec4<f32>(pow(clamp(color, vec3<f32>(0.0), vec3<f32>(1.0)), vec3<f32>(1.0 / 2.2)), 1.0);
}
