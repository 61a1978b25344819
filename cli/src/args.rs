//! The command line, declared with `clap`: every command, its options and their help. The
//! commands' modules take the parsed structures; values are checked here (sizes, counts,
//! thresholds), so that a bad value is refused with the option's name before any work starts.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

use cadr_core::render::{Background, DisplayRgb, HighlightStyle, Palette, Section};
use cadr_core::technique::{Combination, ShadeMode, TechniqueKind};

use crate::motion::CameraPath;

/// What every command's help ends with: scenes, the cache, validation and plugins.
const ENVIRONMENT_HELP: &str = "\
SCENE is a .gltf, .glb, .csf or .csf.gz file, or a generator:
    gen:demo           the built-in demo (default)
    gen:graphicscard   ~68 000 parts of ~10 triangles (the seeds' Graphicscard)
    gen:racecar        ~98 000 parts of ~37 triangles
    gen:cabinet        machines in closed housings, racks of cabinets (optional :cabinets=N,
                       default 24, 366 parts each): most parts hidden from outside
    gen:grid:parts=N   exactly N parts in a cube of objects (optional ,tris=T)

Compiled shaders and the Vulkan pipeline cache are kept between runs in $CADR_CACHE_DIR, else
$XDG_CACHE_HOME/cadr, else ~/.cache/cadr; --no-cache neither reads nor writes it.
Validation layers are on with --validation or CADR_VALIDATION=1. Plugins are found beside the
executable (and in its plugins/ folder) and in the directories of CADR_PLUGIN_PATH;
CADR_DEVICE=INDEX|NAME picks the Vulkan device.
Exit status: 0 on success, 1 when the work failed, 2 when the command line is wrong.";

/// cadr: a Vulkan renderer for very large CAD assemblies.
#[derive(Debug, Parser)]
#[command(
    name = "cadr",
    version,
    propagate_version = true,
    arg_required_else_help = true,
    after_help = ENVIRONMENT_HELP
)]
pub struct Cli {
    /// Neither read nor write the disk cache of compiled shaders and pipelines.
    #[arg(long, global = true)]
    pub no_cache: bool,
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Draw a scene offscreen and write a PNG.
    ///
    /// Draws the scene with the camera fitted to its bounds, writes a PNG and prints what it
    /// drew and the frame's CPU and GPU time. It draws with one technique per kind, solid or
    /// with edges; the default is the built-in combination (per-geometry, push, individual,
    /// none), which needs no plugin library. A frame that would record what the last one
    /// recorded (only the camera or parts moved, or nothing) resubmits it instead.
    #[command(after_help = ENVIRONMENT_HELP)]
    Render(RenderArgs),
    /// What lies under a pixel (or in a rectangle) of the view `render` draws.
    ///
    /// Same size, camera and technique options as `render`: prints the geo node and part, its
    /// path of nodes from the root (a shared part has one per occurrence), the depth and the
    /// world position (f64).
    #[command(after_help = ENVIRONMENT_HELP)]
    Pick(PickArgs),
    /// Print nodes, geometries, parts, materials, instances, triangles, vertices and bounds.
    #[command(after_help = ENVIRONMENT_HELP)]
    Info(InfoArgs),
    /// Write a scene in another format and say what the target cannot hold.
    ///
    /// OUT is .gltf (with a .bin beside it), .glb, .csf or .csf.gz.
    #[command(after_help = ENVIRONMENT_HELP)]
    Convert(ConvertArgs),
    /// List every technique (built in or from a plugin library) and whether this device runs it.
    Techniques(TechniquesArgs),
    /// Measure technique combinations against the built-in baseline in one run.
    ///
    /// Renders the built-in combination (the baseline, which records every frame) and
    /// technique combinations (by default every submission with per-geometry/push and
    /// arena/ssbo-index; --all for every supported one; lists to choose) for N frames after 2
    /// warm-up frames and prints CPU µs (and of it the driver's submission call, submit µs),
    /// GPU µs, scene update µs, bytes uploaded, draw calls, state changes, triangles and the
    /// speedup over the baseline. Rows other than the baseline replay unchanged frames (the
    /// replay column counts them) unless --no-replay.
    #[command(after_help = ENVIRONMENT_HELP)]
    Bench(BenchArgs),
    /// Measure edits of the incremental scene tree against a full rebuild.
    ///
    /// Builds the incremental scene tree of SCENE and measures edits (1 transform, 1% and 100%
    /// of part placements, a material, hiding 1%) against a full rebuild in the same run,
    /// memory per instance and bytes uploaded per frame.
    #[command(after_help = ENVIRONMENT_HELP)]
    BenchTree(BenchTreeArgs),
    /// List the Vulkan devices (CADR_DEVICE=INDEX|NAME picks one).
    Devices,
    /// Print a shell completion script.
    ///
    /// For example: cadr completions bash > ~/.local/share/bash-completion/completions/cadr
    Completions(CompletionsArgs),
}

