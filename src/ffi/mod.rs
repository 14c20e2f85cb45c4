//! The C ABI: a thin translation onto the Rust API and nothing more (rustls-ffi discipline).
//!
//! - Opaque handles, created and destroyed only here; `_destroy(NULL)` is a no-op.
//! - Every fallible call returns an `int32_t`: 0 success, negative errors, positive non-error
//!   status; out-parameters are written only on success.
//! - Enums cross as plain integers and are validated; unknown values are errors.
//! - Every pointer is null-checked; every entry point runs inside `catch_unwind`. A panic
//!   returns `NIMBUS_ERROR_PANIC` and poisons the context.
//! - Root structs carry `next` chains of `{s_type, next}` extension structs.

// The header is C: each function's pointer contract is a plain "Safety:" paragraph there,
// not a rustdoc "# Safety" section, which clippy would otherwise ask for.
#![allow(clippy::missing_safety_doc)]

mod context;
mod log;
mod noise_cache;
mod outputs;
mod query;
mod result;
mod shadows;
mod texture;
mod types;
mod view;
#[cfg(not(any(target_vendor = "apple", target_arch = "wasm32")))]
mod vulkan;

use std::cell::{Cell, RefCell};
use std::ffi::{c_char, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Once;

pub use context::*;
pub use log::*;
pub use noise_cache::*;
pub use outputs::*;
pub use query::*;
pub use result::NimbusResult::{self, *};
pub use result::*;
pub use shadows::*;
pub use texture::*;
pub use types::*;
pub use view::*;
#[cfg(not(any(target_vendor = "apple", target_arch = "wasm32")))]
pub use vulkan::*;

use crate::Error;

/// Major version of the library; a context made with a header of another major version fails.
pub const NIMBUS_VERSION_MAJOR: u32 = 0;
/// Minor version.
pub const NIMBUS_VERSION_MINOR: u32 = 7;
/// Patch version.
pub const NIMBUS_VERSION_PATCH: u32 = 0;
/// The oldest minor version of this major whose headers this library still serves.
pub const NIMBUS_ABI_MIN_MINOR: u32 = 1;
/// The ABI version this header describes: (major << 16) | minor. Pass it in
/// `NimbusContextDesc.abi_version`. A library accepts the same major with a minor from its
/// NIMBUS_ABI_MIN_MINOR up to its own NIMBUS_VERSION_MINOR: older headers keep working, a
/// newer header (which may use structs this library does not know) is refused, and so is 0.
pub const NIMBUS_ABI_VERSION: u32 = (NIMBUS_VERSION_MAJOR << 16) | NIMBUS_VERSION_MINOR;

/// An error on its way to C: a result code and a message.
#[derive(Debug)]
pub(crate) struct FfiError {
    pub code: NimbusResult,
    pub message: String,
}

impl FfiError {
    pub(crate) fn new(code: NimbusResult, message: impl Into<String>) -> Self {
        Self {
            code,
            message: message.into(),
        }
    }
    pub(crate) fn null(name: &str) -> Self {
        Self::new(NIMBUS_ERROR_NULL_POINTER, format!("`{name}` is NULL"))
    }
    pub(crate) fn arg(message: impl Into<String>) -> Self {
        Self::new(NIMBUS_ERROR_INVALID_ARGUMENT, message)
    }
}

impl From<Error> for FfiError {
    fn from(e: Error) -> Self {
        let code = match &e {
            Error::InvalidSettings { .. } => NIMBUS_ERROR_INVALID_SETTINGS,
            Error::InvalidFrame { .. } => NIMBUS_ERROR_INVALID_FRAME,
            Error::InvalidTarget { .. } | Error::UnsupportedFormat { .. } | Error::NotPrepared => {
                NIMBUS_ERROR_INVALID_TARGET
            }
            Error::NoAdapter(_) => NIMBUS_ERROR_NO_ADAPTER,
            Error::RequestDevice(_) | Error::Gpu(_) | Error::Readback(_) => NIMBUS_ERROR_GPU,
            Error::PresetFile { .. } => NIMBUS_ERROR_PRESET_FILE,
            Error::InvalidWeather(_) => NIMBUS_ERROR_WEATHER,
            Error::Surface(_) => NIMBUS_ERROR_SURFACE,
            Error::Vulkan(_) => NIMBUS_ERROR_VULKAN_REQUIREMENT,
            Error::Image(_) | Error::InvalidView(_) | Error::InvalidQuery(_) => {
                NIMBUS_ERROR_INVALID_ARGUMENT
            }
            Error::DeviceLost(_) => NIMBUS_ERROR_DEVICE_LOST,
            Error::NoiseCache(_) => NIMBUS_ERROR_NOISE_CACHE,
        };
        let mut message = e.to_string();
        if code == NIMBUS_ERROR_DEVICE_LOST {
            message.push_str(": destroy this context and create a new one");
        }
        Self::new(code, message)
    }
}

pub(crate) type FfiResult<T = ()> = Result<T, FfiError>;

thread_local! {
    /// The message of the last failed call on this thread (any handle or none).
    static THREAD_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

fn to_cstring(message: &str) -> CString {
    CString::new(message.replace('\0', " ")).unwrap_or_default()
}

pub(crate) fn set_thread_error(message: &str) {
    THREAD_ERROR.with(|e| *e.borrow_mut() = to_cstring(message));
}

pub(crate) fn thread_error_ptr() -> *const c_char {
    THREAD_ERROR.with(|e| e.borrow().as_ptr())
}

fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        s.to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic".to_string()
    }
}

