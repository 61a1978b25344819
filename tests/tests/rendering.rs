//! Image tests against references made on lavapipe, with validation on.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::path::Path;

use cadr_core::generate::{generate, GeneratorSpec};
use cadr_core::load::load_file;
use std::sync::Arc;

use cadr_core::graph::SceneGraph;
use cadr_core::render::{Background, Camera, DEFAULT_DIRECTION};
use cadr_core::scene::{flatten, Scene};
use cadr_core::technique::{feature_bits, PluginRegistry, ShadeMode};
use cadr_core::tree::SceneTree;
use cadr_core::view::View;
use cadr_tests::fixtures::{scratch_dir, CubeGltf};
use cadr_tests::images::{
    self, assert_matches_reference, compare, covered_fraction, DEFAULT_TOLERANCE,
};
use cadr_tests::{assert_no_validation_errors, render_scene, test_device, CYLINDER_ENGINE_GLB};

#[test]
fn demo_matches_reference() {
    let image = render_scene(&generate(&GeneratorSpec::Demo), 320, 240);
    assert_matches_reference("demo", &image, DEFAULT_TOLERANCE);
}

#[test]
fn cylinder_engine_matches_reference_and_is_plausible() {
    let scene = load_file(Path::new(CYLINDER_ENGINE_GLB)).expect("load 2CylinderEngine");
    let image = render_scene(&scene, 320, 240);
    // The fitted camera shows the whole engine: it covers a good part of the frame but not all.
    let covered = covered_fraction(&image);
    assert!(
        (0.15..0.9).contains(&covered),
        "engine covers {covered:.2} of the image"
    );
    assert_matches_reference("cylinder_engine", &image, DEFAULT_TOLERANCE);
}

#[test]
fn cube_fixture_matches_reference() {
    let dir = scratch_dir("render_cube");
    let scene = load_file(&CubeGltf::new().write_glb(&dir, "cube")).expect("load cube");
    let image = render_scene(&scene, 160, 120);
    assert_matches_reference("cubes", &image, DEFAULT_TOLERANCE);
}

#[test]
fn materials_reach_the_image() {
    // The cube's two materials are red and blue: both hues must appear.
    let dir = scratch_dir("render_colors");
    let scene = load_file(&CubeGltf::new().write_glb(&dir, "cube")).expect("load cube");
    let image = render_scene(&scene, 160, 120);
    let reddish = image
        .pixels()
        .filter(|p| p[0] > 120 && p[1] < 90 && p[2] < 90)
        .count();
    let bluish = image.pixels().filter(|p| p[2] > 120 && p[0] < 100).count();
    assert!(reddish > 200, "red pixels: {reddish}");
    assert!(bluish > 200, "blue pixels: {bluish}");
}

#[test]
fn empty_scene_renders_the_background() {
    let image = render_scene(&Scene::default(), 64, 48);
    assert!(
        image
            .enumerate_pixels()
            .all(|(x, y, _)| images::is_background(&image, x, y)),
        "an empty scene is all background"
    );
    // The default background is a gradient, lighter at the top, opaque everywhere.
    let (top, bottom) = (image.get_pixel(0, 0).0, image.get_pixel(0, 47).0);
    assert!(
        (0..3).all(|c| top[c] > bottom[c]),
        "{top:?} over {bottom:?}"
    );
    assert!(image.pixels().all(|p| p.0[3] == 255));
    assert_eq!(
        &top[..3],
        &Background::default().rgb8_at(0, 48)[..],
        "the top row"
    );
}

#[test]
fn moving_a_part_changes_the_image_beyond_tolerance() {
    // The metric must see a real change: move one instance and compare.
    let dir = scratch_dir("render_move");
    let path = CubeGltf::new().write_glb(&dir, "cube");
    let scene = load_file(&path).expect("load cube");
    let before = render_scene(&scene, 160, 120);
    let mut moved = scene.clone();
    moved.nodes[2].local.w_axis.y += 0.4;
    let after = render_scene(&moved, 160, 120);
    let difference = compare(&before, &after).expect("same size");
    assert!(!difference.within(DEFAULT_TOLERANCE), "{difference:?}");
    let same = compare(&before, &before).expect("same size");
    assert!(same.mean < 1e-6 && same.p99 < 1e-6, "{same:?}");
}

