//! Benchmark: a matrix of presets × camera views × sizes × quality levels, with GPU time per
//! pass (timestamp queries; wall time beside it), rays traced, GPU memory, and the error of
//! every image against a converged reference of the same scene and time (FLIP mean and 99th
//! percentile). Also: where a default frame's time goes (light, view rays, fixed passes), cost
//! against pixel count, the cost of a weather bake, a short
//! moving-camera flight, several cameras on one renderer (a stereo pair, a cube probe), and the
//! start-up time, cold and from a noise cache. Writes bench.csv, bench.md and chart.png into the output folder.
//!
//! Usage: cargo run --release --example bench -- [--quick] [--out DIR]
//!        cargo run --release --example bench -- --from-csv DIR/bench.csv   (re-draw from a run)
//!        cargo run --release --example bench -- [--quick] --views-only     (the views section)
//!        cargo run --release --example bench -- --start-only               (the start section)
//!        cargo run --release --example bench -- [--quick] --profile-only   (the frame's breakdown)
//!        cargo run --release --example bench -- [--quick] --weather-only   (a weather request)
//!        cargo run --release --example bench -- [--quick] --model-cost     (the light model's cost,
//!        delta-Eddington against the octaves in alternating rounds)
//!        --size WxH sets the size of the profile, scene matrix, weather request and flight
//!        (default 1280x720, quick 320x180; a real GPU is measured at 1920x1080)

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use nimbus::demo::{standard_views, tonemap, DemoView, Occluder};
use nimbus::glam::Vec3;
use nimbus::settings::{MultipleScatteringModel, Quality, Temporal, TraceResolution};
use nimbus::{Headless, Settings, Weather};

#[path = "bench_model_cost.rs"]
mod bench_model_cost;
#[path = "bench_profile.rs"]
mod bench_profile;
#[path = "bench_start.rs"]
mod bench_start;
#[path = "bench_views.rs"]
mod bench_views;
#[path = "bench_weather.rs"]
mod bench_weather;

const VIEW_NAMES: [&str; 4] = ["ground_up", "horizon", "inside", "above"];
/// Frames a temporal configuration renders from a reset before its image is judged: the
/// issue's "static view settled" (every pixel traced once at one in 16).
const SETTLE_FRAMES: usize = 16;
/// The last this-many settling frames are timed (median).
const TIMED_TAIL: usize = 8;
/// Sustained rendering before a timed configuration (see `measure`).
const WARM_UP: std::time::Duration = std::time::Duration::from_millis(500);

