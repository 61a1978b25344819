//! The `cadr` command as a user runs it.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::process::{Command, Output};

use cadr_tests::c_programs::scratch_dir;

/// Runs `cadr` with the plugins cargo built (in `deps/` beside the binary: the test build makes
/// them as dependencies of the integration tests).
fn cadr(args: &[&str]) -> Output {
    let exe = std::path::Path::new(env!("CARGO_BIN_EXE_cadr"));
    let deps = exe.parent().unwrap().join("deps");
    Command::new(exe)
        .args(args)
        .env("CADR_PLUGIN_PATH", deps)
        .output()
        .expect("run cadr")
}

/// A small bench of `scene` (2 frames at 64×48, per-geometry / push / individual) with
/// `settings`, its JSON written to `json_path`: the run (which must succeed) and the JSON.
fn small_bench(
    scene: &str,
    json_path: &std::path::Path,
    settings: &[&str],
) -> (Output, serde_json::Value) {
    small_bench_of(scene, "individual", json_path, settings)
}

/// As `small_bench`, measuring the submission techniques `submit` (comma-separated).
fn small_bench_of(
    scene: &str,
    submit: &str,
    json_path: &std::path::Path,
    settings: &[&str],
) -> (Output, serde_json::Value) {
    let mut args = vec![
        "bench",
        scene,
        "--frames",
        "2",
        "--size",
        "64x48",
        "--vertex",
        "per-geometry",
        "--params",
        "push",
        "--submit",
        submit,
        "--json",
        json_path.to_str().unwrap(),
    ];
    args.extend_from_slice(settings);
    let output = cadr(&args);
    assert!(output.status.success(), "{}", stderr(&output));
    let json = serde_json::from_str(&std::fs::read_to_string(json_path).unwrap()).unwrap();
    (output, json)
}

fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

