//! The renderer: an offscreen target and the frame that draws into it (uniforms, command
//! buffer, pass, submission, timings, frames in flight, and the replay of an unchanged frame's
//! recording; `stats.rs` says what a frame cost, `output.rs` reads the image back and writes
//! PNGs). The techniques record into its frames
//! (`Renderer::render_techniques`, `Renderer::pick_techniques`); the pick pass draws instance
//! ids and depth into their own target and reads a rectangle of them back ([`pick`]).

mod background;
mod camera;
mod highlight;
mod output;
mod palette;
pub mod pick;
mod pipeline;
mod pixel_keys;
mod section;
mod stats;
mod transparency;

pub use background::Background;
pub use camera::{Camera, DEFAULT_DIRECTION, DEFAULT_FOV_DEGREES};
pub use highlight::HighlightStyle;
pub use output::SaveError;
pub use palette::{DisplayRgb, Palette};
pub use pipeline::{
    FrameUniforms, HierarchyParameters, HierarchyStage, Pipelines, ScatterParameters,
    DISPLAY_CAP_KEYS, DISPLAY_HIGHLIGHT_OUTLINE, DISPLAY_MATERIAL_DESCRIPTIONS,
    DISPLAY_NEAREST_SURFACES, DISPLAY_TEXTURES, DISPLAY_VERTEX_ATTRIBUTES, DISPLAY_XRAY,
    PICK_FORMAT, TEXTURE_TABLE_BINDING,
};
pub use section::{Section, DEFAULT_CAP_COLORS, MAX_SECTION_PLANES};
pub use stats::FrameStats;

use std::sync::Arc;
use std::time::Instant;

use crate::error::{RenderError, RenderResult};
use crate::vk::raw as vk;

use crate::gpu_scene::split_f64;
use crate::gpu_scene::{FrameResources, TextureBindings};
use crate::technique::TransparencyMethod;
pub(crate) use crate::vk::SUSPENDED_DEPTH_LAYOUT;
use crate::vk::{
    begin_overlay, begin_rendering, end_overlay, end_rendering, memory_barrier, record_fullscreen,
    suspend_rendering, Buffer, CommandContext, DescriptorSets, Device, GpuTimer, Image,
    MemoryLocation, Multisampled, OffscreenTarget, RenderingTarget,
};
use pick::{PickTarget, PixelRect};
use pixel_keys::{KeyUse, PixelKeys};
use transparency::{storage_buffer, TransparencyTargets};

/// What the colour pass clears to: nothing drawn, no coverage (the background goes under
/// it after the rendering).
const UNCOVERED: [f32; 4] = [0.0; 4];

/// Renders scenes into an offscreen color + depth target.
pub struct Renderer {
    device: Arc<Device>,
    target: OffscreenTarget,
    frame_uniforms: Buffer,
    pipelines: Pipelines,
    frame_sets: DescriptorSets,
    /// What GPU cullers read of the view (`CadrGpuCullView`), host-written every frame.
    cull_view: Buffer,
    commands: CommandContext,
    /// The GPU time of a frame's pass (the main command buffer).
    timer: Option<GpuTimer>,
    /// The GPU time of a frame's uploads (the prologue submitted ahead of the main buffer).
    upload_timer: Option<GpuTimer>,
    /// Whether the last submission carried an upload prologue (its GPU time is the frame's
    /// too).
    last_submission_uploaded: bool,
    /// The id target and its readback, created on the first pick.
    pick: Option<PickTarget>,
    /// The replay key of the last recorded frame, if it had one.
    last_recorded: Option<u64>,
    /// The frame in the command buffer, if it may be submitted again as it is: its replay
    /// key and what it drew.
    replayable: Option<(u64, FrameStats)>,
    /// Frames the GPU may work on while the CPU prepares the next (see
    /// [`Renderer::set_frames_in_flight`]).
    frames_in_flight: u32,
    /// The section planes and caps every pass applies.
    section: Section,
    /// What the transparency method of the last frame with translucent surfaces drew into.
    transparency: Option<TransparencyTargets>,
    /// The storage the frame set names while no method's storage is made.
    placeholder_storage: Buffer,
    /// The background every picture is drawn over.
    background: Background,
    /// The colours of edge lines and highlights.
    palette: Palette,
    /// Whether frames that fill surfaces get screen-space ambient occlusion.
    ssao: bool,
    /// Whether the edge display modes draw silhouette edges with the feature edges.
    silhouettes: bool,
    /// The set naming the target's depth for the passes over the picture that read it
    /// (ambient occlusion, silhouettes); made on first use, dropped when the target is remade.
    depth_set: Option<DescriptorSets>,
    /// Whether materials' textures are sampled (vertex colours apply either way).
    textures: bool,
    /// How highlighted parts are drawn.
    highlight_style: HighlightStyle,
    /// The pixel keys at the target's size (made by the first frame that needs them: with the
    /// outline style, the silhouettes' nearest surfaces or the cap keys), which binding 7 of
    /// the frame set names; otherwise the placeholder storage is named there.
    pixel_keys: Option<PixelKeys>,
    /// The generation of the GPU scene resources the frame set names, if any.
    bound_scene: Option<u64>,
}

/// The most frames a renderer lets the GPU work on while it prepares the next: techniques
/// keep one copy of what they write on the host per frame, so the next frame's recording
/// waits for the last one.
pub const MAX_FRAMES_IN_FLIGHT: u32 = 2;

