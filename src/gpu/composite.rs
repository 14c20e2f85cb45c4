//! Composite pass: out = scene * T + L, with a depth-aware upsample from the trace resolution.
//! In place, a fullscreen triangle's blend does the multiply-add on the host's color;
//! otherwise the shader reads the scene and writes the output: by a compute pass when the
//! output allows storage writes (`STORAGE_BINDING` and a format in `STORAGE_OUTPUT_FORMATS`),
//! else by a fullscreen triangle. On a half-resolution trace grid the compute pass runs one
//! invocation per 2×2 output pixels, which share the 3×3 trace samples around one. Pipelines
//! are cached per (output format, mode, scene-depth kind, 2×2 or not) on first use.

use std::collections::HashMap;

use bytemuck::{Pod, Zeroable};
use glam::Mat4;

use super::bind_cache::BindCache;
use super::compute::timed_dispatch;
use super::shaders::{pass_source, pass_source_with_output, DepthKind, STORAGE_OUTPUT_FORMATS};

/// Layout must match `CompositeUniforms` in shaders/composite.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct CompositeUniforms {
    inv_view_proj_rel: [f32; 16],
    depth: [f32; 4],
    params: [f32; 4],
    viewport: [f32; 4],
}

impl CompositeUniforms {
    /// The trace divisor starts at 1: [`CompositeUniforms::set_divisor`] sets it at encode.
    pub(crate) fn new(inv_view_proj_rel: Mat4, far_value: f32, has_depth: bool) -> Self {
        Self {
            inv_view_proj_rel: inv_view_proj_rel.to_cols_array(),
            depth: [far_value, 0.0, 0.0, 0.0],
            params: [1.0, if has_depth { 1.0 } else { 0.0 }, 0.0, 0.0],
            viewport: [0.0; 4],
        }
    }

    /// The trace resolution's divisor, set when the frame is encoded (the settings then are
    /// the ones the grid and the pipeline follow).
    pub(crate) fn set_divisor(&mut self, divisor: u32) {
        self.params[0] = divisor as f32;
    }

    /// The rectangle of the targets this frame renders (x, y, width, height in pixels).
    pub(crate) fn set_viewport(&mut self, rect: [u32; 4]) {
        self.viewport = rect.map(|v| v as f32);
    }
}

impl CompositeUniforms {
    /// Whether a scene depth is bound (known only once targets are given).
    pub(crate) fn set_has_depth(&mut self, has_depth: bool) {
        self.params[1] = if has_depth { 1.0 } else { 0.0 };
    }
}

/// The views the composite reads.
pub(crate) struct CompositeInputs<'a> {
    pub clouds: &'a wgpu::TextureView,
    pub cloud_depth: &'a wgpu::TextureView,
    pub scene_depth: &'a wgpu::TextureView,
    pub depth_kind: DepthKind,
    pub uniforms: &'a wgpu::Buffer,
    pub timer: Option<&'a super::timing::GpuTimer>,
    /// The rectangle of the output rendered (x, y, width, height).
    pub viewport: [u32; 4],
    /// The trace resolution's divisor (1, 2 or 4).
    pub divisor: u32,
}

/// How the composite writes its output.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum CompositeMode {
    /// A fullscreen triangle blended onto the scene color.
    InPlace,
    /// A fullscreen triangle that reads the scene and writes a separate output.
    Separate,
    /// A compute pass that reads the scene and stores into a separate output.
    Compute,
}

impl CompositeMode {
    /// The mode for these targets: in place when there is no separate scene, compute when
    /// the output can be a storage texture, else the render pass.
    pub(crate) fn for_output(in_place: bool, output: &wgpu::TextureView) -> Self {
        if in_place {
            CompositeMode::InPlace
        } else if storage_writable(output) {
            CompositeMode::Compute
        } else {
            CompositeMode::Separate
        }
    }
}

/// Whether the compute composite can write `output`.
pub(crate) fn storage_writable(output: &wgpu::TextureView) -> bool {
    let texture = output.texture();
    texture
        .usage()
        .contains(wgpu::TextureUsages::STORAGE_BINDING)
        && storage_format_name(texture.format()).is_some()
}

fn storage_format_name(format: wgpu::TextureFormat) -> Option<&'static str> {
    STORAGE_OUTPUT_FORMATS
        .iter()
        .find(|(f, _)| *f == format)
        .map(|(_, name)| *name)
}

enum CompositePipeline {
    Render(wgpu::RenderPipeline),
    Compute(wgpu::ComputePipeline),
}

/// A composite pipeline and the bind groups made for it.
struct Composite {
    pipeline: CompositePipeline,
    binds: BindCache,
}

#[derive(Default)]
pub(crate) struct CompositeCache {
    pipelines: HashMap<(wgpu::TextureFormat, CompositeMode, DepthKind, bool), Composite>,
}

fn build(
    device: &wgpu::Device,
    format: wgpu::TextureFormat,
    mode: CompositeMode,
    depth: DepthKind,
    quad: bool,
) -> CompositePipeline {
    match mode {
        CompositeMode::Compute => {
            CompositePipeline::Compute(build_compute(device, format, depth, quad))
        }
        _ => CompositePipeline::Render(build_render(
            device,
            format,
            mode == CompositeMode::InPlace,
            depth,
        )),
    }
}

