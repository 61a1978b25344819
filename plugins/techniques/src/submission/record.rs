//! Recording the passes' draws into a command buffer, and the secondary command buffers that
//! replayed and threaded recording use.

use std::ops::Range;
use std::sync::Arc;

use cadr_plugin_sdk::abi::{self, CadrBindState, CadrStats};
use cadr_plugin_sdk::vk::{self, Handle};
use cadr_plugin_sdk::vulkan_failure;
use cadr_plugin_sdk::{Gpu, Record};

use super::lists::PassList;

/// How draws are issued.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Api {
    /// `vkCmdDrawIndexed` per range.
    Direct,
    /// `vkCmdDrawMultiIndexedEXT` per batch.
    MultiDraw,
    /// `vkCmdDrawIndexedIndirect` per pass.
    Indirect,
    /// `vkCmdDrawIndexedIndirectCount` per pass.
    IndirectCount,
    /// `vkCmdExecuteGeneratedCommandsEXT` per pass ([`super::generated`]).
    Generated,
}

/// What one pass draws: its list, and the list's indirect commands where the API draws them.
pub struct PassDraws<'a> {
    pub list: &'a PassList,
    /// Indirect commands (null without).
    pub commands: vk::Buffer,
    /// The count buffer (null without).
    pub count: vk::Buffer,
    /// Number of indirect commands.
    pub indirect_draws: u32,
}

/// Everything a recording thread needs.
pub struct Recorder<'a> {
    pub gpu: &'a Gpu,
    pub record: &'a Record<'a>,
    pub api: Api,
    /// Per pass of the record, in order.
    pub passes: Vec<PassDraws<'a>>,
}

/// A `Record` shared with worker threads: every function it leads to is thread-safe per the
/// ABI (bind functions), and the data it points at is immutable during recording.
struct Shared<'a>(&'a Recorder<'a>);
// SAFETY: see above.
unsafe impl Send for Shared<'_> {}
// SAFETY: see above.
unsafe impl Sync for Shared<'_> {}

/// Adds to a recording thread's own counters (null: not counted).
fn count(stats: *mut CadrStats, add: impl FnOnce(&mut CadrStats)) {
    // SAFETY: each recording thread has its own counters.
    if let Some(stats) = unsafe { stats.as_mut() } {
        add(stats);
    }
}