/// How a frame is drawn: into which target, from which command buffers, in how many phases,
/// and whether it may be replayed.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FramePlan<'a> {
    /// The target of the pass.
    pub pass: PassTarget,
    /// Whether the pass's contents come from secondary command buffers.
    pub secondary: bool,
    /// Phases of the pass (at least 1).
    pub phases: u32,
    /// The GPU cullers' view, written before the frame is submitted.
    pub cull_view: Option<&'a [u8]>,
    /// What the recording depends on, when the techniques allow a replay: a frame with the
    /// key of the last recorded one, recorded twice in a row, resubmits it.
    pub replay_key: Option<u64>,
    /// Whether the frame uploads scene data (recorded into the prologue, whether the frame
    /// is recorded or replayed).
    pub uploads_pending: bool,
    /// `DISPLAY_*` bits for the shaders.
    pub display: u32,
    /// The transparency method and its merge (pipeline, layout), when the frame draws
    /// translucent surfaces.
    pub translucency: Option<(&'a TransparencyMethod, (vk::Pipeline, vk::PipelineLayout))>,
    /// Whether the frame fills surfaces, so that ambient occlusion (when on) applies.
    pub fills_surfaces: bool,
    /// Whether the frame draws feature edges (the edges, hidden-line and X-ray modes), so
    /// that silhouettes (when on) join them.
    pub draws_edges: bool,
    /// Whether some part is highlighted, so that silhouettes (when drawn) take the
    /// highlight's line colour where they outline one.
    pub highlights: bool,
}

/// The passes over a colour frame's picture that read its depth.
#[derive(Clone, Copy, Debug)]
struct DepthOverlays {
    /// Ambient occlusion.
    ssao: bool,
    /// Silhouette edges, and the depth they are found in.
    silhouettes: Option<SilhouetteSource>,
    /// Whether the surfaces record the nearest surfaces (pixel keys plane 1), which the
    /// silhouettes read: X-ray's depth, and which of them outline highlighted parts.
    nearest_surfaces: bool,
}

/// The passes over a colour frame's picture that read only the pixel keys.
#[derive(Clone, Copy, Debug)]
struct KeyedOverlays {
    /// The band around highlighted parts (the outline highlight style).
    outline: bool,
    /// The caps that tie with another part's surface (caps seen, with the cap keys).
    cap_ties: bool,
}

/// The depth a frame's silhouettes are found in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum SilhouetteSource {
    /// The depth buffer: the surfaces fill it (edges, hidden-line). The silhouettes go under
    /// the translucent surfaces merged over the picture, as the edge lines do.
    DepthBuffer,
    /// The nearest surfaces every surface records in the pixel keys (X-ray, whose translucent
    /// surfaces write no depth). They outline the nearest surfaces, so they go over the merge.
    NearestSurfaces,
}

/// Which image a pass draws into.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PassTarget {
    /// The colour target (shaded image).
    Color,
    /// The R32_UINT pick target (instance id + 1, 0 for nothing).
    Pick,
}

/// What a technique records at one point of the frame: before the pass, inside it (once per
/// phase), between phases, or after it; with the phase.
pub(crate) type Recorder<'a> =
    dyn FnMut(&Renderer, vk::CommandBuffer, u32, &mut FrameStats) -> RenderResult<()> + 'a;

/// Gathers a frame's uploads on the host (written into their buffers, counted in the stats)
/// and returns what their commands depend on: equal keys record equal commands.
pub(crate) type UploadGatherer<'a> =
    dyn FnMut(&Renderer, &mut FrameStats) -> RenderResult<u64> + 'a;

/// The recorders of a frame, in the order they run.
pub(crate) struct FrameRecorders<'r, 'a> {
    /// The frame's uploads, when [`FramePlan::uploads_pending`], gathered on the host.
    pub gather_uploads: &'r mut UploadGatherer<'a>,
    /// Their commands: into the prologue, a command buffer of their own submitted ahead of
    /// the frame's, so that a replayed frame gets them too; a prologue with the key of the
    /// last one is submitted again instead. `before` makes their writes visible.
    pub uploads: &'r mut Recorder<'a>,
    /// Outside rendering, before the first phase.
    pub before: &'r mut Recorder<'a>,
    /// Inside rendering, once per phase.
    pub inside: &'r mut Recorder<'a>,
    /// Outside rendering between phases (from phase 1 on), the depth so far readable in
    /// [`SUSPENDED_DEPTH_LAYOUT`].
    pub between: &'r mut Recorder<'a>,
    /// Outside rendering, after the last phase.
    pub after: &'r mut Recorder<'a>,
}

impl Renderer {
    /// Creates a renderer with a `width` × `height` target.
    pub fn new(device: &Arc<Device>, width: u32, height: u32) -> RenderResult<Self> {
        let target = OffscreenTarget::new(device, width, height, 1)?;
        let frame_uniforms = Buffer::new(
            device,
            "frame uniforms",
            std::mem::size_of::<FrameUniforms>() as u64,
            vk::BufferUsageFlags::UNIFORM_BUFFER,
            MemoryLocation::CpuToGpu,
        )?;
        let pipelines = Pipelines::new(device)?;
        let frame_sets = DescriptorSets::new(device, "frame", &[pipelines.frame_set_layout()])?;
        frame_sets.write_buffer(
            0,
            0,
            vk::DescriptorType::UNIFORM_BUFFER,
            frame_uniforms.raw(),
            vk::WHOLE_SIZE,
        );
        let placeholder_storage = storage_buffer(device, 0)?;
        name_storage(&frame_sets, &placeholder_storage);
        name_pixel_keys(&frame_sets, &placeholder_storage);
        let cull_view = Buffer::new(
            device,
            "gpu cull view",
            std::mem::size_of::<cadr_plugin_abi::CadrGpuCullView>() as u64,
            vk::BufferUsageFlags::UNIFORM_BUFFER,
            MemoryLocation::CpuToGpu,
        )?;
        let commands = CommandContext::new(device, "frame commands")?;
        let timer = GpuTimer::new(device, "frame timer")?;
        let upload_timer = GpuTimer::new(device, "frame upload timer")?;
        Ok(Self {
            device: Arc::clone(device),
            target,
            frame_uniforms,
            pipelines,
            frame_sets,
            cull_view,
            commands,
            timer,
            upload_timer,
            last_submission_uploaded: false,
            pick: None,
            last_recorded: None,
            replayable: None,
            frames_in_flight: 1,
            section: Section::none(),
            transparency: None,
            placeholder_storage,
            textures: true,
            highlight_style: HighlightStyle::default(),
            pixel_keys: None,
            bound_scene: None,
            background: Background::default(),
            palette: Palette::default(),
            ssao: false,
            silhouettes: true,
            depth_set: None,
        })
    }

