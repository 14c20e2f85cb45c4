// Density probe (compute): the medium's density at given points, as the march sees it at the
// finest noise mip. The reference for the CPU queries (src/query.rs, tests/query.rs).

@group(0) @binding(6) var<storage, read> probe_points: array<vec4f>;
@group(0) @binding(7) var<storage, read_write> probe_density: array<f32>;

@compute @workgroup_size(64, 1, 1)
fn probe(@builtin(global_invocation_id) id: vec3u) {
    if (id.x >= arrayLength(&probe_density)) {
        return;
    }
    base_texel = 1.0 / (u.scales.x * f32(textureDimensions(base_tex).x));
    detail_texel = 1.0 / (u.scales.y * f32(textureDimensions(detail_tex).x));
    probe_density[id.x] = sample_density(probe_points[id.x].xyz, false, 0.0);
}
