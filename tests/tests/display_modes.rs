//! Display modes: gen:demo and the 2CylinderEngine in each mode (X-ray included) match their
//! references, each mode shows something other than the others, and the line-only modes fill
//! no surface; silhouettes outline curved surfaces in the edge modes; highlighted parts are
//! tinted or outlined, in the colours and band width of the host's palette.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use cadr_core::generate::{generate, GeneratorSpec, GeometryBuilder};
use cadr_core::graph::NodeFlags;
use cadr_core::load::load_file;
use cadr_core::render::{Background, Camera, HighlightStyle, Palette, DEFAULT_FOV_DEGREES};
use cadr_core::scene::edges::{feature_edges, DEFAULT_CREASE_DEGREES};
use cadr_core::scene::{Geometry, Material, MeshRef, Node, Part, Scene, Vertex};
use cadr_core::technique::Combination;
use cadr_core::technique::ShadeMode;
use cadr_tests::images::{
    self, assert_matches_reference, compare, DEFAULT_TOLERANCE, VISIBLE_CHANGE,
};
use cadr_tests::{scene_wide, test_device, SceneView, CYLINDER_ENGINE_GLB};
use glam::{DMat4, DVec3};

const SIZE: (u32, u32) = (160, 120);

/// The scene in every mode, in the order of `ShadeMode::ALL`.
fn render_every_mode(scene: &Scene) -> Vec<image::RgbaImage> {
    let mut f = SceneView::fitted(test_device(), scene, SIZE);
    let images = ShadeMode::ALL
        .iter()
        .map(|&mode| {
            f.view.techniques_mut().set_shade_mode(mode).unwrap();
            f.render()
        })
        .collect();
    f.assert_no_validation_errors();
    images
}

/// The share of pixels that are neither the background nor the dark line colour.
fn filled_fraction(image: &image::RgbaImage) -> f64 {
    let filled = image
        .enumerate_pixels()
        .filter(|(_, y, p)| {
            let background = Background::default().rgb8_at(*y, image.height());
            let near_background = (0..3).all(|i| p.0[i].abs_diff(background[i]) < 12);
            let line = (0..3).all(|i| p.0[i] < 90);
            !near_background && !line
        })
        .count();
    filled as f64 / f64::from(image.width() * image.height())
}

fn check_modes(name: &str, scene: &Scene) {
    let images = render_every_mode(scene);
    for (mode, image) in ShadeMode::ALL.iter().zip(&images) {
        assert_matches_reference(
            &format!("{name}_{}", mode.name().replace('-', "_")),
            image,
            DEFAULT_TOLERANCE,
        );
    }
    for (i, a) in images.iter().enumerate() {
        for b in &images[i + 1..] {
            let difference = compare(a, b).unwrap();
            assert!(
                difference.mean > VISIBLE_CHANGE,
                "{name}: two modes look alike: {difference:?}"
            );
        }
    }
    let [solid, _, hidden_line, wireframe, _] = &images[..] else {
        unreachable!("five modes")
    };
    assert!(
        filled_fraction(solid) > 0.05,
        "{name}: solid fills surfaces"
    );
    for (mode, image) in [("hidden-line", hidden_line), ("wireframe", wireframe)] {
        assert!(
            filled_fraction(image) < 0.2 * filled_fraction(solid),
            "{name}: {mode} fills no surface: {} against {}",
            filled_fraction(image),
            filled_fraction(solid)
        );
    }
}

#[test]
fn the_demo_in_every_display_mode_matches_its_references() {
    check_modes("display_demo", &generate(&GeneratorSpec::Demo));
}

#[test]
fn the_cylinder_engine_in_every_display_mode_matches_its_references() {
    let scene = load_file(std::path::Path::new(CYLINDER_ENGINE_GLB)).unwrap();
    check_modes("display_cylinder_engine", &scene);
}

