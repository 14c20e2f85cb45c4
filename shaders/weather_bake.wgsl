// Weather map bake (compute): R coverage, G cloud type, B density, A unused. Tileable.

struct BakeParams {
    seed: u32,
    size: u32,
    frequency: u32,
    _pad: u32,
    // Mean cloud type, type variation, density variation, unused.
    weather: vec4f,
}

@group(0) @binding(0) var<uniform> params: BakeParams;
@group(0) @binding(1) var map_out: texture_storage_2d<rgba8unorm, write>;

@compute @workgroup_size(8, 8, 1)
fn bake_weather(@builtin(global_invocation_id) id: vec3u) {
    if (any(id.xy >= vec2u(params.size))) {
        return;
    }
    let p = vec3f((vec2f(id.xy) + 0.5) / f32(params.size), 0.0);
    let f = i32(params.frequency);
    let s = params.seed * 16u;
    // Cloud cells: Worley blobs eroded by Perlin, then a contrast curve so that the map holds
    // both clear gaps and solid cores.
    let perlin_v = perlin_fbm(p, f, 4, 0.5, s);
    let worley_v = worley_fbm(p, f, s + 3u);
    let cells = clamp(remap(perlin_v, worley_v - 1.0, 1.0, 0.0, 1.0), 0.0, 1.0);
    let coverage = smoothstep(0.35, 1.0, cells);
    let type_noise = perlin_fbm(p, max(f / 3, 1), 3, 0.5, s + 6u) - 0.5;
    let cloud_type = clamp(params.weather.x + 2.0 * type_noise * params.weather.y, 0.0, 1.0);
    let density = 1.0 - params.weather.z * perlin_fbm(p, f * 2, 2, 0.5, s + 9u);
    textureStore(map_out, id.xy, vec4f(coverage, cloud_type, density, 1.0));
}
