//! The delta-Eddington diffuse field of a homogeneous plane-parallel slab (Joseph, Wiscombe &
//! Weinman 1976, "The delta-Eddington approximation for radiative flux transfer"), the march's
//! multiple-scattering model. `shaders/diffusion.wgsl` mirrors [`delta_eddington`] line by line;
//! the tests here are its oracle.
//!
//! The slab is lit from above by a collimated sun of unit irradiance at cosine μ0. Optical
//! depth τ runs downward from the top; μ is the cosine of a direction of propagation with the
//! downward normal. The diffuse radiance is I(τ, μ) = I0(τ) + μ I1(τ) (Eddington), solved in the
//! delta-scaled medium: the phase's forward peak, a fraction f = g² of it, is folded into the
//! direct beam, so τ' = (1 - ωf) τ, ω' = (1 - f) ω / (1 - ωf), g' = g / (1 + g). The moment
//! equations (scaled quantities, S = 3ω'/4π)
//!
//!   dI1/dτ' = -3 (1 - ω') I0 + S e^{-τ'/μ0},   dI0/dτ' = -(1 - ω'g') I1 + g' μ0 S e^{-τ'/μ0},
//!
//! with Marshak's conditions (no diffuse light enters at the top or the bottom: I0 ± 2/3 I1 = 0),
//! have the closed form below. The homogeneous part is written with e^{-kτ'} and e^{-k(τ*'-τ')}
//! so nothing overflows at any thickness.

use std::f32::consts::PI;

/// Largest single-scattering albedo the closed form is evaluated at: at ω' = 1 its two
/// homogeneous solutions coincide (k = 0). 1 - 1e-6 changes the answer by well under 1%
/// at τ = 200, and the system stays well conditioned (its determinant tends to 8P/3, not 0).
pub const MAX_ALBEDO: f32 = 1.0 - 1e-6;

/// The diffuse field's moments (I0, I1) per unit sun irradiance at optical depth `a` below the
/// top of a slab of optical depth `a + b` (both unscaled, as the march measures them), for a
/// sun at cosine `mu0` (> 0), single-scattering albedo `albedo` and phase asymmetry `g`.
pub fn delta_eddington(a: f32, b: f32, mu0: f32, albedo: f32, g: f32) -> (f32, f32) {
    // The forward peak folded into the beam: f = g² for a forward phase (then g' = g / (1 + g)),
    // none for a backward one (g' = g).
    let f = g.max(0.0) * g.max(0.0);
    let w = albedo.clamp(0.0, MAX_ALBEDO);
    let scale = 1.0 - w * f;
    let ws = w * (1.0 - f) / scale;
    let gs = (g - f) / (1.0 - f);
    let ta = a * scale;
    let tt = (a + b) * scale;
    let k = (3.0 * (1.0 - ws) * (1.0 - ws * gs)).sqrt();
    let p = k / (1.0 - ws * gs);
    // The particular solution is singular at k μ0 = 1 (only for strongly absorbing media):
    // step μ0 off it, which moves the answer continuously.
    let mut m0 = mu0.max(1e-3);
    if (1.0 - k * k * m0 * m0).abs() < 1e-3 {
        m0 *= 1.002;
    }
    let den = 1.0 - k * k * m0 * m0;
    let s = 3.0 * ws / (4.0 * PI);
    let alpha = -m0 * m0 * s * (1.0 + gs * (1.0 - ws)) / den;
    let beta = m0 * (3.0 * (1.0 - ws) * alpha - s);
    let e_bottom = (-tt / m0).exp();
    let e_k = (-k * tt).exp();
    let (ca, cb) = (1.0 + 2.0 * p / 3.0, 1.0 - 2.0 * p / 3.0);
    let r_top = -(alpha + 2.0 * beta / 3.0);
    let r_bottom = -(alpha - 2.0 * beta / 3.0) * e_bottom;
    let det = ca * ca - cb * cb * e_k * e_k;
    let c1 = (r_top * ca - r_bottom * cb * e_k) / det;
    let c2 = (r_bottom * ca - r_top * cb * e_k) / det;
    let (ea, eb, ed) = ((-k * ta).exp(), (-k * (tt - ta)).exp(), (-ta / m0).exp());
    let i0 = c1 * ea + c2 * eb + alpha * ed;
    let i1 = p * (c1 * ea - c2 * eb) + beta * ed;
    (i0, i1)
}

/// Where a march sample sits in its column, and how it is lit and seen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ColumnSample {
    /// Optical depth toward the sun (the light march's).
    pub tau_sun: f32,
    /// Optical depth below the sample, down to the column's bottom.
    pub tau_below: f32,
    /// Cosine of the sun with the vertical.
    pub mu0: f32,
    /// Cosine of the light leaving toward the camera with the downward vertical.
    pub mu_view: f32,
    /// Cosine of the scattering angle (sun direction · view direction).
    pub cos_theta: f32,
}

