//! A frame drawn by the active techniques: culling on the CPU (only changed bits applied) or
//! on the GPU (`gpu_cull.rs`: compute work per phase that writes the draws), uploads and the
//! techniques' preparations before the pass, the submission's recording inside it, and the
//! replay key that lets the renderer resubmit a recording nothing has changed. The pick pass is the same frame with the pick pipelines (the same vertex shader,
//! instance ids into the pick target) and a readback of the picked rectangle after it.

use std::cell::RefCell;
use std::ffi::c_void;
use std::time::Instant;

use crate::commands_key::mix;
use crate::error::{RenderError, RenderResult};
use crate::vk::raw::{self as vk, Handle};
use cadr_plugin_abi as abi;

use super::gpu_cull::{cull_view, cull_view_bytes, GpuCuller, PhaseDepth};
use crate::gpu_scene::ViewedScene;
use crate::render::pick::{PickSample, PixelRect};
use crate::render::{Camera, FrameStats, Section, TransparencyMethod, MAX_SECTION_PLANES};
use crate::technique::{
    announces, status, Message, PassFilters, PassSet, ShadeMode, SurfaceInputs, TechniqueKind,
    TechniquePipelines, Techniques,
};
use crate::vk::{memory_barrier, SUSPENDED_DEPTH_LAYOUT};

use super::passes::PassTarget;
use super::record::{FramePlan, FrameRecorders};
use super::Renderer;

impl Renderer {
    /// Renders one frame of `scene` with the active techniques and reports its cost. The CPU
    /// time covers culling, the techniques' preparation, recording and submission.
    pub fn render_techniques(
        &mut self,
        scene: &mut ViewedScene<'_>,
        techniques: &mut Techniques,
        camera: &Camera,
    ) -> RenderResult<FrameStats> {
        let mode = techniques.shade_mode();
        let translucency = scene.scene.has_translucency(self.textures());
        let dashed_hidden = mode == ShadeMode::HiddenLine && techniques.dashed_hidden_lines();
        let caps_over_lines = matches!(mode, ShadeMode::Edges | ShadeMode::HiddenLine)
            && self.section().caps_seen_from(camera.eye());
        let shaded = |back_faces_culled: bool| PassSet::Shaded {
            mode,
            translucent: mode == ShadeMode::XRay || (mode.shows_translucency() && translucency),
            samples: self.msaa(),
            dashed_hidden,
            lines_through_translucent: mode == ShadeMode::HiddenLine && translucency,
            caps_over_lines,
            hidden_silhouettes: dashed_hidden
                && self.silhouettes()
                && self.device().capabilities().geometry_shader,
            back_faces_culled,
            face_pipelines_picked_by_gpu: back_faces_culled
                && techniques.submission_switches_pipelines(),
            inputs: self.surface_inputs(&*scene.scene),
        };
        let back_faces_culled =
            techniques.culler_routes_back_faces() && shaded(false).may_split_back_faces();
        let passes = shaded(back_faces_culled);
        self.draw_techniques(scene, techniques, camera, passes)
    }

    /// Runs the pick pass of the active techniques over `scene` and reads `rect` back: the
    /// pixels covered by pickable instances, with their instance and depth. Hidden instances
    /// are not drawn and instances that are not pickable let the click through.
    pub fn pick_techniques(
        &mut self,
        scene: &mut ViewedScene<'_>,
        techniques: &mut Techniques,
        camera: &Camera,
        rect: PixelRect,
    ) -> RenderResult<Vec<PickSample>> {
        self.prepare_pick(rect)?;
        let passes = PassSet::Pick {
            through_translucent: techniques.pick_through_translucent(),
            inputs: self.surface_inputs(&*scene.scene),
        };
        self.draw_techniques(scene, techniques, camera, passes)?;
        self.pick_samples()
    }

