// Weather map bake (compute): R, G, B coverage of cloud layers 1-3, A cirrus streaks. Tileable.

struct BakeParams {
    seed: u32,
    size: u32,
    // The first row this dispatch writes (a generation in slices over frames).
    row_offset: u32,
    _pad1: u32,
    // Cloud cells across the tile per layer (xyz); w unused.
    frequency: vec4u,
    // Amount of each layer (xyz); w unused.
    amount: vec4f,
}

@group(0) @binding(0) var<uniform> params: BakeParams;
@group(0) @binding(1) var map_out: texture_storage_2d<rgba8unorm, write>;

// One layer's coverage: Worley blobs eroded by Perlin, then a soft contrast curve so that the
// 3D base noise still carves the clouds.
fn layer_coverage(p: vec3f, freq: u32, amount: f32, seed: u32) -> f32 {
    if (amount <= 0.0) {
        return 0.0;
    }
    let f = i32(max(freq, 1u));
    let perlin_v = perlin_fbm(p, f, 4, 0.5, seed);
    let worley_v = worley_fbm(p, f, seed + 3u);
    let cells = clamp(remap(perlin_v, worley_v - 1.0, 1.0, 0.0, 1.0), 0.0, 1.0);
    return smoothstep(0.35, 1.0, cells) * amount;
}

@compute @workgroup_size(8, 8, 1)
fn bake_weather(@builtin(global_invocation_id) gid: vec3u) {
    let id = vec2u(gid.x, gid.y + params.row_offset);
    if (any(id >= vec2u(params.size))) {
        return;
    }
    let p = vec3f((vec2f(id) + 0.5) / f32(params.size), 0.0);
    let s = params.seed * 64u;
    let r = layer_coverage(p, params.frequency.x, params.amount.x, s);
    let g = layer_coverage(p, params.frequency.y, params.amount.y, s + 16u);
    let b = layer_coverage(p, params.frequency.z, params.amount.z, s + 32u);
    // Cirrus: streaks, long along x and thin across.
    let cirrus = perlin_fbm3(p, vec3i(2, 11, 1), 4, 0.55, s + 48u);
    textureStore(map_out, id, vec4f(r, g, b, smoothstep(0.35, 0.8, cirrus)));
}
