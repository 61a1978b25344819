//! The incremental scene tree equals a full rebuild after any sequence of edits, and the
//! changes it hands out are enough for a consumer to stay exactly in sync.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::collections::HashMap;

use cadr_core::generate::GeometryBuilder;
use cadr_core::graph::{
    GeometryHandle, GraphError, MaterialHandle, NodeFlags, NodeHandle, SceneGraph,
};
use cadr_core::scene::Material;
use cadr_core::tree::{InstanceRef, SceneTree};
use glam::{DMat4, DVec3};
use proptest::prelude::*;

type Snapshot = Vec<(Vec<(u32, u32)>, u32, u32, u32, [u64; 16], bool, bool, bool)>;

/// Every live instance: its path (as handle parts), part, geometry, material, world bits, visibility.
fn snapshot(tree: &SceneTree) -> Snapshot {
    let mut out: Snapshot = tree
        .instances()
        .map(|id| {
            let i = tree.instance(id).unwrap();
            let path = tree
                .path(i.tree_node)
                .into_iter()
                .map(|h| (h.index(), h.generation()))
                .collect();
            let world = tree.world(i.tree_node).to_cols_array().map(f64::to_bits);
            (
                path,
                i.part,
                i.geometry,
                i.material,
                world,
                i.visible,
                i.highlighted,
                i.pickable,
            )
        })
        .collect();
    out.sort();
    out
}

/// What a renderer keeps, updated only from `take_changes`.
#[derive(Default)]
struct Consumer {
    instances: HashMap<u32, InstanceRef>,
    matrices: HashMap<u32, DMat4>,
}

impl Consumer {
    fn apply(&mut self, tree: &mut SceneTree) {
        let changes = tree.take_changes();
        for id in &changes.removed {
            self.instances.remove(id);
        }
        for &id in changes
            .added
            .iter()
            .chain(&changes.changed)
            .chain(&changes.visibility_changed)
        {
            let i = tree.instance(id).unwrap();
            self.instances.insert(id, i);
        }
        for &t in &changes.dirty_matrices {
            self.matrices.insert(t, tree.world(t));
        }
        // A moved path's whole subtree has new world matrices (a host reader walks it).
        tree.refresh_worlds();
        let mut below: Vec<u32> = changes.moved.clone();
        while let Some(t) = below.pop() {
            self.matrices.insert(t, tree.world(t));
            below.extend_from_slice(tree.children(t));
        }
    }

    fn check(&self, tree: &SceneTree) {
        assert_eq!(
            self.instances.len(),
            tree.instance_count(),
            "consumer has the live instances"
        );
        for id in tree.instances() {
            let i = tree.instance(id).unwrap();
            assert_eq!(self.instances.get(&id), Some(&i), "instance {id}");
            assert_eq!(
                self.matrices.get(&i.tree_node),
                Some(&tree.world(i.tree_node)),
                "matrix of instance {id}"
            );
        }
    }
}

