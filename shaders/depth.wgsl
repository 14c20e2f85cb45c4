// Scene depth to distance: shared by the march and the composite. Mirrors frame::scene_distance.

const NO_SCENE: f32 = 1.0e30;

// Distance from `camera` to the scene point behind NDC `ndc` with clip depth `depth`, or
// NO_SCENE where the depth buffer holds `far_value` (the sky).
// `inv_view_proj_rel` is camera-relative (see `unproject` in medium.wgsl): the point it gives is
// the offset from the camera, so its length is the distance with no f32 cancellation.
fn scene_distance_at(inv_view_proj_rel: mat4x4f, far_value: f32, ndc: vec2f, depth: f32) -> f32 {
    if (depth == far_value) {
        return NO_SCENE;
    }
    let p = inv_view_proj_rel * vec4f(ndc, depth, 1.0);
    if (abs(p.w) < 1e-20) {
        return NO_SCENE;
    }
    return min(length(p.xyz / p.w), NO_SCENE);
}

// NDC of the center of pixel `pixel` in an image of `dims`.
fn pixel_ndc(pixel: vec2u, dims: vec2u) -> vec2f {
    return vec2f(
        (f32(pixel.x) + 0.5) / f32(dims.x) * 2.0 - 1.0,
        1.0 - (f32(pixel.y) + 0.5) / f32(dims.y) * 2.0,
    );
}
