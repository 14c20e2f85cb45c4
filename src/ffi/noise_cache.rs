//! The noise cache in the C API: handed in at creation by a chained struct (the volumes are
//! uploaded instead of baked), written out by the host's call. See docs/c-api.md "Fast start".

use std::ffi::c_void;

use super::context::with_ctx;
use super::{FfiError, FfiResult, NimbusChainedStruct, NimbusContext, NimbusResult};
use super::{NIMBUS_ERROR_INVALID_TARGET, NIMBUS_OK};
use crate::NoiseStart;

/// `s_type` of `NimbusNoiseCacheExt` (chain it to `NimbusContextDesc.next`). Since ABI 0.6.
pub const NIMBUS_STYPE_NOISE_CACHE: u32 = 7;

/// `NimbusNoiseCacheExt.flags`: a cache that cannot serve this context (damaged, written by a
/// library with another noise bake, or for another seed or volume size) is ignored with a
/// warning in the log and the volumes are baked, instead of failing the creation with
/// `NIMBUS_ERROR_NOISE_CACHE`. `nimbus_context_noise_from_cache` tells which happened.
/// Since ABI 0.6.
pub const NIMBUS_NOISE_CACHE_FALLBACK: u32 = 1;

/// Chained to the context's creation: the noise volumes from a cache that
/// `nimbus_context_export_noise_cache` wrote, uploaded instead of baked (most of a creation's
/// time on software Vulkan). The bytes are read during `nimbus_context_create` only; the host
/// may free them once it returns. Since ABI 0.6.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NimbusNoiseCacheExt {
    /// `s_type` = `NIMBUS_STYPE_NOISE_CACHE`.
    pub chain: NimbusChainedStruct,
    /// The cache's bytes.
    pub data: *const c_void,
    /// Their count (not 0).
    pub size: usize,
    /// `NIMBUS_NOISE_CACHE_*` flags; 0 = none (an unusable cache fails the creation).
    pub flags: u32,
    /// Must be 0.
    pub reserved: u32,
}

/// A checked `NimbusNoiseCacheExt`, for the creation to turn into a `NoiseStart`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct NoiseCacheArg {
    data: *const u8,
    size: usize,
    fallback: bool,
}

impl NoiseCacheArg {
    /// The noise start it asks for.
    ///
    /// Safety: `data` is still readable for `size` bytes (during the creation call).
    pub(crate) unsafe fn start(&self) -> NoiseStart<'_> {
        // SAFETY: checked non-NULL and at most isize::MAX; readable per the caller.
        let bytes = unsafe { std::slice::from_raw_parts(self.data, self.size) };
        if self.fallback {
            NoiseStart::CacheOrBake(bytes)
        } else {
            NoiseStart::Cache(bytes)
        }
    }
}

impl NoiseCacheArg {
    /// Refuses, before any device work, a cache that cannot serve `settings` (unless the
    /// host asked for the fallback, which decides at creation).
    ///
    /// Safety: as for `start`.
    pub(crate) unsafe fn check(&self, settings: &crate::Settings) -> FfiResult<()> {
        // SAFETY: per the caller.
        if let NoiseStart::Cache(bytes) = unsafe { self.start() } {
            crate::noise_cache::volumes_for(bytes, &settings.noise)?;
        }
        Ok(())
    }
}

/// Checks a chain's `NimbusNoiseCacheExt`.
///
/// Safety: `p` points to a `NimbusNoiseCacheExt`.
pub(crate) unsafe fn cache_from_ext(p: *const NimbusChainedStruct) -> FfiResult<NoiseCacheArg> {
    // SAFETY: per the caller.
    let ext = unsafe { &*p.cast::<NimbusNoiseCacheExt>() };
    if ext.flags & !NIMBUS_NOISE_CACHE_FALLBACK != 0 {
        return Err(FfiError::arg(format!(
            "unknown NimbusNoiseCacheExt.flags bits 0x{:x}",
            ext.flags & !NIMBUS_NOISE_CACHE_FALLBACK
        )));
    }
    if ext.reserved != 0 {
        return Err(FfiError::arg("NimbusNoiseCacheExt.reserved must be 0"));
    }
    if ext.data.is_null() {
        return Err(FfiError::null("NimbusNoiseCacheExt.data"));
    }
    if ext.size == 0 || ext.size > isize::MAX as usize {
        return Err(FfiError::arg(format!(
            "NimbusNoiseCacheExt.size is {}: give the byte count nimbus_context_export_noise_cache wrote",
            ext.size
        )));
    }
    Ok(NoiseCacheArg {
        data: ext.data.cast(),
        size: ext.size,
        fallback: ext.flags & NIMBUS_NOISE_CACHE_FALLBACK != 0,
    })
}

