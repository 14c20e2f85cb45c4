// Composite into a separate output by a compute pass: out = scene * T + L, scene alpha kept,
// the same arithmetic as fs_separate (composite_separate.wgsl). Chosen when the output texture
// allows storage writes: a GPU built for compute runs a fullscreen pass much faster this way
// (an NVIDIA H200 keeps few raster units; docs/performance.md has the measurement), and the
// render pipeline stays for outputs without STORAGE_BINDING and for compositing in place.

@group(0) @binding(1) var scene: texture_2d<f32>;
//!OUTPUT_STORAGE_BINDING(5)

@compute @workgroup_size(8, 8)
fn cs_separate(@builtin(global_invocation_id) id: vec3u) {
    let local = id.xy;
    if (any(local >= vec2u(cu.viewport.zw))) {
        return;
    }
    let pixel = local + vec2u(cu.viewport.xy);
    let c = fetch_clouds(local);
    let s = textureLoad(scene, pixel, 0);
    textureStore(output, pixel, vec4f(s.rgb * c.a + c.rgb, s.a));
}
