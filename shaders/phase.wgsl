// Phase functions, normalised over the sphere. Mirrors src/lighting/phase.rs.

fn henyey_greenstein(cos_theta: f32, g: f32) -> f32 {
    let g2 = g * g;
    // (1 - g)² + 2g(1 - cos θ) equals 1 + g² - 2g cos θ but keeps its precision in f32 near
    // the forward peak, where the usual form cancels (+8e-4 relative at θ = 0, g = 0.988).
    let denom = max((1.0 - g) * (1.0 - g) + 2.0 * g * (1.0 - cos_theta), 1e-12);
    return (1.0 - g2) / (4.0 * PI * denom * sqrt(denom));
}

// Draine 2003: HG times a normalised generalised-Rayleigh term.
fn draine(cos_theta: f32, g: f32, alpha: f32) -> f32 {
    return henyey_greenstein(cos_theta, g) * (1.0 + alpha * cos_theta * cos_theta)
        / (1.0 + alpha * (1.0 + 2.0 * g * g) / 3.0);
}

// model 0: Jendersie & d'Eon HG + Draine, params = (g_hg, g_d, alpha, w).
// model 1: dual-lobe HG, params = (g_forward, g_backward, unused, forward weight).
// `k` scales the asymmetries (Wrenninge's c^i per octave).
fn phase_eval(model: u32, params: vec4f, cos_theta: f32, k: f32) -> f32 {
    if (model == 0u) {
        return (1.0 - params.w) * henyey_greenstein(cos_theta, params.x * k)
            + params.w * draine(cos_theta, params.y * k, params.z);
    }
    return params.w * henyey_greenstein(cos_theta, params.x * k)
        + (1.0 - params.w) * henyey_greenstein(cos_theta, params.y * k);
}