/// `--validation` and `--no-validation`.
#[derive(Debug, Args)]
pub struct ValidationArgs {
    /// Turn the Vulkan validation layers on (as CADR_VALIDATION=1 does).
    #[arg(long)]
    pub validation: bool,
    /// Keep them off even when CADR_VALIDATION asks for them.
    #[arg(long, conflicts_with = "validation")]
    pub no_validation: bool,
}

impl ValidationArgs {
    /// Whether the options or the environment ask for the validation layers.
    pub fn requested(&self) -> bool {
        if self.no_validation {
            return false;
        }
        self.validation || std::env::var("CADR_VALIDATION").is_ok_and(|v| v != "0" && !v.is_empty())
    }
}

/// The display modes of `render` and `pick`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Shade {
    /// Shaded surfaces.
    #[value(alias = "shaded")]
    Solid,
    /// Shaded surfaces with their feature edges.
    Edges,
    /// Feature edges only, those hidden behind opaque surfaces removed (section caps filled).
    HiddenLine,
    /// Every triangle's edges, hidden ones included.
    Wireframe,
    /// Every part translucent with its edges, highlighted parts opaque.
    #[value(name = "xray")]
    XRay,
}

impl Shade {
    /// The renderer's mode.
    pub fn mode(self) -> ShadeMode {
        match self {
            Self::Solid => ShadeMode::Solid,
            Self::Edges => ShadeMode::Edges,
            Self::HiddenLine => ShadeMode::HiddenLine,
            Self::Wireframe => ShadeMode::Wireframe,
            Self::XRay => ShadeMode::XRay,
        }
    }
}

/// One technique per kind, the shade mode and the sub-pixel threshold (`render`, `pick`).
#[derive(Debug, Args)]
pub struct TechniqueArgs {
    /// Vertex technique (see cadr techniques; default per-geometry).
    #[arg(long, value_name = "NAME")]
    pub vertex: Option<String>,
    /// Parameter technique (default push).
    #[arg(long = "params", value_name = "NAME")]
    pub parameters: Option<String>,
    /// Submission technique (default individual).
    #[arg(long = "submit", value_name = "NAME")]
    pub submission: Option<String>,
    /// Culling technique (default none).
    #[arg(long = "cull", value_name = "NAME")]
    pub culling: Option<String>,
    /// Transparency method for translucent parts (default weighted-blended; per-pixel-lists is
    /// exact).
    #[arg(long, value_name = "NAME")]
    pub transparency: Option<String>,
    /// Display mode (--shade is another name for it).
    #[arg(long = "display", alias = "shade", value_enum, value_name = "MODE")]
    pub shade: Option<Shade>,
    /// Skip parts whose bounding sphere projects under PX pixels across (gpu- cullers only;
    /// off by default, as CAD users count small parts).
    #[arg(long, value_name = "PX", value_parser = parse_min_pixels, allow_negative_numbers = true)]
    pub min_pixels: Option<f32>,
    /// The level of detail of --cull gpu-clusters: each part is drawn with the coarsest
    /// clusters whose simplification error projects at or under PX pixels (default 1; 0 draws
    /// full detail).
    #[arg(long, value_name = "PX", value_parser = parse_min_pixels, allow_negative_numbers = true)]
    pub lod_error: Option<f32>,
}

