//! Soak: Nimbus in a long frame loop, the way a game uses it, with memory reported as it goes.
//!
//! Renders `--frames` small frames on a moving camera while switching presets every few
//! frames, loading a preset file, resizing, resetting the history and recreating the whole
//! context every `--recreate-every` frames. Every `--report-every` frames it prints the
//! process's resident memory, Nimbus's GPU allocations and wgpu's live object counts.
//!
//! Pass condition (with `--check`): memory is flat. After the warm-up (the first report, which
//! includes driver start-up and the first context), resident memory may not rise by more than
//! `--max-growth-mb` between the first report and the lower of the last two (one reading can
//! catch the driver's threads holding memory for a moment), and the second half of the run
//! may not sit higher than the first half by more than half of that; the live wgpu object
//! counts may not climb (the second half's peak of each kind stays within the first half's).
//!
//! Usage: cargo run --release --example soak -- [--frames 10000] [--size 32x18]
//!        [--report-every 500] [--recreate-every 1000] [--check] [--max-growth-mb 24]
//!        [--csv FILE] [--trim]
//!
//! `--lose-device-every N` destroys the device every N frames (a simulated device loss): the
//! frame must return `Error::DeviceLost`, and a new context takes over.
//!
//! `--trim` also returns malloc's free arena memory right after each context is dropped (Nimbus
//! does it itself when it next creates a device).

use std::process::ExitCode;

use glam::{Mat4, Vec3};
use nimbus::settings::NoiseSettings;
use nimbus::{Camera, DepthConvention, FrameInputs, Headless, Preset, Settings, Sun, Weather};

struct Options {
    frames: u32,
    size: (u32, u32),
    report_every: u32,
    recreate_every: u32,
    check: bool,
    max_growth_mb: f64,
    csv: Option<std::path::PathBuf>,
    trim: bool,
    lose_device_every: u32,
}

fn parse_size(s: &str) -> Option<(u32, u32)> {
    let (w, h) = s.split_once('x')?;
    Some((w.parse().ok()?, h.parse().ok()?))
}

fn parse_args() -> Result<Options, String> {
    let mut o = Options {
        frames: 10_000,
        size: (32, 18),
        report_every: 500,
        recreate_every: 1_000,
        check: false,
        max_growth_mb: 24.0,
        csv: None,
        trim: false,
        lose_device_every: 0,
    };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = |name: &str| args.next().ok_or(format!("{name} needs a value"));
        let number = |v: String| v.parse::<u32>().map_err(|_| format!("bad number {v:?}"));
        match a.as_str() {
            "--frames" => o.frames = number(value("--frames")?)?,
            "--report-every" => o.report_every = number(value("--report-every")?)?.max(1),
            "--recreate-every" => o.recreate_every = number(value("--recreate-every")?)?,
            "--size" => {
                let v = value("--size")?;
                o.size = parse_size(&v).ok_or(format!("bad size {v:?}"))?;
            }
            "--check" => o.check = true,
            "--trim" => o.trim = true,
            "--lose-device-every" => o.lose_device_every = number(value("--lose-device-every")?)?,
            "--max-growth-mb" => {
                let v = value("--max-growth-mb")?;
                o.max_growth_mb = v.parse().map_err(|_| format!("bad number {v:?}"))?;
            }
            "--csv" => o.csv = Some(value("--csv")?.into()),
            "-h" | "--help" => {
                println!(
                    "usage: soak [--frames N] [--size WxH] [--report-every N] \
                     [--recreate-every N] [--check] [--max-growth-mb MB] [--csv FILE] [--trim] [--lose-device-every N]"
                );
                std::process::exit(0);
            }
            _ => return Err(format!("unexpected argument {a:?}")),
        }
    }
    Ok(o)
}

/// Resident set size of this process in MiB (Linux: /proc/self/status, VmRSS).
fn rss_mib() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        .map_or(0.0, |kb| kb / 1024.0)
}