#[derive(Clone, Debug)]
enum Op {
    CreateGroup,
    CreateTransform(i8, i8),
    CreateGeo(u8, u8),
    CreateSwitch,
    CreateLod,
    CreateLodByScreenSize(u8),
    CreateBillboard,
    AddChild(u8, u8),
    InsertChild(u8, u8, u8),
    RemoveChildAt(u8, u8),
    Destroy(u8),
    SetMatrix(u8, i8, i8),
    SetFlags(u8, bool, bool, bool),
    SetMask(u8, u32),
    SetPartMaterial(u8, u8, u8),
    SetMaterial(u8),
    SetPartVisible(u8, u8, bool),
    ReplaceGeometry(u8, i8),
    SetLodDistances(u8, u8),
    MoveEye(i8, i8),
    Update,
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        1 => Just(Op::CreateGroup),
        1 => (any::<i8>(), any::<i8>()).prop_map(|(x, z)| Op::CreateTransform(x, z)),
        1 => (any::<u8>(), any::<u8>()).prop_map(|(g, m)| Op::CreateGeo(g, m)),
        1 => Just(Op::CreateSwitch),
        1 => Just(Op::CreateLod),
        1 => any::<u8>().prop_map(Op::CreateLodByScreenSize),
        1 => Just(Op::CreateBillboard),
        4 => (any::<u8>(), any::<u8>()).prop_map(|(p, c)| Op::AddChild(p, c)),
        1 => (any::<u8>(), any::<u8>(), any::<u8>()).prop_map(|(p, i, c)| Op::InsertChild(p, i, c)),
        2 => (any::<u8>(), any::<u8>()).prop_map(|(p, i)| Op::RemoveChildAt(p, i)),
        1 => any::<u8>().prop_map(Op::Destroy),
        3 => (any::<u8>(), any::<i8>(), any::<i8>()).prop_map(|(n, x, z)| Op::SetMatrix(n, x, z)),
        1 => (any::<u8>(), any::<bool>(), any::<bool>(), any::<bool>()).prop_map(|(n, v, h, p)| Op::SetFlags(n, v, h, p)),
        1 => (any::<u8>(), any::<u32>()).prop_map(|(n, m)| Op::SetMask(n, m)),
        1 => (any::<u8>(), any::<u8>(), any::<u8>()).prop_map(|(n, p, m)| Op::SetPartMaterial(n, p, m)),
        1 => any::<u8>().prop_map(Op::SetMaterial),
        2 => (any::<u8>(), any::<u8>(), any::<bool>()).prop_map(|(n, p, v)| Op::SetPartVisible(n, p, v)),
        1 => (any::<u8>(), any::<i8>()).prop_map(|(g, y)| Op::ReplaceGeometry(g, y)),
        1 => (any::<u8>(), any::<u8>()).prop_map(|(n, d)| Op::SetLodDistances(n, d)),
        1 => (any::<i8>(), any::<i8>()).prop_map(|(x, z)| Op::MoveEye(x, z)),
        2 => Just(Op::Update),
    ]
}

const MAX_PATHS: u64 = 4096;

fn cases_from_env(default: u32) -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Number of paths from `node` down (memoised over the DAG).
fn path_count(graph: &SceneGraph, node: NodeHandle) -> u64 {
    fn count(graph: &SceneGraph, node: NodeHandle, memo: &mut HashMap<NodeHandle, u64>) -> u64 {
        if let Some(&n) = memo.get(&node) {
            return n;
        }
        let children: Vec<NodeHandle> = graph
            .node(node)
            .unwrap()
            .children()
            .iter()
            .map(|l| l.node)
            .collect();
        let n = children
            .into_iter()
            .fold(1_u64, |sum, c| sum.saturating_add(count(graph, c, memo)));
        memo.insert(node, n);
        n
    }
    count(graph, node, &mut HashMap::new())
}

struct World {
    graph: SceneGraph,
    geometries: Vec<GeometryHandle>,
    materials: Vec<MaterialHandle>,
    eye: DVec3,
}

impl World {
    fn new() -> Self {
        let mut graph = SceneGraph::new();
        let geometries = (1..=3)
            .map(|parts| {
                let mut builder = GeometryBuilder::new(format!("g{parts}"));
                for p in 0..parts {
                    builder.prism(
                        3 + p,
                        DMat4::from_translation(DVec3::new(f64::from(p), 0.0, 0.0)),
                    );
                }
                graph.create_geometry(builder.finish()).unwrap()
            })
            .collect();
        let materials = (0..4)
            .map(|i| {
                graph
                    .create_material(Material {
                        name: format!("m{i}"),
                        ..Material::default()
                    })
                    .unwrap()
            })
            .collect();
        Self {
            graph,
            geometries,
            materials,
            eye: DVec3::new(0.0, 0.0, 10.0),
        }
    }

    /// Links `child` under `parent`, undone when sharing would multiply the paths past
    /// `MAX_PATHS` (a chain of nodes each linked twice doubles them at every level).
    fn link_bounded(
        &mut self,
        parent: NodeHandle,
        position: usize,
        child: NodeHandle,
    ) -> Result<(), GraphError> {
        self.graph.insert_child(parent, position, child)?;
        if path_count(&self.graph, self.graph.root()) > MAX_PATHS {
            self.graph.remove_child_at(parent, position)?;
        }
        Ok(())
    }

