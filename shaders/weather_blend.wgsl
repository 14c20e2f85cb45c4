// Freezes a running transition: out = mix(from, to, weight), texel by texel. The result
// becomes the new "from" map, so an interrupted transition never pops. In half floats: 8 bits
// would move each texel by up to half a step (src/gpu/weather.rs).

struct BlendParams {
    weight: f32,
    size: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> params: BlendParams;
@group(0) @binding(1) var map_from: texture_2d<f32>;
@group(0) @binding(2) var map_to: texture_2d<f32>;
@group(0) @binding(3) var map_out: texture_storage_2d<rgba16float, write>;

@compute @workgroup_size(8, 8, 1)
fn blend_maps(@builtin(global_invocation_id) id: vec3u) {
    if (any(id.xy >= vec2u(params.size))) {
        return;
    }
    let a = textureLoad(map_from, id.xy, 0);
    let b = textureLoad(map_to, id.xy, 0);
    textureStore(map_out, id.xy, mix(a, b, params.weight));
}
