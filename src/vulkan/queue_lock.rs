//! The host's queue lock around every Vulkan call of Nimbus that touches its queue.
//!
//! Vulkan requires external synchronisation of a `VkQueue` (vkQueueSubmit, vkQueueWaitIdle).
//! wgpu-hal calls them through the `ash::Device` it is given, so the adopted device is loaded
//! with wrapped entry points that take the host's lock around the real ones. Vulkan function
//! pointers carry no user data: the wrappers find the lock by the queue handle they are called
//! with, in a process-wide registry.

use std::sync::{Arc, Mutex};

use ash::vk;

/// The host's lock and unlock for its queue, called around each queue call Nimbus makes.
pub struct QueueLock {
    lock: Box<dyn Fn() + Send + Sync>,
    unlock: Box<dyn Fn() + Send + Sync>,
}

impl QueueLock {
    /// A lock from two callbacks. They must not call into Nimbus.
    pub fn new(
        lock: impl Fn() + Send + Sync + 'static,
        unlock: impl Fn() + Send + Sync + 'static,
    ) -> Self {
        Self {
            lock: Box::new(lock),
            unlock: Box::new(unlock),
        }
    }

    fn around<T>(&self, f: impl FnOnce() -> T) -> T {
        (self.lock)();
        let out = f();
        (self.unlock)();
        out
    }
}

struct Entry {
    token: u64,
    queue: vk::Queue,
    lock: Arc<QueueLock>,
    submit: vk::PFN_vkQueueSubmit,
    wait_idle: vk::PFN_vkQueueWaitIdle,
}

static REGISTRY: Mutex<Vec<Entry>> = Mutex::new(Vec::new());
static NEXT_TOKEN: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

fn registry() -> std::sync::MutexGuard<'static, Vec<Entry>> {
    REGISTRY.lock().unwrap_or_else(|p| p.into_inner())
}

/// The lock and real entry points for `queue` (the latest registration wins).
fn find(
    queue: vk::Queue,
) -> Option<(
    Arc<QueueLock>,
    vk::PFN_vkQueueSubmit,
    vk::PFN_vkQueueWaitIdle,
)> {
    registry()
        .iter()
        .rev()
        .find(|e| e.queue == queue)
        .map(|e| (e.lock.clone(), e.submit, e.wait_idle))
}

unsafe extern "system" fn locked_queue_submit(
    queue: vk::Queue,
    submit_count: u32,
    submits: *const vk::SubmitInfo<'_>,
    fence: vk::Fence,
) -> vk::Result {
    match find(queue) {
        // SAFETY: the real vkQueueSubmit with the caller's arguments.
        Some((lock, submit, _)) => {
            lock.around(|| unsafe { submit(queue, submit_count, submits, fence) })
        }
        None => vk::Result::ERROR_INITIALIZATION_FAILED,
    }
}

unsafe extern "system" fn locked_queue_wait_idle(queue: vk::Queue) -> vk::Result {
    match find(queue) {
        // SAFETY: the real vkQueueWaitIdle.
        Some((lock, _, wait_idle)) => lock.around(|| unsafe { wait_idle(queue) }),
        None => vk::Result::ERROR_INITIALIZATION_FAILED,
    }
}

/// Loads the device's entry points, routing the queue calls through `lock` when there is one.
/// Returns the device and the registration token to pass to [`unregister`] (0: none).
///
/// Safety: `device` was created from `instance`; `queue` is its queue.
pub(crate) unsafe fn load_device(
    instance: &ash::Instance,
    device: vk::Device,
    queue: vk::Queue,
    lock: Option<Arc<QueueLock>>,
) -> (ash::Device, u64) {
    let gdpa = instance.fp_v1_0().get_device_proc_addr;
    let real = |name: &std::ffi::CStr| {
        // SAFETY: a valid device and a NUL-terminated name.
        unsafe { gdpa(device, name.as_ptr()) }
    };
    let Some(lock) = lock else {
        // SAFETY: `device` belongs to `instance`.
        return (unsafe { ash::Device::load(instance.fp_v1_0(), device) }, 0);
    };
    let (Some(submit), Some(wait_idle)) = (real(c"vkQueueSubmit"), real(c"vkQueueWaitIdle")) else {
        // SAFETY: as above; without the core entry points nothing can be wrapped.
        return (unsafe { ash::Device::load(instance.fp_v1_0(), device) }, 0);
    };
    let token = NEXT_TOKEN.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    registry().push(Entry {
        token,
        queue,
        lock,
        // SAFETY: the driver's own vkQueueSubmit / vkQueueWaitIdle, cast to their types.
        submit: unsafe {
            std::mem::transmute::<unsafe extern "system" fn(), vk::PFN_vkQueueSubmit>(submit)
        },
        // SAFETY: as above.
        wait_idle: unsafe {
            std::mem::transmute::<unsafe extern "system" fn(), vk::PFN_vkQueueWaitIdle>(wait_idle)
        },
    });
    let load = |name: &std::ffi::CStr| -> *const std::ffi::c_void {
        if name == c"vkQueueSubmit" {
            locked_queue_submit as *const std::ffi::c_void
        } else if name == c"vkQueueWaitIdle" {
            locked_queue_wait_idle as *const std::ffi::c_void
        } else {
            real(name).map_or(std::ptr::null(), |f| f as *const std::ffi::c_void)
        }
    };
    // SAFETY: every pointer is the driver's or a wrapper of the same signature.
    (unsafe { ash::Device::load_with(load, device) }, token)
}

/// Forgets a registration (when the adopted device is dropped).
pub(crate) fn unregister(token: u64) {
    if token != 0 {
        registry().retain(|e| e.token != token);
    }
}
