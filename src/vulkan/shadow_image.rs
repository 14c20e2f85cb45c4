//! The cloud shadow map as a `VkImage`, for hosts on their own Vulkan device that bind or copy
//! it with their own commands (docs/c-api.md, "The shadow map on the host's device").

use ash::vk;
use wgpu::hal::vulkan as hv;

use crate::renderer::CloudShadowMap;

/// The layout [`super::HostFrame::render`] leaves the cloud shadow map in after every frame,
/// and expects it back in before the next: the host samples it there (or copies from it,
/// returning it to this layout).
pub const SHADOW_MAP_LAYOUT: vk::ImageLayout = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;

/// The format of the map's image (`Rgba16Float`).
pub const SHADOW_MAP_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;

/// Usages the map's image certainly has (wgpu may add more for its own needs, such as
/// `TRANSFER_DST` for zero-initialisation).
pub const SHADOW_MAP_USAGE: vk::ImageUsageFlags = vk::ImageUsageFlags::from_raw(
    vk::ImageUsageFlags::SAMPLED.as_raw()
        | vk::ImageUsageFlags::STORAGE.as_raw()
        | vk::ImageUsageFlags::TRANSFER_SRC.as_raw(),
);

/// The `VkImage` behind the cloud shadow map, or `None` when the renderer's device is not a
/// Vulkan device. The handle stays valid while the map does: until a settings change makes a
/// map of another size, or the renderer is dropped; ask again every frame (it costs nothing).
/// Nimbus owns the image: never destroy it, write it, or leave it in another layout than
/// [`SHADOW_MAP_LAYOUT`] when Nimbus's next frame runs. A read-back through wgpu
/// ([`crate::device::read_texture`]) leaves it in a transfer layout until the next
/// [`super::HostFrame::render`] (the C read-back restores the layout itself).
pub fn shadow_map_image(map: &CloudShadowMap<'_>) -> Option<vk::Image> {
    // SAFETY: the raw handle is only read, never destroyed or used here; the hal texture
    // guard is dropped at once (it borrows nothing the caller keeps).
    unsafe { map.texture.as_hal::<hv::Api>().map(|t| t.raw_handle()) }
}
