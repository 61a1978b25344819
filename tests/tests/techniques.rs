//! Technique plugins: every valid combination renders what the baseline renders, invalid ones
//! are refused with a reason, and broken plugins are refused without taking the renderer down.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::path::Path;
use std::sync::Arc;

use cadr_core::generate::{generate, GeneratorSpec};
use cadr_core::graph::SceneGraph;
use cadr_core::load::load_file;
use cadr_core::render::{Camera, GpuScene, Renderer, DEFAULT_DIRECTION};
use cadr_core::scene::{flatten, Scene};
use cadr_core::technique::{
    feature_bits, Combination, PluginRegistry, ShadeMode, TechniqueKind, TechniqueScene, Techniques,
};
use cadr_core::tree::SceneTree;
use cadr_core::vk::Device;
use cadr_tests::images::compare;
use cadr_tests::{assert_no_validation_errors, test_device, CYLINDER_ENGINE_GLB};

const SIZE: (u32, u32) = (160, 120);

/// The plugins cargo built next to this test binary.
fn registry(device: &Device) -> Arc<PluginRegistry> {
    let dir = std::env::current_exe()
        .unwrap()
        .parent()
        .unwrap()
        .to_path_buf();
    let registry = PluginRegistry::discover(&[dir], feature_bits(device.capabilities()));
    assert!(
        registry.refusals().is_empty(),
        "refused: {:?}",
        registry.refusals()
    );
    Arc::new(registry)
}

struct Fixture {
    device: Arc<Device>,
    renderer: Renderer,
    graph: SceneGraph,
    tree: SceneTree,
    scene: TechniqueScene,
    techniques: Techniques,
    camera: Camera,
    baseline: image::RgbaImage,
}

impl Fixture {
    fn new(source: &Scene) -> Self {
        let device = test_device();
        let mut renderer = Renderer::new(&device, SIZE.0, SIZE.1).unwrap();
        let bounds = flatten(source).unwrap().bounds;
        let camera = Camera::fit(
            &bounds,
            f64::from(SIZE.0) / f64::from(SIZE.1),
            DEFAULT_DIRECTION,
        );
        let gpu_scene = GpuScene::upload(&device, source).unwrap();
        renderer.render(&gpu_scene, &camera).unwrap();
        let baseline = renderer.read_rgba8().unwrap();
        drop(gpu_scene);
        let (mut graph, _) = SceneGraph::from_scene(source).unwrap();
        let mut tree = SceneTree::build(&mut graph);
        let scene = TechniqueScene::new(&device, &graph, &mut tree).unwrap();
        let techniques = Techniques::new(
            &device,
            registry(&device),
            renderer.pipelines().frame_set_layout,
        );
        Self {
            device,
            renderer,
            graph,
            tree,
            scene,
            techniques,
            camera,
            baseline,
        }
    }

    fn render(&mut self) -> (image::RgbaImage, cadr_core::render::FrameStats) {
        self.tree.update(&mut self.graph);
        self.scene.sync(&self.graph, &mut self.tree).unwrap();
        let stats = self
            .renderer
            .render_techniques(&mut self.scene, &mut self.techniques, &self.camera)
            .unwrap();
        (self.renderer.read_rgba8().unwrap(), stats)
    }
}

#[test]
fn the_simplest_combination_matches_the_baseline() {
    let mut f = Fixture::new(&generate(&GeneratorSpec::Demo));
    f.techniques.select(&Combination::simplest()).unwrap();
    let (image, stats) = f.render();
    let difference = compare(&image, &f.baseline).unwrap();
    assert!(
        difference.mean < 0.3 && difference.p99 < 6.0,
        "{difference:?}"
    );
    assert!(stats.draw_calls > 0);
    assert_no_validation_errors(&f.device);
}

/// Every combination of the registry's techniques, in a stable order.
fn all_combinations(registry: &PluginRegistry) -> Vec<Combination> {
    let names = |kind| {
        registry
            .of_kind(kind)
            .map(|t| t.name.clone())
            .collect::<Vec<_>>()
    };
    let mut all = Vec::new();
    for vertex in names(TechniqueKind::Vertex) {
        for parameters in names(TechniqueKind::Parameters) {
            for submission in names(TechniqueKind::Submission) {
                for culling in names(TechniqueKind::Culling) {
                    all.push(Combination {
                        vertex: vertex.clone(),
                        parameters: parameters.clone(),
                        submission: submission.clone(),
                        culling,
                    });
                }
            }
        }
    }
    all
}

/// Renders every valid combination in both shade modes and compares it with the reference
/// (the baseline for solid; the simplest combination for edges, checked against the baseline
/// where no edges are drawn). Invalid combinations must be refused with a reason.
fn every_combination_matches(source: &Scene, what: &str) {
    let mut f = Fixture::new(source);
    let combinations = all_combinations(f.techniques.registry());
    assert!(
        combinations.len() >= 5 * 4 * 17 * 2,
        "{} combinations",
        combinations.len()
    );
    let (mut rendered, mut refused) = (0, 0);
    let mut failures = Vec::new();
    for mode in ShadeMode::ALL {
        f.techniques.select(&Combination::simplest()).unwrap();
        f.techniques.set_shade_mode(mode).unwrap();
        let reference = match mode {
            ShadeMode::Solid => f.baseline.clone(),
            ShadeMode::Edges => {
                let (image, stats) = f.render();
                let lines = compare(&image, &f.baseline).unwrap();
                assert!(lines.mean > 0.2, "{what}: edges are drawn: {lines:?}");
                assert!(stats.draw_calls > 0);
                image
            }
        };
        for combination in &combinations {
            match f.techniques.check(combination) {
                Ok(()) => {
                    f.techniques.select(combination).unwrap();
                    let (image, stats) = f.render();
                    let difference = compare(&image, &reference).unwrap();
                    if !(difference.mean < 0.3 && difference.p99 < 6.0) || stats.draw_calls == 0 {
                        failures.push(format!(
                            "{combination} [{}]: {difference:?}, {} draw calls",
                            mode.name(),
                            stats.draw_calls
                        ));
                    }
                    rendered += 1;
                }
                Err(reason) => {
                    let error = f.techniques.select(combination).unwrap_err().to_string();
                    assert!(error.contains(&reason), "{error} / {reason}");
                    assert!(
                        reason.contains("needs") || reason.contains("not supported"),
                        "{reason}"
                    );
                    refused += 1;
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{what}: {} of {rendered} differ:\n{}",
        failures.len(),
        failures.join("\n")
    );
    assert!(
        rendered > 0 && refused > 0,
        "{rendered} rendered, {refused} refused"
    );
    println!("{what}: {rendered} combinations rendered, {refused} refused");
    drop(f.techniques);
    assert_no_validation_errors(&f.device);
}

#[test]
fn every_valid_combination_renders_the_demo_like_the_baseline() {
    every_combination_matches(&generate(&GeneratorSpec::Demo), "gen:demo");
}

#[test]
fn every_valid_combination_renders_the_cylinder_engine_like_the_baseline() {
    let scene = load_file(Path::new(CYLINDER_ENGINE_GLB)).unwrap();
    every_combination_matches(&scene, "2CylinderEngine");
}
