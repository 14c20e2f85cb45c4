// Path-traced reference (compute): unbiased and progressive, the ground truth the march is
// judged against. Per pixel and sample, a path from the camera through the pixel centre:
// - free flights by delta tracking (Woodcock; Novák et al. 2018, "Monte Carlo methods for
//   volumetric light transport simulation") through exactly the density the march sees
//   (medium.wgsl, at mip 0), with the density bound as majorant;
// - at each real collision the path scatters with probability = albedo (the weight carries
//   it), takes next-event estimation toward the sun with ratio-tracked transmittance (Novák
//   et al. 2014, "Residual ratio tracking"), and samples its new direction from the phase
//   function exactly (Henyey-Greenstein inverted in closed form; the Draine lobe by rejection
//   from its HG factor, accepted with (1 + α cos²θ) / (1 + α));
// - the sun is its real disc (0.533°; the march's sun, and the single-scattering-only mode's,
//   is a direction): it is reached both by
//   sampling the disc (next-event estimation) and by phase-sampled directions that leave the
//   medium inside it, combined with the balance heuristic (Veach 1997), so the forward peak of
//   a cloud phase function (g 0.988: 1100 / sr) does not turn into fireflies;
// - at each collision, half the time, a branch toward the sun: a direction from the phase's
//   forward lobe turned toward the sun, a free flight and next-event estimation at its
//   collision, combined with the continuation's draws of the same segment by the balance
//   heuristic, so the light of paths that travel near the sun's direction (seen through the
//   forward peak at their next collision) is drawn as often as it matters, not as fireflies;
// - every order, ended only by escape or Russian roulette on the weight;
// - a path that leaves the medium after scattering sees the sky the march's ambient terms
//   stand for: `ambient_top` above the horizontal, `ambient_bottom` below it and on the ground.
// The camera ray's own transmittance is ratio-tracked too. Sums go to `accum` (rgb: radiance,
// a: transmittance); the host divides by the sample count.

struct PathParams {
    size: vec4u,      // image width, height, seed of this dispatch, samples per pixel in it
    mode: vec4u,      // x: 1 = single scattering only, y: order at which roulette starts,
                      // z: 1 = the branch toward the sun at each collision (guide_lobe),
                      // w: the seed's sequence epoch (src/reference.rs, rng_words)
}

@group(0) @binding(6) var<storage, read_write> accum: array<vec4f>;
@group(0) @binding(7) var<storage, read> pt: PathParams;

var<private> rng_state: u32;

// The sun's disc: cos of its angular radius (0.2665°) and its solid angle (sr).
const SUN_COS: f32 = 0.99998918;
const SUN_SOLID_ANGLE: f32 = 6.7987e-5;

// PCG (O'Neill 2014), the RXS-M-XS output: one uniform number in [0, 1).
fn rand() -> f32 {
    rng_state = rng_state * 747796405u + 2891336453u;
    var w = ((rng_state >> ((rng_state >> 28u) + 4u)) ^ rng_state) * 277803737u;
    w = (w >> 22u) ^ w;
    return f32(w >> 8u) * (1.0 / 16777216.0);
}

fn sigma_t(p: vec3f) -> f32 {
    return sample_density(p, false, 0.0) * u.shape.z;
}

// The extinction bound: density never exceeds the weather's density scale (noise model) or
// the debug medium's density.
fn majorant() -> f32 {
    return u.shape.z * select(u.shape.y, u.debug.z, debug_mode() != DEBUG_OFF);
}

// The first real collision along o + t d, t in the medium's intervals below max_t; -1: none.
fn collide(o: vec3f, d: vec3f, max_t: f32, m: f32) -> f32 {
    let seg = medium_segments(o, d, max_t);
    for (var k = 0u; k < seg.count; k++) {
        let s = select(seg.b, seg.a, k == 0u);
        var t = s.x;
        for (var guard = 0u; guard < 1000000u; guard++) {
            t -= log(1.0 - rand()) / m;
            if (t >= s.y) {
                break;
            }
            if (rand() * m < sigma_t(o + d * t)) {
                return t;
            }
        }
    }
    return -1.0;
}

// Ratio tracking: an unbiased estimate of the transmittance along o + t d up to max_t, with
// twice the majorant so each tentative collision halves the estimate at most (smoother than
// the all-or-nothing track-length estimate in a homogeneous medium).
fn transmittance(o: vec3f, d: vec3f, max_t: f32, m: f32) -> f32 {
    let seg = medium_segments(o, d, max_t);
    let mr = 2.0 * m;
    var tr = 1.0;
    for (var k = 0u; k < seg.count; k++) {
        let s = select(seg.b, seg.a, k == 0u);
        var t = s.x;
        for (var guard = 0u; guard < 1000000u; guard++) {
            t -= log(1.0 - rand()) / mr;
            if (t >= s.y || tr <= 0.0) {
                break;
            }
            tr *= 1.0 - sigma_t(o + d * t) / mr;
            // Russian roulette on a small estimate (unbiased: survivors count double), so
            // shadow rays from deep inside a thick cloud stop early.
            if (tr < 0.05) {
                if (rand() < 0.5) {
                    return 0.0;
                }
                tr *= 2.0;
            }
        }
    }
    return tr;
}

