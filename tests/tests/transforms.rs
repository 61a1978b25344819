//! The transform hierarchy on the GPU: after random moves and edits of a nested assembly, the
//! world matrices the GPU computed equal the scene tree's (f64) within f32 rounding, with
//! either method, also 100 km from the origin; a move uploads 64 bytes per moved node; frames
//! drawn from GPU-computed matrices look like a fresh upload's.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::sync::Arc;

use cadr_core::generate::GeometryBuilder;
use cadr_core::gpu_scene::Transforms;
use cadr_core::gpu_scene::{GpuScene, HierarchyMethod, LOCAL_BYTES, MATRIX_BYTES};
use cadr_core::graph::{GeometryHandle, MaterialHandle, NodeFlags, NodeHandle, SceneGraph};
use cadr_core::render::Camera;
use cadr_core::scene::Material;
use cadr_core::technique::TechniqueKind;
use cadr_core::tree::SceneTree;
use cadr_core::view::View;
use cadr_tests::{assert_no_validation_errors, images, plugin_registry, scene_wide, test_device};
use glam::{DMat4, DQuat, DVec3};
use proptest::prelude::*;

/// How far the far assemblies lie from the origin (100 km, in metres).
const FAR: f64 = 1e5;

/// A nested assembly: assemblies below the root, sub-assemblies below them, parts below
/// those, each part a transform over a cube; sub-assembly 0 of assembly 0 is shared by
/// assembly 1 as well (two paths).
struct Assembly {
    graph: SceneGraph,
    shape: (GeometryHandle, MaterialHandle),
    assemblies: Vec<NodeHandle>,
    subs: Vec<NodeHandle>,
    parts: Vec<NodeHandle>,
}

fn placement(angle: f64, scale: f64, at: DVec3) -> DMat4 {
    DMat4::from_scale_rotation_translation(
        DVec3::splat(scale),
        DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), angle),
        at,
    )
}

impl Assembly {
    fn new() -> Self {
        let mut graph = SceneGraph::new();
        let mut builder = GeometryBuilder::new("cube");
        builder.cuboid(DVec3::splat(-0.4), DVec3::splat(0.4), DMat4::IDENTITY);
        let geometry = graph.create_geometry(builder.finish()).unwrap();
        let material = graph.create_material(Material::default()).unwrap();
        let mut assembly = Self {
            graph,
            shape: (geometry, material),
            assemblies: Vec::new(),
            subs: Vec::new(),
            parts: Vec::new(),
        };
        let root = assembly.graph.root();
        for a in 0..4 {
            let far = if a % 2 == 1 { FAR } else { 0.0 };
            let at = DVec3::new(far + f64::from(a) * 3.0, 0.0, 0.0);
            let node = assembly.transform(root, placement(0.1 * f64::from(a), 1.0, at));
            assembly.assemblies.push(node);
            for s in 0..3 {
                let at = DVec3::new(0.0, f64::from(s) * 1.5, 0.5);
                let sub = assembly.transform(node, placement(0.3 * f64::from(s), 1.0, at));
                assembly.subs.push(sub);
                for p in 0..2 {
                    assembly.add_part(sub, p);
                }
            }
        }
        let (shared, second) = (assembly.subs[0], assembly.assemblies[1]);
        assembly.graph.add_child(second, shared).unwrap();
        assembly
    }

    fn transform(&mut self, parent: NodeHandle, matrix: DMat4) -> NodeHandle {
        let node = self.graph.create_transform("t", matrix).unwrap();
        self.graph.add_child(parent, node).unwrap();
        node
    }

    fn add_part(&mut self, sub: NodeHandle, index: u32) {
        let at = DVec3::new(f64::from(index) * 0.9, 0.0, 0.0);
        let part = self.transform(sub, placement(0.2 * f64::from(index), 1.0, at));
        let geo = self
            .graph
            .create_geo("part", self.shape.0, &[self.shape.1])
            .unwrap();
        self.graph.add_child(part, geo).unwrap();
        self.parts.push(part);
    }
}

