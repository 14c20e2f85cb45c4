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

fn not_ready() -> FfiError {
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
            let want = 4 * (map.resolution as usize).pow(2);
            if float_count != want {
                return Err(FfiError::new(
                    NIMBUS_ERROR_INVALID_TARGET,
                    format!(
                        "float_count is {float_count}; the {n}x{n} map needs 4 x {n} x {n} = {want}",
                        n = map.resolution
                    ),
                ));
            }
            let bytes = read_texture(&device, &queue, map.texture, 0)?;
            inner.take_device_errors()?;
            let floats = read_halfs(&bytes);
            // SAFETY: the caller guarantees room for float_count (= want) floats.
            std::slice::from_raw_parts_mut(out, want).copy_from_slice(&floats);
            Ok(NIMBUS_OK)
        })
    }
}

fn read_halfs(bytes: &[u8]) -> Vec<f32> {
    bytes
        .chunks_exact(2)
        .map(|c| half::f16::from_le_bytes([c[0], c[1]]).to_f32())
        .collect()
}

/// A view's per-frame outputs besides the picture (contract version
/// `NIMBUS_FRAME_OUTPUTS_VERSION`; docs/frame-outputs.md). Since ABI 0.5.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NimbusFrameOutputs {
    /// Must be NULL.
    pub next: *const NimbusChainedStruct,
    /// `NIMBUS_FRAME_OUTPUTS_VERSION` of the library that wrote it.
    pub version: u32,
    /// The cloud image's size: the viewport divided by the trace resolution's divisor.
    pub grid_width: u32,
    /// See `grid_width`.
    pub grid_height: u32,
    /// 1 when the context keeps a cloud shadow map (`nimbus_context_cloud_shadows`), else 0.
    pub has_cloud_shadows: u32,
}

/// The per-frame output contract's version (`NimbusFrameOutputs.version`). Since ABI 0.5.
pub const NIMBUS_FRAME_OUTPUTS_VERSION: u32 = 1;

/// Writes what `view`'s last frame left besides the picture to `*out`: the contract version,
/// the cloud image's grid size, whether a shadow map exists. `NIMBUS_ERROR_NOT_READY` before
/// the view's first frame; `NIMBUS_ERROR_INVALID_ARGUMENT` for an unknown view. Since ABI 0.5.
///
/// Safety: `ctx` NULL or live; `out` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_frame_outputs(
    ctx: *mut NimbusContext,
    view: u32,
    out: *mut NimbusFrameOutputs,
) -> NimbusResult {
    // SAFETY: the caller guarantees a live context or NULL, and `out` writable or NULL.
    unsafe {
        with_ctx(ctx, |inner| {
            let out = out.as_mut().ok_or_else(|| FfiError::null("out"))?;
            check_chain(out.next, &[])?;
            let outputs = frame_outputs(inner, view)?;
            *out = NimbusFrameOutputs {
                next: out.next,
                version: outputs.version,
                grid_width: outputs.grid.0,
                grid_height: outputs.grid.1,
                has_cloud_shadows: outputs.shadows.is_some() as u32,
            };
            Ok(NIMBUS_OK)
        })
    }
}

fn frame_outputs(
    inner: &mut super::context::ContextInner,
    view: u32,
) -> Result<crate::FrameOutputs<'_>, FfiError> {
    let id = crate::ViewId::from_raw(view);
    let renderer = inner.renderer_mut();
    // An unknown view is the caller's mistake; a known one without a frame is not ready.
    renderer.view_memory_bytes(id)?;
    renderer.frame_outputs(id).map_err(|_| {
        FfiError::new(
            NIMBUS_ERROR_NOT_READY,
            "this view has not rendered a frame yet",
        )
    })
}

/// Copies `view`'s cloud image to `out`: `float_count` must be 4 × grid_width × grid_height
/// (from `nimbus_context_frame_outputs`), filled row by row with (transmittance, front depth
/// in m, representative depth in m, 0) per grid pixel; depths are 0 where the ray met no
/// cloud. Waits for the GPU. Since ABI 0.5.
///
/// Safety: `ctx` NULL or live; `out` NULL or writable for `float_count` floats.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_read_frame_outputs(
    ctx: *mut NimbusContext,
    view: u32,
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
            let outputs = frame_outputs(inner, view)?;
            let want = 4 * outputs.grid.0 as usize * outputs.grid.1 as usize;
            if float_count != want {
                return Err(FfiError::new(
                    NIMBUS_ERROR_INVALID_TARGET,
                    format!(
                        "float_count is {float_count}; the {}x{} cloud image needs 4 x {} x {} = {want}",
                        outputs.grid.0, outputs.grid.1, outputs.grid.0, outputs.grid.1
                    ),
                ));
            }
            let pixels = crate::headless::read_outputs(&device, &queue, &outputs)?;
            inner.take_device_errors()?;
            // SAFETY: the caller guarantees room for float_count (= want) floats.
            std::slice::from_raw_parts_mut(out, want)
                .copy_from_slice(bytemuck::cast_slice(&pixels));
            Ok(NIMBUS_OK)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Released with ABI 0.5: the sizes and offsets a C compiler must agree on.
    #[test]
    fn the_c_contract_version_is_the_rust_one() {
        assert_eq!(NIMBUS_FRAME_OUTPUTS_VERSION, crate::FRAME_OUTPUTS_VERSION);
    }

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
        assert_eq!(size_of::<NimbusFrameOutputs>(), 24);
        assert_eq!(offset_of!(NimbusFrameOutputs, version), 8);
        assert_eq!(offset_of!(NimbusFrameOutputs, grid_width), 12);
        assert_eq!(offset_of!(NimbusFrameOutputs, grid_height), 16);
        assert_eq!(offset_of!(NimbusFrameOutputs, has_cloud_shadows), 20);
    }
}
