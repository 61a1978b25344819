//! The combination of techniques a renderer uses, one of each kind, swappable between frames.
//! Swapping creates the new instance first (so a refusal leaves the old combination working),
//! waits for the GPU, then destroys the old one.

use std::ffi::{c_char, c_void, CStr};
use std::sync::Arc;

use crate::error::{RenderError, RenderResult};
use crate::vk::raw::{self as vk, Handle};
use cadr_plugin_abi as abi;

use super::host_api::{AllocationCounts, HostServices};
use super::pass_pipelines::{PipelineInputs, TechniquePipelines};
use super::registry::{feature_bits, PluginRegistry, TechniqueEntry, TechniqueKind};
use super::shader_assembly::{
    assemble_mesh_shader, assemble_vertex_shader, ShaderCache, TechniqueShaderSources,
};
use super::shared_pipelines::{shared_or_built, KeptPipelines, KeyInputs, PipelineKey};
use super::surface_passes::{PassSet, ShadeMode};
use crate::gpu_scene::Transforms;
use crate::render::TransparencyMethod;
use crate::vk::{Device, COLOR_FORMAT, DEPTH_FORMAT};

/// Technique names, one per kind.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Combination {
    /// Vertex path.
    pub vertex: String,
    /// Parameter path.
    pub parameters: String,
    /// Submission.
    pub submission: String,
    /// Culling.
    pub culling: String,
    /// Transparency method.
    pub transparency: String,
}

/// The transparency method of [`Combination::built_in`], built into cadr.
pub const DEFAULT_TRANSPARENCY: &str = "weighted-blended";

impl Combination {
    /// The built-in combination, the default: the simplest technique of each kind, linked
    /// into cadr (no plugin library needed), the seeds' baseline every other combination is
    /// measured against.
    pub fn built_in() -> Self {
        Self {
            vertex: "per-geometry".into(),
            parameters: "push".into(),
            submission: "individual".into(),
            culling: "none".into(),
            transparency: DEFAULT_TRANSPARENCY.into(),
        }
    }

    /// The name of `kind`.
    pub fn get(&self, kind: TechniqueKind) -> &str {
        match kind {
            TechniqueKind::Vertex => &self.vertex,
            TechniqueKind::Parameters => &self.parameters,
            TechniqueKind::Submission => &self.submission,
            TechniqueKind::Culling => &self.culling,
            TechniqueKind::Transparency => &self.transparency,
        }
    }

    /// Sets the name of `kind`.
    pub fn set(&mut self, kind: TechniqueKind, name: &str) {
        let slot = match kind {
            TechniqueKind::Vertex => &mut self.vertex,
            TechniqueKind::Parameters => &mut self.parameters,
            TechniqueKind::Submission => &mut self.submission,
            TechniqueKind::Culling => &mut self.culling,
            TechniqueKind::Transparency => &mut self.transparency,
        };
        name.clone_into(slot);
    }
}

impl std::fmt::Display for Combination {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} / {} / {} / {}",
            self.vertex, self.parameters, self.submission, self.culling
        )?;
        // The default method is left unsaid, so that names stay short where it does not matter.
        if self.transparency != DEFAULT_TRANSPARENCY {
            write!(f, " / {}", self.transparency)?;
        }
        Ok(())
    }
}

/// Names of `CADR_TRAIT_*` bits, for messages.
fn trait_name(bit: u64) -> &'static str {
    match bit {
        abi::CADR_TRAIT_GEOMETRY_SHARES_BINDING => {
            "a vertex path whose parts of a geometry share one binding"
        }
        abi::CADR_TRAIT_SCENE_SHARES_BINDING => {
            "a vertex path that binds the whole scene once (offsets in the draw)"
        }
        abi::CADR_TRAIT_PARAMETERS_FROM_INSTANCE_INDEX => {
            "a parameter path that finds parameters from the instance index (no per-draw commands)"
        }
        abi::CADR_TRAIT_PARAMETERS_IN_COMMANDS => {
            "a parameter path that writes values into commands"
        }
        abi::CADR_TRAIT_SECONDARY_COMMAND_BUFFERS => "secondary command buffers",
        abi::CADR_TRAIT_DRAWS_GPU_COMMANDS => {
            "a submission that draws the GPU-written commands (individual-indirect-count, dgc, individual-mdi)"
        }
        abi::CADR_TRAIT_READS_HOST_MATRICES => "a technique that reads world matrices on the host",
        _ => "an unknown trait",
    }
}

/// The default level-of-detail threshold, in pixels: a simplification that moves the surface
/// by less than a pixel on screen is not seen.
pub const DEFAULT_LOD_ERROR: f32 = 1.0;

/// How the active techniques draw: what a host chooses besides the techniques themselves.
struct DrawOptions {
    /// The display mode.
    shade: ShadeMode,
    /// Whether picking goes through translucent parts.
    pick_through_translucent: bool,
    /// Whether the hidden-line mode shows hidden edges dashed.
    dashed_hidden_lines: bool,
    /// Sub-pixel culling threshold of GPU cullers, in pixels (0: off).
    min_pixels: f32,
    /// Level-of-detail threshold of cluster cullers, in pixels (0: full detail).
    lod_error: f32,
    /// Whether unchanged frames may be resubmitted rather than recorded.
    frame_replay: bool,
}

/// The combination's technique of `kind`, if it has one.
fn of_kind<'e>(entries: &[&'e TechniqueEntry], kind: TechniqueKind) -> Option<&'e TechniqueEntry> {
    entries.iter().copied().find(|e| e.kind == kind)
}

