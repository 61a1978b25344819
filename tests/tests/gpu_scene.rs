//! The one GPU scene and picking through the technique path: picks agree with what is drawn in
//! every valid combination, occurrences of a shared part are told apart, unpickable and hidden
//! parts let the click through, world positions are exact far from the origin; several
//! readers of one tree upload only what changed; a replaced geometry is written in place;
//! geometries created after the first frame are placed without laying the arenas out again,
//! and destroyed ones leave their room to the next; any sequence of edits leaves the GPU scene
//! drawing what a fresh upload draws.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::sync::Arc;

use cadr_core::frame::Renderer;
use cadr_core::generate::{generate, GeneratorSpec, GeometryBuilder};
use cadr_core::gpu_scene::Transforms;
use cadr_core::gpu_scene::{GpuScene, ViewState, MATRIX_BYTES};
use cadr_core::graph::{GeometryHandle, MaterialHandle, NodeFlags, NodeHandle, SceneGraph};
use cadr_core::render::pick::PixelRect;
use cadr_core::render::{Camera, DEFAULT_DIRECTION};
use cadr_core::scene::{flatten, Material};
use cadr_core::technique::{Combination, TechniqueKind};
use cadr_core::tree::SceneTree;
use cadr_core::view::{SharedScenes, View};
use cadr_core::vk::Device;
use cadr_tests::{
    assert_no_validation_errors, plugin_registry, scene_wide, test_device, CYLINDER_ENGINE_GLB,
};
use glam::{DMat4, DVec3};
use proptest::prelude::*;

const SIZE: (u32, u32) = (96, 72);

fn view(device: &Arc<Device>, combination: &Combination) -> View {
    let mut view = View::new(device, plugin_registry(device), SIZE.0, SIZE.1).unwrap();
    view.techniques_mut().select(combination).unwrap();
    view
}

/// A unit cube (one part) and a grey material.
fn cube(graph: &mut SceneGraph) -> (GeometryHandle, MaterialHandle) {
    let mut builder = GeometryBuilder::new("cube");
    builder.cuboid(DVec3::splat(-0.5), DVec3::splat(0.5), DMat4::IDENTITY);
    let geometry = graph.create_geometry(builder.finish()).unwrap();
    let material = graph.create_material(Material::default()).unwrap();
    (geometry, material)
}

/// A transform placing one cube at `at`, below `parent`.
fn place(
    graph: &mut SceneGraph,
    parent: NodeHandle,
    name: &str,
    at: DVec3,
    shape: (GeometryHandle, MaterialHandle),
) -> (NodeHandle, NodeHandle) {
    let transform = graph
        .create_transform(name, DMat4::from_translation(at))
        .unwrap();
    let geo = graph
        .create_geo(&format!("{name} geo"), shape.0, &[shape.1])
        .unwrap();
    graph.add_child(parent, transform).unwrap();
    graph.add_child(transform, geo).unwrap();
    (transform, geo)
}

/// A camera at `eye` looking down -Z at `target`.
fn camera_at(eye: DVec3, target: DVec3) -> Camera {
    Camera::look_at(
        eye,
        target,
        40.0,
        f64::from(SIZE.0) / f64::from(SIZE.1),
        0.1,
        100.0,
    )
}

fn centre() -> PixelRect {
    PixelRect::pixel(SIZE.0 / 2, SIZE.1 / 2)
}

#[test]
fn every_valid_combination_picks_what_it_draws_in_the_demo() {
    every_valid_combination_picks_what_it_draws(&generate(&GeneratorSpec::Demo), true);
}

#[test]
fn every_valid_combination_picks_what_it_draws_in_2_cylinder_engine() {
    let engine = cadr_core::load::load_file(std::path::Path::new(CYLINDER_ENGINE_GLB)).unwrap();
    every_valid_combination_picks_what_it_draws(&engine, false);
}

