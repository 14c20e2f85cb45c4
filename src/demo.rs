//! Canonical views and synthetic scenes, shared by the snapshot example, the benchmark and the
//! GPU tests, plus tone-mapped PNG output for looking at HDR results.

use std::path::Path;

use glam::{Mat4, Vec3, Vec4};

use crate::error::{Error, Result};
use crate::frame::{Camera, DepthConvention, FrameInputs, Sun};

/// What stands in front of the sky in a view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Occluder {
    /// Nothing: depth holds the far value everywhere.
    None,
    /// A ridge of mountains on a vertical plane `distance` meters ahead, peaks up to `height`.
    Ridge {
        /// Horizontal distance to the ridge plane.
        distance: f32,
        /// Highest peak above the ground.
        height: f32,
    },
    /// A box-shaped wall filling the lower `fraction` of the image, `distance` meters away.
    NearWall {
        /// Distance along the view ray.
        distance: f32,
        /// Fraction of the image height covered, from the bottom.
        fraction: f32,
    },
}

/// One fixed view: a camera, a sun and a scene.
#[derive(Clone, Copy, Debug)]
pub struct DemoView {
    /// File-name-safe name.
    pub name: &'static str,
    /// Camera position (m).
    pub eye: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Vertical field of view (radians).
    pub fov_y: f32,
    /// The sun.
    pub sun: Sun,
    /// What occludes the clouds.
    pub occluder: Occluder,
}

fn sun_at(elevation_deg: f32, azimuth_deg: f32, color: Vec3, illuminance: f32) -> Sun {
    let (e, a) = (elevation_deg.to_radians(), azimuth_deg.to_radians());
    Sun {
        direction: Vec3::new(e.cos() * a.sin(), e.sin(), -e.cos() * a.cos()),
        color,
        illuminance,
    }
}

/// The views the snapshot renders and the tests check.
pub fn standard_views() -> Vec<DemoView> {
    let white = Vec3::ONE;
    vec![
        DemoView {
            name: "ground_looking_up",
            eye: Vec3::new(0.0, 2.0, 0.0),
            target: Vec3::new(0.0, 1_000.0, -1_200.0),
            fov_y: 75f32.to_radians(),
            sun: sun_at(55.0, 150.0, white, 10.0),
            occluder: Occluder::None,
        },
        DemoView {
            name: "horizon_sunset",
            eye: Vec3::new(0.0, 30.0, 0.0),
            target: Vec3::new(0.0, 120.0, -10_000.0),
            fov_y: 55f32.to_radians(),
            sun: sun_at(4.0, 12.0, Vec3::new(1.0, 0.62, 0.35), 6.0),
            occluder: Occluder::None,
        },
        DemoView {
            name: "inside_layer",
            eye: Vec3::new(0.0, 2_600.0, 0.0),
            target: Vec3::new(0.0, 2_500.0, -10_000.0),
            fov_y: 70f32.to_radians(),
            sun: sun_at(35.0, 60.0, white, 10.0),
            occluder: Occluder::None,
        },
        DemoView {
            name: "above_layer_8km",
            eye: Vec3::new(0.0, 8_000.0, 0.0),
            target: Vec3::new(0.0, 3_000.0, -12_000.0),
            fov_y: 70f32.to_radians(),
            sun: sun_at(40.0, 200.0, white, 10.0),
            occluder: Occluder::None,
        },
        DemoView {
            name: "mountains_occluding",
            eye: Vec3::new(0.0, 200.0, 0.0),
            target: Vec3::new(0.0, 1_300.0, -8_000.0),
            fov_y: 60f32.to_radians(),
            sun: sun_at(30.0, 140.0, white, 10.0),
            occluder: Occluder::Ridge {
                distance: 9_000.0,
                height: 2_600.0,
            },
        },
    ]
}

/// A synthetic scene for a view: linear RGBA color and clip-space depth per pixel.
pub struct SyntheticScene {
    /// Linear HDR color, row-major from the top.
    pub color: Vec<[f32; 4]>,
    /// Clip-space depth in the view's convention (far value where only sky is seen).
    pub depth: Vec<f32>,
}

impl DemoView {
    /// The camera for a `width`×`height` image (standard depth, finite far plane).
    pub fn camera(&self, width: u32, height: u32) -> Camera {
        Camera {
            view: Mat4::look_at_rh(self.eye, self.target, Vec3::Y),
            projection: Mat4::perspective_rh(
                self.fov_y,
                width as f32 / height as f32,
                1.0,
                400_000.0,
            ),
            depth: DepthConvention::default(),
        }
    }

    /// The frame inputs at time `time`.
    pub fn frame(&self, width: u32, height: u32, time: f64) -> FrameInputs {
        FrameInputs {
            camera: self.camera(width, height),
            sun: self.sun,
            time,
        }
    }