    /// The background pictures are drawn over ([`Background::GRADIENT`] by default).
    pub fn background(&self) -> Background {
        self.background
    }

    /// Sets the background; the next frame draws it (through the frame's uniforms, so a
    /// recorded frame replays with it).
    pub fn set_background(&mut self, background: Background) -> RenderResult<()> {
        background.validate().map_err(RenderError::InvalidUse)?;
        self.background = background;
        Ok(())
    }

    /// The colours of edge lines and highlights and the outline band's width
    /// ([`Palette::DEFAULT`] by default).
    pub fn palette(&self) -> Palette {
        self.palette
    }

    /// Sets the colours of edge lines and highlights and the outline band's width; the next
    /// frame draws with them (through the frame's uniforms, so a recorded frame replays with
    /// them). Refuses colours outside 0..1 and widths outside 1 to
    /// [`Palette::MAX_OUTLINE_WIDTH`], keeping the palette it had.
    pub fn set_palette(&mut self, palette: Palette) -> RenderResult<()> {
        palette.validate().map_err(RenderError::InvalidUse)?;
        self.palette = palette;
        Ok(())
    }

    /// Whether frames that fill surfaces (solid, edges, X-ray) get screen-space ambient
    /// occlusion: creases, corners and gaps between parts darkened from the depth (off by
    /// default).
    pub fn ssao(&self) -> bool {
        self.ssao
    }

    /// Turns screen-space ambient occlusion on or off (see [`Renderer::ssao`]); the next frame
    /// draws with it.
    pub fn set_ssao(&mut self, on: bool) -> RenderResult<()> {
        if on != self.ssao {
            self.commands.wait()?;
            // The recorded frame has (or lacks) the occlusion pass.
            self.forget_recording();
            self.ssao = on;
        }
        Ok(())
    }

    /// Whether the display modes that draw feature edges (edges, hidden-line, X-ray) draw
    /// silhouette edges with them: the outlines of curved surfaces where the depth breaks,
    /// which no feature edge marks (on by default), in the edge lines' colour, or a
    /// highlighted part's in the highlight's line colour as its edges. X-ray finds them in the
    /// nearest surfaces its surfaces record, and the highlight's colour is found there too,
    /// which needs the device's `fragmentStoresAndAtomics`: without it, X-ray draws none and
    /// the others draw every silhouette in the edge lines' colour.
    pub fn silhouettes(&self) -> bool {
        self.silhouettes
    }

    /// Where the silhouettes of a frame planned as `plan` are found, if it draws them.
    fn silhouette_source(&self, plan: &FramePlan<'_>) -> Option<SilhouetteSource> {
        if !(self.silhouettes && plan.draws_edges && plan.pass == PassTarget::Color) {
            return None;
        }
        if plan.display & DISPLAY_XRAY == 0 {
            Some(SilhouetteSource::DepthBuffer)
        } else if self.device.capabilities().fragment_stores_and_atomics {
            Some(SilhouetteSource::NearestSurfaces)
        } else {
            None
        }
    }

    /// Whether a frame planned as `plan` whose silhouettes are found in `silhouettes` has
    /// its surfaces record the nearest surfaces: for X-ray's silhouettes, and for the others
    /// where some part is highlighted and the device can record them.
    fn records_nearest_surfaces(
        &self,
        plan: &FramePlan<'_>,
        silhouettes: Option<SilhouetteSource>,
    ) -> bool {
        match silhouettes {
            Some(SilhouetteSource::NearestSurfaces) => true,
            Some(SilhouetteSource::DepthBuffer) => {
                plan.highlights && self.device.capabilities().fragment_stores_and_atomics
            }
            None => false,
        }
    }

    /// Turns silhouette edges on or off (see [`Renderer::silhouettes`]); the next frame
    /// draws with it.
    pub fn set_silhouettes(&mut self, on: bool) -> RenderResult<()> {
        if on != self.silhouettes {
            self.commands.wait()?;
            // The recorded frame has (or lacks) the silhouettes pass.
            self.forget_recording();
            self.silhouettes = on;
        }
        Ok(())
    }

    /// How highlighted parts are drawn ([`HighlightStyle::Tint`] by default).
    pub fn highlight_style(&self) -> HighlightStyle {
        self.highlight_style
    }

    /// Sets how highlighted parts are drawn; the next frame draws so. The outline style is
    /// refused on a device without `fragmentStoresAndAtomics` (its surfaces record the
    /// outline keys from their fragment shaders).
    pub fn set_highlight_style(&mut self, style: HighlightStyle) -> RenderResult<()> {
        if style == HighlightStyle::Outline
            && !self.device.capabilities().fragment_stores_and_atomics
        {
            return Err(RenderError::InvalidUse(format!(
                "the outline highlight style needs fragmentStoresAndAtomics, which {} lacks",
                self.device.adapter().name
            )));
        }
        if style != self.highlight_style {
            self.commands.wait()?;
            // The recorded frame has (or lacks) the outline's clear and pass.
            self.forget_recording();
            self.highlight_style = style;
            self.drop_pixel_keys();
        }
        Ok(())
    }

    /// Whether materials' textures are sampled (on by default). Vertex colours apply either way.
    pub fn textures(&self) -> bool {
        self.textures
    }

    /// Turns the sampling of materials' textures on or off (`cadr render --no-textures`); the
    /// next frame draws with it (it reaches the shaders through the frame uniforms, so a
    /// replayed frame follows too). A BLEND material that is translucent only through its
    /// texture still goes through the translucent pass, where it comes out opaque.
    pub fn set_textures(&mut self, on: bool) {
        self.textures = on;
    }

