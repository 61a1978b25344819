//! The scene tree (the seeds' XBAR): the render model generated from the scene graph. One
//! tree node per path from the root (so a shared subgraph appears once per path), one instance
//! per path to a drawable part, both stored as structure-of-arrays with dense, reused ids.
//! World matrices are cached per path in f64.
//!
//! [`SceneTree::update`] applies the graph's events with work proportional to what changed:
//! structural edits reconcile only the children of the parents that changed; a matrix, flag or
//! selection edit refreshes only the subtrees of the paths through that node. What changed is
//! kept in bit arrays and handed to each reader ([`SceneTree::subscribe`], [`SceneTree::changes_for`]). LOD selection and
//! billboards depend on the eye: [`SceneTree::update_view`] refreshes only their subtrees.

mod bits;
mod changes;
mod shown;

pub use bits::BitSet;
pub use changes::{ChangeReader, TreeChanges};
pub use shown::{shown, Shown};

use changes::ChangeLogs;

use glam::{DMat4, DVec3};

use crate::graph::{ChildLink, GraphEvent, GraphNode, LodMetric, NodeHandle, NodeKind, SceneGraph};

const NONE: u32 = u32::MAX;

/// The most graph events whose storage the tree keeps between updates (a frame that drags
/// parts has one per moved node).
const KEPT_GRAPH_EVENTS: usize = 4096;

/// What a path inherits from the nodes along it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct PathState {
    visible: bool,
    highlighted: bool,
    pickable: bool,
}

/// One drawable part on one path.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InstanceRef {
    /// The tree node (path) whose world matrix places it: its matrix slot.
    pub tree_node: u32,
    /// Part index in the geometry.
    pub part: u32,
    /// Geometry slot in the graph.
    pub geometry: u32,
    /// Material slot in the graph.
    pub material: u32,
    /// Effectively visible (flags, switches, LOD along the path).
    pub visible: bool,
    /// Highlighted (the flag of any node along the path).
    pub highlighted: bool,
    /// Pickable (the flag of every node along the path).
    pub pickable: bool,
}

/// The scene tree.
///
/// Structure of arrays, one `Vec` per column of a node or an instance (hence its many fields):
/// the update loops touch one or two columns over many ids, which stay dense in memory this
/// way; grouping columns into structs would interleave what the loops read with what they skip.
#[derive(Default)]
pub struct SceneTree {
    node_graph: Vec<NodeHandle>,
    node_parent: Vec<u32>,
    node_children: Vec<Vec<u32>>,
    /// World matrices, a cache: up to date except in the subtrees of `stale_roots`.
    node_world: Vec<DMat4>,
    /// The transform each path applies to its subtree (a Transform's matrix, a billboard's
    /// turn, identity otherwise).
    node_local: Vec<DMat4>,
    /// Paths moved by the fast path (`moved` changes) whose subtrees' cached world matrices
    /// are stale until [`SceneTree::refresh_worlds`], each once (`stale_marks`): a reader that
    /// never refreshes (the GPU transform hierarchy) keeps the list as long as the set of
    /// distinct moved paths, not growing frame after frame.
    stale_roots: Vec<u32>,
    stale_marks: BitSet,
    /// LOD and billboard paths in each path's subtree (itself included): a subtree without
    /// them moves by its local matrix alone.
    view_dependent_below: Vec<u32>,
    /// Bumped whenever tree nodes are created or removed.
    structure_generation: u64,
    node_instances: Vec<Vec<u32>>,
    node_visible: BitSet,
    node_highlighted: BitSet,
    node_unpickable: BitSet,
    node_alive: BitSet,
    free_nodes: Vec<u32>,
    /// Tree nodes of each graph node slot (may hold paths of a destroyed node until reconciled).
    paths_of: Vec<Vec<u32>>,
    view_dependent: BitSet,
    inst_node: Vec<u32>,
    inst_part: Vec<u32>,
    inst_geometry: Vec<u32>,
    inst_material: Vec<u32>,
    inst_alive: BitSet,
    inst_visible: BitSet,
    inst_highlighted: BitSet,
    inst_unpickable: BitSet,

