// The ambient probe (compute): the light reaching the camera from each hemisphere around the
// local vertical, from the clouds, as the march renders them (march_ray, shaders/march_ray.wgsl).
//
// Irradiance E = ∫ L(ω) cos θ dω over a hemisphere. With directions drawn cosine-weighted
// (pdf cos θ / π) the estimate is E ≈ π / N Σ L_i, and the cosine-weighted mean transmittance
// V = 1/π ∫ T(ω) cos θ dω ≈ 1/N Σ T_i is the fraction of the hemisphere's light that comes from
// behind the clouds: the host's own sky above, its ground below. The host's irradiance is then
// E_clouds + V × E_host (exact when the host's radiance is uniform over the hemisphere).
// Directions: fixed spherical Fibonacci sets (Keinert et al. 2015), so the answer changes only
// when the clouds, the sun or the camera do. AMBIENT_COSINE_RAYS are cosine-weighted (cos² θ
// uniform). AMBIENT_SUN_RAYS follow the phase function's two lobes around the sun (each a
// Henyey-Greenstein lobe with that lobe's asymmetry, in proportion to its weight): light
// scattered through the clouds toward the sun comes in a peak as narrow as the phase function's
// (about 1° for the default Jendersie-d'Eon fit, g = 0.988), which no cosine set of this size
// resolves (34% off the integral of the picture at 128 cosine rays, tests/ambient.rs). The
// sets are combined with the balance heuristic (Veach 1997): a ray in direction ω weighs
// w = cos θ / Σ_k N_k p_k(ω), and E ≈ π Σ L_i w_i / Σ w_i, V ≈ Σ T_i w_i / Σ w_i (normalised by
// Σ w, which is π up to the quadrature's error, so that a clear sky gives V = 1 exactly).

// The rays are marched in AMBIENT_SUBSETS interleaved subsets (ray i in subset i mod 12), one
// subset per frame (all of them on a view's first frame and after its history is dropped:
// a camera cut, a resize, a settings change); each subset keeps its sums, and
// `ambient_resolve` adds the latest of all of them. So a frame costs a twelfth of the rays
// (64), the estimate is the whole set's (768), and each part of it is at most eleven frames
// old. Twelve subsets, not three (before 2026-12-07): a sparse cumulus sky has a few bright
// clouds, each about as wide as the solid angle one of 128 cosine rays stands for, and 192
// directions put the probe up to 27% off the picture's integral; 768 are within 6.3%.
// Each ray is marched in AMBIENT_PARTS consecutive ranges of its steps, one per invocation
// (march_layer, shaders/march_ray.wgsl), put together front to back in workgroup memory: the
// pass is a few hundred invocations, so its time on a GPU is one ray's chain of dependent
// samples, which the parts shorten (0.38 -> 0.16 ms on an NVIDIA H200: each part first sums
// its range's optical depth along the view, and a workgroup waits for its slowest part;
// docs/performance.md).

// Per hemisphere (0 above, 1 below): rgb E_clouds (the sun's units × sr), a V.
@group(0) @binding(13) var<storage, read_write> ambient_out: array<vec4f, 2>;
// Per subset, hemisphere and workgroup (index AMBIENT_GROUPS × (2 × subset + hemisphere) +
// group), two vec4: the weighted sums of (L, T), and (the sum of the weights, 0, 0, 0).
@group(0) @binding(14) var<storage, read_write> ambient_partial: array<vec4f, 384>;
// x: the first subset this frame marches, y: how many (1, or all 3).
@group(0) @binding(15) var<storage, read> ambient_params: vec4u;

const AMBIENT_SUBSETS: u32 = 12u;
const AMBIENT_THREADS: u32 = 64u;
const AMBIENT_PARTS: u32 = 8u;
// Rays per workgroup, and workgroups per subset and hemisphere (64 rays).
const AMBIENT_GROUP_RAYS: u32 = 8u;
const AMBIENT_GROUPS: u32 = 8u;
const AMBIENT_COSINE_RAYS: u32 = 512u;
const AMBIENT_SUN_RAYS: u32 = 256u;
const GOLDEN_ANGLE: f32 = 2.39996322973;

