//! Per-frame inputs: camera, depth convention, sun and time.
//!
//! Matrices are column-major glam matrices in a right-handed world (meters). The projection
//! maps to wgpu clip space: x, y in [-1, 1], depth in [0, 1]. Reversed-Z and an infinite far
//! plane are declared with [`DepthConvention`], never guessed; `prepare` checks the declaration
//! against the projection matrix and refuses a mismatch.

use glam::{Mat4, Vec3, Vec4};

use crate::error::{invalid_frame, Result};

/// How the host's depth buffer encodes distance.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DepthConvention {
    /// Near plane at depth 1, far (or infinity) at depth 0. Default false.
    pub reversed_z: bool,
    /// The projection has no far plane (depth reaches its far value only at infinity).
    /// Default false.
    pub infinite_far: bool,
    /// The projection is OpenGL-style: clip z in [-w, w], and the depth buffer holds window
    /// depth (z / w + 1) / 2, as OpenGL writes it with its default depth range. Nimbus maps it
    /// to [0, 1] clip space itself. A projection matrix cannot tell the two conventions apart
    /// (every OpenGL matrix is also a valid [0, 1] matrix with other near and far planes), so
    /// this flag is the host's word, not a guess. Default false: [0, 1] (Vulkan, D3D, Metal,
    /// wgpu).
    pub gl_clip_z: bool,
}

impl DepthConvention {
    /// The depth value of "nothing here" (the far plane or infinity): 1, or 0 for reversed-Z.
    /// Pixels holding it are treated as sky: clouds are marched to their full distance.
    pub fn far_value(&self) -> f32 {
        if self.reversed_z {
            0.0
        } else {
            1.0
        }
    }

    /// The depth value of the near plane.
    pub fn near_value(&self) -> f32 {
        1.0 - self.far_value()
    }
}

/// The camera of the frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// World-to-view matrix (right-handed, camera looks down -Z).
    pub view: Mat4,
    /// View-to-clip perspective projection (wgpu clip space, depth in [0, 1]).
    pub projection: Mat4,
    /// How the projection encodes depth.
    pub depth: DepthConvention,
}

/// The sun.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sun {
    /// Direction from the scene toward the sun (normalised on use).
    pub direction: Vec3,
    /// Linear RGB tint, each channel >= 0. Default white.
    pub color: Vec3,
    /// Illuminance in lux-like linear units (>= 0). Output radiance scales with it.
    pub illuminance: f32,
}

impl Default for Sun {
    fn default() -> Self {
        Self {
            direction: Vec3::new(0.3, 0.6, -0.74).normalize(),
            color: Vec3::ONE,
            illuminance: 10.0,
        }
    }
}

/// Everything that changes per frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameInputs {
    /// The camera.
    pub camera: Camera,
    /// The sun.
    pub sun: Sun,
    /// Time in seconds on the host's clock: it drives the wind and weather transitions; there
    /// is no hidden clock, so the same times give the same sky.
    pub time: f64,
}

/// Camera quantities derived once per frame and used by both CPU mirror and shader.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct CameraDerived {
    /// Inverse of view-projection × translation(camera): NDC to positions relative to the
    /// camera, so that the shaders build ray directions and scene distances without
    /// subtracting the camera position (f32 cancellation far from the world origin).
    pub inv_view_proj_rel: Mat4,
    pub view_proj: Mat4,
    pub position: Vec3,
}

fn matrix_finite(field: &'static str, m: &Mat4) -> Result<()> {
    if m.is_finite() {
        Ok(())
    } else {
        Err(invalid_frame(field, "contains NaN or infinity"))
    }
}