impl Recorder<'_> {
    /// Records every pass's share `part` of `parts` (of its batches) into `command_buffer`,
    /// counting into `stats`. Indirect draws are one call per pass, recorded by the first part.
    pub fn record_passes(
        &self,
        command_buffer: vk::CommandBuffer,
        (part, parts): (Range<usize>, usize),
        passes: Range<usize>,
        stats: *mut CadrStats,
    ) {
        let all = self.record.passes();
        let passes = passes.start.min(all.len())..passes.end.min(all.len());
        let gpu_draws = matches!(self.api, Api::Indirect | Api::IndirectCount);
        for (pass, draws) in all[passes.clone()].iter().zip(&self.passes[passes]) {
            if gpu_draws {
                if part.start == 0 && draws.indirect_draws > 0 {
                    self.record_indirect(command_buffer, pass, draws, stats);
                }
                continue;
            }
            let batches = draws.list.batches.len();
            let batch_range = if part.end == usize::MAX {
                0..batches
            } else {
                let per = batches.div_ceil(parts.max(1));
                (part.start * per).min(batches)..(part.end * per).min(batches)
            };
            if !batch_range.is_empty() {
                self.record_batches(command_buffer, pass, (draws.list, batch_range), stats);
            }
        }
    }

    /// Binds `pass` and draws its indirect commands with one call (more where they outnumber
    /// the device's `maxDrawIndirectCount`, without a count).
    fn record_indirect(
        &self,
        command_buffer: vk::CommandBuffer,
        pass: &abi::CadrPass,
        draws: &PassDraws<'_>,
        stats: *mut CadrStats,
    ) {
        bind_pass(self.gpu, self.record, pass, (command_buffer, stats));
        let calls = if self.api == Api::Indirect {
            // SAFETY: recording; the indirect buffer holds `draws.indirect_draws` commands of
            // 20 bytes.
            unsafe {
                draw_indexed_indirect(
                    self.gpu,
                    command_buffer,
                    (draws.commands, 0),
                    draws.indirect_draws,
                    20,
                )
            }
        } else {
            // SAFETY: recording; the indirect buffers hold `draws.indirect_draws` commands of
            // 20 bytes and their count.
            unsafe {
                self.gpu.device.cmd_draw_indexed_indirect_count(
                    command_buffer,
                    draws.commands,
                    0,
                    draws.count,
                    0,
                    draws.indirect_draws,
                    20,
                );
            }
            1
        };
        let triangles = surface_triangles(pass, &draws.list.ranges);
        count(stats, |s| {
            s.draw_calls += calls;
            s.draws += u64::from(draws.indirect_draws);
            s.primitives += triangles;
        });
    }

    /// Binds `pass` and draws the `batches` of `list`, each with its instance's parameters.
    fn record_batches(
        &self,
        command_buffer: vk::CommandBuffer,
        pass: &abi::CadrPass,
        (list, batches): (&PassList, Range<usize>),
        stats: *mut CadrStats,
    ) {
        let (bind, mut vertex_state, mut parameter_state) =
            bind_pass(self.gpu, self.record, pass, (command_buffer, stats));
        let instances = self.record.scene().instances();
        let (vertex, parameters) = (self.record.vertex(), self.record.parameters());
        let mut multi: Vec<vk::MultiDrawIndexedInfoEXT> = Vec::new();
        for batch in &list.batches[batches] {
            let Some(first) = instances.get(batch.instance as usize) else {
                continue;
            };
            let first_instance =
                parameters.bind_draw(&bind, batch.instance, first, &mut parameter_state);
            let ranges = &list.ranges[batch.ranges.clone()];
            let calls = if self.api == Api::MultiDraw {
                let base = self
                    .record
                    .vertex()
                    .bind_draw(&bind, first, &mut vertex_state);
                if base.ok == 0 {
                    continue;
                }
                multi.clear();
                multi.extend(ranges.iter().map(|r| vk::MultiDrawIndexedInfoEXT {
                    first_index: r.first - base.index_base,
                    index_count: r.count,
                    vertex_offset: instances[r.instance as usize].vertex_base as i32
                        - base.vertex_base as i32,
                }));
                if let Some(multi_draw) = &self.gpu.multi_draw {
                    // SAFETY: recording; `multi` holds `len` tightly packed entries.
                    unsafe {
                        (multi_draw.fp().cmd_draw_multi_indexed_ext)(
                            command_buffer,
                            multi.len() as u32,
                            multi.as_ptr(),
                            1,
                            first_instance,
                            std::mem::size_of::<vk::MultiDrawIndexedInfoEXT>() as u32,
                            std::ptr::null(),
                        )
                    };
                }
                1
            } else {
                for range in ranges {
                    let instance = &instances[range.instance as usize];
                    let base = vertex.bind_draw(&bind, instance, &mut vertex_state);
                    if base.ok == 0 {
                        continue;
                    }
                    // SAFETY: recording; the range lies in the bound buffers.
                    unsafe {
                        self.gpu.device.cmd_draw_indexed(
                            command_buffer,
                            range.count,
                            1,
                            range.first - base.index_base,
                            instance.vertex_base as i32 - base.vertex_base as i32,
                            first_instance,
                        )
                    };
                }
                ranges.len() as u64
            };
            let triangles = surface_triangles(pass, ranges);
            count(stats, |s| {
                s.draw_calls += calls;
                s.draws += ranges.len() as u64;
                s.primitives += triangles;
            });
        }
    }
}

/// The triangles `ranges` draw in `pass`: none in an edge pass (lines), each range's third
/// otherwise. Counted where the ranges are recorded, so that a frame's triangles are those
/// its surface passes rasterise, as GPU cullers count them.
pub fn surface_triangles(pass: &abi::CadrPass, ranges: &[super::lists::Range]) -> u64 {
    if pass.kind == abi::CADR_PASS_EDGES {
        return 0;
    }
    ranges.iter().map(|r| u64::from(r.count / 3)).sum()
}