/// The compute composite; `quad`: one invocation per 2×2 output pixels, for a half-resolution
/// trace grid (shaders/composite_compute.wgsl).
fn build_compute(
    device: &wgpu::Device,
    format: wgpu::TextureFormat,
    depth: DepthKind,
    quad: bool,
) -> wgpu::ComputePipeline {
    let storage = storage_format_name(format)
        .unwrap_or_else(|| unreachable!("compute composite chosen for {format:?}"));
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("composite_compute"),
        source: wgpu::ShaderSource::Wgsl(
            pass_source_with_output("composite_compute", depth, storage).into(),
        ),
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("composite_compute"),
        layout: None,
        module: &module,
        entry_point: Some("cs_separate"),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants: &[("QUAD", if quad { 1.0 } else { 0.0 })],
            ..Default::default()
        },
        cache: None,
    })
}

fn build_render(
    device: &wgpu::Device,
    format: wgpu::TextureFormat,
    in_place: bool,
    depth: DepthKind,
) -> wgpu::RenderPipeline {
    let (pass, entry) = if in_place {
        ("composite_in_place", "fs_in_place")
    } else {
        ("composite_separate", "fs_separate")
    };
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(pass),
        source: wgpu::ShaderSource::Wgsl(pass_source(pass, depth).into()),
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
        inputs: &CompositeInputs,
        scene: Option<&wgpu::TextureView>,
        output: &wgpu::TextureView,
        format: wgpu::TextureFormat,
    ) {
        let mode = CompositeMode::for_output(scene.is_none(), output);
        // The half grid's 2×2 pixels per invocation: the default level's composite.
        let quad = mode == CompositeMode::Compute && inputs.divisor == 2;
        let composite = self
            .pipelines
            .entry((format, mode, inputs.depth_kind, quad))
            .or_insert_with(|| Composite {
                pipeline: build(device, format, mode, inputs.depth_kind, quad),
                binds: BindCache::default(),
            });
        let tex = |binding, view| wgpu::BindGroupEntry {
            binding,
            resource: wgpu::BindingResource::TextureView(view),
        };
        let mut views = vec![inputs.clouds, inputs.cloud_depth, inputs.scene_depth];
        views.extend(scene);
        if mode == CompositeMode::Compute {
            views.push(output);
        }
        let Composite { pipeline, binds } = composite;
        let bind = binds.get(inputs.uniforms, &views, || {
            let layout = match &*pipeline {
                CompositePipeline::Render(p) => p.get_bind_group_layout(0),
                CompositePipeline::Compute(p) => p.get_bind_group_layout(0),
            };
            let mut entries = vec![
                tex(0, inputs.clouds),
                tex(2, inputs.cloud_depth),
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: inputs.uniforms.as_entire_binding(),
                },
                tex(4, inputs.scene_depth),
            ];
            if let Some(scene) = scene {
                entries.push(tex(1, scene));
            }
            if mode == CompositeMode::Compute {
                entries.push(tex(5, output));
            }
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("nimbus composite"),
                layout: &layout,
                entries: &entries,
            })
        });
        let [x, y, w, h] = inputs.viewport;
        match &*pipeline {
            CompositePipeline::Compute(pipeline) => timed_dispatch(
                encoder,
                "nimbus composite",
                pipeline,
                &bind,
                if quad {
                    (w.div_ceil(2), h.div_ceil(2))
                } else {
                    (w, h)
                },
                inputs.timer,
                super::timing::Pass::Composite,
            ),
            CompositePipeline::Render(pipeline) => {
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
                    timestamp_writes: inputs.timer.map(|t| {
                        let (begin, end) = t.writes(super::timing::Pass::Composite);
                        wgpu::RenderPassTimestampWrites {
                            query_set: &t.query_set,
                            beginning_of_pass_write_index: begin,
                            end_of_pass_write_index: end,
                        }
                    }),
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, &bind, &[]);
                pass.set_viewport(x as f32, y as f32, w as f32, h as f32, 0.0, 1.0);
                pass.set_scissor_rect(x, y, w, h);
                pass.draw(0..3, 0..1);
            }
        }
    }

    /// How many pipelines have been built (one per output format, mode, depth kind and, for the
    /// compute composite, whether it runs 2×2 pixels per invocation).
    pub(crate) fn len(&self) -> usize {
        self.pipelines.len()
    }

    /// Bind groups made so far, over all pipelines.
    pub(crate) fn bind_groups_created(&self) -> u64 {
        self.pipelines.values().map(|c| c.binds.created()).sum()
    }

    /// Drops every cached bind group (the pipelines stay).
    pub(crate) fn clear_bind_groups(&mut self) {
        for c in self.pipelines.values_mut() {
            c.binds.clear();
        }
    }

    /// Drops the bind groups made with `uniforms` (one view's).
    pub(crate) fn forget(&mut self, uniforms: &wgpu::Buffer) {
        for c in self.pipelines.values_mut() {
            c.binds.forget(uniforms);
        }
    }
}
