//! Section planes: what a plane cuts away is neither drawn nor picked, cuts through closed parts
//! are capped with the plane's colour where the cut is, cuts through open parts are not, every
//! technique combination draws the same section, and a cut far from the origin is as exact as
//! one at the origin.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use cadr_core::generate::{generate, GeneratorSpec};
use cadr_core::render::{Camera, Section, DEFAULT_DIRECTION};
use cadr_core::scene::{flatten, Material, MeshRef, Node, Scene};
use cadr_core::technique::ShadeMode;
use cadr_core::view::unproject;
use cadr_tests::fixtures::unit_box;
use cadr_tests::images::{assert_matches_reference, compare, DEFAULT_TOLERANCE, SAME_PICTURE};
use cadr_tests::{all_combinations, scene_wide, test_device, SceneView};
use glam::{DMat4, DVec3, DVec4};

const SIZE: (u32, u32) = (160, 120);
const EYE: DVec3 = DVec3::new(3.0, 2.5, 4.0);

/// Boxes at `places`, gray, the first geometry closed or open.
fn boxes(open: bool, places: &[DVec3]) -> Scene {
    let mut scene = Scene {
        name: "boxes".into(),
        geometries: vec![unit_box(open)],
        materials: vec![Material {
            name: "gray".into(),
            base_color: [0.5, 0.5, 0.5, 1.0],
            metallic: 0.0,
            roughness: 0.8,
            ..Material::default()
        }],
        ..Scene::default()
    };
    for (i, place) in places.iter().enumerate() {
        let mut node = Node::new(format!("box {i}"));
        node.local = DMat4::from_translation(*place);
        node.mesh = Some(MeshRef::new(0, vec![0]));
        scene.nodes.push(node);
        scene.roots.push(i as u32);
    }
    scene
}

/// A [`SceneView`] of `scene` seen from `EYE + offset`, looking at `offset`.
fn looking_at_the_origin(scene: &Scene, offset: DVec3) -> SceneView {
    let aspect = f64::from(SIZE.0) / f64::from(SIZE.1);
    let camera = Camera::look_at(EYE + offset, offset, 40.0, aspect, 0.1, 100.0);
    SceneView::new(test_device(), scene, SIZE, camera)
}

/// The section helper of these tests on a [`SceneView`].
trait SectionView {
    /// Cuts the view with `planes`, capped or not.
    fn section(&mut self, planes: &[DVec4], caps: bool);
}

impl SectionView for SceneView {
    fn section(&mut self, planes: &[DVec4], caps: bool) {
        let mut section = Section::none();
        section.set_planes(planes).unwrap();
        section.set_caps(caps);
        self.view.set_section(section);
    }
}

fn reddish([r, g, b]: [f32; 3]) -> bool {
    r - g > 0.25 && r - b > 0.25
}

fn bluish([r, g, b]: [f32; 3]) -> bool {
    b - r > 0.25 && b - g > 0.1
}

fn grayish([r, g, b]: [f32; 3]) -> bool {
    (r - g).abs() < 0.05 && (g - b).abs() < 0.05 && r > 0.1
}

/// Keeps z <= 0: cuts the front half of a box seen from `EYE` away.
const KEEP_BELOW_Z0: DVec4 = DVec4::new(0.0, 0.0, -1.0, 0.0);

