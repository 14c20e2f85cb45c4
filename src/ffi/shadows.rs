//! The cloud shadow map in the C API: turned on at creation by a chained struct, read each
//! frame as a matrix and, for hosts that shade on the CPU, as a copy of the texels.

use super::context::{check_chain, with_ctx};
use super::{FfiError, NimbusChainedStruct, NimbusContext, NimbusResult};
use super::{NIMBUS_ERROR_INVALID_TARGET, NIMBUS_ERROR_NOT_READY, NIMBUS_OK};
use crate::device::read_texture;
use crate::settings::CloudShadows;

/// `s_type` of `NimbusCloudShadowsExt` (chain it to `NimbusContextDesc.next`). Since ABI 0.5.
pub const NIMBUS_STYPE_CLOUD_SHADOWS: u32 = 6;

/// Chained to the context's creation: make and update the cloud shadow map, the clouds'
/// optical depth toward the sun over a square around the default view's camera. Zero in a
/// field means its default. Since ABI 0.5.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NimbusCloudShadowsExt {
    /// `s_type` = `NIMBUS_STYPE_CLOUD_SHADOWS`.
    pub chain: NimbusChainedStruct,
    /// Side of the square in meters, in [1000, 1000000]; 0 = 40000.
    pub extent: f32,
    /// Texels along a side, a power of two in [16, 2048]; 0 = 256.
    pub resolution: u32,
    /// Density samples along each texel's ray, in [4, 256]; 0 = 32.
    pub steps: u32,
    /// Frames one refresh of the whole map is spread over, in [1, 16]; 0 = 4. Texels the
    /// camera's motion brings into the square, and a sun that turned by more than 0.1 degree,
    /// are updated at once.
    pub update_slices: u32,
    /// `NIMBUS_CLOUD_SHADOWS_*` flags; 0 = none.
    pub flags: u32,
    /// Must be 0.
    pub reserved: u32,
}

/// `NimbusCloudShadowsExt.flags`: the march reads the long part of its light path toward the
/// sun from the map (a few light samples next to each cloud sample, then the map). Since ABI 0.5.
pub const NIMBUS_CLOUD_SHADOWS_MARCH_LIGHT: u32 = 1;

/// Where the cloud shadow map stands after the last frame of the default view. Since ABI 0.5.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NimbusCloudShadowInfo {
    /// Must be NULL.
    pub next: *const NimbusChainedStruct,
    /// World position to map coordinates, column-major (like GLSL's mat4): x and y are
    /// texture coordinates (sample with repeat addressing: the map is toroidal), z is the
    /// depth along the light in meters. A point at depth z under texel t receives the fraction
    /// exp(-min(t.g * max(z - t.r, 0), t.b)) of the sunlight.
    pub world_to_map: [f32; 16],
    /// The direction toward the sun the map was built for.
    pub sun: [f32; 3],
    /// Texels along a side.
    pub resolution: u32,
    /// The map coordinates of the square's first texel corner: a point lies inside the square
    /// iff its x and y minus these are both in [0, 1).
    pub window_origin: [f32; 2],
    /// Side of the square in meters.
    pub extent: f32,
    /// Written as 0.
    pub reserved: u32,
}

/// The shadow-map settings of a creation chain's `NimbusCloudShadowsExt`.
///
/// Safety: `p` points to a `NimbusCloudShadowsExt`.
pub(crate) unsafe fn shadows_from_ext(
    p: *const NimbusChainedStruct,
) -> Result<CloudShadows, FfiError> {
    // SAFETY: the caller found this link by its s_type, which promises the struct.
    let ext = unsafe { &*p.cast::<NimbusCloudShadowsExt>() };
    if ext.flags & !NIMBUS_CLOUD_SHADOWS_MARCH_LIGHT != 0 {
        return Err(FfiError::arg(format!(
            "unknown NimbusCloudShadowsExt.flags bits 0x{:x}",
            ext.flags & !NIMBUS_CLOUD_SHADOWS_MARCH_LIGHT
        )));
    }
    if ext.reserved != 0 {
        return Err(FfiError::arg("NimbusCloudShadowsExt.reserved must be 0"));
    }
    let d = CloudShadows::default();
    let or = |v: u32, default: u32| if v == 0 { default } else { v };
    Ok(CloudShadows {
        enabled: true,
        extent: if ext.extent == 0.0 {
            d.extent
        } else {
            ext.extent
        },
        resolution: or(ext.resolution, d.resolution),
        steps: or(ext.steps, d.steps),
        update_slices: or(ext.update_slices, d.update_slices),
        march_light: ext.flags & NIMBUS_CLOUD_SHADOWS_MARCH_LIGHT != 0,
        ..d
    })
}

pub(crate) fn not_ready() -> FfiError {
    FfiError::new(
        NIMBUS_ERROR_NOT_READY,
        "no cloud shadow map: chain a NimbusCloudShadowsExt when creating the context, and \
         render a frame of the default view first",
    )
}