/// Hidden-line with its hidden edges dashed: the visible lines stay as they are, and grey
/// dashes appear where edges run behind surfaces (none of them where hidden-line alone shows
/// a line, more of them than the visible lines' share of the picture would allow by chance).
#[test]
fn hidden_line_shows_hidden_edges_dashed_when_asked() {
    let scene = load_file(std::path::Path::new(CYLINDER_ENGINE_GLB)).unwrap();
    let mut f = SceneView::fitted(test_device(), &scene, SIZE);
    f.view
        .techniques_mut()
        .set_shade_mode(ShadeMode::HiddenLine)
        .unwrap();
    let draw = |f: &mut SceneView, dashed: bool| {
        f.view.techniques_mut().set_dashed_hidden_lines(dashed);
        f.render()
    };
    let removed = draw(&mut f, false);
    let dashed = draw(&mut f, true);
    assert!(f.view.techniques().dashed_hidden_lines());
    assert_matches_reference(
        "display_cylinder_engine_hidden_line_dashed",
        &dashed,
        DEFAULT_TOLERANCE,
    );
    let dark = |p: &image::Rgba<u8>| (0..3).all(|i| p.0[i] < 90);
    let grey = |p: &image::Rgba<u8>| (0..3).all(|i| (100..140).contains(&p.0[i]));
    let lines = removed.pixels().filter(|p| dark(p)).count();
    let kept = removed
        .pixels()
        .zip(dashed.pixels())
        .filter(|(a, b)| dark(a) && dark(b))
        .count();
    assert!(
        kept as f64 >= 0.99 * lines as f64,
        "{kept} of {lines} visible line pixels kept"
    );
    let dashes = removed
        .pixels()
        .zip(dashed.pixels())
        .filter(|(a, b)| !dark(a) && grey(b))
        .count();
    assert!(
        dashes > lines / 4,
        "{dashes} grey dash pixels against {lines} visible line pixels"
    );
    // The other modes do not change.
    f.view
        .techniques_mut()
        .set_shade_mode(ShadeMode::Edges)
        .unwrap();
    let edges_dashed = draw(&mut f, true);
    let edges = draw(&mut f, false);
    assert_eq!(
        edges_dashed, edges,
        "edges mode has no hidden lines to dash"
    );
    f.assert_no_validation_errors();
}

/// Screen-space ambient occlusion darkens where parts meet (the demo's parts on their
/// plates), never the background, and leaves the line-only modes alone; with MSAA too.
#[test]
fn ambient_occlusion_darkens_where_parts_meet_and_only_there() {
    let mut f = SceneView::fitted(test_device(), &generate(&GeneratorSpec::Demo), SIZE);
    let draw = |f: &mut SceneView, ssao: bool| {
        f.view.renderer_mut().set_ssao(ssao).unwrap();
        f.render()
    };
    let luminance = |p: &image::Rgba<u8>| p.0[..3].iter().map(|&c| u32::from(c)).sum::<u32>();
    for samples in [1, 4] {
        f.view.renderer_mut().set_msaa(samples).unwrap();
        let plain = draw(&mut f, false);
        let occluded = draw(&mut f, true);
        assert!(f.view.renderer().ssao());
        if samples == 1 {
            assert_matches_reference("display_demo_solid_ssao", &occluded, DEFAULT_TOLERANCE);
        }
        let mut darker = 0;
        for ((x, y, a), b) in plain.enumerate_pixels().zip(occluded.pixels()) {
            assert!(
                luminance(b) <= luminance(a) + 3,
                "{samples}x: occlusion only darkens ({x}, {y}): {a:?} -> {b:?}"
            );
            if cadr_tests::images::is_background(&plain, x, y) {
                assert_eq!(
                    a, b,
                    "{samples}x: the background at ({x}, {y}) is untouched"
                );
            } else if luminance(b) + 30 < luminance(a) {
                darker += 1;
            }
        }
        let covered = plain
            .enumerate_pixels()
            .filter(|(x, y, _)| !cadr_tests::images::is_background(&plain, *x, *y))
            .count();
        assert!(
            darker > covered / 50 && darker < covered / 2,
            "{samples}x: {darker} of {covered} covered pixels clearly darker"
        );
    }
    // Line-only modes fill no surface to occlude.
    f.view
        .techniques_mut()
        .set_shade_mode(ShadeMode::Wireframe)
        .unwrap();
    let with = draw(&mut f, true);
    let without = draw(&mut f, false);
    assert_eq!(with, without, "wireframe is not occluded");
    f.assert_no_validation_errors();
}

/// `scene` in a view of `SIZE`, seen from `eye` looking at the origin.
fn seen_from(scene: &Scene, eye: DVec3) -> SceneView {
    let aspect = f64::from(SIZE.0) / f64::from(SIZE.1);
    let camera = Camera::look_at(eye, DVec3::ZERO, DEFAULT_FOV_DEGREES, aspect, 0.1, 100.0);
    SceneView::new(test_device(), scene, SIZE, camera)
}

/// Gives `geometry` the feature edges `feature_edges` derives at the default crease angle.
fn with_feature_edges(geometry: &mut Geometry) {
    let (wire_indices, parts) = feature_edges(geometry, DEFAULT_CREASE_DEGREES);
    geometry.wire_indices = wire_indices;
    geometry.parts = parts;
}

