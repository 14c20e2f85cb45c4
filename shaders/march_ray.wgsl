// The march of one view ray (march_ray) and the light toward the sun it takes at each sample:
// the body of the march pass (shaders/march.wgsl) and of the ambient probe (shaders/ambient.wgsl).
// Binds 10-11 (the cloud shadow map) besides the medium's bindings.

// The cloud shadow map (shaders/shadow.wgsl) and where it lies, for the light march's long
// part (u.shadow_light.x on). A 1x1 stand-in with window.w = 0 when there is no map.
struct ShadowSampling {
    world_to_map: mat4x4f,
    window: vec4f,          // xy: the square's origin in map coordinates, w: 1 once updated
}
@group(0) @binding(10) var shadow_map: texture_2d<f32>;
@group(0) @binding(11) var<storage, read> shadow_sampling: ShadowSampling;

// Whether a pipeline can take the light march's long part from the shadow map (a
// pipeline-overridable constant, MarchVariant in src/gpu/march.rs): 0 never (the setting is off),
// 1, the default, as u.shadow_light.x says. See MEDIUM in medium.wgsl for why.
override SHADOW_LIGHT: u32 = 1u;

// Density samples taken toward the sun by this invocation (the per-ray counter).
var<private> light_samples: u32;

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
// bulk of the cloud between the sample and the sun. The planet's shadow is total. The march
// stops once the depth is past `limit` (1e30: never), returning what it has.
fn sun_optical_depth(p: vec3f, n: u32, footprint: f32, limit: f32) -> f32 {
    let d = u.sun.xyz;
    let ground = sphere_roots(p, d, u.planet.xyz, u.planet.w, 0.0);
    if (ground.hit && ground.t0 > 0.0) {
        return 1e4;
    }
    var length_total = min(light_exit(p, d), u.ambient_top.w);
    var n_steps = n;
    // Beer shadow map light (Hillaire 2016; three-clouds' "BSM"): march only the first
    // local meters, where the self-shadowing next to the sample lives, and read the optical
    // depth from there to the sun from the map: min(mean extinction * (depth - front), total).
    // The map covers the whole path (no light_distance cut). Outside its square: march.
    var tau_map = 0.0;
    if (SHADOW_LIGHT != 0u && u.shadow_light.x > 0.5 && shadow_sampling.window.w > 0.5) {
        let local = min(u.shadow_light.y, light_exit(p, d));
        let q = p + d * local;
        let m = shadow_sampling.world_to_map * vec4f(q, 1.0);
        let inside = m.xy - shadow_sampling.window.xy;
        // Half a texel in from the square's edge, so that the bilinear footprint does not
        // reach across the toroidal seam into the square's other side.
        let margin = 0.5 / f32(textureDimensions(shadow_map).x);
        if (all(inside >= vec2f(margin)) && all(inside < vec2f(1.0 - margin))) {
            let t = textureSampleLevel(shadow_map, noise_sampler, m.xy, 0.0);
            tau_map = min(t.g * max(m.z - t.r, 0.0), t.b);
            length_total = local;
            n_steps = u32(u.shadow_light.z);
        }
    }
    let ratio = u.cirrus.w;
    // First step of a geometric series of n steps summing to the total (uniform for r = 1).
    var unit = length_total / f32(n_steps);
    if (ratio > 1.0001) {
        unit = length_total * (ratio - 1.0) / (pow(ratio, f32(n_steps)) - 1.0);
    }
    var t = 0.0;
    var tau = 0.0;
    var len = unit;
    for (var i = 0u; i < n_steps; i++) {
        // Every light sample sees the full density, detail erosion included. Schneider 2015
        // reads only the base shape beyond the first steps ("detail is invisible in a soft
        // shadow"), but the base shape bounds the eroded density from above: on fair cumulus
        // from the ground that made the single scattering 0.60-0.67 of the path tracer's (0.28
        // in the opaque parts), and 0.99-1.01 with the detail (docs/fidelity.md, 2026-12-04).
        // A light sample stands for a segment of length `len`: a quarter of it is the widest
        // footprint that keeps thin cloud parts from vanishing in the prefiltered noise.
        let mid = t + 0.5 * len;
        tau += sample_density(p + d * mid, false, max(footprint, 0.25 * len)) * len;
        light_samples += 1u;
        if (tau * u.shape.z > limit) {
            break;
        }
        t += len;
        len *= ratio;
    }
    return tau * u.shape.z + tau_map;
}

