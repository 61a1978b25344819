//! Injected Vulkan failures (feature `fault-injection`: `cargo nextest run --workspace
//! --features cadr-tests/fault-injection --test fault_injection`, as `scripts/test.sh` does;
//! one test at a time with `cargo test`, `--test-threads=1`): device memory allocations, host
//! memory allocations (through the allocation callbacks), queue submissions and device losses
//! of a render of gen:demo with a technique swap in between, from instance creation on, are
//! made to fail in turn. Each failure must come back as an error with a clear message, never a
//! panic; nothing may leak (device memory and the host memory of Vulkan objects counted,
//! Vulkan objects also by the validation layer at device destruction); a lost device must say
//! so at the next call; and after any failure the host can destroy what it has, create it
//! again and render the same picture. A host allocation the render can do without (a debug
//! name) may fail without an error if the picture stays the same.
//!
//! Every call of each kind is made to fail in turn by default (a render makes about 250
//! that can: see `cadr_core::vk::fault` for those of the driver and the validation
//! layer that are never failed); `CADR_FAULT_POINTS=N` samples N per kind instead, evenly
//! spread.
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
use cadr_core::vk::host_memory::live_object_allocations;
use cadr_core::vk::{Device, DeviceOptions, InstanceOptions};
use cadr_tests::images::{compare, SAME_PICTURE};
use cadr_tests::{plugin_registry, scene_wide};

const SIZE: (u32, u32) = (96, 72);
/// At most this many failure points per kind (evenly spread, the first and last included):
/// every one unless `CADR_FAULT_POINTS` says a number (`all` is accepted too).
fn most_points() -> u64 {
    match std::env::var("CADR_FAULT_POINTS").as_deref() {
        Ok("all") | Err(_) => u64::MAX,
        Ok(text) => text.parse().ok().filter(|&n| n >= 2).unwrap_or_else(|| {
            panic!("CADR_FAULT_POINTS={text}: expected a number from 2, or all")
        }),
    }
}

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
    // A frame that failed keeps the GPU times read before it (none before the first frame's).
    let mut render = |view: &mut View| {
        let before = view.renderer().gpu_pass_times().to_vec();
        view.render(&graph, &mut tree, &camera).map_err(|error| {
            assert_eq!(view.renderer().gpu_pass_times(), before, "after {error}");
            error.to_string()
        })
    };
    view.techniques_mut()
        .select(&scene_wide("individual-indirect-count", "gpu-frustum"))
        .map_err(|e| e.to_string())?;
    render(&mut view)?;
    view.techniques_mut()
        .select(&Combination::built_in())
        .map_err(|e| e.to_string())?;
    render(&mut view)?;
    view.renderer().read_rgba8().map_err(|e| e.to_string())
}

/// Runs the render on a device of its own (whose creation may fail too) and checks that
/// nothing is left behind: no device memory once the view is gone; no host memory of a Vulkan
/// object and no validation error (leaked objects included) once the device is gone. A lost
/// device must refuse the next call, saying so.
///
/// `armed` is the fault injected, if any.
fn on_a_fresh_device(
    what: &str,
    armed: Option<(FaultKind, u64)>,
) -> Result<image::RgbaImage, String> {
    let objects_before = live_object_allocations();
    let options = DeviceOptions {
        instance: InstanceOptions {
            validation: true,
            ..InstanceOptions::default()
        },
        ..DeviceOptions::default()
    };
    let device = match Device::new(&options) {
        Ok(device) => device,
        Err(error) => {
            assert_eq!(
                live_object_allocations(),
                objects_before,
                "{what}: a failed device creation left host memory allocated"
            );
            return Err(error.to_string());
        }
    };
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
    let host_memory_armed = armed.is_some_and(|(kind, _)| kind == FaultKind::HostMemory);
    // Mesa's drivers report each VK_ERROR_OUT_OF_HOST_MEMORY they return through the debug
    // messenger with that name as the whole text, and the loader says it failed to allocate:
    // the injected failure itself, not a misuse.
    let reports_injected_failure = |text: &str| {
        text == "VK_ERROR_OUT_OF_HOST_MEMORY"
            || (text.starts_with("loader_") && text.contains("Failed to allocate"))
    };
    let errors: Vec<String> = log
        .errors()
        .into_iter()
        .filter(|text| !(host_memory_armed && reports_injected_failure(text)))
        .collect();
    assert!(errors.is_empty(), "{what}: validation errors: {errors:?}");
    let leaked = live_object_allocations() - objects_before;
    assert_eq!(
        leaked, 0,
        "{what}: host allocations of Vulkan objects left allocated"
    );
    result
}

