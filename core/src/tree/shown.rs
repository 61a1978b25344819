//! What a scene shows: the world bounds of its shown instances and their counts, read from the
//! graph and its tree (for `cadr_scene_bounds`, `cadr_scene_statistics` and `cadr render`),
//! with no geometry read: bounds of paged geometries come from what the graph keeps of them.

use std::collections::HashMap;

use super::SceneTree;
use crate::graph::{NodeHandle, SceneGraph};
use crate::scene::Aabb;

/// What the scene (or the part of it below a node) shows.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Shown {
    /// World bounds of the visible instances (empty: `min` > `max`).
    pub bounds: Aabb,
    /// Instances (a path to a Geo node and one of its parts), shown or hidden.
    pub instances: u64,
    /// Instances shown.
    pub visible_instances: u64,
    /// Triangles of the instances shown.
    pub visible_triangles: u64,
}

/// What `tree` (up to date with `graph`) shows, only below `below` when given.
pub fn shown(graph: &SceneGraph, tree: &SceneTree, below: Option<NodeHandle>) -> Shown {
    let mut geometry_bounds: HashMap<u32, Aabb> = HashMap::new();
    let mut shown = Shown::default();
    for id in tree.instances() {
        let Some(instance) = tree.instance(id) else {
            continue;
        };
        if let Some(node) = below {
            if !tree.path(instance.tree_node).contains(&node) {
                continue;
            }
        }
        shown.instances += 1;
        if !instance.visible {
            continue;
        }
        let Some(geometry) = graph.geometry_info_at(instance.geometry) else {
            continue;
        };
        shown.visible_instances += 1;
        if let Some(part) = geometry.parts.get(instance.part as usize) {
            shown.visible_triangles += u64::from(part.triangle_count());
        }
        let local = *geometry_bounds.entry(instance.geometry).or_insert_with(|| {
            graph
                .geometry_bounds_at(instance.geometry)
                .unwrap_or_default()
        });
        shown
            .bounds
            .add_box(&local.transformed(&tree.world(instance.tree_node)));
    }
    shown
}