    free_instances: Vec<u32>,
    /// Storage for the graph's events that [`SceneTree::update`] applies, kept between updates
    /// (up to [`KEPT_GRAPH_EVENTS`]).
    graph_events: Vec<GraphEvent>,
    /// What changed, for each reader.
    changes: ChangeLogs,
    eye: DVec3,
    root: u32,
    live_instances: usize,
}

/// The transform a node applies to its subtree, given its parent's world matrix and the eye.
fn local_transform(node: &GraphNode, parent_world: &DMat4, eye: DVec3) -> DMat4 {
    match node.kind {
        NodeKind::Transform { matrix } => matrix,
        NodeKind::Billboard => {
            // Turn about the local +Y axis so that local +Z points at the eye.
            let local_eye = parent_world.inverse().transform_point3(eye);
            if local_eye.x == 0.0 && local_eye.z == 0.0 || !local_eye.is_finite() {
                DMat4::IDENTITY
            } else {
                DMat4::from_rotation_y(local_eye.x.atan2(local_eye.z))
            }
        }
        _ => DMat4::IDENTITY,
    }
}

/// The child a LOD shows, given its world matrix and the eye.
fn lod_selection(thresholds: &[f64], metric: LodMetric, world: &DMat4, eye: DVec3) -> usize {
    let distance = (world.w_axis.truncate() - eye).length();
    match metric {
        LodMetric::Distance => thresholds.iter().take_while(|&&d| d <= distance).count(),
        LodMetric::ScreenSize { radius } => {
            // The sphere subtends 2·asin(r/d) (the whole view when the eye is inside it).
            let scale = world
                .x_axis
                .truncate()
                .length()
                .max(world.y_axis.truncate().length())
                .max(world.z_axis.truncate().length());
            let world_radius = radius * scale;
            let angle = if distance <= world_radius {
                std::f64::consts::PI
            } else {
                2.0 * (world_radius / distance).asin()
            };
            thresholds.iter().take_while(|&&size| angle < size).count()
        }
    }
}

/// Whether `node` shows its child link at `position`, given the node's world matrix.
fn shows_child(
    node: &GraphNode,
    position: usize,
    link: &ChildLink,
    world: &DMat4,
    eye: DVec3,
) -> bool {
    match &node.kind {
        NodeKind::Lod { thresholds, metric } => {
            let last = node.children().len().saturating_sub(1);
            link.active && position == lod_selection(thresholds, *metric, world, eye).min(last)
        }
        _ => link.active,
    }
}

impl SceneTree {
    /// Builds the tree of `graph` from scratch (and discards the graph's pending events, which
    /// the new tree already reflects).
    pub fn build(graph: &mut SceneGraph) -> Self {
        Self::build_with_eye(graph, DVec3::ZERO)
    }

    /// Builds the tree with LOD and billboards evaluated for `eye`.
    pub fn build_with_eye(graph: &mut SceneGraph, eye: DVec3) -> Self {
        crate::timings::time(crate::timings::Phase::SceneBuild, || {
            let mut tree = Self {
                eye,
                ..Self::default()
            };
            // Dropped with their storage: a scene's creation events can be millions.
            graph.take_events(&mut Vec::new());
            let root = graph.root();
            tree.root = tree.build_subtree(graph, NONE, 0, root, true);
            tree
        })
    }

    /// The eye LOD and billboards were last evaluated for.
    pub fn eye(&self) -> DVec3 {
        self.eye
    }

    fn alloc_node(&mut self, handle: NodeHandle, parent: u32) -> u32 {
        let id = match self.free_nodes.pop() {
            Some(id) => id,
            None => {
                self.node_graph.push(handle);
                self.node_parent.push(NONE);
                self.node_children.push(Vec::new());
                self.node_world.push(DMat4::IDENTITY);
                self.node_local.push(DMat4::IDENTITY);
                self.view_dependent_below.push(0);
                self.node_instances.push(Vec::new());
                self.node_graph.len() as u32 - 1
            }
        };
        let i = id as usize;
        self.node_graph[i] = handle;
        self.node_parent[i] = parent;
        self.view_dependent_below[i] = 0;
        self.node_alive.insert(id);
        self.structure_generation += 1;
        let slot = handle.index() as usize;
        if slot >= self.paths_of.len() {
            self.paths_of.resize(slot + 1, Vec::new());
        }
        self.paths_of[slot].push(id);
        id
    }

