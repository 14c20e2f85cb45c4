//! Result codes: one typed C enum with stable values in reserved blocks (rustls-ffi's
//! `rustls_result` is the model), and functions that name and explain a code.

use std::ffi::c_char;

/// The result of every fallible call. Values are stable forever; new codes take new values in
/// their block:
///
/// - 0: success; 1 to 99: statuses that are not errors;
/// - -1 to -99: errors in the call's arguments or in what they describe;
/// - -100 to -199: errors inside Nimbus (a caught panic and what it leaves);
/// - -200 to -299: the GPU device (its loss).
///
/// Functions return it as a 32-bit integer (`NimbusResult` is a typedef of `int32_t`), so an
/// older library's codes and a newer header's compare as plain numbers.
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[allow(non_camel_case_types)]
pub enum NimbusResult {
    /// Success.
    NIMBUS_OK = 0,
    /// The frame was not presented (window minimised, surface outdated or lost and
    /// reconfigured); render again next frame. Not an error.
    NIMBUS_STATUS_FRAME_SKIPPED = 1,
    /// A required pointer argument was NULL.
    NIMBUS_ERROR_NULL_POINTER = -1,
    /// An argument is out of range, NaN, or an unknown enum value or flag.
    NIMBUS_ERROR_INVALID_ARGUMENT = -2,
    /// A chained struct has an unknown `s_type`, or appears where it does not belong.
    NIMBUS_ERROR_UNKNOWN_STRUCT = -3,
    /// The header's ABI version cannot be served by this library (see NIMBUS_ABI_VERSION).
    NIMBUS_ERROR_ABI_VERSION = -4,
    /// A setting is out of range, alone or in combination with another.
    NIMBUS_ERROR_INVALID_SETTINGS = -5,
    /// The camera, sun or time of a frame is unusable (NaN, non-invertible, mismatched flags).
    NIMBUS_ERROR_INVALID_FRAME = -6,
    /// A texture or target has the wrong size, format or role, belongs to another context, or
    /// a data size does not match.
    NIMBUS_ERROR_INVALID_TARGET = -7,
    /// No GPU adapter was found (install Mesa's software Vulkan on machines without a GPU).
    NIMBUS_ERROR_NO_ADAPTER = -8,
    /// The GPU device could not be created, or reported a validation or out-of-memory error.
    NIMBUS_ERROR_GPU = -9,
    /// A preset file is missing, too large or malformed (the message names the line and field).
    NIMBUS_ERROR_PRESET_FILE = -10,
    /// A weather request is unusable (bad duration, earlier than the running transition).
    NIMBUS_ERROR_WEATHER = -11,
    /// The window surface could not be created or configured.
    NIMBUS_ERROR_SURFACE = -12,
    /// The host's Vulkan instance or device lacks an API version, extension, feature or queue
    /// Nimbus needs, or describes it inconsistently (since ABI 0.3; the message names it).
    NIMBUS_ERROR_VULKAN_REQUIREMENT = -13,
    /// The output asked for is not there: the feature that makes it is off, or no frame has
    /// rendered it yet (since ABI 0.5).
    NIMBUS_ERROR_NOT_READY = -14,
    /// A noise cache is malformed, damaged, from another Nimbus bake, or holds other volumes
    /// than the settings ask for (since ABI 0.6).
    NIMBUS_ERROR_NOISE_CACHE = -15,
    /// A panic inside Nimbus was caught; the context is now poisoned.
    NIMBUS_ERROR_PANIC = -100,
    /// The context was poisoned by an earlier panic; only nimbus_context_destroy remains.
    NIMBUS_ERROR_POISONED = -101,
    /// The GPU device was lost (driver reset, device removed or destroyed). The context can
    /// only be destroyed; create a new one.
    NIMBUS_ERROR_DEVICE_LOST = -200,
}

/// Every code, for the name and message lookups and their tests.
pub(crate) const ALL_RESULTS: &[NimbusResult] = &[
    NIMBUS_OK,
    NIMBUS_STATUS_FRAME_SKIPPED,
    NIMBUS_ERROR_NULL_POINTER,
    NIMBUS_ERROR_INVALID_ARGUMENT,
    NIMBUS_ERROR_UNKNOWN_STRUCT,
    NIMBUS_ERROR_ABI_VERSION,
    NIMBUS_ERROR_INVALID_SETTINGS,
    NIMBUS_ERROR_INVALID_FRAME,
    NIMBUS_ERROR_INVALID_TARGET,
    NIMBUS_ERROR_NO_ADAPTER,
    NIMBUS_ERROR_GPU,
    NIMBUS_ERROR_PRESET_FILE,
    NIMBUS_ERROR_WEATHER,
    NIMBUS_ERROR_SURFACE,
    NIMBUS_ERROR_VULKAN_REQUIREMENT,
    NIMBUS_ERROR_NOT_READY,
    NIMBUS_ERROR_NOISE_CACHE,
    NIMBUS_ERROR_PANIC,
    NIMBUS_ERROR_POISONED,
    NIMBUS_ERROR_DEVICE_LOST,
];

