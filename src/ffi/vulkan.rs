//! The C side of the host-Vulkan-device path: C structs translated onto `crate::vulkan`.
//!
//! Vulkan handles travel without vulkan.h: dispatchable ones (VkInstance, VkPhysicalDevice,
//! VkDevice, VkQueue) as `void *`, the others (VkImage, VkSemaphore) as `uint64_t`, enums and
//! flags as `uint32_t` with Vulkan's values.

use std::ffi::{c_char, c_void, CStr, CString};
use std::sync::Arc;

use ash::vk;
use ash::vk::Handle;

use super::context::{with_ctx, ContextInner};
use super::result::NimbusResult::{self, *};
use super::types::{NimbusChainedStruct, NimbusFrame};
use super::{boundary, FfiError, FfiResult};
use crate::vulkan::{
    AdoptedDevice, DeviceRequirements, HostDevice, HostFrame, HostImage, HostInstance, QueueLock,
    Semaphore,
};

/// `s_type` of `NimbusVulkanDeviceExt` (chain it to `NimbusContextDesc.next`). Since ABI 0.3.
pub const NIMBUS_STYPE_VULKAN_DEVICE: u32 = 3;

/// A Vulkan function pointer (`PFN_vkVoidFunction`).
pub type NimbusVkVoidFunction = Option<unsafe extern "C" fn()>;
/// `vkGetInstanceProcAddr`: pass `(NimbusVkGetInstanceProcAddr)vkGetInstanceProcAddr`.
pub type NimbusVkGetInstanceProcAddr = Option<
    unsafe extern "C" fn(instance: *mut c_void, name: *const c_char) -> NimbusVkVoidFunction,
>;
/// The host's queue lock or unlock, called with `lock_user_data`.
pub type NimbusQueueLockFn = Option<unsafe extern "C" fn(user_data: *mut c_void)>;

/// The host's `VkInstance`, as it created it. Since ABI 0.3.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NimbusVulkanInstance {
    /// The loader's (or the host's) `vkGetInstanceProcAddr`. Required.
    pub get_instance_proc_addr: NimbusVkGetInstanceProcAddr,
    /// The `VkInstance`.
    pub instance: *mut c_void,
    /// `VkApplicationInfo.apiVersion` given to `vkCreateInstance` (at least Vulkan 1.1).
    pub api_version: u32,
    /// How many names `extensions` holds.
    pub extension_count: u32,
    /// The `ppEnabledExtensionNames` given to `vkCreateInstance`.
    pub extensions: *const *const c_char,
}

/// Chained to `NimbusContextDesc.next`: create the context on the host's own Vulkan device
/// (`desc.window` must be NULL). Every handle must outlive the context. Since ABI 0.3.
///
/// The calls that touch the queue (vkQueueSubmit or vkQueueWaitIdle, under `lock_queue` /
/// `unlock_queue` when given): `nimbus_context_create` (uploads, the noise bake),
/// `nimbus_context_render_vulkan` and `nimbus_context_render` (one submit),
/// `nimbus_texture_write` and `nimbus_texture_read` on its textures, the weather calls
/// (`nimbus_context_set_weather`, `_load_weather`, `_set_weather_toml`, `_cancel_weather`: they
/// bake a weather map), `nimbus_context_release_vulkan_images` and `nimbus_context_destroy`
/// (they wait). No other call does.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NimbusVulkanDeviceExt {
    /// `s_type` = `NIMBUS_STYPE_VULKAN_DEVICE`.
    pub chain: NimbusChainedStruct,
    /// The instance the device was created from.
    pub instance: NimbusVulkanInstance,
    /// The `VkPhysicalDevice`.
    pub physical_device: *mut c_void,
    /// The `VkDevice`.
    pub device: *mut c_void,
    /// How many names `extensions` holds.
    pub extension_count: u32,
    /// The device extensions given to `vkCreateDevice`.
    pub extensions: *const *const c_char,
    /// The `VkPhysicalDeviceFeatures2` (itself, with its `pNext` chain) given to
    /// `vkCreateDevice` as `VkDeviceCreateInfo.pNext`. Required: Vulkan cannot be asked which
    /// features a device has enabled. Read only during `nimbus_context_create`.
    pub enabled_features: *const c_void,
    /// The `VkQueue` Nimbus submits to (`vkGetDeviceQueue(device, family, index)`).
    pub queue: *mut c_void,
    /// Its family: must be 0 (wgpu 30 drives queue family 0 only).
    pub queue_family_index: u32,
    /// Its index in the family.
    pub queue_index: u32,
    /// Optional, with `unlock_queue` (both or neither): called before every `vkQueueSubmit`
    /// and `vkQueueWaitIdle` Nimbus makes on the queue, from the thread making the Nimbus call.
    /// It must not call into Nimbus.
    pub lock_queue: NimbusQueueLockFn,
    /// Called after each such call.
    pub unlock_queue: NimbusQueueLockFn,
    /// Passed to both callbacks.
    pub lock_user_data: *mut c_void,
}

