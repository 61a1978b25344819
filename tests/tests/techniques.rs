//! Technique plugins: every valid combination renders what the built-in combination (the
//! baseline, itself checked against reference images in `rendering.rs`) renders, invalid ones
//! are refused with a reason, and broken plugins are refused without taking the renderer down.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::path::Path;
use std::sync::Arc;

use cadr_core::frame::Renderer;
use cadr_core::generate::{generate, GeneratorSpec};
use cadr_core::gpu_scene::{GpuScene, Transforms, ViewState, ViewedScene};
use cadr_core::graph::SceneGraph;
use cadr_core::load::load_file;
use cadr_core::render::{Camera, DEFAULT_DIRECTION};
use cadr_core::scene::{flatten, Scene};
use cadr_core::technique::{
    feature_bits, Combination, PluginRegistry, ShadeMode, TechniqueKind, Techniques,
};
use cadr_core::tree::SceneTree;
use cadr_core::vk::Device;
use cadr_tests::images::{compare, SAME_PICTURE, VISIBLE_CHANGE};
use cadr_tests::{
    all_combinations, assert_no_validation_errors, plugin_registry, test_device,
    CYLINDER_ENGINE_GLB,
};

const SIZE: (u32, u32) = (160, 120);

struct Fixture {
    device: Arc<Device>,
    renderer: Renderer,
    graph: SceneGraph,
    tree: SceneTree,
    scene: GpuScene,
    own: ViewState,
    techniques: Techniques,
    camera: Camera,
    baseline: image::RgbaImage,
}

impl Fixture {
    fn new(source: &Scene) -> Self {
        Self::with_size(source, SIZE)
    }

    fn with_size(source: &Scene, size: (u32, u32)) -> Self {
        let device = test_device();
        let mut renderer = Renderer::new(&device, size.0, size.1).unwrap();
        let bounds = flatten(source).unwrap().bounds;
        let camera = Camera::fit(
            &bounds,
            f64::from(size.0) / f64::from(size.1),
            DEFAULT_DIRECTION,
        );
        let (mut graph, _) = SceneGraph::from_scene(source).unwrap();
        let mut tree = SceneTree::build(&mut graph);
        let mut scene = GpuScene::new(&device, &graph, &mut tree, Transforms::Host).unwrap();
        let mut techniques = Techniques::new(
            &device,
            plugin_registry(&device),
            renderer.pipelines().technique_set_layouts(),
        );
        techniques.select(&Combination::built_in()).unwrap();
        let mut own = ViewState::new();
        scene.catch_up(&mut own);
        let mut viewed = ViewedScene {
            scene: &mut scene,
            own: &mut own,
        };
        renderer
            .render_techniques(&mut viewed, &mut techniques, &camera)
            .unwrap();
        let baseline = renderer.read_rgba8().unwrap();
        Self {
            device,
            renderer,
            graph,
            tree,
            scene,
            own,
            techniques,
            camera,
            baseline,
        }
    }

    fn try_render(
        &mut self,
    ) -> Result<cadr_core::render::FrameStats, cadr_core::error::RenderError> {
        self.tree.update(&mut self.graph);
        self.scene
            .sync(&self.graph, &mut self.tree, Transforms::Host)
            .unwrap();
        self.scene.catch_up(&mut self.own);
        let mut viewed = ViewedScene {
            scene: &mut self.scene,
            own: &mut self.own,
        };
        self.renderer
            .render_techniques(&mut viewed, &mut self.techniques, &self.camera)
    }

    fn render(&mut self) -> (image::RgbaImage, cadr_core::render::FrameStats) {
        let stats = self.try_render().unwrap();
        (self.renderer.read_rgba8().unwrap(), stats)
    }

    fn assert_matches_baseline(&mut self, what: &str) {
        let (image, _) = self.render();
        let difference = compare(&image, &self.baseline).unwrap();
        assert!(difference.within(SAME_PICTURE), "{what}: {difference:?}");
    }
}

