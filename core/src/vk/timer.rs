//! GPU timestamps around a span of commands.

use super::host_memory::core_callbacks as host_callbacks;
use std::sync::Arc;

use ash::vk;

use super::device::Device;
use super::error::{VkResult, VkResultExt};

/// A pair of timestamp queries that measures the GPU time of the commands between them.
pub struct GpuTimer {
    device: Arc<Device>,
    pool: vk::QueryPool,
    written: bool,
}

impl GpuTimer {
    /// Creates the query pool; `None` when the queue has no timestamps.
    pub fn new(device: &Arc<Device>, name: &str) -> VkResult<Option<Self>> {
        if !device.capabilities().timestamps {
            return Ok(None);
        }
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(2);
        // SAFETY: info is valid.
        let pool = unsafe { device.raw.create_query_pool(&info, host_callbacks()) }
            .or_vk("vkCreateQueryPool")?;
        device.set_name(pool, name);
        Ok(Some(Self {
            device: Arc::clone(device),
            pool,
            written: false,
        }))
    }

    /// Records the reset and the start timestamp; call before the measured commands.
    pub fn begin(&mut self, command_buffer: vk::CommandBuffer) {
        // SAFETY: command_buffer is recording outside a render pass; the pool is alive.
        unsafe {
            self.device
                .raw
                .cmd_reset_query_pool(command_buffer, self.pool, 0, 2);
            self.device.raw.cmd_write_timestamp2(
                command_buffer,
                vk::PipelineStageFlags2::TOP_OF_PIPE,
                self.pool,
                0,
            );
        }
    }

    /// Records the end timestamp; call after the measured commands.
    pub fn end(&mut self, command_buffer: vk::CommandBuffer) {
        // SAFETY: command_buffer is recording; query 1 was reset by begin.
        unsafe {
            self.device.raw.cmd_write_timestamp2(
                command_buffer,
                vk::PipelineStageFlags2::BOTTOM_OF_PIPE,
                self.pool,
                1,
            )
        };
        self.written = true;
    }

    /// The measured time in microseconds, once the submission has completed.
    pub fn elapsed_us(&self) -> VkResult<Option<f64>> {
        if !self.written {
            return Ok(None);
        }
        let mut ticks = [0_u64; 2];
        // Lavapipe leaks an allocation when a later one in this call fails.
        super::fault::with_first_host_memory_fault_only(|| {
            // SAFETY: both queries were written by a completed submission (the caller waited).
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
        let delta = (ticks[1] & mask).wrapping_sub(ticks[0] & mask) & mask;
        Ok(Some(delta as f64 * period_ns / 1000.0))
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
