// The hybrid mode's G-buffer pass (seed 003, Stokes 2014, section 3.1): rasterises the scene from the CPU
// camera's exact projection (`CameraRaster::clip_matrix`), so each pixel centre sees what the CPU's primary
// ray through it would see, and writes per pixel:
//   target 0 (rgba32float): world position, and material id + 1 in w (0 where nothing was drawn);
//   target 1 (rgba32float): unit shading normal turned toward the viewer, and in w the distance from the eye
//                           where the material reflects (reflection weight above 0), else 0;
//   depth (depth32float).
// The CPU reads target 1 alone back (16 bytes a pixel): it needs only the reflective pixels, and puts each on
// its primary ray at that distance.
// Normals are turned exactly as the CPU shades a hit: the geometric normal toward the viewer, the shading
// normal onto the geometric normal's side.

struct Camera {
    clip: mat4x4<f32>,
    eye: vec4<f32>,
}

@group(0) @binding(0) var<uniform> camera: Camera;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    // The triangle's unnormalised geometric normal, the same on its three vertices.
    @location(2) face: vec3<f32>,
    // Material id and reflection weight.
    @location(3) material: vec2<f32>,
}

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) @interpolate(flat) face: vec3<f32>,
    @location(3) @interpolate(flat) material: vec2<f32>,
}

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = camera.clip * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    out.face = v.face;
    out.material = v.material;
    return out;
}

struct GBuffer {
    @location(0) position: vec4<f32>,
    @location(1) normal: vec4<f32>,
}

@fragment
fn fs_main(v: VertexOut) -> GBuffer {
    let view = v.world - camera.eye.xyz;
    var g = normalize(v.face);
    if (dot(g, view) >= 0.0) {
        g = -g;
    }
    var n = normalize(v.normal);
    if (dot(n, g) < 0.0) {
        n = -n;
    }
    var out: GBuffer;
    out.position = vec4<f32>(v.world, v.material.x + 1.0);
    out.normal = vec4<f32>(n, select(0.0, length(view), v.material.y > 0.0));
    return out;
}
