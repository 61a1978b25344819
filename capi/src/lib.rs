//! The C API of cadr.
//!
//! Conventions (every function follows them):
//! - Fallible functions return a [`CadrResult`]; outputs are written through out-parameters
//!   only on success.
//! - A null pointer argument gives `CADR_RESULT_NULL_ARGUMENT`; bad content gives its own code.
//! - Details of the last error on the calling thread are available from
//!   [`cadr_last_error_message`].
//! - Every body runs inside a panic guard: a panic becomes `CADR_RESULT_PANIC`, never unwinds
//!   into C.
//!
//! This first version renders a scene to a PNG; scene editing, plugins and windowed rendering
//! follow the same conventions.

mod error;

pub use error::{cadr_last_error_message, cadr_result_string, CadrResult};

use std::ffi::{c_char, CStr};
use std::path::PathBuf;

use cadr_core::load::SceneSource;
use cadr_core::render::{Camera, GpuScene, Renderer, DEFAULT_DIRECTION};
use cadr_core::vk::{Device, DeviceOptions, InstanceOptions};

use error::{guard, Failure};

/// The library version as a static NUL-terminated string such as "0.1.0".
///
/// Ownership: the string is static; do not free it. Thread-safety: callable from any thread.
#[no_mangle]
pub extern "C" fn cadr_version_string() -> *const c_char {
    concat!(env!("CARGO_PKG_VERSION"), "\0").as_ptr().cast()
}

/// Reads a required C string argument.
///
/// # Safety
/// `text` is null or points to a NUL-terminated string that stays valid during the call.
unsafe fn required_str<'a>(text: *const c_char, name: &str) -> Result<&'a str, Failure> {
    if text.is_null() {
        return Err(Failure::new(
            CadrResult::NullArgument,
            format!("{name} is NULL"),
        ));
    }
    // SAFETY: non-null, and the caller guarantees a valid NUL-terminated string.
    unsafe { CStr::from_ptr(text) }.to_str().map_err(|_| {
        Failure::new(
            CadrResult::InvalidArgument,
            format!("{name} is not valid UTF-8"),
        )
    })
}

/// Renders `scene` (a .gltf/.glb path or a generator such as "gen:demo") with the camera
/// fitted to its bounds into a `width` × `height` PNG at `png_path`.
///
/// `validation` turns the Vulkan validation layers on; a validation error then fails the call.
/// Returns `CADR_RESULT_OK`, or `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_INVALID_ARGUMENT`
/// (zero or too large size), `CADR_RESULT_LOAD_FAILED`, `CADR_RESULT_VULKAN` or
/// `CADR_RESULT_IO`, with details from `cadr_last_error_message`.
///
/// Ownership: the strings are borrowed for the duration of the call. Thread-safety: callable
/// from any thread; each call creates and destroys its own Vulkan device.
///
/// # Safety
/// `scene` and `png_path` must be null or valid NUL-terminated strings.
#[no_mangle]
pub unsafe extern "C" fn cadr_render_scene_to_png(
    scene: *const c_char,
    png_path: *const c_char,
    width: u32,
    height: u32,
    validation: bool,
) -> CadrResult {
    guard(|| {
        // SAFETY: the caller passes null or valid strings (see the function's contract).
        let (scene, png_path) = unsafe {
            (
                required_str(scene, "scene")?,
                required_str(png_path, "png_path")?,
            )
        };
        if width == 0 || height == 0 || width > 16384 || height > 16384 {
            return Err(Failure::new(
                CadrResult::InvalidArgument,
                format!("size {width}x{height}: each side must be 1 to 16384"),
            ));
        }
        let load =
            |e: cadr_core::load::LoadError| Failure::new(CadrResult::LoadFailed, e.to_string());
        let vulkan = |e: &dyn std::fmt::Display| Failure::new(CadrResult::Vulkan, e.to_string());
        let scene = SceneSource::parse(scene)
            .map_err(load)?
            .load()
            .map_err(load)?;
        let options = DeviceOptions {
            instance: InstanceOptions {
                validation,
                ..InstanceOptions::default()
            },
            ..DeviceOptions::default()
        };
        let device = Device::new(&options).map_err(|e| vulkan(&e))?;
        let gpu_scene = GpuScene::upload(&device, &scene).map_err(|e| match e {
            cadr_core::render::UploadError::Scene(e) => {
                Failure::new(CadrResult::LoadFailed, e.to_string())
            }
            other => vulkan(&other),
        })?;
        let mut renderer = Renderer::new(&device, width, height).map_err(|e| vulkan(&e))?;
        let camera = Camera::fit(
            &gpu_scene.stats.bounds,
            f64::from(width) / f64::from(height),
            DEFAULT_DIRECTION,
        );
        renderer
            .render(&gpu_scene, &camera)
            .map_err(|e| vulkan(&e))?;
        renderer
            .save_png(&PathBuf::from(png_path))
            .map_err(|e| match e {
                cadr_core::render::SaveError::Write { .. } => {
                    Failure::new(CadrResult::Io, e.to_string())
                }
                other => vulkan(&other),
            })?;
        let errors = device.validation_log().errors();
        if !errors.is_empty() {
            return Err(Failure::new(
                CadrResult::Vulkan,
                format!("{} validation errors: {}", errors.len(), errors.join("; ")),
            ));
        }
        Ok(())
    })
}