/// What a row measures: the converged reference, a quality level, or the default level with
/// one optimisation switched off.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Variant {
    Reference,
    Level(Quality),
    Without(&'static str),
    With(&'static str),
}

/// The optimisations the ablation switches off one at a time.
/// "delta_eddington" is not an optimisation but the multiple-scattering model: its row is the
/// default level with Wrenninge's octaves instead, which prices the model.
const OPTIMISATIONS: [&str; 6] = [
    "temporal",
    "coarse_then_fine",
    "distance_steps",
    "noise_lod",
    "light_lod",
    "delta_eddington",
];

/// Options the default level leaves off, priced by rows with each switched on.
/// "shadow_map_light": the cloud shadow map on, and the march's light read from it beyond the
/// first `shadows.local_distance` meters (the row's time includes the map's update).
const ADDITIONS: [&str; 1] = ["shadow_map_light"];

impl Variant {
    fn name(self) -> String {
        match self {
            Variant::Reference => "reference".into(),
            Variant::Level(q) => format!("{q:?}").to_lowercase(),
            Variant::Without(o) => format!("medium-no-{o}"),
            Variant::With(o) => format!("medium-with-{o}"),
        }
    }
}

/// The settings of a variant. The reference: tiny steps, many short light steps, full resolution,
/// one ray per pixel per frame, no jitter, no temporal reuse, no LOD.
fn settings_for(weather: &Weather, variant: Variant) -> Settings {
    let mut s = Settings {
        weather: weather.clone(),
        ..Settings::default()
    };
    match variant {
        Variant::Reference => {
            Quality::Ultra.apply(&mut s);
            s.march.resolution = TraceResolution::Full;
            s.march.min_steps = 512;
            s.march.max_steps = 512;
            s.march.jitter = false;
            // As Ultra: no early exit (the remaining light of a thick cloud is not negligible).
            s.march.transmittance_cutoff = 0.0;
            // 32 gently growing light steps: 5 m first, 400 m last.
            s.lighting.light_steps = 32;
            s.lighting.light_step_growth = 1.15;
        }
        Variant::Level(q) => q.apply(&mut s),
        Variant::Without(o) => {
            Quality::Medium.apply(&mut s);
            match o {
                "temporal" => s.march.temporal = Temporal::OFF,
                "coarse_then_fine" => s.march.coarse_then_fine = false,
                "distance_steps" => s.march.distance_steps = false,
                "noise_lod" => s.march.noise_lod = false,
                "light_lod" => s.lighting.light_lod = false,
                "delta_eddington" => {
                    s.lighting.multiple_scattering.model = MultipleScatteringModel::Octaves
                }
                _ => unreachable!("unknown optimisation {o}"),
            }
        }
        Variant::With(o) => {
            Quality::Medium.apply(&mut s);
            match o {
                "shadow_map_light" => {
                    s.shadows.enabled = true;
                    s.shadows.march_light = true;
                }
                _ => unreachable!("unknown addition {o}"),
            }
        }
    }
    s
}

#[derive(Clone)]
struct Row {
    preset: String,
    view: &'static str,
    size: (u32, u32),
    config: String,
    march_ms: f64,
    resolve_ms: f64,
    composite_ms: f64,
    wall_ms: f64,
    rays: u64,
    samples_per_ray: f64,
    light_per_ray: f64,
    memory_mb: f64,
    flip_mean: f32,
    flip_p99: f32,
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// One configuration's result: its final image, median times and ray counters.
struct Measured {
    image: Vec<[f32; 4]>,
    /// GPU ms (timestamps, medians) of the march, the cloud shadow map's update and the
    /// ambient probe's.
    march_ms: f64,
    shadow_ms: f64,
    ambient_ms: f64,
    resolve_ms: f64,
    composite_ms: f64,
    wall_ms: f64,
    stats: nimbus::RayStats,
}

impl Measured {
    /// The march with the cloud shadow map's update (when on), which serves it, and the
    /// ambient probe (the same ray march, at the camera): the tables' march column.
    fn march_total_ms(&self) -> f64 {
        self.march_ms + self.shadow_ms + self.ambient_ms
    }
}

/// Renders a static view with `settings` from a fresh history: temporal configurations
/// settle for SETTLE_FRAMES and time the last TIMED_TAIL; others render one untimed frame
/// and one timed frame (or just one when `timed` is false).
fn measure(
    h: &mut Headless,
    view: &DemoView,
    time: f64,
    settings: Settings,
    timed: bool,
) -> Result<Measured, String> {
    let (w, hgt) = h.size().ok_or("no size")?;
    let temporal = settings.march.temporal.enabled;
    h.renderer_mut()
        .set_settings(settings)
        .map_err(|e| e.to_string())?;
    let scene = view.scene(w, hgt);
    h.upload_scene(&scene.color, Some(&scene.depth))
        .map_err(|e| e.to_string())?;
    let frame = view.frame(w, hgt, time);
    if timed {
        // A real GPU idles at a fraction of its clock and ramps up only under sustained load
        // (an H200's passes read up to 5.7x slower between the CPU's FLIP work): render the
        // view for WARM_UP first, then start again from a reset history, so the timestamps
        // are those of a GPU inside a frame loop. On software Vulkan this is one frame.
        let warm = Instant::now();
        while warm.elapsed() < WARM_UP {
            h.render(&frame).map_err(|e| e.to_string())?;
        }
        h.renderer_mut().reset_history();
    }
    let (frames, tail) = match (temporal, timed) {
        (true, _) => (SETTLE_FRAMES, TIMED_TAIL),
        (false, true) => (2, 1),
        (false, false) => (1, 0),
    };
    let (mut march, mut resolve, mut comp, mut wall) = (vec![], vec![], vec![], vec![]);
    let (mut shadow, mut ambient) = (vec![], vec![]);
    for i in 0..frames {
        let t = Instant::now();
        h.render(&frame).map_err(|e| e.to_string())?;
        let elapsed = t.elapsed().as_secs_f64() * 1e3;
        if i + tail >= frames {
            wall.push(elapsed);
            if let Some(p) = h.renderer().last_pass_times().map_err(|e| e.to_string())? {
                march.push(p.march_ms);
                shadow.push(p.shadow_ms);
                ambient.push(p.ambient_ms);
                resolve.push(p.resolve_ms);
                comp.push(p.composite_ms);
            }
        }
    }
    Ok(Measured {
        image: h.read_output().map_err(|e| e.to_string())?,
        march_ms: median(march),
        shadow_ms: median(shadow),
        ambient_ms: median(ambient),
        resolve_ms: median(resolve),
        composite_ms: median(comp),
        wall_ms: median(wall),
        stats: h.read_ray_stats().map_err(|e| e.to_string())?,
    })
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
    // The noise and weather bakes run asynchronously: let them finish before anything is timed
    // (on software Vulkan they would share the CPU with the timed frames).
    h.device()
        .poll(nimbus::wgpu::PollType::wait_indefinitely())
        .map_err(|e| e.to_string())?;
    Ok(h)
}

/// Renders the reference and `variants` of one scene; returns a row per variant.
#[allow(clippy::too_many_arguments)]
fn scene_rows(
    h: &mut Headless,
    weather: &Weather,
    v: usize,
    variants: &[Variant],
    started: Instant,
) -> Result<Vec<Row>, String> {
    let size = h.size().ok_or("no size")?;
    let view = standard_views()[v];
    let reference = measure(
        h,
        &view,
        0.0,
        settings_for(weather, Variant::Reference),
        false,
    )?;
    let mut rows = Vec::new();
    for &variant in variants {
        let m = measure(h, &view, 0.0, settings_for(weather, variant), true)?;
        let (flip_mean, flip_p99) = flip(&reference.image, &m.image, size);
        let row = Row {
            preset: weather.name.clone(),
            view: VIEW_NAMES[v],
            size,
            config: variant.name(),
            march_ms: m.march_total_ms(),
            resolve_ms: m.resolve_ms,
            composite_ms: m.composite_ms,
            wall_ms: m.wall_ms,
            rays: m.stats.rays,
            samples_per_ray: m.stats.mean_samples,
            light_per_ray: m.stats.mean_light_samples,
            memory_mb: h.renderer().gpu_memory_bytes() as f64 / (1 << 20) as f64,
            flip_mean,
            flip_p99,
        };
        println!(
            "[{:5.0}s] {:8} {:9} {}x{} {:22} wall {:8.1} ms  GPU {:.3}+{:.3}+{:.3} ms  rays {:7}  samples/ray {:5.1} (+{:5.1} light)  FLIP {:.4} (p99 {:.3})",
            started.elapsed().as_secs_f64(),
            row.preset, row.view, size.0, size.1, row.config, row.wall_ms,
            row.march_ms, row.resolve_ms, row.composite_ms, row.rays,
            row.samples_per_ray, row.light_per_ray, row.flip_mean, row.flip_p99
        );
        rows.push(row);
    }
    Ok(rows)
}

/// Draws one bar per row (wall ms, log scale with a line per decade), colored by config.
fn chart(rows: &[&Row], path: &std::path::Path) -> Result<(), String> {
    let bar = 6u32;
    let (w, h) = ((rows.len() as u32) * (bar + 2) + 20, 240u32);
    let lo = 1.0f64; // 1 ms at the bottom
    let hi = rows.iter().map(|r| r.wall_ms).fold(10.0, f64::max);
    let scale = |ms: f64| ((ms.max(lo) / lo).log10() / (hi / lo).log10() * (h - 20) as f64) as u32;
    let mut img = image::RgbImage::from_pixel(w, h, image::Rgb([255, 255, 255]));
    let mut decade = lo;
    while decade <= hi {
        let y = h - 10 - scale(decade);
        for x in 0..w {
            img.put_pixel(x, y, image::Rgb([220, 220, 220]));
        }
        decade *= 10.0;
    }
    for (i, r) in rows.iter().enumerate() {
        let color = match r.config.as_str() {
            "low" => [80, 170, 80],
            "medium" => [60, 120, 220],
            "high" => [230, 150, 40],
            "ultra" => [200, 60, 60],
            _ => [120, 120, 120],
        };
        let height = scale(r.wall_ms).max(1);
        let x0 = 10 + i as u32 * (bar + 2);
        for x in x0..x0 + bar {
            for y in (h - 10 - height)..(h - 10) {
                img.put_pixel(x, y, image::Rgb(color));
            }
        }
    }
    img.save(path).map_err(|e| e.to_string())
}

fn sum_wall(rows: &[&Row]) -> f64 {
    rows.iter().map(|r| r.wall_ms).sum()
}

/// A table of configs against a baseline config over the same scenes: cost is the summed
/// wall time of the config over the summed wall time of the baseline.
fn config_table(rows: &[Row], configs: &[String], baseline: &str, title: &str) -> String {
    let mut md = format!(
        "## {title}\n\n\
         | size | config | wall ms (median) | cost vs {baseline} | FLIP mean (median) | FLIP mean (worst) | FLIP p99 (median) | rays | samples/ray | light samples/ray | GPU ms (all passes) | GPU MiB |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|\n"
    );
    let mut sizes: Vec<(u32, u32)> = rows.iter().map(|r| r.size).collect();
    sizes.dedup();
    for size in sizes {
        let of = |c: &str| {
            rows.iter()
                .filter(|r| r.size == size && r.config == c)
                .collect::<Vec<_>>()
        };
        let base = sum_wall(&of(baseline));
        for c in configs {
            let rs = of(c);
            if rs.is_empty() {
                continue;
            }
            let col = |f: fn(&Row) -> f64| median(rs.iter().map(|r| f(r)).collect());
            let _ = writeln!(
                md,
                "| {}x{} | {c} | {:.1} | {:.3} | {:.4} | {:.4} | {:.3} | {} | {:.1} | {:.1} | {:.2} | {:.1} |",
                size.0,
                size.1,
                col(|r| r.wall_ms),
                sum_wall(&rs) / base,
                col(|r| r.flip_mean as f64),
                rs.iter().map(|r| r.flip_mean).fold(0.0, f32::max),
                col(|r| r.flip_p99 as f64),
                rs[0].rays,
                col(|r| r.samples_per_ray),
                col(|r| r.light_per_ray),
                col(|r| r.march_ms + r.resolve_ms + r.composite_ms),
                rs[0].memory_mb
            );
        }
    }
    md
}

fn level_names() -> Vec<String> {
    Quality::ALL
        .iter()
        .map(|q| Variant::Level(*q).name())
        .collect()
}

fn ablation_names() -> Vec<String> {
    std::iter::once(Variant::Level(Quality::Medium))
        .chain(OPTIMISATIONS.iter().map(|o| Variant::Without(o)))
        .chain(ADDITIONS.iter().map(|o| Variant::With(o)))
        .map(Variant::name)
        .collect()
}

const CSV_HEADER: &str = "group,preset,view,width,height,config,march_ms,resolve_ms,composite_ms,wall_ms,rays,samples_per_ray,light_samples_per_ray,gpu_memory_mb,flip_mean,flip_p99";

/// Reads rows back from a `bench.csv`: (levels rows, ablation rows).
fn read_csv(path: &std::path::Path) -> Result<(Vec<Row>, Vec<Row>), String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let (mut levels, mut ablation) = (Vec::new(), Vec::new());
    for (n, line) in text.lines().enumerate().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let bad = || format!("{}:{}: malformed row", path.display(), n + 1);
        if f.len() != 16 {
            return Err(bad());
        }
        let num = |i: usize| f[i].parse::<f64>().map_err(|_| bad());
        let row = Row {
            preset: f[1].to_string(),
            view: VIEW_NAMES
                .iter()
                .copied()
                .find(|v| *v == f[2])
                .ok_or_else(bad)?,
            size: (num(3)? as u32, num(4)? as u32),
            config: f[5].to_string(),
            march_ms: num(6)?,
            resolve_ms: num(7)?,
            composite_ms: num(8)?,
            wall_ms: num(9)?,
            rays: num(10)? as u64,
            samples_per_ray: num(11)?,
            light_per_ray: num(12)?,
            memory_mb: num(13)?,
            flip_mean: num(14)? as f32,
            flip_p99: num(15)? as f32,
        };
        match f[0] {
            "levels" => levels.push(row),
            "ablation" => ablation.push(row),
            _ => return Err(bad()),
        }
    }
    Ok((levels, ablation))
}