// Optical depth straight down from p (density sigma_t there) to the bottom of a layer, for
// the independent-column diffuse model: exact for the debug slab. For the noise model the
// density below is probed once, 0.1-0.6 of the way down to the layer's base (0.35 on average:
// the place, below; the full density,
// detail included): the top of a tower stands on its body, a wisp on a tower's side or a thin
// cloud's top on little or nothing. Before (2026-12-04) the column was taken as dense as the
// sample all the way down, which stood every thin part on a thick column: from 12 km above
// the partly transparent parts (reference transmittance 0.2-0.5) came out 1.41 times the path
// tracer, 1.60 once the ambient took the column's share (column_ambient_share). With both,
// against the 2048-sample references (docs/fidelity.md): sparse from the ground FLIP 0.209 ->
// 0.186, overcast 0.188 -> 0.187, sparse from above 0.111 -> 0.111. A probe at 0.25 gave
// 0.184 / 0.188 / 0.114, at 0.45 0.189 / 0.182 / 0.110, two (0.25 and 0.6) 0.186 / 0.188 /
// 0.108 for another density call per view sample.
// The probe's place is the ray's `jitter` spread over 0.1 to 0.6 of the way down (0.35 on
// average, exactly 0.35 with the jitter off): at one fixed place it followed the noise
// textures' texel rows as the sample rose, and near cumulus showed them as horizontal streaks
// in the diffuse light (2026-12-05); the temporal accumulation averages it over the stretch.
fn column_below(p: vec3f, local_up: vec3f, sigma_t: f32, footprint: f32, jitter: f32) -> f32 {
    let h = altitude(p, u.planet.xyz, u.planet.w);
    if (debug_mode() == DEBUG_SLAB) {
        return max(h - u.debug.x, 0.0) * sigma_t;
    }
    let depth = max(h - u.layer.x, 0.0);
    let probe = 0.1 + 0.5 * jitter;
    return depth * sample_density(p - local_up * (probe * depth), false, footprint) * u.shape.z;
}

// The sun's optical depth the diffuse field of a noise-model sample's column takes: the light
// march's `tau` at p, averaged with the light marches from two points `radius` to p's sides (a
// horizontal pair, turned by the ray's `jitter`, which the temporal accumulation averages over
// every direction). Diffusion carries a cloud's light sideways over about a transport mean free
// path (diffuse_spread_radius), so its diffuse light follows the sun's depth averaged over that
// scale, not the depth along one line, which jumps from one part of a cloud to the next. Along
// one line, sparse cumulus from the ground drew a big cloud's base near the zenith (57° from the
// sun, depth 1.9 toward it) at 0.76 of the path tracer and its far part (90°, depth 5.4) at
// 1.42: the path tracer's near base is 1.8 times as bright, the march drew both alike
// (docs/fidelity.md, 2026-12-06). The depth is spread up to SPREAD_LIMIT.
fn spread_sun_depth(p: vec3f, tau: f32, n: u32, footprint: f32, jitter: f32, radius: f32) -> f32 {
    let local_up = local_up_at(p);
    let side = normalize(cross(local_up, select(vec3f(0.0, 0.0, 1.0), vec3f(1.0, 0.0, 0.0), abs(local_up.z) > 0.9)));
    let ahead = cross(side, local_up);
    let angle = 2.0 * PI * jitter;
    let v = (side * cos(angle) + ahead * sin(angle)) * radius;
    let centre = min(tau, SPREAD_LIMIT);
    let one_side = min(sun_optical_depth(p + v, n, footprint, SPREAD_LIMIT), SPREAD_LIMIT);
    let other_side = min(sun_optical_depth(p - v, n, footprint, SPREAD_LIMIT), SPREAD_LIMIT);
    return (centre + one_side + other_side) / 3.0 + (tau - centre);
}

// Where the sun's optical depth is past this, around the sample and to its sides, the diffuse
// field's column is thick, and where it is past it only on some sides the column is thick enough
// that spreading adds little: spread_sun_depth spreads the depth up to it (and its light marches
// to the sides stop there). Without it, stormy from the ground cost 1.28 times the octaves
// (1.22 with it); the noise views' FLIP was the same within 0.001.
const SPREAD_LIMIT: f32 = 16.0;

// Optical distance (m) from p inside the debug sphere to its surface along d.
fn sphere_exit(p: vec3f, d: vec3f) -> f32 {
    let s = ball_segment(p, d, u.debug_sphere.xyz, u.debug_sphere.w, 1e9);
    return select(0.0, s.a.y, s.count > 0u);
}

