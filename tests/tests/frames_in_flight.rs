//! Frames in flight: with two or three, a frame returns once submitted; the next one waits only
//! for the frame that last used its slot when nothing but the view changed and every technique
//! keeps frame slots, for every earlier frame otherwise (and so do a readback, a pick, an
//! edit). The pictures must be those of waiting for every frame, edits included, with GPU
//! times read late, frames that overlap where they may, and no validation error.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use cadr_core::generate::{generate, GeneratorSpec};
use cadr_core::graph::SceneGraph;
use cadr_core::render::pick::PixelRect;
use cadr_core::render::Camera;
use cadr_core::scene::flatten;
use cadr_core::technique::Combination;
use cadr_core::tree::SceneTree;
use cadr_core::view::View;
use cadr_tests::images::{compare, SAME_PICTURE};
use cadr_tests::{
    assert_no_validation_errors, first_transform, plugin_registry, scene_wide, test_device,
};
use glam::{DMat4, DVec3};

const SIZE: (u32, u32) = (128, 96);

/// What a run showed: the picture after every third frame, each frame's GPU time and whether
/// it overlapped earlier frames, and what the pick at the centre hit at the end.
struct Run {
    pictures: Vec<image::RgbaImage>,
    gpu_us: Vec<Option<f64>>,
    overlapped: Vec<bool>,
    picked: Option<u32>,
}

/// Orbits gen:demo for 12 frames with `frames_in_flight`, reading the picture back only every
/// third frame (the others stay in flight); at frame 5 an assembly is lifted.
fn orbit(combination: &Combination, frames_in_flight: u32) -> Run {
    let device = test_device();
    let scene = generate(&GeneratorSpec::Demo);
    let bounds = flatten(&scene).unwrap().bounds;
    let (mut graph, handles) = SceneGraph::from_scene(&scene).unwrap();
    let (node, original) = first_transform(&mut graph, &handles).unwrap();
    let mut tree = SceneTree::build(&mut graph);
    let mut view = View::new(&device, plugin_registry(&device), SIZE.0, SIZE.1).unwrap();
    view.techniques_mut().select(combination).unwrap();
    view.renderer_mut()
        .set_frames_in_flight(frames_in_flight)
        .unwrap();
    assert_eq!(view.renderer().frames_in_flight(), frames_in_flight);
    let aspect = f64::from(SIZE.0) / f64::from(SIZE.1);
    let mut run = Run {
        pictures: Vec::new(),
        gpu_us: Vec::new(),
        overlapped: Vec::new(),
        picked: None,
    };
    let mut camera = Camera::fit(&bounds, aspect, cadr_core::render::DEFAULT_DIRECTION);
    for frame in 0..12 {
        if frame == 5 {
            let lift = DMat4::from_translation(DVec3::new(0.0, bounds.radius() * 0.2, 0.0));
            graph.set_matrix(node, lift * original).unwrap();
            tree.update(&mut graph);
        }
        camera = Camera::orbit(&bounds, aspect, frame as f64 / 30.0, 1.3);
        let stats = view.render(&graph, &mut tree, &camera).unwrap();
        // The pass times are those of the frame whose GPU time the stats report (with frames
        // in flight, the latest finished one, none for the first), and add up to it.
        let passes = view.renderer().gpu_pass_times();
        match stats.gpu_us {
            Some(frame_us) => {
                let sum: f64 = passes.iter().map(|(_, us)| us).sum();
                assert!(
                    (sum - frame_us).abs() <= 1e-6 * frame_us + 0.01,
                    "frame {frame}: {passes:?} against {frame_us} µs"
                );
            }
            None => assert!(passes.is_empty(), "frame {frame}: {passes:?}"),
        }
        run.gpu_us.push(stats.gpu_us);
        run.overlapped.push(stats.overlapped);
        if frame % 3 == 2 {
            run.pictures.push(view.renderer().read_rgba8().unwrap());
        }
    }
    view.sync(&graph, &mut tree).unwrap();
    let hits = view
        .pick(&tree, &camera, PixelRect::pixel(SIZE.0 / 2, SIZE.1 / 2))
        .unwrap();
    run.picked = hits.first().map(|hit| hit.instance);
    assert!(
        view.renderer_mut().set_frames_in_flight(4).is_err(),
        "at most 3 frames in flight"
    );
    assert_no_validation_errors(&device);
    run
}

/// Frames of a run that never overlap earlier ones: the first (there is none) and the lift's
/// (frame 5 uploads the moved matrices, and the scene changed).
const WAITING_FRAMES: [usize; 2] = [0, 5];

#[test]
fn frames_in_flight_draw_and_pick_what_waiting_for_each_frame_does() {
    // Lavapipe runs submissions one after another, so a missing barrier between overlapping
    // frames would not show in the pictures: the synchronization checks of the validation
    // layer look for them (this test runs in a process of its own).
    std::env::set_var(
        "VK_LAYER_ENABLES",
        "VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT",
    );
    for (combination, keeps_frame_slots) in [
        (Combination::built_in(), true),
        (
            scene_wide("individual-indirect-count", "gpu-occlusion"),
            true,
        ),
        (scene_wide("groups-mdi-replay", "frustum"), true),
        // Records its secondary buffers every frame: one frame at a time.
        (scene_wide("individual-threads", "none"), false),
    ] {
        let waited = orbit(&combination, 1);
        assert!(!waited.overlapped.iter().any(|&o| o), "{combination}");
        for frames in [2, 3] {
            let overlapped = orbit(&combination, frames);
            for (index, (a, b)) in waited.pictures.iter().zip(&overlapped.pictures).enumerate() {
                let difference = compare(b, a).unwrap();
                assert!(
                    difference.within(SAME_PICTURE),
                    "{combination}, {frames} in flight, picture {index}: {difference:?}"
                );
            }
            assert_eq!(waited.picked, overlapped.picked, "{combination}");
            assert!(
                waited.picked.is_some(),
                "{combination}: the centre shows a part"
            );
            // Waiting, each frame knows its own GPU time; in flight, that of an earlier one
            // known to have finished: none before the first frame has, which takes at most as
            // many frames as are in flight.
            if waited.gpu_us.iter().all(Option::is_some) {
                assert_eq!(overlapped.gpu_us[0], None, "{combination}");
                assert!(
                    overlapped.gpu_us[frames as usize..]
                        .iter()
                        .all(Option::is_some),
                    "{combination}, {frames} in flight: {:?}",
                    overlapped.gpu_us
                );
            }
            // Frustum culling on the CPU changes what is drawn as the camera turns, so its
            // frames overlap only where the drawn parts stay the same.
            let culls_on_the_cpu = combination.to_string().contains("frustum");
            for (frame, &overlaps) in overlapped.overlapped.iter().enumerate() {
                if WAITING_FRAMES.contains(&frame) || !keeps_frame_slots {
                    assert!(
                        !overlaps,
                        "{combination}, {frames} in flight, frame {frame}"
                    );
                } else if !culls_on_the_cpu {
                    assert!(overlaps, "{combination}, {frames} in flight, frame {frame}");
                }
            }
        }
    }
}
