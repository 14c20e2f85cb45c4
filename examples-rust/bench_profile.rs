//! The benchmark's profile: where a settled default-level frame's time goes, measured in one
//! run by switching parts off (issue 13 item 1), so every later change shows which part it
//! moved. On software Vulkan the passes' timestamps read near zero, so parts are told apart by
//! wall time: the full frame; the frame with a single light sample per cloud sample (the
//! light march's share is the difference); the frame with no clouds at all (the fixed
//! full-resolution passes: trace-grid setup, temporal resolve, composite); the view-ray march
//! is what lies between.

use nimbus::demo::standard_views;
use nimbus::{Quality, Settings, Weather};

/// One measured configuration: (wall ms, density samples per ray, light samples per ray),
/// and its GPU time per pass from timestamps (view-ray march, cloud shadow map, ambient probe,
/// resolve, composite; NaN without timestamp queries).
type Cost = (f64, f64, f64, [f64; 5]);

fn cost(h: &mut nimbus::Headless, settings: Settings) -> Result<Cost, String> {
    let m = super::measure(h, &standard_views()[0], 0.0, settings, true)?;
    Ok((
        m.wall_ms,
        m.stats.mean_samples,
        m.stats.mean_light_samples,
        [
            m.march_ms,
            m.shadow_ms,
            m.ambient_ms,
            m.resolve_ms,
            m.composite_ms,
        ],
    ))
}

/// The GPU-time table (timestamp queries) of the three configurations, or nothing when the
/// adapter has none. On a real GPU these, not the wall times, are the figures: the wall time
/// also holds the submit, the wait and the CPU's share of a frame.
fn gpu_table(rows: &[(&str, &Cost)]) -> String {
    if rows.iter().any(|(_, c)| c.3.iter().any(|t| !t.is_finite())) {
        return String::new();
    }
    let mut md = String::from(
        "\nGPU time per pass (timestamp queries, median of the timed frames):\n\n\
         | configuration | march ms | shadow map ms | ambient probe ms | temporal resolve ms | composite ms | GPU total ms | wall ms |\n\
         |---|---|---|---|---|---|---|---|\n",
    );
    for (name, c) in rows {
        let [march, shadow, ambient, resolve, composite] = c.3;
        md.push_str(&format!(
            "| {name} | {march:.3} | {shadow:.3} | {ambient:.3} | {resolve:.3} | {composite:.3} | {:.3} | {:.2} |\n",
            c.3.iter().sum::<f64>(),
            c.0
        ));
    }
    md
}

/// Measures the breakdown (sparse, ground view, default level, settled) at `size`; returns the
/// markdown section (also printed).
pub fn profile_section(size: (u32, u32)) -> Result<String, String> {
    let mut h = super::new_headless(size)?;
    let weather = Weather::sparse();
    let medium = || {
        let mut s = Settings {
            weather: weather.clone(),
            ..Settings::default()
        };
        Quality::Medium.apply(&mut s);
        s
    };
    let full = cost(&mut h, medium())?;
    let mut one_light = medium();
    one_light.lighting.light_steps = 1;
    let one_light = cost(&mut h, one_light)?;
    let mut clear = medium();
    clear.weather = Weather::clear();
    let no_clouds = cost(&mut h, clear.clone())?;
    // The same clear frame with the output a render-pass-only target: the composite as a
    // fullscreen triangle instead of a compute pass (what a host gets without STORAGE_BINDING).
    h.set_storage_output(false).map_err(|e| e.to_string())?;
    let render_composite = cost(&mut h, clear)?;
    h.set_storage_output(true).map_err(|e| e.to_string())?;

    let light = (full.0 - one_light.0).max(0.0);
    let view = (one_light.0 - no_clouds.0).max(0.0);
    let fixed = no_clouds.0;
    let share = |ms: f64| 100.0 * ms / full.0;
    println!(
        "profile {}x{}: frame {:.1} ms = light {light:.1} ({:.0}%) + view rays {view:.1} ({:.0}%) + fixed passes {fixed:.1} ({:.0}%); samples/ray {:.1} view + {:.1} light",
        size.0,
        size.1,
        full.0,
        share(light),
        share(view),
        share(fixed),
        full.1,
        full.2
    );
    let [march, shadow, ambient, resolve, composite] = full.3;
    println!(
        "profile {}x{} GPU (timestamps): march {march:.3} ms, shadow map {shadow:.3} ms, ambient probe {ambient:.3} ms, resolve {resolve:.3} ms, composite {composite:.3} ms; one light sample: march {:.3} ms; no clouds: march {:.3} ms",
        size.0, size.1, one_light.3[0], no_clouds.3[0]
    );
    println!(
        "profile {}x{} composite: compute pass {:.1} ms wall ({:.3} ms GPU), fullscreen triangle {:.1} ms wall ({:.3} ms GPU), frames with no clouds",
        size.0, size.1, no_clouds.0, no_clouds.3[4], render_composite.0, render_composite.3[4]
    );
    let gpu = gpu_table(&[
        ("full frame", &full),
        ("one light sample", &one_light),
        ("no clouds", &no_clouds),
        (
            "no clouds, composite as a fullscreen triangle",
            &render_composite,
        ),
    ]);
    Ok(format!(
        "\n## Where a default frame's time goes ({}x{}, sparse, ground view, medium, settled)\n\n\
         Wall time of the settled frame with each part switched off in turn, in the same run: \
         the full frame ({:.1} view and {:.1} light samples per traced ray); one light sample \
         per cloud sample instead of {} ({:.1} light samples per ray left; the difference is \
         the light march); the clear preset (no cloud anywhere: what remains are the fixed \
         passes, every pixel's resolve and composite and the empty trace). The view-ray march \
         is what lies between. The composite is a compute pass (the output allows storage \
         writes); the last row of the GPU table composites the clear frame by a fullscreen \
         triangle instead ({:.1} ms wall against {:.1}).\n\n| part | wall ms | share of the frame |\n|---|---|---|\n\
         | light march toward the sun | {light:.1} | {:.0}% |\n\
         | view-ray march (coarse probes included) | {view:.1} | {:.0}% |\n\
         | fixed full-resolution passes | {fixed:.1} | {:.0}% |\n\
         | **frame** | **{:.1}** | 100% |\n{gpu}",
        size.0,
        size.1,
        full.1,
        full.2,
        Settings::default().lighting.light_steps,
        one_light.2,
        render_composite.0,
        no_clouds.0,
        share(light),
        share(view),
        share(fixed),
        full.0
    ))
}
