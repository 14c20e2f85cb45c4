//! The light at a view's camera from the hemisphere above and the one below (frame outputs,
//! docs/frame-outputs.md): what a host needs to light its own objects under, inside or above
//! the clouds with what the clouds do to the sky.
//!
//! The ambient probe (shaders/ambient.wgsl) marches, per hemisphere around the local vertical,
//! 512 cosine-weighted rays and 256 around the sun (the phase function's lobes) with the march's
//! own ray function, a twelfth of them per frame (all of them when the view has no history).
//! For each hemisphere it gives the clouds' irradiance E_clouds = ∫ L_clouds(ω) cos θ dω (what they scatter toward
//! the camera, haze included, in the sun's units) and the sky visibility
//! V = 1/π ∫ T(ω) cos θ dω, the cosine-weighted transmittance through them: the share of the
//! host's own light from that hemisphere (its sky above, its ground below) that still arrives.

use glam::Vec3;

/// The light from one hemisphere at the camera.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HemisphereLight {
    /// The clouds' irradiance on a surface facing this hemisphere (the sun's units: an
    /// illuminance of 1 with a white sun gives irradiance in units of the sun's).
    pub cloud_irradiance: Vec3,
    /// The cosine-weighted transmittance of the clouds over this hemisphere, in [0, 1]: 1 with
    /// no clouds, exp(−τ)-like under a cloud layer of optical depth τ (2 E₃(τ) for a flat slab).
    pub sky_visibility: f32,
}

impl HemisphereLight {
    /// The total irradiance with the host's own light from this hemisphere behind the clouds:
    /// `cloud_irradiance + sky_visibility × host`. Exact when the host's radiance is the same
    /// in every direction of the hemisphere (a uniform sky or ground); otherwise the host's
    /// cosine-weighted mean stands for it.
    pub fn irradiance(&self, host: Vec3) -> Vec3 {
        self.cloud_irradiance + self.sky_visibility * host
    }
}

/// The light at a view's camera, from above and below the local horizontal plane (the
/// planet's vertical through the camera). See the module docs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AmbientLight {
    /// From the hemisphere above (the sky side).
    pub above: HemisphereLight,
    /// From the hemisphere below (the ground side: clouds below a camera above them).
    pub below: HemisphereLight,
}

impl AmbientLight {
    /// Decodes the probe's buffer: two `vec4<f32>` (above, below), rgb E_clouds, a V.
    pub(crate) fn from_bytes(bytes: &[u8]) -> Self {
        let f: &[f32] = bytemuck::cast_slice(&bytes[..32]);
        let hemisphere = |v: &[f32]| HemisphereLight {
            cloud_irradiance: Vec3::new(v[0], v[1], v[2]),
            sky_visibility: v[3],
        };
        Self {
            above: hemisphere(&f[0..4]),
            below: hemisphere(&f[4..8]),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decodes_above_then_below() {
        let values: [f32; 8] = [1.0, 2.0, 3.0, 0.25, 4.0, 5.0, 6.0, 0.75];
        let light = AmbientLight::from_bytes(bytemuck::cast_slice(&values));
        assert_eq!(light.above.cloud_irradiance, Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(light.above.sky_visibility, 0.25);
        assert_eq!(light.below.cloud_irradiance, Vec3::new(4.0, 5.0, 6.0));
        assert_eq!(light.below.sky_visibility, 0.75);
        assert_eq!(
            light.above.irradiance(Vec3::splat(4.0)),
            Vec3::new(2.0, 3.0, 4.0)
        );
    }
}
