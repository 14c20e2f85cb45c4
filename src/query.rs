//! CPU queries for gameplay: the cloud density at a point, the transmittance along a segment
//! and the coverage above a point, answered on the CPU without a GPU round trip, from the same
//! weather timeline, density model and noise as the march.
//!
//! The noise volumes and weather maps are **read back** from the GPU (once when a query is
//! made, again only after a weather request or a settings change), not regenerated on the
//! CPU: the bake is a GPU program (Perlin-Worley and Worley octaves, then the weather map's own
//! noise) and a second CPU implementation would have to match it bit for bit and stay in step
//! with every change to it; a readback is exact by construction and costs one copy of the
//! mip-0 textures (9 MB at the default sizes) per weather change. The density itself mirrors
//! `sample_density` in shaders/medium.wgsl (at the finest mip), with `weather::profile`'s
//! height profiles; tests/query.rs checks it against a GPU evaluation of the same points.

use std::sync::Arc;

use glam::{DVec2, Vec2, Vec3};

use crate::atmosphere::{altitude, Shell};
use crate::error::{Error, Result};
use crate::settings::{DebugDensity, Settings};
use crate::weather::profile::{eroded_density, layered_base_density, layers_can_cloud, smoothstep};
use crate::weather::{Timeline, WeatherSample};

/// The texels of a read-back RGBA texture, in its own format.
#[derive(Clone, Debug)]
pub(crate) enum TexelValues {
    /// RGBA8 unorm: the noise volumes and the generated weather maps.
    Unorm8(Vec<u8>),
    /// RGBA16F: a frozen blend of two weather maps (src/gpu/weather.rs).
    Half(Vec<half::f16>),
}

impl TexelValues {
    /// `bytes` as read back from a texture of `format`; an error for a format Nimbus does not
    /// read back into a query.
    fn from_bytes(format: wgpu::TextureFormat, bytes: Vec<u8>) -> Result<Self> {
        match format {
            wgpu::TextureFormat::Rgba8Unorm => Ok(Self::Unorm8(bytes)),
            wgpu::TextureFormat::Rgba16Float => {
                Ok(Self::Half(bytemuck::pod_collect_to_vec(&bytes)))
            }
            other => Err(Error::Readback(format!(
                "a query cannot read a {other:?} texture"
            ))),
        }
    }

    /// Mip 0 of `texture`, read back.
    pub fn read(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        texture: &wgpu::Texture,
    ) -> Result<Self> {
        let bytes = crate::gpu::readback::read_texture(device, queue, texture, 0)?;
        Self::from_bytes(texture.format(), bytes)
    }

    /// Texel `i` (RGBA) as the GPU's sampler returns it.
    pub fn texel(&self, i: usize) -> [f32; 4] {
        match self {
            Self::Unorm8(v) => {
                let c = &v[i * 4..i * 4 + 4];
                [c[0], c[1], c[2], c[3]].map(|v| v as f32 / 255.0)
            }
            Self::Half(v) => {
                let c = &v[i * 4..i * 4 + 4];
                [c[0], c[1], c[2], c[3]].map(half::f16::to_f32)
            }
        }
    }

    /// The number of texels.
    pub fn len(&self) -> usize {
        match self {
            Self::Unorm8(v) => v.len() / 4,
            Self::Half(v) => v.len() / 4,
        }
    }
}

/// An RGBA texture as read back, sampled like the GPU's repeat / linear sampler.
#[derive(Clone, Debug)]
pub(crate) struct Texels {
    pub size: u32,
    /// Depth 1 for a 2D map.
    pub depth: u32,
    pub values: TexelValues,
}

impl Texels {
    fn at(&self, x: i64, y: i64, z: i64) -> [f32; 4] {
        let n = self.size as i64;
        let d = self.depth as i64;
        let i = ((z.rem_euclid(d) * n + y.rem_euclid(n)) * n + x.rem_euclid(n)) as usize;
        self.values.texel(i)
    }

    /// Trilinear (bilinear for a map) sample at texture coordinates `uvw` (repeat).
    fn sample(&self, uvw: Vec3) -> [f32; 4] {
        let dims = Vec3::new(self.size as f32, self.size as f32, self.depth as f32);
        let f = uvw * dims - 0.5;
        let base = f.floor();
        let w = f - base;
        let (x0, y0, z0) = (base.x as i64, base.y as i64, base.z as i64);
        let corners = if self.depth == 1 { 4 } else { 8 };
        let mut out = [0.0f32; 4];
        for k in 0..corners {
            let (dx, dy, dz) = (k & 1, (k >> 1) & 1, (k >> 2) & 1);
            let weight = (if dx == 1 { w.x } else { 1.0 - w.x })
                * (if dy == 1 { w.y } else { 1.0 - w.y })
                * if self.depth == 1 {
                    1.0
                } else if dz == 1 {
                    w.z
                } else {
                    1.0 - w.z
                };
            let t = self.at(x0 + dx, y0 + dy, z0 + dz);
            for (o, v) in out.iter_mut().zip(t) {
                *o += weight * v;
            }
        }
        out
    }
}