// The delta-Eddington multiple-scattering source of a sample (per unit sun irradiance, the
// march's `ms`): the diffuse field of the independent column through it. `tau_sun` is the light
// march's optical depth, `tau_diffuse` the one the column's diffuse field takes (the light
// march's in the debug media, spread sideways in the noise model: spread_sun_depth),
// `tau_view` the view ray's since it entered the cloud.
//
// The column runs along the direction in which the medium's boundary is nearest, since diffuse
// light leaves a cloud mostly through its nearest side:
// - In a layer (the debug slab, the noise model) that is the local vertical. Its top is tau_sun
//   mu0 above (the light march's optical depth projected: the slab's exact top), its bottom the
//   column below (column_below). A sun near or below the local
//   horizon still lights a bounded cloud through its sides: the column is lit at no less than
//   DE_MIN_MU0. The debug slab is infinitely wide; a noise cloud's own width is not known to
//   the march, and its column has the radius noise_cloud_radius gives the layer's coverage,
//   whose sides leak, and the extinction of the cloud's body (NOISE_CLOUD_BODY_DENSITY).
// - In the debug sphere it is the radius, with both ends on the surface (exact). The sun lights
//   it from the end that faces it; within DE_MIN_MU0 of the terminator the two ends share the
//   light, so the terminator has no seam (the system is linear in the incident flux). The lit
//   end is no farther than the light march's own path to the surface, which also reaches a lit
//   point. The column's cross-section is the great circle every radius crosses, and its sides
//   leak (the transverse buckling in src/lighting/diffusion.rs). A vertical column through a
//   sphere keeps light that leaks out of its sides (1.55x the path tracer back-lit) and lights a
//   side-lit sphere only through DE_MIN_MU0 (0.36x).
//
// Returns (the source, the share of the sky above in the column's ambient: see
// column_ambient_share).
fn column_light(p: vec3f, dir: vec3f, tau_sun: f32, tau_diffuse: f32, sigma_t: f32, tau_view: f32, cos_theta: f32, footprint: f32, jitter: f32) -> vec2f {
    let albedo = u.shape.w;
    let g = u.ms_model.y;
    let beam = beam_light(u32(u.misc.y), u.phase, cos_theta, tau_sun, albedo, g, u.ms_model.z, u.ms_model.w);
    let chi2 = phase_second_moment(u32(u.misc.y), u.phase);
    let lobe = thin_lobe(u32(u.misc.y), u.phase, cos_theta, thin_lobe_asymmetry(g));
    if (debug_mode() == DEBUG_SPHERE) {
        let offset = p - u.debug_sphere.xyz;
        let r = length(offset);
        // At the centre every radius is as short: the one toward the sun.
        let radial = select(u.sun.xyz, offset / max(r, 1e-6), r > 1e-3 * u.debug_sphere.w);
        let outward = sphere_exit(p, radial) * sigma_t;
        let inward = sphere_exit(p, -radial) * sigma_t;
        let across = u.debug_sphere.w * sigma_t;
        let c = dot(u.sun.xyz, radial);
        let mu_view = dot(dir, radial);
        let w_out = clamp(0.5 + 0.5 * c / DE_MIN_MU0, 0.0, 1.0);
        var light = 0.0;
        if (w_out > 0.0) {
            light += w_out * delta_eddington_source(min(outward, tau_sun), inward, max(c, DE_MIN_MU0), mu_view, cos_theta, lobe, albedo, g, chi2, beam, across);
        }
        if (w_out < 1.0) {
            light += (1.0 - w_out) * delta_eddington_source(min(inward, tau_sun), outward, max(-c, DE_MIN_MU0), -mu_view, cos_theta, lobe, albedo, g, chi2, beam, across);
        }
        return vec2f(light, 0.5);
    }
    let local_up = local_up_at(p);
    let mu0 = lit_face_cosine(dot(u.sun.xyz, local_up));
    let mu_view = dot(dir, local_up);
    // The column below is the probe's, whichever way the camera looks. Until 2026-12-05 a
    // camera looking up bounded it by the view ray's own optical depth since it entered the
    // cloud, projected on the vertical (exact for a layer seen from below, and needed while the
    // column was taken as dense as the sample all the way down). Cumulus seen from below at an
    // angle are entered through their sides, and the bound took a sample just inside a side
    // wall for one just above the base: without it, against the same references, sparse from
    // the ground FLIP 0.136 -> 0.124 (ratio 0.936 -> 1.015), the close-up 0.125 -> 0.116
    // (0.753 -> 0.782), overcast 0.193 -> 0.200 (its floor 0.195; ratio 1.075 -> 1.091), from
    // above unchanged; half the bound scored between. For a slab seen from below the two were
    // the same.
    var below = column_below(p, local_up, sigma_t, footprint, jitter);
    // The ambient's share of the sky above (column_ambient_share) is the column's own, seen
    // through the phase's first moment from the view's side (seen_ambient_share, the
    // diffusion's flux term): its bottom before the view-dependent bound below; its top the light
    // march's depth projected on the vertical, but no more than the column as dense as the
    // sample up to the layer's top (in the planet's shadow the light march returns 1e4, and
    // under a low sun mu0 is clamped at DE_MIN_MU0 while the slant path keeps growing).
    let top_column = max(u.layer.y - altitude(p, u.planet.xyz, u.planet.w), 0.0) * sigma_t;
    let ambient_share = seen_ambient_share(min(tau_sun * mu0, top_column), below, g, mu_view);
    // Looking toward the sun, the camera sees the cloud's dark side: light escapes there through
    // the boundary the view ray came in by, however the cloud is shaped, so that boundary is no
    // farther than the ray's own optical depth (for a slab seen from below, never closer than
    // the column: no change). A ray going down came in through the layer's top, its lit face,
    // not a dark side: the bound fades out below the horizontal (a slab seen from above 20°
    // toward the sun read as a column no thicker than the view ray's depth: 0.30-0.36 of the
    // path tracer at τ 20-50, 0.48-0.56 without the bound).
    let dark_entry = smoothstep(0.0, 0.5, cos_theta) * smoothstep(-0.35, 0.0, mu_view);
    below = mix(below, min(below, tau_view), dark_entry);
    // The column's optical radius is the cloud body's, not the sample's: a wisp at a cloud's
    // edge sits in a body as dense as the rest (NOISE_CLOUD_BODY_DENSITY says why).
    let across = select(noise_cloud_optical_radius(u.shape.x, u.shape.y * u.shape.z), 1e30, debug_mode() == DEBUG_SLAB);
    let light = delta_eddington_source(tau_diffuse * mu0, below, mu0, mu_view, cos_theta, lobe, albedo, g, chi2, beam, across);
    return vec2f(light, ambient_share);
}

