//! Drawing through `VK_EXT_device_generated_commands`: the commands of a pass (written by a
//! GPU culler, or by the submission from its list) are a stream of sequences that
//! `vkCmdExecuteGeneratedCommandsEXT` runs, as many as the `u32` count in GPU memory says.
//!
//! A pass's stream holds only indexed draws, drawn with the pass's pipeline: the indirect
//! commands layout is one `DRAW_INDEXED` token at offset 0, one sequence every `stride` bytes,
//! the stream the cullers already write. Where the host splits the opaque surfaces into a pass
//! whose pipeline culls back faces and one that keeps them, the GPU culler writes both passes
//! into one stream whose commands each start with a word naming their pass
//! (`CadrSharedFaceStreams`): the layout is then an `EXECUTION_SET` token at offset
//! 0 and the draw at 4, and an execution set holding the two pipelines (index 0 the culled
//! pass's, 1 the kept pass's) lets the GPU switch pipeline per sequence, the whole split drawn
//! by one execution. Where the host asks for parameter blocks (plugin ABI 1.22,
//! `CadrParameterBlocks`: the `push` parameter path with a GPU culler), each draw comes after
//! its instance's 96-byte block, which a `PUSH_CONSTANT` token pushes at offset 0 of the vertex
//! stage's push constants: the matrix and material values then reach the shaders as `push`
//! gives them, written by the GPU. The implementation preprocesses the
//! stream into memory of its own ("preprocess" memory, sized by
//! `vkGetGeneratedCommandsMemoryRequirementsEXT`); each execution of a frame gets a region of
//! it, and frames rotate through [`FRAMES`] sets of regions so that a frame never writes what
//! an earlier one still reads.
//!
//! A pass runs as chunks ([`chunk_size_for`] picks their size): Mesa 25.0's lavapipe asks for
//! memory that grows with the square of the sequences (and wraps at 4 GiB: 394 MB for 1 654
//! sequences, 3.6 MB for 16 384), so a large pass runs as many small chunks; NVIDIA's driver
//! (580 on an H200) asks for tens of kilobytes an execution plus a little a sequence, so a pass
//! runs as one chunk (chunks of one sequence cost it 0.8 s a frame). Every chunk reads
//! the pass's count and runs at most its own share; what lies past the count in the stream is
//! zeroed by the GPU cullers (a draw of no instances: `dgc` announces
//! `CADR_TRAIT_EMPTY_COMMAND_TAILS`, so the host asks them to) or never there (the lists).

use std::sync::Arc;

use cadr_plugin_sdk::abi;
use cadr_plugin_sdk::dgc;
use cadr_plugin_sdk::vk;
use cadr_plugin_sdk::{vulkan_failure, Gpu};

/// Frames whose preprocess regions are kept apart (the host has at most this many in flight).
const FRAMES: u64 = 3;
/// The most preprocess memory the chunks of one pass may ask for together, unless a chunk of
/// one sequence asks for more.
const PASS_BYTES: u64 = 64 << 20;
/// The most sequences one chunk runs.
const MAX_CHUNK: u32 = 1 << 20;
/// The most (pipeline, sequences) pairs whose chunk size is remembered.
const KEPT_CHUNK_SIZES: usize = 64;
/// Bytes before the draw of a sequence that names its pipeline (the execution-set index).
const PIPELINE_INDEX_BYTES: u32 = crate::NAMED_COMMAND_BYTES - 20;
/// Bytes of a parameter block (`CadrParameterBlock`), before the draw where sequences carry one.
const PARAMETER_BLOCK_BYTES: u32 = std::mem::size_of::<abi::CadrParameterBlock>() as u32;

/// One execution: the pass's pipeline and where its sequences and count are.
#[derive(Clone, Copy)]
pub struct Execution {
    /// Which of the record's passes it draws (the first, where it draws two).
    pub pass: usize,
    /// The pass's pipeline (bound before the execution).
    pub pipeline: vk::Pipeline,
    /// Where the stream is shared with the next pass, that pass's pipeline: each sequence
    /// starts with the index of its pipeline, 0 for `pipeline`, 1 for this one.
    pub next_pass_pipeline: Option<vk::Pipeline>,
    pub commands: vk::Buffer,
    pub commands_offset: u64,
    pub count: vk::Buffer,
    pub count_offset: u64,
    pub max_sequences: u32,
    pub stride: u32,
    /// Where each draw comes after its parameter block, the pipeline layout the blocks are
    /// pushed with.
    pub parameter_blocks: Option<vk::PipelineLayout>,
}

