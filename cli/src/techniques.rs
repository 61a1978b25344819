//! `cadr techniques` and what the commands that render with technique plugins share: finding
//! the plugins, choosing a combination from the command line, and a scene ready for them.

use std::path::PathBuf;
use std::sync::Arc;

use cadr_core::graph::{NodeFlags, NodeHandle, SceneGraph};
use cadr_core::render::{Background, Camera, FrameStats, Section};
use cadr_core::scene::Aabb;
use cadr_core::technique::{
    default_plugin_dirs, feature_bits, feature_names, Combination, PluginRegistry, ShadeMode,
    TechniqueKind, Techniques, PLUGIN_PATH_VARIABLE,
};
use cadr_core::tree::SceneTree;

use crate::motion::Motion;
use cadr_core::view::{Coverage, View};
use cadr_core::vk::{Device, DeviceOptions, InstanceOptions};

use crate::args::TechniquesArgs;

/// The command-line option of each technique kind.
pub const KIND_OPTIONS: [(TechniqueKind, &str); 5] = [
    (TechniqueKind::Vertex, "--vertex"),
    (TechniqueKind::Parameters, "--params"),
    (TechniqueKind::Submission, "--submit"),
    (TechniqueKind::Culling, "--cull"),
    (TechniqueKind::Transparency, "--transparency"),
];

/// The plugins for `device`, from the default directories.
pub fn load_registry(device: &Device) -> (Arc<PluginRegistry>, Vec<PathBuf>) {
    let dirs = default_plugin_dirs();
    let registry = PluginRegistry::discover(&dirs, feature_bits(device.capabilities()));
    (Arc::new(registry), dirs)
}

/// A message for when no plugin library was found.
pub fn no_plugins_message(dirs: &[PathBuf]) -> String {
    let searched: Vec<String> = dirs.iter().map(|d| d.display().to_string()).collect();
    format!(
        "no technique plugin library found, only the built-in techniques (searched {}; build them with `cargo build --workspace` or set {PLUGIN_PATH_VARIABLE})",
        searched.join(", ")
    )
}

/// Highlights the graph's nodes named one of `names` (a scene node keeps its name in the
/// graph); a name that no node has is an error.
pub fn highlight_named(graph: &mut SceneGraph, names: &[String]) -> Result<(), String> {
    for name in names {
        let named: Vec<NodeHandle> = graph
            .nodes()
            .filter(|(_, node)| &node.name == name)
            .map(|(handle, _)| handle)
            .collect();
        if named.is_empty() {
            return Err(format!(
                "--highlight {name}: no node of the scene is named so"
            ));
        }
        for handle in named {
            let flags = NodeFlags {
                highlighted: true,
                ..graph.node(handle).map_err(|e| e.to_string())?.flags
            };
            graph.set_flags(handle, flags).map_err(|e| e.to_string())?;
        }
    }
    Ok(())
}

/// A scene ready for technique plugins: its graph and tree, and the view that draws them.
pub struct TechniqueSession {
    pub graph: SceneGraph,
    pub tree: SceneTree,
    pub view: View,
}

impl TechniqueSession {
    /// Builds the tree of `graph` and a `width` × `height` view of it. The GPU scene is
    /// uploaded by the first frame, once the techniques are chosen: techniques that compute
    /// world matrices on the GPU lay it out otherwise than the built-in ones. For a large
    /// scene, dropping the loaded copy first lowers the peak.
    pub fn from_graph(
        device: &Arc<Device>,
        mut graph: SceneGraph,
        registry: Arc<PluginRegistry>,
        (width, height): (u32, u32),
    ) -> Result<Self, String> {
        crate::progress::spin("building the scene tree", || {
            let tree = SceneTree::build(&mut graph);
            let view = View::new(device, registry, width, height).map_err(|e| e.to_string())?;
            Ok(Self { graph, tree, view })
        })
    }

    /// The active techniques.
    pub fn techniques(&mut self) -> &mut Techniques {
        self.view.techniques_mut()
    }

    /// Switches to `combination` in `shade` mode. When it fails and no plugin library was
    /// found, the message says where they were looked for.
    pub fn choose(&mut self, combination: &Combination, shade: ShadeMode) -> Result<(), String> {
        let techniques = self.view.techniques_mut();
        let only_built_in = techniques
            .registry()
            .techniques()
            .iter()
            .all(|t| t.is_built_in());
        let explain = |error: String| {
            if only_built_in {
                format!("{error}; {}", no_plugins_message(&default_plugin_dirs()))
            } else {
                error
            }
        };
        techniques
            .select(combination)
            .map_err(|e| explain(e.to_string()))?;
        techniques.set_shade_mode(shade).map_err(|e| e.to_string())
    }