/// Small noise volumes: the soak is about the frame loop, not the bake.
fn settings() -> Settings {
    Settings {
        noise: NoiseSettings {
            base_size: 32,
            detail_size: 16,
            weather_size: 128,
            blue_noise_size: 16,
            ..NoiseSettings::default()
        },
        ..Settings::default()
    }
}

fn frame_at(i: u32, size: (u32, u32)) -> FrameInputs {
    let t = i as f32 / 60.0;
    // A slow circle at 800 m looking at the horizon, so every frame reprojects.
    let eye = Vec3::new(300.0 * (t * 0.2).cos(), 800.0, 300.0 * (t * 0.2).sin());
    let target = eye + Vec3::new((t * 0.05).sin(), 0.15, -(t * 0.05).cos());
    FrameInputs {
        camera: Camera {
            view: Mat4::look_at_rh(eye, target, Vec3::Y),
            projection: Mat4::perspective_rh(1.0, size.0 as f32 / size.1 as f32, 1.0, 400_000.0),
            depth: DepthConvention::default(),
        },
        sun: Sun::default(),
        time: i as f64 / 60.0,
    }
}

struct Report {
    frame: u32,
    rss: f64,
    gpu_bytes: u64,
    live_objects: nimbus::LiveObjects,
}

fn run(o: &Options) -> Result<Vec<Report>, String> {
    let err = |e: nimbus::Error| e.to_string();
    let preset_file = std::env::temp_dir().join(format!("nimbus-soak-{}.toml", std::process::id()));
    Weather::cloudy()
        .with_high_layer(Weather::cirrus())
        .save(&preset_file)
        .map_err(err)?;
    let sizes = [o.size, (o.size.0 + o.size.0 / 2, o.size.1 + o.size.1 / 2)];
    let presets = [
        Preset::Sparse,
        Preset::Cloudy,
        Preset::Overcast,
        Preset::Stormy,
        Preset::Clear,
    ];
    let mut reports = Vec::new();
    let mut nimbus: Option<Headless> = None;
    let mut size = sizes[0];
    let mut weather_time = 0.0f64;
    for i in 0..o.frames {
        if nimbus.is_none() || (o.recreate_every > 0 && i > 0 && i % o.recreate_every == 0) {
            // Drop the old context first, as a host would on a level change.
            drop(nimbus.take());
            if o.trim {
                nimbus::device::release_freed_memory();
            }
            let mut h = Headless::new(settings()).map_err(err)?;
            h.resize(size.0, size.1).map_err(err)?;
            nimbus = Some(h);
            weather_time = 0.0;
        }
        let h = nimbus.as_mut().expect("created above");
        let frame = frame_at(i, size);
        // Weather requests must come in time order on each context's clock.
        let now = frame.time.max(weather_time);
        if i % 7 == 3 {
            let p = presets[(i as usize / 7) % presets.len()];
            h.renderer_mut()
                .set_weather(p.weather(), now, 0.5)
                .map_err(err)?;
            weather_time = now;
        }
        if i % 97 == 50 {
            let w = Weather::load(&preset_file).map_err(err)?;
            h.renderer_mut().set_weather(w, now, 0.0).map_err(err)?;
            weather_time = now;
        }
        if i % 150 == 149 {
            size = if size == sizes[0] { sizes[1] } else { sizes[0] };
            h.resize(size.0, size.1).map_err(err)?;
        }
        if i % 61 == 60 {
            h.renderer_mut().reset_history();
        }
        if o.lose_device_every > 0 && i % o.lose_device_every == o.lose_device_every - 1 {
            // The device goes away (as on a driver reset): the frame must report it, and the
            // next frame starts on a new context.
            h.device().destroy();
            match h.render(&frame_at(i, size)) {
                Err(nimbus::Error::DeviceLost(_)) => {}
                other => return Err(format!("frame {i} after a device loss: {other:?}")),
            }
            drop(nimbus.take());
            continue;
        }
        h.render(&frame_at(i, size)).map_err(err)?;
        if (i + 1) % o.report_every == 0 {
            let r = Report {
                frame: i + 1,
                rss: rss_mib(),
                gpu_bytes: h.renderer().gpu_memory_bytes(),
                live_objects: h.live_objects(),
            };
            println!(
                "frame {:>6}  rss {:>8.1} MiB  nimbus gpu {:>8.2} MiB  live {}",
                r.frame,
                r.rss,
                r.gpu_bytes as f64 / (1 << 20) as f64,
                r.live_objects
            );
            reports.push(r);
        }
    }
    let _ = std::fs::remove_file(&preset_file);
    Ok(reports)
}

