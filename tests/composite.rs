//! The composite's two ways of writing a separate output: a compute pass when the output
//! allows storage writes, a fullscreen triangle otherwise. They must give the same picture,
//! pixel for pixel (the same arithmetic; only the store differs), with the depth-aware
//! upsample of a half-resolution trace grid and a viewport inside the targets, and leave the
//! pixels outside the viewport as they were; the compute pass composites the half grid's 2×2
//! pixels per invocation, so an odd-sized viewport checks its last column and row. An output
//! neither path can write is refused, and so is a frame prepared before a settings change.

mod common;
use common::{halfs, quiet, rgba, setup, small_noise, upload, H, W};

use nimbus::demo::standard_views;
use nimbus::device::{read_texture, texture_2d};
use nimbus::settings::TraceResolution;
use nimbus::{ColorTargets, Error, Renderer, Targets, Viewport};

use wgpu::TextureFormat as F;
use wgpu::TextureUsages as U;

const OUTSIDE: [f32; 4] = [0.9, 0.1, 0.1, 1.0];

/// One frame of the ridge view (scene depth in front of part of the clouds) in a `rect.0` x
/// `rect.1` viewport at the top right of 2W x H targets (`viewport_x`: its left edge) into
/// `output`, which holds OUTSIDE before; returns its pixels.
fn composite_into(
    format: F,
    usage: U,
    to_bytes: &dyn Fn(&[[f32; 4]]) -> Vec<u8>,
    bpp: u32,
    rect: (u32, u32),
) -> Vec<[f32; 4]> {
    setup();
    let (device, queue, _) = nimbus::headless::create_device().unwrap();
    let mut settings = quiet(small_noise(3));
    // A half-resolution grid: the composite's depth-aware upsample runs.
    settings.march.resolution = TraceResolution::Half;
    let mut r = Renderer::new(&device, &queue, settings).unwrap();
    let view = standard_views()[4];
    let scene = view.scene(W, H);
    let wide = |left: [f32; 4], right: &[[f32; 4]]| -> Vec<[f32; 4]> {
        (0..2 * W * H)
            .map(|i| {
                let (x, y) = (i % (2 * W), i / (2 * W));
                if x < W {
                    left
                } else {
                    right[(y * W + x - W) as usize]
                }
            })
            .collect()
    };
    let color = texture_2d(
        &device,
        "scene",
        (2 * W, H),
        F::Rgba16Float,
        U::TEXTURE_BINDING | U::COPY_DST,
    );
    upload(&queue, &color, &halfs(&wide(OUTSIDE, &scene.color)), 8);
    let depth = texture_2d(
        &device,
        "depth",
        (2 * W, H),
        F::R32Float,
        U::TEXTURE_BINDING | U::COPY_DST,
    );
    let depths: Vec<f32> = wide(
        [0.01; 4],
        &scene.depth.iter().map(|d| [*d; 4]).collect::<Vec<_>>(),
    )
    .iter()
    .map(|d| d[0])
    .collect();
    upload(&queue, &depth, bytemuck::cast_slice(&depths), 4);
    let output = texture_2d(
        &device,
        "output",
        (2 * W, H),
        format,
        usage | U::COPY_DST | U::COPY_SRC,
    );
    upload(
        &queue,
        &output,
        &to_bytes(&vec![OUTSIDE; (2 * W * H) as usize]),
        bpp,
    );
    let (cv, dv, ov) = (
        color.create_view(&Default::default()),
        depth.create_view(&Default::default()),
        output.create_view(&Default::default()),
    );
    r.prepare(&view.frame(rect.0, rect.1, 0.0)).unwrap();
    let mut enc = device.create_command_encoder(&Default::default());
    r.encode(
        &mut enc,
        &Targets {
            color: ColorTargets::Separate {
                scene: &cv,
                output: &ov,
            },
            depth: Some(&dv),
            viewport: Some(Viewport {
                x: viewport_x(rect),
                y: 0,
                width: rect.0,
                height: rect.1,
            }),
        },
    )
    .unwrap();
    queue.submit([enc.finish()]);
    let bytes = read_texture(&device, &queue, &output, 0).unwrap();
    if bpp == 8 {
        rgba(&bytes)
    } else {
        bytes
            .chunks_exact(4)
            .map(|c| [0, 1, 2, 3].map(|k| c[k] as f32 / 255.0))
            .collect()
    }
}

