//! Result codes, the per-thread last error message and the panic guard.

use std::cell::RefCell;
use std::ffi::c_char;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// The result of every fallible cadr function.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CadrResult {
    /// Success.
    Ok = 0,
    /// A required pointer argument was NULL.
    NullArgument = 1,
    /// An argument had a value outside its range (size, flag, string encoding).
    InvalidArgument = 2,
    /// A scene file or generator could not be loaded; the message names the file and item.
    LoadFailed = 3,
    /// Vulkan failed: no device, out of memory, device lost, or a validation error.
    Vulkan = 4,
    /// A file could not be written.
    Io = 5,
    /// The output buffer is too small; the needed size was written to the length out-parameter.
    BufferTooSmall = 6,
    /// An internal error (a bug): cadr caught a panic. The message says where.
    Panic = 7,
    /// The handle was valid once but its object has been destroyed.
    DestroyedHandle = 8,
    /// The value is not a handle of the expected type (another type's handle, or garbage).
    ForeignHandle = 9,
    /// No item has this name or index (a technique, a list entry).
    NotFound = 10,
    /// The techniques chosen cannot work together; the message says which need is unmet.
    InvalidCombination = 11,
    /// The device or the platform cannot do this (missing feature, extension or technique).
    Unsupported = 12,
    /// The object is still used (a geometry or material referenced by nodes).
    InUse = 13,
    /// A technique plugin failed (its create, prepare or record call returned an error or
    /// panicked); the renderer keeps its previous techniques.
    PluginFailed = 14,
    /// The Vulkan device was lost (a driver reset, a removed or switched GPU): every later call
    /// that needs the GPU on this context returns this too. Destroy the context's renderers and
    /// the context, and create them again; scenes are not affected.
    DeviceLost = 15,
}

thread_local! {
    static LAST_ERROR: RefCell<String> = const { RefCell::new(String::new()) };
}

/// A failed call: its code and message.
#[derive(Debug)]
pub(crate) struct Failure {
    code: CadrResult,
    message: String,
}

impl Failure {
    pub(crate) fn new(code: CadrResult, message: String) -> Self {
        Self { code, message }
    }

    /// The same failure, its message prefixed with what it concerns (`settings.msaa_samples`).
    pub(crate) fn named(self, what: &str) -> Self {
        Self::new(self.code, format!("{what}: {}", self.message))
    }

    /// A failure with `CADR_RESULT_INVALID_ARGUMENT`.
    pub(crate) fn invalid(message: impl Into<String>) -> Self {
        Self::new(CadrResult::InvalidArgument, message.into())
    }
}

impl From<cadr_core::vk::VkError> for Failure {
    fn from(error: cadr_core::vk::VkError) -> Self {
        let code = match error {
            cadr_core::vk::VkError::Unsupported { .. } => CadrResult::Unsupported,
            cadr_core::vk::VkError::DeviceLost(_) => CadrResult::DeviceLost,
            _ => CadrResult::Vulkan,
        };
        Self::new(code, error.to_string())
    }
}

impl From<cadr_core::error::RenderError> for Failure {
    fn from(error: cadr_core::error::RenderError) -> Self {
        use cadr_core::error::RenderError;
        match error {
            RenderError::Vulkan(vulkan) => vulkan.into(),
            // A technique's own failure, or its shader snippet failing to compile in the
            // assembled shader.
            RenderError::Technique { .. } | RenderError::ShaderCompile(_) => {
                Self::new(CadrResult::PluginFailed, error.to_string())
            }
            RenderError::InvalidUse(_) => Self::new(CadrResult::InvalidArgument, error.to_string()),
            RenderError::SceneData(_) => Self::new(CadrResult::Io, error.to_string()),
        }
    }
}

