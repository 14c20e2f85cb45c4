//! Benchmark: a matrix of presets × camera views × sizes × quality levels, with GPU time per
//! pass (timestamp queries; wall time beside it), rays traced, GPU memory, and the error of
//! every image against a converged reference of the same scene and time (FLIP mean and 99th
//! percentile). Also: cost against pixel count, the cost of a weather bake, and a short
//! moving-camera flight. Writes bench.csv, bench.md and chart.png into the output folder.
//!
//! Usage: cargo run --release --example bench -- [--quick] [--out DIR]
//!        cargo run --release --example bench -- --from-csv DIR/bench.csv   (re-draw from a run)

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use nimbus::demo::{standard_views, tonemap, DemoView};
use nimbus::glam::Vec3;
use nimbus::settings::{Quality, TraceResolution};
use nimbus::{Headless, Settings, Weather};

const VIEW_NAMES: [&str; 4] = ["ground_up", "horizon", "inside", "above"];
const TIMED_FRAMES: usize = 3;

struct Row {
    preset: String,
    view: &'static str,
    size: (u32, u32),
    quality: String,
    march_ms: f64,
    composite_ms: f64,
    wall_ms: f64,
    rays: u64,
    memory_mb: f64,
    flip_mean: f32,
    flip_p99: f32,
}

fn level_name(q: Option<Quality>) -> String {
    q.map_or("reference".to_string(), |q| format!("{q:?}").to_lowercase())
}

