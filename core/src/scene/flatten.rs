//! Flattening: one instance per path from a root to a node with a mesh, one draw item per
//! instance and part, world matrices computed once in double precision.

use glam::DMat4;

use super::{Aabb, Geometry, GeometrySummary, NodeIndex, Scene, SceneError};

/// The most draw items a scene may expand to (shared subgraphs multiply paths).
pub const MAX_DRAW_ITEMS: u64 = 1 << 31;

/// One path from a root to a node with a mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instance {
    /// The node at the end of the path.
    pub node: NodeIndex,
    /// The geometry it draws.
    pub geometry: u32,
    /// Product of the local matrices along the path.
    pub world: DMat4,
}

/// One part of one instance: what a draw call draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DrawItem {
    /// Index in [`FlatScene::instances`].
    pub instance: u32,
    /// Index in [`Scene::geometries`].
    pub geometry: u32,
    /// Index of the part in its geometry.
    pub part: u32,
    /// Index in [`Scene::materials`].
    pub material: u32,
    /// First index of the part.
    pub first_index: u32,
    /// Number of indices of the part.
    pub index_count: u32,
}

/// The flattened scene, in depth-first traversal order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FlatScene {
    /// Paths to nodes with meshes.
    pub instances: Vec<Instance>,
    /// One per instance and part.
    pub draws: Vec<DrawItem>,
    /// World-space bounds of everything drawn.
    pub bounds: Aabb,
}

/// Number of draw items the scene expands to (saturating).
fn drawn_parts(scene: &Scene) -> u64 {
    let counts = draw_counts(scene);
    scene
        .roots
        .iter()
        .fold(0_u64, |sum, &r| sum.saturating_add(counts[r as usize]))
}

/// Checks that a scene (otherwise valid) expands to at most [`MAX_DRAW_ITEMS`] drawn parts, and
/// to no more than the memory budget holds ([`crate::memory_budget`]); returns that number.
pub(super) fn check_expansion(scene: &Scene) -> Result<u64, SceneError> {
    let total = drawn_parts(scene);
    if total > MAX_DRAW_ITEMS {
        return Err(SceneError(format!(
            "the scene expands to {total} drawn parts through shared subgraphs (at most {MAX_DRAW_ITEMS})"
        )));
    }
    crate::memory_budget::check_drawn_parts(total).map_err(SceneError)?;
    Ok(total)
}

/// Number of draw items under each node, saturating (memoised over the DAG).
fn draw_counts(scene: &Scene) -> Vec<u64> {
    let mut counts: Vec<Option<u64>> = vec![None; scene.nodes.len()];
    let mut stack: Vec<NodeIndex> = Vec::new();
    for start in 0..scene.nodes.len() as NodeIndex {
        stack.push(start);
        while let Some(&node) = stack.last() {
            if counts[node as usize].is_some() {
                stack.pop();
                continue;
            }
            let children = &scene.nodes[node as usize].children;
            let pending: Vec<NodeIndex> = children
                .iter()
                .copied()
                .filter(|&c| counts[c as usize].is_none())
                .collect();
            if pending.is_empty() {
                let own = scene.nodes[node as usize]
                    .mesh
                    .as_ref()
                    .map_or(0, |m| m.part_materials.len() as u64);
                let total = children.iter().fold(own, |sum, &c| {
                    sum.saturating_add(counts[c as usize].unwrap_or(0))
                });
                counts[node as usize] = Some(total);
                stack.pop();
            } else {
                stack.extend(pending);
            }
        }
    }
    counts.into_iter().map(|c| c.unwrap_or(0)).collect()
}

/// Flattens a validated scene (see [`Scene::validate`]).
pub fn flatten(scene: &Scene) -> Result<FlatScene, SceneError> {
    crate::timings::time(crate::timings::Phase::SceneBuild, || {
        scene.validate_references()?;
        let bounds: Vec<Aabb> = scene.geometries.iter().map(Geometry::bounds).collect();
        flatten_checked(scene, &bounds)
    })
}

/// [`flatten`] for an outline (a scene whose geometries are stand-ins, see
/// [`super::GeometrySink`]), with what is known of each geometry: `summaries`, in the scene's
/// order.
pub fn flatten_outline(
    outline: &Scene,
    summaries: &[GeometrySummary],
) -> Result<FlatScene, SceneError> {
    crate::timings::time(crate::timings::Phase::SceneBuild, || {
        outline.validate_outline_references()?;
        if summaries.len() != outline.geometries.len() {
            return Err(SceneError(format!(
                "{} geometry summaries for {} geometries",
                summaries.len(),
                outline.geometries.len()
            )));
        }
        let bounds: Vec<Aabb> = summaries.iter().map(|s| s.bounds).collect();
        flatten_checked(outline, &bounds)
    })
}

/// Flattens a scene whose references are checked; `geometry_bounds` are its geometries'.
fn flatten_checked(scene: &Scene, geometry_bounds: &[Aabb]) -> Result<FlatScene, SceneError> {
    let total = check_expansion(scene)?;
    let mut flat = FlatScene {
        draws: Vec::with_capacity(total as usize),
        ..FlatScene::default()
    };
    let mut stack: Vec<(NodeIndex, DMat4)> = scene
        .roots
        .iter()
        .rev()
        .map(|&r| (r, DMat4::IDENTITY))
        .collect();
    while let Some((node_index, parent_world)) = stack.pop() {
        let node = &scene.nodes[node_index as usize];
        let world = parent_world * node.local;
        if let Some(mesh) = &node.mesh {
            let instance = flat.instances.len() as u32;
            flat.instances.push(Instance {
                node: node_index,
                geometry: mesh.geometry,
                world,
            });
            let bounds = &geometry_bounds[mesh.geometry as usize];
            flat.bounds.add_box(&bounds.transformed(&world));
            let geometry = &scene.geometries[mesh.geometry as usize];
            for (part_index, (part, &material)) in
                geometry.parts.iter().zip(&mesh.part_materials).enumerate()
            {
                let mut part_instance = instance;
                if let Some(part_override) = mesh.part_override(part_index as u32) {
                    if !part_override.visible {
                        continue;
                    }
                    if let Some(child) = part_override.transform_child {
                        // The part is placed by a child's matrix: it gets an instance of its own.
                        let part_world = world * scene.nodes[child as usize].local;
                        part_instance = flat.instances.len() as u32;
                        flat.instances.push(Instance {
                            node: node_index,
                            geometry: mesh.geometry,
                            world: part_world,
                        });
                        flat.bounds.add_box(&bounds.transformed(&part_world));
                    }
                }
                flat.draws.push(DrawItem {
                    instance: part_instance,
                    geometry: mesh.geometry,
                    part: part_index as u32,
                    material,
                    first_index: part.first_index,
                    index_count: part.index_count,
                });
            }
        }
        stack.extend(node.children.iter().rev().map(|&c| (c, world)));
    }
    Ok(flat)
}
