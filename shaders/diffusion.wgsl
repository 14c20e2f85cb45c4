// The delta-Eddington diffuse field of a homogeneous plane-parallel column (Joseph, Wiscombe &
// Weinman 1976): the march's multiple-scattering model. Mirrors src/lighting/diffusion.rs line
// by line (the derivation and the tests are there).

const DE_MAX_ALBEDO: f32 = 0.999999;
// The least sun cosine a column is lit at (about 17°; see march.wgsl).
const DE_MIN_MU0: f32 = 0.3;
// The share of a column's scaled optical thickness that light scattered once crosses on its
// way out toward a camera below, which sets the blend from the thin lobe to the P1 field; the
// whole column toward a camera above (DIFFUSE_CROSSING in src/lighting/diffusion.rs).
const DE_DIFFUSE_CROSSING: f32 = 0.5;

// The radius (m) of the column a noise-model cloud is taken as at coverage 1/2, whose sides
// leak diffuse light; at coverage c it is c / (1 - c) times this (NOISE_CLOUD_RADIUS in
// src/lighting/diffusion.rs says why).
const NOISE_CLOUD_RADIUS: f32 = 1500.0;

// The extinction of a noise-model cloud's body, as a share of the layer's peak (its density
// times its extinction): the column's optical radius is noise_cloud_radius times that
// (NOISE_CLOUD_BODY_DENSITY in src/lighting/diffusion.rs says why).
const NOISE_CLOUD_BODY_DENSITY: f32 = 0.5;

// The radius (m) of a noise-model cloud's column at coverage `coverage`.
fn noise_cloud_radius(coverage: f32) -> f32 {
    let c = clamp(coverage, 0.0, 0.999);
    return NOISE_CLOUD_RADIUS * c / (1.0 - c);
}

// The optical radius of a noise-model cloud's column for a layer of coverage `coverage` and
// peak extinction `peak_sigma_t` (its density times its extinction): the body's, not the
// sample's (noise_cloud_optical_radius in src/lighting/diffusion.rs).
fn noise_cloud_optical_radius(coverage: f32, peak_sigma_t: f32) -> f32 {
    return noise_cloud_radius(coverage) * NOISE_CLOUD_BODY_DENSITY * peak_sigma_t;
}

// The bounds (m) of diffuse_spread_radius (DIFFUSE_SPREAD_MIN / MAX in
// src/lighting/diffusion.rs).
const DIFFUSE_SPREAD_MIN: f32 = 50.0;
const DIFFUSE_SPREAD_MAX: f32 = 2000.0;

// How far (m) a noise-model cloud's diffuse light spreads sideways: the transport mean free
// path of its body, 1 / (sigma_body (1 - g)), within [DIFFUSE_SPREAD_MIN, DIFFUSE_SPREAD_MAX]
// (diffuse_spread_radius in src/lighting/diffusion.rs).
fn diffuse_spread_radius(peak_sigma_t: f32, g: f32) -> f32 {
    let transport = peak_sigma_t * NOISE_CLOUD_BODY_DENSITY * (1.0 - clamp(g, 0.0, 0.999));
    return clamp(1.0 / max(transport, 1e-9), DIFFUSE_SPREAD_MIN, DIFFUSE_SPREAD_MAX);
}

// j0,1, the first zero of J0: a cylinder of radius a has the transverse buckling j0,1 / a.
const BESSEL_J0_FIRST_ZERO: f32 = 2.4048256;

// (I0, I1) per unit sun irradiance at optical depth a below the top of a column of optical depth
// a + b, sun at cosine mu0, single-scattering albedo w, phase asymmetry g, in a column whose
// cross-section has the optical radius tau_across (its sides leak diffuse light: the transverse
// buckling, see src/lighting/diffusion.rs; 1e30 for a layer).
fn delta_eddington(a: f32, b: f32, mu0: f32, albedo: f32, g: f32, tau_across: f32) -> vec2f {
    let leaky = delta_eddington_moments(a, b, mu0, albedo, g, tau_across);
    if (tau_across >= 1e30) {
        return leaky.xy;
    }
    // Matched to the broad medium's field at the sunlit face, and never above the broad
    // medium's field at the sample: a leak only takes light away (delta_eddington_column in
    // src/lighting/diffusion.rs says why).
    let broad = delta_eddington_moments(a, b, mu0, albedo, g, 1e30);
    let capped = leaky.xy * min(broad.z / leaky.z, broad.x / leaky.x);
    return select(capped, broad.xy, leaky.z <= 0.0 || leaky.x <= 0.0);
}