/// Box selection of the whole view with the built-in combination is the reference (checked
/// against its own image and the parts' geometry); every valid combination must pick exactly
/// its parts. With `joins`, the scene has parts that joining submissions merge when shading.
fn every_valid_combination_picks_what_it_draws(source: &cadr_core::scene::Scene, joins: bool) {
    let device = test_device();
    let (mut graph, _) = SceneGraph::from_scene(source).unwrap();
    let mut tree = SceneTree::build(&mut graph);
    let bounds = flatten(source).unwrap().bounds;
    let camera = Camera::fit(
        &bounds,
        f64::from(SIZE.0) / f64::from(SIZE.1),
        DEFAULT_DIRECTION,
    );
    let registry = plugin_registry(&device);
    let names = |kind| -> Vec<String> {
        registry
            .of_kind(kind)
            .filter(|t| t.support.is_ok())
            .map(|t| t.name.clone())
            .collect()
    };
    let mut view = View::new(&device, Arc::clone(&registry), SIZE.0, SIZE.1).unwrap();
    view.techniques_mut()
        .select(&Combination::built_in())
        .unwrap();
    let whole = PixelRect {
        x: 0,
        y: 0,
        width: SIZE.0,
        height: SIZE.1,
    };
    // The reference: the simplest combination's box selection of the whole image, checked
    // against its own drawing: a covered pixel is never background, and every hit's world
    // position lies on its part (within its bounding sphere).
    view.sync(&graph, &mut tree).unwrap();
    let reference = view.pick(&tree, &camera, whole).unwrap();
    assert!(reference.len() >= 10, "{} parts picked", reference.len());
    view.render(&graph, &mut tree, &camera).unwrap();
    let image = view.renderer().read_rgba8().unwrap();
    for hit in &reference {
        assert!(
            !cadr_tests::images::is_background(&image, hit.pixel.0, hit.pixel.1),
            "{hit:?} picks a background pixel"
        );
        let instance = tree.instance(hit.instance).unwrap();
        let world = tree.world(instance.tree_node);
        let geometry = graph.geometry_at(instance.geometry).unwrap().unwrap();
        let part = geometry.parts[hit.part as usize];
        let local = world.inverse().transform_point3(hit.position);
        let indices = &geometry.indices
            [part.first_index as usize..(part.first_index + part.index_count) as usize];
        let nearest = indices
            .iter()
            .map(|&i| DVec3::from(geometry.vertices[i as usize].position.map(f64::from)))
            .fold(None::<(DVec3, DVec3)>, |b, p| match b {
                None => Some((p, p)),
                Some((lo, hi)) => Some((lo.min(p), hi.max(p))),
            })
            .unwrap();
        let slack = 0.02 * (nearest.1 - nearest.0).length() + 1e-3;
        assert!(
            local.cmpge(nearest.0 - slack).all() && local.cmple(nearest.1 + slack).all(),
            "{hit:?}: world position {local} (part space) is off the part's box {nearest:?}"
        );
    }
    // What a combination must pick: the same parts of the same occurrences. Submissions that
    // join parts for shading (join, material groups) draw the pick pass one part per range.
    let occurrence = |tree: &SceneTree, instance: u32| tree.instance(instance).unwrap().tree_node;
    let mut reference_parts: Vec<(u32, u32)> =
        reference.iter().map(|h| (h.instance, h.part)).collect();
    reference_parts.sort_unstable();
    let reference_occurrences: std::collections::BTreeSet<u32> = reference
        .iter()
        .map(|h| occurrence(&tree, h.instance))
        .collect();
    if joins {
        assert!(
            reference_occurrences.len() < reference_parts.len(),
            "some occurrences have several parts, which joining submissions would merge"
        );
    }
    let individual_draws = view.render(&graph, &mut tree, &camera).unwrap().draws;
    let mut checked = 0;
    for vertex in names(TechniqueKind::Vertex) {
        for parameters in names(TechniqueKind::Parameters) {
            for submission in names(TechniqueKind::Submission) {
                let combination = Combination {
                    vertex: vertex.clone(),
                    parameters: parameters.clone(),
                    submission: submission.clone(),
                    culling: "none".into(),
                    ..Combination::built_in()
                };
                if view.techniques().check(&combination).is_err() {
                    continue;
                }
                view.techniques_mut().select(&combination).unwrap();
                view.sync(&graph, &mut tree).unwrap();
                let hits = view.pick(&tree, &camera, whole).unwrap();
                let mut parts: Vec<(u32, u32)> =
                    hits.iter().map(|h| (h.instance, h.part)).collect();
                parts.sort_unstable();
                assert_eq!(parts, reference_parts, "{combination}");
                if joins && submission == "join" {
                    let shaded = view.render(&graph, &mut tree, &camera).unwrap();
                    assert!(
                        shaded.draws < individual_draws,
                        "{combination} joins parts when shading ({} of {individual_draws})",
                        shaded.draws
                    );
                }
                checked += 1;
            }
        }
    }
    assert!(checked >= 20, "only {checked} combinations checked");
    assert_no_validation_errors(&device);
}

#[test]
fn occurrences_pickable_flags_and_hidden_parts() {
    let device = test_device();
    let mut graph = SceneGraph::new();
    let root = graph.root();
    let shape = cube(&mut graph);
    // One bolt subgraph shared by two transforms: two occurrences of one Geo node.
    let bolt = graph.create_group("bolt");
    let bolt_geo = graph.create_geo("bolt geo", shape.0, &[shape.1]).unwrap();
    graph.add_child(bolt, bolt_geo).unwrap();
    let left = graph
        .create_transform("left", DMat4::from_translation(DVec3::new(-1.0, 0.0, 0.0)))
        .unwrap();
    let right = graph
        .create_transform("right", DMat4::from_translation(DVec3::new(1.0, 0.0, 0.0)))
        .unwrap();
    for side in [left, right] {
        graph.add_child(root, side).unwrap();
        graph.add_child(side, bolt).unwrap();
    }
    // A cube in front of a cube, on the axis.
    let (front, _) = place(&mut graph, root, "front", DVec3::new(0.0, 3.0, 1.0), shape);
    let (_, back_geo) = place(&mut graph, root, "back", DVec3::new(0.0, 3.0, -1.0), shape);
    let mut tree = SceneTree::build(&mut graph);
    let mut view = view(&device, &Combination::built_in());

    let pick_at = |view: &mut View, graph: &SceneGraph, tree: &mut SceneTree, target: DVec3| {
        let camera = camera_at(target + DVec3::new(0.0, 0.0, 6.0), target);
        view.sync(graph, tree).unwrap();
        view.pick(tree, &camera, centre()).unwrap()
    };
    let on_left = pick_at(&mut view, &graph, &mut tree, DVec3::new(-1.0, 0.0, 0.0));
    let on_right = pick_at(&mut view, &graph, &mut tree, DVec3::new(1.0, 0.0, 0.0));
    assert_eq!(on_left.len(), 1);
    assert_eq!(on_right.len(), 1);
    assert_eq!(on_left[0].node, bolt_geo);
    assert_eq!(on_right[0].node, bolt_geo);
    assert_eq!(on_left[0].path, vec![root, left, bolt, bolt_geo]);
    assert_eq!(on_right[0].path, vec![root, right, bolt, bolt_geo]);
    // The front face of the left bolt is at z = 0.5.
    // (within a pixel: the centre pixel is half a pixel off the image centre)
    assert!((on_left[0].position - DVec3::new(-1.0, 0.0, 0.5)).length() < 0.06);

    let behind = DVec3::new(0.0, 3.0, 0.0);
    let hit = pick_at(&mut view, &graph, &mut tree, behind);
    assert_eq!(hit[0].path[1], front, "the front cube is hit first");
    let unpickable = NodeFlags {
        pickable: false,
        ..NodeFlags::default()
    };
    graph.set_flags(front, unpickable).unwrap();
    tree.update(&mut graph);
    let hit = pick_at(&mut view, &graph, &mut tree, behind);
    assert_eq!(
        hit[0].node, back_geo,
        "an unpickable part lets the click through"
    );
    graph.set_flags(front, NodeFlags::default()).unwrap();
    let hidden = NodeFlags {
        visible: false,
        ..NodeFlags::default()
    };
    graph.set_flags(front, hidden).unwrap();
    tree.update(&mut graph);
    let hit = pick_at(&mut view, &graph, &mut tree, behind);
    assert_eq!(hit[0].node, back_geo, "a hidden part is not picked");
    let nothing = pick_at(&mut view, &graph, &mut tree, DVec3::new(0.0, -20.0, 0.0));
    assert!(nothing.is_empty(), "background gives no hit: {nothing:?}");

    // Box selection over the two bolts: exactly the two occurrences.
    let camera = camera_at(DVec3::new(0.0, 0.0, 8.0), DVec3::ZERO);
    view.sync(&graph, &mut tree).unwrap();
    let boxed = view
        .pick(
            &tree,
            &camera,
            PixelRect::spanning((0, SIZE.1 / 2 - 2), (SIZE.0 - 1, SIZE.1 / 2 + 2)),
        )
        .unwrap();
    let mut paths: Vec<Vec<NodeHandle>> = boxed.into_iter().map(|h| h.path).collect();
    paths.sort_by_key(|p| p[1].index());
    assert_eq!(
        paths,
        vec![
            vec![root, left, bolt, bolt_geo],
            vec![root, right, bolt, bolt_geo]
        ]
    );
    assert_no_validation_errors(&device);
}

