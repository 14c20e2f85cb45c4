// The medium both the march and the path tracer see: the per-frame parameters, the noise and
// weather textures, and the density at a point (noise model or debug media). Passes that
// include this module bind 0-5 and 9 as below and keep 6-8 for their own outputs.

struct MarchUniforms {
    inv_view_proj_rel: mat4x4f, // NDC to positions relative to the camera (depth.wgsl)
    camera: vec4f,          // xyz position (m), w: depth value of the near plane
    planet: vec4f,          // xyz up, w: planet radius (m)
    sun: vec4f,             // xyz direction toward the sun, w: illuminance
    sun_color: vec4f,       // rgb, w: depth value meaning "far / sky"
    layer: vec4f,           // bottom, top altitude (m), softness, max distance (m)
    shape: vec4f,           // coverage, density, extinction (1/m), albedo
    scales: vec4f,          // 1/base scale, 1/detail scale, 1/weather extent, detail strength
    wind: vec4f,            // weather-map offset (m, tangent x/z), base-noise offset (m)
    wind_detail: vec4f,     // detail-noise offset (m, tangent x/z), edge sharpness, unused
    phase: vec4f,           // phase parameters (see phase.wgsl)
    ms: vec4f,              // octaves, attenuation a, contribution b, eccentricity c
    ambient_top: vec4f,     // rgb, w: light-march distance (m)
    ambient_bottom: vec4f,  // rgb, w: light-march steps
    march: vec4f,           // min steps, max steps, transmittance cutoff, jitter (0/1)
    haze: vec4f,            // rgb, w: haze start distance (m)
    misc: vec4f,            // 1/haze fade distance, phase model, debug mode, has depth (0/1)
    debug: vec4f,           // slab bottom, slab top, debug density, unused
    debug_sphere: vec4f,    // sphere center xyz, radius
    tangent_x: vec4f,       // world-space horizontal axis for the weather map, w: unused
    tangent_z: vec4f,       // second horizontal axis, w: trace resolution divisor (1, 2, 4)
    layer_types: vec4f,     // cloud type of layers 1-3, w: weight of the "to" weather map
    horizon: vec4f,         // horizon gradient: strength, start distance (m), coverage, type
    cirrus: vec4f,          // high layer: coverage, altitude (m), optical depth; w: light-step growth
    skew: vec4f,            // xyz: how far (m) cloud tops lean downwind of their bases
    grid: vec4f,            // trace grid width, height, block edge k (1, 2, 4), pixel angle (rad)
    pattern: vec4f,         // this frame's offset in the block (x, y), visit index, unused
    opts: vec4f,            // coarse-then-fine, distance-grown steps, noise LOD, light LOD (0/1)
    viewport: vec4f,        // the rectangle of the scene targets rendered: x, y, width, height (px)
    ms_model: vec4f,        // multiple scattering: 0 single, 1 octaves, 2 delta-Eddington; y: phase g; z: the beam's narrow spread, w: its narrow weight (PhaseModel::beam_split)
    shadow_light: vec4f,    // light from the cloud shadow map (0/1), local distance (m), local steps, unused
}

// Per-frame parameters: a read-only storage buffer, not a uniform (lavapipe compiles a shader
// variant per distinct uniform value; see FRAME_PARAMS_USAGE in src/gpu/compute.rs).
@group(0) @binding(0) var<storage, read> u: MarchUniforms;
@group(0) @binding(1) var base_tex: texture_3d<f32>;
@group(0) @binding(2) var detail_tex: texture_3d<f32>;
@group(0) @binding(3) var weather_from: texture_2d<f32>;
@group(0) @binding(4) var blue_noise: texture_2d<f32>;
@group(0) @binding(5) var noise_sampler: sampler;
@group(0) @binding(9) var weather_to: texture_2d<f32>;

const DEBUG_OFF: u32 = 0u;
const DEBUG_SLAB: u32 = 1u;
const DEBUG_SPHERE: u32 = 2u;

// Texel sizes (m) of the base and detail volumes, set once per invocation.
var<private> base_texel: f32;
var<private> detail_texel: f32;

// Mip level at which one texel covers `footprint` meters (0 with the noise LOD off).
fn lod_for(footprint: f32, texel: f32) -> f32 {
    if (u.opts.z < 0.5 || footprint <= texel) {
        return 0.0;
    }
    return log2(footprint / texel);
}

// The medium a pipeline is built for (a pipeline-overridable constant, MarchVariant in
// src/gpu/march.rs): 0 the noise model, 1 the debug slab, 2 the debug sphere; 3, the default,
// as the frame parameters say (the passes that do not specialise). A software rasteriser runs
// every branch's body under a mask, taken or not: with the medium a constant, the noise model's
// march carries none of the debug media's code.
override MEDIUM: u32 = 3u;

fn debug_mode() -> u32 {
    if (MEDIUM < 3u) {
        return MEDIUM;
    }
    return u32(u.misc.z);
}

fn horizontal_of(p: vec3f) -> vec2f {
    return vec2f(dot(p, u.tangent_x.xyz), dot(p, u.tangent_z.xyz));
}

