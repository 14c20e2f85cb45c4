// Shared helpers for every Nimbus pass.

const PI: f32 = 3.14159265358979;

fn remap(v: f32, lo: f32, hi: f32, new_lo: f32, new_hi: f32) -> f32 {
    // Mirrors weather::profile::remap, including its degenerate-range rule.
    let span = hi - lo;
    var t: f32;
    if (abs(span) < 1e-6) {
        t = select(1.0, 0.0, v < hi);
    } else {
        t = (v - lo) / span;
    }
    return new_lo + t * (new_hi - new_lo);
}

// PCG-based 3D integer hash (Jarzynski & Olano 2020, "Hash Functions for GPU Rendering").
fn pcg3d(v_in: vec3u) -> vec3u {
    var v = v_in * 1664525u + 1013904223u;
    v.x += v.y * v.z;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v ^= v >> vec3u(16u);
    v.x += v.y * v.z;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    return v;
}

// Three uniform numbers in [0, 1) from an integer lattice point and a seed.
fn hash33(p: vec3i, seed: u32) -> vec3f {
    let h = pcg3d(bitcast<vec3u>(p) ^ vec3u(seed * 0x9E3779B9u, seed * 0x85EBCA6Bu, seed * 0xC2B2AE35u));
    return vec3f(h >> vec3u(8u)) * (1.0 / 16777216.0);
}
