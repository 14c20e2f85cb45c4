// Tileable procedural noise on the unit cube: every function below is periodic with period 1
// in x, y and z, because lattice and cell indices wrap modulo the frequency.

fn wrap_cell(c: vec3i, period: vec3i) -> vec3i {
    return ((c % period) + period) % period;
}

// Perlin 2002 fade: 6t^5 - 15t^4 + 10t^3.
fn fade(t: vec3f) -> vec3f {
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}

// Perlin 2002 gradient set: the 12 edge directions of a cube.
fn grad_dot(hash: u32, d: vec3f) -> f32 {
    switch (hash % 12u) {
        case 0u: { return d.x + d.y; }
        case 1u: { return -d.x + d.y; }
        case 2u: { return d.x - d.y; }
        case 3u: { return -d.x - d.y; }
        case 4u: { return d.x + d.z; }
        case 5u: { return -d.x + d.z; }
        case 6u: { return d.x - d.z; }
        case 7u: { return -d.x - d.z; }
        case 8u: { return d.y + d.z; }
        case 9u: { return -d.y + d.z; }
        case 10u: { return d.y - d.z; }
        default: { return -d.y - d.z; }
    }
}

fn lattice_hash(c: vec3i, period: vec3i, seed: u32) -> u32 {
    return pcg3d(bitcast<vec3u>(wrap_cell(c, period)) ^ vec3u(seed, seed * 7919u, seed * 104729u)).x;
}

// Improved Perlin noise with `freq` lattice cells per unit along each axis, in [-1, 1] (about).
fn perlin3(p_unit: vec3f, freq: vec3i, seed: u32) -> f32 {
    let p = p_unit * vec3f(freq);
    let i = vec3i(floor(p));
    let f = p - floor(p);
    let u = fade(f);
    var corners: array<f32, 8>;
    for (var k = 0; k < 8; k++) {
        let o = vec3i(k & 1, (k >> 1) & 1, (k >> 2) & 1);
        corners[k] = grad_dot(lattice_hash(i + o, freq, seed), f - vec3f(o));
    }
    let x00 = mix(corners[0], corners[1], u.x);
    let x10 = mix(corners[2], corners[3], u.x);
    let x01 = mix(corners[4], corners[5], u.x);
    let x11 = mix(corners[6], corners[7], u.x);
    return mix(mix(x00, x10, u.y), mix(x01, x11, u.y), u.z);
}

fn perlin(p_unit: vec3f, freq: i32, seed: u32) -> f32 {
    return perlin3(p_unit, vec3i(freq), seed);
}

// Anisotropic Perlin fBM in [0, 1]: different cell counts per axis (streaks), lacunarity 2.
fn perlin_fbm3(p: vec3f, freq: vec3i, octaves: i32, persistence: f32, seed: u32) -> f32 {
    var sum = 0.0;
    var amp = 1.0;
    var total = 0.0;
    var f = freq;
    for (var o = 0; o < octaves; o++) {
        sum += perlin3(p, f, seed + u32(o)) * amp;
        total += amp;
        amp *= persistence;
        f *= 2;
    }
    return clamp(sum / total * 0.5 + 0.5, 0.0, 1.0);
}

// Perlin fBM, normalised to [0, 1]; lacunarity 2 keeps every octave tileable.
fn perlin_fbm(p: vec3f, freq: i32, octaves: i32, persistence: f32, seed: u32) -> f32 {
    return perlin_fbm3(p, vec3i(freq), octaves, persistence, seed);
}

// Inverted Worley F1 with wrapped cells (one feature point per cell): 1 at feature points,
// falling to 0 a cell away. Billowy rather than cellular (Aetherius, "Worley Noise").
fn worley(p_unit: vec3f, freq: i32, seed: u32) -> f32 {
    let p = p_unit * f32(freq);
    let cell = vec3i(floor(p));
    var best = 1e9;
    for (var z = -1; z <= 1; z++) {
        for (var y = -1; y <= 1; y++) {
            for (var x = -1; x <= 1; x++) {
                let c = cell + vec3i(x, y, z);
                let feature = vec3f(c) + hash33(wrap_cell(c, vec3i(freq)), seed);
                let d = p - feature;
                best = min(best, dot(d, d));
            }
        }
    }
    return 1.0 - clamp(sqrt(best), 0.0, 1.0);
}

// Three Worley octaves at freq, 2 freq, 4 freq weighted 0.625 / 0.25 / 0.125 (Schneider).
fn worley_fbm(p: vec3f, freq: i32, seed: u32) -> f32 {
    return worley(p, freq, seed) * 0.625 + worley(p, freq * 2, seed + 1u) * 0.25
        + worley(p, freq * 4, seed + 2u) * 0.125;
}