/// Binds what every draw of `pass` needs into `command_buffer` (the record's, or a worker's
/// secondary buffer): its pipeline, the frame's set, and the vertex and parameter paths' pass
/// bindings; counts the binds into `stats` (that thread's counters). Returns the pass's bind
/// context and the paths' bind states, for the per-draw binds that follow.
pub fn bind_pass(
    gpu: &Gpu,
    record: &Record<'_>,
    pass: &abi::CadrPass,
    (command_buffer, stats): (vk::CommandBuffer, *mut CadrStats),
) -> (abi::CadrBindContext, CadrBindState, CadrBindState) {
    let device = &gpu.device;
    let bind = record.bind_context(command_buffer, pass.kind, stats);
    // SAFETY: recording inside rendering; the pipeline, layout and set outlive the frame.
    unsafe {
        device.cmd_bind_pipeline(
            command_buffer,
            vk::PipelineBindPoint::GRAPHICS,
            vk::Pipeline::from_raw(pass.pipeline),
        );
        device.cmd_bind_descriptor_sets(
            command_buffer,
            vk::PipelineBindPoint::GRAPHICS,
            record.layout(),
            0,
            &[record.frame_set()],
            &[],
        );
    }
    let mut vertex_state = CadrBindState::default();
    let mut parameter_state = CadrBindState::default();
    record.vertex().bind_pass(&bind, &mut vertex_state);
    record.parameters().bind_pass(&bind, &mut parameter_state);
    // SAFETY: each recording thread has its own counters, valid for the call.
    if let Some(stats) = unsafe { stats.as_mut() } {
        stats.pipeline_binds += 1;
        stats.parameter_binds += 1;
    }
    (bind, vertex_state, parameter_state)
}

/// How many of a pass's GPU-written commands a draw runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GpuDrawCount {
    /// The count the culler wrote (`vkCmdDrawIndexedIndirectCount`).
    Read,
    /// Every command of the culler's room (`vkCmdDrawIndexedIndirect` of `max_draws`), those
    /// past the count empty: the host asked the culler so (`CadrEmptyCommandTails`, ABI 1.24).
    Capacity,
}

/// Records each pass's draws from the commands a GPU culler wrote (`draws`, one per pass):
/// the pass's pipeline and bindings, then one indirect draw, `by` the count or the capacity.
pub fn record_gpu_draws(
    gpu: &Gpu,
    record: &Record<'_>,
    draws: &[abi::CadrGpuDraws],
    by: GpuDrawCount,
) {
    for (pass, source) in record.passes().iter().zip(draws) {
        record_gpu_pass(gpu, record, pass, source, by);
    }
}

/// Binds `pass` and draws the commands of `source` with one indirect draw, `by` the count or
/// the capacity (nothing where the culler wrote no commands for it).
pub fn record_gpu_pass(
    gpu: &Gpu,
    record: &Record<'_>,
    pass: &abi::CadrPass,
    source: &abi::CadrGpuDraws,
    by: GpuDrawCount,
) {
    if source.commands == 0 || source.max_draws == 0 {
        return;
    }
    let command_buffer = record.command_buffer();
    bind_pass(gpu, record, pass, (command_buffer, record.stats()));
    let commands = vk::Buffer::from_raw(source.commands);
    let calls = match by {
        GpuDrawCount::Read => {
            // SAFETY: recording; the culler's buffers hold `max_draws` commands of `stride`
            // bytes and the count, written before rendering began.
            unsafe {
                gpu.device.cmd_draw_indexed_indirect_count(
                    command_buffer,
                    commands,
                    source.commands_offset,
                    vk::Buffer::from_raw(source.count_buffer),
                    source.count_offset,
                    source.max_draws,
                    source.stride,
                )
            };
            1
        }
        // SAFETY: recording; the culler's buffer holds `max_draws` commands of `stride` bytes,
        // written before rendering began, those past the count of zero instances.
        GpuDrawCount::Capacity => unsafe {
            draw_indexed_indirect(
                gpu,
                command_buffer,
                (commands, source.commands_offset),
                source.max_draws,
                source.stride,
            )
        },
    };
    record.count(|s| s.draw_calls += calls);
}

/// The calls that draw `draws` indirect commands when one call may draw at most `most`: each
/// call's first command and how many it draws.
fn indirect_calls(draws: u32, most: u32) -> impl Iterator<Item = (u32, u32)> {
    let most = most.max(1);
    (0..draws.div_ceil(most)).map(move |call| {
        let first = call * most;
        (first, (draws - first).min(most))
    })
}

/// Records `vkCmdDrawIndexedIndirect` of the `draws` commands `stride` bytes apart from byte
/// `offset` of `buffer`, in as many calls as the device's `maxDrawIndirectCount` asks; returns
/// the calls.
///
/// # Safety
/// `command_buffer` is recording inside a rendering with a pipeline bound, and the buffer holds
/// the `draws` commands from the offset on.
unsafe fn draw_indexed_indirect(
    gpu: &Gpu,
    command_buffer: vk::CommandBuffer,
    (buffer, offset): (vk::Buffer, u64),
    draws: u32,
    stride: u32,
) -> u64 {
    let mut calls = 0;
    for (first, count) in indirect_calls(draws, gpu.max_draw_indirect_count) {
        let at = offset + u64::from(first) * u64::from(stride);
        // SAFETY: the caller vouches for the recording and the commands.
        unsafe {
            gpu.device
                .cmd_draw_indexed_indirect(command_buffer, buffer, at, count, stride)
        };
        calls += 1;
    }
    calls
}

