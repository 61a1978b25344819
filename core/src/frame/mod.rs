//! The frame: a [`Renderer`] (an offscreen target, the frame uniforms and set, command
//! buffers, timers, frames in flight and the settings a host changes between frames) and the
//! frames drawn into it. `techniques.rs` plans a frame of the GPU scene with the active
//! techniques (`Renderer::render_techniques`, `Renderer::pick_techniques`): CPU culling, the
//! surface pass set, uploads, the recorders each technique contributes; `gpu_cull.rs` drives a
//! GPU culler's phases; `passes.rs` turns the frame's shape into its ordered list of passes
//! (preparation, culling phases, surfaces, the passes over the picture, the pick readback);
//! `record.rs` records each pass and submits the frame (or replays an unchanged frame's
//! recording); `slots.rs` keeps what each frame in flight owns and decides how long a frame
//! waits for earlier ones; `output.rs` reads the image back and writes PNGs. The pieces it draws with (camera, sections, targets, pipelines over the picture)
//! are in [`crate::render`].

mod gpu_cull;
mod output;
mod passes;
mod record;
mod slots;
mod techniques;

pub use output::SaveError;
pub use slots::MAX_FRAMES_IN_FLIGHT;

use std::sync::Arc;

use crate::error::{RenderError, RenderResult};
use crate::vk::raw as vk;

use crate::gpu_scene::{FrameResources, TextureBindings};
use crate::render::pick::{self, PickTarget, PixelRect};
use crate::render::pixel_keys::PixelKeys;
use crate::render::transparency::{storage_buffer, TransparencyTargets};
use crate::render::{
    Background, HighlightStyle, Palette, Pipelines, Section, TEXTURE_TABLE_BINDING,
};
use crate::vk::{
    Buffer, DepthSharing, DescriptorSets, Device, Image, MemoryLocation, OffscreenTarget,
};
use slots::{FrameSlots, CULL_VIEW_STRIDE};

/// Renders scenes into an offscreen color + depth target.
pub struct Renderer {
    device: Arc<Device>,
    target: OffscreenTarget,
    pipelines: Arc<Pipelines>,
    /// One frame set per frame slot (set `i` names slot `i`'s uniforms at binding 0; every
    /// other binding names the same resources in all of them).
    frame_sets: DescriptorSets,
    /// What GPU cullers read of the view (`CadrGpuCullView`), host-written every frame, one
    /// per frame slot [`CULL_VIEW_STRIDE`] bytes apart.
    cull_view: Buffer,
    /// The frames in flight and what each owns.
    slots: FrameSlots,
    /// The storage the frame set names while no method's storage is made.
    placeholder_storage: Buffer,
    /// The generation of the GPU scene resources the frame set names, if any.
    bound_scene: Option<u64>,
    settings: FrameSettings,
    on_demand: OnDemandTargets,
    /// Whether the depth image holds the last frame's depth in `TRANSFER_SRC_OPTIMAL` (that
    /// frame kept it for the host, or was a pick).
    depth_readable: bool,
}

/// What a host sets on a renderer and every later frame draws with.
struct FrameSettings {
    /// The section planes and caps every pass applies.
    section: Section,
    /// The background every picture is drawn over.
    background: Background,
    /// The colours of edge lines and highlights.
    palette: Palette,
    /// Whether frames that fill surfaces get screen-space ambient occlusion.
    ssao: bool,
    /// Whether the edge display modes draw silhouette edges with the feature edges.
    silhouettes: bool,
    /// Whether materials' textures are sampled (vertex colours apply either way).
    textures: bool,
    /// How highlighted parts are drawn.
    highlight_style: HighlightStyle,
    /// Whether colour frames leave their depth for the host ([`Renderer::depth_for_host`]).
    depth_to_host: bool,
}

/// What frames make on first need besides the picture, kept while the size (and method)
/// stays the same.
#[derive(Default)]
struct OnDemandTargets {
    /// What the transparency method of the last frame with translucent surfaces drew into.
    transparency: Option<TransparencyTargets>,
    /// The pixel keys at the target's size (made by the first frame that needs them: with the
    /// outline style, the silhouettes' nearest surfaces or the cap keys), which binding 7 of
    /// the frame set names; otherwise the placeholder storage is named there.
    pixel_keys: Option<PixelKeys>,
    /// The set naming the target's depth for the passes over the picture that read it
    /// (ambient occlusion, silhouettes); made on first use, dropped when the target is remade.
    depth_set: Option<DescriptorSets>,
    /// The id target and its readback, created on the first pick.
    pick: Option<PickTarget>,
}