    fn nodes(&self) -> Vec<NodeHandle> {
        self.graph.nodes().map(|(h, _)| h).collect()
    }

    fn pick(&self, i: u8) -> NodeHandle {
        let nodes = self.nodes();
        nodes[i as usize % nodes.len()]
    }

    /// Applies an edit; refused edits (cycles, wrong kinds) must leave everything consistent.
    fn apply(&mut self, op: &Op, tree: &mut SceneTree, consumer: &mut Consumer) {
        let g = &mut self.graph;
        let _ = match *op {
            Op::CreateGroup => Ok(g.create_group("group")).map(|_| ()),
            Op::CreateTransform(x, z) => g
                .create_transform(
                    "transform",
                    DMat4::from_translation(DVec3::new(f64::from(x), 0.5, f64::from(z))),
                )
                .map(|_| ()),
            Op::CreateGeo(geometry, material) => {
                let geometry = self.geometries[geometry as usize % 3];
                let parts = g.geometry(geometry).unwrap().parts.len();
                let materials: Vec<_> = (0..parts)
                    .map(|p| self.materials[(material as usize + p) % 4])
                    .collect();
                g.create_geo("geo", geometry, &materials).map(|_| ())
            }
            Op::CreateSwitch => Ok(g.create_switch("switch")).map(|_| ()),
            Op::CreateLod => g.create_lod("lod", &[5.0, 20.0]).map(|_| ()),
            Op::CreateLodByScreenSize(r) => g
                .create_lod_by_screen_size("lod by size", 0.5 + f64::from(r % 8), &[0.5, 0.1])
                .map(|_| ()),
            Op::CreateBillboard => Ok(g.create_billboard("billboard")).map(|_| ()),
            Op::AddChild(p, c) => {
                let (p, c) = (self.pick(p), self.pick(c));
                let position = self.graph.node(p).unwrap().children().len();
                self.link_bounded(p, position, c)
            }
            Op::InsertChild(p, i, c) => {
                let (p, c) = (self.pick(p), self.pick(c));
                let len = self.graph.node(p).unwrap().children().len();
                self.link_bounded(p, i as usize % (len + 1), c)
            }
            Op::RemoveChildAt(p, i) => {
                let p = self.pick(p);
                let len = self.graph.node(p).unwrap().children().len();
                if len == 0 {
                    Ok(())
                } else {
                    self.graph.remove_child_at(p, i as usize % len)
                }
            }
            Op::Destroy(n) => {
                let n = self.pick(n);
                self.graph.destroy_node(n)
            }
            Op::SetMatrix(n, x, z) => {
                let n = self.pick(n);
                let m = DMat4::from_rotation_y(f64::from(x) * 0.1)
                    * DMat4::from_translation(DVec3::new(f64::from(z), 0.0, 1.0));
                self.graph.set_matrix(n, m)
            }
            Op::SetFlags(n, visible, highlighted, pickable) => {
                let n = self.pick(n);
                self.graph.set_flags(
                    n,
                    NodeFlags {
                        visible,
                        highlighted,
                        pickable,
                    },
                )
            }
            Op::SetMask(n, bits) => {
                let n = self.pick(n);
                let len = self.graph.node(n).unwrap().children().len();
                let mask: Vec<bool> = (0..len).map(|i| bits >> (i % 32) & 1 == 1).collect();
                self.graph.set_switch_mask(n, &mask)
            }
            Op::SetPartMaterial(n, part, m) => {
                let n = self.pick(n);
                self.graph
                    .set_part_material(n, part as usize % 3, self.materials[m as usize % 4])
            }
            Op::SetMaterial(m) => {
                let handle = self.materials[m as usize % 4];
                self.graph.set_material(
                    handle,
                    Material {
                        name: "changed".into(),
                        base_color: [0.1, 0.2, 0.3, 1.0],
                        ..Material::default()
                    },
                )
            }
            Op::SetPartVisible(n, part, visible) => {
                let n = self.pick(n);
                self.graph.set_part_visible(n, part as usize % 3, visible)
            }
            Op::ReplaceGeometry(g, y) => {
                // Same part count (required while in use), moved vertices.
                let handle = self.geometries[g as usize % 3];
                let mut data = self.graph.geometry(handle).unwrap().into_owned();
                for v in &mut data.vertices {
                    v.position[1] += f32::from(y) * 0.01;
                }
                self.graph.replace_geometry(handle, data)
            }
            Op::SetLodDistances(n, d) => {
                let n = self.pick(n);
                let near = 1.0 + f64::from(d % 16);
                // Increasing distances, or for a screen-size LOD decreasing angles.
                self.graph
                    .set_lod_thresholds(n, &[near, near * 3.0])
                    .or_else(|_| self.graph.set_lod_thresholds(n, &[1.0 / near, 0.3 / near]))
            }
            Op::MoveEye(x, z) => {
                self.eye = DVec3::new(f64::from(x), 1.0, f64::from(z));
                tree.update(&mut self.graph);
                tree.update_view(&self.graph, self.eye);
                consumer.apply(tree);
                Ok(())
            }
            Op::Update => {
                tree.update(&mut self.graph);
                consumer.apply(tree);
                Ok(())
            }
        };
    }
}

