//! The ambient probe: per view and frame, the clouds' irradiance at the camera from the
//! hemisphere above and below, and how much of each hemisphere's light comes from behind the
//! clouds (shaders/ambient.wgsl). 768 march rays per hemisphere in twelve interleaved subsets
//! of 64, one subset a frame (all twelve when the view has no history), each ray in
//! [`AMBIENT_PARTS`] ranges of its steps, one per invocation; a resolve adds every subset's
//! latest sums into the view's [`AMBIENT_BYTES`]-byte buffer, which stays on the GPU until
//! read.

use super::bind_cache::BindCache;
use super::compute::{frame_pipeline, storage_buffer_entry};
use super::march::{medium_entries, medium_layout_entries, medium_views, shadow_layout_entries};
use super::noise::NoiseTextures;
use super::shaders::{pass_source, DepthKind};

/// Size of a view's ambient buffer: two `vec4<f32>` (above, below), each rgb the clouds'
/// irradiance and a the sky visibility.
pub(crate) const AMBIENT_BYTES: u64 = 32;

/// Usage of a view's ambient buffer: written by the probe, bindable and copyable by the host.
pub(crate) const AMBIENT_USAGE: wgpu::BufferUsages =
    wgpu::BufferUsages::STORAGE.union(wgpu::BufferUsages::COPY_SRC);

/// The interleaved ray subsets (shaders/ambient.wgsl `AMBIENT_SUBSETS`): 64 rays each, one a
/// frame. Twelve (768 directions) since 2026-12-07: with three (192) a sparse cumulus sky fell
/// between the directions, up to 27% off the picture's integral (tests/ambient.rs).
pub(crate) const AMBIENT_SUBSETS: u32 = 12;

/// The invocations one ray is marched by (shaders/ambient.wgsl `AMBIENT_PARTS`).
pub(crate) const AMBIENT_PARTS: u32 = 8;

/// Workgroups per subset and hemisphere (shaders/ambient.wgsl `AMBIENT_GROUPS`): 64 rays of
/// [`AMBIENT_PARTS`] invocations, 64 invocations a workgroup.
pub(crate) const AMBIENT_GROUPS: u32 = 64 * AMBIENT_PARTS / 64;

/// Size of a view's per-subset sums: per subset, hemisphere and workgroup two `vec4<f32>`.
pub(crate) const AMBIENT_PARTIAL_BYTES: u64 =
    AMBIENT_SUBSETS as u64 * 2 * AMBIENT_GROUPS as u64 * 2 * 16;

/// A view's ambient probe buffers: the output, the per-subset sums, the frame's parameters.
pub(crate) struct AmbientBuffers {
    pub out: wgpu::Buffer,
    pub partial: wgpu::Buffer,
    pub params: wgpu::Buffer,
}

impl AmbientBuffers {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let buffer = |label, size, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        use wgpu::BufferUsages as U;
        Self {
            out: buffer("nimbus ambient light", AMBIENT_BYTES, AMBIENT_USAGE),
            partial: buffer("nimbus ambient sums", AMBIENT_PARTIAL_BYTES, U::STORAGE),
            params: buffer("nimbus ambient params", 16, U::STORAGE | U::COPY_DST),
        }
    }

    /// Bytes held.
    pub(crate) fn bytes(&self) -> u64 {
        self.out.size() + self.partial.size() + self.params.size()
    }

    /// Which subsets this frame marches: all on a view's first frame and whenever it has no
    /// history (`fresh`), else one, in turn by `frame_index`.
    pub(crate) fn write_params(&self, queue: &wgpu::Queue, frame_index: u32, fresh: bool) {
        let (first, count) = if fresh {
            (0, AMBIENT_SUBSETS)
        } else {
            (frame_index % AMBIENT_SUBSETS, 1)
        };
        queue.write_buffer(&self.params, 0, bytemuck::cast_slice(&[first, count, 0, 0]));
    }
}

pub(crate) struct AmbientPipeline {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    /// `ambient_resolve`: the subsets' sums into the output (same layout).
    resolve: wgpu::ComputePipeline,
    /// Bind groups by the views they bind, per view (its uniform buffer; the ambient buffer
    /// belongs to the same view).
    pub binds: BindCache,
}

impl AmbientPipeline {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let (layout, pipeline) = frame_pipeline(
            device,
            "nimbus ambient probe",
            "ambient",
            DepthKind::Depth,
            "ambient",
            &[
                medium_layout_entries().as_slice(),
                &shadow_layout_entries(),
                &[
                    storage_buffer_entry(13, false, AMBIENT_BYTES),
                    storage_buffer_entry(14, false, AMBIENT_PARTIAL_BYTES),
                    storage_buffer_entry(15, true, 16),
                ],
            ]
            .concat(),
        );
        let resolve = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("nimbus ambient resolve"),
            layout: Some(
                &device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some("nimbus ambient resolve"),
                    bind_group_layouts: &[Some(&layout)],
                    immediate_size: 0,
                }),
            ),
            module: &device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("nimbus ambient resolve"),
                source: wgpu::ShaderSource::Wgsl(pass_source("ambient", DepthKind::Depth).into()),
            }),
            entry_point: Some("ambient_resolve"),
            compilation_options: Default::default(),
            cache: None,
        });
        Self {
            layout,
            pipeline,
            resolve,
            binds: BindCache::default(),
        }
    }

    /// Records the probe for the view whose march uniforms are `uniforms` into its buffers
    /// (their parameters written for this frame: `AmbientBuffers::write_params`).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn record(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        uniforms: &wgpu::Buffer,
        noise: &NoiseTextures,
        weather: (&wgpu::TextureView, &wgpu::TextureView),
        shadow: (&wgpu::TextureView, &wgpu::Buffer),
        out: &AmbientBuffers,
        subsets: u32,
        timer: Option<&super::timing::GpuTimer>,
    ) {
        let mut views = medium_views(noise, weather).to_vec();
        views.push(shadow.0);
        let layout = &self.layout;
        let bind = self.binds.get(uniforms, &views, || {
            let mut entries = medium_entries(uniforms, noise, weather);
            entries.extend([
                wgpu::BindGroupEntry {
                    binding: 10,
                    resource: wgpu::BindingResource::TextureView(shadow.0),
                },
                wgpu::BindGroupEntry {
                    binding: 11,
                    resource: shadow.1.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 13,
                    resource: out.out.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 14,
                    resource: out.partial.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 15,
                    resource: out.params.as_entire_binding(),
                },
            ]);
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("nimbus ambient probe"),
                layout,
                entries: &entries,
            })
        });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("nimbus ambient probe"),
                timestamp_writes: timer.map(|t| {
                    let (begin, _) = t.writes(super::timing::Pass::Ambient);
                    wgpu::ComputePassTimestampWrites {
                        query_set: &t.query_set,
                        beginning_of_pass_write_index: begin,
                        end_of_pass_write_index: None,
                    }
                }),
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bind, &[]);
            // AMBIENT_GROUPS workgroups per hemisphere and subset marched.
            pass.dispatch_workgroups(2 * AMBIENT_GROUPS, subsets, 1);
        }
        // A pass of its own: the sums are written above and read here.
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("nimbus ambient resolve"),
            timestamp_writes: timer.map(|t| {
                let (_, end) = t.writes(super::timing::Pass::Ambient);
                wgpu::ComputePassTimestampWrites {
                    query_set: &t.query_set,
                    beginning_of_pass_write_index: None,
                    end_of_pass_write_index: end,
                }
            }),
        });
        pass.set_pipeline(&self.resolve);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(1, 1, 1);
    }
}
