//! Recording and submitting a frame: its plan ([`FramePlan`]), the shape it takes from the
//! renderer's settings, the list of passes that follows from it (`passes.rs`), the recorders
//! techniques contribute to those passes ([`FrameRecorders`]), the recording of each pass,
//! the replay of an unchanged frame's recording, in the frame slot `slots.rs` hands it.

use std::time::Instant;

use crate::error::{RenderError, RenderResult};
use crate::render::pixel_keys::{self, PixelKeys};
use crate::render::transparency::TransparencyTargets;
use crate::render::{
    split_f64, Camera, FrameStats, FrameUniforms, HighlightStyle, OverlaySets, TransparencyMethod,
    DISPLAY_XRAY,
};
use crate::vk::raw as vk;
use crate::vk::{
    begin_overlay, begin_rendering, end_overlay, end_rendering, memory_barrier, record_fullscreen,
    suspend_rendering, transition, Buffer, GpuTimer, Image, Multisampled, RenderingTarget,
};

use super::passes::{
    FramePass, FramePasses, FrameShape, OverlayDraw, PassTarget, Resources, SilhouetteSource,
    OVERLAY_PASSES,
};
use super::slots::{FrameWait, CULL_VIEW_STRIDE};
use super::{name_pixel_keys, name_storage, opaque, Renderer};

/// What the colour pass clears to: nothing drawn, no coverage (the background goes under
/// it after the rendering).
const UNCOVERED: [f32; 4] = [0.0; 4];

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
    /// What the frame's recording and the techniques' host writes depend on besides the view
    /// (the commands key with the parameter values), none for a pick: a frame with the key of
    /// the last one may run on the GPU while the next is recorded (see `slots.rs`).
    pub frame_key: Option<u64>,
    /// Whether every active technique keeps its per-frame data per frame slot.
    pub keeps_frame_slots: bool,
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

/// What the recording of a frame's passes takes besides the list.
struct PassInputs<'a> {
    /// The frame's command buffer.
    command_buffer: vk::CommandBuffer,
    /// Whether the surfaces' contents come from secondary command buffers.
    secondary: bool,
    /// The transparency method's targets and its merge (pipeline, layout), when the frame
    /// draws translucent surfaces.
    merge: Option<(&'a TransparencyTargets, (vk::Pipeline, vk::PipelineLayout))>,
    /// The set naming the picture's depth, when a pass over the picture reads it.
    depth_set: Option<vk::DescriptorSet>,
    /// Whether the frame hands its depth to the host: the surfaces store it.
    depth_to_host: bool,
}

/// One phase of the surfaces' rendering.
#[derive(Clone, Copy, Debug)]
struct SurfacesRendering {
    /// The image drawn into.
    target: PassTarget,
    /// The phase.
    phase: u32,
    /// Whether it is the last.
    last: bool,
    /// Whether the surfaces have several phases (the depth is then stored between them).
    phased: bool,
}

/// The frame's pass timer while its passes are recorded.
struct PassTimeline {
    /// The slot's timer, taken out of it until the recording ends (none without timestamps).
    timer: Option<GpuTimer>,
    /// The frame's command buffer.
    command_buffer: vk::CommandBuffer,
}

impl PassTimeline {
    /// Ends the span `name` (from the last mark) with a timestamp, where the timer has room.
    fn mark(&mut self, name: &'static str) {
        if let Some(timer) = &mut self.timer {
            timer.mark(self.command_buffer, name);
        }
    }

    /// Ends the last span, `name`, with the frame's last timestamp.
    fn end(&mut self, name: &'static str) {
        if let Some(timer) = &mut self.timer {
            timer.end(self.command_buffer, name);
        }
    }
}

/// What a technique records at one point of the frame: before the pass, inside it (once per
/// phase), between phases, or after it; with the phase.
pub(crate) type Recorder<'a> =
    dyn FnMut(&Renderer, vk::CommandBuffer, u32, &mut FrameStats) -> RenderResult<()> + 'a;

