//! GPU tests on whatever Vulkan adapter is present (Mesa's lavapipe in CI): noise, compositing
//! invariants, the integrator against a closed form, and errors instead of panics.

use glam::{Mat4, Vec3, Vec4};
use nimbus::demo::{standard_views, DemoView, Occluder};
use nimbus::lighting::phase::PhaseModel;
use nimbus::lighting::scattering::{slab_single_reflection, slab_single_scattering};
use nimbus::settings::{MultipleScattering, MultipleScatteringModel};
use nimbus::{
    Camera, ColorTargets, DebugDensity, DepthConvention, Error, FrameInputs, Headless, NoiseVolume,
    Renderer, Settings, Sun, Targets,
};

mod common;
use common::{debug_sphere, f16, headless, quiet, setup, small_noise, H, W};

fn render_view(h: &mut Headless, view: &DemoView) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
    let scene = view.scene(W, H);
    h.upload_scene(&scene.color, Some(&scene.depth)).unwrap();
    h.render(&view.frame(W, H, 0.0)).unwrap();
    (scene.color, h.read_output().unwrap())
}

// ---- noise ---------------------------------------------------------------------------------

/// A frame from `view` and `projection` (the default depth convention) under a white sun of
/// `illuminance` toward `sun_direction`, at time 0.
fn still_frame(view: Mat4, projection: Mat4, sun_direction: Vec3, illuminance: f32) -> FrameInputs {
    FrameInputs {
        camera: Camera {
            view,
            projection,
            depth: DepthConvention::default(),
        },
        sun: Sun {
            direction: sun_direction,
            color: Vec3::ONE,
            illuminance,
        },
        time: 0.0,
    }
}

fn at(v: &[u8], n: usize, x: usize, y: usize, z: usize, c: usize) -> f64 {
    v[((z * n + y) * n + x) * 4 + c] as f64
}

/// Mean absolute difference between slices `a` and `b` along `axis`.
fn slice_diff(v: &[u8], n: usize, axis: usize, a: usize, b: usize, channels: usize) -> f64 {
    let mut sum = 0.0;
    for i in 0..n {
        for j in 0..n {
            for c in 0..channels {
                let (p, q) = match axis {
                    0 => (at(v, n, a, i, j, c), at(v, n, b, i, j, c)),
                    1 => (at(v, n, i, a, j, c), at(v, n, i, b, j, c)),
                    _ => (at(v, n, i, j, a, c), at(v, n, i, j, b, c)),
                };
                sum += (p - q).abs();
            }
        }
    }
    sum / (n * n * channels) as f64
}

#[test]
fn noise_volumes_tile_across_opposite_faces() {
    let h = headless(Settings::default());
    for (which, n, channels) in [(NoiseVolume::Base, 128, 4), (NoiseVolume::Detail, 32, 3)] {
        let v = h.read_noise(which, 0).unwrap();
        assert_eq!(v.len(), n * n * n * 4);
        for axis in 0..3 {
            // Across the wrap (last slice to first) the noise must change like between any two
            // neighbouring slices, and much less than between unrelated slices.
            let wrap = slice_diff(&v, n, axis, n - 1, 0, channels);
            let interior: f64 = (0..n - 1)
                .map(|i| slice_diff(&v, n, axis, i, i + 1, channels))
                .sum::<f64>()
                / (n - 1) as f64;
            let far = slice_diff(&v, n, axis, 0, n / 2, channels);
            assert!(
                wrap <= interior * 1.15 + 0.5,
                "{which:?} axis {axis}: wrap {wrap:.2} vs neighbour {interior:.2}"
            );
            assert!(
                far > interior * 2.0,
                "{which:?} axis {axis}: test cannot discriminate"
            );
        }
    }
}

#[test]
fn weather_map_tiles() {
    let h = headless(Settings::default());
    let n = Settings::default().noise.weather_size as usize;
    let (v, _) = h.read_weather_maps().unwrap();
    let px = |x: usize, y: usize, c: usize| v[y * n + x][c] as f64;
    let (mut wrap, mut inner) = (0.0, 0.0);
    for i in 0..n {
        for c in 0..3 {
            wrap += (px(n - 1, i, c) - px(0, i, c)).abs() + (px(i, n - 1, c) - px(i, 0, c)).abs();
            inner += (px(n / 2, i, c) - px(n / 2 + 1, i, c)).abs()
                + (px(i, n / 2, c) - px(i, n / 2 + 1, c)).abs();
        }
    }
    assert!(
        wrap <= inner * 1.5 + n as f64 / 255.0,
        "wrap {wrap} vs interior {inner}"
    );
}

#[test]
fn same_seed_same_volumes_other_seed_differs() {
    let a = headless(small_noise(3));
    let b = headless(small_noise(3));
    let c = headless(small_noise(4));
    for which in [NoiseVolume::Base, NoiseVolume::Detail] {
        let (va, vb, vc) = (
            a.read_noise(which, 0).unwrap(),
            b.read_noise(which, 0).unwrap(),
            c.read_noise(which, 0).unwrap(),
        );
        assert_eq!(va, vb, "{which:?}: same seed must give identical bytes");
        let differing = va.iter().zip(&vc).filter(|(x, y)| x != y).count();
        assert!(
            differing * 2 > va.len(),
            "{which:?}: only {differing} bytes differ"
        );
    }
}

#[test]
fn mip_levels_average_the_level_below() {
    let h = headless(small_noise(1));
    let m0 = h.read_noise(NoiseVolume::Base, 0).unwrap();
    let m1 = h.read_noise(NoiseVolume::Base, 1).unwrap();
    let (n0, n1) = (32usize, 16usize);
    for (x, y, z) in [(0, 0, 0), (5, 9, 2), (15, 15, 15)] {
        for c in 0..4 {
            let mut sum = 0.0;
            for k in 0..8 {
                sum += at(
                    &m0,
                    n0,
                    2 * x + (k & 1),
                    2 * y + ((k >> 1) & 1),
                    2 * z + (k >> 2),
                    c,
                );
            }
            let got = at(&m1, n1, x, y, z, c);
            assert!(
                (got - sum / 8.0).abs() <= 1.0,
                "mip1 ({x},{y},{z}) c{c}: {got} vs {}",
                sum / 8.0
            );
        }
    }
    assert!(matches!(
        h.read_noise(NoiseVolume::Base, 99),
        Err(Error::InvalidTarget { .. })
    ));
}

// ---- compositing invariants ------------------------------------------------------------------

#[test]
fn clear_sky_leaves_the_scene_untouched() {
    let mut settings = small_noise(1);
    settings.weather.clouds.coverage = 0.0;
    let mut h = headless(settings);
    for view in standard_views() {
        let (scene, out) = render_view(&mut h, &view);
        let clouds = h.read_clouds().unwrap();
        assert!(
            clouds.iter().all(|c| c == &[0.0, 0.0, 0.0, 1.0]),
            "{}: L != 0 or T != 1",
            view.name
        );
        for (s, o) in scene.iter().zip(&out) {
            assert_eq!(s.map(f16), *o, "{}", view.name);
        }
    }
}