    /// Draws `passes` of `scene` with the active techniques: culling, the plan of the frame
    /// (its commands key, replay key, display bits, GPU culler phases) and the recorders each
    /// technique contributes, which [`Renderer::frame`] runs.
    fn draw_techniques(
        &mut self,
        scene: &mut ViewedScene<'_>,
        techniques: &mut Techniques,
        camera: &Camera,
        passes: PassSet,
    ) -> RenderResult<FrameStats> {
        techniques.ensure_pipelines(passes)?;
        self.bind_scene(&scene.scene.frame_resources())?;
        let cull_start = Instant::now();
        cull(scene, techniques, camera, self.section())?;
        let techniques = &*techniques;
        let cull_us = cull_start.elapsed().as_secs_f64() * 1e6;

        let secondary = secondary_buffers_allowed(techniques, passes.samples())?;
        let pipelines = techniques.pipelines_for(passes)?;
        // Which instances each pass needs: without textures, parts translucent by their
        // texture only are opaque.
        let pass_filters = pipelines.pass_filters(self.textures());
        let view = scene.view();
        let key = commands_key(
            techniques,
            &view,
            self.size(),
            passes,
            pipelines,
            pass_filters,
        )?;
        let recording = FrameRecording {
            techniques,
            pipelines,
            pass_filters,
            size: self.size(),
            samples: passes.samples(),
            extra_color_formats: extra_color_formats(pipelines),
            key,
            parameter_blocks: techniques.parameter_blocks(),
        };
        let culler = GpuCuller::of(techniques, pipelines.passes.len())?;
        let phases = culler.as_ref().map_or(1, |c| c.phases);
        // Only a GPU culler needs the view relative to the eye.
        let gpu_view = culler
            .as_ref()
            .map(|_| cull_view(camera, self.size(), techniques.min_pixels(), self.section()));
        let cull_view_bytes = gpu_view.as_ref().map(cull_view_bytes);
        let replay_key = replay_key(techniques, passes, key, &view);
        let frame_key = frame_key(passes, key, &view);
        let uploads_pending = scene.scene.has_pending_uploads();
        let display = self.display_bits(passes, scene.scene);
        let highlights = scene.scene.has_highlighted();
        let target = match passes {
            PassSet::Shaded { .. } => PassTarget::Color,
            PassSet::Pick { .. } => PassTarget::Pick,
        };
        let translucency = translucency(techniques, pipelines);
        let drawing = FrameDrawing {
            recording,
            gpu_view,
            shared: RefCell::new((
                ViewedScene {
                    scene: &mut *scene.scene,
                    own: &mut *scene.own,
                },
                abi::CadrStats::default(),
                culler,
            )),
        };
        let mut gather_uploads = |stats: &mut FrameStats| drawing.gather_uploads(stats);
        let mut uploads = |_: &Renderer, cb: vk::CommandBuffer, _: u32, _: &mut FrameStats| {
            drawing.record_uploads(cb)
        };
        let mut before =
            |renderer: &Renderer, cb: vk::CommandBuffer, _: u32, _: &mut FrameStats| {
                drawing.before(renderer, cb)
            };
        let mut between =
            |renderer: &Renderer, cb: vk::CommandBuffer, phase: u32, _: &mut FrameStats| {
                drawing.between(renderer, cb, phase)
            };
        let mut inside =
            |renderer: &Renderer, cb: vk::CommandBuffer, phase: u32, _: &mut FrameStats| {
                drawing.inside(renderer, cb, phase)
            };
        let mut after = |_: &Renderer, _: vk::CommandBuffer, _: u32, stats: &mut FrameStats| {
            drawing.after(stats)
        };
        let mut stats = self.frame(
            camera,
            FramePlan {
                pass: target,
                secondary,
                phases,
                cull_view: cull_view_bytes.as_ref().map(|bytes| &bytes[..]),
                replay_key,
                frame_key,
                keeps_frame_slots: techniques.keep_frame_slots(),
                uploads_pending,
                display,
                translucency,
                fills_surfaces: passes.fills_surfaces(),
                draws_edges: passes.draws_edges(),
                highlights,
            },
            FrameRecorders {
                gather_uploads: &mut gather_uploads,
                uploads: &mut uploads,
                before: &mut before,
                inside: &mut inside,
                between: &mut between,
                after: &mut after,
            },
        )?;
        stats.cpu_record_us += cull_us;
        let (scene, counters, culler) = drawing.shared.into_inner();
        drawn_stats(stats, techniques, (&scene, counters, culler.as_ref()))
    }

    /// What the surface and pick shaders interpolate in a frame of `scene`: vertex colours and
    /// texture coordinates where [`Self::display_bits`] shows either, the offset that finds a
    /// cap where caps are on and some plane is active.
    fn surface_inputs(&self, scene: &crate::gpu_scene::GpuScene) -> SurfaceInputs {
        let display = self.display_bits_of_scene(scene);
        SurfaceInputs {
            attributes: display
                & (crate::render::DISPLAY_VERTEX_ATTRIBUTES | crate::render::DISPLAY_TEXTURES)
                != 0,
            caps: self.section().caps() && !self.section().planes().is_empty(),
        }
    }

