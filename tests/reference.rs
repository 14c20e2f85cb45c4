//! The path-traced reference against closed forms, on homogeneous debug slabs:
//! - first-order scattering alone equals the slab's single-scattering closed form;
//! - a thin slab's all-order radiance is its single scattering plus a little;
//! - an albedo-1 slab over black ground conserves energy: the reflected flux above it, the
//!   diffuse and the direct transmitted flux below it (each hemisphere integrated from six
//!   90° camera faces) add up to the incident flux;
//! - bad sizes and reads before any sample are errors;
//! - the march's default multiple-scattering model (delta-Eddington columns) against the path
//!   tracer through a thick slab, and its answer to albedo.

mod common;
use common::{debug_sphere, setup, small_noise};

use glam::{Mat4, Vec3, Vec4};
use nimbus::lighting::phase::PhaseModel;
use nimbus::lighting::scattering::slab_single_scattering;
use nimbus::settings::{MultipleScatteringModel, TraceResolution};
use nimbus::{
    Camera, DebugDensity, DepthConvention, FrameInputs, Headless, Orders, PathTracer, Renderer,
    Settings, Sun,
};

const BOTTOM: f32 = 1_000.0;
const TOP: f32 = 1_500.0;

fn slab_settings(extinction: f32, albedo: f32) -> Settings {
    let mut s = small_noise(1);
    s.debug_density = DebugDensity::Slab {
        bottom_altitude: BOTTOM,
        top_altitude: TOP,
        density: 1.0,
    };
    s.weather.clouds.extinction = extinction;
    s.weather.clouds.albedo = albedo;
    s.weather.ambient_top = Vec3::ZERO;
    s.weather.ambient_bottom = Vec3::ZERO;
    s.haze.fade_distance = f32::INFINITY;
    s
}

fn sun_dir() -> Vec3 {
    Vec3::new(0.3, 0.85, 0.2).normalize()
}

fn frame(eye: Vec3, forward: Vec3, up: Vec3, fov_deg: f32, aspect: f32) -> FrameInputs {
    FrameInputs {
        camera: Camera {
            view: Mat4::look_at_rh(eye, eye + forward, up),
            projection: Mat4::perspective_rh(fov_deg.to_radians(), aspect, 1.0, 1e6),
            depth: DepthConvention::default(),
        },
        sun: Sun {
            direction: sun_dir(),
            color: Vec3::ONE,
            illuminance: 10.0,
        },
        time: 0.0,
    }
}

/// The direction through the centre of pixel (x, y) of a w × h image of `f`.
fn pixel_dir(f: &FrameInputs, x: u32, y: u32, w: u32, h: u32) -> Vec3 {
    let inv = (f.camera.projection * f.camera.view).inverse();
    let eye = f.camera.view.inverse().w_axis.truncate();
    let ndc_x = (x as f32 + 0.5) / w as f32 * 2.0 - 1.0;
    let ndc_y = 1.0 - (y as f32 + 0.5) / h as f32 * 2.0;
    let p = inv * Vec4::new(ndc_x, ndc_y, 0.0, 1.0);
    (p.truncate() / p.w - eye).normalize()
}

fn trace(
    r: &Renderer,
    f: &FrameInputs,
    size: (u32, u32),
    orders: Orders,
    spp: u32,
) -> Vec<[f32; 4]> {
    let mut pt = PathTracer::new(r, size.0, size.1, orders).unwrap();
    pt.accumulate(r, f, spp).unwrap();
    assert_eq!(pt.samples(), spp);
    pt.read(r).unwrap()
}

fn renderer(settings: Settings) -> Renderer {
    setup();
    let (device, queue, _) = nimbus::headless::create_device().unwrap();
    Renderer::new(&device, &queue, settings).unwrap()
}

