//! Scenes: the scene graph a host edits (nodes of every kind, geometry, materials, loaded
//! files) and the scene tree that flattens it incrementally for renderers.

use std::ffi::c_char;

use cadr_core::graph::{
    GeometryHandle, GraphError, MaterialHandle, NodeFlags, NodeHandle, SceneGraph,
};
use cadr_core::load::SceneSource;
use cadr_core::scene::Aabb;
use cadr_core::tree::SceneTree;

use crate::args::{deliver, matrix, non_null, optional_str, required_str, slice};
use crate::error::{guard, CadrResult, Failure};
use crate::handles::{lock, Registry};

/// Opaque type behind [`CadrScene`].
pub struct CadrSceneObject {
    _private: (),
}

/// A scene: a scene graph with one root Group, and the scene tree flattened from it.
/// Created by `cadr_scene_create`, released by `cadr_scene_destroy`. A scene needs no context:
/// any renderer can draw it.
pub type CadrScene = *mut CadrSceneObject;

/// A node of a scene (0 is never a valid node). Generation-checked: a destroyed node's handle
/// gives `CADR_RESULT_DESTROYED_HANDLE`.
pub type CadrNode = u64;

/// A geometry of a scene (0 is never valid).
pub type CadrGeometry = u64;

/// A material of a scene (0 is never valid).
pub type CadrMaterial = u64;

/// Node flag: the node and its subtree are drawn.
pub const CADR_NODE_VISIBLE: u32 = 1;
/// Node flag: the node's parts can be picked.
pub const CADR_NODE_PICKABLE: u32 = 2;
/// Node flag: the node's parts are drawn highlighted.
pub const CADR_NODE_HIGHLIGHTED: u32 = 4;

/// An axis-aligned box in world space; `min` > `max` when empty.
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
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CadrSceneStatistics {
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
}

/// What `cadr_scene_load` created. Free the arrays with `cadr_load_result_free`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrLoadResult {
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

/// What a scene holds.
pub(crate) struct SceneState {
    pub(crate) graph: SceneGraph,
    /// The scene tree; each renderer that draws the scene reads its changes as a reader of
    /// its own, so renderers drawing one scene alternately upload only what changed.
    pub(crate) tree: SceneTree,
}

impl SceneState {
    /// Brings the tree up to date with the graph's edits.
    pub(crate) fn update(&mut self) {
        self.tree.update(&mut self.graph);
    }
}

pub(crate) static SCENES: Registry<SceneState> = Registry::new(0xC2, "scene");

const NODE_TAG: u64 = 0x4E;
const GEOMETRY_TAG: u64 = 0x47;
const MATERIAL_TAG: u64 = 0x4D;
const GENERATION_MASK: u32 = 0xff_ffff;

fn encode(tag: u64, index: u32, generation: u32) -> u64 {
    tag << 56 | u64::from(generation & GENERATION_MASK) << 32 | u64::from(index)
}

/// Decodes an item handle: checks its tag, finds the live handle in its slot and compares
/// generations.
fn decode<T>(
    value: u64,
    tag: u64,
    what: &str,
    type_name: &str,
    capacity: usize,
    handle_at: impl Fn(u32) -> Option<cadr_core::graph::Handle<T>>,
) -> Result<cadr_core::graph::Handle<T>, Failure> {
    if value == 0 {
        return Err(Failure::new(
            CadrResult::NullArgument,
            format!("{what} is 0"),
        ));
    }
    let index = value as u32;
    let generation = (value >> 32) as u32 & GENERATION_MASK;
    let foreign = || {
        Failure::new(
            CadrResult::ForeignHandle,
            format!("{what} ({value:#x}) is not a {type_name} of this scene"),
        )
    };
    if value >> 56 != tag || index as usize >= capacity {
        return Err(foreign());
    }
    match handle_at(index) {
        Some(handle) if handle.generation() & GENERATION_MASK == generation => Ok(handle),
        _ => Err(Failure::new(
            CadrResult::DestroyedHandle,
            format!("{what} ({value:#x}) is a destroyed {type_name}"),
        )),
    }
}