#[test]
fn info_prints_the_statistics() {
    let output = cadr(&["info", "gen:grid:parts=1000"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let text = stdout(&output);
    for expected in [
        "nodes:",
        "geometries:",
        "parts:",
        "materials:",
        "triangles:",
        "vertices:",
        "bounds:",
    ] {
        assert!(text.contains(expected), "missing {expected} in:\n{text}");
    }
    assert!(
        text.contains("instances:        1000 (paths to drawable parts)"),
        "{text}"
    );
    // gen:grid's parts are closed prisms.
    assert!(
        text.contains("closed parts:     160 of 160, 0 more inside out"),
        "{text}"
    );
}

#[test]
fn render_writes_a_png_and_reports_the_frame() {
    let scratch = scratch_dir("cli-render");
    let path = scratch.join("out.png");
    let output = cadr(&[
        "render",
        "gen:grid:parts=300",
        "-o",
        path.to_str().unwrap(),
        "--size",
        "80x60",
        "--frames",
        "3",
        "--validation",
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let text = stdout(&output);
    assert!(text.contains("300 parts"), "{text}");
    assert!(text.contains("300 draw calls"), "{text}");
    assert!(text.contains("median of 3"), "{text}");
    assert!(text.contains("GPU") && text.contains("µs"), "{text}");
    assert!(text.contains("validation:  0 errors"), "{text}");
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    assert_eq!(u32::from_be_bytes(bytes[16..20].try_into().unwrap()), 80);
}

#[test]
fn bad_input_gives_a_clear_error_and_exit_code() {
    // Work that fails exits with 1; a wrong command line with 2, as clap's programs do.
    for (args, code, expected) in [
        (
            vec!["render", "/nonexistent/engine.glb"],
            1,
            "/nonexistent/engine.glb",
        ),
        (vec!["info", "gen:grid:parts=-5"], 1, "not a whole number"),
        (
            vec!["render", "gen:demo", "--size", "big"],
            2,
            "invalid value 'big' for '--size <WxH>': expected WIDTHxHEIGHT",
        ),
        (
            vec!["render", "gen:demo", "--frames", "0"],
            2,
            "invalid value '0' for '--frames <N>'",
        ),
        (
            vec!["render", "gen:demo", "--colour", "red"],
            2,
            "unexpected argument '--colour'",
        ),
        (
            vec!["info", "a.glb", "b.glb"],
            2,
            "unexpected argument 'b.glb'",
        ),
        (vec!["explode"], 2, "unrecognized subcommand 'explode'"),
        (
            vec!["render", "gen:demo", "-o"],
            2,
            "a value is required for '--output",
        ),
        (
            vec!["convert", "gen:demo"],
            2,
            "required arguments were not provided",
        ),
        (
            vec!["bench", "--shade", "toon"],
            2,
            "[possible values: solid, edges, hidden-line, wireframe, xray, all]",
        ),
    ] {
        let output = cadr(&args);
        assert_eq!(output.status.code(), Some(code), "{args:?}");
        let text = stderr(&output);
        assert!(
            text.starts_with("error: ") && text.contains(expected),
            "{args:?}: {text}"
        );
    }
}

#[test]
fn a_misspelt_option_gets_a_suggestion_and_every_command_its_help() {
    let output = cadr(&["render", "gen:demo", "--frame", "3"]);
    assert_eq!(output.status.code(), Some(2));
    assert!(
        stderr(&output).contains("a similar argument exists: '--frames'"),
        "{}",
        stderr(&output)
    );
    for (command, option) in [
        ("render", "--min-pixels <PX>"),
        ("bench", "--sweep-parts <N,N,...>"),
        ("pick", "--rect <X2,Y2>"),
    ] {
        let output = cadr(&[command, "--help"]);
        assert!(output.status.success(), "{command}");
        assert!(
            stdout(&output).contains(option),
            "{command}: {}",
            stdout(&output)
        );
    }
    let output = cadr(&["--version"]);
    assert_eq!(
        stdout(&output).trim(),
        format!("cadr {}", env!("CARGO_PKG_VERSION"))
    );
}

#[test]
fn completions_name_the_commands_for_each_shell() {
    for shell in ["bash", "zsh", "fish"] {
        let output = cadr(&["completions", shell]);
        assert!(output.status.success(), "{shell}: {}", stderr(&output));
        let script = stdout(&output);
        for word in ["render", "bench-tree", "min-pixels", "sweep-parts"] {
            assert!(script.contains(word), "{shell} completions lack {word}");
        }
    }
    let output = cadr(&["completions", "tcsh"]);
    assert_eq!(output.status.code(), Some(2));
}

#[test]
fn convert_writes_csf_and_gltf_that_info_reads() {
    let dir = scratch_dir("cli-convert");
    let csf = dir.join("grid.csf.gz");
    let output = cadr(&["convert", "gen:grid:parts=120", csf.to_str().unwrap()]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(
        stdout(&output).contains("120 parts drawn"),
        "{}",
        stdout(&output)
    );
    let glb = dir.join("grid.glb");
    let output = cadr(&["convert", csf.to_str().unwrap(), glb.to_str().unwrap()]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(
        stdout(&output).contains("note: ") && stdout(&output).contains("edges"),
        "{}",
        stdout(&output)
    );
    let output = cadr(&["info", glb.to_str().unwrap()]);
    assert!(
        stdout(&output).contains("instances:        120 "),
        "{}",
        stdout(&output)
    );
    let output = cadr(&["convert", "gen:demo", "out.stl"]);
    assert!(
        stderr(&output).contains("unknown output format"),
        "{}",
        stderr(&output)
    );
}

#[test]
fn bench_tree_prints_ratios_memory_and_uploads() {
    let output = cadr(&["bench-tree", "gen:grid:parts=2000", "--runs", "3"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let text = stdout(&output);
    for expected in [
        "build tree:",
        "bytes per instance besides matrices",
        "1 transform (1)",
        "1% of transforms",
        "100% of transforms",
        "goal 1% of transforms",
    ] {
        assert!(text.contains(expected), "missing {expected} in:\n{text}");
    }
    // One moved part uploads one matrix to the GPU scene behind its slot (4 + 64 bytes) and
    // no instance record.
    let one = text
        .lines()
        .find(|l| l.starts_with("1 transform (1)"))
        .unwrap();
    let columns: Vec<&str> = one.split_whitespace().collect();
    assert_eq!(
        columns[columns.len() - 3..],
        ["1", "0", "68"],
        "matrices, records, bytes: {one}"
    );
}

#[test]
fn help_lists_the_commands_and_generators() {
    let output = cadr(&["--help"]);
    assert!(output.status.success());
    let text = stdout(&output);
    for expected in [
        "Usage: cadr [OPTIONS] <COMMAND>",
        "  render ",
        "  bench-tree ",
        "  completions ",
        "gen:graphicscard",
        "gen:racecar",
        "gen:grid:parts=N",
    ] {
        assert!(text.contains(expected), "{expected}");
    }
}

#[test]
fn techniques_lists_every_kind_with_support() {
    let output = cadr(&["techniques", "--json"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let json: serde_json::Value = serde_json::from_str(&stdout(&output)).unwrap();
    let techniques = json["techniques"].as_array().unwrap();
    for (kind, name) in [
        ("vertex", "pulling"),
        ("params", "ssbo-index"),
        ("submit", "groups-replay"),
        ("cull", "frustum"),
    ] {
        let found = techniques
            .iter()
            .find(|t| t["kind"] == kind && t["name"] == name)
            .unwrap_or_else(|| panic!("{kind} {name} missing"));
        assert_eq!(found["supported"], true, "{found}");
        assert!(!found["description"].as_str().unwrap().is_empty());
    }
    let text = stdout(&cadr(&["techniques"]));
    assert!(
        text.contains("submit techniques (--submit NAME; default individual)"),
        "{text}"
    );
}

#[test]
fn render_uses_the_chosen_techniques_and_refuses_bad_combinations() {
    let scratch = scratch_dir("cli-techniques");
    let path = scratch.join("out.png");
    let output = cadr(&[
        "render",
        "gen:demo",
        "-o",
        path.to_str().unwrap(),
        "--size",
        "96x72",
        "--vertex",
        "arena",
        "--params",
        "ssbo-index",
        "--submit",
        "groups-mdi",
        "--shade",
        "edges",
        "--validation",
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let text = stdout(&output);
    assert!(
        text.contains("techniques:  arena / ssbo-index / groups-mdi / none, edges"),
        "{text}"
    );
    assert!(
        text.contains("2 draw calls"),
        "one indirect call per pass: {text}"
    );
    assert!(text.contains("validation:  0 errors"), "{text}");
    assert!(path.exists());

    let output = cadr(&[
        "render",
        "gen:demo",
        "-o",
        path.to_str().unwrap(),
        "--submit",
        "individual-mdi",
    ]);
    assert!(!output.status.success());
    assert!(
        stderr(&output).contains("submit 'individual-mdi' needs"),
        "{}",
        stderr(&output)
    );
    let output = cadr(&[
        "render",
        "gen:demo",
        "-o",
        path.to_str().unwrap(),
        "--vertex",
        "wobbly",
    ]);
    assert!(!output.status.success());
    assert!(
        stderr(&output)
            .contains("no vertex technique named 'wobbly' (known: per-geometry, per-part"),
        "{}",
        stderr(&output)
    );
    let output = cadr(&[
        "render",
        "gen:demo",
        "-o",
        path.to_str().unwrap(),
        "--shade",
        "toon",
    ]);
    assert!(
        stderr(&output).contains("invalid value 'toon' for '--display <MODE>'"),
        "{}",
        stderr(&output)
    );
}

#[test]
fn bench_prints_the_table_and_writes_json() {
    let scratch = scratch_dir("cli-bench");
    let path = scratch.join("out.json");
    let (output, json) =
        small_bench_of("gen:grid:parts=500", "individual,groups-replay", &path, &[]);
    let text = stdout(&output);
    assert!(text.contains("baseline (built-in)"), "{text}");
    assert!(
        text.contains("per-geometry / push / groups-replay / none"),
        "{text}"
    );
    let rows = json["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 3, "baseline and two combinations");
    assert_eq!(json["scene"]["parts"], 500);
    assert_eq!(rows[0]["speedup"], 1.0);
    for row in rows {
        assert!(row["cpu_us"].as_f64().unwrap() > 0.0, "{row}");
        // The driver's submission call is a part of the frame's CPU time, not all of it.
        let submit = row["cpu_submit_us"].as_f64().unwrap();
        assert!(
            submit > 0.0 && submit < row["cpu_us"].as_f64().unwrap(),
            "{row}"
        );
        assert_eq!(row["triangles"], rows[0]["triangles"], "{row}");
    }
    assert_eq!(rows[1]["draw_calls"], 500, "individual: one call per part");
    // The still camera changes nothing: the baseline records every frame, the others resubmit
    // (the frames after the two warm-up frames) and report the recorded frame's counters.
    assert_eq!(rows[0]["replayed_frames"], 0, "{}", rows[0]);
    assert_eq!(rows[1]["replayed_frames"], 2, "{}", rows[1]);
    assert_eq!(rows[2]["replayed_frames"], 2, "{}", rows[2]);
    assert_eq!(json["frame_replay"], true);
    // The driver's floor under every replayed frame, measured in the same run.
    assert!(json["submit_floor_us"].as_f64().unwrap() > 0.0, "{json}");
    assert!(text.contains("floor: the driver takes"), "{text}");
    // What the picture covers: every row draws the same one, whose parts with a pixel are those a
    // pick over the whole view finds, and the triangles are counted against its pixels.
    let picked = cadr(&[
        "pick",
        "gen:grid:parts=500",
        "0",
        "0",
        "--size",
        "64x48",
        "--rect",
        "63,47",
        "--json",
    ]);
    assert!(picked.status.success(), "{}", stderr(&picked));
    let picked: serde_json::Value = serde_json::from_str(&stdout(&picked)).unwrap();
    let parts_picked = picked["hits"].as_array().unwrap().len() as u64;
    assert!(parts_picked > 10, "{picked}");
    for row in rows {
        let covered = row["covered_pixels"].as_u64().unwrap();
        assert!(covered > 0 && covered < 64 * 48, "{row}");
        assert_eq!(row["covered_pixels"], rows[0]["covered_pixels"], "{row}");
        assert_eq!(
            row["parts_with_pixels"].as_u64(),
            Some(parts_picked),
            "{row}"
        );
        let per_pixel = row["triangles_per_covered_pixel"].as_f64().unwrap();
        let rasterized = row["triangles_rasterized"].as_f64().unwrap();
        assert!(
            (per_pixel - rasterized / covered as f64).abs() < 1e-9,
            "{row}"
        );
    }

    let (_, json) = small_bench("gen:grid:parts=500", &path, &["--no-replay"]);
    let rows = json["rows"].as_array().unwrap();
    assert_eq!(
        rows[1]["replayed_frames"], 0,
        "--no-replay records every frame"
    );
    assert_eq!(rows[1]["draw_calls"], 500);
}

/// `bench --section` cuts every row; in the edges mode, seen from the cut side, the caps pass
/// draws the parts a third time (after the surfaces and the lines), and `--no-caps` drops it.
#[test]
fn bench_measures_a_sectioned_scene_with_and_without_caps() {
    let scratch = scratch_dir("cli-bench-section");
    let path = scratch.join("out.json");
    // The fitted camera looks from +z: it sees the cut side of a plane keeping z <= 1.6.
    let plane = "--section=0,0,-2,3.2";
    let (output, json) = small_bench("gen:grid:parts=200", &path, &["--display", "edges", plane]);
    assert!(
        stdout(&output).contains("1 section plane, capped"),
        "{}",
        stdout(&output)
    );
    assert_eq!(
        json["section"]["planes"],
        serde_json::json!([[0.0, 0.0, -1.0, 1.6]])
    );
    assert_eq!(json["section"]["caps"], true);
    let rows = json["rows"].as_array().unwrap();
    assert_eq!(rows[1]["shade"], "edges");
    assert_eq!(
        rows[1]["draw_calls"], 600,
        "surfaces, lines, caps: {}",
        rows[1]
    );
    let (_, json) = small_bench(
        "gen:grid:parts=200",
        &path,
        &["--display", "edges", plane, "--no-caps"],
    );
    assert_eq!(json["section"]["caps"], false);
    assert_eq!(json["rows"][1]["draw_calls"], 400, "{}", json["rows"][1]);
    let (_, json) = small_bench("gen:grid:parts=200", &path, &[]);
    assert_eq!(json["section"], serde_json::Value::Null);
    let output = cadr(&["bench", "gen:grid:parts=200", "--section=0,0,0,1"]);
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("the normal not zero"),
        "{}",
        stderr(&output)
    );
}

#[test]
fn bench_animate_moves_assemblies_on_the_gpu_with_64_bytes_per_node() {
    let scratch = scratch_dir("cli-animate");
    let path = scratch.join("out.json");
    let output = cadr(&[
        "bench",
        "gen:cabinet:cabinets=2",
        "--frames",
        "3",
        "--size",
        "64x48",
        "--vertex",
        "arena",
        "--params",
        "ssbo-index",
        "--submit",
        "individual-indirect-count",
        "--cull",
        "none,gpu-frustum",
        "--camera",
        "orbit",
        "--animate",
        "4",
        "--json",
        path.to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    assert_eq!(json["camera"], "orbit");
    assert_eq!(json["animate"], 4);
    let rows = json["rows"].as_array().unwrap();
    let row = |technique: &str| {
        rows.iter()
            .find(|r| r["technique"] == technique)
            .unwrap_or_else(|| panic!("no row {technique}: {rows:?}"))
    };
    for technique in [
        "arena / ssbo-index / individual-indirect-count / none",
        "arena / ssbo-index / individual-indirect-count / gpu-frustum",
    ] {
        let gpu = row(technique);
        assert_eq!(gpu["transforms"], "gpu", "{gpu}");
        assert_eq!(
            gpu["bytes_uploaded"],
            4 * 64,
            "a slot and a local matrix per moved node: {gpu}"
        );
        assert!(gpu["scene_update_us"].as_f64().unwrap() > 0.0, "{gpu}");
        // Every frame uploads the moved nodes before its passes.
        let passes: Vec<&str> = gpu["gpu_pass_us"]
            .as_array()
            .unwrap()
            .iter()
            .map(|pass| {
                assert!(pass["us"].as_f64().unwrap() >= 0.0, "{gpu}");
                pass["pass"].as_str().unwrap()
            })
            .collect();
        assert_eq!(
            passes[..3],
            ["uploads", "prepare and cull", "surfaces phase 0"],
            "{gpu}"
        );
    }
    // The baseline (push constants) reads matrices on the host.
    let host = row("baseline (built-in)");
    assert_eq!(host["transforms"], "host", "{host}");
    assert!(
        host["bytes_uploaded"].as_u64().unwrap() > 4 * 64,
        "the host uploads the world matrices below the moved nodes: {host}"
    );
}

#[test]
fn without_plugin_libraries_the_built_in_combination_draws_and_others_are_explained() {
    // A copy of the binary in a directory of its own finds no plugin library.
    let dir = scratch_dir("cli-alone");
    let exe = dir.join("cadr");
    std::fs::copy(env!("CARGO_BIN_EXE_cadr"), &exe).unwrap();
    let alone = |args: &[&str]| {
        Command::new(&exe)
            .args(args)
            .env_remove("CADR_PLUGIN_PATH")
            .output()
            .expect("run the copied cadr")
    };
    let png = dir.join("built-in.png");
    let output = alone(&[
        "render",
        "gen:demo",
        "-o",
        png.to_str().unwrap(),
        "--size",
        "64x48",
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(
        stdout(&output).contains("techniques:  per-geometry / push / individual / none, solid"),
        "{}",
        stdout(&output)
    );
    assert!(png.exists());

    let output = alone(&[
        "render",
        "gen:demo",
        "-o",
        png.to_str().unwrap(),
        "--submit",
        "groups",
    ]);
    assert!(!output.status.success());
    let text = stderr(&output);
    assert!(
        text.contains("no submit technique named 'groups' (known: individual)")
            && text.contains("no technique plugin library found, only the built-in techniques"),
        "{text}"
    );

    let output = alone(&["techniques", "--json"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let listing: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    let techniques = listing["techniques"].as_array().unwrap();
    assert_eq!(
        techniques.len(),
        5,
        "one built-in technique per kind: {listing}"
    );
    assert!(techniques
        .iter()
        .all(|t| t["built_in"] == true && t["library"] == "built-in" && t["supported"] == true));
}

#[test]
fn render_min_pixels_culls_small_parts_on_the_gpu_and_is_refused_elsewhere() {
    let scratch = scratch_dir("cli-subpixel");
    let path = scratch.join("out.png");
    let triangles = |extra: &[&str]| {
        let mut arguments = vec![
            "render",
            "gen:grid:parts=512",
            "-o",
            path.to_str().unwrap(),
            "--size",
            "200x150",
            "--vertex",
            "arena",
            "--params",
            "ssbo-index",
            "--submit",
            "individual-indirect-count",
            "--cull",
            "gpu-frustum",
            "--validation",
        ];
        arguments.extend_from_slice(extra);
        let output = cadr(&arguments);
        assert!(output.status.success(), "{}", stderr(&output));
        let text = stdout(&output);
        assert!(text.contains("validation:  0 errors"), "{text}");
        let drawn = text
            .lines()
            .find_map(|line| line.strip_prefix("drawn:"))
            .unwrap_or_else(|| panic!("no drawn line: {text}"));
        let count: u64 = drawn
            .split(", ")
            .find_map(|field| field.strip_suffix(" triangles"))
            .and_then(|n| n.trim().parse().ok())
            .unwrap_or_else(|| panic!("no triangles in: {drawn}"));
        (count, text)
    };
    let (all, _) = triangles(&[]);
    let (culled, text) = triangles(&["--min-pixels", "8"]);
    assert!(
        culled < all && culled > 0,
        "parts under 8 px are skipped: {culled} of {all} triangles"
    );
    assert!(text.contains("parts under 8 px culled"), "{text}");

    let output = cadr(&[
        "render",
        "gen:demo",
        "--cull",
        "frustum",
        "--min-pixels",
        "4",
    ]);
    assert!(!output.status.success());
    assert!(
        stderr(&output).contains("--min-pixels culls on the GPU"),
        "{}",
        stderr(&output)
    );
    let output = cadr(&["render", "gen:demo", "--min-pixels", "-1"]);
    assert!(!output.status.success());
    assert!(
        stderr(&output).contains(
            "invalid value '-1' for '--min-pixels <PX>': expected a number of pixels >= 0"
        ),
        "{}",
        stderr(&output)
    );
}

#[test]
fn the_disk_cache_serves_the_second_run_and_survives_damaged_entries() {
    let dir = scratch_dir("cli-cache");
    let png = dir.join("frame.png");
    let cache = dir.join("cache");
    let exe = std::path::Path::new(env!("CARGO_BIN_EXE_cadr"));
    let render = |cache: &std::path::Path, extra: &[&str]| {
        let output = Command::new(exe)
            .args(["render", "gen:demo", "-o"])
            .arg(&png)
            .args([
                "--size",
                "96x72",
                "--vertex",
                "arena",
                "--params",
                "ssbo-index",
            ])
            .args([
                "--submit",
                "individual-indirect-count",
                "--cull",
                "gpu-frustum",
            ])
            .arg("--validation")
            .args(extra)
            .env("CADR_PLUGIN_PATH", exe.parent().unwrap().join("deps"))
            .env("CADR_CACHE_DIR", cache)
            .output()
            .expect("run cadr");
        assert!(output.status.success(), "{}", stderr(&output));
        assert!(
            stdout(&output).contains("validation:  0 errors"),
            "{}",
            stdout(&output)
        );
        std::fs::read(&png).unwrap()
    };
    let entries = |kind: &str| -> Vec<(std::path::PathBuf, std::time::SystemTime)> {
        let mut files: Vec<_> = std::fs::read_dir(cache.join(kind))
            .map(|dir| {
                dir.map(|e| e.unwrap().path())
                    .map(|p| {
                        (
                            p.clone(),
                            std::fs::metadata(&p).unwrap().modified().unwrap(),
                        )
                    })
                    .collect()
            })
            .unwrap_or_default();
        files.sort();
        files
    };

    let first = render(&cache, &[]);
    let shaders = entries("spirv");
    assert!(shaders.len() >= 3, "compiled shaders are kept: {shaders:?}");
    assert_eq!(
        entries("pipelines").len(),
        1,
        "the device's pipeline cache is kept"
    );
    for (path, _) in shaders.iter().chain(&entries("pipelines")) {
        assert!(
            std::fs::read(path).unwrap().starts_with(b"CADRCACH"),
            "{path:?}"
        );
    }

    // The second run finds every shader: none is compiled and written again.
    let second = render(&cache, &[]);
    assert_eq!(
        first, second,
        "the cached shaders and pipelines draw the same image"
    );
    assert_eq!(entries("spirv"), shaders, "no shader entry was rewritten");

    // Damaged, truncated and foreign entries are ignored and rewritten, never trusted.
    for (index, (path, _)) in shaders.iter().chain(&entries("pipelines")).enumerate() {
        let mut bytes = std::fs::read(path).unwrap();
        match index % 3 {
            0 => bytes.truncate(bytes.len() / 2),
            1 => {
                let last = bytes.len() - 1;
                bytes[last] ^= 0x5a;
            }
            _ => bytes = b"not a cadr cache entry".to_vec(),
        }
        std::fs::write(path, bytes).unwrap();
    }
    let third = render(&cache, &[]);
    assert_eq!(first, third, "damaged entries change nothing drawn");
    for (path, _) in entries("spirv").iter().chain(&entries("pipelines")) {
        let bytes = std::fs::read(path).unwrap();
        assert!(
            bytes.starts_with(b"CADRCACH") && bytes.len() > 40,
            "{path:?} was rewritten"
        );
    }

    // --no-cache neither reads nor writes.
    let untouched = dir.join("untouched");
    let fourth = render(&untouched, &["--no-cache"]);
    assert_eq!(first, fourth);
    assert!(!untouched.exists(), "--no-cache wrote {untouched:?}");
}

#[test]
fn render_timings_split_the_run_into_its_phases() {
    let scratch = scratch_dir("cli-timings");
    let path = scratch.join("out.png");
    let output = cadr(&[
        "render",
        "gen:demo",
        "-o",
        path.to_str().unwrap(),
        // Large enough that the readback and the PNG take a measurable time: at 64×48 the
        // readback (12 KB) once took under the 0.05 ms the report rounds to 0.0.
        "--size",
        "640x480",
        "--timings",
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let text = stdout(&output);
    let total: f64 = text
        .lines()
        .find_map(|l| l.strip_prefix("timings:"))
        .and_then(|rest| rest.split_whitespace().next())
        .and_then(|ms| ms.parse().ok())
        .unwrap_or_else(|| panic!("no total in:\n{text}"));
    let mut sum = 0.0;
    for phase in [
        "device",
        "load",
        "scene build",
        "upload",
        "shader compile",
        "pipeline creation",
        "first frame",
        "readback",
        "png encode",
        "other",
    ] {
        let line = text
            .lines()
            .find(|l| l.trim_start().starts_with(phase) && l.contains(" ms "))
            .unwrap_or_else(|| panic!("no {phase} line in:\n{text}"));
        let ms: f64 = line.trim_start()[phase.len()..]
            .split_whitespace()
            .next()
            .and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("no figure in {line}"));
        if phase != "other" {
            assert!(ms > 0.0, "{phase} took no time: {line}");
        }
        sum += ms;
    }
    // The frame's GPU time, pass by pass.
    let gpu_passes = text
        .lines()
        .find(|l| l.starts_with("gpu passes:"))
        .unwrap_or_else(|| panic!("no gpu passes line in:\n{text}"));
    for pass in ["surfaces phase 0 ", "background "] {
        assert!(gpu_passes.contains(pass), "no {pass}in {gpu_passes}");
    }
    let memory = text
        .lines()
        .find(|l| l.starts_with("memory:"))
        .unwrap_or_else(|| panic!("no memory line in:\n{text}"));
    assert!(
        memory.contains("peak resident") && memory.contains("B per part"),
        "{memory}"
    );
    // The phases and the rest account for the run, each counted once.
    assert!(
        (sum - total).abs() <= 0.1 * total + 1.0,
        "{sum} vs {total}:\n{text}"
    );
}

#[test]
fn bench_plots_the_table_and_the_sweep() {
    let dir = scratch_dir("cli-plot");
    let (svg, png, sweep) = (dir.join("t.svg"), dir.join("t.png"), dir.join("s.svg"));
    let table = |plot: &std::path::Path| {
        cadr(&[
            "bench",
            "gen:grid:parts=300",
            "--frames",
            "1",
            "--size",
            "48x32",
            "--vertex",
            "per-geometry",
            "--params",
            "push",
            "--submit",
            "individual,groups-replay",
            "--plot",
            plot.to_str().unwrap(),
        ])
    };
    let output = table(&svg);
    assert!(output.status.success(), "{}", stderr(&output));
    // Nothing but the table on the pipes: progress is for terminals.
    assert!(stderr(&output).is_empty(), "{}", stderr(&output));
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg"), "{}", &text[..80.min(text.len())]);
    for label in [
        "baseline (built-in) [solid]",
        "per-geometry / push / groups-replay / none [solid]",
        "CPU µs per frame (log scale)",
    ] {
        assert!(text.contains(label), "the chart lacks {label}");
    }
    let output = table(&png);
    assert!(output.status.success(), "{}", stderr(&output));
    let picture = image::open(&png).unwrap().to_rgb8();
    assert_eq!(picture.width(), 1400);
    // Bars are drawn: some pixels are neither white nor grey.
    assert!(picture.pixels().any(|p| p[2] > p[0].saturating_add(60)));

    let output = cadr(&[
        "bench",
        "--sweep-parts",
        "100,400",
        "--frames",
        "1",
        "--size",
        "32x32",
        "--plot",
        sweep.to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let text = std::fs::read_to_string(&sweep).unwrap();
    assert!(text.contains("parts (log scale)") && text.contains("groups-mdi-replay"));

    let output = table(&dir.join("t.txt"));
    assert_eq!(output.status.code(), Some(1));
    assert!(stderr(&output).contains("expected a file ending in .svg or .png"));
}

#[test]
fn sections_cut_what_render_draws_and_pick_hits() {
    let dir = scratch_dir("cli-section");
    let whole = dir.join("whole.png");
    let cut = dir.join("cut.png");
    let render = |out: &std::path::Path, extra: &[&str]| {
        let mut args = vec![
            "render",
            "gen:demo",
            "-o",
            out.to_str().unwrap(),
            "--size",
            "80x60",
        ];
        args.extend_from_slice(extra);
        cadr(&args)
    };
    assert!(render(&whole, &[]).status.success());
    // Keep y <= 0.4 and hatch the caps; negative numbers need no '='.
    let output = render(
        &cut,
        &["--section", "0,-1,0,0.4", "--hatch", "--validation"],
    );
    assert!(output.status.success(), "{}", stderr(&output));
    let text = stdout(&output);
    assert!(text.contains("1 section plane, capped, hatched"), "{text}");
    assert!(text.contains("validation:  0 errors"), "{text}");
    assert_ne!(std::fs::read(&whole).unwrap(), std::fs::read(&cut).unwrap());

    // A plane keeping nothing of the scene: the centre picks nothing.
    let pick = |extra: &[&str]| {
        let mut args = vec![
            "pick", "gen:demo", "400", "300", "--size", "800x600", "--json",
        ];
        args.extend_from_slice(extra);
        cadr(&args)
    };
    let hit = pick(&[]);
    assert!(hit.status.success(), "{}", stderr(&hit));
    assert!(stdout(&hit).contains("\"node\""), "{}", stdout(&hit));
    let missed = pick(&["--section", "0,1,0,-1000"]);
    assert!(missed.status.success(), "{}", stderr(&missed));
    assert!(!stdout(&missed).contains("\"node\""), "{}", stdout(&missed));

    let bad = render(&cut, &["--section", "0,0,0,1"]);
    assert_eq!(bad.status.code(), Some(2), "{}", stderr(&bad));
    assert!(stderr(&bad).contains("NX,NY,NZ,D"), "{}", stderr(&bad));
    let plane = ["--section", "1,0,0,0"];
    let seven: Vec<&str> = plane.iter().copied().cycle().take(14).collect();
    let many = render(&cut, &seven);
    assert_eq!(many.status.code(), Some(1), "{}", stderr(&many));
    assert!(
        stderr(&many).contains("--section: 7 section planes given; at most 6"),
        "{}",
        stderr(&many)
    );
}

/// `bench --display` takes a list of modes, and `--highlight NAME` selects nodes in every
/// row, as `render --highlight` does.
#[test]
fn bench_measures_a_list_of_display_modes_with_highlighted_nodes() {
    let dir = scratch_dir("cli-bench-modes");
    let json_path = dir.join("bench.json");
    // A list of display modes, each measured once in the order given; highlighted nodes
    // (a host's selection) X-ray draws opaque.
    let xray_draws = |highlight: &[&str]| {
        let mut settings = vec!["--display", "xray,solid,xray"];
        for name in highlight {
            settings.extend(["--highlight", name]);
        }
        let (_, json) = small_bench("gen:demo", &json_path, &settings);
        let rows = json["rows"].as_array().unwrap();
        let modes: Vec<&str> = rows[1..]
            .iter()
            .map(|row| row["shade"].as_str().unwrap())
            .collect();
        assert_eq!(
            modes,
            ["xray", "solid"],
            "each mode once, in the order given"
        );
        let names: Vec<&str> = json["highlight"]
            .as_array()
            .unwrap()
            .iter()
            .map(|name| name.as_str().unwrap())
            .collect();
        assert_eq!(names, highlight);
        let draws = |row: &serde_json::Value| row["draws"].as_u64().unwrap();
        (draws(&rows[1]), draws(&rows[2]))
    };
    let (plain_xray, plain_solid) = xray_draws(&[]);
    let (selected_xray, selected_solid) = xray_draws(&["module 0"]);
    assert_eq!(selected_solid, plain_solid, "solid draws every part once");
    // Highlighted parts move from X-ray's translucent pass to its opaque one: each part is
    // still drawn once by a surface pass (plugin ABI 1.11's pass exclusions).
    assert_eq!(
        selected_xray, plain_xray,
        "X-ray draws module 0's parts in the opaque pass instead of the translucent one"
    );
    let output = cadr(&["bench", "gen:demo", "--highlight", "nope"]);
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("--highlight nope"),
        "{}",
        stderr(&output)
    );
}

#[test]
fn msaa_anti_aliases_render_and_bench_measures_each_level() {
    let devices = stdout(&cadr(&["devices"]));
    assert!(devices.contains("MSAA "), "{devices}");
    // How an OpenGL host gets the frames (on Mesa 25's lavapipe: shared memory, each copy
    // waited for; on SwiftShader: shared memory and semaphores).
    assert!(devices.contains("frames to OpenGL "), "{devices}");
    // The video memory, which bounds the full detail the GPU holds before the scene streams
    // (lavapipe offers the host's memory: more than zero).
    assert!(
        devices.contains(" GB of video memory") && !devices.contains(" 0.0 GB of video memory"),
        "{devices}"
    );
    let dir = scratch_dir("cli-msaa");
    let render = |samples: &str| {
        let path = dir.join(format!("msaa{samples}.png"));
        let output = cadr(&[
            "render",
            "gen:demo",
            "-o",
            path.to_str().unwrap(),
            "--size",
            "96x72",
            "--display",
            "edges",
            "--msaa",
            samples,
            "--validation",
        ]);
        (output, path)
    };
    let (output, one_path) = render("1");
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(!stdout(&output).contains("MSAA"), "{}", stdout(&output));
    let (output, four_path) = render("4");
    assert!(output.status.success(), "{}", stderr(&output));
    let text = stdout(&output);
    assert!(text.contains(", MSAA 4x"), "{text}");
    assert!(text.contains("validation:  0 errors"), "{text}");
    let (one, four) = (
        image::open(&one_path).unwrap().to_rgba8(),
        image::open(&four_path).unwrap().to_rgba8(),
    );
    assert_ne!(one, four, "4x blends the edges");

    // Not a sample count: a usage error; a count the device lacks: named with those it has.
    let (output, _) = render("3");
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("samples per pixel"),
        "{}",
        stderr(&output)
    );
    let (output, _) = render("64");
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("MSAA 64x") && stderr(&output).contains("offers 1"),
        "{}",
        stderr(&output)
    );

    let output = cadr(&["render", "gen:demo", "-o", "/dev/null", "--dashed"]);
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("hidden-line"),
        "{}",
        stderr(&output)
    );

    let json_path = dir.join("bench.json");
    let (output, json) = small_bench(
        "gen:grid:parts=200",
        &json_path,
        &["--display", "edges", "--msaa", "1,4", "--ssao"],
    );
    let levels: Vec<u64> = json["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|row| row["msaa"].as_u64().unwrap())
        .collect();
    assert_eq!(levels, [1, 1, 4, 1, 4], "the baseline, then each level");
    let occlusion: Vec<bool> = json["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|row| row["ssao"].as_bool().unwrap())
        .collect();
    assert_eq!(
        occlusion,
        [false, false, false, true, true],
        "each level without, then with ambient occlusion"
    );
    let text = stdout(&output);
    assert!(text.contains("edges+ao"), "{text}");

    // Silhouettes on and off in the modes that draw them, each highlight style.
    let (output, json) = small_bench(
        "gen:grid:parts=200",
        &json_path,
        &[
            "--display",
            "all",
            "--silhouettes",
            "on,off",
            "--highlight-style",
            "tint,outline",
        ],
    );
    let rows: Vec<(String, bool, String)> = json["rows"].as_array().unwrap()[1..]
        .iter()
        .map(|row| {
            (
                row["shade"].as_str().unwrap().to_owned(),
                row["silhouettes"].as_bool().unwrap(),
                row["highlight_style"].as_str().unwrap().to_owned(),
            )
        })
        .collect();
    let mut expected = Vec::new();
    for style in ["tint", "outline"] {
        for silhouettes in [true, false] {
            for mode in ["solid", "edges", "hidden-line", "wireframe", "xray"] {
                if silhouettes || ["edges", "hidden-line", "xray"].contains(&mode) {
                    expected.push((mode.to_owned(), silhouettes, style.to_owned()));
                }
            }
        }
    }
    assert_eq!(
        rows, expected,
        "each style, silhouettes on then off in the modes with feature edges"
    );
    let text = stdout(&output);
    assert!(text.contains("hidden-line+outline-sil"), "{text}");

    // Hidden-line dashed and not; the other modes once.
    for (dashed, expected) in [
        (
            "on,off",
            &[
                ("solid", false),
                ("hidden-line", true),
                ("hidden-line", false),
            ][..],
        ),
        ("", &[("solid", false), ("hidden-line", true)][..]),
    ] {
        let mut options = vec!["--display", "solid,hidden-line", "--dashed"];
        if !dashed.is_empty() {
            options.push(dashed);
        }
        let (output, json) = small_bench("gen:grid:parts=200", &json_path, &options);
        let rows: Vec<(String, bool)> = json["rows"].as_array().unwrap()[1..]
            .iter()
            .map(|row| {
                (
                    row["shade"].as_str().unwrap().to_owned(),
                    row["dashed"].as_bool().unwrap(),
                )
            })
            .collect();
        let expected: Vec<(String, bool)> = expected
            .iter()
            .map(|(mode, dashed)| ((*mode).to_owned(), *dashed))
            .collect();
        assert_eq!(rows, expected, "--dashed {dashed}");
        assert!(
            stdout(&output).contains("hidden-line+dashed"),
            "{}",
            stdout(&output)
        );
    }

    let output = cadr(&["bench", "gen:grid:parts=200", "--silhouettes", "maybe"]);
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("not on or off"),
        "{}",
        stderr(&output)
    );
    let output = cadr(&["bench", "gen:grid:parts=200", "--msaa", "64"]);
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert!(stderr(&output).contains("--msaa 64"), "{}", stderr(&output));
}

/// `--highlight NAME` highlights the nodes so named, `--highlight-style outline` draws a band
/// around them instead of tinting them, `--no-silhouettes` leaves the silhouettes out of the
/// edge modes, `--highlight-color`, `--outline-width` and `--edge-color` set the palette; each
/// changes the picture and says so, and an unknown name, style, colour or width is refused.
#[test]
fn render_highlights_named_nodes_and_draws_silhouettes_on_request() {
    let dir = scratch_dir("cli-highlight");
    let draw = |name: &str, scene: &str, extra: &[&str]| {
        let path = dir.join(format!("{name}.png"));
        let mut args = vec![
            "render",
            scene,
            "--size",
            "160x120",
            "--validation",
            "-o",
            path.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let output = cadr(&args);
        assert!(output.status.success(), "{name}: {}", stderr(&output));
        assert!(stdout(&output).contains("validation:  0 errors"));
        (stdout(&output), image::open(&path).unwrap().to_rgba8())
    };
    let (_, plain) = draw("plain", "gen:demo", &[]);
    let (text, tinted) = draw("tinted", "gen:demo", &["--highlight", "module 0"]);
    assert!(text.contains("module 0 highlighted (tint)"), "{text}");
    let (text, outlined) = draw(
        "outlined",
        "gen:demo",
        &["--highlight", "module 0", "--highlight-style", "outline"],
    );
    assert!(text.contains("module 0 highlighted (outline)"), "{text}");
    let orange = |p: &image::Rgba<u8>| p.0[0] > 200 && (100..180).contains(&p.0[1]) && p.0[2] < 60;
    let band = outlined
        .pixels()
        .zip(plain.pixels())
        .filter(|(o, p)| orange(o) && !orange(p))
        .count();
    assert!(band > 20, "{band} pixels of the band");
    assert!(tinted != plain, "the tint shows");
    assert!(tinted != outlined, "the outline is no tint");
    let engine = "/usr/share/assimp/models/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb";
    let (_, with) = draw("edges", engine, &["--display", "hidden-line"]);
    let (text, without) = draw(
        "edges-without",
        engine,
        &["--display", "hidden-line", "--no-silhouettes"],
    );
    assert!(text.contains("no silhouettes"), "{text}");
    assert!(with != without, "the engine's cylinders have silhouettes");
    // The palette: a green band 4 pixels wide, blue edge lines.
    let (_, green) = draw(
        "green",
        "gen:demo",
        &[
            "--highlight",
            "module 0",
            "--highlight-style",
            "outline",
            "--highlight-color",
            "#00ff00",
            "--outline-width",
            "4",
            "--display",
            "edges",
            "--edge-color",
            "#0000FF",
        ],
    );
    let exactly =
        |image: &image::RgbaImage, rgb: [u8; 3]| image.pixels().filter(|p| p.0[..3] == rgb).count();
    assert!(
        exactly(&green, [0, 255, 0]) > band,
        "a wider band, in green"
    );
    assert!(exactly(&green, [0, 0, 255]) > 20, "blue lines");
    assert_eq!(exactly(&outlined, [0, 0, 255]), 0);

    let refused = |option: &str, value: &str, code: i32, says: &str| {
        let output = cadr(&["render", "gen:demo", "-o", "/dev/null", option, value]);
        assert_eq!(output.status.code(), Some(code), "{}", stderr(&output));
        assert!(stderr(&output).contains(says), "{}", stderr(&output));
    };
    refused("--highlight", "nope", 1, "--highlight nope");
    refused("--highlight-style", "glow", 2, "tint or outline");
    refused("--edge-color", "blue", 2, "expected a colour #RRGGBB");
    refused(
        "--highlight-color",
        "#12345",
        2,
        "expected a colour #RRGGBB",
    );
    refused("--outline-width", "9", 2, "1..=8");
}

/// What the library warns of reaches the user: `info` of a glTF whose only image is no image
/// loads the scene and says the image is left out.
#[test]
fn the_librarys_warnings_reach_standard_error() {
    let dir = scratch_dir("cli-warnings");
    let path = dir.join("broken-image.gltf");
    // One triangle whose material's texture image is the text "not an image".
    let gltf = r#"{
  "asset": {"version": "2.0"},
  "buffers": [{"byteLength": 36,
    "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
  "bufferViews": [{"buffer": 0, "byteLength": 36}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
    "min": [0, 0, 0], "max": [1, 1, 0]}],
  "images": [{"name": "decal", "uri": "data:image/png;base64,bm90IGFuIGltYWdl"}],
  "textures": [{"source": 0}],
  "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
  "nodes": [{"mesh": 0}],
  "scenes": [{"nodes": [0]}]
}"#;
    std::fs::write(&path, gltf).unwrap();
    let output = cadr(&["info", path.to_str().unwrap()]);
    assert!(output.status.success(), "{}", stderr(&output));
    let expected = format!(
        "warning: {}: image 0 (decal) is left out: its format is not one cadr decodes",
        path.display()
    );
    assert!(stderr(&output).contains(&expected), "{}", stderr(&output));
}

/// With the `fault-injection` feature (`scripts/test.sh` runs this test so): a panic while a
/// file is read, injected on a worker thread as one inside a dependency would arise, is an
/// error naming the file, with the panic's location on a second error line, and no backtrace
/// even where `RUST_BACKTRACE` asks for one.
#[cfg(feature = "fault-injection")]
#[test]
fn a_panic_while_reading_a_file_is_an_error_without_a_backtrace() {
    let engine = "/usr/share/assimp/models/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb";
    let output = Command::new(env!("CARGO_BIN_EXE_cadr"))
        .args(["info", engine])
        .env(cadr_core::load::INJECTED_PANIC_VARIABLE, "1")
        .env("RUST_BACKTRACE", "1")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains(&format!(
            "error: {engine}: the file could not be read: {}",
            cadr_core::load::READER_PANIC
        )),
        "{stderr}"
    );
    assert!(
        stderr.contains(&format!("error: {engine}: reading it panicked at"))
            && stderr.contains("load/mod.rs:"),
        "the location is logged: {stderr}"
    );
    for backtrace in ["stack backtrace", "thread '", "RUST_BACKTRACE", "note: "] {
        assert!(
            !stderr.contains(backtrace),
            "{backtrace:?} printed: {stderr}"
        );
    }
}

/// `scripts/bench-gpu.sh --dry-run`, the GPU benchmark at a small size on this machine's
/// driver: it starts, writes every table's JSON and plot and the device's description, the
/// device-generated-commands tables hold `dgc` beside `groups-mdi-replay`, and the mesh
/// table `mesh-tasks` beside `individual-indirect-count`.
#[test]
fn the_gpu_benchmark_script_dry_runs_and_writes_its_files() {
    let exe = std::path::Path::new(env!("CARGO_BIN_EXE_cadr"));
    let repository = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let out = scratch_dir("bench-gpu");
    let output = Command::new("bash")
        .arg(repository.join("scripts/bench-gpu.sh"))
        .arg("--dry-run")
        .arg(&out)
        .env("CADR_BIN", exe)
        .env("CADR_PLUGIN_PATH", exe.parent().unwrap().join("deps"))
        .output()
        .expect("run scripts/bench-gpu.sh");
    let log = format!("{}{}", stdout(&output), stderr(&output));
    assert!(output.status.success(), "{log}");
    assert!(log.contains("0 of 13 tables failed"), "{log}");
    assert!(log.contains("scaling goal: GPU time"), "{log}");
    assert!(log.contains("in the edges mode: GPU time"), "{log}");
    let devices = std::fs::read_to_string(out.join("devices.txt")).unwrap();
    assert!(devices.contains("Vulkan"), "{devices}");
    for table in [
        "graphicscard-static",
        "graphicscard-orbit",
        "cabinet-orbit",
        "graphicscard-display-all",
        "triangle-heavy",
        "grid-10m",
        "dgc-graphicscard",
        "dgc-racecar",
        "clusters-fine",
        "mesh-fine",
        "scaling-small",
        "scaling-large",
    ] {
        let plot = std::fs::metadata(out.join(format!("{table}.png"))).unwrap();
        assert!(plot.len() > 0, "{table}.png is empty");
        let json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join(format!("{table}.json"))).unwrap())
                .unwrap();
        let rows = json["rows"].as_array().unwrap();
        assert!(rows.len() >= 2, "{table}: {json}");
        let pairs: &[&str] = match table {
            "dgc-graphicscard" | "dgc-racecar" => &["/ dgc /", "/ groups-mdi-replay /"],
            "mesh-fine" => &["/ mesh-tasks /", "/ individual-indirect-count /"],
            _ => &[],
        };
        if !pairs.is_empty() {
            let names: Vec<&str> = rows
                .iter()
                .map(|row| row["technique"].as_str().unwrap())
                .collect();
            for submission in pairs {
                assert!(
                    names.iter().any(|name| name.contains(submission)),
                    "{table}: no {submission} row: {names:?}"
                );
            }
        }
    }
    let sweep: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("clusters-sweep.json")).unwrap()).unwrap();
    assert_eq!(
        sweep["detail_sweep"].as_array().unwrap().len(),
        2,
        "{sweep}"
    );
    assert!(
        std::fs::metadata(out.join("clusters-sweep.png"))
            .unwrap()
            .len()
            > 0
    );
}

/// `bench` measures gpu-clusters once per `--lod-error`, its JSON rows say what the GPU
/// rasterised, how many clusters and what stays resident; `--sweep-detail` measures the GPU
/// cost over gen:fine of growing tessellation; `--lod-error` without a cluster culler is
/// refused.
#[test]
fn bench_measures_clusters_per_lod_error_and_sweeps_the_detail() {
    let dir = scratch_dir("cli-clusters");
    let json_path = dir.join("b.json");
    let scene_wide = [
        "--vertex",
        "arena",
        "--params",
        "ssbo-index",
        "--submit",
        "individual-indirect-count",
    ];
    let mut args = vec![
        "bench",
        "gen:fine:units=2,detail=1",
        "--frames",
        "2",
        "--size",
        "160x120",
        "--cull",
        "gpu-occlusion,gpu-clusters",
        "--lod-error",
        "0,1",
        "--json",
        json_path.to_str().unwrap(),
    ];
    args.extend_from_slice(&scene_wide);
    let output = cadr(&args);
    assert!(output.status.success(), "{}", stderr(&output));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json_path).unwrap()).unwrap();
    let rows = json["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 4, "baseline, per part, clusters at 0 and 1 px");
    let rasterized = |row: &serde_json::Value| row["triangles_rasterized"].as_u64().unwrap();
    let (parts, full, lod) = (&rows[1], &rows[2], &rows[3]);
    assert_eq!(parts["clusters_drawn"], serde_json::Value::Null, "{parts}");
    assert_eq!(full["lod_error"], 0.0);
    assert_eq!(lod["lod_error"], 1.0);
    assert!(full["clusters_drawn"].as_u64().unwrap() > lod["clusters_drawn"].as_u64().unwrap());
    assert!(rasterized(full) <= rasterized(parts), "{full} {parts}");
    assert!(rasterized(lod) * 2 < rasterized(full), "{lod} {full}");
    for row in rows {
        assert!(row["resident_bytes"].as_u64().unwrap() > 0, "{row}");
        assert!(row["host_allocated_bytes"].as_u64().unwrap() > 0, "{row}");
        assert_eq!(row["streamed_bytes"], 0, "{row}");
    }
    assert!(
        stdout(&output).contains("solid lod 1px"),
        "{}",
        stdout(&output)
    );

    let plot = dir.join("d.svg");
    let output = cadr(&[
        "bench",
        "--sweep-detail",
        "1,2",
        "--sweep-units",
        "1",
        "--frames",
        "1",
        "--size",
        "64x48",
        "--plot",
        plot.to_str().unwrap(),
        "--json",
        json_path.to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let text = std::fs::read_to_string(&plot).unwrap();
    assert!(text.contains("scene triangles (log scale)") && text.contains("gpu-clusters"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json_path).unwrap()).unwrap();
    let sizes = json["detail_sweep"].as_array().unwrap();
    assert_eq!(sizes.len(), 2);
    assert!(
        sizes[1]["scene"]["triangles"].as_u64() > sizes[0]["scene"]["triangles"].as_u64(),
        "{json}"
    );

    let output = cadr(&[
        "render",
        "gen:demo",
        "--cull",
        "frustum",
        "--lod-error",
        "2",
    ]);
    assert_eq!(output.status.code(), Some(1));
    assert!(
        stderr(&output).contains("--lod-error chooses the level of detail of the clusters"),
        "{}",
        stderr(&output)
    );
}