/// One of the host's images for `nimbus_context_render_vulkan`. Since ABI 0.3.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NimbusVulkanImage {
    /// The `VkImage` (2D, one sample); 0 for "none" (depth only: nothing occludes).
    pub image: u64,
    /// Its `VkFormat`. Color: `VK_FORMAT_R8G8B8A8_UNORM`, `R8G8B8A8_SRGB`, `B8G8R8A8_UNORM`,
    /// `B8G8R8A8_SRGB`, `A2B10G10R10_UNORM_PACK32`, `B10G11R11_UFLOAT_PACK32`,
    /// `R16G16B16A16_SFLOAT`. Depth (read through its depth aspect): `D32_SFLOAT`,
    /// `D24_UNORM_S8_UINT`, `D32_SFLOAT_S8_UINT`, `D16_UNORM`.
    pub format: u32,
    /// Width of mip 0 in pixels.
    pub width: u32,
    /// Height of mip 0 in pixels.
    pub height: u32,
    /// The image's mip count (0 counts as 1).
    pub mip_levels: u32,
    /// The image's layer count (0 counts as 1).
    pub array_layers: u32,
    /// The mip Nimbus uses, below `mip_levels` (0.3 libraries accepted only 0). Its size is
    /// mip 0's halved per level (at least 1); color and depth are compared at their used mips,
    /// and a viewport lies within the used mip.
    pub mip_level: u32,
    /// The layer Nimbus uses.
    pub array_layer: u32,
    /// The `VkImageUsageFlags` it was created with. Color needs `COLOR_ATTACHMENT`, depth
    /// `SAMPLED`, and each layout the usage docs/c-api.md lists for it.
    pub usage: u32,
    /// The `VkImageLayout` the used mip and layer are in when Nimbus's work runs. Color:
    /// `COLOR_ATTACHMENT`, `SHADER_READ_ONLY`, `TRANSFER_SRC` / `_DST` (`_OPTIMAL`), and since
    /// 0.4 `PRESENT_SRC_KHR` and `GENERAL`; depth: `DEPTH_STENCIL_ATTACHMENT`,
    /// `DEPTH_STENCIL_READ_ONLY`, `TRANSFER_SRC` / `_DST` (`_OPTIMAL`), and since 0.4 `GENERAL`.
    pub layout: u32,
    /// The layout to leave them in; 0 (`VK_IMAGE_LAYOUT_UNDEFINED`): the same as `layout`.
    pub final_layout: u32,
}

/// A semaphore Nimbus's submission waits on or signals. Since ABI 0.3.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NimbusVulkanSemaphore {
    /// The `VkSemaphore`.
    pub semaphore: u64,
    /// A timeline semaphore's value; 0 for a binary semaphore.
    pub value: u64,
    /// Waits: the `VkPipelineStageFlags` the wait blocks (0: `ALL_COMMANDS`). Ignored for
    /// signals.
    pub stage: u32,
    /// Must be 0.
    pub reserved: u32,
}