pub(crate) fn node_of(
    graph: &SceneGraph,
    value: CadrNode,
    what: &str,
) -> Result<NodeHandle, Failure> {
    let capacity = graph.capacities().0;
    decode(value, NODE_TAG, what, "node", capacity, |i| {
        graph.node_handle_at(i)
    })
}

pub(crate) fn geometry_of(
    graph: &SceneGraph,
    value: CadrGeometry,
    what: &str,
) -> Result<GeometryHandle, Failure> {
    let capacity = graph.capacities().1;
    decode(value, GEOMETRY_TAG, what, "geometry", capacity, |i| {
        graph.geometry_handle_at(i)
    })
}

pub(crate) fn material_of(
    graph: &SceneGraph,
    value: CadrMaterial,
    what: &str,
) -> Result<MaterialHandle, Failure> {
    let capacity = graph.capacities().2;
    decode(value, MATERIAL_TAG, what, "material", capacity, |i| {
        graph.material_handle_at(i)
    })
}

pub(crate) fn node_value(handle: NodeHandle) -> CadrNode {
    encode(NODE_TAG, handle.index(), handle.generation())
}

pub(crate) fn geometry_value(handle: GeometryHandle) -> CadrGeometry {
    encode(GEOMETRY_TAG, handle.index(), handle.generation())
}

pub(crate) fn material_value(handle: MaterialHandle) -> CadrMaterial {
    encode(MATERIAL_TAG, handle.index(), handle.generation())
}

/// A graph error as a result code and message.
pub(crate) fn graph_failure(error: GraphError) -> Failure {
    let code = match error {
        GraphError::StaleNode { .. }
        | GraphError::StaleGeometry { .. }
        | GraphError::StaleMaterial { .. } => CadrResult::DestroyedHandle,
        GraphError::InUse { .. } => CadrResult::InUse,
        _ => CadrResult::InvalidArgument,
    };
    Failure::new(code, error.to_string())
}

/// Runs `edit` on a scene's state.
pub(crate) fn with_scene<R>(
    scene: CadrScene,
    edit: impl FnOnce(&mut SceneState) -> Result<R, Failure>,
) -> Result<R, Failure> {
    let object = SCENES.get(scene as u64, "scene")?;
    let mut state = lock(&object);
    edit(&mut state)
}

/// Creates an empty scene (a root Group only).
///
/// Returns `CADR_RESULT_OK` and writes `*scene`, or `CADR_RESULT_NULL_ARGUMENT`.
/// Ownership: the scene is the caller's until `cadr_scene_destroy`. Thread-safety: callable
/// from any thread; a scene may be used from several threads, one call at a time (an internal
/// lock serialises them).
///
/// # Safety
/// `scene` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_create(scene: *mut CadrScene) -> CadrResult {
    guard(|| {
        let mut graph = SceneGraph::new();
        let tree = SceneTree::build(&mut graph);
        let state = SceneState { graph, tree };
        let handle = SCENES.insert(state)?;
        // SAFETY: scene is null or writable (the caller's contract).
        unsafe { deliver(scene, "scene", handle as CadrScene) }
    })
}

/// Destroys a scene and everything in it; its node, geometry and material handles become
/// invalid. NULL is a no-op.
///
/// Returns `CADR_RESULT_OK` or a handle error.
/// Ownership: the handle (or item) is given back to cadr and invalid afterwards.
/// Thread-safety: not while another thread uses the scene.
#[no_mangle]
pub extern "C" fn cadr_scene_destroy(scene: CadrScene) -> CadrResult {
    guard(|| {
        let removed = SCENES.remove(scene as u64, "scene")?;
        drop(removed);
        Ok(())
    })
}

/// Writes the scene's root Group.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the outputs are the caller's; cadr keeps no pointer to them.
/// Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// `root` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_root(scene: CadrScene, root: *mut CadrNode) -> CadrResult {
    guard(|| {
        let value = with_scene(scene, |s| Ok(node_value(s.graph.root())))?;
        // SAFETY: root is null or writable (the caller's contract).
        unsafe { deliver(root, "root", value) }
    })
}

