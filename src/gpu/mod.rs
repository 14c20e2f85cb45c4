//! wgpu resources, pipelines and passes. Nothing here knows about C; everything here consumes
//! the CPU domain modules (`atmosphere`, `lighting`, `weather`) through uniforms.

pub(crate) mod blue_noise;
pub(crate) mod composite;
pub(crate) mod compute;
pub(crate) mod march;
pub mod noise;
pub(crate) mod readback;
pub(crate) mod shaders;
pub(crate) mod weather;