    fn alloc_instance(
        &mut self,
        node: u32,
        part: u32,
        geometry: u32,
        material: u32,
        state: PathState,
    ) -> u32 {
        let id = match self.free_instances.pop() {
            Some(id) => id,
            None => {
                self.inst_node.push(0);
                self.inst_part.push(0);
                self.inst_geometry.push(0);
                self.inst_material.push(0);
                self.inst_node.len() as u32 - 1
            }
        };
        let i = id as usize;
        (
            self.inst_node[i],
            self.inst_part[i],
            self.inst_geometry[i],
            self.inst_material[i],
        ) = (node, part, geometry, material);
        self.inst_alive.insert(id);
        self.inst_visible.set(id, state.visible);
        self.inst_highlighted.set(id, state.highlighted);
        self.inst_unpickable.set(id, !state.pickable);
        self.changes.pending.created.insert(id);
        self.live_instances += 1;
        id
    }

    /// Builds the subtree of graph node `handle` as child `position` of tree node `parent`
    /// (`NONE` for the root); `link_shown` says whether the parent shows it. Iterative.
    fn build_subtree(
        &mut self,
        graph: &SceneGraph,
        parent: u32,
        position: usize,
        handle: NodeHandle,
        link_shown: bool,
    ) -> u32 {
        let mut first = NONE;
        // (parent tree node, insert position or NONE to append, graph node, link shown)
        let mut stack: Vec<(u32, u32, NodeHandle, bool)> =
            vec![(parent, position as u32, handle, link_shown)];
        while let Some((parent, position, handle, link_shown)) = stack.pop() {
            let Ok(node) = graph.node(handle) else {
                continue;
            };
            let id = self.alloc_node(handle, parent);
            if first == NONE {
                first = id;
            }
            let parent_world = self.parent_world(parent, first == id);
            let (local, world, state) = self.placement(parent, &parent_world, node, link_shown);
            self.node_world[id as usize] = world;
            self.node_local[id as usize] = local;
            self.set_node_state(id, state);
            self.changes.pending.dirty_matrices.insert(id);
            if matches!(node.kind, NodeKind::Lod { .. } | NodeKind::Billboard) {
                self.view_dependent.insert(id);
                self.count_view_dependent(id, 1);
            }
            if parent != NONE {
                let siblings = &mut self.node_children[parent as usize];
                if position == NONE {
                    siblings.push(id);
                } else {
                    siblings.insert(position as usize, id);
                }
            }
            if let NodeKind::Geo {
                geometry,
                part_materials,
                ..
            } = &node.kind
            {
                let instances = part_materials
                    .iter()
                    .enumerate()
                    .map(|(part, m)| {
                        self.alloc_instance(
                            id,
                            part as u32,
                            geometry.index(),
                            m.index(),
                            PathState {
                                visible: state.visible && node.part_shown(part),
                                ..state
                            },
                        )
                    })
                    .collect();
                self.node_instances[id as usize] = instances;
            }
            // Children are appended in order: push them reversed.
            for (i, link) in node.children().iter().enumerate().rev() {
                stack.push((
                    id,
                    NONE,
                    link.node,
                    shows_child(node, i, link, &world, self.eye),
                ));
            }
        }
        first
    }

    /// The world matrix of tree node `parent` (identity for `NONE`) as a child's placement
    /// needs it: the top of a walk (`top`) computes it along the path, since the cache may be
    /// stale there; below the top the walk has just refreshed it.
    fn parent_world(&self, parent: u32, top: bool) -> DMat4 {
        if parent == NONE {
            DMat4::IDENTITY
        } else if top {
            self.world(parent)
        } else {
            self.node_world[parent as usize]
        }
    }

