//! The density probe: the GPU's density at given points, for checking the CPU queries
//! against what the march evaluates. Not a frame-loop pass: it builds its pipeline per call.

use wgpu::util::DeviceExt;

use super::compute::{frame_pipeline, storage_buffer_entry};
use super::march::{medium_entries, medium_layout_entries, MarchUniforms};
use super::noise::NoiseTextures;
use super::shaders::DepthKind;
use crate::error::Result;

/// The density at each point (unitless, as `sample_density` returns it at mip 0).
pub(crate) fn probe_density(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    noise: &NoiseTextures,
    weather: (&wgpu::TextureView, &wgpu::TextureView),
    uniforms: &MarchUniforms,
    points: &[glam::Vec3],
) -> Result<Vec<f32>> {
    if points.is_empty() {
        return Ok(Vec::new());
    }
    let (layout, pipeline) = frame_pipeline(
        device,
        "nimbus density probe",
        "density_probe",
        DepthKind::Depth,
        "probe",
        &[
            medium_layout_entries().as_slice(),
            &[
                storage_buffer_entry(6, true, 0),
                storage_buffer_entry(7, false, 0),
            ],
        ]
        .concat(),
    );
    let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("nimbus probe params"),
        contents: bytemuck::bytes_of(uniforms),
        usage: super::compute::FRAME_PARAMS_USAGE,
    });
    let padded: Vec<[f32; 4]> = points.iter().map(|p| p.extend(1.0).to_array()).collect();
    let input = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("nimbus probe points"),
        contents: bytemuck::cast_slice(&padded),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let size = (points.len() * 4) as u64;
    let output = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("nimbus probe density"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("nimbus probe readback"),
        size,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut entries = medium_entries(&params, noise, weather);
    entries.extend([
        wgpu::BindGroupEntry {
            binding: 6,
            resource: input.as_entire_binding(),
        },
        wgpu::BindGroupEntry {
            binding: 7,
            resource: output.as_entire_binding(),
        },
    ]);
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("nimbus density probe"),
        layout: &layout,
        entries: &entries,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups((points.len() as u32).div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&output, 0, &readback, 0, None);
    queue.submit([encoder.finish()]);
    let bytes = super::readback::map_read(device, &readback)?;
    Ok(bytemuck::pod_collect_to_vec(&bytes))
}