fn check_against_rebuild(world: &mut World, tree: &mut SceneTree, consumer: &mut Consumer) {
    tree.update(&mut world.graph);
    consumer.apply(tree);
    let rebuilt = SceneTree::build_with_eye(&mut world.graph, world.eye);
    assert_eq!(
        snapshot(tree),
        snapshot(&rebuilt),
        "incremental tree differs from a rebuild"
    );
    assert_eq!(tree.node_count(), rebuilt.node_count());
    consumer.check(tree);
}

proptest! {
    // PROPTEST_CASES overrides the count for longer local runs.
    #![proptest_config(ProptestConfig { cases: cases_from_env(1000), ..ProptestConfig::default() })]

    #[test]
    fn incremental_updates_equal_a_rebuild(ops in prop::collection::vec(op(), 1..80)) {
        let mut world = World::new();
        let mut tree = SceneTree::build_with_eye(&mut world.graph, world.eye);
        let mut consumer = Consumer::default();
        consumer.apply(&mut tree);
        for op in &ops {
            world.apply(op, &mut tree, &mut consumer);
        }
        check_against_rebuild(&mut world, &mut tree, &mut consumer);
    }
}

#[test]
fn shared_subgraphs_appear_once_per_path_and_edits_reach_every_path() {
    let mut world = World::new();
    let g = &mut world.graph;
    let bolt_geometry = world.geometries[0];
    let bolt = g
        .create_geo("bolt", bolt_geometry, &[world.materials[0]])
        .unwrap();
    let places: Vec<NodeHandle> = (0..500)
        .map(|i| {
            let place = g
                .create_transform(
                    "place",
                    DMat4::from_translation(DVec3::new(f64::from(i), 0.0, 0.0)),
                )
                .unwrap();
            g.add_child(place, bolt).unwrap();
            g.add_child(g.root(), place).unwrap();
            place
        })
        .collect();
    let mut tree = SceneTree::build(g);
    assert_eq!(
        tree.instance_count(),
        500,
        "a bolt used 500 times is drawn on 500 paths"
    );
    tree.take_changes();
    // Moving one placement touches one path and nothing else.
    g.set_matrix(
        places[7],
        DMat4::from_translation(DVec3::new(7.0, 1.0, 0.0)),
    )
    .unwrap();
    tree.update(g);
    let changes = tree.take_changes();
    assert_eq!(
        changes.moved.len(),
        1,
        "the placement's one path moved, in O(1)"
    );
    assert!(changes.dirty_matrices.is_empty(), "nothing below it walked");
    let placement_path = changes.moved[0];
    assert_eq!(tree.path(placement_path).last(), Some(&places[7]));
    let bolt_path = tree.children(placement_path)[0];
    assert_eq!(
        tree.world(bolt_path).w_axis.truncate(),
        DVec3::new(7.0, 1.0, 0.0) + g.node(bolt).unwrap().local_matrix().w_axis.truncate(),
        "the bolt's world matrix follows, computed when asked"
    );
    assert!(changes.added.is_empty() && changes.removed.is_empty() && changes.changed.is_empty());
    // A material change of the shared node reaches every path.
    g.set_part_material(bolt, 0, world.materials[1]).unwrap();
    tree.update(g);
    assert_eq!(tree.take_changes().changed.len(), 500);
}