    /// Cuts the view with `section` (`--section`, `--caps`, `--no-caps`, `--hatch`).
    pub fn set_section(&mut self, section: Section) {
        self.view.set_section(section);
    }

    /// Sets the background the picture is drawn over (`--background`).
    pub fn set_background(&mut self, background: Background) -> Result<(), String> {
        self.view
            .renderer_mut()
            .set_background(background)
            .map_err(|e| format!("--background: {e}"))
    }

    /// Sets the samples per pixel of the colour pass (`--msaa`); a count the device does not
    /// offer is refused with those it does.
    pub fn set_msaa(&mut self, samples: u32) -> Result<(), String> {
        self.view
            .renderer_mut()
            .set_msaa(samples)
            .map_err(|e| format!("--msaa: {e}"))
    }

    /// Sets the sub-pixel threshold (`--min-pixels`) of the chosen culler; refused with a
    /// culler that would ignore it (CPU cullers keep every part in the frustum).
    pub fn set_min_pixels(&mut self, min_pixels: f32) -> Result<(), String> {
        let techniques = self.view.techniques_mut();
        if min_pixels > 0.0 && !techniques.culls_on_gpu() {
            return Err(format!(
                "--min-pixels culls on the GPU: choose --cull gpu-frustum or gpu-occlusion (the culler is '{}')",
                techniques.combination().culling
            ));
        }
        techniques
            .set_min_pixels(min_pixels)
            .map_err(|e| e.to_string())
    }

    /// Bytes the GPU scene keeps resident (0 before it is built).
    pub fn resident_bytes(&self) -> u64 {
        self.view.scene().map_or(0, |scene| scene.resident_bytes())
    }

    /// What the scene's geometry streaming holds and has done, where the scene streams under
    /// the memory budget.
    pub fn streaming(&self) -> Option<cadr_core::gpu_scene::StreamingReport> {
        self.view.scene()?.streaming()
    }

    /// Device bytes of the coarse forms of a streaming scene (0 where it does not stream).
    pub fn coarse_form_bytes(&self) -> u64 {
        self.view
            .scene()
            .map_or(0, |scene| scene.coarse_form_bytes())
    }

    /// Bytes streamed to the GPU since the scene was made (0 where it does not stream).
    pub fn streamed_bytes(&self) -> u64 {
        self.streaming().map_or(0, |report| report.streamed_bytes)
    }

    /// Sets the level-of-detail threshold (`--lod-error`) of a cluster culler; refused with a
    /// culler that draws every part whole (it would be ignored).
    pub fn set_lod_error(&mut self, lod_error: Option<f32>) -> Result<(), String> {
        let Some(lod_error) = lod_error else {
            return Ok(());
        };
        let techniques = self.view.techniques_mut();
        let culling = techniques.combination().culling.clone();
        if culling != "gpu-clusters" {
            return Err(format!(
                "--lod-error chooses the level of detail of the clusters: choose --cull gpu-clusters (the culler is '{culling}')"
            ));
        }
        techniques
            .set_lod_error(lod_error)
            .map_err(|e| e.to_string())
    }

    /// Draws frame `frame` of `motion`: moves its nodes, brings the tree and the GPU scene up
    /// to date (timed: the scene update, in microseconds) and draws with its camera.
    pub fn render_moving(
        &mut self,
        motion: &Motion,
        view: (&Aabb, f64),
        frame: usize,
    ) -> Result<FrameSample, String> {
        let start = std::time::Instant::now();
        let camera = self.move_to(motion, view, frame)?;
        let update_us = start.elapsed().as_secs_f64() * 1e6;
        let stats = self.view.draw(&camera).map_err(|e| e.to_string())?;
        Ok(FrameSample {
            stats,
            update_us,
            gpu_passes: self.gpu_pass_times(),
        })
    }