#[test]
fn repeated_frames_are_identical_and_report_costs() {
    let device = test_device();
    let scene = generate(&GeneratorSpec::Grid {
        parts: 2_000,
        triangles_per_part: 12.0,
    });
    let (mut graph, _) = SceneGraph::from_scene(&scene).expect("graph");
    let mut tree = SceneTree::build(&mut graph);
    let registry = PluginRegistry::built_in(feature_bits(device.capabilities()));
    let mut view = View::new(&device, Arc::new(registry), 128, 96).expect("view");
    let bounds = flatten(&scene).expect("flatten").bounds;
    let camera = Camera::fit(&bounds, 128.0 / 96.0, DEFAULT_DIRECTION);
    let first = view.render(&graph, &mut tree, &camera).expect("frame 1");
    let image1 = view.renderer().read_rgba8().expect("read 1");
    let second = view.render(&graph, &mut tree, &camera).expect("frame 2");
    let image2 = view.renderer().read_rgba8().expect("read 2");
    assert_eq!(image1, image2);
    assert_eq!((first.draw_calls, second.draw_calls), (2_000, 2_000));
    assert_eq!(first.triangles, 2_000 * 12);
    assert_eq!(
        first.parameter_updates, 2_001,
        "the built-in parameter path pushes per draw, plus the frame's descriptor set"
    );
    assert!(first.vertex_binds <= first.draw_calls && first.vertex_binds > 0);
    assert_eq!(second.bytes_uploaded, 0, "nothing changed");
    assert!(second.cpu_record_us > 0.0);
    assert!(
        second.gpu_us.is_some_and(|us| us > 0.0),
        "lavapipe has timestamps"
    );
    drop(view);
    assert_no_validation_errors(&device);
}

#[test]
fn far_from_origin_scene_renders_like_one_at_the_origin() {
    // Matrices are made relative to the eye in f64, so a model 100 km away looks the same.
    let dir = scratch_dir("render_far");
    let scene = load_file(&CubeGltf::new().write_glb(&dir, "cube")).expect("load cube");
    let mut far = scene.clone();
    far.nodes[0].local =
        glam::DMat4::from_translation(glam::DVec3::new(100_000.0, -50_000.0, 80_000.0));
    let near_image = render_scene(&scene, 160, 120);
    let far_image = render_scene(&far, 160, 120);
    let difference = compare(&near_image, &far_image).expect("same size");
    assert!(difference.within(DEFAULT_TOLERANCE), "{difference:?}");
}

/// Renderers of one device build each pass set's pipelines once: a second view of a scene draws
/// with the first one's (each path promises layouts of one definition) and with the same
/// passes over the picture, draws the picture it draws with its own, and keeps drawing after the
/// renderer that built them is gone.
#[test]
fn renderers_of_one_device_share_their_pipelines_and_outlive_the_one_that_built_them() {
    let device = test_device();
    let scene = load_file(Path::new(CYLINDER_ENGINE_GLB)).unwrap();
    let orbit = |view: &mut cadr_tests::SceneView| {
        view.camera = Camera::orbit(&flatten(&scene).unwrap().bounds, 96.0 / 72.0, 0.25, 1.5);
    };
    // Alone: the picture a renderer draws with pipelines it built itself.
    let mut alone = cadr_tests::SceneView::fitted(Arc::clone(&device), &scene, (96, 72));
    orbit(&mut alone);
    let own_pipelines = alone.render();
    alone
        .view
        .techniques_mut()
        .set_shade_mode(ShadeMode::Edges)
        .unwrap();
    let own_edges = alone.render();
    drop(alone);

    let mut first = cadr_tests::SceneView::fitted(Arc::clone(&device), &scene, (96, 72));
    first.render();
    let mut second = cadr_tests::SceneView::fitted(Arc::clone(&device), &scene, (96, 72));
    orbit(&mut second);
    assert_eq!(second.render(), own_pipelines);
    let (mine, theirs) = (second.view.techniques(), first.view.techniques());
    assert_eq!(
        (mine.kept_pass_sets(), mine.pass_sets_shared_with(theirs)),
        (1, 1),
        "the second renderer built its solid pass set again"
    );
    // The frame's layouts and the passes over the picture are the device's, made once.
    assert!(std::ptr::eq(
        first.view.renderer().pipelines(),
        second.view.renderer().pipelines()
    ));
    // A pass set only one of them draws is its own until the other draws it too.
    second
        .view
        .techniques_mut()
        .set_shade_mode(ShadeMode::Edges)
        .unwrap();
    assert_eq!(second.render(), own_edges);
    assert_eq!(
        second
            .view
            .techniques()
            .pass_sets_shared_with(first.view.techniques()),
        1
    );
    first
        .view
        .techniques_mut()
        .set_shade_mode(ShadeMode::Edges)
        .unwrap();
    first.render();
    assert_eq!(
        second
            .view
            .techniques()
            .pass_sets_shared_with(first.view.techniques()),
        2
    );
    // The renderer that built them goes; the other keeps drawing with them.
    drop(first);
    for _ in 0..2 {
        assert_eq!(second.render(), own_edges);
    }
    second
        .view
        .techniques_mut()
        .set_shade_mode(ShadeMode::Solid)
        .unwrap();
    assert_eq!(second.render(), own_pipelines);
    assert_no_validation_errors(&device);
}

