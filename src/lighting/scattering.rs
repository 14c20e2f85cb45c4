//! Integration of the volume rendering equation along a view ray (Fong et al. 2017, eq. 3.3 of
//! the Ford thesis): L = T(c,p) L_o + ∫ T(c,x) σs L_scat(x) dx.

use crate::settings::MultipleScattering;

use super::phase::PhaseModel;

/// Running state of one view ray: in-scattered radiance and transmittance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayState {
    /// Radiance scattered toward the camera so far.
    pub radiance: f32,
    /// Transmittance from the camera to the current point (Beer-Lambert).
    pub transmittance: f32,
}

impl Default for RayState {
    fn default() -> Self {
        Self {
            radiance: 0.0,
            transmittance: 1.0,
        }
    }
}

impl RayState {
    /// Adds one march step of length `dt` through a medium of extinction `sigma_t` whose
    /// source term `source` (= σs · L_scat, constant over the step) is known.
    ///
    /// Hillaire 2016, energy-conserving integration: ∫₀^dt e^{-σt x} S dx = S (1 - e^{-σt dt}) / σt,
    /// so a long step neither loses nor invents energy, unlike S · dt.
    pub fn step(&mut self, sigma_t: f32, source: f32, dt: f32) {
        let step_t = (-sigma_t * dt).exp();
        let integral = if sigma_t > 1e-9 {
            source * (1.0 - step_t) / sigma_t
        } else {
            source * dt
        };
        self.radiance += self.transmittance * integral;
        self.transmittance *= step_t;
    }
}

/// Wrenninge 2015 multiple-scattering octaves: Σᵢ bⁱ p(θ, cⁱ g) e^{-aⁱ τ}, where τ is the optical
/// depth toward the sun. With one octave this is single scattering, p(θ) e^{-τ}.
pub fn multiple_scattering(
    phase: &PhaseModel,
    ms: &MultipleScattering,
    cos_theta: f32,
    tau_sun: f32,
) -> f32 {
    let (mut a, mut b, mut c) = (1.0f32, 1.0f32, 1.0f32);
    let mut sum = 0.0;
    for _ in 0..ms.octaves {
        sum += b * phase.eval(cos_theta, c) * (-a * tau_sun).exp();
        a *= ms.attenuation;
        b *= ms.contribution;
        c *= ms.eccentricity;
    }
    sum
}

/// Closed-form single scattering of a homogeneous plane-parallel slab of thickness `h`, seen
/// from below along a view ray making cosine `mu_v` with the slab normal, lit by a sun of
/// illuminance `e_sun` at cosine `mu_s` from above, with phase value `phase`.
///
/// L = E p σs e^{-σt h/μs} ∫₀^{h/μv} e^{-σt s (1 - μv/μs)} ds, T = e^{-σt h/μv}.
/// Returns (L, T).
pub fn slab_single_scattering(
    sigma_t: f32,
    albedo: f32,
    h: f32,
    mu_v: f32,
    mu_s: f32,
    phase: f32,
    e_sun: f32,
) -> (f32, f32) {
    let (sigma_t, h, mu_v, mu_s) = (sigma_t as f64, h as f64, mu_v as f64, mu_s as f64);
    let path = h / mu_v;
    let k = sigma_t * (1.0 - mu_v / mu_s);
    let integral = if k.abs() < 1e-12 {
        path
    } else {
        (1.0 - (-k * path).exp()) / k
    };
    let l = e_sun as f64
        * phase as f64
        * albedo as f64
        * sigma_t
        * (-sigma_t * h / mu_s).exp()
        * integral;
    (l as f32, (-sigma_t * path).exp() as f32)
}

