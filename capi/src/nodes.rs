//! Nodes of a scene: creating each kind, the hierarchy (children, insertion, removal) and what a
//! host edits on a node (matrix, switch mask, flags, per-part material and visibility).

use std::ffi::c_char;

use cadr_core::graph::{NodeFlags, NodeKind};

use crate::args::{copy_string_out, deliver, matrix, optional_str, slice};
use crate::error::{guard, CadrResult, Failure};
use crate::scene::{
    geometry_of, graph_failure, material_of, node_of, node_value, with_scene, CadrGeometry,
    CadrMaterial, CadrNode, CadrScene, CADR_NODE_HIGHLIGHTED, CADR_NODE_PICKABLE,
    CADR_NODE_VISIBLE,
};

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
/// range.
/// Ownership: nothing changes hands; the arguments are read during the call only.
/// Thread-safety: as `cadr_scene_create`.
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
/// `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the outputs are the caller's; cadr keeps no pointer to them.
/// Thread-safety: as `cadr_scene_create`.
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

/// What a node does (see the `cadr_scene_create_*` function of each).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CadrNodeKind {
    /// Groups its children.
    Group = 0,
    /// Places its children with a matrix.
    Transform = 1,
    /// Draws a geometry with one material per part.
    Geo = 2,
    /// Shows only its active children.
    Switch = 3,
    /// Shows one child chosen by distance or size on screen.
    Lod = 4,
    /// Turns its children to face the eye.
    Billboard = 5,
}

/// Copies `node`'s name (as it was created; empty when none was given) into `buffer` as a
/// NUL-terminated UTF-8 string, and its length without the NUL into `*length`. With `buffer`
/// NULL or `capacity` too small, writes only the capacity it needs (length + 1) into `*length`
/// and returns `CADR_RESULT_BUFFER_TOO_SMALL`: a host asks once for the size, then again.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_BUFFER_TOO_SMALL`, `CADR_RESULT_NULL_ARGUMENT`
/// (`length` NULL) or a handle error.
/// Ownership: `buffer` is the caller's; cadr keeps no pointer to it.
/// Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// `buffer` is null or writable for `capacity` bytes; `length` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_node_name(
    scene: CadrScene,
    node: CadrNode,
    buffer: *mut c_char,
    capacity: usize,
    length: *mut usize,
) -> CadrResult {
    guard(|| {
        let name = with_scene(scene, |s| {
            let node = node_of(&s.graph, node, "node")?;
            Ok(s.graph.node(node).map_err(graph_failure)?.name.clone())
        })?;
        // SAFETY: the caller's contract, passed on.
        match unsafe { copy_string_out(&name, buffer, capacity, length) } {
            CadrResult::Ok => Ok(()),
            CadrResult::NullArgument => Err(Failure::new(
                CadrResult::NullArgument,
                "length is NULL".to_owned(),
            )),
            other => Err(Failure::new(
                other,
                format!(
                    "the name needs {} bytes, the buffer has {capacity}",
                    name.len() + 1
                ),
            )),
        }
    })
}

/// Writes what `node` does into `*kind`.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the output is the caller's. Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// `kind` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_node_kind(
    scene: CadrScene,
    node: CadrNode,
    kind: *mut CadrNodeKind,
) -> CadrResult {
    guard(|| {
        let value = with_scene(scene, |s| {
            let node = node_of(&s.graph, node, "node")?;
            Ok(match s.graph.node(node).map_err(graph_failure)?.kind {
                NodeKind::Group => CadrNodeKind::Group,
                NodeKind::Transform { .. } => CadrNodeKind::Transform,
                NodeKind::Geo { .. } => CadrNodeKind::Geo,
                NodeKind::Switch => CadrNodeKind::Switch,
                NodeKind::Lod { .. } => CadrNodeKind::Lod,
                NodeKind::Billboard => CadrNodeKind::Billboard,
            })
        })?;
        // SAFETY: kind is null or writable (the caller's contract).
        unsafe { deliver(kind, "kind", value) }
    })
}

/// Sets a Transform's 4×4 column-major double matrix.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_INVALID_ARGUMENT` (not
/// a Transform, non-finite values) or a handle error.
/// Ownership: nothing changes hands; the arguments are read during the call only.
/// Thread-safety: as `cadr_scene_create`.
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
/// Switch, wrong count) or a handle error.
/// Ownership: nothing changes hands; the arguments are read during the call only.
/// Thread-safety: as `cadr_scene_create`.
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
