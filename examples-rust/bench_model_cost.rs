//! The benchmark's model-cost section (`bench --model-cost`): what the default
//! multiple-scattering model (the delta-Eddington columns) costs against the octaves it
//! replaced (issue 11: within 1.3× on the benchmark's scenes), on each scene of the full run
//! (quick mode: the quick run's) at the default level.
//!
//! The full run prices the octaves once, in its ablation table, minutes away from the default
//! level's own row; on a VM whose speed drifts by more than the model's cost between the two
//! (2026-12-05: single frames of the same configuration from 190 to 430 ms) that one pair of
//! numbers cannot resolve it. Here the two models alternate round by round on one renderer, each
//! round timed as the full run times a row (settled from a reset history, median of the last
//! frames), and each scene's answer is the median of its rounds' ratios: drift slower than a
//! round cancels in each ratio. The last line gives the range over the scenes and the worst.

use nimbus::demo::standard_views;
use nimbus::settings::MultipleScatteringModel;
use nimbus::{Quality, Settings, Weather};

/// Rounds of the two models per scene, alternating (odd, so that each model goes first in all
/// but one pair of rounds as often as the other).
const ROUNDS: usize = 11;

fn timed(
    h: &mut nimbus::Headless,
    weather: &Weather,
    view: usize,
    model: MultipleScatteringModel,
) -> Result<f64, String> {
    let mut s = Settings {
        weather: weather.clone(),
        ..Settings::default()
    };
    Quality::Medium.apply(&mut s);
    s.lighting.multiple_scattering.model = model;
    Ok(super::measure(h, &standard_views()[view], 0.0, s, true)?.wall_ms)
}

/// Times the two models on each of `scenes` (weather, index into `standard_views`); returns
/// the summary line (also printed last).
pub fn model_cost_section(size: (u32, u32), scenes: &[(Weather, usize)]) -> Result<String, String> {
    let mut h = super::new_headless(size)?;
    let mut costs = Vec::with_capacity(scenes.len());
    for (weather, view) in scenes {
        let name = format!("{}, {}", weather.name, super::VIEW_NAMES[*view]);
        costs.push((scene_cost(&mut h, size, weather, *view, &name)?, name));
    }
    let lo = costs.iter().map(|(c, _)| *c).fold(f64::INFINITY, f64::min);
    let (hi, worst) = costs
        .iter()
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(c, n)| (*c, n.as_str()))
        .unwrap_or((f64::NAN, "none"));
    let line = format!(
        "model cost {}x{} (medium, {} scenes, {ROUNDS} alternating rounds each): delta-Eddington / octaves {lo:.3}-{hi:.3} (worst: {worst})",
        size.0,
        size.1,
        costs.len()
    );
    println!("{line}");
    Ok(line)
}

/// One scene's cost: the median over ROUNDS of delta-Eddington's time over the octaves'.
fn scene_cost(
    h: &mut nimbus::Headless,
    size: (u32, u32),
    weather: &Weather,
    view: usize,
    name: &str,
) -> Result<f64, String> {
    let mut ratios = Vec::with_capacity(ROUNDS);
    let (mut de, mut octaves) = (Vec::new(), Vec::new());
    for round in 0..ROUNDS {
        // Alternate which model goes first, so that a drift within a round favours neither.
        let order = if round % 2 == 0 {
            [
                MultipleScatteringModel::DeltaEddington,
                MultipleScatteringModel::Octaves,
            ]
        } else {
            [
                MultipleScatteringModel::Octaves,
                MultipleScatteringModel::DeltaEddington,
            ]
        };
        let (mut d, mut o) = (0.0, 0.0);
        for model in order {
            let ms = timed(h, weather, view, model)?;
            match model {
                MultipleScatteringModel::Octaves => o = ms,
                _ => d = ms,
            }
        }
        println!(
            "model cost {name} round {round}: delta-Eddington {d:.1} ms, octaves {o:.1} ms, ratio {:.3}",
            d / o
        );
        ratios.push(d / o);
        de.push(d);
        octaves.push(o);
    }
    let spread = {
        let mut r = ratios.clone();
        r.sort_by(|a, b| a.total_cmp(b));
        (r[r.len() / 4], r[3 * r.len() / 4])
    };
    let ratio = super::median(ratios);
    println!(
        "model cost {}x{} ({name}, medium; {ROUNDS} alternating rounds): delta-Eddington / octaves {ratio:.3} (median of the rounds' ratios; quartiles {:.3}-{:.3}); medians {:.1} / {:.1} ms",
        size.0,
        size.1,
        spread.0,
        spread.1,
        super::median(de),
        super::median(octaves)
    );
    Ok(ratio)
}
