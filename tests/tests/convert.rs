//! Converting between glTF and CSF keeps what cadr draws, and says what it drops.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::path::Path;

use cadr_core::csf::scene_from_csf;
use cadr_core::generate::{generate, GeneratorSpec};
use cadr_core::load::load_file;
use cadr_core::save::save_scene;
use cadr_tests::fixtures::{rich_csf_file, scratch_dir};
use cadr_tests::images::{assert_matches_reference, DEFAULT_TOLERANCE};
use cadr_tests::{assert_same_drawing, render_scene, CYLINDER_ENGINE_GLB};

#[test]
fn generated_scenes_survive_every_format() {
    let dir = scratch_dir("convert_formats");
    let scene = generate(&GeneratorSpec::Demo);
    for name in ["demo.glb", "demo.gltf", "demo.csf", "demo.csf.gz"] {
        let path = dir.join(name);
        let notes = save_scene(&scene, &path).unwrap();
        let back = load_file(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_same_drawing(&scene, &back);
        assert_eq!(
            back.geometries.len(),
            scene.geometries.len(),
            "{name}: geometries stay shared"
        );
        if name.ends_with(".glb") || name.ends_with(".gltf") {
            assert!(
                notes.iter().any(|n| n.contains("edges")),
                "{name}: glTF drops the edges: {notes:?}"
            );
        } else {
            assert_eq!(
                back.geometries[1].wire_indices, scene.geometries[1].wire_indices,
                "CSF keeps edges"
            );
            assert!(notes.is_empty(), "{name}: {notes:?}");
        }
    }
    assert!(
        dir.join("demo.bin").exists(),
        ".gltf writes its buffer beside it"
    );
}

#[test]
fn csf_only_features_convert_to_gltf_exactly() {
    let dir = scratch_dir("convert_rich");
    let scene = scene_from_csf(&rich_csf_file(), "rich").unwrap();
    let path = dir.join("rich.glb");
    save_scene(&scene, &path).unwrap();
    assert_same_drawing(&scene, &load_file(&path).unwrap());
}

#[test]
fn shared_subgraphs_unfold_with_a_note() {
    let dir = scratch_dir("convert_dag");
    let mut scene = generate(&GeneratorSpec::Demo);
    let module = scene.nodes[0].children[0];
    scene.nodes[0].children.push(module); // the first module is drawn twice
    for name in ["dag.glb", "dag.csf"] {
        let path = dir.join(name);
        let notes = save_scene(&scene, &path).unwrap();
        assert!(
            notes.iter().any(|n| n.contains("unfolded")),
            "{name}: {notes:?}"
        );
        assert_same_drawing(&scene, &load_file(&path).unwrap());
    }
}

#[test]
fn converted_engine_renders_like_the_original() {
    let dir = scratch_dir("convert_engine");
    let original = load_file(Path::new(CYLINDER_ENGINE_GLB)).unwrap();
    let csf = dir.join("engine.csf.gz");
    save_scene(&original, &csf).unwrap();
    let gltf = dir.join("engine.gltf");
    save_scene(&load_file(&csf).unwrap(), &gltf).unwrap();
    let back = load_file(&gltf).unwrap();
    assert_same_drawing(&original, &back);
    // The same reference image as the original file.
    assert_matches_reference(
        "cylinder_engine",
        &render_scene(&back, 320, 240),
        DEFAULT_TOLERANCE,
    );
}

#[test]
fn unknown_output_formats_are_refused() {
    let error = save_scene(&generate(&GeneratorSpec::Demo), Path::new("/tmp/out.obj")).unwrap_err();
    assert!(
        error.to_string().contains("unknown output format"),
        "{error}"
    );
    let error = save_scene(
        &generate(&GeneratorSpec::Demo),
        Path::new("/nonexistent/dir/x.glb"),
    )
    .unwrap_err();
    assert!(
        error.to_string().contains("/nonexistent/dir/x.glb"),
        "{error}"
    );
}

#[test]
fn csf_part_overrides_become_an_editable_graph_that_draws_the_same() {
    // Hidden parts and parts placed by a child's matrix survive the trip into the scene graph
    // (hidden parts, and a Transform + Geo node of their own) and back.
    let scene = scene_from_csf(&rich_csf_file(), "rich").unwrap();
    let (mut graph, _) = cadr_core::graph::SceneGraph::from_scene(&scene).unwrap();
    assert_same_drawing(&scene, &graph.to_scene().unwrap());
    let tree = cadr_core::tree::SceneTree::build(&mut graph);
    let visible = tree
        .instances()
        .filter(|&i| tree.instance(i).unwrap().visible)
        .count();
    assert_eq!(
        visible, 2,
        "the inactive part stays hidden, the placed part shows once"
    );
}