/// A smooth cylinder (48 facets, radius 1, from y = -1 to 1) whose only feature edges are its
/// rims: its sides are outlined by silhouettes alone.
fn smooth_cylinder() -> Scene {
    let mut builder = GeometryBuilder::new("cylinder");
    builder.prism(48, DMat4::from_scale(DVec3::new(1.0, 2.0, 1.0)));
    let mut geometry = builder.finish();
    with_feature_edges(&mut geometry);
    let mut node = Node::new("cylinder");
    node.mesh = Some(MeshRef::new(0, vec![0]));
    Scene {
        name: "cylinder".into(),
        geometries: vec![geometry],
        materials: vec![Material::default()],
        nodes: vec![node],
        roots: vec![0],
        ..Scene::default()
    }
}

/// The smooth cylinder seen a little from above, its sides upright in the picture.
fn smooth_cylinder_view() -> SceneView {
    seen_from(&smooth_cylinder(), DVec3::new(0.0, 1.5, 6.0))
}

/// Silhouette edges outline the sides of a smooth cylinder in the modes that draw feature edges
/// (X-ray's translucent surfaces included), where no feature edge runs: a line at each side of
/// its outline, on the cylinder, and none across its curved face; without them (or in the
/// other modes) there is none; with MSAA too.
#[test]
fn silhouettes_outline_curved_surfaces_in_the_edge_modes() {
    let mut f = smooth_cylinder_view();
    let dark = |p: &image::Rgba<u8>| (0..3).all(|i| p.0[i] < 90);
    // The row through the cylinder's middle, clear of its rims.
    let (_, row) = images::pixel_of(&f.camera, SIZE, DVec3::ZERO);
    let draw = |f: &mut SceneView, mode: ShadeMode, silhouettes: bool| {
        f.view.techniques_mut().set_shade_mode(mode).unwrap();
        f.view.renderer_mut().set_silhouettes(silhouettes).unwrap();
        f.render()
    };
    for samples in [1, 4] {
        f.view.renderer_mut().set_msaa(samples).unwrap();
        let solid = draw(&mut f, ShadeMode::Solid, true);
        let covered: Vec<u32> = (0..SIZE.0)
            .filter(|&x| !images::is_background(&solid, x, row))
            .collect();
        let (left, right) = (covered[0], covered[covered.len() - 1]);
        assert!(
            right - left > SIZE.0 / 8,
            "{samples}x: the cylinder is seen"
        );
        for mode in [ShadeMode::Edges, ShadeMode::HiddenLine, ShadeMode::XRay] {
            let with = draw(&mut f, mode, true);
            assert!(f.view.renderer().silhouettes());
            let without = draw(&mut f, mode, false);
            let dark_columns = |image: &image::RgbaImage| -> Vec<u32> {
                (0..SIZE.0)
                    .filter(|&x| dark(image.get_pixel(x, row)))
                    .collect()
            };
            assert_eq!(
                dark_columns(&without),
                Vec::<u32>::new(),
                "{samples}x {mode:?}: no feature edge crosses the middle row"
            );
            let lines = dark_columns(&with);
            let near = |edge: u32| lines.iter().filter(|&&x| x.abs_diff(edge) <= 1).count();
            assert!(
                near(left) >= 1 && near(right) >= 1,
                "{samples}x {mode:?}: lines at the outline {left}..{right}: {lines:?}"
            );
            assert!(
                lines.len() <= 4,
                "{samples}x {mode:?}: no line across the curved face: {lines:?}"
            );
        }
        // The other modes draw no silhouettes.
        for mode in [ShadeMode::Solid, ShadeMode::Wireframe] {
            assert_eq!(
                draw(&mut f, mode, true),
                draw(&mut f, mode, false),
                "{samples}x {mode:?}"
            );
        }
    }
    f.assert_no_validation_errors();
}

/// A cylinder with shared normals, as CAD tessellations make curved surfaces (radius 1, from
/// y = -1 to 1, 48 sides whose vertices each carry the radial normal), its caps flat: its only
/// feature edges are its rims.
fn shared_normal_cylinder() -> Geometry {
    let sides = 48_u32;
    let mut geometry = Geometry {
        name: "shared-normal cylinder".into(),
        ..Geometry::default()
    };
    let around = |k: u32| {
        let angle = std::f32::consts::TAU * k as f32 / sides as f32;
        (angle.cos(), angle.sin())
    };
    for k in 0..sides {
        let (x, z) = around(k);
        for y in [-1.0, 1.0] {
            geometry.vertices.push(Vertex {
                position: [x, y, z],
                normal: [x, 0.0, z],
            });
        }
    }
    for k in 0..sides {
        let (a, b) = (2 * k, 2 * ((k + 1) % sides));
        // Counter-clockwise seen from outside.
        geometry.indices.extend([a, a + 1, b + 1, a, b + 1, b]);
    }
    for y in [-1.0_f32, 1.0] {
        let first = geometry.vertices.len() as u32;
        for k in 0..sides {
            let (x, z) = around(k);
            geometry.vertices.push(Vertex {
                position: [x, y, z],
                normal: [0.0, y, 0.0],
            });
        }
        for k in 1..sides - 1 {
            if y > 0.0 {
                geometry.indices.extend([first, first + k + 1, first + k]);
            } else {
                geometry.indices.extend([first, first + k, first + k + 1]);
            }
        }
    }
    geometry.parts = vec![Part {
        first_index: 0,
        index_count: geometry.indices.len() as u32,
        first_wire_index: 0,
        wire_index_count: 0,
    }];
    with_feature_edges(&mut geometry);
    geometry
}