impl TechniqueArgs {
    /// The combination the options choose (defaults for kinds not given).
    pub fn combination(&self) -> Combination {
        let mut combination = Combination::built_in();
        for (kind, name) in [
            (TechniqueKind::Vertex, &self.vertex),
            (TechniqueKind::Parameters, &self.parameters),
            (TechniqueKind::Submission, &self.submission),
            (TechniqueKind::Culling, &self.culling),
            (TechniqueKind::Transparency, &self.transparency),
        ] {
            if let Some(name) = name {
                combination.set(kind, name);
            }
        }
        combination
    }

    /// The shade mode (solid unless given).
    pub fn shade_mode(&self) -> ShadeMode {
        self.shade.map_or(ShadeMode::Solid, Shade::mode)
    }

    /// The sub-pixel threshold (0, off, unless given).
    pub fn min_pixels(&self) -> f32 {
        self.min_pixels.unwrap_or(0.0)
    }

    /// Whether any technique option was given.
    pub fn any(&self) -> bool {
        self.vertex.is_some()
            || self.parameters.is_some()
            || self.submission.is_some()
            || self.culling.is_some()
            || self.transparency.is_some()
            || self.shade.is_some()
            || self.min_pixels.is_some()
            || self.lod_error.is_some()
    }
}

/// Section planes and their caps (`render`, `pick`, `bench`).
#[derive(Debug, Args)]
pub struct SectionArgs {
    /// Cut the scene with the plane NX,NY,NZ,D (world units), keeping the side where
    /// NX·x + NY·y + NZ·z + D >= 0; repeat for up to 6 planes. Write --section=-1,0,0,5 when
    /// the first number is negative.
    #[arg(long = "section", value_name = "NX,NY,NZ,D", value_parser = parse_plane,
          allow_negative_numbers = true)]
    pub planes: Vec<glam::DVec4>,
    /// Fill the cut of closed parts with the plane's colour (the default).
    #[arg(long, overrides_with = "no_caps")]
    pub caps: bool,
    /// Show the inside of cut parts instead of filling the cut.
    #[arg(long, overrides_with = "caps")]
    pub no_caps: bool,
    /// Hatch the caps.
    #[arg(long)]
    pub hatch: bool,
}

impl RenderArgs {
    /// The palette `--edge-color`, `--highlight-color` and `--outline-width` give (the
    /// default where one is not given).
    pub fn palette(&self) -> Palette {
        let default = Palette::DEFAULT;
        Palette {
            edges: self.edge_color.unwrap_or(default.edges),
            highlight: self.highlight_color.unwrap_or(default.highlight),
            outline_width: self.outline_width.unwrap_or(default.outline_width),
        }
    }
}

impl SectionArgs {
    /// The section the options give (no planes: nothing cut).
    pub fn section(&self) -> Result<Section, String> {
        let mut section = Section::none();
        section
            .set_planes(&self.planes)
            .map_err(|e| format!("--section: {e}"))?;
        section.set_caps(!self.no_caps);
        section.set_hatched(self.hatch);
        Ok(section)
    }
}

/// A short description of `section` for the report ("2 section planes, capped"); none without
/// planes.
pub fn describe_section(section: &Section) -> Option<String> {
    let count = section.planes().len();
    (count > 0).then(|| {
        format!(
            "{count} section plane{}, {}",
            if count == 1 { "" } else { "s" },
            match (section.caps(), section.hatched()) {
                (false, _) => "uncapped",
                (true, true) => "capped, hatched",
                (true, false) => "capped",
            }
        )
    })
}

