//! `cadr`: render, inspect and benchmark CAD scenes from the command line.

mod args;
mod bench;
mod bench_tree;
mod motion;
mod pick;
mod techniques;

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use cadr_core::generate::GENERATOR_NAMES;
use cadr_core::load::SceneSource;
use cadr_core::render::{Camera, FrameStats, DEFAULT_DIRECTION};
use cadr_core::scene::{flatten, SceneStats};
use cadr_core::vk::{self as cvk, Device, DeviceOptions, InstanceOptions};

use args::{parse_size, Args};

const HELP: &str = "\
cadr — a Vulkan renderer for very large CAD assemblies

USAGE:
    cadr render SCENE [-o OUT.png] [--size WxH] [--frames N] [--validation]
                [--vertex NAME] [--params NAME] [--submit NAME] [--cull NAME]
                [--shade solid|edges] [--min-pixels PX] [--no-replay] [--baseline]
    cadr techniques [--json]
    cadr bench [SCENE] [--frames N] [--json FILE] [--size WxH] [--shade solid|edges|all]
               [--vertex A,B] [--params A,B] [--submit A,B] [--cull A,B] [--all]
               [--camera static|orbit] [--animate N] [--min-pixels PX] [--no-replay]
    cadr bench --sweep [--sweep-parts N,N,...]
    cadr pick SCENE X Y [--size WxH] [--rect X2,Y2] [--json] [technique options]
    cadr info SCENE
    cadr convert SCENE OUT
    cadr bench-tree [SCENE] [--runs N]
    cadr devices

SCENE is a .gltf, .glb, .csf or .csf.gz file, or a generator:
    gen:demo           the built-in demo (default)
    gen:graphicscard   ~68 000 parts of ~10 triangles (the seeds' Graphicscard)
    gen:racecar        ~98 000 parts of ~37 triangles
    gen:cabinet        machines in closed housings, racks of cabinets (optional :cabinets=N,
                       default 24, 366 parts each): most parts hidden from outside
    gen:grid:parts=N   exactly N parts in a cube of objects (optional ,tris=T)

render: draws the scene offscreen with the camera fitted to its bounds, writes a PNG
        (default out.png, 1024x768) and prints what it drew and the frame's CPU and GPU time.
        --frames N renders N frames after one warm-up and reports medians. It draws with one
        technique per kind, solid or with edges; the default is the built-in combination
        (per-geometry, push, individual, none), which needs no plugin library; --baseline
        asks for it explicitly. --min-pixels PX (with a gpu- culler) skips parts whose bounding
        sphere projects under PX pixels across; off by default, as CAD users count small parts.
        A frame that would record what the last one recorded (only the camera moved, or
        nothing) resubmits it instead; --no-replay records every frame (--baseline does).
techniques: lists every technique (built in or from a plugin library), its description and
        whether this device runs it.
bench:  renders the built-in combination (the baseline) and technique combinations (by
        default every submission with per-geometry/push and arena/ssbo-index; --all for every
        supported one; lists to choose) for N frames after 2 warm-up frames and prints CPU
        and GPU µs, draw calls,
        state changes, triangles and the speedup over the baseline; --json FILE writes them
        with the scene statistics. --camera orbit circles the scene close enough that the
        frustum cuts (default static); --animate N moves N assembly nodes every frame (an
        exploded view); the table adds the scene update µs and the bytes uploaded per frame.
        --min-pixels PX sets the gpu- cullers' sub-pixel threshold (CPU cullers ignore it).
        The baseline records every frame; the other rows replay unchanged frames (the replay
        column counts them) unless --no-replay.
        --sweep measures a set over gen:grid of 10 000 to 1 000 000 parts to show how each
        technique's CPU cost grows.
pick:   what lies under pixel (X, Y) of the view `render` draws (same size, camera and
        technique options): the geo node and part, its path of nodes from the root (a shared
        part has one per occurrence), the depth and the world position (f64). --rect X2,Y2
        lists every pickable part with a visible pixel in the rectangle from (X, Y) to
        (X2, Y2). --json prints hit, node, part, path, depth, position (and hits for --rect).
info:   prints nodes, geometries, parts, materials, instances, triangles, vertices, bounds.
convert: writes SCENE as OUT (.gltf with a .bin beside it, .glb, .csf, .csf.gz) and says what
        the target format cannot hold.
bench-tree: builds the incremental scene tree of SCENE (default gen:graphicscard) and measures
        edits (1 transform, 1% and 100% of part placements, a material, hiding 1%) against a
        full rebuild in the same run, memory per instance and bytes uploaded per frame.
devices: lists the Vulkan devices; CADR_DEVICE=INDEX|NAME picks one.


Compiled shaders and the Vulkan pipeline cache are kept between runs in $CADR_CACHE_DIR, else
$XDG_CACHE_HOME/cadr, else ~/.cache/cadr; --no-cache (any command) neither reads nor writes it.
Validation layers are on with --validation or CADR_VALIDATION=1. Plugins are found beside the
executable (and in its plugins/ folder) and in the directories of CADR_PLUGIN_PATH.
";

fn main() -> ExitCode {
    let mut argv: Vec<String> = std::env::args().skip(1).collect();
    // Any command: --no-cache neither reads nor writes the disk cache.
    let before = argv.len();
    argv.retain(|argument| argument != "--no-cache");
    if argv.len() != before {
        cadr_core::disk_cache::set_enabled(false);
    }
    let mut argv = argv.into_iter();
    let command = argv.next();
    let result = match command.as_deref() {
        None | Some("--help" | "-h" | "help") => {
            print!("{HELP}");
            Ok(())
        }
        Some("--version" | "-V") => {
            println!("cadr {}", env!("CARGO_PKG_VERSION"));
            Ok(())
        }
        Some(command) => Args::parse(command, argv).and_then(|args| run(command, &args)),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::FAILURE
        }
    }
}