// (I0, I1) at the sample and I0 at the sunlit face (a = 0) of the same column.
fn delta_eddington_moments(a: f32, b: f32, mu0: f32, albedo: f32, g: f32, tau_across: f32) -> vec3f {
    // The forward peak folded into the beam: f = g² for a forward phase, none for a backward one.
    let f = max(g, 0.0) * max(g, 0.0);
    let w = clamp(albedo, 0.0, DE_MAX_ALBEDO);
    let scale = 1.0 - w * f;
    let ws = w * (1.0 - f) / scale;
    let gs = (g - f) / (1.0 - f);
    let ta = a * scale;
    let tt = (a + b) * scale;
    let d = 1.0 - ws * gs;
    let a_ext = tau_across * scale + 2.0 / (3.0 * d);
    let buckling = BESSEL_J0_FIRST_ZERO / a_ext;
    let absorb3 = 3.0 * (1.0 - ws) + buckling * buckling / d;
    let k = sqrt(absorb3 * d);
    let p = k / d;
    // The particular solution is singular at k mu0 = 1: step mu0 off it.
    var m0 = max(mu0, 1e-3);
    if (abs(1.0 - k * k * m0 * m0) < 1e-3) {
        m0 *= 1.002;
    }
    let den = 1.0 - k * k * m0 * m0;
    let s = 3.0 * ws / (4.0 * PI);
    let alpha = -m0 * m0 * s * (1.0 + gs * (1.0 - ws)) / den;
    let beta = m0 * (absorb3 * alpha - s);
    let e_bottom = exp(-tt / m0);
    let e_k = exp(-k * tt);
    let ca = 1.0 + 2.0 * p / 3.0;
    let cb = 1.0 - 2.0 * p / 3.0;
    let r_top = -(alpha + 2.0 * beta / 3.0);
    let r_bottom = -(alpha - 2.0 * beta / 3.0) * e_bottom;
    let det = ca * ca - cb * cb * e_k * e_k;
    let c1 = (r_top * ca - r_bottom * cb * e_k) / det;
    let c2 = (r_bottom * ca - r_top * cb * e_k) / det;
    let ea = exp(-k * ta);
    let eb = exp(-k * (tt - ta));
    let ed = exp(-ta / m0);
    return vec3f(c1 * ea + c2 * eb + alpha * ed, p * (c1 * ea - c2 * eb) + beta * ed, c1 + c2 * e_k + alpha);
}

// The light the delta scaling keeps in the beam, scattered toward the camera (per unit sun
// irradiance, per steradian) at a sample tau_sun from the sun: its narrow part (weight
// `narrow_weight` of the phase, spread `spread` per scattering: the phase's diffraction lobe)
// through the phase with its asymmetries scaled by spreadⁿ, averaged over n's Poisson law (n = 1,
// 2, and n ≥ 3 at its mean); the rest of f = g² through broad_phase. beam_light in
// src/lighting/diffusion.rs derives it. `model`, `params`: as phase_eval's.
fn beam_light(model: u32, params: vec4f, cos_theta: f32, tau_sun: f32, albedo: f32, g: f32, spread: f32, narrow_weight: f32) -> f32 {
    let gc = clamp(g, 0.0, 1.0);
    let f = gc * gc;
    let w = clamp(albedo, 0.0, DE_MAX_ALBEDO);
    let tau = max(tau_sun, 0.0);
    let m = w * narrow_weight * tau;
    var p = vec3f(1.0 - 0.5 * m, 0.5 * m, 0.0);
    var n3 = 3.0;
    if (m >= 1e-3) {
        let at_least_one = 1.0 - exp(-m);
        p.x = m * exp(-m) / at_least_one;
        p.y = 0.5 * m * p.x;
        p.z = max(1.0 - p.x - p.y, 0.0);
        if (p.z > 1e-6) {
            n3 = max((m / at_least_one - p.x - 2.0 * p.y) / p.z, 3.0);
        }
    }
    let narrow = p.x * phase_eval(model, params, cos_theta, spread)
        + p.y * phase_eval(model, params, cos_theta, spread * spread)
        + p.z * phase_eval(model, params, cos_theta, pow(spread, n3));
    let narrow_beam = exp(-(1.0 - w * narrow_weight) * tau) - exp(-tau);
    let broad_beam = exp(-(1.0 - w * f) * tau) - exp(-(1.0 - w * narrow_weight) * tau);
    var light = narrow * narrow_beam;
    if (broad_beam > 0.0) {
        let mb = w * (f - narrow_weight) * tau;
        let n = select(mb / (1.0 - exp(-mb)), 1.0 + 0.5 * mb, mb < 1e-3);
        light += broad_phase(model, params, cos_theta, n) * broad_beam;
    }
    return light;
}