/// `cadr render`.
///
/// Its many fields are the command's options, one each, as clap parses them.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// The scene: a file or a generator.
    #[arg(value_name = "SCENE", default_value = "gen:demo")]
    pub scene: String,
    /// The PNG to write.
    #[arg(short, long, value_name = "OUT.png", default_value = "out.png")]
    pub output: PathBuf,
    /// Image size.
    #[arg(long, value_name = "WxH", default_value = "1024x768", value_parser = parse_size)]
    pub size: Size,
    /// Render N frames after one warm-up and report medians.
    #[arg(long, value_name = "N", default_value_t = 1,
          value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub frames: u32,
    #[command(flatten)]
    pub techniques: TechniqueArgs,
    #[command(flatten)]
    pub section: SectionArgs,
    /// Record every frame instead of replaying unchanged ones.
    #[arg(long)]
    pub no_replay: bool,
    /// Draw with the built-in combination and record every frame, as the seeds' baseline does.
    #[arg(long)]
    pub baseline: bool,
    /// Print where the run's time went: instance and device creation, load, scene build,
    /// upload, shader compile, pipeline creation, first frame, readback, PNG encode.
    #[arg(long)]
    pub timings: bool,
    /// The background: gradient (the default), flat, one colour #RRGGBB, or a gradient
    /// from the top colour to the bottom one, #RRGGBB,#RRGGBB.
    #[arg(long, value_name = "gradient|flat|#RRGGBB[,#RRGGBB]", value_parser = parse_background,
          default_value = "gradient")]
    pub background: Background,
    /// Darken creases, corners and gaps between parts with screen-space ambient occlusion
    /// (solid, edges and xray).
    #[arg(long)]
    pub ssao: bool,
    /// Draw materials without their textures (base colours and vertex colours only).
    #[arg(long)]
    pub no_textures: bool,
    /// In the hidden-line display mode, show the hidden edges dashed, in a lighter shade of
    /// the edge colour, instead of removing them.
    #[arg(long)]
    pub dashed: bool,
    /// Draw the display modes with feature edges (edges, hidden-line, X-ray) without the
    /// silhouettes of curved surfaces.
    #[arg(long)]
    pub no_silhouettes: bool,
    /// Highlight the nodes named NAME (and what is below them), as a host highlights a
    /// selection; repeatable.
    #[arg(long, value_name = "NAME")]
    pub highlight: Vec<String>,
    /// How highlighted parts show: tinted towards the highlight colour (tint, the default) or
    /// with a band in it around them, their colours kept (outline).
    #[arg(long, value_name = "tint|outline", default_value = "tint", value_parser = parse_highlight_style)]
    pub highlight_style: HighlightStyle,
    /// The colour of edge lines and silhouettes, #RRGGBB (default #0F1217, near-black; dashed
    /// hidden lines take a lighter shade of it).
    #[arg(long, value_name = "#RRGGBB", value_parser = parse_hex_color)]
    pub edge_color: Option<DisplayRgb>,
    /// The highlight colour, #RRGGBB: what highlighted parts are tinted towards or outlined in
    /// (default #FF8C0D, orange).
    #[arg(long, value_name = "#RRGGBB", value_parser = parse_hex_color)]
    pub highlight_color: Option<DisplayRgb>,
    /// The width in pixels of the band the outline highlight style draws, 1 to 8 (default 2).
    #[arg(long, value_name = "PX", value_parser = clap::value_parser!(u32).range(1..=8))]
    pub outline_width: Option<u32>,
    /// Anti-alias with N samples per pixel (MSAA: 1, the default, is off; 2, 4 or 8 where the
    /// device offers them: cadr devices lists them).
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = parse_msaa)]
    pub msaa: u32,
    #[command(flatten)]
    pub validation: ValidationArgs,
}

/// `cadr pick`.
#[derive(Debug, Args)]
pub struct PickArgs {
    /// The scene.
    #[arg(value_name = "SCENE")]
    pub scene: String,
    /// The pixel's column, from the left.
    #[arg(value_name = "X")]
    pub x: u32,
    /// The pixel's row, from the top.
    #[arg(value_name = "Y")]
    pub y: u32,
    /// View size.
    #[arg(long, value_name = "WxH", default_value = "1024x768", value_parser = parse_size)]
    pub size: Size,
    /// List every pickable part with a visible pixel in the rectangle from (X, Y) to (X2, Y2).
    #[arg(long, value_name = "X2,Y2", value_parser = parse_corner)]
    pub rect: Option<(u32, u32)>,
    /// Print hit, node, part, path, depth and position (and hits for --rect) as JSON.
    #[arg(long)]
    pub json: bool,
    /// Pick through translucent parts (material opacity under 1) to what is behind them.
    #[arg(long)]
    pub through_translucent: bool,
    #[command(flatten)]
    pub techniques: TechniqueArgs,
    #[command(flatten)]
    pub section: SectionArgs,
    #[command(flatten)]
    pub validation: ValidationArgs,
}