fn run(command: &str, args: &Args) -> Result<(), String> {
    if args.flag("--help") || args.flag("-h") {
        print!("{HELP}");
        return Ok(());
    }
    match command {
        "render" => render(args),
        "pick" => pick::pick(args),
        "info" => info(args),
        "convert" => convert(args),
        "bench-tree" => {
            args.reject_unknown("bench-tree", &["--runs"])?;
            let runs = match args.value(&["--runs"]).map(str::parse::<usize>) {
                None => 5,
                Some(Ok(n)) if (1..=1000).contains(&n) => n,
                Some(_) => return Err("--runs: expected a number from 1 to 1000".into()),
            };
            let scene = match args.positionals() {
                [] => "gen:graphicscard",
                [scene] => scene.as_str(),
                [_, extra, ..] => return Err(format!("cadr bench-tree: unexpected argument '{extra}'")),
            };
            bench_tree::bench_tree(scene, runs)
        }
        "devices" => devices(args),
        "techniques" => techniques::techniques(args),
        "bench" => bench::bench(args),
        other => Err(format!(
            "unknown command '{other}' (commands: render, pick, info, convert, techniques, bench, bench-tree, devices; see cadr --help)"
        )),
    }
}

fn scene_argument(args: &Args, command: &str) -> Result<SceneSource, String> {
    match args.positionals() {
        [] => SceneSource::parse("gen:demo").map_err(|e| e.to_string()),
        [scene] => SceneSource::parse(scene).map_err(|e| e.to_string()),
        [_, extra, ..] => Err(format!("cadr {command}: unexpected argument '{extra}' (one SCENE; generators: {GENERATOR_NAMES})")),
    }
}

/// The Vulkan device, with the validation layers when the options or the environment ask.
pub(crate) fn open_device(args: &Args) -> Result<std::sync::Arc<Device>, String> {
    let options = DeviceOptions {
        instance: InstanceOptions {
            validation: validation_requested(args),
            ..InstanceOptions::default()
        },
        ..DeviceOptions::default()
    };
    Device::new(&options).map_err(|e| e.to_string())
}