    /// A clear-sky gradient, dark ground below the horizon, and the occluder with its depth.
    pub fn scene(&self, width: u32, height: u32) -> SyntheticScene {
        let cam = self.camera(width, height);
        let view_proj = cam.projection * cam.view;
        let inv = view_proj.inverse();
        let mut color = Vec::with_capacity((width * height) as usize);
        let mut depth = Vec::with_capacity((width * height) as usize);
        let sun = self.sun.direction.normalize();
        for y in 0..height {
            for x in 0..width {
                let ndc_x = (x as f32 + 0.5) / width as f32 * 2.0 - 1.0;
                let ndc_y = 1.0 - (y as f32 + 0.5) / height as f32 * 2.0;
                let p = inv * Vec4::new(ndc_x, ndc_y, 0.0, 1.0);
                let dir = (p.truncate() / p.w - self.eye).normalize();
                let mut c = sky_color(dir, sun, self.sun.color);
                let mut d = 1.0;
                if let Some(hit) = self.occluder_hit(dir, ndc_y) {
                    let clip = view_proj * hit.extend(1.0);
                    d = (clip.z / clip.w).clamp(0.0, 1.0);
                    let shade = 0.25 + 0.5 * sun.y.max(0.0);
                    c = Vec3::new(0.10, 0.12, 0.09) * shade;
                }
                color.push([c.x, c.y, c.z, 1.0]);
                depth.push(d);
            }
        }
        SyntheticScene { color, depth }
    }

    fn occluder_hit(&self, dir: Vec3, ndc_y: f32) -> Option<Vec3> {
        match self.occluder {
            Occluder::None => None,
            Occluder::NearWall { distance, fraction } => {
                (ndc_y < fraction * 2.0 - 1.0).then(|| self.eye + dir * distance)
            }
            Occluder::Ridge { distance, height } => {
                let forward = (self.target - self.eye) * Vec3::new(1.0, 0.0, 1.0);
                let forward = forward.normalize();
                let along = dir.dot(forward);
                if along <= 1e-4 {
                    return None;
                }
                let hit = self.eye + dir * (distance / along);
                let side = hit.dot(forward.cross(Vec3::Y));
                // A few overlapping peaks.
                let ridge = height
                    * (0.55 + 0.25 * (side / 2_300.0).sin() + 0.2 * (side / 870.0 + 1.0).cos())
                        .clamp(0.0, 1.0);
                (hit.y <= ridge && hit.y >= 0.0).then_some(hit)
            }
        }
    }
}

/// A simple analytic clear sky (linear radiance), so composited clouds sit over a plausible
/// background: blue zenith, pale horizon, a sun glow, dark ground below.
pub fn sky_color(dir: Vec3, sun: Vec3, sun_color: Vec3) -> Vec3 {
    if dir.y < 0.0 {
        return Vec3::new(0.16, 0.15, 0.13) * (0.3 + 0.7 * sun.y.max(0.0));
    }
    let zenith = Vec3::new(0.18, 0.33, 0.75);
    let horizon = Vec3::new(0.65, 0.75, 0.9);
    let t = (1.0 - dir.y).powi(4);
    let day = (sun.y * 4.0).clamp(0.15, 1.0);
    let glow = dir.dot(sun).max(0.0).powi(32) * 1.5;
    (zenith.lerp(horizon, t) * day + sun_color * glow) * 0.9
}

/// ACES filmic approximation (Narkowicz 2015) then sRGB encoding, for viewing only.
pub fn tonemap(rgb: [f32; 4], exposure: f32) -> [u8; 3] {
    let aces = |x: f32| {
        let x = (x * exposure).max(0.0);
        ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
    };
    let srgb = |c: f32| {
        if c <= 0.003_130_8 {
            c * 12.92
        } else {
            1.055 * c.powf(1.0 / 2.4) - 0.055
        }
    };
    let q = |c: f32| (srgb(aces(c)) * 255.0 + 0.5) as u8;
    [q(rgb[0]), q(rgb[1]), q(rgb[2])]
}

/// Writes a tone-mapped PNG of a linear HDR image.
pub fn write_png(
    path: &Path,
    pixels: &[[f32; 4]],
    width: u32,
    height: u32,
    exposure: f32,
) -> Result<()> {
    let bytes: Vec<u8> = pixels.iter().flat_map(|p| tonemap(*p, exposure)).collect();
    image::RgbImage::from_raw(width, height, bytes)
        .ok_or_else(|| {
            Error::Image(format!(
                "{} pixels do not make {width}x{height}",
                pixels.len()
            ))
        })?
        .save(path)
        .map_err(|e| Error::Image(format!("{}: {e}", path.display())))
}
