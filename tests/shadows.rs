//! The cloud shadow map on software Vulkan: closed-form umbra of a debug sphere, a clear sky,
//! texel snapping, the sun, amortised refresh and the weather.

mod common;

use common::{headless, quiet, small_noise};
use glam::{Mat4, Vec3};
use nimbus::{
    shadow_optical_depth, Camera, CloudShadowSampler, DebugDensity, DepthConvention, FrameInputs,
    Headless, Preset, Settings, Sun,
};

const RESOLUTION: u32 = 128;
const EXTENT: f32 = 6_400.0;
const SIGMA_T: f32 = 0.002;
const CENTER: Vec3 = Vec3::new(300.0, 3_000.0, -200.0);
const RADIUS: f32 = 1_000.0;

fn sun_dir() -> Vec3 {
    Vec3::new(0.3, 1.0, 0.2).normalize()
}

fn frame(eye: Vec3, sun: Vec3, time: f64) -> FrameInputs {
    FrameInputs {
        camera: Camera {
            view: Mat4::look_at_rh(eye, eye + Vec3::new(0.0, 0.3, -1.0), Vec3::Y),
            projection: Mat4::perspective_rh(60f32.to_radians(), 16.0 / 9.0, 1.0, 1e5),
            depth: DepthConvention::default(),
        },
        sun: Sun {
            direction: sun,
            ..Sun::default()
        },
        time,
    }
}

fn with_shadows(mut s: Settings, slices: u32) -> Settings {
    s.shadows.enabled = true;
    s.shadows.resolution = RESOLUTION;
    s.shadows.extent = EXTENT;
    s.shadows.steps = 16;
    s.shadows.update_slices = slices;
    s
}

fn sphere_settings() -> Settings {
    let mut s = with_shadows(quiet(small_noise(1)), 1);
    s.weather.clouds.extinction = SIGMA_T;
    s.debug_density = DebugDensity::Sphere {
        center: CENTER,
        radius: RADIUS,
        density: 1.0,
    };
    s
}

/// Renders a frame and returns the map's texels and matrix.
fn map_after(h: &mut Headless, f: &FrameInputs) -> (Vec<[f32; 4]>, Mat4) {
    h.render(f).unwrap();
    let m = h.renderer().cloud_shadows().unwrap().world_to_map;
    (h.read_cloud_shadows().unwrap(), m)
}

/// The texel index a map coordinate falls in (the map is toroidal).
fn texel_index(c: f32) -> usize {
    (c.rem_euclid(1.0) * RESOLUTION as f32).floor() as usize % RESOLUTION as usize
}

#[test]
fn a_debug_sphere_casts_the_closed_form_umbra_where_the_matrix_says() {
    let mut h = headless(sphere_settings());
    let eye = Vec3::new(0.0, 2.0, 0.0);
    let (map, m) = map_after(&mut h, &frame(eye, sun_dir(), 0.0));
    let n = RESOLUTION as usize;
    let texel = EXTENT / RESOLUTION as f32;

    // Every texel against the closed form: its ray passes the sphere's center at distance
    // delta (from the matrix), so T = exp(-sigma_t * 2 sqrt(R^2 - delta^2)).
    let c = m * CENTER.extend(1.0);
    let mut worst = 0.0f32;
    let mut shadowed = 0;
    for y in 0..n {
        for x in 0..n {
            let wrap = |d: f32| d - d.round();
            let du = wrap((x as f32 + 0.5) / n as f32 - c.x) * EXTENT;
            let dv = wrap((y as f32 + 0.5) / n as f32 - c.y) * EXTENT;
            let delta2 = du * du + dv * dv;
            let chord = 2.0 * (RADIUS * RADIUS - delta2).max(0.0).sqrt();
            let want = (-SIGMA_T * chord).exp();
            let got = map[y * n + x][3];
            // Texels whose ray grazes the rim are sensitive to f32 rounding of delta.
            if (delta2.sqrt() - RADIUS).abs() > 2.0 {
                worst = worst.max((got - want).abs());
            }
            if got < 0.999 {
                shadowed += 1;
            }
        }
    }
    assert!(worst < 0.005, "worst |T - closed form| = {worst}");
    let disc = std::f32::consts::PI * RADIUS * RADIUS / (texel * texel);
    assert!(
        (shadowed as f32 - disc).abs() < 0.05 * disc,
        "{shadowed} shadowed texels, the disc covers {disc}"
    );

    // A point on the ground under the sphere, along the light through its center: in the
    // umbra, T = exp(-sigma_t * 2R) within 2%.
    let light = -sun_dir();
    let ground = CENTER + light * (CENTER.y / -light.y);
    let q = m * ground.extend(1.0);
    let t = map[texel_index(q.y) * n + texel_index(q.x)];
    let got = (-shadow_optical_depth(t, q.z)).exp();
    let want = (-SIGMA_T * 2.0 * RADIUS).exp();
    assert!(
        (got / want - 1.0).abs() < 0.02,
        "umbra center T = {got}, closed form {want}"
    );
    // The CPU sampler (bilinear, as a host's GPU sampler reads it) agrees, and refuses points
    // outside the square.
    let sampler =
        CloudShadowSampler::new(&h.renderer().cloud_shadows().unwrap(), map.clone()).unwrap();
    let filtered = sampler.transmittance(ground).unwrap();
    assert!(
        (filtered / want - 1.0).abs() < 0.02,
        "sampled {filtered}, closed form {want}"
    );
    assert_eq!(
        sampler.transmittance(eye + Vec3::new(EXTENT, 0.0, 0.0)),
        None
    );
    assert_eq!(
        sampler.transmittance(eye + Vec3::new(0.0, 0.0, 200.0)),
        Some(1.0)
    );
    // Above the sphere, on the same ray, the sun is unobstructed; halfway through, the optical
    // depth is about half.
    let above = m * (CENTER - light * 2.0 * RADIUS).extend(1.0);
    assert_eq!(shadow_optical_depth(t, above.z), 0.0);
    let middle = m * CENTER.extend(1.0);
    let half = shadow_optical_depth(t, middle.z) / (SIGMA_T * 2.0 * RADIUS);
    assert!(
        (half - 0.5).abs() < 0.05,
        "half-way optical depth ratio {half}"
    );
}