/// The host's images and semaphores of one frame. Since ABI 0.3.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NimbusVulkanTargets {
    /// Chained extensions, or NULL.
    pub next: *const NimbusChainedStruct,
    /// The scene color: the clouds are composited into it in place. Required.
    pub color: NimbusVulkanImage,
    /// The scene depth in the frame's depth convention; `image` 0: nothing occludes.
    pub depth: NimbusVulkanImage,
    /// How many semaphores `waits` holds (at most 16).
    pub wait_count: u32,
    /// Waited on before Nimbus's work.
    pub waits: *const NimbusVulkanSemaphore,
    /// How many semaphores `signals` holds (at most 16).
    pub signal_count: u32,
    /// Signalled when Nimbus's work is done.
    pub signals: *const NimbusVulkanSemaphore,
}

/// What a context on a host device keeps: the adopted device and the image wrappers.
pub(crate) struct VulkanHost {
    pub(crate) frame: HostFrame,
    pub(crate) _adopted: AdoptedDevice,
}

/// At most this many names in an extension list.
const MAX_NAMES: u32 = 1024;
/// At most this many semaphores per direction.
const MAX_SEMAPHORES: u32 = 16;

/// Safety: `gipa` is a valid `vkGetInstanceProcAddr`.
unsafe fn entry(gipa: NimbusVkGetInstanceProcAddr, field: &str) -> FfiResult<ash::Entry> {
    let gipa = gipa.ok_or_else(|| FfiError::null(field))?;
    // SAFETY: the C signature is vkGetInstanceProcAddr's; "C" and "system" agree on the
    // platforms wgpu's Vulkan backend runs on (x86_64 and aarch64).
    let static_fn = ash::StaticFn {
        get_instance_proc_addr: unsafe {
            std::mem::transmute::<
                unsafe extern "C" fn(*mut c_void, *const c_char) -> NimbusVkVoidFunction,
                vk::PFN_vkGetInstanceProcAddr,
            >(gipa)
        },
    };
    // SAFETY: loads the global entry points through the host's function.
    Ok(unsafe { ash::Entry::from_static_fn(static_fn) })
}

/// Safety: `names` holds `count` NUL-terminated strings (or `count` is 0).
unsafe fn names(count: u32, names: *const *const c_char, field: &str) -> FfiResult<Vec<CString>> {
    if count == 0 {
        return Ok(Vec::new());
    }
    if count > MAX_NAMES {
        return Err(FfiError::arg(format!(
            "{field}: {count} names, at most {MAX_NAMES}"
        )));
    }
    if names.is_null() {
        return Err(FfiError::null(field));
    }
    (0..count as usize)
        .map(|i| {
            // SAFETY: `count` valid entries per the caller.
            let p = unsafe { *names.add(i) };
            if p.is_null() {
                return Err(FfiError::null(&format!("{field}[{i}]")));
            }
            // SAFETY: NUL-terminated per the caller.
            Ok(unsafe { CStr::from_ptr(p) }.to_owned())
        })
        .collect()
}

/// Safety: the instance struct's pointers are valid.
unsafe fn host_instance(i: &NimbusVulkanInstance, field: &str) -> FfiResult<HostInstance> {
    // SAFETY: per the caller.
    let entry = unsafe {
        entry(
            i.get_instance_proc_addr,
            &format!("{field}.get_instance_proc_addr"),
        )
    }?;
    if i.instance.is_null() {
        return Err(FfiError::null(&format!("{field}.instance")));
    }
    Ok(HostInstance {
        entry,
        instance: vk::Instance::from_raw(i.instance as u64),
        api_version: i.api_version,
        // SAFETY: per the caller.
        extensions: unsafe {
            names(
                i.extension_count,
                i.extensions,
                &format!("{field}.extensions"),
            )
        }?,
    })
}