/// The shared-normal cylinder behind a wide plate (x from -2.5 to 2.5, y from -0.5 to 0.5,
/// z from 1.5 to 2) that hides its middle, seen from the front a little from above.
fn cylinder_behind_a_plate() -> SceneView {
    let mut builder = GeometryBuilder::new("plate");
    builder.cuboid(
        DVec3::new(-2.5, -0.5, 1.5),
        DVec3::new(2.5, 0.5, 2.0),
        DMat4::IDENTITY,
    );
    let mut plate = builder.finish();
    with_feature_edges(&mut plate);
    let mut nodes = Vec::new();
    for (geometry, name) in [(0, "cylinder"), (1, "plate")] {
        let mut node = Node::new(name);
        node.mesh = Some(MeshRef::new(geometry, vec![0]));
        nodes.push(node);
    }
    let scene = Scene {
        name: "cylinder behind a plate".into(),
        geometries: vec![shared_normal_cylinder(), plate],
        materials: vec![Material::default()],
        nodes,
        roots: vec![0, 1],
        ..Scene::default()
    };
    seen_from(&scene, DVec3::new(0.0, 0.3, 6.0))
}

/// The pixels in `rows` that differ between two pictures, in three counts: within 2 pixels of
/// column `left`, within 2 of column `right`, elsewhere from `left - 6` to `right + 6`.
fn changed_near(
    (a, b): (&image::RgbaImage, &image::RgbaImage),
    (left, right): (u32, u32),
    rows: std::ops::RangeInclusive<u32>,
) -> [usize; 3] {
    let mut counts = [0_usize; 3];
    for y in rows {
        for x in left - 6..=right + 6 {
            if a.get_pixel(x, y) != b.get_pixel(x, y) {
                let side = if x.abs_diff(left) <= 2 {
                    0
                } else if x.abs_diff(right) <= 2 {
                    1
                } else {
                    2
                };
                counts[side] += 1;
            }
        }
    }
    counts
}

/// Checks `cylinder_behind_a_plate` in hidden-line as its view now draws it (its camera, MSAA
/// and techniques), the cylinder's outline touching it at x = ±`tangent.0`, z = `tangent.1`:
/// dashes along both hidden sides and nowhere across, none along the sides seen, none without
/// silhouettes or dashes; the silhouettes' pass draws the curved cylinder alone.
fn assert_hidden_silhouettes(f: &mut SceneView, (tangent_x, tangent_z): (f64, f64), case: &str) {
    let camera = f.camera;
    let at = |x: f64, y: f64| images::pixel_of(&camera, SIZE, DVec3::new(x, y, tangent_z));
    let columns = (at(-tangent_x, 0.0).0, at(tangent_x, 0.0).0);
    // Rows the plate hides (the cylinder's y from 0.3 down to -0.35), rows where the sides are
    // seen (y from 0.8 down to 0.65), clear of the plate's edges and the rims.
    let hidden_rows = at(0.0, 0.3).1..=at(0.0, -0.35).1;
    let seen_rows = at(0.0, 0.8).1..=at(0.0, 0.65).1;
    assert!(hidden_rows.clone().count() >= 10 && seen_rows.clone().count() >= 3);
    f.view
        .techniques_mut()
        .set_shade_mode(ShadeMode::HiddenLine)
        .unwrap();
    let mut draw = |dashed: bool, silhouettes: bool| {
        f.view.techniques_mut().set_dashed_hidden_lines(dashed);
        f.view.renderer_mut().set_silhouettes(silhouettes).unwrap();
        f.render()
    };
    let dashed = draw(true, true);
    let dashed_without_silhouettes = draw(true, false);
    let solid_lines = draw(false, true);
    let solid_lines_without_silhouettes = draw(false, false);
    let [hidden_left, hidden_right, across] = changed_near(
        (&dashed, &dashed_without_silhouettes),
        columns,
        hidden_rows.clone(),
    );
    assert!(
        hidden_left >= 4 && hidden_right >= 4,
        "{case}: dashes along both hidden sides: {hidden_left}, {hidden_right}"
    );
    assert_eq!(across, 0, "{case}: no dash across the hidden curved face");
    let [seen_left, seen_right, _] =
        changed_near((&dashed, &solid_lines), columns, seen_rows.clone());
    assert_eq!(
        (seen_left, seen_right),
        (0, 0),
        "{case}: the sides seen are not dashed"
    );
    assert_eq!(
        changed_near(
            (
                &dashed_without_silhouettes,
                &solid_lines_without_silhouettes
            ),
            columns,
            hidden_rows.clone()
        ),
        [0, 0, 0],
        "{case}: without silhouettes, no hidden side is dashed"
    );
    assert_eq!(
        changed_near(
            (&solid_lines, &solid_lines_without_silhouettes),
            columns,
            hidden_rows
        ),
        [0, 0, 0],
        "{case}: without dashes, no hidden side is drawn"
    );
    // The silhouettes' pass draws the curved cylinder alone (CADR_INSTANCE_CURVED): the
    // faceted plate has no triangle a silhouette crosses.
    let mut steady_draws = |silhouettes: bool| {
        f.view.techniques_mut().set_dashed_hidden_lines(true);
        f.view.renderer_mut().set_silhouettes(silhouettes).unwrap();
        f.steady_draws()
    };
    let pass_draws = steady_draws(true) - steady_draws(false);
    assert_eq!(
        pass_draws, 1,
        "{case}: the silhouettes' pass draws one part"
    );
}

