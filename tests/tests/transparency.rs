//! Transparency: translucent materials blend over what is behind them whatever the order they
//! are drawn in, with the fast method (weighted-blended) and the exact one (per-pixel-lists)
//! agreeing where layers do not pile up; every technique combination draws translucency like
//! the built-in one; X-ray shows what is hidden and keeps highlighted parts opaque; glTF's
//! alphaMode gives materials their opacity and survives a save.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use cadr_core::load::load_file;
use cadr_core::render::{Camera, FrameStats};
use cadr_core::save::save_scene;
use cadr_core::scene::{AlphaMode, Geometry, Material, MeshRef, Node, Part, Scene, Vertex};
use cadr_core::technique::{Combination, ShadeMode, TechniqueKind};
use cadr_tests::images::{
    assert_matches_reference, compare, Tolerance, DEFAULT_TOLERANCE, SAME_PICTURE,
};
use cadr_tests::{
    all_combinations, scene_wide, test_device_with_synchronization_checks as test_device, SceneView,
};
use glam::{DMat4, DVec3};

const SIZE: (u32, u32) = (160, 120);

/// The exact method against the fast one where at most two layers overlap: the weighted
/// average of two colours differs from their order in the overlap only.
const METHODS_AGREE: Tolerance = Tolerance {
    mean: 0.02,
    p99: 0.35,
};

/// A square in the z = 0 plane from -1 to 1, facing +z.
fn square() -> Geometry {
    let vertices = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]
        .map(|[x, y]| Vertex {
            position: [x, y, 0.0],
            normal: [0.0, 0.0, 1.0],
        })
        .to_vec();
    Geometry {
        name: "square".into(),
        vertices,
        indices: vec![0, 1, 2, 0, 2, 3],
        wire_indices: Vec::new(),
        parts: vec![Part {
            first_index: 0,
            index_count: 6,
            first_wire_index: 0,
            wire_index_count: 0,
        }],
        attributes: Vec::new(),
    }
}

fn material(name: &str, base_color: [f32; 4]) -> Material {
    Material {
        name: name.into(),
        base_color,
        metallic: 0.0,
        roughness: 1.0,
        ..Material::default()
    }
}

/// Seen from +z: a large opaque red square at z = -1, a blue one at z = 0 (left of centre) and
/// a green one at z = 0.5 (right of centre), overlapping in the middle; blue and green have
/// opacity `alpha`.
fn layers(alpha: f32) -> Scene {
    let mut scene = Scene {
        name: "layers".into(),
        geometries: vec![square()],
        materials: vec![
            material("red", [0.8, 0.1, 0.1, 1.0]),
            material("blue", [0.1, 0.2, 0.9, alpha]),
            material("green", [0.1, 0.8, 0.2, alpha]),
        ],
        ..Scene::default()
    };
    let places = [
        (DVec3::new(0.0, 0.0, -1.0), 2.0, 0),
        (DVec3::new(-0.4, 0.0, 0.0), 0.6, 1),
        (DVec3::new(0.4, 0.0, 0.5), 0.6, 2),
    ];
    for (i, (place, scale, material)) in places.into_iter().enumerate() {
        let mut node = Node::new(format!("square {i}"));
        node.local = DMat4::from_translation(place) * DMat4::from_scale(DVec3::splat(scale));
        node.mesh = Some(MeshRef::new(0, vec![material]));
        scene.nodes.push(node);
        scene.roots.push(i as u32);
    }
    scene
}

/// A [`SceneView`] of the layers, seen from the front.
fn layers_view(scene: &Scene) -> SceneView {
    let aspect = f64::from(SIZE.0) / f64::from(SIZE.1);
    let camera = Camera::look_at(
        DVec3::new(0.0, 0.0, 5.0),
        DVec3::ZERO,
        40.0,
        aspect,
        0.1,
        50.0,
    );
    SceneView::new(test_device(), scene, SIZE, camera)
}

/// The helpers of these tests on a [`SceneView`] of the layers.
trait LayersView {
    /// Draws a frame and returns what it cost and drew.
    fn stats(&mut self) -> FrameStats;
    fn use_method(&mut self, name: &str);
    /// The picture with square `node` hidden.
    fn without(&mut self, node: u32) -> image::RgbaImage;
}