pub(crate) fn validation_requested(args: &Args) -> bool {
    if args.flag("--no-validation") {
        return false;
    }
    args.flag("--validation")
        || std::env::var("CADR_VALIDATION").is_ok_and(|v| v != "0" && !v.is_empty())
}

fn info(args: &Args) -> Result<(), String> {
    args.reject_unknown("info", &[])?;
    let source = scene_argument(args, "info")?;
    let started = Instant::now();
    let scene = source.load().map_err(|e| e.to_string())?;
    let flat = flatten(&scene).map_err(|e| e.to_string())?;
    let stats = SceneStats::new(&scene, &flat);
    println!("scene:            {}", scene.name);
    print!("{stats}");
    println!(
        "loaded in:        {:.1} ms",
        started.elapsed().as_secs_f64() * 1e3
    );
    Ok(())
}

fn convert(args: &Args) -> Result<(), String> {
    args.reject_unknown("convert", &[])?;
    let [input, output] = args.positionals() else {
        return Err(
            "cadr convert needs SCENE and OUT, e.g. cadr convert model.glb model.csf.gz".into(),
        );
    };
    let started = Instant::now();
    let scene = SceneSource::parse(input)
        .and_then(|s| s.load())
        .map_err(|e| e.to_string())?;
    let notes = cadr_core::save::save_scene(&scene, std::path::Path::new(output))
        .map_err(|e| e.to_string())?;
    let flat = flatten(&scene).map_err(|e| e.to_string())?;
    let stats = SceneStats::new(&scene, &flat);
    println!(
        "wrote {output}: {} nodes, {} geometries, {} materials, {} parts drawn, {} triangles ({:.0} ms)",
        stats.nodes,
        stats.geometries,
        stats.materials,
        stats.instances,
        stats.triangles,
        started.elapsed().as_secs_f64() * 1e3
    );
    for note in notes {
        println!("note: {note}");
    }
    Ok(())
}

fn devices(args: &Args) -> Result<(), String> {
    args.reject_unknown("devices", &[])?;
    let instance = cvk::Instance::new(&InstanceOptions::default()).map_err(|e| e.to_string())?;
    let adapters = cvk::enumerate_adapters(&instance).map_err(|e| e.to_string())?;
    for adapter in adapters {
        println!(
            "{}: {} ({:?}, Vulkan {}.{})",
            adapter.index,
            adapter.name,
            adapter.device_type,
            cvk::raw::api_version_major(adapter.api_version),
            cvk::raw::api_version_minor(adapter.api_version)
        );
    }
    Ok(())
}

pub(crate) fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    match values.len() {
        0 => 0.0,
        n if n % 2 == 1 => values[n / 2],
        n => 0.5 * (values[n / 2 - 1] + values[n / 2]),
    }
}