#[test]
fn snapshot_views_have_no_nan_or_inf_and_show_clouds() {
    let mut h = headless(small_noise(1));
    for view in standard_views() {
        let (scene, out) = render_view(&mut h, &view);
        assert!(
            out.iter().flatten().all(|v| v.is_finite()),
            "{}: non-finite output",
            view.name
        );
        let clouds = h.read_clouds().unwrap();
        assert!(
            clouds.iter().flatten().all(|v| v.is_finite() && *v >= 0.0),
            "{}",
            view.name
        );
        assert!(clouds.iter().all(|c| c[3] <= 1.0), "{}: T > 1", view.name);
        let depth = h.read_cloud_depth().unwrap();
        assert!(
            depth.iter().all(|d| d.is_finite() && *d >= 0.0),
            "{}",
            view.name
        );
        // Every standard view shows some cloud, and changes some pixels.
        let cloudy = clouds.iter().filter(|c| c[3] < 0.9).count();
        assert!(cloudy > 0, "{}: no cloud in view", view.name);
        assert!(
            scene.iter().zip(&out).any(|(s, o)| s.map(f16) != *o),
            "{}",
            view.name
        );
    }
}

#[test]
fn pixels_nearer_than_the_clouds_are_unchanged() {
    let mut settings = small_noise(1);
    settings.weather.clouds.coverage = 1.0; // clouds everywhere above the wall
    let mut h = headless(settings);
    let mut view = standard_views()[0];
    // A wall 400 m away, below the cloud base, covering the lower 60% of the image.
    view.occluder = Occluder::NearWall {
        distance: 400.0,
        fraction: 0.6,
    };
    let scene = view.scene(W, H);
    h.upload_scene(&scene.color, Some(&scene.depth)).unwrap();
    h.render(&view.frame(W, H, 0.0)).unwrap();
    let out = h.read_output().unwrap();
    let mut occluded = 0;
    let mut changed_sky = 0;
    for ((depth, color), got) in scene.depth.iter().zip(&scene.color).zip(&out) {
        if *depth < 1.0 {
            assert_eq!(*got, color.map(f16), "an occluded pixel changed");
            occluded += 1;
        } else if *got != color.map(f16) {
            changed_sky += 1;
        }
    }
    assert!(
        occluded > (W * H) as usize / 2,
        "the wall covers {occluded} pixels"
    );
    assert!(
        changed_sky > 0,
        "clouds must still cover the sky above the wall"
    );
}

#[test]
fn in_place_composite_matches_separate_output() {
    let mut h = headless(quiet(small_noise(1)));
    let view = standard_views()[0];
    let (_, separate) = render_view(&mut h, &view);
    h.set_in_place(true);
    let (_, in_place) = render_view(&mut h, &view);
    for (a, b) in separate.iter().zip(&in_place) {
        for c in 0..4 {
            assert!(
                (a[c] - b[c]).abs() <= 2e-3 * a[c].abs().max(1.0),
                "{a:?} vs {b:?}"
            );
        }
    }
}

/// The depth a `projection` in `convention` writes for the scene depth `d0` of the standard
/// projection `p0` (the same view distance; sky stays the far value).
fn reproject_depth(d0: f32, p0: &Mat4, projection: &Mat4, convention: DepthConvention) -> f32 {
    if d0 == 1.0 {
        return convention.far_value();
    }
    let z = nimbus::frame::linearize_depth(d0, p0, DepthConvention::default());
    let c = *projection * Vec4::new(0.0, 0.0, -z, 1.0);
    c.z / c.w
}

#[test]
fn depth_conventions_see_the_same_clouds() {
    // Coarse probes step past a thin wisp or onto it on a one-ulp change of the ray, which
    // another matrix gives: fine steps only, so the comparison is of depth handling.
    let mut s = quiet(small_noise(1));
    s.march.coarse_then_fine = false;
    let mut h = headless(s);
    let view = standard_views()[4]; // a ridge in front of the clouds
    let scene = view.scene(W, H);
    h.upload_scene(&scene.color, Some(&scene.depth)).unwrap();
    let base = view.frame(W, H, 0.0);
    h.render(&base).unwrap();
    let reference = h.read_output().unwrap();
    assert!(scene.depth.iter().any(|d| *d < 1.0), "the ridge occludes");
    let aspect = W as f32 / H as f32;
    for (projection, depth) in [
        (
            Mat4::perspective_infinite_reverse_rh(view.fov_y, aspect, 1.0),
            DepthConvention {
                reversed_z: true,
                infinite_far: true,
                ..Default::default()
            },
        ),
        (
            Mat4::perspective_infinite_rh(view.fov_y, aspect, 1.0),
            DepthConvention {
                reversed_z: false,
                infinite_far: true,
                ..Default::default()
            },
        ),
        (
            Mat4::perspective_rh_gl(view.fov_y, aspect, 1.0, 400_000.0),
            DepthConvention {
                gl_clip_z: true,
                ..Default::default()
            },
        ),
    ] {
        // The same scene distances, written as this convention's depth buffer holds them.
        let depth_buffer: Vec<f32> = scene
            .depth
            .iter()
            .map(|d| {
                let zero_one = if depth.gl_clip_z {
                    // OpenGL writes window depth: (z_ndc + 1) / 2.
                    (reproject_depth(*d, &base.camera.projection, &projection, depth) + 1.0) * 0.5
                } else {
                    reproject_depth(*d, &base.camera.projection, &projection, depth)
                };
                if *d == 1.0 {
                    depth.far_value()
                } else {
                    zero_one.clamp(0.0, 1.0)
                }
            })
            .collect();
        h.upload_scene(&scene.color, Some(&depth_buffer)).unwrap();
        let mut frame = base;
        frame.camera.projection = projection;
        frame.camera.depth = depth;
        h.render(&frame).unwrap();
        let got = h.read_output().unwrap();
        // Another matrix moves each ray by an ulp, and a march step more or less shifts a sky
        // pixel by a percent or two: judge the image, not single pixels. What a misread depth
        // buffer does is far larger (see the no-depth render below).
        let mean = reference
            .iter()
            .zip(&got)
            .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).abs()).sum::<f32>() / 3.0)
            .sum::<f32>()
            / got.len() as f32;
        let moved = (0..got.len())
            .filter(|&i| (0..3).any(|c| (reference[i][c] - got[i][c]).abs() > 0.02))
            .count();
        assert!(mean < 5e-4, "{depth:?}: mean difference {mean}");
        assert!(
            moved * 200 < got.len(),
            "{depth:?}: {moved} pixels moved by > 0.02"
        );
        // Pixels the ridge hides keep the ridge in every convention: a misread depth would
        // march past it (or stop short) on most of them. Clouds in front of the ridge move
        // as sky pixels do (a step more or less), so single pixels may: judge their share
        // (measured 2 of 1868 in each convention).
        let occluded: Vec<usize> = (0..got.len()).filter(|&i| scene.depth[i] < 1.0).collect();
        let occluded_moved = occluded
            .iter()
            .filter(|&&i| (got[i][0] - reference[i][0]).abs() >= 0.02)
            .count();
        println!(
            "{depth:?}: {occluded_moved} of {} occluded pixels moved by 0.02 or more",
            occluded.len()
        );
        assert!(
            occluded_moved * 200 < occluded.len(),
            "{depth:?}: {occluded_moved} of {} occluded pixels moved",
            occluded.len()
        );
    }
    // The depth buffer does matter here: without it the image differs (so the agreement above
    // is not that of conventions all ignoring depth).
    h.upload_scene(&scene.color, None).unwrap();
    h.render(&base).unwrap();
    let without = h.read_output().unwrap();
    let moved = reference
        .iter()
        .zip(&without)
        .map(|(a, b)| (a[0] - b[0]).abs())
        .fold(0.0f32, f32::max);
    assert!(moved > 0.05, "the ridge's depth changed nothing ({moved})");
}

