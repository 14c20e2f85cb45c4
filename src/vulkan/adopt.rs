//! Adopting the host's `VkDevice` and `VkQueue` as a wgpu device, never destroying them.

use std::ffi::{c_void, CString};
use std::sync::Arc;

use ash::vk;
use wgpu::hal::vulkan as hv;

use super::features;
use super::queue_lock::{self, QueueLock};
use super::requirements::{device_needs, expose, HostInstance};
use super::{wanted_features, QUEUE_FAMILY};
use crate::error::{Error, Result};

/// The host's device, as it created it.
pub struct HostDevice {
    /// Its instance.
    pub instance: HostInstance,
    /// The physical device it was created on.
    pub physical_device: vk::PhysicalDevice,
    /// The `VkDevice`.
    pub device: vk::Device,
    /// The device extensions it was created with.
    pub extensions: Vec<CString>,
    /// The `VkPhysicalDeviceFeatures2` chain given to `vkCreateDevice` (read by
    /// [`adopt_device`] only: Vulkan has no query for the features a device has enabled).
    pub enabled_features: *const vk::PhysicalDeviceFeatures2<'static>,
    /// The queue Nimbus submits to (it may be the host's own: ordering then follows
    /// submission order).
    pub queue: vk::Queue,
    /// Its family: must be [`QUEUE_FAMILY`].
    pub queue_family_index: u32,
    /// Its index in the family.
    pub queue_index: u32,
    /// Taken around every `vkQueueSubmit` / `vkQueueWaitIdle` Nimbus makes, when given.
    pub queue_lock: Option<Arc<QueueLock>>,
}

/// The host's device seen through wgpu. Dropping it destroys only what Nimbus made.
pub struct AdoptedDevice {
    /// wgpu's instance on the host's `VkInstance`.
    pub instance: wgpu::Instance,
    /// The adapter of the host's physical device.
    pub adapter: wgpu::Adapter,
    /// The device on the host's `VkDevice`.
    pub device: wgpu::Device,
    /// The queue on the host's `VkQueue`.
    pub queue: wgpu::Queue,
}

fn missing_list(what: &str, names: &[String], fix: &str) -> Error {
    Error::Vulkan(format!(
        "the device lacks {what} Nimbus needs: {} ({fix})",
        names.join(", ")
    ))
}

/// Checks the queue family against what wgpu 30 can use.
fn check_queue(instance: &ash::Instance, host: &HostDevice) -> Result<()> {
    if host.queue_family_index != QUEUE_FAMILY {
        return Err(Error::Vulkan(format!(
            "queue family {} cannot be used: wgpu 30 drives queue family {QUEUE_FAMILY} only \
             (nimbus_vulkan_device_requirements_queue_family); create Nimbus's queue there",
            host.queue_family_index
        )));
    }
    // SAFETY: a live physical device of a live instance (the caller's contract).
    let families =
        unsafe { instance.get_physical_device_queue_family_properties(host.physical_device) };
    let Some(family) = families.first() else {
        return Err(Error::Vulkan(
            "the physical device has no queue family".into(),
        ));
    };
    let needed = vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE;
    if !family.queue_flags.contains(needed) {
        return Err(Error::Vulkan(format!(
            "queue family {QUEUE_FAMILY} has {:?}, Nimbus needs GRAPHICS | COMPUTE",
            family.queue_flags
        )));
    }
    if host.queue_index >= family.queue_count {
        return Err(Error::Vulkan(format!(
            "queue index {} is out of range: queue family {QUEUE_FAMILY} has {} queue(s)",
            host.queue_index, family.queue_count
        )));
    }
    Ok(())
}