thread_local! {
    /// How deep this thread is inside `boundary` (entry points may nest through callbacks).
    static BOUNDARY_DEPTH: Cell<u32> = const { Cell::new(0) };
}

static PANIC_HOOK: Once = Once::new();

/// Panics caught at the boundary are reported through the result code, the last error and the
/// log callback; Rust's default hook would also print them (with a backtrace under
/// `RUST_BACKTRACE`) to the host's stderr. This hook sends panics raised inside an entry point
/// to the log instead and leaves every other panic of the process to the previous hook.
fn install_panic_hook() {
    PANIC_HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if BOUNDARY_DEPTH.with(Cell::get) > 0 {
                ::log::error!("panic inside Nimbus: {info}");
            } else {
                previous(info);
            }
        }));
    });
}

/// Runs `f` inside the panic boundary. Errors and panics become result codes; their messages
/// go to the thread's last error (and `on_error`, which contexts use to keep their own). A
/// success empties the thread's last error.
pub(crate) fn boundary(
    f: impl FnOnce() -> FfiResult<NimbusResult>,
    on_error: impl FnOnce(&str, bool),
) -> NimbusResult {
    install_panic_hook();
    BOUNDARY_DEPTH.with(|d| d.set(d.get() + 1));
    let result = catch_unwind(AssertUnwindSafe(f));
    BOUNDARY_DEPTH.with(|d| d.set(d.get().saturating_sub(1)));
    match result {
        Ok(Ok(code)) => {
            set_thread_error("");
            code
        }
        Ok(Err(e)) => {
            set_thread_error(&e.message);
            on_error(&e.message, false);
            e.code
        }
        Err(payload) => {
            let message = format!("panic inside Nimbus: {}", panic_message(&*payload));
            set_thread_error(&message);
            on_error(&message, true);
            NIMBUS_ERROR_PANIC
        }
    }
}

/// Reads a C string argument.
///
/// Safety: `p` must be NULL or point to a NUL-terminated string.
pub(crate) unsafe fn c_str<'a>(p: *const c_char, name: &str) -> FfiResult<&'a str> {
    if p.is_null() {
        return Err(FfiError::null(name));
    }
    // SAFETY: non-null and NUL-terminated per the caller's contract.
    unsafe { std::ffi::CStr::from_ptr(p) }
        .to_str()
        .map_err(|_| FfiError::arg(format!("`{name}` is not valid UTF-8")))
}