/// The left edge of a `rect` viewport flush with the targets' right edge.
fn viewport_x(rect: (u32, u32)) -> u32 {
    2 * W - rect.0
}

fn unorm8(pixels: &[[f32; 4]]) -> Vec<u8> {
    pixels
        .iter()
        .flat_map(|p| p.map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8))
        .collect()
}

/// Compares the two paths' pixels: equal within `tolerance` inside the `rect` viewport,
/// untouched outside it.
fn assert_same(
    compute: &[[f32; 4]],
    render: &[[f32; 4]],
    outside: [f32; 4],
    tolerance: f32,
    rect: (u32, u32),
) {
    let (mut worst, mut clouds) = (0.0f32, 0);
    for (i, (c, r)) in compute.iter().zip(render).enumerate() {
        let (x, y) = (i as u32 % (2 * W), i as u32 / (2 * W));
        if x < viewport_x(rect) || y >= rect.1 {
            assert_eq!(
                *c, outside,
                "compute: pixel {i} outside the viewport changed"
            );
            assert_eq!(
                *r, outside,
                "render: pixel {i} outside the viewport changed"
            );
            continue;
        }
        clouds += (c != &outside) as u32;
        for k in 0..4 {
            worst = worst.max((c[k] - r[k]).abs());
        }
    }
    println!("compute vs fullscreen triangle: max difference {worst}, {clouds} pixels written");
    assert!(
        clouds > rect.0 * rect.1 / 2,
        "too few pixels written ({clouds})"
    );
    assert!(worst <= tolerance, "the paths differ by {worst}");
}

#[test]
fn compute_composite_matches_the_fullscreen_triangle() {
    let f16 = |p: &[[f32; 4]]| halfs(p);
    let outside = OUTSIDE.map(|v| half::f16::from_f32(v).to_f32());
    // The whole right half, and an odd-sized viewport flush with the targets' right edge:
    // the half grid's last sample then stands for one column and one row.
    for rect in [(W, H), (W - 1, H - 3)] {
        let compute = composite_into(F::Rgba16Float, U::STORAGE_BINDING, &f16, 8, rect);
        let render = composite_into(F::Rgba16Float, U::RENDER_ATTACHMENT, &f16, 8, rect);
        assert_same(&compute, &render, outside, 1e-3, rect);
    }
}

#[test]
fn compute_composite_matches_the_fullscreen_triangle_in_rgba8() {
    let rect = (W, H);
    let compute = composite_into(F::Rgba8Unorm, U::STORAGE_BINDING, &unorm8, 4, rect);
    let render = composite_into(F::Rgba8Unorm, U::RENDER_ATTACHMENT, &unorm8, 4, rect);
    let outside = OUTSIDE.map(|v| (v * 255.0).round() / 255.0);
    assert_same(&compute, &render, outside, 1.0 / 255.0 + 1e-6, rect);
}

