//! Composite pass: out = scene * T + L, as a fullscreen triangle. In place, the blend unit does
//! the multiply-add on the host's color; otherwise the shader reads the scene and writes the
//! output. Pipelines are cached per (output format, in place) on first use.

use std::collections::HashMap;

use super::shaders::{pass_source, DepthKind};

#[derive(Default)]
pub(crate) struct CompositeCache {
    pipelines: HashMap<(wgpu::TextureFormat, bool), wgpu::RenderPipeline>,
}

fn build(
    device: &wgpu::Device,
    format: wgpu::TextureFormat,
    in_place: bool,
) -> wgpu::RenderPipeline {
    let (pass, entry) = if in_place {
        ("composite_in_place", "fs_in_place")
    } else {
        ("composite_separate", "fs_separate")
    };
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(pass),
        source: wgpu::ShaderSource::Wgsl(pass_source(pass, DepthKind::Depth).into()),
    });
    // scene * T + L: src = (L, T), dst = scene; color = src * 1 + dst * src.alpha, alpha kept.
    let blend = in_place.then_some(wgpu::BlendState {
        color: wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::SrcAlpha,
            operation: wgpu::BlendOperation::Add,
        },
        alpha: wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::Zero,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        },
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(pass),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_fullscreen"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format,
                blend,
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        multiview_mask: None,
        cache: None,
    })
}

impl CompositeCache {
    /// Records the composite into `output`. `scene` is `None` for in-place compositing.
    pub(crate) fn record(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        clouds: &wgpu::TextureView,
        scene: Option<&wgpu::TextureView>,
        output: &wgpu::TextureView,
        format: wgpu::TextureFormat,
    ) {
        let in_place = scene.is_none();
        let pipeline = self
            .pipelines
            .entry((format, in_place))
            .or_insert_with(|| build(device, format, in_place));
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: wgpu::BindingResource::TextureView(clouds),
        }];
        if let Some(scene) = scene {
            entries.push(wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::TextureView(scene),
            });
        }
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("nimbus composite"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &entries,
        });
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("nimbus composite"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: output,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.draw(0..3, 0..1);
    }

    /// How many pipelines have been built (one per format and mode used).
    pub(crate) fn len(&self) -> usize {
        self.pipelines.len()
    }
}
