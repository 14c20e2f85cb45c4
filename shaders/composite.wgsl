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

// One trace-grid sample as the upsample reads it.
struct Tap {
    value: vec4f,  // (L, T)
    cloud: f32,    // the cloud's distance (m; 0 = no cloud)
    log_clip: f32, // log of the scene distance its ray was clipped at (at least 1 m)
}

fn load_tap(c: vec2i) -> Tap {
    let d = textureLoad(cloud_depth, c, 0).rg;
    return Tap(textureLoad(clouds, c, 0), d.x, log(max(d.y, 1.0)));
}

// The weight of a sample for a full-resolution pixel at scene distance `d_full` (log:
// `log_full`), whose bilinear weight is `bilinear`.
fn tap_weight(t: Tap, bilinear: f32, d_full: f32, log_full: f32) -> f32 {
    // A cloud behind this pixel's own occluder is not visible here.
    if (t.cloud > 0.0 && t.cloud > d_full) {
        return 0.0;
    }
    // Samples clipped at a very different scene distance belong to another surface.
    return (bilinear + 1e-4) / (1e-3 + abs(t.log_clip - log_full));
}

// (L, T) at full-resolution pixel `pixel` from the four samples around it (t_xy: x, y the
// sample's offset from the lower one; `f` the pixel's bilinear fractions between them).
fn upsample(t00: Tap, t10: Tap, t01: Tap, t11: Tap, f: vec2f, pixel: vec2u) -> vec4f {
    // Four samples with no cloud: any weighting, and dropping any of them, gives (0, 1), and
    // a GPU that branches skips the pixel's scene distance (clear sky, the ground below the
    // horizon: most of a frame).
    let none = vec4f(0.0, 0.0, 0.0, 1.0);
    if (all(t00.value == none) && all(t10.value == none) && all(t01.value == none) && all(t11.value == none)) {
        return none;
    }
    let d_full = full_scene_distance(pixel);
    let log_full = log(max(d_full, 1.0));
    let w00 = tap_weight(t00, (1.0 - f.x) * (1.0 - f.y), d_full, log_full);
    let w10 = tap_weight(t10, f.x * (1.0 - f.y), d_full, log_full);
    let w01 = tap_weight(t01, (1.0 - f.x) * f.y, d_full, log_full);
    let w11 = tap_weight(t11, f.x * f.y, d_full, log_full);
    let total = w00 + w10 + w01 + w11;
    if (total <= 0.0) {
        return none;
    }
    // A sample with no weight adds nothing, even an infinite one (0 × inf is NaN).
    let sum = select(vec4f(0.0), w00 * t00.value, w00 > 0.0)
        + select(vec4f(0.0), w10 * t10.value, w10 > 0.0)
        + select(vec4f(0.0), w01 * t01.value, w01 > 0.0)
        + select(vec4f(0.0), w11 * t11.value, w11 > 0.0);
    return sum / total;
}

// (L, T) for a full-resolution pixel. The four samples are named, not an indexed array: a
// SIMD rasterizer (llvmpipe) keeps such an array in scratch memory, one access per lane.
fn fetch_clouds(pixel: vec2u) -> vec4f {
    let scale = cu.params.x;
    if (scale <= 1.0) {
        return textureLoad(clouds, pixel, 0);
    }
    let last = vec2i(textureDimensions(clouds)) - vec2i(1);
    // Position in trace pixels: the samples below and above it, and the fractions between.
    let q = (vec2f(pixel) + 0.5) / scale - 0.5;
    let f = q - floor(q);
    let lo = clamp(vec2i(floor(q)), vec2i(0), last);
    let hi = min(vec2i(floor(q)) + vec2i(1), last);
    return upsample(
        load_tap(lo),
        load_tap(vec2i(hi.x, lo.y)),
        load_tap(vec2i(lo.x, hi.y)),
        load_tap(hi),
        f,
        pixel,
    );
}

// In place: the blend state does scene * T + L (src One, dst SrcAlpha; alpha kept).
@fragment
fn fs_in_place(@builtin(position) pos: vec4f) -> @location(0) vec4f {
    return fetch_clouds(local_pixel(pos));
}