#[test]
fn cycles_and_stale_handles_are_errors() {
    let mut world = World::new();
    let g = &mut world.graph;
    let a = g.create_group("a");
    let b = g.create_group("b");
    g.add_child(a, b).unwrap();
    let error = g.add_child(b, a).unwrap_err().to_string();
    assert!(
        error.contains("'a' under 'b' would create a cycle"),
        "{error}"
    );
    assert!(g.add_child(a, a).is_err());
    g.destroy_node(b).unwrap();
    let error = g.add_child(a, b).unwrap_err().to_string();
    assert!(
        error.contains("destroyed or belongs to another graph"),
        "{error}"
    );
    let other = SceneGraph::new();
    assert!(other.node(a).is_err(), "a handle from another graph");
    let error = g.set_matrix(a, DMat4::IDENTITY).unwrap_err().to_string();
    assert!(
        error.contains("'a' is a Group; set_matrix needs a Transform"),
        "{error}"
    );
    assert!(g.destroy_node(g.root()).is_err());
    let _in_use = g
        .create_geo("user", world.geometries[0], &[world.materials[0]])
        .unwrap();
    let error = g
        .destroy_geometry(world.geometries[0])
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("geometry 'g1' is still used by 1 node(s)"),
        "{error}"
    );
    let error = g
        .destroy_material(world.materials[0])
        .unwrap_err()
        .to_string();
    assert!(error.contains("material 'm0' is still used"), "{error}");
    let nan = DMat4::from_translation(DVec3::new(f64::NAN, 0.0, 0.0));
    assert!(g.create_transform("bad", nan).is_err());
}

#[test]
fn links_that_multiply_paths_beyond_the_limit_are_refused() {
    // A chain of groups, each linked twice to the next, doubles the paths at every level.
    let mut graph = SceneGraph::new();
    let chain: Vec<NodeHandle> = (0..40)
        .map(|i| graph.create_group(&format!("g{i}")))
        .collect();
    for pair in chain.windows(2) {
        graph.add_child(pair[0], pair[1]).unwrap();
        graph.add_child(pair[0], pair[1]).unwrap();
    }
    let error = graph
        .add_child(graph.root(), chain[0])
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("would add") && error.contains("shared subgraphs multiply paths"),
        "{error}"
    );
    assert!(
        graph.node(graph.root()).unwrap().children().is_empty(),
        "a refused edit changes nothing"
    );

    // Built from the root down, the limit is met part way.
    let mut graph = SceneGraph::new();
    let mut parent = graph.root();
    let mut refused_at = None;
    for i in 0..40 {
        let next = graph.create_group(&format!("g{i}"));
        let linked = graph
            .add_child(parent, next)
            .and_then(|()| graph.add_child(parent, next));
        if linked.is_err() {
            refused_at = Some(i);
            break;
        }
        parent = next;
    }
    // Level i has 2^i paths: the link that would add 2^28 is the first one refused.
    assert_eq!(refused_at, Some(28));
}