/// Writes a static name list with the two-call idiom.
///
/// Safety: `count` is valid; `out` is NULL or holds `*count` writable slots.
unsafe fn write_names(
    list: &[&'static CStr],
    count: *mut u32,
    out: *mut *const c_char,
) -> FfiResult<NimbusResult> {
    if count.is_null() {
        return Err(FfiError::null("count"));
    }
    let n = list.len() as u32;
    if out.is_null() {
        // SAFETY: non-null, writable per the caller.
        unsafe { *count = n };
        return Ok(NIMBUS_OK);
    }
    // SAFETY: as above.
    let room = unsafe { *count };
    if room < n {
        return Err(FfiError::arg(format!(
            "*count is {room} but there are {n} names: call with names NULL first to get the count"
        )));
    }
    for (i, name) in list.iter().enumerate() {
        // SAFETY: `room` >= n writable slots per the caller.
        unsafe { *out.add(i) = name.as_ptr() };
    }
    // SAFETY: as above.
    unsafe { *count = n };
    Ok(NIMBUS_OK)
}

/// The instance extensions Nimbus needs: enable them (with yours) at `vkCreateInstance`,
/// with `apiVersion` at least `VK_API_VERSION_1_1`. Two-call idiom: with `names` NULL, writes
/// the count to `*count`; else `*count` must be at least that and the names are written. The
/// strings are static: never free them. Since ABI 0.3.
///
/// Safety: `get_instance_proc_addr` must be `vkGetInstanceProcAddr` or NULL; `count` NULL or
/// writable; `names` NULL or `*count` writable slots.
#[no_mangle]
pub unsafe extern "C" fn nimbus_vulkan_instance_extensions(
    get_instance_proc_addr: NimbusVkGetInstanceProcAddr,
    count: *mut u32,
    names: *mut *const c_char,
) -> NimbusResult {
    boundary(
        || {
            // SAFETY: per the caller.
            let entry = unsafe { entry(get_instance_proc_addr, "get_instance_proc_addr") }?;
            let list = crate::vulkan::instance_extensions(&entry)?;
            // SAFETY: per the caller.
            unsafe { write_names(&list, count, names) }
        },
        |_, _| {},
    )
}

/// What a physical device needs enabled for Nimbus (see the `nimbus_vulkan_device_requirements_*`
/// calls). Since ABI 0.3.
pub struct NimbusVulkanDeviceRequirements {
    inner: DeviceRequirements,
}

/// The requirements of `physical_device` (a `VkPhysicalDevice` of `instance`), for
/// `vkCreateDevice`. Fails with `NIMBUS_ERROR_VULKAN_REQUIREMENT` when the instance lacks an
/// extension Nimbus needs or wgpu cannot use the device. Destroy it with
/// `nimbus_vulkan_device_requirements_destroy` after `vkCreateDevice`. Since ABI 0.3.
///
/// Safety: pointers NULL or valid; the handles live.
#[no_mangle]
pub unsafe extern "C" fn nimbus_vulkan_device_requirements_create(
    instance: *const NimbusVulkanInstance,
    physical_device: *mut c_void,
    out: *mut *mut NimbusVulkanDeviceRequirements,
) -> NimbusResult {
    boundary(
        || {
            // SAFETY: NULL checked; valid otherwise per the caller.
            let i = unsafe { instance.as_ref() }.ok_or_else(|| FfiError::null("instance"))?;
            if physical_device.is_null() {
                return Err(FfiError::null("physical_device"));
            }
            if out.is_null() {
                return Err(FfiError::null("out"));
            }
            // SAFETY: per the caller.
            let host = unsafe { host_instance(i, "instance") }?;
            // SAFETY: a live physical device of the host's instance.
            let inner = unsafe {
                DeviceRequirements::new(&host, vk::PhysicalDevice::from_raw(physical_device as u64))
            }?;
            let boxed = Box::new(NimbusVulkanDeviceRequirements { inner });
            // SAFETY: non-null, writable.
            unsafe { *out = Box::into_raw(boxed) };
            Ok(NIMBUS_OK)
        },
        |_, _| {},
    )
}

/// The device extensions to enable (two-call idiom as `nimbus_vulkan_instance_extensions`;
/// static strings). Since ABI 0.3.
///
/// Safety: `req` NULL or live; `count` and `names` as for `nimbus_vulkan_instance_extensions`.
#[no_mangle]
pub unsafe extern "C" fn nimbus_vulkan_device_requirements_extensions(
    req: *const NimbusVulkanDeviceRequirements,
    count: *mut u32,
    names: *mut *const c_char,
) -> NimbusResult {
    boundary(
        || {
            // SAFETY: NULL checked; live otherwise.
            let req = unsafe { req.as_ref() }.ok_or_else(|| FfiError::null("req"))?;
            // SAFETY: per the caller.
            unsafe { write_names(req.inner.extensions(), count, names) }
        },
        |_, _| {},
    )
}

/// Merges Nimbus's features into the host's feature chain. `features2` is the host's
/// `VkPhysicalDeviceFeatures2` (sType set; `pNext` its own feature structs or NULL), which the
/// host then gives to `vkCreateDevice` as `VkDeviceCreateInfo.pNext` with `pEnabledFeatures`
/// NULL. Bits go into structs already in the chain (promoted features into the
/// `VkPhysicalDeviceVulkan11/12/13Features` the host chains); structs with no home there are
/// appended at the end of the chain and belong to `req`: keep `req` alive as long as the chain
/// is used, i.e. through `vkCreateDevice` and every `nimbus_context_create` that is given the
/// chain as `NimbusVulkanDeviceExt.enabled_features`. Since ABI 0.3.
///
/// Safety: `req` NULL or live; `features2` NULL or a valid, writable chain.
#[no_mangle]
pub unsafe extern "C" fn nimbus_vulkan_device_requirements_merge_features(
    req: *mut NimbusVulkanDeviceRequirements,
    features2: *mut c_void,
) -> NimbusResult {
    boundary(
        || {
            // SAFETY: NULL checked; live otherwise.
            let req = unsafe { req.as_mut() }.ok_or_else(|| FfiError::null("req"))?;
            if features2.is_null() {
                return Err(FfiError::null("features2"));
            }
            // SAFETY: a valid writable chain per the caller.
            unsafe {
                req.inner
                    .merge_features(features2 as *mut vk::PhysicalDeviceFeatures2<'static>)
            }?;
            Ok(NIMBUS_OK)
        },
        |_, _| {},
    )
}

/// The queue family Nimbus's queue must come from (0 with wgpu 30; it supports graphics and
/// compute). Since ABI 0.3.
///
/// Safety: `req` NULL or live; `family` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nimbus_vulkan_device_requirements_queue_family(
    req: *const NimbusVulkanDeviceRequirements,
    family: *mut u32,
) -> NimbusResult {
    boundary(
        || {
            // SAFETY: NULL checked; live otherwise.
            let req = unsafe { req.as_ref() }.ok_or_else(|| FfiError::null("req"))?;
            // SAFETY: NULL checked; writable otherwise.
            let family = unsafe { family.as_mut() }.ok_or_else(|| FfiError::null("family"))?;
            *family = req.inner.queue_family();
            Ok(NIMBUS_OK)
        },
        |_, _| {},
    )
}

/// Destroys requirements and the feature structs they appended to a chain: after this the
/// chain they were merged into must not be used again. NULL is a no-op. Since ABI 0.3.
///
/// Safety: `req` NULL or from `nimbus_vulkan_device_requirements_create`, destroyed once.
#[no_mangle]
pub unsafe extern "C" fn nimbus_vulkan_device_requirements_destroy(
    req: *mut NimbusVulkanDeviceRequirements,
) {
    if !req.is_null() {
        boundary(
            || {
                // SAFETY: from Box::into_raw, destroyed once.
                drop(unsafe { Box::from_raw(req) });
                Ok(NIMBUS_OK)
            },
            |_, _| {},
        );
    }
}

/// The C lock callbacks as a `QueueLock`.
struct CLock {
    lock: unsafe extern "C" fn(*mut c_void),
    unlock: unsafe extern "C" fn(*mut c_void),
    user: *mut c_void,
}
// SAFETY: the header requires the callbacks to work from any thread Nimbus is called on.
unsafe impl Send for CLock {}
// SAFETY: as above.
unsafe impl Sync for CLock {}

/// The host device a creation chain describes.
///
/// Safety: `ext` is a valid `NimbusVulkanDeviceExt` whose pointers are valid.
pub(crate) unsafe fn host_device(ext: &NimbusVulkanDeviceExt) -> FfiResult<HostDevice> {
    let field = "NimbusVulkanDeviceExt";
    // SAFETY: per the caller.
    let instance = unsafe { host_instance(&ext.instance, &format!("{field}.instance")) }?;
    for (name, p) in [
        ("physical_device", ext.physical_device as *const c_void),
        ("device", ext.device as *const c_void),
        ("queue", ext.queue as *const c_void),
        ("enabled_features", ext.enabled_features),
    ] {
        if p.is_null() {
            return Err(FfiError::null(&format!("{field}.{name}")));
        }
    }
    let queue_lock = match (ext.lock_queue, ext.unlock_queue) {
        (None, None) => None,
        (Some(lock), Some(unlock)) => {
            let c = Arc::new(CLock {
                lock,
                unlock,
                user: ext.lock_user_data,
            });
            let d = c.clone();
            Some(Arc::new(QueueLock::new(
                // SAFETY: the host's callbacks with its user data.
                move || unsafe { (c.lock)(c.user) },
                // SAFETY: as above.
                move || unsafe { (d.unlock)(d.user) },
            )))
        }
        _ => {
            return Err(FfiError::arg(format!(
                "{field}: give both lock_queue and unlock_queue, or neither"
            )))
        }
    };
    Ok(HostDevice {
        instance,
        physical_device: vk::PhysicalDevice::from_raw(ext.physical_device as u64),
        device: vk::Device::from_raw(ext.device as u64),
        // SAFETY: per the caller.
        extensions: unsafe {
            names(
                ext.extension_count,
                ext.extensions,
                &format!("{field}.extensions"),
            )
        }?,
        enabled_features: ext.enabled_features as *const vk::PhysicalDeviceFeatures2<'static>,
        queue: vk::Queue::from_raw(ext.queue as u64),
        queue_family_index: ext.queue_family_index,
        queue_index: ext.queue_index,
        queue_lock,
    })
}

/// Adopts the host device for a new context.
///
/// Safety: as `adopt_device`.
pub(crate) unsafe fn adopt(host: &HostDevice) -> FfiResult<(AdoptedDevice, HostFrame)> {
    // SAFETY: per the caller.
    let adopted = unsafe { crate::vulkan::adopt_device(host) }?;
    let frame = HostFrame::new(&adopted)?;
    Ok((adopted, frame))
}

fn host_image(i: &NimbusVulkanImage) -> HostImage {
    HostImage {
        image: vk::Image::from_raw(i.image),
        format: vk::Format::from_raw(i.format as i32),
        width: i.width,
        height: i.height,
        mip_levels: i.mip_levels,
        array_layers: i.array_layers,
        mip_level: i.mip_level,
        array_layer: i.array_layer,
        usage: vk::ImageUsageFlags::from_raw(i.usage),
        layout: vk::ImageLayout::from_raw(i.layout as i32),
        final_layout: vk::ImageLayout::from_raw(i.final_layout as i32),
    }
}

/// Safety: `p` holds `count` semaphores (or `count` is 0).
unsafe fn semaphores(
    count: u32,
    p: *const NimbusVulkanSemaphore,
    field: &str,
) -> FfiResult<Vec<Semaphore>> {
    if count == 0 {
        return Ok(Vec::new());
    }
    if count > MAX_SEMAPHORES {
        return Err(FfiError::arg(format!(
            "targets.{field}_count is {count}, at most {MAX_SEMAPHORES}"
        )));
    }
    if p.is_null() {
        return Err(FfiError::null(&format!("targets.{field}s")));
    }
    // SAFETY: `count` valid entries per the caller.
    let list = unsafe { std::slice::from_raw_parts(p, count as usize) };
    list.iter()
        .enumerate()
        .map(|(i, s)| {
            if s.semaphore == 0 {
                return Err(FfiError::null(&format!("targets.{field}s[{i}].semaphore")));
            }
            if s.reserved != 0 {
                return Err(FfiError::arg(format!(
                    "targets.{field}s[{i}].reserved must be 0"
                )));
            }
            Ok(Semaphore {
                semaphore: vk::Semaphore::from_raw(s.semaphore),
                value: (s.value != 0).then_some(s.value),
                stage: vk::PipelineStageFlags::from_raw(s.stage),
            })
        })
        .collect()
}

impl ContextInner {
    fn render_vulkan(
        &mut self,
        frame: &NimbusFrame,
        targets: &NimbusVulkanTargets,
    ) -> FfiResult<NimbusResult> {
        let inputs = super::context::decode_frame(frame)?;
        let view = super::view::view_of(frame.next)?;
        let viewport = super::types::viewport_of(targets.next)?;
        if targets.color.image == 0 {
            return Err(FfiError::null("targets.color.image"));
        }
        // SAFETY: arrays valid per the caller's contract.
        let waits = unsafe { semaphores(targets.wait_count, targets.waits, "wait") }?;
        // SAFETY: as above.
        let signals = unsafe { semaphores(targets.signal_count, targets.signals, "signal") }?;
        let color = host_image(&targets.color);
        let depth = (targets.depth.image != 0).then(|| host_image(&targets.depth));
        let (renderer, host) = self.renderer_and_host()?;
        // SAFETY: the images and semaphores are live and as described (the header's contract).
        unsafe {
            let images = (&color, depth.as_ref(), viewport);
            host.frame
                .render(renderer, view, &inputs, images, &waits, &signals)
        }?;
        self.take_device_errors()?;
        Ok(NIMBUS_OK)
    }
}

/// Composites the clouds into the host's color image in place, reading its depth image, on
/// the host's queue (a context created with `NimbusVulkanDeviceExt`). The work waits on
/// `targets->waits`, signals `targets->signals`, and is ordered after the host's earlier
/// submissions on that queue and before its later ones: it begins and ends with a global
/// memory barrier (ALL_COMMANDS / MEMORY_WRITE to ALL_COMMANDS / MEMORY_READ | MEMORY_WRITE).
/// Both images are left in their final layouts. Checks fail before anything is submitted.
/// Touches the queue (one `vkQueueSubmit`, under the lock callbacks when given). Since ABI 0.3.
///
/// Safety: `ctx` NULL or live; `frame` and `targets` NULL or valid; the images live, created
/// as described and in the described layouts when the work runs, and alive until it has
/// finished (wait on a signalled semaphore, a later fence on the queue, or
/// `nimbus_context_release_vulkan_images`).
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_render_vulkan(
    ctx: *mut super::NimbusContext,
    frame: *const NimbusFrame,
    targets: *const NimbusVulkanTargets,
) -> NimbusResult {
    // SAFETY: `ctx` is NULL or live, `frame` and `targets` NULL (checked) or valid, per the
    // caller.
    unsafe {
        with_ctx(ctx, |c| {
            let frame = frame.as_ref().ok_or_else(|| FfiError::null("frame"))?;
            let targets = targets.as_ref().ok_or_else(|| FfiError::null("targets"))?;
            c.render_vulkan(frame, targets)
        })
    }
}

/// Waits for Nimbus's GPU work and drops its wrappers of the host's images. Nimbus keeps them
/// between frames (so nothing is made per frame): call this before destroying or re-creating
/// any image handed to `nimbus_context_render_vulkan`. `nimbus_context_destroy` does the same.
/// Touches the queue (a wait). Since ABI 0.3.
///
/// Safety: `ctx` NULL or live.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_release_vulkan_images(
    ctx: *mut super::NimbusContext,
) -> NimbusResult {
    // SAFETY: `ctx` is NULL or live per the caller.
    unsafe {
        with_ctx(ctx, |c| {
            let (renderer, host) = c.renderer_and_host()?;
            host.frame.release(renderer)?;
            Ok(NIMBUS_OK)
        })
    }
}