fn invertible(field: &'static str, m: &Mat4) -> Result<Mat4> {
    // In f64: a view-projection with a far plane hundreds of km away is ill-conditioned in f32
    // but perfectly usable. Scale-free test: the inverse must exist and round-trip to I.
    let md = m.as_dmat4();
    let det = md.determinant();
    let inv = md.inverse();
    let round_trip = (md * inv - glam::DMat4::IDENTITY)
        .to_cols_array()
        .iter()
        .fold(0.0f64, |a, v| a.max(v.abs()));
    if det == 0.0
        || !det.is_finite()
        || !inv.is_finite()
        || round_trip.is_nan()
        || round_trip >= 1e-6
    {
        return Err(invalid_frame(
            field,
            format!("is not invertible (det {det}, |M M^-1 - I| = {round_trip})"),
        ));
    }
    let inv = inv.as_mat4();
    if !inv.is_finite() {
        return Err(invalid_frame(field, "inverse is not finite in f32"));
    }
    Ok(inv)
}

/// View distance of the depth value `far_value`, in f64 (`f64::INFINITY` at infinity).
fn far_plane_distance(projection: &Mat4, far_value: f32) -> f64 {
    let inv = projection.as_dmat4().inverse();
    let p = inv * glam::DVec4::new(0.0, 0.0, far_value as f64, 1.0);
    if p.w.abs() < 1e-15 {
        return f64::INFINITY;
    }
    let d = -p.z / p.w;
    if d <= 0.0 {
        f64::INFINITY
    } else {
        d
    }
}

/// NDC depth of a point `dist` meters in front of the camera.
fn depth_at(projection: &Mat4, dist: f32) -> f32 {
    let c = *projection * Vec4::new(0.0, 0.0, -dist, 1.0);
    c.z / c.w
}

/// Clip z in [-w, w] to [0, w]: z' = (z + w) / 2. Applied to an OpenGL-style projection, the
/// new NDC depth equals the window depth OpenGL wrote into the depth buffer.
const GL_TO_ZERO_ONE: Mat4 = Mat4::from_cols_array(&[
    1.0, 0.0, 0.0, 0.0, //
    0.0, 1.0, 0.0, 0.0, //
    0.0, 0.0, 0.5, 0.0, //
    0.0, 0.0, 0.5, 1.0,
]);

/// Beyond this distance (m) a far plane counts as infinite: f32 depth cannot resolve it.
const FAR_INDISTINGUISHABLE: f64 = 1e9;

impl Camera {
    /// The projection in wgpu clip space (depth in [0, 1]), whatever the host's convention.
    fn zero_one_projection(&self) -> Mat4 {
        if self.depth.gl_clip_z {
            // In f64, rounded once: the z row's 1 + A is tiny for a far far plane, and an f32
            // product would round A twice and move the far plane by percents.
            (GL_TO_ZERO_ONE.as_dmat4() * self.projection.as_dmat4()).as_mat4()
        } else {
            self.projection
        }
    }

    /// Checks the matrices and that `depth` matches what the projection really does.
    pub(crate) fn derive(&self) -> Result<CameraDerived> {
        matrix_finite("camera.view", &self.view)?;
        matrix_finite("camera.projection", &self.projection)?;
        invertible("camera.view", &self.view)?;
        invertible("camera.projection", &self.projection)?;
        let projection = self.zero_one_projection();
        if projection.w_axis.w.abs() > 1e-6 || projection.z_axis.w.abs() < 1e-6 {
            return Err(invalid_frame(
                "camera.projection",
                "must be a perspective projection (clip w = -view z)",
            ));
        }
        let (near, mid) = (depth_at(&projection, 1e-3), depth_at(&projection, 1e3));
        let reversed = mid < near;
        if reversed != self.depth.reversed_z {
            return Err(invalid_frame(
                "camera.depth.reversed_z",
                format!(
                    "is {} but the projection maps depth {} with distance",
                    self.depth.reversed_z,
                    if reversed { "decreasing" } else { "increasing" }
                ),
            ));
        }
        // Where the far value lands: infinitely far only for an infinite projection. In f64 so
        // that a legitimately huge but finite far plane is not mistaken for infinity.
        let far_dist = far_plane_distance(&projection, self.depth.far_value());
        // A finite far plane past 1e9 m, or a far/near ratio so large that the z row rounds
        // to an infinite projection's in f32, is infinite in effect: it must be declared so.
        let infinite = far_dist > FAR_INDISTINGUISHABLE;
        if infinite != self.depth.infinite_far {
            return Err(invalid_frame(
                "camera.depth.infinite_far",
                if infinite {
                    format!(
                        "is {} but the projection has no far plane in f32 (its z row is an \
                         infinite projection's: a far/near ratio above about 1e7 rounds to \
                         that); declare an infinite far plane",
                        self.depth.infinite_far
                    )
                } else {
                    format!(
                        "is {} but the projection has a far plane, at about {far_dist:.0} m \
                         as its f32 entries encode it (near/far ratios beyond about 1e5 make \
                         f32 place the far plane only roughly)",
                        self.depth.infinite_far
                    )
                },
            ));
        }
        let view_proj = projection * self.view;
        invertible("camera.view * camera.projection", &view_proj)?;
        // In f64: the f32 view's translation is the camera position rotated and rounded, and
        // composing it with translation(camera) must cancel to (nearly) zero, not to f32
        // rounding noise of a 12 km position (about 1e-3 m, 1e-3 rad at a 1 m near plane).
        let position = self.view.as_dmat4().inverse().w_axis.truncate();
        let relative =
            projection.as_dmat4() * self.view.as_dmat4() * glam::DMat4::from_translation(position);
        let inv_view_proj_rel = relative.inverse().as_mat4();
        matrix_finite("camera.view * camera.projection", &inv_view_proj_rel)?;
        Ok(CameraDerived {
            inv_view_proj_rel,
            view_proj,
            position: position.as_vec3(),
        })
    }
}