impl LayersView for SceneView {
    fn stats(&mut self) -> FrameStats {
        self.tree.update(&mut self.graph);
        self.view
            .render(&self.graph, &mut self.tree, &self.camera)
            .unwrap()
    }

    fn use_method(&mut self, name: &str) {
        self.view
            .techniques_mut()
            .swap(TechniqueKind::Transparency, name)
            .unwrap();
    }

    fn without(&mut self, node: u32) -> image::RgbaImage {
        let handle = self.nodes[node as usize];
        let mut flags = self.graph.node(handle).unwrap().flags;
        flags.visible = false;
        self.graph.set_flags(handle, flags).unwrap();
        let image = self.render();
        flags.visible = true;
        self.graph.set_flags(handle, flags).unwrap();
        image
    }
}

/// `a` over `b` with opacity `alpha`, per channel.
fn over(a: [f32; 3], alpha: f32, b: [f32; 3]) -> [f32; 3] {
    [0, 1, 2].map(|i| a[i] * alpha + b[i] * (1.0 - alpha))
}

fn assert_close(what: &str, got: [f32; 3], expected: [f32; 3], tolerance: f32) {
    let worst = (0..3)
        .map(|i| (got[i] - expected[i]).abs())
        .fold(0.0, f32::max);
    assert!(
        worst <= tolerance,
        "{what}: {got:?}, expected {expected:?} (within {tolerance})"
    );
}

/// Only blue over red (left), only green over red (right), both over red (middle).
const LEFT: DVec3 = DVec3::new(-0.75, 0.0, 0.0);
const MIDDLE: DVec3 = DVec3::new(0.0, 0.0, 0.0);

#[test]
fn one_translucent_layer_blends_over_what_is_behind_it_with_either_method() {
    // The colours each square shades to, opaque, and the red behind.
    let mut opaque = layers_view(&layers(1.0));
    let opaque_image = opaque.render();
    let blue = opaque.color_at(&opaque_image, LEFT);
    let behind = opaque.without(1);
    let red = opaque.color_at(&behind, LEFT);
    assert!(blue[2] > 0.5 && red[0] > 0.5, "blue {blue:?}, red {red:?}");

    let mut f = layers_view(&layers(0.5));
    for method in ["weighted-blended", "per-pixel-lists"] {
        f.use_method(method);
        let image = f.render();
        assert_close(
            &format!("{method}: blue at opacity 0.5 over red"),
            f.color_at(&image, LEFT),
            over(blue, 0.5, red),
            3.0 / 255.0,
        );
    }
    opaque.assert_no_validation_errors();
    f.assert_no_validation_errors();
}

#[test]
fn the_exact_method_sorts_layers_and_the_fast_one_agrees_where_they_do_not_pile_up() {
    let mut opaque = layers_view(&layers(1.0));
    let front = opaque.render();
    let green = opaque.color_at(&front, MIDDLE);
    let behind = opaque.without(2);
    let blue = opaque.color_at(&behind, MIDDLE);
    let red = opaque.color_at(&layers_view(&layers(0.0)).render(), MIDDLE);
    let mut f = layers_view(&layers(0.5));
    f.use_method("per-pixel-lists");
    let exact = f.render();
    // Green is in front: green over (blue over red), whatever the order they were drawn in.
    assert_close(
        "per-pixel-lists: green over blue over red",
        f.color_at(&exact, MIDDLE),
        over(green, 0.5, over(blue, 0.5, red)),
        4.0 / 255.0,
    );
    f.use_method("weighted-blended");
    let fast = f.render();
    // The fast method averages the two layers' colours by weight: their coverage is exact.
    let difference = compare(&fast, &exact).unwrap();
    assert!(
        difference.within(METHODS_AGREE),
        "the methods agree within {METHODS_AGREE:?}: {difference:?}"
    );
    opaque.assert_no_validation_errors();
    f.assert_no_validation_errors();
}

