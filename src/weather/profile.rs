//! The density model after Schneider (2015, 2017) as described in the Aetherius thesis
//! ("Density Model"): base shape eroded by low-frequency Worley fBM, per-cloud-type height
//! profile, coverage from the weather map, softened layer boundaries, and detail erosion that
//! is wispy at the bottom and billowy at the top. CPU mirror of `shaders/density.wgsl`.

use super::preset::CloudShape;

/// Linear remap of `v` from [lo, hi] to [new_lo, new_hi] (Aetherius fig. 30), unclamped.
/// A degenerate source range maps everything below `hi` to `new_lo` and the rest to `new_hi`.
pub fn remap(v: f32, lo: f32, hi: f32, new_lo: f32, new_hi: f32) -> f32 {
    let span = hi - lo;
    let t = if span.abs() < 1e-6 {
        if v < hi {
            0.0
        } else {
            1.0
        }
    } else {
        (v - lo) / span
    };
    new_lo + t * (new_hi - new_lo)
}

fn saturate(v: f32) -> f32 {
    v.clamp(0.0, 1.0)
}

/// WGSL's `smoothstep`: 0 below `e0`, 1 above `e1`, the cubic 3t² - 2t³ between.
pub(crate) fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = saturate((x - e0) / (e1 - e0));
    t * t * (3.0 - 2.0 * t)
}

/// A vertical profile as fractions of the layer height: density ramps up from `base` to
/// `full_bottom`, stays 1 to `full_top`, and falls to 0 at `top`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Profile {
    /// Fraction where the cloud starts.
    pub base: f32,
    /// Fraction where full density is reached.
    pub full_bottom: f32,
    /// Fraction where density starts to fall.
    pub full_top: f32,
    /// Fraction of the cloud tops.
    pub top: f32,
}

/// The four cloud types, at cloud-type values 0, 1/3, 2/3 and 1 of the weather map: stratus
/// (a thin sheet low in the layer), stratocumulus, cumulus, cumulonimbus (the whole layer).
pub const PROFILES: [Profile; 4] = [
    Profile {
        base: 0.0,
        full_bottom: 0.03,
        full_top: 0.08,
        top: 0.15,
    },
    Profile {
        base: 0.0,
        full_bottom: 0.06,
        full_top: 0.2,
        top: 0.35,
    },
    Profile {
        base: 0.02,
        full_bottom: 0.1,
        full_top: 0.4,
        top: 0.7,
    },
    Profile {
        base: 0.02,
        full_bottom: 0.1,
        full_top: 0.75,
        top: 1.0,
    },
];

/// The profile for a continuous cloud type in [0, 1], blending the two nearest types.
pub fn profile_for_type(cloud_type: f32) -> Profile {
    let x = saturate(cloud_type) * 3.0;
    let i = (x.floor() as usize).min(2);
    let f = x - i as f32;
    let (a, b) = (PROFILES[i], PROFILES[i + 1]);
    let lerp = |p: f32, q: f32| p + (q - p) * f;
    Profile {
        base: lerp(a.base, b.base),
        full_bottom: lerp(a.full_bottom, b.full_bottom),
        full_top: lerp(a.full_top, b.full_top),
        top: lerp(a.top, b.top),
    }
}

/// The height multiplier (Aetherius "ShapeAltering"): a product of a rising and a falling
/// ramp, for height fraction `h` in the layer.
pub fn height_profile(h: f32, cloud_type: f32) -> f32 {
    let p = profile_for_type(cloud_type);
    let rise = saturate(remap(h, p.base, p.full_bottom, 0.0, 1.0));
    let fall = saturate(remap(h, p.full_top, p.top, 1.0, 0.0));
    rise * fall
}

/// Softening of the whole shell's boundaries (Aetherius "DensityAltering"): fades density in
/// over `softness` of the layer at the bottom and out over `softness` at the top.
pub fn layer_softening(h: f32, softness: f32) -> f32 {
    if softness <= 0.0 {
        return if (0.0..=1.0).contains(&h) { 1.0 } else { 0.0 };
    }
    saturate(h / softness) * saturate((1.0 - h) / softness)
}

/// One density sample's inputs, as the textures deliver them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseSample {
    /// Base volume: R Perlin-Worley, G/B/A Worley octaves of rising frequency.
    pub base: [f32; 4],
    /// Detail volume: R/G/B Worley octaves.
    pub detail: [f32; 3],
    /// Weather map: coverage of layers 1, 2, 3 (R, G, B).
    pub coverage: [f32; 3],
    /// Cloud type of layers 1, 2, 3 (from the weather, not the map).
    pub types: [f32; 3],
}