/// The most passes whose shares workers record into buffers of their own.
const PASS_BUFFERS: usize = 4;

/// Secondary command buffers: a pool per worker (pools are externally synchronised, so each
/// worker thread gets its own) with a buffer per pass, so that several workers' shares of a
/// frame execute pass by pass (every draw of a pass before any of the next: translucent
/// surfaces must come after every opaque one).
pub struct SecondaryBuffers {
    gpu: Arc<Gpu>,
    pools: Vec<vk::CommandPool>,
    buffers: Vec<[vk::CommandBuffer; PASS_BUFFERS]>,
}

impl SecondaryBuffers {
    pub fn new(gpu: &Arc<Gpu>, count: u32) -> Result<Self, String> {
        let mut this = Self {
            gpu: Arc::clone(gpu),
            pools: Vec::new(),
            buffers: Vec::new(),
        };
        for _ in 0..count {
            let info =
                vk::CommandPoolCreateInfo::default().flags(vk::CommandPoolCreateFlags::TRANSIENT);
            // SAFETY: the info lives for the call; the pool is destroyed in Drop.
            let pool = unsafe { gpu.device.create_command_pool(&info, gpu.allocator()) }
                .map_err(vulkan_failure("vkCreateCommandPool"))?;
            this.pools.push(pool);
            let alloc = vk::CommandBufferAllocateInfo::default()
                .command_pool(pool)
                .level(vk::CommandBufferLevel::SECONDARY)
                .command_buffer_count(PASS_BUFFERS as u32);
            // SAFETY: as above.
            let buffers = unsafe { gpu.device.allocate_command_buffers(&alloc) }
                .map_err(vulkan_failure("vkAllocateCommandBuffers"))?;
            let buffers: [vk::CommandBuffer; PASS_BUFFERS] = buffers
                .try_into()
                .map_err(|_| "vkAllocateCommandBuffers gave too few buffers".to_owned())?;
            this.buffers.push(buffers);
        }
        Ok(this)
    }

    pub fn len(&self) -> usize {
        self.buffers.len()
    }

    /// Records the frame on `workers` threads, each its share of the batches of every pass;
    /// adds their counters to `stats` and returns the buffers to execute, in order. One worker
    /// records every pass into one buffer; several record a buffer per pass (up to
    /// [`PASS_BUFFERS`] passes, the rest into the last), executed pass by pass.
    pub fn record_all(
        &self,
        recorder: &Recorder<'_>,
        stats: &mut CadrStats,
        workers: usize,
    ) -> Result<Vec<vk::CommandBuffer>, String> {
        let workers = workers.clamp(1, self.buffers.len());
        let pass_count = recorder.record.passes().len();
        // The passes of each buffer a worker records.
        let groups: Vec<std::ops::Range<usize>> = if workers == 1 {
            std::iter::once(0..usize::MAX).collect()
        } else {
            (0..pass_count.clamp(1, PASS_BUFFERS))
                .map(|p| {
                    if p + 1 == PASS_BUFFERS {
                        p..usize::MAX
                    } else {
                        p..p + 1
                    }
                })
                .collect()
        };
        let shared = Shared(recorder);
        let extent = recorder.record.extent();
        let color_formats = recorder.record.color_formats(self.gpu.formats.0);
        let samples = recorder.record.rasterization_samples();
        let results: Vec<Result<CadrStats, String>> = std::thread::scope(|scope| {
            let handles: Vec<_> = (0..workers)
                .map(|worker| {
                    let shared = &shared;
                    let (pool, buffers) = (self.pools[worker], &self.buffers[worker]);
                    let gpu = &self.gpu;
                    let color_formats = &color_formats;
                    let groups = &groups;
                    let work = move || -> Result<CadrStats, String> {
                        let mut local = CadrStats::default();
                        let part = if workers == 1 {
                            0..usize::MAX
                        } else {
                            worker..worker + 1
                        };
                        // SAFETY: the pool is used by this thread only; the GPU finished its
                        // buffers' last use (the host waits for every frame before the next).
                        unsafe {
                            gpu.device
                                .reset_command_pool(pool, vk::CommandPoolResetFlags::empty())
                        }
                        .map_err(vulkan_failure("vkResetCommandPool"))?;
                        for (group, &buffer) in groups.iter().zip(buffers) {
                            begin_secondary(gpu, buffer, (extent, color_formats, samples))?;
                            shared.0.record_passes(
                                buffer,
                                (part.clone(), workers),
                                group.clone(),
                                &mut local,
                            );
                            // SAFETY: the buffer is recording.
                            unsafe { gpu.device.end_command_buffer(buffer) }
                                .map_err(vulkan_failure("vkEndCommandBuffer"))?;
                        }
                        Ok(local)
                    };
                    if workers == 1 {
                        Err(work)
                    } else {
                        Ok(scope.spawn(work))
                    }
                })
                .collect();
            handles
                .into_iter()
                .map(|handle| match handle {
                    Ok(thread) => thread
                        .join()
                        .unwrap_or_else(|_| Err("a recording thread panicked".into())),
                    Err(work) => work(),
                })
                .collect()
        });
        for result in results {
            super::add(stats, &result?);
        }
        // Pass by pass, each pass's shares in worker order.
        Ok((0..groups.len())
            .flat_map(|group| (0..workers).map(move |worker| (group, worker)))
            .map(|(group, worker)| self.buffers[worker][group])
            .collect())
    }