    /// Points the frame set's scene bindings (2–6, 8 and the texture table 9) at `resources`
    /// unless it names them already. A recorded frame names the old ones: the GPU is waited
    /// for and the recording forgotten.
    pub(crate) fn bind_scene(&mut self, resources: &FrameResources) -> RenderResult<()> {
        if self.bound_scene == Some(resources.generation) {
            return Ok(());
        }
        self.finish()?;
        self.forget_recording();
        let storage = vk::DescriptorType::STORAGE_BUFFER;
        let sets = &self.frame_sets;
        sets.write_buffer(0, 2, storage, resources.records, vk::WHOLE_SIZE);
        sets.write_buffer(0, 3, storage, resources.material_textures, vk::WHOLE_SIZE);
        sets.write_buffer(0, 4, storage, resources.vertex_attributes, vk::WHOLE_SIZE);
        match resources.textures {
            TextureBindings::Array(view) => {
                sets.write_combined_image(0, 5, view, resources.linear_sampler);
                sets.write_combined_image(0, 6, view, resources.nearest_sampler);
            }
            TextureBindings::Table(views) => {
                sets.write_sampler(0, 5, resources.linear_sampler);
                sets.write_sampler(0, 6, resources.nearest_sampler);
                // Runs of filled slots, one write each; empty slots stay unwritten (the
                // table is partially bound, and no material names them).
                let mut first = 0;
                for run in views.split(|view| *view == vk::ImageView::null()) {
                    sets.write_sampled_images(0, TEXTURE_TABLE_BINDING, first, run);
                    first += run.len() as u32 + 1;
                }
            }
        }
        sets.write_buffer(0, 8, storage, resources.cull_entries, vk::WHOLE_SIZE);
        self.bound_scene = Some(resources.generation);
        Ok(())
    }

    /// Forgets the frame in the command buffer: the next frame is recorded afresh, whatever
    /// its replay key (it would draw what no longer holds: other passes, bindings or targets).
    fn forget_recording(&mut self) {
        self.replayable = None;
        self.last_recorded = None;
    }

    /// The depth set of the passes over the picture for the current target (the GPU is
    /// idle: the caller waited for the last frame).
    fn ensure_depth_set(&mut self) -> RenderResult<vk::DescriptorSet> {
        if self.depth_set.is_none() {
            let sets = DescriptorSets::new(
                &self.device,
                "picture depth",
                &[self.pipelines.depth_set_layout()],
            )?;
            sets.write_sampled_image(0, 0, self.target.depth.view());
            self.depth_set = Some(sets);
        }
        Ok(self
            .depth_set
            .as_ref()
            .map_or(vk::DescriptorSet::null(), |s| s.sets[0]))
    }

    /// The section planes and caps (none by default).
    pub fn section(&self) -> &Section {
        &self.section
    }

    /// Sets the section planes and caps; the next frame applies them (a recorded frame may be
    /// replayed: they reach the GPU through the frame's uniforms).
    pub fn set_section(&mut self, section: Section) {
        self.section = section;
    }

    /// The device.
    pub fn device(&self) -> &Arc<Device> {
        &self.device
    }

    /// The pipelines (to create resident scenes with).
    pub fn pipelines(&self) -> &Pipelines {
        &self.pipelines
    }

    /// Width and height of the target.
    pub fn size(&self) -> (u32, u32) {
        let extent = self.target.extent();
        (extent.width, extent.height)
    }

    /// Gives the target a new size (a window was resized); the next frame draws at that size.
    pub fn resize(&mut self, width: u32, height: u32) -> RenderResult<()> {
        if (width, height) == self.size() {
            return Ok(());
        }
        self.commands.wait()?;
        // The recorded frame draws into the old target: never submit it again.
        self.forget_recording();
        self.target = OffscreenTarget::new(&self.device, width, height, self.msaa())?;
        self.depth_set = None;
        self.pick = None;
        self.drop_transparency_targets();
        self.drop_pixel_keys();
        Ok(())
    }

    /// Samples per pixel of the colour pass: 1 (the default) draws one, 2, 4 or 8 anti-alias
    /// edges (MSAA), resolved into the picture at the end of the pass. The pick pass always
    /// draws one sample, so picking stays exact.
    pub fn msaa(&self) -> u32 {
        self.target.samples()
    }

    /// Sets the samples per pixel of the colour pass (see [`Renderer::msaa`]); the next frame
    /// draws with them. A count the device does not offer for colour and depth attachments
    /// ([`Device::sample_counts`]) is refused with the counts it offers.
    pub fn set_msaa(&mut self, samples: u32) -> RenderResult<()> {
        if samples == self.msaa() {
            return Ok(());
        }
        let offered = self.device.sample_counts();
        if !offered.contains(&samples) {
            let offered: Vec<String> = offered.iter().map(u32::to_string).collect();
            return Err(RenderError::InvalidUse(format!(
                "MSAA {samples}x: {} offers {} samples per pixel",
                self.device.adapter().name,
                offered.join(", ")
            )));
        }
        // Not only this renderer's frames use the target: a window's present blits from it.
        self.device.wait_idle()?;
        // The recorded frame draws into the old target: never submit it again.
        self.forget_recording();
        let (width, height) = self.size();
        self.target = OffscreenTarget::new(&self.device, width, height, samples)?;
        self.depth_set = None;
        self.pick = None;
        self.drop_transparency_targets();
        Ok(())
    }

