//! An independent light tracer of homogeneous slabs: the oracle the diffusion model's slab tests
//! compute for themselves (the Rust port of docs/fidelity/slab_light_tracer.py, whose numbers
//! they used to carry pasted in).
//!
//! Photons leave the sun and travel through the slab (optical depth `tau`, the sun's light
//! entering its top), scattering with the phase function sampled from a tabulated inverse CDF
//! in the scattering angle (fine near a forward peak). Every collision is scored toward each
//! camera direction: a point estimator, the phase toward the camera times the transmittance
//! to the face the camera looks at, over |μ| of the view. Unlike the GPU path tracer (camera
//! paths, next-event estimation toward the sun) the photons go where the phase sends them, so a
//! narrow forward peak makes no fireflies; and nothing here is shared with the march but the
//! phase function's definition.

use glam::DVec3;

use crate::lighting::phase::PhaseModel;

/// PCG32 (O'Neill 2014, XSH-RR output): the tracer's own random numbers, fixed by a seed.
struct Pcg32(u64);

impl Pcg32 {
    fn new(seed: u64) -> Self {
        let mut rng = Pcg32(0);
        rng.next();
        rng.0 = rng.0.wrapping_add(seed);
        rng.next();
        rng
    }

    fn next(&mut self) -> u32 {
        let old = self.0;
        self.0 = old
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        xorshifted.rotate_right((old >> 59) as u32)
    }

    /// Uniform in (0, 1]: never 0, so its logarithm is finite.
    fn uniform(&mut self) -> f64 {
        (self.next() as f64 + 1.0) / 4_294_967_296.0
    }
}

/// The phase's inverse CDF in the scattering angle θ: nodes dense below 0.3 rad (a droplet's
/// diffraction lobe is a degree wide), the CDF by the trapezoid rule.
struct PhaseSampler {
    theta: Vec<f64>,
    cdf: Vec<f64>,
}

impl PhaseSampler {
    fn new(phase: &PhaseModel) -> Self {
        let mut theta: Vec<f64> = (0..60_000).map(|i| 0.3 * i as f64 / 60_000.0).collect();
        theta.extend((0..30_000).map(|i| 0.3 + (std::f64::consts::PI - 0.3) * i as f64 / 29_999.0));
        let pdf: Vec<f64> = theta
            .iter()
            .map(|&t| phase.eval(t.cos() as f32, 1.0) as f64 * 2.0 * std::f64::consts::PI * t.sin())
            .collect();
        let mut cdf = vec![0.0; theta.len()];
        for i in 1..theta.len() {
            cdf[i] = cdf[i - 1] + 0.5 * (pdf[i] + pdf[i - 1]) * (theta[i] - theta[i - 1]);
        }
        let total = cdf[cdf.len() - 1];
        cdf.iter_mut().for_each(|c| *c /= total);
        PhaseSampler { theta, cdf }
    }

    fn sample_cos(&self, rng: &mut Pcg32) -> f64 {
        let u = rng.uniform().min(1.0);
        let i = self
            .cdf
            .partition_point(|&c| c < u)
            .clamp(1, self.cdf.len() - 1);
        let (c0, c1) = (self.cdf[i - 1], self.cdf[i]);
        let s = if c1 > c0 { (u - c0) / (c1 - c0) } else { 0.0 };
        (self.theta[i - 1] + s * (self.theta[i] - self.theta[i - 1])).cos()
    }
}

