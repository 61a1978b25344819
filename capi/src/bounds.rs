//! What a scene shows: world bounds (of the scene or below a node) and counts.

use cadr_core::graph::NodeHandle;
use cadr_core::scene::Aabb;

use crate::args::{deliver, deliver_sized};
use crate::error::{guard, CadrResult};
use crate::scene::{node_of, with_scene, CadrNode, CadrScene, SceneState};

/// An axis-aligned box in world space; `min` > `max` when empty.
///
/// Frozen: a box is its two corners, and stays so within a major version.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CadrBounds {
    /// Smallest corner.
    pub min: [f64; 3],
    /// Largest corner.
    pub max: [f64; 3],
}

impl From<Aabb> for CadrBounds {
    fn from(bounds: Aabb) -> Self {
        Self {
            min: bounds.min.to_array(),
            max: bounds.max.to_array(),
        }
    }
}

/// Counts of a scene.
///
/// The struct grows by appending fields: the host sets `size` to `sizeof(CadrSceneStatistics)`; cadr fills
/// the fields within it and zeroes those of a newer header it does not know.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CadrSceneStatistics {
    /// `sizeof(CadrSceneStatistics)`, set by the host.
    pub size: u32,
    /// Live nodes, the root included.
    pub nodes: u64,
    /// Live geometries.
    pub geometries: u64,
    /// Live materials.
    pub materials: u64,
    /// Drawable parts over all paths (a shared subgraph counts once per path).
    pub instances: u64,
    /// Of those, the ones shown (flags, switches, LOD).
    pub visible_instances: u64,
    /// Triangles of the shown instances.
    pub visible_triangles: u64,
    /// Bytes of geometry the scene keeps in host memory (at most its limit: see
    /// `cadr_scene_set_geometry_memory_limit`).
    pub resident_geometry_bytes: u64,
    /// Bytes of geometry the scene keeps in its page file.
    pub paged_geometry_bytes: u64,
    /// Geometries the scene keeps in its page file.
    pub paged_geometries: u64,
}

/// World bounds of what the scene shows (only below `below` when given), and its statistics.
fn shown(state: &mut SceneState, below: Option<NodeHandle>) -> (Aabb, CadrSceneStatistics) {
    state.update();
    let graph = &state.graph;
    let shown = cadr_core::tree::shown(graph, &state.tree, below);
    let (nodes, geometries, materials) = graph.counts();
    let memory = graph.geometry_memory();
    let statistics = CadrSceneStatistics {
        nodes: nodes as u64,
        geometries: geometries as u64,
        materials: materials as u64,
        instances: shown.instances,
        visible_instances: shown.visible_instances,
        visible_triangles: shown.visible_triangles,
        resident_geometry_bytes: memory.resident_bytes,
        paged_geometry_bytes: memory.paged_bytes,
        paged_geometries: memory.paged_geometries,
        ..CadrSceneStatistics::default()
    };
    (shown.bounds, statistics)
}

/// Writes the world-space bounds of everything the scene shows (empty: `min` > `max`).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the outputs are the caller's; cadr keeps no pointer to them.
/// Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// `bounds` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_bounds(
    scene: CadrScene,
    bounds: *mut CadrBounds,
) -> CadrResult {
    guard(|| {
        let value = with_scene(scene, |s| Ok(shown(s, None).0))?;
        // SAFETY: bounds is null or writable (the caller's contract).
        unsafe { deliver(bounds, "bounds", value.into()) }
    })
}

/// Writes the scene's counts: nodes, geometries, materials, instances and what is shown.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the outputs are the caller's; cadr keeps no pointer to them.
/// Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// `statistics` is null or writable for its `size`.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_statistics(
    scene: CadrScene,
    statistics: *mut CadrSceneStatistics,
) -> CadrResult {
    guard(|| {
        let value = with_scene(scene, |s| Ok(shown(s, None).1))?;
        // SAFETY: statistics is null or writable for its size (the caller's contract).
        unsafe { deliver_sized(statistics, "statistics", value) }
    })
}

/// Writes the world-space bounds of what `node` shows, over every path it is reached by
/// (empty: `min` > `max`). Walks all instances of the scene: meant for occasional queries
/// (framing a selection, exploded views), not for every frame.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the outputs are the caller's; cadr keeps no pointer to them.
/// Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// `bounds` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_node_bounds(
    scene: CadrScene,
    node: CadrNode,
    bounds: *mut CadrBounds,
) -> CadrResult {
    guard(|| {
        let value = with_scene(scene, |s| {
            let node = node_of(&s.graph, node, "node")?;
            Ok(shown(s, Some(node)).0)
        })?;
        // SAFETY: bounds is null or writable (the caller's contract).
        unsafe { deliver(bounds, "bounds", value.into()) }
    })
}
