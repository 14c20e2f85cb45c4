//! Weather tour, without a window: a contact sheet of every preset (one PNG: a row per preset,
//! from the ground looking up and from 8 km looking down) and an interrupted transition
//! (cloudy to stormy, interrupted half way by clear) as numbered PNGs, one a second of a
//! 16 fps run. Prints, for every saved frame, the largest per-pixel change from the previous
//! saved one.
//!
//! Usage: cargo run --release --example weather_tour -- OUT_DIR [--size WIDTHxHEIGHT]

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use nimbus::demo::{standard_views, tonemap, write_png, DemoView};
use nimbus::glam::Vec3;
use nimbus::weather::Weather;
use nimbus::{Headless, Settings};

type Image = Vec<[f32; 4]>;

/// Frames each contact-sheet view gets: enough for the default temporal pattern (a 4 × 4 block)
/// to trace every pixel several times.
const SETTLE_FRAMES: u32 = 48;

/// The ground view of the standard set, and a view from 12 km, above every preset's tops.
fn view(which: usize) -> DemoView {
    let mut v = standard_views()[if which == 0 { 0 } else { 3 }];
    if which == 1 {
        v.eye.y = 12_000.0;
        v.target = Vec3::new(0.0, 6_000.0, -14_000.0);
    }
    v
}

/// One view at `time`, after `frames` frames of it (the temporal pattern traces a pixel of each
/// block per frame: the contact sheet shows the settled picture, as a still camera sees it).
fn render(
    h: &mut Headless,
    which: usize,
    size: (u32, u32),
    time: f64,
    frames: u32,
) -> Result<Image, String> {
    let v = view(which);
    let scene = v.scene(size.0, size.1);
    h.upload_scene(&scene.color, Some(&scene.depth))
        .map_err(|e| e.to_string())?;
    for _ in 0..frames.max(1) {
        h.render(&v.frame(size.0, size.1, time))
            .map_err(|e| e.to_string())?;
    }
    h.read_output().map_err(|e| e.to_string())
}

/// Tiles images (row-major, `cols` per row) into one tone-mapped PNG.
fn contact_sheet(
    path: &Path,
    images: &[Image],
    cols: usize,
    size: (u32, u32),
) -> Result<(), String> {
    let rows = images.len().div_ceil(cols);
    let (w, h) = (size.0 as usize, size.1 as usize);
    let mut sheet = image::RgbImage::new((w * cols) as u32, (h * rows) as u32);
    for (i, img) in images.iter().enumerate() {
        let (ox, oy) = ((i % cols) * w, (i / cols) * h);
        for (k, p) in img.iter().enumerate() {
            let rgb = tonemap(*p, 1.0);
            sheet.put_pixel((ox + k % w) as u32, (oy + k / w) as u32, image::Rgb(rgb));
        }
    }
    sheet
        .save(path)
        .map_err(|e| format!("{}: {e}", path.display()))
}

fn max_change(a: &Image, b: &Image) -> f32 {
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |c| (p[c] - q[c]).abs()))
        .fold(0.0, f32::max)
}

fn run() -> Result<(), String> {
    let mut args = std::env::args().skip(1);
    let mut out: Option<PathBuf> = None;
    let mut size = (240, 135);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--size" => {
                let v = args.next().ok_or("--size needs WIDTHxHEIGHT")?;
                let (w, h) = v.split_once('x').ok_or("size is WIDTHxHEIGHT")?;
                size = (
                    w.parse().map_err(|_| "bad width")?,
                    h.parse().map_err(|_| "bad height")?,
                );
            }
            _ if out.is_none() => out = Some(PathBuf::from(a)),
            _ => return Err(format!("unexpected argument {a:?}")),
        }
    }
    let out = out.ok_or("usage: weather_tour OUT_DIR [--size WIDTHxHEIGHT]")?;
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;

    // The sheet jumps from preset to preset: each map at once, in its request, so that every
    // row's frames see its weather from the first (a game's requests take 16 frames instead).
    let mut h = Headless::new(Settings {
        weather_map_texels_per_frame: 0,
        ..Settings::default()
    })
    .map_err(|e| e.to_string())?;
    h.resize(size.0, size.1).map_err(|e| e.to_string())?;

    let presets = [
        Weather::clear(),
        Weather::sparse(),
        Weather::cloudy(),
        Weather::overcast(),
        Weather::stormy(),
        Weather::sparse().with_high_layer(Weather::cirrus()),
    ];
    let mut images = Vec::new();
    for (i, w) in presets.iter().enumerate() {
        let t = i as f64 * 100.0;
        h.renderer_mut()
            .set_weather(w.clone(), t, 0.0)
            .map_err(|e| e.to_string())?;
        for which in [0, 1] {
            h.renderer_mut().reset_history();
            images.push(render(&mut h, which, size, t, SETTLE_FRAMES)?);
        }
        let label = if w.high_layer.coverage > 0.0 {
            format!("{} + cirrus", w.name)
        } else {
            w.name.clone()
        };
        println!("row {}: {label}", i + 1);
    }
    let sheet = out.join("presets.png");
    contact_sheet(&sheet, &images, 2, size)?;
    println!("wrote {}", sheet.display());

    // The transition: cloudy, then stormy over 20 s from t = 0, interrupted at t = 10 by
    // clear (20 s). One frame a second from t = 0 to 30. Jitter off: the per-frame change
    // should measure the weather, not the noise pattern.
    let mut settings = Settings {
        weather: Weather::cloudy(),
        ..Settings::default()
    };
    settings.march.jitter = false;
    let mut h = Headless::new(settings).map_err(|e| e.to_string())?;
    h.resize(size.0, size.1).map_err(|e| e.to_string())?;
    h.renderer_mut()
        .set_weather(Weather::stormy(), 0.0, 20.0)
        .map_err(|e| e.to_string())?;
    let mut prev: Option<Image> = None;
    for k in 0..=30 {
        let t = k as f64;
        // The second before this frame at 16 frames a second, as a game would run it, so the
        // temporal history has followed the weather (one frame a second would show the
        // freshly traced pixels as a grid against a second-old history).
        if k > 0 {
            let v = view(0);
            for j in 1..16 {
                let tj = t - 1.0 + j as f64 / 16.0;
                h.render(&v.frame(size.0, size.1, tj))
                    .map_err(|e| e.to_string())?;
            }
        }
        let note = if k == 10 {
            h.renderer_mut()
                .set_weather(Weather::clear(), t, 20.0)
                .map_err(|e| e.to_string())?;
            "  <- interrupted: clear requested"
        } else {
            ""
        };
        let img = render(&mut h, 0, size, t, 1)?;
        let path = out.join(format!("transition_{k:03}.png"));
        write_png(&path, &img, size.0, size.1, 1.0).map_err(|e| e.to_string())?;
        let change = prev.as_ref().map(|p| max_change(p, &img));
        let w = h.renderer().weather_at(t);
        println!(
            "frame {k:3} t={t:4.1}s coverage {:.3} map weight {:.3} largest change {}{note}",
            w.weather.clouds.coverage,
            w.map_weight,
            change.map_or("-".to_string(), |c| format!("{c:.4}")),
        );
        prev = Some(img);
    }
    println!("wrote {}/transition_000..030.png", out.display());
    Ok(())
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("weather_tour: {e}");
            ExitCode::FAILURE
        }
    }
}