var<workgroup> partial: array<vec4f, 64>;
var<workgroup> partial_weight: array<f32, 64>;
// Each invocation's part of its ray: (L, T) and whether the part stopped at the cutoff.
var<workgroup> part_light: array<vec4f, 64>;
var<workgroup> part_stopped: array<u32, 64>;
var<workgroup> part_entry: array<f32, 64>;

// Two unit vectors completing `axis` to an orthonormal basis.
fn basis_of(axis: vec3f) -> mat2x3f {
    let reference = select(vec3f(1.0, 0.0, 0.0), vec3f(0.0, 0.0, 1.0), abs(axis.x) > 0.9);
    let b1 = normalize(cross(reference, axis));
    return mat2x3f(b1, cross(axis, b1));
}

// The cosine from the axis of the sample with CDF value `xi` (HG inverted; uniform for g = 0).
fn hg_cosine(xi: f32, g: f32) -> f32 {
    if (abs(g) < 1e-3) {
        return 1.0 - 2.0 * xi;
    }
    let q = (1.0 - g * g) / (1.0 - g + 2.0 * g * xi);
    return clamp((1.0 + g * g - q * q) / (2.0 * g), -1.0, 1.0);
}

// The direction at cosine `c` from `axis` and azimuth `phi` around it.
fn around(axis: vec3f, frame: mat2x3f, c: f32, phi: f32) -> vec3f {
    let s = sqrt(max(1.0 - c * c, 0.0));
    return normalize(frame[0] * (s * cos(phi)) + frame[1] * (s * sin(phi)) + axis * c);
}

// The lobe to draw sun ray `k` from: (asymmetry, rays in this lobe, index in it) for the
// phase model's two lobes (phase.wgsl), and each lobe's ray count.
struct SunLobes {
    g: vec2f,
    count: vec2f,
}

fn sun_lobes() -> SunLobes {
    // model 0 (HG + Draine): HG(g_hg) weighs 1 - w, Draine(g_d) ~ HG(g_d) weighs w;
    // model 1 (dual-lobe HG): forward weighs w, backward 1 - w.
    let first_weight = select(u.phase.w, 1.0 - u.phase.w, u32(u.misc.y) == 0u);
    let n = f32(AMBIENT_SUN_RAYS);
    // At least 8 rays per lobe, so neither is left unsampled.
    let first = clamp(round(first_weight * n), 8.0, n - 8.0);
    return SunLobes(u.phase.xy, vec2f(first, n - first));
}