// ---- the integrator against a closed form ----------------------------------------------------

#[test]
fn homogeneous_slab_matches_closed_form_single_scattering() {
    slab_closed_form(Settings::default().planet.radius);
}

/// The largest planet radius the settings accept still renders right (a flat world).
#[test]
fn the_largest_planet_radius_renders_the_slab_right() {
    slab_closed_form(nimbus::settings::MAX_PLANET_RADIUS);
}

/// The direction of the view ray through the centre of pixel (x, y) of a W × H image, from the
/// camera at `eye` whose inverse view-projection is `inv`.
fn pixel_ray(inv: Mat4, eye: Vec3, x: u32, y: u32) -> Vec3 {
    let ndc_x = (x as f32 + 0.5) / W as f32 * 2.0 - 1.0;
    let ndc_y = 1.0 - (y as f32 + 0.5) / H as f32 * 2.0;
    let p = inv * Vec4::new(ndc_x, ndc_y, 0.0, 1.0);
    (p.truncate() / p.w - eye).normalize()
}

/// A homogeneous debug slab between `bottom` and `top` (m) of extinction `extinction`, albedo 1,
/// lit by the sun alone (ambient off) and marched with its single scattering only: the medium
/// the closed forms of src/lighting/scattering.rs describe.
fn single_scattering_slab(bottom: f32, top: f32, extinction: f32) -> Settings {
    let mut settings = small_noise(1);
    settings.debug_density = DebugDensity::Slab {
        bottom_altitude: bottom,
        top_altitude: top,
        density: 1.0,
    };
    settings.weather.clouds.extinction = extinction;
    settings.weather.clouds.albedo = 1.0;
    settings.lighting.multiple_scattering = MultipleScattering {
        model: MultipleScatteringModel::SingleOnly,
        ..Default::default()
    };
    settings.weather.ambient_top = Vec3::ZERO;
    settings.weather.ambient_bottom = Vec3::ZERO;
    settings
}

fn slab_closed_form(radius: f32) {
    let (bottom, top, extinction) = (1_000.0f32, 1_500.0f32, 0.004f32);
    let mut settings = single_scattering_slab(bottom, top, extinction);
    settings.planet.radius = radius;
    settings.lighting.light_distance = 100_000.0;
    settings.haze.fade_distance = f32::INFINITY;
    settings.march.min_steps = 256;
    settings.march.max_steps = 256;
    settings.march.transmittance_cutoff = 0.0;
    // Every pixel traced in this one frame, on the full grid: the closed form is checked per
    // pixel.
    settings.march.temporal = nimbus::Temporal::OFF;
    settings.march.resolution = nimbus::settings::TraceResolution::Full;
    let phase = settings.lighting.phase;
    let mut h = headless(settings);

    let eye = Vec3::new(0.0, 2.0, 0.0);
    let view = Mat4::look_at_rh(eye, eye + Vec3::Y, Vec3::Z);
    let projection = Mat4::perspective_rh(25f32.to_radians(), W as f32 / H as f32, 1.0, 1e5);
    let sun_dir = Vec3::new(0.3, 0.85, 0.2).normalize();
    let frame = still_frame(view, projection, sun_dir, 10.0);
    h.upload_scene(&vec![[0.0; 4]; (W * H) as usize], None)
        .unwrap();
    h.render(&frame).unwrap();
    let clouds = h.read_clouds().unwrap();

    let inv = (projection * view).inverse();
    let mut worst_l = 0.0f32;
    let mut worst_t = 0.0f32;
    for y in 0..H {
        for x in 0..W {
            let dir = pixel_ray(inv, eye, x, y);
            let (l, t) = slab_single_scattering(
                extinction,
                1.0,
                top - bottom,
                dir.y,
                sun_dir.y,
                phase.eval(sun_dir.dot(dir), 1.0),
                10.0,
            );
            let got = clouds[(y * W + x) as usize];
            worst_l = worst_l.max((got[0] - l).abs() / l);
            worst_t = worst_t.max((got[3] - t).abs());
        }
    }
    assert!(worst_l < 0.02, "radiance off by {:.2}%", worst_l * 100.0);
    assert!(worst_t < 0.005, "transmittance off by {worst_t}");
}

