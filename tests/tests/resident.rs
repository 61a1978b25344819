//! The GPU-resident scene follows the scene graph through the tree's changes: it renders what a
//! fresh baseline render of the same scene shows, and uploads only what changed.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use cadr_core::generate::{generate, GeneratorSpec};
use cadr_core::graph::{NodeFlags, NodeHandle, NodeKind, SceneGraph};
use cadr_core::render::{
    Camera, GpuScene, Renderer, ResidentScene, DEFAULT_DIRECTION, MATRIX_UPLOAD_BYTES,
};
use cadr_core::scene::{Material, Scene};
use cadr_core::tree::SceneTree;
use cadr_tests::images::{compare, ImageDifference};
use cadr_tests::{assert_no_validation_errors, test_device};
use glam::{DMat4, DVec3};

const SIZE: (u32, u32) = (200, 150);

struct Fixture {
    renderer: Renderer,
    graph: SceneGraph,
    tree: SceneTree,
    resident: ResidentScene,
    camera: Camera,
}

impl Fixture {
    fn new(scene: &Scene) -> Self {
        let device = test_device();
        let renderer = Renderer::new(&device, SIZE.0, SIZE.1).unwrap();
        let (mut graph, _) = SceneGraph::from_scene(scene).unwrap();
        let mut tree = SceneTree::build(&mut graph);
        let resident =
            ResidentScene::new(&device, renderer.pipelines(), &graph, &mut tree).unwrap();
        let bounds = cadr_core::scene::flatten(scene).unwrap().bounds;
        let camera = Camera::fit(
            &bounds,
            f64::from(SIZE.0) / f64::from(SIZE.1),
            DEFAULT_DIRECTION,
        );
        Self {
            renderer,
            graph,
            tree,
            resident,
            camera,
        }
    }

    /// Aims the camera at `bounds` (instead of the whole scene).
    fn look_at(&mut self, bounds: &cadr_core::scene::Aabb) {
        self.camera = Camera::fit(
            bounds,
            f64::from(SIZE.0) / f64::from(SIZE.1),
            DEFAULT_DIRECTION,
        );
    }

    fn render_resident(&mut self) -> image::RgbaImage {
        self.tree.update(&mut self.graph);
        self.resident.sync(&self.graph, &mut self.tree).unwrap();
        self.renderer
            .render_resident(&mut self.resident, &self.camera)
            .unwrap();
        self.renderer.read_rgba8().unwrap()
    }

    /// The baseline's image of the scene the graph describes now, loaded afresh.
    fn render_fresh_baseline(&mut self) -> image::RgbaImage {
        let scene = self.graph.to_scene();
        let gpu_scene = GpuScene::upload(self.renderer.device(), &scene).unwrap();
        self.renderer.render(&gpu_scene, &self.camera).unwrap();
        self.renderer.read_rgba8().unwrap()
    }

    /// Transform nodes whose only child is a Geo node: the objects' shapes.
    fn shape_transforms(&self) -> Vec<NodeHandle> {
        self.graph
            .nodes()
            .filter(|(_, n)| {
                matches!(n.kind, NodeKind::Transform { .. }) && n.children().len() == 1
            })
            .filter(|(_, n)| {
                matches!(
                    self.graph.node(n.children()[0].node).unwrap().kind,
                    NodeKind::Geo { .. }
                )
            })
            .map(|(h, _)| h)
            .collect()
    }
}

fn assert_close(difference: ImageDifference, what: &str) {
    assert!(
        difference.mean < 0.3 && difference.p99 < 6.0,
        "{what}: {difference:?}"
    );
}

