//! Helpers shared by cadr's integration tests: a device with validation on, reference images
//! compared with a perceptual metric, and small glTF files to break on purpose.

pub mod back_face_cases;
pub mod c_programs;
pub mod fixtures;
pub mod images;

use std::sync::Arc;

use cadr_core::graph::SceneGraph;
use cadr_core::render::{Camera, DEFAULT_DIRECTION};
use cadr_core::scene::{flatten, Scene, SceneStats};
use cadr_core::technique::{feature_bits, Combination, PluginRegistry, TechniqueKind};
use cadr_core::tree::SceneTree;
use cadr_core::view::View;
use cadr_core::vk::{Device, DeviceOptions, InstanceOptions};

/// The first node of `nodes` that takes a matrix (a transform), with its matrix: a part of
/// the scene to move. Probe it before the tree is built, so that the probe is no edit.
pub fn first_transform(
    graph: &mut SceneGraph,
    nodes: &[cadr_core::graph::NodeHandle],
) -> Option<(cadr_core::graph::NodeHandle, glam::DMat4)> {
    nodes.iter().find_map(|&node| {
        let matrix = graph.node(node).ok()?.local_matrix();
        graph
            .set_matrix(node, matrix)
            .is_ok()
            .then_some((node, matrix))
    })
}

/// Up to `count` of `nodes` placed by a matrix other than the identity, with their matrices:
/// the parts of an assembly to move apart.
pub fn placed_nodes(
    graph: &SceneGraph,
    nodes: &[cadr_core::graph::NodeHandle],
    count: usize,
) -> Vec<(cadr_core::graph::NodeHandle, glam::DMat4)> {
    nodes
        .iter()
        .filter_map(|&node| {
            let matrix = graph.node(node).ok()?.local_matrix();
            (matrix != glam::DMat4::IDENTITY).then_some((node, matrix))
        })
        .take(count)
        .collect()
}

/// Moves the `moving` nodes (from [`placed_nodes`]) apart for frame `frame`: node `i` by
/// `step × frame × (i − 2.5)` along x and half that along y, from its original matrix.
pub fn move_apart(
    graph: &mut SceneGraph,
    moving: &[(cadr_core::graph::NodeHandle, glam::DMat4)],
    step: f64,
    frame: usize,
) {
    for (i, &(node, original)) in moving.iter().enumerate() {
        let apart = step * frame as f64 * (i as f64 - 2.5);
        let offset = glam::DMat4::from_translation(glam::DVec3::new(apart, apart * 0.5, 0.0));
        graph
            .set_matrix(node, offset * original)
            .expect("a placed node takes a matrix");
    }
}

/// One frame of `view` through `camera`: its picture, its counters and, where `pick`, the
/// (instance, part) pairs a pick of the whole view finds, sorted (else none: a pick between two
/// frames has the next one record afresh, so tests of replay pick after their last frame).
pub fn frame_with_picks(
    view: &mut View,
    (graph, tree): (&SceneGraph, &mut SceneTree),
    camera: &Camera,
    pick: bool,
) -> (
    image::RgbaImage,
    cadr_core::render::FrameStats,
    Vec<(u32, u32)>,
) {
    let stats = view.render(graph, tree, camera).expect("the frame renders");
    let image = view
        .renderer()
        .read_rgba8()
        .expect("the picture reads back");
    let mut picked: Vec<(u32, u32)> = if pick {
        let whole = cadr_core::render::pick::PixelRect {
            x: 0,
            y: 0,
            width: image.width(),
            height: image.height(),
        };
        let hits = view.pick(tree, camera, whole).expect("the view picks");
        hits.iter().map(|hit| (hit.instance, hit.part)).collect()
    } else {
        Vec::new()
    };
    picked.sort_unstable();
    (image, stats, picked)
}

/// A device with the validation layers on. Tests never skip: without Vulkan they fail here.
pub fn test_device() -> Arc<Device> {
    validated_device(false, false)
}

/// A device with the validation layers on that keeps textures as layers of one array image
/// even where the device has descriptor indexing (the path of devices without it).
pub fn test_device_with_texture_array_only() -> Arc<Device> {
    validated_device(false, true)
}

/// A device with the validation layers and their synchronization checks on (slower): for
/// the tests of paths with many barriers, such as transparency.
pub fn test_device_with_synchronization_checks() -> Arc<Device> {
    validated_device(true, false)
}

fn validated_device(synchronization_validation: bool, texture_array_only: bool) -> Arc<Device> {
    let options = DeviceOptions {
        instance: InstanceOptions {
            validation: true,
            synchronization_validation,
            ..InstanceOptions::default()
        },
        texture_array_only,
        ..DeviceOptions::default()
    };
    match Device::new(&options) {
        Ok(device) => device,
        Err(error) => {
            panic!("cannot create a Vulkan device with validation (run scripts/setup.sh): {error}")
        }
    }
}