#[test]
fn the_map_holds_still_under_sub_texel_moves_and_follows_the_sun() {
    let mut h = headless(sphere_settings());
    let eye = Vec3::new(0.0, 2.0, 0.0);
    let (a, ma) = map_after(&mut h, &frame(eye, sun_dir(), 0.0));
    // A third of a texel sideways: the map and its matrix stay exactly as they were.
    let texel = EXTENT / RESOLUTION as f32;
    let (b, mb) = map_after(
        &mut h,
        &frame(eye + Vec3::new(0.33 * texel, 0.0, 0.0), sun_dir(), 0.0),
    );
    assert_eq!(ma, mb);
    assert!(a == b, "the map changed under a sub-texel camera move");
    // Ten texels: the window moves, the matrix with it, and the shadow stays on the ground
    // where it was (the point under the sphere still reads the umbra).
    let (c, mc) = map_after(
        &mut h,
        &frame(eye + Vec3::new(10.0 * texel, 0.0, 0.0), sun_dir(), 0.0),
    );
    // The map is toroidal: the matrix stays, the window of valid texels moves.
    assert_eq!(ma, mc);
    let origin = h.renderer().cloud_shadows().unwrap().window_origin;
    let inside = |p: Vec3| {
        let q = mc * p.extend(1.0);
        let d = glam::Vec2::new(q.x, q.y) - origin;
        d.min_element() >= 0.0 && d.max_element() < 1.0
    };
    let moved = eye + Vec3::new(10.0 * texel, 0.0, 0.0);
    assert!(inside(moved) && inside(moved + Vec3::new(0.45 * EXTENT, 0.0, 0.0)));
    assert!(!inside(moved + Vec3::new(0.55 * EXTENT, 0.0, 0.0)));
    let light = -sun_dir();
    let ground = CENTER + light * (CENTER.y / -light.y);
    let read = |map: &[[f32; 4]], m: Mat4| {
        let q = m * ground.extend(1.0);
        map[texel_index(q.y) * RESOLUTION as usize + texel_index(q.x)][3]
    };
    assert!((read(&a, ma) - read(&c, mc)).abs() < 1e-3);
    // The sun turns by 3°: the umbra moves on the ground.
    let turned = (sun_dir() + Vec3::new(0.06, 0.0, 0.0)).normalize();
    let (d, md) = map_after(&mut h, &frame(eye, turned, 0.0));
    assert_ne!(h.renderer().cloud_shadows().unwrap().sun, sun_dir());
    assert!(a != d, "the map did not change when the sun turned");
    let l2 = -turned;
    let ground2 = CENTER + l2 * (CENTER.y / -l2.y);
    let q = md * ground2.extend(1.0);
    let umbra = d[texel_index(q.y) * RESOLUTION as usize + texel_index(q.x)][3];
    assert!((umbra / (-SIGMA_T * 2.0 * RADIUS).exp() - 1.0).abs() < 0.02);
}

