//! Command pools and one-shot submissions (uploads, readbacks).

use super::host_memory::{core_callbacks as host_callbacks, core_command_pool_callbacks};
use std::sync::Arc;

use ash::vk;

use super::device::Device;
use super::error::{VkError, VkResult, VkResultExt};

/// The CPU time, in microseconds, of each of `samples` resubmissions of a recorded, empty
/// command buffer, as a replayed frame hands the queue its recording
/// (`CommandContext::resubmit`), each waited for before the next is timed: the floor under
/// any frame on this device and driver, which `cadr bench` prints beside its rows.
pub fn resubmit_times_us(device: &Arc<Device>, samples: usize) -> VkResult<Vec<f64>> {
    let mut context = CommandContext::new(device, "resubmit floor")?;
    context.begin()?;
    context.submit()?;
    let mut times = Vec::with_capacity(samples);
    for _ in 0..samples {
        context.wait()?;
        let start = std::time::Instant::now();
        context.resubmit()?;
        times.push(start.elapsed().as_secs_f64() * 1e6);
    }
    context.wait()?;
    Ok(times)
}

/// A command pool with one primary command buffer and a fence: record, submit, wait. A
/// prologue (a second pool and buffer, made on first use) may be recorded before a
/// submission and goes to the queue ahead of the main buffer, in the same submission: what
/// changes every frame (a frame's uploads) goes there, so that the main recording can be
/// submitted again as it is.
pub struct CommandContext {
    device: Arc<Device>,
    pool: vk::CommandPool,
    command_buffer: vk::CommandBuffer,
    fence: vk::Fence,
    /// Whether the last submission was made (a failed one leaves nothing to wait for).
    in_flight: bool,
    /// The prologue's pool and command buffer, once one was recorded.
    prologue: Option<(vk::CommandPool, vk::CommandBuffer)>,
    /// Where the prologue of the next submission stands.
    prologue_state: PrologueState,
    /// The key of the complete recording the prologue's buffer holds, if any: a prologue
    /// with that key may be submitted again as it is.
    prologue_key: Option<u64>,
}

/// Where the prologue of the next submission stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum PrologueState {
    /// None goes with the next submission.
    Absent,
    /// Begun and not yet ended (not submitted unless ended).
    Recording,
    /// Ended: it goes ahead of the main buffer in the next submission.
    Ready,
}

