//! A viewport inside the targets (split screen, dynamic resolution): the clouds of a view
//! rendered into the right half of a double-width target equal the same view rendered into
//! a target of its own, the scene depth read at the same offset; pixels outside the viewport
//! stay exactly as they were; bad rectangles are refused.

mod common;
use common::{halfs, measured_shape, quiet, rgba, setup, small_noise, upload, H, W};

use nimbus::demo::standard_views;
use nimbus::device::{read_texture, texture_2d};
use nimbus::{ColorTargets, Error, Renderer, Targets, Viewport};

use wgpu::TextureFormat as F;
use wgpu::TextureUsages as U;

const SCENE: [f32; 4] = [0.2, 0.35, 0.7, 1.0];
const OUTSIDE: [f32; 4] = [0.9, 0.1, 0.1, 1.0];

/// Clip depth of the view's scene: an occluder (depth 0.5, a few meters away) in a band of
/// columns, sky elsewhere.
fn depth_at(x: u32) -> f32 {
    if (W / 4..W / 2).contains(&x) {
        0.5
    } else {
        1.0
    }
}

#[test]
fn viewport_render_matches_a_target_of_its_own() {
    // A little more cloud than the default's, so that at least a quarter of the view has some
    // to compare (2660 of 14 400 pixels at coverage 0.4 once cumulus were carved by their
    // noise).
    let mut s = measured_shape(quiet(small_noise(3)));
    s.weather.clouds.coverage = 0.5;
    compare(s, 1);
}

/// With temporal reprojection (the default), whose resolve reads the scene depth too: one
/// renderer per target, 8 frames each.
#[test]
fn viewport_with_temporal_resolve_matches_too() {
    let mut s = measured_shape(small_noise(3));
    s.march.jitter = false;
    compare(s, 8);
}

fn compare(settings: nimbus::Settings, frames: u32) {
    setup();
    let (device, queue, _) = nimbus::headless::create_device().unwrap();
    let mut r = Renderer::new(&device, &queue, settings.clone()).unwrap();
    let mut r_wide = Renderer::new(&device, &queue, settings).unwrap();
    let frame = standard_views()[0].frame(W, H, 0.0);
    let color_usage = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_DST | U::COPY_SRC;

    // The view on its own: a W x H target.
    let own = texture_2d(&device, "own", (W, H), F::Rgba16Float, color_usage);
    let own_depth = texture_2d(
        &device,
        "own depth",
        (W, H),
        F::R32Float,
        U::TEXTURE_BINDING | U::COPY_DST,
    );
    upload(&queue, &own, &halfs(&vec![SCENE; (W * H) as usize]), 8);
    let depth: Vec<f32> = (0..W * H).map(|i| depth_at(i % W)).collect();
    upload(&queue, &own_depth, bytemuck::cast_slice(&depth), 4);

    // The same view in the right half of a 2W x H target; the left half holds something else.
    let wide = texture_2d(&device, "wide", (2 * W, H), F::Rgba16Float, color_usage);
    let wide_depth = texture_2d(
        &device,
        "wide depth",
        (2 * W, H),
        F::R32Float,
        U::TEXTURE_BINDING | U::COPY_DST,
    );
    let wide_color: Vec<[f32; 4]> = (0..2 * W * H)
        .map(|i| if i % (2 * W) < W { OUTSIDE } else { SCENE })
        .collect();
    upload(&queue, &wide, &halfs(&wide_color), 8);
    // Left half: a near depth everywhere, which would hide every cloud if it were read.
    let wide_d: Vec<f32> = (0..2 * W * H)
        .map(|i| {
            let x = i % (2 * W);
            if x < W {
                0.01
            } else {
                depth_at(x - W)
            }
        })
        .collect();
    upload(&queue, &wide_depth, bytemuck::cast_slice(&wide_d), 4);

    let render = |r: &mut Renderer, color: &wgpu::Texture, depth: &wgpu::Texture, viewport| {
        r.prepare(&frame).unwrap();
        let mut enc = device.create_command_encoder(&Default::default());
        let cv = color.create_view(&Default::default());
        let dv = depth.create_view(&Default::default());
        let result = r.encode(
            &mut enc,
            &Targets {
                color: ColorTargets::InPlace(&cv),
                depth: Some(&dv),
                viewport,
            },
        );
        queue.submit([enc.finish()]);
        result
    };
    let right = Viewport {
        x: W,
        y: 0,
        width: W,
        height: H,
    };
    // In place, the clouds accumulate on the scene: upload it afresh before each frame.
    for _ in 0..frames {
        upload(&queue, &own, &halfs(&vec![SCENE; (W * H) as usize]), 8);
        render(&mut r, &own, &own_depth, None).unwrap();
        upload(&queue, &wide, &halfs(&wide_color), 8);
        render(&mut r_wide, &wide, &wide_depth, Some(right)).unwrap();
    }

    let own_px = rgba(&read_texture(&device, &queue, &own, 0).unwrap());
    let wide_px = rgba(&read_texture(&device, &queue, &wide, 0).unwrap());
    let (mut worst, mut outside_changed, mut cloudy) = (0.0f32, 0, 0);
    for y in 0..H {
        for x in 0..2 * W {
            let p = wide_px[(y * 2 * W + x) as usize];
            if x < W {
                outside_changed += (p != halfs_round(OUTSIDE)) as u32;
            } else {
                let q = own_px[(y * W + x - W) as usize];
                for c in 0..3 {
                    worst = worst.max((p[c] - q[c]).abs());
                }
                cloudy += (q != halfs_round(SCENE)) as u32;
            }
        }
    }
    println!("viewport vs own target: max difference {worst}; {cloudy} pixels with clouds");
    assert_eq!(outside_changed, 0, "pixels outside the viewport changed");
    assert!(
        cloudy > (W * H / 4),
        "too few cloud pixels ({cloudy}) to compare"
    );
    assert!(worst <= 1e-3, "the viewport render differs by {worst}");
    // The occluder band (read at the viewport's offset) stays exactly the scene.
    for y in 0..H {
        for x in W / 4..W / 2 {
            assert_eq!(wide_px[(y * 2 * W + W + x) as usize], halfs_round(SCENE));
        }
    }

    // Bad rectangles.
    for bad in [
        Viewport {
            x: W + 1,
            y: 0,
            width: W,
            height: H,
        },
        Viewport {
            x: 0,
            y: 0,
            width: 0,
            height: H,
        },
        Viewport {
            x: 0,
            y: H,
            width: W,
            height: 1,
        },
        Viewport {
            x: u32::MAX,
            y: 0,
            width: 2,
            height: 1,
        },
    ] {
        let e = render(&mut r_wide, &wide, &wide_depth, Some(bad)).unwrap_err();
        assert!(
            matches!(
                e,
                Error::InvalidTarget {
                    target: "viewport",
                    ..
                }
            ),
            "{e}"
        );
    }
}

/// A color as an RGBA16F target stores it.
fn halfs_round(c: [f32; 4]) -> [f32; 4] {
    c.map(|v| half::f16::from_f32(v).to_f32())
}