/// `cadr info`.
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// The scene: a file or a generator.
    #[arg(value_name = "SCENE", default_value = "gen:demo")]
    pub scene: String,
}

/// `cadr convert`.
#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// The scene to read.
    #[arg(value_name = "SCENE")]
    pub scene: String,
    /// The file to write (.gltf, .glb, .csf or .csf.gz).
    #[arg(value_name = "OUT")]
    pub output: PathBuf,
}

/// `cadr techniques`.
#[derive(Debug, Args)]
pub struct TechniquesArgs {
    /// Print the list as JSON.
    #[arg(long)]
    pub json: bool,
}

/// The shade modes `bench` measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BenchShade {
    /// Shaded surfaces.
    #[value(alias = "shaded")]
    Solid,
    /// With feature edges.
    Edges,
    /// Feature edges only, hidden ones removed.
    HiddenLine,
    /// Every triangle's edges.
    Wireframe,
    /// Translucent parts with their edges.
    #[value(name = "xray")]
    XRay,
    /// Every mode, one row each.
    All,
}

impl BenchShade {
    /// The renderer's modes.
    fn modes(self) -> &'static [ShadeMode] {
        match self {
            Self::Solid => &[ShadeMode::Solid],
            Self::Edges => &[ShadeMode::Edges],
            Self::HiddenLine => &[ShadeMode::HiddenLine],
            Self::Wireframe => &[ShadeMode::Wireframe],
            Self::XRay => &[ShadeMode::XRay],
            Self::All => &ShadeMode::ALL,
        }
    }

    /// The renderer's modes `list` names, in the order given, each once.
    pub fn modes_of(list: &[Self]) -> Vec<ShadeMode> {
        let mut modes = Vec::new();
        for mode in list.iter().flat_map(|shade| shade.modes()) {
            if !modes.contains(mode) {
                modes.push(*mode);
            }
        }
        modes
    }
}

