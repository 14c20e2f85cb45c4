//! The benchmark's model-cost section (`bench --model-cost`): what the default
//! multiple-scattering model (the delta-Eddington columns) costs against the octaves it
//! replaced (issue 11: within 1.3×), on sparse cumulus from the ground at the default level.
//!
//! The full run prices the octaves once, in its ablation table, minutes away from the default
//! level's own row; on a VM whose speed drifts by more than the model's cost between the two
//! (2026-12-05: single frames of the same configuration from 190 to 430 ms) that one pair of
//! numbers cannot resolve it. Here the two models alternate round by round on one renderer, each
//! round timed as the full run times a row (settled from a reset history, median of the last
//! frames), and the answer is the median of the rounds' ratios: drift slower than a round
//! cancels in each ratio.

use nimbus::demo::standard_views;
use nimbus::settings::MultipleScatteringModel;
use nimbus::{Quality, Settings, Weather};

/// Rounds of the two models, alternating.
const ROUNDS: usize = 15;

fn timed(h: &mut nimbus::Headless, model: MultipleScatteringModel) -> Result<f64, String> {
    let mut s = Settings {
        weather: Weather::sparse(),
        ..Settings::default()
    };
    Quality::Medium.apply(&mut s);
    s.lighting.multiple_scattering.model = model;
    Ok(super::measure(h, &standard_views()[0], 0.0, s, true)?.wall_ms)
}

pub fn model_cost_section(size: (u32, u32)) -> Result<String, String> {
    let mut h = super::new_headless(size)?;
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
            let ms = timed(&mut h, model)?;
            match model {
                MultipleScatteringModel::Octaves => o = ms,
                _ => d = ms,
            }
        }
        println!(
            "model cost round {round}: delta-Eddington {d:.1} ms, octaves {o:.1} ms, ratio {:.3}",
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
    let line = format!(
        "model cost {}x{} (sparse, ground, medium; {ROUNDS} alternating rounds): delta-Eddington / octaves {:.3} (median of the rounds' ratios; quartiles {:.3}-{:.3}); medians {:.1} / {:.1} ms",
        size.0,
        size.1,
        super::median(ratios),
        spread.0,
        spread.1,
        super::median(de),
        super::median(octaves)
    );
    println!("{line}");
    Ok(line)
}
