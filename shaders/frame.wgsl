// Draws the CPU tracer's latest frame over the whole target, texel for pixel.
//
// The frame texture holds display-ready 8-bit values (gamma already applied by the tracer) and the target
// is a non-sRGB (gamma-space) format, so each texel is copied through unchanged: at 100% render scale a
// screenshot of the window holds exactly the bytes `raylab-bench render` writes. Below 100%, each texel
// covers a block of pixels (nearest neighbour, no filtering), so the traced pixels stay visible as such.

struct Params {
    // Size of the render target in pixels.
    target_size: vec2<f32>,
    // Padding to the 16-byte uniform alignment.
    pad: vec2<f32>,
}

@group(0) @binding(0) var frame: texture_2d<f32>;
@group(0) @binding(1) var<uniform> params: Params;

// One triangle that covers the target: vertices (-1,-1), (3,-1), (-1,3) in clip space.
@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let x = f32((i << 1u) & 2u);
    let y = f32(i & 2u);
    return vec4<f32>(x * 2.0 - 1.0, y * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs_main(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let dims = textureDimensions(frame);
    let scaled = floor(pos.xy * vec2<f32>(dims) / params.target_size);
    let texel = min(vec2<u32>(max(scaled, vec2<f32>(0.0))), dims - vec2<u32>(1u));
    return textureLoad(frame, texel, 0);
}
