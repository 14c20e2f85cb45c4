// Composite (render pass, fullscreen triangle): out = scene * T + L, with the clouds upsampled
// from the trace resolution. The upsample is depth-aware: each traced sample remembers the
// scene distance it was clipped at, and a full-resolution pixel trusts the samples whose scene
// distance resembles its own, and never a cloud behind its own occluder. Occluder edges stay
// sharp, and pixels in front of the clouds stay exactly unchanged.

struct CompositeUniforms {
    inv_view_proj_rel: mat4x4f, // NDC to positions relative to the camera
    depth: vec4f,    // x: depth value meaning "far / sky"
    params: vec4f,   // x: trace divisor (1, 2, 4), y: has scene depth (0/1)
    viewport: vec4f, // the rectangle of the targets rendered: x, y, width, height (px)
}

// Where the rendered rectangle sits in the scene depth (load_scene_depth adds its origin).
fn scene_viewport() -> vec4f {
    return cu.viewport;
}

// A fragment's pixel inside the rendered rectangle (the render pass's viewport and scissor
// keep fragments inside it).
fn local_pixel(pos: vec4f) -> vec2u {
    return vec2u(pos.xy) - vec2u(cu.viewport.xy);
}

@group(0) @binding(0) var clouds: texture_2d<f32>;
@group(0) @binding(2) var cloud_depth: texture_2d<f32>;
// Per-frame parameters: a read-only storage buffer, not a uniform (lavapipe compiles a shader
// variant per distinct uniform value; see FRAME_PARAMS_USAGE in src/gpu/compute.rs).
@group(0) @binding(3) var<storage, read> cu: CompositeUniforms;
//!SCENE_DEPTH_BINDING(4)

@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4f {
    let uv = vec2f(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4f(uv * 2.0 - 1.0, 0.0, 1.0);
}

fn full_scene_distance(pixel: vec2u) -> f32 {
    if (cu.params.y < 0.5) {
        return NO_SCENE;
    }
    let dims = vec2u(cu.viewport.zw);
    return scene_distance_at(cu.inv_view_proj_rel, cu.depth.x, pixel_ndc(pixel, dims), load_scene_depth(pixel));
}

// (L, T) for a full-resolution pixel.
fn fetch_clouds(pixel: vec2u) -> vec4f {
    let scale = cu.params.x;
    if (scale <= 1.0) {
        return textureLoad(clouds, pixel, 0);
    }
    let low = vec2i(textureDimensions(clouds));
    let d_full = full_scene_distance(pixel);
    // Position in trace pixels, and the four nearest samples with bilinear weights.
    let q = (vec2f(pixel) + 0.5) / scale - 0.5;
    let base = vec2i(floor(q));
    let f = q - floor(q);
    var sum = vec4f(0.0);
    var total = 0.0;
    for (var k = 0; k < 4; k++) {
        let o = vec2i(k & 1, k >> 1);
        let c = clamp(base + o, vec2i(0), low - vec2i(1));
        let bilinear = select(1.0 - f.x, f.x, o.x == 1) * select(1.0 - f.y, f.y, o.y == 1);
        let depths = textureLoad(cloud_depth, c, 0).rg;
        // A cloud behind this pixel's own occluder is not visible here.
        if (depths.x > 0.0 && depths.x > d_full) {
            continue;
        }
        // Samples clipped at a very different scene distance belong to another surface.
        let similar = 1.0 / (1e-3 + abs(log(max(depths.y, 1.0)) - log(max(d_full, 1.0))));
        let w = (bilinear + 1e-4) * similar;
        sum += w * textureLoad(clouds, c, 0);
        total += w;
    }
    if (total <= 0.0) {
        return vec4f(0.0, 0.0, 0.0, 1.0);
    }
    return sum / total;
}

// In place: the blend state does scene * T + L (src One, dst SrcAlpha; alpha kept).
@fragment
fn fs_in_place(@builtin(position) pos: vec4f) -> @location(0) vec4f {
    return fetch_clouds(local_pixel(pos));
}