/// The converged reference: tiny steps, many light samples, full resolution, no jitter.
fn settings_for(weather: &Weather, quality: Option<Quality>) -> Settings {
    let mut s = Settings {
        weather: weather.clone(),
        ..Settings::default()
    };
    match quality {
        Some(q) => q.apply(&mut s),
        None => {
            s.march.resolution = TraceResolution::Full;
            s.march.min_steps = 512;
            s.march.max_steps = 512;
            s.march.jitter = false;
            s.march.transmittance_cutoff = 0.001;
            s.lighting.light_steps = 16;
        }
    }
    s
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Renders `frames` times; returns the last image and the median (march, composite, wall) ms.
fn measure(
    h: &mut Headless,
    view: &DemoView,
    time: f64,
    frames: usize,
) -> Result<(Vec<[f32; 4]>, [f64; 3]), String> {
    let (w, hgt) = h.size().ok_or("no size")?;
    let scene = view.scene(w, hgt);
    h.upload_scene(&scene.color, Some(&scene.depth))
        .map_err(|e| e.to_string())?;
    let frame = view.frame(w, hgt, time);
    h.render(&frame).map_err(|e| e.to_string())?; // warm-up: pipelines, caches
    let (mut march, mut comp, mut wall) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..frames {
        let t = Instant::now();
        h.render(&frame).map_err(|e| e.to_string())?;
        wall.push(t.elapsed().as_secs_f64() * 1e3);
        if let Some(p) = h.renderer().last_pass_times().map_err(|e| e.to_string())? {
            march.push(p.march_ms);
            comp.push(p.composite_ms);
        }
    }
    let image = h.read_output().map_err(|e| e.to_string())?;
    let gpu = |v: Vec<f64>| if v.is_empty() { f64::NAN } else { median(v) };
    Ok((image, [gpu(march), gpu(comp), median(wall)]))
}

fn to_rgb8(img: &[[f32; 4]]) -> Vec<u8> {
    img.iter().flat_map(|p| tonemap(*p, 1.0)).collect()
}

/// FLIP mean and 99th percentile of `test` against `reference` (tone-mapped sRGB).
fn flip(reference: &[[f32; 4]], test: &[[f32; 4]], size: (u32, u32)) -> (f32, f32) {
    let r = nv_flip::FlipImageRgb8::with_data(size.0, size.1, &to_rgb8(reference));
    let t = nv_flip::FlipImageRgb8::with_data(size.0, size.1, &to_rgb8(test));
    let error = nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    let mut pool = nv_flip::FlipPool::from_image(&error);
    (pool.mean(), pool.get_percentile(0.99, true))
}

fn new_headless(size: (u32, u32)) -> Result<Headless, String> {
    let mut h = Headless::new(Settings::default()).map_err(|e| e.to_string())?;
    h.resize(size.0, size.1).map_err(|e| e.to_string())?;
    if !h.renderer_mut().enable_gpu_timing() {
        eprintln!("note: no timestamp queries on this adapter; GPU columns are NaN, use wall time");
    }
    Ok(h)
}

/// Draws one bar per row (wall ms), colored by quality level.
fn chart(rows: &[Row], path: &std::path::Path) -> Result<(), String> {
    let bar = 6u32;
    let (w, h) = ((rows.len() as u32) * (bar + 2) + 20, 240u32);
    let cost = |r: &Row| r.wall_ms;
    let max = rows.iter().map(cost).fold(1e-9, f64::max);
    let mut img = image::RgbImage::from_pixel(w, h, image::Rgb([255, 255, 255]));
    for (i, r) in rows.iter().enumerate() {
        let color = match r.quality.as_str() {
            "low" => [80, 170, 80],
            "medium" => [60, 120, 220],
            "high" => [230, 150, 40],
            "ultra" => [200, 60, 60],
            _ => [90, 90, 90],
        };
        let height = ((cost(r) / max) * (h - 20) as f64).max(1.0) as u32;
        let x0 = 10 + i as u32 * (bar + 2);
        for x in x0..x0 + bar {
            for y in (h - 10 - height)..(h - 10) {
                img.put_pixel(x, y, image::Rgb(color));
            }
        }
    }
    img.save(path).map_err(|e| e.to_string())
}

/// The per-quality-level table (medians over presets and views), for every size in `rows`.
/// Cost is wall time; "cost vs ultra" divides by the ultra level's median at the same size.
fn level_table(rows: &[Row]) -> String {
    let mut md = String::from(
        "## Per quality level (medians over presets and views)\n\n\
         | size | quality | wall ms | cost vs ultra | FLIP mean | FLIP p99 | GPU ms (timestamps) | rays | GPU MiB |\n\
         |---|---|---|---|---|---|---|---|---|\n",
    );
    let mut sizes: Vec<(u32, u32)> = rows.iter().map(|r| r.size).collect();
    sizes.dedup();
    for size in sizes {
        let of = |q: &str| {
            rows.iter()
                .filter(|r| r.size == size && r.quality == q)
                .collect::<Vec<_>>()
        };
        let wall = |rs: &[&Row]| median(rs.iter().map(|r| r.wall_ms).collect());
        let ultra = wall(&of("ultra"));
        for q in ["low", "medium", "high", "ultra"] {
            let rs = of(q);
            if rs.is_empty() {
                continue;
            }
            let _ = writeln!(
                md,
                "| {}x{} | {q} | {:.1} | {:.3} | {:.4} | {:.3} | {:.2} | {} | {:.1} |",
                size.0,
                size.1,
                wall(&rs),
                wall(&rs) / ultra,
                median(rs.iter().map(|r| r.flip_mean as f64).collect()),
                median(rs.iter().map(|r| r.flip_p99 as f64).collect()),
                median(rs.iter().map(|r| r.march_ms + r.composite_ms).collect()),
                rs[0].rays,
                rs[0].memory_mb
            );
        }
    }
    md
}

/// Reads rows back from a `bench.csv`.
fn read_csv(path: &std::path::Path) -> Result<Vec<Row>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut rows = Vec::new();
    for (n, line) in text.lines().enumerate().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let bad = || format!("{}:{}: malformed row", path.display(), n + 1);
        if f.len() != 12 {
            return Err(bad());
        }
        let num = |i: usize| f[i].parse::<f64>().map_err(|_| bad());
        rows.push(Row {
            preset: f[0].to_string(),
            view: VIEW_NAMES
                .iter()
                .copied()
                .find(|v| *v == f[1])
                .ok_or_else(bad)?,
            size: (num(2)? as u32, num(3)? as u32),
            quality: f[4].to_string(),
            march_ms: num(5)?,
            composite_ms: num(6)?,
            wall_ms: num(7)?,
            rays: num(8)? as u64,
            memory_mb: num(9)?,
            flip_mean: num(10)? as f32,
            flip_p99: num(11)? as f32,
        });
    }
    Ok(rows)
}

