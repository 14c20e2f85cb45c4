//! Forwards Nimbus's and wgpu's log messages to a C callback: a cdylib has no logger otherwise.

use std::cell::Cell;
use std::ffi::{c_char, c_void, CString};
use std::sync::Mutex;

use super::{boundary, FfiError, NimbusResult, NIMBUS_OK};

/// Receives one log message: `level` 1 error, 2 warning, 3 info, 4 debug, 5 trace. The message
/// is valid only during the call. May be called from any thread that uses Nimbus.
pub type NimbusLogCallback =
    Option<unsafe extern "C" fn(level: i32, message: *const c_char, user_data: *mut c_void)>;

#[derive(Clone, Copy)]
struct Sink {
    callback: NimbusLogCallback,
    user_data: usize,
}

/// The registered callback. Held only to copy it out or replace it: never while the callback
/// runs, so a callback may call back into Nimbus (even `nimbus_set_log_callback`).
static SINK: Mutex<Option<Sink>> = Mutex::new(None);

thread_local! {
    /// Set while this thread runs the host's callback: messages logged from inside it (a
    /// callback that calls into Nimbus) are dropped instead of recursing.
    static IN_CALLBACK: Cell<bool> = const { Cell::new(false) };
}

struct Forwarder;

impl log::Log for Forwarder {
    fn enabled(&self, metadata: &log::Metadata) -> bool {
        metadata.level() <= log::max_level()
    }

    fn log(&self, record: &log::Record) {
        if !self.enabled(record.metadata()) {
            return;
        }
        if IN_CALLBACK.with(Cell::get) {
            return;
        }
        // Copy the sink out and release the lock before calling the host.
        let sink = match SINK.lock() {
            Ok(guard) => *guard,
            Err(_) => return,
        };
        let Some(Sink {
            callback: Some(cb),
            user_data,
        }) = sink
        else {
            return;
        };
        let text = format!("{}: {}", record.target(), record.args()).replace('\0', " ");
        if let Ok(c) = CString::new(text) {
            IN_CALLBACK.with(|f| f.set(true));
            // SAFETY: the host registered this callback for exactly these arguments.
            unsafe { cb(record.level() as i32, c.as_ptr(), user_data as *mut c_void) };
            IN_CALLBACK.with(|f| f.set(false));
        }
    }

    fn flush(&self) {}
}

static FORWARDER: Forwarder = Forwarder;

/// Sets (or, with NULL, removes) the log callback for the whole library. `max_level` 0 turns
/// logging off, 1 errors only ... 5 everything. Returns `NIMBUS_ERROR_INVALID_ARGUMENT` for a
/// level outside 0..=5.
#[no_mangle]
pub extern "C" fn nimbus_set_log_callback(
    callback: NimbusLogCallback,
    user_data: *mut c_void,
    max_level: i32,
) -> NimbusResult {
    boundary(
        || {
            let filter = match max_level {
                0 => log::LevelFilter::Off,
                1 => log::LevelFilter::Error,
                2 => log::LevelFilter::Warn,
                3 => log::LevelFilter::Info,
                4 => log::LevelFilter::Debug,
                5 => log::LevelFilter::Trace,
                _ => {
                    return Err(FfiError::arg(format!(
                        "max_level must be 0..=5, got {max_level}"
                    )))
                }
            };
            // Our own copy of `log` in the cdylib: setting it can only fail if already set.
            let _ = log::set_logger(&FORWARDER);
            *SINK
                .lock()
                .map_err(|_| FfiError::arg("log sink poisoned"))? = Some(Sink {
                callback,
                user_data: user_data as usize,
            });
            log::set_max_level(if callback.is_some() {
                filter
            } else {
                log::LevelFilter::Off
            });
            Ok(NIMBUS_OK)
        },
        |_, _| {},
    )
}
