// Density model after Schneider, as described in the Aetherius thesis. Pure functions on the
// sampled noise; mirrors src/weather/profile.rs (tested there).

// Height profiles of stratus, stratocumulus, cumulus, cumulonimbus: (base, full_bottom,
// full_top, top) as fractions of the layer. Keep in sync with profile::PROFILES.
const PROFILES = array<vec4f, 4>(
    vec4f(0.0, 0.03, 0.08, 0.15),
    vec4f(0.0, 0.06, 0.2, 0.35),
    vec4f(0.02, 0.1, 0.4, 0.7),
    vec4f(0.02, 0.1, 0.75, 1.0),
);

fn height_profile(h: f32, cloud_type: f32) -> f32 {
    let x = clamp(cloud_type, 0.0, 1.0) * 3.0;
    let i = min(u32(floor(x)), 2u);
    // The two neighbouring profiles by selects, not by a computed index into PROFILES: a
    // software rasteriser keeps an indexed constant array in scratch memory and gathers from it
    // lane by lane, per sample and per layer.
    let lower = select(select(PROFILES[0], PROFILES[1], i == 1u), PROFILES[2], i == 2u);
    let upper = select(select(PROFILES[1], PROFILES[2], i == 1u), PROFILES[3], i == 2u);
    let p = mix(lower, upper, x - f32(i));
    let rise = clamp(remap(h, p.x, p.y, 0.0, 1.0), 0.0, 1.0);
    let fall = clamp(remap(h, p.z, p.w, 1.0, 0.0), 0.0, 1.0);
    return rise * fall;
}

fn layer_softening(h: f32, softness: f32) -> f32 {
    if (softness <= 0.0) {
        return select(0.0, 1.0, h >= 0.0 && h <= 1.0);
    }
    return clamp(h / softness, 0.0, 1.0) * clamp((1.0 - h) / softness, 0.0, 1.0);
}

// The three layers' height profiles at h.
fn layer_profiles(h: f32, types: vec3f) -> vec3f {
    return vec3f(height_profile(h, types.x), height_profile(h, types.y), height_profile(h, types.z));
}

// One layer's base shape: the carved noise under its height profile, eroded by its coverage c
// (none where c is 0).
fn layer_cloud(carved: f32, profile: f32, c: f32) -> f32 {
    let cloud = carved * profile;
    return select(0.0, clamp(remap(cloud, 1.0 - c, 1.0, 0.0, 1.0), 0.0, 1.0), c > 0.0);
}

// The densest layer's base shape. The layers written out, not looped: no computed index into
// `profiles` and `coverage`.
fn layers_cloud(carved: f32, profiles: vec3f, coverage: vec3f) -> f32 {
    return max(max(layer_cloud(carved, profiles.x, coverage.x), layer_cloud(carved, profiles.y, coverage.y)), layer_cloud(carved, profiles.z, coverage.z));
}

// Whether any layer can have cloud here, whatever the noise: the carved noise is at most 1 (in
// f32 too: base.r <= 1) and a layer's cloud never falls as it grows, so its cloud at carved = 1
// bounds it. Where this is false the base density is exactly 0 and the noise need not be read.
fn layers_can_cloud(profiles: vec3f, coverage: vec3f) -> bool {
    return layers_cloud(1.0, profiles, coverage) > 0.0;
}

// Base shape before detail erosion at h in [0, 1] (profile::layered_base_density). `coverage`
// holds each layer's effective coverage (global × weather map), `profiles` each layer's height
// profile at h (layer_profiles); the densest layer wins.
fn profiled_base_density(h: f32, base: vec4f, coverage: vec3f, profiles: vec3f, softness: f32) -> f32 {
    let low_freq_fbm = base.g * 0.625 + base.b * 0.25 + base.a * 0.125;
    let carved = remap(base.r, low_freq_fbm - 1.0, 1.0, 0.0, 1.0);
    return layers_cloud(carved, profiles, coverage) * layer_softening(h, softness);
}

// Detail erosion: wispy at the bottom, billowy higher up; returns density before extinction.
fn eroded_density(h: f32, base: f32, detail: vec3f, coverage: f32, strength: f32, density: f32) -> f32 {
    let high_freq_fbm = detail.r * 0.625 + detail.g * 0.25 + detail.b * 0.125;
    var d = high_freq_fbm + (1.0 - 2.0 * high_freq_fbm) * clamp(h * 5.0, 0.0, 1.0);
    d *= strength * exp(-coverage * 0.75);
    return clamp(remap(base, d, 1.0, 0.0, 1.0), 0.0, 1.0) * density;
}