/// Edits of one frame.
#[derive(Clone, Debug)]
enum Edit {
    /// Moves an assembly (level 1), a sub-assembly (2) or a part (3): turn, scale, offset.
    Move(u8, u8, i8, bool),
    /// Hides or shows a sub-assembly (refreshed on the host, uploaded as world matrices).
    Flags(u8, bool),
    /// A new part in a sub-assembly.
    Add(u8),
    /// Removes a sub-assembly's first child.
    Remove(u8),
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        6 => (1u8..4, any::<u8>(), any::<i8>(), any::<bool>())
            .prop_map(|(level, n, turn, far)| Edit::Move(level, n, turn, far)),
        1 => (any::<u8>(), any::<bool>()).prop_map(|(n, visible)| Edit::Flags(n, visible)),
        1 => any::<u8>().prop_map(Edit::Add),
        1 => any::<u8>().prop_map(Edit::Remove),
    ]
}

impl Assembly {
    fn apply(&mut self, edit: &Edit) {
        match *edit {
            Edit::Move(level, n, turn, far) => {
                let nodes = match level {
                    1 => &self.assemblies,
                    2 => &self.subs,
                    _ => &self.parts,
                };
                let node = nodes[usize::from(n) % nodes.len()];
                let offset = f64::from(turn) * 0.05;
                let base = if level == 1 && far { FAR } else { 0.0 };
                let at = DVec3::new(base + offset, offset * 0.5, 1.0);
                let scale = 1.0 + f64::from(n % 3) * 0.25;
                let matrix = placement(f64::from(turn) * 0.01, scale, at);
                self.graph.set_matrix(node, matrix).unwrap();
            }
            Edit::Flags(n, visible) => {
                let sub = self.subs[usize::from(n) % self.subs.len()];
                let flags = NodeFlags {
                    visible,
                    ..NodeFlags::default()
                };
                self.graph.set_flags(sub, flags).unwrap();
            }
            Edit::Add(n) => {
                let sub = self.subs[usize::from(n) % self.subs.len()];
                self.add_part(sub, u32::from(n % 4));
            }
            Edit::Remove(n) => {
                let sub = self.subs[usize::from(n) % self.subs.len()];
                let _ = self.graph.remove_child_at(sub, 0);
            }
        }
    }
}

/// Checks every live tree node's matrix on the GPU against the tree's f64 world matrix:
/// rotation and scale within f32 rounding, the translation (high + low parts) within f32
/// rounding of the local offsets, not of the 100 km.
fn check_gpu_worlds(scene: &GpuScene, tree: &SceneTree) -> Result<usize, TestCaseError> {
    let [matrices, ..] = scene.read_back_arrays().unwrap();
    let floats: Vec<f32> = matrices
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    let mut checked = 0;
    for t in 0..tree.node_capacity() as u32 {
        // On the host path only Geo paths keep a matrix slot; on the GPU path every path.
        let keeps = match scene.transforms() {
            Transforms::Gpu => tree.is_node_alive(t),
            Transforms::Host => tree.has_instances(t),
        };
        if !keeps {
            continue;
        }
        let gpu = &floats[t as usize * 16..t as usize * 16 + 16];
        let world = tree.world(t).to_cols_array();
        for column in 0..3 {
            for row in 0..3 {
                let (got, want) = (f64::from(gpu[column * 4 + row]), world[column * 4 + row]);
                prop_assert!(
                    (got - want).abs() <= 1e-5,
                    "tree node {}: rotation [{}][{}] {} on the GPU, {} on the host",
                    t,
                    column,
                    row,
                    got,
                    want
                );
            }
            let got = f64::from(gpu[12 + column]) + f64::from(gpu[column * 4 + 3]);
            let want = world[12 + column];
            prop_assert!(
                (got - want).abs() <= 1e-4,
                "tree node {}: translation {} {} on the GPU, {} on the host",
                t,
                column,
                got,
                want
            );
        }
        checked += 1;
    }
    Ok(checked)
}