#[test]
fn clear_skies_cast_no_shadow_and_clouds_refresh_a_slice_per_frame() {
    let mut s = with_shadows(quiet(small_noise(3)), 4);
    s.weather = Preset::Clear.weather();
    let mut h = headless(s.clone());
    let eye = Vec3::new(0.0, 2.0, 0.0);
    let (clear, _) = map_after(&mut h, &frame(eye, sun_dir(), 0.0));
    assert!(
        clear.iter().all(|t| t[3] == 1.0 && t[2] == 0.0),
        "a clear sky shadows something"
    );

    // Overcast: the map holds clouds, and with 4 slices a later time's map is complete after
    // 4 frames, a quarter of it after one.
    s.weather = Preset::Overcast.weather();
    h.renderer_mut().set_settings(s.clone()).unwrap();
    let (at0, _) = map_after(&mut h, &frame(eye, sun_dir(), 0.0));
    let dark = at0.iter().filter(|t| t[3] < 0.5).count();
    assert!(
        dark > at0.len() / 2,
        "overcast shadows only {dark} of {} texels",
        at0.len()
    );
    let later = 600.0;
    let (one, _) = map_after(&mut h, &frame(eye, sun_dir(), later));
    for _ in 0..3 {
        h.render(&frame(eye, sun_dir(), later)).unwrap();
    }
    let four = h.read_cloud_shadows().unwrap();
    let mut fresh_settings = s.clone();
    fresh_settings.shadows.update_slices = 1;
    let mut fresh = headless(fresh_settings);
    let (full, _) = map_after(&mut fresh, &frame(eye, sun_dir(), later));
    let differ: Vec<usize> = (0..four.len()).filter(|&i| four[i] != full[i]).collect();
    let worst = differ
        .iter()
        .map(|&i| (four[i][3] - full[i][3]).abs())
        .fold(0.0f32, f32::max);
    assert!(
        differ.is_empty(),
        "four sliced frames differ from one full update in {} texels (first {:?}, rows {:?}), worst |dT| {worst}",
        differ.len(),
        differ.first(),
        differ.iter().map(|i| i / RESOLUTION as usize % 4).collect::<std::collections::BTreeSet<_>>()
    );
    let n = RESOLUTION as usize;
    let rows_changed = (0..n)
        .filter(|y| one[y * n..(y + 1) * n] != at0[y * n..(y + 1) * n])
        .count();
    let rows_now_full = (0..n)
        .filter(|y| one[y * n..(y + 1) * n] == full[y * n..(y + 1) * n])
        .count();
    assert!(
        rows_changed <= n / 4 && rows_changed > n / 8,
        "one sliced frame changed {rows_changed} of {n} rows"
    );
    assert!(rows_now_full >= n / 4, "{rows_now_full}");
}

#[test]
fn a_slab_shadows_every_texel_of_a_wide_map_under_a_low_sun() {
    // At a low sun the map's plane (perpendicular to the light) tilts steeply: 20 km from the
    // camera it lies far above the layer on one side and deep under the ground on the other.
    // Every texel's ray must still cross the whole slab: tau = sigma_t (top - bottom) / mu0.
    let mut s = with_shadows(quiet(small_noise(1)), 1);
    s.shadows.extent = 40_000.0;
    let (bottom, top) = (1_500.0f32, 2_000.0f32);
    s.weather.clouds.extinction = SIGMA_T;
    s.debug_density = DebugDensity::Slab {
        bottom_altitude: bottom,
        top_altitude: top,
        density: 1.0,
    };
    let mut h = headless(s);
    let elevation = 20f32.to_radians();
    let sun = Vec3::new(elevation.cos(), elevation.sin(), 0.0);
    let (map, m) = map_after(&mut h, &frame(Vec3::new(0.0, 2.0, 0.0), sun, 0.0));
    let origin = h.renderer().cloud_shadows().unwrap().window_origin;
    // Each texel's ray, rebuilt from the inverse matrix, crosses the spherical shell between
    // the two altitudes: the closed form is the distance between the two spheres' crossings.
    let inv = m.as_dmat4().inverse();
    let light = -sun.as_dvec3();
    let radius = 6_360_000.0f64;
    let center = glam::DVec3::new(0.0, -radius, 0.0);
    let crossing = |p: glam::DVec3, r: f64| {
        // The entry (first root) of p + light t into the sphere of radius r.
        let o = p - center;
        let b = o.dot(light);
        let c = o.dot(o) - r * r;
        -b - (b * b - c).sqrt()
    };
    let n = RESOLUTION as usize;
    let mut worst = 0.0f64;
    for y in 0..n {
        for x in 0..n {
            let coord = |i: usize, o: f32| {
                let first = (o * n as f32).round() as usize;
                o as f64 + (((i + n - first) % n) as f64 + 0.5) / n as f64
            };
            let p = inv * glam::DVec4::new(coord(x, origin.x), coord(y, origin.y), 0.0, 1.0);
            let p = p.truncate();
            let path = crossing(p, radius + bottom as f64) - crossing(p, radius + top as f64);
            let want = SIGMA_T as f64 * path;
            worst = worst.max((map[y * n + x][2] as f64 / want - 1.0).abs());
        }
    }
    assert!(worst < 0.005, "worst relative optical-depth error {worst}");
}