    /// How many frames the GPU may have: 1 (the default) waits for each frame before
    /// returning from it, so its GPU time is known and its picture ready; 2 returns as soon as
    /// the frame is submitted and waits for it when the next frame begins (or when its picture
    /// or pick is read), so the host's work, scene updates and CPU culling for the next frame
    /// overlap the GPU's drawing. With 2, [`FrameStats::gpu_us`] is the previous frame's.
    pub fn set_frames_in_flight(&mut self, frames: u32) -> RenderResult<()> {
        if !(1..=MAX_FRAMES_IN_FLIGHT).contains(&frames) {
            return Err(RenderError::InvalidUse(format!(
                "{frames} frames in flight: expected 1 to {MAX_FRAMES_IN_FLIGHT}"
            )));
        }
        if frames == 1 {
            self.finish()?;
        }
        self.frames_in_flight = frames;
        Ok(())
    }

    /// How many frames the GPU may have (see [`Renderer::set_frames_in_flight`]).
    pub fn frames_in_flight(&self) -> u32 {
        self.frames_in_flight
    }

    /// Waits until the GPU has finished the last frame (its picture, pick results and
    /// buffers are then the host's to read or change).
    pub fn finish(&self) -> RenderResult<()> {
        Ok(self.commands.wait()?)
    }

    /// The color image of the last frame (in TRANSFER_SRC_OPTIMAL between frames), for
    /// presenting it.
    pub fn color_image(&self) -> &Image {
        &self.target.color
    }

    /// Makes the pick target ready to read back `rect` (inside the target) after the next pick
    /// pass.
    pub(crate) fn prepare_pick(&mut self, rect: PixelRect) -> RenderResult<()> {
        let (width, height) = self.size();
        if rect.width == 0
            || rect.height == 0
            || u64::from(rect.x) + u64::from(rect.width) > u64::from(width)
            || u64::from(rect.y) + u64::from(rect.height) > u64::from(height)
        {
            return Err(RenderError::InvalidUse(format!(
                "pixels {rect} are not inside the {width}x{height} target"
            )));
        }
        match &mut self.pick {
            Some(target) => target.prepare(rect),
            None => {
                self.pick = Some(PickTarget::new(&self.device, self.target.extent(), rect)?);
                Ok(())
            }
        }
    }

    /// Records the copy of the prepared rectangle's ids and depths (after the pick pass).
    pub(crate) fn record_pick_readback(&self, command_buffer: vk::CommandBuffer) {
        if let Some(target) = &self.pick {
            target.record_readback(&self.device, command_buffer, &self.target.depth);
        }
    }

    /// The prepared rectangle's samples from the last pick pass: the pixels covered by a
    /// pickable instance.
    pub(crate) fn pick_samples(&self) -> RenderResult<Vec<pick::PickSample>> {
        self.finish()?;
        match &self.pick {
            Some(target) => target.samples(),
            None => Ok(Vec::new()),
        }
    }