/// One chunk of an execution, as [`GeneratedCommands::begin_frame`] prepared it.
pub struct Chunk {
    /// The sequences it runs (a part of its execution's).
    pub execution: Execution,
    /// Its preprocess region: address and size.
    region: (vk::DeviceAddress, u64),
    /// The layout of its sequences.
    layout: dgc::IndirectCommandsLayout,
    /// What draws them.
    drawer: Drawer,
}

/// What draws an execution's sequences: the bound pipeline, or an execution set the sequences
/// pick from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Drawer {
    Pipeline(vk::Pipeline),
    Set(dgc::IndirectExecutionSet),
}

/// An execution set of two pipelines, the commands key of the recordings it may serve, and
/// the frame that last used it.
struct PipelinePair {
    pipelines: [vk::Pipeline; 2],
    /// The host's commands key when it was made: a pipeline handle is only known to name the
    /// same pipeline while the key stays (the host may destroy pipelines and make others, with
    /// the handles of the old, when the key changes).
    commands_key: u64,
    set: dgc::IndirectExecutionSet,
    last_used: u64,
}

/// Preprocess memory: a buffer with its own allocation and device address.
struct Preprocess {
    buffer: vk::Buffer,
    memory: vk::DeviceMemory,
    address: vk::DeviceAddress,
    /// Bytes of one frame's regions.
    frame_bytes: u64,
}

/// The layout, the preprocess memory and the frame rotation of a `dgc` submission.
pub struct GeneratedCommands {
    gpu: Arc<Gpu>,
    functions: dgc::Device,
    /// The layouts made, each with what it was made for.
    layouts: Vec<(LayoutKey, dgc::IndirectCommandsLayout)>,
    /// The execution sets of the pipeline pairs of shared streams.
    pairs: Vec<PipelinePair>,
    preprocess: Option<Preprocess>,
    /// Frames begun.
    frame: u64,
    /// Per layout, drawer and sequences of a pass, the most sequences a chunk runs.
    chunk_sizes: Vec<((dgc::IndirectCommandsLayout, Drawer, u32), u32)>,
}

/// What a layout of sequences is made for: their stride, whether they name their pipeline, and
/// the pipeline layout their parameter blocks are pushed with (null without blocks).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct LayoutKey {
    stride: u32,
    names_pipeline: bool,
    parameter_blocks: vk::PipelineLayout,
}

/// The stages the sequences' state reaches (the draw token's pipelines).
const STAGES: vk::ShaderStageFlags = vk::ShaderStageFlags::from_raw(
    vk::ShaderStageFlags::VERTEX.as_raw() | vk::ShaderStageFlags::FRAGMENT.as_raw(),
);

impl GeneratedCommands {
    /// Refused where the host did not enable the extension.
    pub fn new(gpu: &Arc<Gpu>) -> Result<Self, String> {
        let functions = gpu
            .generated_commands
            .clone()
            .ok_or("the device has no VK_EXT_device_generated_commands")?;
        Ok(Self {
            gpu: Arc::clone(gpu),
            functions,
            layouts: Vec::new(),
            pairs: Vec::new(),
            preprocess: None,
            frame: 0,
            chunk_sizes: Vec::new(),
        })
    }

