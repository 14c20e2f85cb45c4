//! Textures the host creates, uploads into and reads back: for hosts (and tests) without a GPU
//! API of their own. Each holds its own reference to the device: it may outlive its context.

use std::ffi::c_void;
use std::sync::{Arc, Weak};

use super::context::{with_ctx, NimbusContext};
use super::{
    boundary, check_chain, FfiError, FfiResult, NimbusResult, NimbusTextureDesc, NIMBUS_OK,
};
use super::{
    NIMBUS_ERROR_INVALID_TARGET, NIMBUS_FORMAT_BGRA8_UNORM, NIMBUS_FORMAT_BGRA8_UNORM_SRGB,
    NIMBUS_FORMAT_DEPTH16_UNORM, NIMBUS_FORMAT_R32_FLOAT, NIMBUS_FORMAT_RG11B10_UFLOAT,
    NIMBUS_FORMAT_RGB10A2_UNORM, NIMBUS_FORMAT_RGBA16_FLOAT, NIMBUS_FORMAT_RGBA32_FLOAT,
    NIMBUS_FORMAT_RGBA8_UNORM, NIMBUS_FORMAT_RGBA8_UNORM_SRGB,
};
use crate::device::{gpu_scope, read_texture, texture_2d};
use crate::headless::MAX_HEADLESS_SIZE;

/// An opaque texture handle (see `nimbus_texture_create`).
pub struct NimbusTexture {
    pub(crate) texture: wgpu::Texture,
    pub(crate) view: wgpu::TextureView,
    device: wgpu::Device,
    queue: wgpu::Queue,
    bytes_per_pixel: u32,
    /// Its `NIMBUS_FORMAT_*` value.
    pub(crate) format: u32,
    /// The context that made it: only that one may use it.
    context_id: u64,
    /// Alive while that context is.
    context: Weak<()>,
}

fn format_of(format: u32) -> FfiResult<(wgpu::TextureFormat, u32)> {
    use wgpu::TextureFormat as F;
    Ok(match format {
        NIMBUS_FORMAT_RGBA8_UNORM => (F::Rgba8Unorm, 4),
        NIMBUS_FORMAT_RGBA8_UNORM_SRGB => (F::Rgba8UnormSrgb, 4),
        NIMBUS_FORMAT_RGBA16_FLOAT => (F::Rgba16Float, 8),
        NIMBUS_FORMAT_RGBA32_FLOAT => (F::Rgba32Float, 16),
        NIMBUS_FORMAT_R32_FLOAT => (F::R32Float, 4),
        NIMBUS_FORMAT_BGRA8_UNORM => (F::Bgra8Unorm, 4),
        NIMBUS_FORMAT_BGRA8_UNORM_SRGB => (F::Bgra8UnormSrgb, 4),
        NIMBUS_FORMAT_RGB10A2_UNORM => (F::Rgb10a2Unorm, 4),
        NIMBUS_FORMAT_RG11B10_UFLOAT => (F::Rg11b10Ufloat, 4),
        NIMBUS_FORMAT_DEPTH16_UNORM => (F::Depth16Unorm, 2),
        _ => {
            return Err(FfiError::arg(format!(
                "unknown texture format {format} (valid: NIMBUS_FORMAT_* 1..=10)"
            )))
        }
    })
}

/// The texture behind `tex`, once `data` is non-NULL and `size` is the texture's byte size.
///
/// Safety: `tex` must be NULL or a live texture.
unsafe fn checked<'a>(
    tex: *const NimbusTexture,
    data_is_null: bool,
    size: usize,
) -> FfiResult<&'a NimbusTexture> {
    // SAFETY: checked for NULL; the caller guarantees validity.
    let tex = unsafe { tex.as_ref() }.ok_or_else(|| FfiError::null("tex"))?;
    tex.check_alive()?;
    if data_is_null {
        return Err(FfiError::null("data"));
    }
    tex.check_size(size)?;
    Ok(tex)
}

/// Whether a `NIMBUS_FORMAT_*` value is a color format (else a depth one).
pub(crate) fn is_color(format: u32) -> bool {
    !matches!(
        format,
        NIMBUS_FORMAT_R32_FLOAT | NIMBUS_FORMAT_DEPTH16_UNORM
    )
}