/// Camera 2 m above the ground, looking up into the slab (as tests/gpu.rs does for the march).
fn below_view(w: u32, h: u32) -> FrameInputs {
    frame(
        Vec3::new(0.0, 2.0, 0.0),
        Vec3::Y,
        Vec3::Z,
        25.0,
        w as f32 / h as f32,
    )
}

#[test]
fn single_scattering_matches_the_slab_closed_form() {
    let (w, h, extinction) = (32, 18, 0.004f32);
    let settings = slab_settings(extinction, 1.0);
    let phase = settings.lighting.phase;
    let r = renderer(settings);
    let f = below_view(w, h);
    let spp = 1024;
    let got = trace(&r, &f, (w, h), Orders::SingleOnly, spp);
    // Per pixel the estimate is noisy (ratio-tracked transmittance): compare blocks of 4 x 3
    // pixels, and the whole image.
    let (bw, bh) = (4, 3);
    let mut blocks = vec![(0.0f64, 0.0f64, 0.0f64, 0.0f64); ((w / bw) * (h / bh)) as usize];
    for y in 0..h {
        for x in 0..w {
            let dir = pixel_dir(&f, x, y, w, h);
            let (l, t) = slab_single_scattering(
                extinction,
                1.0,
                TOP - BOTTOM,
                dir.y,
                sun_dir().y,
                phase.eval(sun_dir().dot(dir), 1.0),
                10.0,
            );
            let p = got[(y * w + x) as usize];
            let b = &mut blocks[((y / bh) * (w / bw) + x / bw) as usize];
            b.0 += p[0] as f64;
            b.1 += l as f64;
            b.2 += p[3] as f64;
            b.3 += t as f64;
        }
    }
    let ratio = blocks.iter().map(|b| b.0).sum::<f64>() / blocks.iter().map(|b| b.1).sum::<f64>();
    let worst = blocks
        .iter()
        .map(|b| (b.0 / b.1 - 1.0).abs())
        .fold(0.0, f64::max);
    let worst_t = blocks
        .iter()
        .map(|b| (b.2 - b.3).abs() / (bw * bh) as f64)
        .fold(0.0, f64::max);
    println!(
        "single scattering, path traced / closed form: {ratio:.4} over the image; worst 4x3 block {:.2}%, worst block T {worst_t:.4}",
        worst * 100.0
    );
    assert!((ratio - 1.0).abs() < 0.01, "image mean off by {ratio}");
    assert!(worst < 0.05, "a block is off by {:.1}%", worst * 100.0);
    assert!(worst_t < 0.01, "camera-ray transmittance off by {worst_t}");
}

#[test]
fn a_thin_slab_is_mostly_single_scattering() {
    let (w, h) = (16, 9);
    // tau = 0.05 through the slab's thickness.
    let r = renderer(slab_settings(0.0001, 1.0));
    let f = below_view(w, h);
    let mean = |img: &[[f32; 4]]| img.iter().map(|p| p[0] as f64).sum::<f64>() / img.len() as f64;
    let single = mean(&trace(&r, &f, (w, h), Orders::SingleOnly, 512));
    let all = mean(&trace(&r, &f, (w, h), Orders::All, 512));
    let extra = all / single - 1.0;
    println!(
        "thin slab (tau 0.05): all orders / single = {:.4}",
        all / single
    );
    assert!(
        extra > -0.01 && extra < 0.08,
        "all orders add {:.1}%",
        extra * 100.0
    );
}