    /// The `DISPLAY_*` bits of a frame of `passes` over `scene`.
    fn display_bits(&self, passes: PassSet, scene: &crate::gpu_scene::GpuScene) -> u32 {
        let xray = match passes {
            PassSet::Shaded {
                mode: ShadeMode::XRay,
                ..
            } => crate::render::DISPLAY_XRAY,
            _ => 0,
        };
        xray | self.display_bits_of_scene(scene)
    }

    /// The `DISPLAY_*` bits that follow from `scene` and the renderer's settings alone.
    fn display_bits_of_scene(&self, scene: &crate::gpu_scene::GpuScene) -> u32 {
        let mut display = 0;
        if scene.has_vertex_attributes() {
            display |= crate::render::DISPLAY_VERTEX_ATTRIBUTES;
        }
        if self.textures() && scene.has_textures() {
            display |= crate::render::DISPLAY_TEXTURES;
        }
        if scene.has_material_descriptions() {
            display |= crate::render::DISPLAY_MATERIAL_DESCRIPTIONS;
        }
        display
    }
}

/// Whether the submission records secondary command buffers. One that does and was built
/// before ABI 1.8 is refused when the pass has several `samples`: its buffers would inherit
/// one sample per pixel.
fn secondary_buffers_allowed(techniques: &Techniques, samples: u32) -> RenderResult<bool> {
    let submission = techniques.get(TechniqueKind::Submission)?;
    let secondary = submission.entry.provides & abi::CADR_TRAIT_SECONDARY_COMMAND_BUFFERS != 0;
    if !secondary || samples <= 1 || submission.entry.abi_version >= (1, 8) {
        return Ok(secondary);
    }
    Err(RenderError::Technique {
        technique: format!("submission '{}'", submission.entry.name),
        message: format!(
            "it records secondary command buffers and was built for ABI {}.{}, which cannot \
             draw with MSAA ({samples}x asked; ABI 1.8 or later can)",
            submission.entry.abi_version.0, submission.entry.abi_version.1,
        ),
    })
}

/// The replay key of a frame of `passes` whose commands key is `key`, when the techniques allow
/// a replay: a frame records the same commands as the last one when nothing they depend on
/// changed (the camera reaches the GPU through uniforms, moved parts and new material values
/// through the uploads, when no technique reads them on the host). The pick pass never
/// replays.
fn replay_key(
    techniques: &Techniques,
    passes: PassSet,
    key: u64,
    view: &abi::CadrSceneView,
) -> Option<u64> {
    (matches!(passes, PassSet::Shaded { .. }) && techniques.replayable()).then(|| {
        if techniques.replays_parameter_changes() {
            key
        } else {
            mix(key, view.parameters_generation)
        }
    })
}

/// What the recording and the techniques' host writes of a frame of `passes` whose commands
/// key is `key` depend on besides the view, none for a pick: frames with equal keys may run on
/// the GPU while the next is recorded.
fn frame_key(passes: PassSet, key: u64, view: &abi::CadrSceneView) -> Option<u64> {
    matches!(passes, PassSet::Shaded { .. }).then(|| mix(key, view.parameters_generation))
}

/// What a frame's commands depend on: equal keys record equal commands. The techniques'
/// epoch, the scene's draws and buffers, the target, the pipelines drawn (the pass set, with
/// or without translucent surfaces, and its sample count), each pass's filter, and the
/// parameter values where the parameter path writes them into the commands (not where the
/// GPU culler writes them into parameter blocks).
fn commands_key(
    techniques: &Techniques,
    view: &abi::CadrSceneView,
    (width, height): (u32, u32),
    passes: PassSet,
    pipelines: &TechniquePipelines,
    pass_filters: &PassFilters,
) -> RenderResult<u64> {
    let parameters = techniques.get(TechniqueKind::Parameters)?;
    let values_in_commands =
        techniques.announces(parameters, abi::CADR_TRAIT_PARAMETERS_IN_COMMANDS, 0);
    let mut key = mix(techniques.epoch, view.draws_generation);
    key = mix(key, view.buffers_generation);
    key = mix(key, u64::from(width) << 32 | u64::from(height));
    key = mix(key, pipelines.color_format.as_raw() as u64);
    key = mix(key, pipelines.extra_color_formats.len().min(2) as u64);
    key = mix(key, u64::from(passes.samples()));
    for pass in &pipelines.passes {
        key = mix(key, pass.pipeline);
    }
    for (filter, exclusion) in pass_filters.filters.iter().zip(&pass_filters.exclusions) {
        key = mix(key, u64::from(filter.mask) << 32 | u64::from(filter.value));
        key = mix(key, u64::from(filter.section_cut));
        key = mix(
            key,
            u64::from(exclusion.mask) << 32 | u64::from(exclusion.value),
        );
    }
    if values_in_commands {
        key = mix(key, view.parameters_generation);
    }
    Ok(key)
}

