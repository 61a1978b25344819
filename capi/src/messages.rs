//! Messages cadr sends the host while it works: what a load left out or cannot draw yet (a
//! texture that does not decode, point primitives), Vulkan validation messages where a context
//! enabled validation, and other diagnostics. They go to one callback the host installs; without
//! one they are dropped.

use std::ffi::{c_char, c_void, CString};
use std::sync::{OnceLock, RwLock};

use crate::error::{guard, CadrResult, Failure};

/// Message severity: something failed (a Vulkan validation error, for instance).
pub const CADR_MESSAGE_ERROR: u32 = 1;
/// Message severity: something the host's user should know, usually data left out of a load.
pub const CADR_MESSAGE_WARNING: u32 = 2;
/// Message severity: information on what cadr did.
pub const CADR_MESSAGE_INFO: u32 = 3;
/// Message severity: details for whoever debugs cadr.
pub const CADR_MESSAGE_DEBUG: u32 = 4;

/// Receives one message: its severity (`CADR_MESSAGE_*`), its NUL-terminated UTF-8 text, and the
/// `user_data` given to `cadr_set_message_callback`.
///
/// Ownership: the text is cadr's and valid only during the call; copy what you keep.
/// Thread-safety: called on whichever thread cadr works on when the message arises (the one
/// calling into cadr, a worker thread of cadr, or a Vulkan driver's thread for validation
/// messages), possibly on several threads at once: the callback must be thread-safe. It may call
/// cadr functions, `cadr_set_message_callback` included.
pub type CadrMessageCallback =
    Option<unsafe extern "C" fn(severity: u32, message: *const c_char, user_data: *mut c_void)>;

/// The host's callback with its user data and the most verbose severity it wants.
#[derive(Clone, Copy)]
struct HostCallback {
    callback: unsafe extern "C" fn(u32, *const c_char, *mut c_void),
    /// The host's pointer, kept as a number: cadr never reads through it.
    user_data: usize,
    most_verbose: log::Level,
}

static HOST_CALLBACK: RwLock<Option<HostCallback>> = RwLock::new(None);

/// The host's callback, if one is installed (a copy: it is called without holding the lock,
/// so it may install another).
fn host_callback() -> Option<HostCallback> {
    *HOST_CALLBACK
        .read()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

fn severity(level: log::Level) -> u32 {
    match level {
        log::Level::Error => CADR_MESSAGE_ERROR,
        log::Level::Warn => CADR_MESSAGE_WARNING,
        log::Level::Info => CADR_MESSAGE_INFO,
        log::Level::Debug | log::Level::Trace => CADR_MESSAGE_DEBUG,
    }
}

/// Hands the `log` records of cadr (and of the crates it uses) to the host's callback.
struct ToHost;

impl log::Log for ToHost {
    fn enabled(&self, metadata: &log::Metadata<'_>) -> bool {
        host_callback().is_some_and(|host| metadata.level() <= host.most_verbose)
    }

    fn log(&self, record: &log::Record<'_>) {
        let Some(host) = host_callback() else {
            return;
        };
        if record.level() > host.most_verbose {
            return;
        }
        let text = record.args().to_string().replace('\0', "\u{fffd}");
        let Ok(text) = CString::new(text) else {
            return;
        };
        // SAFETY: the host's callback, as its contract says: a NUL-terminated text valid for
        // the call and the user data it gave.
        unsafe {
            (host.callback)(
                severity(record.level()),
                text.as_ptr(),
                host.user_data as *mut c_void,
            )
        };
    }

    fn flush(&self) {}
}

static TO_HOST: ToHost = ToHost;

/// Whether cadr's messages reach [`TO_HOST`]: `Err` when the process already had another
/// `log` logger (a Rust host's own), decided once.
fn install_logger() -> Result<(), Failure> {
    static INSTALLED: OnceLock<bool> = OnceLock::new();
    let installed = *INSTALLED.get_or_init(|| log::set_logger(&TO_HOST).is_ok());
    if installed {
        Ok(())
    } else {
        Err(Failure::new(
            CadrResult::Unsupported,
            "another logger of the Rust `log` crate already receives this process's messages \
             (a Rust host's own): read cadr's messages there"
                .to_owned(),
        ))
    }
}

/// Installs `callback` to receive cadr's messages of severity `most_verbose` and more serious
/// (`CADR_MESSAGE_ERROR` < `CADR_MESSAGE_WARNING` < `CADR_MESSAGE_INFO` <
/// `CADR_MESSAGE_DEBUG`), replacing the one installed before; NULL removes it, and messages are
/// dropped again (the default). One callback serves the whole process: every context, scene and
/// renderer.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_INVALID_ARGUMENT` (`most_verbose` is not a
/// `CADR_MESSAGE_*` severity) or `CADR_RESULT_UNSUPPORTED` (a Rust host installed a logger of
/// the `log` crate first: cadr's messages go there). Ownership: cadr keeps `user_data` and
/// hands it back to each call, never reading through it; it must stay valid until the callback
/// is replaced or removed. Thread-safety: any thread; a message arising meanwhile goes to the
/// old callback or the new one.
#[no_mangle]
pub extern "C" fn cadr_set_message_callback(
    callback: CadrMessageCallback,
    user_data: *mut c_void,
    most_verbose: u32,
) -> CadrResult {
    guard(|| {
        let level = match most_verbose {
            CADR_MESSAGE_ERROR => log::Level::Error,
            CADR_MESSAGE_WARNING => log::Level::Warn,
            CADR_MESSAGE_INFO => log::Level::Info,
            CADR_MESSAGE_DEBUG => log::Level::Debug,
            other => {
                return Err(Failure::invalid(format!(
                    "message severity {other} is not 1 (error), 2 (warning), 3 (info) or 4 \
                     (debug)"
                )))
            }
        };
        install_logger()?;
        let host = callback.map(|callback| HostCallback {
            callback,
            user_data: user_data as usize,
            most_verbose: level,
        });
        *HOST_CALLBACK
            .write()
            .unwrap_or_else(|poisoned| poisoned.into_inner()) = host;
        log::set_max_level(
            host.map_or(log::LevelFilter::Off, |h| h.most_verbose.to_level_filter()),
        );
        Ok(())
    })
}
