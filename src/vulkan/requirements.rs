//! What Nimbus needs of the host's instance and device, asked before the host creates them.

use std::ffi::{CStr, CString};

use ash::vk;
use wgpu::hal;
use wgpu::hal::vulkan as hv;

use super::features::{self, AppendedStructs, FeatureBit};
use super::{wanted_features, QUEUE_FAMILY};
use crate::error::{Error, Result};

/// The oldest instance API version Nimbus accepts (wgpu-hal needs Vulkan 1.1 entry points).
///
/// cbindgen:ignore
pub const MIN_API_VERSION: u32 = vk::API_VERSION_1_1;

/// The instance extensions Nimbus needs: every one wgpu-hal wants that the loader offers
/// (wgpu-hal assumes that an available extension was enabled, so all of them are needed).
/// The names are static. Merge them with your own before `vkCreateInstance`.
pub fn instance_extensions(entry: &ash::Entry) -> Result<Vec<&'static CStr>> {
    // wgpu's own debug flags stay off: the host's validation layer does the validating.
    hv::Instance::desired_extensions(entry, MIN_API_VERSION, wgpu::InstanceFlags::empty())
        .map_err(|e| Error::Vulkan(format!("cannot list the instance extensions: {e}")))
}

/// The host's instance, as it created it.
#[derive(Clone)]
pub struct HostInstance {
    /// The loader entry (e.g. `ash::Entry::from_static_fn` on the host's `vkGetInstanceProcAddr`).
    pub entry: ash::Entry,
    /// The host's `VkInstance`.
    pub instance: vk::Instance,
    /// `VkApplicationInfo::apiVersion` it was created with.
    pub api_version: u32,
    /// The extensions it was created with.
    pub extensions: Vec<CString>,
}

impl HostInstance {
    /// wgpu-hal's instance on the host's one, never destroying it; fails naming the
    /// extensions the host did not enable.
    ///
    /// # Safety
    ///
    /// `instance` must be a live instance created from `entry` with these extensions
    /// and API version, and stay alive while the returned instance (and anything made from
    /// it) lives.
    pub(crate) unsafe fn to_hal(&self) -> Result<hv::Instance> {
        if self.instance == vk::Instance::null() {
            return Err(Error::Vulkan("the VkInstance is null".into()));
        }
        if self.api_version < MIN_API_VERSION {
            return Err(Error::Vulkan(format!(
                "the instance was created with apiVersion {}, Nimbus needs Vulkan 1.1 or newer \
                 (VK_API_VERSION_1_1)",
                version_name(self.api_version)
            )));
        }
        let desired = instance_extensions(&self.entry)?;
        let missing: Vec<_> = desired
            .iter()
            .filter(|d| !self.extensions.iter().any(|e| e.as_c_str() == **d))
            .map(|d| d.to_string_lossy().into_owned())
            .collect();
        if !missing.is_empty() {
            return Err(Error::Vulkan(format!(
                "the instance lacks extension(s) Nimbus needs: {} (add the names \
                 nimbus_vulkan_instance_extensions returns)",
                missing.join(", ")
            )));
        }
        // SAFETY: the instance was created from `entry` (caller's contract).
        let raw = unsafe { ash::Instance::load(self.entry.static_fn(), self.instance) };
        // SAFETY: created with `desired` enabled (checked above) and `api_version`; the drop
        // callback keeps wgpu-hal from destroying the host's instance.
        unsafe {
            hv::Instance::from_raw(
                self.entry.clone(),
                raw,
                self.api_version,
                0,
                None,
                desired,
                wgpu::InstanceFlags::empty(),
                wgpu::MemoryBudgetThresholds::default(),
                false,
                Some(Box::new(|| ())),
            )
        }
        .map_err(|e| Error::Vulkan(format!("wgpu-hal cannot use the instance: {e}")))
    }
}