fn method_choice() -> impl Strategy<Value = Option<HierarchyMethod>> {
    prop_oneof![
        Just(None),
        Just(Some(HierarchyMethod::Leaves)),
        Just(Some(HierarchyMethod::Levels)),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]
    #[test]
    fn gpu_world_matrices_equal_the_trees_after_random_edits(
        frames in prop::collection::vec(prop::collection::vec(edit(), 1..6), 1..10),
        method in method_choice(),
    ) {
        let device = test_device();
        let mut assembly = Assembly::new();
        let mut tree = SceneTree::build(&mut assembly.graph);
        let mut scene = GpuScene::new(&device, &assembly.graph, &mut tree, Transforms::Gpu).unwrap();
        scene.force_hierarchy_method(method);
        scene.flush_uploads().unwrap();
        let mut passes = 0;
        for edits in &frames {
            for edit in edits {
                assembly.apply(edit);
            }
            tree.update(&mut assembly.graph);
            scene.sync(&assembly.graph, &mut tree, Transforms::Gpu).unwrap();
            scene.flush_uploads().unwrap();
            if let Some(plan) = scene.last_hierarchy() {
                passes += 1;
                if let Some(forced) = method {
                    prop_assert_eq!(plan.method, forced);
                }
            }
            let checked = check_gpu_worlds(&scene, &tree)?;
            prop_assert!(checked >= tree.instance_count());
        }
        // A frame that only moves runs the pass (one that adds nodes may upload afresh).
        let moving_frames = frames
            .iter()
            .filter(|edits| edits.iter().all(|e| matches!(e, Edit::Move(..))))
            .count();
        prop_assert!(moving_frames == 0 || passes > 0, "{} moving frames, no hierarchy pass", moving_frames);
        drop(scene);
        assert_no_validation_errors(&device);
    }
}

#[test]
fn a_move_uploads_its_local_matrices_only() {
    let device = test_device();
    let mut assembly = Assembly::new();
    let mut tree = SceneTree::build(&mut assembly.graph);
    let mut scene = GpuScene::new(&device, &assembly.graph, &mut tree, Transforms::Gpu).unwrap();
    scene.flush_uploads().unwrap();
    // Three assemblies with 6 parts each (and one shared sub-assembly) move.
    for (i, &node) in assembly.assemblies[..3].iter().enumerate() {
        let at = DVec3::new(FAR, i as f64, 2.0);
        assembly
            .graph
            .set_matrix(node, placement(0.5, 1.0, at))
            .unwrap();
    }
    tree.update(&mut assembly.graph);
    scene
        .sync(&assembly.graph, &mut tree, Transforms::Gpu)
        .unwrap();
    let bytes = scene.flush_uploads().unwrap();
    assert_eq!(
        bytes,
        3 * (LOCAL_BYTES as u64 + 4),
        "a slot and a local matrix per moved node, nothing below them"
    );
    assert_eq!(LOCAL_BYTES + 4, 64);
    let plan = scene.last_hierarchy().expect("a hierarchy pass ran");
    assert_eq!(plan.roots, 3);
    // Each assembly: itself, 3 subs with 2 parts (a transform and a geo each); assembly 1
    // also holds the shared sub-assembly's second path.
    let per_assembly = 1 + 3 * (1 + 2 * 2);
    assert_eq!(plan.nodes as usize, 3 * per_assembly + (1 + 2 * 2));
    check_gpu_worlds(&scene, &tree).unwrap();
    // The same move on the host uploads a world matrix for every part below.
    let mut host = GpuScene::new(&device, &assembly.graph, &mut tree, Transforms::Host).unwrap();
    host.flush_uploads().unwrap();
    assembly
        .graph
        .set_matrix(assembly.assemblies[0], DMat4::IDENTITY)
        .unwrap();
    tree.update(&mut assembly.graph);
    host.sync(&assembly.graph, &mut tree, Transforms::Host)
        .unwrap();
    let host_bytes = host.flush_uploads().unwrap();
    assert_eq!(host_bytes, 6 * (MATRIX_BYTES as u64 + 4), "6 parts' worlds");
    drop((scene, host));
    assert_no_validation_errors(&device);
}