#[test]
fn world_positions_stay_exact_100_km_from_the_origin() {
    let device = test_device();
    let far = DVec3::new(100_000.0, -100_000.0, 100_000.0);
    let mut graph = SceneGraph::new();
    let root = graph.root();
    let shape = cube(&mut graph);
    place(&mut graph, root, "far cube", far, shape);
    let mut tree = SceneTree::build(&mut graph);
    let mut view = view(&device, &Combination::built_in());
    let eye = far + DVec3::new(0.0, 0.0, 4.0);
    let camera = camera_at(eye, far);
    for (x, y) in [(SIZE.0 / 2, SIZE.1 / 2), (SIZE.0 / 2 + 7, SIZE.1 / 2 - 5)] {
        view.sync(&graph, &mut tree).unwrap();
        let hits = view.pick(&tree, &camera, PixelRect::pixel(x, y)).unwrap();
        let hit = hits.first().expect("the cube is under the pixel");
        // The true surface is the cube's front face, z = far.z + 0.5; a pixel there spans
        // 2 * 3.5 * tan(20°) / 72 ≈ 0.035 units.
        let footprint = 2.0 * 3.5 * (20.0_f64).to_radians().tan() / f64::from(SIZE.1);
        assert!(
            (hit.position.z - (far.z + 0.5)).abs() < footprint,
            "{:?} is off the front face",
            hit.position
        );
        let offset = hit.position - far;
        assert!(offset.x.abs() < 0.5 + footprint && offset.y.abs() < 0.5 + footprint);
    }
    assert_no_validation_errors(&device);
}

#[test]
fn two_views_of_one_tree_upload_only_what_changed() {
    let device = test_device();
    let mut graph = SceneGraph::new();
    let root = graph.root();
    let shape = cube(&mut graph);
    let (mover, _) = place(&mut graph, root, "mover", DVec3::ZERO, shape);
    for i in 0..20 {
        place(
            &mut graph,
            root,
            &format!("cube {i}"),
            DVec3::new(f64::from(i), 2.0, 0.0),
            shape,
        );
    }
    let mut tree = SceneTree::build(&mut graph);
    let camera = camera_at(DVec3::new(0.0, 0.0, 30.0), DVec3::ZERO);
    let mut a = view(&device, &Combination::built_in());
    let mut b = view(&device, &Combination::built_in());
    a.render(&graph, &mut tree, &camera).unwrap();
    b.render(&graph, &mut tree, &camera).unwrap();
    for step in 1..4 {
        graph
            .set_matrix(
                mover,
                DMat4::from_translation(DVec3::new(0.0, f64::from(step), 0.0)),
            )
            .unwrap();
        tree.update(&mut graph);
        for v in [&mut a, &mut b] {
            let stats = v.render(&graph, &mut tree, &camera).unwrap();
            // One matrix behind its slot: 4 + 64 bytes, nothing else.
            assert_eq!(stats.bytes_uploaded, 4 + MATRIX_BYTES as u64, "step {step}");
            let upload = v.scene().unwrap().last_upload();
            assert_eq!(
                (upload.matrices, upload.records, upload.geometry_bytes),
                (1, 0, 0)
            );
        }
    }
    // A frame with nothing changed uploads nothing.
    assert_eq!(
        a.render(&graph, &mut tree, &camera).unwrap().bytes_uploaded,
        0
    );
    assert_eq!(tree.reader_count(), 2);
    drop(b);
    tree.take_changes();
    a.render(&graph, &mut tree, &camera).unwrap();
    assert_eq!(tree.reader_count(), 1, "a dropped view stops reading");
    assert_no_validation_errors(&device);
}

