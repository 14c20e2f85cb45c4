// Ray-march pass (compute): per pixel, the in-scattered radiance L, the transmittance T and
// a representative cloud depth. Composite later does out = scene * T + L.

struct MarchUniforms {
    inv_view_proj: mat4x4f,
    camera: vec4f,          // xyz position (m), w: depth value of the near plane
    planet: vec4f,          // xyz up, w: planet radius (m)
    sun: vec4f,             // xyz direction toward the sun, w: illuminance
    sun_color: vec4f,       // rgb, w: depth value meaning "far / sky"
    layer: vec4f,           // bottom, top altitude (m), softness, max distance (m)
    shape: vec4f,           // coverage, density, extinction (1/m), albedo
    scales: vec4f,          // 1/base scale, 1/detail scale, 1/weather extent, detail strength
    wind: vec4f,            // weather-map offset (m, tangent x/z), base-noise offset (m)
    wind_detail: vec4f,     // detail-noise offset (m, tangent x/z), unused, unused
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
}

// Where the rendered rectangle sits in the scene depth (load_scene_depth adds its origin).
fn scene_viewport() -> vec4f {
    return u.viewport;
}

// Per-frame parameters: a read-only storage buffer, not a uniform (lavapipe compiles a shader
// variant per distinct uniform value; see FRAME_PARAMS_USAGE in src/gpu/compute.rs).
@group(0) @binding(0) var<storage, read> u: MarchUniforms;
@group(0) @binding(1) var base_tex: texture_3d<f32>;
@group(0) @binding(2) var detail_tex: texture_3d<f32>;
@group(0) @binding(3) var weather_from: texture_2d<f32>;
@group(0) @binding(4) var blue_noise: texture_2d<f32>;
@group(0) @binding(5) var noise_sampler: sampler;
//!SCENE_DEPTH_BINDING(6)
@group(0) @binding(7) var march_out: texture_storage_2d<rgba16float, write>;
// r: representative cloud depth (m, 0 = no cloud), g: the scene distance the ray was clipped at,
// b: density samples taken along the ray, a: density samples taken toward the sun.
@group(0) @binding(8) var depth_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(9) var weather_to: texture_2d<f32>;

const DEBUG_OFF: u32 = 0u;
const DEBUG_SLAB: u32 = 1u;
const DEBUG_SPHERE: u32 = 2u;

// Texel sizes (m) of the base and detail volumes, set once per invocation.
var<private> base_texel: f32;
var<private> detail_texel: f32;
// Density samples taken toward the sun by this invocation (the per-ray counter).
var<private> light_samples: u32;

// Mip level at which one texel covers `footprint` meters (0 with the noise LOD off).
fn lod_for(footprint: f32, texel: f32) -> f32 {
    if (u.opts.z < 0.5 || footprint <= texel) {
        return 0.0;
    }
    return log2(footprint / texel);
}

fn debug_mode() -> u32 {
    return u32(u.misc.z);
}

fn unproject(ndc: vec2f, depth: f32) -> vec4f {
    return u.inv_view_proj * vec4f(ndc, depth, 1.0);
}

fn horizontal_of(p: vec3f) -> vec2f {
    return vec2f(dot(p, u.tangent_x.xyz), dot(p, u.tangent_z.xyz));
}

// The weather map at a horizontal position: the running transition's two maps, blended.
fn weather_at(horizontal: vec2f) -> vec4f {
    let uv = (horizontal + u.wind.xy) * u.scales.z;
    let w = u.layer_types.w;
    // Outside a transition only one map counts: one fetch (uniform branch, no divergence).
    if (w >= 1.0) {
        return textureSampleLevel(weather_to, noise_sampler, uv, 0.0);
    }
    let a = textureSampleLevel(weather_from, noise_sampler, uv, 0.0);
    if (w <= 0.0) {
        return a;
    }
    return mix(a, textureSampleLevel(weather_to, noise_sampler, uv, 0.0), w);
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
    // Empty space is cheap: no coverage here means no base or detail fetch at all.
    if (max(coverage.x, max(coverage.y, coverage.z)) <= 0.0) {
        return 0.0;
    }
    // Wind shear: higher parts of a cloud lean downwind.
    let sheared = horizontal_of(p + u.skew.xyz * hf);
    let q = vec3f(sheared.x + u.wind.z, h, sheared.y + u.wind.w);
    let base = textureSampleLevel(base_tex, noise_sampler, q * u.scales.x, lod_for(footprint, base_texel));
    let b = base_density(hf, base, coverage, types, u.layer.z);
    if (b <= 0.0 || cheap) {
        return b * u.shape.y;
    }
    let qd = vec3f(sheared.x + u.wind_detail.x, h, sheared.y + u.wind_detail.y);
    let detail = textureSampleLevel(detail_tex, noise_sampler, qd * u.scales.y, lod_for(footprint, detail_texel)).rgb;
    return eroded_density(hf, b, detail, u.shape.x, u.scales.w, u.shape.y);
}

