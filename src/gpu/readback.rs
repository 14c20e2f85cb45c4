//! Copies a texture (one mip level, all layers) to the CPU, dropping the row padding.

use crate::error::{Error, Result};

/// Bytes per texel of the formats Nimbus reads back.
fn texel_bytes(format: wgpu::TextureFormat) -> Result<u32> {
    format
        .block_copy_size(None)
        .ok_or_else(|| Error::Readback(format!("format {format:?} cannot be copied")))
}

/// Reads mip level `mip` of `texture` into tightly packed rows (x fastest, then y, then z).
pub(crate) fn read_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    mip: u32,
) -> Result<Vec<u8>> {
    let size = texture.size().mip_level_size(mip, texture.dimension());
    let bpp = texel_bytes(texture.format())?;
    let row = size.width * bpp;
    let padded =
        row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let layers = size.depth_or_array_layers;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("nimbus readback"),
        size: padded as u64 * size.height as u64 * layers as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: mip,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(size.height),
            },
        },
        size,
    );
    queue.submit([encoder.finish()]);
    let mapped = map_read(device, &buffer)?;
    let mut out = Vec::with_capacity((row * size.height * layers) as usize);
    for chunk in mapped.chunks(padded as usize) {
        out.extend_from_slice(&chunk[..row as usize]);
    }
    Ok(out)
}

/// Waits for the GPU, maps a `MAP_READ` buffer and copies its contents out.
pub(crate) fn map_read(device: &wgpu::Device, buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
    let (tx, rx) = std::sync::mpsc::channel();
    buffer
        .slice(..)
        .map_async(wgpu::MapMode::Read, move |r| drop(tx.send(r)));
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| Error::Readback(e.to_string()))?;
    rx.recv()
        .map_err(|e| Error::Readback(e.to_string()))?
        .map_err(|e| Error::Readback(e.to_string()))?;
    let bytes = buffer
        .get_mapped_range(..)
        .map_err(|e| Error::Readback(e.to_string()))?
        .to_vec();
    buffer.unmap();
    Ok(bytes)
}