// Draine 2003's asymmetry over its g (draine_asymmetry_ratio in src/lighting/phase.rs).
fn draine_asymmetry_ratio(g: f32, alpha: f32) -> f32 {
    return (1.0 + alpha * (3.0 + 2.0 * g * g) / 5.0) / (1.0 + alpha * (1.0 + 2.0 * g * g) / 3.0);
}

// PhaseModel::broad_phase: light scattered n times in the broad (Draine) part of the beam, then
// toward the camera. Only the Jendersie-d'Eon blend (model 0) has a broad part.
fn broad_phase(model: u32, params: vec4f, cos_theta: f32, n: f32) -> f32 {
    if (model != 0u) {
        return 0.0;
    }
    let g_d = params.y;
    let alpha = params.z;
    let s = g_d * draine_asymmetry_ratio(g_d, alpha);
    let k = max(n, 1.0);
    return (1.0 - params.w) * draine(cos_theta, g_d * pow(s, k - 1.0), alpha)
        + params.w * draine(cos_theta, g_d * pow(s, k), alpha);
}

// The multiple-scattering part of the source per unit sun irradiance (see
// delta_eddington_source in src/lighting/diffusion.rs for why each term): the forward-scattered
// light the delta scaling keeps in the beam (`beam`, beam_light's); the diffuse field
// seen through the phase, I0 + g mu I1 in a thick column (mu: the light's direction toward the
// camera against the downward vertical), the same energy in an HG lobe of asymmetry g g'
// around the sun in a thin one, blended by 1 - e^{-c tau*'} (c = DE_DIFFUSE_CROSSING for a
// camera below the sample, 1 for one above); light going up toward a camera above takes the P1
// field's upward flux, part of it in a lobe around the sun, instead (reflected_source). `lobe`:
// thin_lobe's shapes of that lobe toward the camera (the HG lobe, the phase's once-scattered
// shape), mixed by once_scattered_share. `cos_theta`: the scattering angle's cosine.
fn delta_eddington_source(tau_above: f32, tau_below: f32, mu0: f32, mu_view: f32, cos_theta: f32, lobe_shapes: vec2f, albedo: f32, g: f32, chi2: f32, beam: f32, tau_across: f32) -> f32 {
    let w = clamp(albedo, 0.0, DE_MAX_ALBEDO);
    let m0 = max(mu0, 1e-3);
    let a = tau_above;
    let i = delta_eddington(a, tau_below, m0, w, g, tau_across);
    let f = max(g, 0.0) * max(g, 0.0);
    let p1 = i.x + g * mu_view * i.y;
    let shape = mix(lobe_shapes.x, lobe_shapes.y, once_scattered_share(a, w, f));
    let lobe = 4.0 * PI * i.x * shape * thin_column_limb(a + tau_below, w, f, mu_view, chi2);
    let crossing = mix(1.0, DE_DIFFUSE_CROSSING, smoothstep(-0.25, 0.25, mu_view));
    let thick = 1.0 - exp(-(a + tau_below) * (1.0 - w * f) * crossing);
    var seen = mix(lobe, p1, thick);
    // Light going up, out of the sunlit face (a camera above sees the column's reflection): the
    // P1 field's upward flux, part of it in a lobe around the sun (reflected_source).
    let up = 1.0 - smoothstep(-DE_REFLECTED_BLEND, DE_REFLECTED_BLEND, mu_view);
    if (up > 0.0) {
        let reflected = reflected_source(i.x, i.y, g, m0, cos_theta, (a + tau_below) * (1.0 - w * f))
            * thin_column_limb(a + tau_below, w, f, mu_view, chi2);
        seen = mix(seen, reflected, up);
    }
    return max(beam + seen, 0.0);
}