/// The flux through a horizontal plane at `eye` from radiance arriving from below
/// (`from_below`) or from above, integrated over six 90° faces of `n` × `n` pixels.
fn hemisphere_flux(r: &Renderer, eye: Vec3, n: u32, spp: u32, from_below: bool) -> f64 {
    let faces = [
        (Vec3::X, Vec3::Y),
        (Vec3::NEG_X, Vec3::Y),
        (Vec3::Z, Vec3::Y),
        (Vec3::NEG_Z, Vec3::Y),
        (Vec3::Y, Vec3::Z),
        (Vec3::NEG_Y, Vec3::Z),
    ];
    let mut flux = 0.0f64;
    for (forward, up) in faces {
        let f = frame(eye, forward, up, 90.0, 1.0);
        let img = trace(r, &f, (n, n), Orders::All, spp);
        for y in 0..n {
            for x in 0..n {
                let d = pixel_dir(&f, x, y, n, n);
                // Looking down (d.y < 0) sees light travelling up, and the reverse.
                if (d.y < 0.0) != from_below {
                    continue;
                }
                let (u, v) = (
                    (x as f64 + 0.5) / n as f64 * 2.0 - 1.0,
                    (y as f64 + 0.5) / n as f64 * 2.0 - 1.0,
                );
                let solid_angle = (2.0 / n as f64).powi(2) / (1.0 + u * u + v * v).powf(1.5);
                flux += img[(y * n + x) as usize][0] as f64 * d.y.abs() as f64 * solid_angle;
            }
        }
    }
    flux
}

#[test]
fn an_albedo_one_slab_conserves_energy() {
    // tau = 2 through the slab's thickness, a moderately forward phase (so the faces' pixel
    // grid resolves the transmitted aureole).
    let extinction = 0.004f32;
    let mut settings = slab_settings(extinction, 1.0);
    settings.lighting.phase = PhaseModel::DualLobeHg {
        g_forward: 0.6,
        g_backward: -0.2,
        forward_weight: 0.8,
    };
    let r = renderer(settings);
    let (n, spp) = (24, 48);
    let reflected = hemisphere_flux(&r, Vec3::new(0.0, TOP + 50.0, 0.0), n, spp, true);
    let diffuse = hemisphere_flux(&r, Vec3::new(0.0, BOTTOM - 50.0, 0.0), n, spp, false);
    let mu0 = sun_dir().y as f64;
    let incident = 10.0 * mu0;
    let direct = incident * (-(extinction as f64) * (TOP - BOTTOM) as f64 / mu0).exp();
    let total = (reflected + diffuse + direct) / incident;
    println!(
        "albedo-1 slab (tau 2): reflected {:.4}, diffuse transmitted {:.4}, direct {:.4} of the incident flux; sum {total:.4}",
        reflected / incident,
        diffuse / incident,
        direct / incident
    );
    assert!((total - 1.0).abs() < 0.03, "energy: {total}");
    assert!(reflected > 0.05 * incident && diffuse > 0.2 * incident);
}

#[test]
fn bad_sizes_and_early_reads_are_errors() {
    let r = renderer(slab_settings(0.004, 1.0));
    for (w, h) in [(0, 10), (10, 0), (5000, 10)] {
        let e = PathTracer::new(&r, w, h, Orders::All)
            .err()
            .expect("refused");
        assert!(e.to_string().contains("reference"), "{e}");
    }
    let mut pt = PathTracer::new(&r, 4, 4, Orders::All).unwrap();
    assert!(pt.read(&r).is_err());
    // A sample count past u32::MAX in all is refused before any work, and the samples
    // already accumulated stay as they were.
    let f = below_view(4, 4);
    pt.accumulate(&r, &f, 2).unwrap();
    let before = pt.read(&r).unwrap();
    let e = pt.accumulate(&r, &f, u32::MAX).expect_err("refused");
    assert!(e.to_string().contains("reset first"), "{e}");
    assert_eq!(pt.samples(), 2);
    assert_eq!(pt.read(&r).unwrap(), before);
}