#[test]
fn every_valid_combination_draws_translucency_like_the_built_in_one() {
    let mut f = layers_view(&layers(0.5));
    let combinations = all_combinations(f.view.techniques().registry());
    let mut checked = 0;
    for method in ["weighted-blended", "per-pixel-lists"] {
        let built_in = Combination {
            transparency: method.into(),
            ..Combination::built_in()
        };
        f.view.techniques_mut().select(&built_in).unwrap();
        let reference = f.render();
        // A sample (every fifth): the translucent pass goes through the submissions' and
        // cullers' code for triangles, which the display-mode tests cover in full.
        for combination in combinations.iter().skip(checked % 5).step_by(5) {
            let combination = Combination {
                transparency: method.into(),
                ..combination.clone()
            };
            if f.view.techniques().check(&combination).is_err() {
                continue;
            }
            f.view.techniques_mut().select(&combination).unwrap();
            let image = f.render();
            let difference = compare(&image, &reference).unwrap();
            assert!(
                difference.within(DEFAULT_TOLERANCE),
                "{combination}: {difference:?}"
            );
            checked += 1;
        }
    }
    assert!(checked > 20, "{checked} combinations checked");
    f.assert_no_validation_errors();
}

#[test]
fn an_opaque_scene_draws_no_translucent_pass() {
    let mut f = layers_view(&layers(1.0));
    f.render();
    let opaque = f.stats();
    let mut translucent = layers_view(&layers(0.5));
    translucent.render();
    let stats = translucent.stats();
    assert_eq!(opaque.draw_calls, 3, "one pass of three squares");
    assert_eq!(
        stats.draw_calls, 3,
        "with translucent squares, the opaque pass draws the red one and the translucent \
         pass the other two"
    );
}

/// Combinations that draw in each way a submission can: direct calls, indirect commands,
/// recorded once and replayed, recorded on threads, and commands a GPU culler writes.
fn one_per_way_of_drawing() -> Vec<Combination> {
    vec![
        Combination::built_in(),
        scene_wide("individual-indirect-count", "none"),
        scene_wide("groups-mdi-replay", "none"),
        scene_wide("individual-threads", "frustum"),
        scene_wide("individual-indirect-count", "gpu-frustum"),
        scene_wide("individual-indirect-count", "gpu-occlusion"),
    ]
}

#[test]
fn each_pass_draws_only_the_parts_it_needs() {
    let mut f = layers_view(&layers(0.5));
    let reference = f.render();
    let mut xray_reference = None;
    let blue = (0..3)
        .filter_map(|i| f.graph.material_handle_at(i))
        .find(|&m| f.graph.material(m).unwrap().name == "blue")
        .unwrap();
    for combination in one_per_way_of_drawing() {
        f.view.techniques_mut().check(&combination).unwrap();
        f.view.techniques_mut().select(&combination).unwrap();
        // Red is opaque, blue and green translucent: each drawn in one pass only.
        assert_eq!(f.steady_draws(), 3, "{combination}: translucent scene");
        let image = f.render();
        let difference = compare(&image, &reference).unwrap();
        assert!(
            difference.within(SAME_PICTURE),
            "{combination}: {difference:?}"
        );

        // Blue made opaque moves to the opaque pass; back, and it returns.
        let mut material = f.graph.material(blue).unwrap().clone();
        material.base_color[3] = 1.0;
        f.graph.set_material(blue, material.clone()).unwrap();
        assert_eq!(f.steady_draws(), 3, "{combination}: blue made opaque");
        let opaque_blue = f.render();
        let hidden = f.without(0);
        assert_close(
            &format!("{combination}: an opaque blue square hides the red one"),
            f.color_at(&opaque_blue, LEFT),
            f.color_at(&hidden, LEFT),
            2.0 / 255.0,
        );
        material.base_color[3] = 0.5;
        f.graph.set_material(blue, material).unwrap();
        let again = f.render();
        let difference = compare(&again, &reference).unwrap();
        assert!(
            difference.within(SAME_PICTURE),
            "{combination}: {difference:?}"
        );

        // X-ray with the red square highlighted: the opaque pass draws it alone, the edge
        // lines (the squares' borders) every part, and the translucent pass every other part.
        f.view
            .techniques_mut()
            .set_shade_mode(ShadeMode::XRay)
            .unwrap();
        let red = f.nodes[0];
        let mut flags = f.graph.node(red).unwrap().flags;
        flags.highlighted = true;
        f.graph.set_flags(red, flags).unwrap();
        assert_eq!(f.steady_draws(), 1 + 3 + 2, "{combination}: X-ray");
        let xray = f.render();
        let xray_reference = xray_reference.get_or_insert_with(|| xray.clone());
        let difference = compare(&xray, xray_reference).unwrap();
        assert!(
            difference.within(SAME_PICTURE),
            "{combination}: {difference:?}"
        );
        // A highlighted part with a translucent material stays in the translucent pass.
        let blue_node = f.nodes[1];
        let mut blue_flags = f.graph.node(blue_node).unwrap().flags;
        blue_flags.highlighted = true;
        f.graph.set_flags(blue_node, blue_flags).unwrap();
        assert_eq!(
            f.steady_draws(),
            1 + 3 + 2,
            "{combination}: X-ray, translucent blue highlighted"
        );
        blue_flags.highlighted = false;
        f.graph.set_flags(blue_node, blue_flags).unwrap();
        flags.highlighted = false;
        f.graph.set_flags(red, flags).unwrap();
        f.view
            .techniques_mut()
            .set_shade_mode(ShadeMode::Solid)
            .unwrap();
    }
    f.assert_no_validation_errors();
}

