//! wgpu resources, pipelines and passes. Nothing here knows about C; everything here consumes
//! the CPU domain modules (`atmosphere`, `lighting`, `weather`) through uniforms.

pub(crate) mod ambient;
pub(crate) mod bind_cache;
pub(crate) mod blue_noise;
pub(crate) mod composite;
pub(crate) mod compute;
pub(crate) mod march;
pub mod noise;
pub(crate) mod probe;
pub(crate) mod readback;
pub(crate) mod shaders;
pub(crate) mod shadow;
pub(crate) mod temporal;
pub mod timing;
pub(crate) mod weather;

/// A single-mip 2D texture: the one descriptor Nimbus's 2D textures share.
pub(crate) fn texture_2d(
    device: &wgpu::Device,
    label: &str,
    size: (u32, u32),
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: size.0,
            height: size.1,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}