/// SwiftShader's Vulkan driver manifest, which `scripts/setup.sh` installs into
/// `target/swiftshader` (`CADR_SWIFTSHADER_DIR` overrides); fails the test, saying so, where
/// it is missing. SwiftShader is the second Vulkan implementation of the tests: it keeps to
/// the specification where lavapipe is lenient, and it has descriptor indexing (the bindless
/// texture path), which lavapipe lacks.
pub fn swiftshader_manifest() -> std::path::PathBuf {
    let dir = std::env::var_os("CADR_SWIFTSHADER_DIR").map_or_else(
        || std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/swiftshader"),
        std::path::PathBuf::from,
    );
    let manifest = dir.join("vk_swiftshader_icd.json");
    assert!(
        manifest.is_file(),
        "SwiftShader is not installed at {}: run scripts/setup.sh",
        manifest.display()
    );
    manifest
}

/// Mesa 22.3's lavapipe manifest (Debian 12's own driver: Vulkan 1.3, no mesh shaders, no
/// descriptor indexing, no device-generated commands), which `scripts/setup.sh` unpacks into
/// `target/mesa-22.3` (`CADR_MESA22_DIR` overrides); fails the test, saying so, where it is
/// missing.
pub fn mesa22_manifest() -> std::path::PathBuf {
    let dir = std::env::var_os("CADR_MESA22_DIR").map_or_else(
        || std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/mesa-22.3"),
        std::path::PathBuf::from,
    );
    let manifest = dir.join("lvp_icd.json");
    assert!(
        manifest.is_file(),
        "Mesa 22.3's lavapipe is not unpacked at {}: run scripts/setup.sh",
        manifest.display()
    );
    manifest
}

/// A device with validation on the driver of `manifest`, which this process's Vulkan loader
/// is pointed at alone (`VK_ICD_FILENAMES`, set once before the first instance: a test binary
/// calling this must create no device on another driver; nextest runs each test in a process
/// of its own); `texture_array_only` as in [`DeviceOptions`]. The device's name must contain
/// `name`.
fn device_on_driver(
    manifest: &std::path::Path,
    name: &str,
    texture_array_only: bool,
) -> Arc<Device> {
    static POINTED: std::sync::OnceLock<std::path::PathBuf> = std::sync::OnceLock::new();
    let pointed = POINTED.get_or_init(|| {
        std::env::set_var("VK_ICD_FILENAMES", manifest);
        manifest.to_path_buf()
    });
    assert_eq!(
        pointed, manifest,
        "this process already uses another Vulkan driver"
    );
    let options = DeviceOptions {
        instance: InstanceOptions {
            validation: true,
            ..InstanceOptions::default()
        },
        texture_array_only,
        ..DeviceOptions::default()
    };
    let device = Device::new(&options).unwrap_or_else(|e| panic!("{name} device: {e}"));
    assert!(
        device.adapter().name.contains(name),
        "the device is {}",
        device.adapter().name
    );
    device
}

/// A device with validation on SwiftShader's driver, which this process's Vulkan loader is
/// pointed at alone (`VK_ICD_FILENAMES`, set once before the first instance: a test binary
/// calling this must create no device on another driver); `texture_array_only` as in
/// [`DeviceOptions`].
pub fn swiftshader_device(texture_array_only: bool) -> Arc<Device> {
    device_on_driver(&swiftshader_manifest(), "SwiftShader", texture_array_only)
}

/// A device with validation on Mesa 22.3's lavapipe, which this process's Vulkan loader is
/// pointed at alone (as for [`swiftshader_device`]).
pub fn mesa22_device() -> Arc<Device> {
    device_on_driver(&mesa22_manifest(), "llvmpipe", false)
}

/// The directory of the running test binary, where cargo puts the plugin libraries it built.
pub fn test_binary_dir() -> std::path::PathBuf {
    let exe = std::env::current_exe().expect("the test binary's path");
    exe.parent()
        .expect("the test binary's directory")
        .to_path_buf()
}

/// The technique plugins cargo built next to the running test binary, for `device`; fails the
/// test if any library there is refused.
pub fn plugin_registry(device: &Device) -> Arc<PluginRegistry> {
    let registry =
        PluginRegistry::discover(&[test_binary_dir()], feature_bits(device.capabilities()));
    assert!(
        registry.refusals().is_empty(),
        "refused: {:?}",
        registry.refusals()
    );
    Arc::new(registry)
}

/// Fails the test if the validation layer reported any error on `device`.
pub fn assert_no_validation_errors(device: &Device) {
    let errors = device.validation_log().errors();
    assert!(
        errors.is_empty(),
        "{} Vulkan validation errors:\n{}",
        errors.len(),
        errors.join("\n")
    );
}