    /// Adds `delta` to the view-dependent count of `t` and of every path above it.
    fn count_view_dependent(&mut self, t: u32, delta: i64) {
        let mut p = t;
        while p != NONE {
            let count = &mut self.view_dependent_below[p as usize];
            *count = (i64::from(*count) + delta) as u32;
            p = self.node_parent[p as usize];
        }
    }

    /// Local matrix, world matrix and state of a path to `node` below tree node `parent`
    /// (`NONE` for the root) whose world matrix is `parent_world`, shown by its parent or not.
    fn placement(
        &self,
        parent: u32,
        parent_world: &DMat4,
        node: &GraphNode,
        link_shown: bool,
    ) -> (DMat4, DMat4, PathState) {
        let parent_state = if parent == NONE {
            PathState {
                visible: true,
                highlighted: false,
                pickable: true,
            }
        } else {
            self.node_state(parent)
        };
        let local = local_transform(node, parent_world, self.eye);
        let world = *parent_world * local;
        let state = PathState {
            visible: parent_state.visible && link_shown && node.flags.visible,
            highlighted: parent_state.highlighted || node.flags.highlighted,
            pickable: parent_state.pickable && node.flags.pickable,
        };
        (local, world, state)
    }

    fn node_state(&self, t: u32) -> PathState {
        PathState {
            visible: self.node_visible.contains(t),
            highlighted: self.node_highlighted.contains(t),
            pickable: !self.node_unpickable.contains(t),
        }
    }

    fn set_node_state(&mut self, t: u32, state: PathState) {
        self.node_visible.set(t, state.visible);
        self.node_highlighted.set(t, state.highlighted);
        self.node_unpickable.set(t, !state.pickable);
    }

    /// Removes tree node `id` and everything below it.
    fn remove_subtree(&mut self, id: u32) {
        let view_dependent = self.view_dependent_below[id as usize];
        let parent = self.node_parent[id as usize];
        if view_dependent > 0 && parent != NONE {
            self.count_view_dependent(parent, -i64::from(view_dependent));
        }
        self.structure_generation += 1;
        let mut stack = vec![id];
        while let Some(t) = stack.pop() {
            let i = t as usize;
            stack.extend(std::mem::take(&mut self.node_children[i]));
            for instance in std::mem::take(&mut self.node_instances[i]) {
                self.inst_alive.remove(instance);
                self.changes.pending.destroyed.insert(instance);
                self.live_instances -= 1;
                self.free_instances.push(instance);
            }
            let slot = self.node_graph[i].index() as usize;
            if let Some(position) = self.paths_of[slot].iter().position(|&p| p == t) {
                self.paths_of[slot].swap_remove(position);
            }
            self.node_alive.remove(t);
            self.node_visible.remove(t);
            self.node_highlighted.remove(t);
            self.node_unpickable.remove(t);
            self.view_dependent.remove(t);
            self.changes.pending.dirty_matrices.remove(t);
            self.changes.pending.moved.remove(t);
            self.free_nodes.push(t);
        }
    }

    /// Whether the parent of tree node `t` shows it (switch mask, LOD choice).
    fn link_shown(&self, graph: &SceneGraph, t: u32) -> bool {
        let parent = self.node_parent[t as usize];
        if parent == NONE {
            return true;
        }
        let Ok(parent_node) = graph.node(self.node_graph[parent as usize]) else {
            return false;
        };
        let Some(position) = self.node_children[parent as usize]
            .iter()
            .position(|&c| c == t)
        else {
            return false;
        };
        parent_node.children().get(position).is_some_and(|link| {
            shows_child(parent_node, position, link, &self.world(parent), self.eye)
        })
    }