/// `cadr bench`.
///
/// Its many fields are the command's options, one each, as clap parses them.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// The scene: a file or a generator.
    #[arg(
        value_name = "SCENE",
        default_value = "gen:demo",
        conflicts_with = "sweep"
    )]
    pub scene: String,
    /// Measured frames per row (default 10, 5 with --sweep).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub frames: Option<u32>,
    /// Write the table and the scene statistics as JSON.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Draw the table as a chart (.svg or .png): bars of CPU µs per frame on a log scale, or
    /// with --sweep lines of cost against scene size. The labels' font is DejaVu Sans
    /// (fonts-dejavu-core) or the .ttf file CADR_PLOT_FONT names.
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Image size.
    #[arg(long, value_name = "WxH", default_value = "640x480", value_parser = parse_size)]
    pub size: Size,
    /// Display modes to measure, comma-separated: solid,xray measures each row in each (--shade
    /// is another name for it).
    #[arg(
        long = "display",
        alias = "shade",
        value_enum,
        value_name = "MODE,MODE",
        value_delimiter = ',',
        default_value = "solid"
    )]
    pub shade: Vec<BenchShade>,
    /// Vertex techniques to measure (comma-separated; others default to every one).
    #[arg(long, value_name = "A,B", value_delimiter = ',')]
    pub vertex: Option<Vec<String>>,
    /// Parameter techniques to measure.
    #[arg(long = "params", value_name = "A,B", value_delimiter = ',')]
    pub parameters: Option<Vec<String>>,
    /// Submission techniques to measure.
    #[arg(long = "submit", value_name = "A,B", value_delimiter = ',')]
    pub submission: Option<Vec<String>>,
    /// Culling techniques to measure (default none, every one with --all).
    #[arg(long = "cull", value_name = "A,B", value_delimiter = ',')]
    pub culling: Option<Vec<String>>,
    /// Transparency methods to measure (default weighted-blended, every one with --all).
    #[arg(long, value_name = "A,B", value_delimiter = ',')]
    pub transparency: Option<Vec<String>>,
    /// Measure every supported combination.
    #[arg(long)]
    pub all: bool,
    /// Measure a set over gen:grid of 10 000 to 1 000 000 parts, to show how each
    /// technique's CPU cost grows.
    #[arg(long)]
    pub sweep: bool,
    /// The sweep's part counts (implies --sweep).
    #[arg(long, value_name = "N,N,...", value_delimiter = ',',
          value_parser = clap::value_parser!(u64).range(1..=50_000_000))]
    pub sweep_parts: Option<Vec<u64>>,
    /// The camera: still, or circling the scene close enough that the frustum cuts.
    #[arg(long, value_enum, value_name = "PATH", default_value = "static")]
    pub camera: CameraPath,
    /// Move N assembly nodes every frame (an exploded view); the table adds the scene update
    /// µs and the bytes uploaded per frame.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub animate: usize,
    /// The gpu- cullers' sub-pixel threshold (CPU cullers ignore it).
    #[arg(long, value_name = "PX", value_parser = parse_min_pixels, allow_negative_numbers = true)]
    pub min_pixels: Option<f32>,
    /// Level-of-detail thresholds of the gpu-clusters rows, in pixels (comma-separated: 0,1
    /// measures each such row at full detail and at 1 px; default 1).
    #[arg(long, value_name = "PX,PX", value_delimiter = ',', default_value = "1",
          value_parser = parse_min_pixels, allow_negative_numbers = true)]
    pub lod_error: Vec<f32>,
    /// Measure gpu-occlusion and gpu-clusters over gen:fine of these tessellation details (at
    /// --sweep-units units), to show how the GPU cost follows the scene's triangles.
    #[arg(long, value_name = "D,D,...", value_delimiter = ',',
          value_parser = clap::value_parser!(u32).range(1..=32),
          conflicts_with_all = ["sweep", "sweep_parts"])]
    pub sweep_detail: Option<Vec<u32>>,
    /// Units of gen:fine in the --sweep-detail scenes.
    #[arg(long, value_name = "N", default_value_t = 16,
          value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub sweep_units: u32,
    /// Record every frame instead of replaying unchanged ones.
    #[arg(long)]
    pub no_replay: bool,
    /// Measure every row also with screen-space ambient occlusion (its cost).
    #[arg(long)]
    pub ssao: bool,
    /// MSAA levels to measure, samples per pixel (comma-separated: 1,4 measures each row
    /// without and with 4x; default 1).
    #[arg(long, value_name = "N,N", value_delimiter = ',', default_value = "1",
          value_parser = parse_msaa)]
    pub msaa: Vec<u32>,
    /// Silhouette edges in the edges, hidden-line and X-ray rows, on or off (comma-separated:
    /// on,off measures those rows with and without, their cost; default on).
    #[arg(long, value_name = "on,off", value_delimiter = ',', default_value = "on",
          value_parser = parse_on_off)]
    pub silhouettes: Vec<bool>,
    /// Hidden-line rows with their hidden lines dashed, hidden silhouettes included: `--dashed`
    /// alone measures them dashed, `--dashed on,off` both ways (their cost; default off).
    #[arg(long, value_name = "on,off", value_delimiter = ',', num_args = 0..=1,
          default_value = "off", default_missing_value = "on", value_parser = parse_on_off)]
    pub dashed: Vec<bool>,
    /// Highlight styles to measure (comma-separated: tint,outline measures each row with
    /// each; default tint).
    #[arg(long, value_name = "tint,outline", value_delimiter = ',', default_value = "tint",
          value_parser = parse_highlight_style)]
    pub highlight_style: Vec<HighlightStyle>,
    /// Highlight the nodes named NAME (and what is below them) in every row, as a host
    /// highlights a selection; repeatable. X-ray draws them opaque, the outline style bands
    /// them.
    #[arg(long, value_name = "NAME", conflicts_with_all = ["sweep", "sweep_parts"])]
    pub highlight: Vec<String>,
    /// Every row (the baseline too) cuts the scene with these planes.
    #[command(flatten)]
    pub section: SectionArgs,
    #[command(flatten)]
    pub validation: ValidationArgs,
}