/// A scene in a view that has the plugin libraries, seen by one camera: for tests that draw it
/// several ways (display modes, MSAA, options) on one device.
pub struct SceneView {
    /// The device, validation on.
    pub device: Arc<Device>,
    /// The scene's graph.
    pub graph: SceneGraph,
    /// The handles of the scene's nodes, in the scene's order.
    pub nodes: Vec<cadr_core::graph::NodeHandle>,
    /// Its tree.
    pub tree: SceneTree,
    /// The view drawing it.
    pub view: View,
    /// The camera.
    pub camera: Camera,
}

impl SceneView {
    /// `scene` in a `width` × `height` view on `device`, seen by `camera`.
    pub fn new(
        device: Arc<Device>,
        scene: &Scene,
        (width, height): (u32, u32),
        camera: Camera,
    ) -> Self {
        let (mut graph, nodes) = SceneGraph::from_scene(scene).expect("build the scene graph");
        let tree = SceneTree::build(&mut graph);
        let view =
            View::new(&device, plugin_registry(&device), width, height).expect("create the view");
        Self {
            device,
            graph,
            nodes,
            tree,
            view,
            camera,
        }
    }

    /// `scene` in a `width` × `height` view on `device`, the camera fitted to its bounds.
    pub fn fitted(device: Arc<Device>, scene: &Scene, (width, height): (u32, u32)) -> Self {
        let bounds = flatten(scene).expect("flatten the scene").bounds;
        let camera = Camera::fit(
            &bounds,
            f64::from(width) / f64::from(height),
            DEFAULT_DIRECTION,
        );
        Self::new(device, scene, (width, height), camera)
    }

    /// Picks the pixel that the world point `point` projects to (the tree must be up to date
    /// with the graph): the hits there.
    pub fn pick_at(&mut self, point: glam::DVec3) -> Vec<cadr_core::view::PickHit> {
        let size = self.view.renderer().size();
        let (x, y) = images::pixel_of(&self.camera, size, point);
        self.view.sync(&self.graph, &mut self.tree).expect("sync");
        self.view
            .pick(
                &self.tree,
                &self.camera,
                cadr_core::render::pick::PixelRect::pixel(x, y),
            )
            .expect("pick")
    }

    /// The material name of the one part a click at `point` hits (the test fails unless it
    /// hits exactly one, a Geo node's).
    pub fn material_picked_at(&mut self, point: glam::DVec3) -> String {
        let hits = self.pick_at(point);
        assert_eq!(hits.len(), 1, "one hit at {point}");
        let node = self.graph.node(hits[0].node).expect("the hit node");
        let cadr_core::graph::NodeKind::Geo { part_materials, .. } = &node.kind else {
            panic!("a Geo node at {point}");
        };
        self.graph
            .material(part_materials[0])
            .expect("the hit part's material")
            .name
            .clone()
    }

    /// Drops the view (its objects destroyed, so that their validation messages are in) and
    /// fails the test if the validation layer reported an error on the device.
    pub fn assert_no_validation_errors(self) {
        let SceneView { device, view, .. } = self;
        drop(view);
        assert_no_validation_errors(&device);
    }

    /// The colour (RGB, 0 to 1) of `image`, drawn through this view's camera, where the world
    /// point `point` shows.
    pub fn color_at(&self, image: &image::RgbaImage, point: glam::DVec3) -> [f32; 3] {
        images::color_at(image, &self.camera, point)
    }

    /// The brightness (the largest of R, G and B, 0 to 1) of the darkest pixel of `image`
    /// among the 3 × 3 around where the world point `point` shows: whether a line of a pixel's
    /// width passes there, wherever the rasterizer put it.
    pub fn darkest_around(&self, image: &image::RgbaImage, point: glam::DVec3) -> f32 {
        let (x, y) = images::pixel_of(&self.camera, image.dimensions(), point);
        let mut darkest = f32::MAX;
        for (dx, dy) in (0..3).flat_map(|dx| (0..3).map(move |dy| (dx, dy))) {
            let p = image
                .get_pixel(
                    (x + dx).saturating_sub(1).min(image.width() - 1),
                    (y + dy).saturating_sub(1).min(image.height() - 1),
                )
                .0;
            darkest = darkest.min(f32::from(p[0].max(p[1]).max(p[2])) / 255.0);
        }
        darkest
    }

    /// Brings the tree up to the graph and draws two frames with the view's current settings:
    /// what the second drew (a steady frame; with a GPU culler, what the GPU drew).
    pub fn steady_draws(&mut self) -> u64 {
        self.tree.update(&mut self.graph);
        let mut draw = || {
            self.view
                .render(&self.graph, &mut self.tree, &self.camera)
                .expect("render a frame")
                .draws
        };
        draw();
        draw()
    }