fn check(o: &Options, reports: &[Report]) -> Result<(), String> {
    if reports.len() < 3 {
        return Err("--check needs at least 3 reports (frames >= 3 * report-every)".into());
    }
    let warm = &reports[1..];
    let first = warm[0].rss;
    // The lower of the last two readings (never the first one itself, with only two): the
    // driver's worker threads now and then still hold ~30 MiB of heap for a moment (seen on
    // llvmpipe, tests/c/vulkan_test.c), which one reading can catch; a leak raises both.
    let last = warm[warm.len().saturating_sub(2).max(1)..]
        .iter()
        .map(|r| r.rss)
        .fold(f64::INFINITY, f64::min);
    let half_warm = warm.len() / 2;
    let mean = |r: &[Report]| r.iter().map(|r| r.rss).sum::<f64>() / r.len() as f64;
    let (early, late) = (mean(&warm[..half_warm.max(1)]), mean(&warm[half_warm..]));
    println!(
        "rss after warm-up {first:.1} MiB, at the end {last:.1} MiB (growth {:.1} MiB); \
         mean first half {early:.1}, second half {late:.1}",
        last - first
    );
    if last - first > o.max_growth_mb {
        return Err(format!(
            "memory grew {:.1} MiB after the warm-up (limit {} MiB)",
            last - first,
            o.max_growth_mb
        ));
    }
    if late - early > o.max_growth_mb / 2.0 {
        return Err(format!(
            "memory trends upward: second half {late:.1} MiB vs first half {early:.1} MiB"
        ));
    }
    // Live objects may wobble (weather bakes free theirs once the GPU is done) but must not
    // climb: the second half never holds more of any kind than the first half's peak.
    let peak = |r: &[Report]| {
        let mut m = [isize::MIN; 5];
        for r in r {
            for (m, c) in m.iter_mut().zip(r.live_objects.counts()) {
                *m = (*m).max(c);
            }
        }
        m
    };
    let half = reports.len() / 2;
    let (first_peak, second_peak) = (peak(&reports[..half]), peak(&reports[half..]));
    if second_peak.iter().zip(first_peak).any(|(b, a)| *b > a) {
        return Err(format!(
            "live wgpu objects climb: peak counts {first_peak:?} in the first half, \
             {second_peak:?} in the second (buffers, views, bind groups, pipelines, shaders)"
        ));
    }
    println!("memory flat: ok");
    Ok(())
}

fn write_csv(path: &std::path::Path, reports: &[Report]) -> Result<(), String> {
    let mut text = String::from("frame,rss_mib,nimbus_gpu_bytes,live_objects\n");
    for r in reports {
        text += &format!(
            "{},{:.1},{},\"{}\"\n",
            r.frame, r.rss, r.gpu_bytes, r.live_objects
        );
    }
    std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))
}

fn main() -> ExitCode {
    let result = parse_args().and_then(|o| {
        let start = std::time::Instant::now();
        let reports = run(&o)?;
        println!(
            "{} frames in {:.1} s",
            o.frames,
            start.elapsed().as_secs_f64()
        );
        if let Some(path) = &o.csv {
            write_csv(path, &reports)?;
        }
        if o.check {
            check(&o, &reports)?;
        }
        Ok(())
    });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("soak: {e}");
            ExitCode::FAILURE
        }
    }
}