impl CommandContext {
    /// Creates the pool, its command buffer and a signalled fence.
    pub fn new(device: &Arc<Device>, name: &str) -> VkResult<Self> {
        let (pool, command_buffer) = pool_with_buffer(device, name)?;
        // Dropped on a later failure: the pool is destroyed with it.
        let mut context = Self {
            device: Arc::clone(device),
            pool,
            command_buffer,
            fence: vk::Fence::null(),
            in_flight: false,
            prologue: None,
            prologue_state: PrologueState::Absent,
            prologue_key: None,
        };
        let fence_info = vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED);
        // SAFETY: fence_info is valid.
        context.fence = unsafe { device.raw.create_fence(&fence_info, host_callbacks()) }
            .or_vk("vkCreateFence")?;
        device.set_name(context.fence, &format!("{name} fence"));
        Ok(context)
    }

    /// Waits for the previous submission, resets the pool and begins recording.
    pub fn begin(&mut self) -> VkResult<vk::CommandBuffer> {
        self.wait()?;
        // SAFETY: the fence is signalled, so the GPU no longer uses the pool's buffers.
        unsafe {
            self.device
                .raw
                .reset_fences(&[self.fence])
                .or_vk("vkResetFences")?;
        }
        // Unsignalled now: nothing to wait for until the next submission is made.
        self.in_flight = false;
        // SAFETY: as above.
        unsafe {
            self.device
                .raw
                .reset_command_pool(self.pool, vk::CommandPoolResetFlags::empty())
                .or_vk("vkResetCommandPool")?;
        }
        // Not one-time: a frame with nothing changed is submitted again (`resubmit`).
        let begin = vk::CommandBufferBeginInfo::default();
        // SAFETY: the command buffer is reset and not in use.
        unsafe {
            self.device
                .raw
                .begin_command_buffer(self.command_buffer, &begin)
        }
        .or_vk("vkBeginCommandBuffer")?;
        Ok(self.command_buffer)
    }

    /// Begins the prologue of the next submission: waits for the last submission, resets the
    /// prologue's pool and begins its buffer. Once `end_prologue` has ended it, the next
    /// `submit`, `resubmit` or `submit_with_semaphores` submits it ahead of the main buffer
    /// (once); a prologue begun and not ended (its recording failed) is not submitted.
    pub fn begin_prologue(&mut self) -> VkResult<vk::CommandBuffer> {
        self.prologue_state = PrologueState::Absent;
        self.prologue_key = None;
        self.wait()?;
        let (pool, command_buffer) = match self.prologue {
            Some(prologue) => prologue,
            None => {
                let prologue = pool_with_buffer(&self.device, "prologue")?;
                self.prologue = Some(prologue);
                prologue
            }
        };
        // SAFETY: the last submission has finished (waited for above), so the GPU no longer
        // uses the prologue's buffer.
        unsafe {
            self.device
                .raw
                .reset_command_pool(pool, vk::CommandPoolResetFlags::empty())
        }
        .or_vk("vkResetCommandPool")?;
        // Not one-time: a prologue that would record the same commands goes again
        // (`reuse_prologue`).
        let begin = vk::CommandBufferBeginInfo::default();
        // SAFETY: the command buffer is reset and not in use.
        unsafe { self.device.raw.begin_command_buffer(command_buffer, &begin) }
            .or_vk("vkBeginCommandBuffer")?;
        self.prologue_state = PrologueState::Recording;
        Ok(command_buffer)
    }

    /// Ends the prologue `begin_prologue` began, for the next submission; `key` says what its
    /// commands depend on (see `reuse_prologue`).
    pub fn end_prologue(&mut self, key: u64) -> VkResult<()> {
        let Some((_, command_buffer)) = self.prologue else {
            return Ok(());
        };
        if self.prologue_state != PrologueState::Recording {
            return Ok(());
        }
        self.prologue_state = PrologueState::Absent;
        // SAFETY: the prologue is recording (begin_prologue began it, state says so).
        unsafe { self.device.raw.end_command_buffer(command_buffer) }
            .or_vk("vkEndCommandBuffer")?;
        self.prologue_state = PrologueState::Ready;
        self.prologue_key = Some(key);
        Ok(())
    }

    /// Makes the last prologue recorded go ahead of the next submission again, as it is,
    /// when it was ended with `key`; false when there is none to reuse (none recorded, its
    /// recording failed, or its commands depend on something else).
    pub fn reuse_prologue(&mut self, key: u64) -> bool {
        if self.prologue.is_some() && self.prologue_key == Some(key) {
            self.prologue_state = PrologueState::Ready;
            return true;
        }
        false
    }

    /// Ends recording and submits; the fence signals when the GPU is done.
    pub fn submit(&mut self) -> VkResult<()> {
        // SAFETY: the command buffer is recording (begin was called).
        unsafe { self.device.raw.end_command_buffer(self.command_buffer) }
            .or_vk("vkEndCommandBuffer")?;
        self.submit_recorded(&[], &[])
    }

    /// Submits the last recorded command buffer again, as it is, after waiting for its
    /// previous submission (a prologue recorded since goes ahead of it); the fence signals
    /// when the GPU is done.
    pub fn resubmit(&mut self) -> VkResult<()> {
        self.wait()?;
        // SAFETY: the fence is signalled (waited for above), so no submission uses it.
        unsafe { self.device.raw.reset_fences(&[self.fence]) }.or_vk("vkResetFences")?;
        self.in_flight = false;
        self.submit_recorded(&[], &[])
    }

    /// Submits the prologue, if one was recorded, and the main buffer, ended, with the fence
    /// (unsignalled: reset by `begin` or `resubmit`).
    fn submit_recorded(
        &mut self,
        wait: &[(vk::Semaphore, vk::PipelineStageFlags)],
        signal: &[vk::Semaphore],
    ) -> VkResult<()> {
        let ready = std::mem::replace(&mut self.prologue_state, PrologueState::Absent);
        let prologue = self
            .prologue
            .filter(|_| ready == PrologueState::Ready)
            .map(|(_, command_buffer)| command_buffer);
        let with_prologue;
        let alone;
        let buffers: &[vk::CommandBuffer] = match prologue {
            Some(prologue) => {
                with_prologue = [prologue, self.command_buffer];
                &with_prologue
            }
            None => {
                alone = [self.command_buffer];
                &alone
            }
        };
        let (wait_semaphores, wait_stages): (Vec<_>, Vec<_>) = wait.iter().copied().unzip();
        let submit = [vk::SubmitInfo::default()
            .command_buffers(buffers)
            .wait_semaphores(&wait_semaphores)
            .wait_dst_stage_mask(&wait_stages)
            .signal_semaphores(signal)];
        let submitted = self.device.submit(&submit, self.fence);
        self.in_flight = submitted.is_ok();
        submitted
    }

    /// Ends recording and submits after each `wait` semaphore (at its stage) has been
    /// signalled; `signal` semaphores are signalled when the commands are done, and so is the
    /// fence.
    pub fn submit_with_semaphores(
        &mut self,
        wait: &[(vk::Semaphore, vk::PipelineStageFlags)],
        signal: &[vk::Semaphore],
    ) -> VkResult<()> {
        // SAFETY: the command buffer is recording (begin was called).
        unsafe { self.device.raw.end_command_buffer(self.command_buffer) }
            .or_vk("vkEndCommandBuffer")?;
        self.submit_recorded(wait, signal)
    }

    /// Waits until the last submission has finished (at once when it failed, so that a host
    /// can go on after an error; an error when the device was lost).
    pub fn wait(&self) -> VkResult<()> {
        if self.in_flight {
            // SAFETY: the fence belongs to this device. A lost device answers at once.
            unsafe {
                self.device
                    .raw
                    .wait_for_fences(&[self.fence], true, u64::MAX)
            }
            .or_vk("vkWaitForFences")?;
        }
        if self.device.is_lost() {
            return Err(VkError::DeviceLost("vkWaitForFences"));
        }
        Ok(())
    }

    /// Waits at most `timeout` for the last submission: whether it has finished (an error
    /// when the device was lost). For a submission that waits on a semaphore another API
    /// signals, which may never come.
    pub fn wait_at_most(&self, timeout: std::time::Duration) -> VkResult<bool> {
        if self.in_flight {
            let nanoseconds = u64::try_from(timeout.as_nanos()).unwrap_or(u64::MAX);
            // SAFETY: the fence belongs to this device. A lost device answers at once.
            match unsafe {
                self.device
                    .raw
                    .wait_for_fences(&[self.fence], true, nanoseconds)
            } {
                Ok(()) => {}
                Err(vk::Result::TIMEOUT) => return Ok(false),
                Err(result) => return Err(super::error::map_result("vkWaitForFences", result)),
            }
        }
        if self.device.is_lost() {
            return Err(VkError::DeviceLost("vkWaitForFences"));
        }
        Ok(true)
    }

    /// The command buffer being recorded.
    pub fn command_buffer(&self) -> vk::CommandBuffer {
        self.command_buffer
    }
}

