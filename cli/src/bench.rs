//! `cadr bench`: renders a scene with the built-in combination (the baseline) and with
//! technique combinations in one run, all through one view of the one GPU scene, and prints a
//! table like the seeds' (CPU microseconds per frame and the driver's submission call's share
//! of them, GPU microseconds, scene update, bytes uploaded, draw calls, state changes,
//! triangles, speedup over the baseline), optionally as JSON and over a growing grid
//! (`--sweep`). The camera stands still or orbits (`--camera`), and
//! `--animate N` moves N assembly nodes every frame: every row sees the same frames.

use std::sync::Arc;

use cadr_core::gpu_scene::Transforms;
use cadr_core::render::{FrameStats, HighlightStyle, Section};
use cadr_core::scene::{Aabb, SceneStats};
use cadr_core::technique::{
    Combination, PluginRegistry, ShadeMode, TechniqueKind, Techniques, DEFAULT_TRANSPARENCY,
};
use cadr_core::view::Coverage;
use cadr_core::vk::Device;

use crate::args::{BenchArgs, BenchShade, Size};
use crate::motion::Motion;
use crate::progress::Steps;
use crate::techniques::{load_registry, FrameSample, TechniqueSession};

/// The (vertex, parameter) pairs the default selection tries with every submission: the
/// classic binds, then the GPU-resident indexed path.
const DEFAULT_PATHS: [(&str, &str); 2] = [("per-geometry", "push"), ("arena", "ssbo-index")];

/// What the sweep measures by default.
pub(crate) const SWEEP_SET: [(&str, &str, &str); 7] = [
    ("per-geometry", "push", "individual"),
    ("per-geometry", "push", "groups"),
    ("per-geometry", "push", "individual-replay"),
    ("per-geometry", "push", "groups-replay"),
    ("arena", "ssbo-index", "individual-mdi"),
    ("arena", "ssbo-index", "groups-mdi-replay"),
    ("per-geometry", "push", "individual-threads"),
];

/// Medians over the measured frames of one row.
///
/// Its many fields are the figures of a row of the table and of `--json` (whose field names
/// tools outside the project read), one each.
#[derive(Clone, Debug)]
pub(crate) struct Row {
    pub(crate) label: String,
    shade: &'static str,
    /// Samples per pixel of the colour pass (1: no MSAA).
    msaa: u32,
    /// Whether screen-space ambient occlusion was on.
    ssao: bool,
    /// Whether silhouette edges were drawn (in the modes that draw them).
    silhouettes: bool,
    /// Whether hidden lines were drawn dashed (in the hidden-line mode).
    dashed: bool,
    /// How highlighted parts were drawn.
    highlight_style: HighlightStyle,
    pub(crate) cpu_us: f64,
    /// Of `cpu_us`, the median time spent handing the recording to the queue (the driver's
    /// submission call); the rest is cadr's own work.
    cpu_submit_us: f64,
    pub(crate) gpu_us: Option<f64>,
    /// Moving nodes and bringing the tree and GPU scene up to date.
    scene_update_us: f64,
    /// Median bytes uploaded per frame.
    bytes_uploaded: u64,
    /// Where moved subtrees' world matrices were computed: "gpu" or "host".
    transforms: &'static str,
    /// Measured frames that resubmitted the last recording, and frames measured.
    replayed: (usize, usize),
    /// The first measured frame's counters.
    pub(crate) stats: FrameStats,
    /// The level-of-detail threshold of a cluster culler's row (none for other rows).
    pub(crate) lod_error: Option<f32>,
    /// Bytes the GPU scene keeps resident.
    resident_bytes: u64,
    /// Bytes the GPU scene's geometry streaming brought to the GPU during the row's frames (its
    /// warm-up included).
    streamed_bytes: u64,
    /// Bytes of host memory cadr's own code held after the row's frames (the scene, the
    /// techniques, the host memory of the Vulkan objects; not the driver's own,
    /// `cadr_core::host_heap`).
    host_allocated_bytes: u64,
    /// The median GPU time of each pass, in the order drawn (`Renderer::gpu_pass_times`).
    gpu_passes: crate::PassTimes,
    /// What the first measured frame's picture covers (`View::coverage`).
    coverage: Option<Coverage>,
}

