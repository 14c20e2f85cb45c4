//! Weather: the density model's per-cloud-type vertical profiles and the weather-map
//! parameters. Presets and transitions build on this module.

pub mod profile;
