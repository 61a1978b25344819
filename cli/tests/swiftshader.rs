//! `cadr render` on a second Vulkan implementation: SwiftShader, Google's CPU driver, which
//! keeps to the specification where lavapipe is lenient (lavapipe allocates descriptor sets
//! past their pool's sizes, for one; SwiftShader refuses, as GPU drivers may). Each display
//! mode and feature, and technique plugins of every kind, render there with no validation
//! error, and look as they do on lavapipe. And Debian 12's Mesa 22.3 lavapipe, which lacks mesh
//! shaders: it draws with indexed indirect draws what Mesa 25 draws with mesh workgroups.
//! `scripts/setup.sh` installs the driver into `target/swiftshader` (`CADR_SWIFTSHADER_DIR`
//! overrides); without it the test fails and says so.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::path::Path;
use std::process::{Command, Output};

use cadr_tests::images::{compare, ImageDifference};
use cadr_tests::swiftshader_manifest;

/// Runs `cadr render gen:demo` into `png` with validation on and `args`, on SwiftShader's
/// driver alone when `manifest` is given (the Vulkan loader then sees no other), otherwise on
/// the default device.
fn render(png: &Path, args: &[&str], manifest: Option<&Path>) -> Output {
    let exe = Path::new(env!("CARGO_BIN_EXE_cadr"));
    let mut command = Command::new(exe);
    command
        .args([
            "render",
            "gen:demo",
            "--size",
            "240x180",
            "--validation",
            "-o",
        ])
        .arg(png)
        .args(args)
        .env("CADR_PLUGIN_PATH", exe.parent().unwrap().join("deps"))
        .env_remove("CADR_DEVICE");
    if let Some(manifest) = manifest {
        command.env("VK_ICD_FILENAMES", manifest);
    }
    command.output().expect("run cadr")
}

fn text(output: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    )
}

/// The display modes and the features drawn over them, each in one render, then technique
/// plugins of each kind that SwiftShader runs (it lacks `drawIndirectCount` and
/// `VK_EXT_multi_draw`: a GPU culler's commands are drawn there by their capacity,
/// `individual-mdi`), which draw the solid picture again.
const CASES: &[(&str, &[&str])] = &[
    ("solid", &[]),
    ("edges with MSAA", &["--display", "edges", "--msaa", "4"]),
    (
        "dashed hidden-line",
        &["--display", "hidden-line", "--dashed"],
    ),
    ("wireframe", &["--display", "wireframe"]),
    (
        "X-ray with a highlight",
        &["--display", "xray", "--highlight", "module 0"],
    ),
    (
        "outlined highlight",
        &["--highlight", "module 1", "--highlight-style", "outline"],
    ),
    (
        "capped section",
        &["--display", "edges", "--section=0,-1,0,0.02", "--caps"],
    ),
    ("ambient occlusion", &["--ssao"]),
    (
        "exact transparency in X-ray",
        &["--display", "xray", "--transparency", "per-pixel-lists"],
    ),
    (
        "arena / ssbo-index / groups-mdi-replay / frustum",
        &[
            "--vertex",
            "arena",
            "--params",
            "ssbo-index",
            "--submit",
            "groups-mdi-replay",
            "--cull",
            "frustum",
        ],
    ),
    (
        "arena / ssbo-index / individual-mdi / gpu-clusters",
        &[
            "--vertex",
            "arena",
            "--params",
            "ssbo-index",
            "--submit",
            "individual-mdi",
            "--cull",
            "gpu-clusters",
        ],
    ),
    (
        "pulling / ubo-dynamic / individual / none",
        &[
            "--vertex",
            "pulling",
            "--params",
            "ubo-dynamic",
            "--submit",
            "individual",
        ],
    ),
];

/// How many of [`CASES`] change the picture (the display modes and features); the technique
/// cases, named by their combination, follow.
const PICTURE_CASES: usize = 9;

/// How far SwiftShader's picture may be from lavapipe's (FLIP, mean over the pixels): the two
/// rasterize, filter and round differently along edges, by up to 0.02 on these pictures.
const DRIVERS_APART: f64 = 0.03;

