//! Small helpers for the init-time compute passes (noise bake, weather bake and blend).

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

/// A 2D RGBA8 texture usable as storage, sampled texture and copy source.
pub(crate) fn map_texture(device: &wgpu::Device, label: &str, size: u32) -> wgpu::Texture {
    use wgpu::TextureUsages as U;
    super::texture_2d(
        device,
        label,
        (size, size),
        wgpu::TextureFormat::Rgba8Unorm,
        U::TEXTURE_BINDING | U::STORAGE_BINDING | U::COPY_SRC,
    )
}