fn write_csv(levels: &[Row], ablation: &[Row]) -> String {
    let mut csv = format!("{CSV_HEADER}\n");
    for (group, rows) in [("levels", levels), ("ablation", ablation)] {
        for r in rows {
            let _ = writeln!(
                csv,
                "{group},{},{},{},{},{},{:.3},{:.3},{:.3},{:.2},{},{:.2},{:.2},{:.1},{:.5},{:.4}",
                r.preset,
                r.view,
                r.size.0,
                r.size.1,
                r.config,
                r.march_ms,
                r.resolve_ms,
                r.composite_ms,
                r.wall_ms,
                r.rays,
                r.samples_per_ray,
                r.light_per_ray,
                r.memory_mb,
                r.flip_mean,
                r.flip_p99
            );
        }
    }
    csv
}

/// The tables a CSV's rows make (levels against ultra, ablation against medium).
fn tables(levels: &[Row], ablation: &[Row]) -> String {
    let mut md = config_table(
        levels,
        &level_names(),
        "ultra",
        "Per quality level (over presets and views)",
    );
    if !ablation.is_empty() {
        md.push('\n');
        md.push_str(&config_table(
            ablation,
            &ablation_names(),
            "medium",
            "Each optimisation switched off in turn (medium level)",
        ));
    }
    md
}