/// Hidden-line with dashed hidden lines dashes the silhouettes of hidden curved surfaces too
/// (where the device has geometry shaders, as lavapipe does): the sides of a cylinder behind a
/// plate, which no feature edge marks, show as dashes in the rows the plate hides, close to
/// the cylinder's outline and nowhere across it; not where the sides are seen (the visible
/// silhouettes are solid lines), not without silhouettes, not without dashes; with MSAA,
/// through a GPU culler and seen through an orthographic projection too; the pass draws only
/// the curved part, not the faceted plate.
#[test]
fn hidden_line_dashes_the_silhouettes_of_hidden_curved_surfaces() {
    let mut f = cylinder_behind_a_plate();
    assert!(f.device.capabilities().geometry_shader, "lavapipe has them");
    // Where the eye's tangents touch the cylinder (radius 1, the eye 6 from its axis).
    let perspective_tangent = ((1.0_f64 - 1.0 / 36.0).sqrt(), 1.0 / 6.0);
    let combinations = [
        Combination::built_in(),
        scene_wide("individual-indirect-count", "gpu-frustum"),
    ];
    for (combination, samples) in combinations
        .iter()
        .zip([4, 1])
        .chain([(&combinations[0], 1)])
    {
        f.view.techniques_mut().select(combination).unwrap();
        f.view.renderer_mut().set_msaa(samples).unwrap();
        let case = format!("{combination} {samples}x");
        assert_hidden_silhouettes(&mut f, perspective_tangent, &case);
    }
    // Parallel rays touch the cylinder at x = ±1, z = 0 (a host's own orthographic matrix,
    // as the C API takes it; Vulkan's y down, depth 0 to 1). The eye close in front, where a
    // perspective's tangents would touch it 4 pixels further in.
    let aspect = f64::from(SIZE.0) / f64::from(SIZE.1);
    f.camera = Camera::look_at(
        DVec3::new(0.0, 0.0, 2.2),
        DVec3::ZERO,
        DEFAULT_FOV_DEGREES,
        aspect,
        0.1,
        100.0,
    );
    let mut orthographic = DMat4::orthographic_rh(-2.0, 2.0, -1.5, 1.5, 0.1, 100.0);
    orthographic.y_axis.y *= -1.0;
    f.camera.projection = orthographic;
    assert_hidden_silhouettes(&mut f, (1.0, 0.0), "orthographic");
    f.assert_no_validation_errors();
}

