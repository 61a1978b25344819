//! The Rust API from several threads at once, as the C API uses it (and as
//! `tests/c/threads.c` does through the C API): two views on two threads draw and pick one
//! scene, shared behind a lock as the C API's scene object shares it, while a third thread
//! edits that scene and a fourth loads files and imports and removes them. Nothing may fail,
//! race on the queue (the validation layer's thread-safety checks would say), or leave the two
//! views disagreeing once the edits stop.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::sync::Mutex;

use cadr_core::generate::{generate, GeneratorSpec};
use cadr_core::graph::SceneGraph;
use cadr_core::load::load_file;
use cadr_core::render::pick::PixelRect;
use cadr_core::render::{Camera, DEFAULT_DIRECTION};
use cadr_core::scene::flatten;
use cadr_core::technique::Combination;
use cadr_core::tree::SceneTree;
use cadr_core::view::View;
use cadr_tests::images::{compare, SAME_PICTURE};
use cadr_tests::{
    assert_no_validation_errors, first_transform, plugin_registry, scene_wide, test_device,
    CYLINDER_ENGINE_GLB,
};

const SIZE: (u32, u32) = (128, 96);

#[test]
fn views_edits_and_loads_on_four_threads_at_once() {
    let device = test_device();
    let source = generate(&GeneratorSpec::Demo);
    let bounds = flatten(&source).unwrap().bounds;
    let camera = Camera::fit(
        &bounds,
        f64::from(SIZE.0) / f64::from(SIZE.1),
        DEFAULT_DIRECTION,
    );
    let (mut graph, nodes) = SceneGraph::from_scene(&source).unwrap();
    let tree = SceneTree::build(&mut graph);
    let moved = first_transform(&mut graph, &nodes).unwrap();
    let hidden = nodes[nodes.len() / 2];
    let scene = Mutex::new((graph, tree));
    let combinations = [
        Combination::built_in(),
        scene_wide("individual-indirect-count", "gpu-frustum"),
    ];
    // The drawing threads wait here, once the edits and loads are over, to draw the last frame.
    let edits_over = std::sync::Barrier::new(3);
    let images: Vec<image::RgbaImage> = std::thread::scope(|scope| {
        let drawing: Vec<_> = combinations
            .iter()
            .map(|combination| {
                let (device, scene, camera, edits_over) = (&device, &scene, &camera, &edits_over);
                scope.spawn(move || {
                    let mut view =
                        View::new(device, plugin_registry(device), SIZE.0, SIZE.1).unwrap();
                    view.techniques_mut().select(combination).unwrap();
                    for frame in 0..30 {
                        let mut guard = scene.lock().unwrap();
                        let (graph, tree) = &mut *guard;
                        tree.update(graph);
                        view.render(graph, tree, camera).unwrap();
                        if frame % 5 == 0 {
                            let centre = PixelRect::pixel(SIZE.0 / 2, SIZE.1 / 2);
                            view.sync(graph, tree).unwrap();
                            view.pick(tree, camera, centre).unwrap();
                        }
                    }
                    edits_over.wait();
                    let mut guard = scene.lock().unwrap();
                    let (graph, tree) = &mut *guard;
                    tree.update(graph);
                    view.render(graph, tree, camera).unwrap();
                    view.renderer().read_rgba8().unwrap()
                })
            })
            .collect();
        let editing = scope.spawn(|| {
            let (node, matrix) = moved;
            for step in 0..60 {
                let mut guard = scene.lock().unwrap();
                let (graph, _) = &mut *guard;
                let offset = glam::DMat4::from_translation(glam::DVec3::X * f64::from(step % 7));
                graph.set_matrix(node, offset * matrix).unwrap();
                let mut flags = graph.node(hidden).unwrap().flags;
                flags.visible = step % 2 == 0;
                graph.set_flags(hidden, flags).unwrap();
                drop(guard);
                std::thread::yield_now();
            }
            // Leave the scene as it started.
            let mut guard = scene.lock().unwrap();
            let (graph, _) = &mut *guard;
            graph.set_matrix(node, matrix).unwrap();
            let mut flags = graph.node(hidden).unwrap().flags;
            flags.visible = true;
            graph.set_flags(hidden, flags).unwrap();
        });
        let loading = scope.spawn(|| {
            for _ in 0..4 {
                let engine = load_file(std::path::Path::new(CYLINDER_ENGINE_GLB)).unwrap();
                let mut guard = scene.lock().unwrap();
                let (graph, _) = &mut *guard;
                let root = graph.root();
                let added = graph.import(&engine, root).unwrap();
                drop(guard);
                std::thread::yield_now();
                let mut guard = scene.lock().unwrap();
                let (graph, _) = &mut *guard;
                graph.destroy_node(added.root).unwrap();
            }
        });
        editing.join().unwrap();
        loading.join().unwrap();
        edits_over.wait();
        drawing.into_iter().map(|w| w.join().unwrap()).collect()
    });
    // Both views drew the scene as the edits left it.
    let difference = compare(&images[0], &images[1]).unwrap();
    assert!(difference.within(SAME_PICTURE), "{difference:?}");
    assert_no_validation_errors(&device);
}
