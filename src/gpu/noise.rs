//! The noise textures Nimbus owns: base-shape and detail volumes (with mips) and the blue
//! noise. Baked by compute passes at init and when their settings change.

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use super::blue_noise;
use super::compute::{compute_pipeline, dispatch};
use crate::settings::NoiseSettings;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct BakeParams {
    seed: u32,
    size: u32,
    _pad: [u32; 2],
}

/// Which baked volume (for readback and inspection).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NoiseVolume {
    /// Base shape, RGBA8: R Perlin-Worley, G/B/A Worley fBM.
    Base,
    /// Detail, RGBA8: R/G/B Worley fBM.
    Detail,
}

pub(crate) struct NoiseTextures {
    pub base: wgpu::Texture,
    pub detail: wgpu::Texture,
    pub base_view: wgpu::TextureView,
    pub detail_view: wgpu::TextureView,
    pub blue_noise_view: wgpu::TextureView,
    pub sampler: wgpu::Sampler,
}

fn mip_count(size: u32) -> u32 {
    size.ilog2() + 1
}

fn volume(device: &wgpu::Device, label: &str, size: u32) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: size,
            height: size,
            depth_or_array_layers: size,
        },
        mip_level_count: mip_count(size),
        sample_count: 1,
        dimension: wgpu::TextureDimension::D3,
        format: wgpu::TextureFormat::Rgba8Unorm,
        usage: wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::STORAGE_BINDING
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    })
}

/// Uploads tightly packed RGBA8 texels into mip 0 of a cubic volume.
fn upload_mip0(queue: &wgpu::Queue, texture: &wgpu::Texture, texels: &[u8]) {
    let edge = texture.width();
    queue.write_texture(
        texture.as_image_copy(),
        texels,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(4 * edge),
            rows_per_image: Some(edge),
        },
        wgpu::Extent3d {
            width: edge,
            height: edge,
            depth_or_array_layers: edge,
        },
    );
}

fn mip_view(texture: &wgpu::Texture, mip: u32) -> wgpu::TextureView {
    texture.create_view(&wgpu::TextureViewDescriptor {
        base_mip_level: mip,
        mip_level_count: Some(1),
        ..Default::default()
    })
}

/// Fills mips 1.. of a volume from mip 0.
fn build_mips(device: &wgpu::Device, encoder: &mut wgpu::CommandEncoder, texture: &wgpu::Texture) {
    let pipeline = compute_pipeline(device, "mip_downsample", "downsample");
    for mip in 1..texture.mip_level_count() {
        let (src, dst) = (mip_view(texture, mip - 1), mip_view(texture, mip));
        let g = (texture.width() >> mip).max(1).div_ceil(4);
        dispatch(
            device,
            encoder,
            &pipeline,
            None,
            &[(0, &src), (1, &dst)],
            [g, g, g],
        );
    }
}

impl NoiseTextures {
    /// Creates and bakes every noise texture. Submits its own command buffer.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, noise: &NoiseSettings) -> Self {
        Self::build(device, queue, noise, None)
    }

    /// Creates the noise textures with the volumes' mip 0 taken from `texels` (base, detail:
    /// a noise cache's payload, checked against `noise` by the caller) instead of baked.
    pub fn from_texels(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        noise: &NoiseSettings,
        texels: (&[u8], &[u8]),
    ) -> Self {
        Self::build(device, queue, noise, Some(texels))
    }

    fn build(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        noise: &NoiseSettings,
        texels: Option<(&[u8], &[u8])>,
    ) -> Self {
        let base = volume(device, "nimbus base noise", noise.base_size);
        let detail = volume(device, "nimbus detail noise", noise.detail_size);
        let bn_size = noise.blue_noise_size;
        let blue = device.create_texture_with_data(
            queue,
            &wgpu::TextureDescriptor {
                label: Some("nimbus blue noise"),
                size: wgpu::Extent3d {
                    width: bn_size,
                    height: bn_size,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::R8Unorm,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            &blue_noise::generate(bn_size, noise.seed),
        );

        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("nimbus noise bake"),
        });
        for (i, (texture, entry, size)) in [
            (&base, "bake_base", noise.base_size),
            (&detail, "bake_detail", noise.detail_size),
        ]
        .into_iter()
        .enumerate()
        {
            if let Some(t) = texels {
                // Queue writes land before the command buffer submitted below.
                upload_mip0(queue, texture, if i == 0 { t.0 } else { t.1 });
                build_mips(device, &mut encoder, texture);
                continue;
            }
            let params = BakeParams {
                seed: noise.seed,
                size,
                _pad: [0; 2],
            };
            let g = size.div_ceil(4);
            dispatch(
                device,
                &mut encoder,
                &compute_pipeline(device, "noise_bake", entry),
                Some(bytemuck::bytes_of(&params)),
                &[(1, &mip_view(texture, 0))],
                [g, g, g],
            );
            build_mips(device, &mut encoder, texture);
        }
        queue.submit([encoder.finish()]);

        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("nimbus noise sampler"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            address_mode_w: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        Self {
            base_view: base.create_view(&Default::default()),
            detail_view: detail.create_view(&Default::default()),
            blue_noise_view: blue.create_view(&Default::default()),
            base,
            detail,
            sampler,
        }
    }

    /// Bytes held, measured per texture by `texture_bytes`.
    pub fn memory_bytes(&self, texture_bytes: impl Fn(&wgpu::Texture) -> u64) -> u64 {
        texture_bytes(&self.base)
            + texture_bytes(&self.detail)
            + texture_bytes(self.blue_noise_view.texture())
    }

    pub fn volume(&self, which: NoiseVolume) -> &wgpu::Texture {
        match which {
            NoiseVolume::Base => &self.base,
            NoiseVolume::Detail => &self.detail,
        }
    }
}