#[test]
fn an_output_neither_path_can_write_is_refused() {
    setup();
    let (device, queue, _) = nimbus::headless::create_device().unwrap();
    let mut r = Renderer::new(&device, &queue, quiet(small_noise(3))).unwrap();
    let make = |format, usage| {
        texture_2d(&device, "t", (W, H), format, usage).create_view(&Default::default())
    };
    let scene = make(F::Rgba16Float, U::TEXTURE_BINDING);
    // Sampled only; and storage in a format the compute composite does not write.
    for output in [
        make(F::Rgba16Float, U::TEXTURE_BINDING | U::COPY_SRC),
        make(F::Rgba8Unorm, U::TEXTURE_BINDING),
    ] {
        r.prepare(&standard_views()[0].frame(W, H, 0.0)).unwrap();
        let mut enc = device.create_command_encoder(&Default::default());
        let e = r
            .encode(
                &mut enc,
                &Targets {
                    color: ColorTargets::Separate {
                        scene: &scene,
                        output: &output,
                    },
                    depth: None,
                    viewport: None,
                },
            )
            .unwrap_err();
        assert!(
            matches!(
                e,
                Error::InvalidTarget {
                    target: "output",
                    ..
                }
            ) && e.to_string().contains("STORAGE_BINDING"),
            "{e}"
        );
    }
}

/// One frame of the ridge view on a half grid into a storage output; with `change`, prepared
/// with the full grid, then `set_settings` to the half grid: encode refuses the frame prepared
/// with the old settings, and the frame prepared again is drawn. Returns its pixels.
fn half_grid_frame(change: bool) -> Vec<[f32; 4]> {
    setup();
    let (device, queue, _) = nimbus::headless::create_device().unwrap();
    let with = |resolution| {
        let mut s = quiet(small_noise(3));
        s.march.resolution = resolution;
        s
    };
    let first = if change {
        TraceResolution::Full
    } else {
        TraceResolution::Half
    };
    let mut r = Renderer::new(&device, &queue, with(first)).unwrap();
    let view = standard_views()[4];
    let scene = view.scene(W, H);
    let make = |label, format, usage| texture_2d(&device, label, (W, H), format, usage);
    let color = make("scene", F::Rgba16Float, U::TEXTURE_BINDING | U::COPY_DST);
    upload(&queue, &color, &halfs(&scene.color), 8);
    let depth = make("depth", F::R32Float, U::TEXTURE_BINDING | U::COPY_DST);
    upload(&queue, &depth, bytemuck::cast_slice(&scene.depth), 4);
    let output = make("output", F::Rgba16Float, U::STORAGE_BINDING | U::COPY_SRC);
    let (cv, dv, ov) = (
        color.create_view(&Default::default()),
        depth.create_view(&Default::default()),
        output.create_view(&Default::default()),
    );
    let targets = Targets {
        color: ColorTargets::Separate {
            scene: &cv,
            output: &ov,
        },
        depth: Some(&dv),
        viewport: None,
    };
    let frame = view.frame(W, H, 0.0);
    r.prepare(&frame).unwrap();
    if change {
        r.set_settings(with(TraceResolution::Half)).unwrap();
        let mut enc = device.create_command_encoder(&Default::default());
        let refused = r.encode(&mut enc, &targets);
        assert!(
            matches!(refused, Err(Error::NotPrepared)),
            "a frame prepared with the old settings was encoded: {refused:?}"
        );
        r.prepare(&frame).unwrap();
    }
    let mut enc = device.create_command_encoder(&Default::default());
    r.encode(&mut enc, &targets).unwrap();
    queue.submit([enc.finish()]);
    rgba(&read_texture(&device, &queue, &output, 0).unwrap())
}

#[test]
fn a_settings_change_between_prepare_and_encode_needs_a_new_prepare() {
    // The trace grid, the march's and the composite's parameters all come from the settings:
    // a frame prepared on the full grid and encoded on the half one read the half grid as if
    // it were full (differences up to 0.49). Encode now refuses it; prepared again, the frame
    // is the half grid's own.
    let (changed, plain) = (half_grid_frame(true), half_grid_frame(false));
    let worst = changed
        .iter()
        .zip(&plain)
        .flat_map(|(a, b)| (0..4).map(move |k| (a[k] - b[k]).abs()))
        .fold(0.0f32, f32::max);
    println!(
        "prepared again after the change, against the half grid throughout: max difference {worst}"
    );
    assert!(
        worst <= 1e-3,
        "the frame after the change differs by {worst}"
    );
}