    /// The layout of sequences made for `key`: each the index of its pipeline in the execution
    /// set where it names its pipeline, then its parameter block where it carries one, then
    /// the draw. Layouts are kept until the submission is dropped (there are a few: one per
    /// stride and kind, and per pipeline layout the host drew blocks with).
    fn layout(&mut self, key: LayoutKey) -> Result<dgc::IndirectCommandsLayout, String> {
        if let Some(&(_, layout)) = self.layouts.iter().find(|(made_for, _)| *made_for == key) {
            return Ok(layout);
        }
        let set_token = dgc::ExecutionSetToken {
            ty: dgc::EXECUTION_SET_OF_PIPELINES,
            shader_stages: STAGES,
        };
        let push_token = dgc::PushConstantToken {
            update_range: vk::PushConstantRange::default()
                .stage_flags(vk::ShaderStageFlags::VERTEX)
                .size(PARAMETER_BLOCK_BYTES),
        };
        let mut tokens = Vec::with_capacity(3);
        let mut offset = 0;
        if key.names_pipeline {
            tokens.push(dgc::LayoutToken::execution_set(&set_token, offset));
            offset += PIPELINE_INDEX_BYTES;
        }
        if key.parameter_blocks != vk::PipelineLayout::null() {
            tokens.push(dgc::LayoutToken::push_constant(&push_token, offset));
            offset += PARAMETER_BLOCK_BYTES;
        }
        tokens.push(dgc::LayoutToken::draw_indexed(offset));
        let info = dgc::LayoutCreateInfo::new(
            dgc::LayoutUsageFlags::default(),
            STAGES,
            key.stride,
            key.parameter_blocks,
            &tokens,
        );
        // SAFETY: the info and its tokens live for the call.
        let layout = unsafe { self.functions.create_layout(&info, self.gpu.allocator()) }
            .map_err(vulkan_failure("vkCreateIndirectCommandsLayoutEXT"))?;
        self.layouts.push((key, layout));
        Ok(layout)
    }

    /// The execution set of `pipelines` (index 0 and 1) for recordings of `commands_key`, made
    /// on first use. Sets unused for more frames than can be in flight are destroyed.
    fn pipeline_pair(
        &mut self,
        pipelines: [vk::Pipeline; 2],
        commands_key: u64,
    ) -> Result<dgc::IndirectExecutionSet, String> {
        let frame = self.frame;
        if let Some(pair) = self
            .pairs
            .iter_mut()
            .find(|p| p.pipelines == pipelines && p.commands_key == commands_key)
        {
            pair.last_used = frame;
            return Ok(pair.set);
        }
        let info = dgc::ExecutionSetPipelineInfo::new(pipelines[0], 2);
        let create = dgc::ExecutionSetCreateInfo::pipelines(&info);
        // SAFETY: the info lives for the call; the host made both pipelines indirect-bindable
        // (CADR_TRAIT_SWITCHES_PIPELINES) and they are alive.
        let set = unsafe {
            self.functions
                .create_execution_set(&create, self.gpu.allocator())
        }
        .map_err(vulkan_failure("vkCreateIndirectExecutionSetEXT"))?;
        let write = [dgc::WriteExecutionSetPipeline::new(1, pipelines[1])];
        // SAFETY: the set was just made; index 1 is within its two and used by no command.
        unsafe { self.functions.update_execution_set_pipelines(set, &write) };
        self.pairs.push(PipelinePair {
            pipelines,
            commands_key,
            set,
            last_used: frame,
        });
        Ok(set)
    }

    /// Destroys the execution sets no frame in flight can use.
    fn forget_old_pairs(&mut self) {
        let frame = self.frame;
        let (old, kept): (Vec<_>, Vec<_>) = std::mem::take(&mut self.pairs)
            .into_iter()
            .partition(|pair| pair.last_used + FRAMES < frame);
        self.pairs = kept;
        for pair in old {
            // SAFETY: the frames that used it have finished (the host keeps at most FRAMES in
            // flight).
            unsafe {
                self.functions
                    .destroy_execution_set(pair.set, self.gpu.allocator())
            };
        }
    }

    /// Bytes of preprocess memory, and their alignment and memory types, that `execution`
    /// needs.
    fn requirements(
        &self,
        layout: dgc::IndirectCommandsLayout,
        drawer: Drawer,
        sequences: u32,
    ) -> vk::MemoryRequirements {
        let (set, pipeline) = match drawer {
            Drawer::Pipeline(pipeline) => (
                dgc::IndirectExecutionSet::null(),
                Some(dgc::GeneratedCommandsPipelineInfo::new(pipeline)),
            ),
            Drawer::Set(set) => (set, None),
        };
        let info = dgc::MemoryRequirementsInfo::new(layout, set, pipeline.as_ref(), sequences);
        // SAFETY: the layout and the pipeline or set are alive.
        unsafe { self.functions.memory_requirements(&info) }
    }

