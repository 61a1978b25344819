//! Criterion benchmarks of the scene tree: a full build, and the incremental update after
//! moving one part and 1% of the parts of the seeds' Graphicscard statistics. `cadr bench-tree`
//! prints the same as a table with ratios measured in one run.

use std::hint::black_box;

use cadr_core::generate::{generate, GeneratorSpec};
use cadr_core::graph::{NodeHandle, NodeKind, SceneGraph};
use cadr_core::tree::SceneTree;
use criterion::{criterion_group, criterion_main, Criterion};
use glam::{DMat4, DVec3};

fn graphicscard() -> SceneGraph {
    SceneGraph::from_scene(&generate(&GeneratorSpec::GraphicsCard))
        .expect("generated scenes convert")
        .0
}

fn placements(graph: &SceneGraph) -> Vec<NodeHandle> {
    graph
        .nodes()
        .filter(|(_, n)| matches!(n.kind, NodeKind::Transform { .. }))
        .map(|(h, _)| h)
        .collect()
}

fn build(c: &mut Criterion) {
    let mut graph = graphicscard();
    c.bench_function("tree build, graphicscard", |b| {
        b.iter(|| black_box(SceneTree::build(&mut graph)))
    });
}

fn update(c: &mut Criterion) {
    let mut graph = graphicscard();
    let mut tree = SceneTree::build(&mut graph);
    let all = placements(&graph);
    for (name, count) in [
        ("tree update, 1 transform", 1),
        ("tree update, 1% of transforms", all.len() / 100),
    ] {
        let sample: Vec<NodeHandle> = all
            .iter()
            .step_by((all.len() / count).max(1))
            .take(count)
            .copied()
            .collect();
        let mut lift = 0.0;
        c.bench_function(name, |b| {
            b.iter(|| {
                lift += 0.001;
                for &h in &sample {
                    let _ =
                        graph.set_matrix(h, DMat4::from_translation(DVec3::new(0.0, lift, 0.0)));
                }
                tree.update(&mut graph);
                black_box(tree.take_changes())
            })
        });
    }
}

criterion_group!(benches, build, update);
criterion_main!(benches);