/// Writes the context's noise volumes as a noise cache: a host stores the bytes (a file, an
/// asset) and chains them in a `NimbusNoiseCacheExt` to later creations. With `data` NULL
/// only `*size` is written: the byte count needed (about 8.5 MB for the default volumes).
/// Otherwise `capacity` must be at least that (`NIMBUS_ERROR_INVALID_TARGET` if not, with
/// `*size` still written), and the cache is copied to `data` (waits for the GPU: call it once,
/// e.g. at exit or after a loading screen, not every frame). Since ABI 0.6.
///
/// Safety: `ctx` NULL or live; `size` NULL or writable; `data` NULL or writable for
/// `capacity` bytes.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_export_noise_cache(
    ctx: *mut NimbusContext,
    data: *mut c_void,
    capacity: usize,
    size: *mut usize,
) -> NimbusResult {
    // SAFETY: the caller guarantees a live context or NULL and the pointers' validity.
    unsafe {
        with_ctx(ctx, |inner| {
            let size = size.as_mut().ok_or_else(|| FfiError::null("size"))?;
            let noise = &inner.renderer_mut().settings().noise;
            let want = crate::noise_cache::cache_bytes(noise.base_size, noise.detail_size)
                .ok_or_else(|| FfiError::arg("the noise volumes are too large for a cache"))?;
            *size = want;
            if data.is_null() {
                return Ok(NIMBUS_OK);
            }
            if capacity < want {
                return Err(FfiError::new(
                    NIMBUS_ERROR_INVALID_TARGET,
                    format!("capacity is {capacity} bytes; the noise cache needs {want}"),
                ));
            }
            let bytes = inner.renderer_mut().export_noise_cache()?;
            inner.take_device_errors()?;
            if bytes.len() != want {
                return Err(FfiError::new(
                    NIMBUS_ERROR_INVALID_TARGET,
                    format!("the noise cache came out {} bytes, not {want}", bytes.len()),
                ));
            }
            // SAFETY: the caller guarantees room for capacity (>= want = bytes.len()) bytes.
            std::slice::from_raw_parts_mut(data.cast::<u8>(), bytes.len()).copy_from_slice(&bytes);
            Ok(NIMBUS_OK)
        })
    }
}

/// Writes 1 to `*out` when the context's noise volumes came from a `NimbusNoiseCacheExt`, 0
/// when they were baked (no cache, a cache ignored under `NIMBUS_NOISE_CACHE_FALLBACK`, or a
/// settings change that re-baked them). Since ABI 0.6.
///
/// Safety: `ctx` NULL or live; `out` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_noise_from_cache(
    ctx: *mut NimbusContext,
    out: *mut u32,
) -> NimbusResult {
    // SAFETY: the caller guarantees a live context or NULL, and `out` writable or NULL.
    unsafe {
        with_ctx(ctx, |inner| {
            let out = out.as_mut().ok_or_else(|| FfiError::null("out"))?;
            *out = u32::from(inner.renderer_mut().noise_from_cache());
            Ok(NIMBUS_OK)
        })
    }
}

#[cfg(all(test, target_pointer_width = "64"))]
mod tests {
    use super::*;

    /// Released with ABI 0.6: the sizes and offsets a C compiler must agree on.
    #[test]
    fn noise_cache_layout_is_pinned() {
        use std::mem::{offset_of, size_of};
        assert_eq!(size_of::<NimbusNoiseCacheExt>(), 40);
        assert_eq!(offset_of!(NimbusNoiseCacheExt, data), 16);
        assert_eq!(offset_of!(NimbusNoiseCacheExt, size), 24);
        assert_eq!(offset_of!(NimbusNoiseCacheExt, flags), 32);
        assert_eq!(offset_of!(NimbusNoiseCacheExt, reserved), 36);
    }
}