/// A highlighted part's silhouettes take the highlight's line colour, as its feature edges do,
/// in every mode that draws them (X-ray's opaque highlighted parts included), with MSAA too;
/// once the highlight is taken away they are drawn in the edge lines' colour again.
#[test]
fn silhouettes_of_a_highlighted_part_take_its_line_colour() {
    let mut f = smooth_cylinder_view();
    let cylinder = f.nodes[0];
    let highlight = |f: &mut SceneView, highlighted: bool| {
        let flags = NodeFlags {
            highlighted,
            ..NodeFlags::default()
        };
        f.graph.set_flags(cylinder, flags).unwrap();
    };
    // The lines' colours in display RGB, as 8-bit values.
    let palette = Palette::default();
    let to_8_bits = |rgb: [f32; 3]| rgb.map(|c| (c * 255.0).round() as i32);
    let edge_line = to_8_bits(palette.edges);
    let highlight_line = to_8_bits(palette.highlight.map(|c| 0.7 * c));
    let is = |p: &image::Rgba<u8>, rgb: [i32; 3]| {
        (0..3).all(|i| (i32::from(p.0[i]) - rgb[i]).abs() <= 6)
    };
    let (_, row) = images::pixel_of(&f.camera, SIZE, DVec3::ZERO);
    for samples in [1, 4] {
        f.view.renderer_mut().set_msaa(samples).unwrap();
        for mode in [ShadeMode::Edges, ShadeMode::HiddenLine, ShadeMode::XRay] {
            f.view.techniques_mut().set_shade_mode(mode).unwrap();
            let columns = |image: &image::RgbaImage, rgb: [i32; 3]| -> Vec<u32> {
                (0..SIZE.0)
                    .filter(|&x| is(image.get_pixel(x, row), rgb))
                    .collect()
            };
            highlight(&mut f, false);
            let plain = f.render();
            let plain_lines = columns(&plain, edge_line);
            assert!(
                plain_lines.len() >= 2,
                "{samples}x {mode:?}: silhouettes in the edge colour: {plain_lines:?}"
            );
            highlight(&mut f, true);
            // Twice: the second frame is the replayed one where the techniques replay.
            for _ in 0..2 {
                let highlighted = f.render();
                assert_eq!(
                    columns(&highlighted, edge_line),
                    Vec::<u32>::new(),
                    "{samples}x {mode:?}: no silhouette in the edge colour"
                );
                assert_eq!(
                    columns(&highlighted, highlight_line),
                    plain_lines,
                    "{samples}x {mode:?}: the same silhouettes in the highlight's line colour"
                );
            }
            highlight(&mut f, false);
            assert_eq!(
                columns(&f.render(), edge_line),
                plain_lines,
                "{samples}x {mode:?}: the edge colour again"
            );
        }
    }
    f.assert_no_validation_errors();
}

/// Two cubes side by side (x = -1.2 and 1.2, edge 1.6), seen from the front.
fn two_cubes() -> SceneView {
    let mut builder = GeometryBuilder::new("cube");
    builder.cuboid(DVec3::splat(-0.8), DVec3::splat(0.8), DMat4::IDENTITY);
    let mut scene = Scene {
        name: "two cubes".into(),
        geometries: vec![builder.finish()],
        materials: vec![Material::default()],
        ..Scene::default()
    };
    for (i, x) in [-1.2, 1.2].into_iter().enumerate() {
        let mut node = Node::new(format!("cube {i}"));
        node.local = DMat4::from_translation(DVec3::new(x, 0.0, 0.0));
        node.mesh = Some(MeshRef::new(0, vec![0]));
        scene.nodes.push(node);
        scene.roots.push(i as u32);
    }
    seen_from(&scene, DVec3::new(0.0, 0.0, 8.0))
}

