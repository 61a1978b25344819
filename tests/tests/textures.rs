//! Textures, texture transforms, vertex colours and alpha modes, from glTF files to the
//! picture: a file of our own (`fixtures::textured_gltf`: a repeated checker with
//! `KHR_texture_transform`, an alpha mask, vertex colours, a translucent texture over a red
//! backdrop) and the Khronos samples Debian ships (TextureTransformTest, BoxTextured in three
//! containers); every vertex and parameter path samples them alike; picking goes through mask
//! holes; `--no-textures` turns them off; the graph's textures can change at run time.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::collections::HashSet;

use cadr_core::load::load_file;
use cadr_core::render::Camera;
use cadr_core::scene::{Material, Scene, Texture, TextureRef, UvTransform};
use cadr_core::technique::{Combination, ShadeMode};
use cadr_tests::fixtures::{give_texture, quad_scene, scratch_dir, textured, textured_gltf};
use cadr_tests::images::{
    assert_matches_reference, color_at, compare, DEFAULT_TOLERANCE, SAME_PICTURE,
};
use cadr_tests::{
    all_combinations, scene_wide, test_device, test_device_with_texture_array_only, SceneView,
};
use glam::DVec3;

const SIZE: (u32, u32) = (480, 480);
const TEXTURE_TRANSFORM_TEST: &str =
    "/usr/share/assimp/models/glTF2/textureTransform/TextureTransformTest.gltf";
const BOX_TEXTURED: [&str; 3] = [
    "/usr/share/assimp/models/glTF2/BoxTextured-glTF/BoxTextured.gltf",
    "/usr/share/assimp/models/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb",
    "/usr/share/assimp/models/glTF2/BoxTextured-glTF-Embedded/BoxTextured.gltf",
];

fn textured_scene(test: &str) -> Scene {
    let dir = scratch_dir(test);
    let scene = load_file(&textured_gltf(&dir)).unwrap_or_else(|e| panic!("{e}"));
    let _ = std::fs::remove_dir_all(&dir);
    scene
}

/// The textured fixture seen straight on.
fn front_view(scene: &Scene) -> SceneView {
    let bounds = cadr_core::scene::flatten(scene).unwrap().bounds;
    let camera = Camera::fit(&bounds, 1.0, DVec3::Z);
    SceneView::new(test_device(), scene, SIZE, camera)
}

fn point((x, y): (f64, f64), dx: f64, dy: f64) -> DVec3 {
    DVec3::new(x + dx, y + dy, 0.0)
}

/// The centre of cell (`i`, `j`) of the checker quad's texture: 16 cells across, counted from
/// its top left.
fn checker_cell_center(i: f64, j: f64) -> DVec3 {
    let half = textured::QUAD_SIZE / 2.0;
    let cell = textured::QUAD_SIZE / 16.0;
    point(
        textured::CHECKER,
        -half + cell * (i + 0.5),
        half - cell * (j + 0.5),
    )
}

fn brightness(c: [f32; 3]) -> f32 {
    c.iter().sum::<f32>() / 3.0
}

#[test]
fn the_textured_file_loads_its_textures_transforms_colours_and_alpha_modes() {
    let scene = textured_scene("load");
    assert_eq!(scene.textures.len(), 3);
    assert_eq!((scene.textures[0].width, scene.textures[0].height), (8, 8));
    assert!(scene.textures[0].sampler.magnify_nearest);
    assert!(!scene.textures[0].has_translucent_texels());
    assert!(scene.textures[2].has_translucent_texels());
    let checker = scene
        .materials
        .iter()
        .find(|m| m.name == "checker")
        .unwrap();
    let reference = checker.base_color_texture.expect("the checker's texture");
    assert_eq!(reference.transform.apply([0.5, 0.25]), [1.0, 0.5]);
    let blended = scene
        .materials
        .iter()
        .find(|m| m.name == "blended")
        .unwrap();
    assert!(blended.is_translucent(|t| scene.textures[t as usize].has_translucent_texels()));
    let with_colors = scene
        .geometries
        .iter()
        .find(|g| g.attributes.iter().any(|a| a.color == [255, 0, 0, 255]))
        .expect("the vertex-coloured quad");
    assert_eq!(with_colors.attributes.len(), with_colors.vertices.len());
}