    /// Runs a frame: uniforms, command buffer, target transitions, the technique's commands
    /// before the pass, inside it in `plan.phases` phases (the pass suspended between them, its
    /// depth readable) and after it, submission, timings, and with one frame in flight the
    /// wait for it (with two, the next frame waits instead). A frame whose replay key is
    /// that of the recording in the command buffer submits it again instead.
    pub(crate) fn frame(
        &mut self,
        camera: &Camera,
        plan: FramePlan<'_>,
        recorders: FrameRecorders<'_, '_>,
    ) -> RenderResult<FrameStats> {
        // The eye in f64, split for relative-to-eye positions on the GPU.
        let eye = camera.eye();
        let (eye_high, eye_low) = split_f64(eye);
        let mut view_rotation = camera.view;
        view_rotation.w_axis = glam::DVec4::W;
        let color = plan.pass == PassTarget::Color;
        let outline = self.highlight_style == HighlightStyle::Outline && color;
        let silhouettes = self.silhouette_source(&plan);
        let depth_overlays = DepthOverlays {
            ssao: self.ssao && plan.fills_surfaces && color,
            silhouettes,
            nearest_surfaces: self.records_nearest_surfaces(&plan, silhouettes),
        };
        let nearest_surfaces = depth_overlays.nearest_surfaces;
        // Caps that tie with another part's surface are painted from the cap keys, which the
        // surfaces record (every mode but wireframe, which draws none).
        let cap_keys = color
            && (plan.fills_surfaces || plan.draws_edges)
            && self.device.capabilities().fragment_stores_and_atomics
            && self.section.caps_seen_from(eye);
        let display = plan.display
            | if nearest_surfaces {
                DISPLAY_NEAREST_SURFACES
            } else {
                0
            }
            | if cap_keys { DISPLAY_CAP_KEYS } else { 0 };
        // The recording has (or lacks) the cap keys' clear and pass, which the camera decides.
        let replay_key = plan
            .replay_key
            .map(|key| crate::commands_key::mix(key, u64::from(cap_keys)));
        let uniforms = FrameUniforms {
            projection: camera.projection.as_mat4().to_cols_array_2d(),
            view_rotation: view_rotation.as_mat4().to_cols_array_2d(),
            eye_high: [eye_high[0], eye_high[1], eye_high[2], 0.0],
            eye_low: [eye_low[0], eye_low[1], eye_low[2], 0.0],
            light: [0.22, 0.68, 0.35, 0.0],
            section_planes: self.section.eye_relative(eye),
            section_colors: self.section.colors(),
            section: [self.section.flags(), 0, 0, 0],
            target: {
                let (width, height) = self.size();
                [width, height, display, 0]
            },
            background_top: opaque(self.background.top),
            background_bottom: opaque(self.background.bottom),
            edge_color: opaque(self.palette.edges),
            highlight: {
                let [r, g, b] = self.palette.highlight;
                [r, g, b, self.palette.outline_width as f32]
            },
        };
        self.commands.wait()?;
        if let Some((method, _)) = plan.translucency {
            self.ensure_transparency_targets(method)?;
        }
        let key_use = KeyUse {
            outline,
            nearest_surfaces,
            cap_keys,
        };
        if let Some(planes) = key_use.plane_count() {
            self.ensure_pixel_keys(planes)?;
        }
        let depth_set = if depth_overlays.ssao || depth_overlays.silhouettes.is_some() {
            Some(self.ensure_depth_set()?)
        } else {
            None
        };
        // With a frame in flight, the last one's GPU time is read now that it is done anyway.
        let previous_gpu_us = if self.frames_in_flight > 1 {
            self.gpu_time()?
        } else {
            None
        };
        let record_start = Instant::now();
        self.frame_uniforms
            .write(0, bytemuck::bytes_of(&uniforms))?;
        if let Some(bytes) = plan.cull_view {
            self.cull_view.write(0, bytes)?;
        }
        let mut stats = FrameStats::default();
        if plan.uploads_pending {
            let key = (recorders.gather_uploads)(self, &mut stats)?;
            if !self.commands.reuse_prologue(key) {
                let command_buffer = self.commands.begin_prologue()?;
                if let Some(timer) = &mut self.upload_timer {
                    timer.begin(command_buffer);
                }
                (recorders.uploads)(self, command_buffer, 0, &mut stats)?;
                if let Some(timer) = &mut self.upload_timer {
                    timer.end(command_buffer);
                }
                self.commands.end_prologue(key)?;
            }
        }
        match (replay_key, self.replayable) {
            (Some(key), Some((recorded, recorded_stats))) if key == recorded => {
                let replayed = FrameStats {
                    bytes_uploaded: stats.bytes_uploaded,
                    ..recorded_stats
                };
                return self.replay(
                    replayed,
                    plan.uploads_pending,
                    record_start,
                    previous_gpu_us,
                );
            }
            _ => self.replayable = None,
        }

        let command_buffer = self.commands.begin()?;
        if let Some(timer) = &mut self.timer {
            timer.begin(command_buffer);
        }
        let phases = plan.phases.max(1);
        (recorders.before)(self, command_buffer, 0, &mut stats)?;
        let transparency = plan
            .translucency
            .and(self.transparency.as_ref())
            .filter(|_| plan.pass == PassTarget::Color);
        if let Some(targets) = transparency {
            self.record_storage_clear(
                command_buffer,
                &targets.storage,
                (0, targets.cleared_bytes),
                0,
            );
        }
        if let Some((keys, span)) = self
            .pixel_keys
            .as_ref()
            .and_then(|keys| Some((keys, keys.span(key_use)?)))
        {
            self.record_storage_clear(command_buffer, &keys.buffer, span, pixel_keys::NO_SURFACE);
        }
        let extra_colors: Vec<(&Image, vk::ClearColorValue)> = transparency
            .map(|t| t.images.iter().zip(t.clears.iter().copied()).collect())
            .unwrap_or_default();
        let multisampled_extra_colors: Vec<&Image> = transparency
            .map(|t| t.multisampled_images.iter().collect())
            .unwrap_or_default();
        for phase in 0..phases {
            let target = self.pass_target(plan.pass, (plan.secondary, phase > 0, phases > 1));
            let target = RenderingTarget {
                extra_colors: &extra_colors,
                shade_from_depth: depth_set.is_some(),
                multisampled: target.multisampled.map(|m| Multisampled {
                    extra_colors: &multisampled_extra_colors,
                    ..m
                }),
                ..target
            };
            if phase > 0 {
                (recorders.between)(self, command_buffer, phase, &mut stats)?;
            }
            begin_rendering(&self.device, command_buffer, &target);
            (recorders.inside)(self, command_buffer, phase, &mut stats)?;
            if phase + 1 < phases {
                suspend_rendering(&self.device, command_buffer, &target);
            } else {
                end_rendering(&self.device, command_buffer, &target);
            }
        }
        if plan.pass == PassTarget::Color {
            let merge = transparency.zip(plan.translucency.map(|(_, merge)| merge));
            let depth_overlays = depth_set.map(|set| (depth_overlays, set));
            let keyed = KeyedOverlays {
                outline,
                cap_ties: cap_keys,
            };
            self.record_overlay(command_buffer, merge, depth_overlays, keyed)?;
        }
        (recorders.after)(self, command_buffer, phases - 1, &mut stats)?;
        if let Some(timer) = &mut self.timer {
            timer.end(command_buffer);
        }
        let submit_start = Instant::now();
        stats.cpu_record_us = (submit_start - record_start).as_secs_f64() * 1e6;
        self.commands.submit()?;
        self.last_submission_uploaded = plan.uploads_pending;
        stats.cpu_submit_us = submit_start.elapsed().as_secs_f64() * 1e6;
        // The first recording after a change may do one-time work (new buffers cleared);
        // the second with the same key is the steady frame. Uploads are not part of it: they
        // go in the prologue.
        if replay_key.is_some() && replay_key == self.last_recorded {
            self.replayable = replay_key.map(|key| (key, stats));
        }
        self.last_recorded = replay_key;
        stats.gpu_us = self.finish_or_keep_in_flight(previous_gpu_us)?;
        Ok(stats)
    }

    /// With one frame in flight, waits for the frame just submitted and returns its GPU time;
    /// with more, leaves it running and returns `previous_gpu_us`, the frame before's.
    fn finish_or_keep_in_flight(&self, previous_gpu_us: Option<f64>) -> RenderResult<Option<f64>> {
        if self.frames_in_flight > 1 {
            return Ok(previous_gpu_us);
        }
        self.finish()?;
        self.gpu_time()
    }

    /// Submits the recorded frame again, after the prologue with this frame's uploads when
    /// it `uploaded`; it draws what it drew when recorded.
    fn replay(
        &mut self,
        recorded: FrameStats,
        uploaded: bool,
        start: Instant,
        previous_gpu_us: Option<f64>,
    ) -> RenderResult<FrameStats> {
        let submit_start = Instant::now();
        self.commands.resubmit()?;
        self.last_submission_uploaded = uploaded;
        let stats = FrameStats {
            cpu_record_us: (submit_start - start).as_secs_f64() * 1e6,
            cpu_submit_us: submit_start.elapsed().as_secs_f64() * 1e6,
            replayed: true,
            ..recorded
        };
        Ok(FrameStats {
            gpu_us: self.finish_or_keep_in_flight(previous_gpu_us)?,
            ..stats
        })
    }

