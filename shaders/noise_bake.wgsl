// Noise bake (compute, at init): base-shape and detail volumes and the 2D weather map.
// Texel centers sample the unit cube, so every output tiles in all axes.

struct BakeParams {
    seed: u32,
    size: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> params: BakeParams;

fn unit_pos3(id: vec3u) -> vec3f {
    return (vec3f(id) + 0.5) / f32(params.size);
}

@group(0) @binding(1) var volume_out: texture_storage_3d<rgba8unorm, write>;

// Base shape (Aetherius "Cloud textures"): R Perlin-Worley, G/B/A Worley fBM of rising frequency.
@compute @workgroup_size(4, 4, 4)
fn bake_base(@builtin(global_invocation_id) id: vec3u) {
    if (any(id >= vec3u(params.size))) {
        return;
    }
    let p = unit_pos3(id);
    let s = params.seed * 16u;
    let perlin_v = perlin_fbm(p, 4, 5, 0.5, s);
    let worley_v = worley_fbm(p, 4, s + 3u);
    // Erode the billowy Worley shape's borders with Perlin (remap Perlin into [worley - 1, 1]).
    let perlin_worley = clamp(remap(perlin_v, worley_v - 1.0, 1.0, 0.0, 1.0), 0.0, 1.0);
    let g = worley_fbm(p, 4, s + 6u);
    let b = worley_fbm(p, 8, s + 9u);
    let a = worley_fbm(p, 16, s + 12u);
    textureStore(volume_out, id, vec4f(perlin_worley, g, b, a));
}

// Detail (32³ by default): R/G/B Worley fBM of rising frequency; A unused (1).
@compute @workgroup_size(4, 4, 4)
fn bake_detail(@builtin(global_invocation_id) id: vec3u) {
    if (any(id >= vec3u(params.size))) {
        return;
    }
    let p = unit_pos3(id);
    let s = params.seed * 16u + 8u;
    textureStore(volume_out, id, vec4f(worley_fbm(p, 2, s), worley_fbm(p, 4, s + 3u), worley_fbm(p, 6, s + 6u), 1.0));
}