#[test]
fn a_cut_through_a_closed_box_is_capped_with_the_plane_colour_where_the_cut_is() {
    let mut f = looking_at_the_origin(&boxes(false, &[DVec3::ZERO]), DVec3::ZERO);
    let whole = f.render();
    let on_cap = DVec3::new(0.3, 0.3, 0.0);
    assert!(grayish(f.color_at(&whole, on_cap)), "the box uncut is gray");

    f.section(&[KEEP_BELOW_Z0], true);
    let cut = f.render();
    assert!(
        reddish(f.color_at(&cut, on_cap)),
        "the cap has the first plane's colour: {:?}",
        f.color_at(&cut, on_cap)
    );
    // The cap ends where the box does: just inside its edge at x = 1 the cap, just outside the
    // box's kept +x side.
    let inside = DVec3::new(0.9, 0.0, 0.0);
    let outside = DVec3::new(1.1, 0.0, 0.0);
    assert!(
        reddish(f.color_at(&cut, inside)),
        "{:?}",
        f.color_at(&cut, inside)
    );
    assert!(
        grayish(f.color_at(&cut, outside)),
        "{:?}",
        f.color_at(&cut, outside)
    );

    // Each plane has a colour of its own, which the host may change.
    let mut section = f.view.section().clone();
    assert!(section.set_cap_color(0, [0.1, 0.2, 0.9, 1.0]));
    f.view.set_section(section);
    let blue = f.render();
    assert!(
        bluish(f.color_at(&blue, on_cap)),
        "{:?}",
        f.color_at(&blue, on_cap)
    );

    // Without caps the inside shows, shaded as it is.
    f.section(&[KEEP_BELOW_Z0], false);
    let uncapped = f.render();
    assert!(
        grayish(f.color_at(&uncapped, on_cap)),
        "{:?}",
        f.color_at(&uncapped, on_cap)
    );
    f.assert_no_validation_errors();
}

/// A cut part standing on another: the cut box's bottom face, which the cap is found on, lies
/// in the plate's top face; the cap covers the whole cut all the same, in every mode that
/// draws caps and with MSAA, and the plate around it keeps its colour.
#[test]
fn a_cut_part_standing_on_another_is_capped_over_the_whole_cut() {
    let mut scene = boxes(false, &[DVec3::ZERO]);
    // A plate of the same box, 10 × 10 × 0.2, its top face at the box's bottom (z = -1).
    let mut plate = Node::new("plate");
    plate.local = DMat4::from_translation(DVec3::new(0.0, 0.0, -1.1))
        * DMat4::from_scale(DVec3::new(5.0, 5.0, 0.1));
    plate.mesh = Some(MeshRef::new(0, vec![0]));
    scene.nodes.push(plate);
    scene.roots.push(1);
    let mut f = looking_at_the_origin(&scene, DVec3::ZERO);
    f.section(&[KEEP_BELOW_Z0], true);
    // Points of the cut, over the box's bottom face, and of the plate's top around the box.
    let grid = |z: f64, extent: f64| -> Vec<DVec3> {
        (0..9)
            .flat_map(|i| (0..9).map(move |j| (i, j)))
            .map(|(i, j)| {
                let at = |k: i32| -extent + 2.0 * extent * f64::from(k) / 8.0;
                DVec3::new(at(i), at(j), z)
            })
            .collect()
    };
    let on_cut = grid(0.0, 0.9);
    let in_view = |p: &DVec3| {
        let (x, y) = cadr_tests::images::pixel_of(&f.camera, SIZE, *p);
        x < SIZE.0 && y < SIZE.1
    };
    let on_plate: Vec<DVec3> = grid(-1.0, 3.0)
        .into_iter()
        // On the eye's side of the box, which hides the plate beyond it.
        .filter(|p| (p.x > 1.2 || p.y > 1.2) && in_view(p))
        .collect();
    assert!(
        on_plate.len() >= 10,
        "{} points of the plate",
        on_plate.len()
    );
    for samples in [1, 4] {
        f.view.renderer_mut().set_msaa(samples).unwrap();
        for mode in [ShadeMode::Solid, ShadeMode::Edges, ShadeMode::HiddenLine] {
            f.view.techniques_mut().set_shade_mode(mode).unwrap();
            let cut = f.render();
            let uncapped: Vec<_> = on_cut
                .iter()
                .filter(|&&p| !reddish(f.color_at(&cut, p)))
                .map(|&p| (p.x, p.y, f.color_at(&cut, p)))
                .collect();
            assert!(
                uncapped.is_empty(),
                "{samples}x {mode:?}: {} of {} points of the cut show no cap: {:?}",
                uncapped.len(),
                on_cut.len(),
                &uncapped[..uncapped.len().min(4)]
            );
            let leaks: Vec<_> = on_plate
                .iter()
                .filter(|&&p| reddish(f.color_at(&cut, p)))
                .collect();
            assert!(
                leaks.is_empty(),
                "{samples}x {mode:?}: the cap shows on the plate at {leaks:?}"
            );
        }
    }
    // A click anywhere on the cut hits the box's cap, on the plane, as the picture shows (the
    // plate's top, the only other surface there, lies at z = -1).
    f.tree.update(&mut f.graph);
    let missed: Vec<(DVec3, Option<DVec3>)> = on_cut
        .iter()
        .map(|&p| (p, f.pick_at(p).first().map(|hit| hit.position)))
        .filter(|(_, at)| !matches!(at, Some(at) if at.z.abs() < 1e-3))
        .collect();
    assert!(
        missed.is_empty(),
        "{} of {} clicks on the cut miss the cap (point, position hit): {:?}",
        missed.len(),
        on_cut.len(),
        &missed[..missed.len().min(4)]
    );
    f.assert_no_validation_errors();
}