/// What one row measured: medians of CPU, GPU, scene update and upload, and the first
/// measured frame.
struct Measured {
    cpu_us: f64,
    cpu_submit_us: f64,
    gpu_us: Option<f64>,
    scene_update_us: f64,
    bytes_uploaded: u64,
    /// Measured frames that were replayed, and frames measured.
    replayed: (usize, usize),
    first: FrameStats,
    /// The median GPU time of each pass, in the order drawn.
    gpu_passes: crate::PassTimes,
}

/// The number of the first measured frame of a row: 2 warm-up frames come before it.
const FIRST_MEASURED_FRAME: usize = 2;

/// Renders 2 warm-up frames, then `frames` measured ones (frame numbers from 0, so that every
/// row sees the same motion); medians.
fn measure(
    frames: usize,
    mut draw: impl FnMut(usize) -> Result<FrameSample, String>,
) -> Result<Measured, String> {
    for frame in 0..FIRST_MEASURED_FRAME {
        draw(frame)?;
    }
    let mut samples = Vec::with_capacity(frames);
    for frame in 0..frames {
        samples.push(draw(frame + FIRST_MEASURED_FRAME)?);
    }
    let cpu = crate::median(&mut samples.iter().map(|s| s.stats.cpu_us()).collect::<Vec<_>>());
    let submit = crate::median(
        &mut samples
            .iter()
            .map(|s| s.stats.cpu_submit_us)
            .collect::<Vec<_>>(),
    );
    let mut gpu: Vec<f64> = samples.iter().filter_map(|s| s.stats.gpu_us).collect();
    let gpu = (!gpu.is_empty()).then(|| crate::median(&mut gpu));
    let update = crate::median(&mut samples.iter().map(|s| s.update_us).collect::<Vec<_>>());
    let uploaded = crate::median(
        &mut samples
            .iter()
            .map(|s| s.stats.bytes_uploaded as f64)
            .collect::<Vec<_>>(),
    );
    Ok(Measured {
        cpu_us: cpu,
        cpu_submit_us: submit,
        gpu_us: gpu,
        scene_update_us: update,
        bytes_uploaded: uploaded as u64,
        replayed: (
            samples.iter().filter(|s| s.stats.replayed).count(),
            samples.len(),
        ),
        first: samples[0].stats,
        gpu_passes: crate::median_pass_times(samples.iter().map(|s| s.gpu_passes.as_slice())),
    })
}

impl Row {
    fn new(label: String, shade: &'static str, transforms: Transforms, measured: Measured) -> Self {
        Self {
            label,
            shade,
            msaa: 1,
            ssao: false,
            silhouettes: true,
            dashed: false,
            highlight_style: HighlightStyle::Tint,
            transforms: match transforms {
                Transforms::Gpu => "gpu",
                Transforms::Host => "host",
            },
            cpu_us: measured.cpu_us,
            cpu_submit_us: measured.cpu_submit_us,
            gpu_us: measured.gpu_us,
            scene_update_us: measured.scene_update_us,
            bytes_uploaded: measured.bytes_uploaded,
            replayed: measured.replayed,
            stats: measured.first,
            lod_error: None,
            resident_bytes: 0,
            streamed_bytes: 0,
            host_allocated_bytes: cadr_core::host_heap::bytes_in_use(),
            gpu_passes: measured.gpu_passes,
            coverage: None,
        }
    }

    /// Triangles rasterized per pixel the picture covers (none where it covers none).
    fn triangles_per_covered_pixel(&self) -> Option<f64> {
        let covered = self.coverage?.pixels;
        (covered > 0).then(|| self.stats.triangles_rasterized as f64 / covered as f64)
    }

    /// Clusters the row drew: a cluster culler's ranges.
    fn clusters_drawn(&self) -> Option<u64> {
        self.lod_error.map(|_| self.stats.draws)
    }
}

/// The culler that draws clusters, whose rows are measured per level-of-detail threshold.
const CLUSTER_CULLER: &str = "gpu-clusters";