/// The transparency method and its merge (pipeline, layout), when `pipelines` draw
/// translucent surfaces.
fn translucency<'a>(
    techniques: &'a Techniques,
    pipelines: &TechniquePipelines,
) -> Option<(&'a TransparencyMethod, (vk::Pipeline, vk::PipelineLayout))> {
    match (&pipelines.merge, &pipelines.merge_layout) {
        (Some(merge), Some(layout)) => techniques
            .transparency_method()
            .map(|method| (method, (merge.raw(), layout.raw()))),
        _ => None,
    }
}

/// The transparency targets' formats of `pipelines` as the record context carries them: the
/// first two, zero where there are fewer.
fn extra_color_formats(pipelines: &TechniquePipelines) -> [i32; 2] {
    let mut formats = [0i32; 2];
    for (slot, format) in formats.iter_mut().zip(&pipelines.extra_color_formats) {
        *slot = format.as_raw();
    }
    formats
}

/// Where the GPU culler (if any) wrote this phase's draws, for the submission.
fn gpu_draws(culler: &Option<GpuCuller<'_>>) -> *const abi::CadrGpuDraws {
    culler
        .as_ref()
        .map_or(std::ptr::null(), |c| c.draws.as_ptr())
}

/// Copies what the recording issued into a frame's stats.
fn count_recorded(stats: &mut FrameStats, counters: &abi::CadrStats) {
    stats.draw_calls = counters.draw_calls;
    stats.draws = counters.draws;
    stats.pipeline_binds = counters.pipeline_binds;
    stats.vertex_binds = counters.vertex_binds;
    stats.parameter_updates = counters.parameter_binds;
    stats.triangles_rasterized = counters.primitives;
}

/// What every technique call of one frame's recording shares: the pipelines and pass filters
/// drawn, the frame set, the target's size and the commands key.
struct FrameRecording<'a> {
    techniques: &'a Techniques,
    pipelines: &'a TechniquePipelines,
    pass_filters: &'a PassFilters,
    size: (u32, u32),
    /// Samples per pixel of the pass.
    samples: u32,
    /// The transparency targets' formats as the record context carries them (at most 2).
    extra_color_formats: [i32; 2],
    key: u64,
    /// Whether the views carry `CadrParameterBlocks` (see [`Techniques::parameter_blocks`]).
    parameter_blocks: bool,
}

