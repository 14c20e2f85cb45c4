//! Compute-pass helpers: the init-time passes (noise bake, weather bake and blend) and the
//! per-frame ones (march, temporal resolve).

use wgpu::util::DeviceExt;

use super::shaders::{pass_source, DepthKind};

/// A compute pipeline with an automatic layout from one pass of `PASSES`.
pub(crate) fn compute_pipeline(
    device: &wgpu::Device,
    pass: &str,
    entry: &str,
) -> wgpu::ComputePipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(pass),
        source: wgpu::ShaderSource::Wgsl(pass_source(pass, DepthKind::Depth).into()),
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: None,
        module: &module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    })
}

/// Records one dispatch: binding 0 is a uniform buffer holding `params` (when given), the
/// `views` take the bindings listed with them.
pub(crate) fn dispatch(
    device: &wgpu::Device,
    encoder: &mut wgpu::CommandEncoder,
    pipeline: &wgpu::ComputePipeline,
    params: Option<&[u8]>,
    views: &[(u32, &wgpu::TextureView)],
    groups: [u32; 3],
) {
    let buffer = params.map(|bytes| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("nimbus compute params"),
            contents: bytes,
            usage: wgpu::BufferUsages::UNIFORM,
        })
    });
    let mut entries: Vec<wgpu::BindGroupEntry> = views
        .iter()
        .map(|(binding, view)| wgpu::BindGroupEntry {
            binding: *binding,
            resource: wgpu::BindingResource::TextureView(view),
        })
        .collect();
    if let Some(buffer) = &buffer {
        entries.push(wgpu::BindGroupEntry {
            binding: 0,
            resource: buffer.as_entire_binding(),
        });
    }
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    });
    let mut pass = encoder.begin_compute_pass(&Default::default());
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, &bind, &[]);
    pass.dispatch_workgroups(groups[0], groups[1], groups[2]);
}

/// A 2D RGBA8 texture usable as storage, sampled texture, copy source and destination.
pub(crate) fn map_texture(device: &wgpu::Device, label: &str, size: u32) -> wgpu::Texture {
    use wgpu::TextureUsages as U;
    super::texture_2d(
        device,
        label,
        (size, size),
        wgpu::TextureFormat::Rgba8Unorm,
        U::TEXTURE_BINDING | U::STORAGE_BINDING | U::COPY_SRC | U::COPY_DST,
    )
}

/// A frozen blend of two weather maps (`weather_blend`): RGBA16F, so that the blend keeps
/// the precision the two maps' mix has (src/gpu/weather.rs).
pub(crate) fn frozen_map_texture(device: &wgpu::Device, label: &str, size: u32) -> wgpu::Texture {
    use wgpu::TextureUsages as U;
    super::texture_2d(
        device,
        label,
        (size, size),
        wgpu::TextureFormat::Rgba16Float,
        U::TEXTURE_BINDING | U::STORAGE_BINDING | U::COPY_SRC,
    )
}

/// A compute-stage sampled-texture layout entry.
pub(crate) fn texture_entry(
    binding: u32,
    sample_type: wgpu::TextureSampleType,
    dim: wgpu::TextureViewDimension,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Texture {
            sample_type,
            view_dimension: dim,
            multisampled: false,
        },
        count: None,
    }
}

/// A compute-stage write-only 2D storage-texture layout entry.
pub(crate) fn storage_entry(
    binding: u32,
    format: wgpu::TextureFormat,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::StorageTexture {
            access: wgpu::StorageTextureAccess::WriteOnly,
            format,
            view_dimension: wgpu::TextureViewDimension::D2,
        },
        count: None,
    }
}

/// A compute-stage storage-buffer layout entry of at least `min_size` bytes (0: any size).
pub(crate) fn storage_buffer_entry(
    binding: u32,
    read_only: bool,
    min_size: u64,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: wgpu::BufferSize::new(min_size),
        },
        count: None,
    }
}

/// A compute-stage layout entry for a `T` of per-frame parameters, bound as a read-only
/// storage buffer rather than a uniform buffer: see [`FRAME_PARAMS_USAGE`].
pub(crate) fn params_entry<T>(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<T>() as u64),
        },
        count: None,
    }
}

/// Usage of the buffers holding per-frame parameters (march, temporal, composite).
///
/// They are read-only storage buffers (`var<storage, read>` in WGSL), not uniform buffers,
/// because Mesa's lavapipe (22.x) "inlines" uniform-buffer values that steer control flow:
/// each distinct set of values compiles a new shader variant, kept until the pipeline is
/// destroyed. With a camera and clock that change every frame, that is a shader compile
/// (seconds on the CPU) and megabytes of memory per frame, for ever. Storage buffers are never
/// inlined; on hardware drivers the two read alike for a few hundred bytes read by every
/// invocation.
pub(crate) const FRAME_PARAMS_USAGE: wgpu::BufferUsages =
    wgpu::BufferUsages::STORAGE.union(wgpu::BufferUsages::COPY_DST);

/// A per-frame compute pass with an explicit layout (so one pipeline serves every frame's bind
/// group): the layout from `entries`, the module from `pass` with its depth-binding variant.
pub(crate) fn frame_pipeline(
    device: &wgpu::Device,
    label: &str,
    pass: &str,
    kind: DepthKind,
    entry: &str,
    entries: &[wgpu::BindGroupLayoutEntry],
) -> (wgpu::BindGroupLayout, wgpu::ComputePipeline) {
    let parts = FramePipelineParts::new(device, label, pass, kind, entries);
    let pipeline = parts.pipeline(device, label, entry, &[]);
    (parts.layout, pipeline)
}

/// What the pipelines of one per-frame pass share when it builds several specialisations
/// (pipeline-overridable constants): the bind-group layout (so every specialisation takes the
/// same bind groups), the pipeline layout and the shader module.
pub(crate) struct FramePipelineParts {
    pub layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
    module: wgpu::ShaderModule,
}

impl FramePipelineParts {
    /// The layout from `entries`, the module from `pass` with its depth-binding variant.
    pub(crate) fn new(
        device: &wgpu::Device,
        label: &str,
        pass: &str,
        kind: DepthKind,
        entries: &[wgpu::BindGroupLayoutEntry],
    ) -> Self {
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(label),
            entries,
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(pass_source(pass, kind).into()),
        });
        Self {
            layout,
            pipeline_layout,
            module,
        }
    }

    /// A pipeline of `entry` with the pipeline-overridable `constants` set (the others keep
    /// their defaults).
    pub(crate) fn pipeline(
        &self,
        device: &wgpu::Device,
        label: &str,
        entry: &str,
        constants: &[(&str, f64)],
    ) -> wgpu::ComputePipeline {
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(label),
            layout: Some(&self.pipeline_layout),
            module: &self.module,
            entry_point: Some(entry),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants,
                ..Default::default()
            },
            cache: None,
        })
    }
}

/// Records one 8×8-workgroup dispatch over `size` invocations, with timestamps for `which`
/// when a timer is given.
pub(crate) fn timed_dispatch(
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    pipeline: &wgpu::ComputePipeline,
    bind: &wgpu::BindGroup,
    size: (u32, u32),
    timer: Option<&super::timing::GpuTimer>,
    which: super::timing::Pass,
) {
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(label),
        timestamp_writes: timer.map(|t| {
            let (begin, end) = t.writes(which);
            wgpu::ComputePassTimestampWrites {
                query_set: &t.query_set,
                beginning_of_pass_write_index: begin,
                end_of_pass_write_index: end,
            }
        }),
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bind, &[]);
    pass.dispatch_workgroups(size.0.div_ceil(8), size.1.div_ceil(8), 1);
}
