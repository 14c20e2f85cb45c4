//! # Nimbus: volumetric clouds for any engine
//!
//! Nimbus ray-marches physically lit volumetric clouds over a curved planet and composites them
//! onto the host's scene: `out = scene * T + L`.
//!
//! ## Conventions
//!
//! - Units: meters; angles in radians; sun illuminance in lux-like linear units; output is
//!   linear HDR radiance in the same units as the sun's illuminance (× 1/sr).
//! - World up is +Y by default ([`settings::Planet::up`]); right-handed; matrices are
//!   column-major glam matrices. The planet's surface passes through the world origin.
//! - Clip-space depth is in [0, 1]; reversed-Z and an infinite far plane are declared with
//!   [`DepthConvention`] and checked against the projection, never guessed.
//! - [`Sun::direction`] points from the scene toward the sun.
//! - Every settings field has a documented default; `Settings::default()` is a good sky.
//!
//! ## Using it
//!
//! Hosts with a wgpu device use [`Renderer`]: `new` once, then per frame `prepare` with the
//! [`FrameInputs`] and `encode` into the host's command encoder (nothing is submitted).
//! Without a device, [`Headless`] creates one (software Vulkan is fine), owns its targets and
//! reads the result back.

pub mod ambient;
pub mod atmosphere;
pub mod demo;
pub mod device;
pub mod error;
pub mod ffi;
pub mod frame;
mod gpu;
pub mod headless;
pub mod lighting;
pub mod noise_cache;
pub mod query;
pub mod reference;
pub mod renderer;
pub mod settings;
pub mod shadows;
mod validate;
pub mod view;
/// Nimbus on the host's own Vulkan device and images (Vulkan targets only).
#[cfg(not(any(target_vendor = "apple", target_arch = "wasm32")))]
pub mod vulkan;
pub mod weather;

pub use ambient::{AmbientLight, HemisphereLight};
pub use error::{Error, Result};
pub use frame::{Camera, DepthConvention, FrameInputs, Sun};
pub use gpu::noise::NoiseVolume;
pub use gpu::timing::PassTimes;
pub use headless::{Headless, LiveObjects, RayStats};
pub use query::CloudQuery;
pub use reference::{Orders, PathTracer};
pub use renderer::{
    CloudShadowMap, ColorTargets, FrameOutputs, NoiseStart, Renderer, Targets, Viewport,
    FRAME_OUTPUTS_VERSION,
};
pub use settings::{CloudShadows, DebugDensity, Quality, Settings, Temporal, TracePattern};
pub use shadows::{shadow_optical_depth, CloudShadowSampler};
pub use view::ViewId;
pub use weather::{Preset, Weather};
pub use wgpu;

/// Crate version, from Cargo.toml.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");
pub use glam;

/// The README's Rust example, compiled as a doctest so it cannot rot.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
