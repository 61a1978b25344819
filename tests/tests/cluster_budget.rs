//! gpu-clusters under a small cluster command budget (`CADR_CLUSTER_COMMAND_BUDGET`, in a test
//! binary of its own, as it sets the process's environment): parts whose cut does not fit are
//! drawn at their coarsest, so none is left out, and the picture stays close.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::sync::Arc;

use cadr_core::generate::{generate, GeneratorSpec};
use cadr_core::graph::SceneGraph;
use cadr_core::render::{Camera, DEFAULT_DIRECTION};
use cadr_core::scene::flatten;
use cadr_core::tree::SceneTree;
use cadr_core::view::View;
use cadr_tests::images::{compare, covered_fraction};
use cadr_tests::{assert_no_validation_errors, gpu_culled, plugin_registry, test_device};

#[test]
fn past_the_budget_parts_are_drawn_at_their_coarsest_and_none_is_left_out() {
    let scene = generate(&GeneratorSpec::Fine {
        units: 2,
        detail: 2,
        unique: false,
    });
    let flat = flatten(&scene).unwrap();
    let parts = flat.instances.len() as u64;
    let camera = Camera::fit(&flat.bounds, 4.0 / 3.0, DEFAULT_DIRECTION);
    let render = |budget: Option<&str>| {
        // SAFETY of the environment: this test binary runs no other test.
        match budget {
            Some(value) => std::env::set_var("CADR_CLUSTER_COMMAND_BUDGET", value),
            None => std::env::remove_var("CADR_CLUSTER_COMMAND_BUDGET"),
        }
        let device = test_device();
        let (mut graph, _) = SceneGraph::from_scene(&scene).unwrap();
        let mut tree = SceneTree::build(&mut graph);
        let mut view = View::new(&device, Arc::clone(&plugin_registry(&device)), 240, 180).unwrap();
        let combination = gpu_culled(&device, "gpu-clusters");
        view.techniques_mut().select(&combination).unwrap();
        view.techniques_mut().set_lod_error(0.0).unwrap();
        let mut stats = None;
        for _ in 0..3 {
            stats = Some(view.render(&graph, &mut tree, &camera).unwrap());
        }
        let image = view.renderer().read_rgba8().unwrap();
        drop(view);
        assert_no_validation_errors(&device);
        (image, stats.unwrap())
    };
    let (full, full_stats) = render(None);
    let (budgeted, budgeted_stats) = render(Some("64"));
    let difference = compare(&budgeted, &full).unwrap();
    println!(
        "full detail: {} triangles, {} clusters; budget 64: {} triangles, {} clusters, {difference:?}",
        full_stats.triangles, full_stats.draws, budgeted_stats.triangles, budgeted_stats.draws
    );
    assert!(budgeted_stats.triangles < full_stats.triangles);
    assert!(
        budgeted_stats.draws >= parts,
        "every part keeps clusters: {} for {parts} parts",
        budgeted_stats.draws
    );
    let (covered_full, covered) = (covered_fraction(&full), covered_fraction(&budgeted));
    assert!(
        (covered - covered_full).abs() < 0.01,
        "no part goes missing: {covered} of the picture covered against {covered_full}"
    );
    assert!(difference.mean < 0.05, "{difference:?}");
}
