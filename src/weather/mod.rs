//! Weather: presets as data, the transition timeline, and the density model's per-cloud-type
//! vertical profiles. Pure CPU code; `gpu/weather.rs` bakes and blends the maps.

pub mod preset;
pub mod profile;
pub mod transition;

pub use preset::{
    CloudLayer, CloudShape, HighLayer, HorizonGradient, MapLayer, Preset, Weather, WeatherMap, Wind,
};
pub use transition::{
    MapAction, Timeline, TransitionPhase, TransitionState, WeatherSample, WindOffsets,
};