/// The cloud shadow map's `VkImage` on the host's device, for hosts that bind or copy it with
/// their own commands. Since ABI 0.6.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NimbusVulkanShadowImage {
    /// Must be NULL.
    pub next: *const NimbusChainedStruct,
    /// The `VkImage` (2D, one mip, one layer). Nimbus owns it: never destroy or write it. It
    /// stays valid until the context is destroyed; ask again every frame (it costs nothing).
    pub image: u64,
    /// Its `VkFormat`: `VK_FORMAT_R16G16B16A16_SFLOAT`.
    pub format: u32,
    /// Texels along a side (the image is square).
    pub resolution: u32,
    /// `VkImageUsageFlags` it certainly has: `SAMPLED | STORAGE | TRANSFER_SRC`.
    pub usage: u32,
    /// The `VkImageLayout` every `nimbus_context_render_vulkan` leaves it in, with its writes
    /// made available by that call's final global barrier, and expects it back in when its
    /// work runs: `VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL`.
    pub layout: u32,
}

/// The cloud shadow map's `VkImage` after the last frame of the default view. Sample it (or
/// copy from it, returning it to `layout`) in commands ordered after that frame's
/// `nimbus_context_render_vulkan` and before the next one's work (on the same queue, the
/// submission order is enough); the matrix and layout are `nimbus_context_cloud_shadows`'s.
/// `NIMBUS_ERROR_INVALID_ARGUMENT` on a context not made on a host Vulkan device;
/// `NIMBUS_ERROR_NOT_READY` without `NimbusCloudShadowsExt` or before the first frame.
/// Since ABI 0.6.
///
/// Safety: `ctx` NULL or live; `out` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nimbus_context_cloud_shadow_vulkan_image(
    ctx: *mut super::NimbusContext,
    out: *mut NimbusVulkanShadowImage,
) -> NimbusResult {
    // SAFETY: `ctx` is NULL or live and `out` NULL or writable, per the caller.
    unsafe {
        with_ctx(ctx, |c| {
            let out = out.as_mut().ok_or_else(|| FfiError::null("out"))?;
            super::context::check_chain(out.next, &[])?;
            let (renderer, _) = c.renderer_and_host()?;
            let map = renderer
                .cloud_shadows()
                .ok_or_else(super::shadows::not_ready)?;
            let image = crate::vulkan::shadow_map_image(&map)
                .ok_or_else(|| FfiError::arg("the cloud shadow map is not a Vulkan image"))?;
            *out = NimbusVulkanShadowImage {
                next: out.next,
                image: vk::Handle::as_raw(image),
                format: crate::vulkan::SHADOW_MAP_FORMAT.as_raw() as u32,
                resolution: map.resolution,
                usage: crate::vulkan::SHADOW_MAP_USAGE.as_raw(),
                layout: crate::vulkan::SHADOW_MAP_LAYOUT.as_raw() as u32,
            };
            Ok(NIMBUS_OK)
        })
    }
}