impl FrameRecording<'_> {
    /// The record context of a submission call into `command_buffer`, with the GPU culler's
    /// draws of `phase`.
    fn context(
        &self,
        frame_set: vk::DescriptorSet,
        command_buffer: vk::CommandBuffer,
        view: &abi::CadrSceneView,
        stats: *mut abi::CadrStats,
        (gpu_draws, phase): (*const abi::CadrGpuDraws, u32),
    ) -> RenderResult<abi::CadrRecordContext> {
        let vertex = self.techniques.get(TechniqueKind::Vertex)?;
        let parameters = self.techniques.get(TechniqueKind::Parameters)?;
        let pipelines = self.pipelines;
        Ok(abi::CadrRecordContext {
            size: std::mem::size_of::<abi::CadrRecordContext>() as u32,
            command_buffer: command_buffer.as_raw() as *mut c_void,
            pipeline_layout: pipelines.layout.raw().as_raw(),
            frame_set: frame_set.as_raw(),
            pass_count: pipelines.passes.len() as u32,
            passes: pipelines.passes.as_ptr(),
            width: self.size.0,
            height: self.size.1,
            scene: view,
            vertex: abi::CadrPathRef {
                instance: vertex.instance,
                vtable: vertex.vtable(),
            },
            parameters: abi::CadrPathRef {
                instance: parameters.instance,
                vtable: parameters.vtable(),
            },
            commands_key: self.key,
            stats,
            color_format: pipelines.color_format.as_raw(),
            gpu_draws,
            phase,
            extra_color_count: pipelines.extra_color_formats.len().min(2) as u32,
            extra_color_formats: self.extra_color_formats,
            rasterization_samples: self.samples,
            pass_filters: self.pass_filters.filters.as_ptr(),
            pass_exclusions: self.pass_filters.exclusions.as_ptr(),
        })
    }

    /// The paths' and the submission's preparation, before the pass.
    fn prepare(
        &self,
        frame_set: vk::DescriptorSet,
        command_buffer: vk::CommandBuffer,
        view: &abi::CadrSceneView,
        counters: &mut abi::CadrStats,
        gpu_draws: *const abi::CadrGpuDraws,
    ) -> RenderResult<()> {
        let raw_command_buffer = command_buffer.as_raw() as *mut c_void;
        for kind in [TechniqueKind::Vertex, TechniqueKind::Parameters] {
            let active = self.techniques.get(kind)?;
            let prepare = match kind {
                TechniqueKind::Vertex => active.vtable::<abi::CadrVertexPathVtable>().prepare,
                _ => active.vtable::<abi::CadrParameterPathVtable>().prepare,
            };
            if let Some(prepare) = prepare {
                let mut message = Message::new();
                // SAFETY: a live instance; the view and command buffer are valid for the call.
                let result =
                    unsafe { prepare(active.instance, view, raw_command_buffer, message.raw()) };
                status(&active.entry, "prepare", result, &message)?;
            }
        }
        let submission = self.techniques.get(TechniqueKind::Submission)?;
        if let Some(prepare) = submission.vtable::<abi::CadrSubmissionVtable>().prepare {
            let record = self.context(frame_set, command_buffer, view, counters, (gpu_draws, 0))?;
            let mut message = Message::new();
            // SAFETY: a live instance; the context is valid for the call.
            let result = unsafe { prepare(submission.instance, &record, message.raw()) };
            status(&submission.entry, "prepare", result, &message)?;
        }
        Ok(())
    }

    /// The submission's recording of one phase, inside the pass.
    fn record(
        &self,
        frame_set: vk::DescriptorSet,
        command_buffer: vk::CommandBuffer,
        view: &abi::CadrSceneView,
        counters: &mut abi::CadrStats,
        draws: (*const abi::CadrGpuDraws, u32),
    ) -> RenderResult<()> {
        let submission = self.techniques.get(TechniqueKind::Submission)?;
        let record_fn = submission
            .vtable::<abi::CadrSubmissionVtable>()
            .record
            .ok_or_else(|| RenderError::Technique {
                technique: format!("submit '{}'", submission.entry.name),
                message: "its vtable has no record function".into(),
            })?;
        let record = self.context(frame_set, command_buffer, view, counters, draws)?;
        let mut message = Message::new();
        // SAFETY: a live instance; the context is valid for the call.
        let result = unsafe { record_fn(submission.instance, &record, message.raw()) };
        status(&submission.entry, "record", result, &message)
    }
}

/// What a frame's recorders share while the renderer runs them: the recording's common
/// inputs, the GPU cullers' view, and (borrowed by one recorder at a time)
/// the scene, the counters of what was recorded and the GPU culler.
struct FrameDrawing<'s, 'a> {
    recording: FrameRecording<'a>,
    gpu_view: Option<abi::CadrGpuCullView>,
    shared: RefCell<(ViewedScene<'s>, abi::CadrStats, Option<GpuCuller<'a>>)>,
}

impl FrameDrawing<'_, '_> {
    /// Gathers the frame's uploads on the host; returns what their commands depend on.
    fn gather_uploads(&self, stats: &mut FrameStats) -> RenderResult<u64> {
        let mut guard = self.shared.borrow_mut();
        let (bytes, key) = guard.0.scene.prepare_uploads()?;
        stats.bytes_uploaded = bytes;
        Ok(key)
    }

    /// Records the uploads' commands (into the prologue).
    fn record_uploads(&self, command_buffer: vk::CommandBuffer) -> RenderResult<()> {
        self.shared.borrow().0.scene.record_uploads(command_buffer)
    }

    /// Before the pass: the techniques' preparation, then phase 0 of the GPU culler.
    fn before(&self, renderer: &Renderer, command_buffer: vk::CommandBuffer) -> RenderResult<()> {
        let mut guard = self.shared.borrow_mut();
        let (scene, counters, culler) = &mut *guard;
        // The uploads went ahead in the prologue (this frame's, or a replayed one's).
        barrier(renderer, command_buffer);
        let mut chain = self.chain(renderer);
        let view = chained_view(scene, &mut chain);
        self.recording.prepare(
            renderer.frame_set(),
            command_buffer,
            &view,
            counters,
            gpu_draws(culler),
        )?;
        barrier(renderer, command_buffer);
        self.record_culling(renderer, command_buffer, 0, scene, culler)
    }

    /// Between phases: the GPU culler's next phase, the depth so far readable.
    fn between(
        &self,
        renderer: &Renderer,
        command_buffer: vk::CommandBuffer,
        phase: u32,
    ) -> RenderResult<()> {
        let mut guard = self.shared.borrow_mut();
        let (scene, _, culler) = &mut *guard;
        self.record_culling(renderer, command_buffer, phase, scene, culler)
    }