/// The kinds of node `create_node` makes.
enum NewNode<'a> {
    Group,
    Transform(*const f64),
    Switch,
    Billboard,
    Geo(CadrGeometry, &'a [CadrMaterial]),
    Lod(&'a [f64], Option<f64>),
}

/// Creates a node of `kind` named `name` (NULL: empty) and writes its handle.
///
/// # Safety
/// `name` is null or a valid string; `node` is null or writable; pointers inside `kind` are
/// null or valid.
unsafe fn create_node(
    scene: CadrScene,
    name: *const c_char,
    kind: NewNode<'_>,
    node: *mut CadrNode,
) -> Result<(), Failure> {
    // SAFETY: forwarded contract.
    let name = unsafe { optional_str(name, "name")? }.unwrap_or("");
    let value = with_scene(scene, |s| {
        let graph = &mut s.graph;
        let handle = match kind {
            NewNode::Group => graph.create_group(name),
            NewNode::Switch => graph.create_switch(name),
            NewNode::Billboard => graph.create_billboard(name),
            NewNode::Transform(values) => {
                // SAFETY: forwarded contract.
                let m = unsafe { matrix(values, "matrix") }?;
                graph.create_transform(name, m).map_err(graph_failure)?
            }
            NewNode::Geo(geometry, materials) => {
                let geometry = geometry_of(graph, geometry, "geometry")?;
                let materials = materials
                    .iter()
                    .enumerate()
                    .map(|(i, &m)| material_of(graph, m, &format!("part_materials[{i}]")))
                    .collect::<Result<Vec<_>, _>>()?;
                graph
                    .create_geo(name, geometry, &materials)
                    .map_err(graph_failure)?
            }
            NewNode::Lod(thresholds, None) => {
                graph.create_lod(name, thresholds).map_err(graph_failure)?
            }
            NewNode::Lod(thresholds, Some(radius)) => graph
                .create_lod_by_screen_size(name, radius, thresholds)
                .map_err(graph_failure)?,
        };
        Ok(node_value(handle))
    })?;
    // SAFETY: node is null or writable (the caller's contract).
    unsafe { deliver(node, "node", value) }
}

/// Creates a Group (not attached yet). `name` may be NULL.
///
/// Returns `CADR_RESULT_OK` and writes `*node`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the node belongs to the scene; `name` is copied. Thread-safety: as
/// `cadr_scene_create`.
///
/// # Safety
/// `name` is null or a valid string; `node` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_create_group(
    scene: CadrScene,
    name: *const c_char,
    node: *mut CadrNode,
) -> CadrResult {
    // SAFETY: forwarded contract.
    guard(|| unsafe { create_node(scene, name, NewNode::Group, node) })
}

/// Creates a Transform with a 4×4 column-major double matrix (child space to parent space).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_INVALID_ARGUMENT`
/// (non-finite values) or a handle error.
/// Ownership: as `cadr_scene_create_group`; the matrix is copied.
/// Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// `matrix` is null or 16 readable doubles; as `cadr_scene_create_group` otherwise.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_create_transform(
    scene: CadrScene,
    name: *const c_char,
    matrix: *const f64,
    node: *mut CadrNode,
) -> CadrResult {
    // SAFETY: forwarded contract.
    guard(|| unsafe { create_node(scene, name, NewNode::Transform(matrix), node) })
}

/// Creates a Geo node that draws `geometry` with one material per part
/// (`part_material_count` must equal the geometry's part count).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_INVALID_ARGUMENT`
/// (wrong count) or a handle error naming the bad handle.
/// Ownership: as `cadr_scene_create_group`; the array is copied.
/// Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// `part_materials` is null or `part_material_count` readable handles; as
/// `cadr_scene_create_group` otherwise.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_create_geo(
    scene: CadrScene,
    name: *const c_char,
    geometry: CadrGeometry,
    part_materials: *const CadrMaterial,
    part_material_count: u32,
    node: *mut CadrNode,
) -> CadrResult {
    guard(|| {
        // SAFETY: forwarded contract.
        let materials = unsafe {
            slice(
                part_materials,
                part_material_count as usize,
                "part_materials",
            )
        }?;
        // SAFETY: forwarded contract.
        unsafe { create_node(scene, name, NewNode::Geo(geometry, materials), node) }
    })
}