/// Gathers a frame's uploads on the host (written into their buffers, counted in the stats)
/// and returns what their commands depend on: equal keys record equal commands.
pub(crate) type UploadGatherer<'a> = dyn FnMut(&mut FrameStats) -> RenderResult<u64> + 'a;

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
    /// Where the silhouettes of a frame planned as `plan` are found, if it draws them.
    fn silhouette_source(&self, plan: &FramePlan<'_>) -> Option<SilhouetteSource> {
        if !(self.settings.silhouettes && plan.draws_edges && plan.pass == PassTarget::Color) {
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

    /// The shape of a frame planned as `plan` seen from `eye`: what the display mode, the
    /// settings, the section and the device make it draw. The one place that decides which
    /// passes a frame has.
    fn frame_shape(&self, plan: &FramePlan<'_>, eye: glam::DVec3) -> FrameShape {
        let color = plan.pass == PassTarget::Color;
        let silhouettes = self.silhouette_source(plan);
        FrameShape {
            target: plan.pass,
            phases: plan.phases.max(1),
            translucent: color && plan.translucency.is_some(),
            ssao: self.settings.ssao && plan.fills_surfaces && color,
            silhouettes,
            nearest_surfaces: self.records_nearest_surfaces(plan, silhouettes),
            // Caps that tie with another part's surface are painted from the cap keys,
            // which the surfaces record (every mode but wireframe, which draws none).
            cap_ties: color
                && (plan.fills_surfaces || plan.draws_edges)
                && self.device.capabilities().fragment_stores_and_atomics
                && self.settings.section.caps_seen_from(eye),
            outline: self.settings.highlight_style == HighlightStyle::Outline && color,
            depth_to_host: self.settings.depth_to_host && color,
        }
    }

    /// Runs a frame in the next frame slot: its passes planned from its shape, the wait for
    /// earlier frames (`slots.rs`), uniforms, command buffer, each pass recorded in order (the
    /// techniques' where they contribute), submission, timings, and with one frame in flight
    /// the wait for it. A frame whose replay key is that of the recording in its slot's
    /// command buffer submits it again instead.
    pub(crate) fn frame(
        &mut self,
        camera: &Camera,
        plan: FramePlan<'_>,
        mut recorders: FrameRecorders<'_, '_>,
    ) -> RenderResult<FrameStats> {
        let eye = camera.eye();
        let passes = FramePasses::plan(&self.frame_shape(&plan, eye));
        // What the depth image holds once this frame is recorded.
        self.depth_readable = passes
            .iter()
            .any(|pass| matches!(pass, FramePass::DepthToHost | FramePass::PickReadback));
        let display = plan.display | passes.display_bits();
        // The recording holds these passes and no others.
        let replay_key = plan
            .replay_key
            .map(|key| crate::commands_key::mix(key, passes.key()));
        let uniforms = self.uniforms(camera, eye, display);
        let frame_key = plan
            .frame_key
            .map(|key| crate::commands_key::mix(key, passes.key()));
        // The latest finished frame's GPU time, read now that it is done anyway.
        let (slot, previous_gpu_us) = self.slots.begin_frame(FrameWait {
            frame_key,
            replay_key,
            keeps_slots: plan.keeps_frame_slots,
            uploads: plan.uploads_pending,
        })?;
        let surface_writes = passes.surface_writes();
        let translucency = plan
            .translucency
            .filter(|_| surface_writes.has(Resources::TRANSPARENCY));
        if let Some((method, _)) = translucency {
            self.ensure_transparency_targets(method)?;
        }
        if let Some(planes) = surface_writes.key_use().plane_count() {
            self.ensure_pixel_keys(planes)?;
        }
        let depth_set = if passes.overlay_reads().has(Resources::DEPTH) {
            Some(self.ensure_depth_set()?)
        } else {
            None
        };
        let record_start = Instant::now();
        self.slots
            .current_mut()
            .uniforms
            .write(0, bytemuck::bytes_of(&uniforms))?;
        if let Some(bytes) = plan.cull_view {
            self.cull_view
                .write(CULL_VIEW_STRIDE * slot as u64, bytes)?;
        }
        let mut stats = FrameStats {
            overlapped: !self.slots.earlier_frames_finished(),
            ..FrameStats::default()
        };
        if plan.uploads_pending {
            self.record_upload_prologue(&mut recorders, &mut stats)?;
        }
        match (replay_key, self.slots.current().replayable) {
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
            _ => self.slots.current_mut().replayable = None,
        }

        let slot = self.slots.current_mut();
        let command_buffer = slot.commands.begin()?;
        // Taken out of the slot while the passes are recorded, so that they can mark it.
        let mut timeline = PassTimeline {
            timer: slot.pass_timer.take(),
            command_buffer,
        };
        if let Some(timer) = &mut timeline.timer {
            timer.begin(command_buffer);
        }
        after_earlier_frames(&self.device, command_buffer);
        let inputs = PassInputs {
            command_buffer,
            secondary: plan.secondary,
            merge: translucency
                .and(self.on_demand.transparency.as_ref())
                .zip(translucency.map(|(_, merge)| merge)),
            depth_set,
            depth_to_host: passes.iter().any(|pass| *pass == FramePass::DepthToHost),
        };
        let recorded = self
            .record_passes(&passes, &inputs, &mut recorders, &mut stats, &mut timeline)
            .and_then(|()| {
                let last_phase = passes.surface_phases().max(1) - 1;
                (recorders.after)(self, command_buffer, last_phase, &mut stats)?;
                timeline.end("techniques after the passes");
                Ok(())
            });
        self.slots.current_mut().pass_timer = timeline.timer;
        recorded?;
        stats.cpu_record_us = record_start.elapsed().as_secs_f64() * 1e6;
        self.submit_recorded(stats, replay_key, plan.uploads_pending, previous_gpu_us)
    }

    /// Records `passes` in order into `inputs.command_buffer`: the techniques' where they
    /// contribute (preparation, culling phases, the surfaces), the renderer's own (the clears
    /// before the surfaces, the passes over the picture, the pick readback).
    fn record_passes(
        &self,
        passes: &FramePasses,
        inputs: &PassInputs<'_>,
        recorders: &mut FrameRecorders<'_, '_>,
        stats: &mut FrameStats,
        timeline: &mut PassTimeline,
    ) -> RenderResult<()> {
        let command_buffer = inputs.command_buffer;
        let phased = passes.surface_phases() > 1;
        let mut over_picture = false;
        for pass in passes.iter() {
            match *pass {
                FramePass::Prepare => (recorders.before)(self, command_buffer, 0, stats)?,
                FramePass::Cull { phase } => {
                    (recorders.between)(self, command_buffer, phase, stats)?;
                }
                FramePass::Surfaces {
                    phase,
                    last,
                    target,
                    writes,
                } => {
                    if phase == 0 {
                        self.record_surface_clears(command_buffer, writes, inputs);
                    }
                    let rendering = SurfacesRendering {
                        target,
                        phase,
                        last,
                        phased,
                    };
                    self.record_surfaces(rendering, inputs, recorders, stats)?;
                }
                FramePass::Overlay { index, reads } => {
                    if !over_picture {
                        self.begin_over_picture(command_buffer, passes);
                        over_picture = true;
                    }
                    self.record_overlay(index, reads, inputs)?;
                }
                FramePass::PickReadback => self.record_pick_readback(command_buffer),
                FramePass::DepthToHost => {
                    if over_picture {
                        // A barrier may not stand inside the passes' rendering.
                        end_overlay(&self.device, command_buffer, &self.target.color);
                        over_picture = false;
                    }
                    self.record_depth_to_host(command_buffer, inputs.depth_set.is_some());
                }
            }
            timeline.mark(pass.name());
        }
        if over_picture {
            end_overlay(&self.device, command_buffer, &self.target.color);
        }
        Ok(())
    }

    /// Submits the frame just recorded (after its prologue when it `uploaded`), keeps it for
    /// replays when it is the steady recording of `replay_key`, and with one frame in flight
    /// waits for it.
    fn submit_recorded(
        &mut self,
        mut stats: FrameStats,
        replay_key: Option<u64>,
        uploaded: bool,
        previous_gpu_us: Option<f64>,
    ) -> RenderResult<FrameStats> {
        let submit_start = Instant::now();
        let slot = self.slots.current_mut();
        slot.commands.submit()?;
        slot.timers_submitted();
        slot.submission_uploaded = uploaded;
        stats.cpu_submit_us = submit_start.elapsed().as_secs_f64() * 1e6;
        // Uploads are not part of the recording: they go in the prologue.
        self.slots.keep_recording(replay_key, stats);
        stats.gpu_us = self.finish_or_keep_in_flight(previous_gpu_us)?;
        Ok(stats)
    }

    /// The frame uniforms of a frame seen by `camera` from `eye` with `display` bits: the eye
    /// in f64 split for relative-to-eye positions on the GPU, the section, background and
    /// palette.
    fn uniforms(&self, camera: &Camera, eye: glam::DVec3, display: u32) -> FrameUniforms {
        let (eye_high, eye_low) = split_f64(eye);
        let mut view_rotation = camera.view;
        view_rotation.w_axis = glam::DVec4::W;
        let (width, height) = self.size();
        let [r, g, b] = self.settings.palette.highlight;
        FrameUniforms {
            projection: camera.projection.as_mat4().to_cols_array_2d(),
            view_rotation: view_rotation.as_mat4().to_cols_array_2d(),
            eye_high: [eye_high[0], eye_high[1], eye_high[2], 0.0],
            eye_low: [eye_low[0], eye_low[1], eye_low[2], 0.0],
            light: [0.22, 0.68, 0.35, 0.0],
            section_planes: self.settings.section.eye_relative(eye),
            section_colors: self.settings.section.colors(),
            section: [self.settings.section.flags(), 0, 0, 0],
            target: [width, height, display, 0],
            background_top: opaque(self.settings.background.top),
            background_bottom: opaque(self.settings.background.bottom),
            edge_color: opaque(self.settings.palette.edges),
            highlight: [r, g, b, self.settings.palette.outline_width as f32],
        }
    }

    /// Gathers the frame's uploads and records their commands into the prologue, unless the
    /// last prologue holds the same commands (then it is submitted again as it is).
    fn record_upload_prologue(
        &mut self,
        recorders: &mut FrameRecorders<'_, '_>,
        stats: &mut FrameStats,
    ) -> RenderResult<()> {
        let key = (recorders.gather_uploads)(stats)?;
        let slot = self.slots.current_mut();
        if slot.commands.reuse_prologue(key) {
            return Ok(());
        }
        let command_buffer = slot.commands.begin_prologue()?;
        if let Some(timer) = &mut slot.upload_timer {
            timer.begin(command_buffer);
        }
        after_earlier_frames(&self.device, command_buffer);
        (recorders.uploads)(self, command_buffer, 0, stats)?;
        let slot = self.slots.current_mut();
        if let Some(timer) = &mut slot.upload_timer {
            timer.end(command_buffer, "uploads");
        }
        Ok(slot.commands.end_prologue(key)?)
    }

    /// Before the surfaces: clears the transparency method's storage and the pixel keys'
    /// planes they `write`.
    fn record_surface_clears(
        &self,
        command_buffer: vk::CommandBuffer,
        writes: Resources,
        inputs: &PassInputs<'_>,
    ) {
        if let Some((targets, _)) = inputs.merge {
            self.record_storage_clear(
                command_buffer,
                &targets.attachments.storage,
                (0, targets.attachments.cleared_bytes),
                0,
            );
        }
        if let Some((keys, span)) = self
            .on_demand
            .pixel_keys
            .as_ref()
            .and_then(|keys| Some((keys, keys.span(writes.key_use())?)))
        {
            self.record_storage_clear(command_buffer, &keys.buffer, span, pixel_keys::NO_SURFACE);
        }
    }

    /// Records one phase of the surfaces: the rendering begun (or resumed), the techniques'
    /// commands inside it, and the rendering suspended (the depth so far readable by the next
    /// culling phase) or, after the last phase, ended.
    fn record_surfaces(
        &self,
        rendering: SurfacesRendering,
        inputs: &PassInputs<'_>,
        recorders: &mut FrameRecorders<'_, '_>,
        stats: &mut FrameStats,
    ) -> RenderResult<()> {
        let command_buffer = inputs.command_buffer;
        let transparency = inputs.merge.map(|(targets, _)| targets);
        let extra_colors: Vec<(&Image, vk::ClearColorValue)> = transparency
            .map(|t| {
                let shared = &t.attachments;
                shared
                    .images
                    .iter()
                    .zip(shared.clears.iter().copied())
                    .collect()
            })
            .unwrap_or_default();
        let multisampled_extra_colors: Vec<&Image> = transparency
            .map(|t| t.attachments.multisampled_images.iter().collect())
            .unwrap_or_default();
        let phase = rendering.phase;
        let target = self.pass_target(
            rendering.target,
            (inputs.secondary, phase > 0, rendering.phased),
        );
        let target = RenderingTarget {
            extra_colors: &extra_colors,
            shade_from_depth: inputs.depth_set.is_some(),
            keep_depth: target.keep_depth || inputs.depth_to_host,
            multisampled: target.multisampled.map(|m| Multisampled {
                extra_colors: &multisampled_extra_colors,
                ..m
            }),
            ..target
        };
        begin_rendering(&self.device, command_buffer, &target);
        (recorders.inside)(self, command_buffer, phase, stats)?;
        if rendering.last {
            end_rendering(&self.device, command_buffer, &target);
        } else {
            suspend_rendering(&self.device, command_buffer, &target);
        }
        Ok(())
    }

    /// Leaves the depth in `TRANSFER_SRC_OPTIMAL` for the host to copy: the surfaces' end did
    /// so already unless passes over the picture `read_depth` as shaders do.
    fn record_depth_to_host(&self, command_buffer: vk::CommandBuffer, read_depth: bool) {
        if !read_depth {
            return;
        }
        transition(
            &self.device,
            command_buffer,
            self.target.depth.raw(),
            vk::ImageAspectFlags::DEPTH,
            (
                vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                vk::PipelineStageFlags2::FRAGMENT_SHADER,
                vk::AccessFlags2::SHADER_SAMPLED_READ,
            ),
            (
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                vk::PipelineStageFlags2::COPY,
                vk::AccessFlags2::TRANSFER_READ,
            ),
        );
    }

    /// With one frame in flight, waits for the frame just submitted and returns its GPU time;
    /// with more, leaves it running and returns `previous_gpu_us`, the frame before's.
    fn finish_or_keep_in_flight(
        &mut self,
        previous_gpu_us: Option<f64>,
    ) -> RenderResult<Option<f64>> {
        if self.slots.in_flight() > 1 {
            return Ok(previous_gpu_us);
        }
        self.finish()?;
        let current = self.slots.current_index();
        Ok(self.slots.read_gpu_time(current)?)
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
        let slot = self.slots.current_mut();
        slot.commands.resubmit()?;
        slot.timers_submitted();
        slot.submission_uploaded = uploaded;
        let stats = FrameStats {
            cpu_record_us: (submit_start - start).as_secs_f64() * 1e6,
            cpu_submit_us: submit_start.elapsed().as_secs_f64() * 1e6,
            replayed: true,
            overlapped: !self.slots.earlier_frames_finished(),
            ..recorded
        };
        Ok(FrameStats {
            gpu_us: self.finish_or_keep_in_flight(previous_gpu_us)?,
            ..stats
        })
    }

    /// The image and clear value of a pass target.
    fn pass_image(&self, pass: PassTarget) -> (&Image, vk::ClearColorValue) {
        match (pass, &self.on_demand.pick) {
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
            .on_demand
            .transparency
            .as_ref()
            .is_some_and(|t| t.fit(method, extent, samples))
        {
            return Ok(());
        }
        // Frames in flight and the recorded ones name the old targets.
        self.finish()?;
        self.forget_recording();
        self.drop_transparency_targets();
        let targets = TransparencyTargets::new(
            &self.device,
            method,
            (extent, samples),
            self.pipelines.merge_set_layout(),
        )?;
        name_storage(&self.frame_sets, &targets.attachments.storage);
        self.on_demand.transparency = Some(targets);
        Ok(())
    }

    /// Makes pixel keys of at least `planes` planes for the target's size unless they are
    /// made (as many as any frame so far needed, so that modes drawn in turn do not remake
    /// them), and names them in the frame set (the GPU is idle: the caller waited for the
    /// last frame; the recorded frame named the old binding and is forgotten).
    fn ensure_pixel_keys(&mut self, planes: u64) -> RenderResult<()> {
        let extent = self.target.extent();
        let made = self.on_demand.pixel_keys.as_ref();
        if made.is_some_and(|k| k.holds(extent, planes)) {
            return Ok(());
        }
        let planes = match made {
            Some(keys) if keys.extent == extent => planes.max(keys.planes()),
            _ => planes,
        };
        // Frames in flight and the recorded ones name the old keys.
        self.finish()?;
        self.forget_recording();
        let keys = PixelKeys::new(&self.device, extent, planes)?;
        name_pixel_keys(&self.frame_sets, &keys.buffer);
        self.on_demand.pixel_keys = Some(keys);
        Ok(())
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

    /// Before the first pass over the picture: a barrier where they read what the surfaces
    /// wrote through storage (translucent fragments, pixel keys), then the picture made a
    /// colour attachment again.
    fn begin_over_picture(&self, command_buffer: vk::CommandBuffer, passes: &FramePasses) {
        if passes.overlays_read_storage() {
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
    }

    /// Records the pass over the picture at `index` of [`OVERLAY_PASSES`], binding the frame
    /// set and what it `reads` beside it: the depth set, or the transparency method's targets.
    fn record_overlay(
        &self,
        index: usize,
        reads: Resources,
        inputs: &PassInputs<'_>,
    ) -> RenderResult<()> {
        let overlay = OVERLAY_PASSES.get(index).ok_or_else(|| {
            RenderError::InvalidUse(format!("no pass over the picture at index {index}"))
        })?;
        let (pipeline, second_set) = match overlay.draw {
            OverlayDraw::Fullscreen(shader) => {
                let second_set = match shader.sets {
                    OverlaySets::Frame => None,
                    OverlaySets::FrameAndDepth => Some(inputs.depth_set.ok_or_else(|| {
                        RenderError::InvalidUse(format!(
                            "{} reads {reads:?} without the picture's depth",
                            overlay.name
                        ))
                    })?),
                };
                (self.pipelines.overlay(index, &shader)?, second_set)
            }
            OverlayDraw::TransparencyMerge => {
                let (targets, merge) = inputs.merge.ok_or_else(|| {
                    RenderError::InvalidUse(format!(
                        "{} without the transparency method's targets",
                        overlay.name
                    ))
                })?;
                (merge, Some(targets.merge_set.sets[0]))
            }
        };
        let frame_set = self.frame_set();
        let sets: &[vk::DescriptorSet] = match &second_set {
            Some(set) => &[frame_set, *set],
            None => &[frame_set],
        };
        record_fullscreen(&self.device, inputs.command_buffer, pipeline, sets);
        Ok(())
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

/// Orders this frame's work after every earlier frame's on the queue (the first command of
/// the frame's buffers): with frames in flight, the next frame is submitted while the last
/// still runs, and its uploads, clears, culling and attachments must not overtake the last
/// frame's reads and writes of the same buffers and images.
fn after_earlier_frames(device: &crate::vk::Device, command_buffer: vk::CommandBuffer) {
    memory_barrier(
        device,
        command_buffer,
        (
            vk::PipelineStageFlags2::ALL_COMMANDS,
            vk::AccessFlags2::MEMORY_WRITE,
        ),
        (
            vk::PipelineStageFlags2::ALL_COMMANDS,
            vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE,
        ),
    );
}