/// What each quad shows: checker cells alternate, the mask cuts its left half (the red
/// backdrop shows), vertex colours blend from their corners, the translucent texture lets the
/// backdrop through; with textures off the checker is one colour, the mask cuts nothing and
/// the blend quad is opaque; the picture matches its references.
#[test]
fn textures_colours_and_alpha_reach_the_picture() {
    let scene = textured_scene("picture");
    let mut f = front_view(&scene);
    // Each part is drawn once, in the opaque pass or the translucent one.
    let parts = cadr_core::scene::flatten(&scene).unwrap().draws.len() as u64;
    assert_eq!(f.steady_draws(), parts, "textures on");
    let image = f.render();
    assert_matches_reference("textured_solid", &image, DEFAULT_TOLERANCE);
    let camera = f.camera;
    let at = |image: &image::RgbaImage, p: DVec3| color_at(image, &camera, p);
    let half = textured::QUAD_SIZE / 2.0;
    let cell_center = checker_cell_center;
    for (i, j) in [(3.0, 4.0), (8.0, 8.0), (12.0, 1.0)] {
        let (a, b) = (
            at(&image, cell_center(i, j)),
            at(&image, cell_center(i + 1.0, j)),
        );
        assert!(
            (brightness(a) - brightness(b)).abs() > 0.3,
            "cells ({i}, {j}) and the next differ: {a:?} {b:?}"
        );
        assert_eq!(
            at(&image, cell_center(i, j)).map(|c| (c * 20.0).round()),
            at(&image, cell_center(i + 2.0, j)).map(|c| (c * 20.0).round()),
            "every other cell is alike"
        );
    }
    // Mask: the left half is cut, the backdrop shows red; the right half is orange.
    let hole = at(&image, point(textured::MASKED, -half / 2.0, 0.0));
    let kept = at(&image, point(textured::MASKED, half / 2.0, 0.0));
    assert!(
        hole[0] > hole[1] + 0.4 && hole[0] > hole[2] + 0.4,
        "backdrop red in the hole: {hole:?}"
    );
    assert!(
        kept[0] > 0.7 && kept[1] > 0.35 && kept[2] < 0.2,
        "orange where kept: {kept:?}"
    );
    // Vertex colours: red, green and blue near their corners.
    let near = 0.8 * half;
    let red = at(&image, point(textured::VERTEX_COLORS, -near, near));
    let green = at(&image, point(textured::VERTEX_COLORS, near, near));
    let blue = at(&image, point(textured::VERTEX_COLORS, near, -near));
    assert!(red[0] > red[1] + 0.3 && red[0] > red[2] + 0.3, "{red:?}");
    assert!(
        green[1] > green[0] + 0.3 && green[1] > green[2] + 0.3,
        "{green:?}"
    );
    assert!(
        blue[2] > blue[0] + 0.3 && blue[2] > blue[1] + 0.3,
        "{blue:?}"
    );
    // The translucent blue lets the red backdrop through.
    let blended = at(&image, point(textured::BLENDED, 0.0, 0.0));
    assert!(
        blended[0] > 0.3 && blended[2] > 0.3,
        "blue over red: {blended:?}"
    );

    // X-ray: everything translucent, the mask still cuts.
    f.view
        .techniques_mut()
        .set_shade_mode(ShadeMode::XRay)
        .unwrap();
    let xray = f.render();
    assert_matches_reference("textured_xray", &xray, DEFAULT_TOLERANCE);
    let xray_hole = at(&xray, point(textured::MASKED, -half / 2.0, 0.0));
    let xray_kept = at(&xray, point(textured::MASKED, half / 2.0, 0.0));
    // Orange (no blue) at X-ray's opacity over the hole's faint backdrop.
    assert!(
        xray_kept[2] < xray_hole[2] - 0.08,
        "X-ray keeps the mask: {xray_hole:?} {xray_kept:?}"
    );

    // Textures off: the checker is one colour, nothing is cut, the blend quad is opaque white.
    f.view
        .techniques_mut()
        .set_shade_mode(ShadeMode::Solid)
        .unwrap();
    f.view.renderer_mut().set_textures(false);
    // Still once each: the quad translucent by its texture only is opaque now, drawn by the
    // opaque pass and by no translucent one.
    assert_eq!(f.steady_draws(), parts, "textures off");
    let plain = f.render();
    let (a, b) = (
        at(&plain, cell_center(3.0, 4.0)),
        at(&plain, cell_center(4.0, 4.0)),
    );
    assert!((brightness(a) - brightness(b)).abs() < 0.02, "{a:?} {b:?}");
    let uncut = at(&plain, point(textured::MASKED, -half / 2.0, 0.0));
    assert!(
        uncut[1] > 0.6 && uncut[2] > 0.6,
        "the mask quad is whole and white: {uncut:?}"
    );
    let opaque = at(&plain, point(textured::BLENDED, 0.0, 0.0));
    assert!(
        opaque.iter().all(|&c| c > 0.6),
        "white, not red-tinted: {opaque:?}"
    );
    // Vertex colours stay: they are not textures.
    assert_eq!(
        at(&plain, point(textured::VERTEX_COLORS, -near, near)),
        red,
        "vertex colours do not depend on textures"
    );
    // And back on: the first picture again.
    f.view.renderer_mut().set_textures(true);
    let again = f.render();
    assert!(compare(&again, &image).unwrap().within(SAME_PICTURE));
    f.assert_no_validation_errors();
}