/// Seed s, 65,536 dispatches in, used to key the hash exactly as seed s + 1 at its start: two
/// halves traced that long drew the same samples. And a still resumed at a saved sequence
/// position draws the samples that come next, not the first ones again.
#[test]
fn seeds_draw_disjoint_sequences_and_a_resumed_still_goes_on() {
    let r = renderer(slab_settings(0.004, 1.0));
    let (w, h) = (8, 8);
    let f = below_view(w, h);
    let image = |seed: u16, position: u64, spp: u32| {
        let mut pt = PathTracer::new(&r, w, h, Orders::All)
            .unwrap()
            .with_seed(seed)
            .with_sequence_position(position);
        pt.accumulate(&r, &f, spp).unwrap();
        // Up to 4 samples per dispatch, one position per dispatch.
        assert_eq!(pt.sequence_position(), position + spp.div_ceil(4) as u64);
        pt.read(&r).unwrap()
    };
    let differing =
        |a: &[[f32; 4]], b: &[[f32; 4]]| a.iter().zip(b).filter(|(p, q)| p != q).count();
    let next_seed = image(3, 0, 4);
    assert_eq!(
        image(3, 0, 4),
        next_seed,
        "the same seed and position, the same samples"
    );
    for (seed, position) in [(2, 1u64 << 16), (1, 2 << 16), (3, 1 << 16)] {
        let n = differing(&image(seed, position, 4), &next_seed);
        assert!(
            n >= 60,
            "seed {seed} at {position}: only {n} of 64 pixels differ"
        );
    }
    // Resuming: 4 samples from the start and 4 from position 1 are the 8 from the start.
    let whole = image(9, 0, 8);
    let (first, second) = (image(9, 0, 4), image(9, 1, 4));
    for ((a, b), c) in first.iter().zip(&second).zip(&whole) {
        for k in 0..4 {
            let halves = 0.5 * (a[k] + b[k]);
            assert!(
                (halves - c[k]).abs() <= 1e-5 * c[k].abs().max(1e-3),
                "{halves} vs {}",
                c[k]
            );
        }
    }
    // A reset keeps the position: the samples after it are new ones.
    let mut pt = PathTracer::new(&r, w, h, Orders::All).unwrap().with_seed(9);
    pt.accumulate(&r, &f, 4).unwrap();
    pt.reset();
    pt.accumulate(&r, &f, 4).unwrap();
    assert_eq!(pt.read(&r).unwrap(), second);
}

fn mean_luminance(img: &[[f32; 4]]) -> f64 {
    img.iter()
        .map(|p| (0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]) as f64)
        .sum::<f64>()
        / img.len() as f64
}

/// The march's converged image of `f` (temporal accumulation of a still view).
fn march(settings: &Settings, f: &FrameInputs, size: (u32, u32)) -> Vec<[f32; 4]> {
    setup();
    let mut h = Headless::new(settings.clone()).unwrap();
    h.resize(size.0, size.1).unwrap();
    h.upload_scene(&vec![[0.0; 4]; (size.0 * size.1) as usize], None)
        .unwrap();
    for _ in 0..40 {
        h.render(f).unwrap();
    }
    h.read_clouds().unwrap()
}

/// The τ = 20 slab (σt 0.04 over 500 m) with an HG 0.8 phase, albedo 0.999.
fn thick_hg_slab() -> Settings {
    let mut s = slab_settings(0.04, 0.999);
    s.lighting.phase = PhaseModel::DualLobeHg {
        g_forward: 0.8,
        g_backward: 0.0,
        forward_weight: 1.0,
    };
    s
}