/// The highlight styles: tint mixes the highlighted cube's colour towards orange; outline keeps
/// its colour and draws an orange band just outside it and nowhere else, in the solid, edges,
/// hidden-line and X-ray modes and with MSAA; with nothing highlighted it draws nothing, and
/// tint again draws the tinted picture again.
#[test]
fn highlighted_parts_are_tinted_or_outlined() {
    let mut f = two_cubes();
    let highlight = |f: &mut SceneView, on: bool| {
        let right = f.nodes[1];
        let flags = NodeFlags {
            highlighted: on,
            ..NodeFlags::default()
        };
        f.graph.set_flags(right, flags).unwrap();
        f.tree.update(&mut f.graph);
    };
    let orange = |p: &image::Rgba<u8>| p.0[0] > 200 && (100..180).contains(&p.0[1]) && p.0[2] < 60;
    let (_, row) = images::pixel_of(&f.camera, SIZE, DVec3::ZERO);
    let (centre, _) = images::pixel_of(&f.camera, SIZE, DVec3::new(1.2, 0.0, 0.0));
    let (left_centre, _) = images::pixel_of(&f.camera, SIZE, DVec3::new(-1.2, 0.0, 0.0));
    for samples in [1, 4] {
        f.view.renderer_mut().set_msaa(samples).unwrap();
        for mode in [
            ShadeMode::Solid,
            ShadeMode::Edges,
            ShadeMode::HiddenLine,
            ShadeMode::XRay,
        ] {
            let context = format!("{samples}x {mode:?}");
            f.view.techniques_mut().set_shade_mode(mode).unwrap();
            f.view
                .renderer_mut()
                .set_highlight_style(HighlightStyle::Tint)
                .unwrap();
            highlight(&mut f, false);
            let plain = f.render();
            let covered: Vec<u32> = (0..SIZE.0)
                .filter(|&x| x > (centre + left_centre) / 2)
                .filter(|&x| !images::is_background(&plain, x, row))
                .collect();
            let (first, last) = (covered[0], covered[covered.len() - 1]);
            assert!(
                first < centre && centre < last,
                "{context}: the right cube is seen"
            );
            highlight(&mut f, true);
            let tinted = f.render();
            f.view
                .renderer_mut()
                .set_highlight_style(HighlightStyle::Outline)
                .unwrap();
            assert_eq!(f.view.renderer().highlight_style(), HighlightStyle::Outline);
            let outlined = f.render();
            if mode == ShadeMode::Solid {
                assert_ne!(
                    tinted.get_pixel(centre, row),
                    plain.get_pixel(centre, row),
                    "{context}: tint changes the highlighted cube's colour"
                );
            }
            if mode == ShadeMode::XRay {
                // Highlighted, the cube is opaque in X-ray: its own colour, not tinted.
                assert!(!orange(outlined.get_pixel(centre, row)), "{context}");
                assert_ne!(
                    outlined.get_pixel(centre, row),
                    tinted.get_pixel(centre, row),
                    "{context}: the outlined cube is not tinted"
                );
            } else {
                assert_eq!(
                    outlined.get_pixel(centre, row),
                    plain.get_pixel(centre, row),
                    "{context}: the outlined cube keeps its colour"
                );
            }
            // The band is 2 pixels wide around the surfaces; a line or an anti-aliased edge
            // may stick out of them by one.
            for x in [last + 1, first - 1] {
                assert!(
                    orange(outlined.get_pixel(x, row)),
                    "{context}: the band at ({x}, {row}) beside {first}..{last}: {:?}",
                    outlined.get_pixel(x, row)
                );
            }
            // Nothing changes away from the band: not the other cube, not the background.
            for (x, y, p) in outlined.enumerate_pixels() {
                let near_band = x + 4 >= first && x <= last + 4;
                if !near_band {
                    assert_eq!(
                        p,
                        plain.get_pixel(x, y),
                        "{context}: ({x}, {y}) is untouched"
                    );
                }
            }
            assert_eq!(
                outlined.get_pixel(left_centre, row),
                plain.get_pixel(left_centre, row)
            );
            highlight(&mut f, false);
            assert_eq!(
                f.render(),
                plain,
                "{context}: nothing highlighted, nothing outlined"
            );
            highlight(&mut f, true);
            f.view
                .renderer_mut()
                .set_highlight_style(HighlightStyle::Tint)
                .unwrap();
            assert_eq!(f.render(), tinted, "{context}: tint again");
        }
    }
    // In the line-only modes a highlighted part's lines are drawn dark orange: the highlight
    // shows there too (on the right cube only). Silhouettes, drawn after the lines, would
    // cover the cube's outline in the edge colour: they are off here.
    f.view.renderer_mut().set_silhouettes(false).unwrap();
    f.view.renderer_mut().set_msaa(1).unwrap();
    let line_orange =
        |p: &image::Rgba<u8>| p.0[0] > 140 && (60..130).contains(&p.0[1]) && p.0[2] < 50;
    for mode in [ShadeMode::HiddenLine, ShadeMode::Wireframe] {
        f.view.techniques_mut().set_shade_mode(mode).unwrap();
        let image = f.render();
        let middle = (centre + left_centre) / 2;
        let right = (middle..SIZE.0)
            .filter(|&x| line_orange(image.get_pixel(x, row)))
            .count();
        let left = (0..middle)
            .filter(|&x| line_orange(image.get_pixel(x, row)))
            .count();
        assert!(
            right >= 2 && left == 0,
            "{mode:?}: {right} right, {left} left"
        );
    }
    f.assert_no_validation_errors();
}