/// Frame `k` of the flight: 150 m/s level flight at 800 m under the cloud base, panning
/// 1.5 degrees a frame (45 degrees a second at 30 fps).
fn flight_view(k: usize) -> DemoView {
    let t = k as f32 / 30.0;
    let yaw = (1.5 * k as f32).to_radians();
    let eye = Vec3::new(0.0, 800.0, 0.0) + Vec3::new(0.0, 0.0, -150.0) * t;
    let dir = Vec3::new(yaw.sin(), 0.12, -yaw.cos()).normalize();
    DemoView {
        name: "flight",
        eye,
        target: eye + dir * 10_000.0,
        fov_y: 60f32.to_radians(),
        sun: standard_views()[0].sun,
        occluder: Occluder::None,
    }
}

struct FlightFrame {
    k: usize,
    wall_ms: f64,
    flip_mean: f32,
    flip_p99: f32,
}

/// Flies `frames` frames at `size` (cloudy, medium) from a reset history and compares the
/// frames in `checks` with a converged reference rendered by a second renderer.
fn flight(
    size: (u32, u32),
    frames: usize,
    checks: &[usize],
    out: &std::path::Path,
) -> Result<Vec<FlightFrame>, String> {
    let weather = Weather::cloudy();
    let mut h = new_headless(size)?;
    h.renderer_mut()
        .set_settings(settings_for(&weather, Variant::Level(Quality::Medium)))
        .map_err(|e| e.to_string())?;
    let mut reference = new_headless(size)?;
    reference
        .renderer_mut()
        .set_settings(settings_for(&weather, Variant::Reference))
        .map_err(|e| e.to_string())?;
    let mut result = Vec::new();
    for k in 0..frames {
        let view = flight_view(k);
        let time = k as f64 / 30.0;
        let scene = view.scene(size.0, size.1);
        h.upload_scene(&scene.color, Some(&scene.depth))
            .map_err(|e| e.to_string())?;
        let t = Instant::now();
        h.render(&view.frame(size.0, size.1, time))
            .map_err(|e| e.to_string())?;
        let wall_ms = t.elapsed().as_secs_f64() * 1e3;
        if !checks.contains(&k) {
            continue;
        }
        let image = h.read_output().map_err(|e| e.to_string())?;
        reference
            .upload_scene(&scene.color, Some(&scene.depth))
            .map_err(|e| e.to_string())?;
        reference
            .render(&view.frame(size.0, size.1, time))
            .map_err(|e| e.to_string())?;
        let ref_image = reference.read_output().map_err(|e| e.to_string())?;
        let (flip_mean, flip_p99) = flip(&ref_image, &image, size);
        println!("flight frame {k}: wall {wall_ms:.1} ms, FLIP {flip_mean:.4} (p99 {flip_p99:.3})");
        if k == *checks.last().unwrap_or(&0) {
            let path = out.join("flight_last.png");
            nimbus::demo::write_png(&path, &image, size.0, size.1, 1.0)
                .map_err(|e| e.to_string())?;
            let path = out.join("flight_last_reference.png");
            nimbus::demo::write_png(&path, &ref_image, size.0, size.1, 1.0)
                .map_err(|e| e.to_string())?;
        }
        result.push(FlightFrame {
            k,
            wall_ms,
            flip_mean,
            flip_p99,
        });
    }
    Ok(result)
}