    /// Recomputes world matrices and visibility below (and including) tree node `id`,
    /// recording what changed.
    fn refresh_subtree(&mut self, graph: &SceneGraph, id: u32) {
        let mut stack = vec![(id, self.link_shown(graph, id))];
        while let Some((t, link_shown)) = stack.pop() {
            let i = t as usize;
            let Ok(node) = graph.node(self.node_graph[i]) else {
                continue;
            };
            let parent = self.node_parent[i];
            let parent_world = self.parent_world(parent, t == id);
            let (local, world, state) = self.placement(parent, &parent_world, node, link_shown);
            self.node_local[i] = local;
            let old = self.node_state(t);
            if state != old {
                self.set_node_state(t, state);
                for (part, &instance) in self.node_instances[i].iter().enumerate() {
                    let visible = state.visible && node.part_shown(part);
                    if visible != self.inst_visible.contains(instance) {
                        self.inst_visible.set(instance, visible);
                        self.changes.pending.visibility_changed.insert(instance);
                    }
                    self.inst_highlighted.set(instance, state.highlighted);
                    self.inst_unpickable.set(instance, !state.pickable);
                    if state.highlighted != old.highlighted || state.pickable != old.pickable {
                        self.changes.pending.changed.insert(instance);
                    }
                }
            }
            if world != self.node_world[i] {
                self.node_world[i] = world;
                self.changes.pending.dirty_matrices.insert(t);
            }
            for (position, (&child, link)) in self.node_children[i]
                .iter()
                .zip(node.children())
                .enumerate()
            {
                stack.push((child, shows_child(node, position, link, &world, self.eye)));
            }
        }
    }

    /// Makes the children of every path through `parent` match the graph again: the common
    /// prefix and suffix of the old and new child lists are kept, the middle rebuilt.
    fn reconcile(&mut self, graph: &SceneGraph, parent: NodeHandle, refresh: &mut Vec<u32>) {
        let Ok(node) = graph.node(parent) else { return };
        let paths: Vec<u32> = self
            .paths_of
            .get(parent.index() as usize)
            .map(|p| {
                p.iter()
                    .copied()
                    .filter(|&t| self.node_graph[t as usize] == parent)
                    .collect()
            })
            .unwrap_or_default();
        let new: &[ChildLink] = node.children();
        for t in paths {
            // Reconciling an earlier parent may have removed this path (it lay in a subtree
            // that no longer exists): skip it.
            if !self.node_alive.contains(t) || self.node_graph[t as usize] != parent {
                continue;
            }
            let old: Vec<NodeHandle> = self.node_children[t as usize]
                .iter()
                .map(|&c| self.node_graph[c as usize])
                .collect();
            let prefix = old
                .iter()
                .zip(new)
                .take_while(|(o, n)| **o == n.node)
                .count();
            let max_suffix = old.len().min(new.len()) - prefix;
            let suffix = old
                .iter()
                .rev()
                .zip(new.iter().rev())
                .take(max_suffix)
                .take_while(|(o, n)| **o == n.node)
                .count();
            if prefix + suffix == old.len() && old.len() == new.len() {
                continue;
            }
            let removed: Vec<u32> = self.node_children[t as usize]
                .drain(prefix..old.len() - suffix)
                .collect();
            for child in removed {
                self.remove_subtree(child);
            }
            let world = self.world(t);
            for (position, link) in new.iter().enumerate().take(new.len() - suffix).skip(prefix) {
                let shown = shows_child(node, position, link, &world, self.eye);
                self.build_subtree(graph, t, position, link.node, shown);
            }
            if matches!(node.kind, NodeKind::Lod { .. }) {
                // A LOD chooses by position: kept children may have moved into or out of view.
                // Refreshed after every parent is reconciled (positions are consistent then).
                refresh.push(t);
            }
        }
    }