/// Creates a Switch: it shows only the children its mask enables (all, until
/// `cadr_scene_set_switch_mask`).
///
/// Returns and ownership as `cadr_scene_create_group`. Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// As `cadr_scene_create_group`.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_create_switch(
    scene: CadrScene,
    name: *const c_char,
    node: *mut CadrNode,
) -> CadrResult {
    // SAFETY: forwarded contract.
    guard(|| unsafe { create_node(scene, name, NewNode::Switch, node) })
}

/// Creates a Billboard: its children turn about +Y to face the eye.
///
/// Returns and ownership as `cadr_scene_create_group`. Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// As `cadr_scene_create_group`.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_create_billboard(
    scene: CadrScene,
    name: *const c_char,
    node: *mut CadrNode,
) -> CadrResult {
    // SAFETY: forwarded contract.
    guard(|| unsafe { create_node(scene, name, NewNode::Billboard, node) })
}

/// Creates a LOD node that shows child `i` while the eye's distance lies between
/// `distances[i - 1]` and `distances[i]` (increasing; one fewer than the children).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_INVALID_ARGUMENT` (not
/// increasing, not finite) or a handle error.
/// Ownership: as `cadr_scene_create_group`; the array is copied.
/// Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// `distances` is null or `distance_count` readable doubles; as `cadr_scene_create_group`.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_create_lod(
    scene: CadrScene,
    name: *const c_char,
    distances: *const f64,
    distance_count: u32,
    node: *mut CadrNode,
) -> CadrResult {
    guard(|| {
        // SAFETY: forwarded contract.
        let distances = unsafe { slice(distances, distance_count as usize, "distances") }?;
        // SAFETY: forwarded contract.
        unsafe { create_node(scene, name, NewNode::Lod(distances, None), node) }
    })
}

/// Creates a LOD node chosen by size on screen: the angle (radians) that a sphere of `radius`
/// at the node's origin subtends at the eye; child `i` shows while the angle lies between
/// `angles[i - 1]` and `angles[i]` (decreasing).
///
/// Returns, ownership and thread-safety as `cadr_scene_create_lod`.
///
/// # Safety
/// As `cadr_scene_create_lod`.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_create_lod_by_screen_size(
    scene: CadrScene,
    name: *const c_char,
    radius: f64,
    angles: *const f64,
    angle_count: u32,
    node: *mut CadrNode,
) -> CadrResult {
    guard(|| {
        // SAFETY: forwarded contract.
        let angles = unsafe { slice(angles, angle_count as usize, "angles") }?;
        // SAFETY: forwarded contract.
        unsafe { create_node(scene, name, NewNode::Lod(angles, Some(radius)), node) }
    })
}

/// Destroys a node: it is removed from all its parents; its children stay alive (they are
/// detached from it). The root cannot be destroyed.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_INVALID_ARGUMENT` (the root) or a handle error.
/// Ownership: the handle (or item) is given back to cadr and invalid afterwards.
/// Thread-safety: as `cadr_scene_create`.
#[no_mangle]
pub extern "C" fn cadr_scene_destroy_node(scene: CadrScene, node: CadrNode) -> CadrResult {
    guard(|| {
        with_scene(scene, |s| {
            let node = node_of(&s.graph, node, "node")?;
            s.graph.destroy_node(node).map_err(graph_failure)
        })
    })
}

/// Appends `child` to `parent`'s children. A node may have several parents (shared
/// subgraphs); cycles are refused.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_INVALID_ARGUMENT` (a cycle) or a handle error.
/// Ownership: nothing changes hands; the arguments are read during the call only.
/// Thread-safety: as `cadr_scene_create`.
#[no_mangle]
pub extern "C" fn cadr_scene_add_child(
    scene: CadrScene,
    parent: CadrNode,
    child: CadrNode,
) -> CadrResult {
    guard(|| {
        with_scene(scene, |s| {
            let parent = node_of(&s.graph, parent, "parent")?;
            let child = node_of(&s.graph, child, "child")?;
            s.graph.add_child(parent, child).map_err(graph_failure)
        })
    })
}