    /// Inside the pass: the submission's recording of `phase`.
    fn inside(
        &self,
        renderer: &Renderer,
        command_buffer: vk::CommandBuffer,
        phase: u32,
    ) -> RenderResult<()> {
        let mut guard = self.shared.borrow_mut();
        let (scene, counters, culler) = &mut *guard;
        let draws = (gpu_draws(culler), phase);
        let mut chain = self.chain(renderer);
        let view = chained_view(scene, &mut chain);
        self.recording
            .record(renderer.frame_set(), command_buffer, &view, counters, draws)
    }

    /// After the passes: what the recording issued (a replay of it issues the same).
    fn after(&self, stats: &mut FrameStats) -> RenderResult<()> {
        count_recorded(stats, &self.shared.borrow().1);
        Ok(())
    }

    /// Records `phase` of the GPU culler (if any) outside rendering.
    fn record_culling(
        &self,
        renderer: &Renderer,
        command_buffer: vk::CommandBuffer,
        phase: u32,
        scene: &ViewedScene<'_>,
        culler: &mut Option<GpuCuller<'_>>,
    ) -> RenderResult<()> {
        let (Some(culler), Some(gpu_view)) = (culler.as_mut(), self.gpu_view.as_ref()) else {
            return Ok(());
        };
        let depth = (phase > 0).then(|| PhaseDepth {
            image: renderer.depth_image().raw(),
            view: renderer.depth_image().view(),
            layout: SUSPENDED_DEPTH_LAYOUT,
        });
        let mut chain = self.chain(renderer);
        culler.record(
            phase,
            command_buffer,
            &chained_view(scene, &mut chain),
            (
                &self.recording.pipelines.passes,
                self.recording.pass_filters,
            ),
            gpu_view,
            renderer.cull_view_buffer(),
            depth,
        )
    }
}

/// What the host chains on the scene's view for a technique's call during a frame, ahead of the
/// scene's own extensions: the frame slot, and the request for parameter blocks where the
/// combination passes them.
struct FrameChain {
    frame_slot: abi::CadrFrameSlot,
    parameter_blocks: Option<abi::CadrParameterBlocks>,
}

impl FrameDrawing<'_, '_> {
    /// The chain of this frame's calls.
    fn chain(&self, renderer: &Renderer) -> FrameChain {
        FrameChain {
            frame_slot: renderer.frame_slot(),
            parameter_blocks: self
                .recording
                .parameter_blocks
                .then_some(abi::CadrParameterBlocks {
                    header: abi::CadrExtension {
                        size: std::mem::size_of::<abi::CadrParameterBlocks>() as u32,
                        kind: abi::CADR_EXTENSION_PARAMETER_BLOCKS,
                        next: std::ptr::null(),
                    },
                }),
        }
    }
}

/// The scene's view for a technique's call during a frame, with `chain` ahead of the scene's own
/// extensions (the view points at it: keep it while the view is used).
fn chained_view(scene: &ViewedScene<'_>, chain: &mut FrameChain) -> abi::CadrSceneView {
    let mut view = scene.view();
    let mut next = view.extensions;
    if let Some(blocks) = chain.parameter_blocks.as_mut() {
        blocks.header.next = next;
        next = &blocks.header;
    }
    chain.frame_slot.header.next = next;
    view.extensions = &chain.frame_slot.header;
    view
}

/// Makes transfer, compute and host writes before the pass visible to vertex input, shaders
/// (GPU culling's too) and indirect reads.
fn barrier(renderer: &Renderer, command_buffer: vk::CommandBuffer) {
    memory_barrier(
        renderer.device(),
        command_buffer,
        (
            vk::PipelineStageFlags2::ALL_TRANSFER
                | vk::PipelineStageFlags2::COMPUTE_SHADER
                | vk::PipelineStageFlags2::HOST,
            vk::AccessFlags2::TRANSFER_WRITE
                | vk::AccessFlags2::SHADER_WRITE
                | vk::AccessFlags2::HOST_WRITE,
        ),
        (
            vk::PipelineStageFlags2::VERTEX_INPUT
                | vk::PipelineStageFlags2::VERTEX_SHADER
                | vk::PipelineStageFlags2::DRAW_INDIRECT
                | vk::PipelineStageFlags2::COMPUTE_SHADER
                | vk::PipelineStageFlags2::ALL_TRANSFER,
            vk::AccessFlags2::VERTEX_ATTRIBUTE_READ
                | vk::AccessFlags2::INDEX_READ
                | vk::AccessFlags2::SHADER_READ
                | vk::AccessFlags2::UNIFORM_READ
                | vk::AccessFlags2::INDIRECT_COMMAND_READ
                | vk::AccessFlags2::TRANSFER_READ
                | vk::AccessFlags2::TRANSFER_WRITE,
        ),
    );
}

