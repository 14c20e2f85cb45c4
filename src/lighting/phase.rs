//! Phase functions, normalised over the sphere (∫ p dω = 1), in 1/sr.
//!
//! `cos_theta` is the cosine of the scattering angle: the angle between the direction light
//! travels before and after the scattering event (1 = straight on, forward scattering).

use std::f32::consts::PI;

use crate::error::Result;
use crate::validate::invalid as invalid_setting;

/// Which phase function the clouds scatter with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PhaseModel {
    /// Jendersie & d'Eon 2023: HG + Draine blend fitted to Mie scattering of water droplets of
    /// the given diameter (micrometres, valid fit range 5–50).
    JendersieDEon {
        /// Droplet diameter in µm. Default 10.
        droplet_diameter_um: f32,
    },
    /// A blend of a forward and a backward Henyey-Greenstein lobe (the common game approach).
    DualLobeHg {
        /// Forward lobe asymmetry in (-1, 1). Typical 0.8.
        g_forward: f32,
        /// Backward lobe asymmetry in (-1, 1). Typical -0.3.
        g_backward: f32,
        /// Weight of the forward lobe in [0, 1]. Typical 0.7.
        forward_weight: f32,
    },
}

impl Default for PhaseModel {
    fn default() -> Self {
        PhaseModel::JendersieDEon {
            droplet_diameter_um: 10.0,
        }
    }
}

/// The four parameters of the HG + Draine blend.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HgDraineParams {
    /// HG asymmetry.
    pub g_hg: f32,
    /// Draine asymmetry.
    pub g_d: f32,
    /// Draine α.
    pub alpha: f32,
    /// Weight of the Draine lobe.
    pub w_d: f32,
}

/// Jendersie & d'Eon 2023, "An Approximate Mie Scattering Function for Fog and Cloud
/// Rendering", fits for droplet diameters 5 µm ≤ d ≤ 50 µm. At 10 µm these give
/// g_hg 0.98818, g_d 0.55567, α 21.9955, w 0.48244 (the Ford thesis prints g_d 0.5567: a typo).
pub fn jendersie_deon_params(d_um: f32) -> HgDraineParams {
    let d = d_um as f64;
    let g_hg = (-0.0990567 / (d - 1.67154)).exp();
    let g_d = (-2.20679 / (d + 3.91029) - 0.428934).exp();
    let alpha = (3.62489 - 8.29288 / (d + 5.52825)).exp();
    let w_d = (-0.599085 / (d - 0.641583) - 0.664888).exp();
    HgDraineParams {
        g_hg: g_hg as f32,
        g_d: g_d as f32,
        alpha: alpha as f32,
        w_d: w_d as f32,
    }
}

/// Henyey-Greenstein: (1 - g²) / (4π (1 + g² - 2g cosθ)^1.5).
pub fn henyey_greenstein(cos_theta: f32, g: f32) -> f32 {
    let g2 = g * g;
    // (1 - g)² + 2g(1 - cos θ): the same value, without the cancellation of 1 + g² - 2g cos θ
    // near the forward peak in f32.
    let denom = ((1.0 - g) * (1.0 - g) + 2.0 * g * (1.0 - cos_theta)).max(1e-12);
    (1.0 - g2) / (4.0 * PI * denom * denom.sqrt())
}

/// Draine 2003: HG times a generalised Rayleigh term, normalised:
/// p_hg(θ, g) (1 + α cos²θ) / (1 + α (1 + 2g²) / 3).
pub fn draine(cos_theta: f32, g: f32, alpha: f32) -> f32 {
    henyey_greenstein(cos_theta, g) * (1.0 + alpha * cos_theta * cos_theta)
        / (1.0 + alpha * (1.0 + 2.0 * g * g) / 3.0)
}

/// Draine 2003's asymmetry ⟨cos θ⟩: g (1 + α (3 + 2g²) / 5) / (1 + α (1 + 2g²) / 3).
pub fn draine_asymmetry(g: f32, alpha: f32) -> f32 {
    g * draine_asymmetry_ratio(g, alpha)
}

/// Draine 2003's asymmetry over its g: (1 + α (3 + 2g²) / 5) / (1 + α (1 + 2g²) / 3).
fn draine_asymmetry_ratio(g: f32, alpha: f32) -> f32 {
    (1.0 + alpha * (3.0 + 2.0 * g * g) / 5.0) / (1.0 + alpha * (1.0 + 2.0 * g * g) / 3.0)
}

