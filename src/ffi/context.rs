//! The context: a device of Nimbus's own (headless or presenting to a window) and a renderer.

use std::ffi::{c_char, CString};
use std::num::NonZeroIsize;
use std::ptr::NonNull;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use glam::{Mat4, Vec3};
use raw_window_handle as rwh;

use super::*;
use crate::headless::{
    collect_uncaptured_errors, create_owned_device, take_errors, MAX_HEADLESS_SIZE,
};
use crate::renderer::{ColorTargets, Targets};
use crate::settings::Quality;
use crate::weather::{Preset, Weather};
use crate::{Camera, DepthConvention, FrameInputs, Renderer, Settings, Sun};

/// An opaque Nimbus context (see `nimbus_context_create`).
pub struct NimbusContext {
    inner: ContextInner,
    poisoned: bool,
    last_error: CString,
}

struct Presenter {
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
}

/// Context ids: textures remember theirs, so a texture is never used with another context.
static NEXT_CONTEXT_ID: AtomicU64 = AtomicU64::new(1);

pub(crate) struct ContextInner {
    /// Unique in the process.
    pub(crate) id: u64,
    /// Textures hold a `Weak` of this: once it is gone, so is their context.
    pub(crate) alive: Arc<()>,
    pub(crate) device: wgpu::Device,
    pub(crate) queue: wgpu::Queue,
    renderer: Renderer,
    errors: Arc<Mutex<Vec<String>>>,
    presenter: Option<Presenter>,
    adapter_name: CString,
}

/// Runs `f` on a live, unpoisoned context inside the panic boundary, keeping the context's
/// last error. A panic poisons the context.
///
/// # Safety
/// `ctx` must be NULL or a live context.
pub(crate) unsafe fn with_ctx(
    ctx: *mut NimbusContext,
    f: impl FnOnce(&mut ContextInner) -> FfiResult<i32>,
) -> i32 {
    // SAFETY: NULL is checked; otherwise the caller guarantees a live context.
    let Some(c) = (unsafe { ctx.as_mut() }) else {
        set_thread_error("`ctx` is NULL");
        return NIMBUS_ERROR_NULL_POINTER;
    };
    if c.poisoned {
        let msg = "the context was poisoned by an earlier panic; destroy it and create another";
        set_thread_error(msg);
        c.last_error = CString::new(msg).unwrap_or_default();
        return NIMBUS_ERROR_POISONED;
    }
    let inner = &mut c.inner;
    let mut failure: Option<(String, bool)> = None;
    let code = boundary(
        || f(inner),
        |m, panicked| failure = Some((m.to_string(), panicked)),
    );
    match failure {
        Some((message, panicked)) => {
            c.last_error = CString::new(message.replace('\0', " ")).unwrap_or_default();
            c.poisoned |= panicked;
        }
        None => c.last_error = CString::default(),
    }
    code
}

/// Walks an extension chain; every `s_type` must be in `allowed`.
pub(crate) fn check_chain(mut next: *const NimbusChainedStruct, allowed: &[u32]) -> FfiResult {
    let mut n = 0;
    while !next.is_null() {
        // SAFETY: chain links are valid by the caller's contract; NULL ends the chain.
        let link = unsafe { &*next };
        if !allowed.contains(&link.s_type) {
            return Err(FfiError::new(
                NIMBUS_ERROR_UNKNOWN_STRUCT,
                format!("unknown chained struct type {} here", link.s_type),
            ));
        }
        n += 1;
        if n > 64 {
            return Err(FfiError::arg("extension chain longer than 64 (a cycle?)"));
        }
        next = link.next;
    }
    Ok(())
}

fn preset(id: u32) -> FfiResult<Weather> {
    Preset::from_id(id)
        .map(Preset::weather)
        .ok_or_else(|| FfiError::arg(format!("unknown preset id {id} (valid: 1..=5)")))
}

fn quality(id: u32) -> FfiResult<Quality> {
    match id {
        NIMBUS_QUALITY_LOW => Ok(Quality::Low),
        NIMBUS_QUALITY_MEDIUM => Ok(Quality::Medium),
        NIMBUS_QUALITY_HIGH => Ok(Quality::High),
        NIMBUS_QUALITY_ULTRA => Ok(Quality::Ultra),
        q => Err(FfiError::arg(format!(
            "unknown quality level {q} (valid: 0 = default, 1..=4 = low..ultra)"
        ))),
    }
}