/// The multiple-scattering part of the march's source per unit sun irradiance for a sample
/// `c` of a medium of single-scattering albedo `albedo`, phase asymmetry `g` and phase value
/// `phase` at the sample's scattering angle:
///
/// - the forward-scattered light the delta scaling keeps in the beam, p (e^{-(1-ωg²)τ} - e^{-τ});
/// - the diffuse field seen through the phase. In a thick column that is its P1 part,
///   I0 + g μ I1, whose anisotropy follows the net (vertical) flux. In a thin one the diffuse
///   light is still mostly light scattered once, bunched around the sun's direction, and a P1
///   field aligned with the vertical sends far too much of it sideways and back (1.7 times the
///   path tracer at 95° on a τ = 1 slab): there the same energy, 4π I0, is spread by a
///   Henyey-Greenstein lobe around the sun of asymmetry g g' (the phase's remainder after the
///   delta scaling, g' = g / (1 + g), seen through the phase once more). The two are blended by
///   the column's scaled optical thickness, 1 - e^{-τ*'}.
pub fn delta_eddington_source(c: &ColumnSample, albedo: f32, g: f32, phase: f32) -> f32 {
    let ColumnSample {
        tau_sun,
        tau_below,
        mu0,
        mu_view,
        cos_theta,
    } = *c;
    let w = albedo.clamp(0.0, MAX_ALBEDO);
    let m0 = mu0.max(1e-3);
    let a = tau_sun * m0;
    let (i0, i1) = delta_eddington(a, tau_below, m0, w, g);
    let f = g.max(0.0) * g.max(0.0);
    let peak = phase * ((-(1.0 - w * f) * tau_sun).exp() - (-tau_sun).exp());
    let p1 = i0 + g * mu_view * i1;
    let ge = g * (g - f) / (1.0 - f);
    let lobe = 4.0 * PI * i0 * crate::lighting::phase::henyey_greenstein(cos_theta, ge);
    let thick = 1.0 - (-(a + tau_below) * (1.0 - w * f)).exp();
    (peak + lobe + (p1 - lobe) * thick).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Upward diffuse flux at the top, downward diffuse flux at the bottom and the direct beam
    /// left at the bottom, per unit sun irradiance (P1 fluxes: π (I0 ∓ 2/3 I1)).
    fn fluxes(tau: f32, mu0: f32, albedo: f32, g: f32) -> (f32, f32, f32) {
        let (i0t, i1t) = delta_eddington(0.0, tau, mu0, albedo, g);
        let (i0b, i1b) = delta_eddington(tau, 0.0, mu0, albedo, g);
        let up = PI * (i0t - 2.0 * i1t / 3.0);
        let down = PI * (i0b + 2.0 * i1b / 3.0);
        let f = g.max(0.0) * g.max(0.0);
        let direct = mu0 * (-(1.0 - albedo.min(MAX_ALBEDO) * f) * tau / mu0).exp();
        (up, down, direct)
    }

    #[test]
    fn conservative_slab_conserves_energy() {
        for tau in [0.1f32, 1.0, 5.0, 20.0, 50.0, 200.0] {
            for mu0 in [0.2f32, 0.5, 0.866, 1.0] {
                for g in [-0.3f32, 0.0, 0.5, 0.8, 0.86] {
                    let (up, down, direct) = fluxes(tau, mu0, 1.0, g);
                    let total = (up + down + direct) / mu0;
                    // Everything that enters leaves (up to the albedo clamp's absorption).
                    assert!(
                        (total - 1.0).abs() < 5e-3,
                        "τ {tau} μ0 {mu0} g {g}: R + T = {total}"
                    );
                    assert!(up >= 0.0 && down >= 0.0, "τ {tau} μ0 {mu0} g {g}");
                }
            }
        }
    }

    #[test]
    fn matches_the_conservative_eddington_closed_form() {
        // Shettle & Weinman 1970, conservative scattering, scaled medium:
        // T = (1/2 + 3/4 μ0 + (1/2 - 3/4 μ0) e^{-τ'/μ0}) / (1 + 3/4 (1 - g') τ') (diffuse + direct).
        for tau in [1.0f32, 5.0, 20.0, 50.0] {
            for mu0 in [0.5f32, 0.866] {
                let g = 0.8f32;
                let (ts, gs) = ((1.0 - g * g) * tau, g / (1.0 + g));
                let e = (-ts / mu0).exp();
                let t_ref =
                    (0.5 + 0.75 * mu0 + (0.5 - 0.75 * mu0) * e) / (1.0 + 0.75 * (1.0 - gs) * ts);
                let (_, down, direct) = fluxes(tau, mu0, 1.0, g);
                let t = (down + direct) / mu0;
                assert!(
                    (t - t_ref).abs() / t_ref < 0.01,
                    "τ {tau} μ0 {mu0}: {t} vs {t_ref}"
                );
            }
        }
    }

    #[test]
    fn absorption_darkens_thick_slabs_more() {
        let (_, d1, _) = fluxes(50.0, 0.866, 1.0, 0.8);
        let (_, d999, _) = fluxes(50.0, 0.866, 0.999, 0.8);
        let (_, d99, _) = fluxes(50.0, 0.866, 0.99, 0.8);
        assert!(d1 > d999 && d999 > d99 && d99 > 0.0, "{d1} {d999} {d99}");
        // Diffusion: the field decays like e^{-k τ'} with k = √(3(1-ω')(1-ω'g')): from ω = 1
        // to 0.999 a τ = 50 slab loses a few tens of percent of its transmission.
        let loss = 1.0 - d999 / d1;
        assert!(loss > 0.03 && loss < 0.4, "{loss}");
    }

    #[test]
    fn thick_slab_fluxes_do_not_overflow() {
        for tau in [1e3f32, 1e5] {
            let (i0, i1) = delta_eddington(tau * 0.5, tau * 0.5, 0.7, 0.2, 0.8);
            assert!(i0.is_finite() && i1.is_finite(), "{i0} {i1}");
            let (i0, i1) = delta_eddington(tau * 0.5, tau * 0.5, 0.7, 1.0, 0.8);
            assert!(i0.is_finite() && i1.is_finite() && i0 >= 0.0, "{i0} {i1}");
        }
        // The singular point k μ0 = 1 is stepped over.
        let w = 0.05f32;
        let (ws, gs) = (w, 0.0f32);
        let k = (3.0 * (1.0 - ws) * (1.0 - ws * gs)).sqrt();
        let (i0, i1) = delta_eddington(1.0, 1.0, 1.0 / k, w, 0.0);
        assert!(i0.is_finite() && i1.is_finite(), "{i0} {i1}");
    }

    /// Light leaving a homogeneous slab through both faces, per unit incident flux, when the
    /// march integrates the model's source (single scattering of the scaled beam included)
    /// along every outgoing direction, plus the direct beam transmitted.
    fn marched_out_flux(tau: f32, mu0: f32, albedo: f32, g: f32) -> f64 {
        use crate::lighting::phase::henyey_greenstein;
        let (n_mu, n_phi, n_t) = (48, 48, 400);
        let sun_h = (1.0 - mu0 * mu0).sqrt();
        let mut out = 0.0f64;
        for exit_bottom in [true, false] {
            for i in 0..n_mu {
                let mu = (i as f32 + 0.5) / n_mu as f32;
                let mu_down = if exit_bottom { mu } else { -mu };
                for j in 0..n_phi {
                    let phi = (j as f32 + 0.5) / n_phi as f32 * 2.0 * PI;
                    let cos_theta = mu_down * mu0 + (1.0 - mu * mu).sqrt() * sun_h * phi.cos();
                    let phase = henyey_greenstein(cos_theta, g);
                    let mut radiance = 0.0f64;
                    for k in 0..n_t {
                        let depth = (k as f32 + 0.5) / n_t as f32 * tau;
                        let to_exit = if exit_bottom { tau - depth } else { depth };
                        let ss = phase * (-depth / mu0).exp();
                        let column = ColumnSample {
                            tau_sun: depth / mu0,
                            tau_below: tau - depth,
                            mu0,
                            mu_view: mu_down,
                            cos_theta,
                        };
                        let ms = delta_eddington_source(&column, albedo, g, phase);
                        let j = albedo * (ss + ms) * (-to_exit / mu).exp() / mu;
                        radiance += (j * tau / n_t as f32) as f64;
                    }
                    let d_omega = (1.0 / n_mu as f64) * (2.0 * std::f64::consts::PI / n_phi as f64);
                    out += radiance * mu as f64 * d_omega;
                }
            }
        }
        out / mu0 as f64 + (-(tau / mu0) as f64).exp()
    }

    #[test]
    fn the_march_of_the_model_sends_out_no_more_than_comes_in() {
        for tau in [0.5f32, 1.0, 5.0, 20.0, 50.0] {
            for mu0 in [0.5f32, 0.866] {
                for g in [-0.3f32, 0.0, 0.8] {
                    // Albedo 1: nothing is absorbed, so all of it should come out; the model
                    // (Eddington's P1 field, the beam's forward peak as a delta) loses 2-11%
                    // and must never invent light.
                    let out = marched_out_flux(tau, mu0, 1.0, g);
                    assert!(
                        out <= 1.0 && out > 0.85,
                        "τ {tau} μ0 {mu0} g {g}: out/in {out}"
                    );
                    let absorbing = marched_out_flux(tau, mu0, 0.9, g);
                    assert!(
                        absorbing < out,
                        "τ {tau} μ0 {mu0} g {g}: {absorbing} vs {out}"
                    );
                }
            }
        }
    }
}
