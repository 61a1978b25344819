//! `cadr`: render, inspect and benchmark CAD scenes from the command line.

/// Every allocation of the command is counted, so that `bench` rows report the host memory
/// cadr holds (`host_allocated_bytes`).
#[global_allocator]
static HEAP: cadr_core::host_heap::CountingAllocator = cadr_core::host_heap::CountingAllocator;

mod args;
mod bench;
mod bench_sweep;
mod bench_tree;
mod motion;
mod pick;
mod plot;
mod progress;
mod techniques;
mod warnings;

use std::process::ExitCode;
use std::time::Instant;

use cadr_core::graph::SceneGraph;
use cadr_core::load::SceneSource;
use cadr_core::render::{Camera, FrameStats, DEFAULT_DIRECTION};
use cadr_core::scene::closure::{ClosedPartCounter, ClosedPartCounts};
use cadr_core::scene::{flatten_outline, SceneStats};
use cadr_core::technique::{Combination, ShadeMode};
use cadr_core::timings::{self, Phase};
use cadr_core::vk::{self as cvk, Device, DeviceOptions, InstanceOptions};

use args::{Cli, Command, ConvertArgs, InfoArgs, RenderArgs, Size, ValidationArgs};
use clap::{CommandFactory, Parser};

fn main() -> ExitCode {
    let process_start = Instant::now();
    warnings::show_on_standard_error();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        // Help and --version print and succeed; a wrong command line exits with 2.
        Err(error) => error.exit(),
    };
    if cli.no_cache {
        cadr_core::disk_cache::set_enabled(false);
    }
    let result = match cli.command {
        Command::Render(args) => render(&args, process_start),
        Command::Pick(args) => pick::pick(&args),
        Command::Info(args) => info(&args),
        Command::Convert(args) => convert(&args),
        Command::Techniques(args) => techniques::techniques(&args),
        Command::Bench(args) => bench::bench(&args),
        Command::BenchTree(args) => bench_tree::bench_tree(&args.scene, args.runs as usize),
        Command::Devices => devices(),
        Command::Completions(args) => {
            clap_complete::generate(
                args.shell,
                &mut Cli::command(),
                "cadr",
                &mut std::io::stdout(),
            );
            Ok(())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::FAILURE
        }
    }
}

/// A scene loaded straight into a new graph ([`load_graph`]).
pub(crate) struct LoadedGraph {
    /// The graph holding it.
    pub graph: SceneGraph,
    /// The scene's name.
    pub name: String,
    /// Its statistics, as loaded.
    pub stats: SceneStats,
}

/// Loads the scene `text` names straight into a new graph (with a spinner if it takes over a
/// second), with the nodes named one of `highlight` highlighted. Each geometry goes to the
/// graph's page file as soon as it is made where the graph's memory limit is reached, so that
/// a model larger than memory loads.
pub(crate) fn load_graph(text: &str, highlight: &[String]) -> Result<LoadedGraph, String> {
    let source = SceneSource::parse(text).map_err(|e| e.to_string())?;
    let mut graph = SceneGraph::new();
    let (outline, geometries) = progress::spin(&format!("loading {text}"), || {
        source.load_for_graph(graph.geometry_memory_left())
    })
    .map_err(|e| e.to_string())?;
    let flat = flatten_outline(&outline, geometries.summaries()).map_err(|e| e.to_string())?;
    let stats = SceneStats::of_outline(&outline, &flat, geometries.summaries());
    drop(flat);
    let root = graph.root();
    graph
        .import_loaded(&outline, geometries, root)
        .map_err(|e| e.to_string())?;
    techniques::highlight_named(&mut graph, highlight)?;
    Ok(LoadedGraph {
        graph,
        name: outline.name,
        stats,
    })
}

/// The Vulkan device, with the validation layers when the options or the environment ask.
pub(crate) fn open_device(validation: &ValidationArgs) -> Result<std::sync::Arc<Device>, String> {
    let options = DeviceOptions {
        instance: InstanceOptions {
            validation: validation.requested(),
            ..InstanceOptions::default()
        },
        ..DeviceOptions::default()
    };
    Device::new(&options).map_err(|e| e.to_string())
}