/// Inserts `child` at `position` (0 to the child count) of `parent`'s children.
///
/// Returns as `cadr_scene_add_child`, and `CADR_RESULT_INVALID_ARGUMENT` for a position out of
/// Ownership: nothing changes hands; the arguments are read during the call only.
/// range. Thread-safety: as `cadr_scene_create`.
#[no_mangle]
pub extern "C" fn cadr_scene_insert_child(
    scene: CadrScene,
    parent: CadrNode,
    position: u32,
    child: CadrNode,
) -> CadrResult {
    guard(|| {
        with_scene(scene, |s| {
            let parent = node_of(&s.graph, parent, "parent")?;
            let child = node_of(&s.graph, child, "child")?;
            s.graph
                .insert_child(parent, position as usize, child)
                .map_err(graph_failure)
        })
    })
}

/// Removes `child` from `parent`'s children (its first occurrence). The child stays alive.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_INVALID_ARGUMENT` (not a child) or a handle error.
/// Ownership: nothing changes hands; the arguments are read during the call only.
/// Thread-safety: as `cadr_scene_create`.
#[no_mangle]
pub extern "C" fn cadr_scene_remove_child(
    scene: CadrScene,
    parent: CadrNode,
    child: CadrNode,
) -> CadrResult {
    guard(|| {
        with_scene(scene, |s| {
            let parent = node_of(&s.graph, parent, "parent")?;
            let child = node_of(&s.graph, child, "child")?;
            s.graph.remove_child(parent, child).map_err(graph_failure)
        })
    })
}

/// Writes the number of children of `node`.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the outputs are the caller's; cadr keeps no pointer to them.
/// Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// `count` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_child_count(
    scene: CadrScene,
    node: CadrNode,
    count: *mut u32,
) -> CadrResult {
    guard(|| {
        let value = with_scene(scene, |s| {
            let node = node_of(&s.graph, node, "node")?;
            Ok(s.graph.node(node).map_err(graph_failure)?.children().len() as u32)
        })?;
        // SAFETY: count is null or writable (the caller's contract).
        unsafe { deliver(count, "count", value) }
    })
}

/// Writes child `index` of `node`.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NOT_FOUND` (index out of range),
/// Ownership: the outputs are the caller's; cadr keeps no pointer to them.
/// `CADR_RESULT_NULL_ARGUMENT` or a handle error. Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// `child` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_child(
    scene: CadrScene,
    node: CadrNode,
    index: u32,
    child: *mut CadrNode,
) -> CadrResult {
    guard(|| {
        let value = with_scene(scene, |s| {
            let node = node_of(&s.graph, node, "node")?;
            let children = s.graph.node(node).map_err(graph_failure)?.children();
            children
                .get(index as usize)
                .map(|link| node_value(link.node))
                .ok_or_else(|| {
                    Failure::new(
                        CadrResult::NotFound,
                        format!(
                            "child index {index} is out of range (0..{})",
                            children.len()
                        ),
                    )
                })
        })?;
        // SAFETY: child is null or writable (the caller's contract).
        unsafe { deliver(child, "child", value) }
    })
}

/// Sets a Transform's 4×4 column-major double matrix.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_INVALID_ARGUMENT` (not
/// Ownership: nothing changes hands; the arguments are read during the call only.
/// a Transform, non-finite values) or a handle error. Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// `matrix` is null or 16 readable doubles.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_set_matrix(
    scene: CadrScene,
    node: CadrNode,
    matrix: *const f64,
) -> CadrResult {
    guard(|| {
        // SAFETY: forwarded contract.
        let m = unsafe { crate::args::matrix(matrix, "matrix") }?;
        with_scene(scene, |s| {
            let node = node_of(&s.graph, node, "node")?;
            s.graph.set_matrix(node, m).map_err(graph_failure)
        })
    })
}

