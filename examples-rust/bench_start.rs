//! The benchmark's start section: how long a renderer takes from nothing to its first frame's
//! readiness (device, noise bake or noise cache upload, weather map, pipelines, GPU idle),
//! cold (baking) and from a noise cache, with the cache's export cost and size.

use std::time::Instant;

use nimbus::{Headless, NoiseStart, Settings};

/// Creates a headless renderer and waits until its start-up GPU work has finished; returns it
/// and the wall time in ms.
fn timed_start(noise: NoiseStart<'_>) -> Result<(Headless, f64), String> {
    let t = Instant::now();
    let h = Headless::with_noise(Settings::default(), noise).map_err(|e| e.to_string())?;
    // The bakes are submitted, not waited for, by the creation: a start is over when they are.
    h.device()
        .poll(nimbus::wgpu::PollType::wait_indefinitely())
        .map_err(|e| e.to_string())?;
    Ok((h, t.elapsed().as_secs_f64() * 1e3))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Measures and returns the section (markdown); also printed.
pub fn start_section() -> Result<String, String> {
    let (cold, cold_ms) = timed_start(NoiseStart::Bake)?;
    let t = Instant::now();
    let cache = cold
        .renderer()
        .export_noise_cache()
        .map_err(|e| e.to_string())?;
    let export_ms = t.elapsed().as_secs_f64() * 1e3;
    drop(cold);
    let mut warm = Vec::new();
    for _ in 0..3 {
        let (h, ms) = timed_start(NoiseStart::Cache(&cache))?;
        if !h.renderer().noise_from_cache() {
            return Err("a start from the noise cache baked instead".into());
        }
        warm.push(ms);
    }
    let warm_ms = median(warm.clone());
    println!(
        "start: cold (bake) {cold_ms:.0} ms; from the noise cache {warm_ms:.0} ms (median of \
         {warm:.0?}); export {export_ms:.0} ms, {:.2} MB",
        cache.len() as f64 / 1e6
    );
    Ok(format!(
        "\n## Start (default settings: 128³ base, 32³ detail, 512² weather map)\n\n\
         Wall time from nothing to a renderer whose start-up GPU work has finished (device, \
         noise volumes, weather map, pipelines).\n\n| start | wall ms |\n|---|---|\n\
         | cold (noise baked) | {cold_ms:.0} |\n| from a noise cache (median of 3) | {warm_ms:.0} |\n\
         | exporting the cache ({:.2} MB) | {export_ms:.0} |\n",
        cache.len() as f64 / 1e6
    ))
}