/// Renderers of one size on one device share their depth, with MSAA their multisampled
/// attachments, and the transparency method's targets and storage (what a frame draws there is
/// of no use after it), so several views hold one set: each still draws the picture it draws alone, frames in flight interleaved, and a
/// renderer whose frames hand the depth to the host keeps its own, which another renderer's
/// frame leaves as it was.
#[test]
fn renderers_of_one_size_share_their_frame_attachments_and_a_kept_depth_stays_their_own() {
    use cadr_core::render::pick::PixelRect;
    let device = test_device();
    let scene = load_file(Path::new(CYLINDER_ENGINE_GLB)).unwrap();
    let allocated = || device.memory_usage().allocated_bytes;
    let mut front = cadr_tests::SceneView::fitted(Arc::clone(&device), &scene, (96, 72));
    let alone_front = front.render();
    let mut side = cadr_tests::SceneView::fitted(Arc::clone(&device), &scene, (96, 72));
    side.camera = Camera::orbit(&flatten(&scene).unwrap().bounds, 96.0 / 72.0, 0.25, 1.5);
    let alone_side = side.render();
    let depth_bytes = 96 * 72 * 4_u64;
    assert_ne!(alone_front, alone_side, "two different pictures");
    // Interleaved, frames in flight: each its own picture.
    for view in [&mut front, &mut side] {
        view.view.renderer_mut().set_frames_in_flight(3).unwrap();
    }
    for _ in 0..3 {
        assert_eq!(front.render(), alone_front);
        assert_eq!(side.render(), alone_side);
    }
    // With MSAA they share the multisampled attachments too: the second renderer's come at
    // no cost, and the pictures stay each renderer's own.
    if device.sample_counts().contains(&4) {
        front.view.renderer_mut().set_msaa(4).unwrap();
        let msaa_front = front.render();
        let before_msaa = allocated();
        side.view.renderer_mut().set_msaa(4).unwrap();
        let grew = allocated().saturating_sub(before_msaa);
        assert!(
            grew < 4 * depth_bytes,
            "the second renderer's MSAA took {grew} bytes, a multisampled image's worth or more"
        );
        let msaa_side = side.render();
        for _ in 0..3 {
            assert_eq!(front.render(), msaa_front);
            assert_eq!(side.render(), msaa_side);
        }
        for view in [&mut front, &mut side] {
            view.view.renderer_mut().set_msaa(1).unwrap();
        }
    }
    // Translucent surfaces (X-ray: every part) share the transparency method's targets and
    // storage the same way.
    let xray = |view: &mut cadr_tests::SceneView, mode| {
        view.view.techniques_mut().set_shade_mode(mode).unwrap();
        let before = allocated();
        let picture = view.render();
        (picture, allocated().saturating_sub(before))
    };
    let (xray_front, front_grew) = xray(&mut front, ShadeMode::XRay);
    let (xray_side, side_grew) = xray(&mut side, ShadeMode::XRay);
    // Weighted blended: RGBA16F and R16F targets.
    let targets_bytes = 96 * 72 * (8 + 2);
    assert!(
        side_grew + targets_bytes <= front_grew,
        "the second renderer's X-ray took {side_grew} bytes, the first's {front_grew}"
    );
    for _ in 0..3 {
        assert_eq!(front.render(), xray_front);
        assert_eq!(side.render(), xray_side);
    }
    xray(&mut front, ShadeMode::Solid);
    xray(&mut side, ShadeMode::Solid);
    // A kept depth is the renderer's own: another renderer's frame between the frame and the
    // read leaves it as picking finds it.
    for view in [&mut front, &mut side] {
        view.view.renderer_mut().set_frames_in_flight(1).unwrap();
    }
    let sharing = allocated();
    front.view.renderer_mut().set_depth_to_host(true).unwrap();
    let own_depth = allocated() - sharing;
    assert!(
        own_depth >= depth_bytes,
        "a depth of its own: {own_depth} bytes"
    );
    front.render();
    side.render();
    let depth = front.view.renderer().read_depth().unwrap();
    front.view.sync(&front.graph, &mut front.tree).unwrap();
    let mut hits = 0;
    for (x, y) in (0..12).flat_map(|i| (0..9).map(move |j| (4 + 8 * i, 4 + 8 * j))) {
        let picked = front
            .view
            .pick(&front.tree, &front.camera, PixelRect::pixel(x, y))
            .unwrap();
        let value = depth[(y * 96 + x) as usize];
        match picked.first() {
            Some(hit) => {
                assert!((value - hit.depth).abs() < 1e-4, "({x}, {y})");
                hits += 1;
            }
            None => assert_eq!(value, 1.0, "({x}, {y})"),
        }
    }
    assert!(hits > 20);
    // Back to sharing: the own depth is given up (with the pick target, made again on the
    // next pick).
    let kept = allocated();
    front.view.renderer_mut().set_depth_to_host(false).unwrap();
    assert!(allocated() + own_depth <= kept);
    assert_eq!(front.render(), alone_front);
    side.assert_no_validation_errors();
    front.assert_no_validation_errors();
}