/// The combination's submission, where it announces `trait_bit` (meaningful since ABI minor
/// `since`).
fn submission_announcing<'e>(
    entries: &[&'e TechniqueEntry],
    trait_bit: abi::CadrTraitBits,
    since: u32,
) -> Option<&'e TechniqueEntry> {
    of_kind(entries, TechniqueKind::Submission).filter(|e| e.announces(trait_bit, since))
}

/// What the combination's parameter blocks offer (plugin ABI 1.22,
/// `CADR_TRAIT_PARAMETER_BLOCKS`): where the parameter path, the submission and the culler all
/// announce them, the culler finds each draw's parameters from its instance id on the GPU, which
/// is what finding them from the instance index asks; a parameter path and submission that
/// announce them with a culler that does not are refused, as nothing would write the blocks.
fn parameter_blocks_offer(entries: &[&TechniqueEntry]) -> Result<u64, String> {
    let of_kind = |kind| of_kind(entries, kind);
    let announces =
        |kind| of_kind(kind).is_some_and(|e| e.announces(abi::CADR_TRAIT_PARAMETER_BLOCKS, 22));
    if !(announces(TechniqueKind::Parameters) && announces(TechniqueKind::Submission)) {
        return Ok(0);
    }
    if announces(TechniqueKind::Culling) {
        return Ok(abi::CADR_TRAIT_PARAMETERS_FROM_INSTANCE_INDEX);
    }
    let name = |kind| of_kind(kind).map_or("", |e| e.name.as_str());
    Err(format!(
        "submission '{}' with parameters '{}' needs a GPU culler that writes each draw's parameter block, which culling '{}' is not",
        name(TechniqueKind::Submission),
        name(TechniqueKind::Parameters),
        name(TechniqueKind::Culling)
    ))
}

/// Whether a mesh-shading submission (plugin ABI 1.23, `CADR_TRAIT_MESH_SHADING`) has what it
/// draws with: paths whose snippets run in a mesh shader, and a GPU culler (one that needs a
/// submission drawing GPU-written commands) to write the commands its mesh workgroups read.
fn mesh_shading_check(entries: &[&TechniqueEntry]) -> Result<(), String> {
    let of_kind = |kind| of_kind(entries, kind);
    let Some(submission) = submission_announcing(entries, abi::CADR_TRAIT_MESH_SHADING, 23) else {
        return Ok(());
    };
    for (kind, what) in [
        (TechniqueKind::Vertex, "vertex path"),
        (TechniqueKind::Parameters, "parameter path"),
    ] {
        if let Some(path) = of_kind(kind) {
            if !path.announces(abi::CADR_TRAIT_MESH_SHADING, 23) {
                return Err(format!(
                    "submission '{}' needs a {what} whose shader also runs in a mesh shader (pulling, ssbo-index), which {} '{}' is not",
                    submission.name,
                    kind.name(),
                    path.name
                ));
            }
        }
    }
    match of_kind(TechniqueKind::Culling) {
        Some(culler) if culler.needs & abi::CADR_TRAIT_DRAWS_GPU_COMMANDS == 0 => Err(format!(
            "submission '{}' needs a GPU culler to write the commands it draws, which culling '{}' is not",
            submission.name, culler.name
        )),
        _ => Ok(()),
    }
}

/// Whether a submission that draws GPU-written commands by their capacity (plugin ABI 1.24,
/// `CADR_TRAIT_EMPTY_COMMAND_TAILS`) has a culler that leaves what lies past its counts empty:
/// a GPU culler (one that needs a submission drawing GPU-written commands) must announce it.
fn empty_command_tails_check(entries: &[&TechniqueEntry]) -> Result<(), String> {
    let Some(submission) = submission_announcing(entries, abi::CADR_TRAIT_EMPTY_COMMAND_TAILS, 24)
    else {
        return Ok(());
    };
    match of_kind(entries, TechniqueKind::Culling) {
        Some(culler)
            if culler.needs & abi::CADR_TRAIT_DRAWS_GPU_COMMANDS != 0
                && !culler.announces(abi::CADR_TRAIT_EMPTY_COMMAND_TAILS, 24) =>
        {
            Err(format!(
                "submission '{}' draws the GPU-written commands without their count, so it needs a GPU culler that leaves the commands past its counts empty, which culling '{}' does not announce",
                submission.name, culler.name
            ))
        }
        _ => Ok(()),
    }
}

/// Why a combination cannot work, or `Ok` when it can.
pub fn check_combination(entries: &[&TechniqueEntry]) -> Result<(), String> {
    for entry in entries {
        entry.support.as_ref().map_err(|why| {
            format!(
                "{} '{}' is not supported: {why}",
                entry.kind.name(),
                entry.name
            )
        })?;
    }
    // Before the traits each needs: it names the paths and cullers that would do.
    mesh_shading_check(entries)?;
    empty_command_tails_check(entries)?;
    let blocks_offer = parameter_blocks_offer(entries);
    for entry in entries {
        let others: u64 = entries
            .iter()
            .filter(|o| o.kind != entry.kind)
            .fold(0, |bits, o| bits | o.provides);
        let mut missing = entry.needs & !others;
        if missing != 0 {
            missing &= !blocks_offer.clone()?;
        }
        if missing != 0 {
            let bit = 1u64 << missing.trailing_zeros();
            return Err(format!(
                "{} '{}' needs {}, which the others do not offer",
                entry.kind.name(),
                entry.name,
                trait_name(bit)
            ));
        }
    }
    blocks_offer.map(|_| ())
}

/// A created technique instance; destroyed on drop (after the GPU is done, see `Techniques`).
pub(crate) struct Active {
    pub(crate) entry: Arc<TechniqueEntry>,
    pub(crate) instance: *mut c_void,
}

impl Drop for Active {
    fn drop(&mut self) {
        if let Some(destroy) = self.entry.common().destroy {
            // SAFETY: the instance came from this vtable's create and is destroyed once.
            unsafe { destroy(self.instance) };
        }
    }
}