/// The textured file in the display modes `textures_colours_and_alpha_reach_the_picture` does
/// not draw (solid and X-ray): each matches its reference; edges keeps the texture under its
/// lines, the line-only modes fill no surface, so no checker shows.
#[test]
fn the_textured_file_in_the_edge_and_line_modes_matches_its_references() {
    let scene = textured_scene("modes");
    let mut f = front_view(&scene);
    let camera = f.camera;
    let cells_apart = |image: &image::RgbaImage| {
        let at = |i, j| brightness(color_at(image, &camera, checker_cell_center(i, j)));
        (at(2.0, 5.0) - at(3.0, 5.0)).abs()
    };
    for mode in [
        ShadeMode::Edges,
        ShadeMode::HiddenLine,
        ShadeMode::Wireframe,
    ] {
        f.view.techniques_mut().set_shade_mode(mode).unwrap();
        let image = f.render();
        assert_matches_reference(
            &format!("textured_{}", mode.name().replace('-', "_")),
            &image,
            DEFAULT_TOLERANCE,
        );
        let apart = cells_apart(&image);
        if mode == ShadeMode::Edges {
            assert!(apart > 0.3, "edges: the checker shows: {apart}");
        } else {
            assert!(apart < 0.02, "{mode:?}: no checker: {apart}");
        }
    }
    f.assert_no_validation_errors();
}

/// A click in the mask's hole reaches the backdrop; beside it, it hits the masked quad.
#[test]
fn picking_goes_through_alpha_mask_holes() {
    let scene = textured_scene("pick");
    let mut f = front_view(&scene);
    let half = textured::QUAD_SIZE / 2.0;
    assert_eq!(
        f.material_picked_at(point(textured::MASKED, -half / 2.0, 0.0)),
        "backdrop"
    );
    assert_eq!(
        f.material_picked_at(point(textured::MASKED, half / 2.0, 0.0)),
        "masked"
    );
    assert_eq!(
        f.material_picked_at(point(textured::CHECKER, 0.0, 0.0)),
        "checker"
    );
    f.assert_no_validation_errors();
}