    /// Applies the graph's pending events.
    pub fn update(&mut self, graph: &mut SceneGraph) {
        let mut events = std::mem::take(&mut self.graph_events);
        graph.take_events(&mut events);
        let mut structural: Vec<NodeHandle> = events
            .iter()
            .filter_map(|e| match *e {
                GraphEvent::ChildInserted { parent, .. }
                | GraphEvent::ChildRemoved { parent, .. } => Some(parent),
                _ => None,
            })
            .collect();
        structural.sort_by_key(|h| (h.index(), h.generation()));
        structural.dedup();
        let mut refresh: Vec<u32> = Vec::new();
        for parent in structural {
            self.reconcile(graph, parent, &mut refresh);
        }
        for event in &events {
            match *event {
                GraphEvent::MatrixChanged(n) => self.move_paths(graph, n, &mut refresh),
                GraphEvent::FlagsChanged(n) | GraphEvent::SelectionChanged(n) => {
                    refresh.extend(self.current_paths(n));
                }
                GraphEvent::PartMaterialChanged { node, part } => {
                    let material = match graph.node(node).map(|n| &n.kind) {
                        Ok(NodeKind::Geo { part_materials, .. }) => {
                            part_materials.get(part as usize).map(|m| m.index())
                        }
                        _ => None,
                    };
                    if let Some(material) = material {
                        for t in self.current_paths(node) {
                            if let Some(&instance) =
                                self.node_instances[t as usize].get(part as usize)
                            {
                                self.inst_material[instance as usize] = material;
                                self.changes.pending.changed.insert(instance);
                            }
                        }
                    }
                }
                GraphEvent::GeometryReplaced(g) => {
                    self.changes.pending.dirty_geometries.insert(g.index());
                    // Only the paths of the Geo nodes that draw it: proportional to the change.
                    let users = graph
                        .geometry_users(g)
                        .map(<[NodeHandle]>::to_vec)
                        .unwrap_or_default();
                    for user in users {
                        for t in self.current_paths(user) {
                            for &instance in &self.node_instances[t as usize] {
                                self.changes.pending.changed.insert(instance);
                            }
                        }
                    }
                }
                GraphEvent::PartVisibilityChanged { node, part } => {
                    let Ok(graph_node) = graph.node(node) else {
                        continue;
                    };
                    let shown = graph_node.part_shown(part as usize);
                    for t in self.current_paths(node) {
                        let Some(&instance) = self.node_instances[t as usize].get(part as usize)
                        else {
                            continue;
                        };
                        let visible = shown && self.node_visible.contains(t);
                        if visible != self.inst_visible.contains(instance) {
                            self.inst_visible.set(instance, visible);
                            self.changes.pending.visibility_changed.insert(instance);
                        }
                    }
                }
                GraphEvent::MaterialChanged(m) => {
                    self.changes.pending.dirty_materials.insert(m.index())
                }
                GraphEvent::ChildInserted { .. } | GraphEvent::ChildRemoved { .. } => {}
            }
        }
        refresh.sort_unstable();
        refresh.dedup();
        for t in refresh {
            if self.node_alive.contains(t) {
                self.refresh_subtree(graph, t);
            }
        }
        // Kept for the next update, unless a large edit made it large.
        events.clear();
        if events.capacity() <= KEPT_GRAPH_EVENTS {
            self.graph_events = events;
        }
    }

    /// Applies a new matrix of graph node `n` to its paths. A path whose subtree holds no LOD
    /// or billboard (whose choice depends on world matrices) takes the fast path: its local
    /// matrix is replaced and it is reported as `moved`, in O(1), and the world matrices below
    /// it are left to whoever needs them (the GPU transform hierarchy, or
    /// [`SceneTree::refresh_worlds`]). Other paths go to `refresh`.
    fn move_paths(&mut self, graph: &SceneGraph, n: NodeHandle, refresh: &mut Vec<u32>) {
        let Ok(node) = graph.node(n) else { return };
        // By index rather than through `current_paths`: a dragged part moves every frame, and
        // its move allocates nothing.
        let path_count = self.paths_of.get(n.index() as usize).map_or(0, Vec::len);
        for i in 0..path_count {
            let t = self.paths_of[n.index() as usize][i];
            if self.node_graph[t as usize] != n {
                continue;
            }
            if self.view_dependent_below[t as usize] > 0 {
                refresh.push(t);
                continue;
            }
            self.node_local[t as usize] = local_transform(node, &DMat4::IDENTITY, self.eye);
            self.changes.pending.moved.insert(t);
            if !self.stale_marks.contains(t) {
                self.stale_marks.insert(t);
                self.stale_roots.push(t);
            }
        }
    }

