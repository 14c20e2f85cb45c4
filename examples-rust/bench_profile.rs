//! The benchmark's profile: where a settled default-level frame's time goes, measured in one
//! run by switching parts off (issue 13 item 1), so every later change shows which part it
//! moved. On software Vulkan the passes' timestamps read near zero, so parts are told apart by
//! wall time: the full frame; the frame with a single light sample per cloud sample (the
//! light march's share is the difference); the frame with no clouds at all (the fixed
//! full-resolution passes: trace-grid setup, temporal resolve, composite); the view-ray march
//! is what lies between.

use nimbus::demo::standard_views;
use nimbus::{Quality, Settings, Weather};

/// One measured configuration: (wall ms, density samples per ray, light samples per ray).
type Cost = (f64, f64, f64);

fn cost(h: &mut nimbus::Headless, settings: Settings) -> Result<Cost, String> {
    let m = super::measure(h, &standard_views()[0], 0.0, settings, true)?;
    Ok((m.wall_ms, m.stats.mean_samples, m.stats.mean_light_samples))
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
    let mut no_clouds = medium();
    no_clouds.weather = Weather::clear();
    let no_clouds = cost(&mut h, no_clouds)?;

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
    Ok(format!(
        "\n## Where a default frame's time goes ({}x{}, sparse, ground view, medium, settled)\n\n\
         Wall time of the settled frame with each part switched off in turn, in the same run: \
         the full frame ({:.1} view and {:.1} light samples per traced ray); one light sample \
         per cloud sample instead of {} ({:.1} light samples per ray left; the difference is \
         the light march); the clear preset (no cloud anywhere: what remains are the fixed \
         passes, every pixel's resolve and composite and the empty trace). The view-ray march \
         is what lies between.\n\n| part | wall ms | share of the frame |\n|---|---|---|\n\
         | light march toward the sun | {light:.1} | {:.0}% |\n\
         | view-ray march (coarse probes included) | {view:.1} | {:.0}% |\n\
         | fixed full-resolution passes | {fixed:.1} | {:.0}% |\n\
         | **frame** | **{:.1}** | 100% |\n",
        size.0,
        size.1,
        full.1,
        full.2,
        Settings::default().lighting.light_steps,
        one_light.2,
        share(light),
        share(view),
        share(fixed),
        full.0
    ))
}
