//! Frames in flight: a ring of [`FrameSlot`]s, each owning what one submitted frame uses until
//! the GPU has finished it (its command buffers, its uniforms, its timers and the recording
//! it may submit again), and the rule that decides how long a new frame waits: for the frame
//! that last used its slot only when nothing but the view changed since the last frame and
//! every technique keeps its per-frame data per slot, otherwise for every earlier frame.

use std::sync::Arc;

use crate::error::RenderResult;
use crate::render::{FrameStats, FrameUniforms};
use crate::vk::raw as vk;
use crate::vk::{
    Buffer, CommandContext, Device, GpuTimer, MemoryLocation, VkResult, MOST_TIMESTAMPS,
};

/// The most frames a renderer lets the GPU work on while it records the next.
pub const MAX_FRAMES_IN_FLIGHT: u32 = 3;

/// Bytes between two slots' views in the GPU cullers' view buffer: the view's size rounded up
/// to 256, the alignment `CadrGpuCullContext::view_offset` promises (and the largest
/// `minUniformBufferOffsetAlignment` Vulkan allows).
pub(super) const CULL_VIEW_STRIDE: u64 =
    (std::mem::size_of::<cadr_plugin_abi::CadrGpuCullView>() as u64).next_multiple_of(256);

/// What one frame in flight owns until the GPU has finished it.
pub(super) struct FrameSlot {
    /// The frame's command buffers (the main one and the upload prologue) and its fence.
    pub commands: CommandContext,
    /// The frame uniforms, host-written when the frame is recorded or replayed (binding 0 of
    /// this slot's frame set).
    pub uniforms: Buffer,
    /// The GPU time of the frame's pass (the main command buffer), and of each of its passes
    /// (a span each, named by `FramePass::name`, then the techniques' work after them).
    pub pass_timer: Option<GpuTimer>,
    /// The GPU time of the frame's uploads (the prologue submitted ahead of the main buffer).
    pub upload_timer: Option<GpuTimer>,
    /// Whether the slot's last submission carried an upload prologue (its GPU time is the
    /// frame's too).
    pub submission_uploaded: bool,
    /// The frame in the command buffer, if it may be submitted again as it is: its replay
    /// key and what it drew.
    pub replayable: Option<(u64, FrameStats)>,
}

impl FrameSlot {
    /// A slot's command buffers, uniforms and timers, named after slot `index`.
    fn new(device: &Arc<Device>, index: usize) -> RenderResult<Self> {
        Ok(Self {
            commands: CommandContext::new(device, &format!("frame {index} commands"))?,
            uniforms: Buffer::new(
                device,
                &format!("frame {index} uniforms"),
                std::mem::size_of::<FrameUniforms>() as u64,
                vk::BufferUsageFlags::UNIFORM_BUFFER,
                MemoryLocation::CpuToGpu,
            )?,
            // As many timestamps as a timer holds: more than a frame has passes (the
            // preparation, two per culler phase, the passes over the picture, the pick readback,
            // the depth handed over, the techniques' work after them).
            pass_timer: GpuTimer::new(device, &format!("frame {index} timer"), MOST_TIMESTAMPS)?,
            upload_timer: GpuTimer::new(device, &format!("frame {index} upload timer"), 2)?,
            submission_uploaded: false,
            replayable: None,
        })
    }

    /// Notes that the slot's recordings (its pass and its upload prologue) were submitted:
    /// their timers read what those recordings write.
    pub fn timers_submitted(&mut self) {
        for timer in [&mut self.pass_timer, &mut self.upload_timer]
            .into_iter()
            .flatten()
        {
            timer.submitted();
        }
    }