/// The combinations to measure: every supported one with `--all`; those the options name
/// (each option a comma-separated list, others defaulting to every technique); or the default
/// selection: every submission with the [`DEFAULT_PATHS`] that fit it, culling `none`.
fn selection(args: &BenchArgs, techniques: &Techniques) -> Result<Vec<Combination>, String> {
    let registry = techniques.registry();
    let names = |kind: TechniqueKind| -> Vec<String> {
        registry
            .of_kind(kind)
            .filter(|t| t.support.is_ok())
            .map(|t| t.name.clone())
            .collect()
    };
    // A kind's list as given (blank names dropped, each checked), or `default`.
    let chosen = |(kind, option, list): (TechniqueKind, &str, Option<&[String]>),
                  default: Vec<String>|
     -> Result<Vec<String>, String> {
        let Some(list) = list else {
            return Ok(default);
        };
        let wanted: Vec<String> = list
            .iter()
            .map(|name| name.trim().to_owned())
            .filter(|name| !name.is_empty())
            .collect();
        if let Some(unknown) = wanted
            .iter()
            .find(|name| registry.find(kind, name).is_none())
        {
            return Err(format!(
                "{option} {unknown}: no such {} technique (see cadr techniques)",
                kind.name()
            ));
        }
        Ok(wanted)
    };
    let [vertex_list, parameter_list, submission_list, culling_list, transparency_list] =
        args.technique_lists();
    let any_filter = [vertex_list, parameter_list, submission_list, culling_list]
        .iter()
        .any(|(_, _, list)| list.is_some());
    let transparency_default = if args.all {
        names(TechniqueKind::Transparency)
    } else {
        vec![DEFAULT_TRANSPARENCY.to_owned()]
    };
    let methods = chosen(transparency_list, transparency_default)?;
    let mut combinations = Vec::new();
    if args.all || any_filter {
        let cull_default = if args.all {
            names(TechniqueKind::Culling)
        } else {
            vec!["none".to_owned()]
        };
        let cullers = chosen(culling_list, cull_default)?;
        for vertex in chosen(vertex_list, names(TechniqueKind::Vertex))? {
            for parameters in chosen(parameter_list, names(TechniqueKind::Parameters))? {
                for submission in chosen(submission_list, names(TechniqueKind::Submission))? {
                    for culling in &cullers {
                        for transparency in &methods {
                            combinations.push(Combination {
                                vertex: vertex.clone(),
                                parameters: parameters.clone(),
                                submission: submission.clone(),
                                culling: culling.clone(),
                                transparency: transparency.clone(),
                            });
                        }
                    }
                }
            }
        }
    } else {
        for submission in names(TechniqueKind::Submission) {
            for (vertex, parameters) in DEFAULT_PATHS {
                for transparency in &methods {
                    combinations.push(Combination {
                        vertex: vertex.into(),
                        parameters: parameters.into(),
                        submission: submission.clone(),
                        culling: "none".into(),
                        transparency: transparency.clone(),
                    });
                }
            }
        }
    }
    Ok(combinations
        .into_iter()
        .filter(|c| techniques.check(c).is_ok())
        .collect())
}

pub(crate) struct Bench {
    pub(crate) device: Arc<Device>,
    registry: Arc<PluginRegistry>,
    size: Size,
    pub(crate) frames: usize,
    motion: Motion,
    /// The `gpu-` cullers' sub-pixel threshold (`--min-pixels`; 0: off).
    min_pixels: f32,
    /// Whether the measured combinations may replay unchanged frames (not `--no-replay`).
    frame_replay: bool,
    /// The section every row cuts the scene with (`--section`, `--caps`, `--no-caps`,
    /// `--hatch`).
    pub(crate) section: Section,
    /// The level-of-detail thresholds cluster rows are measured at (`--lod-error`).
    lod_errors: Vec<f32>,
}

/// Each combination once, a cluster culler's once per level-of-detail threshold.
fn with_lod_errors<'c>(
    combinations: &'c [Combination],
    lod_errors: &[f32],
) -> Vec<(&'c Combination, Option<f32>)> {
    combinations
        .iter()
        .flat_map(|combination| {
            if combination.culling == CLUSTER_CULLER {
                lod_errors
                    .iter()
                    .map(|&pixels| (combination, Some(pixels)))
                    .collect::<Vec<_>>()
            } else {
                vec![(combination, None)]
            }
        })
        .collect()
}