/// What a query needs, shared by its clones (and threads).
#[derive(Debug)]
pub(crate) struct QueryData {
    pub settings: Settings,
    pub timeline: Timeline,
    pub base: Texels,
    pub detail: Texels,
    /// The (from, to) weather maps of the timeline's running transition.
    pub maps: (Texels, Texels),
}

/// CPU answers about the clouds, matching what the GPU renders: make one with
/// [`crate::Renderer::cloud_query`]. Cheap to clone and `Send + Sync`: ask from any thread.
/// It holds a copy of the noise and weather maps of the moment it was made, and the weather
/// timeline: queries at any time before the next weather request (or settings change) answer
/// as the renderer will render that time, transitions included; after a request, make a new
/// one.
#[derive(Clone, Debug)]
pub struct CloudQuery {
    data: Arc<QueryData>,
    /// The camera the horizon gradient is measured from.
    camera: Vec3,
}

/// The wind offset as the march's uniforms carry it (wrapped to a tile): the same f32 values.
fn wrapped(offset: DVec2, tile: f32) -> Vec2 {
    Vec2::from_array(crate::gpu::march::wrapped(offset, tile))
}

fn check_point(name: &str, p: Vec3) -> Result<()> {
    if p.is_finite() {
        Ok(())
    } else {
        Err(Error::InvalidQuery(format!(
            "{name} must be finite, got {p}"
        )))
    }
}

fn check_time(time: f64) -> Result<()> {
    if time.is_finite() {
        Ok(())
    } else {
        Err(Error::InvalidQuery(format!(
            "time must be finite, got {time}"
        )))
    }
}

/// Samples the density march along a segment at least this often (m) in the noise model.
const QUERY_STEP: f32 = 20.0;
/// And at most this many samples per segment (longer segments get longer steps).
const QUERY_MAX_STEPS: u32 = 8192;

impl CloudQuery {
    pub(crate) fn new(data: Arc<QueryData>, camera: Vec3) -> Self {
        Self { data, camera }
    }

    /// The same query with the horizon gradient measured from `camera` (by default the camera
    /// of the last frame prepared for the default view when the query was made, or the world
    /// origin). Shares the read-back textures.
    pub fn with_camera(&self, camera: Vec3) -> Result<Self> {
        check_point("camera", camera)?;
        Ok(Self::new(self.data.clone(), camera))
    }

    /// The unitless cloud density at world point `p` at host time `time`, as the march
    /// computes it (its extinction is this times the weather's `clouds.extinction`).
    pub fn density(&self, p: Vec3, time: f64) -> Result<f32> {
        check_point("point", p)?;
        check_time(time)?;
        Ok(self.density_with(p, &self.data.timeline.sample(time)))
    }

    /// The extinction coefficient σt (1/m) at `p` at `time`.
    pub fn extinction(&self, p: Vec3, time: f64) -> Result<f32> {
        check_point("point", p)?;
        check_time(time)?;
        let sample = self.data.timeline.sample(time);
        Ok(self.density_with(p, &sample) * sample.weather.clouds.extinction)
    }

    /// The transmittance of the clouds along the segment from `a` to `b` at `time`, in
    /// [0, 1]: is the sun visible from here (b far toward the sun), is the aircraft in cloud.
    /// Exact for the debug media; the noise model is integrated with samples every 20 m (up to
    /// 8192 per segment). The ground does not block (that is the host's geometry).
    pub fn transmittance(&self, a: Vec3, b: Vec3, time: f64) -> Result<f32> {
        check_point("a", a)?;
        check_point("b", b)?;
        check_time(time)?;
        Ok((-self.optical_depth(a, b, &self.data.timeline.sample(time))).exp())
    }

