//! Views (split screen, stereo, probes): several cameras on one renderer, sharing its noise,
//! weather maps and pipelines, each with its own history. Two moving cameras rendered as the
//! two halves of one target, both views encoded into one encoder, equal each camera rendered
//! by a renderer of its own over the same frames (temporal reprojection on); the same halves
//! rendered with one shared history do not. Ids of destroyed views are refused, memory is
//! shared, and a steady split-screen loop makes no bind groups.

mod common;
use common::{halfs, rgba, setup, small_noise, H, W};

use glam::Mat4;
use nimbus::demo::standard_views;
use nimbus::device::{read_texture, texture_2d};
use nimbus::view::MAX_VIEWS;
use nimbus::{ColorTargets, Error, FrameInputs, Renderer, Targets, ViewId, Viewport};

use wgpu::TextureFormat as F;
use wgpu::TextureUsages as U;

const SCENE: [f32; 4] = [0.2, 0.35, 0.7, 1.0];
const FRAMES: u32 = 8;

/// Camera `which` at frame `i`: it turns a little every frame and the wind moves on, so the
/// history must be reprojected.
fn camera(which: usize, i: u32) -> FrameInputs {
    let mut f = standard_views()[which].frame(W, H, 0.25 * i as f64);
    f.camera.view = Mat4::from_rotation_y(0.004 * i as f32) * f.camera.view;
    f
}

struct Gpu {
    device: wgpu::Device,
    queue: wgpu::Queue,
}

impl Gpu {
    fn color(&self, size: (u32, u32)) -> wgpu::Texture {
        let usage = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_DST | U::COPY_SRC;
        texture_2d(&self.device, "color", size, F::Rgba16Float, usage)
    }

    /// Fills `texture` with the scene color (in place, the clouds accumulate on it).
    fn clear(&self, texture: &wgpu::Texture) {
        let n = (texture.width() * texture.height()) as usize;
        self.queue.write_texture(
            texture.as_image_copy(),
            &halfs(&vec![SCENE; n]),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(texture.width() * 8),
                rows_per_image: Some(texture.height()),
            },
            texture.size(),
        );
    }

    fn read(&self, texture: &wgpu::Texture) -> Vec<[f32; 4]> {
        rgba(&read_texture(&self.device, &self.queue, texture, 0).unwrap())
    }
}

fn encode(
    r: &mut Renderer,
    view: ViewId,
    enc: &mut wgpu::CommandEncoder,
    target: &wgpu::TextureView,
    frame: &FrameInputs,
    viewport: Option<Viewport>,
) {
    r.prepare_view(view, frame).unwrap();
    r.encode_view(
        view,
        enc,
        &Targets {
            color: ColorTargets::InPlace(target),
            depth: None,
            viewport,
        },
    )
    .unwrap();
}

fn half_of(x: u32) -> Viewport {
    Viewport {
        x,
        y: 0,
        width: W,
        height: H,
    }
}

/// The largest channel difference between the left (`side` 0) or right half of a 2W-wide
/// image and a W-wide one.
fn worst_difference(wide: &[[f32; 4]], own: &[[f32; 4]], side: u32) -> f32 {
    let mut worst = 0.0f32;
    for y in 0..H {
        for x in 0..W {
            let p = wide[(y * 2 * W + side * W + x) as usize];
            let q = own[(y * W + x) as usize];
            for c in 0..3 {
                worst = worst.max((p[c] - q[c]).abs());
            }
        }
    }
    worst
}

#[test]
fn split_screen_views_keep_their_own_history() {
    setup();
    let (device, queue, _) = nimbus::headless::create_device().unwrap();
    let gpu = Gpu { device, queue };
    let mut settings = small_noise(5);
    settings.march.jitter = false;
    let new = || Renderer::new(&gpu.device, &gpu.queue, settings.clone()).unwrap();

    // References: each camera on a renderer (and a target) of its own.
    let mut own = [new(), new()];
    let own_targets = [gpu.color((W, H)), gpu.color((W, H))];
    let own_views = own_targets
        .each_ref()
        .map(|t| t.create_view(&Default::default()));
    // Split screen: one renderer, camera 0 in the left half (default view), camera 1 in the
    // right half (a view of its own), both encoded into one encoder.
    let mut split = new();
    let right = split.create_view().unwrap();
    let wide = gpu.color((2 * W, H));
    let wide_view = wide.create_view(&Default::default());
    // Control: the same halves through the default view only (one history for two cameras).
    let mut shared = new();
    let shared_target = gpu.color((2 * W, H));
    let shared_view = shared_target.create_view(&Default::default());

    let mut steady_binds = None;
    for i in 0..FRAMES {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        for (which, r) in own.iter_mut().enumerate() {
            gpu.clear(&own_targets[which]);
            encode(
                r,
                ViewId::DEFAULT,
                &mut enc,
                &own_views[which],
                &camera(which, i),
                None,
            );
        }
        gpu.clear(&wide);
        gpu.clear(&shared_target);
        for (which, view) in [(0, ViewId::DEFAULT), (1, right)] {
            let rect = Some(half_of(which as u32 * W));
            encode(
                &mut split,
                view,
                &mut enc,
                &wide_view,
                &camera(which, i),
                rect,
            );
            let one = ViewId::DEFAULT;
            encode(
                &mut shared,
                one,
                &mut enc,
                &shared_view,
                &camera(which, i),
                rect,
            );
        }
        gpu.queue.submit([enc.finish()]);
        if i == 3 {
            steady_binds = Some(split.bind_groups_created());
        }
    }
    assert_eq!(
        Some(split.bind_groups_created()),
        steady_binds,
        "a steady split-screen loop made bind groups"
    );

    let wide_px = gpu.read(&wide);
    let shared_px = gpu.read(&shared_target);
    for side in 0..2 {
        let own_px = gpu.read(&own_targets[side as usize]);
        let cloudy = own_px
            .iter()
            .filter(|p| **p != SCENE.map(common::f16))
            .count();
        assert!(
            cloudy > (W * H / 4) as usize,
            "too few cloud pixels ({cloudy})"
        );
        let views = worst_difference(&wide_px, &own_px, side);
        let one_history = worst_difference(&shared_px, &own_px, side);
        println!("camera {side}: views vs own renderer {views}; one shared history {one_history}");
        assert!(
            views <= 1e-3,
            "view {side} differs from its own renderer by {views}"
        );
        // The control proves the comparison can fail: one history for two cameras is wrong.
        assert!(
            one_history > 1e-2,
            "one shared history matched too ({one_history}): the test cannot tell"
        );
    }
}