#[test]
fn the_built_in_combination_needs_no_library_and_draws_each_part_once() {
    let mut f = Fixture::new(&generate(&GeneratorSpec::Demo));
    let built_in = PluginRegistry::built_in(feature_bits(f.device.capabilities()));
    let names: Vec<(TechniqueKind, &str)> = built_in
        .techniques()
        .iter()
        .map(|t| (t.kind, t.name.as_str()))
        .collect();
    let combination = Combination::built_in();
    assert_eq!(
        names,
        TechniqueKind::ALL
            .iter()
            .map(|&kind| (kind, combination.get(kind)))
            .collect::<Vec<_>>()
    );
    assert!(built_in.techniques().iter().all(|t| t.is_built_in()));
    assert!(built_in.refusals().is_empty(), "{:?}", built_in.refusals());
    f.techniques = Techniques::new(
        &f.device,
        Arc::new(built_in),
        f.renderer.pipelines().technique_set_layouts(),
    );
    f.techniques.select(&combination).unwrap();
    let (image, stats) = f.render();
    assert_eq!(
        image, f.baseline,
        "the same techniques from the built-in registry"
    );
    let parts = flatten(&f.graph.to_scene().unwrap()).unwrap().draws.len() as u64;
    assert_eq!((stats.draw_calls, stats.draws), (parts, parts));
    assert!(stats.vertex_binds > 0 && stats.vertex_binds < parts);
    assert!(stats.parameter_updates >= parts, "pushed per draw");
    drop(f.techniques);
    assert_no_validation_errors(&f.device);
}