/// A host compositing its own drawing with cadr's frames gets each colour frame's depth
/// (`Renderer::depth_for_host`): where a part shows, the depth picking finds there, and 1 where
/// nothing is drawn; with plain frames, with ambient occlusion (whose pass reads the depth as
/// a shader does), with the two-phase occlusion culler (whose passes are suspended) and with
/// MSAA (resolved from one sample, so that pixels on a part's outline may differ). It is
/// refused while frames do not keep it.
#[test]
fn colour_frames_hand_their_depth_to_the_host() {
    use cadr_core::render::pick::PixelRect;
    let device = test_device();
    let scene = load_file(Path::new(CYLINDER_ENGINE_GLB)).unwrap();
    let mut f = cadr_tests::SceneView::fitted(Arc::clone(&device), &scene, (96, 72));
    f.render();
    assert!(f.view.renderer().read_depth().is_err());
    // What picking finds on a grid of pixels: the depth of the nearest part, or nothing.
    f.view.sync(&f.graph, &mut f.tree).unwrap();
    let grid: Vec<(u32, u32)> = (0..12)
        .flat_map(|i| (0..9).map(move |j| (4 + 8 * i, 4 + 8 * j)))
        .collect();
    let picked: Vec<Option<f32>> = grid
        .iter()
        .map(|&(x, y)| {
            let hits = f
                .view
                .pick(&f.tree, &f.camera, PixelRect::pixel(x, y))
                .unwrap();
            hits.first().map(|hit| hit.depth)
        })
        .collect();
    assert!(picked.iter().filter(|d| d.is_some()).count() > 20);
    assert!(picked.iter().filter(|d| d.is_none()).count() > 10);
    f.view.renderer_mut().set_depth_to_host(true).unwrap();
    // SwiftShader lacks drawIndirectCount: there the culler's commands are drawn by their
    // capacity.
    let occlusion = cadr_tests::gpu_culled(f.view.renderer().device(), "gpu-occlusion");
    let msaa = f.view.renderer().device().sample_counts().contains(&4);
    for case in ["plain", "ambient occlusion", "occlusion culler", "msaa"] {
        match case {
            "ambient occlusion" => f.view.renderer_mut().set_ssao(true).unwrap(),
            "occlusion culler" => {
                f.view.renderer_mut().set_ssao(false).unwrap();
                f.view.techniques_mut().select(&occlusion).unwrap();
            }
            "msaa" if msaa => f.view.renderer_mut().set_msaa(4).unwrap(),
            "msaa" => continue,
            _ => {}
        }
        f.render();
        let depth = f.view.renderer().read_depth().unwrap();
        assert_eq!(depth.len(), 96 * 72, "{case}");
        // The multisampled depth resolves to one sample, off the pixel's centre.
        let tolerance = if case == "msaa" { 0.02 } else { 1e-4 };
        let agreeing = grid
            .iter()
            .zip(&picked)
            .filter(|&(&(x, y), expected)| {
                let value = depth[(y * 96 + x) as usize];
                match expected {
                    Some(expected) => (value - expected).abs() < tolerance,
                    None => value == 1.0,
                }
            })
            .count();
        let needed = if case == "msaa" {
            grid.len() * 9 / 10
        } else {
            grid.len()
        };
        assert!(
            agreeing >= needed,
            "{case}: {agreeing} of {} pixels hold the depth picking finds",
            grid.len()
        );
    }
    // A new size has no depth until a frame draws one.
    f.view.renderer_mut().resize(48, 36).unwrap();
    assert!(f.view.renderer().read_depth().is_err());
    f.view.renderer_mut().set_depth_to_host(false).unwrap();
    assert!(f.view.renderer().read_depth().is_err());
    f.assert_no_validation_errors();
}
