// Temporal resolve (compute, one invocation per trace-grid pixel). The march traced one pixel
// of every k×k block this frame; this pass rebuilds the full grid from those fresh samples and
// last frame's resolved image, reprojected through the previous view-projection at the cloud
// depth (Schneider 2015/2017, Horizon Zero Dawn: 1 pixel in 16 per frame with reprojection).
//
// Per pixel:
// - its fresh sample, if traced this frame, is averaged into the history with weight 1/n
//   (n = samples in the history + 1, at most `max samples`), so a static view converges to the
//   mean of its jittered samples;
// - otherwise the reprojected history is kept;
// - history is rejected when the host reset it, when it falls off screen, or when the scene
//   surface under it changed (disocclusion); the pixel then takes the depth-aware bilinear
//   interpolation of this frame's fresh samples, marked as holding 0 samples;
// - under camera motion the history is clamped to the range of the fresh samples around it, so
//   fast motion and moving occluders do not smear (neighbourhood clamping, Karis 2014).

struct TemporalUniforms {
    inv_view_proj_rel: mat4x4f, // NDC to positions relative to the camera
    prev_view_proj: mat4x4f,
    camera: vec4f,   // xyz position, w: depth value of the near plane
    grid: vec4f,     // grid width, height, block edge k, trace divisor (output px per grid px)
    pattern: vec4f,  // this frame's offset in the block (x, y), history valid (0/1), max samples
    misc: vec4f,     // has scene depth (0/1), far depth value, max distance (m), unused
    viewport: vec4f, // the rectangle of the scene targets rendered: x, y, width, height (px)
}

// Where the rendered rectangle sits in the scene depth (load_scene_depth adds its origin).
fn scene_viewport() -> vec4f {
    return tu.viewport;
}

// Per-frame parameters: a read-only storage buffer, not a uniform (lavapipe compiles a shader
// variant per distinct uniform value; see FRAME_PARAMS_USAGE in src/gpu/compute.rs).
@group(0) @binding(0) var<storage, read> tu: TemporalUniforms;
// This frame's sparse march: (L, T), and (cloud depth, scene distance, samples, light samples).
@group(0) @binding(1) var fresh_clouds: texture_2d<f32>;
@group(0) @binding(2) var fresh_depth: texture_2d<f32>;
// Last frame's resolved grid: (L, T), and (cloud depth, scene distance, samples held, unused).
@group(0) @binding(3) var history_clouds: texture_2d<f32>;
@group(0) @binding(4) var history_depth: texture_2d<f32>;
//!SCENE_DEPTH_BINDING(5)
@group(0) @binding(6) var out_clouds: texture_storage_2d<rgba16float, write>;
@group(0) @binding(7) var out_depth: texture_storage_2d<rgba32float, write>;

// Scene distances this close in log space (0.1) belong to the same surface: compared as a
// ratio, e^0.1, which spares the resolve eight pairs of logarithms per pixel.
const SAME_SURFACE_RATIO: f32 = 1.10517092;

fn same_surface(a: f32, b: f32) -> bool {
    let x = max(a, 1.0);
    let y = max(b, 1.0);
    return max(x, y) < SAME_SURFACE_RATIO * min(x, y);
}

fn scene_distance_of(p: vec2u, grid: vec2u, ndc: vec2f) -> f32 {
    if (tu.misc.x < 0.5) {
        return NO_SCENE;
    }
    let scale = u32(tu.grid.w);
    let full = vec2u(tu.viewport.zw);
    let at = min(p * scale + vec2u(scale / 2u), full - vec2u(1u));
    return scene_distance_at(tu.inv_view_proj_rel, tu.misc.y, ndc, load_scene_depth(at));
}

// The fresh samples around a grid pixel: their depth-aware bilinear blend, the range they span
// (for clamping history) and their mean cloud depth (for reprojecting).
struct Neighbourhood {
    blend: vec4f,
    lo: vec4f,
    hi: vec4f,
    cloud_depth: f32,
    front_depth: f32,
    found: bool,
}

fn fresh_neighbourhood(p: vec2u, k: u32, offset: vec2u, grid: vec2u, scene_t: f32) -> Neighbourhood {
    var n = Neighbourhood(vec4f(0.0, 0.0, 0.0, 1.0), vec4f(1e9), vec4f(-1e9), 0.0, 0.0, false);
    // Sparse texel s holds grid pixel s * k + offset; only those inside the grid were written.
    if (any(grid <= offset)) {
        return n;
    }
    let last = vec2i((grid - vec2u(1u) - offset) / k);
    let q = (vec2f(p) - vec2f(offset)) / f32(k);
    let base = vec2i(floor(q));
    let f = q - floor(q);
    var sum = vec4f(0.0);
    var total = 0.0;
    var depth_sum = 0.0;
    var front_sum = 0.0;
    var depth_w = 0.0;
    for (var j = 0; j < 4; j++) {
        let o = vec2i(j & 1, j >> 1);
        let c = clamp(base + o, vec2i(0), last);
        let bilinear = select(1.0 - f.x, f.x, o.x == 1) * select(1.0 - f.y, f.y, o.y == 1);
        let d = textureLoad(fresh_depth, c, 0);
        // A cloud behind this pixel's own occluder is not visible here, and a sample clipped
        // at another surface's distance belongs to that surface.
        if ((d.x > 0.0 && d.x > scene_t) || !same_surface(d.y, scene_t)) {
            continue;
        }
        let v = textureLoad(fresh_clouds, c, 0);
        let w = bilinear + 1e-3;
        sum += w * v;
        total += w;
        n.lo = min(n.lo, v);
        n.hi = max(n.hi, v);
        if (d.x > 0.0) {
            depth_sum += w * d.x;
            front_sum += w * d.w;
            depth_w += w;
        }
    }
    if (total > 0.0) {
        n.blend = sum / total;
        n.found = true;
    }
    if (depth_w > 0.0) {
        n.cloud_depth = depth_sum / depth_w;
        n.front_depth = front_sum / depth_w;
    }
    return n;
}