/// The header's name of a `NIMBUS_FORMAT_*` value.
pub(crate) fn format_name(format: u32) -> &'static str {
    match format {
        NIMBUS_FORMAT_RGBA8_UNORM => "NIMBUS_FORMAT_RGBA8_UNORM",
        NIMBUS_FORMAT_RGBA8_UNORM_SRGB => "NIMBUS_FORMAT_RGBA8_UNORM_SRGB",
        NIMBUS_FORMAT_RGBA16_FLOAT => "NIMBUS_FORMAT_RGBA16_FLOAT",
        NIMBUS_FORMAT_RGBA32_FLOAT => "NIMBUS_FORMAT_RGBA32_FLOAT",
        NIMBUS_FORMAT_R32_FLOAT => "NIMBUS_FORMAT_R32_FLOAT",
        NIMBUS_FORMAT_BGRA8_UNORM => "NIMBUS_FORMAT_BGRA8_UNORM",
        NIMBUS_FORMAT_BGRA8_UNORM_SRGB => "NIMBUS_FORMAT_BGRA8_UNORM_SRGB",
        NIMBUS_FORMAT_RGB10A2_UNORM => "NIMBUS_FORMAT_RGB10A2_UNORM",
        NIMBUS_FORMAT_RG11B10_UFLOAT => "NIMBUS_FORMAT_RG11B10_UFLOAT",
        NIMBUS_FORMAT_DEPTH16_UNORM => "NIMBUS_FORMAT_DEPTH16_UNORM",
        _ => "an unknown format",
    }
}

impl NimbusTexture {
    /// Width and height in pixels.
    pub(crate) fn size(&self) -> (u32, u32) {
        (self.texture.width(), self.texture.height())
    }

    /// Refuses a texture whose context is gone: it may then only be destroyed.
    fn check_alive(&self) -> FfiResult {
        if self.context.strong_count() == 0 {
            return Err(FfiError::new(
                NIMBUS_ERROR_INVALID_TARGET,
                "the texture's context was destroyed: the texture can only be destroyed now",
            ));
        }
        Ok(())
    }

    /// Refuses a texture made by another context than `context_id` (or one whose context is
    /// gone); `name` says which argument it was.
    pub(crate) fn check_owner(&self, context_id: u64, name: &str) -> FfiResult {
        self.check_alive()?;
        if self.context_id != context_id {
            return Err(FfiError::new(
                NIMBUS_ERROR_INVALID_TARGET,
                format!("{name} was created by another context: a texture works only with the context that created it"),
            ));
        }
        Ok(())
    }

    fn byte_size(&self) -> usize {
        (self.texture.width() * self.texture.height() * self.bytes_per_pixel) as usize
    }

    fn check_size(&self, size: usize) -> FfiResult {
        if size == self.byte_size() {
            Ok(())
        } else {
            Err(FfiError::new(
                NIMBUS_ERROR_INVALID_TARGET,
                format!(
                    "data is {size} bytes but a {}x{} texture of this format holds {}",
                    self.texture.width(),
                    self.texture.height(),
                    self.byte_size()
                ),
            ))
        }
    }
}

/// Creates a texture on the context's device: color formats can be scene color or output,
/// `NIMBUS_FORMAT_R32_FLOAT` holds scene depth. Contents start zeroed. `*out` is written only
/// on success; free it with `nimbus_texture_destroy`.
///
/// Safety: `ctx`, `desc` and `out` must be NULL or valid pointers.
#[no_mangle]
pub unsafe extern "C" fn nimbus_texture_create(
    ctx: *mut NimbusContext,
    desc: *const NimbusTextureDesc,
    out: *mut *mut NimbusTexture,
) -> NimbusResult {
    // SAFETY: pointers are checked before use; the caller guarantees validity otherwise.
    unsafe {
        with_ctx(ctx, |inner| {
            let desc = desc.as_ref().ok_or_else(|| FfiError::null("desc"))?;
            if out.is_null() {
                return Err(FfiError::null("out"));
            }
            check_chain(desc.next, &[])?;
            let (format, bytes_per_pixel) = format_of(desc.format)?;
            for (name, v) in [("width", desc.width), ("height", desc.height)] {
                if v == 0 || v > MAX_HEADLESS_SIZE {
                    return Err(FfiError::arg(format!(
                        "texture {name} must be in 1..={MAX_HEADLESS_SIZE}, got {v}"
                    )));
                }
            }
            if format == wgpu::TextureFormat::Rg11b10Ufloat
                && !inner
                    .device
                    .features()
                    .contains(wgpu::Features::RG11B10UFLOAT_RENDERABLE)
            {
                return Err(FfiError::new(
                    NIMBUS_ERROR_INVALID_TARGET,
                    "NIMBUS_FORMAT_RG11B10_UFLOAT: this device cannot render to it \
                     (no RG11B10UFLOAT_RENDERABLE); use NIMBUS_FORMAT_RGBA16_FLOAT",
                ));
            }
            use wgpu::TextureUsages as U;
            let mut usage = U::TEXTURE_BINDING | U::COPY_DST | U::COPY_SRC;
            if is_color(desc.format) {
                usage |= U::RENDER_ATTACHMENT;
            }
            // An output Nimbus can store into is composited by a compute pass (much faster
            // on compute-oriented GPUs; src/gpu/composite.rs).
            if crate::gpu::shaders::STORAGE_OUTPUT_FORMATS
                .iter()
                .any(|(f, _)| *f == format)
            {
                usage |= U::STORAGE_BINDING;
            }
            let device = inner.device.clone();
            let texture = gpu_scope(&device, || {
                texture_2d(
                    &device,
                    "nimbus host texture",
                    (desc.width, desc.height),
                    format,
                    usage,
                )
            })?;
            let tex = NimbusTexture {
                view: texture.create_view(&Default::default()),
                texture,
                device,
                queue: inner.queue.clone(),
                bytes_per_pixel,
                format: desc.format,
                context_id: inner.id,
                context: Arc::downgrade(&inner.alive),
            };
            *out = Box::into_raw(Box::new(tex));
            Ok(NIMBUS_OK)
        })
    }
}