#[test]
fn every_display_mode_renders_on_swiftshader_as_on_lavapipe() {
    assert!(CASES[..PICTURE_CASES]
        .iter()
        .all(|(name, _)| !name.contains(" / ")));
    assert!(CASES[PICTURE_CASES..]
        .iter()
        .all(|(name, _)| name.contains(" / ")));
    let manifest = swiftshader_manifest();
    // SwiftShader and the default driver (Mesa 25's lavapipe) draw textures through the
    // bindless table; CADR_TEXTURE_ARRAY=1 keeps SwiftShader on the array. Debian 12's Mesa
    // 22.3 has neither descriptor indexing nor Vulkan 1.4's extras; SwiftShader has no
    // drawIndirectCount, so GPU-culled commands are drawn by their capacity there.
    let mesa22 = cadr_tests::mesa22_manifest();
    let vulkan_1_4 =
        "mesh shaders yes, device-generated commands yes, GPU-culled draws by their count,";
    let vulkan_1_3 =
        "mesh shaders no, device-generated commands no, GPU-culled draws by their count,";
    let no_count = "mesh shaders no, device-generated commands no, GPU-culled draws by their capacity (no drawIndirectCount: --submit individual-mdi)";
    for (driver, array_only, expected) in [
        (
            Some(&*manifest),
            false,
            ["textures bindless, up to ", no_count],
        ),
        (
            Some(&*manifest),
            true,
            ["textures one texture array", no_count],
        ),
        (
            Some(&*mesa22),
            false,
            ["textures one texture array", vulkan_1_3],
        ),
        (None, false, ["textures bindless, up to ", vulkan_1_4]),
    ] {
        let mut command = Command::new(env!("CARGO_BIN_EXE_cadr"));
        command.arg("devices").env_remove("CADR_TEXTURE_ARRAY");
        if let Some(manifest) = driver {
            command.env("VK_ICD_FILENAMES", manifest);
        }
        if array_only {
            command.env("CADR_TEXTURE_ARRAY", "1");
        }
        let devices = text(&command.output().expect("run cadr devices"));
        for part in expected {
            assert!(devices.contains(part), "{part}: {devices}");
        }
    }
    let dir = std::env::temp_dir().join(format!("cadr-swiftshader-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut pictures = Vec::new();
    for (i, &(name, args)) in CASES.iter().enumerate() {
        let [lavapipe, swiftshader] = ["lavapipe", "swiftshader"].map(|driver| {
            let png = dir.join(format!("{i}-{driver}.png"));
            let output = render(&png, args, (driver == "swiftshader").then_some(&*manifest));
            let log = text(&output);
            assert!(output.status.success(), "{name} on {driver}: {log}");
            assert!(
                log.contains("validation:  0 errors"),
                "{name} on {driver}: {log}"
            );
            if driver == "swiftshader" {
                assert!(
                    log.contains("SwiftShader"),
                    "{name}: not on SwiftShader: {log}"
                );
            }
            // SwiftShader has no geometry shaders, so dashed hidden-line leaves the hidden
            // silhouettes out and says so; lavapipe draws them.
            let without_hidden_silhouettes = log.contains("silhouettes of hidden curved surfaces");
            assert_eq!(
                without_hidden_silhouettes,
                driver == "swiftshader" && name == "dashed hidden-line",
                "{name} on {driver}: {log}"
            );
            image::open(&png).unwrap().to_rgba8()
        });
        let difference = compare(&swiftshader, &lavapipe).unwrap();
        assert!(
            difference.mean <= DRIVERS_APART,
            "{name}: SwiftShader's picture is {difference:?} from lavapipe's"
        );
        pictures.push((name, lavapipe, difference));
    }
    let differences: Vec<(&str, f64)> = pictures.iter().map(|(n, _, d)| (*n, d.mean)).collect();
    println!("SwiftShader against lavapipe (FLIP mean): {differences:?}");
    // What each case adds to the solid picture is drawn: the two drivers' pictures of a case
    // are nearer each other than half the way from solid to the case.
    let (_, solid, _) = &pictures[0];
    for (name, picture, drivers) in &pictures[1..PICTURE_CASES] {
        let ImageDifference { mean, .. } = compare(picture, solid).unwrap();
        assert!(
            drivers.mean < 0.5 * mean,
            "{name}: the drivers are {} apart, the case {mean} from solid",
            drivers.mean
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Issue 41's "the same image both ways": `gpu-clusters`' commands drawn by mesh workgroups
/// (`mesh-tasks`) on the default driver, Mesa 25's lavapipe, against the same commands drawn as
/// indexed indirect draws on Debian 12's Mesa 22.3, which has no mesh shaders; in the solid
/// and edges modes, at full detail and at the default level of detail.
#[test]
fn mesh_workgroups_on_mesa_25_draw_what_indexed_draws_draw_on_mesa_22_3() {
    let exe = Path::new(env!("CARGO_BIN_EXE_cadr"));
    let mesa22 = cadr_tests::mesa22_manifest();
    let dir = std::env::temp_dir().join(format!("cadr-mesh-drivers-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (case, display, lod_error) in [(0, "solid", "0"), (1, "edges", "1")] {
        let [mesh, indexed] = ["mesh-tasks", "individual-indirect-count"].map(|submission| {
            let png = dir.join(format!("{case}-{submission}.png"));
            let mut command = Command::new(exe);
            command
                .args(["render", "gen:fine:units=1,detail=1", "--size", "240x180"])
                .args([
                    "--validation",
                    "--vertex",
                    "pulling",
                    "--params",
                    "ssbo-index",
                ])
                .args(["--submit", submission, "--cull", "gpu-clusters"])
                .args(["--display", display, "--lod-error", lod_error, "-o"])
                .arg(&png)
                .env("CADR_PLUGIN_PATH", exe.parent().unwrap().join("deps"))
                .env_remove("CADR_DEVICE");
            if submission != "mesh-tasks" {
                command.env("VK_ICD_FILENAMES", &mesa22);
            }
            let output = command.output().expect("run cadr");
            let log = text(&output);
            assert!(output.status.success(), "{submission}, {display}: {log}");
            assert!(log.contains("validation:  0 errors"), "{submission}: {log}");
            image::open(&png).unwrap().to_rgba8()
        });
        let difference = compare(&mesh, &indexed).unwrap();
        println!("{display}, LOD {lod_error} px: mesh-tasks on Mesa 25 against Mesa 22.3: {difference:?}");
        assert!(
            difference.within(cadr_tests::images::SAME_PICTURE),
            "{display}, LOD {lod_error} px: {difference:?}"
        );
    }
    // On Mesa 22.3 itself the submission is refused, not crashed into (which also shows that
    // the indexed pictures above were drawn there).
    let output = Command::new(exe)
        .args(["render", "gen:demo", "--size", "64x48", "-o"])
        .arg(dir.join("refused.png"))
        .args([
            "--vertex",
            "pulling",
            "--params",
            "ssbo-index",
            "--submit",
            "mesh-tasks",
        ])
        .args(["--cull", "gpu-clusters"])
        .env("CADR_PLUGIN_PATH", exe.parent().unwrap().join("deps"))
        .env("VK_ICD_FILENAMES", &mesa22)
        .env_remove("CADR_DEVICE")
        .output()
        .expect("run cadr");
    let log = text(&output);
    assert!(!output.status.success(), "{log}");
    assert!(log.contains("VK_EXT_mesh_shader"), "{log}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The detail sweep of `cadr bench` on SwiftShader, which lacks `drawIndirectCount`: its GPU
/// culling rows draw through `individual-mdi` there, with validation on, and count what the GPU
/// rasterised.
#[test]
fn the_detail_sweep_draws_its_gpu_culling_rows_by_capacity_on_swiftshader() {
    let exe = Path::new(env!("CARGO_BIN_EXE_cadr"));
    let dir = std::env::temp_dir().join(format!("cadr-swiftshader-sweep-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let json_path = dir.join("sweep.json");
    let output = Command::new(exe)
        .args(["bench", "--sweep-detail", "1", "--sweep-units", "1"])
        .args(["--frames", "1", "--size", "64x48", "--validation", "--json"])
        .arg(&json_path)
        .env("CADR_PLUGIN_PATH", exe.parent().unwrap().join("deps"))
        .env("VK_ICD_FILENAMES", swiftshader_manifest())
        .env_remove("CADR_DEVICE")
        .output()
        .expect("run cadr bench");
    let log = text(&output);
    assert!(output.status.success(), "{log}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json_path).unwrap()).unwrap();
    assert!(
        json["device"].as_str().unwrap().contains("SwiftShader"),
        "{json}"
    );
    let rows = json["detail_sweep"][0]["rows"].as_array().unwrap();
    assert!(rows.len() >= 2, "{json}");
    for row in rows {
        let technique = row["technique"].as_str().unwrap();
        assert!(
            technique.contains("individual-mdi") && technique.contains("gpu-"),
            "{row}"
        );
        assert!(row["triangles_rasterized"].as_u64().unwrap() > 0, "{row}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