    /// The cloud coverage above the horizontal position of `p` at `time`, in [0, 1]: the
    /// densest layer's coverage (global coverage × the weather map, with the horizon gradient),
    /// the fraction of the layer's cells that hold cloud there. 1 inside a debug medium's
    /// footprint, 0 outside.
    pub fn coverage_above(&self, p: Vec3, time: f64) -> Result<f32> {
        check_point("point", p)?;
        check_time(time)?;
        let sample = self.data.timeline.sample(time);
        let s = &self.data.settings;
        Ok(match s.debug_density {
            DebugDensity::Slab { density, .. } => (density > 0.0) as u8 as f32,
            DebugDensity::Sphere {
                center,
                radius,
                density,
            } => {
                let up = s.planet.up.normalize();
                let off = p - center;
                let horizontal = off - up * off.dot(up);
                (density > 0.0 && horizontal.length() <= radius) as u8 as f32
            }
            DebugDensity::Off => {
                let (cov, _) = self.coverage_and_types(p, &sample);
                cov.max_element().clamp(0.0, 1.0)
            }
        })
    }

    fn axes(&self) -> (Vec3, Vec3, Vec3) {
        let up = self.data.settings.planet.up.normalize();
        let (tx, tz) = crate::gpu::march::tangent_basis(up);
        (up, tx, tz)
    }

    /// Effective coverage and cloud type of layers 1-3 at p's horizontal position.
    fn coverage_and_types(&self, p: Vec3, sample: &WeatherSample) -> (Vec3, Vec3) {
        let d = &self.data;
        let s = &d.settings;
        let w = &sample.weather;
        let (_, tx, tz) = self.axes();
        let horizontal = Vec2::new(p.dot(tx), p.dot(tz));
        let uv = (horizontal + wrapped(sample.offsets.weather, s.noise.weather_extent))
            * (1.0 / s.noise.weather_extent);
        let uvw = uv.extend(0.5);
        let weight = sample.map_weight;
        let from = d.maps.0.sample(uvw);
        let weather = if weight >= 1.0 {
            d.maps.1.sample(uvw)
        } else if weight <= 0.0 {
            from
        } else {
            let to = d.maps.1.sample(uvw);
            [0, 1, 2, 3].map(|i| from[i] + (to[i] - from[i]) * weight)
        };
        let mut coverage = Vec3::new(weather[0], weather[1], weather[2]) * w.clouds.coverage;
        let mut types = Vec3::ZERO;
        for (i, l) in w.map.layers.iter().take(3).enumerate() {
            types[i] = l.cloud_type;
        }
        // Horizon Zero Dawn's gradient, as in medium.wgsl.
        if w.horizon.strength > 0.0 {
            let camera = Vec2::new(self.camera.dot(tx), self.camera.dot(tz));
            let far = (horizontal - camera).length();
            let start = w.horizon.start_distance;
            let g = w.horizon.strength * smoothstep(start, start * 1.6 + 1.0, far);
            coverage.x += (coverage.x.max(w.horizon.coverage) - coverage.x) * g;
            types.x += (w.horizon.cloud_type - types.x) * g;
        }
        (coverage, types)
    }

    /// sample_density of shaders/medium.wgsl at the finest mip.
    fn density_with(&self, p: Vec3, sample: &WeatherSample) -> f32 {
        let d = &self.data;
        let s = &d.settings;
        let (up, tx, tz) = self.axes();
        let radius = s.planet.radius;
        let h = altitude(p, up, radius);
        match s.debug_density {
            DebugDensity::Slab {
                bottom_altitude,
                top_altitude,
                density,
            } => {
                return if h >= bottom_altitude && h <= top_altitude {
                    density
                } else {
                    0.0
                }
            }
            DebugDensity::Sphere {
                center,
                radius,
                density,
            } => {
                return if (p - center).length() <= radius {
                    density
                } else {
                    0.0
                }
            }
            DebugDensity::Off => {}
        }
        let w = &sample.weather;
        let (bottom, top) = (w.layer.bottom_altitude, w.layer.top_altitude);
        let hf = (h - bottom) / (top - bottom);
        if !(0.0..=1.0).contains(&hf) {
            return 0.0;
        }
        let (coverage, types) = self.coverage_and_types(p, sample);
        if !layers_can_cloud(hf, coverage.to_array(), types.to_array()) {
            return 0.0;
        }
        let wind_dir = w.wind.direction.normalize_or_zero();
        let skew = (tx * wind_dir.x + tz * wind_dir.y) * w.wind.skew;
        let q = p + skew * hf;
        let sheared = Vec2::new(q.dot(tx), q.dot(tz));
        let n = &s.noise;
        let base_off = wrapped(sample.offsets.base, n.base_scale);
        let detail_off = wrapped(sample.offsets.detail, n.detail_scale);
        let qb =
            Vec3::new(sheared.x + base_off.x, h, sheared.y + base_off.y) * (1.0 / n.base_scale);
        let base = d.base.sample(qb);
        let b = layered_base_density(
            hf,
            base,
            coverage.to_array(),
            types.to_array(),
            w.clouds.layer_softness,
        );
        if b <= 0.0 {
            return 0.0;
        }
        let qd = Vec3::new(sheared.x + detail_off.x, h, sheared.y + detail_off.y)
            * (1.0 / n.detail_scale);
        let detail = d.detail.sample(qd);
        eroded_density(
            hf,
            b,
            [detail[0], detail[1], detail[2]],
            w.clouds.coverage,
            w.clouds.detail_strength,
            w.clouds.edge_sharpness,
            w.clouds.density,
        )
    }