/// The g of the Draine 2003 lobe of shape α whose asymmetry is `asymmetry`: the fixed point of
/// g = asymmetry / (draine_asymmetry(g, α) / g), which contracts (the ratio changes slowly
/// with g: 1.32 at g 0.56, 1.6 at 0.25 for α 22); after four steps g is within 1.2e-4 of it for
/// the droplet fits' α (17 to 32 from 5 to 50 µm) and asymmetries up to 0.6.
pub fn draine_g_for_asymmetry(asymmetry: f32, alpha: f32) -> f32 {
    let mut g = asymmetry / 1.4;
    for _ in 0..4 {
        g = (asymmetry / draine_asymmetry_ratio(g, alpha)).clamp(-0.95, 0.95);
    }
    g
}

/// The HG + Draine blend: (1 - w) p_hg(g_hg) + w p_d(g_d, α).
pub fn hg_draine(cos_theta: f32, p: &HgDraineParams) -> f32 {
    (1.0 - p.w_d) * henyey_greenstein(cos_theta, p.g_hg) + p.w_d * draine(cos_theta, p.g_d, p.alpha)
}

impl PhaseModel {
    /// Evaluates the phase function, with every asymmetry scaled by `eccentricity_scale`
    /// (Wrenninge's c^i for octave i; 1 for single scattering).
    pub fn eval(&self, cos_theta: f32, eccentricity_scale: f32) -> f32 {
        let k = eccentricity_scale;
        match *self {
            PhaseModel::JendersieDEon {
                droplet_diameter_um,
            } => {
                let mut p = jendersie_deon_params(droplet_diameter_um);
                p.g_hg *= k;
                p.g_d *= k;
                hg_draine(cos_theta, &p)
            }
            PhaseModel::DualLobeHg {
                g_forward,
                g_backward,
                forward_weight,
            } => {
                forward_weight * henyey_greenstein(cos_theta, g_forward * k)
                    + (1.0 - forward_weight) * henyey_greenstein(cos_theta, g_backward * k)
            }
        }
    }

    /// The phase's second Legendre moment χ₂ = ⟨P₂(cos θ)⟩ = (3⟨cos²θ⟩ - 1) / 2. HG's is g²;
    /// Draine 2003's, from HG's ⟨cos²θ⟩ = (1 + 2g²)/3 and ⟨cos⁴θ⟩ = (7 + 20g² + 8g⁴)/35 (its
    /// Legendre moments gˡ), is ⟨cos²θ⟩ = (⟨cos²⟩ + α⟨cos⁴⟩) / (1 + α⟨cos²⟩).
    pub fn second_moment(&self) -> f32 {
        let hg = |g: f32| g * g;
        let draine = |g: f32, a: f32| {
            let c2 = (1.0 + 2.0 * g * g) / 3.0;
            let c4 = (7.0 + 20.0 * g * g + 8.0 * g.powi(4)) / 35.0;
            let cos2 = (c2 + a * c4) / (1.0 + a * c2);
            (3.0 * cos2 - 1.0) / 2.0
        };
        match *self {
            PhaseModel::JendersieDEon {
                droplet_diameter_um,
            } => {
                let p = jendersie_deon_params(droplet_diameter_um);
                (1.0 - p.w_d) * hg(p.g_hg) + p.w_d * draine(p.g_d, p.alpha)
            }
            PhaseModel::DualLobeHg {
                g_forward,
                g_backward,
                forward_weight,
            } => forward_weight * hg(g_forward) + (1.0 - forward_weight) * hg(g_backward),
        }
    }

    /// How much one scattering into the delta-Eddington forward peak spreads light: the
    /// asymmetry s of the Henyey-Greenstein lobe with the peak's own second moment.
    ///
    /// Delta-Eddington splits the phase into a peak of weight f = g² and a rest of asymmetry
    /// g' = (g - f) / (1 - f). The peak's first moment is then exactly 1 (a delta, for the
    /// fluxes), but its second is (χ₂ - (1 - f) g'²) / f < 1: it has a width. An HG lobe with
    /// that second moment has s = √((χ₂ - (1 - f) g'²) / f). HG(0.8): s = 0.943. 1 (no spread)
    /// where the phase has no forward peak. For the Jendersie-d'Eon blend this moment is
    /// misleading (the Draine lobe's α cos²θ puts second moment both forward and back: 0.991 at
    /// 10 µm, narrower than its diffraction lobe); [`PhaseModel::beam_split`] splits its peak.
    pub fn peak_spread(&self) -> f32 {
        let g = self.asymmetry().clamp(0.0, 0.98);
        let f = g * g;
        if f <= 1e-6 {
            return 1.0;
        }
        let g_rest = (g - f) / (1.0 - f);
        let peak_moment = (self.second_moment() - (1.0 - f) * g_rest * g_rest) / f;
        peak_moment.clamp(0.0, 1.0).sqrt()
    }