/// Which part of the benchmark a run does.
enum Mode {
    Full,
    Profile,
    Start,
    Weather,
    Views,
    ModelCost,
}

/// `WxH` as a size, both sides at least 16.
fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let parsed = text
        .split_once('x')
        .and_then(|(w, h)| Some((w.parse::<u32>().ok()?, h.parse::<u32>().ok()?)));
    match parsed {
        Some((w, h)) if w >= 16 && h >= 16 && w <= 8192 && h <= 8192 => Ok((w, h)),
        _ => Err(format!(
            "--size needs WIDTHxHEIGHT between 16 and 8192 (e.g. 1920x1080), not {text:?}"
        )),
    }
}

/// The scenes the full run (and `--model-cost`) measures: (weather, index into
/// `standard_views`). At 1280x720 a converged reference takes about two and a half minutes on
/// software Vulkan, so the full run takes every preset from the ground and one horizon view;
/// quick mode one cumulus and one storm.
fn bench_scenes(quick: bool) -> Vec<(Weather, usize)> {
    if quick {
        vec![(Weather::sparse(), 0), (Weather::stormy(), 3)]
    } else {
        vec![
            (Weather::sparse(), 0),
            (Weather::cloudy(), 0),
            (Weather::overcast(), 0),
            (Weather::stormy(), 0),
            (Weather::cloudy(), 1),
        ]
    }
}