impl Bench {
    /// Measures the baseline (when `with_baseline`) and `combinations` (per shade mode) on
    /// the scene `source` names, loaded straight into the graph (a model larger than memory
    /// loads: see `crate::load_graph`); the first row is the reference of the speedups.
    pub(crate) fn run(
        &self,
        source: &str,
        combinations: Option<&[Combination]>,
        args: &BenchArgs,
        (quiet, with_baseline): (bool, bool),
    ) -> Result<(SceneStats, Vec<Row>), String> {
        let crate::LoadedGraph {
            graph,
            name: scene_name,
            stats,
        } = crate::load_graph(source, &args.highlight)?;
        let aspect = self.size.aspect();
        let mut rows = Vec::new();
        let mut session = TechniqueSession::from_graph(
            &self.device,
            graph,
            Arc::clone(&self.registry),
            (self.size.width, self.size.height),
        )?;
        session.set_section(self.section.clone());
        let mut motion = self.motion.clone();
        motion.choose_nodes(&session.graph, &stats.bounds);
        if !quiet && motion.requested > 0 {
            println!(
                "animate: {} of {} requested assembly nodes move every frame",
                motion.moved_nodes(),
                motion.requested
            );
        }
        let combinations = match combinations {
            Some(list) => list.to_vec(),
            None => selection(args, session.techniques())?,
        };
        let modes = BenchShade::modes_of(&args.shade);
        let settings = row_settings(args);
        // Silhouettes change only the modes that draw them, dashes only hidden-line: other
        // modes get one row for the first setting listed.
        let measured_in = |settings: &RowSettings, mode: ShadeMode| {
            (mode.draws_silhouettes() || settings.silhouettes == args.silhouettes[0])
                && (mode == ShadeMode::HiddenLine || settings.dashed == args.dashed[0])
        };
        let rows_to_measure = settings
            .iter()
            .flat_map(|s| modes.iter().filter(|&&mode| measured_in(s, mode)))
            .count()
            * with_lod_errors(&combinations, &self.lod_errors).len();
        let mut steps = Steps::new(
            u64::from(with_baseline) + rows_to_measure as u64,
            &format!("bench {scene_name}"),
        );
        let show = |steps: &Steps, line: String| {
            if !quiet {
                steps.println(&line);
            }
        };
        let view = (&stats.bounds, aspect);
        show(&steps, header_line());
        if with_baseline {
            steps.start("baseline");
            let baseline = self.measure_baseline(&mut session, &motion, view)?;
            show(&steps, row_line(&baseline, baseline.cpu_us));
            steps.done();
            rows.push(baseline);
        }
        for setting in &settings {
            session.set_msaa(setting.msaa)?;
            let renderer = session.view.renderer_mut();
            renderer
                .set_ssao(setting.ssao)
                .and_then(|()| renderer.set_silhouettes(setting.silhouettes))
                .and_then(|()| renderer.set_highlight_style(setting.highlight_style))
                .map_err(|e| e.to_string())?;
            for &mode in modes.iter().filter(|&&mode| measured_in(setting, mode)) {
                for (combination, lod_error) in with_lod_errors(&combinations, &self.lod_errors) {
                    steps.start(&format!(
                        "{combination} [{}, {}x]",
                        mode.name(),
                        setting.msaa
                    ));
                    let row = self.measure_row(
                        &mut session,
                        (&motion, view),
                        (setting, mode),
                        (combination, lod_error),
                    )?;
                    let reference = rows.first().map_or(row.cpu_us, |first| first.cpu_us);
                    show(&steps, row_line(&row, reference));
                    steps.done();
                    rows.push(row);
                }
            }
        }
        Ok((stats, rows))
    }
}

impl Bench {
    /// The reference row: the built-in combination, recording every frame as the seeds'
    /// baseline does.
    fn measure_baseline(
        &self,
        session: &mut TechniqueSession,
        motion: &Motion,
        view: (&Aabb, f64),
    ) -> Result<Row, String> {
        session.choose(&Combination::built_in(), ShadeMode::Solid)?;
        session.techniques().set_frame_replay(false);
        let streamed_before = session.streamed_bytes();
        let measured = measure(self.frames, |frame| {
            session.render_moving(motion, view, frame)
        })?;
        let transforms = session.techniques().transforms();
        let streamed_bytes = session.streamed_bytes() - streamed_before;
        let coverage = session.coverage_at(motion, view, FIRST_MEASURED_FRAME)?;
        let baseline = Row {
            resident_bytes: session.resident_bytes(),
            streamed_bytes,
            coverage: Some(coverage),
            ..Row::new("baseline (built-in)".into(), "solid", transforms, measured)
        };
        session.techniques().set_frame_replay(self.frame_replay);
        Ok(baseline)
    }

