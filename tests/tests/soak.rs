//! The short soak: the C host of `scripts/soak.sh` (`tests/c/soak.c`) loads the 2CylinderEngine,
//! edits, renders, picks, swaps techniques and unloads it, over and over with validation on;
//! after a warm-up, neither the process's resident memory nor the device memory cadr holds may
//! grow past a small bound. The same host keeping every file it loads must fail that check.
//!
//! It runs on SwiftShader (`scripts/setup.sh` fetches it), as `scripts/soak.sh` does by
//! default: Debian 12's lavapipe (Mesa 22.3) itself keeps about 0.3 MB on its queue thread for
//! every pick, which SwiftShader and Mesa 25's lavapipe do not (docs/BENCHMARKS.md, "Soak").
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::path::PathBuf;
use std::process::{Command, Output};

use cadr_tests::c_programs::{build_c_program, describe, repository, scratch_dir, ScratchDir};
use cadr_tests::{swiftshader_manifest, CYLINDER_ENGINE_GLB};

/// Iterations in all, and of them the warm-up's (at least the 8 technique combinations the
/// host cycles through, so that each one's pipelines exist before memory is compared).
const ITERATIONS: &str = "40";
const WARMUP_ITERATIONS: &str = "12";
/// How much either memory may grow after the warm-up, in percent of the warm-up's peak. The
/// 30-minute soak holds 1 %; this short run allows the allocator more room for noise, and a
/// leak of one 2CylinderEngine per iteration would still pass it within a few iterations.
const MAX_GROWTH_PERCENT: &str = "3";

/// The soak host, built into a scratch directory (which lives as long as the first value).
fn soak_program() -> (ScratchDir, PathBuf) {
    let dir = scratch_dir("soak");
    let program = dir.join("soak");
    let samples = repository().join("samples");
    let include_samples = format!("-I{}", samples.display());
    build_c_program(
        &[
            repository().join("tests/c/soak.c"),
            samples.join("common/sample.c"),
        ],
        &program,
        &[&include_samples],
    );
    (dir, program)
}

fn soak(program: &PathBuf, (iterations, warmup): (&str, &str), extra: &[&str]) -> Output {
    Command::new(program)
        .args([
            "--scene",
            "gen:demo",
            "--load",
            CYLINDER_ENGINE_GLB,
            "--size",
            "160x120",
            "--validation",
            "--iterations",
            iterations,
            "--warmup-iterations",
            warmup,
            "--max-growth-percent",
            MAX_GROWTH_PERCENT,
        ])
        .args(extra)
        .env("VK_ICD_FILENAMES", swiftshader_manifest())
        .env_remove("CADR_DEVICE")
        .output()
        .unwrap()
}

#[test]
fn memory_stays_flat_while_a_host_loads_edits_renders_picks_and_swaps() {
    let (_dir, program) = soak_program();
    let flat = soak(&program, (ITERATIONS, WARMUP_ITERATIONS), &[]);
    let stdout = String::from_utf8_lossy(&flat.stdout);
    println!("{stdout}");
    assert!(
        flat.status.success()
            && stdout.contains("SwiftShader")
            && stdout.contains("soak: flat within 3.00 %"),
        "{}",
        describe(&flat)
    );
    assert!(
        stdout.contains(&format!("soak: {ITERATIONS} iterations")),
        "{}",
        describe(&flat)
    );

    // A host that never unloads grows by a 2CylinderEngine an iteration: three after the
    // warm-up's eight (one per technique combination) are enough. Each iteration draws every
    // copy kept, so each takes longer than the last (16 iterations took 56 s here, 11 take 16 s).
    let growing = soak(&program, ("11", "8"), &["--keep-loaded"]);
    assert_eq!(growing.status.code(), Some(1), "{}", describe(&growing));
    assert!(
        String::from_utf8_lossy(&growing.stderr).contains("memory grew by more than 3.00 %"),
        "keeping every loaded file must fail the check: {}",
        describe(&growing)
    );
    // And cadr's own host memory shows it, whatever the driver's heap does.
    let growth = String::from_utf8_lossy(&growing.stdout)
        .lines()
        .find_map(|line| line.strip_prefix("soak: cadr's own host memory: "))
        .and_then(|line| line.rsplit_once('(').map(|(_, percent)| percent.to_owned()))
        .and_then(|percent| percent.trim_end_matches(" %)").parse::<f64>().ok())
        .unwrap_or_else(|| panic!("no cadr host memory line: {}", describe(&growing)));
    assert!(growth > 3.0, "cadr's own host memory grew {growth} %");
}