/// Every vertex path (each says where its vertices lie in its own way) with every parameter
/// path, and the GPU cullers, draw the textured file like the built-in combination.
#[test]
fn every_vertex_and_parameter_path_samples_textures_alike() {
    let scene = textured_scene("paths");
    let mut f = front_view(&scene);
    let reference = f.render();
    let built_in = Combination::built_in();
    let mut combinations: Vec<Combination> = all_combinations(f.view.techniques().registry())
        .into_iter()
        .filter(|c| c.submission == built_in.submission && c.culling == built_in.culling)
        .collect();
    for culling in ["gpu-frustum", "gpu-occlusion"] {
        combinations.push(scene_wide("individual-indirect-count", culling));
    }
    let valid: Vec<Combination> = combinations
        .into_iter()
        .filter(|c| f.view.techniques().check(c).is_ok())
        .collect();
    let mut checked = HashSet::new();
    for combination in &valid {
        f.view.techniques_mut().select(combination).unwrap();
        for mode in [ShadeMode::Solid, ShadeMode::XRay] {
            f.view.techniques_mut().set_shade_mode(mode).unwrap();
            let image = f.render();
            let expected = if mode == ShadeMode::Solid {
                reference.clone()
            } else {
                let mut built_in = front_view(&scene);
                built_in.view.techniques_mut().set_shade_mode(mode).unwrap();
                built_in.render()
            };
            let difference = compare(&image, &expected).unwrap();
            assert!(
                difference.within(SAME_PICTURE),
                "{combination} [{}]: {difference:?}",
                mode.name()
            );
        }
        f.view
            .techniques_mut()
            .set_shade_mode(ShadeMode::Solid)
            .unwrap();
        checked.insert(combination.vertex.clone());
    }
    assert!(checked.len() >= 4, "vertex paths checked: {checked:?}");
    f.assert_no_validation_errors();
}

/// Khronos' TextureTransformTest: each square shows "Correct" marks where offset, rotation,
/// scale and texCoord overrides are applied right; BoxTextured reads its image from a file, a
/// GLB buffer view and a data URI (the last two have the same samplers and draw alike; the
/// first wraps with MIRRORED_REPEAT and CLAMP_TO_EDGE and has a reference of its own).
#[test]
fn the_khronos_texture_samples_draw_as_their_references() {
    let scene = load_file(std::path::Path::new(TEXTURE_TRANSFORM_TEST)).unwrap();
    assert!(
        scene.materials.iter().any(|m| m
            .base_color_texture
            .is_some_and(|t| t.transform != UvTransform::IDENTITY)),
        "texture transforms read"
    );
    let mut f = front_view(&scene);
    let image = f.render();
    // Textures bound each at its own size (descriptor indexing) and as layers of one array
    // image (resampled to the largest texture's size) filter differently: by 0.013-0.015 FLIP
    // mean on this sample, beyond the tolerance, so each path has its reference.
    let reference = if f.device.capabilities().bindless_textures > 0 {
        "textured_transform_test"
    } else {
        "textured_transform_test_texture_array"
    };
    assert_matches_reference(reference, &image, DEFAULT_TOLERANCE);
    f.assert_no_validation_errors();

    let pictures: Vec<image::RgbaImage> = BOX_TEXTURED
        .iter()
        .map(|path| {
            let scene = load_file(std::path::Path::new(path)).unwrap();
            assert_eq!(scene.textures.len(), 1, "{path}");
            cadr_tests::render_scene(&scene, 320, 240)
        })
        .collect();
    assert_matches_reference("textured_box_gltf", &pictures[0], DEFAULT_TOLERANCE);
    assert_matches_reference("textured_box_glb", &pictures[1], DEFAULT_TOLERANCE);
    assert!(
        compare(&pictures[2], &pictures[1])
            .unwrap()
            .within(SAME_PICTURE),
        "{} draws like {}",
        BOX_TEXTURED[2],
        BOX_TEXTURED[1]
    );
}