/// wgpu's instance, adapter, device and queue on the host's objects. Fails, naming it, when the
/// host did not enable an extension or feature Nimbus needs, or gave an unusable queue.
///
/// # Safety
///
/// every handle in `host` must be live and consistent (the device created on the
/// physical device of the instance, with those extensions and that feature chain, the queue
/// obtained from it), and stay alive until the returned device and everything made on it
/// (renderers, textures) are dropped and their GPU work has finished.
pub unsafe fn adopt_device(host: &HostDevice) -> Result<AdoptedDevice> {
    if host.device == vk::Device::null() {
        return Err(Error::Vulkan("the VkDevice is null".into()));
    }
    if host.queue == vk::Queue::null() {
        return Err(Error::Vulkan("the VkQueue is null".into()));
    }
    if host.enabled_features.is_null() {
        return Err(Error::Vulkan(
            "the enabled feature chain is null: pass the VkPhysicalDeviceFeatures2 given to \
             vkCreateDevice (Vulkan cannot be asked which features a device has enabled)"
                .into(),
        ));
    }
    // SAFETY: per the caller.
    let hal_instance = unsafe { host.instance.to_hal() }?;
    let raw_instance = hal_instance.shared_instance().raw_instance().clone();
    let exposed = expose(&hal_instance, host.physical_device)?;
    check_queue(&raw_instance, host)?;
    let (extensions, bits) = device_needs(&exposed)?;
    let missing: Vec<String> = extensions
        .iter()
        .filter(|n| !host.extensions.iter().any(|e| e.as_c_str() == **n))
        .map(|n| n.to_string_lossy().into_owned())
        .collect();
    if !missing.is_empty() {
        return Err(missing_list(
            "extension(s)",
            &missing,
            "add the names nimbus_vulkan_device_requirements_extensions returns",
        ));
    }
    // SAFETY: the host's chain, read only (caller's contract).
    let missing = unsafe { features::missing(&bits, host.enabled_features as *const c_void) }?;
    if !missing.is_empty() {
        let names: Vec<String> = missing.iter().map(|b| b.name()).collect();
        return Err(missing_list(
            "feature(s)",
            &names,
            "merge them with nimbus_vulkan_device_requirements_merge_features",
        ));
    }
    // SAFETY: the device belongs to the instance; the queue is checked just below.
    let (raw_device, token) = unsafe {
        queue_lock::load_device(
            &raw_instance,
            host.device,
            host.queue,
            host.queue_lock.clone(),
        )
    };
    // SAFETY: family and index are in range (check_queue).
    let queue = unsafe { raw_device.get_device_queue(host.queue_family_index, host.queue_index) };
    if queue != host.queue {
        queue_lock::unregister(token);
        return Err(Error::Vulkan(format!(
            "the VkQueue is not queue {} of family {} of this device",
            host.queue_index, host.queue_family_index
        )));
    }
    let wanted = wanted_features(exposed.features);
    let limits = exposed.capabilities.limits.clone();
    // SAFETY: the device was created from this adapter with `extensions` and the feature bits
    // (both checked above). The drop callback keeps wgpu-hal from destroying the host's device;
    // it only forgets the queue lock.
    let open = unsafe {
        exposed.adapter.device_from_raw(
            raw_device,
            Some(Box::new(move || queue_lock::unregister(token))),
            &extensions,
            wanted,
            &limits,
            &wgpu::MemoryHints::Performance,
            host.queue_family_index,
            host.queue_index,
        )
    }
    .map_err(|e| Error::RequestDevice(format!("wgpu-hal cannot adopt the device: {e}")))?;
    // SAFETY: the hal objects were made above from the host's live objects.
    let instance = unsafe { wgpu::Instance::from_hal::<hv::Api>(hal_instance) };
    // SAFETY: as above.
    let adapter = unsafe { instance.create_adapter_from_hal(exposed) };
    // SAFETY: `open` was made from this adapter with `wanted` and `limits`.
    let (device, queue) = unsafe {
        adapter.create_device_from_hal(
            open,
            &wgpu::DeviceDescriptor {
                label: Some("nimbus (host device)"),
                required_features: wanted,
                required_limits: limits,
                ..Default::default()
            },
        )
    }
    .map_err(|e| Error::RequestDevice(e.to_string()))?;
    Ok(AdoptedDevice {
        instance,
        adapter,
        device,
        queue,
    })
}