fn run() -> Result<(), String> {
    let mut quick = false;
    let mut out = PathBuf::from("target/bench");
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--quick" => quick = true,
            "--out" => out = PathBuf::from(args.next().ok_or("--out needs a folder")?),
            "--from-csv" => {
                // Re-draw the chart and the per-level table from an earlier run's CSV.
                let csv = PathBuf::from(args.next().ok_or("--from-csv needs a bench.csv")?);
                let rows = read_csv(&csv)?;
                let dir = csv.parent().map(PathBuf::from).unwrap_or_default();
                chart(&rows, &dir.join("chart.png"))?;
                std::fs::write(dir.join("levels.md"), level_table(&rows))
                    .map_err(|e| e.to_string())?;
                println!(
                    "wrote {0}/chart.png and {0}/levels.md from {1}",
                    dir.display(),
                    csv.display()
                );
                return Ok(());
            }
            _ => {
                return Err(format!(
                    "unexpected argument {a:?}; usage: bench [--quick] [--out DIR]"
                ))
            }
        }
    }
    std::fs::create_dir_all(&out).map_err(|e| e.to_string())?;
    let started = Instant::now();
    let presets = if quick {
        vec![Weather::sparse(), Weather::stormy()]
    } else {
        vec![
            Weather::sparse(),
            Weather::cloudy(),
            Weather::overcast(),
            Weather::stormy(),
        ]
    };
    let views: Vec<usize> = if quick { vec![0, 3] } else { vec![0, 1, 2, 3] };
    let sizes: Vec<(u32, u32)> = if quick {
        vec![(320, 180)]
    } else {
        vec![(320, 180), (640, 360)]
    };
    let levels: Vec<Option<Quality>> = Quality::ALL.iter().copied().map(Some).collect();

    let mut rows = Vec::new();
    let mut adapter = String::new();
    for &size in &sizes {
        let mut h = new_headless(size)?;
        adapter = format!("{} ({:?})", h.adapter_info().name, h.adapter_info().backend);
        for weather in &presets {
            for &v in &views {
                let view = standard_views()[v];
                h.renderer_mut()
                    .set_settings(settings_for(weather, None))
                    .map_err(|e| e.to_string())?;
                let (reference, _) = measure(&mut h, &view, 0.0, 1)?;
                for &q in &levels {
                    let settings = settings_for(weather, q);
                    let rays = {
                        let d = settings.march.resolution.divisor();
                        (size.0.div_ceil(d) * size.1.div_ceil(d)) as u64
                    };
                    h.renderer_mut()
                        .set_settings(settings)
                        .map_err(|e| e.to_string())?;
                    let (img, [march_ms, composite_ms, wall_ms]) =
                        measure(&mut h, &view, 0.0, TIMED_FRAMES)?;
                    let (flip_mean, flip_p99) = flip(&reference, &img, size);
                    let row = Row {
                        preset: weather.name.clone(),
                        view: VIEW_NAMES[v],
                        size,
                        quality: level_name(q),
                        march_ms,
                        composite_ms,
                        wall_ms,
                        rays,
                        memory_mb: h.renderer().gpu_memory_bytes() as f64 / (1 << 20) as f64,
                        flip_mean,
                        flip_p99,
                    };
                    println!(
                        "[{:5.0}s] {:8} {:9} {}x{} {:6}  march {:7.2} ms  composite {:5.2} ms  wall {:7.1} ms  FLIP {:.4} (p99 {:.3})",
                        started.elapsed().as_secs_f64(),
                        row.preset, row.view, size.0, size.1, row.quality,
                        row.march_ms, row.composite_ms, row.wall_ms, row.flip_mean, row.flip_p99
                    );
                    rows.push(row);
                }
            }
        }
    }

    // Cost against pixel count (medium quality, sparse, ground view).
    let scaling_sizes: Vec<(u32, u32)> = if quick {
        vec![(160, 90), (320, 180), (640, 360)]
    } else {
        vec![(160, 90), (320, 180), (640, 360), (1280, 720)]
    };
    let mut scaling = Vec::new();
    for &size in &scaling_sizes {
        let mut h = new_headless(size)?;
        h.renderer_mut()
            .set_settings(settings_for(&Weather::sparse(), Some(Quality::Medium)))
            .map_err(|e| e.to_string())?;
        let (_, [m, c, wall]) = measure(&mut h, &standard_views()[0], 0.0, TIMED_FRAMES)?;
        println!(
            "scaling {}x{}: march {m:.2} ms, composite {c:.2} ms, wall {wall:.1} ms",
            size.0, size.1
        );
        scaling.push((size, m + c, wall));
    }

    // A weather transition's bake against a frame, and a moving-camera flight.
    let size = (320, 180);
    let mut h = new_headless(size)?;
    h.renderer_mut()
        .set_settings(settings_for(&Weather::cloudy(), Some(Quality::Medium)))
        .map_err(|e| e.to_string())?;
    let (_, [m, c, frame_wall]) = measure(&mut h, &standard_views()[0], 0.0, TIMED_FRAMES)?;
    let t = Instant::now();
    h.renderer_mut()
        .set_weather(Weather::stormy(), 0.0, 20.0)
        .map_err(|e| e.to_string())?;
    h.renderer_mut()
        .set_weather(Weather::clear(), 10.0, 20.0)
        .map_err(|e| e.to_string())?;
    h.device()
        .poll(nimbus::wgpu::PollType::wait_indefinitely())
        .map_err(|e| e.to_string())?;
    let bake_ms = t.elapsed().as_secs_f64() * 1e3 / 2.0;
    println!("weather request (generate + bake): {bake_ms:.2} ms wall, frame {frame_wall:.1} ms wall ({:.2} ms GPU)", m + c);

    let flight_frames = if quick { 3 } else { 8 };
    let mut flight = Vec::new();
    for k in 0..flight_frames {
        let time = k as f64 / 30.0;
        let mut view = standard_views()[0];
        let offset = Vec3::new(0.0, 40.0, -60.0) * (k as f32 * 30.0);
        view.eye += offset;
        view.target += offset;
        h.renderer_mut()
            .set_settings(settings_for(&Weather::cloudy(), None))
            .map_err(|e| e.to_string())?;
        let (reference, _) = measure(&mut h, &view, time, 1)?;
        h.renderer_mut()
            .set_settings(settings_for(&Weather::cloudy(), Some(Quality::Medium)))
            .map_err(|e| e.to_string())?;
        let (img, [m, c, wall]) = measure(&mut h, &view, time, 1)?;
        let (mean, p99) = flip(&reference, &img, size);
        println!(
            "flight frame {k}: GPU {:.2} ms, wall {wall:.1} ms, FLIP {mean:.4} (p99 {p99:.3})",
            m + c
        );
        flight.push((m + c, wall, mean, p99));
    }

    // Outputs.
    let mut csv = String::from(
        "preset,view,width,height,quality,march_ms,composite_ms,wall_ms,rays,gpu_memory_mb,flip_mean,flip_p99\n",
    );
    for r in &rows {
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{:.3},{:.3},{:.2},{},{:.1},{:.5},{:.4}",
            r.preset,
            r.view,
            r.size.0,
            r.size.1,
            r.quality,
            r.march_ms,
            r.composite_ms,
            r.wall_ms,
            r.rays,
            r.memory_mb,
            r.flip_mean,
            r.flip_p99
        );
    }
    std::fs::write(out.join("bench.csv"), csv).map_err(|e| e.to_string())?;
    chart(&rows, &out.join("chart.png"))?;

    let mut md = format!(
        "# Nimbus benchmark ({})\n\nAdapter: {adapter}. {} frames timed per configuration (median), after one warm-up. \
         Cost is wall time from submit to completion: on software Vulkan (lavapipe) the compute \
         pass's timestamps read near zero, so GPU ms (timestamp queries, march + composite) are \
         listed but only trustworthy on a real GPU.\n\n",
        if quick { "quick" } else { "full" },
        TIMED_FRAMES
    );
    md.push_str(&level_table(&rows));
    md.push_str("\n## Cost against pixel count (medium, sparse, ground view)\n\n| size | pixels | wall ms | wall ms per Mpixel | GPU ms (timestamps) |\n|---|---|---|---|---|\n");
    for (size, gpu, wall) in &scaling {
        let mp = (size.0 * size.1) as f64 / 1e6;
        let _ = writeln!(
            md,
            "| {}x{} | {} | {wall:.1} | {:.1} | {gpu:.2} |",
            size.0,
            size.1,
            size.0 * size.1,
            wall / mp
        );
    }
    let _ = writeln!(
        md,
        "\n## Weather transition\n\nOne request (new map generated, running blend baked): {bake_ms:.2} ms wall, against a \
         {frame_wall:.1} ms frame (320x180, medium). Spread over a 20 s transition at 30 fps that is {:.4}% of the frames' time.\n",
        100.0 * bake_ms / (frame_wall * 600.0)
    );
    md.push_str("## Moving-camera flight (cloudy, medium, 320x180, vs a converged reference per frame)\n\n| frame | GPU ms | wall ms | FLIP mean | FLIP p99 |\n|---|---|---|---|---|\n");
    for (k, (g, w, m, p)) in flight.iter().enumerate() {
        let _ = writeln!(md, "| {k} | {g:.2} | {w:.1} | {m:.4} | {p:.3} |");
    }
    let _ = writeln!(md, "\nEvery configuration: `bench.csv`. Chart: `chart.png` (one bar per row of the CSV, in order; green low, blue medium, orange high, red ultra).");
    std::fs::write(out.join("bench.md"), &md).map_err(|e| e.to_string())?;
    println!(
        "wrote {0}/bench.csv, {0}/bench.md, {0}/chart.png in {1:.0} s",
        out.display(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("bench: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}