impl BenchArgs {
    /// The names `--vertex`, `--params`, `--submit`, `--cull` and `--transparency` list, by
    /// kind.
    pub fn technique_lists(&self) -> [(TechniqueKind, &'static str, Option<&[String]>); 5] {
        [
            (TechniqueKind::Vertex, "--vertex", self.vertex.as_deref()),
            (
                TechniqueKind::Parameters,
                "--params",
                self.parameters.as_deref(),
            ),
            (
                TechniqueKind::Submission,
                "--submit",
                self.submission.as_deref(),
            ),
            (TechniqueKind::Culling, "--cull", self.culling.as_deref()),
            (
                TechniqueKind::Transparency,
                "--transparency",
                self.transparency.as_deref(),
            ),
        ]
    }

    /// Whether this run is a sweep.
    pub fn sweeping(&self) -> bool {
        self.sweep || self.sweep_parts.is_some()
    }

    /// Whether a sweep over scene triangles was asked for.
    pub fn sweeping_detail(&self) -> bool {
        self.sweep_detail.is_some()
    }
}

/// `cadr bench-tree`.
#[derive(Debug, Args)]
pub struct BenchTreeArgs {
    /// The scene: a file or a generator.
    #[arg(value_name = "SCENE", default_value = "gen:graphicscard")]
    pub scene: String,
    /// Runs per measurement (medians).
    #[arg(long, value_name = "N", default_value_t = 5,
          value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub runs: u32,
}

/// `cadr completions`.
#[derive(Debug, Args)]
pub struct CompletionsArgs {
    /// The shell.
    #[arg(value_enum)]
    pub shell: clap_complete::Shell,
}

/// An image size in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Size {
    pub width: u32,
    pub height: u32,
}

impl Size {
    /// Width over height.
    pub fn aspect(self) -> f64 {
        f64::from(self.width) / f64::from(self.height)
    }
}

/// Parses `WIDTHxHEIGHT`.
fn parse_size(text: &str) -> Result<Size, String> {
    let bad = || "expected WIDTHxHEIGHT, e.g. 1024x768".to_owned();
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(bad)?;
    let (width, height) = (
        w.trim().parse::<u32>().map_err(|_| bad())?,
        h.trim().parse::<u32>().map_err(|_| bad())?,
    );
    if width == 0 || height == 0 || width > 16384 || height > 16384 {
        return Err("each side must be 1 to 16384".into());
    }
    Ok(Size { width, height })
}

/// Parses `X2,Y2`.
fn parse_corner(text: &str) -> Result<(u32, u32), String> {
    let bad = || "expected X2,Y2 (the other corner, in pixels)".to_owned();
    let (x, y) = text.split_once(',').ok_or_else(bad)?;
    Ok((
        x.trim().parse().map_err(|_| bad())?,
        y.trim().parse().map_err(|_| bad())?,
    ))
}

/// Parses a plane `NX,NY,NZ,D`: four finite numbers, the normal not zero.
fn parse_plane(text: &str) -> Result<glam::DVec4, String> {
    let bad = || "expected NX,NY,NZ,D: four numbers, the normal not zero".to_owned();
    let values: Vec<f64> = text
        .split(',')
        .map(|v| v.trim().parse::<f64>().map_err(|_| bad()))
        .collect::<Result<_, _>>()?;
    let [x, y, z, d] = values[..] else {
        return Err(bad());
    };
    let plane = glam::DVec4::new(x, y, z, d);
    if !plane.is_finite() || plane.truncate().length() == 0.0 {
        return Err(bad());
    }
    Ok(plane)
}

/// The one colour of `--background flat`: the middle of the default gradient.
const FLAT_BACKGROUND: [f32; 3] = [0.80, 0.84, 0.88];

/// Parses `on` or `off` (`bench --silhouettes`).
fn parse_on_off(text: &str) -> Result<bool, String> {
    match text {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => Err(format!("'{text}' is not on or off")),
    }
}

/// Parses a highlight style: `tint` or `outline`.
fn parse_highlight_style(text: &str) -> Result<HighlightStyle, String> {
    HighlightStyle::parse(text).ok_or_else(|| format!("'{text}' is not tint or outline"))
}

