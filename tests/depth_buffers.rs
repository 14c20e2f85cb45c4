//! Real depth buffers on the GPU: a `Depth32Float` depth attachment (as engines render it, read
//! through its depth aspect) must occlude exactly like the same values in an `R32Float`
//! texture, in the standard and in the reversed-Z convention.

mod common;
use common::{quiet, setup, small_noise, H, W};

use glam::{Mat4, Vec3, Vec4};
use nimbus::demo::standard_views;
use nimbus::device::{create_device, read_texture, texture_2d};
use nimbus::{Camera, ColorTargets, DepthConvention, FrameInputs, Renderer, Targets};

/// NDC depth of a point `dist` meters ahead.
fn depth_at(p: &Mat4, dist: f32) -> f32 {
    let c = *p * Vec4::new(0.0, 0.0, -dist, 1.0);
    c.z / c.w
}

struct Gpu {
    device: wgpu::Device,
    queue: wgpu::Queue,
}

impl Gpu {
    fn texture(&self, format: wgpu::TextureFormat, usage: wgpu::TextureUsages) -> wgpu::Texture {
        texture_2d(&self.device, "test", (W, H), format, usage)
    }

    /// A depth attachment holding `value` everywhere, written by a render pass's clear (depth
    /// formats take no CPU uploads).
    fn cleared_depth(&self, format: wgpu::TextureFormat, value: f32) -> wgpu::Texture {
        use wgpu::TextureUsages as U;
        let t = self.texture(format, U::RENDER_ATTACHMENT | U::TEXTURE_BINDING);
        let view = t.create_view(&Default::default());
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("clear depth"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(value),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        self.queue.submit([enc.finish()]);
        t
    }

    fn r32_depth(&self, value: f32) -> wgpu::Texture {
        use wgpu::TextureUsages as U;
        let t = self.texture(
            wgpu::TextureFormat::R32Float,
            U::TEXTURE_BINDING | U::COPY_DST,
        );
        self.queue.write_texture(
            t.as_image_copy(),
            bytemuck_f32(&vec![value; (W * H) as usize]),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(W * 4),
                rows_per_image: Some(H),
            },
            t.size(),
        );
        t
    }

    /// Renders the clouds over a black scene with `depth`, returns the RGBA16F output.
    fn render(&self, r: &mut Renderer, frame: &FrameInputs, depth: &wgpu::Texture) -> Vec<u8> {
        use wgpu::TextureUsages as U;
        let f = wgpu::TextureFormat::Rgba16Float;
        let scene = self.texture(f, U::TEXTURE_BINDING);
        let out = self.texture(f, U::RENDER_ATTACHMENT | U::COPY_SRC);
        let (scene_view, out_view) = (
            scene.create_view(&Default::default()),
            out.create_view(&Default::default()),
        );
        let aspect = if depth.format().is_depth_stencil_format() {
            wgpu::TextureAspect::DepthOnly
        } else {
            wgpu::TextureAspect::All
        };
        let depth_view = depth.create_view(&wgpu::TextureViewDescriptor {
            aspect,
            ..Default::default()
        });
        r.prepare(frame).unwrap();
        let mut enc = self.device.create_command_encoder(&Default::default());
        r.encode(
            &mut enc,
            &Targets {
                color: ColorTargets::Separate {
                    scene: &scene_view,
                    output: &out_view,
                },
                depth: Some(&depth_view),
                viewport: None,
            },
        )
        .unwrap();
        self.queue.submit([enc.finish()]);
        read_texture(&self.device, &self.queue, &out, 0).unwrap()
    }
}

fn bytemuck_f32(v: &[f32]) -> &[u8] {
    // SAFETY: f32 has no padding; the slice covers exactly its bytes.
    unsafe { std::slice::from_raw_parts(v.as_ptr().cast(), std::mem::size_of_val(v)) }
}

/// Mean absolute difference of two images' channels.
fn mean_difference(a: &[f32], b: &[f32]) -> f32 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum::<f32>() / a.len() as f32
}

fn halves(bytes: &[u8]) -> Vec<f32> {
    bytes
        .chunks_exact(2)
        .map(|c| half::f16::from_le_bytes([c[0], c[1]]).to_f32())
        .collect()
}

#[test]
fn depth32float_attachments_occlude_like_r32float_in_both_conventions() {
    setup();
    let (device, queue, _) = create_device().unwrap();
    let gpu = Gpu { device, queue };
    let mut r = Renderer::new(&gpu.device, &gpu.queue, quiet(small_noise(1))).unwrap();
    let view = standard_views()[0];
    let aspect = W as f32 / H as f32;
    let look = Mat4::look_at_rh(view.eye, view.target, Vec3::Y);
    let standard = Mat4::perspective_rh(view.fov_y, aspect, 1.0, 400_000.0);
    let reversed = Mat4::perspective_infinite_reverse_rh(view.fov_y, aspect, 1.0);
    let frame = |projection, depth| FrameInputs {
        camera: Camera {
            view: look,
            projection,
            depth,
        },
        sun: view.sun,
        time: 0.0,
    };
    let std_frame = frame(standard, DepthConvention::default());
    let rev_frame = frame(
        reversed,
        DepthConvention {
            reversed_z: true,
            infinite_far: true,
            ..Default::default()
        },
    );
    // A wall 6 km ahead: in the middle of the clouds of this view.
    let (d_std, d_rev) = (depth_at(&standard, 6_000.0), depth_at(&reversed, 6_000.0));
    let f32_std = halves(&gpu.render(&mut r, &std_frame, &gpu.r32_depth(d_std)));
    let mut with_attachment = |frame: &FrameInputs, format, value| {
        halves(&gpu.render(&mut r, frame, &gpu.cleared_depth(format, value)))
    };
    let d32_std = with_attachment(&std_frame, wgpu::TextureFormat::Depth32Float, d_std);
    assert_eq!(
        d32_std, f32_std,
        "Depth32Float and R32Float hold the same values"
    );
    let d32_rev = with_attachment(&rev_frame, wgpu::TextureFormat::Depth32Float, d_rev);
    let mean = mean_difference(&d32_rev, &f32_std);
    assert!(
        mean < 1e-3,
        "reversed-Z Depth32Float differs by {mean} on average"
    );
    // The wall does clip the clouds: with the sky (far value) the image is brighter.
    let sky = with_attachment(&std_frame, wgpu::TextureFormat::Depth32Float, 1.0);
    let sum = |v: &[f32]| v.iter().sum::<f32>();
    assert!(
        sum(&sky) > 1.05 * sum(&f32_std),
        "the 6 km wall hides no cloud"
    );
    // 24-bit depth with stencil, read through its depth aspect, agrees to its precision.
    let d24 = with_attachment(&std_frame, wgpu::TextureFormat::Depth24PlusStencil8, d_std);
    let mean = mean_difference(&d24, &f32_std);
    assert!(
        mean < 2e-3,
        "Depth24PlusStencil8 differs by {mean} on average"
    );
}