/// Sets which children of a Switch are shown: `mask[i]` for child `i`; `count` must equal the
/// child count.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_INVALID_ARGUMENT` (not a
/// Ownership: nothing changes hands; the arguments are read during the call only.
/// Switch, wrong count) or a handle error. Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// `mask` is null or `count` readable bools.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_set_switch_mask(
    scene: CadrScene,
    node: CadrNode,
    mask: *const bool,
    count: u32,
) -> CadrResult {
    guard(|| {
        // SAFETY: forwarded contract.
        let mask = unsafe { slice(mask, count as usize, "mask") }?;
        with_scene(scene, |s| {
            let node = node_of(&s.graph, node, "node")?;
            s.graph.set_switch_mask(node, mask).map_err(graph_failure)
        })
    })
}

/// Sets a node's flags (`CADR_NODE_VISIBLE | CADR_NODE_PICKABLE | CADR_NODE_HIGHLIGHTED`).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_INVALID_ARGUMENT` (unknown bits) or a handle error.
/// Ownership: nothing changes hands; the arguments are read during the call only.
/// Thread-safety: as `cadr_scene_create`.
#[no_mangle]
pub extern "C" fn cadr_scene_set_flags(scene: CadrScene, node: CadrNode, flags: u32) -> CadrResult {
    guard(|| {
        let known = CADR_NODE_VISIBLE | CADR_NODE_PICKABLE | CADR_NODE_HIGHLIGHTED;
        if flags & !known != 0 {
            return Err(Failure::invalid(format!(
                "flags {flags:#x} has unknown bits {:#x}",
                flags & !known
            )));
        }
        with_scene(scene, |s| {
            let node = node_of(&s.graph, node, "node")?;
            let flags = NodeFlags {
                visible: flags & CADR_NODE_VISIBLE != 0,
                pickable: flags & CADR_NODE_PICKABLE != 0,
                highlighted: flags & CADR_NODE_HIGHLIGHTED != 0,
            };
            s.graph.set_flags(node, flags).map_err(graph_failure)
        })
    })
}

/// Writes a node's flags.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the outputs are the caller's; cadr keeps no pointer to them.
/// Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// `flags` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_flags(
    scene: CadrScene,
    node: CadrNode,
    flags: *mut u32,
) -> CadrResult {
    guard(|| {
        let value = with_scene(scene, |s| {
            let node = node_of(&s.graph, node, "node")?;
            let f = s.graph.node(node).map_err(graph_failure)?.flags;
            let bit = |set: bool, flag: u32| if set { flag } else { 0 };
            Ok(bit(f.visible, CADR_NODE_VISIBLE)
                | bit(f.pickable, CADR_NODE_PICKABLE)
                | bit(f.highlighted, CADR_NODE_HIGHLIGHTED))
        })?;
        // SAFETY: flags is null or writable (the caller's contract).
        unsafe { deliver(flags, "flags", value) }
    })
}

/// Gives part `part` of a Geo node another material.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_INVALID_ARGUMENT` (not a Geo node, part out of range)
/// Ownership: nothing changes hands; the arguments are read during the call only.
/// or a handle error. Thread-safety: as `cadr_scene_create`.
#[no_mangle]
pub extern "C" fn cadr_scene_set_part_material(
    scene: CadrScene,
    node: CadrNode,
    part: u32,
    material: CadrMaterial,
) -> CadrResult {
    guard(|| {
        with_scene(scene, |s| {
            let node = node_of(&s.graph, node, "node")?;
            let material = material_of(&s.graph, material, "material")?;
            s.graph
                .set_part_material(node, part as usize, material)
                .map_err(graph_failure)
        })
    })
}

/// Shows or hides part `part` of a Geo node.
///
/// Ownership: nothing changes hands; the arguments are read during the call only.
/// Returns as `cadr_scene_set_part_material`. Thread-safety: as `cadr_scene_create`.
#[no_mangle]
pub extern "C" fn cadr_scene_set_part_visible(
    scene: CadrScene,
    node: CadrNode,
    part: u32,
    visible: bool,
) -> CadrResult {
    guard(|| {
        with_scene(scene, |s| {
            let node = node_of(&s.graph, node, "node")?;
            s.graph
                .set_part_visible(node, part as usize, visible)
                .map_err(graph_failure)
        })
    })
}