impl Active {
    pub(crate) fn vtable<V>(&self) -> &V {
        // SAFETY: the registry copied the vtable into this host's layout for its kind; callers
        // ask for the vtable type of the entry's kind.
        unsafe { &*self.entry.vtable().cast::<V>() }
    }
}

/// A message buffer for plugin calls.
pub(crate) struct Message {
    bytes: Vec<u8>,
    raw: abi::CadrMessage,
}

impl Message {
    pub(crate) fn new() -> Self {
        let mut bytes = vec![0u8; 1024];
        let raw = abi::CadrMessage {
            text: bytes.as_mut_ptr().cast::<c_char>(),
            capacity: bytes.len(),
        };
        Self { bytes, raw }
    }

    pub(crate) fn raw(&mut self) -> *mut abi::CadrMessage {
        &mut self.raw
    }

    pub(crate) fn text(&self) -> String {
        CStr::from_bytes_until_nul(&self.bytes)
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    }
}

/// Checks a plugin call's status.
pub(crate) fn status(
    entry: &TechniqueEntry,
    what: &str,
    status: abi::CadrStatus,
    message: &Message,
) -> RenderResult<()> {
    match status {
        abi::CADR_STATUS_OK => Ok(()),
        abi::CADR_STATUS_PANICKED => Err(RenderError::Technique {
            technique: format!("{} '{}'", entry.kind.name(), entry.name),
            message: format!("{what} panicked ({})", message.text()),
        }),
        _ => Err(RenderError::Technique {
            technique: format!("{} '{}'", entry.kind.name(), entry.name),
            message: format!("{what} failed: {}", message.text()),
        }),
    }
}

/// The active techniques, the plugin registry they come from, and their pipelines.
pub struct Techniques {
    device: Arc<Device>,
    registry: Arc<PluginRegistry>,
    services: Box<HostServices>,
    vulkan: Box<abi::CadrVulkan>,
    pub(crate) active: [Option<Active>; 5],
    /// The active transparency method's description.
    method: Option<TransparencyMethod>,
    options: DrawOptions,
    /// The pipelines of the pass sets drawn since the vertex path, parameter path or
    /// transparency method changed (each display mode's shaded frame with and without
    /// translucent surfaces, at each MSAA level, the pick pass), built on first use, at most
    /// [`KEPT_PASS_SETS`]: a display mode or option turned on again finds them built. The
    /// last drawn is last, so the first is the one unused longest. Shared with the other
    /// renderers of the device where the paths allow it (`shared_pipelines.rs`).
    pipelines: Vec<Arc<KeptPipelines>>,
    shaders: ShaderCache,
    frame_set_layout: vk::DescriptorSetLayout,
    /// The transparency merge's set layout (its targets).
    merge_set_layout: vk::DescriptorSetLayout,
    /// Bumped whenever techniques, pipelines or the target change (part of the commands key).
    pub(crate) epoch: u64,
    /// What culling last ran for (see `frame::cull`).
    pub(crate) cull_key: Option<u64>,
    worker_threads: u32,
}

fn index(kind: TechniqueKind) -> usize {
    kind as usize
}

/// How many pass sets' pipelines are kept at most; past it the one unused longest goes.
const KEPT_PASS_SETS: usize = 8;

/// The kinds whose techniques the pipelines are built from: the vertex shader is assembled
/// from the paths' snippets (its layouts are theirs), the translucent passes and the merge
/// from the transparency method's. Swapping a submission or a culler keeps them.
const PIPELINE_KINDS: [TechniqueKind; 3] = [
    TechniqueKind::Vertex,
    TechniqueKind::Parameters,
    TechniqueKind::Transparency,
];

impl Techniques {
    /// Creates an empty set over `registry` for renderers on `device` whose frame set layout
    /// and transparency merge set layout are `layouts`.
    pub fn new(
        device: &Arc<Device>,
        registry: Arc<PluginRegistry>,
        (frame_set_layout, merge_set_layout): (vk::DescriptorSetLayout, vk::DescriptorSetLayout),
    ) -> Self {
        let services = HostServices::new(device);
        let handles = device.raw_handles();
        let limits = device.limits();
        let vulkan = Box::new(abi::CadrVulkan {
            size: std::mem::size_of::<abi::CadrVulkan>() as u32,
            api_version: vk::API_VERSION_1_3,
            instance: handles.instance.as_raw() as *mut c_void,
            physical_device: handles.physical_device.as_raw() as *mut c_void,
            device: handles.device.as_raw() as *mut c_void,
            queue_family: device.adapter().queue_family,
            color_format: COLOR_FORMAT.as_raw(),
            depth_format: DEPTH_FORMAT.as_raw(),
            // SAFETY: the loader's function has the ABI's signature (handles as pointers).
            get_instance_proc_addr: unsafe {
                std::mem::transmute::<vk::PFN_vkGetInstanceProcAddr, abi::CadrGetInstanceProcAddr>(
                    handles.get_instance_proc_addr,
                )
            },
            features: feature_bits(device.capabilities()),
            min_uniform_buffer_offset_alignment: limits.min_uniform_buffer_offset_alignment,
            max_push_constants_size: limits.max_push_constants_size,
            allocation_callbacks: services.callbacks().cast(),
            pipeline_cache: device.pipeline_cache().as_raw(),
        });
        let worker_threads = std::thread::available_parallelism()
            .map(|n| n.get() as u32)
            .unwrap_or(1)
            .clamp(1, 8);
        Self {
            device: Arc::clone(device),
            registry,
            services,
            vulkan,
            active: [None, None, None, None, None],
            method: None,
            options: DrawOptions {
                shade: ShadeMode::Solid,
                pick_through_translucent: false,
                dashed_hidden_lines: false,
                min_pixels: 0.0,
                lod_error: DEFAULT_LOD_ERROR,
                frame_replay: true,
            },
            pipelines: Vec::new(),
            shaders: ShaderCache::new(device.capabilities()),
            frame_set_layout,
            merge_set_layout,
            epoch: 1,
            cull_key: None,
            worker_threads,
        }
    }

