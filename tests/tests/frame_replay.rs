//! Frame replay: a frame that would record what the last one recorded (the camera moved,
//! parts moved, or nothing did) resubmits the last command buffer. It must draw exactly what
//! recording would: the camera reaches the GPU through uniforms, moved parts through the
//! uploads submitted ahead of the replayed recording (when no technique reads parameter
//! values on the host), and any other edit, resize or technique change records afresh.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::sync::Arc;

use cadr_core::generate::{generate, GeneratorSpec};
use cadr_core::graph::{NodeFlags, SceneGraph};
use cadr_core::render::Camera;
use cadr_core::scene::flatten;
use cadr_core::technique::{Combination, PluginRegistry};
use cadr_core::tree::SceneTree;
use cadr_core::view::View;
use cadr_core::vk::Device;
use cadr_tests::images::{compare, SAME_PICTURE, VISIBLE_CHANGE};
use cadr_tests::{
    assert_no_validation_errors, first_transform, placed_nodes, plugin_registry,
    scene_wide as combination, test_device,
};
use glam::{DMat4, DVec3};

const SIZE: (u32, u32) = (160, 120);

/// A view of `SIZE` drawing with `combination`, frame replay on or off.
fn view_with(
    device: &Arc<Device>,
    registry: &Arc<PluginRegistry>,
    combination: &Combination,
    replay: bool,
) -> View {
    let mut view = View::new(device, Arc::clone(registry), SIZE.0, SIZE.1).unwrap();
    view.techniques_mut().select(combination).unwrap();
    view.techniques_mut().set_frame_replay(replay);
    view
}

/// What one frame showed and whether it was replayed.
struct Shown {
    image: image::RgbaImage,
    replayed: bool,
    triangles: u64,
}

/// Renders `frames` of an orbit with `combination`, frame replay on or off: at frame `edit_at`
/// a transform node is lifted, three frames later the target is resized and back, and the
/// frame after that hides the node.
fn orbit(combination: &Combination, replay: bool, edit_at: usize, frames: usize) -> Vec<Shown> {
    let device = test_device();
    let scene = generate(&GeneratorSpec::Demo);
    let bounds = flatten(&scene).unwrap().bounds;
    let (mut graph, handles) = SceneGraph::from_scene(&scene).unwrap();
    let (root, original) = first_transform(&mut graph, &handles).unwrap();
    let mut tree = SceneTree::build(&mut graph);
    let registry = plugin_registry(&device);
    let mut view = view_with(&device, &registry, combination, replay);
    let aspect = f64::from(SIZE.0) / f64::from(SIZE.1);
    let shown = (0..frames)
        .map(|frame| {
            if frame == edit_at {
                let lift = DMat4::from_translation(DVec3::new(0.0, bounds.radius() * 0.2, 0.0));
                graph.set_matrix(root, lift * original).unwrap();
                tree.update(&mut graph);
            }
            if frame == edit_at + 3 {
                // A resize and back: the recording drew into the old target.
                view.renderer_mut().resize(SIZE.0 / 2, SIZE.1 / 2).unwrap();
                view.renderer_mut().resize(SIZE.0, SIZE.1).unwrap();
            }
            if frame == edit_at + 5 {
                // Other parts are drawn: the recording's draws no longer hold.
                let hidden = NodeFlags {
                    visible: false,
                    ..NodeFlags::default()
                };
                graph.set_flags(root, hidden).unwrap();
                tree.update(&mut graph);
            }
            let camera = Camera::orbit(&bounds, aspect, frame as f64 / 40.0, 1.2);
            let stats = view.render(&graph, &mut tree, &camera).unwrap();
            Shown {
                image: view.renderer().read_rgba8().unwrap(),
                replayed: stats.replayed,
                triangles: stats.triangles,
            }
        })
        .collect();
    drop(view);
    assert_no_validation_errors(&device);
    shown
}

#[test]
fn replayed_frames_follow_the_camera_and_every_change_records_afresh() {
    let (edit_at, frames) = (5, 12);
    for combination in [
        combination("individual-indirect-count", "gpu-frustum"),
        combination("individual-indirect-count", "gpu-occlusion"),
        combination("groups-mdi-replay", "none"),
    ] {
        let replayed = orbit(&combination, true, edit_at, frames);
        let recorded = orbit(&combination, false, edit_at, frames);
        let flags: Vec<bool> = replayed.iter().map(|s| s.replayed).collect();
        println!("{combination}: replayed {flags:?}");
        for (frame, (a, b)) in replayed.iter().zip(&recorded).enumerate() {
            assert!(!b.replayed, "{combination}, frame {frame}: replay is off");
            let difference = compare(&a.image, &b.image).unwrap();
            assert!(
                difference.within(SAME_PICTURE),
                "{combination}, frame {frame}: the replayed frame differs: {difference:?}"
            );
            assert_eq!(a.triangles, b.triangles, "{combination}, frame {frame}");
            // The first two frames record (the first may do one-time work); the resize and
            // the hidden node record, and so does the frame after each; the camera and the
            // lifted node never do (every technique here reads parameter values on the GPU).
            let expected = !matches!(frame, 0 | 1)
                && frame != edit_at + 3
                && frame != edit_at + 4
                && frame != edit_at + 5
                && frame != edit_at + 6;
            assert_eq!(
                a.replayed, expected,
                "{combination}, frame {frame}: {flags:?}"
            );
        }
        // The edits show in the frame they were made.
        for at in [edit_at, edit_at + 5] {
            let before = &replayed[at - 1].image;
            let after = &replayed[at].image;
            let changed = compare(before, after).unwrap();
            assert!(
                changed.mean > VISIBLE_CHANGE,
                "{combination}, frame {at}: the edit shows: {changed:?}"
            );
        }
    }
}