/// Runs `body`, turning its failure or panic into a result code and the thread's last error.
pub(crate) fn guard(body: impl FnOnce() -> Result<(), Failure>) -> CadrResult {
    let outcome = catch_unwind(AssertUnwindSafe(body)).unwrap_or_else(|panic| {
        let text = cadr_core::panic_boundary::payload_text(panic.as_ref());
        Err(Failure::new(
            CadrResult::Panic,
            format!("internal error: {text}"),
        ))
    });
    let (code, message) = match outcome {
        Ok(()) => (CadrResult::Ok, String::new()),
        Err(failure) => (failure.code, failure.message),
    };
    LAST_ERROR.with(|last| *last.borrow_mut() = message);
    code
}

/// A static, NUL-terminated English name of `result` (a `CadrResult` value), e.g.
/// "null argument"; "unknown result" for values that are none.
///
/// Ownership: static; do not free. Thread-safety: callable from any thread.
#[no_mangle]
pub extern "C" fn cadr_result_string(result: i32) -> *const c_char {
    const ALL: [CadrResult; 16] = [
        CadrResult::Ok,
        CadrResult::NullArgument,
        CadrResult::InvalidArgument,
        CadrResult::LoadFailed,
        CadrResult::Vulkan,
        CadrResult::Io,
        CadrResult::BufferTooSmall,
        CadrResult::Panic,
        CadrResult::DestroyedHandle,
        CadrResult::ForeignHandle,
        CadrResult::NotFound,
        CadrResult::InvalidCombination,
        CadrResult::Unsupported,
        CadrResult::InUse,
        CadrResult::PluginFailed,
        CadrResult::DeviceLost,
    ];
    let text: &'static str = match ALL.iter().find(|r| **r as i32 == result) {
        None => "unknown result\0",
        Some(CadrResult::Ok) => "ok\0",
        Some(CadrResult::NullArgument) => "null argument\0",
        Some(CadrResult::InvalidArgument) => "invalid argument\0",
        Some(CadrResult::LoadFailed) => "scene could not be loaded\0",
        Some(CadrResult::Vulkan) => "Vulkan error\0",
        Some(CadrResult::Io) => "file could not be written\0",
        Some(CadrResult::BufferTooSmall) => "buffer too small\0",
        Some(CadrResult::Panic) => "internal error\0",
        Some(CadrResult::DestroyedHandle) => "destroyed handle\0",
        Some(CadrResult::ForeignHandle) => "foreign handle\0",
        Some(CadrResult::NotFound) => "not found\0",
        Some(CadrResult::InvalidCombination) => "invalid technique combination\0",
        Some(CadrResult::Unsupported) => "unsupported\0",
        Some(CadrResult::InUse) => "still in use\0",
        Some(CadrResult::PluginFailed) => "technique plugin failed\0",
        Some(CadrResult::DeviceLost) => "device lost\0",
    };
    text.as_ptr().cast()
}

/// Copies the message of the last failed call on this thread (empty after a success) into
/// `buffer` as a NUL-terminated string, and its length without the NUL into `*length`.
///
/// With `buffer` NULL or `capacity` too small, writes only the needed capacity (length + 1)
/// into `*length` and returns `CADR_RESULT_BUFFER_TOO_SMALL`. `length` must not be NULL.
///
/// Ownership: `buffer` is the caller's. Thread-safety: each thread has its own message.
///
/// # Safety
/// `buffer` is null or writable for `capacity` bytes; `length` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_last_error_message(
    buffer: *mut c_char,
    capacity: usize,
    length: *mut usize,
) -> CadrResult {
    let outcome = catch_unwind(|| LAST_ERROR.with(|last| last.borrow().clone()));
    let message = outcome.unwrap_or_default();
    // SAFETY: the caller's contract, passed on.
    unsafe { crate::args::copy_string_out(&message, buffer, capacity, length) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lost_device_has_a_result_of_its_own() {
        let failure = Failure::from(cadr_core::vk::VkError::DeviceLost("vkQueueSubmit"));
        assert_eq!(failure.code, CadrResult::DeviceLost);
        assert!(failure.message.contains("lost"), "{}", failure.message);
        // SAFETY: the returned strings are static and NUL-terminated.
        let text = unsafe { std::ffi::CStr::from_ptr(cadr_result_string(15)) };
        assert_eq!(text.to_str(), Ok("device lost"));
    }
}
