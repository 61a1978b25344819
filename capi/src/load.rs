//! Loading a file or a generator into a scene, and the list of what it created.

use std::ffi::c_char;

use cadr_core::load::SceneSource;

use crate::args::{check_owning_size, deliver_sized, read_sized, required_str};
use crate::error::{guard, CadrResult, Failure};
use crate::scene::{
    geometry_value, material_value, node_of, node_value, with_scene, CadrGeometry, CadrMaterial,
    CadrNode, CadrScene,
};

/// The size of `CadrLoadResult` in version 1.0: every later header's is at least this, and
/// holds its arrays.
const FIRST_SIZE: usize = 64;
const _: () = assert!(std::mem::size_of::<CadrLoadResult>() >= FIRST_SIZE);

/// What `cadr_scene_load` created. Free the arrays with `cadr_load_result_free`.
///
/// The struct grows by appending fields: the host sets `size` to `sizeof(CadrLoadResult)`;
/// cadr fills the fields within it and zeroes those of a newer header it does not know.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrLoadResult {
    /// `sizeof(CadrLoadResult)`, set by the host.
    pub size: u32,
    /// The new Group, named after the file, that holds the file's content.
    pub root: CadrNode,
    /// Every node created, `root` first.
    pub nodes: *mut CadrNode,
    /// Number of `nodes`.
    pub node_count: usize,
    /// The file's geometries, in the file's order.
    pub geometries: *mut CadrGeometry,
    /// Number of `geometries`.
    pub geometry_count: usize,
    /// The file's materials, in the file's order.
    pub materials: *mut CadrMaterial,
    /// Number of `materials`.
    pub material_count: usize,
}

/// Loads a scene file (`.gltf`, `.glb`, `.csf`, `.csf.gz`) or a built-in generator
/// (`gen:demo`, `gen:grid:parts=N`, …) and adds it below `parent` under a new Group named after
/// it. On success `*result` lists what was created; free it with `cadr_load_result_free`.
/// Each geometry goes to the scene's page file as soon as it is read where the scene's
/// geometry memory limit (`cadr_scene_set_geometry_memory_limit`) is reached, so that a model
/// larger than memory loads.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_LOAD_FAILED` (the
/// message names the file and the bad item; nothing is added) or a handle error. A panic while
/// the file is read (a bug, in cadr or a library it uses) is also `CADR_RESULT_LOAD_FAILED`,
/// saying the file could not be read, and its location goes to the message callback as an
/// error: a load never returns `CADR_RESULT_PANIC`.
/// Ownership: `path` is read during the call; the arrays in `*result` are the caller's until
/// `cadr_load_result_free`. Thread-safety: as `cadr_scene_create`; the file is read while the
/// scene is not locked.
///
/// # Safety
/// `path` is null or a valid string; `result` is null or writable for its `size`.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_load(
    scene: CadrScene,
    path: *const c_char,
    parent: CadrNode,
    result: *mut CadrLoadResult,
) -> CadrResult {
    guard(|| {
        // SAFETY: forwarded contract.
        let path = unsafe { required_str(path, "path") }?;
        // SAFETY: null or writable for its size (the caller's contract).
        unsafe { check_owning_size(result, ("result", "CadrLoadResult"), FIRST_SIZE) }?;
        // Check the handles before the (possibly long) load, and take the graph's memory
        // left: the load keeps that much geometry in memory and pages the rest.
        let memory_left = with_scene(scene, |s| {
            node_of(&s.graph, parent, "parent")?;
            Ok(s.graph.geometry_memory_left())
        })?;
        let load =
            |e: cadr_core::load::LoadError| Failure::new(CadrResult::LoadFailed, e.to_string());
        let (outline, geometries) = SceneSource::parse(path)
            .map_err(load)?
            .load_for_graph(memory_left)
            .map_err(load)?;
        let imported = with_scene(scene, |s| {
            let parent = node_of(&s.graph, parent, "parent")?;
            s.graph
                .import_loaded(&outline, geometries, parent)
                .map_err(|e| Failure::new(CadrResult::LoadFailed, format!("{path}: {e}")))
        })?;
        let boxed = |values: Vec<u64>| -> (*mut u64, usize) {
            let count = values.len();
            (
                Box::into_raw(values.into_boxed_slice()).cast::<u64>(),
                count,
            )
        };
        let (nodes, node_count) = boxed(imported.nodes.iter().map(|&n| node_value(n)).collect());
        let (geometries, geometry_count) = boxed(
            imported
                .geometries
                .iter()
                .map(|&g| geometry_value(g))
                .collect(),
        );
        let (materials, material_count) = boxed(
            imported
                .materials
                .iter()
                .map(|&m| material_value(m))
                .collect(),
        );
        let value = CadrLoadResult {
            size: std::mem::size_of::<CadrLoadResult>() as u32,
            root: node_value(imported.root),
            nodes,
            node_count,
            geometries,
            geometry_count,
            materials,
            material_count,
        };
        // SAFETY: result is writable for its size, checked to hold every array (the caller's
        // contract).
        unsafe { deliver_sized(result, "result", value) }
    })
}

/// Frees the arrays of a load result and zeroes it. NULL, or a zeroed result, is a no-op.
///
/// Ownership: takes back what `cadr_scene_load` handed out; free each result once.
/// Thread-safety: callable from any thread.
///
/// # Safety
/// `result` is null or a result filled by `cadr_scene_load` (or zeroed).
#[no_mangle]
pub unsafe extern "C" fn cadr_load_result_free(result: *mut CadrLoadResult) {
    if result.is_null() {
        return;
    }
    // SAFETY: non-null, readable for its size and filled by cadr_scene_load or zeroed (the
    // caller's contract); zero bytes are a CadrLoadResult (null arrays).
    let Ok(taken) =
        (unsafe { read_sized(result, ("result", "CadrLoadResult"), std::mem::zeroed()) })
    else {
        log::error!("cadr_load_result_free: the result's size is not one cadr_scene_load filled; nothing freed");
        return;
    };
    let free = |items: *mut u64, count: usize| {
        if !items.is_null() {
            // SAFETY: made by Box::into_raw of a boxed slice of `count` items in
            // cadr_scene_load, and freed once (the result is zeroed below).
            drop(unsafe { Box::from_raw(std::ptr::slice_from_raw_parts_mut(items, count)) });
        }
    };
    free(taken.nodes, taken.node_count);
    free(taken.geometries, taken.geometry_count);
    free(taken.materials, taken.material_count);
    // SAFETY: non-null and writable for its size; zero bytes are a CadrLoadResult.
    let _ = unsafe { deliver_sized(result, "result", std::mem::zeroed()) };
}