    /// What the delta-Eddington peak (weight f = g², kept in the sun's beam) is made of:
    /// (the weight of its narrow part, that part's spread per scattering). The rest of the
    /// peak, f minus the narrow weight, is broad: [`PhaseModel::broad_phase`] spreads it.
    ///
    /// The Jendersie-d'Eon blend is a diffraction lobe, HG(g_hg) of weight 1 - w (g_hg 0.988 at
    /// 10 µm: a degree wide), plus a broad Draine lobe (asymmetry 0.73 at 10 µm). Delta-Eddington's
    /// f = g² = 0.747 takes all of the first (0.518) and part of the second into the beam. Light
    /// scattered within the diffraction lobe spreads exactly as HG lobes compose (HG(g₁) ⊛ HG(g₂)
    /// = HG(g₁g₂)): the narrow part, spread g_hg. Light scattered in the Draine lobe is spread
    /// by tens of degrees. Spreading all of f by one moment-matched width (0.991) put it on a
    /// back-lit sphere's rim, 1° from the sun, 4 times the path tracer; a broad lobe there
    /// has left the thin cap near the limb (docs/fidelity.md). A dual-lobe HG has no such
    /// structure: its whole peak is narrow, spread by [`PhaseModel::peak_spread`].
    pub fn beam_split(&self) -> (f32, f32) {
        let g = self.asymmetry().clamp(0.0, 0.98);
        let f = g * g;
        match *self {
            PhaseModel::JendersieDEon {
                droplet_diameter_um,
            } => {
                let p = jendersie_deon_params(droplet_diameter_um);
                ((1.0 - p.w_d).min(f), p.g_hg)
            }
            PhaseModel::DualLobeHg { .. } => (f, self.peak_spread()),
        }
    }

    /// The phase that sends toward the camera light scattered `n` (≥ 1, the mean count) times
    /// in the broad part of the delta-Eddington peak ([`PhaseModel::beam_split`]): the Draine
    /// lobe composed n times with itself, then the phase once more (its diffraction lobe leaves
    /// the direction as it is, its Draine lobe composes once more). Compositions of the Draine
    /// lobe are approximated by scaling its g by the lobe's own asymmetry per composition (as
    /// HG lobes compose; its α cos²θ shape is kept). Normalised. The dual-lobe HG has no broad
    /// part ([`PhaseModel::beam_split`] keeps its whole peak narrow): 0.
    pub fn broad_phase(&self, cos_theta: f32, n: f32) -> f32 {
        match *self {
            PhaseModel::JendersieDEon {
                droplet_diameter_um,
            } => {
                let p = jendersie_deon_params(droplet_diameter_um);
                let s = draine_asymmetry(p.g_d, p.alpha);
                let n = n.max(1.0);
                (1.0 - p.w_d) * draine(cos_theta, p.g_d * s.powf(n - 1.0), p.alpha)
                    + p.w_d * draine(cos_theta, p.g_d * s.powf(n), p.alpha)
            }
            PhaseModel::DualLobeHg { .. } => 0.0,
        }
    }

    /// The angular shapes of a thin column's diffuse light toward the camera at `cos_theta` from
    /// the sun, for the lobe's asymmetry `lobe_g` (g g', delta_eddington_source): (the
    /// Henyey-Greenstein lobe, the lobe with the phase's shape where the light was scattered
    /// once), both normalised. The diffuse light of a thin column was scattered once out of the
    /// delta-Eddington remainder of the phase, whose shape is the Draine lobe's: its deep
    /// side-scattering minimum (1 + α cos²θ, α = 22 at 10 µm) and its rise toward the back. Seen
    /// through the diffraction lobe (weight 1 - w) it keeps that shape; the Draine lobe (weight
    /// w) spreads it over tens of degrees, which fills the minimum in (an HG lobe). Both of
    /// asymmetry `lobe_g`. The dual-lobe HG has no such structure: the HG lobe twice.
    pub fn thin_lobe(&self, cos_theta: f32, lobe_g: f32) -> (f32, f32) {
        let hg = henyey_greenstein(cos_theta, lobe_g);
        match *self {
            PhaseModel::JendersieDEon {
                droplet_diameter_um,
            } => {
                let p = jendersie_deon_params(droplet_diameter_um);
                let shaped = draine(cos_theta, draine_g_for_asymmetry(lobe_g, p.alpha), p.alpha);
                (hg, (1.0 - p.w_d) * shaped + p.w_d * hg)
            }
            PhaseModel::DualLobeHg { .. } => (hg, hg),
        }
    }

