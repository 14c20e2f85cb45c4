//! Lighting math on the CPU: phase functions, Hillaire's energy-conserving step integration and
//! Wrenninge's multiple-scattering octaves. The WGSL in `shaders/phase.wgsl` and
//! `shaders/march.wgsl` mirrors these functions; the tests here are the oracle for both.

pub mod diffusion;
pub mod phase;
pub mod scattering;
#[cfg(test)]
pub(crate) mod slab_light_tracer;
