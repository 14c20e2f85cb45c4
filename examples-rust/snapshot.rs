//! Renders the standard views without a window and writes one tone-mapped PNG each.
//!
//! Each view renders `--frames` frames (default 16) so the temporal reprojection settles: at
//! the default level one pixel in 16 is traced per frame.
//!
//! Usage: cargo run --release --example snapshot -- OUT_DIR [--size WIDTHxHEIGHT] [--frames N]

use std::path::PathBuf;
use std::process::ExitCode;

use nimbus::demo::{standard_views, write_png};
use nimbus::{Headless, NoiseVolume, Settings};

fn parse_size(s: &str) -> Option<(u32, u32)> {
    let (w, h) = s.split_once('x')?;
    Some((w.parse().ok()?, h.parse().ok()?))
}

fn run() -> Result<(), String> {
    let mut args = std::env::args().skip(1);
    let mut out: Option<PathBuf> = None;
    let mut size = (640, 360);
    let mut textures = false;
    let mut frames = 16usize;
    while let Some(a) = args.next() {
        match a.as_str() {
            "--size" => {
                let v = args.next().ok_or("--size needs WIDTHxHEIGHT")?;
                size = parse_size(&v).ok_or(format!("bad size {v:?}, expected e.g. 640x360"))?;
            }
            "--textures" => textures = true,
            "--frames" => {
                let v = args.next().ok_or("--frames needs a count")?;
                frames = v
                    .parse()
                    .ok()
                    .filter(|&n| n > 0)
                    .ok_or(format!("bad frame count {v:?}"))?;
            }
            "-h" | "--help" => {
                println!("usage: snapshot OUT_DIR [--size WIDTHxHEIGHT] [--frames N] [--textures]");
                return Ok(());
            }
            _ if out.is_none() => out = Some(PathBuf::from(a)),
            _ => return Err(format!("unexpected argument {a:?}")),
        }
    }
    let out = out.ok_or("usage: snapshot OUT_DIR [--size WIDTHxHEIGHT]")?;
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;

    let mut nimbus = Headless::new(Settings::default()).map_err(|e| e.to_string())?;
    let info = nimbus.adapter_info();
    println!(
        "adapter: {} ({:?}, {})",
        info.name, info.backend, info.driver_info
    );
    nimbus.resize(size.0, size.1).map_err(|e| e.to_string())?;
    if textures {
        write_textures(&nimbus, &out)?;
    }
    for view in standard_views() {
        let scene = view.scene(size.0, size.1);
        nimbus
            .upload_scene(&scene.color, Some(&scene.depth))
            .map_err(|e| e.to_string())?;
        let frame = view.frame(size.0, size.1, 0.0);
        // A new view is a camera cut: start its history afresh, then let it settle.
        nimbus.renderer_mut().reset_history();
        let mut times = Vec::new();
        for _ in 0..frames {
            times.push(nimbus.render(&frame).map_err(|e| e.to_string())?);
        }
        times.sort();
        let pixels = nimbus.read_output().map_err(|e| e.to_string())?;
        let path = out.join(format!("{}.png", view.name));
        write_png(&path, &pixels, size.0, size.1, 1.0).map_err(|e| e.to_string())?;
        println!(
            "wrote {} ({}x{}), frame {:.1} ms (median of {frames}, submit to completion)",
            path.display(),
            size.0,
            size.1,
            times[times.len() / 2].as_secs_f64() * 1e3
        );
    }
    Ok(())
}

/// Writes the weather map (RGB: layer coverage; cirrus streaks in alpha are not shown) and one
/// slice of each noise volume as PNGs, for inspection.
fn write_textures(nimbus: &Headless, out: &std::path::Path) -> Result<(), String> {
    let settings = Settings::default();
    let n = settings.noise.weather_size;
    let (weather, _) = nimbus.read_weather_maps().map_err(|e| e.to_string())?;
    let rgb: Vec<u8> = weather
        .iter()
        .flat_map(|p| [p[0], p[1], p[2]].map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8))
        .collect();
    let path = out.join("texture_weather_map.png");
    image::RgbImage::from_raw(n, n, rgb)
        .ok_or("weather map size")?
        .save(&path)
        .map_err(|e| e.to_string())?;
    println!("wrote {}", path.display());
    for (which, name, size) in [
        (NoiseVolume::Base, "base", settings.noise.base_size),
        (NoiseVolume::Detail, "detail", settings.noise.detail_size),
    ] {
        let v = nimbus.read_noise(which, 0).map_err(|e| e.to_string())?;
        // Slice z = 0, the four channels side by side.
        let slice = &v[..(size * size * 4) as usize];
        let mut img = image::GrayImage::new(size * 4, size);
        for y in 0..size {
            for x in 0..size {
                for c in 0..4 {
                    let value = slice[((y * size + x) * 4 + c) as usize];
                    img.put_pixel(c * size + x, y, image::Luma([value]));
                }
            }
        }
        let path = out.join(format!("texture_{name}_noise_z0.png"));
        img.save(&path).map_err(|e| e.to_string())?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("snapshot: {e}");
            ExitCode::FAILURE
        }
    }
}