/// The library's version as (major << 16) | (minor << 8) | patch.
#[no_mangle]
pub extern "C" fn nimbus_version() -> u32 {
    (NIMBUS_VERSION_MAJOR << 16) | (NIMBUS_VERSION_MINOR << 8) | NIMBUS_VERSION_PATCH
}

/// The library's version as text, e.g. "0.1.0". Static storage; never free it.
#[no_mangle]
pub extern "C" fn nimbus_version_string() -> *const c_char {
    concat!(env!("CARGO_PKG_VERSION"), "\0").as_ptr().cast()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn version_constants_match_cargo_toml() {
        let v = |s: &str| s.parse::<u32>().unwrap();
        assert_eq!(NIMBUS_VERSION_MAJOR, v(env!("CARGO_PKG_VERSION_MAJOR")));
        assert_eq!(NIMBUS_VERSION_MINOR, v(env!("CARGO_PKG_VERSION_MINOR")));
        assert_eq!(NIMBUS_VERSION_PATCH, v(env!("CARGO_PKG_VERSION_PATCH")));
    }

    /// The header's version macros, the ABI rule docs/c-api.md states and the code agree.
    #[test]
    fn header_docs_and_code_agree_on_versions_and_the_abi_rule() {
        let root = env!("CARGO_MANIFEST_DIR");
        let header = std::fs::read_to_string(format!("{root}/include/nimbus.h")).unwrap();
        let define = |name: &str| -> u32 {
            let line = header
                .lines()
                .find(|l| l.starts_with(&format!("#define {name} ")))
                .unwrap_or_else(|| panic!("no #define {name} in nimbus.h"));
            let value = line.rsplit(' ').next().unwrap();
            // Either a number or the ABI expression of the other two.
            value.parse().unwrap_or(u32::MAX)
        };
        assert_eq!(define("NIMBUS_VERSION_MAJOR"), NIMBUS_VERSION_MAJOR);
        assert_eq!(define("NIMBUS_VERSION_MINOR"), NIMBUS_VERSION_MINOR);
        assert_eq!(define("NIMBUS_VERSION_PATCH"), NIMBUS_VERSION_PATCH);
        assert_eq!(define("NIMBUS_ABI_MIN_MINOR"), NIMBUS_ABI_MIN_MINOR);
        let docs = std::fs::read_to_string(format!("{root}/docs/c-api.md")).unwrap();
        let (major, min, ours) = (
            NIMBUS_VERSION_MAJOR,
            NIMBUS_ABI_MIN_MINOR,
            NIMBUS_VERSION_MINOR,
        );
        let stated =
            format!("This library is {major}.{ours} and serves {major}.{min} to {major}.{ours}.");
        assert!(docs.contains(&stated), "docs/c-api.md must state: {stated}");
        // The code: exactly the minors min..=ours of this major, never 0.
        for minor in 0..ours + 3 {
            let v = (major << 16) | minor;
            let accepted = context::check_abi_version(v).is_ok();
            assert_eq!(
                accepted,
                v != 0 && (min..=ours).contains(&minor),
                "ABI {major}.{minor}"
            );
        }
        assert!(context::check_abi_version(((major + 1) << 16) | ours).is_err());
    }

    #[test]
    fn boundary_turns_panics_and_errors_into_codes() {
        let mut poisoned = false;
        let code = boundary(|| panic!("boom"), |_, p| poisoned = p);
        assert_eq!(code, NIMBUS_ERROR_PANIC);
        assert!(poisoned);
        let code = boundary(|| Err(FfiError::arg("bad")), |_, _| {});
        assert_eq!(code, NIMBUS_ERROR_INVALID_ARGUMENT);
        // SAFETY: thread_error_ptr returns a valid C string of this thread.
        let msg = unsafe { std::ffi::CStr::from_ptr(thread_error_ptr()) };
        assert_eq!(msg.to_str().unwrap(), "bad");
    }
}