// The cosine at which the sun lights a sample's column, given its cosine with the local vertical
// `sun_up`. A layer takes the light through its top at sun_up (never below DE_MIN_MU0). A
// noise-model cloud with sides takes it through its sunward wall too, at the sun's cosine with
// the horizontal, which under a sun below 45° is the larger: its column is lit at the mean of
// the two faces' cosines, the wall weighted by its share of the lit faces' area, the cloud's
// height over its width (the layer's thickness over the diameter of the column
// noise_cloud_radius gives its coverage) to the top's 1. Fair cumulus (coverage 0.4: 2 km wide
// in a layer 3 km thick) weight the wall 0.6; an overcast deck (0.97: 97 km wide) 0.03. Lit
// through the top alone, crisp cumulus seen from 12 km with the sun 40° high behind the camera
// (which sees their sunward walls) came out 0.840 of the path tracer (FLIP 0.131), and lit
// from the side at 30° up close 0.775 (FLIP 0.105). With the mean: 0.949 (0.113) and 0.952
// (0.100); with the wall's cosine alone where larger: 1.021 (0.107) and 1.070 (0.108), the lit
// walls up close 1.3 to 1.9 times too bright. The view from the ground (sun 55°) and the
// overcast deck are the same with each.
fn lit_face_cosine(sun_up: f32) -> f32 {
    let top = max(sun_up, DE_MIN_MU0);
    if (debug_mode() != DEBUG_OFF) {
        return top;
    }
    let wall = sqrt(max(1.0 - sun_up * sun_up, 0.0));
    let height = u.layer.y - u.layer.x;
    let sides = height / max(2.0 * noise_cloud_radius(u.shape.x), 1.0);
    return mix(top, max(top, wall), sides / (1.0 + sides));
}

// The local vertical at p (the planet's centre lies u.planet.w below the origin along
// u.planet.xyz).
fn local_up_at(p: vec3f) -> vec3f {
    return normalize(p + u.planet.xyz * u.planet.w);
}