struct Cirrus {
    radiance: vec3f,
    transmittance: f32,
    distance: f32,
}

// The high layer: a textured sheet at one altitude, lit by single scattering through its
// small optical depth (L = (1 - T) (E p + ambient) for a thin, non-absorbing sheet).
fn cirrus_layer(cam: vec3f, dir: vec3f, max_t: f32, cos_theta: f32, sun_radiance: vec3f) -> Cirrus {
    var none = Cirrus(vec3f(0.0), 1.0, 0.0);
    let up = u.planet.xyz;
    let radius = u.planet.w;
    let h_cam = altitude(cam, up, radius);
    let r = sphere_roots(cam, dir, up, radius, u.cirrus.y);
    if (!r.hit) {
        return none;
    }
    let t = select(r.t0, r.t1, h_cam < u.cirrus.y);
    if (t <= 0.0 || t > max_t) {
        return none;
    }
    let g = sphere_roots(cam, dir, up, radius, 0.0);
    if (h_cam >= 0.0 && g.hit && g.t0 > 0.0 && g.t0 < t) {
        return none;
    }
    let p = cam + dir * t;
    let streak = weather_at(horizontal_of(p)).a;
    let density = clamp(remap(streak, 1.0 - u.cirrus.x, 1.0, 0.0, 1.0), 0.0, 1.0);
    let mu = max(abs(dot(normalize(p + up * radius), dir)), 0.05);
    let transmittance = exp(-u.cirrus.z * density / mu);
    // Ice crystals scatter less forward than droplets, and light bounces between crystals
    // (Wrenninge-style): a flatter lobe, eccentricity scaled by 0.4.
    let source = sun_radiance * phase_eval(u32(u.misc.y), u.phase, cos_theta, 0.4) + u.ambient_top.rgb;
    return Cirrus((1.0 - transmittance) * source, transmittance, t);
}

