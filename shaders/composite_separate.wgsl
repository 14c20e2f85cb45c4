// Composite into a separate output: out = scene * T + L, scene alpha kept.

@group(0) @binding(1) var scene: texture_2d<f32>;

@fragment
fn fs_separate(@builtin(position) pos: vec4f) -> @location(0) vec4f {
    let c = fetch_clouds(local_pixel(pos));
    let s = textureLoad(scene, vec2u(pos.xy), 0);
    return vec4f(s.rgb * c.a + c.rgb, s.a);
}