    /// The most sequences one chunk of a pass of `sequences` drawn by `drawer` runs (see
    /// [`chunk_size_for`]), remembered per layout, drawer and pass size.
    fn chunk_size(
        &mut self,
        layout: dgc::IndirectCommandsLayout,
        drawer: Drawer,
        sequences: u32,
    ) -> u32 {
        let key = (layout, drawer, sequences);
        if let Some(&(_, size)) = self.chunk_sizes.iter().find(|(k, _)| *k == key) {
            return size;
        }
        let size = chunk_size_for(sequences, |chunk| {
            self.requirements(layout, drawer, chunk).size
        });
        if self.chunk_sizes.len() >= KEPT_CHUNK_SIZES {
            self.chunk_sizes.clear();
        }
        self.chunk_sizes.push((key, size));
        size
    }

    /// Makes sure one frame's regions hold `frame_bytes` of memory of `types`.
    fn reserve(&mut self, frame_bytes: u64, types: u32) -> Result<&Preprocess, String> {
        if self
            .preprocess
            .as_ref()
            .is_some_and(|p| p.frame_bytes >= frame_bytes)
        {
            return self.preprocess.as_ref().ok_or_else(String::new);
        }
        if let Some(old) = self.preprocess.take() {
            // Earlier frames may still read it: growing is rare (a larger scene).
            // SAFETY: the device is the host's, alive.
            unsafe { self.gpu.device.device_wait_idle() }
                .map_err(vulkan_failure("vkDeviceWaitIdle"))?;
            self.free(old);
        }
        let frame_bytes = frame_bytes.next_power_of_two().max(256);
        let preprocess = self.allocate(frame_bytes, types)?;
        Ok(self.preprocess.insert(preprocess))
    }

    fn allocate(&self, frame_bytes: u64, types: u32) -> Result<Preprocess, String> {
        let device = &self.gpu.device;
        let mut usage = vk::BufferUsageFlags2CreateInfoKHR::default().usage(
            dgc::BUFFER_USAGE_2_PREPROCESS_BUFFER | vk::BufferUsageFlags2KHR::SHADER_DEVICE_ADDRESS,
        );
        // The usage given in VkBufferUsageFlags2CreateInfoKHR is the buffer's; the legacy
        // field, which the driver then ignores, repeats what it can for validation layers
        // older than VK_KHR_maintenance5.
        let info = vk::BufferCreateInfo::default()
            .size(frame_bytes * FRAMES)
            .usage(vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS)
            .push_next(&mut usage);
        // SAFETY: the info lives for the call; the buffer is destroyed in `free`.
        let buffer =
            unsafe { device.create_buffer(&info, self.gpu.allocator()) }.map_err(|result| {
                format!(
                    "{} ({} bytes of preprocess memory)",
                    vulkan_failure("vkCreateBuffer")(result),
                    frame_bytes * FRAMES
                )
            })?;
        // SAFETY: the buffer was just made on this device.
        let needs = unsafe { device.get_buffer_memory_requirements(buffer) };
        // SAFETY: the physical device is the one the host's device was made on.
        let properties = unsafe {
            self.gpu
                .instance
                .get_physical_device_memory_properties(self.gpu.physical_device)
        };
        let allowed = needs.memory_type_bits & types;
        let pick = |wanted: vk::MemoryPropertyFlags| {
            (0..properties.memory_type_count).find(|&i| {
                allowed & (1 << i) != 0
                    && properties.memory_types[i as usize]
                        .property_flags
                        .contains(wanted)
            })
        };
        let Some(memory_type) =
            pick(vk::MemoryPropertyFlags::DEVICE_LOCAL).or_else(|| pick(Default::default()))
        else {
            // SAFETY: nothing uses the buffer yet.
            unsafe { device.destroy_buffer(buffer, self.gpu.allocator()) };
            return Err("no memory type holds preprocess buffers".into());
        };
        let mut flags =
            vk::MemoryAllocateFlagsInfo::default().flags(vk::MemoryAllocateFlags::DEVICE_ADDRESS);
        let allocate = vk::MemoryAllocateInfo::default()
            .allocation_size(needs.size)
            .memory_type_index(memory_type)
            .push_next(&mut flags);
        // SAFETY: the info lives for the call; the memory is freed in `free`.
        let memory = match unsafe { device.allocate_memory(&allocate, self.gpu.allocator()) } {
            Ok(memory) => memory,
            Err(result) => {
                // SAFETY: nothing uses the buffer yet.
                unsafe { device.destroy_buffer(buffer, self.gpu.allocator()) };
                return Err(vulkan_failure("vkAllocateMemory (preprocess)")(result));
            }
        };
        let preprocess = Preprocess {
            buffer,
            memory,
            address: 0,
            frame_bytes,
        };
        // SAFETY: the memory is of a type the buffer allows, large enough, not bound yet.
        if let Err(result) = unsafe { device.bind_buffer_memory(buffer, memory, 0) } {
            self.free(preprocess);
            return Err(vulkan_failure("vkBindBufferMemory (preprocess)")(result));
        }
        let address_info = vk::BufferDeviceAddressInfo::default().buffer(buffer);
        // SAFETY: the buffer is bound and has the device address usage.
        let address = unsafe { device.get_buffer_device_address(&address_info) };
        Ok(Preprocess {
            address,
            ..preprocess
        })
    }