    /// The registry.
    pub fn registry(&self) -> &Arc<PluginRegistry> {
        &self.registry
    }

    /// The current combination (empty names for kinds not chosen yet).
    pub fn combination(&self) -> Combination {
        let name = |kind: TechniqueKind| {
            self.active[index(kind)]
                .as_ref()
                .map(|a| a.entry.name.clone())
                .unwrap_or_default()
        };
        Combination {
            vertex: name(TechniqueKind::Vertex),
            parameters: name(TechniqueKind::Parameters),
            submission: name(TechniqueKind::Submission),
            culling: name(TechniqueKind::Culling),
            transparency: name(TechniqueKind::Transparency),
        }
    }

    /// The shade mode.
    pub fn shade_mode(&self) -> ShadeMode {
        self.options.shade
    }

    /// Sets the shade mode (its pipelines are built before the next frame unless a frame
    /// drew in it before and they are kept).
    pub fn set_shade_mode(&mut self, mode: ShadeMode) -> RenderResult<()> {
        if mode != self.options.shade {
            self.options.shade = mode;
            self.epoch += 1;
        }
        Ok(())
    }

    /// Whether the hidden-line display mode also draws the hidden edges, dashed and in a
    /// lighter shade of the edge colour (off by default: hidden edges are removed).
    pub fn dashed_hidden_lines(&self) -> bool {
        self.options.dashed_hidden_lines
    }

    /// Shows hidden edges dashed in the hidden-line mode, or removes them (the default); from
    /// the next frame (other modes are not affected). With silhouettes on, the silhouettes of
    /// hidden curved surfaces are dashed too where the device has geometry shaders; where it
    /// has none, turning dashes on logs a warning that says they are left out.
    pub fn set_dashed_hidden_lines(&mut self, dashed: bool) {
        if dashed
            && !self.options.dashed_hidden_lines
            && !self.device.capabilities().geometry_shader
        {
            log::warn!(
                "dashed hidden lines on {}: the silhouettes of hidden curved surfaces are not \
                 drawn, the device has no geometry shaders (geometryShader)",
                self.device.adapter().name
            );
        }
        self.options.dashed_hidden_lines = dashed;
    }

    /// Whether picking goes through translucent parts (materials of opacity under 1) to what
    /// is behind them; off by default: what is seen is what is picked.
    pub fn pick_through_translucent(&self) -> bool {
        self.options.pick_through_translucent
    }

    /// Lets picking go through translucent parts, or not (the default); from the next pick.
    pub fn set_pick_through_translucent(&mut self, through: bool) {
        self.options.pick_through_translucent = through;
    }

    /// The sub-pixel culling threshold: GPU cullers drop parts whose bounding sphere projects
    /// smaller than this many pixels across (0, the default, keeps every part).
    pub fn min_pixels(&self) -> f32 {
        self.options.min_pixels
    }

    /// Whether the active culler culls on the GPU (and so applies the sub-pixel threshold).
    pub fn culls_on_gpu(&self) -> bool {
        self.get(TechniqueKind::Culling).is_ok_and(|active| {
            active
                .vtable::<abi::CadrCullingVtable>()
                .record_gpu
                .is_some()
        })
    }

    /// Sets the sub-pixel culling threshold in pixels (0 turns it off). It applies to GPU
    /// cullers (the `gpu-` culling techniques), from the next frame; CPU cullers keep every
    /// part they find in the frustum.
    pub fn set_min_pixels(&mut self, pixels: f32) -> RenderResult<()> {
        if !pixels.is_finite() || pixels < 0.0 {
            return Err(RenderError::InvalidUse(format!(
                "sub-pixel threshold {pixels}: expected a finite number of pixels >= 0"
            )));
        }
        self.options.min_pixels = pixels;
        Ok(())
    }

    /// The level-of-detail threshold of cluster cullers (`gpu-clusters`), in pixels: each part
    /// is drawn with the coarsest clusters whose simplification error projects at or under
    /// it. 0 draws full detail; the default is [`DEFAULT_LOD_ERROR`].
    pub fn lod_error(&self) -> f32 {
        self.options.lod_error
    }

    /// Sets the level-of-detail threshold from the next frame (see [`Techniques::lod_error`]).
    pub fn set_lod_error(&mut self, pixels: f32) -> RenderResult<()> {
        if !pixels.is_finite() || pixels < 0.0 {
            return Err(RenderError::InvalidUse(format!(
                "level-of-detail error {pixels}: expected a finite number of pixels >= 0"
            )));
        }
        if pixels != self.options.lod_error {
            self.options.lod_error = pixels;
            // Cullers record the threshold into their commands.
            self.epoch += 1;
        }
        Ok(())
    }

    /// Whether frames that would record what the last one recorded resubmit it instead (on by
    /// default; see [`Techniques::replayable`]).
    pub fn frame_replay(&self) -> bool {
        self.options.frame_replay
    }

    /// Turns frame replay on or off. Off, every frame is recorded: the seeds' baseline, and
    /// what `cadr bench` measures its reference row with.
    pub fn set_frame_replay(&mut self, enabled: bool) {
        self.options.frame_replay = enabled;
    }