    /// One row: `combination` in display `mode` with the renderer already set to `setting`,
    /// at `lod_error` where it is a cluster culler's row.
    fn measure_row(
        &self,
        session: &mut TechniqueSession,
        (motion, view): (&Motion, (&Aabb, f64)),
        (setting, mode): (&RowSettings, ShadeMode),
        (combination, lod_error): (&Combination, Option<f32>),
    ) -> Result<Row, String> {
        session.choose(combination, mode)?;
        session
            .techniques()
            .set_min_pixels(self.min_pixels)
            .map_err(|e| e.to_string())?;
        if let Some(pixels) = lod_error {
            session
                .techniques()
                .set_lod_error(pixels)
                .map_err(|e| e.to_string())?;
        }
        session.techniques().set_dashed_hidden_lines(setting.dashed);
        let streamed_before = session.streamed_bytes();
        let measured = measure(self.frames, |frame| {
            session.render_moving(motion, view, frame)
        })?;
        let transforms = session.techniques().transforms();
        let streamed_bytes = session.streamed_bytes() - streamed_before;
        let coverage = session.coverage_at(motion, view, FIRST_MEASURED_FRAME)?;
        Ok(Row {
            coverage: Some(coverage),
            msaa: setting.msaa,
            ssao: setting.ssao,
            silhouettes: setting.silhouettes,
            dashed: setting.dashed && mode == ShadeMode::HiddenLine,
            highlight_style: setting.highlight_style,
            lod_error,
            resident_bytes: session.resident_bytes(),
            streamed_bytes,
            ..Row::new(combination.to_string(), mode.name(), transforms, measured)
        })
    }
}

/// Every setting a row is measured with (`--ssao`, `--msaa`, `--highlight-style`,
/// `--silhouettes`, `--dashed`), the last varied fastest.
fn row_settings(args: &BenchArgs) -> Vec<RowSettings> {
    let ssao_levels: &[bool] = if args.ssao { &[false, true] } else { &[false] };
    ssao_levels
        .iter()
        .flat_map(|&ssao| args.msaa.iter().map(move |&msaa| (ssao, msaa)))
        .flat_map(|(ssao, msaa)| {
            args.highlight_style
                .iter()
                .map(move |&highlight_style| (ssao, msaa, highlight_style))
        })
        .flat_map(|(ssao, msaa, highlight_style)| {
            args.silhouettes
                .iter()
                .map(move |&silhouettes| (ssao, msaa, highlight_style, silhouettes))
        })
        .flat_map(|(ssao, msaa, highlight_style, silhouettes)| {
            args.dashed.iter().map(move |&dashed| RowSettings {
                ssao,
                msaa,
                highlight_style,
                silhouettes,
                dashed,
            })
        })
        .collect()
}

/// The display mode of a row, with its MSAA level when it has one ("edges, 4x").
pub(crate) fn row_mode(row: &Row) -> String {
    let mut mode = shade_label(row);
    if row.msaa > 1 {
        mode += &format!(", {}x", row.msaa);
    }
    mode
}

/// The settings of the renderer a row is measured with.
struct RowSettings {
    ssao: bool,
    msaa: u32,
    highlight_style: HighlightStyle,
    silhouettes: bool,
    dashed: bool,
}

/// The display mode of a row, with "+ao" when ambient occlusion was on, "+outline" with the
/// outline highlight style, "+dashed" for hidden-line with its hidden lines dashed and "-sil"
/// when a mode that draws silhouettes did not.
fn shade_label(row: &Row) -> String {
    let mut label = row.shade.to_owned();
    if row.dashed {
        label += "+dashed";
    }
    if row.ssao {
        label += "+ao";
    }
    if row.highlight_style == HighlightStyle::Outline {
        label += "+outline";
    }
    if !row.silhouettes && ShadeMode::parse(row.shade).is_some_and(ShadeMode::draws_silhouettes) {
        label += "-sil";
    }
    if let Some(pixels) = row.lod_error {
        label += &format!(" lod {pixels}px");
    }
    label
}