    /// Writes the GPU time of each pass of the slot's last frame into `times`, named, in the
    /// order drawn (the uploads first where the frame had any); none where timestamps do not
    /// work. The frame must have finished.
    fn gpu_times(&self, times: &mut Vec<(&'static str, f64)>) -> VkResult<()> {
        times.clear();
        if let (Some(timer), true) = (&self.upload_timer, self.submission_uploaded) {
            timer.spans_us(times)?;
        }
        let measured = match &self.pass_timer {
            Some(timer) => timer.spans_us(times)?,
            None => false,
        };
        if !measured {
            times.clear();
        }
        Ok(())
    }
}

/// What decides how long a frame waits for earlier ones (see [`FrameSlots::begin_frame`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct FrameWait {
    /// What the frame's recording and the techniques' host writes depend on besides the view
    /// (scene generations, parameter values, passes, techniques, target); none for a pick.
    pub frame_key: Option<u64>,
    /// The frame's replay key, if it may be replayed.
    pub replay_key: Option<u64>,
    /// Whether every active technique keeps its per-frame data per frame slot.
    pub keeps_slots: bool,
    /// Whether the frame uploads scene data (through the GPU scene's one staging area).
    pub uploads: bool,
}

/// The ring of frame slots and where the frames stand in it.
pub(super) struct FrameSlots {
    /// [`MAX_FRAMES_IN_FLIGHT`] slots; the first `in_flight` are used.
    slots: Vec<FrameSlot>,
    /// How many frames the GPU may have (see `Renderer::set_frames_in_flight`).
    in_flight: u32,
    /// The slot of the frame being recorded, or of the last one.
    current: usize,
    /// The replay key of the last recorded frame (of any slot), if it had one: a slot's
    /// recording with the same key is a steady one, which may be replayed.
    last_recorded: Option<u64>,
    /// The key of the last frame (see [`FrameSlots::begin_frame`]).
    last_frame_key: Option<u64>,
    /// Whether the frame being recorded began after every earlier frame had finished.
    earlier_frames_finished: bool,
    /// The GPU time of each pass of the latest frame whose time was read (the frame the last
    /// `FrameStats::gpu_us` reports; empty while none is known).
    pass_times: Vec<(&'static str, f64)>,
    /// Where the next read goes, swapped with `pass_times` once it succeeded: reads allocate
    /// nothing after the first frames.
    pass_times_read: Vec<(&'static str, f64)>,
}

impl FrameSlots {
    /// [`MAX_FRAMES_IN_FLIGHT`] slots, one frame in flight.
    pub fn new(device: &Arc<Device>) -> RenderResult<Self> {
        let slots = (0..MAX_FRAMES_IN_FLIGHT as usize)
            .map(|index| FrameSlot::new(device, index))
            .collect::<RenderResult<Vec<_>>>()?;
        Ok(Self {
            slots,
            in_flight: 1,
            current: 0,
            last_recorded: None,
            last_frame_key: None,
            earlier_frames_finished: true,
            pass_times: Vec::new(),
            pass_times_read: Vec::new(),
        })
    }

    /// How many frames the GPU may have.
    pub fn in_flight(&self) -> u32 {
        self.in_flight
    }

    /// Lets the GPU have `frames` frames (1 to [`MAX_FRAMES_IN_FLIGHT`], checked by the
    /// caller) after waiting for every frame, so that the next frame starts a new ring.
    pub fn set_in_flight(&mut self, frames: u32) -> VkResult<()> {
        self.wait_all()?;
        self.in_flight = frames;
        self.current = self.current.min(frames as usize - 1);
        self.last_frame_key = None;
        Ok(())
    }

    /// Begins a frame as `wait` says and returns its slot, with the GPU time of the latest
    /// frame known to have finished when `frames_in_flight > 1`.
    ///
    /// Where an active technique does not keep its per-frame data per slot, the frame takes
    /// the slot of the last one and waits for every earlier frame: one recording, rewritten in
    /// place, as before frame slots. Otherwise it takes the next slot and waits only for the
    /// frame that last used it, unless its frame key is none or differs from the last frame's
    /// or it uploads scene data: then it waits for every earlier frame. Every slot's recording
    /// is forgotten when the replay key differs from the last frame's: techniques may then
    /// rewrite what those recordings use (secondary command buffers, indirect commands).
    pub fn begin_frame(&mut self, wait: FrameWait) -> VkResult<(usize, Option<f64>)> {
        let previous = self.current;
        let changed = wait.frame_key.is_none() || wait.frame_key != self.last_frame_key;
        self.last_frame_key = wait.frame_key;
        let overlaps = wait.keeps_slots && !changed && !wait.uploads && self.in_flight > 1;
        let slot = if wait.keeps_slots {
            (previous + 1) % self.in_flight as usize
        } else {
            previous
        };
        if overlaps {
            self.slots[slot].commands.wait()?;
        } else {
            self.wait_all()?;
        }
        if wait.replay_key.is_none() || wait.replay_key != self.last_recorded {
            for slot in &mut self.slots {
                slot.replayable = None;
            }
        }
        self.earlier_frames_finished = !overlaps;
        self.current = slot;
        // The latest finished frame: the previous one after waiting for all, else the one
        // that last used this slot.
        let finished = if overlaps { slot } else { previous };
        let gpu_us = if self.in_flight > 1 {
            self.read_gpu_time(finished)?
        } else {
            None
        };
        Ok((slot, gpu_us))
    }

    /// Reads the GPU time of slot `slot`'s last frame, which has finished: kept pass by pass
    /// ([`FrameSlots::pass_times`]) and returned whole. A read that fails keeps the times
    /// read before.
    pub fn read_gpu_time(&mut self, slot: usize) -> VkResult<Option<f64>> {
        self.slots[slot].gpu_times(&mut self.pass_times_read)?;
        std::mem::swap(&mut self.pass_times, &mut self.pass_times_read);
        let times = &self.pass_times;
        Ok((!times.is_empty()).then(|| times.iter().map(|(_, us)| us).sum()))
    }

    /// The GPU time of each pass of the latest frame whose time was read.
    pub fn pass_times(&self) -> &[(&'static str, f64)] {
        &self.pass_times
    }

    /// Whether the frame being recorded began after every earlier frame had finished.
    pub fn earlier_frames_finished(&self) -> bool {
        self.earlier_frames_finished
    }

    /// The slot of the frame being recorded (or of the last one).
    pub fn current_index(&self) -> usize {
        self.current
    }

    /// The slot of the frame being recorded (or of the last one).
    pub fn current(&self) -> &FrameSlot {
        &self.slots[self.current]
    }

    /// The slot of the frame being recorded.
    pub fn current_mut(&mut self) -> &mut FrameSlot {
        &mut self.slots[self.current]
    }

    /// Every slot (to set up what each names).
    pub fn all(&self) -> &[FrameSlot] {
        &self.slots
    }

    /// Records that the current slot's frame was recorded with `replay_key`: the recording
    /// may be replayed when the frame before it had the same key (the first recording after a
    /// change may do one-time work, such as clearing new buffers).
    pub fn keep_recording(&mut self, replay_key: Option<u64>, stats: FrameStats) {
        let steady = replay_key.is_some() && replay_key == self.last_recorded;
        let slot = &mut self.slots[self.current];
        slot.replayable = if steady {
            replay_key.map(|key| (key, stats))
        } else {
            None
        };
        self.last_recorded = replay_key;
    }

    /// Forgets every slot's recording: the next frames are recorded afresh, whatever their
    /// replay keys, and wait for every earlier frame.
    pub fn forget_recordings(&mut self) {
        for slot in &mut self.slots {
            slot.replayable = None;
        }
        self.last_recorded = None;
        self.last_frame_key = None;
    }

    /// Waits until the GPU has finished every frame.
    pub fn wait_all(&self) -> VkResult<()> {
        for slot in &self.slots {
            slot.commands.wait()?;
        }
        Ok(())
    }
}
