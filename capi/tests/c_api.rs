//! The C API's functions, called the way C calls them: success, NULL arguments, bad sizes,
//! bad scenes, and the last-error message.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::ffi::{c_char, CStr, CString};

use cadr::{cadr_last_error_message, cadr_render_scene_to_png, cadr_result_string, CadrResult};

fn last_error() -> String {
    let mut needed = 0_usize;
    // SAFETY: a NULL buffer asks for the size; needed is writable.
    let result = unsafe { cadr_last_error_message(std::ptr::null_mut(), 0, &mut needed) };
    assert_eq!(result, CadrResult::BufferTooSmall);
    let mut buffer = vec![0 as c_char; needed];
    let mut length = 0_usize;
    // SAFETY: buffer holds `needed` bytes.
    let result = unsafe { cadr_last_error_message(buffer.as_mut_ptr(), buffer.len(), &mut length) };
    assert_eq!(result, CadrResult::Ok);
    // SAFETY: the function wrote a NUL-terminated string into buffer.
    let text = unsafe { CStr::from_ptr(buffer.as_ptr()) }
        .to_string_lossy()
        .into_owned();
    assert_eq!(text.len(), length);
    text
}

fn render(scene: &str, path: &str, width: u32, height: u32) -> CadrResult {
    let (scene, path) = (CString::new(scene).unwrap(), CString::new(path).unwrap());
    // SAFETY: both strings are valid for the call.
    unsafe { cadr_render_scene_to_png(scene.as_ptr(), path.as_ptr(), width, height, true) }
}

#[test]
fn renders_a_generator_scene_to_png() {
    let path = std::env::temp_dir().join(format!("cadr-capi-{}.png", std::process::id()));
    let result = render("gen:grid:parts=200", path.to_str().unwrap(), 96, 64);
    assert_eq!(result, CadrResult::Ok, "{}", last_error());
    assert_eq!(last_error(), "", "a success clears the message");
    let image = image_size(&path);
    assert_eq!(image, (96, 64));
    // Kept where the test fails, for a look.
    let _ = std::fs::remove_file(&path);
}

fn image_size(path: &std::path::Path) -> (u32, u32) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    let be = |at: usize| u32::from_be_bytes(bytes[at..at + 4].try_into().unwrap());
    (be(16), be(20))
}

#[test]
fn errors_have_codes_and_messages() {
    // SAFETY: NULL arguments are part of the contract and must be reported, not dereferenced.
    let result =
        unsafe { cadr_render_scene_to_png(std::ptr::null(), std::ptr::null(), 10, 10, false) };
    assert_eq!(result, CadrResult::NullArgument);
    assert_eq!(last_error(), "scene is NULL");

    assert_eq!(
        render("gen:demo", "/tmp/x.png", 0, 10),
        CadrResult::InvalidArgument
    );
    assert!(last_error().contains("0x10"));

    assert_eq!(
        render("/nonexistent/model.glb", "/tmp/x.png", 10, 10),
        CadrResult::LoadFailed
    );
    assert!(last_error().contains("/nonexistent/model.glb"));

    assert_eq!(
        render("gen:bogus", "/tmp/x.png", 10, 10),
        CadrResult::LoadFailed
    );
    assert!(last_error().contains("unknown generator"));

    assert_eq!(
        render("gen:grid:parts=10", "/nonexistent/dir/out.png", 16, 16),
        CadrResult::Io
    );
    assert!(last_error().contains("/nonexistent/dir/out.png"));

    // SAFETY: length NULL is reported.
    let result = unsafe { cadr_last_error_message(std::ptr::null_mut(), 0, std::ptr::null_mut()) };
    assert_eq!(result, CadrResult::NullArgument);
}

#[test]
fn every_result_has_a_name() {
    for result in [
        CadrResult::Ok,
        CadrResult::NullArgument,
        CadrResult::InvalidArgument,
        CadrResult::LoadFailed,
        CadrResult::Vulkan,
        CadrResult::Io,
        CadrResult::BufferTooSmall,
        CadrResult::Panic,
    ] {
        // SAFETY: the function returns a static NUL-terminated string.
        let name = unsafe { CStr::from_ptr(cadr_result_string(result as i32)) }
            .to_str()
            .unwrap();
        assert!(!name.is_empty());
    }
}