    /// Whether frames may be replayed: frame replay is on and every active technique lets the
    /// host resubmit a frame whose recording would not change (`CADR_TRAIT_REPLAYABLE`,
    /// libraries of ABI 1.5 or later).
    pub fn replayable(&self) -> bool {
        self.options.frame_replay
            && self.active.iter().all(|active| {
                active
                    .as_ref()
                    .is_some_and(|active| active.entry.announces(abi::CADR_TRAIT_REPLAYABLE, 5))
            })
    }

    /// Whether frames in which only parameter values changed (moved parts, new material
    /// values) may be replayed too: frames may be replayed and every active technique reads
    /// no parameter values on the host while recording
    /// (`CADR_TRAIT_REPLAYS_PARAMETER_CHANGES`, libraries of ABI 1.10 or later).
    pub fn replays_parameter_changes(&self) -> bool {
        self.replayable()
            && self.active.iter().all(|active| {
                active.as_ref().is_some_and(|active| {
                    self.announces(active, abi::CADR_TRAIT_REPLAYS_PARAMETER_CHANGES, 10)
                })
            })
    }

    /// Whether every active technique keeps its per-frame data per frame slot
    /// (`CADR_TRAIT_FRAME_SLOTS`, libraries of ABI 1.15 or later), so that a frame may be
    /// recorded while earlier ones still run on the GPU.
    pub fn keep_frame_slots(&self) -> bool {
        self.active.iter().all(|active| {
            active
                .as_ref()
                .is_some_and(|active| active.entry.announces(abi::CADR_TRAIT_FRAME_SLOTS, 15))
        })
    }

    /// Whether the active culler routes parts into passes by whether their back faces are
    /// culled (`CADR_TRAIT_ROUTES_BACK_FACES`, libraries of ABI 1.18 or later), so that the
    /// opaque surfaces of closed parts may be drawn with their back faces culled.
    pub fn culler_routes_back_faces(&self) -> bool {
        self.get(TechniqueKind::Culling).is_ok_and(|active| {
            active
                .entry
                .announces(abi::CADR_TRAIT_ROUTES_BACK_FACES, 18)
        })
    }

    /// Whether the active submission draws shared streams whose commands name their pass's
    /// pipeline (`CADR_TRAIT_SWITCHES_PIPELINES`, libraries of ABI 1.19 or later), so that the
    /// two surface passes of closed and other parts may share one stream.
    pub fn submission_switches_pipelines(&self) -> bool {
        self.get(TechniqueKind::Submission).is_ok_and(|active| {
            active
                .entry
                .announces(abi::CADR_TRAIT_SWITCHES_PIPELINES, 19)
        })
    }

    /// Whether the active parameter path, submission and culler pass each draw's parameters in
    /// blocks the culler writes on the GPU (`CADR_TRAIT_PARAMETER_BLOCKS`, libraries of ABI
    /// 1.22 or later): the host then asks the culler and the submission for them.
    pub fn parameter_blocks(&self) -> bool {
        [
            TechniqueKind::Parameters,
            TechniqueKind::Submission,
            TechniqueKind::Culling,
        ]
        .into_iter()
        .all(|kind| {
            self.get(kind)
                .is_ok_and(|active| active.entry.announces(abi::CADR_TRAIT_PARAMETER_BLOCKS, 22))
        })
    }

    /// Whether the active submission draws with mesh workgroups (`CADR_TRAIT_MESH_SHADING`,
    /// libraries of ABI 1.23 or later): the host then builds the triangle passes as mesh
    /// pipelines (the combination check made sure the paths and the culler allow it).
    pub fn mesh_shading(&self) -> bool {
        self.get(TechniqueKind::Submission)
            .is_ok_and(|active| active.entry.announces(abi::CADR_TRAIT_MESH_SHADING, 23))
    }

    /// Whether the active submission draws GPU-written commands by their capacity, without
    /// their count (`CADR_TRAIT_EMPTY_COMMAND_TAILS`, libraries of ABI 1.24 or later): the host
    /// then asks the GPU culler to leave what lies past its counts empty (the combination check
    /// made sure it announces that it does).
    pub fn empty_command_tails(&self) -> bool {
        self.get(TechniqueKind::Submission).is_ok_and(|active| {
            active
                .entry
                .announces(abi::CADR_TRAIT_EMPTY_COMMAND_TAILS, 24)
        })
    }

    /// Whether `active` announces `trait_bit` (from a library of ABI `since` or later) as this
    /// combination uses it: a parameter path whose blocks the GPU culler writes (see
    /// [`Self::parameter_blocks`]) pushes nothing, so it puts no values in commands, reads none
    /// on the host and replays parameter changes, whatever it announces for drawing alone.
    pub(crate) fn announces(&self, active: &Active, trait_bit: u64, since: u32) -> bool {
        if active.entry.kind == TechniqueKind::Parameters && self.parameter_blocks() {
            match trait_bit {
                abi::CADR_TRAIT_REPLAYS_PARAMETER_CHANGES => return true,
                abi::CADR_TRAIT_PARAMETERS_IN_COMMANDS | abi::CADR_TRAIT_READS_HOST_MATRICES => {
                    return false
                }
                _ => {}
            }
        }
        active.entry.announces(trait_bit, since)
    }

    /// What plugins hold now (objects through the allocation callbacks, buffers).
    pub fn plugin_allocations(&self) -> AllocationCounts {
        self.services.snapshot()
    }

    /// Whether `combination` can be used here; `Err` says why not.
    pub fn check(&self, combination: &Combination) -> Result<(), String> {
        let entries = self.entries(combination)?;
        check_combination(&entries.iter().map(|e| &**e).collect::<Vec<_>>())
    }