    fn optical_depth(&self, a: Vec3, b: Vec3, sample: &WeatherSample) -> f32 {
        let length = (b - a).length();
        if length <= 0.0 {
            return 0.0;
        }
        let dir = (b - a) / length;
        let s = &self.data.settings;
        let extinction = sample.weather.clouds.extinction;
        match s.debug_density {
            DebugDensity::Sphere {
                center,
                radius,
                density,
            } => {
                // The chord of the ball inside [0, length].
                let oc = a - center;
                let half_b = oc.dot(dir);
                let c = oc.length_squared() - radius * radius;
                let disc = half_b * half_b - c;
                if disc <= 0.0 {
                    return 0.0;
                }
                let root = disc.sqrt();
                let (t0, t1) = ((-half_b - root).max(0.0), (-half_b + root).min(length));
                (t1 - t0).max(0.0) * density * extinction
            }
            DebugDensity::Slab {
                bottom_altitude,
                top_altitude,
                density,
            } => {
                let up = s.planet.up.normalize();
                self.shell_length(a, dir, length, up, bottom_altitude, top_altitude)
                    * density
                    * extinction
            }
            DebugDensity::Off => {
                let steps = ((length / QUERY_STEP).ceil() as u32).clamp(1, QUERY_MAX_STEPS);
                let dt = length / steps as f32;
                let tau: f32 = (0..steps)
                    .map(|i| self.density_with(a + dir * ((i as f32 + 0.5) * dt), sample))
                    .sum();
                tau * dt * extinction
            }
        }
    }

    /// The length of [0, length] along the ray inside the shell between two altitudes,
    /// the ground not blocking.
    fn shell_length(&self, a: Vec3, dir: Vec3, length: f32, up: Vec3, lo: f32, hi: f32) -> f32 {
        let r = self.data.settings.planet.radius;
        // Below the ground the shell's own rule (rays from below the ground see through it)
        // applies; from above it, split the segment where it meets the ground.
        let shell = Shell {
            planet_radius: r,
            up,
            bottom: lo,
            top: hi,
        };
        let h = altitude(a, up, r);
        if h < 0.0 {
            return shell.segments(a, dir, length).length();
        }
        match crate::atmosphere::sphere_roots(a, dir, up, r, 0.0) {
            Some((g0, g1)) if g0 > 0.0 && g0 < length => {
                // Down to the ground, then from where it comes out again (if within reach).
                let first = shell.segments(a, dir, g0).length();
                let rest = if g1 < length {
                    let p = a + dir * g1;
                    shell.segments(p, dir, length - g1).length()
                } else {
                    0.0
                };
                first + rest
            }
            _ => shell.segments(a, dir, length).length(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texels_sample_like_a_repeat_linear_sampler() {
        // A 2x2 map: texel centers at 0.25 and 0.75; halfway between is the mean; the edge
        // wraps to the other side.
        let t = Texels {
            size: 2,
            depth: 1,
            values: TexelValues::Unorm8(vec![0, 0, 0, 0, 255, 0, 0, 0, 0, 0, 0, 0, 255, 0, 0, 0]),
        };
        assert_eq!(t.sample(Vec3::new(0.25, 0.25, 0.0))[0], 0.0);
        assert_eq!(t.sample(Vec3::new(0.75, 0.25, 0.0))[0], 1.0);
        assert!((t.sample(Vec3::new(0.5, 0.25, 0.0))[0] - 0.5).abs() < 1e-6);
        assert!((t.sample(Vec3::new(0.0, 0.25, 0.0))[0] - 0.5).abs() < 1e-6);
        assert!((t.sample(Vec3::new(1.25, 0.75, 0.0))[0]).abs() < 1e-6);
    }
}