fn info(args: &InfoArgs) -> Result<(), String> {
    let started = Instant::now();
    // One geometry at a time: each is counted and summarised as it is read, then let go, so
    // that a model larger than memory can be described.
    let source = SceneSource::parse(&args.scene).map_err(|e| e.to_string())?;
    let mut counter = ClosedPartCounter::default();
    let outline = progress::spin(&format!("loading {}", args.scene), || {
        source.load_through(&mut counter)
    })
    .map_err(|e| e.to_string())?;
    let flat = flatten_outline(&outline, &counter.summaries).map_err(|e| e.to_string())?;
    let stats = SceneStats::of_outline(&outline, &flat, &counter.summaries);
    println!("scene:            {}", outline.name);
    print!("{stats}");
    let ClosedPartCounts {
        closed,
        inside_out,
        parts,
    } = counter.counts;
    println!(
        "closed parts:     {closed} of {parts}, {inside_out} more inside out (section cuts \
         through them are capped; GPU cullers skip their back faces)"
    );
    println!(
        "loaded in:        {:.1} ms",
        started.elapsed().as_secs_f64() * 1e3
    );
    Ok(())
}

fn convert(args: &ConvertArgs) -> Result<(), String> {
    let started = Instant::now();
    // One geometry at a time: each loaded geometry stays in memory up to half the memory budget
    // (CADR_MEMORY_BUDGET) and goes to a page file past it, and is read back as it is written.
    let source = SceneSource::parse(&args.scene).map_err(|e| e.to_string())?;
    let limit = cadr_core::memory_budget::budget()?.saturating_div(2);
    let (outline, geometries) = progress::spin(&format!("loading {}", args.scene), || {
        source.load_for_graph(limit)
    })
    .map_err(|e| e.to_string())?;
    let flat = flatten_outline(&outline, geometries.summaries()).map_err(|e| e.to_string())?;
    let stats = SceneStats::of_outline(&outline, &flat, geometries.summaries());
    drop(flat);
    let notes = cadr_core::save::save_outline(&outline, &geometries, &args.output)
        .map_err(|e| e.to_string())?;
    println!(
        "wrote {}: {} nodes, {} geometries, {} materials, {} parts drawn, {} triangles ({:.0} ms)",
        args.output.display(),
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

fn devices() -> Result<(), String> {
    let instance = cvk::Instance::new(&InstanceOptions::default()).map_err(|e| e.to_string())?;
    let adapters = cvk::enumerate_adapters(&instance).map_err(|e| e.to_string())?;
    for adapter in adapters {
        let msaa: Vec<String> = adapter
            .sample_counts
            .iter()
            .filter(|&&count| count > 1)
            .map(|count| format!("{count}x"))
            .collect();
        let textures = match adapter.bindless_textures {
            0 => "one texture array".to_owned(),
            capacity => format!("bindless, up to {capacity}"),
        };
        let hidden_silhouettes = if adapter.geometry_shader {
            "dashed"
        } else {
            "not drawn (no geometry shaders)"
        };
        let yes_no = |has: bool| if has { "yes" } else { "no" };
        let mesh_shaders = yes_no(adapter.mesh_shader);
        let generated_commands = yes_no(adapter.device_generated_commands);
        // How a GPU culler's commands are drawn: as many as its count says, or all its room
        // (`individual-mdi`) where the device cannot read a count.
        let gpu_culled_draws = if adapter.draw_indirect_count {
            "by their count"
        } else {
            "by their capacity (no drawIndirectCount: --submit individual-mdi)"
        };
        // How an OpenGL host gets the frames (`cadr_renderer_create_for_export`,
        // `cadr_renderer_export_semaphores`).
        let frames_to_opengl = match (adapter.external_memory_fd, adapter.external_semaphore_fd) {
            (true, true) => "shared memory and semaphores",
            (true, false) => "shared memory, each copy waited for",
            (false, _) => "read back",
        };
        println!(
            "{}: {} ({:?}, Vulkan {}.{}, {:.1} GB of video memory, MSAA {}, textures {textures}, \
             hidden silhouettes {hidden_silhouettes}, mesh shaders {mesh_shaders}, \
             device-generated commands {generated_commands}, GPU-culled draws \
             {gpu_culled_draws}, frames to OpenGL {frames_to_opengl})",
            adapter.index,
            adapter.name,
            adapter.device_type,
            cvk::raw::api_version_major(adapter.api_version),
            cvk::raw::api_version_minor(adapter.api_version),
            adapter.video_memory as f64 / 1e9,
            if msaa.is_empty() {
                "none".to_owned()
            } else {
                msaa.join(" ")
            }
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

fn render(args: &RenderArgs, process_start: Instant) -> Result<(), String> {
    let combination = args.techniques.combination();
    let shade = args.techniques.shade_mode();
    let min_pixels = args.techniques.min_pixels();
    if args.baseline && args.techniques.any() {
        return Err(
            "--baseline draws with the built-in combination; it takes no technique options".into(),
        );
    }
    let section = args.section.section()?;
    let output = &args.output;
    let Size { width, height } = args.size;
    let frames = args.frames as usize;

    let device = open_device(&args.validation)?;
    let (registry, _) = techniques::load_registry(&device);
    let LoadedGraph {
        graph,
        name: scene_name,
        stats,
    } = load_graph(&args.scene, &args.highlight)?;
    let loading_heap_peak = cadr_core::host_heap::peak_bytes_in_use();
    cadr_core::host_heap::reset_peak();
    let mut session =
        techniques::TechniqueSession::from_graph(&device, graph, registry, (width, height))?;
    session.choose(&combination, shade)?;
    session.set_min_pixels(min_pixels)?;
    session.set_lod_error(args.techniques.lod_error)?;
    let section_line = args::describe_section(&section);
    session.set_section(section);
    apply_render_settings(&mut session, args, shade)?;
    let technique_line = describe_render(
        args,
        &combination,
        session.view.techniques().lod_error(),
        section_line,
    );
    let camera = Camera::fit(
        &stats.bounds,
        f64::from(width) / f64::from(height),
        DEFAULT_DIRECTION,
    );

    let (samples, pass_samples) = render_frames(&mut session, &camera, frames)?;
    session
        .view
        .renderer()
        .save_png(output)
        .map_err(|e| e.to_string())?;

    let validation_errors = device.validation_log().errors().len();
    let adapter = device.adapter();
    println!(
        "scene:       {} ({} nodes, {} geometries, {} materials)",
        scene_name, stats.nodes, stats.geometries, stats.materials
    );
    println!("device:      {} ({:?})", adapter.name, adapter.device_type);
    println!("techniques:  {technique_line}");
    print_frames(stats.instances, &samples);
    let spent = timings::snapshot();
    println!(
        "setup:       load {:.1} ms, upload {:.1} ms",
        spent.ms(Phase::Load),
        spent.ms(Phase::Upload)
    );
    if let Some(report) = session.streaming() {
        let mb = |bytes: u64| bytes as f64 / 1e6;
        println!(
            "streaming:   {:.1} of {:.1} MB of full-detail geometry on the GPU (budget {:.1} MB), {:.1} MB streamed, coarse forms {:.1} MB",
            mb(report.full_bytes),
            mb(report.total_full_bytes),
            mb(report.budget),
            mb(report.streamed_bytes),
            mb(session.coarse_form_bytes())
        );
    }
    let memory = session.graph.geometry_memory();
    if let Some(page_file) = &memory.page_file {
        let mb = |bytes: u64| bytes as f64 / 1e6;
        println!(
            "paging:      {:.1} MB of geometry in memory, {:.1} MB ({} geometries) in {}",
            mb(memory.resident_bytes),
            mb(memory.paged_bytes),
            memory.paged_geometries,
            page_file.display()
        );
    }
    if args.validation.requested() {
        println!("validation:  {validation_errors} errors");
    }
    println!(
        "wrote:       {} ({width}x{height}) in {:.0} ms total",
        output.display(),
        process_start.elapsed().as_secs_f64() * 1e3
    );
    if args.timings {
        print_gpu_passes(&pass_samples);
        print_timings(process_start.elapsed());
        print_memory(&device, stats.instances as u64, loading_heap_peak);
    }
    if validation_errors > 0 {
        return Err(format!(
            "{validation_errors} Vulkan validation errors (see above)"
        ));
    }
    Ok(())
}

/// The renderer's settings that `render` takes from its options besides the techniques.
fn apply_render_settings(
    session: &mut techniques::TechniqueSession,
    args: &RenderArgs,
    shade: ShadeMode,
) -> Result<(), String> {
    session.set_background(args.background)?;
    session.set_msaa(args.msaa)?;
    let renderer = session.view.renderer_mut();
    renderer.set_ssao(args.ssao).map_err(|e| e.to_string())?;
    renderer.set_textures(!args.no_textures);
    renderer
        .set_highlight_style(args.highlight_style)
        .map_err(|e| e.to_string())?;
    renderer
        .set_palette(args.palette())
        .map_err(|e| e.to_string())?;
    renderer
        .set_silhouettes(!args.no_silhouettes)
        .map_err(|e| e.to_string())?;
    if args.dashed && shade != ShadeMode::HiddenLine {
        return Err("--dashed shows hidden edges dashed in --display hidden-line only".into());
    }
    session.techniques().set_dashed_hidden_lines(args.dashed);
    // The baseline records every frame, as the seeds' does.
    session
        .techniques()
        .set_frame_replay(!args.no_replay && !args.baseline);
    Ok(())
}

/// The GPU time of each pass of one frame, in the order drawn (`Renderer::gpu_pass_times`).
pub(crate) type PassTimes = Vec<(&'static str, f64)>;

/// The frames `render` measures: the first alone, or after it (a warm-up frame, so that
/// first-use costs do not count) `frames` more; each one's counters and GPU time per pass.
fn render_frames(
    session: &mut techniques::TechniqueSession,
    camera: &Camera,
    frames: usize,
) -> Result<(Vec<FrameStats>, Vec<PassTimes>), String> {
    let first = session.render(camera)?;
    if frames == 1 {
        return Ok((vec![first], vec![session.gpu_pass_times()]));
    }
    let mut passes = Vec::with_capacity(frames);
    let samples = (0..frames)
        .map(|_| {
            let stats = session.render(camera)?;
            passes.push(session.gpu_pass_times());
            Ok(stats)
        })
        .collect::<Result<_, String>>()?;
    Ok((samples, passes))
}

/// The `techniques:` line of `render`: the combination, the display mode and every option that
/// changes the picture.
fn describe_render(
    args: &RenderArgs,
    combination: &Combination,
    lod_error: f32,
    section_line: Option<String>,
) -> String {
    let shade = args.techniques.shade_mode();
    let min_pixels = args.techniques.min_pixels();
    let mut line = format!("{combination}, {}", shade.name());
    if min_pixels > 0.0 {
        line += &format!(", parts under {min_pixels} px culled");
    }
    if combination.culling == "gpu-clusters" {
        line += &format!(", level of detail {lod_error} px");
    }
    if let Some(section) = section_line {
        line += &format!(", {section}");
    }
    if args.dashed {
        line += ", hidden edges dashed";
    }
    if args.ssao {
        line += ", ambient occlusion";
    }
    if args.no_textures {
        line += ", no textures";
    }
    if !args.highlight.is_empty() {
        line += &format!(
            ", {} highlighted ({})",
            args.highlight.join(", "),
            args.highlight_style.name()
        );
    }
    if args.no_silhouettes && shade.draws_silhouettes() {
        line += ", no silhouettes";
    }
    if args.msaa > 1 {
        line += &format!(", MSAA {}x", args.msaa);
    }
    line
}

/// The `drawn:`, `state:` and `frame:` lines of `render`: what the first measured frame drew
/// of `instances` parts, and the medians of the measured frames.
fn print_frames(instances: usize, samples: &[FrameStats]) {
    let Some(first) = samples.first() else { return };
    println!(
        "drawn:       {} parts, {} triangles, {} draw calls ({} ranges)",
        instances, first.triangles, first.draw_calls, first.draws
    );
    println!(
        "state:       {} pipeline binds, {} vertex/index binds, {} parameter updates",
        first.pipeline_binds, first.vertex_binds, first.parameter_updates
    );
    let mut record: Vec<f64> = samples.iter().map(|s| s.cpu_record_us).collect();
    let mut cpu: Vec<f64> = samples.iter().map(FrameStats::cpu_us).collect();
    let mut gpu: Vec<f64> = samples.iter().filter_map(|s| s.gpu_us).collect();
    let label = if samples.len() == 1 {
        "frame:      ".to_owned()
    } else {
        format!("frame:       median of {},", samples.len())
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
}

/// `--timings`: the median GPU time of each pass of the measured frames (`samples`, each
/// frame's passes in the order drawn).
fn print_gpu_passes(samples: &[PassTimes]) {
    let passes = median_pass_times(samples.iter().map(Vec::as_slice));
    if passes.is_empty() {
        println!("gpu passes:  n/a (no timestamps)");
        return;
    }
    let passes: Vec<String> = passes
        .iter()
        .map(|(name, us)| format!("{name} {us:.0} µs"))
        .collect();
    println!("gpu passes:  {}", passes.join(", "));
}

/// The median GPU time of each pass over the frames `samples` (each frame's passes in the order
/// drawn, `Renderer::gpu_pass_times`), in the order they first appear (a pass some frames lack,
/// such as the uploads, over the frames that have it).
pub(crate) fn median_pass_times<'a>(
    samples: impl Iterator<Item = &'a [(&'static str, f64)]> + Clone,
) -> PassTimes {
    let mut names: Vec<&'static str> = Vec::new();
    for (name, _) in samples.clone().flatten() {
        if !names.contains(name) {
            names.push(name);
        }
    }
    names
        .into_iter()
        .map(|name| {
            let mut times: Vec<f64> = samples
                .clone()
                .flatten()
                .filter(|(pass, _)| *pass == name)
                .map(|(_, us)| *us)
                .collect();
            (name, median(&mut times))
        })
        .collect()
}

/// The most memory this process held resident so far (Linux), in bytes.
fn peak_resident_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kilobytes: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kilobytes * 1024)
}

/// `--timings`: peak memory, device memory and the host's bytes per part, and cadr's own heap
/// at its peak while loading (`loading_heap_peak`) and after. A CPU device (lavapipe) keeps
/// device memory in host memory, so it is taken out of the resident peak.
fn print_memory(device: &Device, parts: u64, loading_heap_peak: u64) {
    let (_, device_peak) = device.memory_in_use();
    let on_host = device.adapter().device_type == cvk::raw::PhysicalDeviceType::CPU;
    let Some(resident) = peak_resident_bytes() else {
        return;
    };
    let host = if on_host {
        resident.saturating_sub(device_peak)
    } else {
        resident
    };
    let mb = |bytes: u64| bytes as f64 / (1024.0 * 1024.0);
    println!(
        "memory:      peak resident {:.0} MB; device memory {:.0} MB at most{}; host {:.0} MB, {:.0} B per part",
        mb(resident),
        mb(device_peak),
        if on_host {
            " (in host memory on this CPU device)"
        } else {
            ""
        },
        mb(host),
        host as f64 / parts.max(1) as f64
    );
    println!(
        "heap:        cadr held {:.0} MB at most while loading, {:.0} MB at most after, {:.0} MB now",
        mb(loading_heap_peak),
        mb(cadr_core::host_heap::peak_bytes_in_use()),
        mb(cadr_core::host_heap::bytes_in_use())
    );
}

/// `--timings`: each phase's share of the run so far (`wall`), and what no phase accounts
/// for (argument parsing, technique selection, plugin discovery, printing).
fn print_timings(wall: std::time::Duration) {
    let spent = timings::snapshot();
    let wall_ms = wall.as_secs_f64() * 1e3;
    let percent = |ms: f64| 100.0 * ms / wall_ms.max(1e-9);
    println!("timings:     {wall_ms:.1} ms from start to PNG written");
    for phase in Phase::ALL {
        let ms = spent.ms(phase);
        println!("  {:<18} {ms:>9.1} ms {:>5.1}%", phase.name(), percent(ms));
    }
    let other = (wall_ms - spent.total().as_secs_f64() * 1e3).max(0.0);
    println!("  {:<18} {other:>9.1} ms {:>5.1}%", "other", percent(other));
}
