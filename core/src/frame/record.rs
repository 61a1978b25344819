//! Recording and submitting a frame: its plan ([`FramePlan`]), the recorders techniques
//! contribute at each point of it ([`FrameRecorders`]), the pass and its phases, the passes
//! over the picture (merge, ambient occlusion, silhouettes, outline, cap ties, background),
//! the replay of an unchanged frame's recording, and frames in flight.

use std::time::Instant;

use crate::error::RenderResult;
use crate::render::pixel_keys::{self, KeyUse, PixelKeys};
use crate::render::transparency::TransparencyTargets;
use crate::render::{
    split_f64, Camera, FrameStats, FrameUniforms, HighlightStyle, TransparencyMethod,
    DISPLAY_CAP_KEYS, DISPLAY_NEAREST_SURFACES, DISPLAY_XRAY,
};
use crate::vk::raw as vk;
use crate::vk::{
    begin_overlay, begin_rendering, end_overlay, end_rendering, memory_barrier, record_fullscreen,
    suspend_rendering, Buffer, Image, Multisampled, RenderingTarget,
};

use super::{name_pixel_keys, name_storage, opaque, Renderer};

/// What the colour pass clears to: nothing drawn, no coverage (the background goes under
/// it after the rendering).
const UNCOVERED: [f32; 4] = [0.0; 4];

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

    /// Runs a frame: uniforms, command buffer, target transitions, the technique's commands
    /// before the pass, inside it in `plan.phases` phases (the pass suspended between them, its
    /// depth readable) and after it, submission, timings, and with one frame in flight the
    /// wait for it (with two, the next frame waits instead). A frame whose replay key is
    /// that of the recording in the command buffer submits it again instead.
    pub(crate) fn frame(
        &mut self,
        camera: &Camera,
        plan: FramePlan<'_>,
        mut recorders: FrameRecorders<'_, '_>,
    ) -> RenderResult<FrameStats> {
        let eye = camera.eye();
        let color = plan.pass == PassTarget::Color;
        let outline = self.settings.highlight_style == HighlightStyle::Outline && color;
        let silhouettes = self.silhouette_source(&plan);
        let depth_overlays = DepthOverlays {
            ssao: self.settings.ssao && plan.fills_surfaces && color,
            silhouettes,
            nearest_surfaces: self.records_nearest_surfaces(&plan, silhouettes),
        };
        let nearest_surfaces = depth_overlays.nearest_surfaces;
        // Caps that tie with another part's surface are painted from the cap keys, which the
        // surfaces record (every mode but wireframe, which draws none).
        let cap_keys = color
            && (plan.fills_surfaces || plan.draws_edges)
            && self.device.capabilities().fragment_stores_and_atomics
            && self.settings.section.caps_seen_from(eye);
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
        let uniforms = self.uniforms(camera, eye, display);
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
            self.record_upload_prologue(&mut recorders, &mut stats)?;
        }
        match (replay_key, self.replay.replayable) {
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
            _ => self.replay.replayable = None,
        }

        let command_buffer = self.commands.begin()?;
        if let Some(timer) = &mut self.timers.pass {
            timer.begin(command_buffer);
        }
        let phases = plan.phases.max(1);
        (recorders.before)(self, command_buffer, 0, &mut stats)?;
        let transparency = plan
            .translucency
            .and(self.on_demand.transparency.as_ref())
            .filter(|_| plan.pass == PassTarget::Color);
        let pass = (&plan, transparency, key_use, depth_set.is_some());
        self.record_pass(command_buffer, pass, &mut recorders, &mut stats)?;
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
        if let Some(timer) = &mut self.timers.pass {
            timer.end(command_buffer);
        }
        stats.cpu_record_us = record_start.elapsed().as_secs_f64() * 1e6;
        self.submit_recorded(stats, replay_key, plan.uploads_pending, previous_gpu_us)
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
        self.commands.submit()?;
        self.replay.last_submission_uploaded = uploaded;
        stats.cpu_submit_us = submit_start.elapsed().as_secs_f64() * 1e6;
        // The first recording after a change may do one-time work (new buffers cleared);
        // the second with the same key is the steady frame. Uploads are not part of it: they
        // go in the prologue.
        if replay_key.is_some() && replay_key == self.replay.last_recorded {
            self.replay.replayable = replay_key.map(|key| (key, stats));
        }
        self.replay.last_recorded = replay_key;
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
        if self.commands.reuse_prologue(key) {
            return Ok(());
        }
        let command_buffer = self.commands.begin_prologue()?;
        if let Some(timer) = &mut self.timers.uploads {
            timer.begin(command_buffer);
        }
        (recorders.uploads)(self, command_buffer, 0, stats)?;
        if let Some(timer) = &mut self.timers.uploads {
            timer.end(command_buffer);
        }
        Ok(self.commands.end_prologue(key)?)
    }

    /// Records the pass of `plan` into `command_buffer`: the clears of the transparency
    /// method's storage and of the pixel keys the frame uses (`key_use`), then each phase's
    /// rendering with the techniques' commands inside it and, from phase 1 on, what they record
    /// between phases (the pass suspended, its depth readable). `shade_from_depth`: a pass
    /// over the picture reads the depth afterwards.
    fn record_pass(
        &self,
        command_buffer: vk::CommandBuffer,
        (plan, transparency, key_use, shade_from_depth): (
            &FramePlan<'_>,
            Option<&TransparencyTargets>,
            KeyUse,
            bool,
        ),
        recorders: &mut FrameRecorders<'_, '_>,
        stats: &mut FrameStats,
    ) -> RenderResult<()> {
        let phases = plan.phases.max(1);
        if let Some(targets) = transparency {
            self.record_storage_clear(
                command_buffer,
                &targets.storage,
                (0, targets.cleared_bytes),
                0,
            );
        }
        if let Some((keys, span)) = self
            .on_demand
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
                shade_from_depth,
                multisampled: target.multisampled.map(|m| Multisampled {
                    extra_colors: &multisampled_extra_colors,
                    ..m
                }),
                ..target
            };
            if phase > 0 {
                (recorders.between)(self, command_buffer, phase, stats)?;
            }
            begin_rendering(&self.device, command_buffer, &target);
            (recorders.inside)(self, command_buffer, phase, stats)?;
            if phase + 1 < phases {
                suspend_rendering(&self.device, command_buffer, &target);
            } else {
                end_rendering(&self.device, command_buffer, &target);
            }
        }
        Ok(())
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
        self.replay.last_submission_uploaded = uploaded;
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
        let pass = match &self.timers.pass {
            Some(timer) => timer.elapsed_us()?,
            None => None,
        };
        let uploads = match (&self.timers.uploads, self.replay.last_submission_uploaded) {
            (Some(timer), true) => timer.elapsed_us()?,
            _ => None,
        };
        Ok(pass.map(|pass| pass + uploads.unwrap_or(0.0)))
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