fn run() -> Result<(), String> {
    let mut quick = false;
    let mut size_arg = None;
    let mut mode = Mode::Full;
    let mut out = PathBuf::from("target/bench");
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--quick" => quick = true,
            "--size" => size_arg = Some(parse_size(&args.next().ok_or("--size needs WxH")?)?),
            "--profile-only" => mode = Mode::Profile,
            "--start-only" => mode = Mode::Start,
            "--weather-only" => mode = Mode::Weather,
            "--views-only" => mode = Mode::Views,
            "--model-cost" => mode = Mode::ModelCost,
            "--out" => out = PathBuf::from(args.next().ok_or("--out needs a folder")?),
            "--from-csv" => {
                // Re-draw the chart and the tables from an earlier run's CSV.
                let csv = PathBuf::from(args.next().ok_or("--from-csv needs a bench.csv")?);
                let (levels, ablation) = read_csv(&csv)?;
                let dir = csv.parent().map(PathBuf::from).unwrap_or_default();
                let all: Vec<&Row> = levels.iter().chain(&ablation).collect();
                chart(&all, &dir.join("chart.png"))?;
                std::fs::write(dir.join("tables.md"), tables(&levels, &ablation))
                    .map_err(|e| e.to_string())?;
                println!(
                    "wrote {0}/chart.png and {0}/tables.md from {1}",
                    dir.display(),
                    csv.display()
                );
                return Ok(());
            }
            _ => {
                return Err(format!(
                "unexpected argument {a:?}; usage: bench [--quick] [--size WxH] [--out DIR] [--views-only | --start-only | --profile-only | --weather-only | --model-cost] | --from-csv FILE"
            ))
            }
        }
    }
    // The targets are at 1280x720; quick mode checks the machinery at 320x180; a real
    // GPU is measured at 1920x1080 (`--size`). The profile, the scene matrix, the weather
    // request and the flight run at this size.
    let size = size_arg.unwrap_or(if quick { (320, 180) } else { (1280, 720) });
    match mode {
        Mode::Full => {}
        Mode::Profile => {
            bench_profile::profile_section(size)?;
            return Ok(());
        }
        Mode::Start => {
            bench_start::start_section()?;
            return Ok(());
        }
        Mode::Weather => {
            bench_weather::weather_section(size)?;
            return Ok(());
        }
        Mode::Views => {
            bench_views::views_section(quick)?;
            return Ok(());
        }
        Mode::ModelCost => {
            bench_model_cost::model_cost_section(size, &bench_scenes(quick))?;
            return Ok(());
        }
    }
    std::fs::create_dir_all(&out).map_err(|e| e.to_string())?;
    let started = Instant::now();
    let scenes = bench_scenes(quick);
    let levels: Vec<Variant> = Quality::ALL.iter().map(|q| Variant::Level(*q)).collect();
    // The first scene also runs the default level with each optimisation switched off in turn
    // (sharing its reference).
    let ablation: Vec<Variant> = OPTIMISATIONS
        .iter()
        .map(|o| Variant::Without(o))
        .chain(ADDITIONS.iter().map(|o| Variant::With(o)))
        .collect();

    let mut h = new_headless(size)?;
    let adapter = format!("{} ({:?})", h.adapter_info().name, h.adapter_info().backend);
    let (mut level_rows, mut ablation_rows) = (Vec::new(), Vec::new());
    for (i, (weather, v)) in scenes.iter().enumerate() {
        let mut variants = levels.clone();
        if i == 0 {
            variants.extend(&ablation);
        }
        for row in scene_rows(&mut h, weather, *v, &variants, started)? {
            let medium = row.config == Variant::Level(Quality::Medium).name();
            let ablated =
                row.config.starts_with("medium-no-") || row.config.starts_with("medium-with-");
            if i == 0 && (medium || ablated) {
                ablation_rows.push(row.clone());
            }
            if !ablated {
                level_rows.push(row);
            }
        }
    }
    drop(h);

    // Cost against pixel count (medium, sparse, ground view, settled).
    let mut scaling_sizes: Vec<(u32, u32)> = if quick {
        vec![(160, 90), (320, 180), (640, 360)]
    } else {
        vec![(160, 90), (320, 180), (640, 360), (1280, 720)]
    };
    if !scaling_sizes.contains(&size) && size.0 * size.1 > 640 * 360 {
        scaling_sizes.push(size);
    }
    let mut scaling = Vec::new();
    for &s in &scaling_sizes {
        let mut h = new_headless(s)?;
        let settings = settings_for(&Weather::sparse(), Variant::Level(Quality::Medium));
        let m = measure(&mut h, &standard_views()[0], 0.0, settings, true)?;
        println!(
            "scaling {}x{}: wall {:.1} ms (GPU {:.2} ms)",
            s.0,
            s.1,
            m.wall_ms,
            m.march_total_ms() + m.resolve_ms + m.composite_ms
        );
        scaling.push((
            s,
            m.march_total_ms() + m.resolve_ms + m.composite_ms,
            m.wall_ms,
        ));
    }

    let weather_md = bench_weather::weather_section(size)?;

    let (flight_size, flight_frames, checks): ((u32, u32), usize, Vec<usize>) = if quick {
        (size, 20, vec![16, 19])
    } else {
        (size, 48, vec![16, 47])
    };
    let flown = flight(flight_size, flight_frames, &checks, &out)?;

    // Outputs.
    std::fs::write(
        out.join("bench.csv"),
        write_csv(&level_rows, &ablation_rows),
    )
    .map_err(|e| e.to_string())?;
    let all: Vec<&Row> = level_rows.iter().chain(&ablation_rows).collect();
    chart(&all, &out.join("chart.png"))?;

    let mut md = format!(
        "# Nimbus benchmark ({})\n\nAdapter: {adapter}; {:.0} s in all. Static views render from a reset history: \
         temporal levels {SETTLE_FRAMES} frames (FLIP on the last, wall time the median of the last {TIMED_TAIL}), \
         the others one warm-up frame and one timed frame. Cost is wall time from submit to completion: on \
         software Vulkan (lavapipe) the compute passes' timestamps read near zero, so the GPU ms (timestamp \
         queries) are listed but only trustworthy on a real GPU.\n\n",
        if quick { "quick" } else { "full" },
        started.elapsed().as_secs_f64()
    );
    md.push_str(&bench_profile::profile_section(size)?);
    md.push_str(&tables(&level_rows, &ablation_rows));
    md.push_str("\n## Cost against pixel count (medium, sparse, ground view, settled)\n\n| size | pixels | wall ms | wall ms per Mpixel | GPU ms (timestamps) |\n|---|---|---|---|---|\n");
    for (s, gpu, wall) in &scaling {
        let mp = (s.0 * s.1) as f64 / 1e6;
        let _ = writeln!(
            md,
            "| {}x{} | {} | {wall:.1} | {:.1} | {gpu:.2} |",
            s.0,
            s.1,
            s.0 * s.1,
            wall / mp
        );
    }
    md.push_str(&weather_md);
    let _ = writeln!(
        md,
        "## Moving-camera flight ({}x{}, cloudy, medium; 150 m/s level flight panning 45 degrees/s at 30 fps, from a reset history; FLIP against a converged reference of the same frame)\n\n| frame | wall ms | FLIP mean | FLIP p99 |\n|---|---|---|---|",
        flight_size.0, flight_size.1
    );
    for f in &flown {
        let _ = writeln!(
            md,
            "| {} | {:.1} | {:.4} | {:.3} |",
            f.k, f.wall_ms, f.flip_mean, f.flip_p99
        );
    }
    md.push_str(&bench_views::views_section(quick)?);
    md.push_str(&bench_start::start_section()?);
    let _ = writeln!(md, "\nEvery configuration: `bench.csv`. Chart: `chart.png` (one bar per row of the CSV, in order, log scale with a grey line per decade from 1 ms; green low, blue medium, orange high, red ultra, grey the ablation).");
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