/// Single scattering off the sunlit top of a dense slab (τ = 50), seen from 1.5 km above at
/// the default level's steps (a few of them span the whole skin the light comes from) and
/// transmittance cutoff, against the closed form (`slab_single_reflection`). Held constant over
/// a step, the sun's light at a sample some way into its step stood for the step's front: the
/// image's mean was 0.784 of the closed form and its median pixel 0.677 (the fidelity
/// benchmark's slabs seen from above, `--single`: 0.70 to 0.91 at τ = 50). With the light's
/// fall-off along the step (march_ray.wgsl, `skin_step`): 0.995 and 1.000.
#[test]
fn single_scattering_off_a_dense_slab_seen_from_above_matches_closed_form() {
    let (bottom, top, extinction) = (1_000.0f32, 1_500.0f32, 0.1f32);
    let mut settings = single_scattering_slab(bottom, top, extinction);
    settings.haze.fade_distance = f32::INFINITY;
    settings.march.temporal = nimbus::Temporal::OFF;
    settings.march.resolution = nimbus::settings::TraceResolution::Full;
    let phase = settings.lighting.phase;
    let mut h = headless(settings);

    // Looking down 35° (22.5° to 47.5° over the image) away from a sun 30° high: near
    // backscatter, where the view ray and the sun's light cross the skin alike.
    let eye = Vec3::new(0.0, 3_000.0, 0.0);
    let down = Vec3::new(0.0, -35f32.to_radians().sin(), -35f32.to_radians().cos());
    let view = Mat4::look_at_rh(eye, eye + down, Vec3::Y);
    let projection = Mat4::perspective_rh(25f32.to_radians(), W as f32 / H as f32, 1.0, 1e5);
    let sun_dir = Vec3::new(0.0, 30f32.to_radians().sin(), 30f32.to_radians().cos());
    let frame = still_frame(view, projection, sun_dir, 10.0);
    h.upload_scene(&vec![[0.0; 4]; (W * H) as usize], None)
        .unwrap();
    h.render(&frame).unwrap();
    let clouds = h.read_clouds().unwrap();

    let inv = (projection * view).inverse();
    let (mut got_sum, mut want_sum) = (0.0f64, 0.0f64);
    let mut ratios = Vec::new();
    for y in 0..H {
        for x in 0..W {
            let dir = pixel_ray(inv, eye, x, y);
            let (l, _) = slab_single_reflection(
                extinction,
                1.0,
                top - bottom,
                -dir.y,
                sun_dir.y,
                phase.eval(sun_dir.dot(dir), 1.0),
                10.0,
            );
            let got = clouds[(y * W + x) as usize][0];
            got_sum += got as f64;
            want_sum += l as f64;
            ratios.push(got / l);
        }
    }
    // Each pixel's ray has its own jitter: a sample that falls just above the slab's top in the
    // step that straddles it misses the skin that step holds (about one pixel in a hundred
    // here, as in any one-sample-per-step march; the temporal accumulation averages the jitter),
    // so the image's mean and its median pixel are what is checked.
    ratios.sort_by(f32::total_cmp);
    let mean = got_sum / want_sum;
    let median = ratios[ratios.len() / 2];
    eprintln!("single scattering from above: mean {mean:.4}, median pixel {median:.4}");
    assert!(
        (mean - 1.0).abs() < 0.01,
        "image mean {mean:.4} of the closed form"
    );
    assert!(
        (median - 1.0).abs() < 0.01,
        "median pixel {median:.4} of the closed form"
    );
}

/// The march's multiple-scattering light (the default model less single scattering) through a
/// τ = 5 slab seen from below, against the CPU mirror of the model (src/lighting/diffusion.rs)
/// integrated finely along every pixel's ray: the shader computes what the tested CPU code does.
#[test]
fn delta_eddington_in_the_march_matches_its_cpu_mirror() {
    use nimbus::lighting::diffusion::{beam_light, delta_eddington_source, ColumnSample};
    let (bottom, top, extinction, albedo) = (1_000.0f32, 1_500.0f32, 0.01f32, 0.999f32);
    let mut settings = quiet(small_noise(1));
    settings.debug_density = DebugDensity::Slab {
        bottom_altitude: bottom,
        top_altitude: top,
        density: 1.0,
    };
    settings.weather.clouds.extinction = extinction;
    settings.weather.clouds.albedo = albedo;
    settings.weather.ambient_top = Vec3::ZERO;
    settings.weather.ambient_bottom = Vec3::ZERO;
    settings.lighting.light_distance = 100_000.0;
    settings.haze.fade_distance = f32::INFINITY;
    settings.march.min_steps = 256;
    settings.march.max_steps = 256;
    settings.march.transmittance_cutoff = 0.0;
    let phase = settings.lighting.phase;
    let eye = Vec3::new(0.0, 2.0, 0.0);
    let view = Mat4::look_at_rh(eye, eye + Vec3::new(0.3, 0.8, 0.2), Vec3::Y);
    let projection = Mat4::perspective_rh(40f32.to_radians(), W as f32 / H as f32, 1.0, 1e5);
    let sun_dir = Vec3::new(-0.4, 0.6, 0.1).normalize();
    let frame = still_frame(view, projection, sun_dir, 10.0);
    let render = |model: MultipleScatteringModel| {
        let mut s = settings.clone();
        s.lighting.multiple_scattering.model = model;
        let mut h = headless(s);
        h.upload_scene(&vec![[0.0; 4]; (W * H) as usize], None)
            .unwrap();
        h.render(&frame).unwrap();
        h.read_clouds().unwrap()
    };
    let all = render(MultipleScatteringModel::DeltaEddington);
    let single = render(MultipleScatteringModel::SingleOnly);

    let inv = (projection * view).inverse();
    let mut worst = 0.0f32;
    for y in (0..H).step_by(7) {
        for x in (0..W).step_by(7) {
            let ndc_x = (x as f32 + 0.5) / W as f32 * 2.0 - 1.0;
            let ndc_y = 1.0 - (y as f32 + 0.5) / H as f32 * 2.0;
            let p = inv * Vec4::new(ndc_x, ndc_y, 0.0, 1.0);
            let dir = (p.truncate() / p.w - eye).normalize();
            let cos_theta = sun_dir.dot(dir);
            // ∫ e^{-σt s} σs E ms(s) ds over the path inside the slab (flat-Earth heights: the
            // curvature over these few km moves a height by centimetres).
            let (enter, exit) = ((bottom - eye.y) / dir.y, (top - eye.y) / dir.y);
            let n = 4000;
            let ds = (exit - enter) / n as f32;
            let mut l = 0.0f64;
            for i in 0..n {
                let s = (i as f32 + 0.5) * ds;
                let h = eye.y + (enter + s) * dir.y;
                let column = ColumnSample {
                    tau_sun: extinction * (top - h) / sun_dir.y,
                    tau_above: extinction * (top - h) / sun_dir.y * sun_dir.y.max(0.3),
                    tau_below: extinction * (h - bottom),
                    mu0: sun_dir.y.max(0.3),
                    mu_view: dir.y,
                    cos_theta,
                    tau_across: f32::INFINITY,
                };
                let beam = beam_light(&phase, cos_theta, column.tau_sun, albedo);
                let ms = delta_eddington_source(&column, albedo, &phase, beam);
                l += ((-extinction * s).exp() * albedo * extinction * 10.0 * ms * ds) as f64;
            }
            let i = (y * W + x) as usize;
            let got = all[i][0] - single[i][0];
            let err = (got - l as f32).abs() / l as f32;
            worst = worst.max(err);
        }
    }
    println!(
        "multiple scattering, march vs CPU mirror: worst {:.2}%",
        worst * 100.0
    );
    assert!(worst < 0.02, "off by {:.2}%", worst * 100.0);
}