#[test]
fn a_replaced_geometry_is_written_in_place() {
    let device = test_device();
    let mut graph = SceneGraph::new();
    let root = graph.root();
    let shape = cube(&mut graph);
    let other = cube(&mut graph);
    for i in 0..3 {
        place(
            &mut graph,
            root,
            &format!("user {i}"),
            DVec3::new(f64::from(i) * 2.0, 0.0, 0.0),
            shape,
        );
    }
    for i in 0..5 {
        place(
            &mut graph,
            root,
            &format!("other {i}"),
            DVec3::new(f64::from(i) * 2.0, 3.0, 0.0),
            other,
        );
    }
    let mut tree = SceneTree::build(&mut graph);
    let camera = camera_at(DVec3::new(4.0, 1.0, 20.0), DVec3::new(4.0, 1.0, 0.0));
    let mut v = view(&device, &Combination::built_in());
    v.render(&graph, &mut tree, &camera).unwrap();
    let mut smaller = GeometryBuilder::new("smaller cube");
    smaller.cuboid(DVec3::splat(-0.25), DVec3::splat(0.25), DMat4::IDENTITY);
    let smaller = smaller.finish();
    let bytes = (smaller.vertices.len() * std::mem::size_of::<cadr_core::scene::Vertex>()
        + smaller.indices.len() * 4) as u64;
    graph.replace_geometry(shape.0, smaller.clone()).unwrap();
    tree.update(&mut graph);
    v.render(&graph, &mut tree, &camera).unwrap();
    let scene = v.scene().unwrap();
    let upload = scene.last_upload();
    assert!(
        upload.geometry_bytes >= bytes && upload.geometry_bytes < 2 * bytes,
        "{upload:?}: only the replaced geometry's vertices, indices and edges ({bytes} B + edges)"
    );
    assert_eq!(upload.records, 3, "only its 3 users' records");
    assert_eq!(scene.last_touched(), 3);
    // The result equals a fresh upload.
    let fresh = GpuScene::new(&device, &graph, &mut tree, Transforms::Host).unwrap();
    assert_eq!(scene.content().instances, fresh.content().instances);
    assert_no_validation_errors(&device);
}

#[test]
fn staged_and_direct_uploads_fill_the_gpu_scene_alike() {
    // Lavapipe's device memory is host-visible, so uploads write it directly; a discrete GPU's
    // go through staging buffers and a GPU copy. 100 000 parts make arrays of several 4 MiB
    // pieces, filled on several threads, with items cut by the pieces' edges (48-byte cull
    // entries). Both ways, after a whole upload and after sparse edits, the GPU holds the same.
    let device = test_device();
    let source = generate(&GeneratorSpec::Grid {
        parts: 100_000,
        triangles_per_part: 12.0,
    });
    let (mut graph, _) = SceneGraph::from_scene(&source).unwrap();
    let mut tree = SceneTree::build(&mut graph);
    let renderer = Renderer::new(&device, 1, 1).unwrap();
    let mut arrays = Vec::new();
    for staged in [false, true] {
        device.set_staged_uploads(staged);
        let mut scene = GpuScene::new(&device, &graph, &mut tree, Transforms::Gpu).unwrap();
        scene.flush_uploads().unwrap();
        let whole = scene.read_back_arrays().unwrap();
        assert!(
            whole.iter().all(|bytes| bytes.iter().any(|&b| b != 0)),
            "every array holds data"
        );
        arrays.push(whole);
    }
    device.set_staged_uploads(false);
    assert!(
        arrays[0] == arrays[1],
        "staged and direct whole uploads differ"
    );
    // The records and cull entries are made from the instance entries on the fly: compare them
    // with what the entries say.
    let scene = GpuScene::new(&device, &graph, &mut tree, Transforms::Gpu).unwrap();
    let instances = scene.content().instances;
    let [_, _, records, cull_entries, part_boxes] = &arrays[0];
    let words = |bytes: &[u8]| -> Vec<u32> {
        bytes
            .chunks_exact(4)
            .map(|w| u32::from_le_bytes(w.try_into().unwrap()))
            .collect()
    };
    let (records, cull_entries) = (words(records), words(cull_entries));
    for (id, entry) in instances.iter().enumerate() {
        let record = [entry.matrix, entry.material, entry.flags, id as u32];
        assert_eq!(records[id * 4..id * 4 + 4], record, "record {id}");
        let cull = [
            entry.sphere[0].to_bits(),
            entry.sphere[1].to_bits(),
            entry.sphere[2].to_bits(),
            entry.sphere[3].to_bits(),
            entry.first_index,
            entry.index_count,
            entry.first_wire_index,
            entry.wire_index_count,
            entry.vertex_base,
            entry.matrix,
        ];
        assert_eq!(cull_entries[id * 12..id * 12 + 10], cull, "cull entry {id}");
        // The part's box holds what the sphere holds, so it lies inside the sphere's cube; an
        // id not in use has none.
        let float = |w: usize| f32::from_le_bytes(part_boxes[w * 4..w * 4 + 4].try_into().unwrap());
        let (center, half) = (
            [0, 1, 2].map(|a| float(id * 8 + a)),
            [0, 1, 2].map(|a| float(id * 8 + 4 + a)),
        );
        if entry.flags & cadr_plugin_abi::CADR_INSTANCE_ALIVE == 0 {
            assert_eq!(
                (center, half),
                ([0.0; 3], [0.0; 3]),
                "box of unused id {id}"
            );
            continue;
        }
        for axis in 0..3 {
            let reach = (center[axis] - entry.sphere[axis]).abs() + half[axis];
            assert!(
                reach <= entry.sphere[3] * 1.0001 + 1e-5,
                "part box of instance {id} leaves its sphere on axis {axis}"
            );
        }
    }
    drop(scene);
    drop(renderer);
    assert_no_validation_errors(&device);
}

/// Edits for the property test.
#[derive(Clone, Debug)]
enum Edit {
    Move(u8, i8),
    Flags(u8, bool, bool, bool),
    Material(u8),
    Add(u8),
    Remove(u8),
    Replace(bool),
    /// A geometry of 1 + n % 4 boxes, new after the first frame, placed once.
    NewGeometry(u8),
    /// The n-th geometry made by `NewGeometry` still alive: its node and it destroyed.
    DestroyGeometry(u8),
}

