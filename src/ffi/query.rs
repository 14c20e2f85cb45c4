//! CPU cloud queries in the C API: a query handle made from a context (a copy of its noise and
//! weather maps and its weather timeline), then density, transmittance and coverage calls
//! from any thread, with no GPU work and no lock on the context.

use super::context::with_ctx;
use super::{boundary, FfiError, NimbusContext, NimbusResult, NIMBUS_OK};
use crate::CloudQuery;

/// A CPU cloud query (see `nimbus_context_create_cloud_query`): independent of its context
/// once made, safe to use from several threads at once. Since ABI 0.5.
pub struct NimbusCloudQuery {
    query: CloudQuery,
}

/// Makes a CPU query that answers as the context renders: the cloud density at a point, the
/// transmittance along a segment, the coverage above a point, at any host time, transitions
/// included, until the next weather request or settings change (make a new one then; the
/// old one keeps the old weather). The first after creation or a weather request reads the
/// noise and weather maps back (waits for the GPU); later ones share that copy. The horizon
/// gradient is measured from the camera of the last frame of the default view. Free it with
/// `nimbus_cloud_query_destroy` (it may outlive the context). Since ABI 0.5.
///
/// Safety: `ctx` NULL or live; `out` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_create_cloud_query(
    ctx: *mut NimbusContext,
    out: *mut *mut NimbusCloudQuery,
) -> NimbusResult {
    // SAFETY: the caller guarantees a live context or NULL, and `out` writable or NULL.
    unsafe {
        with_ctx(ctx, |inner| {
            let out = out.as_mut().ok_or_else(|| FfiError::null("out"))?;
            let query = inner.renderer_mut().cloud_query()?;
            inner.take_device_errors()?;
            *out = Box::into_raw(Box::new(NimbusCloudQuery { query }));
            Ok(NIMBUS_OK)
        })
    }
}

/// Runs `f` on a live query inside the panic boundary (errors on the thread's message only).
unsafe fn with_query(
    q: *const NimbusCloudQuery,
    out: *mut f32,
    f: impl FnOnce(&CloudQuery) -> Result<f32, FfiError>,
) -> NimbusResult {
    boundary(
        || {
            // SAFETY: the caller guarantees a live query or NULL, `out` writable or NULL.
            let q = unsafe { q.as_ref() }.ok_or_else(|| FfiError::null("query"))?;
            let out = unsafe { out.as_mut() }.ok_or_else(|| FfiError::null("out"))?;
            *out = f(&q.query)?;
            Ok(NIMBUS_OK)
        },
        |_, _| {},
    )
}

/// Three floats from C.
unsafe fn point(p: *const f32, name: &str) -> Result<glam::Vec3, FfiError> {
    if p.is_null() {
        return Err(FfiError::null(name));
    }
    // SAFETY: the caller guarantees three readable floats.
    Ok(glam::Vec3::from_slice(unsafe {
        std::slice::from_raw_parts(p, 3)
    }))
}

/// Writes the unitless cloud density at world point `p` (3 floats, m) at host time `time` to
/// `*out`, as the march computes it (the extinction is this times the weather's extinction).
/// `NIMBUS_ERROR_INVALID_ARGUMENT` for a non-finite point or time. Since ABI 0.5.
///
/// Safety: `query` NULL or live; `p` NULL or 3 readable floats; `out` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nimbus_cloud_query_density(
    query: *const NimbusCloudQuery,
    p: *const f32,
    time: f64,
    out: *mut f32,
) -> NimbusResult {
    // SAFETY: forwarded from the caller's guarantees.
    unsafe {
        with_query(query, out, |q| {
            let p = point(p, "p")?;
            Ok(q.density(p, time)?)
        })
    }
}

/// Writes the clouds' transmittance along the segment from `a` to `b` (3 floats each, m) at
/// host time `time` to `*out`, in [0, 1]: is the sun visible from a point (b far toward the
/// sun), is an aircraft in cloud. The ground does not block. Since ABI 0.5.
///
/// Safety: `query` NULL or live; `a`, `b` NULL or 3 readable floats; `out` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nimbus_cloud_query_transmittance(
    query: *const NimbusCloudQuery,
    a: *const f32,
    b: *const f32,
    time: f64,
    out: *mut f32,
) -> NimbusResult {
    // SAFETY: forwarded from the caller's guarantees.
    unsafe {
        with_query(query, out, |q| {
            let a = point(a, "a")?;
            let b = point(b, "b")?;
            Ok(q.transmittance(a, b, time)?)
        })
    }
}

/// Writes the cloud coverage above the horizontal position of `p` (3 floats, m) at host time
/// `time` to `*out`, in [0, 1]: the densest layer's coverage there. Since ABI 0.5.
///
/// Safety: `query` NULL or live; `p` NULL or 3 readable floats; `out` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nimbus_cloud_query_coverage_above(
    query: *const NimbusCloudQuery,
    p: *const f32,
    time: f64,
    out: *mut f32,
) -> NimbusResult {
    // SAFETY: forwarded from the caller's guarantees.
    unsafe {
        with_query(query, out, |q| {
            let p = point(p, "p")?;
            Ok(q.coverage_above(p, time)?)
        })
    }
}

/// Frees a query. NULL is a no-op. No call may be using it. Since ABI 0.5.
///
/// Safety: `query` NULL or from `nimbus_context_create_cloud_query`, not yet destroyed.
#[no_mangle]
pub unsafe extern "C" fn nimbus_cloud_query_destroy(query: *mut NimbusCloudQuery) {
    if !query.is_null() {
        boundary(
            || {
                // SAFETY: made by Box::into_raw in nimbus_context_create_cloud_query.
                drop(unsafe { Box::from_raw(query) });
                Ok(NIMBUS_OK)
            },
            |_, _| {},
        );
    }
}