use NimbusResult::*;

impl NimbusResult {
    /// The code for a plain integer, if it is one.
    pub fn from_i32(code: i32) -> Option<Self> {
        ALL_RESULTS.iter().copied().find(|r| *r as i32 == code)
    }

    /// The constant's name, NUL-terminated.
    fn name(self) -> &'static str {
        match self {
            NIMBUS_OK => "NIMBUS_OK\0",
            NIMBUS_STATUS_FRAME_SKIPPED => "NIMBUS_STATUS_FRAME_SKIPPED\0",
            NIMBUS_ERROR_NULL_POINTER => "NIMBUS_ERROR_NULL_POINTER\0",
            NIMBUS_ERROR_INVALID_ARGUMENT => "NIMBUS_ERROR_INVALID_ARGUMENT\0",
            NIMBUS_ERROR_UNKNOWN_STRUCT => "NIMBUS_ERROR_UNKNOWN_STRUCT\0",
            NIMBUS_ERROR_ABI_VERSION => "NIMBUS_ERROR_ABI_VERSION\0",
            NIMBUS_ERROR_INVALID_SETTINGS => "NIMBUS_ERROR_INVALID_SETTINGS\0",
            NIMBUS_ERROR_INVALID_FRAME => "NIMBUS_ERROR_INVALID_FRAME\0",
            NIMBUS_ERROR_INVALID_TARGET => "NIMBUS_ERROR_INVALID_TARGET\0",
            NIMBUS_ERROR_NO_ADAPTER => "NIMBUS_ERROR_NO_ADAPTER\0",
            NIMBUS_ERROR_GPU => "NIMBUS_ERROR_GPU\0",
            NIMBUS_ERROR_PRESET_FILE => "NIMBUS_ERROR_PRESET_FILE\0",
            NIMBUS_ERROR_WEATHER => "NIMBUS_ERROR_WEATHER\0",
            NIMBUS_ERROR_SURFACE => "NIMBUS_ERROR_SURFACE\0",
            NIMBUS_ERROR_VULKAN_REQUIREMENT => "NIMBUS_ERROR_VULKAN_REQUIREMENT\0",
            NIMBUS_ERROR_NOT_READY => "NIMBUS_ERROR_NOT_READY\0",
            NIMBUS_ERROR_NOISE_CACHE => "NIMBUS_ERROR_NOISE_CACHE\0",
            NIMBUS_ERROR_PANIC => "NIMBUS_ERROR_PANIC\0",
            NIMBUS_ERROR_POISONED => "NIMBUS_ERROR_POISONED\0",
            NIMBUS_ERROR_DEVICE_LOST => "NIMBUS_ERROR_DEVICE_LOST\0",
        }
    }

    /// What the code means, in one sentence, NUL-terminated.
    fn message(self) -> &'static str {
        match self {
            NIMBUS_OK => "success\0",
            NIMBUS_STATUS_FRAME_SKIPPED => "the frame was not presented; render again next frame\0",
            NIMBUS_ERROR_NULL_POINTER => "a required pointer argument was NULL\0",
            NIMBUS_ERROR_INVALID_ARGUMENT => {
                "an argument is out of range, NaN, or an unknown enum value or flag\0"
            }
            NIMBUS_ERROR_UNKNOWN_STRUCT => "a chained struct has an unknown or misplaced s_type\0",
            NIMBUS_ERROR_ABI_VERSION => {
                "the header's ABI version cannot be served by this library\0"
            }
            NIMBUS_ERROR_INVALID_SETTINGS => "a setting is out of range\0",
            NIMBUS_ERROR_INVALID_FRAME => "the camera, sun or time of the frame is unusable\0",
            NIMBUS_ERROR_INVALID_TARGET => {
                "a texture or target has the wrong size, format, role or context\0"
            }
            NIMBUS_ERROR_NO_ADAPTER => "no GPU adapter was found\0",
            NIMBUS_ERROR_GPU => "the GPU device failed or reported an error\0",
            NIMBUS_ERROR_PRESET_FILE => "a preset file is missing, too large or malformed\0",
            NIMBUS_ERROR_WEATHER => "the weather request is unusable\0",
            NIMBUS_ERROR_SURFACE => "the window surface could not be created or configured\0",
            NIMBUS_ERROR_VULKAN_REQUIREMENT => {
                "the host's Vulkan instance or device lacks something Nimbus needs\0"
            }
            NIMBUS_ERROR_NOT_READY => {
                "the output is not there: its feature is off or no frame has made it yet\0"
            }
            NIMBUS_ERROR_NOISE_CACHE => "the noise cache is damaged or does not match\0",
            NIMBUS_ERROR_PANIC => "a panic inside Nimbus was caught; the context is poisoned\0",
            NIMBUS_ERROR_POISONED => "the context was poisoned by an earlier panic\0",
            NIMBUS_ERROR_DEVICE_LOST => "the GPU device was lost; create a new context\0",
        }
    }
}