/// Stopping at the transmittance cutoff adds an estimate of the rest of the ray, so a thick
/// slab seen from below loses almost nothing to an early exit at T = 0.05 (dropping the rest
/// would lose about 5%: the light the remaining weight gathers).
#[test]
fn an_early_exit_estimates_the_rest_of_the_ray() {
    let mut settings = quiet(small_noise(1));
    settings.debug_density = DebugDensity::Slab {
        bottom_altitude: 1_000.0,
        top_altitude: 1_500.0,
        density: 1.0,
    };
    settings.weather.clouds.extinction = 0.04;
    settings.weather.ambient_top = Vec3::ZERO;
    settings.weather.ambient_bottom = Vec3::ZERO;
    settings.haze.fade_distance = f32::INFINITY;
    settings.march.min_steps = 128;
    settings.march.max_steps = 128;
    let eye = Vec3::new(0.0, 2.0, 0.0);
    let frame = still_frame(
        Mat4::look_at_rh(eye, eye + Vec3::new(0.2, 0.9, 0.1), Vec3::Y),
        Mat4::perspective_rh(30f32.to_radians(), W as f32 / H as f32, 1.0, 1e5),
        Vec3::new(0.3, 0.85, 0.2).normalize(),
        10.0,
    );
    let mean = |cutoff: f32| {
        let mut s = settings.clone();
        s.march.transmittance_cutoff = cutoff;
        let mut h = headless(s);
        h.upload_scene(&vec![[0.0; 4]; (W * H) as usize], None)
            .unwrap();
        h.render(&frame).unwrap();
        let img = h.read_clouds().unwrap();
        img.iter().map(|p| p[0] as f64).sum::<f64>() / img.len() as f64
    };
    let (full, early) = (mean(0.0), mean(0.05));
    println!(
        "τ 20 slab, early exit at T 0.05 / no exit: {:.4}",
        early / full
    );
    assert!((early / full - 1.0).abs() < 0.015, "{}", early / full);
}

#[test]
fn homogeneous_sphere_is_round_and_transmits_by_beer_lambert() {
    // Every pixel traced (no temporal reconstruction), no jitter, no early exit.
    let mut settings = quiet(small_noise(1));
    let center = Vec3::new(0.0, 2_000.0, -3_000.0);
    let (radius, sigma) = (500.0f32, 0.002f32);
    settings.debug_density = DebugDensity::Sphere {
        center,
        radius,
        density: 1.0,
    };
    settings.weather.clouds.extinction = sigma;
    settings.march.min_steps = 256;
    settings.march.max_steps = 256;
    settings.march.transmittance_cutoff = 0.0;
    let mut h = headless(settings);
    let eye = Vec3::new(0.0, 2_000.0, 0.0);
    let view = Mat4::look_at_rh(eye, center, Vec3::Y);
    let projection = Mat4::perspective_rh(30f32.to_radians(), W as f32 / H as f32, 1.0, 1e5);
    let frame = FrameInputs {
        camera: Camera {
            view,
            projection,
            depth: DepthConvention::default(),
        },
        sun: Sun::default(),
        time: 0.0,
    };
    h.upload_scene(&vec![[0.0; 4]; (W * H) as usize], None)
        .unwrap();
    h.render(&frame).unwrap();
    let clouds = h.read_clouds().unwrap();
    // Each pixel's own ray against the sphere: T = exp(-σ × chord). Pixels whose ray grazes
    // the rim (within half a pixel's angle) are left out: a step there straddles the edge.
    let inv = (projection * view).inverse();
    let pixel_angle = 30f32.to_radians() / H as f32;
    let distance = (center - eye).length();
    let (mut inside, mut worst) = (0, 0.0f32);
    for y in 0..H {
        for x in 0..W {
            let ndc = Vec4::new(
                (x as f32 + 0.5) / W as f32 * 2.0 - 1.0,
                1.0 - (y as f32 + 0.5) / H as f32 * 2.0,
                0.5,
                1.0,
            );
            let p = inv * ndc;
            let dir = (p.truncate() / p.w - eye).normalize();
            let along = (center - eye).dot(dir);
            let miss = ((center - eye).length_squared() - along * along).sqrt();
            if (miss - radius).abs() < distance * pixel_angle {
                continue;
            }
            let chord = if miss < radius {
                inside += 1;
                2.0 * (radius * radius - miss * miss).sqrt()
            } else {
                0.0
            };
            let t = clouds[(y * W + x) as usize][3];
            worst = worst.max((t - (-sigma * chord).exp()).abs());
        }
    }
    // The disc covers what its angular radius says: asin(r / d) over a pixel angle.
    let disc = std::f32::consts::PI * ((radius / distance).asin() / pixel_angle).powi(2);
    assert!(
        (inside as f32) > 0.8 * disc && (inside as f32) < 1.05 * disc,
        "{inside} pixels inside, the disc holds {disc:.0}"
    );
    assert!(worst < 0.01, "transmittance off the closed form by {worst}");
}

/// The debug sphere (r 1000 m, σt 0.02, the default phase) lit from the side and from behind,
/// against what the path tracer shows of it (docs/fidelity.md): the radial column makes the
/// sun's side brighter than the far side (a vertical column lit both alike), with no seam where
/// its lit end changes sides at the terminator, and the forward-peak light at a back-lit rim is
/// spread (unspread, the rim outshone the disc's middle a hundredfold).
#[test]
fn a_sphere_is_lit_from_its_sun_side_and_its_rim_is_not_a_spike() {
    let center = Vec3::new(0.0, 3_000.0, -4_000.0);
    let settings = quiet(debug_sphere(center));
    let eye = Vec3::new(0.0, 3_000.0, 0.0);
    let render = |sun: Vec3| {
        let mut h = headless(settings.clone());
        h.upload_scene(&vec![[0.0; 4]; (W * H) as usize], None)
            .unwrap();
        let frame = still_frame(
            Mat4::look_at_rh(eye, center, Vec3::Y),
            Mat4::perspective_rh(36f32.to_radians(), W as f32 / H as f32, 1.0, 1e6),
            sun,
            10.0,
        );
        h.render(&frame).unwrap();
        h.read_clouds().unwrap()
    };
    let lum = |p: &[f32; 4]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    // Side-lit (sun +x, the image's right): the middle row across the disc.
    let side = render(Vec3::X);
    let row: Vec<(u32, f32)> = (0..W)
        .map(|x| (x, &side[((H / 2) * W + x) as usize]))
        .filter(|(_, p)| p[3] < 0.5)
        .map(|(x, p)| (x, lum(p)))
        .collect();
    let (first, last) = (row[0].0, row[row.len() - 1].0);
    let width = (last - first) as f32;
    let mean = |from: f32, to: f32| {
        let v: Vec<f32> = row
            .iter()
            .filter(|(x, _)| {
                let u = (*x - first) as f32 / width;
                u >= from && u < to
            })
            .map(|(_, l)| *l)
            .collect();
        v.iter().sum::<f32>() / v.len().max(1) as f32
    };
    let contrast = mean(0.75, 0.95) / mean(0.05, 0.25);
    // The path tracer: 7.9 over the outer halves; the vertical column gave about 1.
    assert!(
        contrast > 3.0 && contrast < 20.0,
        "side-lit sun-side / far-side {contrast}"
    );
    // No seam: inside the disc, neighbours differ smoothly (a one-ended column flipping at
    // the terminator jumped by about 2x between two pixels).
    let worst_step = row
        .windows(2)
        .skip(3)
        .take(row.len().saturating_sub(7))
        .map(|w| (w[1].1 / w[0].1.max(1e-6)).ln().abs())
        .fold(0.0f32, f32::max);
    assert!(
        worst_step < 0.2,
        "largest step between neighbours {:.3} (ln)",
        worst_step
    );
    // Back-lit, the sun 15° above the line of sight: the rim next to the sun against the
    // disc's middle. The path tracer: about 4.5 over the same rows (their mean); the march with
    // its forward-peak light unspread: 12.
    let beyond = (center - eye).normalize();
    let behind = Mat4::from_axis_angle(Vec3::X, 15f32.to_radians()).transform_vector3(beyond);
    let back = render(behind.normalize());
    let column: Vec<f32> = (0..H)
        .map(|y| &back[(y * W + W / 2) as usize])
        .filter(|p| p[3] < 0.5)
        .map(lum)
        .collect();
    // The top eighth of the disc (two of docs/fidelity.md's 64-pixel bands), by its median: the
    // first row's rays graze the surface 1° from the sun, where single scattering alone reaches
    // hundreds (phase about 1100 / sr) on one pixel.
    let mut rim: Vec<f32> = column[..column.len() / 8].to_vec();
    rim.sort_by(f32::total_cmp);
    let top = rim[rim.len() / 2];
    let middle = column[column.len() / 2 - 2..column.len() / 2 + 2]
        .iter()
        .sum::<f32>()
        / 4.0;
    println!(
        "side-lit contrast {contrast:.2}, worst step {worst_step:.3}, back-lit rim / middle {:.2}",
        top / middle
    );
    assert!(top / middle < 9.0, "back-lit rim / middle {}", top / middle);
    assert!(top > middle, "the rim toward the sun is the bright side");
}

