//! Injected Vulkan failures (feature `fault-injection`: `cargo nextest run -p cadr-tests
//! --features fault-injection`, as `scripts/test.sh` does): every device memory allocation,
//! queue submission and device loss of a render of gen:demo with a technique swap in between
//! is made to fail in turn. Each failure must come back as an error with a clear message, never
//! a panic; nothing may leak (device memory counted, Vulkan objects by the validation layer at
//! device destruction); a lost device must say so at the next call; and after any failure the
//! host can destroy what it has, create it again and render the same picture.
#![cfg(feature = "fault-injection")]
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::sync::Arc;

use cadr_core::generate::{generate, GeneratorSpec};
use cadr_core::graph::SceneGraph;
use cadr_core::render::{Camera, DEFAULT_DIRECTION};
use cadr_core::scene::flatten;
use cadr_core::technique::Combination;
use cadr_core::tree::SceneTree;
use cadr_core::view::View;
use cadr_core::vk::fault::{self, FaultKind};
use cadr_core::vk::Device;
use cadr_tests::images::{compare, SAME_PICTURE};
use cadr_tests::{plugin_registry, test_device};

const SIZE: (u32, u32) = (96, 72);
/// At most this many failure points per kind (evenly spread, the first and last included).
const MOST_POINTS: u64 = 40;

/// Renders gen:demo with a GPU-culled combination, swaps to the built-in one, renders again
/// and reads the picture back.
fn render_with_a_swap(device: &Arc<Device>) -> Result<image::RgbaImage, String> {
    let scene = generate(&GeneratorSpec::Demo);
    let bounds = flatten(&scene).map_err(|e| e.to_string())?.bounds;
    let (mut graph, _) = SceneGraph::from_scene(&scene).map_err(|e| e.to_string())?;
    let mut tree = SceneTree::build(&mut graph);
    let mut view =
        View::new(device, plugin_registry(device), SIZE.0, SIZE.1).map_err(|e| e.to_string())?;
    let camera = Camera::fit(
        &bounds,
        f64::from(SIZE.0) / f64::from(SIZE.1),
        DEFAULT_DIRECTION,
    );
    view.techniques_mut()
        .select(&Combination {
            vertex: "arena".into(),
            parameters: "ssbo-index".into(),
            submission: "individual-indirect-count".into(),
            culling: "gpu-frustum".into(),
        })
        .map_err(|e| e.to_string())?;
    view.render(&graph, &mut tree, &camera)
        .map_err(|e| e.to_string())?;
    view.techniques_mut()
        .select(&Combination::built_in())
        .map_err(|e| e.to_string())?;
    view.render(&graph, &mut tree, &camera)
        .map_err(|e| e.to_string())?;
    view.renderer().read_rgba8().map_err(|e| e.to_string())
}

/// Runs the render on a device of its own and checks that nothing is left behind: no device
/// memory once the view is gone, no validation error (leaked objects included) once the
/// device is gone. A lost device must refuse the next call, saying so.
fn on_a_fresh_device(what: &str) -> Result<image::RgbaImage, String> {
    let device = test_device();
    let log = Arc::clone(device.validation_log());
    let result = render_with_a_swap(&device);
    if device.is_lost() {
        let again = View::new(&device, plugin_registry(&device), SIZE.0, SIZE.1)
            .map(|_| ())
            .map_err(|e| e.to_string());
        assert!(
            again
                .as_ref()
                .is_err_and(|message| message.contains("lost")),
            "{what}: the next call on a lost device must say so: {again:?}"
        );
    }
    assert_eq!(
        device.memory_in_use().0,
        0,
        "{what}: device memory left allocated"
    );
    drop(device);
    let errors = log.errors();
    assert!(errors.is_empty(), "{what}: validation errors: {errors:?}");
    result
}

/// The failure points of a kind that was called `calls` times in a clean run.
fn points(calls: u64) -> Vec<u64> {
    if calls <= MOST_POINTS {
        return (1..=calls).collect();
    }
    let mut points: Vec<u64> = (0..MOST_POINTS)
        .map(|i| 1 + i * (calls - 1) / (MOST_POINTS - 1))
        .collect();
    points.dedup();
    points
}

#[test]
fn every_injected_failure_is_an_error_and_the_host_recovers() {
    fault::disarm();
    let clean = on_a_fresh_device("clean run").unwrap();
    let calls: Vec<(FaultKind, u64)> = FaultKind::ALL
        .iter()
        .map(|&kind| (kind, fault::calls(kind)))
        .collect();
    for &(kind, count) in &calls {
        assert!(count > 0, "a render makes no {} call", kind.name());
        for n in points(count) {
            let what = format!("{}:{n} of {count}", kind.name());
            fault::arm(kind, n);
            let outcome = std::panic::catch_unwind(|| on_a_fresh_device(&what));
            let result = outcome.unwrap_or_else(|_| panic!("{what}: panicked"));
            let message = result.expect_err(&format!("{what}: the failure was not reported"));
            let expected = match kind {
                FaultKind::DeviceMemory | FaultKind::Submit => "out of",
                FaultKind::DeviceLost => "lost",
            };
            assert!(
                message.to_lowercase().contains(expected),
                "{what}: unclear message: {message}"
            );
            // The host starts again and draws what it drew before.
            fault::disarm();
            let again = on_a_fresh_device(&format!("{what}, again")).unwrap();
            let difference = compare(&again, &clean).unwrap();
            assert!(difference.within(SAME_PICTURE), "{what}: {difference:?}");
        }
    }
    println!("failure points per kind (calls in a clean run): {calls:?}");
}