/// Tone-mapped sRGB bytes of a linear image, for FLIP.
fn srgb_bytes(pixels: &[[f32; 4]]) -> Vec<u8> {
    pixels
        .iter()
        .flat_map(|p| nimbus::demo::tonemap(*p, 1.0))
        .collect()
}

fn flip_mean(reference: &[[f32; 4]], test: &[[f32; 4]]) -> f32 {
    let (w, h) = (common::W, common::H);
    let r = nv_flip::FlipImageRgb8::with_data(w, h, &srgb_bytes(reference));
    let t = nv_flip::FlipImageRgb8::with_data(w, h, &srgb_bytes(test));
    let error = nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    nv_flip::FlipPool::from_image(&error).mean()
}

#[test]
fn light_from_the_map_equals_the_full_light_march_in_a_slab() {
    // A homogeneous slab thin enough that the full light march reaches its top (no
    // light_distance cut): both light paths are exact, so the march's images agree; what is
    // left is the map's f16 storage and its bilinear filtering.
    let mut s = with_shadows(quiet(small_noise(1)), 1);
    s.shadows.extent = 20_000.0;
    s.shadows.resolution = 256;
    s.weather.clouds.extinction = 0.004;
    s.debug_density = DebugDensity::Slab {
        bottom_altitude: 1_000.0,
        top_altitude: 1_600.0,
        density: 1.0,
    };
    let view = &nimbus::demo::standard_views()[0];
    let f = view.frame(common::W, common::H, 0.0);
    let mut h = headless(s.clone());
    h.render(&f).unwrap();
    let full = h.read_clouds().unwrap();
    let marched = h.read_ray_stats().unwrap();
    s.shadows.march_light = true;
    h.renderer_mut().set_settings(s).unwrap();
    h.render(&f).unwrap();
    let mapped = h.read_clouds().unwrap();
    let stats = h.read_ray_stats().unwrap();
    let mut worst = 0.0f32;
    for (a, b) in full.iter().zip(&mapped) {
        if a[0] > 1e-3 {
            worst = worst.max((b[0] / a[0] - 1.0).abs());
        }
        assert_eq!(a[3], b[3], "the view transmittance changed");
    }
    println!(
        "slab: worst relative radiance difference {worst:.4}; light samples per ray {:.1} -> {:.1}",
        marched.mean_light_samples, stats.mean_light_samples
    );
    assert!(worst < 0.01, "light from the map differs by {worst}");
    assert!(stats.mean_light_samples < 0.6 * marched.mean_light_samples);
}

#[test]
fn light_from_the_map_stays_within_the_flip_budget_on_the_noise_model() {
    let mut s = with_shadows(quiet(small_noise(2)), 1);
    s.weather = Preset::Cloudy.weather();
    let mut s = common::measured_shape(s);
    s.shadows.extent = 40_000.0;
    s.shadows.resolution = 256;
    // The full light march stops at lighting.light_distance (3 km by default), the map's
    // light goes all the way to the sun: compare the two over the same path.
    s.lighting.light_distance = 30_000.0;
    let mut results = Vec::new();
    for view in &nimbus::demo::standard_views()[..3] {
        let f = view.frame(common::W, common::H, 0.0);
        let mut h = headless(s.clone());
        h.render(&f).unwrap();
        let full = h.read_output().unwrap();
        let full_stats = h.read_ray_stats().unwrap();
        let mut on = s.clone();
        on.shadows.march_light = true;
        h.renderer_mut().set_settings(on).unwrap();
        h.render(&f).unwrap();
        let mapped = h.read_output().unwrap();
        let stats = h.read_ray_stats().unwrap();
        let flip = flip_mean(&full, &mapped);
        println!(
            "{}: FLIP {flip:.4}, light samples per ray {:.1} -> {:.1}",
            view.name, full_stats.mean_light_samples, stats.mean_light_samples
        );
        results.push((view.name, flip));
    }
    // Measured: 0.052, 0.052 and 0.025 (0.052, 0.050 and 0.024 before noise clouds' columns
    // leaked, 0.073 on the ground view with the leak at the sample's own extinction; 0.041,
    // 0.058 and 0.006 before cumulus were carved by
    // their noise, 2026-12-05; the Beer shadow map's linear ramp through a
    // texel's clouds is its approximation; the benchmark's budget for the default level
    // against its reference is 0.05).
    for (name, flip) in results {
        assert!(
            flip < 0.07,
            "{name}: FLIP {flip} against the full light march"
        );
    }
}
