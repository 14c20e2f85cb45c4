//! The per-frame outputs in the C API (contract version `NIMBUS_FRAME_OUTPUTS_VERSION`,
//! docs/frame-outputs.md): what a view's last frame left besides the picture.

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
}