// The weather map at a horizontal position: the running transition's two maps, blended. Both
// maps are read and the weight picks (exactly the "to" map at w >= 1, the "from" map at
// w <= 0): a software rasteriser runs every branch's fetch whether taken or not, so early
// returns cost a third fetch.
fn weather_at(horizontal: vec2f) -> vec4f {
    let uv = (horizontal + u.wind.xy) * u.scales.z;
    let w = u.layer_types.w;
    let a = textureSampleLevel(weather_from, noise_sampler, uv, 0.0);
    let b = textureSampleLevel(weather_to, noise_sampler, uv, 0.0);
    return select(select(mix(a, b, w), a, w <= 0.0), b, w >= 1.0);
}

// Unitless density at p (σt = density × extinction); `cheap` skips the detail erosion.
// `footprint` (m) is how wide a region the sample stands for: it picks the noise mip level.
fn sample_density(p: vec3f, cheap: bool, footprint: f32) -> f32 {
    let up = u.planet.xyz;
    let radius = u.planet.w;
    let mode = debug_mode();
    if (mode == DEBUG_SLAB) {
        let h = altitude(p, up, radius);
        return select(0.0, u.debug.z, h >= u.debug.x && h <= u.debug.y);
    }
    if (mode == DEBUG_SPHERE) {
        return select(0.0, u.debug.z, length(p - u.debug_sphere.xyz) <= u.debug_sphere.w);
    }
    let h = altitude(p, up, radius);
    let hf = (h - u.layer.x) / (u.layer.y - u.layer.x);
    if (hf < 0.0 || hf > 1.0) {
        return 0.0;
    }
    let horizontal = horizontal_of(p);
    let weather = weather_at(horizontal);
    var coverage = u.shape.x * weather.rgb;
    var types = u.layer_types.xyz;
    // Horizon Zero Dawn's gradient: far away, layer 1 tends to big cumulus at a set coverage.
    if (u.horizon.x > 0.0) {
        let far = length(horizontal - horizontal_of(u.camera.xyz));
        let g = u.horizon.x * smoothstep(u.horizon.y, u.horizon.y * 1.6 + 1.0, far);
        coverage.x = mix(coverage.x, max(coverage.x, u.horizon.z), g);
        types.x = mix(types.x, u.horizon.w, g);
    }
    // Where no layer's height profile reaches above its coverage threshold (no coverage at
    // all, above the tops, below the bases) the density is exactly 0 without the base or detail
    // noise: a GPU skips the fetches there (llvmpipe runs them under a mask all the same).
    let profiles = layer_profiles(hf, types);
    let cumulus = cumuliform_weights(types);
    if (!layers_can_cloud(profiles, coverage, cumulus)) {
        return 0.0;
    }
    // Wind shear: higher parts of a cloud lean downwind.
    let sheared = horizontal_of(p + u.skew.xyz * hf);
    let q = vec3f(sheared.x + u.wind.z, h, sheared.y + u.wind.w);
    let base = textureSampleLevel(base_tex, noise_sampler, q * u.scales.x, lod_for(footprint, base_texel));
    let b = profiled_base_density(hf, base, coverage, profiles, cumulus, u.layer.z);
    if (b <= 0.0 || cheap) {
        return b * u.shape.y;
    }
    let qd = vec3f(sheared.x + u.wind_detail.x, h, sheared.y + u.wind_detail.y);
    let detail = textureSampleLevel(detail_tex, noise_sampler, qd * u.scales.y, lod_for(footprint, detail_texel)).rgb;
    return eroded_density(hf, b, detail, u.shape.x, u.scales.w, u.wind_detail.z, u.shape.y);
}

// Where a ray from p toward the sun leaves the medium (m).
fn light_exit(p: vec3f, d: vec3f) -> f32 {
    let mode = debug_mode();
    if (mode == DEBUG_SPHERE) {
        let s = ball_segment(p, d, u.debug_sphere.xyz, u.debug_sphere.w, 1e9);
        return select(0.0, s.a.y, s.count > 0u);
    }
    let top = select(u.layer.y, u.debug.y, mode == DEBUG_SLAB);
    let r = sphere_roots(p, d, u.planet.xyz, u.planet.w, top);
    return select(0.0, max(r.t1, 0.0), r.hit);
}

// The intervals of a ray inside the medium's bounds (the layer shell, or the debug slab or
// sphere), clipped to [0, max_t] and the ground.
fn medium_segments(cam: vec3f, dir: vec3f, max_t: f32) -> Segments {
    let up = u.planet.xyz;
    let radius = u.planet.w;
    switch (debug_mode()) {
        case 1u: { return shell_segments(cam, dir, up, radius, u.debug.x, u.debug.y, max_t); }
        case 2u: { return ball_segment(cam, dir, u.debug_sphere.xyz, u.debug_sphere.w, max_t); }
        default: { return shell_segments(cam, dir, up, radius, u.layer.x, u.layer.y, max_t); }
    }
}