    fn entries(&self, combination: &Combination) -> Result<Vec<Arc<TechniqueEntry>>, String> {
        TechniqueKind::ALL
            .iter()
            .map(|&kind| {
                let name = combination.get(kind);
                self.registry.find(kind, name).cloned().ok_or_else(|| {
                    let known: Vec<&str> = self.registry.of_kind(kind).map(|t| t.name.as_str()).collect();
                    if known.is_empty() {
                        format!("no {} technique named '{name}': no plugin offers any (are the plugins installed? see CADR_PLUGIN_PATH)", kind.name())
                    } else {
                        format!("no {} technique named '{name}' (known: {})", kind.name(), known.join(", "))
                    }
                })
            })
            .collect()
    }

    fn wait_idle(&self) -> RenderResult<()> {
        Ok(self.device.wait_idle()?)
    }

    fn create(&self, entry: &Arc<TechniqueEntry>) -> RenderResult<Active> {
        let create = entry
            .common()
            .create
            .ok_or_else(|| RenderError::Technique {
                technique: format!("{} '{}'", entry.kind.name(), entry.name),
                message: "its vtable has no create function".into(),
            })?;
        let info = abi::CadrCreateInfo {
            size: std::mem::size_of::<abi::CadrCreateInfo>() as u32,
            vulkan: &*self.vulkan,
            host: self.services.api(),
            worker_threads: self.worker_threads,
            extensions: std::ptr::null(),
        };
        let mut instance: *mut c_void = std::ptr::null_mut();
        let mut message = Message::new();
        // SAFETY: every pointer is valid for the call; the plugin's ABI version was negotiated.
        let result = unsafe { create(&info, &mut instance, message.raw()) };
        status(entry, "create", result, &message)?;
        if instance.is_null() {
            return Err(RenderError::Technique {
                technique: format!("{} '{}'", entry.kind.name(), entry.name),
                message: "create returned no instance".into(),
            });
        }
        Ok(Active {
            entry: Arc::clone(entry),
            instance,
        })
    }

    /// Switches to `combination`: refuses it (keeping the current one) when a name is unknown,
    /// a technique is unsupported, the techniques do not fit together, or a plugin fails to
    /// create its instance. Kinds whose technique does not change keep their instance.
    pub fn select(&mut self, combination: &Combination) -> RenderResult<()> {
        let refuse = |message: String| RenderError::Technique {
            technique: combination.to_string(),
            message,
        };
        let entries = self.entries(combination).map_err(refuse)?;
        check_combination(&entries.iter().map(|e| &**e).collect::<Vec<_>>()).map_err(refuse)?;
        let mut created: Vec<(usize, Active)> = Vec::new();
        for entry in &entries {
            let slot = index(entry.kind);
            let same = self.active[slot]
                .as_ref()
                .is_some_and(|a| Arc::ptr_eq(&a.entry, entry));
            if !same {
                // A failure drops what was created so far; the current set stays.
                created.push((slot, self.create(entry)?));
            }
        }
        if created.is_empty() {
            return Ok(());
        }
        let method = match created
            .iter()
            .find(|(slot, _)| *slot == index(TechniqueKind::Transparency))
        {
            Some((_, active)) => Some(describe_method(active)?),
            None => self.method.clone(),
        };
        let pick_kind = self.pick_pass_kind();
        let mesh_shading = self.mesh_shading();
        let rebuilt = created
            .iter()
            .any(|(slot, _)| PIPELINE_KINDS.map(index).contains(slot));
        self.wait_idle()?;
        if rebuilt {
            self.pipelines.clear();
        }
        for (slot, active) in created {
            // The old instance drops here, after the GPU finished with it.
            self.active[slot] = Some(active);
        }
        self.method = method;
        if self.pick_pass_kind() != pick_kind {
            // A library of an older ABI came or went: the pick pass is drawn as another kind.
            self.pipelines
                .retain(|p| !matches!(p.pass_set, PassSet::Pick { .. }));
        }
        if self.mesh_shading() != mesh_shading {
            // The submission draws with or without mesh workgroups: other pipelines.
            self.pipelines.clear();
        }
        self.epoch += 1;
        Ok(())
    }

    /// Replaces one kind's technique.
    pub fn swap(&mut self, kind: TechniqueKind, name: &str) -> RenderResult<()> {
        let mut combination = self.combination();
        combination.set(kind, name);
        self.select(&combination)
    }

    /// Where the active combination needs world matrices kept: on the host when one of its
    /// techniques reads them there (`CADR_TRAIT_READS_HOST_MATRICES`, or a library older than
    /// ABI 1.4, which could not say), otherwise on the GPU only.
    pub fn transforms(&self) -> Transforms {
        let on_host = self.active.iter().flatten().any(|active| {
            self.announces(active, abi::CADR_TRAIT_READS_HOST_MATRICES, 0)
                || active.entry.abi_version.1 < 4
        });
        if on_host {
            Transforms::Host
        } else {
            Transforms::Gpu
        }
    }

    pub(crate) fn get(&self, kind: TechniqueKind) -> RenderResult<&Active> {
        self.active[index(kind)].as_ref().ok_or_else(|| {
            RenderError::InvalidUse(format!("no {} technique selected", kind.name()))
        })
    }

    /// Builds the pipelines of the current combination for `passes` (the shade mode's, with or
    /// without translucent surfaces, or the pick pass's) if needed.
    pub(crate) fn ensure_pipelines(&mut self, passes: PassSet) -> RenderResult<()> {
        if let Some(i) = self.pipelines.iter().position(|p| p.pass_set == passes) {
            // Drawn now: last (a frame drawing one pass set moves nothing).
            self.pipelines[i..].rotate_left(1);
            return Ok(());
        }
        let pipelines = self.build_pipelines(passes)?;
        if self.pipelines.len() >= KEPT_PASS_SETS {
            // The one unused longest goes; the GPU may still draw with it.
            self.wait_idle()?;
            self.pipelines.remove(0);
        }
        self.pipelines.push(pipelines);
        self.epoch += 1;
        Ok(())
    }