    /// Brings the tree up to the graph, draws a frame with the view's current settings and
    /// reads it back.
    pub fn render(&mut self) -> image::RgbaImage {
        self.tree.update(&mut self.graph);
        self.view
            .render(&self.graph, &mut self.tree, &self.camera)
            .expect("render a frame");
        self.view
            .renderer()
            .read_rgba8()
            .expect("read the frame back")
    }
}

/// Renders `scene` with the built-in combination (no plugin library), the camera fitted to its
/// bounds, and returns the image; checks one draw per part and validation.
pub fn render_scene(scene: &Scene, width: u32, height: u32) -> image::RgbaImage {
    let device = test_device();
    let flat = flatten(scene).expect("flatten the scene");
    let (mut graph, _) = SceneGraph::from_scene(scene).expect("build the scene graph");
    let mut tree = SceneTree::build(&mut graph);
    let registry = PluginRegistry::built_in(feature_bits(device.capabilities()));
    let mut view = View::new(&device, Arc::new(registry), width, height).expect("create the view");
    let camera = Camera::fit(
        &flat.bounds,
        f64::from(width) / f64::from(height),
        DEFAULT_DIRECTION,
    );
    let stats = view
        .render(&graph, &mut tree, &camera)
        .expect("render a frame");
    assert_eq!(
        stats.draw_calls,
        flat.draws.len() as u64,
        "one draw per part"
    );
    let image = view.renderer().read_rgba8().expect("read the frame back");
    drop(view);
    assert_no_validation_errors(&device);
    image
}

/// The path of the Khronos "2CylinderEngine" sample shipped by Debian's assimp-testmodels.
pub const CYLINDER_ENGINE_GLB: &str =
    "/usr/share/assimp/models/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb";

/// Draw items and world matrices agree (to f32 precision, as CSF stores f32 matrices).
pub fn assert_same_drawing(a: &Scene, b: &Scene) {
    let (fa, fb) = (
        flatten(a).expect("flatten a"),
        flatten(b).expect("flatten b"),
    );
    assert_eq!(fa.draws.len(), fb.draws.len());
    for (da, db) in fa.draws.iter().zip(&fb.draws) {
        assert_eq!(
            (da.part, da.material, da.index_count),
            (db.part, db.material, db.index_count)
        );
        // Geometries may be numbered differently after a conversion: compare what they hold.
        let (ga, gb) = (
            &a.geometries[da.geometry as usize],
            &b.geometries[db.geometry as usize],
        );
        let part_indices = |g: &cadr_core::scene::Geometry, first: u32, count: u32| {
            g.indices[first as usize..(first + count) as usize]
                .iter()
                .map(|&i| g.vertices[i as usize].position)
                .collect::<Vec<_>>()
        };
        assert_eq!(
            part_indices(ga, da.first_index, da.index_count),
            part_indices(gb, db.first_index, db.index_count),
            "part {} of geometry '{}' holds other triangles",
            da.part,
            ga.name
        );

        let (wa, wb) = (
            fa.instances[da.instance as usize].world,
            fb.instances[db.instance as usize].world,
        );
        let scale = wa
            .to_cols_array()
            .iter()
            .fold(1.0_f64, |m, v| m.max(v.abs()));
        assert!(wa.abs_diff_eq(wb, 1e-5 * scale), "{wa:?} vs {wb:?}");
    }
    assert_eq!(
        SceneStats::new(a, &fa).triangles,
        SceneStats::new(b, &fb).triangles
    );
}

/// The combination that binds the whole scene once (`arena` / `ssbo-index`) with `submission`
/// and `culling`: what GPU cullers need of their partners.
pub fn scene_wide(submission: &str, culling: &str) -> Combination {
    Combination {
        vertex: "arena".into(),
        parameters: "ssbo-index".into(),
        submission: submission.into(),
        culling: culling.into(),
        ..Combination::built_in()
    }
}

/// The scene-wide combination with `culling` whose submission draws a GPU culler's commands on
/// `device`: by the count the GPU wrote (`individual-indirect-count`), or by their capacity
/// (`individual-mdi`) where the device lacks `drawIndirectCount`, as SwiftShader does.
pub fn gpu_culled(device: &Device, culling: &str) -> Combination {
    let submission = if device.capabilities().draw_indirect_count {
        "individual-indirect-count"
    } else {
        "individual-mdi"
    };
    scene_wide(submission, culling)
}

/// Every combination of the registry's techniques, valid or not, kind by kind in registry order.
pub fn all_combinations(registry: &PluginRegistry) -> Vec<Combination> {
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
                        ..Combination::built_in()
                    });
                }
            }
        }
    }
    all
}