    fn free(&self, preprocess: Preprocess) {
        // SAFETY: no pending frame uses it (the caller waited, or the submission is dropped
        // after the host's wait).
        unsafe {
            self.gpu
                .device
                .destroy_buffer(preprocess.buffer, self.gpu.allocator());
            self.gpu
                .device
                .free_memory(preprocess.memory, self.gpu.allocator());
        }
    }

    fn address(&self, buffer: vk::Buffer, offset: u64) -> vk::DeviceAddress {
        let info = vk::BufferDeviceAddressInfo::default().buffer(buffer);
        // SAFETY: the buffer is alive and was made with the device address usage (the host
        // adds nothing; the cullers and the lists ask for it).
        unsafe { self.gpu.device.get_buffer_device_address(&info) + offset }
    }

    /// Prepares a frame of `executions`, recorded under the host's `commands_key`: the layouts
    /// and execution sets, and every execution split into chunks, each with its preprocess
    /// region (address and size), in order.
    pub fn begin_frame(
        &mut self,
        executions: &[Execution],
        commands_key: u64,
    ) -> Result<Vec<Vec<Chunk>>, String> {
        self.frame += 1;
        self.forget_old_pairs();
        let mut chunked = Vec::with_capacity(executions.len());
        let mut frame_bytes: u64 = 0;
        let mut types = u32::MAX;
        for execution in executions {
            let (layout, drawer) = self.drawn_by(execution, commands_key)?;
            let chunk = self.chunk_size(layout, drawer, execution.max_sequences);
            // Every chunk but the last is full: two queries per pass, whatever the chunks.
            let full = self.requirements(layout, drawer, chunk);
            let mut chunks = Vec::new();
            let mut first = 0;
            while first < execution.max_sequences {
                let sequences = chunk.min(execution.max_sequences - first);
                let needs = if sequences == chunk {
                    full
                } else {
                    self.requirements(layout, drawer, sequences)
                };
                frame_bytes = frame_bytes.next_multiple_of(needs.alignment.max(1));
                chunks.push(Chunk {
                    execution: Execution {
                        commands_offset: execution.commands_offset
                            + u64::from(first) * u64::from(execution.stride),
                        max_sequences: sequences,
                        ..*execution
                    },
                    region: (frame_bytes, needs.size),
                    layout,
                    drawer,
                });
                frame_bytes += needs.size;
                types &= needs.memory_type_bits;
                first += sequences;
            }
            chunked.push(chunks);
        }
        if chunked.is_empty() {
            return Ok(chunked);
        }
        let frame = self.frame % FRAMES;
        let preprocess = self.reserve(frame_bytes, types)?;
        let base = preprocess.address + frame * preprocess.frame_bytes;
        for chunk in chunked.iter_mut().flatten() {
            chunk.region.0 += base;
        }
        Ok(chunked)
    }