// ---- errors, never panics ----------------------------------------------------------------------

#[test]
fn bad_settings_and_frames_are_errors() {
    setup();
    let mut bad = Settings::default();
    bad.weather.layer.bottom_altitude = 9_000.0;
    assert!(matches!(
        Headless::new(bad),
        Err(Error::InvalidSettings { .. })
    ));
    let mut h = headless(small_noise(1));
    let view = standard_views()[0];
    let mut frame = view.frame(W, H, 0.0);
    frame.camera.view.x_axis.x = f32::NAN;
    let e = h.render(&frame).unwrap_err();
    assert!(e.to_string().contains("camera.view"), "{e}");
    let mut frame = view.frame(W, H, 0.0);
    frame.camera.projection = Mat4::ZERO;
    assert!(matches!(h.render(&frame), Err(Error::InvalidFrame { .. })));
    // Still usable afterwards.
    h.render(&view.frame(W, H, 0.0)).unwrap();
    // Bad settings at runtime leave the old ones in place.
    let mut s = small_noise(1);
    s.weather.clouds.density = f32::NAN;
    assert!(h.renderer_mut().set_settings(s).is_err());
    assert!(h
        .renderer_mut()
        .settings()
        .weather
        .clouds
        .density
        .is_finite());
}

#[test]
fn bad_sizes_and_scene_data_are_errors() {
    let mut h = headless(small_noise(1));
    assert!(matches!(h.resize(0, 10), Err(Error::InvalidTarget { .. })));
    assert!(matches!(
        h.resize(10, 100_000),
        Err(Error::InvalidTarget { .. })
    ));
    assert!(matches!(
        h.upload_scene(&[[0.0; 4]; 3], None),
        Err(Error::InvalidTarget {
            target: "scene_color",
            ..
        })
    ));
    let color = vec![[0.0; 4]; (W * H) as usize];
    assert!(matches!(
        h.upload_scene(&color, Some(&[0.5; 7])),
        Err(Error::InvalidTarget {
            target: "scene_depth",
            ..
        })
    ));
    let mut depth = vec![0.5; (W * H) as usize];
    depth[3] = f32::NAN;
    assert!(h.upload_scene(&color, Some(&depth)).is_err());
}

