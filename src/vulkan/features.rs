//! Vulkan feature bits: which ones wgpu-hal needs on a device, merging them into a host's own
//! `VkPhysicalDeviceFeatures2` chain, and checking a host's chain for them.
//!
//! wgpu-hal describes its needs as a chain of per-feature structs
//! (`PhysicalDeviceFeatures::add_to_device_create`). A host that already chains
//! `VkPhysicalDeviceVulkan12Features` may not also chain `VkPhysicalDeviceTimelineSemaphoreFeatures`
//! (VUID-VkDeviceCreateInfo-pNext-02830), so the bits are merged one by one: into the struct of
//! the same type when the host has one, else into the `VkPhysicalDeviceVulkan1xFeatures` the
//! feature was promoted to (members keep their names on promotion), else into a copy that is
//! appended to the chain.

use std::ffi::c_void;

use ash::vk;

use super::feature_table::{CORE, STRUCTS};
use crate::error::{Error, Result};

/// One Vulkan feature struct of the table: its type, size and VkBool32 members.
pub(crate) struct FeatureStruct {
    pub(crate) name: &'static str,
    pub(crate) s_type: vk::StructureType,
    pub(crate) size: usize,
    /// The core version (11, 12, 13) whose `VkPhysicalDeviceVulkan1xFeatures` holds these
    /// members since their promotion, if any.
    pub(crate) promoted_to: Option<u32>,
    pub(crate) members: &'static [&'static str],
}

/// Where a feature struct's VkBool32 members start (after sType and pNext).
const MEMBERS_OFFSET: usize = 16;
/// Longest chain walked: a longer one is taken for a cycle.
const MAX_CHAIN: usize = 64;

/// One feature bit Nimbus needs: a member of `VkPhysicalDeviceFeatures` (`structure` None) or
/// of a feature struct of the table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FeatureBit {
    structure: Option<usize>,
    member: usize,
}

impl FeatureBit {
    /// The Vulkan member name, e.g. `timelineSemaphore`.
    pub fn member_name(&self) -> &'static str {
        match self.structure {
            None => CORE[self.member],
            Some(s) => STRUCTS[s].members[self.member],
        }
    }

    /// The struct and member, e.g. `VkPhysicalDeviceTimelineSemaphoreFeatures::timelineSemaphore`.
    pub fn name(&self) -> String {
        let owner = self
            .structure
            .map_or("VkPhysicalDeviceFeatures", |s| STRUCTS[s].name);
        format!("{owner}::{}", self.member_name())
    }
}

fn table_index(s_type: vk::StructureType) -> Option<usize> {
    STRUCTS.iter().position(|s| s.s_type == s_type)
}

fn core_struct(version: u32) -> usize {
    let name = match version {
        11 => "VkPhysicalDeviceVulkan11Features",
        12 => "VkPhysicalDeviceVulkan12Features",
        _ => "VkPhysicalDeviceVulkan13Features",
    };
    STRUCTS
        .iter()
        .position(|s| s.name == name)
        .expect("the table has the Vulkan 1.1 to 1.3 structs")
}

/// Reads the VkBool32 at `offset` bytes into a struct.
///
/// Safety: `base` points to a struct at least `offset + 4` bytes long.
unsafe fn bool_at(base: *const u8, offset: usize) -> bool {
    // SAFETY: in bounds per the caller; VkBool32 members are 4-byte aligned.
    unsafe { (base.add(offset) as *const vk::Bool32).read() != 0 }
}

/// The bits set in a device create info's `pEnabledFeatures` and feature chain (how wgpu-hal
/// hands out its needs).
///
/// Safety: `info`'s pointers must be valid, as for `vkCreateDevice`.
pub(crate) unsafe fn bits_of_create_info(info: &vk::DeviceCreateInfo) -> Result<Vec<FeatureBit>> {
    let mut bits = Vec::new();
    if !info.p_enabled_features.is_null() {
        let core = info.p_enabled_features as *const u8;
        for member in 0..CORE.len() {
            // SAFETY: VkPhysicalDeviceFeatures is CORE.len() VkBool32s.
            if unsafe { bool_at(core, member * 4) } {
                bits.push(FeatureBit {
                    structure: None,
                    member,
                });
            }
        }
    }
    let mut next = info.p_next as *const vk::BaseInStructure;
    let mut walked = 0;
    while !next.is_null() && walked < MAX_CHAIN {
        // SAFETY: a valid chain, per the caller.
        let header = unsafe { &*next };
        let index = table_index(header.s_type).ok_or_else(|| {
            Error::Vulkan(format!(
                "wgpu-hal asks for a feature struct Nimbus cannot merge (sType {})",
                header.s_type.as_raw()
            ))
        })?;
        for member in 0..STRUCTS[index].members.len() {
            // SAFETY: the struct is STRUCTS[index].size bytes, members within it.
            if unsafe { bool_at(next as *const u8, MEMBERS_OFFSET + member * 4) } {
                bits.push(FeatureBit {
                    structure: Some(index),
                    member,
                });
            }
        }
        next = header.p_next;
        walked += 1;
    }
    Ok(bits)
}

