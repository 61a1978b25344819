//! Fuzz targets of cadr's readers, shared by the AFL++ entry points (`src/bin/`, built with
//! `cargo afl build --features afl`) and by the replay of their corpora and findings in the
//! ordinary test run (`tests/replay.rs`).
//!
//! A target returns normally for every input: the input may be refused with an error, but
//! nothing may panic (inside cadr or a dependency, even where the load's panic boundary catches
//! it), abort, hang or allocate without bound. What
//! a reader accepts must also survive what cadr does next with it: validation, flattening into a
//! scene tree, conversion to CSF and back, and import into a scene graph through the C API.

use std::ffi::CString;
use std::path::{Path, PathBuf};

use cadr_core::csf::{csf_from_scene, read_csf, write_csf};
use cadr_core::load::{load_bytes, LoadError, SceneFormat, READER_PANIC};
use cadr_core::scene::{flatten, Scene};

/// The fuzz targets, by the name of their corpus directory.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// glTF 2.0, JSON or GLB (told apart by the GLB magic).
    Gltf,
    /// CSF, plain or gzip-compressed (told apart by the gzip magic).
    Csf,
    /// `cadr_scene_load` through the C API, on a file of any format cadr reads.
    SceneLoad,
}

impl Target {
    /// Every target.
    pub const ALL: [Target; 3] = [Target::Gltf, Target::Csf, Target::SceneLoad];

    /// The name of the target's corpus and findings directories.
    pub fn name(self) -> &'static str {
        match self {
            Target::Gltf => "gltf",
            Target::Csf => "csf",
            Target::SceneLoad => "scene_load",
        }
    }

    /// Runs the target on one input.
    pub fn run(self, data: &[u8]) {
        match self {
            Target::Gltf => gltf(data),
            Target::Csf => csf(data),
            Target::SceneLoad => scene_load(data),
        }
    }
}

/// The format a file's first bytes say: GLB, gzip (a `.csf.gz`), CSF, else glTF JSON.
pub fn sniff_format(data: &[u8]) -> SceneFormat {
    if data.starts_with(b"glTF") {
        SceneFormat::Glb
    } else if data.starts_with(&[0x1f, 0x8b]) {
        SceneFormat::CsfGz
    } else if data.starts_with(&cadr_core::csf::MAGIC.to_le_bytes()) {
        SceneFormat::Csf
    } else {
        SceneFormat::Gltf
    }
}

/// A path in no directory that exists: external glTF buffers are not found, whatever they name.
fn nowhere(file_name: &str) -> PathBuf {
    Path::new("/nonexistent/cadr-fuzz").join(file_name)
}

/// The glTF reader, then what cadr does with a scene it accepted.
pub fn gltf(data: &[u8]) {
    let (format, name) = match sniff_format(data) {
        SceneFormat::Glb => (SceneFormat::Glb, "input.glb"),
        _ => (SceneFormat::Gltf, "input.gltf"),
    };
    if let Some(scene) = loaded(load_bytes(data, format, &nowhere(name))) {
        use_accepted(&scene);
    }
}

/// The scene a reader accepted, `None` for a refusal; a panic that the load's panic boundary
/// caught is still a finding, and panics here.
fn loaded(result: Result<Scene, LoadError>) -> Option<Scene> {
    match result {
        Ok(scene) => Some(scene),
        Err(error @ LoadError::ReaderPanicked { .. }) => {
            panic!("the load's panic boundary caught a panic: {error}")
        }
        Err(_) => None,
    }
}

/// The CSF reader (gzip when the input starts with the gzip magic), then what cadr does with a
/// scene it accepted; a file that reads also writes back to the same bytes.
pub fn csf(data: &[u8]) {
    let gzip = sniff_format(data) == SceneFormat::CsfGz;
    let (format, name) = if gzip {
        (SceneFormat::CsfGz, "input.csf.gz")
    } else {
        (SceneFormat::Csf, "input.csf")
    };
    if !gzip {
        if let Ok(file) = read_csf(data) {
            // Compared as bytes: a mutation may have written a NaN, which is not equal to itself.
            let written = write_csf(&file, file.version);
            let again = read_csf(&written).expect("what cadr writes, it reads");
            assert!(
                write_csf(&again, again.version) == written,
                "a CSF file read and written twice changed"
            );
        }
    }
    if let Some(scene) = loaded(load_bytes(data, format, &nowhere(name))) {
        use_accepted(&scene);
    }
}

