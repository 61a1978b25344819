//! GPU timestamps along a span of commands: at its start, at marks between the parts of it
//! that are measured apart, and at its end.

use super::host_memory::core_callbacks as host_callbacks;
use std::sync::Arc;

use ash::vk;

use super::device::Device;
use super::error::{VkResult, VkResultExt};

/// The most timestamps a timer holds (its pool's queries; the ticks are read onto the stack).
pub const MOST_TIMESTAMPS: u32 = 32;

/// Timestamp queries that measure the GPU time of the commands between the first and the last
/// written, and of each named span between two written one after the other.
pub struct GpuTimer {
    device: Arc<Device>,
    pool: vk::QueryPool,
    /// Queries in the pool: the most timestamps one recording writes.
    capacity: u32,
    /// The name of each span the recording being made (or the last one made) measures, in
    /// order; it writes one timestamp more than it has spans.
    recorded: Vec<&'static str>,
    /// Whether a recording began since the timer was made (its start is written).
    begun: bool,
    /// The spans of the last submitted recording: those whose timestamps may be read. A
    /// recording that failed, or was never submitted, writes none of its own.
    submitted: Vec<&'static str>,
}

impl GpuTimer {
    /// Creates the query pool for `capacity` timestamps (from 2, the start and the end, to
    /// [`MOST_TIMESTAMPS`]); `None` when the queue has no timestamps.
    pub fn new(device: &Arc<Device>, name: &str, capacity: u32) -> VkResult<Option<Self>> {
        if !device.capabilities().timestamps {
            return Ok(None);
        }
        let capacity = capacity.clamp(2, MOST_TIMESTAMPS);
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
            recorded: Vec::new(),
            begun: false,
            submitted: Vec::new(),
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
        self.recorded.clear();
        self.begun = true;
    }

    /// Records a timestamp once the commands recorded so far have completed: the end of the
    /// span `name` (from the last timestamp) and the start of the next. Returns whether there
    /// was room for it (the last query is kept for [`GpuTimer::end`]).
    pub fn mark(&mut self, command_buffer: vk::CommandBuffer, name: &'static str) -> bool {
        if !self.begun || self.written() + 1 >= self.capacity {
            return false;
        }
        self.write_after_all(command_buffer, name);
        true
    }

    /// Records the end timestamp, ending the span `name`; call after the measured commands.
    /// Returns whether it was written (always, after [`GpuTimer::begin`]: marks leave room for
    /// it).
    pub fn end(&mut self, command_buffer: vk::CommandBuffer, name: &'static str) -> bool {
        if !self.begun || self.written() >= self.capacity {
            return false;
        }
        self.write_after_all(command_buffer, name);
        true
    }

    /// Notes that the recording was submitted: its timestamps are the ones read from now on.
    pub fn submitted(&mut self) {
        self.submitted.clone_from(&self.recorded);
    }

    /// Timestamps the recording writes: its start and the end of each span.
    fn written(&self) -> u32 {
        self.recorded.len() as u32 + 1
    }

    /// Writes the next query once every command before has completed, ending span `name`.
    fn write_after_all(&mut self, command_buffer: vk::CommandBuffer, name: &'static str) {
        // SAFETY: command_buffer is recording; begin reset every query of the pool, and the
        // query written stays under the pool's capacity.
        unsafe {
            self.device.raw.cmd_write_timestamp2(
                command_buffer,
                vk::PipelineStageFlags2::BOTTOM_OF_PIPE,
                self.pool,
                self.written(),
            )
        };
        self.recorded.push(name);
    }

    /// Appends each span of the last submitted recording to `spans`, named, with its time in
    /// microseconds, once that submission has completed; returns whether there were any
    /// (none before anything was measured). Called every frame: it allocates nothing once
    /// `spans` has room.
    pub fn spans_us(&self, spans: &mut Vec<(&'static str, f64)>) -> VkResult<bool> {
        if self.submitted.is_empty() {
            return Ok(false);
        }
        let mut all_ticks = [0_u64; MOST_TIMESTAMPS as usize];
        let ticks = &mut all_ticks[..self.submitted.len() + 1];
        // Lavapipe leaks an allocation when a later one in this call fails.
        super::fault::with_first_host_memory_fault_only(|| {
            // SAFETY: the queries read were written by the last submission, which completed
            // (the caller waited).
            unsafe {
                self.device.raw.get_query_pool_results(
                    self.pool,
                    0,
                    ticks,
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
        spans.extend(
            self.submitted
                .iter()
                .zip(ticks.windows(2))
                .map(|(name, pair)| {
                    let delta = (pair[1] & mask).wrapping_sub(pair[0] & mask) & mask;
                    (*name, delta as f64 * period_ns / 1000.0)
                }),
        );
        Ok(true)
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