// Last frame's resolved value at grid position `at` (pixel units, centers at integers),
// bilinear over the texels that saw the same scene surface. w = 0 when none did.
struct History {
    value: vec4f,
    depth: vec4f,
    weight: f32,
}

fn fetch_history(at: vec2f, grid: vec2u, scene_t: f32) -> History {
    var h = History(vec4f(0.0), vec4f(0.0), 0.0);
    let base = vec2i(floor(at));
    let f = at - floor(at);
    let last = vec2i(grid) - vec2i(1);
    var samples = 1e9;
    var best = -1.0;
    for (var j = 0; j < 4; j++) {
        let o = vec2i(j & 1, j >> 1);
        let c = clamp(base + o, vec2i(0), last);
        let bilinear = select(1.0 - f.x, f.x, o.x == 1) * select(1.0 - f.y, f.y, o.y == 1);
        let d = textureLoad(history_depth, c, 0);
        if (bilinear <= 0.0 || !same_surface(d.y, scene_t)) {
            continue;
        }
        h.value += bilinear * textureLoad(history_clouds, c, 0);
        h.weight += bilinear;
        // The sample count is the smallest of the texels used: a blend is no better than
        // its least converged part.
        samples = min(samples, d.z);
        if (bilinear > best) {
            best = bilinear;
            h.depth = d;
        }
    }
    if (h.weight > 1e-3) {
        h.value /= h.weight;
        h.depth.z = samples;
    }
    return h;
}

@compute @workgroup_size(8, 8, 1)
fn resolve(@builtin(global_invocation_id) id: vec3u) {
    let grid = vec2u(tu.grid.xy);
    let p = id.xy;
    if (any(p >= grid)) {
        return;
    }
    let k = u32(tu.grid.z);
    let offset = vec2u(tu.pattern.xy);
    let ndc = pixel_ndc(p, grid);
    let cam = tu.camera.xyz;
    let dir = view_ray_dir(tu.inv_view_proj_rel, ndc, tu.camera.w);
    let scene_t = scene_distance_of(p, grid, ndc);

    let is_fresh = all(p % vec2u(k) == offset);
    var fresh = vec4f(0.0, 0.0, 0.0, 1.0);
    var fresh_d = vec4f(0.0);
    if (is_fresh) {
        fresh = textureLoad(fresh_clouds, p / k, 0);
        fresh_d = textureLoad(fresh_depth, p / k, 0);
    }
    let around = fresh_neighbourhood(p, k, offset, grid, scene_t);

    // Reproject at the cloud depth (sky: the far end of the march), never past the scene.
    var depth = select(around.cloud_depth, fresh_d.x, is_fresh);
    if (depth <= 0.0) {
        depth = tu.misc.z;
    }
    depth = min(depth, scene_t);
    let prev_clip = tu.prev_view_proj * vec4f(cam + dir * depth, 1.0);
    var history = History(vec4f(0.0), vec4f(0.0), 0.0);
    var motion = 0.0;
    if (tu.pattern.z > 0.5 && prev_clip.w > 0.0) {
        let prev_ndc = prev_clip.xy / prev_clip.w;
        var prev_px = vec2f((prev_ndc.x + 1.0) * 0.5, (1.0 - prev_ndc.y) * 0.5) * vec2f(grid) - 0.5;
        let inside = all(prev_px >= vec2f(-0.5)) && all(prev_px <= vec2f(grid) - 0.5);
        if (inside) {
            motion = length(prev_px - vec2f(p));
            // A static camera reprojects onto its own pixel up to float error: read it exactly,
            // or repeated bilinear reads would slowly blur a still image.
            if (motion < 0.01) {
                prev_px = vec2f(p);
                motion = 0.0;
            }
            history = fetch_history(prev_px, grid, scene_t);
        }
    }

    var value: vec4f;
    var cloud_depth: f32;
    var front_depth: f32;
    var samples: f32;
    if (history.weight > 1e-3) {
        var h = history.value;
        // Clamp to the fresh neighbourhood, from 0.05 pixels of motion on and fully from half a
        // pixel. A (nearly) static view is left unclamped so that it converges to the mean of
        // its samples rather than being pulled into the range of its noisy neighbours.
        if (around.found) {
            let span = around.hi - around.lo;
            let clamped = clamp(h, around.lo - 0.05 * span, around.hi + 0.05 * span);
            h = mix(h, clamped, smoothstep(0.05, 0.5, motion));
        }
        samples = history.depth.z;
        cloud_depth = history.depth.x;
        front_depth = history.depth.w;
        value = h;
        if (is_fresh) {
            samples = min(samples + 1.0, tu.pattern.w);
            value = mix(h, fresh, 1.0 / samples);
            cloud_depth = fresh_d.x;
            front_depth = fresh_d.w;
        }
    } else if (is_fresh) {
        value = fresh;
        cloud_depth = fresh_d.x;
        front_depth = fresh_d.w;
        samples = 1.0;
    } else {
        value = around.blend;
        cloud_depth = around.cloud_depth;
        front_depth = around.front_depth;
        samples = 0.0;
    }
    textureStore(out_clouds, p, value);
    // a: the front depth (m) of the last sample that reached this pixel (0 = no cloud).
    textureStore(out_depth, p, vec4f(cloud_depth, scene_t, samples, front_depth));
}
