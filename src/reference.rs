//! [`PathTracer`]: the path-traced reference (shaders/path_trace.wgsl). Unbiased and
//! progressive: every call adds samples per pixel to a float accumulation, through exactly
//! the medium a [`Renderer`] marches (its noise volumes, weather maps and settings, or its
//! debug media). It is what the march's lighting model is judged against, and a way for users
//! to check their own settings or render stills.
//!
//! What it models: all scattering orders (Russian roulette on the path weight, no order cap),
//! the sun by next-event estimation with ratio-tracked transmittance (the planet's shadow
//! total), the phase function sampled exactly, a branch toward the sun at each collision for
//! forward-peaked phases (see [`PathTracer::with_sun_guiding`]), and the ambient terms as the
//! sky a scattered path sees when it leaves the medium (`ambient_top` above the horizontal,
//! `ambient_bottom` below it and on the ground). What it leaves out: the host's scene depth
//! (the clouds are traced over an empty scene), the haze and the cirrus sheet (set the haze
//! fade distance to infinity and cirrus coverage to 0 when comparing). Rays go through pixel
//! centres, as the march's do.

use bytemuck::{Pod, Zeroable};

use crate::device::gpu_scope;
use crate::error::{Error, Result};
use crate::frame::FrameInputs;
use crate::gpu::bind_cache::BindCache;
use crate::gpu::compute::{frame_pipeline, FRAME_PARAMS_USAGE};
use crate::gpu::march::{medium_entries, medium_layout_entries, medium_views, MarchUniforms};
use crate::gpu::shaders::DepthKind;
use crate::Renderer;

/// Mirrors `PathParams` in shaders/path_trace.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct PathParams {
    size: [u32; 4],
    mode: [u32; 4],
}

/// What the path tracer counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Orders {
    /// Every scattering order (the reference).
    All,
    /// First-order scattering only (to check against single-scattering closed forms).
    SingleOnly,
}

/// The largest image side the path tracer takes.
pub const MAX_REFERENCE_SIZE: u32 = 4096;

// A pixel's column fills the hash input's low 12 bits; the random sequence's epoch takes the
// bits above them (`rng_words`).
const _: () = assert!(MAX_REFERENCE_SIZE <= 1 << 12);

/// Dispatches a seed's sequence counts before its epoch changes (the hash input's third word
/// holds the seed in its high half and the dispatch in its low half).
const DISPATCHES_PER_EPOCH: u64 = 1 << 16;

/// Epochs a sequence runs through before it repeats (the 20 bits above a pixel's column).
const EPOCHS: u64 = 1 << 20;

/// The words that key dispatch `position` of seed `seed`'s sequence in the shader's hash:
/// (the epoch, put above the pixel's column in the first word; the seed and the dispatch
/// within the epoch, the third word). Distinct (seed, position) pairs give distinct words for
/// 2^36 dispatches of every seed: before, the third word alone was `seed << 16` plus the
/// dispatch, and seed s's sequence ran into seed s + 1's after 65,536 dispatches. Epoch 0 keys
/// exactly as before, so images traced in it are unchanged.
fn rng_words(seed: u16, position: u64) -> (u32, u32) {
    let epoch = ((position / DISPATCHES_PER_EPOCH) % EPOCHS) as u32;
    let within = (position % DISPATCHES_PER_EPOCH) as u32;
    (epoch, (seed as u32) << 16 | within)
}

/// Samples per pixel one dispatch takes at most (the rest is split over several dispatches,
/// so no single GPU submission runs long enough to trip a driver watchdog).
const SAMPLES_PER_DISPATCH: u32 = 4;

/// The path-traced reference of one view: see the module docs.
pub struct PathTracer {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    binds: BindCache,
    uniforms: wgpu::Buffer,
    params: wgpu::Buffer,
    accum: wgpu::Buffer,
    /// Where `read` copies the accumulation to map it.
    staging: wgpu::Buffer,
    size: (u32, u32),
    orders: Orders,
    samples: u32,
    seed: u16,
    /// Dispatches drawn from the seed's sequence so far (across resets).
    position: u64,
    sun_guiding: bool,
}

impl PathTracer {
    /// An id of the shader code a traced image depends on: the path tracer's pass (medium,
    /// density model, phases) and the noise and weather bakes that make the medium. The same
    /// id, settings, view, sample count and seed trace the same image, so a host (or the
    /// fidelity benchmark) can key a cache of references by it. It hashes the code's tokens:
    /// an edit of the shaders' comments or layout keeps it.
    pub fn source_id() -> u32 {
        use crate::gpu::shaders::pass_modules;
        let modules: Vec<(&str, &str)> = ["path_trace", "noise_bake", "weather_bake"]
            .into_iter()
            .flat_map(|pass| pass_modules(pass).iter().copied())
            .collect();
        crate::noise_cache::source_hash(&modules)
    }