/// A box geometry of `boxes` boxes side by side, one part.
fn boxes(boxes: u8) -> cadr_core::scene::Geometry {
    let mut builder = GeometryBuilder::new("boxes");
    for i in 0..boxes {
        let x = f64::from(i);
        builder.cuboid(
            DVec3::new(x, 0.0, 0.0),
            DVec3::new(x + 0.5, 0.5, 0.5),
            DMat4::IDENTITY,
        );
    }
    let mut geometry = builder.finish();
    let whole = geometry.indices.len() as u32;
    geometry.parts.truncate(1);
    geometry.parts[0].index_count = whole;
    geometry.parts[0].wire_index_count = 0;
    geometry
}

/// An instance entry without where its geometry lies in the arenas (which depends on the
/// order geometries were placed in).
fn without_place(entry: &cadr_plugin_abi::CadrInstance) -> cadr_plugin_abi::CadrInstance {
    cadr_plugin_abi::CadrInstance {
        vertex_base: 0,
        geometry_first_index: 0,
        geometry_first_wire_index: 0,
        first_index: 0,
        first_wire_index: 0,
        ..*entry
    }
}

/// The cull entries' bytes without where the geometry lies (first index, first wire index,
/// vertex base, first cluster: words 4, 6, 8 and 11 of each 48-byte entry).
fn cull_entries_without_place(bytes: &[u8]) -> Vec<u8> {
    let mut bytes = bytes.to_vec();
    for entry in bytes.chunks_mut(48) {
        for word in [4, 6, 8, 11] {
            entry[word * 4..word * 4 + 4].fill(0);
        }
    }
    bytes
}