    /// The pipelines built for `passes` (see `ensure_pipelines`).
    pub(crate) fn pipelines_for(&self, passes: PassSet) -> RenderResult<&TechniquePipelines> {
        self.pipelines
            .iter()
            .find(|p| p.pass_set == passes)
            .map(|kept| &***kept)
            .ok_or_else(|| RenderError::InvalidUse("technique pipelines were not built".into()))
    }

    /// How many pass sets' pipelines are kept (at most 8: past that, the one unused longest
    /// goes).
    pub fn kept_pass_sets(&self) -> usize {
        self.pipelines.len()
    }

    /// How many of the pass sets kept here are drawn with the very pipelines `other` keeps:
    /// built once and shared by the renderers of one device (`CADR_TRAIT_SHARES_PIPELINES`),
    /// not built again.
    pub fn pass_sets_shared_with(&self, other: &Techniques) -> usize {
        self.pipelines
            .iter()
            .filter(|mine| {
                other
                    .pipelines
                    .iter()
                    .any(|theirs| Arc::ptr_eq(mine, theirs))
            })
            .count()
    }

    /// The active transparency method.
    pub fn transparency_method(&self) -> Option<&TransparencyMethod> {
        self.method.as_ref()
    }

    /// [`abi::CADR_PASS_PICK`] when every active technique was built for ABI 1.2 or later
    /// (which knows that the pick pass must not join parts), else the triangles kind older
    /// libraries know.
    fn pick_pass_kind(&self) -> abi::CadrPassKind {
        let knows_pick = self
            .active
            .iter()
            .flatten()
            .all(|active| active.entry.abi_version >= (1, 2));
        if knows_pick {
            abi::CADR_PASS_PICK
        } else {
            abi::CADR_PASS_TRIANGLES
        }
    }

    fn build_pipelines(&mut self, passes: PassSet) -> RenderResult<Arc<KeptPipelines>> {
        let vertex = self.get(TechniqueKind::Vertex)?;
        let parameters = self.get(TechniqueKind::Parameters)?;
        let vertex_table: &abi::CadrVertexPathVtable = vertex.vtable();
        let parameter_table: &abi::CadrParameterPathVtable = parameters.vtable();
        let snippet = |f: abi::CadrShaderSnippetFn, instance: *mut c_void| -> String {
            f.map(|f| {
                // SAFETY: a live instance; the string lives as long as it.
                let text = unsafe { f(instance) };
                if text.is_null() {
                    String::new()
                } else {
                    // SAFETY: NUL-terminated per the ABI.
                    unsafe { CStr::from_ptr(text) }
                        .to_string_lossy()
                        .into_owned()
                }
            })
            .unwrap_or_default()
        };
        let vertex_snippet = snippet(vertex_table.shader_snippet, vertex.instance);
        let parameter_snippet = snippet(parameter_table.shader_snippet, parameters.instance);
        let mut input = abi::CadrVertexInput::default();
        if let Some(f) = vertex_table.vertex_input {
            // SAFETY: a live instance; `input` is writable.
            unsafe { f(vertex.instance, &mut input) };
        }
        let vertex_set = vertex_table
            .set_layout
            // SAFETY: a live instance.
            .map_or(0, |f| unsafe { f(vertex.instance) });
        let mut parameter_sets = [0u64; 2];
        let mut push_bytes = 0u32;
        if let Some(f) = parameter_table.layout {
            // SAFETY: a live instance; room for two layouts and a count.
            unsafe {
                f(
                    parameters.instance,
                    parameter_sets.as_mut_ptr(),
                    &mut push_bytes,
                )
            };
        }
        let pick_kind = self.pick_pass_kind();
        let mesh_shading = self.mesh_shading();
        let shared_key = PipelineKey::new(&KeyInputs {
            paths: (&vertex.entry, &parameters.entry),
            snippets: (&vertex_snippet, &parameter_snippet),
            vertex_input: &input,
            passes,
            pick_kind,
            method: self.method.as_ref(),
            mesh_shading,
        });
        let shader_key = (vertex.entry.name.clone(), parameters.entry.name.clone());
        let device = Arc::clone(&self.device);
        let (shader_cache, frame_set_layout, merge_set_layout) = (
            &mut self.shaders,
            self.frame_set_layout,
            self.merge_set_layout,
        );
        let method = self.method.as_ref();
        shared_or_built(&device, shared_key, || {
            let shaders = shader_cache.prepare(
                shader_key,
                TechniqueShaderSources {
                    vertex: &|| assemble_vertex_shader(&vertex_snippet, &parameter_snippet),
                    mesh: mesh_shading
                        .then_some(&|| assemble_mesh_shader(&vertex_snippet, &parameter_snippet)),
                },
                passes,
                method,
            )?;
            let inputs = PipelineInputs {
                frame_set_layout,
                merge_set_layout,
                path_set_layouts: [
                    vk::DescriptorSetLayout::from_raw(parameter_sets[0]),
                    vk::DescriptorSetLayout::from_raw(parameter_sets[1]),
                    vk::DescriptorSetLayout::from_raw(vertex_set),
                ],
                vertex_input: input,
                shaders: &shaders,
                passes,
                pick_kind,
                method,
            };
            TechniquePipelines::new(&device, &inputs)
        })
    }
}

impl Drop for Techniques {
    fn drop(&mut self) {
        let _ = self.wait_idle();
        self.pipelines.clear();
        for slot in &mut self.active {
            *slot = None;
        }
    }
}