impl Renderer {
    /// Creates a renderer with a `width` × `height` target.
    pub fn new(device: &Arc<Device>, width: u32, height: u32) -> RenderResult<Self> {
        // A new renderer hands no depth to the host: it shares the device's depth.
        let target = OffscreenTarget::new(device, (width, height), 1, DepthSharing::Shared)?;
        let pipelines = Pipelines::shared(device, passes::OVERLAY_PASSES.len())?;
        let slots = FrameSlots::new(device)?;
        let layouts = vec![pipelines.frame_set_layout(); slots.all().len()];
        let frame_sets = DescriptorSets::new(device, "frame", &layouts)?;
        for (index, slot) in slots.all().iter().enumerate() {
            frame_sets.write_buffer(
                index,
                0,
                vk::DescriptorType::UNIFORM_BUFFER,
                slot.uniforms.raw(),
                vk::WHOLE_SIZE,
            );
        }
        let placeholder_storage = storage_buffer(device, 0)?;
        name_storage(&frame_sets, &placeholder_storage);
        name_pixel_keys(&frame_sets, &placeholder_storage);
        let cull_view = Buffer::new(
            device,
            "gpu cull view",
            CULL_VIEW_STRIDE * slots.all().len() as u64,
            vk::BufferUsageFlags::UNIFORM_BUFFER,
            MemoryLocation::CpuToGpu,
        )?;
        Ok(Self {
            device: Arc::clone(device),
            target,
            pipelines,
            frame_sets,
            cull_view,
            slots,
            placeholder_storage,
            bound_scene: None,
            settings: FrameSettings {
                section: Section::none(),
                background: Background::default(),
                palette: Palette::default(),
                ssao: false,
                silhouettes: true,
                textures: true,
                highlight_style: HighlightStyle::default(),
                depth_to_host: false,
            },
            on_demand: OnDemandTargets::default(),
            depth_readable: false,
        })
    }

    /// The background pictures are drawn over ([`Background::GRADIENT`] by default).
    pub fn background(&self) -> Background {
        self.settings.background
    }

    /// Sets the background; the next frame draws it (through the frame's uniforms, so a
    /// recorded frame replays with it).
    pub fn set_background(&mut self, background: Background) -> RenderResult<()> {
        background.validate().map_err(RenderError::InvalidUse)?;
        self.settings.background = background;
        Ok(())
    }

    /// The colours of edge lines and highlights and the outline band's width
    /// ([`Palette::DEFAULT`] by default).
    pub fn palette(&self) -> Palette {
        self.settings.palette
    }

    /// Sets the colours of edge lines and highlights and the outline band's width; the next
    /// frame draws with them (through the frame's uniforms, so a recorded frame replays with
    /// them). Refuses colours outside 0..1 and widths outside 1 to
    /// [`Palette::MAX_OUTLINE_WIDTH`], keeping the palette it had.
    pub fn set_palette(&mut self, palette: Palette) -> RenderResult<()> {
        palette.validate().map_err(RenderError::InvalidUse)?;
        self.settings.palette = palette;
        Ok(())
    }

    /// Whether frames that fill surfaces (solid, edges, X-ray) get screen-space ambient
    /// occlusion: creases, corners and gaps between parts darkened from the depth (off by
    /// default).
    pub fn ssao(&self) -> bool {
        self.settings.ssao
    }

    /// Whether colour frames keep their depth for the host (see [`Renderer::depth_for_host`]).
    pub fn depth_to_host(&self) -> bool {
        self.settings.depth_to_host
    }

    /// Makes colour frames store their depth and leave it in `TRANSFER_SRC_OPTIMAL` for the
    /// host to copy (a host compositing its own drawing with cadr's frames), or not (the
    /// default: the depth is then not stored, which costs nothing).
    pub fn set_depth_to_host(&mut self, on: bool) -> RenderResult<()> {
        if on != self.settings.depth_to_host {
            self.finish()?;
            // The recorded frame has (or lacks) the pass that hands the depth over, and draws
            // into the depth this renderer is about to leave.
            self.forget_recording();
            self.settings.depth_to_host = on;
            self.target.set_depth_sharing(self.depth_sharing())?;
            self.depth_readable = false;
            self.on_demand.depth_set = None;
            self.on_demand.pick = None;
        }
        Ok(())
    }

    /// Whether the target's depth is shared with the device's other renderers of its size:
    /// unless frames hand it to the host, a frame's depth is of no use after the frame.
    fn depth_sharing(&self) -> DepthSharing {
        if self.settings.depth_to_host {
            DepthSharing::Own
        } else {
            DepthSharing::Shared
        }
    }