/// A host's `VkPhysicalDeviceFeatures2` chain, walked once.
struct HostChain {
    head: *mut vk::PhysicalDeviceFeatures2<'static>,
    /// Every struct after the head, in order.
    links: Vec<*mut vk::BaseOutStructure<'static>>,
}

impl HostChain {
    /// Safety: `head` points to a valid `VkPhysicalDeviceFeatures2` whose chain is valid.
    unsafe fn walk(head: *mut vk::PhysicalDeviceFeatures2<'static>) -> Result<Self> {
        // SAFETY: valid per the caller.
        let first = unsafe { &*head };
        if first.s_type != vk::StructureType::PHYSICAL_DEVICE_FEATURES_2 {
            return Err(Error::Vulkan(format!(
                "the feature chain must start with a VkPhysicalDeviceFeatures2 \
                 (sType {}), got sType {}",
                vk::StructureType::PHYSICAL_DEVICE_FEATURES_2.as_raw(),
                first.s_type.as_raw()
            )));
        }
        let mut links = Vec::new();
        let mut next = first.p_next as *mut vk::BaseOutStructure<'static>;
        while !next.is_null() {
            if links.len() == MAX_CHAIN {
                return Err(Error::Vulkan(
                    "the feature chain is longer than 64 structs (a cycle?)".into(),
                ));
            }
            links.push(next);
            // SAFETY: a valid chain, per the caller.
            next = unsafe { (*next).p_next };
        }
        Ok(Self { head, links })
    }

    fn find(&self, s_type: vk::StructureType) -> Option<*mut u8> {
        self.links
            .iter()
            // SAFETY: every link is a valid struct header (walk's contract).
            .find(|l| unsafe { (***l).s_type } == s_type)
            .map(|l| *l as *mut u8)
    }

    /// Where the host's chain holds `bit`, if anywhere.
    fn locate(&self, bit: FeatureBit) -> Option<*mut vk::Bool32> {
        let Some(index) = bit.structure else {
            // SAFETY: the head is valid; `features` is VkPhysicalDeviceFeatures.
            let core = unsafe { &raw mut (*self.head).features } as *mut u8;
            // SAFETY: member < CORE.len(), within the struct.
            return Some(unsafe { core.add(bit.member * 4) } as *mut vk::Bool32);
        };
        let table = &STRUCTS[index];
        if let Some(base) = self.find(table.s_type) {
            // SAFETY: the host's struct of this type has these members.
            return Some(unsafe { base.add(MEMBERS_OFFSET + bit.member * 4) } as *mut vk::Bool32);
        }
        let core = &STRUCTS[core_struct(table.promoted_to?)];
        let base = self.find(core.s_type)?;
        let member = core
            .members
            .iter()
            .position(|m| *m == table.members[bit.member])?;
        // SAFETY: as above, in the promoted core struct.
        Some(unsafe { base.add(MEMBERS_OFFSET + member * 4) } as *mut vk::Bool32)
    }
}

/// Feature structs Nimbus appended to a host's chain: they must live until `vkCreateDevice`.
#[derive(Default)]
pub(crate) struct AppendedStructs {
    storage: Vec<Box<[u64]>>,
}

// SAFETY: plain memory, only ever read by the Vulkan driver through the host's chain.
unsafe impl Send for AppendedStructs {}
// SAFETY: as above.
unsafe impl Sync for AppendedStructs {}