#[test]
fn the_default_march_carries_light_through_a_thick_slab() {
    // τ = 20 (σt 0.04 over 500 m), HG 0.8, seen from below looking up 55° toward the sun's
    // side: the single-scattered light is e^-23 of the sun, everything seen is diffuse.
    let size = (16, 9);
    let s = thick_hg_slab();
    let eye = Vec3::new(0.0, 2.0, 0.0);
    let forward = Vec3::new(0.3, 0.8, 0.2).normalize();
    let f = frame(eye, forward, Vec3::Y, 30.0, 16.0 / 9.0);
    let r = renderer(s.clone());
    let traced = mean_luminance(&trace(&r, &f, size, Orders::All, 256));
    let model = mean_luminance(&march(&s, &f, size));
    let mut octave_settings = s.clone();
    octave_settings.lighting.multiple_scattering.model = MultipleScatteringModel::Octaves;
    let octaves = mean_luminance(&march(&octave_settings, &f, size));
    println!(
        "τ 20 slab from below: march / path traced {:.3} (octaves {:.2e})",
        model / traced,
        octaves / traced
    );
    // Issue 11's target: within 20% on every slab view.
    assert!((model / traced - 1.0).abs() < 0.2, "{}", model / traced);
    // The octaves it replaced are hundreds of times too dark here.
    assert!(octaves / traced < 0.05, "{}", octaves / traced);
}

/// The direction at `elevation_deg` above the horizontal and `azimuth_deg` from -z toward +x.
fn toward(elevation_deg: f32, azimuth_deg: f32) -> Vec3 {
    let (e, a) = (elevation_deg.to_radians(), azimuth_deg.to_radians());
    Vec3::new(e.cos() * a.sin(), e.sin(), -e.cos() * a.cos())
}

/// 1.5 km above the slab's top, looking down at `view_el` (negative) degrees, at `azimuth`
/// from the sun's (the sun 30° high), a 20° field at 16:9.
fn from_above(view_el: f32, azimuth: f32) -> FrameInputs {
    let up = if view_el <= -89.0 { Vec3::Z } else { Vec3::Y };
    let eye = Vec3::new(0.0, TOP + 1_500.0, 0.0);
    let mut f = frame(eye, toward(view_el, azimuth), up, 20.0, 16.0 / 9.0);
    f.sun.direction = toward(30.0, 0.0);
    f
}

#[test]
fn a_deck_seen_from_above_toward_the_sun_is_lit_through_its_whole_depth() {
    // τ = 20 (σt 0.04 over 500 m), HG 0.8, sun 30° high, seen from 1.5 km above the top looking
    // down 20° toward the sun: the view ray comes in through the lit top. The rule that bounds
    // the column below by the view ray's depth when looking toward the sun (a cloud's dark
    // side) read this deck as thin: 0.34 of the path tracer (docs/fidelity.md, 32x18). Without
    // it 0.54: what was left was the forward sheen of the first ten orders, which the P1 field
    // (no azimuth) does not hold. With the reflected light in a lobe around the sun
    // (reflected_source in src/lighting/diffusion.rs) 1.115.
    let size = (16, 9);
    let s = thick_hg_slab();
    let f = from_above(-20.0, 0.0);
    let r = renderer(s.clone());
    let traced = mean_luminance(&trace(&r, &f, size, Orders::All, 256));
    let model = mean_luminance(&march(&s, &f, size));
    println!(
        "τ 20 slab from above, 20° toward the sun: march / path traced {:.3}",
        model / traced
    );
    assert!(model / traced > 0.8, "{}", model / traced);
    // Nor brighter than the light that is there.
    assert!(model / traced < 1.2, "{}", model / traced);
}

#[test]
fn a_thicker_deck_reflects_no_less_light() {
    // Seen from above, a slab of optical depth τ1 + τ2 reflects every path that τ1 alone does
    // (the top τ1 is the same medium) plus those that come back from below it: its reflected
    // radiance can only grow with the depth, for any phase and albedo (the ground under it is
    // black). The march's columns must keep that order in every view from above, from the
    // zenith to 20° over the deck toward and away from the sun.
    let size = (16, 9);
    for (view_el, azimuth) in [
        (-90f32, 0.0f32),
        (-55.0, 0.0),
        (-20.0, 0.0),
        (-55.0, 180.0),
        (-20.0, 180.0),
    ] {
        let f = from_above(view_el, azimuth);
        let mut last = 0.0;
        for tau in [0.5f32, 2.0, 8.0, 32.0] {
            let mut s = slab_settings(tau / (TOP - BOTTOM), 0.999);
            s.lighting.phase = PhaseModel::default();
            let seen = mean_luminance(&march(&s, &f, size));
            println!("from above, elevation {view_el}°, azimuth {azimuth}°, τ {tau}: {seen:.4}");
            assert!(seen >= last * 0.99, "τ {tau}: {seen} after {last}");
            last = seen;
        }
    }
}