fn texture(
    device: &wgpu::Device,
    w: u32,
    h: u32,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: None,
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

#[test]
fn renderer_refuses_bad_targets_and_turns_wgpu_errors_into_errors() {
    setup();
    let (device, queue, _) = nimbus::headless::create_device().unwrap();
    let mut r = Renderer::new(&device, &queue, small_noise(1)).unwrap();
    use wgpu::TextureFormat as F;
    use wgpu::TextureUsages as U;
    let rw = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING;
    let out = texture(&device, W, H, F::Rgba16Float, rw).create_view(&Default::default());
    let mut enc = device.create_command_encoder(&Default::default());
    let in_place = Targets {
        color: ColorTargets::InPlace(&out),
        depth: None,
        viewport: None,
    };
    assert!(matches!(
        r.encode(&mut enc, &in_place),
        Err(Error::NotPrepared)
    ));
    r.prepare(&standard_views()[0].frame(W, H, 0.0)).unwrap();

    // Unsupported formats.
    let uint = texture(&device, W, H, F::Rgba8Uint, rw).create_view(&Default::default());
    let e = r
        .encode(
            &mut enc,
            &Targets {
                color: ColorTargets::InPlace(&uint),
                depth: None,
                viewport: None,
            },
        )
        .unwrap_err();
    assert!(
        matches!(
            e,
            Error::UnsupportedFormat {
                target: "output",
                ..
            }
        ),
        "{e}"
    );
    let f32out = texture(&device, W, H, F::Rgba32Float, rw).create_view(&Default::default());
    assert!(matches!(
        r.encode(
            &mut enc,
            &Targets {
                color: ColorTargets::InPlace(&f32out),
                depth: None,
                viewport: None,
            }
        ),
        Err(Error::UnsupportedFormat { .. })
    ));
    let bad_depth =
        texture(&device, W, H, F::Rg32Float, U::TEXTURE_BINDING).create_view(&Default::default());
    assert!(matches!(
        r.encode(
            &mut enc,
            &Targets {
                color: ColorTargets::InPlace(&out),
                depth: Some(&bad_depth),
                viewport: None,
            }
        ),
        Err(Error::UnsupportedFormat {
            target: "scene_depth",
            ..
        })
    ));
    // Mismatched sizes and missing usage.
    let small = texture(&device, W / 2, H, F::Depth32Float, U::TEXTURE_BINDING)
        .create_view(&Default::default());
    let e = r
        .encode(
            &mut enc,
            &Targets {
                color: ColorTargets::InPlace(&out),
                depth: Some(&small),
                viewport: None,
            },
        )
        .unwrap_err();
    assert!(e.to_string().contains("80x90"), "{e}");
    let no_render =
        texture(&device, W, H, F::Rgba16Float, U::TEXTURE_BINDING).create_view(&Default::default());
    assert!(matches!(
        r.encode(
            &mut enc,
            &Targets {
                color: ColorTargets::InPlace(&no_render),
                depth: None,
                viewport: None,
            }
        ),
        Err(Error::InvalidTarget {
            target: "output",
            ..
        })
    ));
    assert!(matches!(
        r.encode(
            &mut enc,
            &Targets {
                color: ColorTargets::Separate {
                    scene: &out,
                    output: &out
                },
                depth: None,
                viewport: None,
            }
        ),
        Err(Error::InvalidTarget { .. })
    ));
    // A depth-stencil view that includes the stencil aspect passes our checks but not wgpu's
    // binding validation: that must come back as Error::Gpu, not a panic.
    let ds = texture(&device, W, H, F::Depth24PlusStencil8, U::TEXTURE_BINDING)
        .create_view(&Default::default());
    let e = r
        .encode(
            &mut enc,
            &Targets {
                color: ColorTargets::InPlace(&out),
                depth: Some(&ds),
                viewport: None,
            },
        )
        .unwrap_err();
    assert!(matches!(e, Error::Gpu(_)), "{e}");

    // The renderer is still usable, and pipelines are cached per output format.
    r.prepare(&standard_views()[0].frame(W, H, 0.0)).unwrap();
    let mut enc = device.create_command_encoder(&Default::default());
    r.encode(&mut enc, &in_place).unwrap();
    let count = r.cached_pipeline_count();
    r.prepare(&standard_views()[0].frame(W, H, 1.0)).unwrap();
    r.encode(&mut enc, &in_place).unwrap();
    assert_eq!(
        r.cached_pipeline_count(),
        count,
        "same format must reuse its pipeline"
    );
    let rgba8 = texture(&device, W, H, F::Rgba8UnormSrgb, rw).create_view(&Default::default());
    r.prepare(&standard_views()[0].frame(W, H, 2.0)).unwrap();
    r.encode(
        &mut enc,
        &Targets {
            color: ColorTargets::InPlace(&rgba8),
            depth: None,
            viewport: None,
        },
    )
    .unwrap();
    assert_eq!(r.cached_pipeline_count(), count + 1);
    queue.submit([enc.finish()]);
    device.poll(wgpu::PollType::wait_indefinitely()).unwrap();

    // A non-invertible camera is refused at prepare and encode then refuses stale state.
    let mut frame = standard_views()[0].frame(W, H, 0.0);
    frame.camera.view = Mat4::ZERO;
    assert!(r.prepare(&frame).is_err());
    let mut enc = device.create_command_encoder(&Default::default());
    assert!(matches!(
        r.encode(&mut enc, &in_place),
        Err(Error::NotPrepared)
    ));
}

/// The march's pipeline is specialised per medium and shadow-map light (a software rasteriser
/// pays for untaken branches): a settings change that asks for another specialisation builds
/// it once, frames never do, and going back reuses the first. That each draws what its
/// settings ask is what the debug-media and shadow-map tests check.
#[test]
fn march_specialisations_are_built_per_setting_not_per_frame() {
    let settings = small_noise(1);
    let mut h = headless(settings.clone());
    let frame = standard_views()[0].frame(W, H, 0.0);
    let frames = |h: &mut Headless, s: &Settings| {
        h.renderer_mut().set_settings(s.clone()).unwrap();
        for _ in 0..3 {
            h.render(&frame).unwrap();
        }
        h.renderer().cached_pipeline_count()
    };
    let base = frames(&mut h, &settings);
    assert_eq!(frames(&mut h, &settings), base, "frames built a pipeline");
    let mut slab = settings.clone();
    slab.debug_density = DebugDensity::Slab {
        bottom_altitude: 1_000.0,
        top_altitude: 1_500.0,
        density: 1.0,
    };
    assert_eq!(frames(&mut h, &slab), base + 1, "the slab's march");
    assert_eq!(frames(&mut h, &slab), base + 1);
    assert_eq!(
        frames(&mut h, &settings),
        base + 1,
        "the noise model's again"
    );
    let mut shadow_light = settings.clone();
    shadow_light.shadows.enabled = true;
    shadow_light.shadows.march_light = true;
    assert_eq!(
        frames(&mut h, &shadow_light),
        base + 2,
        "the shadow-map light's"
    );
    // The map on, its light off: the pipeline without the shadow-map light serves.
    shadow_light.shadows.march_light = false;
    assert_eq!(frames(&mut h, &shadow_light), base + 2);
}

#[test]
fn the_dual_lobe_phase_model_renders_and_changes_the_light() {
    let view = standard_views()[1]; // low sun: the phase function matters most
    let render = |phase| {
        let mut s = quiet(small_noise(1));
        s.lighting.phase = phase;
        let mut h = headless(s);
        render_view(&mut h, &view).1
    };
    let default = render(PhaseModel::default());
    let dual = render(PhaseModel::DualLobeHg {
        g_forward: 0.8,
        g_backward: -0.3,
        forward_weight: 0.7,
    });
    assert!(dual.iter().flatten().all(|v| v.is_finite()));
    let diff = default
        .iter()
        .zip(&dual)
        .map(|(a, b)| (a[0] - b[0]).abs())
        .sum::<f32>()
        / dual.len() as f32;
    assert!(
        diff > 1e-4,
        "the phase model did not reach the shader (mean change {diff})"
    );
}

/// Clouds in the planet's shadow (the sun 10° below the horizon) keep their sky light. The
/// ambient is shared between `ambient_top` and `ambient_bottom` by the sample's column; the
/// column's top is the light march's depth projected on the vertical, which the planet's
/// shadow makes 1e4: unbounded, the share fell to 0 and the clouds lost the sky above. With
/// the sun's light off, the clouds' ambient light may not depend much on where the sun is:
/// measured 0.57 times the sunlit-sky value in the shadow (the column's top is then the bound,
/// the column as dense as the sample up to the layer's top), 0.0045 times before the bound.
#[test]
fn clouds_in_the_planets_shadow_keep_their_sky_light() {
    let render = |elevation_deg: f32| {
        let mut s = quiet(small_noise(1));
        s.weather.ambient_top = Vec3::splat(0.5);
        s.weather.ambient_bottom = Vec3::ZERO;
        s.haze.fade_distance = f32::INFINITY;
        let mut h = headless(s);
        let eye = Vec3::new(0.0, 2.0, 0.0);
        let view = Mat4::look_at_rh(eye, eye + Vec3::new(0.0, 1.0, 0.6), Vec3::Z);
        let projection = Mat4::perspective_rh(70f32.to_radians(), W as f32 / H as f32, 1.0, 1e6);
        let e = elevation_deg.to_radians();
        let frame = still_frame(view, projection, Vec3::new(e.cos(), e.sin(), 0.0), 0.0);
        h.upload_scene(&vec![[0.0; 4]; (W * H) as usize], None)
            .unwrap();
        h.render(&frame).unwrap();
        let clouds = h.read_clouds().unwrap();
        // Radiance per unit opacity over the cloudy pixels.
        let (l, a) = clouds
            .iter()
            .filter(|c| c[3] < 0.5)
            .fold((0.0f32, 0.0f32), |(l, a), c| (l + c[1], a + 1.0 - c[3]));
        assert!(a > 10.0, "the view shows clouds (opacity {a})");
        l / a
    };
    let sunlit_sky = render(30.0);
    let shadowed = render(-10.0);
    assert!(
        sunlit_sky > 0.05,
        "ambient light of the clouds: {sunlit_sky}"
    );
    assert!(
        shadowed > 0.3 * sunlit_sky,
        "in the planet's shadow {shadowed}, under a sunlit sky {sunlit_sky}"
    );
}

// ---- reduced-resolution tracing ----------------------------------------------------------------

/// The bilinear interpolation of a `gw`×`gh` grid at output pixel (x, y) of a grid `divisor`
/// times finer: texel centres at (i + 0.5) × divisor output pixels, edges clamped.
fn bilinear_upsample(
    grid: &[[f32; 4]],
    gw: u32,
    gh: u32,
    divisor: u32,
    x: u32,
    y: u32,
) -> [f32; 4] {
    let axis = |p: u32, n: u32| {
        let q = (p as f32 + 0.5) / divisor as f32 - 0.5;
        let lo = q.floor();
        let f = q - lo;
        let at = |i: f32| (i.max(0.0) as u32).min(n - 1);
        (at(lo), at(lo + 1.0), f)
    };
    let (x0, x1, fx) = axis(x, gw);
    let (y0, y1, fy) = axis(y, gh);
    let texel = |i: u32, j: u32| grid[(j * gw + i) as usize];
    let mut out = [0.0f32; 4];
    for (c, v) in out.iter_mut().enumerate() {
        let top = texel(x0, y0)[c] * (1.0 - fx) + texel(x1, y0)[c] * fx;
        let bottom = texel(x0, y1)[c] * (1.0 - fx) + texel(x1, y1)[c] * fx;
        *v = top * (1.0 - fy) + bottom * fy;
    }
    out
}

#[test]
fn without_scene_depth_the_upsample_is_the_grids_bilinear_interpolation() {
    // With no depth to tell surfaces apart, every sample is trusted by its bilinear weight
    // alone: the composite of a reduced grid is exactly scene × T + L of the interpolated
    // (L, T), up to the 1e-4 floor the depth-aware weights add and the f16 targets. An oracle
    // for the upsample that no retuning of the clouds moves (the distance from the full-
    // resolution march is the grid's own loss: `reduced_resolution_keeps_occluders_exact_...`).
    use nimbus::settings::TraceResolution;
    let view = standard_views()[0];
    let scene = view.scene(W, H);
    for (resolution, divisor) in [(TraceResolution::Half, 2), (TraceResolution::Quarter, 4)] {
        let mut settings = common::measured_shape(quiet(small_noise(1)));
        settings.march.resolution = resolution;
        let mut h = headless(settings);
        h.upload_scene(&scene.color, None).unwrap();
        h.render(&view.frame(W, H, 0.0)).unwrap();
        let (gw, gh) = (W.div_ceil(divisor), H.div_ceil(divisor));
        let grid = h.read_clouds().unwrap();
        assert_eq!(grid.len() as u32, gw * gh, "{resolution:?}");
        let out = h.read_output().unwrap();
        let cloudy = grid.iter().filter(|v| v[3] < 0.9).count();
        assert!(
            cloudy * 5 > grid.len(),
            "{resolution:?}: {cloudy} cloudy texels"
        );
        let mut worst = 0.0f32;
        for y in 0..H {
            for x in 0..W {
                let i = (y * W + x) as usize;
                let lt = bilinear_upsample(&grid, gw, gh, divisor, x, y);
                for c in 0..3 {
                    let want = f16(scene.color[i][c]) * lt[3] + lt[c];
                    let err = (out[i][c] - want).abs() / want.abs().max(1.0);
                    worst = worst.max(err);
                }
            }
        }
        println!("{resolution:?}: worst relative difference from bilinear {worst:.2e}");
        assert!(
            worst < 3e-3,
            "{resolution:?}: {worst} from the bilinear upsample"
        );
    }
}

#[test]
fn reduced_resolution_keeps_occluders_exact_and_stays_close_to_full() {
    use nimbus::settings::TraceResolution;
    let render = |resolution| {
        let mut settings = common::measured_shape(quiet(small_noise(1)));
        settings.march.resolution = resolution;
        let mut h = headless(settings);
        let mut view = standard_views()[4]; // mountains: a ridge in front of the clouds
        view.occluder = Occluder::NearWall {
            distance: 400.0,
            fraction: 0.3,
        };
        let scene = view.scene(W, H);
        h.upload_scene(&scene.color, Some(&scene.depth)).unwrap();
        h.render(&view.frame(W, H, 0.0)).unwrap();
        (scene, h.read_output().unwrap())
    };
    let (scene, full) = render(TraceResolution::Full);
    for resolution in [TraceResolution::Half, TraceResolution::Quarter] {
        let (_, out) = render(resolution);
        assert!(
            out.iter().flatten().all(|v| v.is_finite()),
            "{resolution:?}: NaN"
        );
        let mut diff = 0.0f64;
        for ((got, want), (depth, color)) in out
            .iter()
            .zip(&full)
            .zip(scene.depth.iter().zip(&scene.color))
        {
            if *depth < 1.0 {
                // The wall is 400 m away, in front of every cloud: exactly the scene.
                assert_eq!(
                    *got,
                    color.map(f16),
                    "{resolution:?}: an occluded pixel changed"
                );
            }
            diff += (0..3).map(|c| (got[c] - want[c]).abs() as f64).sum::<f64>() / 3.0;
        }
        // Relative to the picture's mean level: the grid's loss scales with the clouds'
        // contrast, which a change of lighting moves with nothing in the machinery changing
        // (the walls lit by a low sun, `lit_face_cosine`, 2026-12-07: half 0.069 -> 0.084,
        // quarter 0.093 -> 0.112 of the level, 0.021 -> 0.028 and 0.029 -> 0.038 absolute).
        let mean = diff / full.len() as f64;
        let level = common::mean_level(&full);
        let budget = match resolution {
            TraceResolution::Half => 0.09,
            _ => 0.12,
        };
        println!("{resolution:?}: mean difference {mean:.4}, mean level {level:.4}");
        assert!(
            mean < budget * level,
            "{resolution:?}: mean difference from full resolution {mean}, {} of the level",
            mean / level
        );
    }
}