/// Sets every bit in the host's chain, appending structs (kept in `appended`) for bits with no
/// home there.
///
/// Safety: `head` points to a valid, writable `VkPhysicalDeviceFeatures2` chain.
pub(crate) unsafe fn merge(
    bits: &[FeatureBit],
    head: *mut vk::PhysicalDeviceFeatures2<'static>,
    appended: &mut AppendedStructs,
) -> Result<()> {
    // SAFETY: per the caller.
    let mut chain = unsafe { HostChain::walk(head) }?;
    for &bit in bits {
        if let Some(slot) = chain.locate(bit) {
            // SAFETY: `locate` points into the host's writable struct.
            unsafe { slot.write(vk::TRUE) };
            continue;
        }
        let index = bit.structure.expect("core bits always have a home");
        let table = &STRUCTS[index];
        let mut block = vec![0u64; table.size.div_ceil(8)].into_boxed_slice();
        let base = block.as_mut_ptr() as *mut vk::BaseOutStructure<'static>;
        // SAFETY: the block is at least the struct's size and 8-byte aligned.
        unsafe {
            (*base).s_type = table.s_type;
            (*base).p_next = std::ptr::null_mut();
        }
        let tail = chain
            .links
            .last()
            .copied()
            .unwrap_or(head as *mut vk::BaseOutStructure<'static>);
        // SAFETY: the tail is the host's last struct (or the head); linking ours after it.
        unsafe { (*tail).p_next = base };
        chain.links.push(base);
        appended.storage.push(block);
        let slot = chain
            .locate(bit)
            .expect("the appended struct holds the bit");
        // SAFETY: inside our own block.
        unsafe { slot.write(vk::TRUE) };
    }
    Ok(())
}

/// The bits of `bits` the host's chain does not enable.
///
/// Safety: `head` points to a valid `VkPhysicalDeviceFeatures2` chain (only read).
pub(crate) unsafe fn missing(bits: &[FeatureBit], head: *const c_void) -> Result<Vec<FeatureBit>> {
    // SAFETY: per the caller; only read.
    let chain = unsafe { HostChain::walk(head as *mut vk::PhysicalDeviceFeatures2<'static>) }?;
    Ok(bits
        .iter()
        .copied()
        // SAFETY: `locate` points into the host's struct.
        .filter(|b| {
            chain
                .locate(*b)
                .is_none_or(|slot| unsafe { slot.read() } == 0)
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_matches_the_structs() {
        for s in STRUCTS {
            let packed = MEMBERS_OFFSET + s.members.len() * 4;
            assert_eq!(s.size, packed.div_ceil(8) * 8, "{}", s.name);
        }
        assert_eq!(
            CORE.len() * 4,
            std::mem::size_of::<vk::PhysicalDeviceFeatures>()
        );
    }

    fn bit(name: &str, member: &str) -> FeatureBit {
        let structure = STRUCTS.iter().position(|s| s.name == name).unwrap();
        let member = STRUCTS[structure]
            .members
            .iter()
            .position(|m| *m == member)
            .unwrap();
        FeatureBit {
            structure: Some(structure),
            member,
        }
    }

    #[test]
    fn promoted_bits_go_into_the_hosts_vulkan12_struct() {
        let timeline = bit(
            "VkPhysicalDeviceTimelineSemaphoreFeatures",
            "timelineSemaphore",
        );
        let robust2 = bit(
            "VkPhysicalDeviceRobustness2FeaturesEXT",
            "robustBufferAccess2",
        );
        let core = FeatureBit {
            structure: None,
            member: CORE
                .iter()
                .position(|m| *m == "robustBufferAccess")
                .unwrap(),
        };
        let mut v12 = vk::PhysicalDeviceVulkan12Features::default();
        let mut head = vk::PhysicalDeviceFeatures2 {
            p_next: &raw mut v12 as *mut c_void,
            ..Default::default()
        };
        let head_ptr: *mut vk::PhysicalDeviceFeatures2<'static> = (&raw mut head).cast();
        let bits = [timeline, robust2, core];
        // SAFETY: a valid two-struct chain on the stack.
        assert_eq!(
            unsafe { missing(&bits, head_ptr as *const c_void) }
                .unwrap()
                .len(),
            3
        );
        let mut appended = AppendedStructs::default();
        // SAFETY: as above.
        unsafe { merge(&bits, head_ptr, &mut appended) }.unwrap();
        assert_eq!(
            v12.timeline_semaphore,
            vk::TRUE,
            "merged into Vulkan12Features"
        );
        assert_eq!(head.features.robust_buffer_access, vk::TRUE);
        // Robustness2 has no core home: one struct appended after the host's last.
        assert_eq!(appended.storage.len(), 1);
        assert!(!v12.p_next.is_null());
        // SAFETY: the appended struct is alive in `appended`.
        let r2 = unsafe { &*(v12.p_next as *const vk::PhysicalDeviceRobustness2FeaturesEXT) };
        assert_eq!(
            r2.s_type,
            vk::StructureType::PHYSICAL_DEVICE_ROBUSTNESS_2_FEATURES_EXT
        );
        assert_eq!(r2.robust_buffer_access2, vk::TRUE);
        assert_eq!(r2.robust_image_access2, vk::FALSE);
        // SAFETY: as above.
        assert!(unsafe { missing(&bits, head_ptr as *const c_void) }
            .unwrap()
            .is_empty());
    }

    #[test]
    fn same_type_struct_is_used_and_wrong_head_refused() {
        let timeline = bit(
            "VkPhysicalDeviceTimelineSemaphoreFeatures",
            "timelineSemaphore",
        );
        let mut ts = vk::PhysicalDeviceTimelineSemaphoreFeatures::default();
        let mut head = vk::PhysicalDeviceFeatures2 {
            p_next: &raw mut ts as *mut c_void,
            ..Default::default()
        };
        let head_ptr: *mut vk::PhysicalDeviceFeatures2<'static> = (&raw mut head).cast();
        let mut appended = AppendedStructs::default();
        // SAFETY: a valid chain on the stack.
        unsafe { merge(&[timeline], head_ptr, &mut appended) }.unwrap();
        assert_eq!(ts.timeline_semaphore, vk::TRUE);
        assert!(appended.storage.is_empty());
        let missing_name = timeline.name();
        assert!(
            missing_name.ends_with("::timelineSemaphore"),
            "{missing_name}"
        );
        let mut wrong = vk::PhysicalDeviceVulkan12Features::default();
        // SAFETY: reads the sType only, then refuses.
        let err = unsafe { missing(&[timeline], &raw mut wrong as *const c_void) }.unwrap_err();
        assert!(
            err.to_string().contains("VkPhysicalDeviceFeatures2"),
            "{err}"
        );
    }
}