impl Drop for CommandContext {
    fn drop(&mut self) {
        // SAFETY: waiting first (for a submission that was made, even on a device marked lost:
        // a lost device answers at once) makes sure the GPU no longer uses the buffer; the
        // handles are destroyed once (null handles are ignored by Vulkan).
        unsafe {
            if self.in_flight {
                let _ = self
                    .device
                    .raw
                    .wait_for_fences(&[self.fence], true, u64::MAX);
            }
            self.device.raw.destroy_fence(self.fence, host_callbacks());
            self.device
                .raw
                .destroy_command_pool(self.pool, core_command_pool_callbacks());
            if let Some((pool, _)) = self.prologue {
                self.device
                    .raw
                    .destroy_command_pool(pool, core_command_pool_callbacks());
            }
        }
    }
}

/// A transient command pool with one primary command buffer, named after `name`; the pool is
/// destroyed again when the buffer cannot be allocated.
fn pool_with_buffer(device: &Device, name: &str) -> VkResult<(vk::CommandPool, vk::CommandBuffer)> {
    let pool_info = vk::CommandPoolCreateInfo::default()
        .queue_family_index(device.queue_family())
        .flags(vk::CommandPoolCreateFlags::TRANSIENT);
    // SAFETY: pool_info is valid for this device.
    let pool = unsafe {
        device
            .raw
            .create_command_pool(&pool_info, core_command_pool_callbacks())
    }
    .or_vk("vkCreateCommandPool")?;
    let alloc_info = vk::CommandBufferAllocateInfo::default()
        .command_pool(pool)
        .level(vk::CommandBufferLevel::PRIMARY)
        .command_buffer_count(1);
    // SAFETY: the pool is alive; one buffer is requested.
    match unsafe { device.raw.allocate_command_buffers(&alloc_info) } {
        Ok(buffers) => {
            device.set_name(pool, &format!("{name} pool"));
            device.set_name(buffers[0], name);
            Ok((pool, buffers[0]))
        }
        Err(error) => {
            // SAFETY: the pool was just created and holds nothing in use.
            unsafe {
                device
                    .raw
                    .destroy_command_pool(pool, core_command_pool_callbacks())
            };
            Err(error).or_vk("vkAllocateCommandBuffers")
        }
    }
}