    /// The layout of `execution`'s sequences and what draws them: its pipeline, or where the
    /// stream is shared with the next pass, the execution set of both passes' pipelines.
    fn drawn_by(
        &mut self,
        execution: &Execution,
        commands_key: u64,
    ) -> Result<(dgc::IndirectCommandsLayout, Drawer), String> {
        let parameter_blocks = execution
            .parameter_blocks
            .unwrap_or(vk::PipelineLayout::null());
        let names_pipeline = execution.next_pass_pipeline.is_some();
        let least_stride = sequence_bytes(names_pipeline, execution.parameter_blocks.is_some());
        if execution.stride < least_stride {
            return Err(format!(
                "a stream of {}-byte commands: each needs {least_stride} bytes ({})",
                execution.stride,
                if names_pipeline {
                    "its pipeline's index, then its parameter block where it has one, then its draw"
                } else {
                    "its parameter block, then its draw"
                }
            ));
        }
        let layout = self.layout(LayoutKey {
            stride: execution.stride,
            names_pipeline,
            parameter_blocks,
        })?;
        match execution.next_pass_pipeline {
            Some(next) => {
                let set = self.pipeline_pair([execution.pipeline, next], commands_key)?;
                Ok((layout, Drawer::Set(set)))
            }
            None => Ok((layout, Drawer::Pipeline(execution.pipeline))),
        }
    }