#[test]
fn xray_shows_hidden_parts_and_keeps_highlighted_ones_opaque() {
    let mut f = layers_view(&layers(1.0));
    let solid = f.render();
    let blue = f.color_at(&solid, LEFT);
    f.view
        .techniques_mut()
        .set_shade_mode(ShadeMode::XRay)
        .unwrap();
    let xray = f.render();
    let seen = f.color_at(&xray, LEFT);
    assert!(
        seen[0] > blue[0] + 0.1,
        "the red square behind the blue one shows through: {seen:?} against {blue:?}"
    );
    // Highlight the blue square: it hides the red one again (tinted, and opaque).
    let handle = f.nodes[1];
    let mut flags = f.graph.node(handle).unwrap().flags;
    flags.highlighted = true;
    f.graph.set_flags(handle, flags).unwrap();
    let highlighted = f.render();
    let hidden = f.without(0);
    let without_red = f.color_at(&hidden, LEFT);
    assert_close(
        "a highlighted part stays opaque in X-ray",
        f.color_at(&highlighted, LEFT),
        without_red,
        2.0 / 255.0,
    );
    assert_matches_reference("transparency_layers_xray", &highlighted, DEFAULT_TOLERANCE);
    f.assert_no_validation_errors();
}

#[test]
fn hidden_line_shows_the_lines_behind_translucent_surfaces() {
    // The blue square's right border (x = 0.2) lies behind the green square. Opaque, green
    // hides it in the hidden-line mode; translucent, green is glass and the line shows.
    let behind_green = DVec3::new(0.2, 0.0, 0.0);
    let line_behind_green = |alpha: f32| {
        let mut f = layers_view(&layers(alpha));
        f.view
            .techniques_mut()
            .set_shade_mode(ShadeMode::HiddenLine)
            .unwrap();
        let image = f.render();
        let darkest = f.darkest_around(&image, behind_green);
        f.assert_no_validation_errors();
        darkest
    };
    let through_opaque = line_behind_green(1.0);
    assert!(through_opaque > 0.5, "hidden: {through_opaque}");
    let through_glass = line_behind_green(0.5);
    assert!(through_glass < 0.3, "shown: {through_glass}");
}