/// A host adds a texture and a material using it at run time: the GPU scene rebuilds its
/// textures and the part shows it; the texture cannot be destroyed while the material uses
/// it.
#[test]
fn a_texture_created_at_run_time_reaches_the_picture() {
    let scene = textured_scene("runtime");
    let mut f = front_view(&scene);
    let before = f.render();
    let green = Texture {
        name: "green".into(),
        width: 2,
        height: 2,
        texels: std::sync::Arc::new([0u8, 200, 0, 255].repeat(4)),
        sampler: Default::default(),
    };
    let texture = f.graph.create_texture(green).unwrap();
    let material = f
        .graph
        .create_material(Material {
            name: "green texture".into(),
            base_color: [1.0; 4],
            base_color_texture: Some(TextureRef {
                texture: texture.index(),
                transform: UvTransform::IDENTITY,
            }),
            ..Material::default()
        })
        .unwrap();
    // The checker quad's Geo node gets the new material.
    let checker_node = f
        .graph
        .nodes()
        .find(|(_, n)| match &n.kind {
            cadr_core::graph::NodeKind::Geo { part_materials, .. } => {
                f.graph.material(part_materials[0]).unwrap().name == "checker"
            }
            _ => false,
        })
        .map(|(h, _)| h)
        .unwrap();
    f.graph
        .set_part_material(checker_node, 0, material)
        .unwrap();
    f.tree.update(&mut f.graph);
    let after = f.render();
    let center = point(textured::CHECKER, 0.0, 0.0);
    let now = color_at(&after, &f.camera, center);
    assert!(
        now[1] > now[0] + 0.3 && now[1] > now[2] + 0.3,
        "green: {now:?}"
    );
    assert_ne!(color_at(&before, &f.camera, center), now);
    let refused = f.graph.destroy_texture(texture).unwrap_err().to_string();
    assert!(
        refused.contains("texture 'green'") && refused.contains("still used"),
        "{refused}"
    );
    f.assert_no_validation_errors();
}

/// A TEXCOORD accessor with a count other than the positions' is refused naming it; an image
/// that cannot be decoded leaves its material untextured, and the file loads.
#[test]
fn bad_texture_data_is_refused_or_left_out_clearly() {
    let dir = scratch_dir("bad-textures");
    let path = textured_gltf(&dir);
    let json = std::fs::read_to_string(&path).unwrap();
    // The checker quad's TEXCOORD_0 accessor claims 3 elements.
    let broken = json.replacen(
        r#""componentType": 5126, "count": 4, "type": "VEC2""#,
        r#""componentType": 5126, "count": 3, "type": "VEC2""#,
        1,
    );
    assert_ne!(broken, json);
    std::fs::write(&path, broken).unwrap();
    let error = load_file(&path).unwrap_err().to_string();
    assert!(
        error.contains("TEXCOORD_0") && error.contains("3 elements for 4 vertices"),
        "{error}"
    );
    // The first image replaced by bytes that are no PNG.
    let undecodable = with_first_image(&json, "data:image/png;base64,bm90IGFuIGltYWdl");
    std::fs::write(&path, undecodable).unwrap();
    assert_checker_left_untextured(&path);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The fixture's JSON with its first image (the checker's) at `uri`.