fn header_line() -> String {
    format!(
        "{:<58} {:>26} {:>4} {:>7} {:>10} {:>9} {:>10} {:>9} {:>9} {:>8} {:>8} {:>6} {:>7} {:>7} {:>10} {:>9}",
        "technique (vertex / params / submit / cull)",
        "shade",
        "AA",
        "replay",
        "CPU µs",
        "submit µs",
        "GPU µs",
        "update µs",
        "upload B",
        "calls",
        "ranges",
        "pipe",
        "vertex",
        "param",
        "triangles",
        "speedup"
    )
}

fn row_line(row: &Row, baseline_cpu: f64) -> String {
    let gpu = row.gpu_us.map_or("n/a".to_owned(), |g| format!("{g:.0}"));
    let s = &row.stats;
    format!(
        "{:<58} {:>26} {:>4} {:>7} {:>10.1} {:>9.1} {:>10} {:>9.1} {:>9} {:>8} {:>8} {:>6} {:>7} {:>7} {:>10} {:>8.1}x",
        row.label,
        shade_label(row),
        format!("{}x", row.msaa),
        format!("{}/{}", row.replayed.0, row.replayed.1),
        row.cpu_us,
        row.cpu_submit_us,
        gpu,
        row.scene_update_us,
        row.bytes_uploaded,
        s.draw_calls,
        s.draws,
        s.pipeline_binds,
        s.vertex_binds,
        s.parameter_updates,
        s.triangles_rasterized,
        baseline_cpu / row.cpu_us.max(0.001)
    )
}

fn row_json(row: &Row, baseline_cpu: f64) -> serde_json::Value {
    let s = &row.stats;
    serde_json::json!({
        "technique": row.label,
        "shade": row.shade,
        "msaa": row.msaa,
        "ssao": row.ssao,
        "silhouettes": row.silhouettes,
        "dashed": row.dashed,
        "highlight_style": row.highlight_style.name(),
        "cpu_us": row.cpu_us,
        "cpu_submit_us": row.cpu_submit_us,
        "gpu_us": row.gpu_us,
        "gpu_pass_us": row
            .gpu_passes
            .iter()
            .map(|(pass, us)| serde_json::json!({ "pass": pass, "us": us }))
            .collect::<Vec<_>>(),
        "scene_update_us": row.scene_update_us,
        "bytes_uploaded": row.bytes_uploaded,
        "transforms": row.transforms,
        "replayed_frames": row.replayed.0,
        "draw_calls": s.draw_calls,
        "draws": s.draws,
        "pipeline_binds": s.pipeline_binds,
        "vertex_binds": s.vertex_binds,
        "parameter_binds": s.parameter_updates,
        "triangles": s.triangles,
        "triangles_rasterized": s.triangles_rasterized,
        "clusters_drawn": row.clusters_drawn(),
        "covered_pixels": row.coverage.map(|c| c.pixels),
        "parts_with_pixels": row.coverage.map(|c| c.parts),
        "triangles_per_covered_pixel": row.triangles_per_covered_pixel(),
        "lod_error": row.lod_error,
        "resident_bytes": row.resident_bytes,
        "host_allocated_bytes": row.host_allocated_bytes,
        "streamed_bytes": row.streamed_bytes,
        "speedup": baseline_cpu / row.cpu_us.max(0.001),
    })
}

pub(crate) fn stats_json(name: &str, stats: &SceneStats) -> serde_json::Value {
    serde_json::json!({
        "name": name,
        "nodes": stats.nodes,
        "geometries": stats.geometries,
        "materials": stats.materials,
        "parts": stats.instances,
        "triangles": stats.triangles,
        "vertices": stats.vertices,
    })
}

pub(crate) fn rows_json(rows: &[Row]) -> Vec<serde_json::Value> {
    let baseline_cpu = rows.first().map_or(1.0, |r| r.cpu_us);
    rows.iter().map(|r| row_json(r, baseline_cpu)).collect()
}

/// The section of every row: its planes (unit normals, `[nx, ny, nz, d]`), whether cuts are
/// capped and hatched; null without planes.
pub(crate) fn section_json(section: &Section) -> serde_json::Value {
    if section.planes().is_empty() {
        return serde_json::Value::Null;
    }
    serde_json::json!({
        "planes": section.planes().iter().map(|p| p.to_array()).collect::<Vec<_>>(),
        "caps": section.caps(),
        "hatch": section.hatched(),
    })
}