#[test]
fn a_cap_hides_the_lines_of_the_far_faces_it_is_painted_on() {
    // Seen from EYE through the cut at z = 0, the cap lies over the box's far faces: the crease
    // where its -x and -y faces meet, and the edge between its -x and -z faces.
    let behind_cap = [DVec3::new(-1.0, -1.0, -0.5), DVec3::new(-1.0, 0.0, -1.0)];
    // The crease between the kept +x and +y faces is in front of everything.
    let near_crease = DVec3::new(1.0, 1.0, -0.5);
    // Hidden-line also with its hidden lines dashed: a cut face hides them, as a section view
    // in a drawing omits them.
    let modes = [
        (ShadeMode::Edges, false),
        (ShadeMode::HiddenLine, false),
        (ShadeMode::HiddenLine, true),
    ];
    for (mode, dashed) in modes {
        let mut f = looking_at_the_origin(&boxes(false, &[DVec3::ZERO]), DVec3::ZERO);
        f.view.techniques_mut().set_shade_mode(mode).unwrap();
        f.view.techniques_mut().set_dashed_hidden_lines(dashed);
        f.section(&[KEEP_BELOW_Z0], true);
        let capped = f.render();
        for point in behind_cap {
            let color = f.color_at(&capped, point);
            assert!(
                reddish(color),
                "{mode:?} (dashed: {dashed}): the cap at {point}: {color:?}"
            );
            let darkest = f.darkest_around(&capped, point);
            assert!(
                darkest > 0.3,
                "{mode:?} (dashed: {dashed}): no line shows through the cap at {point} (darkest {darkest})"
            );
        }
        assert!(
            f.darkest_around(&capped, near_crease) < 0.3,
            "{mode:?} (dashed: {dashed}): the lines in front of the cut still show"
        );
        // Without caps the cut box is seen from inside, its far faces' lines with it.
        f.section(&[KEEP_BELOW_Z0], false);
        let uncapped = f.render();
        for point in behind_cap {
            let darkest = f.darkest_around(&uncapped, point);
            assert!(
                darkest < 0.3,
                "{mode:?} (dashed: {dashed}): uncapped, the line at {point} shows (darkest {darkest})"
            );
        }
        f.assert_no_validation_errors();
    }
}

#[test]
fn the_caps_pass_draws_only_closed_parts() {
    // A closed box at the origin, an open one beside it, both cut; edges mode, where caps
    // are painted again over the lines in a pass of their own.
    let mut scene = boxes(false, &[DVec3::ZERO, DVec3::new(0.0, -3.0, 0.0)]);
    scene.geometries.push(unit_box(true));
    scene.nodes[1].mesh = Some(MeshRef::new(1, vec![0]));
    let mut f = looking_at_the_origin(&scene, DVec3::ZERO);
    f.view
        .techniques_mut()
        .set_shade_mode(ShadeMode::Edges)
        .unwrap();
    // The surfaces and the (feature) edge lines of both boxes.
    assert_eq!(f.steady_draws(), 2 + 2, "uncut");
    f.section(&[KEEP_BELOW_Z0], false);
    assert_eq!(f.steady_draws(), 2 + 2, "cut, no caps");
    f.section(&[KEEP_BELOW_Z0], true);
    let capped = f.render();
    assert_eq!(
        f.steady_draws(),
        2 + 2 + 1,
        "the caps pass draws the closed box only"
    );
    let on_cap = DVec3::new(0.3, 0.3, 0.0);
    assert!(reddish(f.color_at(&capped, on_cap)), "capped");
    f.assert_no_validation_errors();
}