// Over |mu_view| below this the light toward the camera goes from the reflected light (going
// up) to the diffuse field going down (REFLECTED_BLEND in src/lighting/diffusion.rs).
const DE_REFLECTED_BLEND: f32 = 0.1;

// The light a column's diffuse field sends up toward a camera above (per unit sun irradiance):
// the P1 field's upward flux pi (I0 - 2/3 g I1), a share `memory` of it in an HG lobe of
// asymmetry g^3 around the sun's light, the rest even; memory = e^{-tau*} + (1 - e^{-tau*})
// (1 - mu0) (reflected_source in src/lighting/diffusion.rs says why).
fn reflected_source(i0: f32, i1: f32, g: f32, mu0: f32, cos_theta: f32, tau_scaled: f32) -> f32 {
    let flux_up = max(PI * (i0 - 2.0 / 3.0 * g * i1), 0.0);
    let thin = exp(-max(tau_scaled, 0.0));
    let memory = thin + (1.0 - thin) * (1.0 - mu0);
    let lobe_g = clamp(g * g * g, -0.6, 0.6);
    let lobe = henyey_greenstein(cos_theta, lobe_g) / upward_lobe_flux(mu0, lobe_g);
    return flux_up * ((1.0 - memory) / PI + memory * lobe);
}

// The flux an HG lobe of asymmetry g around the sun's light (going down at cosine mu0) sends
// up: its Legendre series to l = 6 (upward_lobe_flux in src/lighting/diffusion.rs).
fn upward_lobe_flux(mu0: f32, g: f32) -> f32 {
    let x2 = mu0 * mu0;
    let p2 = 0.5 * (3.0 * x2 - 1.0);
    let p4 = (35.0 * x2 * x2 - 30.0 * x2 + 3.0) / 8.0;
    let p6 = (231.0 * x2 * x2 * x2 - 315.0 * x2 * x2 + 105.0 * x2 - 5.0) / 16.0;
    let g2 = g * g;
    return 0.25 - 0.5 * g * mu0 + 5.0 / 16.0 * g2 * p2 - 3.0 / 32.0 * g2 * g2 * p4 + 13.0 / 256.0 * g2 * g2 * g2 * p6;
}

// The asymmetry of the thin column's lobe around the sun, g g' (g' = (g - f) / (1 - f), the
// phase's remainder after the delta scaling, f = g²).
fn thin_lobe_asymmetry(g: f32) -> f32 {
    let f = max(g, 0.0) * max(g, 0.0);
    return g * (g - f) / (1.0 - f);
}

// The thin column's lobe toward the camera at cos_theta from the sun (PhaseModel::thin_lobe in
// src/lighting/phase.rs says why): (HG of asymmetry lobe_g, the same with the phase's
// once-scattered shape: for the Jendersie-d'Eon blend (1 - w) Draine + w HG, the Draine lobe of
// the phase's alpha with asymmetry lobe_g). `model`, `params`: as phase_eval's.
fn thin_lobe(model: u32, params: vec4f, cos_theta: f32, lobe_g: f32) -> vec2f {
    let hg = henyey_greenstein(cos_theta, lobe_g);
    if (model != 0u) {
        return vec2f(hg, hg);
    }
    let alpha = params.z;
    // draine_g_for_asymmetry in src/lighting/phase.rs.
    var gd = lobe_g / 1.4;
    for (var k = 0; k < 4; k++) {
        gd = clamp(lobe_g / draine_asymmetry_ratio(gd, alpha), -0.95, 0.95);
    }
    return vec2f(hg, (1.0 - params.w) * draine(cos_theta, gd, alpha) + params.w * hg);
}

// The share of a column's diffuse light a below its sunlit face scattered only once
// (once_scattered_share in src/lighting/diffusion.rs): e^{-(1 - w f) a}.
fn once_scattered_share(a: f32, w: f32, f: f32) -> f32 {
    return exp(-(1.0 - w * f) * max(a, 0.0));
}