fn blocked_by_ground(o: vec3f, d: vec3f) -> bool {
    let g = sphere_roots(o, d, u.planet.xyz, u.planet.w, 0.0);
    return altitude(o, u.planet.xyz, u.planet.w) >= 0.0 && g.hit && g.t0 > 0.0;
}

// cos θ from Henyey-Greenstein with asymmetry g, by inversion of its CDF.
fn sample_hg(g: f32) -> f32 {
    let xi = rand();
    if (abs(g) < 1e-3) {
        return 1.0 - 2.0 * xi;
    }
    let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * xi);
    return clamp((1.0 + g * g - s * s) / (2.0 * g), -1.0, 1.0);
}

// cos θ from Draine's phase function: HG(g) proposals accepted with (1 + α cos²θ) / (1 + α).
fn sample_draine(g: f32, alpha: f32) -> f32 {
    var c = sample_hg(g);
    for (var guard = 0u; guard < 4096u; guard++) {
        if (rand() * (1.0 + alpha) <= 1.0 + alpha * c * c) {
            return c;
        }
        c = sample_hg(g);
    }
    return c;
}

// cos θ from the phase function of phase.wgsl (the same models and parameters).
fn sample_phase_cos(model: u32, params: vec4f) -> f32 {
    if (model == 0u) {
        if (rand() < params.w) {
            return sample_draine(params.y, params.z);
        }
        return sample_hg(params.x);
    }
    if (rand() < params.w) {
        return sample_hg(params.x);
    }
    return sample_hg(params.y);
}

// How often a collision sends the branch toward the sun (its expected sample count in the MIS
// weights).
const BRANCH_SHARE: f32 = 0.5;

// The asymmetry of the lobe around the sun the branch draws its directions from: the phase's
// sharpest forward lobe where it has one above 0.5 (the droplet phase's diffraction peak), else
// 0 (no branch: a broad phase finds the sun's directions by itself).
fn guide_lobe(model: u32, params: vec4f) -> f32 {
    if (pt.mode.z == 0u) {
        return 0.0;
    }
    var g = params.x;
    if (model != 0u) {
        g = max(params.x, params.y);
    }
    return select(0.0, g, g >= 0.5);
}

// The branch's pdf of travelling along `dir` (its expected sample count times the lobe around
// the sun) over the phase's (`phase_pdf`): the ratio the MIS weights take of a segment that
// both the path's continuation and the branch can draw. 0 without the branch.
fn branch_ratio(dir: vec3f, sun: vec3f, guide_g: f32, phase_pdf: f32) -> f32 {
    if (guide_g <= 0.0) {
        return 0.0;
    }
    return BRANCH_SHARE * henyey_greenstein(dot(dir, sun), guide_g) / max(phase_pdf, 1e-30);
}

// A direction at angle acos(cos_theta) from d, uniform in azimuth.
fn turn(d: vec3f, cos_theta: f32) -> vec3f {
    let a = select(vec3f(1.0, 0.0, 0.0), vec3f(0.0, 1.0, 0.0), abs(d.x) > 0.9);
    let x = normalize(cross(a, d));
    let y = cross(d, x);
    let phi = 2.0 * PI * rand();
    let sin_theta = sqrt(max(1.0 - cos_theta * cos_theta, 0.0));
    return normalize(d * cos_theta + (x * cos(phi) + y * sin(phi)) * sin_theta);
}

fn sky(o: vec3f, d: vec3f) -> vec3f {
    let up = normalize(o + u.planet.xyz * u.planet.w);
    let above = dot(d, up) > 0.0 && !blocked_by_ground(o, d);
    return select(u.ambient_bottom.rgb, u.ambient_top.rgb, above);
}