/// Replaces the whole texture's contents with `size` bytes: rows from the top, tightly packed
/// (width × bytes per pixel each), channels in format order (floats little-endian).
///
/// Safety: `tex` must be NULL or a live texture; `data` must be NULL or point to `size` readable bytes.
#[no_mangle]
pub unsafe extern "C" fn nimbus_texture_write(
    tex: *mut NimbusTexture,
    data: *const c_void,
    size: usize,
) -> NimbusResult {
    boundary(
        || {
            // SAFETY: `tex` is NULL or live per the caller's contract.
            let tex = unsafe { checked(tex, data.is_null(), size) }?;
            // SAFETY: `data` points to `size` readable bytes per the caller's contract.
            let bytes = unsafe { std::slice::from_raw_parts(data.cast::<u8>(), size) };
            let (w, h) = (tex.texture.width(), tex.texture.height());
            tex.queue.write_texture(
                tex.texture.as_image_copy(),
                bytes,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(w * tex.bytes_per_pixel),
                    rows_per_image: Some(h),
                },
                wgpu::Extent3d {
                    width: w,
                    height: h,
                    depth_or_array_layers: 1,
                },
            );
            Ok(NIMBUS_OK)
        },
        |_, _| {},
    )
}

/// Waits for the GPU and copies the texture into `data` (`size` bytes, layout as for
/// `nimbus_texture_write`).
///
/// Safety: `tex` must be NULL or a live texture; `data` must be NULL or point to `size` writable bytes.
#[no_mangle]
pub unsafe extern "C" fn nimbus_texture_read(
    tex: *const NimbusTexture,
    data: *mut c_void,
    size: usize,
) -> NimbusResult {
    boundary(
        || {
            // SAFETY: `tex` is NULL or live per the caller's contract.
            let tex = unsafe { checked(tex, data.is_null(), size) }?;
            let bytes = read_texture(&tex.device, &tex.queue, &tex.texture, 0)?;
            // SAFETY: `data` has room for `size` == bytes.len() bytes per the caller's contract.
            unsafe { std::ptr::copy_nonoverlapping(bytes.as_ptr(), data.cast::<u8>(), size) };
            Ok(NIMBUS_OK)
        },
        |_, _| {},
    )
}

/// Writes the number of bytes the texture holds (width × height × bytes per pixel) to `*out`.
///
/// Safety: `tex` must be NULL or a live texture; `out` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nimbus_texture_byte_size(
    tex: *const NimbusTexture,
    out: *mut usize,
) -> NimbusResult {
    boundary(
        || {
            // SAFETY: checked for NULL; the caller guarantees validity.
            let tex = unsafe { tex.as_ref() }.ok_or_else(|| FfiError::null("tex"))?;
            tex.check_alive()?;
            if out.is_null() {
                return Err(FfiError::null("out"));
            }
            // SAFETY: non-null and writable per the caller's contract.
            unsafe { *out = tex.byte_size() };
            Ok(NIMBUS_OK)
        },
        |_, _| {},
    )
}

/// Frees a texture. NULL is a no-op. The texture must not be in use by a running call.
///
/// Safety: `tex` must be NULL or a texture from `nimbus_texture_create`, not yet destroyed.
#[no_mangle]
pub unsafe extern "C" fn nimbus_texture_destroy(tex: *mut NimbusTexture) {
    if !tex.is_null() {
        boundary(
            || {
                // SAFETY: created by Box::into_raw in nimbus_texture_create, destroyed once.
                drop(unsafe { Box::from_raw(tex) });
                Ok(NIMBUS_OK)
            },
            |_, _| {},
        );
    }
}