impl Sun {
    pub(crate) fn validate(&self) -> Result<Vec3> {
        if !self.direction.is_finite() || self.direction.length() < 1e-6 {
            return Err(invalid_frame(
                "sun.direction",
                format!(
                    "must be a finite non-zero vector, got {}",
                    crate::validate::vec(self.direction)
                ),
            ));
        }
        if !self.color.is_finite() || self.color.min_element() < 0.0 {
            return Err(invalid_frame(
                "sun.color",
                format!(
                    "must be finite and non-negative, got {}",
                    crate::validate::vec(self.color)
                ),
            ));
        }
        if !self.illuminance.is_finite() || self.illuminance < 0.0 {
            return Err(invalid_frame(
                "sun.illuminance",
                format!(
                    "must be finite and >= 0, got {}",
                    crate::validate::num(self.illuminance)
                ),
            ));
        }
        Ok(self.direction.normalize())
    }
}

impl FrameInputs {
    /// Checks the inputs exactly as [`crate::Renderer::prepare`] does, without a renderer: the
    /// matrices, the declared depth convention against the projection, the sun and the time.
    pub fn check(&self) -> Result<()> {
        self.validate().map(|_| ())
    }

    pub(crate) fn validate(&self) -> Result<(CameraDerived, Vec3)> {
        if !self.time.is_finite() {
            return Err(invalid_frame(
                "time",
                format!("must be finite, got {}", crate::validate::num(self.time)),
            ));
        }
        Ok((self.camera.derive()?, self.sun.validate()?))
    }
}

/// Distance in meters from the camera to the scene point behind NDC position (x, y) with
/// depth `depth`, or `f32::INFINITY` where the depth buffer holds the far value (the sky).
/// Mirrors `scene_distance` in `shaders/march.wgsl`.
pub fn scene_distance(
    ndc_x: f32,
    ndc_y: f32,
    depth: f32,
    inv_view_proj: &Mat4,
    camera_pos: Vec3,
    convention: DepthConvention,
) -> f32 {
    if depth == convention.far_value() {
        return f32::INFINITY;
    }
    let p = *inv_view_proj * Vec4::new(ndc_x, ndc_y, depth, 1.0);
    if p.w.abs() < 1e-20 {
        return f32::INFINITY;
    }
    (p.truncate() / p.w - camera_pos).length()
}