    /// Brings the cached world matrices of moved subtrees up to date (work in proportion to
    /// those subtrees). Readers that keep world matrices on the host call it before walking
    /// the subtrees of `moved` paths; [`SceneTree::world`] is right without it.
    pub fn refresh_worlds(&mut self) {
        if self.stale_roots.is_empty() {
            return;
        }
        // Each root starts from its parent's chain (computed while the list is non-empty, so
        // it stays until the end), so the order does not matter.
        let roots = self.stale_roots.clone();
        for &root in &roots {
            if !self.node_alive.contains(root) {
                continue;
            }
            let parent = self.node_parent[root as usize];
            let mut stack = vec![(root, self.parent_world(parent, true))];
            while let Some((t, parent_world)) = stack.pop() {
                let world = parent_world * self.node_local[t as usize];
                self.node_world[t as usize] = world;
                stack.extend(self.node_children[t as usize].iter().map(|&c| (c, world)));
            }
        }
        self.stale_roots.clear();
        self.stale_marks.clear();
    }

    /// Moves the eye: refreshes the subtrees of LOD and billboard paths (only).
    pub fn update_view(&mut self, graph: &SceneGraph, eye: DVec3) {
        if eye == self.eye {
            return;
        }
        self.eye = eye;
        let view_dependent: Vec<u32> = self.view_dependent.iter().collect();
        for t in view_dependent {
            if self.node_alive.contains(t) {
                self.refresh_subtree(graph, t);
            }
        }
    }

    fn current_paths(&self, node: NodeHandle) -> Vec<u32> {
        self.paths_of
            .get(node.index() as usize)
            .map(|p| {
                p.iter()
                    .copied()
                    .filter(|&t| self.node_graph[t as usize] == node)
                    .collect()
            })
            .unwrap_or_default()
    }

    /// Hands out what changed since the tree's own reader last looked (the tree is a reader of
    /// itself, for hosts with one consumer) and starts recording afresh.
    pub fn take_changes(&mut self) -> TreeChanges {
        let (instances, nodes) = (&self.inst_alive, &self.node_alive);
        self.changes.own_log().take(instances, nodes)
    }

    /// A new reader of this tree's changes: it sees what changes from now on (the state up to
    /// now it reads from the tree itself).
    pub fn subscribe(&mut self) -> ChangeReader {
        self.changes.subscribe()
    }

    /// What changed since `reader` last looked; `None` when `reader` does not read this tree
    /// (it was subscribed to another one).
    pub fn changes_for(&mut self, reader: &ChangeReader) -> Option<TreeChanges> {
        let (instances, nodes) = (&self.inst_alive, &self.node_alive);
        Some(self.changes.log_of(reader)?.take(instances, nodes))
    }

    /// Number of live readers subscribed (the tree's own not counted).
    pub fn reader_count(&self) -> usize {
        self.changes.reader_count()
    }

    // ---- queries ------------------------------------------------------------------------------

    /// Number of live instances.
    pub fn instance_count(&self) -> usize {
        self.live_instances
    }

    /// Bound of instance ids.
    pub fn instance_capacity(&self) -> usize {
        self.inst_node.len()
    }

    /// Number of live tree nodes (paths).
    pub fn node_count(&self) -> usize {
        self.node_alive.count()
    }

    /// Bound of tree node ids (matrix slots).
    pub fn node_capacity(&self) -> usize {
        self.node_graph.len()
    }

    /// The instance `id`, if alive.
    pub fn instance(&self, id: u32) -> Option<InstanceRef> {
        self.inst_alive.contains(id).then(|| {
            let i = id as usize;
            InstanceRef {
                tree_node: self.inst_node[i],
                part: self.inst_part[i],
                geometry: self.inst_geometry[i],
                material: self.inst_material[i],
                visible: self.inst_visible.contains(id),
                highlighted: self.inst_highlighted.contains(id),
                pickable: !self.inst_unpickable.contains(id),
            }
        })
    }