#[test]
fn resident_rendering_matches_the_baseline_and_follows_edits() {
    let mut f = Fixture::new(&generate(&GeneratorSpec::Demo));
    let resident = f.render_resident();
    let baseline = f.render_fresh_baseline();
    assert_close(compare(&resident, &baseline).unwrap(), "before edits");

    let shapes = f.shape_transforms();
    for (i, &shape) in shapes.iter().enumerate().take(40) {
        let matrix = f.graph.node(shape).unwrap().local_matrix();
        f.graph
            .set_matrix(
                shape,
                DMat4::from_translation(DVec3::new(0.0, 0.4 + 0.05 * i as f64, 0.0)) * matrix,
            )
            .unwrap();
    }
    for &shape in shapes.iter().skip(40).take(10) {
        f.graph
            .set_flags(
                shape,
                NodeFlags {
                    visible: false,
                    ..NodeFlags::default()
                },
            )
            .unwrap();
    }
    let red = f
        .graph
        .create_material(Material {
            name: "red".into(),
            base_color: [0.9, 0.05, 0.05, 1.0],
            ..Material::default()
        })
        .unwrap();
    let geo = f.graph.node(shapes[60]).unwrap().children()[0].node;
    f.graph.set_part_material(geo, 0, red).unwrap();
    let module = f
        .graph
        .node(f.graph.node(f.graph.root()).unwrap().children()[0].node)
        .unwrap()
        .children()[1]
        .node;
    let root_child = f.graph.node(f.graph.root()).unwrap().children()[0].node;
    f.graph.remove_child(root_child, module).unwrap();
    let edited = f.render_resident();
    let fresh = f.render_fresh_baseline();
    assert_close(compare(&edited, &fresh).unwrap(), "after edits");
    let changed = compare(&edited, &resident).unwrap();
    assert!(changed.mean > 0.5, "the edits are visible: {changed:?}");
    assert_no_validation_errors(f.renderer.device());
}

#[test]
fn only_what_changed_is_uploaded() {
    let mut f = Fixture::new(&generate(&GeneratorSpec::Demo));
    f.render_resident();
    // Nothing changed: nothing is uploaded and the draw list stays.
    f.render_resident();
    assert_eq!(f.resident.last_upload().bytes, 0);
    assert_eq!(f.resident.last_upload().draws_updated, 0);

    let shapes = f.shape_transforms();
    for &shape in shapes.iter().take(10) {
        let matrix = f.graph.node(shape).unwrap().local_matrix();
        f.graph
            .set_matrix(shape, DMat4::from_translation(DVec3::Y) * matrix)
            .unwrap();
    }
    f.render_resident();
    let upload = f.resident.last_upload();
    assert_eq!(
        upload.matrices, 10,
        "changing 10 matrices uploads 10 matrices"
    );
    assert_eq!(
        upload.bytes,
        10 * MATRIX_UPLOAD_BYTES,
        "slot, matrix and low translation, nothing else"
    );
    assert!(
        upload.draws_updated == 0,
        "moving parts does not touch the draw list"
    );

    let material = f.graph.nodes().find_map(|(_, n)| match &n.kind {
        NodeKind::Geo { part_materials, .. } => Some(part_materials[0]),
        _ => None,
    });
    f.graph
        .set_material(
            material.unwrap(),
            Material {
                name: "blue".into(),
                base_color: [0.0, 0.0, 1.0, 1.0],
                ..Material::default()
            },
        )
        .unwrap();
    f.render_resident();
    let upload = f.resident.last_upload();
    assert_eq!(
        (upload.matrices, upload.materials, upload.bytes),
        (0, 1, 32)
    );
    assert_no_validation_errors(f.renderer.device());
}

#[test]
fn a_scene_far_from_the_origin_renders_like_one_at_the_origin() {
    // A 3 cm assembly (features of a tenth of a millimetre): at 100 km, f32 coordinates are
    // 8 mm apart, so only origin-relative matrices keep it intact.
    let mut scene = generate(&GeneratorSpec::Demo);
    scene.nodes[0].local = DMat4::from_scale(DVec3::splat(0.001)) * scene.nodes[0].local;
    let mut far = scene.clone();
    far.nodes[0].local =
        DMat4::from_translation(DVec3::new(100_000.0, 20_000.0, -100_000.0)) * far.nodes[0].local;

    let near_image = Fixture::new(&scene).render_resident();
    let far_image = Fixture::new(&far).render_resident();
    assert_close(compare(&near_image, &far_image).unwrap(), "100 km away");
}