#[test]
fn screen_size_lod_switches_to_coarser_children_as_parts_shrink_on_screen() {
    let mut world = World::new();
    let g = &mut world.graph;
    let (fine, coarse) = (world.geometries[2], world.geometries[0]);
    let material = world.materials[0];
    // A LOD of radius 1 showing 3 parts while it spans more than 0.2 rad, then 1 part.
    let lod = g.create_lod_by_screen_size("lod", 1.0, &[0.2]).unwrap();
    let detailed = g.create_geo("fine", fine, &[material; 3]).unwrap();
    let simple = g.create_geo("coarse", coarse, &[material]).unwrap();
    g.add_child(lod, detailed).unwrap();
    g.add_child(lod, simple).unwrap();
    // The same LOD scaled by 4: it looks bigger, so it switches farther away.
    let big = g
        .create_transform("big", DMat4::from_scale(DVec3::splat(4.0)))
        .unwrap();
    g.add_child(big, lod).unwrap();
    g.add_child(g.root(), lod).unwrap();
    g.add_child(g.root(), big).unwrap();
    let visible_parts = |tree: &SceneTree| -> Vec<usize> {
        // Visible instances per path through the LOD: [unscaled, scaled].
        let mut counts = vec![0, 0];
        for id in tree.instances() {
            let i = tree.instance(id).unwrap();
            if i.visible {
                counts[usize::from(tree.path(i.tree_node).len() > 3)] += 1;
            }
        }
        counts
    };
    let mut tree = SceneTree::build_with_eye(g, DVec3::new(0.0, 0.0, 5.0));
    assert_eq!(
        visible_parts(&tree),
        vec![3, 3],
        "close: both detailed (0.4 and 1.7 rad)"
    );
    tree.update_view(g, DVec3::new(0.0, 0.0, 20.0));
    assert_eq!(
        visible_parts(&tree),
        vec![1, 3],
        "at 20: 0.1 rad and 0.4 rad"
    );
    tree.update_view(g, DVec3::new(0.0, 0.0, 100.0));
    assert_eq!(visible_parts(&tree), vec![1, 1], "far: both coarse");
    let error = g
        .create_lod_by_screen_size("bad", 1.0, &[0.1, 0.2])
        .unwrap_err()
        .to_string();
    assert!(error.contains("decreasing"), "{error}");
}

#[test]
fn moving_the_same_nodes_every_frame_without_refreshing_holds_memory_steady() {
    // A reader that never asks for world matrices on the host (the GPU transform hierarchy)
    // must not make the tree's bookkeeping grow frame after frame.
    let mut world = World::new();
    let g = &mut world.graph;
    let placement = g.create_transform("placement", DMat4::IDENTITY).unwrap();
    g.add_child(g.root(), placement).unwrap();
    let mut tree = SceneTree::build(g);
    let mut memory = Vec::new();
    for frame in 0..1000 {
        let at = DVec3::new(f64::from(frame), 0.0, 0.0);
        g.set_matrix(placement, DMat4::from_translation(at))
            .unwrap();
        tree.update(g);
        assert_eq!(tree.take_changes().moved.len(), 1);
        if frame == 10 || frame == 999 {
            memory.push(tree.memory_bytes());
        }
    }
    assert_eq!(memory[0], memory[1], "tree bytes after 10 and 1000 moves");
}

#[test]
fn a_large_edit_leaves_no_large_event_storage_behind() {
    // The tree keeps the storage of the graph's events between updates, so that dragging parts
    // allocates nothing, but not the storage of an edit that moved thousands of nodes.
    let mut world = World::new();
    let g = &mut world.graph;
    let placements: Vec<_> = (0..6000)
        .map(|i| {
            let node = g
                .create_transform(&format!("placement {i}"), DMat4::IDENTITY)
                .unwrap();
            g.add_child(g.root(), node).unwrap();
            node
        })
        .collect();
    let mut tree = SceneTree::build(g);
    let mut frame = 0.0;
    let mut drag = |tree: &mut SceneTree, g: &mut SceneGraph, count: usize| {
        frame += 1.0;
        for &node in &placements[..count] {
            g.set_matrix(node, DMat4::from_translation(DVec3::X * frame))
                .unwrap();
        }
        tree.update(g);
        assert_eq!(tree.take_changes().moved.len(), count);
        tree.memory_bytes()
    };
    drag(&mut tree, g, 10);
    let steady = drag(&mut tree, g, 10);
    assert_eq!(
        drag(&mut tree, g, 10),
        steady,
        "dragging holds memory steady"
    );
    let large = drag(&mut tree, g, 6000);
    drag(&mut tree, g, 10);
    let after = drag(&mut tree, g, 10);
    // The change logs' bit sets grow to the 6000 nodes and stay (a few bytes per node); the
    // storage of 6000 events does not.
    let events_bytes = 6000 * std::mem::size_of::<cadr_core::graph::GraphEvent>();
    assert!(
        large.1 < steady.1 + events_bytes && after.1 < steady.1 + events_bytes,
        "after moving 6000 nodes the tree keeps no storage of their events: {steady:?} then \
         {large:?}, {after:?}"
    );
}