    /// Executes `buffers` (recorded by [`SecondaryBuffers::record_all`]) in `primary`.
    pub fn execute(&self, primary: vk::CommandBuffer, buffers: &[vk::CommandBuffer]) {
        // SAFETY: recording inside rendering begun for secondary contents; the buffers were
        // recorded for it and stay alive until the frame finishes.
        unsafe { self.gpu.device.cmd_execute_commands(primary, buffers) };
    }
}

fn begin_secondary(
    gpu: &Gpu,
    buffer: vk::CommandBuffer,
    (extent, color_formats, samples): (vk::Extent2D, &[vk::Format], vk::SampleCountFlags),
) -> Result<(), String> {
    let mut rendering = vk::CommandBufferInheritanceRenderingInfo::default()
        .color_attachment_formats(color_formats)
        .depth_attachment_format(gpu.formats.1)
        .rasterization_samples(samples);
    let inheritance = vk::CommandBufferInheritanceInfo::default().push_next(&mut rendering);
    // Simultaneous use: a recording replayed while nothing changes is executed by the primary
    // buffers of several frames in flight at once.
    let begin = vk::CommandBufferBeginInfo::default()
        .flags(
            vk::CommandBufferUsageFlags::RENDER_PASS_CONTINUE
                | vk::CommandBufferUsageFlags::SIMULTANEOUS_USE,
        )
        .inheritance_info(&inheritance);
    let area = vk::Rect2D {
        offset: vk::Offset2D::default(),
        extent,
    };
    let viewport = vk::Viewport {
        x: 0.0,
        y: 0.0,
        width: extent.width as f32,
        height: extent.height as f32,
        min_depth: 0.0,
        max_depth: 1.0,
    };
    // SAFETY: the pool is used by this thread only and was reset by it for this frame.
    unsafe {
        gpu.device
            .begin_command_buffer(buffer, &begin)
            .map_err(vulkan_failure("vkBeginCommandBuffer"))?;
        gpu.device.cmd_set_viewport(buffer, 0, &[viewport]);
        gpu.device.cmd_set_scissor(buffer, 0, &[area]);
    }
    Ok(())
}

impl Drop for SecondaryBuffers {
    fn drop(&mut self) {
        // SAFETY: the host destroys instances after the GPU is done with them; buffers go
        // with their pools.
        unsafe {
            for &pool in &self.pools {
                self.gpu
                    .device
                    .destroy_command_pool(pool, self.gpu.allocator());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::indirect_calls;

    #[test]
    fn indirect_draws_past_the_device_limit_are_split_into_calls() {
        let calls = |draws, most| indirect_calls(draws, most).collect::<Vec<_>>();
        assert_eq!(calls(0, 10), []);
        assert_eq!(calls(7, 10), [(0, 7)]);
        assert_eq!(calls(10, 10), [(0, 10)]);
        assert_eq!(calls(25, 10), [(0, 10), (10, 10), (20, 5)]);
        assert_eq!(calls(3, 1), [(0, 1), (1, 1), (2, 1)]);
        // A limit of 0 (no driver reports it) is taken as 1.
        assert_eq!(calls(2, 0), [(0, 1), (1, 1)]);
        assert_eq!(calls(u32::MAX, u32::MAX), [(0, u32::MAX)]);
    }
}