#[test]
fn highlighted_parts_are_drawn_tinted_until_cleared() {
    let mut f = Fixture::new(&generate(&GeneratorSpec::Demo));
    let plain = f.render_resident();
    let module = f
        .graph
        .node(f.graph.node(f.graph.root()).unwrap().children()[0].node)
        .unwrap()
        .children()[0]
        .node;

    f.graph
        .set_flags(
            module,
            NodeFlags {
                highlighted: true,
                ..NodeFlags::default()
            },
        )
        .unwrap();
    let highlighted = f.render_resident();
    assert!(
        f.resident.last_upload().draws_updated > 0,
        "the highlight reaches the draws"
    );
    // The module's pixels change, and turn warmer (red minus blue grows, towards orange).
    let changed: Vec<(i32, i32)> = plain
        .pixels()
        .zip(highlighted.pixels())
        .filter(|(a, b)| a != b)
        .map(|(a, b)| {
            (
                i32::from(a[0]) - i32::from(a[2]),
                i32::from(b[0]) - i32::from(b[2]),
            )
        })
        .collect();
    assert!(changed.len() > 1000, "{} pixels changed", changed.len());
    let warmth =
        |pick: fn(&(i32, i32)) -> i32| changed.iter().map(pick).sum::<i32>() / changed.len() as i32;
    assert!(
        warmth(|c| c.1) > warmth(|c| c.0) + 60,
        "red-blue {} -> {}",
        warmth(|c| c.0),
        warmth(|c| c.1)
    );
    f.graph.set_flags(module, NodeFlags::default()).unwrap();
    let cleared = f.render_resident();
    assert_eq!(
        compare(&cleared, &plain).unwrap().max,
        0.0,
        "clearing the highlight restores the image"
    );
    assert_no_validation_errors(f.renderer.device());
}

#[test]
fn a_scene_spanning_200_km_keeps_millimetre_parts_intact_at_both_ends() {
    // Two 3 cm assemblies 200 km apart: one origin for the whole scene would leave each 100 km
    // from it, where f32 coordinates are 8 mm apart. Relative-to-eye keeps both exact.
    let mut part = generate(&GeneratorSpec::Demo);
    part.nodes[0].local = DMat4::from_scale(DVec3::splat(0.001)) * part.nodes[0].local;
    let part_bounds = cadr_core::scene::flatten(&part).unwrap().bounds;
    let mut site = part.clone();
    let root = site.roots[0];
    let (west, east) = (
        DVec3::new(-100_000.0, 0.0, 0.0),
        DVec3::new(100_000.0, 0.0, 35.0),
    );
    let mut far_copy = site.nodes[root as usize].clone();
    far_copy.local = DMat4::from_translation(east) * far_copy.local;
    site.nodes[root as usize].local =
        DMat4::from_translation(west) * site.nodes[root as usize].local;
    site.nodes.push(far_copy);
    site.roots.push(site.nodes.len() as u32 - 1);

    let reference = Fixture::new(&part).render_resident();
    let mut f = Fixture::new(&site);
    for offset in [west, east] {
        f.look_at(&part_bounds.transformed(&DMat4::from_translation(offset)));
        let image = f.render_resident();
        assert_close(
            compare(&image, &reference).unwrap(),
            &format!("the assembly at {offset:?}"),
        );
    }
    assert_no_validation_errors(f.renderer.device());
}

