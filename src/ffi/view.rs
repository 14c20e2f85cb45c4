//! Views in the C API: several cameras (split screen, stereo, probe faces) on one context,
//! sharing its noise, weather maps and pipelines, each with its own history (`crate::view`).

use super::context::{check_chain, with_ctx};
use super::{FfiError, FfiResult, NimbusChainedStruct, NimbusContext, NimbusResult};
use super::{NIMBUS_ERROR_NULL_POINTER, NIMBUS_ERROR_UNKNOWN_STRUCT, NIMBUS_OK};
use crate::ViewId;

/// `s_type` of `NimbusViewExt` (chain it to `NimbusFrame.next`). Since ABI 0.4.
pub const NIMBUS_STYPE_VIEW: u32 = 5;

/// The view a context has from its creation: frames with no `NimbusViewExt` render it.
pub const NIMBUS_VIEW_DEFAULT: u32 = 0;

/// Chained to a frame: the frame is this view's camera, and renders with this view's
/// history and trace textures. Without it a frame renders `NIMBUS_VIEW_DEFAULT`. Since ABI
/// 0.4.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NimbusViewExt {
    /// `s_type` = `NIMBUS_STYPE_VIEW`.
    pub chain: NimbusChainedStruct,
    /// A view from `nimbus_context_create_view`, or `NIMBUS_VIEW_DEFAULT`.
    pub view: u32,
    /// Must be 0.
    pub reserved: u32,
}

/// The s_types a frame's chain may hold.
pub(crate) const FRAME_CHAIN: &[u32] = &[NIMBUS_STYPE_VIEW];

/// The view a frame's chain names (the default view when none), checking the chain.
pub(crate) fn view_of(next: *const NimbusChainedStruct) -> FfiResult<ViewId> {
    check_chain(next, FRAME_CHAIN)?;
    if next.is_null() {
        return Ok(ViewId::DEFAULT);
    }
    // SAFETY: the chain was checked; its first link has s_type NIMBUS_STYPE_VIEW.
    let link = unsafe { &*next };
    if !link.next.is_null() {
        return Err(FfiError::new(
            NIMBUS_ERROR_UNKNOWN_STRUCT,
            "NimbusViewExt appears more than once in the frame's chain",
        ));
    }
    // SAFETY: an s_type of NIMBUS_STYPE_VIEW promises a NimbusViewExt.
    let v = unsafe { &*(next as *const NimbusViewExt) };
    if v.reserved != 0 {
        return Err(FfiError::arg("NimbusViewExt.reserved must be 0"));
    }
    Ok(ViewId::from_raw(v.view))
}

/// Makes a view: its own camera history and trace textures (made at its first frame, sized
/// to its viewport), sharing the context's noise, weather maps and pipelines. Render it by
/// chaining a `NimbusViewExt` to the frame. Use one view per camera that renders every
/// frame (each split-screen player, each eye, each probe face); a context holds at most 64
/// (`NIMBUS_ERROR_INVALID_ARGUMENT` beyond). Creates no GPU work. Since ABI 0.4.
///
/// Safety: `ctx` NULL or live; `out_view` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_create_view(
    ctx: *mut NimbusContext,
    out_view: *mut u32,
) -> NimbusResult {
    if out_view.is_null() {
        super::set_thread_error("`out_view` is NULL");
        return NIMBUS_ERROR_NULL_POINTER;
    }
    // SAFETY: `ctx` is NULL or live, `out_view` writable, per the caller.
    unsafe {
        with_ctx(ctx, |inner| {
            let view = inner.renderer_mut().create_view()?;
            *out_view = view.to_raw();
            Ok(NIMBUS_OK)
        })
    }
}

/// Destroys a view made by `nimbus_context_create_view`; its textures are freed once the
/// GPU work that uses them has finished. Its id is refused from then on
/// (`NIMBUS_ERROR_INVALID_ARGUMENT`), and so is `NIMBUS_VIEW_DEFAULT`. Since ABI 0.4.
///
/// Safety: `ctx` NULL or live.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_destroy_view(
    ctx: *mut NimbusContext,
    view: u32,
) -> NimbusResult {
    // SAFETY: `ctx` is NULL or live per the caller.
    unsafe {
        with_ctx(ctx, |inner| {
            inner.renderer_mut().destroy_view(ViewId::from_raw(view))?;
            Ok(NIMBUS_OK)
        })
    }
}

/// Drops one view's accumulated history (a camera cut in that view);
/// `nimbus_context_reset_history` drops every view's. Since ABI 0.4.
///
/// Safety: `ctx` NULL or live.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_reset_view_history(
    ctx: *mut NimbusContext,
    view: u32,
) -> NimbusResult {
    // SAFETY: `ctx` is NULL or live per the caller.
    unsafe {
        with_ctx(ctx, |inner| {
            inner
                .renderer_mut()
                .reset_view_history(ViewId::from_raw(view))?;
            Ok(NIMBUS_OK)
        })
    }
}

/// GPU memory in bytes: what one view holds (its trace textures and uniforms) into
/// `out_view_bytes`, and what all views share (noise volumes, weather maps, blue noise) into
/// `out_shared_bytes` (may be NULL). A context's total is the shared part plus every view's.
/// Since ABI 0.4.
///
/// Safety: `ctx` NULL or live; `out_view_bytes` NULL or writable; `out_shared_bytes` NULL or
/// writable.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_view_memory(
    ctx: *mut NimbusContext,
    view: u32,
    out_view_bytes: *mut u64,
    out_shared_bytes: *mut u64,
) -> NimbusResult {
    if out_view_bytes.is_null() {
        super::set_thread_error("`out_view_bytes` is NULL");
        return NIMBUS_ERROR_NULL_POINTER;
    }
    // SAFETY: `ctx` is NULL or live, the outputs writable or (the shared one) NULL, per the
    // caller.
    unsafe {
        with_ctx(ctx, |inner| {
            let renderer = inner.renderer_mut();
            *out_view_bytes = renderer.view_memory_bytes(ViewId::from_raw(view))?;
            if let Some(shared) = out_shared_bytes.as_mut() {
                *shared = renderer.shared_memory_bytes();
            }
            Ok(NIMBUS_OK)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Released with ABI 0.4: the size and offsets a C compiler must agree on.
    #[test]
    fn view_ext_layout_is_pinned() {
        assert_eq!(std::mem::size_of::<NimbusViewExt>(), 24);
        assert_eq!(std::mem::offset_of!(NimbusViewExt, view), 16);
        assert_eq!(std::mem::offset_of!(NimbusViewExt, reserved), 20);
    }
}
