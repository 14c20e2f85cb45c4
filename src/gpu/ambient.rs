//! The ambient probe: per view and frame, the clouds' irradiance at the camera from the
//! hemisphere above and below, and how much of each hemisphere's light comes from behind the
//! clouds (shaders/ambient.wgsl). Two workgroups of 64 invocations, 128 march rays each, after
//! the view's march uniforms are written; the result stays on the GPU in the view's
//! [`AMBIENT_BYTES`]-byte buffer until read.

use super::bind_cache::BindCache;
use super::compute::frame_pipeline;
use super::march::{medium_entries, medium_layout_entries, medium_views, shadow_layout_entries};
use super::noise::NoiseTextures;
use super::shaders::DepthKind;

/// Size of a view's ambient buffer: two `vec4<f32>` (above, below), each rgb the clouds'
/// irradiance and a the sky visibility.
pub(crate) const AMBIENT_BYTES: u64 = 32;

/// Usage of a view's ambient buffer: written by the probe, bindable and copyable by the host.
pub(crate) const AMBIENT_USAGE: wgpu::BufferUsages =
    wgpu::BufferUsages::STORAGE.union(wgpu::BufferUsages::COPY_SRC);

pub(crate) struct AmbientPipeline {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
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
                &[wgpu::BindGroupLayoutEntry {
                    binding: 13,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Storage { read_only: false },
                        has_dynamic_offset: false,
                        min_binding_size: wgpu::BufferSize::new(AMBIENT_BYTES),
                    },
                    count: None,
                }],
            ]
            .concat(),
        );
        Self {
            layout,
            pipeline,
            binds: BindCache::default(),
        }
    }

    /// Records the probe for the view whose march uniforms are `uniforms`, into `out`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn record(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        uniforms: &wgpu::Buffer,
        noise: &NoiseTextures,
        weather: (&wgpu::TextureView, &wgpu::TextureView),
        shadow: (&wgpu::TextureView, &wgpu::Buffer),
        out: &wgpu::Buffer,
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
                    resource: out.as_entire_binding(),
                },
            ]);
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("nimbus ambient probe"),
                layout,
                entries: &entries,
            })
        });
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("nimbus ambient probe"),
            timestamp_writes: timer.map(|t| {
                let (begin, end) = t.writes(super::timing::Pass::Ambient);
                wgpu::ComputePassTimestampWrites {
                    query_set: &t.query_set,
                    beginning_of_pass_write_index: begin,
                    end_of_pass_write_index: end,
                }
            }),
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind, &[]);
        // One workgroup per hemisphere.
        pass.dispatch_workgroups(2, 1, 1);
    }
}