#[test]
fn picking_finds_the_part_under_a_pixel_and_passes_through_unpickable_ones() {
    let mut f = Fixture::new(&generate(&GeneratorSpec::Demo));
    let image = f.render_resident();
    let (x, y) = (SIZE.0 / 2, SIZE.1 / 2);
    assert_ne!(
        image.get_pixel(x, y).0,
        image.get_pixel(0, 0).0,
        "the centre shows a part"
    );
    assert_eq!(
        f.renderer.pick(&mut f.resident, &f.camera, 0, 0).unwrap(),
        None,
        "background"
    );

    let hit = f
        .renderer
        .pick(&mut f.resident, &f.camera, x, y)
        .unwrap()
        .expect("a part at the centre");
    let instance = f.tree.instance(hit).expect("a live instance");
    assert!(instance.visible && instance.pickable);
    let path = f.tree.path(instance.tree_node);
    let geo = *path.last().unwrap();
    assert!(
        matches!(f.graph.node(geo).unwrap().kind, NodeKind::Geo { .. }),
        "the path ends in the part's Geo node"
    );

    // Not pickable: the click passes through to whatever lies behind (or nothing).
    f.graph
        .set_flags(
            geo,
            NodeFlags {
                pickable: false,
                ..NodeFlags::default()
            },
        )
        .unwrap();
    f.tree.update(&mut f.graph);
    f.resident.sync(&f.graph, &mut f.tree).unwrap();
    let behind = f.renderer.pick(&mut f.resident, &f.camera, x, y).unwrap();
    assert_ne!(behind, Some(hit));
    let error = f
        .renderer
        .pick(&mut f.resident, &f.camera, SIZE.0, 0)
        .unwrap_err()
        .to_string();
    assert!(error.contains("outside the 200x150 target"), "{error}");
    assert_no_validation_errors(f.renderer.device());
}

#[test]
fn replacing_a_geometry_uploads_only_that_geometry_and_touches_only_its_users() {
    let mut f = Fixture::new(&generate(&GeneratorSpec::Demo));
    f.render_resident();
    let (handle, users) = {
        let geo = f.shape_transforms()[3];
        let geo = f.graph.node(geo).unwrap().children()[0].node;
        match &f.graph.node(geo).unwrap().kind {
            NodeKind::Geo { geometry, .. } => {
                (*geometry, f.graph.geometry_users(*geometry).unwrap().len())
            }
            _ => unreachable!("shape transforms hold a Geo node"),
        }
    };
    // Same size, raised vertices: written in place.
    let mut data = f.graph.geometry(handle).unwrap().clone();
    for v in &mut data.vertices {
        v.position[1] += 0.3;
    }
    let bytes = (std::mem::size_of_val(&data.vertices[..])
        + std::mem::size_of_val(&data.indices[..])) as u64;
    f.graph.replace_geometry(handle, data.clone()).unwrap();
    let edited = f.render_resident();
    let upload = f.resident.last_upload();
    assert_eq!(
        upload.bytes, bytes,
        "only the replaced geometry is uploaded"
    );
    let parts = data.parts.len();
    assert_eq!(
        upload.draws_updated as usize,
        users * parts,
        "only its users' draws are touched"
    );
    assert_close(
        compare(&edited, &f.render_fresh_baseline()).unwrap(),
        "after an in-place replacement",
    );

    // Bigger than its room: a raised copy of every vertex and index is appended and the parts
    // point at the copy. The arenas are laid out again, and the image is still right.
    let mut bigger = data;
    let (vertex_count, index_count) = (bigger.vertices.len() as u32, bigger.indices.len() as u32);
    let copy: Vec<_> = bigger
        .vertices
        .iter()
        .map(|v| {
            let mut v = *v;
            v.position[1] += 0.2;
            v
        })
        .collect();
    bigger.vertices.extend(copy);
    let copied: Vec<u32> = bigger.indices.iter().map(|i| i + vertex_count).collect();
    bigger.indices.extend(copied);
    for part in &mut bigger.parts {
        part.first_index += index_count;
    }
    f.graph.replace_geometry(handle, bigger).unwrap();
    let edited = f.render_resident();
    assert!(
        f.resident.last_upload().bytes > bytes,
        "the whole arena was laid out again"
    );
    assert_close(
        compare(&edited, &f.render_fresh_baseline()).unwrap(),
        "after the arenas were laid out again",
    );
    assert_no_validation_errors(f.renderer.device());
}