    /// The GPU time of the last finished frame (its uploads and its pass), if timestamps
    /// work.
    fn gpu_time(&self) -> RenderResult<Option<f64>> {
        let pass = match &self.timer {
            Some(timer) => timer.elapsed_us()?,
            None => None,
        };
        let uploads = match (&self.upload_timer, self.last_submission_uploaded) {
            (Some(timer), true) => timer.elapsed_us()?,
            _ => None,
        };
        Ok(pass.map(|pass| pass + uploads.unwrap_or(0.0)))
    }

    /// The buffer GPU cullers read the view from (`CadrGpuCullView` at offset 0).
    pub(crate) fn cull_view_buffer(&self) -> vk::Buffer {
        self.cull_view.raw()
    }

    /// The image and clear value of a pass target.
    fn pass_image(&self, pass: PassTarget) -> (&Image, vk::ClearColorValue) {
        match (pass, &self.pick) {
            (PassTarget::Pick, Some(target)) => {
                (target.ids(), vk::ClearColorValue { uint32: [0; 4] })
            }
            _ => (
                &self.target.color,
                vk::ClearColorValue { float32: UNCOVERED },
            ),
        }
    }

    /// Makes the targets and storage of `method` at the target's size, unless the last ones
    /// fit; the frame set's binding 1 then names the new storage (the GPU is idle: the caller
    /// waited for the last frame).
    fn ensure_transparency_targets(&mut self, method: &TransparencyMethod) -> RenderResult<()> {
        let extent = self.target.extent();
        let samples = self.msaa();
        if self
            .transparency
            .as_ref()
            .is_some_and(|t| t.fit(method, extent, samples))
        {
            return Ok(());
        }
        // The recorded frame names the old targets.
        self.forget_recording();
        self.drop_transparency_targets();
        let targets = TransparencyTargets::new(
            &self.device,
            method,
            (extent, samples),
            self.pipelines.merge_set_layout(),
        )?;
        name_storage(&self.frame_sets, &targets.storage);
        self.transparency = Some(targets);
        Ok(())
    }

    /// Makes pixel keys of at least `planes` planes for the target's size unless they are
    /// made (as many as any frame so far needed, so that modes drawn in turn do not remake
    /// them), and names them in the frame set (the GPU is idle: the caller waited for the
    /// last frame; the recorded frame named the old binding and is forgotten).
    fn ensure_pixel_keys(&mut self, planes: u64) -> RenderResult<()> {
        let extent = self.target.extent();
        let made = self.pixel_keys.as_ref();
        if made.is_some_and(|k| k.holds(extent, planes)) {
            return Ok(());
        }
        let planes = match made {
            Some(keys) if keys.extent == extent => planes.max(keys.planes()),
            _ => planes,
        };
        self.forget_recording();
        let keys = PixelKeys::new(&self.device, extent, planes)?;
        name_pixel_keys(&self.frame_sets, &keys.buffer);
        self.pixel_keys = Some(keys);
        Ok(())
    }

    /// Forgets the pixel keys; the frame set names the placeholder storage there again.
    fn drop_pixel_keys(&mut self) {
        if self.pixel_keys.take().is_some() {
            name_pixel_keys(&self.frame_sets, &self.placeholder_storage);
        }
    }

    /// Forgets the transparency targets; the frame set names the placeholder storage again.
    fn drop_transparency_targets(&mut self) {
        if self.transparency.take().is_some() {
            name_storage(&self.frame_sets, &self.placeholder_storage);
        }
    }

    /// Fills `(offset, bytes)` of `storage` with `value` (the part of the method's storage it
    /// wants cleared, the pixel keys' planes in use), after the last frame's passes read it
    /// and before this frame's fragments write it. The fill is scoped as
    /// any transfer: validation layers disagree on whether `vkCmdFillBuffer` is a clear or a
    /// copy stage.
    fn record_storage_clear(
        &self,
        command_buffer: vk::CommandBuffer,
        storage: &Buffer,
        (offset, bytes): (u64, u64),
        value: u32,
    ) {
        if bytes == 0 {
            return;
        }
        memory_barrier(
            &self.device,
            command_buffer,
            (
                vk::PipelineStageFlags2::FRAGMENT_SHADER,
                vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE,
            ),
            (
                vk::PipelineStageFlags2::ALL_TRANSFER,
                vk::AccessFlags2::TRANSFER_WRITE,
            ),
        );
        storage.record_fill(command_buffer, offset, bytes, value);
        memory_barrier(
            &self.device,
            command_buffer,
            (
                vk::PipelineStageFlags2::ALL_TRANSFER,
                vk::AccessFlags2::TRANSFER_WRITE,
            ),
            (
                vk::PipelineStageFlags2::FRAGMENT_SHADER,
                vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE,
            ),
        );
    }

