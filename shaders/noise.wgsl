// Tileable procedural noise on the unit cube: every function below is periodic with period 1
// in x, y and z, because lattice and cell indices wrap modulo the frequency.

// Callers pass cells within one period of the tile, c in [-period, 2 period): two selects
// give the same answer as ((c % period) + period) % period without an integer division
// (which software rasterisers run lane by lane).
fn wrap_cell(c: vec3i, period: vec3i) -> vec3i {
    let up = select(c, c + period, c < vec3i(0));
    return select(up, up - period, up >= period);
}

// Perlin 2002 fade: 6t^5 - 15t^4 + 10t^3.
fn fade(t: vec3f) -> vec3f {
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}

// Perlin 2002 gradient set: the 12 edge directions of a cube, hash % 12 picking
// (x+y, -x+y, x-y, -x-y, x+z, -x+z, x-z, -x-z, y+z, -y+z, y-z, -y-z). Written with selects
// instead of a switch: a software rasteriser runs a divergent switch case by case.
fn grad_dot(hash: u32, d: vec3f) -> f32 {
    let h = hash % 12u;
    let u = select(d.y, d.x, h < 8u);
    let v = select(d.z, d.y, h < 4u);
    return select(u, -u, (h & 1u) != 0u) + select(v, -v, (h & 2u) != 0u);
}

fn lattice_hash(c: vec3i, period: vec3i, seed: u32) -> u32 {
    return pcg3d(bitcast<vec3u>(wrap_cell(c, period)) ^ vec3u(seed, seed * 7919u, seed * 104729u)).x;
}

// One lattice corner's gradient term: the corner at cell i + o, seen from the point at f.
fn perlin_corner(i: vec3i, f: vec3f, o: vec3i, freq: vec3i, seed: u32) -> f32 {
    return grad_dot(lattice_hash(i + o, freq, seed), f - vec3f(o));
}

// Improved Perlin noise with `freq` lattice cells per unit along each axis, in [-1, 1] (about).
fn perlin3(p_unit: vec3f, freq: vec3i, seed: u32) -> f32 {
    let p = p_unit * vec3f(freq);
    let i = vec3i(floor(p));
    let f = p - floor(p);
    let u = fade(f);
    // The eight corners by name, not in an indexed array (which lives in scratch memory
    // on software rasterisers).
    let x00 = mix(perlin_corner(i, f, vec3i(0, 0, 0), freq, seed), perlin_corner(i, f, vec3i(1, 0, 0), freq, seed), u.x);
    let x10 = mix(perlin_corner(i, f, vec3i(0, 1, 0), freq, seed), perlin_corner(i, f, vec3i(1, 1, 0), freq, seed), u.x);
    let x01 = mix(perlin_corner(i, f, vec3i(0, 0, 1), freq, seed), perlin_corner(i, f, vec3i(1, 0, 1), freq, seed), u.x);
    let x11 = mix(perlin_corner(i, f, vec3i(0, 1, 1), freq, seed), perlin_corner(i, f, vec3i(1, 1, 1), freq, seed), u.x);
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
// A cell's feature point lies inside the cell, so a neighbour whose nearest face is already
// farther than the best distance found cannot win: skipping it gives the same minimum (a
// branch-and-bound search, seeded with the point's own cell).
fn worley(p_unit: vec3f, freq: i32, seed: u32) -> f32 {
    let p = p_unit * f32(freq);
    let cell = vec3i(floor(p));
    let f = p - vec3f(cell);
    let period = vec3i(freq);
    let own = p - (vec3f(cell) + hash33(wrap_cell(cell, period), seed));
    var best = dot(own, own);
    for (var z = -1; z <= 1; z++) {
        for (var y = -1; y <= 1; y++) {
            for (var x = -1; x <= 1; x++) {
                let o = vec3i(x, y, z);
                // Distance from p to the neighbour cell's box, per axis.
                let gap = select(vec3f(0.0), select(1.0 - f, f, o < vec3i(0)), o != vec3i(0));
                if (dot(gap, gap) < best) {
                    let c = cell + o;
                    let d = p - (vec3f(c) + hash33(wrap_cell(c, period), seed));
                    best = min(best, dot(d, d));
                }
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