#[test]
fn the_default_march_answers_albedo_as_the_path_tracer_does() {
    // τ = 50 from below: from ω = 0.999 to 1 the diffuse light rises by several percent (the
    // path tracer's answer, same seed for both so the noise mostly cancels in the ratio).
    let size = (16, 9);
    let f = below_view(size.0, size.1);
    let (mut pt, mut mm) = (Vec::new(), Vec::new());
    for albedo in [0.999f32, 1.0] {
        let mut s = slab_settings(0.1, albedo);
        s.lighting.phase = PhaseModel::DualLobeHg {
            g_forward: 0.8,
            g_backward: 0.0,
            forward_weight: 1.0,
        };
        let r = renderer(s.clone());
        pt.push(mean_luminance(&trace(&r, &f, size, Orders::All, 128)));
        mm.push(mean_luminance(&march(&s, &f, size)));
    }
    let (pt_rise, march_rise) = (pt[1] / pt[0], mm[1] / mm[0]);
    println!("τ 50, albedo 0.999 -> 1: path traced x{pt_rise:.3}, march x{march_rise:.3}");
    assert!(
        pt_rise > 1.02,
        "the reference itself should rise: {pt_rise}"
    );
    assert!(
        (march_rise - 1.0) > 0.5 * (pt_rise - 1.0) && (march_rise - 1.0) < 2.0 * (pt_rise - 1.0),
        "march rises x{march_rise}, path tracer x{pt_rise}"
    );
}

/// A homogeneous sphere (radius 1000 m, σt 0.02) lit from behind, the sun 15° above the line
/// of sight: 0.5° beyond the limb on the image, so the rim toward the sun is seen through the
/// phase's forward peak. The contrast between the disc's quarter toward the sun and its quarter
/// away, march against path tracer (1024 samples: at 256 the rim's rare bright paths are
/// mostly missed and the reference's contrast reads half). The beam light kept by the delta
/// scaling, spread by one moment-matched width, made this contrast 2.41 times the path
/// tracer's (14.1 against 5.84); split into the phase's diffraction lobe and its broad Draine
/// lobe (PhaseModel::beam_split) it is 1.09 times (docs/fidelity.md: 0.98 on the outer halves
/// at 64 x 64).
#[test]
fn a_back_lit_sphere_and_its_rim_are_lit_as_the_path_tracer_sees_them() {
    let size = (48u32, 48u32);
    let center = Vec3::new(0.0, 3_000.0, -4_000.0);
    let mut s = debug_sphere(center);
    // Pixel for pixel: the trace grid at the image's resolution (the half grid's upsample is
    // the benchmark's to judge).
    s.march.resolution = TraceResolution::Full;
    let eye = Vec3::new(0.0, 3_000.0, 0.0);
    let beyond = (center - eye).normalize();
    let mut f = frame(eye, beyond, Vec3::Y, 36.0, 1.0);
    f.sun.direction = Mat4::from_axis_angle(Vec3::X, 15f32.to_radians())
        .transform_vector3(beyond)
        .normalize();
    let r = renderer(s.clone());
    let traced = trace(&r, &f, size, Orders::All, 1024);
    let marched = march(&s, &f, size);
    // The disc (the reference sees through less than half) split by rows: its top quarter
    // faces the sun, its bottom quarter the other way.
    let rows: Vec<u32> = (0..size.1)
        .filter(|&y| (0..size.0).any(|x| traced[(y * size.0 + x) as usize][3] < 0.5))
        .collect();
    assert!(rows.len() >= 8, "the disc spans {} rows", rows.len());
    let (first, last) = (rows[0], rows[rows.len() - 1]);
    let quarter = (last - first + 1) / 4;
    let mean = |img: &[[f32; 4]], ys: std::ops::Range<u32>| {
        let (mut sum, mut n) = (0.0f64, 0u32);
        for y in ys {
            for x in 0..size.0 {
                let i = (y * size.0 + x) as usize;
                if traced[i][3] < 0.5 {
                    sum += (0.2126 * img[i][0] + 0.7152 * img[i][1] + 0.0722 * img[i][2]) as f64;
                    n += 1;
                }
            }
        }
        sum / n.max(1) as f64
    };
    let contrast = |img: &[[f32; 4]]| {
        mean(img, first..first + quarter) / mean(img, last + 1 - quarter..last + 1)
    };
    let (m, t) = (contrast(&marched), contrast(&traced));
    let disc = mean(&marched, first..last + 1) / mean(&traced, first..last + 1);
    println!(
        "back-lit sphere: sun-side / far quarter march {m:.3}, path traced {t:.3}; disc {disc:.3}"
    );
    assert!(t > 1.5, "the reference's rim should stand out: {t}");
    assert!(m / t > 0.6 && m / t < 1.6, "march {m}, path traced {t}");
    // The disc: 0.789 here, 0.819 at 64 x 64 in docs/fidelity.md (issue 11's target: within
    // 20%; 1.32 there with the beam spread as a whole).
    assert!(
        (disc - 1.0).abs() < 0.25,
        "disc: march / path traced {disc}"
    );
}