/// The radiance each camera sees of a homogeneous slab of optical depth `tau` and albedo
/// `albedo` lit by a sun `sun_elevation_deg` high (toward the sun: (0, sin e, -cos e), y up),
/// in the fidelity program's units (sun illuminance 10). Each camera is a set of look
/// directions (unit, y up) whose radiances are averaged: up (y > 0) for a camera below the
/// slab, down for one above. `photons` from the sun, random numbers seeded by `seed`.
pub(crate) fn slab_radiance(
    phase: &PhaseModel,
    tau: f64,
    albedo: f64,
    sun_elevation_deg: f64,
    cameras: &[Vec<[f64; 3]>],
    photons: u32,
    seed: u64,
) -> Vec<f64> {
    let e = sun_elevation_deg.to_radians();
    let sun = DVec3::new(0.0, e.sin(), -e.cos());
    let sampler = PhaseSampler::new(phase);
    let mut rng = Pcg32::new(seed);
    let mut score = vec![0.0f64; cameras.len()];
    for _ in 0..photons {
        // Optical height above the slab's bottom; the photon enters the top.
        let mut z = tau;
        let mut d = -sun;
        let mut weight = 1.0;
        for _ in 0..5000 {
            let z_next = z - rng.uniform().ln() * d.y;
            if !(0.0..=tau).contains(&z_next) {
                break;
            }
            z = z_next;
            weight *= albedo;
            for (sum, looks) in score.iter_mut().zip(cameras) {
                let mut total = 0.0;
                for &v in looks {
                    // The light the camera sees travels along -v, out of the bottom (v up) or
                    // the top (v down).
                    let v = DVec3::from_array(v);
                    let c = -d.dot(v);
                    let out = if v.y > 0.0 { z } else { tau - z };
                    let mu = v.y.abs();
                    total +=
                        phase.eval(c.clamp(-1.0, 1.0) as f32, 1.0) as f64 * (-out / mu).exp() / mu;
                }
                *sum += weight * total / looks.len() as f64;
            }
            // The next direction: θ from the phase, uniform in azimuth about d.
            let c = sampler.sample_cos(&mut rng);
            let s = (1.0 - c * c).max(0.0).sqrt();
            let phi = 2.0 * std::f64::consts::PI * rng.uniform();
            let helper = if d.y.abs() < 0.9 { DVec3::Y } else { DVec3::X };
            let t1 = helper.cross(d).normalize();
            let t2 = d.cross(t1);
            d = (c * d + s * (phi.cos() * t1 + phi.sin() * t2)).normalize();
        }
    }
    // Photons per unit horizontal area stand for the irradiance on it, 10 mu0.
    let norm = 10.0 * sun.y / photons as f64;
    score.iter().map(|s| s * norm).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_thin_isotropic_slab_matches_single_scattering_in_closed_form() {
        // In a slab of τ = 0.01 nearly all the light a camera below sees was scattered once
        // (the second order is about τ of it). Single scattering seen from below at μ, the sun
        // at μ0: ∫ E ω p e^{-t/μ0} e^{-(τ - t)/μ} dt / μ = E ω p (e^{-τ/μ} - e^{-τ/μ0}) /
        // ((1/μ0 - 1/μ) μ), E = 10 (across the sun's beam), p = 1 / (4π) (isotropic).
        let phase = PhaseModel::DualLobeHg {
            g_forward: 0.0,
            g_backward: 0.0,
            forward_weight: 1.0,
        };
        let tau = 0.01f64;
        for (elevation, look) in [(90.0f64, [0.0, 1.0, 0.0]), (40.0, [0.0, 0.643, 0.766])] {
            let mu0 = 0.5f64;
            let mu = look[1];
            let got = slab_radiance(&phase, tau, 1.0, 30.0, &[vec![look]], 400_000, 3)[0];
            let single = 10.0 / (4.0 * std::f64::consts::PI)
                * ((-tau / mu).exp() - (-tau / mu0).exp())
                / ((1.0 / mu0 - 1.0 / mu) * mu);
            assert!(
                (got / single - 1.0).abs() < 0.03,
                "view {elevation}°: light tracer {got:.6} vs single scattering {single:.6}"
            );
        }
    }

    #[test]
    fn the_sampled_scattering_angles_have_the_phases_asymmetry() {
        // The mean cosine of the tabulated inverse CDF's draws is the phase's first moment
        // (PhaseModel::asymmetry, in closed form): HG's g, the droplet blend's 0.86.
        for phase in [
            PhaseModel::default(),
            PhaseModel::DualLobeHg {
                g_forward: 0.8,
                g_backward: -0.3,
                forward_weight: 0.7,
            },
        ] {
            let sampler = PhaseSampler::new(&phase);
            let mut rng = Pcg32::new(5);
            let n = 400_000;
            let mean = (0..n).map(|_| sampler.sample_cos(&mut rng)).sum::<f64>() / n as f64;
            let g = phase.asymmetry() as f64;
            assert!(
                (mean - g).abs() < 0.005,
                "{phase:?}: mean cos {mean:.4}, asymmetry {g:.4}"
            );
        }
    }
}