    /// Records `chunk` (its execution's pipeline and bindings already bound, inside rendering).
    pub fn execute(&self, command_buffer: vk::CommandBuffer, chunk: &Chunk) -> Result<(), String> {
        let execution = &chunk.execution;
        let pipeline;
        let (set, p_next) = match chunk.drawer {
            Drawer::Set(set) => (set, std::ptr::null()),
            // The bound pipeline draws a stream without an execution set.
            Drawer::Pipeline(bound) => {
                pipeline = dgc::GeneratedCommandsPipelineInfo::new(bound);
                (
                    dgc::IndirectExecutionSet::null(),
                    (&pipeline as *const dgc::GeneratedCommandsPipelineInfo<'_>).cast(),
                )
            }
        };
        let info = dgc::GeneratedCommandsInfo {
            p_next,
            shader_stages: STAGES,
            indirect_execution_set: set,
            indirect_commands_layout: chunk.layout,
            indirect_address: self.address(execution.commands, execution.commands_offset),
            indirect_address_size: u64::from(execution.max_sequences) * u64::from(execution.stride),
            preprocess_address: chunk.region.0,
            preprocess_size: chunk.region.1,
            max_sequence_count: execution.max_sequences,
            sequence_count_address: self.address(execution.count, execution.count_offset),
            ..Default::default()
        };
        // SAFETY: recording inside rendering with the pass's pipeline (the set's initial one)
        // bound; the stream, the count and the preprocess region stay alive until the frame
        // has run.
        unsafe { self.functions.cmd_execute(command_buffer, false, &info) };
        Ok(())
    }
}

/// Bytes of a sequence's tokens: the pipeline's index where it names one, the parameter block
/// where it carries one, and the draw.
pub fn sequence_bytes(names_pipeline: bool, parameter_blocks: bool) -> u32 {
    u32::from(names_pipeline) * PIPELINE_INDEX_BYTES
        + u32::from(parameter_blocks) * PARAMETER_BLOCK_BYTES
        + 20
}

/// The most sequences one chunk of a pass of `sequences` runs, given `chunk_bytes`, the
/// preprocess memory the driver asks for a chunk of so many sequences. Sizes are tried from 1,
/// doubling up to the pass's sequences or [`MAX_CHUNK`], and stop where a chunk's memory shrinks as it grows (a size
/// that wrapped). Of those, the largest whose chunks together (the pass) ask for at most
/// [`PASS_BYTES`]; where none fits, the largest whose pass asks for at most an eighth more than
/// the least any size asks for.
///
/// The two shapes of driver this serves: a GPU driver asks for a constant (tens of kilobytes on
/// NVIDIA) plus tens of bytes a sequence, so the pass is cheapest as one chunk, and many small
/// chunks would cost an execution each (68 462 of them on gen:graphicscard: 0.8 s a frame);
/// Mesa 25.0's lavapipe asks for memory that grows with the square of the sequences, so a
/// large pass needs many small chunks.
fn chunk_size_for(sequences: u32, mut chunk_bytes: impl FnMut(u32) -> u64) -> u32 {
    let pass_bytes =
        |size: u32, bytes: u64| u64::from(sequences.div_ceil(size)).saturating_mul(bytes);
    let mut bytes = chunk_bytes(1);
    let mut tried = vec![(1, pass_bytes(1, bytes))];
    let mut size = 1;
    while size < MAX_CHUNK.min(sequences) {
        let next_size = (size * 2).min(MAX_CHUNK).min(sequences);
        let next = chunk_bytes(next_size);
        if next < bytes {
            break;
        }
        (size, bytes) = (next_size, next);
        tried.push((size, pass_bytes(size, bytes)));
    }
    let largest_within = |limit: u64| {
        tried
            .iter()
            .filter(|&&(_, pass)| pass <= limit)
            .map(|&(size, _)| size)
            .max()
    };
    let least = tried.iter().map(|&(_, pass)| pass).min().unwrap_or(0);
    // Where the budget cannot be met, fewer executions are worth an eighth more memory.
    largest_within(PASS_BYTES)
        .or_else(|| largest_within(least.saturating_add(least / 8)))
        .unwrap_or(1)
}

impl Drop for GeneratedCommands {
    fn drop(&mut self) {
        if let Some(preprocess) = self.preprocess.take() {
            self.free(preprocess);
        }
        // SAFETY: the host drops techniques after the GPU finished their frames.
        unsafe {
            for pair in self.pairs.drain(..) {
                self.functions
                    .destroy_execution_set(pair.set, self.gpu.allocator());
            }
            for (_, layout) in self.layouts.drain(..) {
                self.functions.destroy_layout(layout, self.gpu.allocator());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A GPU driver's shape: a constant plus a little per sequence.
    fn constant_plus_linear(sequences: u32) -> u64 {
        32_768 + 40 * u64::from(sequences)
    }

    /// Mesa 25.0 lavapipe's shape: the square of the sequences, wrapping at 4 GiB.
    fn square_wrapping(sequences: u32) -> u64 {
        (144 * u64::from(sequences) * u64::from(sequences)) % (1 << 32)
    }

    #[test]
    fn a_driver_with_a_constant_per_execution_runs_a_pass_as_one_chunk() {
        // 68 462 chunks of one would ask for 2.2 GB; one chunk asks for 2.8 MB.
        assert_eq!(chunk_size_for(68_462, constant_plus_linear), 68_462);
        assert_eq!(chunk_size_for(1_000, constant_plus_linear), 1_000);
        assert_eq!(chunk_size_for(1, constant_plus_linear), 1);
    }

    #[test]
    fn a_pass_over_the_budget_takes_the_chunks_that_ask_for_least() {
        // Ten million sequences: 400 MB at best, more than PASS_BYTES; still chunks of the
        // most sequences one chunk may run.
        assert_eq!(chunk_size_for(10_000_000, constant_plus_linear), MAX_CHUNK);
    }

    #[test]
    fn a_driver_whose_memory_grows_with_the_square_runs_small_chunks() {
        let size = chunk_size_for(68_462, square_wrapping);
        let pass = u64::from(68_462u32.div_ceil(size)) * square_wrapping(size);
        assert!(
            pass <= PASS_BYTES,
            "{size} sequences a chunk ask for {pass} bytes"
        );
        assert!(square_wrapping(size * 2) * u64::from(68_462u32.div_ceil(size * 2)) > PASS_BYTES);
        assert!(size > 1 && size < 1 << 12, "{size}");
    }

    #[test]
    fn a_size_that_wrapped_is_never_chosen() {
        // At 4 096 sequences a chunk's size wraps to 32 KiB, which would look cheapest.
        let wrapping = |sequences: u32| (32_768 + 4_096 * u64::from(sequences)) % (1 << 24);
        assert_eq!(chunk_size_for(100_000, wrapping), 2_048);
    }
}
