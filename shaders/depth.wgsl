// Scene depth to distance: shared by the march and the composite. Mirrors frame::scene_distance.

const NO_SCENE: f32 = 1.0e30;

// `inv_view_proj_rel` in every pass maps NDC to positions relative to the camera: the host
// inverts view-projection × translation(camera) in f64. Rays and distances then never subtract
// the camera position in f32, which 12 km from the world origin lost about 1e-3 rad (a still
// camera's reprojection missed its own pixel and the history blurred).

// The direction of the view ray through `ndc`: the unprojected near-plane point's own.
fn view_ray_dir(inv_view_proj_rel: mat4x4f, ndc: vec2f, near_value: f32) -> vec3f {
    let p = inv_view_proj_rel * vec4f(ndc, near_value, 1.0);
    return normalize(p.xyz / p.w);
}

// Distance from the camera to the scene point behind NDC `ndc` with clip depth `depth` (the
// unprojected point's length), or NO_SCENE where the depth buffer holds `far_value` (the sky).
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