    /// The asymmetry parameter g = ⟨cos θ⟩ (the phase's first Legendre moment), which is what
    /// a P1 (Eddington) diffuse field sees of the phase. HG's is its g; Draine 2003's is
    /// g (1 + α (3 + 2g²) / 5) / (1 + α (1 + 2g²) / 3).
    pub fn asymmetry(&self) -> f32 {
        match *self {
            PhaseModel::JendersieDEon {
                droplet_diameter_um,
            } => {
                let p = jendersie_deon_params(droplet_diameter_um);
                (1.0 - p.w_d) * p.g_hg + p.w_d * draine_asymmetry(p.g_d, p.alpha)
            }
            PhaseModel::DualLobeHg {
                g_forward,
                g_backward,
                forward_weight,
            } => forward_weight * g_forward + (1.0 - forward_weight) * g_backward,
        }
    }

    /// Refuses parameters outside the model's domain.
    pub fn validate(&self) -> Result<()> {
        match *self {
            PhaseModel::JendersieDEon {
                droplet_diameter_um: d,
            } => {
                if !(d.is_finite() && (5.0..=50.0).contains(&d)) {
                    return Err(invalid_setting(
                        "lighting.phase.droplet_diameter_um",
                        format!("the Jendersie & d'Eon fit holds for 5..=50 µm, got {d}"),
                    ));
                }
            }
            PhaseModel::DualLobeHg {
                g_forward,
                g_backward,
                forward_weight,
            } => {
                for (field, g) in [
                    ("lighting.phase.g_forward", g_forward),
                    ("lighting.phase.g_backward", g_backward),
                ] {
                    if !(g.is_finite() && g.abs() < 0.999) {
                        return Err(invalid_setting(
                            field,
                            format!("must be in (-0.999, 0.999), got {g}"),
                        ));
                    }
                }
                if !(forward_weight.is_finite() && (0.0..=1.0).contains(&forward_weight)) {
                    return Err(invalid_setting(
                        "lighting.phase.forward_weight",
                        format!("must be in [0, 1], got {forward_weight}"),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The four numbers the shader needs: for JdE (g_hg, g_d, α, w); for dual-lobe
    /// (g_forward, g_backward, 0, forward_weight). The model index goes separately.
    pub(crate) fn gpu_params(&self) -> ([f32; 4], u32) {
        match *self {
            PhaseModel::JendersieDEon {
                droplet_diameter_um,
            } => {
                let p = jendersie_deon_params(droplet_diameter_um);
                ([p.g_hg, p.g_d, p.alpha, p.w_d], 0)
            }
            PhaseModel::DualLobeHg {
                g_forward,
                g_backward,
                forward_weight,
            } => ([g_forward, g_backward, 0.0, forward_weight], 1),
        }
    }
}

/// ∫ f(μ) 2π dμ over the sphere (f of the cosine with the forward direction), by the midpoint
/// rule on `n` points in u = ln(1 + ε - μ), which crowds them into a forward peak.
#[cfg(test)]
pub(crate) fn over_the_sphere(n: usize, f: impl Fn(f64) -> f64) -> f64 {
    let eps = 1e-7f64;
    let (u0, u1) = ((2.0 + eps).ln(), eps.ln());
    let mut sum = 0.0f64;
    for i in 0..n {
        let u = u0 + (u1 - u0) * (i as f64 + 0.5) / n as f64;
        let mu = 1.0 + eps - u.exp();
        let dmu = u.exp() * (u0 - u1) / n as f64;
        sum += f(mu) * 2.0 * std::f64::consts::PI * dmu;
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn henyey_greenstein_keeps_its_precision_at_the_forward_peak() {
        let exact = |c: f64, g: f64| {
            (1.0 - g * g) / (4.0 * std::f64::consts::PI * (1.0 + g * g - 2.0 * g * c).powf(1.5))
        };
        for g in [0.5f32, 0.9, 0.988, 0.995] {
            for c in [1.0f32, 0.9999, 0.999, 0.99, 0.5, 0.0, -1.0] {
                let want = exact(c as f64, g as f64);
                let got = henyey_greenstein(c, g) as f64;
                assert!(
                    ((got - want) / want).abs() < 1e-5,
                    "g {g}, cos {c}: {got} vs {want}"
                );
            }
        }
    }

    /// ∫ p dω over the sphere, by the midpoint rule in cosθ (p depends on θ only), in f64 with
    /// many intervals near cosθ = 1 where strongly forward lobes peak.
    fn integrate(p: impl Fn(f32) -> f32) -> f64 {
        // Substitute u = (1 - cosθ) on a geometric grid to resolve the forward peak.
        let n = 200_000;
        let mut sum = 0.0f64;
        let umin = 1e-9f64;
        let umax = 2.0f64;
        let ratio = (umax / umin).ln();
        for i in 0..n {
            let a = umin * ((i as f64 / n as f64) * ratio).exp();
            let b = umin * (((i + 1) as f64 / n as f64) * ratio).exp();
            let mid = 0.5 * (a + b);
            sum += p((1.0 - mid) as f32) as f64 * (b - a);
        }
        // [0, umin] adds at most p(1) * umin.
        sum += p(1.0) as f64 * umin;
        2.0 * std::f64::consts::PI * sum
    }

    #[test]
    fn jendersie_deon_fits_at_10_um() {
        let p = jendersie_deon_params(10.0);
        assert!((p.g_hg - 0.98818).abs() < 5e-6, "g_hg {}", p.g_hg);
        assert!((p.g_d - 0.55567).abs() < 5e-6, "g_d {}", p.g_d);
        assert!((p.alpha - 21.9955).abs() < 5e-4, "alpha {}", p.alpha);
        assert!((p.w_d - 0.48244).abs() < 5e-6, "w {}", p.w_d);
    }

    #[test]
    fn phase_functions_integrate_to_one() {
        for g in [-0.7f32, 0.0, 0.3, 0.8, 0.95] {
            let i = integrate(|c| henyey_greenstein(c, g));
            assert!((i - 1.0).abs() < 2e-3, "HG g={g}: {i}");
        }
        for (g, a) in [(0.0f32, 1.0f32), (0.5, 21.9955), (0.8, 5.0)] {
            let i = integrate(|c| draine(c, g, a));
            assert!((i - 1.0).abs() < 2e-3, "Draine g={g} a={a}: {i}");
        }
        for d in [5.0f32, 10.0, 20.0, 50.0] {
            let m = PhaseModel::JendersieDEon {
                droplet_diameter_um: d,
            };
            for k in [1.0f32, 0.5, 0.25] {
                let i = integrate(|c| m.eval(c, k));
                assert!((i - 1.0).abs() < 3e-3, "JdE d={d} k={k}: {i}");
            }
        }
        let dual = PhaseModel::DualLobeHg {
            g_forward: 0.8,
            g_backward: -0.3,
            forward_weight: 0.7,
        };
        let i = integrate(|c| dual.eval(c, 1.0));
        assert!((i - 1.0).abs() < 2e-3, "dual lobe: {i}");
    }

    #[test]
    fn isotropic_hg_is_one_over_four_pi() {
        for c in [-1.0f32, 0.0, 0.5, 1.0] {
            assert!((henyey_greenstein(c, 0.0) - 1.0 / (4.0 * PI)).abs() < 1e-7);
        }
    }

    #[test]
    fn cloud_phase_is_strongly_forward() {
        let m = PhaseModel::default();
        assert!(m.eval(1.0, 1.0) > 100.0 * m.eval(0.0, 1.0));
        // Lower eccentricity flattens the lobe.
        assert!(m.eval(1.0, 0.5) < m.eval(1.0, 1.0));
    }

    #[test]
    fn out_of_domain_parameters_are_refused() {
        assert!(PhaseModel::JendersieDEon {
            droplet_diameter_um: 2.0
        }
        .validate()
        .is_err());
        assert!(PhaseModel::JendersieDEon {
            droplet_diameter_um: f32::NAN
        }
        .validate()
        .is_err());
        assert!(PhaseModel::DualLobeHg {
            g_forward: 1.0,
            g_backward: 0.0,
            forward_weight: 0.5
        }
        .validate()
        .is_err());
    }

    /// The test models: the default, a larger droplet, a dual-lobe HG with a back lobe.
    fn models() -> [PhaseModel; 3] {
        [
            PhaseModel::default(),
            PhaseModel::JendersieDEon {
                droplet_diameter_um: 30.0,
            },
            PhaseModel::DualLobeHg {
                g_forward: 0.8,
                g_backward: -0.3,
                forward_weight: 0.7,
            },
        ]
    }

    #[test]
    fn asymmetry_is_the_mean_cosine() {
        for model in models() {
            let mean = over_the_sphere(400_000, |mu| model.eval(mu as f32, 1.0) as f64 * mu);
            let g = model.asymmetry() as f64;
            assert!(
                (mean - g).abs() < 2e-3,
                "{model:?}: quadrature {mean}, formula {g}"
            );
        }
    }

    /// The thin column's lobe with the phase's shape (delta_eddington_source) moves light
    /// between directions, not its amount: both shapes are normalised and have the lobe's
    /// asymmetry. The droplet phase's is darker sideways and brighter toward the back than the
    /// HG lobe (its Draine lobe's 1 + α cos²θ); the dual-lobe HG's is the HG lobe.
    #[test]
    fn the_thin_lobe_moves_light_between_directions_only() {
        for model in models() {
            for lobe_g in [0.2f32, 0.4, 0.6] {
                for part in 0..2 {
                    let shape = |mu: f64| {
                        let (hg, once) = model.thin_lobe(mu as f32, lobe_g);
                        [hg, once][part] as f64
                    };
                    let total = over_the_sphere(200_000, shape);
                    let mean = over_the_sphere(200_000, |mu| shape(mu) * mu);
                    assert!((total - 1.0).abs() < 1e-3, "{model:?} {lobe_g}: ∫ {total}");
                    assert!(
                        (mean - lobe_g as f64).abs() < 2e-3,
                        "{model:?} {lobe_g}: asymmetry {mean}"
                    );
                }
                let at = |mu: f32| model.thin_lobe(mu, lobe_g);
                if let PhaseModel::JendersieDEon { .. } = model {
                    assert!(at(0.0).1 < 0.7 * at(0.0).0, "{model:?} {lobe_g}: 90°");
                    assert!(at(-1.0).1 > at(-1.0).0, "{model:?} {lobe_g}: 180°");
                } else {
                    assert_eq!(at(0.3).0, at(0.3).1);
                }
            }
        }
    }

    #[test]
    fn second_moment_is_the_mean_legendre_p2() {
        for model in models() {
            let chi2 = over_the_sphere(400_000, |mu| {
                model.eval(mu as f32, 1.0) as f64 * 0.5 * (3.0 * mu * mu - 1.0)
            });
            let formula = model.second_moment() as f64;
            assert!(
                (chi2 - formula).abs() < 2e-3,
                "{model:?}: quadrature {chi2}, formula {formula}"
            );
        }
    }

    #[test]
    fn the_delta_eddington_peak_has_the_width_its_second_moment_says() {
        // HG(g): χ₂ = g², f = g², g' = g / (1 + g): the peak's second moment is 2g / (1 + g).
        let hg = PhaseModel::DualLobeHg {
            g_forward: 0.8,
            g_backward: 0.0,
            forward_weight: 1.0,
        };
        let expected = (2.0f32 * 0.8 / 1.8).sqrt();
        assert!(
            (hg.peak_spread() - expected).abs() < 1e-5,
            "{}",
            hg.peak_spread()
        );
        // The default phase's peak is narrower than its mean cosine but not a delta.
        let s = PhaseModel::default().peak_spread();
        let g = PhaseModel::default().asymmetry();
        assert!(s > g && s < 1.0, "spread {s}, g {g}");
        // An isotropic phase has no peak to spread by.
        let iso = PhaseModel::DualLobeHg {
            g_forward: 0.0,
            g_backward: 0.0,
            forward_weight: 1.0,
        };
        assert_eq!(iso.peak_spread(), 1.0);
        println!(
            "default phase: g {g}, chi2 {}, spread {s}",
            PhaseModel::default().second_moment()
        );
    }
}