#[test]
fn view_ids_memory_and_limits() {
    setup();
    let (device, queue, _) = nimbus::headless::create_device().unwrap();
    let gpu = Gpu { device, queue };
    let mut r = Renderer::new(&gpu.device, &gpu.queue, small_noise(2)).unwrap();
    assert_eq!(r.view_count(), 1);
    let shared = r.shared_memory_bytes();
    assert!(shared > 0);
    // A view holds nothing until its first frame; then its trace textures, at its own size.
    let probe = r.create_view().unwrap();
    assert_ne!(probe, ViewId::DEFAULT);
    assert_ne!(probe.to_raw(), 0);
    let small = gpu.color((W / 2, H / 2));
    let small_view = small.create_view(&Default::default());
    let big = gpu.color((W, H));
    let big_view = big.create_view(&Default::default());
    let uniforms_only = r.view_memory_bytes(probe).unwrap();
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    let probe_frame = standard_views()[0].frame(W / 2, H / 2, 0.0);
    encode(&mut r, probe, &mut enc, &small_view, &probe_frame, None);
    encode(
        &mut r,
        ViewId::DEFAULT,
        &mut enc,
        &big_view,
        &camera(0, 0),
        None,
    );
    gpu.queue.submit([enc.finish()]);
    let probe_bytes = r.view_memory_bytes(probe).unwrap();
    let main_bytes = r.view_memory_bytes(ViewId::DEFAULT).unwrap();
    println!(
        "shared {shared} B, main view {main_bytes} B ({W}x{H}), probe view {probe_bytes} B ({}x{})",
        W / 2,
        H / 2
    );
    assert!(probe_bytes > uniforms_only);
    // A quarter of the pixels: about a quarter of the main view's textures (grids round up).
    assert!(probe_bytes * 3 < main_bytes && probe_bytes * 5 > main_bytes);
    assert_eq!(r.shared_memory_bytes(), shared, "a view copied shared data");
    assert_eq!(r.gpu_memory_bytes(), shared + main_bytes + probe_bytes);

    // Destroyed: its memory goes, its id is refused everywhere, a new view gets a new id.
    r.destroy_view(probe).unwrap();
    assert_eq!(r.gpu_memory_bytes(), shared + main_bytes);
    let refused = |e: Error| assert!(matches!(e, Error::InvalidView(_)), "{e}");
    refused(r.prepare_view(probe, &probe_frame).unwrap_err());
    refused(r.view_memory_bytes(probe).unwrap_err());
    refused(r.reset_view_history(probe).unwrap_err());
    refused(r.destroy_view(probe).unwrap_err());
    refused(r.destroy_view(ViewId::DEFAULT).unwrap_err());
    refused(
        r.prepare_view(ViewId::from_raw(0xdead_beef), &probe_frame)
            .unwrap_err(),
    );
    let again = r.create_view().unwrap();
    assert_ne!(again, probe, "a reused slot must not revive the old id");
    // A view prepared but never encoded, and encode without prepare, as for the default view.
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    let unprepared = r.encode_view(
        again,
        &mut enc,
        &Targets {
            color: ColorTargets::InPlace(&big_view),
            depth: None,
            viewport: None,
        },
    );
    assert!(matches!(unprepared, Err(Error::NotPrepared)));

    // The limit, with a clear error, and room again after a destroy.
    let mut made = vec![again];
    while r.view_count() < MAX_VIEWS {
        made.push(r.create_view().unwrap());
    }
    let e = r.create_view().unwrap_err();
    assert!(e.to_string().contains("at most 64 views"), "{e}");
    r.destroy_view(made.pop().unwrap()).unwrap();
    r.create_view().unwrap();
}
