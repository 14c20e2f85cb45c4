//! The cloud shadow map in a host's lighting: an aerial view over a ground the host shades
//! itself (on the CPU here, from a read-back copy of the map), with the sunlight on the ground
//! multiplied by the clouds' transmittance. Writes OUT_DIR/cloud_shadows.png (the view),
//! OUT_DIR/cloud_shadows_unshadowed.png (the same ground without the map, for comparison) and
//! OUT_DIR/cloud_shadow_map.png (the map's transmittance, camera at the center, sun-space).
//!
//! Usage: cargo run --release --example cloud_shadows -- OUT_DIR [--size WIDTHxHEIGHT]
//!        [--preset NAME] [--frames N]

use std::path::PathBuf;
use std::process::ExitCode;

use glam::{Mat4, Vec3, Vec4};
use nimbus::demo::{sky_color, write_png};
use nimbus::{
    Camera, CloudShadowSampler, CloudShadows, DepthConvention, FrameInputs, Headless, Preset,
    Settings, Sun,
};

/// The ground's reflectance and the sky's share of its light (the rest is direct sun).
const GROUND_ALBEDO: Vec3 = Vec3::new(0.16, 0.18, 0.11);
const SKY_SHARE: f32 = 0.25;

fn frame(size: (u32, u32), time: f64) -> FrameInputs {
    let eye = Vec3::new(0.0, 7_000.0, 9_000.0);
    let (e, a) = (30f32.to_radians(), 100f32.to_radians());
    FrameInputs {
        camera: Camera {
            view: Mat4::look_at_rh(eye, Vec3::new(0.0, 0.0, -6_000.0), Vec3::Y),
            projection: Mat4::perspective_rh(
                55f32.to_radians(),
                size.0 as f32 / size.1 as f32,
                10.0,
                400_000.0,
            ),
            depth: DepthConvention::default(),
        },
        sun: Sun {
            direction: Vec3::new(e.cos() * a.sin(), e.sin(), -e.cos() * a.cos()),
            ..Sun::default()
        },
        time,
    }
}

/// The host's scene: sky above the horizon, a flat ground below lit by the sun through the
/// clouds (`shadows`: the map; `None`: no shadows) and by the sky.
fn scene(
    f: &FrameInputs,
    size: (u32, u32),
    shadows: Option<&CloudShadowSampler>,
) -> (Vec<[f32; 4]>, Vec<f32>) {
    let view_proj = f.camera.projection * f.camera.view;
    let inv = view_proj.inverse();
    let eye = f.camera.view.inverse().w_axis.truncate();
    let sun = f.sun.direction.normalize();
    let (mut color, mut depth) = (Vec::new(), Vec::new());
    for y in 0..size.1 {
        for x in 0..size.0 {
            let ndc_x = (x as f32 + 0.5) / size.0 as f32 * 2.0 - 1.0;
            let ndc_y = 1.0 - (y as f32 + 0.5) / size.1 as f32 * 2.0;
            let p = inv * Vec4::new(ndc_x, ndc_y, 0.0, 1.0);
            let dir = (p.truncate() / p.w - eye).normalize();
            if dir.y >= -1e-4 {
                let c = sky_color(dir, sun, f.sun.color);
                color.push([c.x, c.y, c.z, 1.0]);
                depth.push(1.0);
                continue;
            }
            let hit = eye + dir * (-eye.y / dir.y);
            let t = shadows.and_then(|s| s.transmittance(hit)).unwrap_or(1.0);
            let direct = f.sun.color * (f.sun.illuminance * 0.1) * sun.y.max(0.0) * t;
            let c = GROUND_ALBEDO * (direct * (1.0 - SKY_SHARE) + Vec3::splat(SKY_SHARE));
            color.push([c.x, c.y, c.z, 1.0]);
            let clip = view_proj * hit.extend(1.0);
            depth.push((clip.z / clip.w).clamp(0.0, 1.0));
        }
    }
    (color, depth)
}