/// The object-space corners of every triangle each live instance of `scene` draws, read back
/// from its arenas.
fn drawn_triangles(scene: &GpuScene) -> Vec<Vec<[f32; 3]>> {
    let [vertices, indices] = scene.read_back_geometry().unwrap();
    let float = |at: &[u8]| f32::from_le_bytes([at[0], at[1], at[2], at[3]]);
    // A vertex is 24 bytes: position, then normal.
    let vertices: Vec<[f32; 3]> = vertices
        .chunks_exact(24)
        .map(|v| [float(&v[0..]), float(&v[4..]), float(&v[8..])])
        .collect();
    let indices: Vec<u32> = indices
        .chunks_exact(4)
        .map(|i| u32::from_le_bytes([i[0], i[1], i[2], i[3]]))
        .collect();
    scene
        .content()
        .instances
        .iter()
        .map(|entry| {
            let first = entry.first_index as usize;
            indices[first..first + entry.index_count as usize]
                .iter()
                .map(|&i| vertices[(entry.vertex_base + i) as usize])
                .collect()
        })
        .collect()
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        3 => (any::<u8>(), any::<i8>()).prop_map(|(n, y)| Edit::Move(n, y)),
        2 => (any::<u8>(), any::<bool>(), any::<bool>(), any::<bool>()).prop_map(|(n, v, p, h)| Edit::Flags(n, v, p, h)),
        1 => any::<u8>().prop_map(Edit::Material),
        2 => any::<u8>().prop_map(Edit::Add),
        2 => any::<u8>().prop_map(Edit::Remove),
        1 => any::<bool>().prop_map(Edit::Replace),
        2 => any::<u8>().prop_map(Edit::NewGeometry),
        1 => any::<u8>().prop_map(Edit::DestroyGeometry),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn incremental_syncs_equal_a_fresh_upload(edits in prop::collection::vec(edit(), 1..24)) {
        let device = test_device();
        let mut graph = SceneGraph::new();
        let root = graph.root();
        let shape = cube(&mut graph);
        let mut transforms: Vec<NodeHandle> = (0..6)
            .map(|i| place(&mut graph, root, &format!("t{i}"), DVec3::new(f64::from(i), 0.0, 0.0), shape).0)
            .collect();
        let mut tree = SceneTree::build(&mut graph);
        let mut scene = GpuScene::new(&device, &graph, &mut tree, Transforms::Host).unwrap();
        scene.flush_uploads().unwrap();
        // Two views of the scene: one catches up after every sync, one after every third.
        let (mut every, mut late) = (ViewState::new(), ViewState::new());
        scene.catch_up(&mut every);
        scene.catch_up(&mut late);
        let mut created: Vec<(GeometryHandle, NodeHandle)> = Vec::new();
        for (step, edit) in edits.iter().enumerate() {
            let pick = |n: u8| transforms[n as usize % transforms.len()];
            match *edit {
                Edit::Move(n, y) => {
                    let m = DMat4::from_translation(DVec3::new(f64::from(n % 7), f64::from(y) * 0.1, 1e5));
                    graph.set_matrix(pick(n), m).unwrap();
                }
                Edit::Flags(n, visible, pickable, highlighted) => {
                    graph.set_flags(pick(n), NodeFlags { visible, pickable, highlighted }).unwrap();
                }
                Edit::Material(shade) => {
                    let material = Material { base_color: [f32::from(shade) / 255.0, 0.5, 0.5, 1.0], ..Material::default() };
                    graph.set_material(shape.1, material).unwrap();
                }
                Edit::Add(n) => {
                    // Share an existing transform once more (a new occurrence).
                    let _ = graph.add_child(root, pick(n));
                    let (t, _) = place(&mut graph, root, &format!("added {step}"), DVec3::new(0.0, f64::from(n), 0.0), shape);
                    transforms.push(t);
                }
                Edit::Remove(n) => {
                    let _ = graph.remove_child_at(root, usize::from(n) % 6);
                }
                Edit::Replace(grow) => {
                    let mut builder = GeometryBuilder::new("replacement");
                    builder.cuboid(DVec3::splat(-0.3), DVec3::splat(0.3), DMat4::IDENTITY);
                    if grow {
                        // Twice the size: no longer fits in place.
                        let mut two = GeometryBuilder::new("grown");
                        two.cuboid(DVec3::splat(-0.3), DVec3::splat(0.3), DMat4::IDENTITY);
                        two.cuboid(DVec3::splat(0.3), DVec3::splat(0.6), DMat4::IDENTITY);
                        let mut grown = two.finish();
                        let whole = grown.indices.len() as u32;
                        grown.parts.truncate(1);
                        grown.parts[0].index_count = whole;
                        grown.parts[0].wire_index_count = 0;
                        graph.replace_geometry(shape.0, grown).unwrap();
                    } else {
                        graph.replace_geometry(shape.0, builder.finish()).unwrap();
                    }
                }
                Edit::NewGeometry(n) => {
                    let geometry = graph.create_geometry(boxes(1 + n % 4)).unwrap();
                    let at = DVec3::new(0.0, -f64::from(n % 5), 0.0);
                    let (t, geo) = place(&mut graph, root, &format!("new {step}"), at, (geometry, shape.1));
                    transforms.push(t);
                    created.push((geometry, geo));
                }
                Edit::DestroyGeometry(n) => {
                    if !created.is_empty() {
                        let (geometry, geo) = created.remove(usize::from(n) % created.len());
                        graph.destroy_node(geo).unwrap();
                        graph.destroy_geometry(geometry).unwrap();
                    }
                }
            }
            tree.update(&mut graph);
            scene.sync(&graph, &mut tree, Transforms::Host).unwrap();
            scene.flush_uploads().unwrap();
            scene.catch_up(&mut every);
            if step % 3 == 0 {
                scene.catch_up(&mut late);
            }
        }
        scene.catch_up(&mut late);
        let mut fresh = GpuScene::new(&device, &graph, &mut tree, Transforms::Host).unwrap();
        fresh.flush_uploads().unwrap();
        let mut first = ViewState::new();
        fresh.catch_up(&mut first);
        for view in [&every, &late] {
            prop_assert_eq!(view.drawn_bits(), first.drawn_bits());
            prop_assert_eq!(view.drawn_triangles(), first.drawn_triangles());
        }
        let (synced, expected) = (scene.content(), fresh.content());
        let places = |entries: &[cadr_plugin_abi::CadrInstance]| {
            entries.iter().map(without_place).collect::<Vec<_>>()
        };
        prop_assert_eq!(places(synced.instances), places(expected.instances));
        prop_assert_eq!(drawn_triangles(&scene), drawn_triangles(&fresh));
        prop_assert_eq!(synced.candidate_bits, expected.candidate_bits);
        prop_assert_eq!(synced.materials, expected.materials);
        for (slot, (a, b)) in synced.matrices.iter().zip(expected.matrices).enumerate() {
            if tree.has_instances(slot as u32) {
                prop_assert_eq!(a, b, "matrix slot {}", slot);
            }
        }
        // What the GPU holds equals the CPU copy (the scatter put every item in place).
        let [matrices, materials, records, cull_entries, part_boxes] =
            scene.read_back_arrays().unwrap();
        let [fresh_matrices, fresh_materials, fresh_records, fresh_cull_entries, fresh_part_boxes] =
            fresh.read_back_arrays().unwrap();
        prop_assert_eq!(records, fresh_records);
        prop_assert_eq!(part_boxes, fresh_part_boxes);
        prop_assert_eq!(
            cull_entries_without_place(&cull_entries),
            cull_entries_without_place(&fresh_cull_entries)
        );
        prop_assert_eq!(materials, fresh_materials);
        for slot in 0..synced.matrices.len() {
            if tree.has_instances(slot as u32) {
                let range = slot * MATRIX_BYTES..(slot + 1) * MATRIX_BYTES;
                prop_assert_eq!(&matrices[range.clone()], &fresh_matrices[range], "GPU matrix slot {}", slot);
            }
        }
        drop(scene);
        drop(fresh);
        assert_no_validation_errors(&device);
    }
}

