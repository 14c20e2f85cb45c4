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

/// Cells per unit of the base volume's Worley octaves (noise_bake.wgsl: fBMs from 4, 4, 8 and
/// 16 cells, each with octaves at 1x, 2x and 4x).
const BASE_WORLEY_FREQS: [u32; 5] = [4, 8, 16, 32, 64];

/// Whether `bake_base` (a feature-point table per 4x4x4 workgroup) serves a base volume of
/// this edge: every octave's cell must span a whole number of texels, at least 2, so that each
/// workgroup's texels lie in at most 2 cells per axis. Otherwise `bake_base_plain`.
pub(crate) fn base_table_fits(size: u32) -> bool {
    BASE_WORLEY_FREQS
        .iter()
        .all(|&f| size % f == 0 && size / f >= 2)
}

/// The bake entry point for a base volume of this edge.
fn base_entry(size: u32) -> &'static str {
    if base_table_fits(size) {
        "bake_base"
    } else {
        "bake_base_plain"
    }
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

/// Records the bake of a volume's mip 0 by one of noise_bake.wgsl's entry points.
fn record_bake(
    device: &wgpu::Device,
    encoder: &mut wgpu::CommandEncoder,
    texture: &wgpu::Texture,
    entry: &str,
    size: u32,
    seed: u32,
) {
    let params = BakeParams {
        seed,
        size,
        _pad: [0; 2],
    };
    let g = size.div_ceil(4);
    dispatch(
        device,
        encoder,
        &compute_pipeline(device, "noise_bake", entry),
        Some(bytemuck::bytes_of(&params)),
        &[(1, &mip_view(texture, 0))],
        [g, g, g],
    );
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
            (&base, base_entry(noise.base_size), noise.base_size),
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
            record_bake(device, &mut encoder, texture, entry, size, noise.seed);
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

    /// Bakes a base volume of edge `size` with the given entry point and returns its mip 0
    /// (tightly packed RGBA8): for the test that both entry points agree.
    #[cfg(test)]
    pub(crate) fn bake_base_texels(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        entry: &str,
        size: u32,
        seed: u32,
    ) -> Vec<u8> {
        let texture = volume(device, "nimbus base noise (test)", size);
        let mut encoder = device.create_command_encoder(&Default::default());
        record_bake(device, &mut encoder, &texture, entry, size, seed);
        queue.submit([encoder.finish()]);
        super::readback::read_texture(device, queue, &texture, 0).unwrap()
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The rule behind `base_table_fits`, checked by brute force with the shader's own f32
    /// arithmetic: where it says yes, every 4-aligned run of texels lies in at most 2 cells of
    /// every octave (the table holds a 4x4x4 block of cells around them).
    #[test]
    fn the_feature_point_table_covers_every_workgroup_where_it_is_used() {
        let mut used = 0;
        for size in (3..=8).map(|k| 1u32 << k) {
            if !base_table_fits(size) {
                continue;
            }
            used += 1;
            for &f in &BASE_WORLEY_FREQS {
                let cell = |i: u32| (((i as f32 + 0.5) / size as f32) * f as f32).floor() as i64;
                for w in 0..size / 4 {
                    let span = cell(4 * w + 3) - cell(4 * w);
                    assert!(
                        span <= 1,
                        "size {size}, {f} cells: a workgroup spans {span} + 1 cells"
                    );
                }
            }
        }
        assert_eq!(used, 2, "the default 128 and 256 use the table");
        assert!(!base_table_fits(64) && !base_table_fits(100));
        assert_eq!(base_entry(128), "bake_base");
        assert_eq!(base_entry(32), "bake_base_plain");
    }
}