/// What a CPU culler's result depends on, by what it announced.
#[derive(Clone, Copy)]
struct CullDepends {
    /// The scene's parameter values (matrices, materials).
    parameters: bool,
    /// The view: its frustum and section planes.
    view: bool,
}

impl CullDepends {
    /// What a culler that `provides` these traits, from a library of ABI `minor`, reads:
    /// everything, unless its minor lets it say otherwise and it does.
    fn of(provides: abi::CadrTraitBits, minor: u32) -> Self {
        let announces = |trait_bit, since| announces((provides, minor), trait_bit, since);
        Self {
            // Unless it replays parameter changes and reads no host matrices.
            parameters: !announces(abi::CADR_TRAIT_REPLAYS_PARAMETER_CHANGES, 10)
                || provides & abi::CADR_TRAIT_READS_HOST_MATRICES != 0,
            // Unless its result is the same whatever the view.
            view: !announces(abi::CADR_TRAIT_CULLS_WHATEVER_THE_VIEW, 11),
        }
    }
}

/// What a culling result depends on: the culler, the scene (its parameter values and the view,
/// frustum and section planes, as far as the culler `depends` on them).
fn cull_key(
    epoch: u64,
    view: &abi::CadrSceneView,
    planes: (&[[f64; 4]; 6], &[[f64; 4]]),
    depends: CullDepends,
) -> u64 {
    let generations = (
        view.draws_generation,
        view.parameters_generation,
        view.buffers_generation,
    );
    cull_key_of(epoch, generations, planes, depends)
}

/// [`cull_key`] of the scene's draws, parameters and buffers generations.
fn cull_key_of(
    epoch: u64,
    (draws, parameters, buffers): (u64, u64, u64),
    (frustum, section): (&[[f64; 4]; 6], &[[f64; 4]]),
    depends: CullDepends,
) -> u64 {
    let mut key = mix(epoch, draws);
    if depends.parameters {
        key = mix(key, parameters);
    }
    key = mix(key, buffers);
    if depends.view {
        key = mix(key, section.len() as u64);
        for value in frustum.iter().chain(section).flatten() {
            key = mix(key, value.to_bits());
        }
    }
    key
}

/// Runs the culling technique and applies the bits that changed. Culling depends only on the
/// view (with its section) and the scene, so it runs again only when one of them (or the
/// culler) changed.
fn cull(
    scene: &mut ViewedScene<'_>,
    techniques: &mut Techniques,
    camera: &Camera,
    section: &Section,
) -> RenderResult<()> {
    if techniques.culls_on_gpu() {
        // The GPU decides: every candidate stays in the drawn set (once per culler and
        // scene layout, so a moving camera costs the CPU nothing here).
        let key = mix(techniques.epoch, scene.view().buffers_generation);
        if techniques.cull_key != Some(key) {
            let visible = vec![u64::MAX; scene.own.culled_bits().len()];
            let changed: Vec<u64> = scene.own.culled_bits().iter().map(|w| !w).collect();
            scene.apply_culling(&visible, &changed);
            techniques.cull_key = Some(key);
        }
        return Ok(());
    }
    let planes = camera.frustum_planes();
    let mut section_planes = [[0.0; 4]; MAX_SECTION_PLANES];
    for (slot, plane) in section_planes.iter_mut().zip(section.planes()) {
        *slot = plane.to_array();
    }
    let section_plane_count = section.planes().len().min(MAX_SECTION_PLANES);
    let all_planes = (&planes, &section_planes[..section_plane_count]);
    let culling = techniques.get(TechniqueKind::Culling)?;
    // Moved parts do not make a culler cull again that reads no parameter values, nor a
    // moving camera one whose result does not depend on the view.
    let depends = CullDepends::of(culling.entry.provides, culling.entry.abi_version.1);
    let key = cull_key(techniques.epoch, &scene.view(), all_planes, depends);
    if techniques.cull_key == Some(key) {
        return Ok(());
    }
    let Some(cull_fn) = culling.vtable::<abi::CadrCullingVtable>().cull else {
        // Every candidate is drawn: asked for once per change of the drawn set.
        scene.ask_for_visible();
        techniques.cull_key = Some(key);
        return Ok(());
    };
    let view = scene.view();
    let mut visible = scene.own.culled_bits().to_vec();
    let mut changed = vec![0u64; visible.len()];
    let input = abi::CadrCullInput {
        size: std::mem::size_of::<abi::CadrCullInput>() as u32,
        scene: &view,
        candidate_bits: scene.scene.candidate_bits().as_ptr(),
        world_matrices: match scene.scene.worlds() {
            [] => std::ptr::null(),
            worlds => worlds.as_ptr().cast(),
        },
        planes,
        section_plane_count: section_plane_count as u32,
        section_planes,
    };
    let mut output = abi::CadrCullOutput {
        size: std::mem::size_of::<abi::CadrCullOutput>() as u32,
        word_count: visible.len() as u32,
        visible_bits: visible.as_mut_ptr(),
        changed_bits: changed.as_mut_ptr(),
    };
    let mut message = Message::new();
    // SAFETY: a live instance; input and output are valid and unaliased for the call.
    let result = unsafe { cull_fn(culling.instance, &input, &mut output, message.raw()) };
    status(&culling.entry, "cull", result, &message)?;
    scene.apply_culling(&visible, &changed);
    scene.ask_for_visible();
    // The draws generation moved if anything changed: key on what the scene is now.
    techniques.cull_key = Some(cull_key(
        techniques.epoch,
        &scene.view(),
        all_planes,
        depends,
    ));
    Ok(())
}

