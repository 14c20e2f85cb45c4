//! GPU device plumbing that hosts without a device of their own need, public so that Rust
//! hosts get what the C API uses: a device of Nimbus's own (headless or for a window), error
//! scopes that turn wgpu errors into [`Error`]s, a collector for wgpu errors that happen
//! outside any scope and for the device's loss, 2D textures and readback.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use crate::error::{Error, Result};

/// A device of Nimbus's own, and the window surface it presents to, if any.
pub struct OwnedDevice {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// The adapter it was made on.
    pub adapter: wgpu::Adapter,
    /// What the adapter is.
    pub info: wgpu::AdapterInfo,
    /// The window's surface, when a window was given.
    pub surface: Option<wgpu::Surface<'static>>,
}

/// The wgpu features Nimbus asks for where the adapter has them: GPU timing, and the render
/// formats `Depth32FloatStencil8` and `Rg11b10Ufloat` need.
pub(crate) fn wanted_features(available: wgpu::Features) -> wgpu::Features {
    available
        & (wgpu::Features::TIMESTAMP_QUERY
            | wgpu::Features::DEPTH32FLOAT_STENCIL8
            | wgpu::Features::RG11B10UFLOAT_RENDERABLE)
}

/// Returns memory the C allocator holds free to the system (glibc: `malloc_trim`; elsewhere
/// nothing). A device's driver worker threads (llvmpipe starts its own per device) each get a
/// malloc arena, and what they free stays in it after they end: without a trim every device
/// created and dropped leaves a few MiB counted in the process's RSS (measured: 2.7 MiB per
/// context over 9 recreations, none of it in use; see docs/soak.md). Nimbus calls this before
/// it creates a device and after `nimbus_context_destroy`.
pub fn release_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim has no preconditions; it only returns free pages.
    unsafe {
        libc::malloc_trim(0);
    }
}

/// Creates a device on the first adapter found (compatible with `window` when given), with
/// timestamp queries when the adapter has them and the adapter's full limits. Backends follow
/// `WGPU_BACKEND` when set (e.g. `vulkan`), else the platform's primary ones. wgpu's debug flag
/// stays off: Debian's validation layers misread naga's debug SPIR-V.
///
/// # Safety
/// The handles in `window` must stay valid for the life of the returned surface.
pub unsafe fn create_owned_device(
    window: Option<wgpu::SurfaceTargetUnsafe>,
) -> Result<OwnedDevice> {
    // What earlier devices' threads freed goes back before a new device starts its own.
    release_freed_memory();
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Backends::PRIMARY;
    desc.flags = wgpu::InstanceFlags::empty();
    let instance = wgpu::Instance::new(desc.with_env());
    let surface = match window {
        Some(target) => Some(
            // SAFETY: the caller guarantees the handles outlive the surface.
            unsafe { instance.create_surface_unsafe(target) }
                .map_err(|e| Error::Surface(e.to_string()))?,
        ),
        None => None,
    };
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        force_fallback_adapter: false,
        compatible_surface: surface.as_ref(),
        ..Default::default()
    }))
    .map_err(|e| {
        Error::NoAdapter(format!(
            "{e} (on Linux without a GPU, install Mesa's software Vulkan: mesa-vulkan-drivers)"
        ))
    })?;
    let features = wanted_features(adapter.features());
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("nimbus"),
        required_features: features,
        required_limits: adapter.limits(),
        ..Default::default()
    }))
    .map_err(|e| Error::RequestDevice(e.to_string()))?;
    let info = adapter.get_info();
    Ok(OwnedDevice {
        device,
        queue,
        adapter,
        info,
        surface,
    })
}

/// Creates a headless device on the first adapter found (see [`create_owned_device`]).
pub fn create_device() -> Result<(wgpu::Device, wgpu::Queue, wgpu::AdapterInfo)> {
    // SAFETY: no window handles are involved.
    let d = unsafe { create_owned_device(None) }?;
    Ok((d.device, d.queue, d.info))
}

/// What a device reported outside any error scope: wgpu errors (wgpu's default handler would
/// panic on them) and the device's loss. Install it once, right after creating the device.
#[derive(Clone)]
pub struct DeviceErrors {
    errors: Arc<Mutex<Vec<String>>>,
    lost: Arc<Mutex<Option<String>>>,
    lost_flag: Arc<AtomicBool>,
}

impl DeviceErrors {
    /// Replaces the device's uncaptured-error handler and device-lost callback with collectors.
    pub fn install(device: &wgpu::Device) -> Self {
        let this = Self {
            errors: Arc::new(Mutex::new(Vec::new())),
            lost: Arc::new(Mutex::new(None)),
            lost_flag: Arc::new(AtomicBool::new(false)),
        };
        let sink = this.errors.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut v) = sink.lock() {
                v.push(e.to_string());
            }
        }));
        let (lost, flag) = (this.lost.clone(), this.lost_flag.clone());
        device.set_device_lost_callback(move |reason, message| {
            let why = match reason {
                wgpu::DeviceLostReason::Destroyed => "destroyed",
                wgpu::DeviceLostReason::Unknown => "lost by the driver or the system",
            };
            if let Ok(mut l) = lost.lock() {
                *l = Some(if message.is_empty() {
                    why.to_string()
                } else {
                    format!("{why}: {message}")
                });
            }
            flag.store(true, Ordering::SeqCst);
            log::error!("nimbus: the GPU device was lost ({reason:?}): {message}");
        });
        this
    }

    /// Whether the device was lost. A lost device stays lost: make a new one.
    pub fn is_lost(&self) -> bool {
        self.lost_flag.load(Ordering::SeqCst)
    }

    /// `Err(Error::DeviceLost)` once the device is lost.
    pub fn check_lost(&self) -> Result<()> {
        if !self.is_lost() {
            return Ok(());
        }
        let why = self
            .lost
            .lock()
            .ok()
            .and_then(|l| l.clone())
            .unwrap_or_else(|| "lost".into());
        Err(Error::DeviceLost(why))
    }

    /// Drains the collected errors: `Err(Error::DeviceLost)` when the device is lost, else
    /// one `Err(Error::Gpu)` holding every collected message, else `Ok`.
    pub fn take(&self) -> Result<()> {
        self.check_lost()?;
        let mut v = self
            .errors
            .lock()
            .map_err(|_| Error::Gpu("error log poisoned".into()))?;
        if v.is_empty() {
            Ok(())
        } else {
            Err(Error::Gpu(std::mem::take(&mut *v).join("; ")))
        }
    }
}

/// Runs `f` inside validation and out-of-memory error scopes and turns a captured wgpu error
/// into `Error::Gpu`.
pub fn gpu_scope<T>(device: &wgpu::Device, f: impl FnOnce() -> T) -> Result<T> {
    let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let value = f();
    let v = pollster::block_on(validation.pop());
    let o = pollster::block_on(oom.pop());
    match v.or(o) {
        Some(e) => Err(Error::Gpu(e.to_string())),
        None => Ok(value),
    }
}

/// A single-mip, single-sample 2D texture.
pub fn texture_2d(
    device: &wgpu::Device,
    label: &str,
    size: (u32, u32),
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    crate::gpu::texture_2d(device, label, size, format, usage)
}

/// Waits for the GPU and reads mip level `mip` of `texture` (every layer) into tightly packed
/// rows: x fastest, then y, then z. The texture needs `COPY_SRC` usage.
pub fn read_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    mip: u32,
) -> Result<Vec<u8>> {
    crate::gpu::readback::read_texture(device, queue, texture, mip)
}
