// Ray-march pass (compute): per pixel, the in-scattered radiance L, the transmittance T and
// a representative cloud depth. Composite later does out = scene * T + L.

// Where the rendered rectangle sits in the scene depth (load_scene_depth adds its origin).
fn scene_viewport() -> vec4f {
    return u.viewport;
}

//!SCENE_DEPTH_BINDING(6)
@group(0) @binding(7) var march_out: texture_storage_2d<rgba16float, write>;
// r: representative cloud depth (m, 0 = no cloud), g: the scene distance the ray was clipped at,
// b: 0, a: front depth (m, where the ray first met cloud; 0 = no cloud).
@group(0) @binding(8) var depth_out: texture_storage_2d<rgba32float, write>;
// The per-ray counters: density samples taken along the ray, and toward the sun.
@group(0) @binding(12) var stats_out: texture_storage_2d<rg32float, write>;

@compute @workgroup_size(8, 8, 1)
fn march(@builtin(global_invocation_id) id: vec3u) {
    // The march runs on the sparse grid: invocation `id` traces grid pixel id * k + offset.
    let k = u32(u.grid.z);
    let grid = vec2u(u.grid.xy);
    let gp = id.xy * k + vec2u(u.pattern.xy);
    if (any(id.xy >= textureDimensions(march_out)) || any(gp >= grid)) {
        return;
    }
    light_samples = 0u;
    let ndc = pixel_ndc(gp, grid);
    let cam = u.camera.xyz;
    let dir = view_ray_dir(u.inv_view_proj_rel, ndc, u.camera.w);

    // At reduced resolution a traced pixel stands for a block of scene pixels: it reads the
    // scene depth at the block's center; the composite's upsample handles the edges.
    var max_t = u.layer.w;
    var scene_t = NO_SCENE;
    if (u.misc.w > 0.5) {
        let scale = u32(u.tangent_z.w);
        let full = vec2u(u.viewport.zw);
        let at = min(gp * scale + vec2u(scale / 2u), full - vec2u(1u));
        scene_t = scene_distance_at(u.inv_view_proj_rel, u.sun_color.w, ndc, load_scene_depth(at));
        max_t = min(max_t, scene_t);
    }

    // Blue-noise jitter of the sample position inside each step, rotated by the golden ratio
    // on every visit of this pixel, so that temporal accumulation sees fresh offsets.
    var jitter = 0.5;
    if (u.march.w > 0.5) {
        let bn_size = textureDimensions(blue_noise);
        let bn = textureLoad(blue_noise, gp % bn_size, 0).r;
        jitter = fract(bn + u.pattern.z * 0.61803398875);
    }
    let ray = march_ray(cam, dir, max_t, jitter, u.grid.w);
    textureStore(march_out, id.xy, vec4f(ray.radiance, ray.transmittance));
    textureStore(depth_out, id.xy, vec4f(ray.cloud_depth, scene_t, 0.0, ray.front_depth));
    textureStore(stats_out, id.xy, vec4f(f32(ray.samples), f32(light_samples), 0.0, 0.0));
}
