//! The C API from C: a suite that calls every function with good and bad arguments, built with
//! the strict flags, run as is and under AddressSanitizer with leak checking.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::process::Command;

use cadr_tests::c_programs::{build_c_program, describe, repository, scratch_dir};

/// Builds `sources` into a program, runs it and returns its standard output, failing the test
/// unless it succeeded and said its checks passed.
fn run_program(name: &str, sources: &[&str], extra: &[&str], env: &[(&str, String)]) -> String {
    let dir = scratch_dir(name);
    let program = dir.join("program");
    let sources: Vec<_> = sources.iter().map(|s| repository().join(s)).collect();
    build_c_program(&sources, &program, extra);
    let output = Command::new(&program)
        .env("CADR_TEST_OUT", &dir)
        .envs(env.iter().map(|(k, v)| (k, v)))
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", describe(&output));
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    assert!(stdout.contains("checks passed"), "{}", describe(&output));
    stdout
}

#[test]
fn every_function_and_error_path_from_c() {
    run_program("c-api", &["tests/c/api_suite.c"], &[], &[]);
}

/// A host that creates the Vulkan instance and device itself and lends them to cadr
/// (`cadr_context_create_from_vulkan`): see `tests/c/host_vulkan.c`.
#[test]
fn a_context_on_the_hosts_vulkan_draws_what_one_on_its_own_device_draws() {
    run_program(
        "c-host-vulkan",
        &["tests/c/host_vulkan.c"],
        &["-lvulkan", "-lpthread"],
        &[],
    );
}

/// An OpenGL host's hand-over of exported frames by semaphores, played by a second Vulkan
/// device (`tests/c/export_semaphores.c`): on SwiftShader, which exports semaphores as file
/// descriptors, every frame the host reads is the renderer's; on lavapipe, which cannot, the
/// call is refused naming the extension.
#[test]
fn exported_frames_are_handed_over_by_semaphores_where_the_driver_shares_them() {
    let program = "tests/c/export_semaphores.c";
    let output = run_program("c-export-semaphores", &[program], &["-lvulkan"], &[]);
    assert!(output.contains("semaphores unsupported"), "{output}");
    let icd = cadr_tests::swiftshader_manifest().display().to_string();
    let output = run_program(
        "c-export-semaphores-swiftshader",
        &[program],
        &["-lvulkan"],
        &[("VK_ICD_FILENAMES", icd)],
    );
    assert!(
        output.contains("9 frames handed over by semaphores"),
        "{output}"
    );
}

/// The same suite with AddressSanitizer: no invalid access anywhere in the C program, and no
/// leak anywhere in the process (cadr's Rust code allocates through the same malloc). Leaks of
/// the Vulkan driver and layers, which cadr does not own, are suppressed by library name.
#[test]
fn the_suite_under_address_sanitizer_finds_no_leak_or_invalid_access() {
    let suppressions = repository().join("tests/c/lsan.supp");
    run_program(
        "c-api-asan",
        // Unloaded drivers and layers would hide who kept memory: see keep_libraries_loaded.c.
        &["tests/c/api_suite.c", "tests/c/keep_libraries_loaded.c"],
        // Linking the Vulkan loader keeps it mapped until exit, so that what it keeps for the
        // process is attributed to it (and suppressed) instead of to an unloaded module.
        &[
            "-fsanitize=address",
            "-fno-omit-frame-pointer",
            "-Wl,--no-as-needed",
            "-lvulkan",
        ],
        &[
            (
                "ASAN_OPTIONS",
                "detect_leaks=1:abort_on_error=0:exitcode=23".to_owned(),
            ),
            (
                "LSAN_OPTIONS",
                format!(
                    "suppressions={}:print_suppressions=0",
                    suppressions.display()
                ),
            ),
        ],
    );
}

/// Threads, atomics and thread-local storage are C11.
const THREADS: [&str; 2] = ["-std=c11", "-pthread"];

/// Two renderers drawing and picking one scene on two threads while a third edits it and a
/// fourth loads scenes, then a renderer destroyed while a thread draws with it: every call
/// succeeds or is refused with a result, with validation on.
#[test]
fn the_api_from_several_threads_at_once() {
    run_program("c-api-threads", &["tests/c/threads.c"], &THREADS, &[]);
}

/// The same under ThreadSanitizer: no data race on what the C program's threads share and
/// hand to cadr. cadr's own Rust code cannot be instrumented on the stable compiler, and its
/// locks are futexes TSan cannot see, so what its library calls is suppressed
/// (`tests/c/tsan.supp`); safe Rust has no data races, and its unsafe hand-overs between
/// threads are the renderer and scene locks this test exercises. TSan's lock-order (deadlock)
/// detector is off: the program takes no lock of its own, cadr's are invisible to TSan, and
/// lavapipe's LLVM JIT holds more than the detector's 64 locks at once while it compiles a
/// large shader (a CHECK failure inside TSan); a deadlock would hang the test, which fails it.
#[test]
fn the_threads_test_under_thread_sanitizer_finds_no_race() {
    let suppressions = repository().join("tests/c/tsan.supp");
    run_program(
        "c-api-threads-tsan",
        // Suppressions by library need the libraries mapped until exit.
        &["tests/c/threads.c", "tests/c/keep_libraries_loaded.c"],
        &[
            &THREADS[..],
            &["-fsanitize=thread", "-fno-omit-frame-pointer"],
        ]
        .concat(),
        &[(
            "TSAN_OPTIONS",
            format!(
                "halt_on_error=1:exitcode=66:detect_deadlocks=0:suppressions={}",
                suppressions.display()
            ),
        )],
    );
}