    /// What goes over the finished rendering: the section caps that tie with another part's
    /// surface (caps seen), ambient occlusion darkening the opaque picture and silhouette
    /// edges over it (each when on, with the set naming the depth), the transparency method's
    /// result at each pixel blended over the picture (with translucent surfaces), X-ray's
    /// silhouettes over that, the band around highlighted parts (with the outline style), then
    /// the background under whatever the picture leaves uncovered.
    fn record_overlay(
        &self,
        command_buffer: vk::CommandBuffer,
        merge: Option<(&TransparencyTargets, (vk::Pipeline, vk::PipelineLayout))>,
        depth_overlays: Option<(DepthOverlays, vk::DescriptorSet)>,
        keyed: KeyedOverlays,
    ) -> RenderResult<()> {
        let background = self.pipelines.background()?;
        let outline = keyed
            .outline
            .then(|| self.pipelines.outline())
            .transpose()?;
        let cap_ties = keyed
            .cap_ties
            .then(|| self.pipelines.cap_ties())
            .transpose()?;
        // Occlusion darkens the opaque surfaces, before lines go over them and translucent
        // surfaces are merged over both.
        let reads_pixel_keys =
            keyed.cap_ties || depth_overlays.is_some_and(|(overlays, _)| overlays.nearest_surfaces);
        let (ssao, silhouettes) = match depth_overlays {
            Some((overlays, set)) => (
                (overlays.ssao)
                    .then(|| self.pipelines.ssao().map(|pipeline| (pipeline, set)))
                    .transpose()?,
                overlays
                    .silhouettes
                    .map(|source| {
                        self.pipelines
                            .silhouettes()
                            .map(|pipeline| (pipeline, set, source))
                    })
                    .transpose()?,
            ),
            None => (None, None),
        };
        let silhouettes_from = |wanted: SilhouetteSource| {
            silhouettes
                .filter(|&(_, _, source)| source == wanted)
                .map(|(pipeline, set, _)| (pipeline, set))
        };
        if merge.is_some() || outline.is_some() || reads_pixel_keys {
            // The fragments' storage writes (translucent ones, pixel keys), read by the
            // merge, the outline and the silhouettes.
            memory_barrier(
                &self.device,
                command_buffer,
                (
                    vk::PipelineStageFlags2::FRAGMENT_SHADER,
                    vk::AccessFlags2::SHADER_STORAGE_WRITE,
                ),
                (
                    vk::PipelineStageFlags2::FRAGMENT_SHADER,
                    vk::AccessFlags2::SHADER_STORAGE_READ,
                ),
            );
        }
        begin_overlay(&self.device, command_buffer, &self.target.color);
        // The caps are part of the opaque picture: first.
        if let Some(cap_ties) = cap_ties {
            record_fullscreen(&self.device, command_buffer, cap_ties, &[self.frame_set()]);
        }
        let record_depth_overlay = |(pipeline, set): ((vk::Pipeline, vk::PipelineLayout), _)| {
            record_fullscreen(
                &self.device,
                command_buffer,
                pipeline,
                &[self.frame_set(), set],
            );
        };
        [ssao, silhouettes_from(SilhouetteSource::DepthBuffer)]
            .into_iter()
            .flatten()
            .for_each(record_depth_overlay);
        if let Some((targets, merge)) = merge {
            record_fullscreen(
                &self.device,
                command_buffer,
                merge,
                &[self.frame_set(), targets.merge_set.sets[0]],
            );
        }
        silhouettes_from(SilhouetteSource::NearestSurfaces)
            .into_iter()
            .for_each(record_depth_overlay);
        if let Some(outline) = outline {
            record_fullscreen(&self.device, command_buffer, outline, &[self.frame_set()]);
        }
        record_fullscreen(
            &self.device,
            command_buffer,
            background,
            &[self.frame_set()],
        );
        end_overlay(&self.device, command_buffer, &self.target.color);
        Ok(())
    }

    /// The frame uniforms' descriptor set (set 0 of every pipeline).
    pub(crate) fn frame_set(&self) -> vk::DescriptorSet {
        self.frame_sets.sets[0]
    }

    /// The frame's depth image, as a later phase reads it (in [`SUSPENDED_DEPTH_LAYOUT`]).
    pub(crate) fn depth_image(&self) -> &Image {
        &self.target.depth
    }

    /// What a pass renders into: the colour or id image, cleared (loaded when the phase
    /// `resume`s a suspended pass), and the depth, kept for the pick pass (picking reads the
    /// depth under the cursor) and stored when the frame has several phases. With
    /// `secondary`, the pass's contents come from secondary command buffers, which set their
    /// own viewport and scissor. With MSAA the colour pass draws into the multisampled
    /// images and resolves them into these; the pick pass never does.
    fn pass_target(
        &self,
        pass: PassTarget,
        (secondary, resume, phased): (bool, bool, bool),
    ) -> RenderingTarget<'_> {
        let (color, clear_color) = self.pass_image(pass);
        RenderingTarget {
            color,
            clear_color,
            depth: &self.target.depth,
            keep_depth: pass == PassTarget::Pick,
            shade_from_depth: false,
            store_depth: phased,
            extent: self.target.extent(),
            secondary,
            resume,
            extra_colors: &[],
            multisampled: match (pass, &self.target.multisampled) {
                (PassTarget::Color, Some(images)) => Some(Multisampled {
                    color: &images.color,
                    depth: &images.depth,
                    extra_colors: &[],
                    depth_resolve: self.device.depth_resolve_mode(),
                }),
                _ => None,
            },
        }
    }
}

/// Points the frame set's binding 1 at `storage`, the transparency method's storage (the
/// caller makes sure no submitted frame uses the set).
fn name_storage(frame_sets: &DescriptorSets, storage: &Buffer) {
    frame_sets.write_buffer(
        0,
        1,
        vk::DescriptorType::STORAGE_BUFFER,
        storage.raw(),
        vk::WHOLE_SIZE,
    );
}

/// Names `storage` as the pixel keys (binding 7 of the frame set).
fn name_pixel_keys(frame_sets: &DescriptorSets, storage: &Buffer) {
    frame_sets.write_buffer(
        0,
        7,
        vk::DescriptorType::STORAGE_BUFFER,
        storage.raw(),
        vk::WHOLE_SIZE,
    );
}

impl Drop for Renderer {
    fn drop(&mut self) {
        // Resources are destroyed by their own Drop; make sure the GPU is done with them.
        let _ = self.commands.wait();
    }
}

/// A background colour as the uniforms carry it.
fn opaque(color: [f32; 3]) -> [f32; 4] {
    [color[0], color[1], color[2], 1.0]
}
