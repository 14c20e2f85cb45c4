//! Reading the cloud shadow map on the CPU: what a texel means (a Beer shadow map, Hillaire
//! 2016) and a sampler over a read-back copy, for hosts that shade on the CPU (and as the
//! reference for the WGSL and GLSL snippets in docs/cloud-shadows.md).

use glam::{Mat4, Vec2, Vec3};

use crate::renderer::CloudShadowMap;

/// The optical depth from the sun to a point at depth `depth` (m, the map matrix's z) through
/// a texel (front depth, mean extinction, total optical depth, -): min(mean extinction ×
/// max(depth − front, 0), total) (Hillaire 2016, Beer shadow maps). The transmittance of the
/// sunlight reaching the point is exp(−that).
pub fn shadow_optical_depth(texel: [f32; 4], depth: f32) -> f32 {
    let [front, mean_extinction, total, _] = texel;
    (mean_extinction * (depth - front).max(0.0)).min(total)
}

/// A read-back copy of the cloud shadow map with what is needed to look points up in it.
#[derive(Clone, Debug)]
pub struct CloudShadowSampler {
    texels: Vec<[f32; 4]>,
    resolution: u32,
    world_to_map: Mat4,
    window_origin: Vec2,
}

impl CloudShadowSampler {
    /// A sampler over `texels` (row-major, `map.resolution`² of them, as
    /// [`crate::Headless::read_cloud_shadows`] returns them) read back after the frame that
    /// left `map` as it is. `None` when the count does not match.
    pub fn new(map: &CloudShadowMap, texels: Vec<[f32; 4]>) -> Option<Self> {
        (texels.len() == (map.resolution as usize).pow(2)).then_some(Self {
            texels,
            resolution: map.resolution,
            world_to_map: map.world_to_map,
            window_origin: map.window_origin,
        })
    }

    /// The fraction of sunlight that reaches world point `p` through the clouds (bilinear,
    /// like a GPU sampler with repeat addressing), or `None` outside the map's square (less
    /// half a texel at its edges, where the filter would reach across the toroidal seam).
    pub fn transmittance(&self, p: Vec3) -> Option<f32> {
        let q = self.world_to_map * p.extend(1.0);
        let inside = Vec2::new(q.x, q.y) - self.window_origin;
        // Half a texel in from the edge: the bilinear footprint must not reach across the
        // toroidal seam into the square's other side.
        let margin = 0.5 / self.resolution as f32;
        if inside.min_element() < margin || inside.max_element() >= 1.0 - margin {
            return None;
        }
        let n = self.resolution as i64;
        let fx = q.x * n as f32 - 0.5;
        let fy = q.y * n as f32 - 0.5;
        let (x0, y0) = (fx.floor(), fy.floor());
        let (wx, wy) = (fx - x0, fy - y0);
        let at = |x: i64, y: i64| self.texels[(y.rem_euclid(n) * n + x.rem_euclid(n)) as usize];
        let (x0, y0) = (x0 as i64, y0 as i64);
        let mut texel = [0.0f32; 4];
        for (x, y, w) in [
            (x0, y0, (1.0 - wx) * (1.0 - wy)),
            (x0 + 1, y0, wx * (1.0 - wy)),
            (x0, y0 + 1, (1.0 - wx) * wy),
            (x0 + 1, y0 + 1, wx * wy),
        ] {
            for (t, v) in texel.iter_mut().zip(at(x, y)) {
                *t += w * v;
            }
        }
        Some((-shadow_optical_depth(texel, q.z)).exp())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_optical_depth_ramps_from_the_front_to_the_total() {
        let texel = [100.0, 0.01, 5.0, (-5.0f32).exp()];
        assert_eq!(shadow_optical_depth(texel, 50.0), 0.0);
        assert!((shadow_optical_depth(texel, 300.0) - 2.0).abs() < 1e-6);
        assert_eq!(shadow_optical_depth(texel, 10_000.0), 5.0);
    }
}
