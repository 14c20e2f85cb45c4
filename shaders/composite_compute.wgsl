// Composite into a separate output by a compute pass: out = scene * T + L, scene alpha kept,
// the same arithmetic as fs_separate (composite_separate.wgsl). Chosen when the output texture
// allows storage writes: a GPU built for compute runs a fullscreen pass much faster this way
// (an NVIDIA H200 keeps few raster units; docs/performance.md has the measurement), and the
// render pipeline stays for outputs without STORAGE_BINDING and for compositing in place.

@group(0) @binding(1) var scene: texture_2d<f32>;
//!OUTPUT_STORAGE_BINDING(5)

// On a half-resolution trace grid (divisor 2), one invocation composites the 2x2 pixels that
// share trace sample `id`: their four 2x2 sets of samples lie in the 3x3 around it, read once
// (9 samples for 4 pixels instead of 16, the same values and weights as one pixel at a time).
override QUAD: bool = false;

fn inside(local: vec2u) -> bool {
    return all(local < vec2u(cu.viewport.zw));
}

// Writes scene * T + L at `local`, a pixel inside the viewport.
fn composite_pixel(local: vec2u, clouds_here: vec4f) {
    let pixel = local + vec2u(cu.viewport.xy);
    let s = textureLoad(scene, pixel, 0);
    textureStore(output, pixel, vec4f(s.rgb * clouds_here.a + clouds_here.rgb, s.a));
}

// Pixel 2x + i (i = 0, 1) lies at trace position x - 1/4 + i/2: between samples x - 1 and x
// at 3/4 for i = 0, between x and x + 1 at 1/4 for i = 1 (fetch_clouds with scale 2).
fn composite_quad(id: vec2u) {
    let local = id * 2u;
    if (!inside(local)) {
        return;
    }
    let last = vec2i(textureDimensions(clouds)) - vec2i(1);
    let c = min(vec2i(id), last);
    let l = max(c - vec2i(1), vec2i(0));
    let h = min(c + vec2i(1), last);
    // t_xy: x, y each l (below), c (this sample) or h (above).
    let t_ll = load_tap(vec2i(l.x, l.y));
    let t_cl = load_tap(vec2i(c.x, l.y));
    let t_hl = load_tap(vec2i(h.x, l.y));
    let t_lc = load_tap(vec2i(l.x, c.y));
    let t_cc = load_tap(vec2i(c.x, c.y));
    let t_hc = load_tap(vec2i(h.x, c.y));
    let t_lh = load_tap(vec2i(l.x, h.y));
    let t_ch = load_tap(vec2i(c.x, h.y));
    let t_hh = load_tap(vec2i(h.x, h.y));
    let p00 = local;
    let p10 = local + vec2u(1u, 0u);
    let p01 = local + vec2u(0u, 1u);
    let p11 = local + vec2u(1u, 1u);
    composite_pixel(p00, upsample(t_ll, t_cl, t_lc, t_cc, vec2f(0.75, 0.75), p00));
    // An odd-sized viewport's last column and row have no second pixel.
    if (inside(p10)) {
        composite_pixel(p10, upsample(t_cl, t_hl, t_cc, t_hc, vec2f(0.25, 0.75), p10));
    }
    if (inside(p01)) {
        composite_pixel(p01, upsample(t_lc, t_cc, t_lh, t_ch, vec2f(0.75, 0.25), p01));
    }
    if (inside(p11)) {
        composite_pixel(p11, upsample(t_cc, t_hc, t_ch, t_hh, vec2f(0.25, 0.25), p11));
    }
}

@compute @workgroup_size(8, 8)
fn cs_separate(@builtin(global_invocation_id) id: vec3u) {
    if (QUAD) {
        composite_quad(id.xy);
    } else if (inside(id.xy)) {
        composite_pixel(id.xy, fetch_clouds(id.xy));
    }
}