fn settings_from_chain(mut next: *const NimbusChainedStruct) -> FfiResult<Settings> {
    check_chain(next, &[NIMBUS_STYPE_SETTINGS])?;
    let mut s = Settings::default();
    while !next.is_null() {
        // SAFETY: validated chain; NIMBUS_STYPE_SETTINGS links are NimbusSettingsExt.
        let link = unsafe { &*next };
        if link.s_type == NIMBUS_STYPE_SETTINGS {
            // SAFETY: the header says a NimbusSettingsExt starts with its chain header.
            let ext = unsafe { &*next.cast::<NimbusSettingsExt>() };
            if ext.initial_preset != 0 {
                s.weather = preset(ext.initial_preset)?;
            }
            // The level first: the explicit fields below refine it.
            match ext.quality {
                NIMBUS_QUALITY_DEFAULT => {}
                q => quality(q)?.apply(&mut s),
            }
            if ext.noise_seed != 0 {
                s.noise.seed = ext.noise_seed;
            }
            if ext.march_max_steps != 0 {
                s.march.max_steps = ext.march_max_steps;
            }
            if ext.march_min_steps != 0 {
                s.march.min_steps = ext.march_min_steps;
            }
            s.march.jitter = match ext.jitter {
                NIMBUS_JITTER_DEFAULT | NIMBUS_JITTER_ON => true,
                NIMBUS_JITTER_OFF => false,
                j => return Err(FfiError::arg(format!("unknown jitter value {j}"))),
            };
            if ext.max_distance != 0.0 {
                s.march.max_distance = ext.max_distance;
            }
            if ext.planet_radius != 0.0 {
                s.planet.radius = ext.planet_radius;
            }
        }
        next = link.next;
    }
    Ok(s)
}

fn window_target(w: &NimbusWindowHandle) -> FfiResult<wgpu::SurfaceTargetUnsafe> {
    let need = |p: *mut std::ffi::c_void, name: &str| {
        NonNull::new(p).ok_or_else(|| FfiError::null(&format!("window.{name}")))
    };
    let (display, window) = match w.platform {
        NIMBUS_PLATFORM_X11 => {
            let display = need(w.display, "display")?;
            if w.window == 0 {
                return Err(FfiError::arg("window.window (the X11 Window) is 0"));
            }
            (
                Some(rwh::XlibDisplayHandle::new(Some(display), 0).into()),
                rwh::XlibWindowHandle::new(w.window as _).into(),
            )
        }
        NIMBUS_PLATFORM_WAYLAND => (
            Some(rwh::WaylandDisplayHandle::new(need(w.display, "display")?).into()),
            rwh::WaylandWindowHandle::new(need(w.surface, "surface")?).into(),
        ),
        NIMBUS_PLATFORM_WIN32 => {
            let hwnd = NonZeroIsize::new(w.window as isize)
                .ok_or_else(|| FfiError::arg("window.window (the HWND) is 0"))?;
            let mut h = rwh::Win32WindowHandle::new(hwnd);
            h.hinstance = NonZeroIsize::new(w.display as isize);
            (Some(rwh::WindowsDisplayHandle::new().into()), h.into())
        }
        NIMBUS_PLATFORM_APPKIT => (
            Some(rwh::AppKitDisplayHandle::new().into()),
            rwh::AppKitWindowHandle::new(need(w.surface, "surface")?).into(),
        ),
        p => return Err(FfiError::arg(format!("unknown window platform {p}"))),
    };
    Ok(wgpu::SurfaceTargetUnsafe::RawHandle {
        raw_display_handle: display,
        raw_window_handle: window,
    })
}

fn check_size(width: u32, height: u32) -> FfiResult {
    for (name, v) in [("width", width), ("height", height)] {
        if v == 0 || v > MAX_HEADLESS_SIZE {
            return Err(FfiError::arg(format!(
                "{name} must be in 1..={MAX_HEADLESS_SIZE}, got {v}"
            )));
        }
    }
    Ok(())
}