/// A command buffer for one transfer that is submitted and waited for at once.
pub struct OneShot {
    context: CommandContext,
}

impl OneShot {
    /// Starts recording.
    pub fn begin(device: &Arc<Device>, name: &str) -> VkResult<Self> {
        let mut context = CommandContext::new(device, name)?;
        context.begin()?;
        Ok(Self { context })
    }

    /// The command buffer to record into.
    pub fn command_buffer(&self) -> vk::CommandBuffer {
        self.context.command_buffer()
    }

    /// Submits and waits until the GPU has finished.
    pub fn submit_and_wait(&mut self) -> VkResult<()> {
        self.context.submit()?;
        self.context.wait()
    }
}

/// Records a compute dispatch into `command_buffer` (recording, outside rendering): binds
/// `pipeline` with its `layout`, `set` as set 0 and `push` as its push constants, and
/// dispatches `groups` × 1 × 1 work groups.
pub fn record_dispatch(
    device: &Device,
    command_buffer: vk::CommandBuffer,
    (pipeline, layout): (vk::Pipeline, vk::PipelineLayout),
    set: vk::DescriptorSet,
    push: &[u8],
    groups: u32,
) {
    let raw = device.raw();
    // SAFETY: the caller records outside rendering; pipeline, layout and set are live and
    // compatible (the set's layout is set 0 of `layout`); `push` fits the layout's range.
    unsafe {
        raw.cmd_bind_pipeline(command_buffer, vk::PipelineBindPoint::COMPUTE, pipeline);
        raw.cmd_bind_descriptor_sets(
            command_buffer,
            vk::PipelineBindPoint::COMPUTE,
            layout,
            0,
            &[set],
            &[],
        );
        raw.cmd_push_constants(
            command_buffer,
            layout,
            vk::ShaderStageFlags::COMPUTE,
            0,
            push,
        );
        raw.cmd_dispatch(command_buffer, groups, 1, 1);
    }
}

/// Records one triangle covering the target with `pipeline` (a full-screen pass whose vertex
/// shader makes the triangle from `gl_VertexIndex`), `sets` bound from set 0 of `layout`.
pub fn record_fullscreen(
    device: &Device,
    command_buffer: vk::CommandBuffer,
    (pipeline, layout): (vk::Pipeline, vk::PipelineLayout),
    sets: &[vk::DescriptorSet],
) {
    let raw = device.raw();
    // SAFETY: the caller records inside rendering compatible with the pipeline; pipeline,
    // layout and sets are live and compatible.
    unsafe {
        raw.cmd_bind_pipeline(command_buffer, vk::PipelineBindPoint::GRAPHICS, pipeline);
        raw.cmd_bind_descriptor_sets(
            command_buffer,
            vk::PipelineBindPoint::GRAPHICS,
            layout,
            0,
            sets,
            &[],
        );
        raw.cmd_draw(command_buffer, 3, 1, 0, 0);
    }
}