/// Parses `--background`: `gradient`, `flat`, `#RRGGBB` or `#RRGGBB,#RRGGBB` (top, bottom).
fn parse_background(text: &str) -> Result<Background, String> {
    let bad = |part: &str| {
        format!("'{part}': expected gradient, flat, #RRGGBB or #RRGGBB,#RRGGBB (top, bottom)")
    };
    let color = |part: &str| parse_hex_color(part).map_err(|_| bad(part));
    match text.trim() {
        "gradient" => Ok(Background::GRADIENT),
        "flat" => Ok(Background::flat(FLAT_BACKGROUND)),
        colors => match colors.split_once(',') {
            Some((top, bottom)) => Ok(Background {
                top: color(top)?,
                bottom: color(bottom)?,
            }),
            None => Ok(Background::flat(color(colors)?)),
        },
    }
}

/// Parses a colour written #RRGGBB (display values, as a PNG stores them).
fn parse_hex_color(text: &str) -> Result<DisplayRgb, String> {
    let bad = || format!("'{}': expected a colour #RRGGBB", text.trim());
    let hex = text.trim().strip_prefix('#').ok_or_else(bad)?;
    if hex.len() != 6 || !hex.is_ascii() {
        return Err(bad());
    }
    let mut rgb = [0.0; 3];
    for (i, value) in rgb.iter_mut().enumerate() {
        let byte = u8::from_str_radix(&hex[2 * i..2 * i + 2], 16).map_err(|_| bad())?;
        *value = f32::from(byte) / 255.0;
    }
    Ok(rgb)
}

/// Parses an MSAA level: a sample count Vulkan can name (1, 2, 4, … 64); whether the device
/// offers it is checked once it is open.
fn parse_msaa(text: &str) -> Result<u32, String> {
    text.parse::<u32>()
        .ok()
        .filter(|samples| samples.is_power_of_two() && *samples <= 64)
        .ok_or_else(|| "expected samples per pixel: 1, 2, 4 or 8".to_owned())
}

/// Parses a sub-pixel threshold: a number of pixels, 0 or more.
fn parse_min_pixels(text: &str) -> Result<f32, String> {
    text.parse::<f32>()
        .ok()
        .filter(|pixels| pixels.is_finite() && *pixels >= 0.0)
        .ok_or_else(|| "expected a number of pixels >= 0".to_owned())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn the_command_line_declaration_is_consistent() {
        Cli::command().debug_assert();
    }

    #[test]
    fn sizes_and_thresholds_are_checked() {
        assert_eq!(
            parse_size("640X480"),
            Ok(Size {
                width: 640,
                height: 480
            })
        );
        assert!(parse_size("0x10").is_err());
        assert!(parse_size("big").is_err());
        assert_eq!(parse_corner("3, 4"), Ok((3, 4)));
        assert!(parse_min_pixels("-1").is_err());
        assert!(parse_min_pixels("NaN").is_err());
        assert_eq!(parse_min_pixels("2.5"), Ok(2.5));
    }

    #[test]
    fn msaa_levels_are_sample_counts() {
        assert_eq!(parse_msaa("1"), Ok(1));
        assert_eq!(parse_msaa("8"), Ok(8));
        for bad in ["0", "3", "128", "four", "-4"] {
            let error = parse_msaa(bad).expect_err(bad);
            assert!(error.contains("samples per pixel"), "{bad}: {error}");
        }
    }

    #[test]
    fn backgrounds_are_names_or_hex_colours() {
        assert_eq!(parse_background("gradient"), Ok(Background::GRADIENT));
        assert_eq!(
            parse_background("flat"),
            Ok(Background::flat(FLAT_BACKGROUND))
        );
        assert_eq!(
            parse_background("#ff0000,#000080"),
            Ok(Background {
                top: [1.0, 0.0, 0.0],
                bottom: [0.0, 0.0, 128.0 / 255.0]
            })
        );
        assert_eq!(parse_background("#FFFFFF"), Ok(Background::flat([1.0; 3])));
        for bad in [
            "", "red", "#12345", "#1234567", "#gg0000", "#ffffff,", "#ééé",
        ] {
            let error = parse_background(bad).expect_err(bad);
            assert!(error.contains("expected gradient"), "{bad}: {error}");
        }
    }
}