impl ContextInner {
    fn create(desc: &NimbusContextDesc) -> FfiResult<Self> {
        let major = desc.abi_version >> 16;
        let minor = desc.abi_version & 0xffff;
        if major != NIMBUS_VERSION_MAJOR || minor > NIMBUS_VERSION_MINOR {
            return Err(FfiError::new(
                NIMBUS_ERROR_ABI_VERSION,
                format!(
                    "the header is ABI {major}.{minor} but the library is {NIMBUS_VERSION_MAJOR}.{NIMBUS_VERSION_MINOR}: \
                     rebuild against this library's nimbus.h"
                ),
            ));
        }
        let settings = settings_from_chain(desc.next)?;
        // SAFETY: checked for NULL; the caller guarantees validity otherwise.
        let window = unsafe { desc.window.as_ref() };
        let target = match window {
            Some(w) => {
                check_size(desc.width, desc.height)?;
                Some(window_target(w)?)
            }
            None => None,
        };
        // SAFETY: the header requires the window handles to outlive the context.
        let owned = unsafe { create_owned_device(target) }?;
        let errors = collect_uncaptured_errors(&owned.device);
        let presenter = match owned.surface {
            Some(surface) => {
                let caps = surface.get_capabilities(&owned.adapter);
                let format = caps
                    .formats
                    .iter()
                    .copied()
                    .find(|f| f.is_srgb() && crate::renderer::OUTPUT_FORMATS.contains(f))
                    .or_else(|| {
                        caps.formats
                            .iter()
                            .copied()
                            .find(|f| crate::renderer::OUTPUT_FORMATS.contains(f))
                    })
                    .ok_or_else(|| {
                        FfiError::new(
                            NIMBUS_ERROR_SURFACE,
                            format!("no supported surface format in {:?}", caps.formats),
                        )
                    })?;
                let mut config = surface
                    .get_default_config(&owned.adapter, desc.width, desc.height)
                    .ok_or_else(|| {
                        FfiError::new(
                            NIMBUS_ERROR_SURFACE,
                            "the adapter cannot present to this window",
                        )
                    })?;
                config.format = format;
                config.present_mode = wgpu::PresentMode::Fifo;
                config.view_formats = vec![];
                crate::renderer::gpu_scope(&owned.device, || {
                    surface.configure(&owned.device, &config)
                })?;
                Some(Presenter { surface, config })
            }
            None => None,
        };
        let renderer = Renderer::new(&owned.device, &owned.queue, settings)?;
        Ok(Self {
            id: NEXT_CONTEXT_ID.fetch_add(1, Ordering::Relaxed),
            alive: Arc::new(()),
            adapter_name: CString::new(
                format!("{} ({:?})", owned.info.name, owned.info.backend).replace('\0', " "),
            )
            .unwrap_or_default(),
            device: owned.device,
            queue: owned.queue,
            renderer,
            errors,
            presenter,
        })
    }

    fn render(&mut self, frame: &NimbusFrame, targets: &NimbusTargets) -> FfiResult<i32> {
        check_chain(frame.next, &[])?;
        check_chain(targets.next, &[])?;
        let known = NIMBUS_DEPTH_REVERSED_Z | NIMBUS_DEPTH_INFINITE_FAR;
        if frame.depth_flags & !known != 0 {
            return Err(FfiError::arg(format!(
                "unknown depth flags {:#x}",
                frame.depth_flags & !known
            )));
        }
        let color = Vec3::from_array(frame.sun_color);
        let inputs = FrameInputs {
            camera: Camera {
                view: Mat4::from_cols_array(&frame.view),
                projection: Mat4::from_cols_array(&frame.projection),
                depth: DepthConvention {
                    reversed_z: frame.depth_flags & NIMBUS_DEPTH_REVERSED_Z != 0,
                    infinite_far: frame.depth_flags & NIMBUS_DEPTH_INFINITE_FAR != 0,
                },
            },
            sun: Sun {
                direction: Vec3::from_array(frame.sun_direction),
                color: if color == Vec3::ZERO {
                    Vec3::ONE
                } else {
                    color
                },
                illuminance: frame.sun_illuminance,
            },
            time: frame.time,
        };
        // SAFETY: texture pointers are NULL or live textures per the caller's contract.
        let scene = unsafe { targets.scene_color.as_ref() }
            .ok_or_else(|| FfiError::null("targets.scene_color"))?;
        // SAFETY: as above.
        let depth = unsafe { targets.scene_depth.as_ref() };
        // SAFETY: as above.
        let output = unsafe { targets.output.as_ref() };
        let named = [
            ("targets.scene_color", Some(scene)),
            ("targets.scene_depth", depth),
            ("targets.output", output),
        ];
        for (name, tex) in named {
            if let Some(tex) = tex {
                tex.check_owner(self.id, name)?;
            }
        }
        self.renderer.prepare(&inputs)?;
        let mut encoder = self.device.create_command_encoder(&Default::default());
        let depth_view = depth.map(|d| &d.view);
        let status = match output {
            Some(out) => {
                let color = if std::ptr::eq(out, scene) {
                    ColorTargets::InPlace(&scene.view)
                } else {
                    ColorTargets::Separate {
                        scene: &scene.view,
                        output: &out.view,
                    }
                };
                self.renderer.encode(
                    &mut encoder,
                    &Targets {
                        color,
                        depth: depth_view,
                    },
                )?;
                self.queue.submit([encoder.finish()]);
                NIMBUS_OK
            }
            None => {
                let p = self.presenter.as_ref().ok_or_else(|| {
                    FfiError::new(
                        NIMBUS_ERROR_INVALID_TARGET,
                        "targets.output is NULL but the context has no window",
                    )
                })?;
                let frame = match p.surface.get_current_texture() {
                    wgpu::CurrentSurfaceTexture::Success(t)
                    | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
                    wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                        p.surface.configure(&self.device, &p.config);
                        return Ok(NIMBUS_STATUS_FRAME_SKIPPED);
                    }
                    wgpu::CurrentSurfaceTexture::Validation => {
                        return Err(FfiError::new(
                            NIMBUS_ERROR_SURFACE,
                            "surface validation error",
                        ));
                    }
                    _ => return Ok(NIMBUS_STATUS_FRAME_SKIPPED),
                };
                let view = frame.texture.create_view(&Default::default());
                self.renderer.encode(
                    &mut encoder,
                    &Targets {
                        color: ColorTargets::Separate {
                            scene: &scene.view,
                            output: &view,
                        },
                        depth: depth_view,
                    },
                )?;
                self.queue.submit([encoder.finish()]);
                self.queue.present(frame);
                NIMBUS_OK
            }
        };
        take_errors(&self.errors)?;
        Ok(status)
    }
}