pub(crate) fn version_name(v: u32) -> String {
    format!(
        "{}.{}.{}",
        vk::api_version_major(v),
        vk::api_version_minor(v),
        vk::api_version_patch(v)
    )
}

/// wgpu-hal's adapter on a physical device, or why it cannot be one.
pub(crate) fn expose(
    instance: &hv::Instance,
    physical_device: vk::PhysicalDevice,
) -> Result<hal::ExposedAdapter<hv::Api>> {
    if physical_device == vk::PhysicalDevice::null() {
        return Err(Error::Vulkan("the VkPhysicalDevice is null".into()));
    }
    instance.expose_adapter(physical_device).ok_or_else(|| {
        Error::Vulkan(
            "wgpu cannot use this physical device (it needs Vulkan 1.1 or \
             VK_KHR_maintenance1, and queue family 0 with graphics)"
                .into(),
        )
    })
}

/// What one physical device needs enabled for Nimbus: extensions, feature bits, the queue
/// family. When you merged its features, keep it alive as long as the merged chain is used
/// (`vkCreateDevice`, and [`super::HostDevice::enabled_features`] at adoption): structs it
/// appended to the chain live in it.
pub struct DeviceRequirements {
    extensions: Vec<&'static CStr>,
    bits: Vec<FeatureBit>,
    appended: AppendedStructs,
}

impl DeviceRequirements {
    /// The requirements of `physical_device` of the host's instance.
    ///
    /// # Safety
    ///
    /// as [`HostInstance`]'s fields promise; `physical_device` belongs to it.
    pub unsafe fn new(
        instance: &HostInstance,
        physical_device: vk::PhysicalDevice,
    ) -> Result<Self> {
        // SAFETY: per the caller.
        let hal_instance = unsafe { instance.to_hal() }?;
        let exposed = expose(&hal_instance, physical_device)?;
        let (extensions, bits) = device_needs(&exposed)?;
        Ok(Self {
            extensions,
            bits,
            appended: AppendedStructs::default(),
        })
    }

    /// The device extensions to enable (static names; merge them with yours).
    pub fn extensions(&self) -> &[&'static CStr] {
        &self.extensions
    }

    /// The feature bits to enable.
    pub fn features(&self) -> &[FeatureBit] {
        &self.bits
    }

    /// The queue family Nimbus's queue must come from.
    pub fn queue_family(&self) -> u32 {
        QUEUE_FAMILY
    }

    /// Sets Nimbus's feature bits in the host's `VkPhysicalDeviceFeatures2` chain (in structs
    /// already there, promoted bits in `VkPhysicalDeviceVulkan1xFeatures`), appending structs
    /// owned by `self` for bits with no home; keep `self` alive until `vkCreateDevice`.
    ///
    /// # Safety
    ///
    /// `features2` points to a valid, writable `VkPhysicalDeviceFeatures2` chain.
    pub unsafe fn merge_features(
        &mut self,
        features2: *mut vk::PhysicalDeviceFeatures2<'static>,
    ) -> Result<()> {
        // SAFETY: per the caller.
        unsafe { features::merge(&self.bits, features2, &mut self.appended) }
    }
}

/// The device extensions and feature bits wgpu-hal needs on an adapter for Nimbus's features.
pub(crate) fn device_needs(
    exposed: &hal::ExposedAdapter<hv::Api>,
) -> Result<(Vec<&'static CStr>, Vec<FeatureBit>)> {
    let wanted = wanted_features(exposed.features);
    let extensions = exposed.adapter.required_device_extensions(wanted);
    let mut phd_features = exposed
        .adapter
        .physical_device_features(&extensions, wanted);
    let info = phd_features.add_to_device_create(vk::DeviceCreateInfo::default());
    // SAFETY: wgpu-hal built the chain from structs `phd_features` owns, alive here.
    let bits = unsafe { features::bits_of_create_info(&info) }?;
    Ok((extensions, bits))
}
