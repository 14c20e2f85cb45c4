//! The benchmark's views section: one renderer serving a stereo pair and a six-face cube
//! probe (each camera a `nimbus::ViewId` with its own history), with the frame cost and the
//! GPU memory, against what separate renderers would take. Included by bench.rs.

use std::fmt::Write as _;
use std::time::Instant;

use nimbus::device::texture_2d;
use nimbus::glam::{Mat4, Vec3};
use nimbus::{
    Camera, ColorTargets, DepthConvention, FrameInputs, Renderer, Settings, Sun, Targets, ViewId,
};

/// One camera of a multi-view setup: its view, its target and the camera's matrices.
struct Eye {
    view: ViewId,
    target: nimbus::wgpu::Texture,
    camera: Camera,
}

fn eye_camera(eye: Vec3, forward: Vec3, up: Vec3, fov_deg: f32, aspect: f32) -> Camera {
    Camera {
        view: Mat4::look_at_rh(eye, eye + forward, up),
        projection: Mat4::perspective_rh(fov_deg.to_radians(), aspect, 1.0, 400_000.0),
        depth: DepthConvention::default(),
    }
}

/// Renders `frames` frames of every eye (all encoded into one encoder a frame); returns the
/// median wall time of a frame in ms, from the third on.
fn run_frames(
    device: &nimbus::wgpu::Device,
    queue: &nimbus::wgpu::Queue,
    r: &mut Renderer,
    eyes: &[Eye],
    frames: u32,
) -> Result<f64, String> {
    let views: Vec<_> = eyes
        .iter()
        .map(|e| e.target.create_view(&Default::default()))
        .collect();
    let mut times = Vec::new();
    for i in 0..frames {
        let t = Instant::now();
        let mut enc = device.create_command_encoder(&Default::default());
        for (e, v) in eyes.iter().zip(&views) {
            let frame = FrameInputs {
                camera: e.camera,
                sun: Sun::default(),
                time: i as f64 / 30.0,
            };
            r.prepare_view(e.view, &frame).map_err(|e| e.to_string())?;
            let targets = Targets {
                color: ColorTargets::InPlace(v),
                depth: None,
                viewport: None,
            };
            r.encode_view(e.view, &mut enc, &targets)
                .map_err(|e| e.to_string())?;
        }
        queue.submit([enc.finish()]);
        device
            .poll(nimbus::wgpu::PollType::wait_indefinitely())
            .map_err(|e| e.to_string())?;
        if i >= 2 {
            times.push(t.elapsed().as_secs_f64() * 1e3);
        }
    }
    times.sort_by(f64::total_cmp);
    Ok(times[times.len() / 2])
}

fn mb(bytes: u64) -> f64 {
    bytes as f64 / (1024.0 * 1024.0)
}

/// The views section of bench.md.
pub fn views_section(quick: bool) -> Result<String, String> {
    let e = |e: nimbus::Error| e.to_string();
    let (device, queue, _) = nimbus::headless::create_device().map_err(e)?;
    let started = Instant::now();
    let mut r = Renderer::new(&device, &queue, Settings::default()).map_err(e)?;
    device
        .poll(nimbus::wgpu::PollType::wait_indefinitely())
        .map_err(|e| e.to_string())?;
    let renderer_ms = started.elapsed().as_secs_f64() * 1e3;
    let usage = nimbus::wgpu::TextureUsages::RENDER_ATTACHMENT
        | nimbus::wgpu::TextureUsages::TEXTURE_BINDING;
    let target = |size: (u32, u32)| {
        texture_2d(
            &device,
            "bench view",
            size,
            nimbus::wgpu::TextureFormat::Rgba16Float,
            usage,
        )
    };
    let eye_size = if quick { (160, 90) } else { (640, 360) };
    let face = if quick { 32 } else { 128 };
    let frames = if quick { 6 } else { 12 };
    let origin = Vec3::new(0.0, 2.0, 0.0);
    let look = Vec3::new(0.0, 0.6, -1.0).normalize();

    let mut md = String::from("\n## Views: one renderer, several cameras\n\n");
    let mut eyes = Vec::new();
    let mut create_view_ms = 0.0;
    for side in [-1.0f32, 1.0] {
        let view = if side < 0.0 {
            ViewId::DEFAULT
        } else {
            let t = Instant::now();
            let v = r.create_view().map_err(e)?;
            create_view_ms = t.elapsed().as_secs_f64() * 1e3;
            v
        };
        let eye = origin + Vec3::X * (0.032 * side);
        eyes.push(Eye {
            view,
            target: target(eye_size),
            camera: eye_camera(
                eye,
                look,
                Vec3::Y,
                70.0,
                eye_size.0 as f32 / eye_size.1 as f32,
            ),
        });
    }
    let stereo_ms = run_frames(&device, &queue, &mut r, &eyes, frames)?;
    let shared = r.shared_memory_bytes();
    let per_eye = r.view_memory_bytes(eyes[1].view).map_err(e)?;
    let mut probe = Vec::new();
    let faces = [
        (Vec3::X, Vec3::Y),
        (Vec3::NEG_X, Vec3::Y),
        (Vec3::Y, Vec3::Z),
        (Vec3::NEG_Y, Vec3::Z),
        (Vec3::Z, Vec3::Y),
        (Vec3::NEG_Z, Vec3::Y),
    ];
    for (forward, up) in faces {
        probe.push(Eye {
            view: r.create_view().map_err(e)?,
            target: target((face, face)),
            camera: eye_camera(origin, forward, up, 90.0, 1.0),
        });
    }
    let probe_ms = run_frames(&device, &queue, &mut r, &probe, frames)?;
    let per_face = r.view_memory_bytes(probe[0].view).map_err(e)?;
    let _ = writeln!(
        md,
        "Default settings and weather, wall time per frame (every camera of the \
         set encoded into one encoder, then submit and wait; median from the third frame). A \
         renderer takes {renderer_ms:.0} ms to create (noise bake, blue noise, pipelines); a \
         view {:.2} ms (its textures are made at its first frame).\n\n\
         | set | cameras | size | ms a frame | GPU memory: shared + views | as separate renderers |\n\
         |---|---|---|---|---|---|\n\
         | stereo pair | 2 | {}x{} | {stereo_ms:.1} | {:.1} + 2 × {:.1} MB | {:.1} MB |\n\
         | cube probe | 6 | {face}x{face} | {probe_ms:.1} | {:.1} + 6 × {:.2} MB | {:.1} MB |",
        create_view_ms,
        eye_size.0,
        eye_size.1,
        mb(shared),
        mb(per_eye),
        mb(2 * (shared + per_eye)),
        mb(shared),
        mb(per_face),
        mb(6 * (shared + per_face)),
    );
    println!("{md}");
    Ok(md)
}