/// Image means of `seeds` independent estimates of `spp` samples per pixel each.
fn seeded_means(
    r: &Renderer,
    f: &FrameInputs,
    size: (u32, u32),
    spp: u32,
    seeds: u16,
    guided: bool,
) -> Vec<f64> {
    (0..seeds)
        .map(|seed| {
            let mut pt = PathTracer::new(r, size.0, size.1, Orders::All)
                .unwrap()
                .with_seed(seed + 1)
                .with_sun_guiding(guided);
            pt.accumulate(r, f, spp).unwrap();
            mean_luminance(&pt.read(r).unwrap())
        })
        .collect()
}

fn mean_and_error(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

#[test]
fn sun_guided_directions_keep_the_estimate_and_cut_its_noise() {
    // The droplet phase (its forward peak 1100 / sr) through a slab of tau 1, seen from below
    // 10-40 degrees from the sun: the light of paths that travelled near the sun's direction.
    let settings = slab_settings(0.002, 1.0);
    assert!(matches!(
        settings.lighting.phase,
        PhaseModel::JendersieDEon { .. }
    ));
    let r = renderer(settings);
    let (w, h) = (16, 9);
    let f = below_view(w, h);
    let (spp, seeds) = (192, 20);
    let guided = mean_and_error(&seeded_means(&r, &f, (w, h), spp, seeds, true));
    let plain = mean_and_error(&seeded_means(&r, &f, (w, h), spp, seeds, false));
    println!(
        "tau-1 droplet slab, image mean over {seeds} seeds of {spp} samples: guided {:.4} ± {:.4}, \
         phase-sampled {:.4} ± {:.4}",
        guided.0, guided.1, plain.0, plain.1
    );
    // Unbiased: the two estimators agree within their Monte-Carlo error.
    let sigma = (guided.1.powi(2) + plain.1.powi(2)).sqrt();
    assert!(
        (guided.0 - plain.0).abs() < 4.0 * sigma,
        "guided {} vs phase-sampled {} (sigma {sigma})",
        guided.0,
        plain.0
    );
    // And less noisy: the guided estimate's error well under the phase-sampled one's.
    assert!(
        guided.1 < 0.6 * plain.1,
        "errors {} vs {}",
        guided.1,
        plain.1
    );
}
