//! Nimbus on the host's own Vulkan device: the requirement queries a host makes before it
//! creates its instance and device, the adoption of that device by wgpu (never destroying a
//! host object), and the host's images wrapped per frame, composited in place.
//!
//! The order of calls: [`instance_extensions`] → the host creates its `VkInstance` →
//! [`DeviceRequirements::new`] for the chosen physical device → the host merges
//! [`DeviceRequirements::extensions`] and [`DeviceRequirements::merge_features`] into its
//! `vkCreateDevice` → [`adopt_device`] → a [`crate::Renderer`] on the adopted device, fed each
//! frame through [`HostFrame`]. The C API (`src/ffi/vulkan.rs`) translates onto exactly this.
//!
//! Built on wgpu-hal 30 (`Instance::from_raw`, `expose_adapter`, `Adapter::device_from_raw`,
//! `Device::texture_from_raw`) and wgpu (`Instance::from_hal`, `create_adapter_from_hal`,
//! `create_device_from_hal`, `create_texture_from_hal`), always with drop callbacks.

mod adopt;
pub(crate) mod feature_table;
mod features;
mod image;
mod queue_lock;
mod requirements;
mod shadow_image;

/// The `ash` crate wgpu-hal is built on, for Rust hosts on ash.
pub use ash;

pub use adopt::{adopt_device, AdoptedDevice, HostDevice};
pub use features::FeatureBit;
pub use image::{HostFrame, HostImage, ImageRole, Semaphore, ACCEPTED_LAYOUTS};
pub use queue_lock::QueueLock;
pub use requirements::{instance_extensions, DeviceRequirements, HostInstance, MIN_API_VERSION};
pub use shadow_image::{shadow_map_image, SHADOW_MAP_FORMAT, SHADOW_MAP_LAYOUT, SHADOW_MAP_USAGE};

/// The only queue family wgpu 30 can use: `expose_adapter` inspects family 0 alone.
///
/// cbindgen:ignore
pub const QUEUE_FAMILY: u32 = 0;

pub(crate) use crate::device::wanted_features;