/// Views of one tree sharing its GPU scene ([`SharedScenes`]) draw what views with scenes of
/// their own draw, through edits of every kind, whichever view draws first after an edit and
/// when a view skips frames (it catches up with every change it missed); views whose
/// techniques keep world matrices in the same place share one scene.
#[test]
fn views_sharing_a_gpu_scene_draw_what_views_of_their_own_draw() {
    let device = test_device();
    let mut graph = SceneGraph::new();
    let root = graph.root();
    let shape = cube(&mut graph);
    let cubes: Vec<(NodeHandle, NodeHandle)> = (0..24)
        .map(|i| {
            let at = DVec3::new(
                f64::from(i % 6) * 1.5 - 3.75,
                f64::from(i / 6) * 1.5 - 2.25,
                0.0,
            );
            place(&mut graph, root, &format!("cube {i}"), at, shape)
        })
        .collect();
    let mut tree = SceneTree::build(&mut graph);
    // Built-in, uniforms updated from the changed slots and CPU frustum culling (the second
    // camera sees only part of the scene), and a GPU culler.
    let combinations = [
        Combination::built_in(),
        Combination {
            parameters: "ubo-dynamic".into(),
            submission: "individual".into(),
            culling: "frustum".into(),
            ..Combination::built_in()
        },
        scene_wide("individual-indirect-count", "gpu-frustum"),
    ];
    let cameras = [
        camera_at(DVec3::new(0.0, 0.0, 12.0), DVec3::ZERO),
        camera_at(DVec3::new(-2.0, 0.0, 8.0), DVec3::new(-2.0, 0.0, 0.0)),
        camera_at(DVec3::new(1.0, 0.0, 9.0), DVec3::new(1.0, 0.0, 0.0)),
    ];
    let mut scenes = SharedScenes::default();
    let mut shared: Vec<View> = combinations.iter().map(|c| view(&device, c)).collect();
    let mut own: Vec<View> = combinations.iter().map(|c| view(&device, c)).collect();
    shared[0].renderer_mut().set_frames_in_flight(2).unwrap();
    own[0].renderer_mut().set_frames_in_flight(2).unwrap();
    let red = graph
        .create_material(Material {
            base_color: [0.8, 0.1, 0.1, 1.0],
            ..Material::default()
        })
        .unwrap();
    for step in 0..10u32 {
        match step {
            1 | 7 => graph
                .set_matrix(
                    cubes[3].0,
                    DMat4::from_translation(DVec3::new(-3.0, f64::from(step) * 0.3, 1.0)),
                )
                .unwrap(),
            2 => graph
                .set_flags(
                    cubes[5].0,
                    NodeFlags {
                        visible: false,
                        ..NodeFlags::default()
                    },
                )
                .unwrap(),
            3 => graph
                .set_flags(
                    cubes[7].1,
                    NodeFlags {
                        highlighted: true,
                        ..NodeFlags::default()
                    },
                )
                .unwrap(),
            4 => graph.set_part_material(cubes[8].1, 0, red).unwrap(),
            5 => {
                place(&mut graph, root, "new", DVec3::new(-3.0, -1.0, 1.0), shape);
            }
            6 => graph.destroy_node(cubes[0].0).unwrap(),
            8 => graph
                .set_material(
                    shape.1,
                    Material {
                        base_color: [0.2, 0.6, 0.3, 1.0],
                        ..Material::default()
                    },
                )
                .unwrap(),
            _ => {}
        }
        tree.update(&mut graph);
        // A different view draws first after each edit; on odd steps the last one skips.
        let count = shared.len();
        for k in 0..count {
            let i = (k + step as usize) % count;
            if step % 2 == 1 && i == count - 1 {
                continue;
            }
            let mut view = &mut shared[i];
            view.sync_shared(&graph, &mut tree, &mut scenes).unwrap();
            let drawn = view.draw(&cameras[i]).unwrap();
            let image = view.renderer().read_rgba8().unwrap();
            view = &mut own[i];
            let expected = view.render(&graph, &mut tree, &cameras[i]).unwrap();
            let expected_image = view.renderer().read_rgba8().unwrap();
            assert!(
                image == expected_image,
                "step {step}, view {i} ({}): the shared scene draws another picture",
                combinations[i]
            );
            assert_eq!(
                (drawn.draws, drawn.triangles),
                (expected.draws, expected.triangles),
                "step {step}, view {i}"
            );
            assert_eq!(shared[i].drawn_triangles(), own[i].drawn_triangles());
        }
    }
    let on_host = shared
        .iter()
        .filter(|view| view.techniques().transforms() == Transforms::Host)
        .count();
    let places = usize::from(on_host > 0) + usize::from(on_host < shared.len());
    assert_eq!(scenes.len(), places, "one scene per place of matrices");
    // The sharing views hold one scene per place of matrices, the others one each.
    let scene_bytes = shared
        .iter()
        .map(|view| view.scene().unwrap().resident_bytes())
        .min()
        .unwrap();
    // Renderers of one size share one depth, which the last of them frees: a renderer that
    // outlives both groups keeps it out of the comparison.
    let holds_the_depth = cadr_core::frame::Renderer::new(&device, SIZE.0, SIZE.1).unwrap();
    let with_all = device.memory_usage().allocated_bytes;
    drop(own);
    let with_shared = device.memory_usage().allocated_bytes;
    drop(shared);
    assert!(scenes.is_empty(), "the scenes go with the last view");
    let with_none = device.memory_usage().allocated_bytes;
    drop(holds_the_depth);
    let (own_bytes, shared_bytes) = (with_all - with_shared, with_shared - with_none);
    assert!(
        own_bytes >= shared_bytes + (3 - places as u64) * scene_bytes * 9 / 10,
        "views of their own {own_bytes} bytes, sharing views {shared_bytes}, a scene {scene_bytes}"
    );
    assert_no_validation_errors(&device);
}

#[test]
fn views_on_two_threads_share_one_device_and_its_queue() {
    // The device guards its queue: two views rendering at once on two threads never submit
    // together (the validation layer's thread-safety checks would report it) and both draw the
    // same picture.
    let device = test_device();
    let registry = plugin_registry(&device);
    let source = generate(&GeneratorSpec::Demo);
    let bounds = flatten(&source).unwrap().bounds;
    let camera = Camera::fit(
        &bounds,
        f64::from(SIZE.0) / f64::from(SIZE.1),
        DEFAULT_DIRECTION,
    );
    let combinations = [
        Combination::built_in(),
        scene_wide("individual-mdi", "none"),
    ];
    let images: Vec<image::RgbaImage> = std::thread::scope(|scope| {
        let workers: Vec<_> = combinations
            .iter()
            .map(|combination| {
                let (device, registry, source) = (&device, &registry, &source);
                scope.spawn(move || {
                    let (mut graph, _) = SceneGraph::from_scene(source).unwrap();
                    let mut tree = SceneTree::build(&mut graph);
                    let mut view = View::new(device, Arc::clone(registry), SIZE.0, SIZE.1).unwrap();
                    view.techniques_mut().select(combination).unwrap();
                    for _ in 0..50 {
                        view.render(&graph, &mut tree, &camera).unwrap();
                    }
                    view.renderer().read_rgba8().unwrap()
                })
            })
            .collect();
        workers.into_iter().map(|w| w.join().unwrap()).collect()
    });
    let difference = cadr_tests::images::compare(&images[0], &images[1]).unwrap();
    assert!(
        difference.within(cadr_tests::images::SAME_PICTURE),
        "{difference:?}"
    );
    assert_no_validation_errors(&device);
}