/// Creates a context: its own GPU device (any adapter; Mesa's software Vulkan works), a
/// renderer, and, when `desc->window` is set, a surface presenting to that window. Blocks while
/// the noise volumes are baked. On success writes the handle to `*out`; on failure `*out` is
/// untouched and `nimbus_context_last_error(NULL)` says why.
///
/// # Safety
/// `desc` and `out` must be NULL or valid; the chain and window handles must be valid.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_create(
    desc: *const NimbusContextDesc,
    out: *mut *mut NimbusContext,
) -> i32 {
    boundary(
        || {
            // SAFETY: checked for NULL; the caller guarantees validity otherwise.
            let desc = unsafe { desc.as_ref() }.ok_or_else(|| FfiError::null("desc"))?;
            if out.is_null() {
                return Err(FfiError::null("out"));
            }
            let inner = ContextInner::create(desc)?;
            let ctx = Box::new(NimbusContext {
                inner,
                poisoned: false,
                last_error: CString::default(),
            });
            // SAFETY: `out` is non-null and writable per the caller's contract.
            unsafe { *out = Box::into_raw(ctx) };
            Ok(NIMBUS_OK)
        },
        |_, _| {},
    )
}

/// Destroys a context (waiting for its GPU work). NULL is a no-op.
///
/// # Safety
/// `ctx` must be NULL or a context from `nimbus_context_create`, not yet destroyed.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_destroy(ctx: *mut NimbusContext) {
    if !ctx.is_null() {
        let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            // SAFETY: created by Box::into_raw in nimbus_context_create, destroyed once.
            let ctx = unsafe { Box::from_raw(ctx) };
            let _ = ctx.inner.device.poll(wgpu::PollType::wait_indefinitely());
            drop(ctx);
        }));
    }
}

/// The message of the last failed call on `ctx`, or with NULL the last failed call on this
/// thread (e.g. a failed `nimbus_context_create`). Empty after a success. Valid until the next
/// call with the same context (or on this thread); never free it.
///
/// # Safety
/// `ctx` must be NULL or a live context.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_last_error(ctx: *const NimbusContext) -> *const c_char {
    // SAFETY: NULL is checked; otherwise the caller guarantees a live context.
    match unsafe { ctx.as_ref() } {
        Some(c) => c.last_error.as_ptr(),
        None => thread_error_ptr(),
    }
}

/// The GPU adapter in use, e.g. "llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan)". NULL for a NULL
/// context. Valid while the context lives.
///
/// # Safety
/// `ctx` must be NULL or a live context.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_adapter_name(ctx: *const NimbusContext) -> *const c_char {
    // SAFETY: NULL is checked; otherwise the caller guarantees a live context.
    match unsafe { ctx.as_ref() } {
        Some(c) => c.inner.adapter_name.as_ptr(),
        None => std::ptr::null(),
    }
}