    /// The depth of the last colour frame when frames keep it for the host
    /// ([`Renderer::set_depth_to_host`]): one-sample `D32_SFLOAT` (resolved from the
    /// multisampled depth with MSAA), 0 at the near plane and 1 at the far plane and where
    /// nothing is drawn, in `TRANSFER_SRC_OPTIMAL` until the next frame. It is the opaque
    /// surfaces' depth: translucent surfaces (and X-ray's) write none.
    pub fn depth_for_host(&self) -> Option<&Image> {
        self.settings.depth_to_host.then_some(&self.target.depth)
    }

    /// Turns screen-space ambient occlusion on or off (see [`Renderer::ssao`]); the next frame
    /// draws with it.
    pub fn set_ssao(&mut self, on: bool) -> RenderResult<()> {
        if on != self.settings.ssao {
            self.finish()?;
            // The recorded frame has (or lacks) the occlusion pass.
            self.forget_recording();
            self.settings.ssao = on;
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
        self.settings.silhouettes
    }

    /// Turns silhouette edges on or off (see [`Renderer::silhouettes`]); the next frame
    /// draws with it.
    pub fn set_silhouettes(&mut self, on: bool) -> RenderResult<()> {
        if on != self.settings.silhouettes {
            self.finish()?;
            // The recorded frame has (or lacks) the silhouettes pass.
            self.forget_recording();
            self.settings.silhouettes = on;
        }
        Ok(())
    }

    /// How highlighted parts are drawn ([`HighlightStyle::Tint`] by default).
    pub fn highlight_style(&self) -> HighlightStyle {
        self.settings.highlight_style
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
        if style != self.settings.highlight_style {
            self.finish()?;
            // The recorded frame has (or lacks) the outline's clear and pass.
            self.forget_recording();
            self.settings.highlight_style = style;
            self.drop_pixel_keys();
        }
        Ok(())
    }

    /// Whether materials' textures are sampled (on by default). Vertex colours apply either way.
    pub fn textures(&self) -> bool {
        self.settings.textures
    }

    /// Turns the sampling of materials' textures on or off (`cadr render --no-textures`); the
    /// next frame draws with it (it reaches the shaders through the frame uniforms, so a
    /// replayed frame follows too). A BLEND material that is translucent only through its
    /// texture still goes through the translucent pass, where it comes out opaque.
    pub fn set_textures(&mut self, on: bool) {
        self.settings.textures = on;
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
        for set in 0..self.frame_sets.sets.len() {
            name_scene(&self.frame_sets, set, resources);
        }
        self.bound_scene = Some(resources.generation);
        Ok(())
    }

    /// Forgets the frame in the command buffer: the next frame is recorded afresh, whatever
    /// its replay key (it would draw what no longer holds: other passes, bindings or targets).
    fn forget_recording(&mut self) {
        self.slots.forget_recordings();
    }

    /// The depth set of the passes over the picture for the current target (the GPU is
    /// idle: the caller waited for the last frame).
    fn ensure_depth_set(&mut self) -> RenderResult<vk::DescriptorSet> {
        if self.on_demand.depth_set.is_none() {
            let sets = DescriptorSets::new(
                &self.device,
                "picture depth",
                &[self.pipelines.depth_set_layout()],
            )?;
            sets.write_sampled_image(0, 0, self.target.depth.view());
            self.on_demand.depth_set = Some(sets);
        }
        Ok(self
            .on_demand
            .depth_set
            .as_ref()
            .map_or(vk::DescriptorSet::null(), |s| s.sets[0]))
    }

    /// The section planes and caps (none by default).
    pub fn section(&self) -> &Section {
        &self.settings.section
    }

    /// Sets the section planes and caps; the next frame applies them (a recorded frame may be
    /// replayed: they reach the GPU through the frame's uniforms).
    pub fn set_section(&mut self, section: Section) {
        self.settings.section = section;
    }

    /// The device.
    pub fn device(&self) -> &Arc<Device> {
        &self.device
    }

    /// Makes every pipeline of the renderer's own passes over the picture now, which are
    /// otherwise made on the first frame that draws them: a host may call it ahead of its first
    /// frame to take their compilation out of it.
    pub fn make_overlay_pipelines(&self) -> RenderResult<()> {
        for (index, pass) in passes::OVERLAY_PASSES.iter().enumerate() {
            if let passes::OverlayDraw::Fullscreen(shader) = pass.draw {
                self.pipelines.overlay(index, &shader)?;
            }
        }
        Ok(())
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
        self.finish()?;
        // The recorded frame draws into the old target: never submit it again.
        self.forget_recording();
        self.target = OffscreenTarget::new(
            &self.device,
            (width, height),
            self.msaa(),
            self.depth_sharing(),
        )?;
        self.depth_readable = false;
        self.on_demand.depth_set = None;
        self.on_demand.pick = None;
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
        self.target =
            OffscreenTarget::new(&self.device, (width, height), samples, self.depth_sharing())?;
        self.depth_readable = false;
        self.on_demand.depth_set = None;
        self.on_demand.pick = None;
        self.drop_transparency_targets();
        Ok(())
    }

    /// How many frames the GPU may have: 1 (the default) waits for each frame before
    /// returning from it, so its GPU time is known and its picture ready. With 2 or 3 a frame
    /// returns as soon as it is submitted (its picture or pick is waited for when read), so
    /// the host's work for the next frames overlaps the GPU's drawing; each frame has its own
    /// command buffers, uniforms and timers (a frame slot), and a frame waits only for the
    /// one that used its slot before, `frames` frames ago, when nothing but the view changed
    /// since the last frame and every active technique keeps its per-frame data per slot
    /// (`CADR_TRAIT_FRAME_SLOTS`, which cadr's own techniques announce, but the `-threads`
    /// submissions). Otherwise (the scene or the passes changed, the frame uploads moved
    /// parts, picks, or a technique keeps one copy) it waits for every earlier frame, as
    /// with 1. With more than 1, [`crate::render::FrameStats::gpu_us`] is the GPU time of the latest frame
    /// known to have finished. Lowering the count waits for every frame.
    pub fn set_frames_in_flight(&mut self, frames: u32) -> RenderResult<()> {
        if !(1..=MAX_FRAMES_IN_FLIGHT).contains(&frames) {
            return Err(RenderError::InvalidUse(format!(
                "{frames} frames in flight: expected 1 to {MAX_FRAMES_IN_FLIGHT}"
            )));
        }
        Ok(self.slots.set_in_flight(frames)?)
    }

    /// How many frames the GPU may have (see [`Renderer::set_frames_in_flight`]).
    pub fn frames_in_flight(&self) -> u32 {
        self.slots.in_flight()
    }

    /// Waits until the GPU has finished every frame (their pictures, pick results and
    /// buffers are then the host's to read or change).
    pub fn finish(&self) -> RenderResult<()> {
        Ok(self.slots.wait_all()?)
    }

    /// The GPU time of each pass of the frame the last [`crate::render::FrameStats::gpu_us`]
    /// reported (the last frame with one frame in flight, the latest finished one with more),
    /// in microseconds, in the order drawn: its uploads where it had any, the preparation with
    /// the GPU culler's first phase, each culler phase and surfaces phase after, each pass over
    /// the picture, and the techniques' work after the passes (`FramePass::name` names them).
    /// Together they make that `gpu_us`. Empty while no time is known, and where the queue has
    /// no timestamps. Read when the frame's time was: this waits for nothing.
    pub fn gpu_pass_times(&self) -> &[(&'static str, f64)] {
        self.slots.pass_times()
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
        match &mut self.on_demand.pick {
            Some(target) => target.prepare(rect),
            None => {
                self.on_demand.pick =
                    Some(PickTarget::new(&self.device, self.target.extent(), rect)?);
                Ok(())
            }
        }
    }

    /// Records the copy of the prepared rectangle's ids and depths (after the pick pass).
    pub(crate) fn record_pick_readback(&self, command_buffer: vk::CommandBuffer) {
        if let Some(target) = &self.on_demand.pick {
            target.record_readback(&self.device, command_buffer, &self.target.depth);
        }
    }

    /// The prepared rectangle's samples from the last pick pass: the pixels covered by a
    /// pickable instance.
    pub(crate) fn pick_samples(&self) -> RenderResult<Vec<pick::PickSample>> {
        self.finish()?;
        match &self.on_demand.pick {
            Some(target) => target.samples(),
            None => Ok(Vec::new()),
        }
    }

    /// The buffer GPU cullers read the view from and the offset of the current frame's
    /// `CadrGpuCullView` in it.
    pub(crate) fn cull_view_buffer(&self) -> (vk::Buffer, u64) {
        let offset = CULL_VIEW_STRIDE * self.slots.current_index() as u64;
        (self.cull_view.raw(), offset)
    }

    /// The frame slot of the frame being recorded, as techniques see it on the scene view.
    pub(crate) fn frame_slot(&self) -> cadr_plugin_abi::CadrFrameSlot {
        cadr_plugin_abi::CadrFrameSlot {
            header: cadr_plugin_abi::CadrExtension {
                size: std::mem::size_of::<cadr_plugin_abi::CadrFrameSlot>() as u32,
                kind: cadr_plugin_abi::CADR_EXTENSION_FRAME_SLOT,
                next: std::ptr::null(),
            },
            slot: self.slots.current_index() as u32,
            slot_count: self.slots.in_flight(),
            earlier_frames_finished: u32::from(self.slots.earlier_frames_finished()),
            reserved: 0,
        }
    }

    /// Forgets the pixel keys; the frame set names the placeholder storage there again.
    fn drop_pixel_keys(&mut self) {
        if self.on_demand.pixel_keys.take().is_some() {
            name_pixel_keys(&self.frame_sets, &self.placeholder_storage);
        }
    }

    /// Forgets the transparency targets; the frame set names the placeholder storage again.
    fn drop_transparency_targets(&mut self) {
        if self.on_demand.transparency.take().is_some() {
            name_storage(&self.frame_sets, &self.placeholder_storage);
        }
    }

    /// The frame set of the frame being recorded (set 0 of every pipeline).
    pub(crate) fn frame_set(&self) -> vk::DescriptorSet {
        self.frame_sets.sets[self.slots.current_index()]
    }

    /// The frame's depth image, as a later phase reads it (in [`SUSPENDED_DEPTH_LAYOUT`]).
    pub(crate) fn depth_image(&self) -> &Image {
        &self.target.depth
    }
}

/// Points set `set` of the frame sets at the scene's `resources` (bindings 2–6, 8 and the
/// texture table 9).
fn name_scene(frame_sets: &DescriptorSets, set: usize, resources: &FrameResources) {
    let storage = vk::DescriptorType::STORAGE_BUFFER;
    frame_sets.write_buffer(set, 2, storage, resources.records, vk::WHOLE_SIZE);
    frame_sets.write_buffer(set, 3, storage, resources.material_textures, vk::WHOLE_SIZE);
    frame_sets.write_buffer(set, 4, storage, resources.vertex_attributes, vk::WHOLE_SIZE);
    match resources.textures {
        TextureBindings::Array(view) => {
            frame_sets.write_combined_image(set, 5, view, resources.linear_sampler);
            frame_sets.write_combined_image(set, 6, view, resources.nearest_sampler);
        }
        TextureBindings::Table(views) => {
            frame_sets.write_sampler(set, 5, resources.linear_sampler);
            frame_sets.write_sampler(set, 6, resources.nearest_sampler);
            // Runs of filled slots, one write each; empty slots stay unwritten (the table is
            // partially bound, and no material names them).
            let mut first = 0;
            for run in views.split(|view| *view == vk::ImageView::null()) {
                frame_sets.write_sampled_images(set, TEXTURE_TABLE_BINDING, first, run);
                first += run.len() as u32 + 1;
            }
        }
    }
    frame_sets.write_buffer(set, 8, storage, resources.cull_entries, vk::WHOLE_SIZE);
}

/// Points binding 1 of every frame set at `storage`, the transparency method's storage (the
/// caller makes sure no submitted frame uses the sets).
fn name_storage(frame_sets: &DescriptorSets, storage: &Buffer) {
    name_in_every_set(frame_sets, 1, storage);
}

/// Names `storage` as the pixel keys (binding 7 of every frame set).
fn name_pixel_keys(frame_sets: &DescriptorSets, storage: &Buffer) {
    name_in_every_set(frame_sets, 7, storage);
}

/// Points storage-buffer `binding` of every frame set at `storage` (whole range).
fn name_in_every_set(frame_sets: &DescriptorSets, binding: u32, storage: &Buffer) {
    for set in 0..frame_sets.sets.len() {
        frame_sets.write_buffer(
            set,
            binding,
            vk::DescriptorType::STORAGE_BUFFER,
            storage.raw(),
            vk::WHOLE_SIZE,
        );
    }
}

impl Drop for Renderer {
    fn drop(&mut self) {
        // Resources are destroyed by their own Drop; make sure the GPU is done with them.
        let _ = self.slots.wait_all();
    }
}

/// A background colour as the uniforms carry it.
fn opaque(color: [f32; 3]) -> [f32; 4] {
    [color[0], color[1], color[2], 1.0]
}
