//! The C entry points' argument decoding on arbitrary input: context descriptors with chains
//! of any shape (unknown, repeated, cyclic links; every field), window handles of any
//! platform, frames of any numbers and flags, and the device-free calls with any enum values
//! and buffer sizes. Every outcome must be a known result code with a message; never a panic
//! (a caught panic is NIMBUS_ERROR_PANIC, which fails here).
#![no_main]

use std::ffi::CStr;

use nimbus::ffi::*;

#[path = "bytes.rs"]
mod bytes;
use bytes::Bytes;

/// Raw bits a third of the time (NaN, infinities, denormals), else a plain integer value.
fn number(b: &mut Bytes) -> f32 {
    let v = b.u32();
    if v % 3 == 0 {
        f32::from_bits(v)
    } else {
        (v % 100_000) as f32
    }
}

fn check(code: NimbusResult) {
    assert_ne!(code, NimbusResult::NIMBUS_ERROR_PANIC, "a panic was caught");
    if (code as i32) < 0 {
        // SAFETY: the library returns a valid C string.
        let msg = unsafe { CStr::from_ptr(nimbus_context_last_error(std::ptr::null())) };
        assert!(!msg.to_bytes().is_empty(), "{code:?} without a message");
    }
}

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let mut b = Bytes(data);
    // A chain of up to four links over a fixed pool, linked in any order, cycles included.
    let mut settings = [NimbusSettingsExt {
        chain: NimbusChainedStruct {
            s_type: 0,
            next: std::ptr::null(),
        },
        initial_preset: 0,
        noise_seed: 0,
        march_max_steps: 0,
        march_min_steps: 0,
        jitter: 0,
        max_distance: 0.0,
        planet_radius: 0.0,
    }; 4];
    for s in settings.iter_mut() {
        s.chain.s_type =
            [NIMBUS_STYPE_SETTINGS, NIMBUS_STYPE_QUALITY, b.u32()][b.small(3) as usize];
        // NimbusVulkanDeviceExt holds the host's Vulkan handles and pointers, which bytes
        // cannot stand for: the C test covers it.
        // A NimbusNoiseCacheExt points at the host's bytes: it gets a link of its own below.
        if s.chain.s_type == NIMBUS_STYPE_VULKAN_DEVICE
            || s.chain.s_type == NIMBUS_STYPE_NOISE_CACHE
        {
            s.chain.s_type = 0;
        }
        s.initial_preset = b.small(8);
        s.noise_seed = b.u32();
        s.march_max_steps = b.small(1500);
        s.march_min_steps = b.small(1500);
        s.jitter = b.small(4);
        s.max_distance = number(&mut b);
        s.planet_radius = number(&mut b);
    }
    // NimbusSettingsExt is the larger struct: a quality link read from it stays in bounds.
    let base = settings.as_mut_ptr();
    let links = b.small(5) as usize;
    for i in 0..4 {
        let next = if i + 1 < links {
            b.small(4) as usize
        } else {
            usize::MAX
        };
        // SAFETY: indices are in the pool.
        unsafe {
            (*base.add(i)).chain.next = if next == usize::MAX {
                std::ptr::null()
            } else {
                base.add(next).cast()
            };
        }
    }
    // Sometimes a noise-cache link in front, over the input's own bytes (its header and
    // checksum parsed like any cache), with any flags and a size within them.
    let cache_len = b.small(4096) as usize;
    let cache_bytes: Vec<u8> = b.0.iter().rev().take(cache_len).copied().collect();
    let cache = NimbusNoiseCacheExt {
        chain: NimbusChainedStruct {
            s_type: NIMBUS_STYPE_NOISE_CACHE,
            next: if links == 0 {
                std::ptr::null()
            } else {
                base.cast()
            },
        },
        data: if b.small(8) == 0 {
            std::ptr::null()
        } else {
            cache_bytes.as_ptr().cast()
        },
        size: b.small(cache_bytes.len() as u32 + 1) as usize,
        flags: b.small(4),
        reserved: b.small(2),
    };
    let with_cache = b.small(3) == 0;
    let window = NimbusWindowHandle {
        platform: b.small(6),
        // Never dereferenced before a device exists, which the decoder does not reach.
        display: if b.small(2) == 0 {
            std::ptr::null_mut()
        } else {
            0x1000 as *mut _
        },
        window: b.u32() as u64 % 3,
        surface: if b.small(2) == 0 {
            std::ptr::null_mut()
        } else {
            0x2000 as *mut _
        },
    };
    let abi = match b.small(4) {
        0 => NIMBUS_ABI_VERSION,
        1 => (NIMBUS_VERSION_MAJOR << 16) | 1,
        _ => b.u32(),
    };
    let desc = NimbusContextDesc {
        next: if with_cache {
            &cache.chain
        } else if links == 0 {
            std::ptr::null()
        } else {
            base.cast()
        },
        abi_version: abi,
        width: b.small(10_000),
        height: b.small(10_000),
        window: if b.small(2) == 0 {
            std::ptr::null()
        } else {
            &window
        },
    };
    // SAFETY: every pointer in `desc` is NULL, into `settings`, `cache` (its data within
    // `cache_bytes`), or `window`.
    check(unsafe { nimbus::ffi::fuzzing::decode_desc(&desc) });

    let mut frame = NimbusFrame {
        next: std::ptr::null(),
        view: [0.0; 16],
        projection: [0.0; 16],
        depth_flags: b.small(16),
        sun_direction: [number(&mut b), number(&mut b), number(&mut b)],
        sun_color: [number(&mut b), number(&mut b), number(&mut b)],
        sun_illuminance: number(&mut b),
        time: number(&mut b) as f64,
    };
    for v in frame.view.iter_mut().chain(frame.projection.iter_mut()) {
        *v = number(&mut b) / 1000.0;
    }
    if b.small(2) == 0 {
        frame.next = base.cast();
    }
    check(nimbus::ffi::fuzzing::decode_frame(&frame));

    // Device-free entry points with any values.
    let mut size = b.small(4096) as usize;
    let mut buf = vec![0 as std::ffi::c_char; size];
    let ptr = if b.small(2) == 0 {
        std::ptr::null_mut()
    } else {
        buf.as_mut_ptr()
    };
    // SAFETY: `ptr` is NULL or `size` writable bytes.
    check(unsafe { nimbus_preset_write_toml(b.small(8), b.small(8), ptr, &mut size) });
    // SAFETY: static strings.
    let name = unsafe { CStr::from_ptr(nimbus_result_name(b.u32() as i32)) };
    assert!(!name.to_bytes().is_empty());
    check(nimbus_set_log_callback(
        None,
        std::ptr::null_mut(),
        b.small(8) as i32 - 1,
    ));
});