/// View-space linear depth (distance along the view axis) of an NDC depth value, from the
/// inverse projection; `f32::INFINITY` for the far value.
pub fn linearize_depth(depth: f32, projection: &Mat4, convention: DepthConvention) -> f32 {
    if depth == convention.far_value() {
        return f32::INFINITY;
    }
    let projection = Camera {
        view: Mat4::IDENTITY,
        projection: *projection,
        depth: convention,
    }
    .zero_one_projection();
    let p = projection.inverse() * Vec4::new(0.0, 0.0, depth, 1.0);
    if p.w.abs() < 1e-20 {
        return f32::INFINITY;
    }
    -p.z / p.w
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Error;

    const N: f32 = 0.5;
    const F: f32 = 5_000.0;

    fn conv(reversed_z: bool, infinite_far: bool) -> DepthConvention {
        DepthConvention {
            reversed_z,
            infinite_far,
            ..Default::default()
        }
    }

    /// 12 km from the origin the rays must still point where f64 says they do: "near-plane
    /// point minus camera position" in f32 was off by about 1e-3 rad there on the GPU (more
    /// than a pixel at 1920x1080, and a still camera's history drifted); the camera-relative
    /// inverse is exact to f32 rounding of the direction itself.
    #[test]
    fn ray_directions_stay_exact_far_from_the_origin() {
        let eye = Vec3::new(300.0, 12_000.0, -200.0);
        let target = Vec3::new(0.0, 6_000.0, -14_000.0);
        let camera = Camera {
            view: Mat4::look_at_rh(eye, target, Vec3::Y),
            projection: Mat4::perspective_rh(1.0, 16.0 / 9.0, N, F),
            depth: DepthConvention::default(),
        };
        let d = camera.derive().unwrap();
        assert!((d.position - eye).length() < 2e-3, "{}", d.position);
        let inv64 = (camera.projection.as_dmat4() * camera.view.as_dmat4()).inverse();
        let eye64 = camera.view.as_dmat4().inverse().w_axis.truncate();
        let mut worst = 0.0f64;
        for (x, y) in [(0.0, 0.0), (0.9, 0.7), (-0.8, -0.95), (0.33, -0.4)] {
            let p = d.inv_view_proj_rel * Vec4::new(x, y, 0.0, 1.0);
            let dir = (p.truncate() / p.w).normalize().as_dvec3();
            let q = inv64 * glam::DVec4::new(x as f64, y as f64, 0.0, 1.0);
            let exact = (q.truncate() / q.w - eye64).normalize();
            worst = worst.max(dir.angle_between(exact));
        }
        assert!(worst < 1e-6, "{worst}");
    }

    #[test]
    fn gl_clip_z_projection_reads_as_its_zero_one_twin() {
        let fov = 1.1;
        let gl = Mat4::perspective_rh_gl(fov, 1.5, N, F);
        let zero_one = Mat4::perspective_rh(fov, 1.5, N, F);
        let view = Mat4::look_at_rh(
            Vec3::new(0.0, 2.0, 0.0),
            Vec3::new(0.0, 3.0, -10.0),
            Vec3::Y,
        );
        let flagged = Camera {
            view,
            projection: gl,
            depth: DepthConvention {
                gl_clip_z: true,
                ..Default::default()
            },
        };
        let plain = Camera {
            view,
            projection: zero_one,
            depth: DepthConvention::default(),
        };
        let (a, b) = (flagged.derive().unwrap(), plain.derive().unwrap());
        let scale = b
            .inv_view_proj_rel
            .to_cols_array()
            .iter()
            .fold(0.0f32, |m, v| m.max(v.abs()));
        assert!(a
            .inv_view_proj_rel
            .abs_diff_eq(b.inv_view_proj_rel, 1e-3 * scale));
        // The window depth OpenGL writes for a point 100 m away linearises back to 100 m.
        let c = gl * Vec4::new(0.0, 0.0, -100.0, 1.0);
        let window_depth = (c.z / c.w + 1.0) * 0.5;
        let d = linearize_depth(window_depth, &gl, flagged.depth);
        assert!((d - 100.0).abs() < 0.05, "{d}");
        // Without the flag the same buffer value reads as another distance: the silent misread
        // the flag exists for.
        let misread = linearize_depth(window_depth, &gl, DepthConvention::default());
        assert!((misread - 100.0).abs() > 10.0, "{misread}");
    }

    #[test]
    fn a_far_plane_beyond_f32_reach_must_be_declared_infinite_and_says_why() {
        let cam = |infinite_far| Camera {
            view: Mat4::IDENTITY,
            projection: Mat4::perspective_rh(1.0, 1.5, 0.01, 1e13),
            depth: conv(false, infinite_far),
        };
        cam(true).derive().unwrap();
        let e = cam(false).derive().unwrap_err().to_string();
        assert!(e.contains("in f32") && e.contains("far/near"), "{e}");
        // A far plane well within reach must still be declared truthfully, and the message
        // quotes it short.
        let cam = Camera {
            view: Mat4::IDENTITY,
            projection: Mat4::perspective_rh(1.0, 1.5, 1.0, 200_000.0),
            depth: conv(false, true),
        };
        let e = cam.derive().unwrap_err().to_string();
        assert!(e.contains("far plane") && e.len() < 260, "{e}");
    }

    type Case = (Mat4, DepthConvention, fn(f32) -> f32);

    fn projections() -> [Case; 4] {
        let fov = 1.0;
        [
            // Standard [0,1]: z = n f / (f - d (f - n)).
            (
                Mat4::perspective_rh(fov, 1.5, N, F),
                conv(false, false),
                |d| N * F / (F - d * (F - N)),
            ),
            // Reversed: z = n f / (n + d (f - n)).
            (
                Mat4::perspective_rh(fov, 1.5, F, N),
                conv(true, false),
                |d| N * F / (N + d * (F - N)),
            ),
            // Infinite: z = n / (1 - d).
            (
                Mat4::perspective_infinite_rh(fov, 1.5, N),
                conv(false, true),
                |d| N / (1.0 - d),
            ),
            // Infinite reversed: z = n / d.
            (
                Mat4::perspective_infinite_reverse_rh(fov, 1.5, N),
                conv(true, true),
                |d| N / d,
            ),
        ]
    }

    #[test]
    fn linearization_matches_closed_forms_per_convention() {
        for (proj, c, analytic) in projections() {
            for z in [0.7f32, 3.0, 50.0, 800.0, 4_000.0] {
                let d = depth_at(&proj, z);
                let lin = linearize_depth(d, &proj, c);
                let expect = analytic(d);
                assert!((lin - z).abs() / z < 2e-3, "{c:?} z={z}: {lin}");
                assert!(
                    (lin - expect).abs() / z < 2e-3,
                    "{c:?} z={z}: {lin} vs {expect}"
                );
            }
            assert_eq!(linearize_depth(c.far_value(), &proj, c), f32::INFINITY);
        }
    }

    #[test]
    fn scene_distance_is_distance_along_the_ray() {
        for (proj, c, _) in projections() {
            let eye = Vec3::new(10.0, 1_000.0, -30.0);
            let view = Mat4::look_at_rh(eye, eye + Vec3::new(1.0, 0.2, 0.3), Vec3::Y);
            let inv = (proj * view).inverse();
            // A world point, projected, must come back at its true distance.
            let p = eye + Vec3::new(200.0, 60.0, 50.0);
            let clip = proj * view * p.extend(1.0);
            let ndc = clip.truncate() / clip.w;
            let dist = scene_distance(ndc.x, ndc.y, ndc.z, &inv, eye, c);
            let truth = (p - eye).length();
            assert!(
                (dist - truth).abs() / truth < 2e-3,
                "{c:?}: {dist} vs {truth}"
            );
            assert_eq!(
                scene_distance(0.0, 0.0, c.far_value(), &inv, eye, c),
                f32::INFINITY
            );
        }
    }

    fn camera(projection: Mat4, depth: DepthConvention) -> Camera {
        Camera {
            view: Mat4::look_at_rh(
                Vec3::new(0.0, 10.0, 0.0),
                Vec3::new(0.0, 10.0, -1.0),
                Vec3::Y,
            ),
            projection,
            depth,
        }
    }

    fn field_of(r: Result<CameraDerived>) -> &'static str {
        match r {
            Err(Error::InvalidFrame { field, .. }) => field,
            other => panic!("expected InvalidFrame, got {other:?}"),
        }
    }

    #[test]
    fn declared_convention_must_match_projection() {
        for (proj, c, _) in projections() {
            camera(proj, c).derive().unwrap();
            let wrong_rev = conv(!c.reversed_z, c.infinite_far);
            assert_eq!(
                field_of(camera(proj, wrong_rev).derive()),
                "camera.depth.reversed_z"
            );
            let wrong_inf = conv(c.reversed_z, !c.infinite_far);
            assert_eq!(
                field_of(camera(proj, wrong_inf).derive()),
                "camera.depth.infinite_far"
            );
        }
    }

    #[test]
    fn bad_matrices_are_refused() {
        let good = Mat4::perspective_rh(1.0, 1.0, 0.1, 100.0);
        let c = conv(false, false);
        let mut nan = good;
        nan.x_axis.x = f32::NAN;
        assert_eq!(field_of(camera(nan, c).derive()), "camera.projection");
        assert_eq!(
            field_of(camera(Mat4::ZERO, c).derive()),
            "camera.projection"
        );
        let mut cam = camera(good, c);
        cam.view = Mat4::ZERO;
        assert_eq!(field_of(cam.derive()), "camera.view");
        let ortho = Mat4::orthographic_rh(-1.0, 1.0, -1.0, 1.0, 0.1, 100.0);
        assert_eq!(field_of(camera(ortho, c).derive()), "camera.projection");
    }

    #[test]
    fn far_planes_and_far_cameras_are_not_mistaken_for_singular() {
        // The benchmark's flight camera: 400 km far plane, camera a few km from the origin.
        // In f32 its view-projection round-trips only to 1e-3; it is a valid camera.
        // Flight frame 4: eye (0, 2, 0) + (0, 40, -60) * 120.
        let eye = Vec3::new(0.0, 4_802.0, -7_200.0);
        let projection = Mat4::perspective_rh(75f32.to_radians(), 16.0 / 9.0, 1.0, 400_000.0);
        let view = Mat4::look_at_rh(eye, eye + Vec3::new(0.0, 998.0, -1_200.0), Vec3::Y);
        let vp = projection * view;
        let f32_round_trip = (vp * vp.inverse() - Mat4::IDENTITY)
            .to_cols_array()
            .iter()
            .fold(0.0f32, |a, v| a.max(v.abs()));
        assert!(
            f32_round_trip > 1e-4,
            "this camera must be ill-conditioned in f32 ({f32_round_trip})"
        );
        let cam = Camera {
            view,
            projection,
            depth: DepthConvention::default(),
        };
        cam.derive().unwrap();
        for offset in [1e3f32, 1e4, 1e5] {
            let eye = Vec3::new(offset, 3_000.0, -offset);
            let far = Camera {
                view: Mat4::look_at_rh(eye, eye + Vec3::new(0.3, 0.1, -1.0), Vec3::Y),
                ..cam
            };
            far.derive()
                .unwrap_or_else(|e| panic!("camera at {offset} m: {e}"));
        }
    }

    #[test]
    fn bad_sun_and_time_are_refused() {
        let cam = camera(
            Mat4::perspective_rh(1.0, 1.0, 0.1, 100.0),
            conv(false, false),
        );
        let mut f = FrameInputs {
            camera: cam,
            sun: Sun::default(),
            time: 0.0,
        };
        f.validate().unwrap();
        f.sun.direction = Vec3::ZERO;
        assert!(matches!(
            f.validate(),
            Err(Error::InvalidFrame {
                field: "sun.direction",
                ..
            })
        ));
        f.sun = Sun {
            illuminance: f32::NAN,
            ..Sun::default()
        };
        assert!(matches!(
            f.validate(),
            Err(Error::InvalidFrame {
                field: "sun.illuminance",
                ..
            })
        ));
        f.sun = Sun::default();
        f.time = f64::INFINITY;
        assert!(matches!(
            f.validate(),
            Err(Error::InvalidFrame { field: "time", .. })
        ));
    }
}
