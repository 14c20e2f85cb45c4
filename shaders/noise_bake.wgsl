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

// Base shape (Aetherius "Cloud textures") from its four Worley fBMs (R's and those of G, B, A):
// R Perlin-Worley, G/B/A Worley fBM of rising frequency.
fn base_texel(p: vec3f, s: u32, worley: vec4f) -> vec4f {
    let perlin_v = perlin_fbm(p, 4, 5, 0.5, s);
    // Erode the billowy Worley shape's borders with Perlin (remap Perlin into [worley - 1, 1]).
    let perlin_worley = clamp(remap(perlin_v, worley.x - 1.0, 1.0, 0.0, 1.0), 0.0, 1.0);
    return vec4f(perlin_worley, worley.yzw);
}

// The base volume, one texel per invocation: for sizes `bake_base` cannot serve.
@compute @workgroup_size(4, 4, 4)
fn bake_base_plain(@builtin(global_invocation_id) id: vec3u) {
    if (any(id >= vec3u(params.size))) {
        return;
    }
    let p = unit_pos3(id);
    let s = params.seed * 16u;
    let worley = vec4f(worley_fbm(p, 4, s + 3u), worley_fbm(p, 4, s + 6u), worley_fbm(p, 8, s + 9u), worley_fbm(p, 16, s + 12u));
    textureStore(volume_out, id, base_texel(p, s, worley));
}

// The feature points of the 4x4x4 cells around one workgroup's texels, for one Worley octave.
var<workgroup> feature_points: array<vec3f, 64>;

// Squared distance from p (in cells) to the feature point at table index k.
fn feature_distance_sq(p: vec3f, k: vec3u) -> f32 {
    let d = p - feature_points[k.x + 4u * (k.y + 4u * k.z)];
    return dot(d, d);
}

// The nearest of the three feature points in a row of the table, starting at k.
fn row_distance_sq(p: vec3f, k: vec3u) -> f32 {
    return min(min(feature_distance_sq(p, k), feature_distance_sq(p, k + vec3u(1u, 0u, 0u))), feature_distance_sq(p, k + vec3u(2u, 0u, 0u)));
}

// `worley` (noise.wgsl) for a whole 4x4x4 workgroup whose texels lie in at most 2 cells per
// axis (the host picks `bake_base` only for sizes where every octave's cell spans a whole
// number >= 2 of texels, `base_table_fits` in src/gpu/noise.rs): their 27-cell neighbourhoods
// fit in 4x4x4 cells, so each invocation hashes one of those feature points into workgroup
// memory and every texel takes the nearest of its 27 from there. Same points, same arithmetic,
// same minimum as `worley`, with one hash per texel instead of up to 27: the 128^3 base bake
// takes 0.7 s on llvmpipe instead of 2.0 s. The 27 are written out and nothing branches:
// llvmpipe runs both sides of a branch under masks and a loop's bookkeeping on every pass,
// and looped or with an in-shader fallback this bake took 1.3 to 1.9 s.
fn worley_wg(p_unit: vec3f, freq: i32, seed: u32, first_texel: vec3f, local: vec3u) -> f32 {
    let fq = f32(freq);
    let origin = vec3i(floor(first_texel * fq)) - vec3i(1);
    let c = origin + vec3i(local);
    workgroupBarrier(); // the previous octave's readers are done with the table
    feature_points[local.x + 4u * (local.y + 4u * local.z)] = vec3f(c) + hash33(wrap_cell(c, vec3i(freq)), seed);
    workgroupBarrier();
    let p = p_unit * fq;
    let k = vec3u(vec3i(floor(p)) - origin) - vec3u(1u);
    let z0 = min(min(row_distance_sq(p, k), row_distance_sq(p, k + vec3u(0u, 1u, 0u))), row_distance_sq(p, k + vec3u(0u, 2u, 0u)));
    let z1 = min(min(row_distance_sq(p, k + vec3u(0u, 0u, 1u)), row_distance_sq(p, k + vec3u(0u, 1u, 1u))), row_distance_sq(p, k + vec3u(0u, 2u, 1u)));
    let z2 = min(min(row_distance_sq(p, k + vec3u(0u, 0u, 2u)), row_distance_sq(p, k + vec3u(0u, 1u, 2u))), row_distance_sq(p, k + vec3u(0u, 2u, 2u)));
    return 1.0 - clamp(sqrt(min(min(z0, z1), z2)), 0.0, 1.0);
}

// `worley_fbm` (noise.wgsl) through `worley_wg`.
fn worley_fbm_wg(p: vec3f, freq: i32, seed: u32, first_texel: vec3f, local: vec3u) -> f32 {
    return worley_wg(p, freq, seed, first_texel, local) * 0.625
        + worley_wg(p, freq * 2, seed + 1u, first_texel, local) * 0.25
        + worley_wg(p, freq * 4, seed + 2u, first_texel, local) * 0.125;
}

// The base volume through the workgroup's feature-point table; the same texels as
// `bake_base_plain`. Every invocation runs to the end (the barriers need all of them).
@compute @workgroup_size(4, 4, 4)
fn bake_base(
    @builtin(global_invocation_id) id: vec3u,
    @builtin(workgroup_id) wg: vec3u,
    @builtin(local_invocation_id) local: vec3u,
) {
    let p = unit_pos3(id);
    let first = unit_pos3(wg * 4u);
    let s = params.seed * 16u;
    let worley = vec4f(
        worley_fbm_wg(p, 4, s + 3u, first, local),
        worley_fbm_wg(p, 4, s + 6u, first, local),
        worley_fbm_wg(p, 8, s + 9u, first, local),
        worley_fbm_wg(p, 16, s + 12u, first, local),
    );
    if (all(id < vec3u(params.size))) {
        textureStore(volume_out, id, base_texel(p, s, worley));
    }
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