/// Writes the cloud shadow map's matrix and layout after the last frame of the default view
/// to `*out`. `NIMBUS_ERROR_NOT_READY` when the context was made without
/// `NimbusCloudShadowsExt` or no frame of the default view has rendered yet. Since ABI 0.5.
///
/// Safety: `ctx` NULL or live; `out` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_cloud_shadows(
    ctx: *mut NimbusContext,
    out: *mut NimbusCloudShadowInfo,
) -> NimbusResult {
    // SAFETY: the caller guarantees a live context or NULL, and `out` writable or NULL.
    unsafe {
        with_ctx(ctx, |inner| {
            let out = out.as_mut().ok_or_else(|| FfiError::null("out"))?;
            check_chain(out.next, &[])?;
            let map = inner.renderer_mut().cloud_shadows().ok_or_else(not_ready)?;
            *out = NimbusCloudShadowInfo {
                next: out.next,
                world_to_map: map.world_to_map.to_cols_array(),
                sun: map.sun.to_array(),
                resolution: map.resolution,
                window_origin: map.window_origin.to_array(),
                extent: map.extent,
                reserved: 0,
            };
            Ok(NIMBUS_OK)
        })
    }
}

/// Copies the cloud shadow map to `out`: `float_count` must be 4 × resolution², filled row by
/// row from texel (0, 0) with (front depth m, mean extinction 1/m, optical depth,
/// transmittance) per texel. Waits for the GPU (for CPU shading and tests, not every frame of
/// a GPU host: bind the texture instead). `NIMBUS_ERROR_NOT_READY` as for
/// `nimbus_context_cloud_shadows`; `NIMBUS_ERROR_INVALID_TARGET` for a wrong count. Since
/// ABI 0.5.
///
/// Safety: `ctx` NULL or live; `out` NULL or writable for `float_count` floats.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_read_cloud_shadows(
    ctx: *mut NimbusContext,
    out: *mut f32,
    float_count: usize,
) -> NimbusResult {
    // SAFETY: the caller guarantees a live context or NULL.
    unsafe {
        with_ctx(ctx, |inner| {
            if out.is_null() {
                return Err(FfiError::null("out"));
            }
            let (device, queue) = (inner.device.clone(), inner.queue.clone());
            let map = inner.renderer_mut().cloud_shadows().ok_or_else(not_ready)?;
            let want = check_float_count(float_count, (map.resolution, map.resolution), "map")?;
            let bytes = read_texture(&device, &queue, map.texture, 0)?;
            // The copy left the map in a transfer layout: put it back where the host's Vulkan
            // device expects it (NimbusVulkanShadowImage.layout), whoever samples it next.
            let mut encoder = device.create_command_encoder(&Default::default());
            encoder.transition_resources(
                std::iter::empty(),
                std::iter::once(wgpu::TextureTransition {
                    texture: map.texture,
                    selector: None,
                    state: wgpu::TextureUses::RESOURCE,
                }),
            );
            queue.submit([encoder.finish()]);
            inner.take_device_errors()?;
            let floats = read_halfs(&bytes);
            // SAFETY: the caller guarantees room for float_count (= want) floats.
            std::slice::from_raw_parts_mut(out, want).copy_from_slice(&floats);
            Ok(NIMBUS_OK)
        })
    }
}

/// The float count a 4-float-per-texel copy of a `size` image needs, or the error naming it.
pub(crate) fn check_float_count(
    float_count: usize,
    size: (u32, u32),
    what: &str,
) -> Result<usize, FfiError> {
    let want = 4 * size.0 as usize * size.1 as usize;
    if float_count == want {
        return Ok(want);
    }
    Err(FfiError::new(
        NIMBUS_ERROR_INVALID_TARGET,
        format!(
            "float_count is {float_count}; the {w}x{h} {what} needs 4 x {w} x {h} = {want}",
            w = size.0,
            h = size.1
        ),
    ))
}

fn read_halfs(bytes: &[u8]) -> Vec<f32> {
    bytes
        .chunks_exact(2)
        .map(|c| half::f16::from_le_bytes([c[0], c[1]]).to_f32())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Released with ABI 0.5: the sizes and offsets a C compiler must agree on.
    #[test]
    fn cloud_shadow_layouts_are_pinned() {
        use std::mem::{offset_of, size_of};
        assert_eq!(size_of::<NimbusCloudShadowsExt>(), 40);
        assert_eq!(offset_of!(NimbusCloudShadowsExt, flags), 32);
        assert_eq!(offset_of!(NimbusCloudShadowsExt, reserved), 36);
        assert_eq!(offset_of!(NimbusCloudShadowsExt, extent), 16);
        assert_eq!(offset_of!(NimbusCloudShadowsExt, resolution), 20);
        assert_eq!(offset_of!(NimbusCloudShadowsExt, steps), 24);
        assert_eq!(offset_of!(NimbusCloudShadowsExt, update_slices), 28);
        assert_eq!(size_of::<NimbusCloudShadowInfo>(), 104);
        assert_eq!(offset_of!(NimbusCloudShadowInfo, world_to_map), 8);
        assert_eq!(offset_of!(NimbusCloudShadowInfo, sun), 72);
        assert_eq!(offset_of!(NimbusCloudShadowInfo, resolution), 84);
        assert_eq!(offset_of!(NimbusCloudShadowInfo, window_origin), 88);
        assert_eq!(offset_of!(NimbusCloudShadowInfo, extent), 96);
        assert_eq!(offset_of!(NimbusCloudShadowInfo, reserved), 100);
    }
}