#[test]
fn moving_assemblies_draws_like_a_fresh_upload() {
    // Frames drawn from the GPU's world matrices (ssbo-index reads them there) against a view
    // that uploads the moved scene afresh, and against the host path (push constants).
    let device = test_device();
    let registry = plugin_registry(&device);
    let gpu_combination = scene_wide("individual", "none");
    let mut assembly = Assembly::new();
    let mut tree = SceneTree::build(&mut assembly.graph);
    let camera = Camera::look_at(
        DVec3::new(5.0, 3.0, 25.0),
        DVec3::new(5.0, 2.0, 0.0),
        40.0,
        4.0 / 3.0,
        0.1,
        200.0,
    );
    // One view draws from the GPU's matrices, one from the host's (push constants); both
    // against a view that uploads the moved scene afresh.
    let mut on_gpu = View::new(&device, Arc::clone(&registry), 96, 72).unwrap();
    on_gpu.techniques_mut().select(&gpu_combination).unwrap();
    assert_eq!(on_gpu.techniques().transforms(), Transforms::Gpu);
    let mut on_host = View::new(&device, Arc::clone(&registry), 96, 72).unwrap();
    on_host
        .techniques_mut()
        .swap(TechniqueKind::Vertex, "arena")
        .unwrap();
    assert_eq!(on_host.techniques().transforms(), Transforms::Host);
    on_gpu.render(&assembly.graph, &mut tree, &camera).unwrap();
    on_host.render(&assembly.graph, &mut tree, &camera).unwrap();
    for frame in 0..4 {
        for (i, &node) in assembly.assemblies.iter().enumerate().step_by(2) {
            let at = DVec3::new(i as f64 * 3.0, f64::from(frame) * 0.3, 0.0);
            let matrix = placement(0.2 * f64::from(frame), 1.0, at);
            assembly.graph.set_matrix(node, matrix).unwrap();
        }
        let sub = assembly.subs[4];
        let matrix = placement(0.4 * f64::from(frame), 1.0, DVec3::new(0.0, 2.0, 1.0));
        assembly.graph.set_matrix(sub, matrix).unwrap();
        tree.update(&mut assembly.graph);
        let drawn = on_gpu.render(&assembly.graph, &mut tree, &camera).unwrap();
        assert!(drawn.triangles >= 12 * 8, "frame {frame}: {drawn:?}");
        on_host.render(&assembly.graph, &mut tree, &camera).unwrap();
        let scene = on_gpu.scene().unwrap();
        assert!(
            scene.last_hierarchy().is_some(),
            "frame {frame}: no hierarchy pass"
        );
        let mut fresh = View::new(&device, Arc::clone(&registry), 96, 72).unwrap();
        fresh.techniques_mut().select(&gpu_combination).unwrap();
        let mut fresh_tree = SceneTree::build(&mut assembly.graph);
        fresh
            .render(&assembly.graph, &mut fresh_tree, &camera)
            .unwrap();
        let expected = fresh.renderer().read_rgba8().unwrap();
        for (view, name) in [(&on_gpu, "GPU"), (&on_host, "host")] {
            let image = view.renderer().read_rgba8().unwrap();
            let difference = images::compare(&image, &expected).unwrap();
            assert!(
                difference.within(images::SAME_PICTURE),
                "frame {frame}, {name} transforms: {difference:?}"
            );
        }
    }
    // Choosing a host-matrix technique after moves: the next frame (synced) draws right, a
    // frame drawn without syncing is refused.
    on_gpu
        .techniques_mut()
        .swap(TechniqueKind::Parameters, "push")
        .unwrap();
    let refused = on_gpu.draw(&camera).unwrap_err().to_string();
    assert!(refused.contains("sync"), "{refused}");
    on_gpu.render(&assembly.graph, &mut tree, &camera).unwrap();
    drop((on_gpu, on_host));
    assert_no_validation_errors(&device);
}

#[test]
fn a_planned_pass_is_dropped_when_the_scene_is_uploaded_afresh() {
    // A move synced on the GPU path, then, before any upload, a sync that switches to the host
    // path (which uploads every matrix): the planned hierarchy pass must not run on what the
    // next upload holds.
    let device = test_device();
    let mut assembly = Assembly::new();
    let mut tree = SceneTree::build(&mut assembly.graph);
    let mut scene = GpuScene::new(&device, &assembly.graph, &mut tree, Transforms::Gpu).unwrap();
    scene.flush_uploads().unwrap();
    let moved = assembly.assemblies[1];
    let matrix = placement(0.3, 1.5, DVec3::new(FAR, 2.0, 0.0));
    assembly.graph.set_matrix(moved, matrix).unwrap();
    tree.update(&mut assembly.graph);
    scene
        .sync(&assembly.graph, &mut tree, Transforms::Gpu)
        .unwrap();
    scene
        .sync(&assembly.graph, &mut tree, Transforms::Host)
        .unwrap();
    scene.flush_uploads().unwrap();
    assert_eq!(scene.last_hierarchy(), None);
    check_gpu_worlds(&scene, &tree).unwrap();
    drop(scene);
    assert_no_validation_errors(&device);
}