// How fast (1/m) the sun's optical depth grows along the view ray at p, whose extinction is
// sigma_t: in a layer lit from above, τ_sun is the depth below the sunlit top over μ0, so it
// grows by sigma_t (-dir · up) / μ0 per metre (exact in the debug slab; for the noise model the
// layer's geometry, as its diffuse columns take it). 0 in the debug sphere, whose depth toward
// the sun is not a layer's.
fn skin_rate(p: vec3f, dir: vec3f, sigma_t: f32) -> f32 {
    if (debug_mode() == DEBUG_SPHERE) {
        return 0.0;
    }
    let local_up = local_up_at(p);
    let mu0 = max(dot(u.sun.xyz, local_up), DE_MIN_MU0);
    return sigma_t * -dot(dir, local_up) / mu0;
}

// The single scattering's share of a march step of length dt (extinction sigma_t) whose sample,
// `offset` into the step, sees the sun through optical depth tau, which grows along the step at
// `rate` (skin_rate): x, ∫ e^{-sigma_t x - τ_sun(x)} dx over the step, per unit phase and
// source, exact where τ_sun is linear along it; y, the same from the step's end on without end
// (the early exit's remainder), at the step's end. Held constant over the step (Hillaire 2016),
// a sample half a step in sees e^{-rate dt / 2} of the light its step's front does: from
// 1.5 km above a slab of τ 50 (σt 0.1 /m, about 20 m steps), single scattering came out 0.70
// to 0.91 of the closed form.
fn skin_step(tau: f32, rate: f32, offset: f32, dt: f32, sigma_t: f32) -> vec2f {
    let x = clamp(offset, 0.0, dt);
    // τ_sun at the step's start (never below 0), and the rate no steeper downward than that
    // reaches 0 at the step's end.
    let tau0 = max(tau - rate * x, 0.0);
    let k = max(rate, -tau0 / max(dt, 1e-6));
    let total = sigma_t + k;
    var within = dt;
    if (abs(total * dt) > 1e-4) {
        within = (1.0 - exp(-total * dt)) / total;
    }
    let at_end = exp(-(tau0 + k * dt));
    return vec2f(exp(-tau0) * within, at_end / (sigma_t + max(k, 0.0)));
}

// One view ray from `cam` along `dir` up to `max_t` (m): the in-scattered radiance, the
// transmittance and the depths the march pass writes for a pixel. Shared by the march (a
// pixel's ray) and the ambient probe (a hemisphere of rays at the camera), so that the probe
// sees exactly what the picture shows. `jitter` in [0, 1) places each sample inside its step;
// `pixel_angle` (rad) is the angle one ray stands for, which sets the noise footprint.
struct MarchRay {
    radiance: vec3f,
    transmittance: f32,
    cloud_depth: f32,
    front_depth: f32,
    samples: u32,
    // Where the ray enters the main layer (a negative value: it does not).
    layer_entry: f32,
    // Whether the march stopped at the transmittance cutoff, with its estimate of the rest of
    // the ray added (a part of a ray that did: the parts after it add nothing).
    stopped: bool,
}

// The whole ray: the main layer, then the high (cirrus) layer.
fn march_ray(cam: vec3f, dir: vec3f, max_t: f32, jitter: f32, pixel_angle: f32) -> MarchRay {
    return with_cirrus(march_layer(cam, dir, max_t, jitter, pixel_angle, 0u, 1u, 0.0), cam, dir, max_t);
}

// The main layer's march over part `part` of `parts` consecutive ranges of the ray's steps
// (the whole ray for 0 of 1). The steps are the whole ray's: the parts of one ray partition
// its steps, each starts with transmittance 1, and put together front to back
// (L = L0 + T0 L1 + ..., T = T0 T1 ..., up to the first part that stopped) they give the
// whole ray's march, except that a part entering the middle of a cloud starts its optical
// depth along the view (tau_view, the column's view bound) and its coarse probes afresh, and
// takes the haze at its own depth. The ambient probe marches its rays so, a part per
// invocation: a ray's latency, not the work, bounds that pass on a GPU.
// Where a ray's steps lie: its segments in the layer, their lengths, the step count and the
// power of the distance-grown spacing. The march and the ambient probe's parts share them.
struct RaySteps {
    seg: Segments,
    len_a: f32,
    total: f32,
    n: u32,
    power: f32,
}

fn ray_steps(cam: vec3f, dir: vec3f, max_t: f32) -> RaySteps {
    let seg = medium_segments(cam, dir, max_t);
    let len_a = select(0.0, seg.a.y - seg.a.x, seg.count > 0u);
    let len_b = select(0.0, seg.b.y - seg.b.x, seg.count > 1u);
    let total = len_a + len_b;
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
    return RaySteps(seg, len_a, total, n, power);
}

// The distance along the ray of the path length `s` inside the layer.
fn ray_distance(steps: RaySteps, s: f32) -> f32 {
    return select(steps.seg.b.x + (s - steps.len_a), steps.seg.a.x + s, s < steps.len_a);
}

