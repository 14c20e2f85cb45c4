//! The context: a device of Nimbus's own (headless or presenting to a window) or the host's
//! Vulkan device, and a renderer.

use std::ffi::{c_char, CString};
use std::num::NonZeroIsize;
use std::ptr::NonNull;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use glam::{Mat4, Vec3};
use raw_window_handle as rwh;

use super::texture::{format_name, is_color};
use super::*;
use crate::device::{create_owned_device, gpu_scope, DeviceErrors};
use crate::headless::MAX_HEADLESS_SIZE;
use crate::renderer::{ColorTargets, Targets};
use crate::settings::Quality;
use crate::weather::{Preset, Weather};
use crate::{Camera, DepthConvention, FrameInputs, NoiseStart, Renderer, Settings, Sun};

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
    errors: DeviceErrors,
    presenter: Option<Presenter>,
    /// The host's Vulkan device and the wrappers of its images, for a context created with
    /// `NimbusVulkanDeviceExt`.
    vulkan: Option<super::vulkan::VulkanHost>,
    adapter_name: CString,
    /// The minor ABI version of the header the context was made with (what it may be told).
    abi_minor: u32,
}

/// Runs `f` on a live, unpoisoned context inside the panic boundary, keeping the context's
/// last error. A panic poisons the context.
///
/// Safety: `ctx` must be NULL or a live context.
pub(crate) unsafe fn with_ctx(
    ctx: *mut NimbusContext,
    f: impl FnOnce(&mut ContextInner) -> FfiResult<NimbusResult>,
) -> NimbusResult {
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
    if let Err(e) = c.inner.errors.check_lost() {
        let e = FfiError::from(e);
        set_thread_error(&e.message);
        c.last_error = CString::new(e.message.replace('\0', " ")).unwrap_or_default();
        return e.code;
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

/// The links of a validated chain, as (s_type, pointer to the link).
fn links(mut next: *const NimbusChainedStruct) -> Vec<(u32, *const NimbusChainedStruct)> {
    let mut v = Vec::new();
    while !next.is_null() {
        // SAFETY: the chain was validated by check_chain; NULL ends it.
        let link = unsafe { &*next };
        v.push((link.s_type, next));
        next = link.next;
    }
    v
}

/// Where ABI 0.1's `NimbusSettingsExt` carried `quality`: in what is now its tail padding. A
/// 0.1 header declared the field there, so for 0.1 hosts it is read from there (the bytes
/// exist either way: the struct is 48 bytes in both layouts).
const V0_1_QUALITY_OFFSET: usize = 44;

/// The settings a creation chain asks for. `abi_minor` is the header's minor version.
fn settings_from_chain(next: *const NimbusChainedStruct, abi_minor: u32) -> FfiResult<Settings> {
    let kinds = [
        NIMBUS_STYPE_SETTINGS,
        NIMBUS_STYPE_QUALITY,
        NIMBUS_STYPE_VULKAN_DEVICE,
        NIMBUS_STYPE_CLOUD_SHADOWS,
        NIMBUS_STYPE_NOISE_CACHE,
    ];
    check_chain(next, &kinds)?;
    let links = links(next);
    for kind in kinds {
        if links.iter().filter(|(t, _)| *t == kind).count() > 1 {
            return Err(FfiError::new(
                NIMBUS_ERROR_UNKNOWN_STRUCT,
                format!("the chain holds s_type {kind} twice; give each extension once"),
            ));
        }
    }
    let find = |kind| links.iter().find(|(t, _)| *t == kind).map(|(_, p)| *p);
    let mut s = Settings::default();
    // The level first: the explicit march fields of the settings extension refine it.
    let mut level = NIMBUS_QUALITY_DEFAULT;
    if let Some(p) = find(NIMBUS_STYPE_QUALITY) {
        // SAFETY: a NIMBUS_STYPE_QUALITY link is a NimbusQualityExt per the header.
        level = unsafe { &*p.cast::<NimbusQualityExt>() }.quality;
    } else if let (Some(p), 1) = (find(NIMBUS_STYPE_SETTINGS), abi_minor) {
        // SAFETY: a NimbusSettingsExt is 48 bytes; offset 44 lies inside it.
        level = unsafe {
            p.cast::<u8>()
                .add(V0_1_QUALITY_OFFSET)
                .cast::<u32>()
                .read_unaligned()
        };
    }
    if level != NIMBUS_QUALITY_DEFAULT {
        quality(level)?.apply(&mut s);
    }
    if let Some(p) = find(NIMBUS_STYPE_SETTINGS) {
        // SAFETY: a NIMBUS_STYPE_SETTINGS link is a NimbusSettingsExt per the header.
        let ext = unsafe { &*p.cast::<NimbusSettingsExt>() };
        if ext.initial_preset != 0 {
            s.weather = preset(ext.initial_preset)?;
        }
        if ext.noise_seed != 0 {
            s.noise.seed = ext.noise_seed;
        }
        if ext.march_max_steps != 0 {
            s.march.max_steps = ext.march_max_steps;
            // A defaulted minimum follows a smaller maximum instead of exceeding it.
            s.march.min_steps = s.march.min_steps.min(ext.march_max_steps);
        }
        if ext.march_min_steps != 0 {
            s.march.min_steps = ext.march_min_steps;
        }
        s.march.jitter = match ext.jitter {
            NIMBUS_JITTER_DEFAULT | NIMBUS_JITTER_ON => true,
            NIMBUS_JITTER_OFF => false,
            j => {
                return Err(FfiError::arg(format!(
                    "unknown jitter value {j} (valid: 0 = default, 1 = on, 2 = off)"
                )))
            }
        };
        if ext.max_distance != 0.0 {
            s.march.max_distance = ext.max_distance;
        }
        if ext.planet_radius != 0.0 {
            s.planet.radius = ext.planet_radius;
        }
    }
    if let Some(p) = find(NIMBUS_STYPE_CLOUD_SHADOWS) {
        // SAFETY: a NIMBUS_STYPE_CLOUD_SHADOWS link is a NimbusCloudShadowsExt per the header.
        s.shadows = unsafe { super::shadows::shadows_from_ext(p) }?;
    }
    Ok(s)
}

/// The ABI rule: the same major version, and a minor from the first this library serves
/// (NIMBUS_ABI_MIN_MINOR) up to its own. 0 is what a forgotten field holds: never valid.
/// Returns the header's minor version.
pub(crate) fn check_abi_version(abi_version: u32) -> FfiResult<u32> {
    let (major, minor) = (abi_version >> 16, abi_version & 0xffff);
    let ours = format!("{NIMBUS_VERSION_MAJOR}.{NIMBUS_VERSION_MINOR}");
    if abi_version == 0 {
        return Err(FfiError::new(
            NIMBUS_ERROR_ABI_VERSION,
            format!("abi_version is 0: set NimbusContextDesc.abi_version = NIMBUS_ABI_VERSION (this library is ABI {ours})"),
        ));
    }
    if major != NIMBUS_VERSION_MAJOR
        || !(NIMBUS_ABI_MIN_MINOR..=NIMBUS_VERSION_MINOR).contains(&minor)
    {
        return Err(FfiError::new(
            NIMBUS_ERROR_ABI_VERSION,
            format!(
                "the header is ABI {major}.{minor} but this library serves ABI \
                 {NIMBUS_VERSION_MAJOR}.{NIMBUS_ABI_MIN_MINOR} to {ours}: build against this library's nimbus.h"
            ),
        ));
    }
    Ok(minor)
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

/// Everything a context creation decodes from its descriptor before touching a device: the
/// ABI version, the settings chain (validated) and the window handle.
fn decode_desc(desc: &NimbusContextDesc) -> FfiResult<DecodedDesc> {
    let minor = check_abi_version(desc.abi_version)?;
    let settings = settings_from_chain(desc.next, minor)?;
    settings.validate()?;
    let noise = match links(desc.next)
        .into_iter()
        .find(|(t, _)| *t == NIMBUS_STYPE_NOISE_CACHE)
    {
        Some(_) if minor < 6 => {
            return Err(FfiError::new(
                NIMBUS_ERROR_UNKNOWN_STRUCT,
                "NimbusNoiseCacheExt needs a header of ABI 0.6 or newer",
            ))
        }
        // SAFETY: the chain link is a NimbusNoiseCacheExt (its s_type) per the caller.
        Some((_, p)) => Some(unsafe { super::noise_cache::cache_from_ext(p) }?),
        None => None,
    };
    if let Some(n) = &noise {
        // SAFETY: the header requires the cache's bytes to be readable during the creation.
        unsafe { n.check(&settings) }?;
    }
    // SAFETY: checked for NULL; the caller guarantees validity otherwise.
    let window = unsafe { desc.window.as_ref() };
    let vulkan = links(desc.next)
        .into_iter()
        .find(|(t, _)| *t == NIMBUS_STYPE_VULKAN_DEVICE)
        .map(|(_, p)| p as *const NimbusVulkanDeviceExt);
    if let Some(ext) = vulkan {
        if window.is_some() {
            return Err(FfiError::arg(
                "desc.window must be NULL with NimbusVulkanDeviceExt: a context on the host's \
                 device composites into the host's images and does not present",
            ));
        }
        if minor < 3 {
            return Err(FfiError::new(
                NIMBUS_ERROR_UNKNOWN_STRUCT,
                "NimbusVulkanDeviceExt needs a header of ABI 0.3 or newer",
            ));
        }
        // SAFETY: the chain link is a NimbusVulkanDeviceExt (its s_type) per the caller.
        let host = unsafe { super::vulkan::host_device(&*ext) }?;
        return Ok(DecodedDesc {
            abi_minor: minor,
            settings,
            target: None,
            host: Some(host),
            noise,
        });
    }
    let target = match window {
        Some(w) => {
            check_size(desc.width, desc.height)?;
            Some(window_target(w)?)
        }
        None => None,
    };
    Ok(DecodedDesc {
        abi_minor: minor,
        settings,
        target,
        host: None,
        noise,
    })
}

/// What a creation descriptor asks for: settings, a window or the host's Vulkan device, and
/// where the noise volumes come from.
struct DecodedDesc {
    /// The header's minor ABI version.
    abi_minor: u32,
    settings: Settings,
    target: Option<wgpu::SurfaceTargetUnsafe>,
    host: Option<crate::vulkan::HostDevice>,
    noise: Option<super::noise_cache::NoiseCacheArg>,
}

/// A C frame as Rust frame inputs, checked as `Renderer::prepare` checks them.
pub(crate) fn decode_frame(frame: &NimbusFrame) -> FfiResult<FrameInputs> {
    check_chain(frame.next, super::view::FRAME_CHAIN)?;
    let known = NIMBUS_DEPTH_REVERSED_Z | NIMBUS_DEPTH_INFINITE_FAR | NIMBUS_DEPTH_GL_CLIP_Z;
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
                gl_clip_z: frame.depth_flags & NIMBUS_DEPTH_GL_CLIP_Z != 0,
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
    inputs.check()?;
    Ok(inputs)
}

/// Entry points for the fuzz targets (tests/fuzz), built only with `--cfg fuzzing`: the C
/// argument decoding of context creation and frames, inside the panic boundary, with no device.
#[cfg(fuzzing)]
#[doc(hidden)]
pub mod fuzzing {
    use super::*;

    /// Decodes a context descriptor as `nimbus_context_create` does, up to the device.
    ///
    /// Safety: as for `nimbus_context_create` (valid chain and window pointers).
    pub unsafe fn decode_desc(desc: &NimbusContextDesc) -> NimbusResult {
        boundary(|| super::decode_desc(desc).map(|_| NIMBUS_OK), |_, _| {})
    }

    /// Decodes and checks a frame as `nimbus_context_render` does.
    pub fn decode_frame(frame: &NimbusFrame) -> NimbusResult {
        boundary(
            || {
                super::decode_frame(frame)?;
                super::super::view::view_of(frame.next).map(|_| NIMBUS_OK)
            },
            |_, _| {},
        )
    }
}

impl ContextInner {
    fn create(desc: &NimbusContextDesc) -> FfiResult<Self> {
        let DecodedDesc {
            abi_minor,
            settings,
            target,
            host,
            noise,
        } = decode_desc(desc)?;
        let (device, queue, info, presenter, vulkan) = match host {
            Some(host) => {
                // SAFETY: the header requires the host's handles to be live, consistent and to
                // outlive the context.
                let (adopted, frame) = unsafe { super::vulkan::adopt(&host) }?;
                let info = adopted.adapter.get_info();
                let (device, queue) = (adopted.device.clone(), adopted.queue.clone());
                let host = super::vulkan::VulkanHost {
                    frame,
                    _adopted: adopted,
                };
                (device, queue, info, None, Some(host))
            }
            None => {
                // SAFETY: the header requires the window handles to outlive the context.
                let mut owned = unsafe { create_owned_device(target) }?;
                let presenter = match owned.surface.take() {
                    Some(surface) => Some(presenter(&owned, surface, desc)?),
                    None => None,
                };
                (owned.device, owned.queue, owned.info, presenter, None)
            }
        };
        let errors = DeviceErrors::install(&device);
        // SAFETY: the header requires the cache's bytes to be readable during this call.
        let start = noise
            .as_ref()
            .map_or(NoiseStart::Bake, |n| unsafe { n.start() });
        let renderer = Renderer::with_noise(&device, &queue, settings, start)?;
        Ok(Self {
            id: NEXT_CONTEXT_ID.fetch_add(1, Ordering::Relaxed),
            alive: Arc::new(()),
            adapter_name: CString::new(
                format!("{} ({:?})", info.name, info.backend).replace('\0', " "),
            )
            .unwrap_or_default(),
            device,
            queue,
            renderer,
            errors,
            presenter,
            vulkan,
            abi_minor,
        })
    }

    /// The renderer, for the calls of other modules (views).
    pub(crate) fn renderer_mut(&mut self) -> &mut Renderer {
        &mut self.renderer
    }

    /// The renderer and the host-device state, for the Vulkan calls.
    pub(crate) fn renderer_and_host(
        &mut self,
    ) -> FfiResult<(&mut Renderer, &mut super::vulkan::VulkanHost)> {
        match self.vulkan.as_mut() {
            Some(host) => Ok((&mut self.renderer, host)),
            None => Err(FfiError::arg(
                "the context was not created on a host Vulkan device (NimbusVulkanDeviceExt): \
                 use nimbus_context_render with NimbusTextures",
            )),
        }
    }

    /// Errors the device reported since the last call (validation, out of memory, loss).
    pub(crate) fn take_device_errors(&self) -> FfiResult {
        Ok(self.errors.take()?)
    }

    fn render(&mut self, frame: &NimbusFrame, targets: &NimbusTargets) -> FfiResult<NimbusResult> {
        let inputs = decode_frame(frame)?;
        let view = super::view::view_of(frame.next)?;
        let viewport = super::types::viewport_of(targets.next)?;
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
        let surface_size = self
            .presenter
            .as_ref()
            .map(|p| (p.config.width, p.config.height));
        check_c_targets(scene, depth, output, surface_size)?;
        self.renderer.prepare_view(view, &inputs)?;
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
                self.renderer.encode_view(
                    view,
                    &mut encoder,
                    &Targets {
                        color,
                        depth: depth_view,
                        viewport,
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
                let surface_view = frame.texture.create_view(&Default::default());
                self.renderer.encode_view(
                    view,
                    &mut encoder,
                    &Targets {
                        color: ColorTargets::Separate {
                            scene: &scene.view,
                            output: &surface_view,
                        },
                        depth: depth_view,
                        viewport,
                    },
                )?;
                self.queue.submit([encoder.finish()]);
                self.queue.present(frame);
                NIMBUS_OK
            }
        };
        self.errors.take()?;
        Ok(status)
    }
}

/// The window surface of an owned device, configured for presenting.
fn presenter(
    owned: &crate::device::OwnedDevice,
    surface: wgpu::Surface<'static>,
    desc: &NimbusContextDesc,
) -> FfiResult<Presenter> {
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
    gpu_scope(&owned.device, || surface.configure(&owned.device, &config))?;
    Ok(Presenter { surface, config })
}

fn invalid_target(message: String) -> FfiError {
    FfiError::new(NIMBUS_ERROR_INVALID_TARGET, message)
}

/// The target rules in the C API's own terms (NIMBUS_FORMAT_* names, the `targets.*` fields),
/// checked before the renderer's checks, whose messages speak of Rust and wgpu types.
fn check_c_targets(
    scene: &NimbusTexture,
    depth: Option<&NimbusTexture>,
    output: Option<&NimbusTexture>,
    surface_size: Option<(u32, u32)>,
) -> FfiResult {
    let size = |t: &NimbusTexture| format!("{}x{}", t.size().0, t.size().1);
    if !is_color(scene.format) {
        return Err(invalid_target(format!(
            "targets.scene_color is {}, a depth format: give a color texture",
            format_name(scene.format)
        )));
    }
    if let Some(d) = depth {
        if is_color(d.format) {
            return Err(invalid_target(format!(
                "targets.scene_depth must be NIMBUS_FORMAT_R32_FLOAT (clip-space depth) or \
                 NIMBUS_FORMAT_DEPTH16_UNORM, got {}",
                format_name(d.format)
            )));
        }
        if d.size() != scene.size() {
            return Err(invalid_target(format!(
                "targets.scene_depth is {} but targets.scene_color is {}: all targets must have one size",
                size(d),
                size(scene)
            )));
        }
    }
    match output {
        Some(out) => {
            if !is_color(out.format) {
                return Err(invalid_target(format!(
                    "targets.output is {}, a depth format: give a color texture",
                    format_name(out.format)
                )));
            }
            if std::ptr::eq(out, scene) && out.format == NIMBUS_FORMAT_RGBA32_FLOAT {
                return Err(invalid_target(
                    "compositing in place (targets.output == targets.scene_color) needs a blendable \
                     format, and NIMBUS_FORMAT_RGBA32_FLOAT is not: use a separate output texture"
                        .into(),
                ));
            }
            if out.size() != scene.size() {
                return Err(invalid_target(format!(
                    "targets.output is {} but targets.scene_color is {}: all targets must have one size",
                    size(out),
                    size(scene)
                )));
            }
        }
        None => {
            if let Some((w, h)) = surface_size {
                if (w, h) != scene.size() {
                    return Err(invalid_target(format!(
                        "targets.scene_color is {} but the window surface is {w}x{h}: \
                         resize the scene or call nimbus_context_resize",
                        size(scene)
                    )));
                }
            }
        }
    }
    Ok(())
}

/// Creates a context: its own GPU device (any adapter; Mesa's software Vulkan works), a
/// renderer, and, when `desc->window` is set, a surface presenting to that window. Blocks while
/// the noise volumes are baked. On success writes the handle to `*out`; on failure `*out` is
/// untouched and `nimbus_context_last_error(NULL)` says why.
///
/// Safety: `desc` and `out` must be NULL or valid; the chain and window handles must be valid.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_create(
    desc: *const NimbusContextDesc,
    out: *mut *mut NimbusContext,
) -> NimbusResult {
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
/// Safety: `ctx` must be NULL or a context from `nimbus_context_create`, not yet destroyed.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_destroy(ctx: *mut NimbusContext) {
    if !ctx.is_null() {
        boundary(
            || {
                // SAFETY: created by Box::into_raw in nimbus_context_create, destroyed once.
                let ctx = unsafe { Box::from_raw(ctx) };
                let _ = ctx.inner.device.poll(wgpu::PollType::wait_indefinitely());
                drop(ctx);
                crate::device::release_freed_memory();
                Ok(NIMBUS_OK)
            },
            |_, _| {},
        );
    }
}

/// The message of the last failed call on `ctx`, or with NULL the last failed call on this
/// thread (e.g. a failed `nimbus_context_create`). Empty after a success. Valid until the next
/// call with the same context (or on this thread); never free it.
///
/// Safety: `ctx` must be NULL or a live context.
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
/// Safety: `ctx` must be NULL or a live context.
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
/// Safety: `ctx`, `frame`, `targets` and the textures they point to must be NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_render(
    ctx: *mut NimbusContext,
    frame: *const NimbusFrame,
    targets: *const NimbusTargets,
) -> NimbusResult {
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
/// Safety: `ctx` must be NULL or a live context.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_resize(
    ctx: *mut NimbusContext,
    width: u32,
    height: u32,
) -> NimbusResult {
    // SAFETY: the caller guarantees a live context or NULL.
    unsafe {
        with_ctx(ctx, |inner| {
            check_size(width, height)?;
            if let Some(p) = inner.presenter.as_mut() {
                let mut config = p.config.clone();
                config.width = width;
                config.height = height;
                let (surface, device) = (&p.surface, &inner.device);
                gpu_scope(device, || surface.configure(device, &config))?;
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
/// The preset's weather map is generated a slice per frame (16 frames at the default size),
/// so the request costs no frame a hitch: until it is ready `nimbus_context_weather_state`
/// says `NIMBUS_TRANSITION_PENDING`, then the transition starts at the later of `start` and
/// that frame's time. Requests made meanwhile wait their turn, in order.
///
/// Safety: `ctx` must be NULL or a live context.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_set_weather(
    ctx: *mut NimbusContext,
    preset_id: u32,
    options: u32,
    start: f64,
    duration: f64,
) -> NimbusResult {
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
/// Safety: `ctx` must be NULL or a live context; `path` NULL or a NUL-terminated UTF-8 path.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_load_weather(
    ctx: *mut NimbusContext,
    path: *const c_char,
    start: f64,
    duration: f64,
) -> NimbusResult {
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

/// Like `nimbus_context_load_weather`, with the preset's TOML text in memory (`size` bytes,
/// UTF-8, no NUL needed): for engines that ship packed assets. The same size limit and checks
/// as for files apply; errors name the line and field.
///
/// Safety: `ctx` must be NULL or a live context; `text` NULL or `size` readable bytes.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_set_weather_toml(
    ctx: *mut NimbusContext,
    text: *const c_char,
    size: usize,
    start: f64,
    duration: f64,
) -> NimbusResult {
    // SAFETY: the caller guarantees a live context or NULL, and `size` readable bytes.
    unsafe {
        with_ctx(ctx, |inner| {
            if text.is_null() {
                return Err(FfiError::null("text"));
            }
            if size > crate::weather::preset::MAX_PRESET_BYTES {
                return Err(FfiError::new(
                    NIMBUS_ERROR_PRESET_FILE,
                    format!(
                        "the preset text is {size} bytes; a preset is at most {} bytes",
                        crate::weather::preset::MAX_PRESET_BYTES
                    ),
                ));
            }
            let bytes = std::slice::from_raw_parts(text.cast::<u8>(), size);
            let text = std::str::from_utf8(bytes).map_err(|_| {
                FfiError::new(NIMBUS_ERROR_PRESET_FILE, "the preset text is not UTF-8")
            })?;
            let w = Weather::from_toml(text, "<memory>")?;
            inner.renderer.set_weather(w, start, duration)?;
            Ok(NIMBUS_OK)
        })
    }
}

/// Writes a built-in preset (`NIMBUS_PRESET_*` with `NIMBUS_WEATHER_*` options) as TOML, the
/// template for preset files: with `buf` NULL, writes the size it needs (NUL included) to
/// `*size`; otherwise `*size` must hold `buf`'s capacity, the text is written NUL-terminated
/// and `*size` becomes its length with the NUL. A too small buffer is
/// NIMBUS_ERROR_INVALID_ARGUMENT (nothing written).
///
/// Safety: `size` must be NULL or valid; `buf` NULL or `*size` writable bytes.
#[no_mangle]
pub unsafe extern "C" fn nimbus_preset_write_toml(
    preset_id: u32,
    options: u32,
    buf: *mut c_char,
    size: *mut usize,
) -> NimbusResult {
    boundary(
        || {
            // SAFETY: checked for NULL; the caller guarantees validity.
            let size = unsafe { size.as_mut() }.ok_or_else(|| FfiError::null("size"))?;
            let text = weather_with(preset(preset_id)?, options)?.to_toml();
            let needed = text.len() + 1;
            if buf.is_null() {
                *size = needed;
                return Ok(NIMBUS_OK);
            }
            if *size < needed {
                return Err(FfiError::arg(format!(
                    "the buffer holds {} bytes but the template needs {needed}",
                    *size
                )));
            }
            // SAFETY: `buf` has `*size` >= needed writable bytes per the caller's contract.
            unsafe {
                std::ptr::copy_nonoverlapping(text.as_ptr(), buf.cast::<u8>(), text.len());
                *buf.add(text.len()) = 0;
            }
            *size = needed;
            Ok(NIMBUS_OK)
        },
        |_, _| {},
    )
}

fn name_field(name: &str) -> [c_char; NIMBUS_WEATHER_NAME_CAPACITY] {
    let mut out = [0 as c_char; NIMBUS_WEATHER_NAME_CAPACITY];
    // Cut on a character boundary, leaving room for the NUL.
    let mut end = name.len().min(NIMBUS_WEATHER_NAME_CAPACITY - 1);
    while !name.is_char_boundary(end) {
        end -= 1;
    }
    for (o, b) in out.iter_mut().zip(&name.as_bytes()[..end]) {
        *o = *b as c_char;
    }
    out
}

/// Writes where the weather transition stands at host time `time` to `*out`: from and to,
/// start, duration, progress and phase.
///
/// Safety: `ctx` must be NULL or a live context; `out` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_weather_state(
    ctx: *mut NimbusContext,
    time: f64,
    out: *mut NimbusWeatherState,
) -> NimbusResult {
    // SAFETY: the caller guarantees a live context or NULL, and `out` writable or NULL.
    unsafe {
        with_ctx(ctx, |inner| {
            let out = out.as_mut().ok_or_else(|| FfiError::null("out"))?;
            check_chain(out.next, &[])?;
            if !time.is_finite() {
                // Only NaN and the infinities reach here: they print short.
                return Err(FfiError::arg(format!("time must be finite, got {time}")));
            }
            let s = inner.renderer.weather_state(time);
            *out = NimbusWeatherState {
                next: out.next,
                from_name: name_field(&s.from),
                to_name: name_field(&s.to),
                start: s.start,
                duration: s.duration,
                progress: s.progress,
                phase: match s.phase {
                    // A header before 0.7 has no PENDING: for it the request is scheduled.
                    crate::weather::TransitionPhase::Pending if inner.abi_minor >= 7 => {
                        NIMBUS_TRANSITION_PENDING
                    }
                    crate::weather::TransitionPhase::Pending => NIMBUS_TRANSITION_SCHEDULED,
                    crate::weather::TransitionPhase::Scheduled => NIMBUS_TRANSITION_SCHEDULED,
                    crate::weather::TransitionPhase::Running => NIMBUS_TRANSITION_RUNNING,
                    crate::weather::TransitionPhase::Done => NIMBUS_TRANSITION_DONE,
                },
            };
            Ok(NIMBUS_OK)
        })
    }
}

/// Stops the weather where it is at host time `now`: a running transition freezes at its
/// current blend, a scheduled one (starting after `now`) is dropped, and the sky holds until
/// the next weather request (which must not be earlier than `now`).
///
/// Safety: `ctx` must be NULL or a live context.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_cancel_weather(
    ctx: *mut NimbusContext,
    now: f64,
) -> NimbusResult {
    // SAFETY: the caller guarantees a live context or NULL.
    unsafe {
        with_ctx(ctx, |inner| {
            inner.renderer.cancel_weather(now)?;
            Ok(NIMBUS_OK)
        })
    }
}

/// Drops the accumulated cloud history of every view, so the next frames start afresh. Call
/// it on camera cuts (a teleport, a switch to another camera); ordinary and fast motion need
/// no call. For one view: `nimbus_context_reset_view_history`.
///
/// Safety: `ctx` must be NULL or a live context.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_reset_history(ctx: *mut NimbusContext) -> NimbusResult {
    // SAFETY: the caller guarantees a live context or NULL.
    unsafe {
        with_ctx(ctx, |inner| {
            inner.renderer.reset_history();
            Ok(NIMBUS_OK)
        })
    }
}

/// Test hook, only in builds with the `test-hooks` cargo feature (never in the release
/// library, and not in nimbus.h): panics inside the boundary, so a C test can check that a
/// panic comes back as NIMBUS_ERROR_PANIC and poisons the context.
///
/// Safety: `ctx` must be NULL or a live context.
#[cfg(feature = "test-hooks")]
#[no_mangle]
pub unsafe extern "C" fn nimbus_test_hook_panic(ctx: *mut NimbusContext) -> NimbusResult {
    // SAFETY: the caller guarantees a live context or NULL.
    unsafe { with_ctx(ctx, |_| panic!("nimbus_test_hook_panic was called")) }
}

/// Test hook, only with the `test-hooks` cargo feature (not in nimbus.h): destroys the
/// context's GPU device, as a driver reset would lose it, so a C test can check that later
/// calls return NIMBUS_ERROR_DEVICE_LOST and that a new context works afterwards.
///
/// Safety: `ctx` must be NULL or a live context.
#[cfg(feature = "test-hooks")]
#[no_mangle]
pub unsafe extern "C" fn nimbus_test_hook_lose_device(ctx: *mut NimbusContext) -> NimbusResult {
    // SAFETY: the caller guarantees a live context or NULL.
    unsafe {
        with_ctx(ctx, |inner| {
            inner.device.destroy();
            let _ = inner.device.poll(wgpu::PollType::wait_indefinitely());
            Ok(NIMBUS_OK)
        })
    }
}