/// Every combination of the registry's techniques, in a stable order.
/// Renders every valid combination in both shade modes and compares it with the reference
/// (the baseline for solid; the simplest combination for edges, checked against the baseline
/// where no edges are drawn), clusters at full detail. Invalid combinations must be refused
/// with a reason.
fn every_combination_matches(source: &Scene, what: &str) {
    let mut f = Fixture::new(source);
    // The same picture at full detail: gpu-clusters' level of detail is judged in clusters.rs.
    f.techniques.set_lod_error(0.0).unwrap();
    // Highlight the geo node of every third instance, so that every combination must show
    // highlighted and plain parts side by side.
    let geo_nodes: Vec<_> = f
        .tree
        .instances()
        .step_by(3)
        .filter_map(|id| f.tree.path(f.tree.instance(id)?.tree_node).last().copied())
        .collect();
    for node in geo_nodes {
        let mut flags = f.graph.node(node).unwrap().flags;
        flags.highlighted = true;
        f.graph.set_flags(node, flags).unwrap();
    }
    let (highlighted, _) = f.render();
    let tint = compare(&highlighted, &f.baseline).unwrap();
    assert!(
        tint.mean > VISIBLE_CHANGE,
        "{what}: the highlight shows: {tint:?}"
    );
    f.baseline = highlighted;
    let combinations = all_combinations(f.techniques.registry());
    assert!(
        combinations.len() >= 5 * 4 * 18 * 2,
        "{} combinations",
        combinations.len()
    );
    let (mut rendered, mut refused) = (0, 0);
    let mut failures = Vec::new();
    for mode in ShadeMode::ALL {
        f.techniques.select(&Combination::built_in()).unwrap();
        f.techniques.set_shade_mode(mode).unwrap();
        let reference = match mode {
            ShadeMode::Solid => f.baseline.clone(),
            ShadeMode::Edges | ShadeMode::HiddenLine | ShadeMode::Wireframe | ShadeMode::XRay => {
                let (image, stats) = f.render();
                let lines = compare(&image, &f.baseline).unwrap();
                assert!(
                    lines.mean > VISIBLE_CHANGE,
                    "{what}: edges are drawn: {lines:?}"
                );
                assert!(stats.draw_calls > 0);
                image
            }
        };
        // Solid and edges: every combination; the line-only modes and X-ray share their passes'
        // kinds (triangles, edges) with those two, so every third combination is checked there.
        let stride = match mode {
            ShadeMode::Solid | ShadeMode::Edges => 1,
            ShadeMode::HiddenLine | ShadeMode::Wireframe | ShadeMode::XRay => 3,
        };
        for combination in combinations.iter().step_by(stride) {
            match f.techniques.check(combination) {
                Ok(()) => {
                    f.techniques.select(combination).unwrap();
                    let (image, stats) = f.render();
                    let difference = compare(&image, &reference).unwrap();
                    if !(difference.within(SAME_PICTURE)) || stats.draw_calls == 0 {
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

fn fixture_library(name: &str) -> std::path::PathBuf {
    cadr_tests::test_binary_dir().join(format!(
        "{}{name}{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    ))
}

#[test]
fn libraries_that_cannot_be_used_are_refused_with_the_reason() {
    let features = feature_bits(test_device().capabilities());
    let mut registry = PluginRegistry::default();
    registry.load(&fixture_library("cadr_fixture_future_abi"), features);
    registry.load(
        Path::new("/nonexistent/libcadr_plugin_missing.so"),
        features,
    );
    // A shared library that is not a plugin: the C API library.
    registry.load(&fixture_library("cadr"), features);
    let reasons: Vec<String> = registry
        .refusals()
        .iter()
        .map(ToString::to_string)
        .collect();
    assert_eq!(reasons.len(), 3, "{reasons:?}");
    let speaks = format!(
        "built for plugin ABI 2.0; this cadr speaks {}.{}",
        cadr_plugin_abi::CADR_PLUGIN_ABI_MAJOR,
        cadr_plugin_abi::CADR_PLUGIN_ABI_MINOR
    );
    assert!(reasons[0].contains(&speaks), "{}", reasons[0]);
    assert!(
        reasons[1].contains("libcadr_plugin_missing.so") && reasons[1].contains("cannot be opened"),
        "{}",
        reasons[1]
    );
    assert!(
        reasons[2].contains("is not a cadr plugin"),
        "{}",
        reasons[2]
    );
    assert!(registry.techniques().is_empty());
}

#[test]
fn failing_techniques_are_refused_and_the_renderer_keeps_working() {
    let mut f = Fixture::with_size(&generate(&GeneratorSpec::Demo), (96, 72));
    let mut registry = PluginRegistry::discover(
        &[cadr_tests::test_binary_dir()],
        feature_bits(f.device.capabilities()),
    );
    registry.load(
        &fixture_library("cadr_fixture_faulty"),
        feature_bits(f.device.capabilities()),
    );
    let registry = Arc::new(registry);
    let lacking = registry
        .find(TechniqueKind::Vertex, "needs-nv-generated-commands")
        .unwrap();
    assert_eq!(
        lacking.support,
        Err("the device lacks VK_NV_device_generated_commands".to_owned())
    );
    f.techniques = Techniques::new(
        &f.device,
        registry,
        f.renderer.pipelines().technique_set_layouts(),
    );
    f.techniques.select(&Combination::built_in()).unwrap();
    f.assert_matches_baseline("before");

    let error = f
        .techniques
        .swap(TechniqueKind::Vertex, "needs-nv-generated-commands")
        .unwrap_err()
        .to_string();
    assert!(
        error.contains(
            "vertex 'needs-nv-generated-commands' is not supported: the device lacks VK_NV_device_generated_commands"
        ),
        "{error}"
    );
    let error = f
        .techniques
        .swap(TechniqueKind::Vertex, "panics-on-create")
        .unwrap_err();
    assert!(
        matches!(error, cadr_core::error::RenderError::Technique { .. }),
        "a technique's failure is not a Vulkan error: {error:?}"
    );
    let error = error.to_string();
    assert!(
        error.contains("create panicked") && error.contains("this vertex path always panics"),
        "{error}"
    );
    let error = f
        .techniques
        .swap(TechniqueKind::Vertex, "no-such-path")
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("no vertex technique named 'no-such-path' (known: per-geometry, per-part"),
        "{error}"
    );
    assert_eq!(
        f.techniques.combination(),
        Combination::built_in(),
        "refusals keep the combination"
    );
    f.assert_matches_baseline("after refused swaps");

    f.techniques
        .swap(TechniqueKind::Culling, "panics-on-cull")
        .unwrap();
    let error = f.try_render().unwrap_err().to_string();
    assert!(
        error.contains("cull panicked") && error.contains("this culler always panics"),
        "{error}"
    );
    f.techniques.swap(TechniqueKind::Culling, "none").unwrap();
    f.assert_matches_baseline("after a panicking culler");

    f.techniques
        .swap(TechniqueKind::Parameters, "panics-in-bind")
        .unwrap();
    let error = f.try_render().unwrap_err().to_string();
    assert!(error.contains("bind calls panicked"), "{error}");
    f.techniques
        .swap(TechniqueKind::Parameters, "push")
        .unwrap();
    f.assert_matches_baseline("after a panicking parameter path");
    drop(f.techniques);
    assert_no_validation_errors(&f.device);
}

/// The demo, small, drawn by plugin techniques of every kind (pulling / ubo-dynamic /
/// groups-replay / frustum), from which the swap tests start; and that combination.
fn small_demo_with_plugins() -> (Fixture, Combination) {
    let mut f = Fixture::with_size(&generate(&GeneratorSpec::Demo), (64, 48));
    let start = Combination {
        vertex: "pulling".into(),
        parameters: "ubo-dynamic".into(),
        submission: "groups-replay".into(),
        culling: "frustum".into(),
        ..Combination::built_in()
    };
    f.techniques.select(&start).unwrap();
    (f, start)
}

#[test]
fn a_thousand_swaps_leak_nothing() {
    let (mut f, start) = small_demo_with_plugins();
    f.render();
    let before = f.techniques.plugin_allocations();
    assert!(
        before.object_allocations > 0,
        "plugins' Vulkan objects are counted: {before:?}"
    );
    assert!(
        before.buffers > 0,
        "plugins' buffers are counted: {before:?}"
    );
    // Each kind in turn goes to another technique and back, a frame after every swap.
    let others = [
        (TechniqueKind::Vertex, "arena"),
        (TechniqueKind::Parameters, "ssbo-index"),
        (TechniqueKind::Submission, "groups-multidraw"),
        (TechniqueKind::Culling, "none"),
        (TechniqueKind::Submission, "individual-threads"),
    ];
    for swap in 0..1000 {
        let (kind, other) = others[(swap / 2) % others.len()];
        let name = if swap % 2 == 0 {
            other
        } else {
            start.get(kind)
        };
        f.techniques.swap(kind, name).unwrap();
        if swap % 2 == 0 {
            f.techniques
                .set_shade_mode(if swap % 4 == 0 {
                    ShadeMode::Edges
                } else {
                    ShadeMode::Solid
                })
                .unwrap();
        }
        f.try_render().unwrap();
    }
    f.techniques.set_shade_mode(ShadeMode::Solid).unwrap();
    assert_eq!(f.techniques.combination(), start);
    f.assert_matches_baseline("after 1000 swaps");
    assert_eq!(
        f.techniques.plugin_allocations(),
        before,
        "plugin objects and buffers after 1000 swaps"
    );
    drop(f.techniques);
    assert_no_validation_errors(&f.device);
}

/// Pipelines follow the vertex path, the parameter path and the transparency method only:
/// swapping a submission or a culler, or going back to a display mode drawn before, builds
/// none; swapping a path drops them; at most 8 pass sets are kept (every mode at two MSAA
/// levels makes 10); and what is drawn stays right throughout.
#[test]
fn pipelines_are_kept_across_swaps_and_modes_that_do_not_change_them() {
    let (mut f, _) = small_demo_with_plugins();
    f.assert_matches_baseline("the first combination");
    assert_eq!(f.techniques.kept_pass_sets(), 1, "solid's pass set");
    f.techniques.set_shade_mode(ShadeMode::Edges).unwrap();
    let (edges, _) = f.render();
    assert_eq!(f.techniques.kept_pass_sets(), 2, "edges builds its own");
    f.techniques.set_shade_mode(ShadeMode::Solid).unwrap();
    f.assert_matches_baseline("back in solid");
    assert_eq!(f.techniques.kept_pass_sets(), 2, "solid's were kept");
    for (kind, name) in [
        (TechniqueKind::Culling, "none"),
        (TechniqueKind::Submission, "groups-multidraw"),
        (TechniqueKind::Submission, "individual-threads"),
    ] {
        f.techniques.swap(kind, name).unwrap();
        f.assert_matches_baseline(name);
        assert_eq!(
            f.techniques.kept_pass_sets(),
            2,
            "swapping to {name} keeps the pipelines"
        );
    }
    f.techniques.set_shade_mode(ShadeMode::Edges).unwrap();
    let (edges_again, _) = f.render();
    let difference = compare(&edges_again, &edges).unwrap();
    assert!(difference.within(SAME_PICTURE), "edges: {difference:?}");
    assert_eq!(f.techniques.kept_pass_sets(), 2);

    f.techniques.swap(TechniqueKind::Vertex, "arena").unwrap();
    assert_eq!(
        f.techniques.kept_pass_sets(),
        0,
        "a new vertex path drops them"
    );
    f.techniques.set_shade_mode(ShadeMode::Solid).unwrap();
    f.assert_matches_baseline("a new vertex path");
    assert_eq!(f.techniques.kept_pass_sets(), 1);

    for samples in [1, 4] {
        f.renderer.set_msaa(samples).unwrap();
        for mode in ShadeMode::ALL {
            f.techniques.set_shade_mode(mode).unwrap();
            f.try_render().unwrap();
            assert!(f.techniques.kept_pass_sets() <= 8, "{samples}x {mode:?}");
        }
    }
    assert_eq!(f.techniques.kept_pass_sets(), 8, "the bound");
    f.renderer.set_msaa(1).unwrap();
    f.techniques.set_shade_mode(ShadeMode::Solid).unwrap();
    f.assert_matches_baseline("solid again after the oldest went");
    drop(f.techniques);
    assert_no_validation_errors(&f.device);
}

#[test]
fn frustum_culling_draws_only_what_the_camera_sees() {
    let mut f = Fixture::with_size(&generate(&GeneratorSpec::Demo), SIZE);
    let combination = Combination {
        culling: "frustum".into(),
        ..Combination::built_in()
    };
    f.techniques.select(&combination).unwrap();
    let (_, all) = f.render();
    // Look at one corner of the scene from close by: most parts fall outside the frustum.
    let bounds = flatten(&f.graph.to_scene().unwrap()).unwrap().bounds;
    let corner = cadr_core::scene::Aabb {
        min: bounds.min,
        max: bounds.min + (bounds.max - bounds.min) * 0.25,
    };
    f.camera = Camera::fit(
        &corner,
        f64::from(SIZE.0) / f64::from(SIZE.1),
        DEFAULT_DIRECTION,
    );
    let (culled_image, culled) = f.render();
    assert!(
        culled.draws < all.draws / 2,
        "culled {} of {} draws",
        all.draws - culled.draws,
        all.draws
    );
    f.techniques.select(&Combination::built_in()).unwrap();
    let (baseline, _) = f.render();
    let difference = compare(&culled_image, &baseline).unwrap();
    assert!(
        difference.within(SAME_PICTURE),
        "culling removes only unseen parts: {difference:?}"
    );
    drop(f.techniques);
    assert_no_validation_errors(&f.device);
}

/// Builds `tests/c-plugin/{source}` against the plugin header in `include` as the plugin
/// library `name` in `dir` (strict C99, warnings as errors) and returns its path.
fn build_c_plugin(dir: &Path, name: &str, include: &Path, source: &str) -> std::path::PathBuf {
    build_c_plugin_defining(dir, name, include, source, &[])
}

/// [`build_c_plugin`] with the preprocessor symbols `defines` defined.
fn build_c_plugin_defining(
    dir: &Path,
    name: &str,
    include: &Path,
    source: &str,
    defines: &[&str],
) -> std::path::PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let library = dir.join(format!(
        "{}{name}{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    ));
    let output = std::process::Command::new("cc")
        .args([
            "-std=c99",
            "-Wall",
            "-Wextra",
            "-Wpedantic",
            "-Werror",
            "-shared",
            "-fPIC",
            "-I",
        ])
        .arg(include)
        .args(defines.iter().map(|symbol| format!("-D{symbol}")))
        .arg(root.join("tests/c-plugin").join(source))
        .arg("-o")
        .arg(&library)
        .output()
        .expect("cc is needed (build-essential)");
    assert!(
        output.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    library
}

/// The plugin ABI's compatibility matrix: a C technique built for this minor, for the oldest
/// (1.0, against the header as released) and for a newer one (one minor more, a longer
/// technique description, an extension this host does not know) loads and draws what the
/// baseline draws, and lets frames overlap when its minor has frame slots; built for the newer
/// minor and requiring that extension, it is refused, naming the extension.
#[test]
fn c_techniques_of_older_and_newer_abi_minors_plug_in_unless_they_require_the_unknown() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let (major, minor) = (
        cadr_plugin_abi::CADR_PLUGIN_ABI_MAJOR,
        cadr_plugin_abi::CADR_PLUGIN_ABI_MINOR,
    );
    const {
        assert!(
            cadr_plugin_abi::CADR_PLUGIN_ABI_MINOR > 0,
            "1.0 is an older minor"
        )
    };
    // Library name, header folder, preprocessor symbols, the ABI version it says it has.
    type Build<'a> = (&'a str, std::path::PathBuf, &'a [&'a str], (u32, u32));
    let builds: [Build; 3] = [
        ("cadr_fixture_c", root.join("include"), &[], (major, minor)),
        (
            "cadr_fixture_c_abi_1_0",
            root.join("tests/c-plugin/abi-1.0"),
            &[],
            (1, 0),
        ),
        (
            "cadr_fixture_c_newer_minor",
            root.join("include"),
            &["CADR_FIXTURE_NEWER_MINOR"],
            (major, minor + 1),
        ),
    ];
    let dir = cadr_tests::fixtures::scratch_dir("c-plugin");
    for (name, include, defines, version) in builds {
        let library =
            build_c_plugin_defining(&dir, name, &include, "cull_everything_visible.c", defines);
        let mut f = Fixture::with_size(&generate(&GeneratorSpec::Demo), (96, 72));
        let features = feature_bits(f.device.capabilities());
        let mut registry = PluginRegistry::discover(&[cadr_tests::test_binary_dir()], features);
        registry.load(&library, features);
        assert!(
            registry.refusals().is_empty(),
            "{name}: {:?}",
            registry.refusals()
        );
        let c_culler = registry
            .find(TechniqueKind::Culling, "c-candidates")
            .unwrap();
        assert_eq!(c_culler.description, "Written in C: draws every candidate.");
        assert_eq!(c_culler.abi_version, version, "{name}");
        f.techniques = Techniques::new(
            &f.device,
            Arc::new(registry),
            f.renderer.pipelines().technique_set_layouts(),
        );
        let combination = Combination {
            culling: "c-candidates".into(),
            ..Combination::built_in()
        };
        f.techniques.select(&combination).unwrap();
        f.assert_matches_baseline(name);
        // Frames overlap earlier ones only where every technique keeps frame slots: the
        // fixture announces it from 1.15 on; at 1.0 the same bit meant nothing.
        f.renderer.set_frames_in_flight(3).unwrap();
        let overlapped: Vec<bool> = (0..4).map(|_| f.try_render().unwrap().overlapped).collect();
        f.renderer.set_frames_in_flight(1).unwrap();
        let announces = version.1 >= 15;
        assert_eq!(
            overlapped,
            [false, announces, announces, announces],
            "{name}"
        );
        drop(f.techniques);
        assert_no_validation_errors(&f.device);
    }

    let library = build_c_plugin_defining(
        &dir,
        "cadr_fixture_c_requires_unknown",
        &root.join("include"),
        "cull_everything_visible.c",
        &["CADR_FIXTURE_NEWER_MINOR", "CADR_FIXTURE_REQUIRES_UNKNOWN"],
    );
    let features = feature_bits(test_device().capabilities());
    let mut registry = PluginRegistry::default();
    registry.load(&library, features);
    assert!(
        registry
            .find(TechniqueKind::Culling, "c-candidates")
            .is_none(),
        "a technique requiring an unknown extension is not offered"
    );
    let reasons: Vec<String> = registry
        .refusals()
        .iter()
        .map(ToString::to_string)
        .collect();
    assert_eq!(reasons.len(), 1, "{reasons:?}");
    assert!(
        reasons[0].contains("c-candidates")
            && reasons[0].contains("requires plugin ABI extension 0x7fff0001")
            && reasons[0].contains(&format!("plugin ABI {major}.{minor}")),
        "{reasons:?}"
    );
}

#[test]
fn a_secondary_buffer_submission_built_before_abi_1_8_is_refused_under_msaa() {
    // Its secondary command buffers would inherit one sample per pixel inside a pass of
    // four: the host refuses the frame, naming the technique, its ABI and the sample count,
    // and draws with it as before without MSAA.
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let dir = cadr_tests::fixtures::scratch_dir("c-secondary");
    let library = build_c_plugin(
        &dir,
        "cadr_fixture_c_secondary_abi_1_0",
        &root.join("tests/c-plugin/abi-1.0"),
        "secondary_submission.c",
    );
    let mut f = Fixture::with_size(&generate(&GeneratorSpec::Demo), (96, 72));
    let features = feature_bits(f.device.capabilities());
    let mut registry = PluginRegistry::built_in(features);
    registry.load(&library, features);
    assert!(registry.refusals().is_empty(), "{:?}", registry.refusals());
    let submission = registry
        .find(TechniqueKind::Submission, "c-secondary")
        .unwrap();
    assert_eq!(submission.abi_version, (1, 0));
    f.techniques = Techniques::new(
        &f.device,
        Arc::new(registry),
        f.renderer.pipelines().technique_set_layouts(),
    );
    f.techniques
        .select(&Combination {
            submission: "c-secondary".into(),
            ..Combination::built_in()
        })
        .unwrap();
    let one_sample = f.try_render().unwrap();
    assert_eq!(one_sample.draw_calls, 0, "the fixture records nothing");
    let samples = 4;
    assert!(
        f.device.sample_counts().contains(&samples),
        "lavapipe and every GPU offer 4 samples"
    );
    f.renderer.set_msaa(samples).unwrap();
    let refusal = f.try_render().unwrap_err().to_string();
    for expected in ["submission 'c-secondary'", "ABI 1.0", "MSAA (4x asked"] {
        assert!(refusal.contains(expected), "{expected:?} in {refusal}");
    }
    f.renderer.set_msaa(1).unwrap();
    f.try_render().unwrap();
    drop(f.techniques);
    assert_no_validation_errors(&f.device);
}