    /// Live instance ids, ascending.
    pub fn instances(&self) -> impl Iterator<Item = u32> + '_ {
        self.inst_alive.iter()
    }

    /// Whether tree node `id` is alive and carries instances (a Geo path).
    pub fn has_instances(&self, id: u32) -> bool {
        self.node_alive.contains(id) && !self.node_instances[id as usize].is_empty()
    }

    /// The world matrix of tree node `id`: the cached one, or, while moved subtrees are
    /// stale, the product of the local matrices along the path (O(depth), multiplied from the
    /// root down as the cache is, so the result is the same to the bit).
    pub fn world(&self, id: u32) -> DMat4 {
        if self.stale_roots.is_empty() {
            return self.node_world[id as usize];
        }
        let mut path = Vec::with_capacity(16);
        let mut t = id;
        while t != NONE {
            path.push(t);
            t = self.node_parent[t as usize];
        }
        path.iter().rev().fold(DMat4::IDENTITY, |world, &t| {
            world * self.node_local[t as usize]
        })
    }

    /// The local matrix of tree node `id` (what it applies to its subtree).
    pub fn local(&self, id: u32) -> DMat4 {
        self.node_local[id as usize]
    }

    /// The parent of tree node `id`, `None` for the root.
    pub fn parent(&self, id: u32) -> Option<u32> {
        let parent = self.node_parent[id as usize];
        (parent != NONE).then_some(parent)
    }

    /// Whether tree node `id` is alive.
    pub fn is_node_alive(&self, id: u32) -> bool {
        self.node_alive.contains(id)
    }

    /// The root tree node.
    pub fn root(&self) -> u32 {
        self.root
    }

    /// The children of tree node `id`, in order.
    pub fn children(&self, id: u32) -> &[u32] {
        &self.node_children[id as usize]
    }

    /// Bumped whenever tree nodes are created or removed (a layout of the tree built at one
    /// value holds while it stays).
    pub fn structure_generation(&self) -> u64 {
        self.structure_generation
    }

    /// The graph nodes along the path of tree node `id`, from the root.
    pub fn path(&self, id: u32) -> Vec<NodeHandle> {
        let mut path = Vec::new();
        let mut t = id;
        while t != NONE {
            path.push(self.node_graph[t as usize]);
            t = self.node_parent[t as usize];
        }
        path.reverse();
        path
    }

    /// Bytes held by the tree, split into (world matrices, everything else).
    pub fn memory_bytes(&self) -> (usize, usize) {
        let matrices = (self.node_world.capacity() + self.node_local.capacity())
            * std::mem::size_of::<DMat4>();
        let vec_heap = |v: &Vec<Vec<u32>>| {
            v.iter().map(|c| c.capacity() * 4).sum::<usize>() + v.capacity() * 24
        };
        let other = self.node_graph.capacity() * 8
            + self.node_parent.capacity() * 4
            + vec_heap(&self.node_children)
            + vec_heap(&self.node_instances)
            + vec_heap(&self.paths_of)
            + self.free_nodes.capacity() * 4
            + self.stale_roots.capacity() * 4
            + self.stale_marks.memory_bytes()
            + self.view_dependent_below.capacity() * 4
            + (self.inst_node.capacity()
                + self.inst_part.capacity()
                + self.inst_geometry.capacity()
                + self.inst_material.capacity())
                * 4
            + self.free_instances.capacity() * 4
            + self.graph_events.capacity() * std::mem::size_of::<GraphEvent>()
            + [
                &self.node_visible,
                &self.node_highlighted,
                &self.inst_highlighted,
                &self.node_unpickable,
                &self.inst_unpickable,
                &self.node_alive,
                &self.view_dependent,
                &self.inst_alive,
                &self.inst_visible,
            ]
            .iter()
            .map(|b| b.memory_bytes())
            .sum::<usize>()
            + self.changes.memory_bytes();
        (matrices, other)
    }
}