/// A finished frame's `stats` with what it drew: the scene's triangles, or what a GPU
/// `culler` decided to draw; an error where bind calls panicked while recording.
fn drawn_stats(
    mut stats: FrameStats,
    techniques: &Techniques,
    (scene, counters, culler): (&ViewedScene<'_>, abi::CadrStats, Option<&GpuCuller>),
) -> RenderResult<FrameStats> {
    if counters.failures > 0 {
        return Err(RenderError::Technique {
            technique: techniques.combination().to_string(),
            message: format!("{} bind calls panicked while recording", counters.failures),
        });
    }
    stats.triangles = scene.own.drawn_triangles();
    if let Some(culler) = culler {
        // The frame has finished: what the GPU decided to draw.
        let drawn = culler.counts();
        stats.draws = drawn.draws;
        stats.triangles = drawn.primitives;
        stats.triangles_rasterized = drawn.primitives;
    }
    Ok(stats)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two orbit positions' frustums and one section plane.
    fn views() -> [[[f64; 4]; 6]; 2] {
        let mut turned = [[0.0, 0.0, 1.0, 5.0]; 6];
        turned[0] = [0.6, 0.0, 0.8, 5.0];
        [[[0.0, 0.0, 1.0, 5.0]; 6], turned]
    }

    #[test]
    fn a_culler_is_called_again_only_for_what_its_result_depends_on() {
        let [front, side] = views();
        let section = [[1.0, 0.0, 0.0, 0.0]];
        let scene = (3, 7, 11);
        let moved = (3, 8, 11);
        let redrawn = (4, 7, 11);
        let key = |provides, minor, generations, planes| {
            cull_key_of(1, generations, planes, CullDepends::of(provides, minor))
        };
        let frustum = abi::CADR_TRAIT_READS_HOST_MATRICES | abi::CADR_TRAIT_REPLAYABLE;
        let none = abi::CADR_TRAIT_REPLAYABLE
            | abi::CADR_TRAIT_REPLAYS_PARAMETER_CHANGES
            | abi::CADR_TRAIT_CULLS_WHATEVER_THE_VIEW;
        // A view-dependent culler culls again for a turned camera and a new section.
        assert_ne!(
            key(frustum, 11, scene, (&front, &[][..])),
            key(frustum, 11, scene, (&side, &[][..]))
        );
        assert_ne!(
            key(frustum, 11, scene, (&front, &[][..])),
            key(frustum, 11, scene, (&front, &section[..]))
        );
        assert_ne!(
            key(frustum, 11, scene, (&front, &[][..])),
            key(frustum, 11, moved, (&front, &[][..]))
        );
        // `none` does not for either, nor for moved parts, but does for changed draws.
        let still = key(none, 11, scene, (&front, &[][..]));
        assert_eq!(still, key(none, 11, scene, (&side, &[][..])));
        assert_eq!(still, key(none, 11, scene, (&side, &section[..])));
        assert_eq!(still, key(none, 11, moved, (&front, &[][..])));
        assert_ne!(still, key(none, 11, redrawn, (&front, &[][..])));
        // A library of ABI 1.10 cannot have said so: its culler culls for every view.
        assert_ne!(
            key(none, 10, scene, (&front, &[][..])),
            key(none, 10, scene, (&side, &[][..]))
        );
    }
}