/// An edit of the page file property: create a geometry of a prism with this many sides,
/// replace the geometry at this index (of those alive) by one, or destroy it.
#[derive(Clone, Debug)]
enum PagedEdit {
    Create(u32),
    Replace(usize, u32),
    Destroy(usize),
}

fn paged_edit() -> impl Strategy<Value = PagedEdit> {
    prop_oneof![
        (3u32..40).prop_map(PagedEdit::Create),
        (0usize..8, 3u32..40).prop_map(|(i, sides)| PagedEdit::Replace(i, sides)),
        (0usize..8).prop_map(PagedEdit::Destroy),
    ]
}

/// A prism geometry of `sides` sides, named after them and `tag`.
fn prism(sides: u32, tag: usize) -> cadr_core::scene::Geometry {
    let mut builder = GeometryBuilder::new(format!("prism {sides} #{tag}"));
    builder.prism(
        sides,
        DMat4::from_translation(DVec3::new(tag as f64, 0.0, 0.0)),
    );
    builder.finish()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases_from_env(64), ..ProptestConfig::default() })]

    /// Geometries kept in the page file (the limit at 0) read back as they were made after
    /// any sequence of creations, replacements and destructions, whose rooms are used again,
    /// and the file is empty once the last is destroyed.
    #[test]
    fn paged_geometries_read_back_as_made_after_any_edits(
        edits in prop::collection::vec(paged_edit(), 1..40)
    ) {
        let mut graph = SceneGraph::new();
        graph.set_geometry_memory_limit(0);
        let mut alive: Vec<(GeometryHandle, cadr_core::scene::Geometry)> = Vec::new();
        for (tag, edit) in edits.into_iter().enumerate() {
            match edit {
                PagedEdit::Create(sides) => {
                    let geometry = prism(sides, tag);
                    alive.push((graph.create_geometry(geometry.clone()).unwrap(), geometry));
                }
                PagedEdit::Replace(i, sides) if !alive.is_empty() => {
                    let i = i % alive.len();
                    let geometry = prism(sides, tag);
                    graph.replace_geometry(alive[i].0, geometry.clone()).unwrap();
                    alive[i].1 = geometry;
                }
                PagedEdit::Destroy(i) if !alive.is_empty() => {
                    let (handle, _) = alive.swap_remove(i % alive.len());
                    graph.destroy_geometry(handle).unwrap();
                }
                _ => {}
            }
            for (handle, geometry) in &alive {
                prop_assert!(graph.geometry_info_at(handle.index()).unwrap().paged);
                prop_assert_eq!(&*graph.geometry(*handle).unwrap(), geometry);
                prop_assert_eq!(graph.geometry_bounds(*handle).unwrap(), geometry.bounds());
            }
            let memory = graph.geometry_memory();
            prop_assert_eq!(memory.paged_geometries, alive.len() as u64);
            prop_assert_eq!(memory.resident_bytes, 0);
            if let Some(file) = &memory.page_file {
                // The file holds the records alive and the free rooms between them, never
                // more than it has to after its end is freed.
                let length = std::fs::metadata(file).unwrap().len();
                prop_assert!(length >= memory.paged_bytes);
                if alive.is_empty() {
                    prop_assert_eq!(length, 0);
                }
            }
        }
    }
}