// How much brighter than its flux-weighted mean over directions a thin column's diffuse light
// is toward the camera (thin_column_limb in src/lighting/diffusion.rs): 1 - e^{-tau*/|mu|} over
// that mean, tau* the column's scaled optical thickness, |mu| the RMS cosine with the vertical of
// the directions the phase (second moment chi2) scatters toward the camera.
fn thin_column_limb(tau_column: f32, w: f32, f: f32, mu_view: f32, chi2: f32) -> f32 {
    let t = max(tau_column * (1.0 - w * f), 1e-4);
    let mu = sqrt(max(1.0 / 3.0 + (mu_view * mu_view - 1.0 / 3.0) * chi2, 0.0));
    let along = 1.0 - exp(-t / max(mu, 0.1));
    let mean = 1.0 - 0.5 * (0.125 * exp(-t / 0.125) + 0.375 * exp(-t / 0.375) + 0.625 * exp(-t / 0.625) + 0.875 * exp(-t / 0.875));
    return along / mean;
}

// The phase's second Legendre moment (PhaseModel::second_moment): model and params as
// phase_eval's.
fn phase_second_moment(model: u32, params: vec4f) -> f32 {
    if (model == 0u) {
        let g = params.y;
        let c2 = (1.0 + 2.0 * g * g) / 3.0;
        let c4 = (7.0 + 20.0 * g * g + 8.0 * g * g * g * g) / 35.0;
        let cos2 = (c2 + params.z * c4) / (1.0 + params.z * c2);
        return (1.0 - params.w) * params.x * params.x + params.w * (3.0 * cos2 - 1.0) / 2.0;
    }
    return params.w * params.x * params.x + (1.0 - params.w) * params.y * params.y;
}

// The share of `ambient_top` in the ambient light inside a column with optical depths `above`
// and `below`, lit by the sky (`ambient_top`) from above and `ambient_bottom` from below:
// Eddington's diffusion solution for a conservative column (Joseph, Wiscombe & Weinman 1976,
// the march's own diffuse model) has I0 linear in the transport optical depth (1 - g) tau,
// with the boundary extrapolated 2/3 beyond each face (Marshak's condition), so the share is
// ((1 - g) below + 2/3) / ((1 - g)(above + below) + 4/3): one half in a thin wisp, which sees
// as much of each side, the sample's height in the layer deep in a thick one. The height in
// the layer (hf), used before, gave a wisp high in the layer nearly the whole sky above and a
// thick cloud's base nearly none: from the ground the opaque parts came out 0.85 of the path
// tracer (0.92 with the column's share). Mirrors column_ambient_share in src/lighting/diffusion.rs.
fn column_ambient_share(above: f32, below: f32, g: f32) -> f32 {
    let transport = 1.0 - clamp(g, 0.0, 0.999);
    return (transport * below + 2.0 / 3.0) / (transport * (above + below) + 4.0 / 3.0);
}

// The share of `ambient_top` in the ambient light a sample scatters toward the camera, whose
// view ray (from the camera) has cosine `mu_view` with the local vertical. The same Eddington
// solution's radiance is I0 + I1 mu, with the net flux term I1 = -(L_top - L_bottom) /
// ((1 - g)(above + below) + 4/3) along the upward axis (Fick's law in transport depth); any
// phase function with first moment g scatters it toward the camera (direction -dir) as
// I0 + g I1 (-mu_view): share + g mu_view / ((1 - g)(above + below) + 4/3), clamped to [0, 1].
// A thin wisp seen from above shows mostly the light from below (its phase scatters forward
// what travels up), one seen from below the sky's: 1/2 -+ 3g/4 |mu| in the thin limit, the
// view-independent share deep in a thick cloud, and the mean over all views is the share.
// Mirrors seen_ambient_share in src/lighting/diffusion.rs.
fn seen_ambient_share(above: f32, below: f32, g: f32, mu_view: f32) -> f32 {
    let gc = clamp(g, 0.0, 0.999);
    let depth = (1.0 - gc) * (above + below) + 4.0 / 3.0;
    return clamp(column_ambient_share(above, below, g) + gc * mu_view / depth, 0.0, 1.0);
}