// The optical depth along the view where part `part` of `parts` of the ray's steps starts, as
// march_layer's tau_view counts it (since the ray entered the current cloud), from one density
// sample per step before it, all fine: each invocation of a ray's parts sums its own part's
// (the whole of it, and since its last run of FINE_EMPTY empty samples) and the parts before
// put it together (ambient.wgsl).
fn part_view_depth(cam: vec3f, dir: vec3f, max_t: f32, jitter: f32, pixel_angle: f32, part: u32, parts: u32) -> vec3f {
    base_texel = 1.0 / (u.scales.x * f32(textureDimensions(base_tex).x));
    detail_texel = 1.0 / (u.scales.y * f32(textureDimensions(detail_tex).x));
    let steps = ray_steps(cam, dir, max_t);
    var all = 0.0;
    var since_gap = 0.0;
    var gap = 0.0;
    var empty_run = 0u;
    if (steps.total > 0.0) {
        let inv_n = 1.0 / f32(steps.n);
        for (var i = steps.n * part / parts; i < steps.n * (part + 1u) / parts; i++) {
            let x0 = f32(i) * inv_n;
            let x1 = f32(i + 1u) * inv_n;
            let s = steps.total * pow(x0 + jitter * (x1 - x0), steps.power);
            let dt = steps.total * (pow(x1, steps.power) - pow(x0, steps.power));
            let t = ray_distance(steps, s);
            let sigma_t = sample_density(cam + dir * t, false, t * pixel_angle) * u.shape.z;
            if (sigma_t <= 0.0) {
                empty_run += 1u;
                if (empty_run >= FINE_EMPTY) {
                    since_gap = 0.0;
                    gap = 1.0;
                }
                continue;
            }
            empty_run = 0u;
            all += sigma_t * dt;
            since_gap += sigma_t * dt;
        }
    }
    return vec3f(all, since_gap, gap);
}

// After FINE_EMPTY empty fine samples the march goes coarse again (march_layer).
const FINE_EMPTY: u32 = 4u;