#[test]
fn gltf_alpha_modes_give_materials_their_opacity_and_survive_a_save() {
    let dir = std::env::temp_dir().join(format!("cadr-alpha-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("layers.gltf");
    let mut scene = layers(0.4);
    scene
        .materials
        .push(material("masked", [0.5, 0.5, 0.5, 0.4]));
    scene.materials.push(material("cut", [0.5, 0.5, 0.5, 0.4]));
    save_scene(&scene, &path).unwrap();
    let saved = load_file(&path).unwrap();
    let alphas: Vec<f32> = saved.materials.iter().map(|m| m.base_color[3]).collect();
    assert_eq!(alphas, [1.0, 0.4, 0.4, 0.4, 0.4], "BLEND keeps the opacity");
    let translucent: Vec<bool> = saved
        .materials
        .iter()
        .map(|m| m.is_translucent(|_| false))
        .collect();
    assert_eq!(translucent, [false, true, true, true, true]);

    // The same file with other modes: OPAQUE makes alpha 1; MASK keeps the factor's alpha,
    // which the shaders compare with the cutoff (default 0.5); neither is translucent.
    let text = std::fs::read_to_string(&path).unwrap();
    let mut modes = [
        r#""alphaMode":"OPAQUE""#,
        r#""alphaMode":"BLEND""#,
        r#""alphaMode":"OPAQUE""#,
        r#""alphaMode":"MASK","alphaCutoff":0.3"#,
        r#""alphaMode":"MASK""#,
    ]
    .into_iter();
    let compact: String = text.split_whitespace().collect::<Vec<_>>().join("");
    let rewritten: Vec<String> = compact
        .split(r#""alphaMode":"#)
        .enumerate()
        .map(|(i, piece)| {
            if i == 0 {
                return piece.to_owned();
            }
            // Drop the old value ("OPAQUE" or "BLEND") and put the next mode in.
            let rest = piece.split_once(',').map_or("", |(_, rest)| rest);
            format!("{},{rest}", modes.next().unwrap())
        })
        .collect();
    std::fs::write(&path, rewritten.concat()).unwrap();
    let modes = load_file(&path).unwrap();
    let alphas: Vec<f32> = modes.materials.iter().map(|m| m.base_color[3]).collect();
    assert_eq!(alphas, [1.0, 0.4, 1.0, 0.4, 0.4]);
    let loaded: Vec<AlphaMode> = modes.materials.iter().map(|m| m.alpha_mode).collect();
    assert_eq!(
        loaded,
        [
            AlphaMode::Opaque,
            AlphaMode::Blend,
            AlphaMode::Opaque,
            AlphaMode::Mask { cutoff: 0.3 },
            AlphaMode::Mask { cutoff: 0.5 }
        ]
    );
    let translucent: Vec<bool> = modes
        .materials
        .iter()
        .map(|m| m.is_translucent(|_| false))
        .collect();
    assert_eq!(translucent, [false, true, false, false, false]);
    // Saved again, every mode survives.
    save_scene(&modes, &path).unwrap();
    let again: Vec<AlphaMode> = load_file(&path)
        .unwrap()
        .materials
        .iter()
        .map(|m| m.alpha_mode)
        .collect();
    assert_eq!(again, loaded);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Picking sees a translucent part in front by default and, asked to, goes through it to the
/// opaque one behind; the picture does not change; an opaque part in front stops it either way.
#[test]
fn picking_goes_through_translucent_parts_when_asked() {
    let mut f = layers_view(&layers(0.5));
    let picture = f.render();
    let pick_at = |f: &mut SceneView, point: DVec3| {
        let hits = f.pick_at(point);
        assert_eq!(hits.len(), 1, "one hit at {point}");
        hits[0].path.clone()
    };
    // Left of centre only the blue square (z = 0) is in front of the red one (z = -1).
    let blue_point = DVec3::new(-0.7, 0.0, 0.0);
    assert!(!f.view.techniques().pick_through_translucent());
    let picked = pick_at(&mut f, blue_point);
    assert!(picked.contains(&f.nodes[1]), "blue is seen, so picked");
    f.view.techniques_mut().set_pick_through_translucent(true);
    let picked = pick_at(&mut f, blue_point);
    assert!(picked.contains(&f.nodes[0]), "through blue to red");
    assert_eq!(f.render(), picture, "the picture is the same");
    // Made opaque, the green square stops the click again.
    let mut opaque = layers(0.5);
    opaque.materials[2].base_color[3] = 1.0;
    let mut g = layers_view(&opaque);
    g.view.techniques_mut().set_pick_through_translucent(true);
    let green_point = DVec3::new(0.7, 0.0, 0.5);
    let picked = pick_at(&mut g, green_point);
    assert!(picked.contains(&g.nodes[2]), "opaque green stops the click");
    f.assert_no_validation_errors();
    g.assert_no_validation_errors();
}
