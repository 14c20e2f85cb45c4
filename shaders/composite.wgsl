// Composite (render pass, fullscreen triangle): out = scene * T + L.

@group(0) @binding(0) var clouds: texture_2d<f32>;

@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4f {
    let uv = vec2f(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4f(uv * 2.0 - 1.0, 0.0, 1.0);
}

// In place: the blend state does scene * T + L (src One, dst SrcAlpha; alpha kept).
@fragment
fn fs_in_place(@builtin(position) pos: vec4f) -> @location(0) vec4f {
    return textureLoad(clouds, vec2u(pos.xy), 0);
}