/// The name of a result code, e.g. "NIMBUS_ERROR_NULL_POINTER"; "NIMBUS_UNKNOWN_RESULT" for
/// a value that is no code. Static storage; never free it.
#[no_mangle]
pub extern "C" fn nimbus_result_name(code: i32) -> *const c_char {
    NimbusResult::from_i32(code)
        .map_or("NIMBUS_UNKNOWN_RESULT\0", NimbusResult::name)
        .as_ptr()
        .cast()
}

/// What a result code means, in one sentence (the per-call details are in
/// nimbus_context_last_error). Static storage; never free it.
#[no_mangle]
pub extern "C" fn nimbus_result_message(code: i32) -> *const c_char {
    NimbusResult::from_i32(code)
        .map_or("not a Nimbus result code\0", NimbusResult::message)
        .as_ptr()
        .cast()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::ffi::CStr;

    #[test]
    fn every_code_has_a_name_and_a_message_and_values_stay_in_their_blocks() {
        for r in ALL_RESULTS {
            let code = *r as i32;
            // SAFETY: the lookups return static NUL-terminated strings.
            let name = unsafe { CStr::from_ptr(nimbus_result_name(code)) }
                .to_str()
                .unwrap();
            assert_eq!(name, format!("{r:?}"));
            // SAFETY: as above.
            let message = unsafe { CStr::from_ptr(nimbus_result_message(code)) };
            assert!(!message.to_bytes().is_empty());
            assert!((-299..=99).contains(&code), "{name} = {code}");
            assert_eq!(NimbusResult::from_i32(code), Some(*r));
        }
        // SAFETY: as above.
        let unknown = unsafe { CStr::from_ptr(nimbus_result_name(-77)) };
        assert_eq!(unknown.to_str().unwrap(), "NIMBUS_UNKNOWN_RESULT");
    }

    #[test]
    fn released_values_never_change() {
        let pinned = [
            (NIMBUS_OK, 0),
            (NIMBUS_STATUS_FRAME_SKIPPED, 1),
            (NIMBUS_ERROR_NULL_POINTER, -1),
            (NIMBUS_ERROR_INVALID_ARGUMENT, -2),
            (NIMBUS_ERROR_UNKNOWN_STRUCT, -3),
            (NIMBUS_ERROR_ABI_VERSION, -4),
            (NIMBUS_ERROR_INVALID_SETTINGS, -5),
            (NIMBUS_ERROR_INVALID_FRAME, -6),
            (NIMBUS_ERROR_INVALID_TARGET, -7),
            (NIMBUS_ERROR_NO_ADAPTER, -8),
            (NIMBUS_ERROR_GPU, -9),
            (NIMBUS_ERROR_PRESET_FILE, -10),
            (NIMBUS_ERROR_WEATHER, -11),
            (NIMBUS_ERROR_SURFACE, -12),
            (NIMBUS_ERROR_VULKAN_REQUIREMENT, -13),
            (NIMBUS_ERROR_NOT_READY, -14),
            (NIMBUS_ERROR_NOISE_CACHE, -15),
            (NIMBUS_ERROR_PANIC, -100),
            (NIMBUS_ERROR_POISONED, -101),
            (NIMBUS_ERROR_DEVICE_LOST, -200),
        ];
        assert_eq!(pinned.len(), ALL_RESULTS.len());
        for (r, v) in pinned {
            assert_eq!(r as i32, v, "{r:?}");
        }
    }
}