#[cfg(all(test, target_pointer_width = "64"))]
mod tests {
    use super::*;
    use std::mem::{offset_of, size_of};

    /// Released with ABI 0.3: sizes and the offsets a C compiler must agree on.
    #[test]
    fn vulkan_struct_layouts_are_pinned() {
        assert_eq!(size_of::<NimbusVulkanInstance>(), 32);
        assert_eq!(size_of::<NimbusVulkanDeviceExt>(), 128);
        assert_eq!(offset_of!(NimbusVulkanDeviceExt, enabled_features), 80);
        assert_eq!(offset_of!(NimbusVulkanDeviceExt, queue_family_index), 96);
        assert_eq!(size_of::<NimbusVulkanImage>(), 48);
        assert_eq!(offset_of!(NimbusVulkanImage, final_layout), 44);
        assert_eq!(size_of::<NimbusVulkanSemaphore>(), 24);
        assert_eq!(size_of::<NimbusVulkanTargets>(), 136);
        assert_eq!(offset_of!(NimbusVulkanTargets, signals), 128);
    }

    /// Released with ABI 0.6.
    #[test]
    fn shadow_image_layout_is_pinned() {
        assert_eq!(size_of::<NimbusVulkanShadowImage>(), 32);
        assert_eq!(offset_of!(NimbusVulkanShadowImage, image), 8);
        assert_eq!(offset_of!(NimbusVulkanShadowImage, format), 16);
        assert_eq!(offset_of!(NimbusVulkanShadowImage, resolution), 20);
        assert_eq!(offset_of!(NimbusVulkanShadowImage, usage), 24);
        assert_eq!(offset_of!(NimbusVulkanShadowImage, layout), 28);
    }
}