fn with_first_image(json: &str, uri: &str) -> String {
    let start = json.find(r#""uri": "data:image/png;base64,"#).unwrap();
    let end = start + json[start..].find("\"}").unwrap();
    format!("{}\"uri\": \"{uri}{}", &json[..start], &json[end..])
}

/// Loads the fixture at `path`, whose checker image is refused: the other two textures load
/// and the checker material draws untextured.
fn assert_checker_left_untextured(path: &std::path::Path) {
    let scene = load_file(path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.textures.len(), 2, "the refused image is left out");
    let checker = scene
        .materials
        .iter()
        .find(|m| m.name == "checker")
        .unwrap();
    assert!(checker.base_color_texture.is_none());
}

/// Saved as glTF (JSON with its buffer, and GLB), the textured file keeps its textures,
/// samplers, transforms, texture coordinates, colours and alpha modes, and draws the same
/// picture; saved as CSF, the notes say what is lost.
#[test]
fn saving_keeps_textures_or_says_what_is_lost() {
    let scene = textured_scene("save");
    let dir = scratch_dir("save-textured");
    let original = {
        let mut f = front_view(&scene);
        f.render()
    };
    for name in ["again.gltf", "again.glb"] {
        let path = dir.join(name);
        let notes = cadr_core::save::save_scene(&scene, &path).unwrap();
        assert!(notes.iter().all(|n| !n.contains("texture")), "{notes:?}");
        let saved = load_file(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(
            saved.textures, scene.textures,
            "{name}: textures and samplers"
        );
        for (a, b) in saved.materials.iter().zip(&scene.materials) {
            assert_eq!(a.alpha_mode, b.alpha_mode, "{name}: '{}'", b.name);
            match (&a.base_color_texture, &b.base_color_texture) {
                (Some(a), Some(b)) => {
                    assert_eq!(a.texture, b.texture);
                    for (x, y) in a
                        .transform
                        .u_row
                        .iter()
                        .chain(&a.transform.v_row)
                        .zip(b.transform.u_row.iter().chain(&b.transform.v_row))
                    {
                        assert!((x - y).abs() < 1e-6, "{name}: {a:?} vs {b:?}");
                    }
                }
                (a, b) => assert_eq!(a.is_some(), b.is_some(), "{name}: '{}'", b.is_some()),
            }
        }
        let attributes = |s: &Scene| {
            s.geometries
                .iter()
                .map(|g| g.attributes.clone())
                .collect::<Vec<_>>()
        };
        assert_eq!(attributes(&saved), attributes(&scene), "{name}");
        let mut f = front_view(&saved);
        let picture = f.render();
        assert!(
            compare(&picture, &original).unwrap().within(SAME_PICTURE),
            "{name} draws like the original"
        );
    }
    let notes = cadr_core::save::save_scene(&scene, &dir.join("flat.csf")).unwrap();
    assert!(
        notes
            .iter()
            .any(|n| n.contains("3 textures used by 3 materials are not written")),
        "{notes:?}"
    );
    assert!(
        notes
            .iter()
            .any(|n| n.contains("texture coordinates and vertex colours")),
        "{notes:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A scene without textures (the shaders then skip every material description) gets one at
/// run time by a material change: the textures are built, the description reaches the GPU
/// and the part shows the texture.
#[test]
fn a_scene_without_textures_gets_one_by_a_material_change() {
    let plain = Material {
        name: "plain".into(),
        base_color: [0.9, 0.9, 0.9, 1.0],
        ..Material::default()
    };
    let scene = quad_scene(plain, Vec::new(), 1.0);
    let mut f = front_view(&scene);
    let before = f.render();
    let left = DVec3::new(-0.5, 0.0, 0.0);
    let right = DVec3::new(0.5, 0.0, 0.0);
    let plain = color_at(&before, &f.camera, left);
    assert_eq!(plain, color_at(&before, &f.camera, right));
    // Two texels: blue on the left, yellow on the right.
    let texture = f
        .graph
        .create_texture(Texture {
            name: "halves".into(),
            width: 2,
            height: 1,
            texels: std::sync::Arc::new(vec![20, 40, 230, 255, 240, 220, 20, 255]),
            sampler: cadr_core::scene::Sampler {
                magnify_nearest: true,
                ..Default::default()
            },
        })
        .unwrap();
    give_texture(&mut f.graph, 0, texture);
    f.tree.update(&mut f.graph);
    let after = f.render();
    let (l, r) = (
        color_at(&after, &f.camera, left),
        color_at(&after, &f.camera, right),
    );
    assert!(l[2] > l[0] + 0.3, "blue on the left: {l:?}");
    assert!(
        r[0] > r[2] + 0.3 && r[1] > r[2] + 0.3,
        "yellow on the right: {r:?}"
    );
    f.assert_no_validation_errors();
}

/// The warnings logged in this process (each test runs in a process of its own).
fn logged_warnings() -> &'static std::sync::Mutex<Vec<String>> {
    struct Capture(std::sync::Mutex<Vec<String>>);
    impl log::Log for Capture {
        fn enabled(&self, metadata: &log::Metadata<'_>) -> bool {
            metadata.level() <= log::Level::Warn
        }
        fn log(&self, record: &log::Record<'_>) {
            if self.enabled(record.metadata()) {
                let mut lines = self.0.lock().unwrap_or_else(|e| e.into_inner());
                lines.push(record.args().to_string());
            }
        }
        fn flush(&self) {}
    }
    static CAPTURE: Capture = Capture(std::sync::Mutex::new(Vec::new()));
    if log::set_logger(&CAPTURE).is_ok() {
        log::set_max_level(log::LevelFilter::Warn);
    }
    &CAPTURE.0
}

/// Images are decoded only while their texels fit the memory budget; one past it is left out
/// with a warning that names it and the budget, and the scene loads without its texture.
#[test]
fn an_image_past_the_memory_budget_is_left_out_saying_so() {
    // SAFETY: nextest runs each test in a process of its own; no other thread reads it.
    std::env::set_var(cadr_core::memory_budget::VARIABLE, "4K");
    let warnings = logged_warnings();
    let dir = scratch_dir("budget-textures");
    let path = textured_gltf(&dir);
    let json = std::fs::read_to_string(&path).unwrap();
    // The 8×8 checker becomes 64×64: 16 KiB of texels, past the 4 KiB budget, which the four
    // quads (1 KiB) and the other two images (12 bytes) fit.
    let large = cadr_tests::fixtures::png_data_uri(64, 64, vec![200; 64 * 64 * 4]);
    std::fs::write(&path, with_first_image(&json, &large)).unwrap();
    assert_checker_left_untextured(&path);
    let warnings = warnings.lock().unwrap().clone();
    assert!(
        warnings
            .iter()
            .any(|w| w.starts_with(&format!("{}: image 0 ", path.display()))
                && w.contains("16.0 KiB")
                && w.contains("memory budget of 4.0 KiB")
                && w.contains("CADR_MEMORY_BUDGET")),
        "{warnings:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A device without descriptor indexing holds the textures as layers of one array: a scene
/// with more textures than the device's array has layers is refused, saying how many of each.
#[test]
fn more_textures_than_the_array_has_layers_are_refused_clearly() {
    let mut scene = textured_scene("too_many");
    let device = test_device_with_texture_array_only();
    assert_eq!(device.capabilities().bindless_textures, 0);
    let layers = device.limits().max_image_array_layers as usize;
    let one_texel = Texture {
        name: "one texel".into(),
        width: 1,
        height: 1,
        texels: std::sync::Arc::new(vec![255; 4]),
        sampler: Default::default(),
    };
    scene.textures.resize(layers + 1, one_texel);
    let bounds = cadr_core::scene::flatten(&scene).unwrap().bounds;
    let camera = Camera::fit(&bounds, 1.0, DVec3::Z);
    let mut f = SceneView::new(device, &scene, (64, 64), camera);
    f.tree.update(&mut f.graph);
    let error = f
        .view
        .render(&f.graph, &mut f.tree, &f.camera)
        .unwrap_err()
        .to_string();
    assert!(
        error.contains(&format!("{} texture slots", layers + 1))
            && error.contains(&format!("at most {layers} (maxImageArrayLayers)")),
        "{error}"
    );
    f.assert_no_validation_errors();
}