/// Closed-form single scattering of the same slab seen from above: the light it reflects
/// toward a camera over its sunlit top, along a view ray going down at cosine `mu_v` with the
/// slab normal (the sun at cosine `mu_s`).
///
/// At path length s below the top the depth is s μv, so the sun's optical depth is σt s μv/μs:
/// L = E p σs ∫₀^{h/μv} e^{-σt s (1 + μv/μs)} ds = E p ω μs / (μs + μv) (1 - e^{-τ (1/μv + 1/μs)}),
/// τ = σt h, T = e^{-τ/μv}. Returns (L, T).
pub fn slab_single_reflection(
    sigma_t: f32,
    albedo: f32,
    h: f32,
    mu_v: f32,
    mu_s: f32,
    phase: f32,
    e_sun: f32,
) -> (f32, f32) {
    let (sigma_t, h, mu_v, mu_s) = (sigma_t as f64, h as f64, mu_v as f64, mu_s as f64);
    let tau = sigma_t * h;
    let l = e_sun as f64
        * phase as f64
        * albedo as f64
        * mu_s
        * (1.0 - (-tau * (1.0 / mu_v + 1.0 / mu_s)).exp())
        / (mu_s + mu_v);
    (l as f32, (-tau / mu_v).exp() as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The reflection's closed form against a fine midpoint sum of its defining integral, thin
    /// and thick, at grazing and steep views.
    #[test]
    fn slab_reflection_closed_form_matches_its_integral() {
        for (sigma_t, mu_v, mu_s) in [
            (0.002f32, 0.9f32, 0.5f32),
            (0.1, 0.34, 0.5),
            (0.04, 0.57, 0.87),
        ] {
            let h = 500.0f64;
            let (l, t) = slab_single_reflection(sigma_t, 0.9, h as f32, mu_v, mu_s, 0.3, 2.0);
            let (sigma_t, mu_v, mu_s) = (sigma_t as f64, mu_v as f64, mu_s as f64);
            let n = 200_000;
            let ds = h / mu_v / n as f64;
            let sum: f64 = (0..n)
                .map(|i| {
                    let s = (i as f64 + 0.5) * ds;
                    (-sigma_t * s - sigma_t * s * mu_v / mu_s).exp() * ds
                })
                .sum();
            let expected = 2.0 * 0.3 * 0.9 * sigma_t * sum;
            assert!(
                ((l as f64) - expected).abs() < 1e-4 * expected,
                "{l} against {expected}"
            );
            assert!(((t as f64) - (-sigma_t * h / mu_v).exp()).abs() < 1e-6);
        }
    }

    /// March a homogeneous slab with `n` steps, computing the sun optical depth exactly at each
    /// step midpoint, as the shader does.
    fn march_slab(n: u32, sigma_t: f32, h: f32, mu_v: f32, mu_s: f32) -> RayState {
        let path = h / mu_v;
        let dt = path / n as f32;
        let mut s = RayState::default();
        for i in 0..n {
            let x = (i as f32 + 0.5) * dt;
            let z = x * mu_v;
            let tau = sigma_t * (h - z) / mu_s;
            let source = sigma_t * (-tau).exp(); // albedo 1, phase 1, E 1
            s.step(sigma_t, source, dt);
        }
        s
    }

    #[test]
    fn hillaire_step_converges_to_closed_form() {
        let (sigma_t, h, mu_v, mu_s) = (0.02, 500.0, 0.9, 0.7);
        let (l_ref, t_ref) = slab_single_scattering(sigma_t, 1.0, h, mu_v, mu_s, 1.0, 1.0);
        let fine = march_slab(512, sigma_t, h, mu_v, mu_s);
        assert!(
            (fine.radiance - l_ref).abs() / l_ref < 2e-3,
            "{fine:?} vs {l_ref}"
        );
        assert!((fine.transmittance - t_ref).abs() < 1e-5);
        // At 8 steps over optical depth 11, the energy-conserving step beats the naive S·dt
        // Riemann sum by far: the point of Hillaire's formula.
        let coarse = march_slab(8, sigma_t, h, mu_v, mu_s);
        let err = (coarse.radiance - l_ref).abs() / l_ref;
        let dt = h / mu_v / 8.0;
        let (mut naive, mut t) = (0.0f32, 1.0f32);
        for i in 0..8 {
            let z = (i as f32 + 0.5) * dt * mu_v;
            naive += t * sigma_t * (-sigma_t * (h - z) / mu_s).exp() * dt;
            t *= (-sigma_t * dt).exp();
        }
        let naive_err = (naive - l_ref).abs() / l_ref;
        assert!(
            err < 0.1 && err * 3.0 < naive_err,
            "hillaire {err}, naive {naive_err}"
        );
    }

    #[test]
    fn energy_conserving_step_never_exceeds_source_over_extinction() {
        // A single huge step through an optically thick medium: the naive S·dt would explode,
        // the energy-conserving integral saturates at S/σt.
        let mut s = RayState::default();
        s.step(0.1, 1.0, 1.0e4);
        assert!((s.radiance - 10.0).abs() < 1e-4);
        assert!(s.transmittance < 1e-6);
    }

    #[test]
    fn zero_extinction_is_transparent() {
        let mut s = RayState::default();
        s.step(0.0, 0.0, 1000.0);
        assert_eq!(s, RayState::default());
    }

    #[test]
    fn one_octave_is_single_scattering() {
        let phase = PhaseModel::default();
        let ms = MultipleScattering {
            octaves: 1,
            ..Default::default()
        };
        let v = multiple_scattering(&phase, &ms, 0.3, 2.0);
        assert!((v - phase.eval(0.3, 1.0) * (-2.0f32).exp()).abs() < 1e-7);
        // More octaves add light that reaches deeper.
        let ms4 = MultipleScattering::default();
        assert!(multiple_scattering(&phase, &ms4, 0.3, 2.0) > v);
    }
}