/// The failure points of a kind that was called `calls` times in a clean run.
fn points(calls: u64) -> Vec<u64> {
    let most = most_points();
    if calls <= most {
        return (1..=calls).collect();
    }
    let mut points: Vec<u64> = (0..most)
        .map(|i| 1 + i * (calls - 1) / (most - 1))
        .collect();
    points.dedup();
    points
}

/// Fails every call of `kind` in turn (or the sampled points), each on a fresh device; of those
/// points, the ones whose place in the list leaves `remainder` divided by `shares`. One test per
/// kind and share, so that nextest runs them side by side (each test is a process of its own:
/// the armed failure is the process's).
fn every_injected_failure_of(kind: FaultKind, (remainder, shares): (usize, usize)) {
    fault::disarm();
    let clean = on_a_fresh_device("clean run", None).unwrap();
    let count = fault::calls(kind);
    let mut tolerated = Vec::new();
    assert!(count > 0, "a render makes no {} call", kind.name());
    for n in points(count).into_iter().skip(remainder).step_by(shares) {
        let what = format!("{}:{n} of {count}", kind.name());
        fault::arm(kind, n);
        let outcome = std::panic::catch_unwind(|| on_a_fresh_device(&what, Some((kind, n))));
        let result = outcome.unwrap_or_else(|_| panic!("{what}: panicked"));
        match result {
            // A host allocation that a call can do without (an object's debug name) may
            // fail without failing the render; the picture must then be the same.
            Ok(picture) if kind == FaultKind::HostMemory => {
                let difference = compare(&picture, &clean).unwrap();
                assert!(difference.within(SAME_PICTURE), "{what}: {difference:?}");
                tolerated.push(what);
                continue;
            }
            Ok(_) => panic!("{what}: the failure was not reported"),
            Err(message) => {
                let expected = match kind {
                    FaultKind::DeviceMemory | FaultKind::HostMemory | FaultKind::Submit => "out of",
                    FaultKind::DeviceLost => "lost",
                };
                assert!(
                    message.to_lowercase().contains(expected),
                    "{what}: unclear message: {message}"
                );
            }
        }
        // The host starts again and draws what it drew before.
        fault::disarm();
        let again = on_a_fresh_device(&format!("{what}, again"), None).unwrap();
        let difference = compare(&again, &clean).unwrap();
        assert!(difference.within(SAME_PICTURE), "{what}: {difference:?}");
    }
    println!("failures the render did without: {tolerated:?}");
    println!(
        "failure points of {} (calls in a clean run): {count}",
        kind.name()
    );
}

/// Every point of a kind, in one test.
const WHOLE: (usize, usize) = (0, 1);

#[test]
fn every_failed_device_memory_allocation_is_an_error_and_the_host_recovers() {
    every_injected_failure_of(FaultKind::DeviceMemory, WHOLE);
}

// A render makes about five times as many host allocations as device ones (211 against 38 on
// Mesa 25): two tests share them.
#[test]
fn every_failed_host_memory_allocation_is_an_error_and_the_host_recovers_first_share() {
    every_injected_failure_of(FaultKind::HostMemory, (0, 2));
}

#[test]
fn every_failed_host_memory_allocation_is_an_error_and_the_host_recovers_second_share() {
    every_injected_failure_of(FaultKind::HostMemory, (1, 2));
}

#[test]
fn every_failed_submission_is_an_error_and_the_host_recovers() {
    every_injected_failure_of(FaultKind::Submit, WHOLE);
}

#[test]
fn every_lost_device_is_an_error_and_the_host_recovers() {
    every_injected_failure_of(FaultKind::DeviceLost, WHOLE);
}
