//! GPU timestamps along a span of commands: at its start, at marks between the parts of it
//! that are measured apart, and at its end.

use super::host_memory::core_callbacks as host_callbacks;
use std::sync::Arc;

use ash::vk;

use super::device::Device;
use super::error::{VkResult, VkResultExt};

/// Timestamp queries that measure the GPU time of the commands between the first and the last
/// written, and of each span between two written one after the other.
pub struct GpuTimer {
    device: Arc<Device>,
    pool: vk::QueryPool,
    /// Queries in the pool: the most timestamps one recording writes.
    capacity: u32,
    /// Timestamps the last recording wrote (0 before one began).
    written: u32,
}

impl GpuTimer {
    /// Creates the query pool for `capacity` timestamps (at least 2: the start and the end);
    /// `None` when the queue has no timestamps.
    pub fn new(device: &Arc<Device>, name: &str, capacity: u32) -> VkResult<Option<Self>> {
        if !device.capabilities().timestamps {
            return Ok(None);
        }
        let capacity = capacity.max(2);
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(capacity);
        // SAFETY: info is valid.
        let pool = unsafe { device.raw.create_query_pool(&info, host_callbacks()) }
            .or_vk("vkCreateQueryPool")?;
        device.set_name(pool, name);
        Ok(Some(Self {
            device: Arc::clone(device),
            pool,
            capacity,
            written: 0,
        }))
    }

    /// Records the reset and the start timestamp; call before the measured commands.
    pub fn begin(&mut self, command_buffer: vk::CommandBuffer) {
        // SAFETY: command_buffer is recording outside a render pass; the pool is alive.
        unsafe {
            self.device
                .raw
                .cmd_reset_query_pool(command_buffer, self.pool, 0, self.capacity);
            self.device.raw.cmd_write_timestamp2(
                command_buffer,
                vk::PipelineStageFlags2::TOP_OF_PIPE,
                self.pool,
                0,
            );
        }
        self.written = 1;
    }

    /// Records a timestamp once the commands recorded so far have completed: the end of one
    /// measured span and the start of the next. Returns whether there was room for it (the
    /// last query is kept for [`GpuTimer::end`]).
    pub fn mark(&mut self, command_buffer: vk::CommandBuffer) -> bool {
        if self.written == 0 || self.written + 1 >= self.capacity {
            return false;
        }
        self.write_after_all(command_buffer);
        true
    }

    /// Records the end timestamp; call after the measured commands. Returns whether it was
    /// written (always, after [`GpuTimer::begin`]: marks leave room for it).
    pub fn end(&mut self, command_buffer: vk::CommandBuffer) -> bool {
        if self.written == 0 || self.written >= self.capacity {
            return false;
        }
        self.write_after_all(command_buffer);
        true
    }

    /// Writes the next query once every command before has completed.
    fn write_after_all(&mut self, command_buffer: vk::CommandBuffer) {
        // SAFETY: command_buffer is recording; begin reset every query of the pool, and
        // `written` stays under the pool's capacity.
        unsafe {
            self.device.raw.cmd_write_timestamp2(
                command_buffer,
                vk::PipelineStageFlags2::BOTTOM_OF_PIPE,
                self.pool,
                self.written,
            )
        };
        self.written += 1;
    }

    /// The measured time in microseconds, from the start to the end, once the submission has
    /// completed.
    pub fn elapsed_us(&self) -> VkResult<Option<f64>> {
        Ok(self.spans_us()?.map(|spans| spans.iter().sum::<f64>()))
    }

    /// The time of each span between two timestamps written one after the other, in
    /// microseconds, once the submission has completed (`None` before anything was measured).
    pub fn spans_us(&self) -> VkResult<Option<Vec<f64>>> {
        if self.written < 2 {
            return Ok(None);
        }
        let mut ticks = vec![0_u64; self.written as usize];
        // Lavapipe leaks an allocation when a later one in this call fails.
        super::fault::with_first_host_memory_fault_only(|| {
            // SAFETY: the queries read were written by a completed submission (the caller
            // waited).
            unsafe {
                self.device.raw.get_query_pool_results(
                    self.pool,
                    0,
                    &mut ticks,
                    vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                )
            }
        })
        .or_vk("vkGetQueryPoolResults")?;
        let (period_ns, valid_bits) = self.device.timestamp_info();
        let mask = if valid_bits >= 64 {
            u64::MAX
        } else {
            (1_u64 << valid_bits) - 1
        };
        Ok(Some(
            ticks
                .windows(2)
                .map(|pair| {
                    let delta = (pair[1] & mask).wrapping_sub(pair[0] & mask) & mask;
                    delta as f64 * period_ns / 1000.0
                })
                .collect(),
        ))
    }
}

impl Drop for GpuTimer {
    fn drop(&mut self) {
        // SAFETY: owners wait for their frames before dropping; destroyed once.
        unsafe {
            self.device
                .raw
                .destroy_query_pool(self.pool, host_callbacks())
        };
    }
}