/// The base shape before detail erosion (the cheap density used to find clouds). Each layer
/// erodes the shape with its own height profile and coverage; the densest layer wins
/// (Aetherius, "Weather System").
pub fn base_density(h: f32, s: &NoiseSample, shape: &CloudShape) -> f32 {
    let coverage = s.coverage.map(|c| shape.coverage * c);
    layered_base_density(h, s.base, coverage, s.types, shape.layer_softness)
}

/// [`base_density`] from a base-volume texel and each layer's effective coverage (global ×
/// weather map, as density.wgsl's `profiled_base_density` takes them; the cloud queries too).
pub fn layered_base_density(
    h: f32,
    base: [f32; 4],
    coverage: [f32; 3],
    types: [f32; 3],
    softness: f32,
) -> f32 {
    if !(0.0..=1.0).contains(&h) {
        return 0.0;
    }
    let [r, g, b, a] = base;
    let low_freq_fbm = g * 0.625 + b * 0.25 + a * 0.125;
    // Carve the Perlin-Worley shape with the Worley fBM.
    let carved = remap(r, low_freq_fbm - 1.0, 1.0, 0.0, 1.0);
    let best = (0..3)
        .map(|i| layer_cloud(carved, h, coverage[i], types[i]))
        .fold(0.0f32, f32::max);
    best * layer_softening(h, softness)
}

/// The range the carved base noise spans over the baked volume (1st to 99th percentile):
/// density.wgsl's `CARVED_LOW` / `CARVED_HIGH`. Cumuliform layers stretch it to [0, 1].
pub const CARVED_RANGE: (f32, f32) = (0.68, 0.87);

/// How cumuliform a layer of cloud type `cloud_type` is (density.wgsl's
/// `cumuliform_weights`): 0 up to stratocumulus (1/3), 1 from cumulus (2/3), smoothstep between.
pub fn cumuliform_weight(cloud_type: f32) -> f32 {
    smoothstep(1.0 / 3.0, 2.0 / 3.0, cloud_type)
}

/// One layer's base shape for the carved noise `carved`: coverage `c` erodes the shape under
/// the layer's height profile, so only the densest parts survive low coverage (none where `c`
/// is 0).
///
/// The carved noise spans only [`CARVED_RANGE`]: thresholded against 1 - c as it is, the
/// height profile and not the 3D noise decides where a cloud ends (flat lids, soft horizontal
/// layers; near cumulus read as cotton). Cumuliform layers stretch it to [0, 1], so that the
/// noise's cells carve the outline and its gradient, five times steeper, the edges, and take
/// their coverage through c (2 - c), which keeps a coverage's cloud fraction about what it was.
/// Stratiform decks keep the narrow range (stretched, an overcast deck at coverage 0.999 fell
/// apart into holes).
fn layer_cloud(carved: f32, h: f32, c: f32, cloud_type: f32) -> f32 {
    if c <= 0.0 {
        return 0.0;
    }
    let cumulus = cumuliform_weight(cloud_type);
    let (lo, hi) = CARVED_RANGE;
    let stretched = saturate((carved - lo) / (hi - lo));
    let shaped = carved + (stretched - carved) * cumulus;
    let covered = c + (c * (2.0 - c) - c) * cumulus;
    saturate(remap(
        shaped * height_profile(h, cloud_type),
        1.0 - covered,
        1.0,
        0.0,
        1.0,
    ))
}

/// Whether any layer can have cloud at height fraction `h` whatever the noise
/// (density.wgsl's `layers_can_cloud`). The carved noise is at most 1, in f32 too, and a
/// layer's cloud never falls as the carved noise grows (every step is monotonic), so its cloud
/// at carved = 1 bounds it: where this is false, [`layered_base_density`] is exactly 0 for
/// every base texel, and the march, the light march and the cloud queries skip the noise
/// fetches (above a layer's tops, below its bases, outside its coverage).
pub fn layers_can_cloud(h: f32, coverage: [f32; 3], types: [f32; 3]) -> bool {
    (0..3).any(|i| layer_cloud(1.0, h, coverage[i], types[i]) > 0.0)
}

/// The full density (before multiplying by extinction): base shape eroded by detail noise,
/// wispy at the bottom and billowy at the top, times the global density.
pub fn density(h: f32, s: &NoiseSample, shape: &CloudShape) -> f32 {
    let base = base_density(h, s, shape);
    if base <= 0.0 {
        return 0.0;
    }
    eroded_density(
        h,
        base,
        s.detail,
        shape.coverage,
        shape.detail_strength,
        shape.edge_sharpness,
        shape.density,
    )
}