/// What each of `frames` frames of an exploding assembly showed, with `combination` and frame
/// replay on or off: every frame moves the demo's transform nodes apart (a still camera), as
/// a host dragging parts does. Also what a fresh view shows of the last frame's scene.
fn explode(
    combination: &Combination,
    replay: bool,
    frames: usize,
) -> (Vec<(Shown, u64)>, image::RgbaImage) {
    let device = test_device();
    let scene = generate(&GeneratorSpec::Demo);
    let bounds = flatten(&scene).unwrap().bounds;
    let (mut graph, handles) = SceneGraph::from_scene(&scene).unwrap();
    let moving = placed_nodes(&graph, &handles, 8);
    assert!(moving.len() > 1, "the demo has transform nodes to move");
    let mut tree = SceneTree::build(&mut graph);
    let registry = plugin_registry(&device);
    let mut view = view_with(&device, &registry, combination, replay);
    let aspect = f64::from(SIZE.0) / f64::from(SIZE.1);
    let camera = Camera::orbit(&bounds, aspect, 0.3, 1.2);
    let shown = (0..frames)
        .map(|frame| {
            for (i, &(node, original)) in moving.iter().enumerate() {
                let apart = bounds.radius() * 0.04 * frame as f64 * (i as f64 - 3.5);
                let offset = DMat4::from_translation(DVec3::new(apart, 0.0, apart * 0.5));
                graph.set_matrix(node, offset * original).unwrap();
            }
            tree.update(&mut graph);
            let stats = view.render(&graph, &mut tree, &camera).unwrap();
            let shown = Shown {
                image: view.renderer().read_rgba8().unwrap(),
                replayed: stats.replayed,
                triangles: stats.triangles,
            };
            (shown, stats.bytes_uploaded)
        })
        .collect();
    drop(view);
    let mut fresh = view_with(&device, &registry, combination, true);
    let mut fresh_tree = SceneTree::build(&mut graph);
    fresh.render(&graph, &mut fresh_tree, &camera).unwrap();
    let expected = fresh.renderer().read_rgba8().unwrap();
    drop(fresh);
    assert_no_validation_errors(&device);
    (shown, expected)
}

#[test]
fn moving_parts_replay_the_recorded_pass_after_their_upload() {
    let frames = 6;
    let reads_on_host = Combination {
        parameters: "ubo-dynamic".into(),
        ..combination("individual", "none")
    };
    for (combination, replays) in [
        (
            combination("individual-indirect-count", "gpu-frustum"),
            true,
        ),
        (combination("groups-mdi-replay", "none"), true),
        // Copies matrices into its own buffers on the host: a moved part records afresh.
        (reads_on_host, false),
    ] {
        let (replayed, fresh) = explode(&combination, true, frames);
        let (recorded, _) = explode(&combination, false, frames);
        let flags: Vec<bool> = replayed.iter().map(|(s, _)| s.replayed).collect();
        println!("{combination}: replayed {flags:?}");
        for (frame, ((a, uploaded), (b, _))) in replayed.iter().zip(&recorded).enumerate() {
            let difference = compare(&a.image, &b.image).unwrap();
            assert!(
                difference.within(SAME_PICTURE),
                "{combination}, frame {frame}: the replayed frame differs: {difference:?}"
            );
            assert_eq!(a.triangles, b.triangles, "{combination}, frame {frame}");
            assert_eq!(
                a.replayed,
                replays && frame >= 2,
                "{combination}, frame {frame}: {flags:?}"
            );
            assert!(
                *uploaded > 0,
                "{combination}, frame {frame}: the moved parts were uploaded"
            );
        }
        let first = &replayed[1].0.image;
        let last = &replayed[frames - 1].0.image;
        let difference = compare(last, &fresh).unwrap();
        assert!(
            difference.within(SAME_PICTURE),
            "{combination}: the last frame differs from a fresh upload: {difference:?}"
        );
        let moved = compare(first, last).unwrap();
        assert!(
            moved.mean > VISIBLE_CHANGE,
            "{combination}: the parts moved apart on screen: {moved:?}"
        );
    }
}