fn haze_fade(distance: f32) -> f32 {
    return exp(-max(distance - u.haze.w, 0.0) * u.misc.x);
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

// Light steps for a sample `distance` meters from the camera: with the light LOD on, one fewer
// per doubling of the distance beyond 5 km (at least 2). Far clouds cover few pixels and their
// self-shadowing is soft, so fewer, longer steps over the same length lose little.
fn light_step_count(distance: f32) -> u32 {
    let n = u32(u.ambient_bottom.w);
    if (u.opts.w < 0.5 || distance <= 5000.0) {
        return n;
    }
    let fewer = u32(floor(log2(distance / 5000.0)));
    return max(n - min(fewer, n), min(n, 2u));
}

// Optical depth toward the sun: steps growing geometrically (ratio r = u.cirrus.w), partitioning
// [0, exit] exactly so a homogeneous medium integrates without error. Short first steps resolve
// the self-shadowing right at the sample, which is what the eye sees; long last steps catch the
// bulk of the cloud between the sample and the sun. The planet's shadow is total.
const LIGHT_DETAIL_DISTANCE: f32 = 150.0;
fn sun_optical_depth(p: vec3f, n: u32, footprint: f32) -> f32 {
    let d = u.sun.xyz;
    let ground = sphere_roots(p, d, u.planet.xyz, u.planet.w, 0.0);
    if (ground.hit && ground.t0 > 0.0) {
        return 1e4;
    }
    let length_total = min(light_exit(p, d), u.ambient_top.w);
    let ratio = u.cirrus.w;
    // First step of a geometric series of n steps summing to the total (uniform for r = 1).
    var unit = length_total / f32(n);
    if (ratio > 1.0001) {
        unit = length_total * (ratio - 1.0) / (pow(ratio, f32(n)) - 1.0);
    }
    var t = 0.0;
    var tau = 0.0;
    var len = unit;
    for (var i = 0u; i < n; i++) {
        // Light samples beyond LIGHT_DETAIL_DISTANCE only see the base shape: detail is
        // invisible in a soft shadow (Schneider 2015), and it saves fetches. A fixed distance
        // (rather than "after the second step") keeps the model the same for every step layout,
        // so coarse and converged light marches estimate the same integral.
        // A light sample stands for a segment of length `len`: a quarter of it is the widest
        // footprint that keeps thin cloud parts from vanishing in the prefiltered noise.
        let mid = t + 0.5 * len;
        tau += sample_density(p + d * mid, mid > LIGHT_DETAIL_DISTANCE, max(footprint, 0.25 * len)) * len;
        light_samples += 1u;
        t += len;
        len *= ratio;
    }
    return tau * u.shape.z;
}

@compute @workgroup_size(8, 8, 1)
fn march(@builtin(global_invocation_id) id: vec3u) {
    // The march runs on the sparse grid: invocation `id` traces grid pixel id * k + offset.
    let k = u32(u.grid.z);
    let grid = vec2u(u.grid.xy);
    let gp = id.xy * k + vec2u(u.pattern.xy);
    if (any(id.xy >= textureDimensions(march_out)) || any(gp >= grid)) {
        return;
    }
    base_texel = 1.0 / (u.scales.x * f32(textureDimensions(base_tex).x));
    detail_texel = 1.0 / (u.scales.y * f32(textureDimensions(detail_tex).x));
    light_samples = 0u;
    var samples = 0u;
    let ndc = pixel_ndc(gp, grid);
    let cam = u.camera.xyz;
    let near_p = unproject(ndc, u.camera.w);
    let dir = normalize(near_p.xyz / near_p.w - cam);

    // At reduced resolution a traced pixel stands for a block of scene pixels: it reads the
    // scene depth at the block's center; the composite's upsample handles the edges.
    var max_t = u.layer.w;
    var scene_t = NO_SCENE;
    if (u.misc.w > 0.5) {
        let scale = u32(u.tangent_z.w);
        let full = vec2u(u.viewport.zw);
        let at = min(gp * scale + vec2u(scale / 2u), full - vec2u(1u));
        scene_t = scene_distance_at(u.inv_view_proj, cam, u.sun_color.w, ndc, load_scene_depth(at));
        max_t = min(max_t, scene_t);
    }

    let up = u.planet.xyz;
    let radius = u.planet.w;
    var seg: Segments;
    switch (debug_mode()) {
        case 1u: { seg = shell_segments(cam, dir, up, radius, u.debug.x, u.debug.y, max_t); }
        case 2u: { seg = ball_segment(cam, dir, u.debug_sphere.xyz, u.debug_sphere.w, max_t); }
        default: { seg = shell_segments(cam, dir, up, radius, u.layer.x, u.layer.y, max_t); }
    }
    let len_a = select(0.0, seg.a.y - seg.a.x, seg.count > 0u);
    let len_b = select(0.0, seg.b.y - seg.b.x, seg.count > 1u);
    let total = len_a + len_b;
    let cos_theta = dot(u.sun.xyz, dir);
    let sun_radiance = u.sun.w * u.sun_color.rgb;
    var radiance = vec3f(0.0);
    var transmittance = 1.0;
    var cloud_depth = 0.0;
    let clouds_possible = debug_mode() != DEBUG_OFF || u.shape.x > 0.0 || u.horizon.x > 0.0;
    if (total > 0.0 && clouds_possible) {
        // Step count grows with the length inside the layer (long horizon paths get more steps).
        let thickness = u.layer.y - u.layer.x;
        let n_f = mix(u.march.x, u.march.y, clamp(total / (4.0 * thickness), 0.0, 1.0));
        let n = max(u32(ceil(n_f)), 1u);
        // Steps grow with distance on long paths: sample k sits at s = total (k / n)^p, p from 1
        // (paths up to a layer thick) to 2 (five layers and more), so the cloud around the camera
        // is resolved finely and the far horizon coarsely. Consecutive positions partition
        // [0, total] exactly, which keeps Hillaire's per-step integral energy-conserving.
        var power = 1.0;
        if (u.opts.y > 0.5) {
            power = 1.0 + clamp((total - thickness) / (4.0 * thickness), 0.0, 1.0);
        }

        // Blue-noise jitter of the sample position inside each step, rotated by the golden ratio
        // on every visit of this pixel, so that temporal accumulation sees fresh offsets.
        var jitter = 0.5;
        if (u.march.w > 0.5) {
            let bn_size = textureDimensions(blue_noise);
            let bn = textureLoad(blue_noise, gp % bn_size, 0).r;
            jitter = fract(bn + u.pattern.z * 0.61803398875);
        }

        // Phase per multiple-scattering octave (Wrenninge: eccentricity scaled by c^i).
        let octaves = u32(u.ms.x);
        var phase_oct: array<f32, 8>;
        var c_i = 1.0;
        for (var i = 0u; i < octaves; i++) {
            phase_oct[i] = phase_eval(u32(u.misc.y), u.phase, cos_theta, c_i);
            c_i *= u.ms.w;
        }
        var depth_weighted = 0.0;
        let inv_n = 1.0 / f32(n);
        // Coarse-then-fine (Schneider 2015): while nothing has been found, steps COARSE times as
        // long probe the cheap base-shape density, which bounds the full density from above, so
        // an empty probe means an empty step. A hit steps back to the start of the coarse step
        // and marches it finely; after FINE_EMPTY empty fine samples the ray goes coarse again.
        // Every step, coarse or fine, is one interval of the same partition of [0, total]:
        // skipped intervals count as empty, so the integral stays energy-conserving.
        let coarse_on = u.opts.x > 0.5 && debug_mode() == DEBUG_OFF;
        let coarse = select(1u, 4u, coarse_on);
        const FINE_EMPTY: u32 = 4u;
        var fine = !coarse_on;
        var empty_run = 0u;
        var i = 0u;
        // Bounded: each fine step advances i; each coarse probe either advances i by `coarse`
        // or switches to fine mode (at most once per run of fine steps).
        for (var guard = 0u; guard < 3u * n + 8u && i < n; guard++) {
            let steps = select(min(coarse, n - i), 1u, fine);
            let x0 = f32(i) * inv_n;
            let x1 = f32(i + steps) * inv_n;
            let s = total * pow(x0 + jitter * (x1 - x0), power);
            let dt = total * (pow(x1, power) - pow(x0, power));
            let t = select(seg.b.x + (s - len_a), seg.a.x + s, s < len_a);
            let p = cam + dir * t;
            let footprint = t * u.grid.w;
            samples += 1u;
            if (!fine) {
                if (sample_density(p, true, footprint) > 0.0) {
                    fine = true;
                    empty_run = 0u;
                } else {
                    i += steps;
                }
                continue;
            }
            i += 1u;
            let density = sample_density(p, false, footprint);
            if (density <= 0.0) {
                empty_run += 1u;
                if (coarse_on && empty_run >= FINE_EMPTY) {
                    fine = false;
                }
                continue;
            }
            empty_run = 0u;
            let sigma_t = density * u.shape.z;
            let tau = sun_optical_depth(p, light_step_count(t), footprint);
            // Wrenninge 2015 multiple-scattering octaves.
            var ms = 0.0;
            var a_i = 1.0;
            var b_i = 1.0;
            for (var o = 0u; o < octaves; o++) {
                ms += b_i * phase_oct[o] * exp(-a_i * tau);
                a_i *= u.ms.y;
                b_i *= u.ms.z;
            }
            let hf = clamp((altitude(p, up, radius) - u.layer.x) / thickness, 0.0, 1.0);
            let ambient = mix(u.ambient_bottom.rgb, u.ambient_top.rgb, hf);
            let source = u.shape.w * sigma_t * (sun_radiance * ms + ambient);
            // Hillaire 2016 energy-conserving integration over the step.
            let step_t = exp(-sigma_t * dt);
            radiance += transmittance * source * (1.0 - step_t) / sigma_t;
            depth_weighted += transmittance * (1.0 - step_t) * t;
            transmittance *= step_t;
            if (transmittance < u.march.z) {
                break;
            }
        }

        let opacity = 1.0 - transmittance;
        if (opacity > 1e-4) {
            cloud_depth = depth_weighted / opacity;
            // Aerial perspective: distant clouds take the haze color.
            let fade = haze_fade(cloud_depth);
            radiance = radiance * fade + (1.0 - fade) * opacity * u.haze.rgb;
        }
    }

    // The high layer, in front of or behind the main layer depending on where it is crossed.
    if (debug_mode() == DEBUG_OFF && u.cirrus.x > 0.0) {
        let c = cirrus_layer(cam, dir, max_t, cos_theta, sun_radiance);
        if (c.transmittance < 1.0) {
            let fade = haze_fade(c.distance);
            let lc = c.radiance * fade + (1.0 - fade) * (1.0 - c.transmittance) * u.haze.rgb;
            let in_front = seg.count == 0u || c.distance < seg.a.x;
            if (in_front) {
                radiance = lc + c.transmittance * radiance;
            } else {
                radiance = radiance + transmittance * lc;
            }
            if (cloud_depth == 0.0) {
                cloud_depth = c.distance;
            }
            transmittance *= c.transmittance;
        }
    }
    textureStore(march_out, id.xy, vec4f(radiance, transmittance));
    textureStore(depth_out, id.xy, vec4f(cloud_depth, scene_t, f32(samples), f32(light_samples)));
}