/// density.wgsl's `eroded_density`: the base shape `base` eroded by a detail-volume texel,
/// wispy (fBM) at the bottom and billowy (inverted fBM) from a fifth of the way up, times the
/// global `density`; `coverage` is the global coverage (less erosion under more cloud).
///
/// `sharpness` ([`CloudShape::edge_sharpness`], >= 1) multiplies the eroded ramp before it is
/// capped at 1: where the erosion leaves any cloud (base above the erosion) there still is
/// cloud, and nowhere else, but the density reaches full `sharpness` times closer to the edge.
/// The remapped base rises over the whole of a cloud's body, so unsharpened the body is a soft
/// gradient whose edge the detail can only dent (cotton); sharpened, the body is nearly uniform
/// and the detail's cells carve its edge (the cauliflower billows of Schneider 2015's images).
pub fn eroded_density(
    h: f32,
    base: f32,
    detail: [f32; 3],
    coverage: f32,
    strength: f32,
    sharpness: f32,
    density: f32,
) -> f32 {
    let [r, g, b] = detail;
    let high_freq_fbm = r * 0.625 + g * 0.25 + b * 0.125;
    let mut erosion = high_freq_fbm + (1.0 - 2.0 * high_freq_fbm) * saturate(h * 5.0);
    erosion *= strength * (-coverage * 0.75).exp();
    saturate(sharpness * remap(base, erosion, 1.0, 0.0, 1.0)) * density
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(coverage: f32, cloud_type: f32) -> NoiseSample {
        NoiseSample {
            base: [0.8, 0.5, 0.5, 0.5],
            detail: [0.3, 0.4, 0.5],
            coverage: [coverage, 0.0, 0.0],
            types: [cloud_type, 0.0, 0.0],
        }
    }

    #[test]
    fn the_densest_layer_wins() {
        let shape = CloudShape {
            coverage: 0.9,
            detail_strength: 0.0,
            ..CloudShape::default()
        };
        // Layer 1 stratus (thin, low), layer 2 cumulonimbus (tall).
        let both = NoiseSample {
            coverage: [1.0, 0.8, 0.0],
            types: [0.0, 1.0, 0.0],
            ..sample(0.0, 0.0)
        };
        let only = |i: usize| {
            let mut s = both;
            s.coverage = [0.0; 3];
            s.coverage[i] = both.coverage[i];
            s
        };
        for h in [0.05, 0.1, 0.5, 0.8] {
            let d = base_density(h, &both, &shape);
            let d0 = base_density(h, &only(0), &shape);
            let d1 = base_density(h, &only(1), &shape);
            assert!(
                (d - d0.max(d1)).abs() < 1e-6,
                "h={h}: {d} vs max({d0}, {d1})"
            );
        }
        // High in the layer only the cumulonimbus reaches.
        assert_eq!(base_density(0.6, &only(0), &shape), 0.0);
        assert!(base_density(0.6, &both, &shape) > 0.0);
    }

    /// The march skips the noise fetches where `layers_can_cloud` is false: there the base
    /// density must be exactly 0 for every base texel, including the extremes of the carving.
    #[test]
    fn no_layer_can_cloud_means_no_base_density() {
        let levels = [0.0, 1e-7, 0.01, 0.25, 0.5, 0.6, 0.75, 0.99, 1.0];
        let mut skipped_with_coverage = 0;
        let mut seed = 0x9e37_79b9u32;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            (seed >> 8) as f32 / (1u32 << 24) as f32
        };
        for hi in 0..=200 {
            let h = hi as f32 / 200.0;
            for &c in &levels {
                for &t in &[0.0, 0.2, 1.0 / 3.0, 0.5, 0.7, 1.0] {
                    let coverage = [c, 0.5 * c, 0.0];
                    let types = [t, 1.0 - t, 0.5];
                    if layers_can_cloud(h, coverage, types) {
                        continue;
                    }
                    skipped_with_coverage += usize::from(c > 0.0);
                    let mut bases = vec![[1.0; 4], [1.0, 0.0, 0.0, 0.0], [1.0, 1.0, 1.0, 1.0]];
                    bases.extend((0..16).map(|_| [next(), next(), next(), next()]));
                    for base in bases {
                        let d = layered_base_density(h, base, coverage, types, 0.05);
                        assert_eq!(d, 0.0, "h {h} c {c} t {t} base {base:?}");
                    }
                }
            }
        }
        // The bound skips real work: covered columns above their tops and below their bases.
        assert!(skipped_with_coverage > 1000, "{skipped_with_coverage}");
        // ...and never where a layer's profile peaks under full coverage.
        assert!(layers_can_cloud(0.3, [1.0, 0.0, 0.0], [0.5, 0.0, 0.0]));
    }

    /// Cumulus are carved by their noise, not by their height profile: across the range the
    /// carved noise spans, a cumulus layer's base shape at coverage 0.4 runs from none to most
    /// of full, a stratus layer's stays cloud everywhere (its noise only modulates it).
    #[test]
    fn cumulus_are_carved_by_their_noise() {
        // carved = (r - (fbm - 1)) / (2 - fbm): with the Worley fBM at 0.5, r = 1.5 carved - 0.5.
        let texel = |carved: f32| [1.5 * carved - 0.5, 0.5, 0.5, 0.5];
        let at = |carved: f32, h: f32, t: f32| {
            layered_base_density(h, texel(carved), [0.4, 0.0, 0.0], [t, 0.0, 0.0], 0.0)
        };
        let (lo, hi) = CARVED_RANGE;
        // Cumulus (2/3) where its profile is full (h 0.3).
        assert_eq!(at(lo + 0.01, 0.3, 2.0 / 3.0), 0.0);
        assert!(at(0.5 * (lo + hi), 0.3, 2.0 / 3.0) > 0.0);
        assert!(at(hi, 0.3, 2.0 / 3.0) > 0.6, "{}", at(hi, 0.3, 2.0 / 3.0));
        // Stratus (0) where its profile is full (h 0.05): cloud across the whole range.
        for k in 0..=10 {
            let carved = lo + (hi - lo) * k as f32 / 10.0;
            let d = at(carved, 0.05, 0.0);
            assert!(d > 0.15 && d < 0.7, "stratus at carved {carved}: {d}");
        }
        assert_eq!(cumuliform_weight(0.0), 0.0);
        assert_eq!(cumuliform_weight(1.0 / 3.0), 0.0);
        assert!((cumuliform_weight(0.5) - 0.5).abs() < 1e-6);
        assert_eq!(cumuliform_weight(2.0 / 3.0), 1.0);
    }

    #[test]
    fn remap_maps_ranges() {
        assert_eq!(remap(0.5, 0.0, 1.0, 10.0, 20.0), 15.0);
        assert_eq!(remap(2.0, 1.0, 3.0, 0.0, 1.0), 0.5);
        assert_eq!(remap(0.25, 0.0, 1.0, 1.0, 0.0), 0.75);
        // Degenerate range does not divide by zero.
        assert_eq!(remap(0.5, 1.0, 1.0, 0.0, 1.0), 0.0);
        assert_eq!(remap(1.0, 1.0, 1.0, 0.0, 1.0), 1.0);
    }

    #[test]
    fn height_profiles_have_their_shape() {
        for (i, p) in PROFILES.iter().enumerate() {
            let t = i as f32 / 3.0;
            assert_eq!(height_profile(-0.1, t), 0.0);
            assert_eq!(
                height_profile(p.top + 0.01, t),
                0.0,
                "type {i} above its top"
            );
            let mid = 0.5 * (p.full_bottom + p.full_top);
            assert!(
                (height_profile(mid, t) - 1.0).abs() < 1e-6,
                "type {i} plateau"
            );
            // Monotonic ramps.
            let mut prev = 0.0;
            for k in 0..=20 {
                let h = p.base + (p.full_bottom - p.base) * k as f32 / 20.0;
                let v = height_profile(h, t);
                assert!(v + 1e-6 >= prev, "type {i} rise at {h}");
                prev = v;
            }
        }
        // Stratus is thin and low, cumulonimbus fills the layer.
        assert_eq!(height_profile(0.5, 0.0), 0.0);
        assert_eq!(height_profile(0.5, 1.0), 1.0);
        assert!(height_profile(0.9, 1.0) > 0.0);
        // Types blend continuously.
        let a = height_profile(0.3, 0.5);
        assert!(
            a > height_profile(0.3, 1.0 / 3.0) - 1e-6 && a < height_profile(0.3, 2.0 / 3.0) + 1e-6
        );
    }

    #[test]
    fn layer_softening_fades_the_boundaries() {
        assert_eq!(layer_softening(0.0, 0.1), 0.0);
        assert_eq!(layer_softening(1.0, 0.1), 0.0);
        assert_eq!(layer_softening(0.5, 0.1), 1.0);
        assert!((layer_softening(0.05, 0.1) - 0.5).abs() < 1e-6);
        assert_eq!(layer_softening(0.5, 0.0), 1.0);
    }

    #[test]
    fn zero_coverage_means_no_cloud() {
        let mut shape = CloudShape::default();
        for cov in [0.0, 1.0] {
            for h in [0.1, 0.3, 0.6] {
                assert_eq!(
                    density(
                        h,
                        &sample(cov, 1.0),
                        &CloudShape {
                            coverage: 0.0,
                            ..shape
                        }
                    ),
                    0.0
                );
            }
        }
        shape.coverage = 1.0;
        assert_eq!(density(0.3, &sample(0.0, 1.0), &shape), 0.0);
    }

    #[test]
    fn density_grows_with_coverage_and_vanishes_outside_the_layer() {
        let mut last = 0.0;
        for k in 1..=10 {
            let shape = CloudShape {
                coverage: k as f32 / 10.0,
                detail_strength: 0.0,
                ..CloudShape::default()
            };
            let d = base_density(0.3, &sample(1.0, 1.0), &shape);
            assert!(d >= last, "coverage {k}: {d} < {last}");
            last = d;
        }
        assert!(last > 0.5);
        let shape = CloudShape::default();
        assert_eq!(density(-0.01, &sample(1.0, 1.0), &shape), 0.0);
        assert_eq!(density(1.01, &sample(1.0, 1.0), &shape), 0.0);
    }

    #[test]
    fn detail_only_erodes() {
        // Unsharpened: edge sharpness fills the eroded ramp up to full density on purpose
        // (edge_sharpness_crisps_the_edge_without_moving_it).
        let shape = CloudShape {
            coverage: 0.8,
            edge_sharpness: 1.0,
            ..CloudShape::default()
        };
        for h in [0.1, 0.2, 0.5] {
            let s = sample(1.0, 1.0);
            assert!(density(h, &s, &shape) <= base_density(h, &s, &shape) * shape.density + 1e-6);
        }
    }

    /// Edge sharpness steepens the ramp from the eroded edge into the body and caps it at full
    /// density: cloud stays exactly where it was (same zero set), nowhere thinner, never above
    /// the density scale, and where the soft ramp is below 1 / k exactly k times as dense.
    #[test]
    fn edge_sharpness_crisps_the_edge_without_moving_it() {
        let mut rnd = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            rnd ^= rnd << 13;
            rnd ^= rnd >> 7;
            rnd ^= rnd << 17;
            (rnd >> 40) as f32 / (1u64 << 24) as f32
        };
        let (mut inside, mut capped) = (0, 0);
        for _ in 0..5_000 {
            let h = next();
            let base = next();
            let detail = [next(), next(), next()];
            let (coverage, strength, density) = (next(), next(), 0.5 + next());
            let soft = eroded_density(h, base, detail, coverage, strength, 1.0, density);
            let mut last = soft;
            for k in [1.5f32, 4.0, 8.0] {
                let sharp = eroded_density(h, base, detail, coverage, strength, k, density);
                assert_eq!(sharp > 0.0, soft > 0.0, "the outline moved (k {k}, h {h})");
                assert!(
                    sharp >= last && sharp <= density,
                    "k {k}: {sharp} after {last}"
                );
                let expected = (k * soft / density).min(1.0) * density;
                assert!(
                    (sharp - expected).abs() <= 1e-5 * density,
                    "k {k}: {sharp} against {expected}"
                );
                last = sharp;
            }
            inside += (soft > 0.0) as u32;
            capped += (last == density && soft < 0.5 * density) as u32;
        }
        // The draws cover both the ramp and its capped body.
        assert!(
            inside > 1_000 && capped > 100,
            "{inside} in cloud, {capped} capped"
        );
        // The cloud model's entry point passes the preset's sharpness through.
        let soft = CloudShape {
            edge_sharpness: 1.0,
            ..CloudShape::default()
        };
        let sharp = CloudShape {
            edge_sharpness: 3.0,
            ..soft
        };
        let on_ramp = (0..100)
            .map(|i| {
                let mut s = sample(1.0, 2.0 / 3.0);
                s.base[0] = 0.6 + 0.004 * i as f32;
                (density(0.3, &s, &soft), density(0.3, &s, &sharp))
            })
            .filter(|(a, _)| *a > 0.0 && *a < soft.density / 3.0)
            .inspect(|(a, b)| assert!((b - 3.0 * a).abs() < 1e-5, "{b} against 3 × {a}"))
            .count();
        assert!(on_ramp > 3, "only {on_ramp} samples on the soft ramp");
    }
}
