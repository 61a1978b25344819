//! The load's panic boundary (feature `fault-injection`, run by `scripts/test.sh` as the
//! injected Vulkan failures are): a panic while a file is read, injected on a worker thread as
//! one inside a dependency's decoder would arise, is refused as an error that names the file
//! and says it could not be read; the panic's location goes to the log; a C host gets
//! `CADR_RESULT_LOAD_FAILED` with that message, never `CADR_RESULT_PANIC`.
#![cfg(feature = "fault-injection")]
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::ffi::{c_char, c_void, CStr, CString};
use std::path::Path;
use std::sync::Mutex;

use cadr_core::load::{load_file, LoadError, INJECTED_PANIC_VARIABLE, READER_PANIC};
use cadr_tests::CYLINDER_ENGINE_GLB;

/// The messages cadr sent to the C API's callback.
static MESSAGES: Mutex<Vec<(u32, String)>> = Mutex::new(Vec::new());

/// # Safety
/// `text` is a NUL-terminated string, valid during the call (as cadr passes it).
unsafe extern "C" fn keep_message(severity: u32, text: *const c_char, _user_data: *mut c_void) {
    // SAFETY: the function's contract.
    let text = unsafe { CStr::from_ptr(text) }
        .to_string_lossy()
        .into_owned();
    MESSAGES.lock().unwrap().push((severity, text));
}

#[test]
fn a_panic_while_reading_a_file_is_refused_naming_the_file_and_logged_with_its_location() {
    std::env::set_var(INJECTED_PANIC_VARIABLE, "1");
    let file = Path::new(CYLINDER_ENGINE_GLB);

    let error = load_file(file).unwrap_err();
    let LoadError::ReaderPanicked { path, panic } = &error else {
        panic!("not refused as a caught panic: {error}");
    };
    assert_eq!(path, file);
    assert!(panic.message.contains(INJECTED_PANIC_VARIABLE), "{panic}");
    assert!(
        panic
            .location
            .as_deref()
            .is_some_and(|location| location.contains("load/mod.rs:")),
        "the worker's panic location was recorded: {panic}"
    );
    let text = error.to_string();
    assert!(
        text.starts_with(&format!(
            "{CYLINDER_ENGINE_GLB}: the file could not be read: "
        )) && text.contains(READER_PANIC),
        "{text}"
    );

    // Through the C API: a refusal with that message, and the location in the log.
    // `keep_message` is thread-safe and copies what it keeps.
    let installed = cadr::cadr_set_message_callback(Some(keep_message), std::ptr::null_mut(), 1);
    assert_eq!(installed, cadr::CadrResult::Ok);
    let mut scene: cadr::CadrScene = std::ptr::null_mut();
    // SAFETY: `scene` is writable.
    assert_eq!(
        unsafe { cadr::cadr_scene_create(&mut scene) },
        cadr::CadrResult::Ok
    );
    let mut root: cadr::CadrNode = 0;
    // SAFETY: `root` is writable; `scene` was just created.
    assert_eq!(
        unsafe { cadr::cadr_scene_root(scene, &mut root) },
        cadr::CadrResult::Ok
    );
    let c_path = CString::new(CYLINDER_ENGINE_GLB).unwrap();
    let mut loaded = std::mem::MaybeUninit::<cadr::CadrLoadResult>::zeroed();
    // SAFETY: zero bytes are a CadrLoadResult; its size, the first field, is the host's to set.
    unsafe {
        loaded
            .as_mut_ptr()
            .cast::<u32>()
            .write(std::mem::size_of::<cadr::CadrLoadResult>() as u32)
    };
    // SAFETY: `c_path` is a NUL-terminated string; `loaded` is writable.
    let result =
        unsafe { cadr::cadr_scene_load(scene, c_path.as_ptr(), root, loaded.as_mut_ptr()) };
    assert_eq!(result, cadr::CadrResult::LoadFailed);
    let mut message = vec![0_u8; 4096];
    let mut length = 0_usize;
    // SAFETY: `message` is writable for its length; `length` is writable.
    unsafe {
        cadr::cadr_last_error_message(message.as_mut_ptr().cast(), message.len(), &mut length)
    };
    let message = String::from_utf8_lossy(&message[..length]).into_owned();
    assert!(
        message.contains("2CylinderEngine.glb: the file could not be read")
            && message.contains(READER_PANIC),
        "{message}"
    );
    let mut children = 0_u32;
    // SAFETY: `children` is writable.
    unsafe { cadr::cadr_scene_child_count(scene, root, &mut children) };
    assert_eq!(children, 0, "nothing was added to the scene");
    assert_eq!(cadr::cadr_scene_destroy(scene), cadr::CadrResult::Ok);
    cadr::cadr_set_message_callback(None, std::ptr::null_mut(), 1);

    let messages = MESSAGES.lock().unwrap();
    assert!(
        messages.iter().any(|(severity, text)| *severity == 1
            && text.contains("2CylinderEngine.glb: reading it panicked at")
            && text.contains("load/mod.rs:")),
        "the panic's location is logged as an error: {messages:?}"
    );
    std::env::remove_var(INJECTED_PANIC_VARIABLE);
}