/// Uploads the host's scene (ground lit through `shadows`), renders `frames` frames over it
/// so the clouds settle, and writes the result to `path`.
fn render_scene(
    h: &mut Headless,
    f: &FrameInputs,
    size: (u32, u32),
    shadows: Option<&CloudShadowSampler>,
    frames: u32,
    path: &std::path::Path,
) -> Result<(), String> {
    let err = |e: nimbus::Error| e.to_string();
    let (color, depth) = scene(f, size, shadows);
    h.upload_scene(&color, Some(&depth)).map_err(err)?;
    for _ in 0..frames {
        h.render(f).map_err(err)?;
    }
    write_png(path, &h.read_output().map_err(err)?, size.0, size.1, 1.0).map_err(err)
}

fn run() -> Result<(), String> {
    let mut args = std::env::args().skip(1);
    let (mut out, mut size, mut preset, mut frames) = (None, (640, 360), Preset::Sparse, 32);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--size" => {
                let v = args.next().ok_or("--size needs WIDTHxHEIGHT")?;
                let (w, h) = v.split_once('x').ok_or("--size needs WIDTHxHEIGHT")?;
                size = (
                    w.parse().map_err(|_| "bad width")?,
                    h.parse().map_err(|_| "bad height")?,
                );
            }
            "--preset" => {
                let v = args.next().ok_or("--preset needs a name")?;
                preset = Preset::ALL
                    .into_iter()
                    .find(|p| format!("{p:?}").eq_ignore_ascii_case(&v))
                    .ok_or(format!("unknown preset {v:?}"))?;
            }
            "--frames" => {
                let v = args.next().ok_or("--frames needs a count")?;
                frames = v.parse().map_err(|_| format!("bad frame count {v:?}"))?;
            }
            _ if out.is_none() => out = Some(PathBuf::from(a)),
            _ => return Err(format!("unexpected argument {a:?}")),
        }
    }
    let out = out.ok_or("usage: cloud_shadows OUT_DIR [--size WxH] [--preset NAME]")?;
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    let settings = Settings {
        weather: preset.weather(),
        shadows: CloudShadows {
            enabled: true,
            extent: 60_000.0,
            resolution: 512,
            ..CloudShadows::default()
        },
        ..Settings::default()
    };
    let mut h = Headless::new(settings).map_err(|e| e.to_string())?;
    h.resize(size.0, size.1).map_err(|e| e.to_string())?;
    let f = frame(size, 0.0);
    let err = |e: nimbus::Error| e.to_string();

    // First the unshadowed ground, which also makes the map; then the host shades its ground
    // with the map and the clouds settle over it.
    render_scene(
        &mut h,
        &f,
        size,
        None,
        frames,
        &out.join("cloud_shadows_unshadowed.png"),
    )?;
    let map = h.renderer().cloud_shadows().ok_or("no shadow map")?;
    let (n, extent) = (map.resolution, map.extent);
    let texels = h.read_cloud_shadows().map_err(err)?;
    let sampler = CloudShadowSampler::new(&map, texels.clone()).ok_or("bad map size")?;
    let shadowed = out.join("cloud_shadows.png");
    render_scene(&mut h, &f, size, Some(&sampler), frames, &shadowed)?;
    // The map as stored (toroidal: the camera's texel is wherever the window starts).
    let shown: Vec<[f32; 4]> = texels.iter().map(|t| [t[3], t[3], t[3], 1.0]).collect();
    write_png(&out.join("cloud_shadow_map.png"), &shown, n, n, 4.0).map_err(err)?;
    let lit = texels.iter().map(|t| t[3]).sum::<f32>() / texels.len() as f32;
    println!(
        "{preset:?}: map {n}x{n} over {} km, mean sun transmittance {lit:.3}; wrote {}",
        extent / 1000.0,
        out.display()
    );
    Ok(())
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