    /// What the picture of frame `frame` of `motion` covers (`View::coverage`): its parts moved
    /// and its camera placed as that frame's, the pixels showing a part and the parts showing.
    pub fn coverage_at(
        &mut self,
        motion: &Motion,
        view: (&Aabb, f64),
        frame: usize,
    ) -> Result<Coverage, String> {
        let camera = self.move_to(motion, view, frame)?;
        self.view.coverage(&camera).map_err(|e| e.to_string())
    }

    /// Moves the nodes of `motion` as in frame `frame`, brings the tree and the GPU scene up to
    /// date, and returns the frame's camera around `bounds` at `aspect`.
    fn move_to(
        &mut self,
        motion: &Motion,
        (bounds, aspect): (&Aabb, f64),
        frame: usize,
    ) -> Result<Camera, String> {
        motion.animate(&mut self.graph, frame)?;
        self.tree.update(&mut self.graph);
        self.view
            .sync(&self.graph, &mut self.tree)
            .map_err(|e| e.to_string())?;
        Ok(motion.camera(bounds, aspect, frame))
    }

    /// The GPU time of each pass of the last frame (`Renderer::gpu_pass_times`).
    pub fn gpu_pass_times(&self) -> crate::PassTimes {
        self.view.renderer().gpu_pass_times().to_vec()
    }

    /// Draws one frame (the first uploads the GPU scene, with a spinner if it takes long).
    pub fn render(&mut self, camera: &Camera) -> Result<FrameStats, String> {
        if self.view.scene().is_none() {
            crate::progress::spin("uploading the scene", || {
                self.view.sync(&self.graph, &mut self.tree)
            })
            .map_err(|e| e.to_string())?;
        }
        self.view
            .render(&self.graph, &mut self.tree, camera)
            .map_err(|e| e.to_string())
    }
}

/// One frame a benchmark measured: what it drew, the time its scene took to update, and the GPU
/// time of each of its passes.
pub struct FrameSample {
    /// The frame's counters and times.
    pub stats: FrameStats,
    /// Moving nodes and bringing the tree and GPU scene up to date, in microseconds.
    pub update_us: f64,
    /// The GPU time of each pass (`Renderer::gpu_pass_times`).
    pub gpu_passes: crate::PassTimes,
}

/// `cadr techniques [--json]`.
pub fn techniques(args: &TechniquesArgs) -> Result<(), String> {
    let options = DeviceOptions {
        instance: InstanceOptions::default(),
        ..DeviceOptions::default()
    };
    let device = Device::new(&options).map_err(|e| e.to_string())?;
    let (registry, dirs) = load_registry(&device);
    let device_name = device.adapter().name.clone();
    if args.json {
        let techniques: Vec<serde_json::Value> = registry
            .techniques()
            .iter()
            .map(|t| {
                serde_json::json!({
                    "kind": t.kind.name(),
                    "name": t.name,
                    "description": t.description,
                    "library": t.library.display().to_string(),
                    "built_in": t.is_built_in(),
                    "abi": format!("{}.{}", t.abi_version.0, t.abi_version.1),
                    "required_features": feature_names(t.required_features),
                    "supported": t.support.is_ok(),
                    "reason": t.support.as_ref().err(),
                })
            })
            .collect();
        let refused: Vec<String> = registry
            .refusals()
            .iter()
            .map(ToString::to_string)
            .collect();
        let report = serde_json::json!({
            "device": device_name,
            "techniques": techniques,
            "refused": refused,
        });
        println!(
            "{}",
            serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?
        );
        return Ok(());
    }
    if registry.techniques().iter().all(|t| t.is_built_in()) {
        println!("{}", no_plugins_message(&dirs));
    }
    println!("device: {device_name}");
    for (kind, option) in KIND_OPTIONS {
        println!(
            "\n{} techniques ({option} NAME; default {}):",
            kind.name(),
            Combination::built_in().get(kind)
        );
        for t in registry.of_kind(kind) {
            let support = match &t.support {
                Ok(()) => String::new(),
                Err(why) => format!(" [unsupported: {why}]"),
            };
            let origin = if t.is_built_in() { " (built in)" } else { "" };
            println!("  {:<26} {}{origin}{support}", t.name, t.description);
        }
    }
    let modes: Vec<&str> = ShadeMode::ALL.iter().map(|m| m.name()).collect();
    println!(
        "\ndisplay modes (--display): {} (default {})",
        modes.join(", "),
        ShadeMode::Solid.name()
    );
    for refusal in registry.refusals() {
        println!("refused: {refusal}");
    }
    Ok(())
}
