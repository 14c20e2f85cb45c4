// Cloud shadow map (compute): for each texel of a sun-space square around the camera, the
// clouds' optical depth along the sun's ray through it, stored as a Beer shadow map (Hillaire
// 2016, "Physically Based Sky, Atmosphere and Cloud Rendering in Frostbite", section 5.6):
// r = front depth (m along the light from the map's depth origin), g = mean extinction (1/m)
// between the first and last cloud sample, b = total optical depth, a = exp(-b). The optical
// depth from the sun to a point at depth d is min(g * max(d - r, 0), b).
//
// Texels are addressed toroidally: world cell c (along each axis) lives in texel c mod N, so
// when the camera moves by whole texels only the cells that entered the square are marched
// again, and the others keep what they hold. The rest of the map is refreshed a slice of rows
// per frame (row mod slices == this frame's slice).

struct ShadowUniforms {
    light_dir: vec4f,  // xyz: the direction light travels (-sun), w: depth origin (m)
    axis_u: vec4f,     // xyz: the map's u axis, w: world coordinate (m) of the window's first cell along u
    axis_v: vec4f,     // xyz: the map's v axis, w: the same along v
    grid: vec4f,       // resolution N, texel (m), the window's first cell mod N along u, v
    update: vec4f,     // slices, this frame's slice, full update (0/1), steps per ray
    previous: vec4f,   // the previous window's first cell minus this one's (u, v), unused, medium top (m)
}

@group(0) @binding(6) var<storage, read> sh: ShadowUniforms;
@group(0) @binding(7) var shadow_out: texture_storage_2d<rgba16float, write>;

// Whether cell j (0..N, from the window's first cell) was outside the previous window.
fn entered(j: f32, shift: f32, n: f32) -> bool {
    return j < shift || j >= shift + n;
}

@compute @workgroup_size(8, 8, 1)
fn shadow(@builtin(global_invocation_id) id: vec3u) {
    let n = u32(sh.grid.x);
    if (any(id.xy >= vec2u(n))) {
        return;
    }
    let nf = sh.grid.x;
    // Cell offset inside the window for this storage texel: (x - first mod N) mod N.
    let j = vec2f((vec2u(id.xy + vec2u(n)) - vec2u(sh.grid.zw)) % vec2u(n));
    let due = sh.update.z > 0.5
        || (id.y % u32(sh.update.x)) == u32(sh.update.y)
        || entered(j.x, sh.previous.x, nf)
        || entered(j.y, sh.previous.y, nf);
    if (!due) {
        return;
    }
    base_texel = 1.0 / (u.scales.x * f32(textureDimensions(base_tex).x));
    detail_texel = 1.0 / (u.scales.y * f32(textureDimensions(detail_tex).x));
    let texel = sh.grid.y;
    let d = sh.light_dir.xyz;
    // The texel's center on the plane at depth 0, then back toward the sun to start the ray.
    let plane = sh.axis_u.xyz * (sh.axis_u.w + (j.x + 0.5) * texel)
        + sh.axis_v.xyz * (sh.axis_v.w + (j.y + 0.5) * texel)
        + d * sh.light_dir.w;
    // The plane is perpendicular to the light, so it tilts: far from the camera it may lie
    // above the medium or deep below the ground. Each ray starts where the sphere of the
    // medium's top (with headroom) meets the texel's line on the sun's side of the plane.
    let top = sphere_roots(plane, -d, u.planet.xyz, u.planet.w, sh.previous.w);
    let back = select(0.0, max(top.t1, 0.0), top.hit);
    let start = plane - d * back;
    // No far limit: the medium's intervals end at the ground.
    let seg = medium_segments(start, d, back + 1.0e7);
    let len_a = select(0.0, seg.a.y - seg.a.x, seg.count > 0u);
    let len_b = select(0.0, seg.b.y - seg.b.x, seg.count > 1u);
    let total = len_a + len_b;
    // Where the ray enters the medium: the front of an empty texel, so that filtering across
    // a cloud's edge blends sensible depths.
    var front = select(0.0, seg.a.x - back, seg.count > 0u);
    var last = front;
    var tau = 0.0;
    var found = false;
    if (total > 0.0) {
        let steps = u32(sh.update.w);
        let dt = total / f32(steps);
        // Uniform steps over the medium's intervals, sampled at their midpoints (no jitter: the
        // map must be the same for the same inputs). A homogeneous medium integrates exactly.
        for (var i = 0u; i < steps; i++) {
            let s = (f32(i) + 0.5) * dt;
            let t = select(seg.b.x + (s - len_a), seg.a.x + s, s < len_a);
            let density = sample_density(start + d * t, false, texel);
            if (density > 0.0) {
                if (!found) {
                    front = t - 0.5 * dt - back;
                    found = true;
                }
                last = t + 0.5 * dt - back;
                tau += density * u.shape.z * dt;
            }
        }
    }
    let mean_extinction = select(0.0, tau / max(last - front, 1e-3), found);
    textureStore(shadow_out, id.xy, vec4f(front, mean_extinction, tau, exp(-tau)));
}