// AMBIENT_GROUPS workgroups per hemisphere (x / AMBIENT_GROUPS) and subset marched this frame
// (y); in each, AMBIENT_GROUP_RAYS rays of AMBIENT_PARTS invocations.
@compute @workgroup_size(64, 1, 1)
fn ambient(@builtin(local_invocation_id) lid: vec3u, @builtin(workgroup_id) wg: vec3u) {
    let cam = u.camera.xyz;
    let hemisphere = wg.x / AMBIENT_GROUPS;
    let group = wg.x % AMBIENT_GROUPS;
    let sign = select(1.0, -1.0, hemisphere == 1u);
    let normal = sign * normalize(cam + u.planet.xyz * u.planet.w);
    let normal_frame = basis_of(normal);
    let sun = u.sun.xyz;
    let sun_frame = basis_of(sun);
    let lobes = sun_lobes();
    let n_c = f32(AMBIENT_COSINE_RAYS);
    // The solid angle one cosine ray stands for, 2π / N, as an angle; a quarter of it is the
    // noise footprint (as the light march takes a quarter of its segment): the rays sample the
    // clouds' detail rather than a blur of it, whose transmittance would be too low.
    let pixel_angle = 0.25 * sqrt(2.0 * PI / n_c);
    let subset = (ambient_params.x + wg.y) % AMBIENT_SUBSETS;
    // (AMBIENT_COSINE_RAYS + AMBIENT_SUN_RAYS) / AMBIENT_SUBSETS = 64 rays per subset.
    let ray_in_group = lid.x / AMBIENT_PARTS;
    let part = lid.x % AMBIENT_PARTS;
    let i = subset + AMBIENT_SUBSETS * (group * AMBIENT_GROUP_RAYS + ray_in_group);
    var dir: vec3f;
    if (i < AMBIENT_COSINE_RAYS) {
        let k = f32(i);
        dir = around(normal, normal_frame, sqrt((k + 0.5) / n_c), k * GOLDEN_ANGLE);
    } else {
        var k = f32(i - AMBIENT_COSINE_RAYS);
        var lobe = 0u;
        if (k >= lobes.count.x) {
            k -= lobes.count.x;
            lobe = 1u;
        }
        let xi = (k + 0.5) / lobes.count[lobe];
        dir = around(sun, sun_frame, hg_cosine(xi, lobes.g[lobe]), k * GOLDEN_ANGLE);
    }
    var sum = vec4f(0.0);
    var weight = 0.0;
    let cos_n = dot(dir, normal);
    // A fixed low-discrepancy offset per ray (the directions are fixed too).
    let jitter = fract(0.5 + f32(i) * 0.61803398875);
    // A sun-lobe ray outside this hemisphere weighs 0 (and is not marched).
    let marched = cos_n > 0.0;
    let first_part = lid.x - part;
    // First the optical depth along the view where each part starts (the column light looks
    // back along the view ray by it): each part's own, put together over the parts before.
    if (marched) {
        part_light[lid.x] = vec4f(part_view_depth(cam, dir, u.layer.w, jitter, pixel_angle, part, AMBIENT_PARTS), 0.0);
    }
    workgroupBarrier();
    var tau_view_start = 0.0;
    for (var k = 0u; k < part; k++) {
        let d = part_light[first_part + k];
        tau_view_start = select(tau_view_start + d.x, d.y, d.z > 0.0);
    }
    workgroupBarrier();
    if (marched) {
        light_samples = 0u;
        let ray = march_layer(cam, dir, u.layer.w, jitter, pixel_angle, part, AMBIENT_PARTS, tau_view_start);
        part_light[lid.x] = vec4f(ray.radiance, ray.transmittance);
        part_stopped[lid.x] = u32(ray.stopped);
        part_entry[lid.x] = ray.layer_entry;
    }
    workgroupBarrier();
    if (marched && part == 0u) {
        let c = dot(dir, sun);
        let density = n_c * cos_n / PI
            + lobes.count.x * henyey_greenstein(c, lobes.g.x)
            + lobes.count.y * henyey_greenstein(c, lobes.g.y);
        weight = cos_n / density;
        // The parts front to back (join_parts), up to the first that stopped.
        var ray = march_layer_none();
        for (var k = 0u; k < AMBIENT_PARTS; k++) {
            let p = part_light[lid.x + k];
            ray = join_parts(ray, MarchRay(p.rgb, p.a, 0.0, 0.0, 0u, part_entry[lid.x + k], part_stopped[lid.x + k] != 0u));
        }
        ray = with_cirrus(ray, cam, dir, u.layer.w);
        sum = weight * vec4f(ray.radiance, ray.transmittance);
    }
    partial[lid.x] = sum;
    partial_weight[lid.x] = weight;
    workgroupBarrier();
    for (var stride = AMBIENT_THREADS / 2u; stride > 0u; stride >>= 1u) {
        if (lid.x < stride) {
            partial[lid.x] += partial[lid.x + stride];
            partial_weight[lid.x] += partial_weight[lid.x + stride];
        }
        workgroupBarrier();
    }
    if (lid.x == 0u) {
        let slot = 2u * (AMBIENT_GROUPS * (2u * subset + hemisphere) + group);
        ambient_partial[slot] = partial[0];
        ambient_partial[slot + 1u] = vec4f(partial_weight[0], 0.0, 0.0, 0.0);
    }
}

// The estimate from every subset's latest sums, per hemisphere (invocation = hemisphere).
@compute @workgroup_size(2, 1, 1)
fn ambient_resolve(@builtin(local_invocation_id) lid: vec3u) {
    var sum = vec4f(0.0);
    var weight = 0.0;
    for (var subset = 0u; subset < AMBIENT_SUBSETS; subset++) {
        for (var group = 0u; group < AMBIENT_GROUPS; group++) {
            let slot = 2u * (AMBIENT_GROUPS * (2u * subset + lid.x) + group);
            sum += ambient_partial[slot];
            weight += ambient_partial[slot + 1u].x;
        }
    }
    let total = sum / weight;
    ambient_out[lid.x] = vec4f(total.rgb * PI, total.a);
}