/// A loaded scene validates, flattens into a scene tree, and converts to CSF and back.
fn use_accepted(scene: &Scene) {
    scene.validate().expect("a loaded scene is valid");
    flatten(scene).expect("a valid scene flattens");
    let file = csf_from_scene(scene).expect("a valid scene converts to CSF");
    let bytes = write_csf(&file, file.version);
    read_csf(&bytes).expect("a converted scene reads back");
}

/// `cadr_scene_load` on the input written to a file (its extension from [`sniff_format`]),
/// into a new scene. Refusals are `CADR_RESULT_LOAD_FAILED`; `CADR_RESULT_PANIC` (a panic the
/// C API caught) and a refusal by the load's panic boundary (a panic it caught) are findings.
pub fn scene_load(data: &[u8]) {
    use cadr::*;
    let extension = match sniff_format(data) {
        SceneFormat::Glb => "glb",
        SceneFormat::CsfGz => "csf.gz",
        SceneFormat::Csf => "csf",
        SceneFormat::Gltf => "gltf",
    };
    let dir = std::env::temp_dir().join(format!("cadr-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a scratch directory");
    let path = dir.join(format!("input.{extension}"));
    std::fs::write(&path, data).expect("the input written");
    let c_path = CString::new(path.to_string_lossy().as_bytes()).expect("a path without NUL");

    let mut scene: CadrScene = std::ptr::null_mut();
    // SAFETY: `scene` is writable.
    assert_eq!(unsafe { cadr_scene_create(&mut scene) }, CadrResult::Ok);
    let mut root: CadrNode = 0;
    // SAFETY: `root` is writable; `scene` was just created.
    assert_eq!(unsafe { cadr_scene_root(scene, &mut root) }, CadrResult::Ok);
    let mut loaded = std::mem::MaybeUninit::<CadrLoadResult>::zeroed();
    // SAFETY: zero bytes are a CadrLoadResult; its size, the first field, is the host's to set.
    unsafe {
        loaded
            .as_mut_ptr()
            .cast::<u32>()
            .write(std::mem::size_of::<CadrLoadResult>() as u32)
    };
    // SAFETY: `c_path` is a NUL-terminated string; `loaded` is writable.
    let result = unsafe { cadr_scene_load(scene, c_path.as_ptr(), root, loaded.as_mut_ptr()) };
    let message = last_error();
    assert!(
        matches!(result, CadrResult::Ok | CadrResult::LoadFailed),
        "cadr_scene_load returned {result:?}: {message}"
    );
    if result == CadrResult::LoadFailed {
        assert!(!message.is_empty(), "a refusal without a message");
        assert!(
            !message.contains(READER_PANIC),
            "the load's panic boundary caught a panic: {message}"
        );
    }
    // SAFETY: `loaded` is zeroed or filled by cadr_scene_load.
    unsafe { cadr_load_result_free(loaded.as_mut_ptr()) };
    assert_eq!(cadr_scene_destroy(scene), CadrResult::Ok);
    let _ = std::fs::remove_file(&path);
}

fn last_error() -> String {
    let mut length = 0usize;
    // SAFETY: a NULL buffer asks for the needed capacity, written to `length`.
    unsafe { cadr::cadr_last_error_message(std::ptr::null_mut(), 0, &mut length) };
    let mut buffer = vec![0u8; length.max(1)];
    // SAFETY: `buffer` is writable for its length.
    unsafe { cadr::cadr_last_error_message(buffer.as_mut_ptr().cast(), buffer.len(), &mut length) };
    buffer.truncate(length.min(buffer.len()));
    String::from_utf8_lossy(&buffer).into_owned()
}