fn march_layer(cam: vec3f, dir: vec3f, max_t: f32, jitter: f32, pixel_angle: f32, part: u32, parts: u32, tau_view_start: f32) -> MarchRay {
    base_texel = 1.0 / (u.scales.x * f32(textureDimensions(base_tex).x));
    detail_texel = 1.0 / (u.scales.y * f32(textureDimensions(detail_tex).x));
    var samples = 0u;
    let up = u.planet.xyz;
    let radius = u.planet.w;
    let path = ray_steps(cam, dir, max_t);
    let seg = path.seg;
    let total = path.total;
    let n = path.n;
    let power = path.power;
    let thickness = u.layer.y - u.layer.x;
    let cos_theta = dot(u.sun.xyz, dir);
    let sun_radiance = u.sun.w * u.sun_color.rgb;
    var radiance = vec3f(0.0);
    var transmittance = 1.0;
    var cloud_depth = 0.0;
    // Where the ray first met cloud (the start of the first step with density), 0 = never.
    var front_depth = 0.0;
    var stopped = false;
    let clouds_possible = debug_mode() != DEBUG_OFF || u.shape.x > 0.0 || u.horizon.x > 0.0;
    if (total > 0.0 && clouds_possible) {
        // Phase per multiple-scattering octave (Wrenninge: eccentricity scaled by c^i).
        let octaves = u32(u.ms.x);
        var phase_oct: array<f32, 8>;
        var c_i = 1.0;
        for (var i = 0u; i < octaves; i++) {
            phase_oct[i] = phase_eval(u32(u.misc.y), u.phase, cos_theta, c_i);
            c_i *= u.ms.w;
        }
        var depth_weighted = 0.0;
        // Optical depth from where the ray entered the current cloud to the step start.
        var tau_view = tau_view_start;
        let delta_eddington_on = u32(u.ms_model.x) == 2u;
        // The diffuse field's spread sun depth (spread_sun_depth): its offset from the light
        // march's, taken at the ray's first sample in cloud and kept for the rest of the ray, so
        // that a ray pays for the two light marches to the sides once. Taken again wherever the
        // ray had moved two spread radii on, the noise views' FLIP was within 0.001 and stormy
        // from the ground cost 1.32 times the octaves instead of 1.22.
        let spread_radius = diffuse_spread_radius(u.shape.y * u.shape.z, u.ms_model.y);
        var spread_offset = 0.0;
        var spread_taken = false;
        let inv_n = 1.0 / f32(n);
        // Coarse-then-fine (Schneider 2015): while nothing has been found, steps COARSE times as
        // long probe the cheap base-shape density, which bounds the full density from above
        // where it is read. A hit steps back to the start of the coarse step before it (not only
        // its own) and marches both finely; after FINE_EMPTY empty fine samples, and not before
        // FINE_EMPTY past the hit's step, the ray goes coarse again. One probe stands for a
        // whole coarse step, and cloud in the step before a hit lies between that step's probe
        // and the cloud the hit found: stepping back only to the hit's own step lost it, more
        // or less of it by where the jitter put that probe, which drew the entries of the
        // cumulus carved by their noise (2026-12-05) as speckle (stormy from the ground: FLIP
        // 0.090 against the converged reference with the step back to the hit's step, 0.067
        // with it to the step before, 0.067 with no coarse steps at all).
        // Every step, coarse or fine, is one interval of the same partition of [0, total]:
        // skipped intervals count as empty, so the integral stays energy-conserving.
        let coarse_on = u.opts.x > 0.5 && debug_mode() == DEBUG_OFF;
        let coarse = select(1u, 4u, coarse_on);
        var fine = !coarse_on;
        var empty_run = 0u;
        var i = n * part / parts;
        let end = n * (part + 1u) / parts;
        // Where the fine march has been (its steps are never marched twice), and the first
        // step at which a run of fine steps may go coarse again.
        var marched_to = i;
        var resume = i;
        // Bounded: each fine step advances i; each coarse probe either advances i by `coarse`
        // or switches to fine mode (at most once per run of fine steps).
        for (var guard = 0u; guard < 3u * n + 8u && i < end; guard++) {
            let steps = select(min(coarse, end - i), 1u, fine);
            let x0 = f32(i) * inv_n;
            let x1 = f32(i + steps) * inv_n;
            let s = total * pow(x0 + jitter * (x1 - x0), power);
            let dt = total * (pow(x1, power) - pow(x0, power));
            let t = ray_distance(path, s);
            let p = cam + dir * t;
            let footprint = t * pixel_angle;
            samples += 1u;
            // One density call for both kinds of step (the probe without the detail), so that a
            // SIMD batch of rays in both modes does not evaluate the density twice per step.
            let density = sample_density(p, !fine, footprint);
            if (!fine) {
                if (density > 0.0) {
                    fine = true;
                    empty_run = 0u;
                    resume = i + FINE_EMPTY;
                    i = max(i - min(i, coarse), marched_to);
                } else {
                    i += steps;
                }
                continue;
            }
            i += 1u;
            marched_to = i;
            if (density <= 0.0) {
                empty_run += 1u;
                if (coarse_on && empty_run >= FINE_EMPTY && i >= resume) {
                    fine = false;
                    tau_view = 0.0;
                }
                continue;
            }
            empty_run = 0u;
            if (front_depth == 0.0) {
                // The start of this step (not the jittered sample): the same for every visit.
                let s0 = total * pow(x0, power);
                front_depth = max(ray_distance(path, s0), 1e-3);
            }
            let sigma_t = density * u.shape.z;
            let tau = sun_optical_depth(p, light_step_count(t), footprint, 1e30);
            // Wrenninge 2015 multiple-scattering octaves. The first (single scattering,
            // phase_oct[0] e^{-tau}) is integrated apart (skin_step); `ms` holds the others, and
            // the loop indexes phase_oct by its counter, which a software rasteriser gathers from
            // scratch memory lane by lane.
            var ms = 0.0;
            var a_i = u.ms.y;
            var b_i = u.ms.z;
            for (var o = 1u; o < octaves; o++) {
                ms += b_i * phase_oct[o] * exp(-a_i * tau);
                a_i *= u.ms.y;
                b_i *= u.ms.z;
            }
            let sample_tau_view = tau_view + 0.5 * sigma_t * dt;
            // The ambient's share of the sky above: the height in the layer (Schneider's
            // gradient) with the octaves and in the debug media; the column's diffusion share
            // (column_ambient_share) with delta-Eddington in the noise model.
            var hf = clamp((altitude(p, up, radius) - u.layer.x) / thickness, 0.0, 1.0);
            if (delta_eddington_on) {
                // The debug media are homogeneous: their light is exact along one line.
                var tau_diffuse = tau;
                if (debug_mode() == DEBUG_OFF) {
                    if (!spread_taken) {
                        spread_offset = spread_sun_depth(p, tau, light_step_count(t), footprint, jitter, spread_radius) - tau;
                        spread_taken = true;
                    }
                    tau_diffuse = max(tau + spread_offset, 0.0);
                }
                let column = column_light(p, dir, tau, tau_diffuse, sigma_t, sample_tau_view, cos_theta, footprint, jitter);
                ms += column.x;
                hf = select(hf, column.y, debug_mode() == DEBUG_OFF);
            }
            let ambient = mix(u.ambient_bottom.rgb, u.ambient_top.rgb, hf);
            // Hillaire 2016 energy-conserving integration over the step, the source held at the
            // sample's, except the single scattering's: it falls off along the step as the
            // sun's optical depth grows (skin_rate), which in a dense medium seen from the sun's
            // side is within the step as fast as the view's own extinction.
            let step_t = exp(-sigma_t * dt);
            let skin = skin_step(tau, skin_rate(p, dir, sigma_t), s - total * pow(x0, power), dt, sigma_t);
            let single_source = u.shape.w * sigma_t * sun_radiance * phase_oct[0];
            let source = u.shape.w * sigma_t * (sun_radiance * ms + ambient);
            radiance += transmittance * (source * (1.0 - step_t) / sigma_t + single_source * skin.x);
            depth_weighted += transmittance * (1.0 - step_t) * t;
            transmittance *= step_t;
            tau_view += sigma_t * dt;
            if (transmittance < u.march.z) {
                // Early exit with an estimate of what the rest of the ray would add: the medium
                // ahead taken as this sample's, without end (∫ T e^{-σt x} S dx = T S / σt; the
                // single scattering from the step's end on, falling as in the step), so the
                // light the remaining weight T would have gathered is not dropped. The
                // transmittance is left as it is (the scene behind still shows through T).
                radiance += transmittance * (source / sigma_t + single_source * skin.y);
                stopped = true;
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

    let layer_entry = select(-1.0, seg.a.x, seg.count > 0u);
    return MarchRay(radiance, transmittance, cloud_depth, front_depth, samples, layer_entry, stopped);
}

// A ray that met nothing: no light, full transmittance (the start of join_parts).
fn march_layer_none() -> MarchRay {
    return MarchRay(vec3f(0.0), 1.0, 0.0, 0.0, 0u, -1.0, false);
}

// Two consecutive ranges of one ray's march put together, front to back (march_layer): the
// back one seen through the front's transmittance, the cloud depth weighted by each one's
// share of the opacity; a front that stopped at the cutoff already holds its estimate of all
// that lies behind it. The layer entry is the ray's, the same in every range.
fn join_parts(front: MarchRay, back: MarchRay) -> MarchRay {
    if (front.stopped) {
        return front;
    }
    var ray = back;
    let o_front = 1.0 - front.transmittance;
    let o_back = front.transmittance * (1.0 - back.transmittance);
    ray.cloud_depth = 0.0;
    if (o_front + o_back > 0.0) {
        ray.cloud_depth = (o_front * front.cloud_depth + o_back * back.cloud_depth) / (o_front + o_back);
    }
    ray.radiance = front.radiance + front.transmittance * back.radiance;
    ray.transmittance = front.transmittance * back.transmittance;
    ray.front_depth = select(back.front_depth, front.front_depth, front.front_depth > 0.0);
    ray.samples = front.samples + back.samples;
    return ray;
}

// The high layer added to a main-layer march: in front of or behind the main layer depending
// on where it is crossed.
fn with_cirrus(layer: MarchRay, cam: vec3f, dir: vec3f, max_t: f32) -> MarchRay {
    var ray = layer;
    if (debug_mode() == DEBUG_OFF && u.cirrus.x > 0.0) {
        let c = cirrus_layer(cam, dir, max_t, dot(u.sun.xyz, dir), u.sun.w * u.sun_color.rgb);
        if (c.transmittance < 1.0) {
            let fade = haze_fade(c.distance);
            let lc = c.radiance * fade + (1.0 - fade) * (1.0 - c.transmittance) * u.haze.rgb;
            let in_front = ray.layer_entry < 0.0 || c.distance < ray.layer_entry;
            if (in_front) {
                ray.radiance = lc + c.transmittance * ray.radiance;
            } else {
                ray.radiance = ray.radiance + ray.transmittance * lc;
            }
            if (ray.cloud_depth == 0.0) {
                ray.cloud_depth = c.distance;
            }
            if (ray.front_depth == 0.0 || c.distance < ray.front_depth) {
                ray.front_depth = c.distance;
            }
            ray.transmittance *= c.transmittance;
        }
    }
    return ray;
}