fn render(args: &Args) -> Result<(), String> {
    args.reject_unknown(
        "render",
        &[
            "-o",
            "--output",
            "--size",
            "--frames",
            "--validation",
            "--no-validation",
            "--vertex",
            "--params",
            "--submit",
            "--cull",
            "--shade",
            "--min-pixels",
            "--no-replay",
            "--baseline",
        ],
    )?;
    let (combination, shade) = techniques::combination_from_args(args)?;
    let min_pixels = techniques::min_pixels_from_args(args)?;
    if args.flag("--baseline") && techniques::technique_requested(args) {
        return Err(
            "--baseline draws with the built-in combination; it takes no technique options".into(),
        );
    }
    let process_start = Instant::now();
    let source = scene_argument(args, "render")?;
    let output = PathBuf::from(args.value(&["-o", "--output"]).unwrap_or("out.png"));
    let (width, height) = parse_size(args.value(&["--size"]).unwrap_or("1024x768"))?;
    let frames: usize = match args.value(&["--frames"]) {
        None => 1,
        Some(text) => match text.parse::<usize>() {
            Ok(n) if (1..=100_000).contains(&n) => n,
            _ => {
                return Err(format!(
                    "--frames {text}: expected a number from 1 to 100000"
                ))
            }
        },
    };

    let load_start = Instant::now();
    let scene = source.load().map_err(|e| e.to_string())?;
    let load_ms = load_start.elapsed().as_secs_f64() * 1e3;

    let device = open_device(args)?;
    let upload_start = Instant::now();
    let flat = flatten(&scene).map_err(|e| e.to_string())?;
    let stats = SceneStats::new(&scene, &flat);
    drop(flat);
    let (registry, _) = techniques::load_registry(&device);
    let mut session =
        techniques::TechniqueSession::new(&device, &scene, registry, (width, height))?;
    session.choose(&combination, shade)?;
    session.set_min_pixels(min_pixels)?;
    // The baseline records every frame, as the seeds' does.
    session
        .techniques()
        .set_frame_replay(!args.flag("--no-replay") && !args.flag("--baseline"));
    let mut technique_line = format!("{combination}, {}", shade.name());
    if min_pixels > 0.0 {
        technique_line += &format!(", parts under {min_pixels} px culled");
    }
    let upload_ms = upload_start.elapsed().as_secs_f64() * 1e3;
    let camera = Camera::fit(
        &stats.bounds,
        f64::from(width) / f64::from(height),
        DEFAULT_DIRECTION,
    );

    // One warm-up frame when measuring several, so that first-use costs do not count.
    let mut first = session.render(&camera)?;
    let mut samples: Vec<FrameStats> = Vec::with_capacity(frames);
    if frames == 1 {
        samples.push(first);
    } else {
        for _ in 0..frames {
            samples.push(session.render(&camera)?);
        }
        first = samples[0];
    }
    session
        .view
        .renderer()
        .save_png(&output)
        .map_err(|e| e.to_string())?;

    let validation_errors = device.validation_log().errors().len();
    let adapter = device.adapter();
    println!(
        "scene:       {} ({} nodes, {} geometries, {} materials)",
        scene.name, stats.nodes, stats.geometries, stats.materials
    );
    println!("device:      {} ({:?})", adapter.name, adapter.device_type);
    println!("techniques:  {technique_line}");
    println!(
        "drawn:       {} parts, {} triangles, {} draw calls ({} ranges)",
        stats.instances, first.triangles, first.draw_calls, first.draws
    );
    println!(
        "state:       {} pipeline binds, {} vertex/index binds, {} parameter updates",
        first.pipeline_binds, first.vertex_binds, first.parameter_updates
    );
    let mut record: Vec<f64> = samples.iter().map(|s| s.cpu_record_us).collect();
    let mut cpu: Vec<f64> = samples.iter().map(FrameStats::cpu_us).collect();
    let mut gpu: Vec<f64> = samples.iter().filter_map(|s| s.gpu_us).collect();
    let label = if frames == 1 {
        "frame:      ".to_owned()
    } else {
        format!("frame:       median of {frames},")
    };
    let gpu_text = if gpu.is_empty() {
        "n/a (no timestamps)".to_owned()
    } else {
        format!("{:.0} µs", median(&mut gpu))
    };
    let replayed = samples.iter().filter(|s| s.replayed).count();
    println!(
        "{label} CPU {:.0} µs (recording {:.0} µs), GPU {gpu_text}, {replayed} of {} replayed",
        median(&mut cpu),
        median(&mut record),
        samples.len()
    );
    println!("setup:       load {load_ms:.1} ms, upload {upload_ms:.1} ms");
    if validation_requested(args) {
        println!("validation:  {validation_errors} errors");
    }
    println!(
        "wrote:       {} ({width}x{height}) in {:.0} ms total",
        output.display(),
        process_start.elapsed().as_secs_f64() * 1e3
    );
    if validation_errors > 0 {
        return Err(format!(
            "{validation_errors} Vulkan validation errors (see above)"
        ));
    }
    Ok(())
}