/// Renders one frame: the clouds over `targets->scene_color` (clipped by `scene_depth`),
/// composited into `targets->output` or presented to the window when `output` is NULL. Returns
/// `NIMBUS_STATUS_FRAME_SKIPPED` when the window could not take a frame (render again).
///
/// # Safety
/// `ctx`, `frame`, `targets` and the textures they point to must be NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_render(
    ctx: *mut NimbusContext,
    frame: *const NimbusFrame,
    targets: *const NimbusTargets,
) -> i32 {
    // SAFETY: checked below; the caller guarantees validity.
    unsafe {
        with_ctx(ctx, |inner| {
            let frame = frame.as_ref().ok_or_else(|| FfiError::null("frame"))?;
            let targets = targets.as_ref().ok_or_else(|| FfiError::null("targets"))?;
            inner.render(frame, targets)
        })
    }
}

/// Resizes the window surface (windowed contexts; for headless ones the size only is checked).
/// On failure the previous size stays in use.
///
/// # Safety
/// `ctx` must be NULL or a live context.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_resize(
    ctx: *mut NimbusContext,
    width: u32,
    height: u32,
) -> i32 {
    // SAFETY: the caller guarantees a live context or NULL.
    unsafe {
        with_ctx(ctx, |inner| {
            check_size(width, height)?;
            if let Some(p) = inner.presenter.as_mut() {
                let mut config = p.config.clone();
                config.width = width;
                config.height = height;
                let (surface, device) = (&p.surface, &inner.device);
                crate::renderer::gpu_scope(device, || surface.configure(device, &config))?;
                p.config = config;
            }
            Ok(NIMBUS_OK)
        })
    }
}

fn weather_with(mut w: Weather, options: u32) -> FfiResult<Weather> {
    let known = NIMBUS_WEATHER_CIRRUS | NIMBUS_WEATHER_HORIZON_GRADIENT;
    if options & !known != 0 {
        return Err(FfiError::arg(format!(
            "unknown weather option flags {:#x}",
            options & !known
        )));
    }
    if options & NIMBUS_WEATHER_CIRRUS != 0 {
        w = w.with_high_layer(Weather::cirrus());
    }
    if options & NIMBUS_WEATHER_HORIZON_GRADIENT != 0 {
        w = w.with_horizon_gradient();
    }
    Ok(w)
}

/// Starts a transition to a built-in preset (`NIMBUS_PRESET_*`, with `NIMBUS_WEATHER_*`
/// option flags) at host time `start` seconds, lasting `duration` seconds (0 = at once). A
/// transition already running is frozen where it is and continued from, so the sky never
/// jumps. Requests must come in time order.
///
/// # Safety
/// `ctx` must be NULL or a live context.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_set_weather(
    ctx: *mut NimbusContext,
    preset_id: u32,
    options: u32,
    start: f64,
    duration: f64,
) -> i32 {
    // SAFETY: the caller guarantees a live context or NULL.
    unsafe {
        with_ctx(ctx, |inner| {
            let w = weather_with(preset(preset_id)?, options)?;
            inner.renderer.set_weather(w, start, duration)?;
            Ok(NIMBUS_OK)
        })
    }
}

/// Like `nimbus_context_set_weather`, with the weather read from a TOML preset file. A missing
/// or malformed file returns `NIMBUS_ERROR_PRESET_FILE`; the message names the line and field.
///
/// # Safety
/// `ctx` must be NULL or a live context; `path` NULL or a NUL-terminated UTF-8 path.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_load_weather(
    ctx: *mut NimbusContext,
    path: *const c_char,
    start: f64,
    duration: f64,
) -> i32 {
    // SAFETY: the caller guarantees a live context or NULL, and a valid string or NULL.
    unsafe {
        with_ctx(ctx, |inner| {
            let path = c_str(path, "path")?;
            let w = Weather::load(std::path::Path::new(path))?;
            inner.renderer.set_weather(w, start, duration)?;
            Ok(NIMBUS_OK)
        })
    }
}

/// Drops the accumulated cloud history, so the next frame starts afresh. Call it on camera
/// cuts (a teleport, a switch to another camera); ordinary and fast motion need no call.
///
/// # Safety
/// `ctx` must be NULL or a live context.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_reset_history(ctx: *mut NimbusContext) -> i32 {
    // SAFETY: the caller guarantees a live context or NULL.
    unsafe {
        with_ctx(ctx, |inner| {
            inner.renderer.reset_history();
            Ok(NIMBUS_OK)
        })
    }
}

/// Deliberately panics inside the boundary: lets hosts check that a panic comes back as
/// `NIMBUS_ERROR_PANIC` and poisons the context. Never call it in production.
///
/// # Safety
/// `ctx` must be NULL or a live context.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_debug_panic(ctx: *mut NimbusContext) -> i32 {
    // SAFETY: the caller guarantees a live context or NULL.
    unsafe { with_ctx(ctx, |_| panic!("nimbus_context_debug_panic was called")) }
}