/// Empty submissions timed for the floor line.
const FLOOR_SAMPLES: usize = 1000;

/// `cadr bench`.
pub fn bench(args: &BenchArgs) -> Result<(), String> {
    if let Some(path) = &args.plot {
        crate::plot::check_path(path)?;
    }
    let motion = Motion::new(args.camera, args.animate);
    let sweep = args.sweeping();
    let frames = args.frames.map_or(
        if sweep || args.sweeping_detail() {
            5
        } else {
            10
        },
        |n| n as usize,
    );
    let size = args.size;
    let device = crate::open_device(&args.validation)?;
    let offered = device.sample_counts();
    if let Some(samples) = args.msaa.iter().find(|s| !offered.contains(s)) {
        return Err(format!(
            "--msaa {samples}: {} offers {offered:?} samples per pixel",
            device.adapter().name
        ));
    }
    let section = args.section.section()?;
    let (registry, _) = load_registry(&device);
    let bench = Bench {
        device: Arc::clone(&device),
        registry,
        size,
        frames,
        motion: motion.clone(),
        min_pixels: args.min_pixels.unwrap_or(0.0),
        frame_replay: !args.no_replay,
        section,
        lod_errors: args.lod_error.clone(),
    };
    println!(
        "device: {} — {} measured frames after 2 warm-up frames, {}x{}, medians; camera {}, {} animated nodes{}{}{}",
        device.adapter().name,
        frames,
        size.width,
        size.height,
        motion.camera.name(),
        motion.requested,
        if bench.min_pixels > 0.0 {
            format!("; gpu- cullers skip parts under {} px", bench.min_pixels)
        } else {
            String::new()
        },
        crate::args::describe_section(&bench.section)
            .map_or(String::new(), |section| format!("; {section}")),
        if args.highlight.is_empty() {
            String::new()
        } else {
            format!("; highlighted: {}", args.highlight.join(", "))
        },
    );
    let json = if let Some(details) = &args.sweep_detail {
        crate::bench_sweep::run_detail_sweep(&bench, args, details)?
    } else if sweep {
        crate::bench_sweep::run_sweep(&bench, args)?
    } else {
        let name = args.scene.as_str();
        let (stats, rows) = bench.run(name, None, args, (false, true))?;
        println!(
            "scene: {name}: {} parts, {} triangles, {} materials, {} geometries",
            stats.instances, stats.triangles, stats.materials, stats.geometries
        );
        let floor_us = crate::median(
            &mut cadr_core::vk::resubmit_times_us(&device, FLOOR_SAMPLES)
                .map_err(|e| e.to_string())?,
        );
        println!(
            "floor: the driver takes {floor_us:.1} µs to resubmit an empty recorded command buffer \
             (median of {FLOOR_SAMPLES}, back to back); a row's CPU µs is its submit µs (the \
             driver's submission call, dearer to a queue that idled through a long frame) plus \
             cadr's own work"
        );
        if let Some(path) = &args.plot {
            let bars: Vec<(String, f64)> = rows
                .iter()
                .map(|row| (format!("{} [{}]", row.label, row_mode(row)), row.cpu_us))
                .collect();
            let title = format!(
                "{name}: {} parts, camera {}, {} — CPU µs per frame",
                stats.instances,
                motion.camera.name(),
                device.adapter().name
            );
            crate::plot::bars(path, &title, &bars)?;
            println!("wrote {}", path.display());
        }
        serde_json::json!({
            "device": device.adapter().name,
            "frames": frames,
            "size": [size.width, size.height],
            "camera": motion.camera.name(),
            "animate": motion.requested,
            "min_pixels": bench.min_pixels,
            "frame_replay": bench.frame_replay,
            "section": section_json(&bench.section),
            "highlight": args.highlight,
            "scene": stats_json(name, &stats),
            "submit_floor_us": floor_us,
            "rows": rows_json(&rows),
        })
    };
    if let Some(path) = &args.json {
        let text = serde_json::to_string_pretty(&json).map_err(|e| e.to_string())?;
        std::fs::write(path, text + "\n")
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        println!("wrote {}", path.display());
    }
    let errors = device.validation_log().errors().len();
    if errors > 0 {
        return Err(format!("{errors} Vulkan validation errors"));
    }
    Ok(())
}