/// Loads a scene file (`.gltf`, `.glb`, `.csf`, `.csf.gz`) or a built-in generator
/// (`gen:demo`, `gen:grid:parts=N`, …) and adds it below `parent` under a new Group named after
/// it. On success `*result` lists what was created; free it with `cadr_load_result_free`.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_LOAD_FAILED` (the
/// message names the file and the bad item; nothing is added) or a handle error.
/// Ownership: `path` is read during the call; the arrays in `*result` are the caller's until
/// `cadr_load_result_free`. Thread-safety: as `cadr_scene_create`; the file is read while the
/// scene is not locked.
///
/// # Safety
/// `path` is null or a valid string; `result` is null or writable.
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
        non_null(result, "result")?;
        // Check the handles before the (possibly long) load.
        with_scene(scene, |s| node_of(&s.graph, parent, "parent").map(|_| ()))?;
        let load =
            |e: cadr_core::load::LoadError| Failure::new(CadrResult::LoadFailed, e.to_string());
        let loaded = SceneSource::parse(path)
            .map_err(load)?
            .load()
            .map_err(load)?;
        let imported = with_scene(scene, |s| {
            let parent = node_of(&s.graph, parent, "parent")?;
            s.graph
                .import(&loaded, parent)
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
            root: node_value(imported.root),
            nodes,
            node_count,
            geometries,
            geometry_count,
            materials,
            material_count,
        };
        // SAFETY: result is null or writable (the caller's contract).
        unsafe { deliver(result, "result", value) }
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
    // SAFETY: non-null and filled by cadr_scene_load or zeroed (the caller's contract).
    let taken = unsafe { result.read() };
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
    // SAFETY: non-null and writable.
    unsafe {
        result.write(CadrLoadResult {
            root: 0,
            nodes: std::ptr::null_mut(),
            node_count: 0,
            geometries: std::ptr::null_mut(),
            geometry_count: 0,
            materials: std::ptr::null_mut(),
            material_count: 0,
        })
    };
}

/// World bounds of what the scene shows (only below `below` when given), and its statistics.
fn shown(state: &mut SceneState, below: Option<NodeHandle>) -> (Aabb, CadrSceneStatistics) {
    state.update();
    let (graph, tree) = (&state.graph, &state.tree);
    let mut geometry_bounds: std::collections::HashMap<u32, Aabb> = Default::default();
    let mut bounds = Aabb::default();
    let (nodes, geometries, materials) = graph.counts();
    let mut statistics = CadrSceneStatistics {
        nodes: nodes as u64,
        geometries: geometries as u64,
        materials: materials as u64,
        ..CadrSceneStatistics::default()
    };
    for id in tree.instances() {
        let Some(instance) = tree.instance(id) else {
            continue;
        };
        if let Some(node) = below {
            if !tree.path(instance.tree_node).contains(&node) {
                continue;
            }
        }
        statistics.instances += 1;
        if !instance.visible {
            continue;
        }
        let Some(geometry) = graph.geometry_at(instance.geometry) else {
            continue;
        };
        statistics.visible_instances += 1;
        if let Some(part) = geometry.parts.get(instance.part as usize) {
            statistics.visible_triangles += u64::from(part.triangle_count());
        }
        let local = *geometry_bounds
            .entry(instance.geometry)
            .or_insert_with(|| geometry.bounds());
        bounds.add_box(&local.transformed(&tree.world(instance.tree_node)));
    }
    (bounds, statistics)
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
/// `statistics` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_statistics(
    scene: CadrScene,
    statistics: *mut CadrSceneStatistics,
) -> CadrResult {
    guard(|| {
        let value = with_scene(scene, |s| Ok(shown(s, None).1))?;
        // SAFETY: statistics is null or writable (the caller's contract).
        unsafe { deliver(statistics, "statistics", value) }
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