/// The host's palette: edge lines and silhouettes in its edge colour (and dashed hidden lines
/// in a lighter shade of it), highlighted parts tinted towards or outlined in its highlight
/// colour, the band as wide as it asks; a palette out of range is refused and the last kept.
#[test]
fn the_palette_colours_lines_and_highlights_and_sizes_the_outline() {
    let mut f = two_cubes();
    let right = f.nodes[1];
    let flags = NodeFlags {
        highlighted: true,
        ..NodeFlags::default()
    };
    f.graph.set_flags(right, flags).unwrap();
    f.tree.update(&mut f.graph);
    let blue = [0.0, 0.0, 1.0];
    let green = [0.0, 1.0, 0.0];
    let is = |p: &image::Rgba<u8>, rgb: [u8; 3]| p.0[..3] == rgb;
    let count =
        |image: &image::RgbaImage, rgb: [u8; 3]| image.pixels().filter(|p| is(p, rgb)).count();
    let (centre, row) = images::pixel_of(&f.camera, SIZE, DVec3::new(1.2, 0.0, 0.0));

    // Edge lines (and the silhouettes of the cubes against the background) in blue: the left
    // cube, not highlighted, is drawn with them.
    f.view
        .techniques_mut()
        .set_shade_mode(ShadeMode::Edges)
        .unwrap();
    let default_lines = f.render();
    assert_eq!(count(&default_lines, [0, 0, 255]), 0);
    f.view
        .renderer_mut()
        .set_palette(Palette {
            edges: blue,
            ..Palette::DEFAULT
        })
        .unwrap();
    let blue_lines = f.render();
    assert!(
        count(&blue_lines, [0, 0, 255]) > 40,
        "{} blue pixels",
        count(&blue_lines, [0, 0, 255])
    );
    // Dashed hidden lines: a lighter blue (mixed 42 % towards white), where none was before;
    // the highlighted cube's a lighter shade of the highlight's line colour (70 % of orange).
    f.view
        .techniques_mut()
        .set_shade_mode(ShadeMode::HiddenLine)
        .unwrap();
    f.view.techniques_mut().set_dashed_hidden_lines(true);
    let light = |rgb: [f32; 3]| rgb.map(|c| ((c + (1.0 - c) * 0.42) * 255.0).round() as u8);
    let light_blue = light(blue);
    let light_highlight = light(Palette::DEFAULT.highlight.map(|c| 0.7 * c));
    let near = |p: &image::Rgba<u8>, rgb: [u8; 3]| {
        p.0[..3].iter().zip(rgb).all(|(&a, b)| a.abs_diff(b) <= 3)
    };
    let dashed = f.render();
    let dashes = |rgb: [u8; 3], on_the_right: bool| {
        dashed
            .enumerate_pixels()
            .filter(|&(x, _, p)| near(p, rgb) && (x >= SIZE.0 / 2) == on_the_right)
            .count()
    };
    assert!(dashes(light_blue, false) > 10, "dashed lines in light blue");
    assert_eq!(dashes(light_blue, true), 0, "none on the highlighted cube");
    assert!(
        dashes(light_highlight, true) > 10,
        "the highlighted cube's dashed lines in {light_highlight:?}"
    );
    assert_eq!(dashes(light_highlight, false), 0);
    f.view.techniques_mut().set_dashed_hidden_lines(false);

    // The highlight: tint towards green, then a green band 5 pixels wide.
    f.view
        .techniques_mut()
        .set_shade_mode(ShadeMode::Solid)
        .unwrap();
    let orange_tint = *f.render().get_pixel(centre, row);
    f.view
        .renderer_mut()
        .set_palette(Palette {
            highlight: green,
            outline_width: 5,
            ..Palette::DEFAULT
        })
        .unwrap();
    let green_tint = *f.render().get_pixel(centre, row);
    assert!(
        green_tint.0[1] > orange_tint.0[1] + 20 && green_tint.0[0] + 40 < orange_tint.0[0],
        "tinted towards green: {green_tint:?}, towards orange: {orange_tint:?}"
    );
    f.view
        .renderer_mut()
        .set_highlight_style(HighlightStyle::Outline)
        .unwrap();
    let outlined = f.render();
    let last = (centre..SIZE.0)
        .take_while(|&x| !is(outlined.get_pixel(x, row), [0, 255, 0]))
        .last()
        .unwrap();
    let band = (last + 1..SIZE.0)
        .take_while(|&x| is(outlined.get_pixel(x, row), [0, 255, 0]))
        .count();
    assert_eq!(band, 5, "the band right of the cube is 5 pixels wide");

    // Out of range: refused, the last palette kept.
    let before = f.view.renderer().palette();
    for wrong in [
        Palette {
            outline_width: 9,
            ..before
        },
        Palette {
            edges: [0.0, -0.1, 0.0],
            ..before
        },
    ] {
        assert!(f.view.renderer_mut().set_palette(wrong).is_err());
        assert_eq!(f.view.renderer().palette(), before);
    }
    f.assert_no_validation_errors();
}
