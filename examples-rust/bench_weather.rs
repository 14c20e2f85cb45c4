//! The benchmark's weather request section (issue 13 item 4): the worst frame while a
//! request's map is generated a slice per frame (the default budget) against settled frames,
//! and the whole map made at once in the call (budget 0).

use std::time::Instant;

use nimbus::demo::standard_views;
use nimbus::settings::Quality;
use nimbus::{Headless, Weather};

/// Measures and returns the section (markdown); also printed.
pub fn weather_section(bake_size: (u32, u32)) -> Result<String, String> {
    // A weather request against settled frames: the worst frame while its map is made a
    // slice per frame (the default budget), and the whole map made at once (budget 0).
    let mut h = super::new_headless(bake_size)?;
    let settings = super::settings_for(&Weather::cloudy(), super::Variant::Level(Quality::Medium));
    let view = &standard_views()[0];
    super::measure(&mut h, view, 0.0, settings.clone(), true)?;
    let frame = view.frame(bake_size.0, bake_size.1, 0.0);
    let timed_frame = |h: &mut Headless| -> Result<f64, String> {
        let t = Instant::now();
        h.render(&frame).map_err(|e| e.to_string())?;
        Ok(t.elapsed().as_secs_f64() * 1e3)
    };
    let mut normal = Vec::new();
    for _ in 0..6 {
        normal.push(timed_frame(&mut h)?);
    }
    normal.sort_by(f64::total_cmp);
    let frame_wall = normal[normal.len() / 2];
    let normal_worst = normal[normal.len() - 1];
    let t = Instant::now();
    h.renderer_mut()
        .set_weather(Weather::stormy(), 0.0, 20.0)
        .map_err(|e| e.to_string())?;
    let request_ms = t.elapsed().as_secs_f64() * 1e3;
    let (mut request_worst, mut request_frames) = (0.0f64, 0);
    while h.renderer().pending_weather_progress().is_some() {
        request_worst = request_worst.max(timed_frame(&mut h)?);
        request_frames += 1;
    }
    // The same request with the whole map at once, in the call.
    let mut at_once = settings;
    at_once.weather_map_texels_per_frame = 0;
    h.renderer_mut()
        .set_settings(at_once)
        .map_err(|e| e.to_string())?;
    timed_frame(&mut h)?;
    let t = Instant::now();
    h.renderer_mut()
        .set_weather(Weather::clear(), 0.0, 20.0)
        .map_err(|e| e.to_string())?;
    h.device()
        .poll(nimbus::wgpu::PollType::wait_indefinitely())
        .map_err(|e| e.to_string())?;
    let bake_ms = t.elapsed().as_secs_f64() * 1e3;
    drop(h);
    println!(
        "weather request at {}x{}: frames {frame_wall:.1} ms (worst {normal_worst:.1}); in slices \
         {request_frames} frames, worst {request_worst:.1} ms ({:.2}x; the call {request_ms:.1} ms); \
         at once {bake_ms:.1} ms in the call",
        bake_size.0,
        bake_size.1,
        request_worst / frame_wall
    );
    let md = format!(
        "\n## Weather request\n\n{}x{}, medium, cloudy, ground view, settled: frames {frame_wall:.1} ms wall \
         (median of 6; worst {normal_worst:.1}). A request's map in slices (default budget): {request_frames} frames, \
         the worst {request_worst:.1} ms ({:.2}x the median), the call itself {request_ms:.2} ms. The whole map at once \
         (budget 0): {bake_ms:.1} ms in the call, on top of that frame.\n",
        bake_size.0,
        bake_size.1,
        request_worst / frame_wall
    );
    Ok(md)
}