    /// An id of the sources an image of a debug medium (`DebugDensity::Slab` or `Sphere`)
    /// depends on: the path tracer's pass without the clouds' density model, which those media
    /// do not read (medium.wgsl returns their density before it), and without the noise and
    /// weather bakes. A cache of debug-medium references keyed by it survives work on the
    /// clouds' shapes; one of noise-model references needs [`PathTracer::source_id`].
    pub fn debug_media_source_id() -> u32 {
        let modules: Vec<(&str, &str)> = crate::gpu::shaders::pass_modules("path_trace")
            .iter()
            .copied()
            .filter(|(name, _)| *name != "density.wgsl")
            .collect();
        crate::noise_cache::source_hash(&modules)
    }

    /// A path tracer for `width` × `height` images on `renderer`'s device, counting `orders`.
    pub fn new(renderer: &Renderer, width: u32, height: u32, orders: Orders) -> Result<Self> {
        if width == 0 || height == 0 || width > MAX_REFERENCE_SIZE || height > MAX_REFERENCE_SIZE {
            return Err(Error::InvalidTarget {
                target: "reference",
                reason: format!("{width}x{height}: each side must be 1..={MAX_REFERENCE_SIZE}"),
            });
        }
        let (device, _, _, _) = renderer.medium();
        gpu_scope(device, || {
            let storage = crate::gpu::compute::storage_buffer_entry;
            let (layout, pipeline) = frame_pipeline(
                device,
                "nimbus path trace",
                "path_trace",
                DepthKind::Depth,
                "trace",
                &[
                    medium_layout_entries().as_slice(),
                    &[
                        storage(6, false, 16),
                        storage(7, true, std::mem::size_of::<PathParams>() as u64),
                    ],
                ]
                .concat(),
            );
            let buffer = |label, size, usage| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size,
                    usage,
                    mapped_at_creation: false,
                })
            };
            let pixels = width as u64 * height as u64;
            Self {
                layout,
                pipeline,
                binds: BindCache::default(),
                uniforms: buffer(
                    "nimbus path trace uniforms",
                    std::mem::size_of::<MarchUniforms>() as u64,
                    FRAME_PARAMS_USAGE,
                ),
                params: buffer(
                    "nimbus path trace params",
                    std::mem::size_of::<PathParams>() as u64,
                    FRAME_PARAMS_USAGE,
                ),
                accum: buffer(
                    "nimbus path trace accumulation",
                    pixels * 16,
                    wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::COPY_SRC
                        | wgpu::BufferUsages::COPY_DST,
                ),
                staging: buffer(
                    "nimbus path trace readback",
                    pixels * 16,
                    wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                ),
                size: (width, height),
                orders,
                samples: 0,
                seed: 0,
                position: 0,
                sun_guiding: true,
            }
        })
    }

    /// Starts the random sequence at `seed` (tracers with different seeds draw independent
    /// samples; two halves of an estimate tell its Monte-Carlo error).
    /// The sequence is long enough for 2^38 samples per pixel (2^36 dispatches of up to 4).
    pub fn with_seed(mut self, seed: u16) -> Self {
        self.seed = seed;
        self.position = 0;
        self
    }

    /// Where the tracer stands in its seed's random sequence (an opaque count that
    /// [`PathTracer::reset`] keeps, so samples after a reset are independent of those
    /// before). A host that saves a progressive still can store it with the sums and resume
    /// with [`PathTracer::with_sequence_position`], drawing new samples, not the same again.
    pub fn sequence_position(&self) -> u64 {
        self.position
    }

    /// Continues the seed's sequence from `position` (from [`PathTracer::sequence_position`]);
    /// call it after [`PathTracer::with_seed`], which starts the sequence over.
    pub fn with_sequence_position(mut self, position: u64) -> Self {
        self.position = position;
        self
    }

    /// Whether each collision (half the time) also sends a branch toward the sun: a direction
    /// from the phase's forward lobe turned toward the sun, a free flight and next-event
    /// estimation at its collision, combined with the path's own draws by multiple importance
    /// sampling, so the estimate stays unbiased (default true; only phases with a forward lobe
    /// of g >= 0.5 take it). The droplet phase's forward peak (1100 / sr) makes paths that
    /// travel near the sun's direction carry much of a cloud's diffuse light; drawn by phase
    /// sampling alone they are rare and show as fireflies, and a few hundred samples per pixel
    /// underestimate the mean. Off: the continuation alone (for checks).
    pub fn with_sun_guiding(mut self, on: bool) -> Self {
        self.sun_guiding = on;
        self
    }

    /// Samples per pixel accumulated since creation or the last [`PathTracer::reset`].
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// Drops the accumulation (call it when the view, the settings or the time change).
    pub fn reset(&mut self) {
        self.samples = 0;
    }

    /// Adds `samples` paths per pixel of `frame` (its camera, sun and time) through
    /// `renderer`'s medium, submitting the work on the renderer's queue. The image must be
    /// reset by the caller when the frame changes: the accumulation assumes one still view.
    pub fn accumulate(
        &mut self,
        renderer: &Renderer,
        frame: &FrameInputs,
        samples: u32,
    ) -> Result<()> {
        // The count divides the sums in `read`: one that wrapped would scale the image wrong.
        let total = self
            .samples
            .checked_add(samples)
            .ok_or_else(|| Error::InvalidTarget {
                target: "reference",
                reason: format!(
                    "{samples} more samples on the {} accumulated exceed {} in all: reset first",
                    self.samples,
                    u32::MAX
                ),
            })?;
        let uniforms = renderer.march_uniforms(frame)?;
        let (device, queue, noise, weather) = renderer.medium();
        gpu_scope(device, || {
            if self.samples == 0 {
                let mut enc = device.create_command_encoder(&Default::default());
                enc.clear_buffer(&self.accum, 0, None);
                queue.submit([enc.finish()]);
            }
            queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&uniforms));
            let views = medium_views(noise, weather);
            let layout = &self.layout;
            let (u, p, a) = (&self.uniforms, &self.params, &self.accum);
            let bind = self.binds.get(u, &views, || {
                let mut entries = medium_entries(u, noise, weather);
                entries.extend([
                    wgpu::BindGroupEntry {
                        binding: 6,
                        resource: a.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 7,
                        resource: p.as_entire_binding(),
                    },
                ]);
                device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("nimbus path trace"),
                    layout,
                    entries: &entries,
                })
            });
            let mut left = samples;
            while left > 0 {
                let n = left.min(SAMPLES_PER_DISPATCH);
                let (epoch, key) = rng_words(self.seed, self.position);
                let params = PathParams {
                    size: [self.size.0, self.size.1, key, n],
                    mode: [
                        (self.orders == Orders::SingleOnly) as u32,
                        3,
                        self.sun_guiding as u32,
                        epoch,
                    ],
                };
                // One submit per dispatch: the params buffer is written between them.
                queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
                let mut enc = device.create_command_encoder(&Default::default());
                {
                    let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some("nimbus path trace"),
                        timestamp_writes: None,
                    });
                    pass.set_pipeline(&self.pipeline);
                    pass.set_bind_group(0, &bind, &[]);
                    pass.dispatch_workgroups(self.size.0.div_ceil(8), self.size.1.div_ceil(8), 1);
                }
                queue.submit([enc.finish()]);
                self.position = self.position.wrapping_add(1);
                left -= n;
            }
        })?;
        self.samples = total;
        Ok(())
    }

    /// The image so far, row by row: (radiance r, g, b, transmittance of the camera ray) per
    /// pixel, the means over the accumulated samples. Waits for the GPU.
    pub fn read(&self, renderer: &Renderer) -> Result<Vec<[f32; 4]>> {
        if self.samples == 0 {
            return Err(Error::InvalidTarget {
                target: "reference",
                reason: "no samples accumulated yet".into(),
            });
        }
        let (device, queue, _, _) = renderer.medium();
        let mut enc = device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(&self.accum, 0, &self.staging, 0, None);
        queue.submit([enc.finish()]);
        let bytes = crate::gpu::readback::map_read(device, &self.staging)?;
        let n = self.samples as f32;
        Ok(bytemuck::cast_slice::<u8, [f32; 4]>(&bytes)
            .iter()
            .map(|p| p.map(|c| c / n))
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::noise_cache::source_hash;

    /// Every seed's sequence keys the hash with words no other (seed, dispatch) pair uses,
    /// for 2^36 dispatches; within the first epoch it keys as before (traced images unchanged).
    #[test]
    fn seeds_key_disjoint_sequences() {
        for (seed, position) in [(0u16, 0u64), (7, 1), (65535, 65535)] {
            assert_eq!(
                rng_words(seed, position),
                (0, (seed as u32) << 16 | position as u32)
            );
        }
        let positions = [0u64, 1, 65_535, 65_536, 65_537, 1 << 20, (1 << 36) - 1];
        let mut seen = std::collections::HashSet::new();
        for seed in [0u16, 1, 2, 65_535] {
            for position in positions {
                assert!(
                    seen.insert(rng_words(seed, position)),
                    "seed {seed} at {position} repeats another pair's words"
                );
                assert!(rng_words(seed, position).0 < EPOCHS as u32);
            }
        }
        // The documented period.
        assert_eq!(rng_words(5, 1 << 36), rng_words(5, 0));
    }

    /// The id covers what makes the medium, not only the tracer's own file: the density
    /// model and the noise bake are among its modules, and leaving either out changes it.
    #[test]
    fn the_source_id_covers_the_medium_and_the_bakes() {
        let id = PathTracer::source_id();
        assert_eq!(id, PathTracer::source_id());
        let tracer = crate::gpu::shaders::pass_modules("path_trace");
        assert!(tracer.iter().any(|(name, _)| *name == "density.wgsl"));
        assert_ne!(id, source_hash(tracer), "the bakes count");
        assert_ne!(id, crate::noise_cache::BAKE_ID, "the tracer counts");
        // The debug media's id leaves out only the density model.
        let debug = PathTracer::debug_media_source_id();
        assert_ne!(debug, id);
        let without: Vec<(&str, &str)> = tracer
            .iter()
            .copied()
            .filter(|(name, _)| *name != "density.wgsl")
            .collect();
        assert_eq!(without.len() + 1, tracer.len());
        assert_eq!(debug, source_hash(&without));
    }
}
