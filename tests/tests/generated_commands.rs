//! The `dgc` submission (`VK_EXT_device_generated_commands`, Mesa 25's lavapipe): under every
//! culler it draws the picture `groups-mdi-replay` draws, frame by frame while the camera
//! orbits, as one generated-commands execution per pass. Validation is on; the messages the
//! 1.3.239 layer gives about the extension, which it predates, are the only ones excused
//! (`cadr_core::vk` instance module).
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::sync::Arc;

use cadr_core::generate::{generate, GeneratorSpec};
use cadr_core::graph::SceneGraph;
use cadr_core::render::{Camera, FrameStats, DEFAULT_DIRECTION};
use cadr_core::scene::flatten;
use cadr_core::technique::Combination;
use cadr_core::tree::SceneTree;
use cadr_core::view::View;
use cadr_tests::images::{compare, SAME_PICTURE};
use cadr_tests::{assert_no_validation_errors, plugin_registry, scene_wide, test_device};

const SIZE: (u32, u32) = (200, 150);

#[test]
fn dgc_draws_what_groups_mdi_replay_draws_under_every_culler() {
    let device = test_device();
    assert!(
        device.capabilities().device_generated_commands,
        "the default driver ({}) has no VK_EXT_device_generated_commands: run scripts/setup.sh",
        device.adapter().name
    );
    let scene = generate(&GeneratorSpec::Cabinet { cabinets: 6 });
    let bounds = flatten(&scene).unwrap().bounds;
    let aspect = f64::from(SIZE.0) / f64::from(SIZE.1);
    let mut cameras = vec![Camera::fit(&bounds, aspect, DEFAULT_DIRECTION); 3];
    cameras.extend((0..3).map(|i| Camera::orbit(&bounds, aspect, 0.3 * f64::from(i), 1.2)));

    let (mut graph, _) = SceneGraph::from_scene(&scene).unwrap();
    let mut tree = SceneTree::build(&mut graph);
    let registry = plugin_registry(&device);
    let mut view = View::new(&device, Arc::clone(&registry), SIZE.0, SIZE.1).unwrap();
    let mut render = |combination: &Combination| -> Vec<(image::RgbaImage, FrameStats)> {
        view.techniques_mut().select(combination).unwrap();
        cameras
            .iter()
            .map(|camera| {
                let stats = view.render(&graph, &mut tree, camera).unwrap();
                (view.renderer().read_rgba8().unwrap(), stats)
            })
            .collect()
    };
    let reference = render(&scene_wide("groups-mdi-replay", "none"));
    for culler in ["none", "frustum", "gpu-frustum", "gpu-occlusion"] {
        let frames = render(&scene_wide("dgc", culler));
        for (frame, ((image, stats), (expected, reference_stats))) in
            frames.iter().zip(&reference).enumerate()
        {
            let difference = compare(image, expected).unwrap();
            assert!(
                difference.within(SAME_PICTURE),
                "dgc / {culler}, frame {frame}: {difference:?}"
            );
            // One execution per pass (and per phase of gpu-occlusion), whatever the parts.
            assert!(
                (1..=2).contains(&stats.draw_calls),
                "dgc / {culler}, frame {frame}: {} draw calls",
                stats.draw_calls
            );
            assert!(stats.triangles > 0 && stats.triangles <= reference_stats.triangles);
        }
    }
    drop(view);
    assert_no_validation_errors(&device);
}