#[test]
fn cullers_cull_what_a_plane_cuts_away_and_gpu_cullers_cap_only_what_it_cuts() {
    // Box 0 is cut by the plane z = 0, box 1 lies wholly on the kept side, box 2 wholly on the
    // side cut away. Edges mode with caps: surfaces, edge lines, and the caps pass.
    let places = [
        DVec3::ZERO,
        DVec3::new(-2.5, 0.0, -2.5),
        DVec3::new(2.5, 0.0, 2.5),
    ];
    let reference = {
        let mut f = looking_at_the_origin(&boxes(false, &places), DVec3::ZERO);
        f.view
            .techniques_mut()
            .set_shade_mode(ShadeMode::Edges)
            .unwrap();
        f.section(&[KEEP_BELOW_Z0], true);
        f.render()
    };
    // Per culler: draws uncut, and cut with caps. Without culling every box is drawn in every
    // pass; a CPU culler culls box 2 but its submission cannot tell which closed parts a plane
    // cuts; a GPU culler can, so its caps pass draws box 0 alone.
    let expected = [
        (
            scene_wide("individual-indirect-count", "none"),
            3 + 3,
            3 + 3 + 3,
        ),
        (
            scene_wide("individual-indirect-count", "frustum"),
            3 + 3,
            2 + 2 + 2,
        ),
        (
            scene_wide("individual-indirect-count", "gpu-frustum"),
            3 + 3,
            2 + 2 + 1,
        ),
        (
            scene_wide("individual-indirect-count", "gpu-occlusion"),
            3 + 3,
            2 + 2 + 1,
        ),
    ];
    for (combination, uncut, cut) in expected {
        let mut f = looking_at_the_origin(&boxes(false, &places), DVec3::ZERO);
        f.view.techniques_mut().select(&combination).unwrap();
        f.view
            .techniques_mut()
            .set_shade_mode(ShadeMode::Edges)
            .unwrap();
        assert_eq!(f.steady_draws(), uncut, "{combination}: uncut");
        f.section(&[KEEP_BELOW_Z0], true);
        assert_eq!(f.steady_draws(), cut, "{combination}: cut");
        let image = f.render();
        let difference = compare(&image, &reference).unwrap();
        assert!(
            difference.within(SAME_PICTURE),
            "{combination}: {difference:?}"
        );
        f.assert_no_validation_errors();
    }
}

#[test]
fn a_cut_through_an_open_mesh_shows_no_cap() {
    // Without its top face the box is open; the cut removes where that face was anyway, so
    // what remains is the closed box's remainder, but drawn without a cap.
    let mut f = looking_at_the_origin(&boxes(true, &[DVec3::ZERO]), DVec3::ZERO);
    f.section(&[KEEP_BELOW_Z0], true);
    let cut = f.render();
    let on_cap = DVec3::new(0.3, 0.3, 0.0);
    let color = f.color_at(&cut, on_cap);
    assert!(grayish(color), "no cap, no smear: {color:?}");
    f.assert_no_validation_errors();
}

#[test]
fn picking_through_a_cut_hits_what_is_behind() {
    // Box 0 at the origin, box 1 behind it on the line of sight.
    let behind = -EYE * 0.8;
    let mut f = looking_at_the_origin(&boxes(false, &[DVec3::ZERO, behind]), DVec3::ZERO);
    let pick = |f: &mut SceneView| {
        let hits = f.pick_at(DVec3::ZERO);
        let name = f.graph.node(hits[0].node).unwrap().name.clone();
        name.trim_end_matches(" geometry").to_owned()
    };
    assert_eq!(pick(&mut f), "box 0");
    // Keep what lies more than 2.2 beyond the origin along the view: box 0 is cut away whole.
    let away = -EYE.normalize();
    f.section(&[away.extend(-2.2)], true);
    assert_eq!(pick(&mut f), "box 1");
    f.assert_no_validation_errors();
}

