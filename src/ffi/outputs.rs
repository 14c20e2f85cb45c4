//! The per-frame outputs in the C API (contract version `NIMBUS_FRAME_OUTPUTS_VERSION`,
//! docs/frame-outputs.md): what a view's last frame left besides the picture, and the light
//! at its camera.

use super::context::{check_chain, with_ctx};
use super::shadows::check_float_count;
use super::{FfiError, NimbusChainedStruct, NimbusContext, NimbusResult};
use super::{NIMBUS_ERROR_NOT_READY, NIMBUS_OK};

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
            let want = check_float_count(float_count, outputs.grid, "cloud image")?;
            let pixels = crate::headless::read_outputs(&device, &queue, &outputs)?;
            inner.take_device_errors()?;
            // SAFETY: the caller guarantees room for float_count (= want) floats.
            std::slice::from_raw_parts_mut(out, want)
                .copy_from_slice(bytemuck::cast_slice(&pixels));
            Ok(NIMBUS_OK)
        })
    }
}

/// The light at a view's camera from the hemisphere above and the one below, as its last
/// submitted frame found it (docs/frame-outputs.md, "Ambient light"). For each hemisphere:
/// the clouds' irradiance (rgb, linear, the sun's units) and the sky visibility in [0, 1], the
/// share of the host's own light from that hemisphere (its sky above, its ground below) that
/// still arrives through the clouds; the total is `cloud_irradiance + sky_visibility × host`.
/// Since ABI 0.7.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NimbusAmbientLight {
    /// Must be NULL.
    pub next: *const NimbusChainedStruct,
    /// The clouds' irradiance on a surface facing up (rgb).
    pub above_cloud_irradiance: [f32; 3],
    /// The cosine-weighted transmittance of the clouds over the upper hemisphere.
    pub above_sky_visibility: f32,
    /// The clouds' irradiance on a surface facing down (clouds below a camera above them).
    pub below_cloud_irradiance: [f32; 3],
    /// The cosine-weighted transmittance of the clouds over the lower hemisphere.
    pub below_sky_visibility: f32,
}

/// Writes the light at `view`'s camera (above and below) to `*out`. Waits for the GPU (a
/// 32-byte copy after what was submitted): a host that lights with it every frame may read it
/// every few frames. `NIMBUS_ERROR_NOT_READY` before the view's first frame;
/// `NIMBUS_ERROR_INVALID_ARGUMENT` for an unknown view; `NIMBUS_ERROR_UNKNOWN_STRUCT` when
/// `out->next` is not NULL. Since ABI 0.7.
///
/// Safety: `ctx` NULL or live; `out` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_read_ambient_light(
    ctx: *mut NimbusContext,
    view: u32,
    out: *mut NimbusAmbientLight,
) -> NimbusResult {
    // SAFETY: the caller guarantees a live context or NULL, and `out` writable or NULL.
    unsafe {
        with_ctx(ctx, |inner| {
            let out = out.as_mut().ok_or_else(|| FfiError::null("out"))?;
            check_chain(out.next, &[])?;
            frame_outputs(inner, view)?;
            let light = inner
                .renderer_mut()
                .read_ambient_light(crate::ViewId::from_raw(view))?;
            inner.take_device_errors()?;
            *out = NimbusAmbientLight {
                next: out.next,
                above_cloud_irradiance: light.above.cloud_irradiance.to_array(),
                above_sky_visibility: light.above.sky_visibility,
                below_cloud_irradiance: light.below.cloud_irradiance.to_array(),
                below_sky_visibility: light.below.sky_visibility,
            };
            Ok(NIMBUS_OK)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_c_contract_version_is_the_rust_one() {
        assert_eq!(NIMBUS_FRAME_OUTPUTS_VERSION, crate::FRAME_OUTPUTS_VERSION);
    }

    /// Released with ABI 0.5: the size and offsets a C compiler must agree on.
    #[test]
    fn frame_outputs_layout_is_pinned() {
        use std::mem::{offset_of, size_of};
        assert_eq!(size_of::<NimbusFrameOutputs>(), 24);
        assert_eq!(offset_of!(NimbusFrameOutputs, version), 8);
        assert_eq!(offset_of!(NimbusFrameOutputs, grid_width), 12);
        assert_eq!(offset_of!(NimbusFrameOutputs, grid_height), 16);
        assert_eq!(offset_of!(NimbusFrameOutputs, has_cloud_shadows), 20);
    }

    /// Released with ABI 0.7.
    #[test]
    fn ambient_light_layout_is_pinned() {
        use std::mem::{offset_of, size_of};
        assert_eq!(size_of::<NimbusAmbientLight>(), 40);
        assert_eq!(offset_of!(NimbusAmbientLight, above_cloud_irradiance), 8);
        assert_eq!(offset_of!(NimbusAmbientLight, above_sky_visibility), 20);
        assert_eq!(offset_of!(NimbusAmbientLight, below_cloud_irradiance), 24);
        assert_eq!(offset_of!(NimbusAmbientLight, below_sky_visibility), 36);
    }
}
