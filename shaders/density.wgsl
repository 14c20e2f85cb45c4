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

// The carved base noise (Perlin-Worley carved by the Worley fBM) spans only about [0.68, 0.87]
// over the baked volume (1st to 99th percentile). Thresholded as it is against 1 - coverage, it
// leaves the height profile, not the 3D noise, to decide where a cloud ends: flat lids and soft
// horizontal layers. Cumuliform layers stretch it to [0, 1], so that the noise's cells carve
// their outline (and its gradient, five times steeper, their edges), and take their coverage
// through c (2 - c), which keeps a coverage's cloud fraction about what it was (0.4 -> 0.64,
// 0.8 -> 0.96: matched on the presets' ground and from-above views). Stratiform decks keep the
// narrow range: stretched, an overcast deck at coverage 0.999 fell apart into holes.
const CARVED_LOW: f32 = 0.68;
const CARVED_HIGH: f32 = 0.87;

// How cumuliform each layer is: 0 up to stratocumulus (cloud type 1/3), 1 from cumulus (2/3).
fn cumuliform_weights(types: vec3f) -> vec3f {
    return smoothstep(vec3f(1.0 / 3.0), vec3f(2.0 / 3.0), types);
}

// One layer's base shape: the carved noise under its height profile, eroded by its coverage c
// (none where c is 0); `cumulus` is the layer's cumuliform weight.
fn layer_cloud(carved: f32, profile: f32, c: f32, cumulus: f32) -> f32 {
    let shaped = mix(carved, clamp((carved - CARVED_LOW) / (CARVED_HIGH - CARVED_LOW), 0.0, 1.0), cumulus);
    let threshold = 1.0 - mix(c, c * (2.0 - c), cumulus);
    let cloud = shaped * profile;
    return select(0.0, clamp(remap(cloud, threshold, 1.0, 0.0, 1.0), 0.0, 1.0), c > 0.0);
}

// The densest layer's base shape. The layers written out, not looped: no computed index into
// `profiles` and `coverage`.
fn layers_cloud(carved: f32, profiles: vec3f, coverage: vec3f, cumulus: vec3f) -> f32 {
    return max(max(layer_cloud(carved, profiles.x, coverage.x, cumulus.x), layer_cloud(carved, profiles.y, coverage.y, cumulus.y)), layer_cloud(carved, profiles.z, coverage.z, cumulus.z));
}

// Whether any layer can have cloud here, whatever the noise: the carved noise is at most 1 (in
// f32 too: base.r <= 1), stretched it is 1 there too, and a layer's cloud never falls as it
// grows, so its cloud at carved = 1 bounds it. Where this is false the base density is exactly 0
// and the noise need not be read.
fn layers_can_cloud(profiles: vec3f, coverage: vec3f, cumulus: vec3f) -> bool {
    return layers_cloud(1.0, profiles, coverage, cumulus) > 0.0;
}

// Base shape before detail erosion at h in [0, 1] (profile::layered_base_density). `coverage`
// holds each layer's effective coverage (global × weather map), `profiles` each layer's height
// profile at h (layer_profiles), `cumulus` each layer's cumuliform weight; the densest
// layer wins.
fn profiled_base_density(h: f32, base: vec4f, coverage: vec3f, profiles: vec3f, cumulus: vec3f, softness: f32) -> f32 {
    let low_freq_fbm = base.g * 0.625 + base.b * 0.25 + base.a * 0.125;
    let carved = remap(base.r, low_freq_fbm - 1.0, 1.0, 0.0, 1.0);
    return layers_cloud(carved, profiles, coverage, cumulus) * layer_softening(h, softness);
}

// Detail erosion: wispy at the bottom, billowy higher up; returns density before extinction.
// `sharpness` (>= 1) steepens the eroded ramp into the body, capped at full density
// (profile::eroded_density): the outline stays where it is, the edge crisps.
fn eroded_density(h: f32, base: f32, detail: vec3f, coverage: f32, strength: f32, sharpness: f32, density: f32) -> f32 {
    let high_freq_fbm = detail.r * 0.625 + detail.g * 0.25 + detail.b * 0.125;
    var d = high_freq_fbm + (1.0 - 2.0 * high_freq_fbm) * clamp(h * 5.0, 0.0, 1.0);
    d *= strength * exp(-coverage * 0.75);
    return clamp(sharpness * remap(base, d, 1.0, 0.0, 1.0), 0.0, 1.0) * density;
}