@compute @workgroup_size(8, 8, 1)
fn trace(@builtin(global_invocation_id) id: vec3u) {
    let size = pt.size.xy;
    if (any(id.xy >= size)) {
        return;
    }
    let cam = u.camera.xyz;
    let view_dir = view_ray_dir(u.inv_view_proj_rel, pixel_ndc(id.xy, size), u.camera.w);
    let m = majorant();
    let model = u32(u.misc.y);
    let sun = u.sun.xyz;
    let sun_radiance = u.sun.w * u.sun_color.rgb;
    let albedo = u.shape.w;
    var sum = vec4f(0.0);
    for (var s = 0u; s < pt.size.w; s++) {
        // The hash's words: the pixel's column with the epoch above it (a column is below
        // 4096), its row with the sample above it, the seed with the dispatch.
        rng_state = pcg3d(vec3u(id.x | (pt.mode.w << 12u), id.y | (s << 16u), pt.size.z)).x;
        var radiance = vec3f(0.0);
        if (m > 0.0) {
            sum.a += transmittance(cam, view_dir, u.layer.w, m);
            var o = cam;
            var d = view_dir;
            var max_t = u.layer.w;
            var weight = 1.0;
            var order = 0u;
            // The phase pdf of the direction the path travels in (for the MIS weights).
            var last_pdf = 0.0;
            // The branch's pdf over the phase's for the segment into the current collision
            // (in_ratio) and the one before it (prev_ratio); the camera ray's is 0.
            var in_ratio = 0.0;
            var prev_ratio = 0.0;
            let guide_g = guide_lobe(model, u.phase);
            for (var guard = 0u; guard < 100000u; guard++) {
                let t = collide(o, d, max_t, m);
                if (t < 0.0) {
                    if (order > 0u) {
                        radiance += weight * sky(o, d);
                        // A phase-sampled direction that leaves the medium inside the sun's
                        // disc: its share by the balance heuristic.
                        if (dot(d, sun) >= SUN_COS && !blocked_by_ground(o, d)) {
                            let mis = last_pdf / (last_pdf + (1.0 + prev_ratio) / SUN_SOLID_ANGLE);
                            radiance += weight * sun_radiance / SUN_SOLID_ANGLE * mis;
                        }
                    }
                    break;
                }
                o += d * t;
                order += 1u;
                weight *= albedo;
                // Next-event estimation: a direction in the sun's disc (radiance E / Ω over it,
                // so radiance / pdf = E).
                // Single scattering alone keeps the sun a direction, as the closed forms and
                // the march have it (near the forward peak the disc's average differs).
                let single = pt.mode.x == 1u;
                var to_sun = sun;
                if (!single) {
                    to_sun = turn(sun, 1.0 - rand() * (1.0 - SUN_COS));
                }
                if (!blocked_by_ground(o, to_sun)) {
                    let p = phase_eval(model, u.phase, dot(to_sun, d), 1.0);
                    var mis = 1.0;
                    if (!single) {
                        mis = 1.0 / (1.0 + p * SUN_SOLID_ANGLE + in_ratio);
                    }
                    radiance += weight * sun_radiance * p * mis * transmittance(o, to_sun, 1e9, m);
                }
                if (pt.mode.x == 1u) {
                    break;
                }
                // The branch toward the sun: a direction from the phase's forward lobe turned
                // toward the sun, a free flight along it and next-event estimation at its
                // collision (not continued). A path travelling within a degree of the sun sees
                // it through the forward peak at its next collision (1100 / sr for g 0.988);
                // the continuation alone draws that direction from a generic one once in
                // thousands of collisions, as fireflies. The two draws of the segment are
                // combined with the balance heuristic over the whole two-segment path (its
                // pdfs: continuation then next-event p s, continuation then a hit on the disc
                // p p2, branch then next-event b s; Veach 1997), so every strategy adds
                // f / (p s + p p2 + b s), bounded where the lobe matches the peak.
                if (guide_g > 0.0 && rand() < BRANCH_SHARE) {
                    let dir = turn(sun, sample_hg(guide_g));
                    let hit = collide(o, dir, 1e9, m);
                    if (hit >= 0.0) {
                        let y = o + dir * hit;
                        let sigma = turn(sun, 1.0 - rand() * (1.0 - SUN_COS));
                        if (!blocked_by_ground(y, sigma)) {
                            let p1 = phase_eval(model, u.phase, dot(dir, d), 1.0);
                            let p2 = phase_eval(model, u.phase, dot(sigma, dir), 1.0);
                            let b = BRANCH_SHARE * henyey_greenstein(dot(dir, sun), guide_g);
                            let share = p1 * p2 / (p1 + p1 * p2 * SUN_SOLID_ANGLE + b);
                            radiance += weight * albedo * sun_radiance * share * transmittance(y, sigma, 1e9, m);
                        }
                    }
                }
                if (order >= pt.mode.y) {
                    let q = min(weight, 1.0);
                    if (rand() >= q) {
                        break;
                    }
                    weight /= q;
                }
                let next = turn(d, sample_phase_cos(model, u.phase));
                last_pdf = phase_eval(model, u.phase, dot(next, d), 1.0);
                prev_ratio = in_ratio;
                in_ratio = branch_ratio(next, sun, guide_g, last_pdf);
                d = next;
                max_t = 1e9;
            }
        } else {
            sum.a += 1.0;
        }
        sum += vec4f(radiance, 0.0);
    }
    let i = id.y * size.x + id.x;
    accum[i] += sum;
}