#[test]
fn a_pick_on_a_cap_finds_the_cut_part_at_the_plane() {
    // The cap is where the plane cuts the box, so a pick there reports that point, not the
    // far face the cap is painted on; the hit's depth is the plane's too.
    let mut f = looking_at_the_origin(&boxes(false, &[DVec3::ZERO]), DVec3::ZERO);
    f.section(&[KEEP_BELOW_Z0], true);
    let on_cap = DVec3::new(0.3, 0.3, 0.0);
    let hits = f.pick_at(on_cap);
    assert_eq!(hits.len(), 1, "{hits:?}");
    let hit = &hits[0];
    assert!(hit.position.z.abs() < 1e-4, "on the plane z = 0: {hit:?}");
    assert!(
        (hit.position - on_cap).length() < 0.05,
        "within a pixel of the point picked: {hit:?}"
    );
    let size = f.view.renderer().size();
    let at_depth = unproject(&f.camera, size, hit.pixel, hit.depth);
    assert!(
        (at_depth - hit.position).length() < 1e-3,
        "the depth is the plane's: {at_depth} against {}",
        hit.position
    );
    // Without caps the cut is open and the pick finds the far face behind it.
    f.section(&[KEEP_BELOW_Z0], false);
    let open = f.pick_at(on_cap);
    assert!(open[0].position.z < -0.5, "{:?}", open[0]);
    f.assert_no_validation_errors();
}

#[test]
fn a_cut_far_from_the_origin_is_as_exact_as_one_at_the_origin() {
    // 10 000 km away, f32 world coordinates would round the plane by a metre; relative to
    // the eye in f64 the cut lands where it does at the origin.
    let far = DVec3::new(1.0e7, -3.0e6, 5.0e6);
    let plane = DVec4::new(0.6, 0.0, -0.8, 0.1);
    let far_plane = plane.truncate().extend(plane.w - plane.truncate().dot(far));
    let mut near_fixture = looking_at_the_origin(&boxes(false, &[DVec3::ZERO]), DVec3::ZERO);
    near_fixture.section(&[plane], true);
    let near_image = near_fixture.render();
    let mut far_fixture = looking_at_the_origin(&boxes(false, &[far]), far);
    far_fixture.section(&[far_plane], true);
    let far_image = far_fixture.render();
    let difference = compare(&far_image, &near_image).unwrap();
    assert!(difference.within(DEFAULT_TOLERANCE), "{difference:?}");
}

/// gen:demo cut by two planes, with edges, capped and hatched as the reference shows it.
fn demo_section(f: &mut SceneView) {
    let mut section = Section::none();
    section
        .set_planes(&[
            DVec4::new(0.0, -1.0, 0.0, 0.4),
            DVec4::new(-1.0, 0.0, -0.2, 14.0),
        ])
        .unwrap();
    section.set_hatched(true);
    f.view.set_section(section);
    f.view
        .techniques_mut()
        .set_shade_mode(ShadeMode::Edges)
        .unwrap();
}

fn demo_fixture() -> SceneView {
    let scene = generate(&GeneratorSpec::Demo);
    let bounds = flatten(&scene).unwrap().bounds;
    let camera = Camera::fit(
        &bounds,
        f64::from(SIZE.0) / f64::from(SIZE.1),
        DEFAULT_DIRECTION,
    );
    SceneView::new(test_device(), &scene, SIZE, camera)
}

#[test]
fn the_demo_section_matches_its_reference_in_every_sampled_combination() {
    let mut f = demo_fixture();
    demo_section(&mut f);
    let reference = f.render();
    assert_matches_reference("section_demo", &reference, DEFAULT_TOLERANCE);
    // Every third valid combination (a deterministic sample over all kinds), culled on the
    // CPU and on the GPU, draws the same section.
    let valid: Vec<_> = all_combinations(f.view.techniques().registry())
        .into_iter()
        .filter(|c| f.view.techniques().check(c).is_ok())
        .collect();
    let mut failures = Vec::new();
    let sampled: Vec<_> = valid.iter().step_by(3).collect();
    for combination in &sampled {
        f.view.techniques_mut().select(combination).unwrap();
        let image = f.render();
        let difference = compare(&image, &reference).unwrap();
        if !difference.within(SAME_PICTURE) {
            failures.push(format!("{combination}: {difference:?}"));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} differ:\n{}",
        failures.len(),
        sampled.len(),
        failures.join("\n")
    );
    assert!(sampled.iter().any(|c| c.culling.starts_with("gpu-")));
    println!(
        "{} of {} valid combinations sampled",
        sampled.len(),
        valid.len()
    );
    f.assert_no_validation_errors();
}