/// Asks a transparency technique what it is (`CadrTransparencyVtable::method`) and checks the
/// answer: at most 2 targets of formats the host can use, snippets present.
fn describe_method(active: &Active) -> RenderResult<TransparencyMethod> {
    let entry = &active.entry;
    let refuse = |message: String| RenderError::Technique {
        technique: format!("{} '{}'", entry.kind.name(), entry.name),
        message,
    };
    let method_fn = active
        .vtable::<abi::CadrTransparencyVtable>()
        .method
        .ok_or_else(|| refuse("its vtable has no method function".into()))?;
    // SAFETY: all-zero is a valid CadrTransparencyMethod (integers and null pointers).
    let mut raw: abi::CadrTransparencyMethod = unsafe { std::mem::zeroed() };
    raw.size = std::mem::size_of::<abi::CadrTransparencyMethod>() as u32;
    let mut message = Message::new();
    // SAFETY: a live instance; `raw` is writable for the call.
    let result = unsafe { method_fn(active.instance, &mut raw, message.raw()) };
    status(entry, "method", result, &message)?;
    let text = |pointer: *const c_char, what: &str| -> RenderResult<String> {
        if pointer.is_null() {
            return Err(refuse(format!("it gave no {what}")));
        }
        // SAFETY: NUL-terminated per the ABI, alive as long as the instance.
        Ok(unsafe { CStr::from_ptr(pointer) }
            .to_string_lossy()
            .into_owned())
    };
    if raw.target_count as usize > raw.targets.len() {
        return Err(refuse(format!(
            "{} targets: at most {}",
            raw.target_count,
            raw.targets.len()
        )));
    }
    let targets = raw.targets[..raw.target_count as usize].to_vec();
    // Formats every Vulkan device must blend into (and sample).
    let usable = [
        vk::Format::R16G16B16A16_SFLOAT,
        vk::Format::R16G16_SFLOAT,
        vk::Format::R16_SFLOAT,
        vk::Format::R8G8B8A8_UNORM,
    ];
    if let Some((i, target)) = targets
        .iter()
        .enumerate()
        .find(|(_, t)| !usable.contains(&vk::Format::from_raw(t.format)))
    {
        return Err(refuse(format!(
            "target {i} has format {}, not one cadr blends into ({usable:?})",
            target.format
        )));
    }
    if raw.storage_cleared_words_per_pixel > raw.storage_words_per_pixel {
        return Err(refuse(format!(
            "it clears {} storage words per pixel of {}",
            raw.storage_cleared_words_per_pixel, raw.storage_words_per_pixel
        )));
    }
    Ok(TransparencyMethod {
        name: entry.name.clone(),
        targets,
        storage_header_words: raw.storage_header_words,
        storage_words_per_pixel: raw.storage_words_per_pixel,
        storage_cleared_words_per_pixel: raw.storage_cleared_words_per_pixel,
        fragment_snippet: text(raw.fragment_snippet, "fragment snippet")?,
        merge_snippet: text(raw.merge_snippet, "merge snippet")?,
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.
    use super::*;

    const GPU_DRAWS: u64 = abi::CADR_TRAIT_DRAWS_GPU_COMMANDS;
    const TAILS: u64 = abi::CADR_TRAIT_EMPTY_COMMAND_TAILS;

    /// A vertex path, a parameter path and a transparency method that suit any submission and
    /// culler, with `submission` and `culler`.
    fn combination(submission: &TechniqueEntry, culler: &TechniqueEntry) -> Result<(), String> {
        let wide = abi::CADR_TRAIT_SCENE_SHARES_BINDING | abi::CADR_TRAIT_GEOMETRY_SHARES_BINDING;
        let vertex = TechniqueEntry::described(TechniqueKind::Vertex, "v", 24, (wide, 0));
        let parameters = TechniqueEntry::described(
            TechniqueKind::Parameters,
            "p",
            24,
            (abi::CADR_TRAIT_PARAMETERS_FROM_INSTANCE_INDEX, 0),
        );
        let transparency = TechniqueEntry::described(TechniqueKind::Transparency, "t", 24, (0, 0));
        check_combination(&[&vertex, &parameters, submission, culler, &transparency])
    }

    #[test]
    fn commands_drawn_by_their_capacity_need_a_culler_that_empties_the_tails() {
        let by_capacity = TechniqueEntry::described(
            TechniqueKind::Submission,
            "by-capacity",
            24,
            (GPU_DRAWS | TAILS, 0),
        );
        let by_count =
            TechniqueEntry::described(TechniqueKind::Submission, "by-count", 24, (GPU_DRAWS, 0));
        let culler = |minor, provides| {
            TechniqueEntry::described(TechniqueKind::Culling, "gpu", minor, (provides, GPU_DRAWS))
        };
        let cpu_culler = TechniqueEntry::described(TechniqueKind::Culling, "cpu", 24, (0, 0));
        combination(&by_capacity, &culler(24, TAILS)).unwrap();
        combination(&by_count, &culler(24, 0)).unwrap();
        // A CPU culler writes no commands: the submission draws its own.
        combination(&by_capacity, &cpu_culler).unwrap();
        // A culler that does not announce it, or announces the bit from before ABI 1.24 (when
        // it meant nothing), would leave last frame's commands past the count.
        for refused in [culler(24, 0), culler(23, TAILS)] {
            let why = combination(&by_capacity, &refused).unwrap_err();
            assert!(
                why.contains("submission 'by-capacity'")
                    && why.contains("culling 'gpu'")
                    && why.contains("past its counts empty"),
                "{why}"
            );
        }
        // A submission of ABI 1.23 with the bit draws by the count, as then.
        let older = TechniqueEntry::described(
            TechniqueKind::Submission,
            "older",
            23,
            (GPU_DRAWS | TAILS, 0),
        );
        combination(&older, &culler(24, 0)).unwrap();
    }
}