/// A CAD tool's day: a file loaded into a scene already drawn, unloaded, loaded again. The
/// file's parts draw after the first frame; the first load lays the arenas out again with room
/// to spare, and from then on a load takes the rooms the last unload freed: it uploads only
/// its own geometry and the arenas keep their size.
#[test]
fn files_loaded_after_the_first_frame_draw_and_reuse_the_room_of_those_unloaded() {
    let device = test_device();
    let base = generate(&GeneratorSpec::parse("grid:parts=200").unwrap());
    let file = generate(&GeneratorSpec::Demo);
    let (mut graph, _) = SceneGraph::from_scene(&base).unwrap();
    let mut tree = SceneTree::build(&mut graph);
    let mut view = view(&device, &Combination::built_in());
    let camera = camera_at(DVec3::new(0.0, 0.0, 50.0), DVec3::ZERO);
    let alone = view.render(&graph, &mut tree, &camera).unwrap();
    let view_triangles = view.drawn_triangles();
    let base_bytes = view.scene().unwrap().resident_bytes();
    let file_triangles =
        cadr_core::scene::SceneStats::new(&file, &flatten(&file).unwrap()).triangles;
    let mut sizes = Vec::new();
    for round in 0..3 {
        let root = graph.root();
        let imported = graph.import(&file, root).unwrap();
        tree.update(&mut graph);
        let drawn = view.render(&graph, &mut tree, &camera).unwrap();
        assert_eq!(
            view.drawn_triangles(),
            view_triangles + file_triangles,
            "round {round}: every triangle of the file is drawn besides the scene's"
        );
        assert!(drawn.triangles > alone.triangles, "round {round}");
        let (upload, resident) = {
            let scene = view.scene().unwrap();
            (scene.last_upload(), scene.resident_bytes())
        };
        sizes.push(resident);
        if round > 0 {
            assert!(
                upload.geometry_bytes < 2 * (sizes[0] - base_bytes),
                "round {round}: {} bytes of geometry uploaded, the arenas were laid out again",
                upload.geometry_bytes
            );
        }
        // Unload: the nodes, then the geometries and materials they used.
        for &node in imported.nodes.iter().rev() {
            graph.destroy_node(node).unwrap();
        }
        for &geometry in &imported.geometries {
            graph.destroy_geometry(geometry).unwrap();
        }
        for &material in &imported.materials {
            graph.destroy_material(material).unwrap();
        }
        tree.update(&mut graph);
        let after = view.render(&graph, &mut tree, &camera).unwrap();
        assert_eq!(after.triangles, alone.triangles, "round {round}: unloaded");
    }
    assert!(sizes[0] > base_bytes, "the first load grew the arenas");
    assert_eq!(
        sizes[1], sizes[0],
        "the second load fits the room the first left"
    );
    assert_eq!(sizes[2], sizes[0], "and so does the third");
    drop(view);
    assert_no_validation_errors(&device);
}

/// A material that cuts texels out (MASK with a texture) flags its parts `CADR_INSTANCE_CUTOUT`,
/// which keeps their back faces drawn (the holes may show the inside): set when the material
/// becomes one, cleared when it stops being one, without a rebuild.
#[test]
fn parts_of_a_cutout_material_are_flagged_and_unflagged_as_the_material_changes() {
    use cadr_core::scene::{AlphaMode, Texture, TextureRef, UvTransform};
    let device = test_device();
    let scene = generate(&GeneratorSpec::Demo);
    let (mut graph, _) = SceneGraph::from_scene(&scene).unwrap();
    let mut tree = SceneTree::build(&mut graph);
    let mut gpu = GpuScene::new(&device, &graph, &mut tree, Transforms::Gpu).unwrap();
    let cutouts = |gpu: &GpuScene| {
        let instances = gpu.content().instances;
        let flagged = instances
            .iter()
            .filter(|e| e.flags & cadr_plugin_abi::CADR_INSTANCE_CUTOUT != 0)
            .map(|e| e.material)
            .collect::<Vec<_>>();
        (flagged, instances.len())
    };
    assert!(cutouts(&gpu).0.is_empty(), "no cutout material yet");

    let texture = graph
        .create_texture(Texture {
            name: "holes".into(),
            width: 2,
            height: 2,
            texels: Arc::new([255u8, 255, 255, 255, 255, 255, 255, 0].repeat(2)),
            sampler: Default::default(),
        })
        .unwrap();
    let handle = graph.material_handle_at(0).unwrap();
    let plain = graph.material(handle).unwrap().clone();
    let mut cut_out = plain.clone();
    cut_out.alpha_mode = AlphaMode::Mask { cutoff: 0.5 };
    cut_out.base_color_texture = Some(TextureRef {
        texture: texture.index(),
        transform: UvTransform::IDENTITY,
    });
    graph.set_material(handle, cut_out).unwrap();
    tree.update(&mut graph);
    gpu.sync(&graph, &mut tree, Transforms::Gpu).unwrap();
    let (flagged, instances) = cutouts(&gpu);
    assert!(!flagged.is_empty(), "the parts of material 0 are flagged");
    assert!(flagged.iter().all(|&m| m == 0), "only material 0's parts");
    assert!(flagged.len() < instances);

    graph.set_material(handle, plain).unwrap();
    tree.update(&mut graph);
    gpu.sync(&graph, &mut tree, Transforms::Gpu).unwrap();
    assert!(
        cutouts(&gpu).0.is_empty(),
        "unflagged with the plain material"
    );
    drop(gpu);
    assert_no_validation_errors(&device);
}
