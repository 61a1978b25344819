//! Draw submission: which draws are issued and how (the seeds' strategies and their
//! glMultiDraw*, MDI and token-buffer rows in Vulkan form).
//!
//! A technique is a strategy ([`lists::Strategy`]: individual, sorted, join, material groups),
//! an API (direct `vkCmdDrawIndexed`, `VK_EXT_multi_draw`, multi-draw-indirect, indirect with
//! count) and a recording mode: inline every frame, recorded once into a secondary command
//! buffer and replayed while nothing changed (the Vulkan form of the seeds' token buffer), or
//! recorded every frame in parallel on worker threads. Bindings are filtered by the vertex and
//! parameter paths' bind states, so an unchanged binding is never re-issued.

mod generated;
pub mod lists;
mod mesh_tasks;
mod record;

use std::sync::Arc;

use crate::{KEEPS_FRAME_SLOTS, REPLAYABLE};
use cadr_plugin_sdk::abi;
use cadr_plugin_sdk::vk::{self, Handle};
use cadr_plugin_sdk::{
    grown_capacity, technique_library, Gpu, HostBuffer, PassFilter, Record, Submission, Technique,
};

use generated::{Execution, GeneratedCommands};
use lists::{PassList, Strategy};
use mesh_tasks::MeshTasks;
use record::{Api, PassDraws, Recorder, SecondaryBuffers};

/// The recording mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    Inline,
    Replay,
    Threads,
}

const INDIVIDUAL: u8 = 0;
const SORTED: u8 = 1;
const JOIN: u8 = 2;
const GROUPS: u8 = 3;
const DIRECT: u8 = 0;
const MULTI_DRAW: u8 = 1;
const INDIRECT: u8 = 2;
const INDIRECT_COUNT: u8 = 3;
const GENERATED: u8 = 4;
const INLINE: u8 = 0;
const REPLAY: u8 = 1;
const THREADS: u8 = 2;

fn strategy(code: u8) -> Strategy {
    match code {
        SORTED => Strategy::Sorted,
        JOIN => Strategy::Join,
        GROUPS => Strategy::Groups,
        _ => Strategy::Individual,
    }
}

fn api(code: u8) -> Api {
    match code {
        MULTI_DRAW => Api::MultiDraw,
        INDIRECT => Api::Indirect,
        INDIRECT_COUNT => Api::IndirectCount,
        GENERATED => Api::Generated,
        _ => Api::Direct,
    }
}

fn mode(code: u8) -> Mode {
    match code {
        REPLAY => Mode::Replay,
        THREADS => Mode::Threads,
        _ => Mode::Inline,
    }
}

/// Indirect commands of one list, on the GPU.
#[derive(Default)]
struct IndirectPass {
    commands: Option<HostBuffer>,
    count: Option<HostBuffer>,
    draws: u32,
}

/// What a list is made for: a pass slot (the kind's ranges) and the pass's filter. Passes with
/// equal keys draw the same list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct ListKey {
    slot: usize,
    filter: PassFilter,
}

/// A list kept for the passes of its key, with its indirect commands.
struct KeptList {
    key: ListKey,
    /// The scene generations it was built for.
    built_for: Option<(u64, u64)>,
    list: PassList,
    indirect: IndirectPass,
    /// Whether `indirect` holds the commands of `list`.
    indirect_written: bool,
}

/// The most lists kept (every pass set and filter a frame alternates between).
const MAX_KEPT_LISTS: usize = 12;

/// One submission technique.
pub struct Submit<const STRATEGY: u8, const API: u8, const MODE: u8> {
    gpu: Arc<Gpu>,
    kept: Vec<KeptList>,
    /// Per pass of the last record, the kept list it draws.
    pass_lists: Vec<usize>,
    secondary: Option<SecondaryBuffers>,
    recorded_key: Option<u64>,
    recorded_stats: abi::CadrStats,
    /// The secondary buffers the recording executes, in order.
    recorded_order: Vec<vk::CommandBuffer>,
    /// With [`Api::Generated`], the commands layout and preprocess memory.
    generated: Option<GeneratedCommands>,
}

impl<const S: u8, const A: u8, const M: u8> Technique for Submit<S, A, M> {
    fn create(gpu: Arc<Gpu>) -> Result<Self, String> {
        let buffers = match mode(M) {
            Mode::Inline => 0,
            Mode::Replay => 1,
            Mode::Threads => gpu.worker_threads,
        };
        let secondary = if buffers > 0 {
            Some(SecondaryBuffers::new(&gpu, buffers)?)
        } else {
            None
        };
        let generated = if api(A) == Api::Generated {
            Some(GeneratedCommands::new(&gpu)?)
        } else {
            None
        };
        Ok(Self {
            gpu,
            generated,
            kept: Vec::new(),
            pass_lists: Vec::new(),
            secondary,
            recorded_key: None,
            recorded_stats: abi::CadrStats::default(),
            recorded_order: Vec::new(),
        })
    }
}

/// The ranges a pass kind draws: triangles, edges, or the pick pass's (unknown kinds draw as
/// triangles).
pub(crate) fn pass_slot(kind: abi::CadrPassKind) -> usize {
    match kind {
        abi::CADR_PASS_EDGES => 1,
        abi::CADR_PASS_PICK => 2,
        _ => 0,
    }
}

impl<const S: u8, const A: u8, const M: u8> Submit<S, A, M> {
    /// Finds or makes the list of each of the record's passes and rebuilds those whose draws
    /// changed since they were built; true when any was.
    fn refresh_lists(&mut self, record: &Record<'_>) -> bool {
        let scene = record.scene();
        let generations = (scene.raw().draws_generation, scene.raw().buffers_generation);
        if self.kept.len() > MAX_KEPT_LISTS {
            self.kept.clear();
        }
        self.pass_lists.clear();
        let mut changed = false;
        for (pass, filter) in record.passes().iter().zip(record.pass_filters()) {
            let key = ListKey {
                slot: pass_slot(pass.kind),
                filter,
            };
            let index = match self.kept.iter().position(|kept| kept.key == key) {
                Some(index) => index,
                None => {
                    self.kept.push(KeptList {
                        key,
                        built_for: None,
                        list: PassList::default(),
                        indirect: IndirectPass::default(),
                        indirect_written: false,
                    });
                    self.kept.len() - 1
                }
            };
            let kept = &mut self.kept[index];
            if kept.built_for != Some(generations) {
                kept.list = lists::build(&scene, (pass.kind, filter), strategy(S));
                kept.built_for = Some(generations);
                kept.indirect_written = false;
                changed = true;
            }
            self.pass_lists.push(index);
        }
        changed
    }

    /// Writes the indirect commands of every pass's list that lacks them.
    fn write_indirect(&mut self, record: &Record<'_>) -> Result<(), String> {
        let instances = record.scene().instances();
        for &index in &self.pass_lists {
            let kept = &mut self.kept[index];
            if kept.indirect_written {
                continue;
            }
            let list = &kept.list;
            let mut bytes: Vec<u8> = Vec::with_capacity(list.ranges.len() * 20);
            for batch in &list.batches {
                for range in &list.ranges[batch.ranges.clone()] {
                    let vertex_base = instances
                        .get(range.instance as usize)
                        .map_or(0, |i| i.vertex_base);
                    for word in [range.count, 1, range.first, vertex_base, batch.instance] {
                        bytes.extend_from_slice(&word.to_le_bytes());
                    }
                }
            }
            let draws = (bytes.len() / 20) as u32;
            let indirect = &mut kept.indirect;
            let needed = (bytes.len() as u64).max(20);
            // Generated commands read the stream and the count by device address.
            let usage = if api(A) == Api::Generated {
                vk::BufferUsageFlags::INDIRECT_BUFFER | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS
            } else {
                vk::BufferUsageFlags::INDIRECT_BUFFER
            };
            let held = indirect.commands.as_ref().map_or(0, HostBuffer::size);
            if held < needed {
                indirect.commands = Some(self.gpu.create_buffer(
                    "indirect commands",
                    grown_capacity(held, needed),
                    usage,
                    abi::CADR_MEMORY_CPU_TO_GPU,
                )?);
            }
            if let Some(commands) = indirect.commands.as_mut() {
                commands.write(0, &bytes)?;
            }
            if matches!(api(A), Api::IndirectCount | Api::Generated) {
                if indirect.count.is_none() {
                    indirect.count = Some(self.gpu.create_buffer(
                        "indirect count",
                        4,
                        usage,
                        abi::CADR_MEMORY_CPU_TO_GPU,
                    )?);
                }
                if let Some(count) = indirect.count.as_mut() {
                    count.write(0, &draws.to_le_bytes())?;
                }
            }
            indirect.draws = draws;
            kept.indirect_written = true;
        }
        Ok(())
    }

    /// Records every pass as one execution of generated commands: the GPU culler's commands
    /// where one wrote them, else the pass list's indirect commands.
    fn record_generated(&mut self, record: &Record<'_>) -> Result<(), String> {
        let passes = record.passes();
        let blocks = record.scene().parameter_blocks();
        let executions: Vec<Execution> = match record.gpu_draws() {
            Some(draws) => gpu_executions(passes, draws, blocks.then_some(record.layout())),
            None if blocks => {
                return Err("the host asks for parameter blocks, which only a GPU culler's commands carry, and this frame has none".into());
            }
            None => {
                // A host that skipped prepare still gets the right lists.
                if self.refresh_lists(record) {
                    return Err("the draws changed after prepare".into());
                }
                passes
                    .iter()
                    .zip(&self.pass_lists)
                    .enumerate()
                    .filter_map(|(index, (pass, &kept))| {
                        let indirect = &self.kept[kept].indirect;
                        match (&indirect.commands, &indirect.count) {
                            (Some(commands), Some(count)) if indirect.draws > 0 => {
                                Some(Execution {
                                    pass: index,
                                    pipeline: vk::Pipeline::from_raw(pass.pipeline),
                                    commands: commands.raw(),
                                    commands_offset: 0,
                                    count: count.raw(),
                                    count_offset: 0,
                                    max_sequences: indirect.draws,
                                    stride: 20,
                                    next_pass_pipeline: None,
                                    parameter_blocks: None,
                                })
                            }
                            _ => None,
                        }
                    })
                    .collect()
            }
        };
        let generated = self
            .generated
            .as_mut()
            .ok_or("no generated commands state")?;
        let chunked = generated.begin_frame(&executions, record.commands_key())?;
        let from_list = record.gpu_draws().is_none();
        for (execution, chunks) in executions.iter().zip(chunked) {
            let triangles = if from_list {
                self.pass_lists.get(execution.pass).map_or(0, |&kept| {
                    record::surface_triangles(&passes[execution.pass], &self.kept[kept].list.ranges)
                })
            } else {
                0
            };
            record::bind_pass(
                &self.gpu,
                record,
                &passes[execution.pass],
                (record.command_buffer(), record.stats()),
            );
            for chunk in &chunks {
                generated.execute(record.command_buffer(), chunk)?;
            }
            let sequences = u64::from(execution.max_sequences);
            let calls = chunks.len() as u64;
            record.count(|s| {
                s.draw_calls += calls;
                if from_list {
                    s.draws += sequences;
                    s.primitives += triangles;
                }
            });
        }
        Ok(())
    }

    fn recorder<'a>(&'a self, record: &'a Record<'a>) -> Recorder<'a> {
        Recorder {
            gpu: &self.gpu,
            record,
            api: api(A),
            passes: self
                .pass_lists
                .iter()
                .map(|&index| {
                    let kept = &self.kept[index];
                    let indirect = &kept.indirect;
                    PassDraws {
                        list: &kept.list,
                        commands: indirect
                            .commands
                            .as_ref()
                            .map_or(vk::Buffer::null(), HostBuffer::raw),
                        count: indirect
                            .count
                            .as_ref()
                            .map_or(vk::Buffer::null(), HostBuffer::raw),
                        indirect_draws: indirect.draws,
                    }
                })
                .collect(),
        }
    }
}

/// The executions of the GPU culler's `draws` for `passes`: one per pass that draws, and one
/// for two consecutive passes whose draws are equal, a shared stream whose commands each name
/// their pass's pipeline (`CadrSharedFaceStreams`, which the host asks for because
/// `dgc` announces `CADR_TRAIT_SWITCHES_PIPELINES`). Where the host asks for parameter blocks,
/// `parameter_blocks` is the pipeline layout they are pushed with.
fn gpu_executions(
    passes: &[abi::CadrPass],
    draws: &[abi::CadrGpuDraws],
    parameter_blocks: Option<vk::PipelineLayout>,
) -> Vec<Execution> {
    let mut executions = Vec::new();
    let mut index = 0;
    let named_bytes = generated::sequence_bytes(true, parameter_blocks.is_some());
    while index < passes.len().min(draws.len()) {
        let source = &draws[index];
        // A stream shared by two passes has room for the word before each command.
        let shared_with_next = draws.get(index + 1) == Some(source)
            && index + 1 < passes.len()
            && source.stride >= named_bytes;
        if source.commands != 0 && source.max_draws != 0 {
            executions.push(Execution {
                pass: index,
                pipeline: vk::Pipeline::from_raw(passes[index].pipeline),
                commands: vk::Buffer::from_raw(source.commands),
                commands_offset: source.commands_offset,
                count: vk::Buffer::from_raw(source.count_buffer),
                count_offset: source.count_offset,
                max_sequences: source.max_draws,
                stride: source.stride,
                next_pass_pipeline: shared_with_next
                    .then(|| vk::Pipeline::from_raw(passes[index + 1].pipeline)),
                parameter_blocks,
            });
        }
        index += 1 + usize::from(shared_with_next);
    }
    executions
}

impl<const S: u8, const A: u8, const M: u8> Submission for Submit<S, A, M> {
    /// `dgc` runs a pass in chunks that may draw a GPU culler's commands past the count, so it
    /// needs the host to ask the culler for empty tails (`CadrEmptyCommandTails`, ABI 1.24): a
    /// host older than that refuses it rather than drawing what lies there.
    const REQUIRED_EXTENSIONS: &'static [abi::CadrExtensionKind] = if A == GENERATED {
        &[abi::CADR_EXTENSION_EMPTY_COMMAND_TAILS]
    } else {
        &[]
    };

    fn prepare(&mut self, record: &Record<'_>) -> Result<(), String> {
        if record.gpu_draws().is_some() {
            // A GPU culler writes this frame's draws: no lists to keep.
            return Ok(());
        }
        self.refresh_lists(record);
        if matches!(api(A), Api::Indirect | Api::IndirectCount | Api::Generated) {
            self.write_indirect(record)?;
        }
        Ok(())
    }

    fn record(&mut self, record: &Record<'_>) -> Result<(), String> {
        if api(A) == Api::Generated {
            return self.record_generated(record);
        }
        if let Some(draws) = record.gpu_draws() {
            let by = match (api(A), mode(M)) {
                (Api::IndirectCount, Mode::Inline) => record::GpuDrawCount::Read,
                (Api::Indirect, Mode::Inline) => record::GpuDrawCount::Capacity,
                _ => return Err("this submission cannot draw GPU-written commands".into()),
            };
            record::record_gpu_draws(&self.gpu, record, draws, by);
            return Ok(());
        }
        // A host that skipped prepare still gets the right lists.
        if self.refresh_lists(record) && matches!(api(A), Api::Indirect | Api::IndirectCount) {
            return Err("the draws changed after prepare".into());
        }
        match mode(M) {
            Mode::Inline => {
                self.recorder(record).record_passes(
                    record.command_buffer(),
                    (0..usize::MAX, 1),
                    0..usize::MAX,
                    record.stats(),
                );
                Ok(())
            }
            Mode::Replay => {
                if self.recorded_key != Some(record.commands_key()) {
                    let mut stats = abi::CadrStats::default();
                    let secondary = self
                        .secondary
                        .as_ref()
                        .ok_or("no secondary command buffer")?;
                    self.recorded_order =
                        secondary.record_all(&self.recorder(record), &mut stats, 1)?;
                    self.recorded_stats = stats;
                    self.recorded_key = Some(record.commands_key());
                }
                let secondary = self
                    .secondary
                    .as_ref()
                    .ok_or("no secondary command buffer")?;
                secondary.execute(record.command_buffer(), &self.recorded_order);
                let recorded = self.recorded_stats;
                record.count(|s| add(s, &recorded));
                Ok(())
            }
            Mode::Threads => {
                let secondary = self
                    .secondary
                    .as_ref()
                    .ok_or("no secondary command buffers")?;
                let workers = secondary.len();
                let mut stats = abi::CadrStats::default();
                let order = secondary.record_all(&self.recorder(record), &mut stats, workers)?;
                secondary.execute(record.command_buffer(), &order);
                record.count(|s| add(s, &stats));
                Ok(())
            }
        }
    }
}

fn add(total: &mut abi::CadrStats, more: &abi::CadrStats) {
    total.draw_calls += more.draw_calls;
    total.draws += more.draws;
    total.primitives += more.primitives;
    total.pipeline_binds += more.pipeline_binds;
    total.vertex_binds += more.vertex_binds;
    total.parameter_binds += more.parameter_binds;
    total.failures += more.failures;
}

const GEOMETRY: u64 = abi::CADR_TRAIT_GEOMETRY_SHARES_BINDING;

/// `individual`, the built-in submission.
pub type Individual = Submit<INDIVIDUAL, DIRECT, INLINE>;
const GPU_DRAWS: u64 =
    abi::CADR_TRAIT_SCENE_SHARES_BINDING | abi::CADR_TRAIT_PARAMETERS_FROM_INSTANCE_INDEX;
const SECONDARY: u64 = abi::CADR_TRAIT_SECONDARY_COMMAND_BUFFERS;
const MDI_FEATURES: u64 =
    abi::CADR_FEATURE_MULTI_DRAW_INDIRECT | abi::CADR_FEATURE_DRAW_INDIRECT_FIRST_INSTANCE;
const COUNT_FEATURES: u64 = MDI_FEATURES | abi::CADR_FEATURE_DRAW_INDIRECT_COUNT;
const MESH_FEATURES: u64 =
    COUNT_FEATURES | abi::CADR_FEATURE_BUFFER_DEVICE_ADDRESS | abi::CADR_FEATURE_MESH_SHADER;
const DGC_FEATURES: u64 = abi::CADR_FEATURE_DRAW_INDIRECT_FIRST_INSTANCE
    | abi::CADR_FEATURE_BUFFER_DEVICE_ADDRESS
    | abi::CADR_FEATURE_DEVICE_GENERATED_COMMANDS_EXT;

technique_library! {
    pub fn entry;
    library: "cadr draw submission",
    techniques: [
        submission Submit<SORTED, DIRECT, INLINE> {
            name: "individual-sorted",
            description: "One draw per part, globally sorted by geometry and material so bindings change least.",
            features: 0, provides: REPLAYABLE | KEEPS_FRAME_SLOTS, needs: 0,
        },
        submission Submit<JOIN, DIRECT, INLINE> {
            name: "join",
            description: "Adjacent parts of an object with equal state joined into one draw.",
            features: 0, provides: REPLAYABLE | KEEPS_FRAME_SLOTS, needs: 0,
        },
        submission Submit<GROUPS, DIRECT, INLINE> {
            name: "groups",
            description: "Per object, one parameter binding per material group; one draw per range.",
            features: 0, provides: REPLAYABLE | KEEPS_FRAME_SLOTS, needs: 0,
        },
        submission Submit<INDIVIDUAL, MULTI_DRAW, INLINE> {
            name: "individual-multidraw",
            description: "One vkCmdDrawMultiIndexedEXT per part (the call shape of glMultiDrawElements, one range each).",
            features: abi::CADR_FEATURE_MULTI_DRAW, provides: REPLAYABLE | KEEPS_FRAME_SLOTS, needs: GEOMETRY,
        },
        submission Submit<JOIN, MULTI_DRAW, INLINE> {
            name: "join-multidraw",
            description: "Joined ranges, each through VK_EXT_multi_draw.",
            features: abi::CADR_FEATURE_MULTI_DRAW, provides: REPLAYABLE | KEEPS_FRAME_SLOTS, needs: GEOMETRY,
        },
        submission Submit<GROUPS, MULTI_DRAW, INLINE> {
            name: "groups-multidraw",
            description: "Material groups: every range of a group in one vkCmdDrawMultiIndexedEXT (the seeds' glMultiDrawElements).",
            features: abi::CADR_FEATURE_MULTI_DRAW, provides: REPLAYABLE | KEEPS_FRAME_SLOTS, needs: GEOMETRY,
        },
        submission Submit<INDIVIDUAL, INDIRECT, INLINE> {
            name: "individual-mdi",
            description: "Every part as an indirect command; one vkCmdDrawIndexedIndirect per pass (the seeds' indexedmdi); with a gpu- culler, one per pass over the whole room the culler has for commands, those past its count empty (for devices without drawIndirectCount, such as SwiftShader).",
            features: MDI_FEATURES, provides: abi::CADR_TRAIT_DRAWS_GPU_COMMANDS | abi::CADR_TRAIT_EMPTY_COMMAND_TAILS | REPLAYABLE | KEEPS_FRAME_SLOTS, needs: GPU_DRAWS,
        },
        submission Submit<JOIN, INDIRECT, INLINE> {
            name: "join-mdi",
            description: "Joined ranges as indirect commands; one multi-draw-indirect call per pass.",
            features: MDI_FEATURES, provides: REPLAYABLE | KEEPS_FRAME_SLOTS, needs: GPU_DRAWS,
        },
        submission Submit<GROUPS, INDIRECT, INLINE> {
            name: "groups-mdi",
            description: "Material-group ranges as indirect commands; one multi-draw-indirect call per pass.",
            features: MDI_FEATURES, provides: REPLAYABLE | KEEPS_FRAME_SLOTS, needs: GPU_DRAWS,
        },
        submission Submit<INDIVIDUAL, INDIRECT_COUNT, INLINE> {
            name: "individual-indirect-count",
            description: "Indirect commands with the count read from a buffer; with a gpu- culler, one vkCmdDrawIndexedIndirectCount per pass of the commands the GPU wrote.",
            features: COUNT_FEATURES, provides: abi::CADR_TRAIT_DRAWS_GPU_COMMANDS | REPLAYABLE | KEEPS_FRAME_SLOTS, needs: GPU_DRAWS,
        },
        submission Submit<JOIN, INDIRECT_COUNT, INLINE> {
            name: "join-indirect-count",
            description: "Joined ranges, indirect with the count read from a buffer.",
            features: COUNT_FEATURES, provides: REPLAYABLE | KEEPS_FRAME_SLOTS, needs: GPU_DRAWS,
        },
        submission Submit<GROUPS, INDIRECT_COUNT, INLINE> {
            name: "groups-indirect-count",
            description: "Material-group ranges, indirect with the count read from a buffer.",
            features: COUNT_FEATURES, provides: REPLAYABLE | KEEPS_FRAME_SLOTS, needs: GPU_DRAWS,
        },
        submission Submit<INDIVIDUAL, GENERATED, INLINE> {
            name: "dgc",
            description: "Device-generated commands (VK_EXT_device_generated_commands): each pass's indirect commands, written by a gpu- culler or from the part list, run as a generated command stream whose length the GPU reads; where a gpu- culler splits the surfaces by their back faces, one stream draws both, the GPU picking each part's pipeline from an execution set; with the push parameter path, each sequence pushes the matrix and material values the gpu- culler wrote.",
            features: DGC_FEATURES, provides: abi::CADR_TRAIT_DRAWS_GPU_COMMANDS | abi::CADR_TRAIT_SWITCHES_PIPELINES | abi::CADR_TRAIT_PARAMETER_BLOCKS | abi::CADR_TRAIT_EMPTY_COMMAND_TAILS | REPLAYABLE | KEEPS_FRAME_SLOTS, needs: GPU_DRAWS,
        },
        submission MeshTasks {
            name: "mesh-tasks",
            description: "With a gpu- culler and paths that run in mesh shaders (pulling, ssbo-index): each pass's GPU-written commands drawn by mesh workgroups (VK_EXT_mesh_shader), 32 triangles each, the task shader reading the count; edge lines as individual-indirect-count draws them.",
            features: MESH_FEATURES, provides: abi::CADR_TRAIT_DRAWS_GPU_COMMANDS | abi::CADR_TRAIT_MESH_SHADING | REPLAYABLE | KEEPS_FRAME_SLOTS, needs: GPU_DRAWS,
        },
        submission Submit<INDIVIDUAL, DIRECT, REPLAY> {
            name: "individual-replay",
            description: "One draw per part recorded once into a secondary command buffer and replayed while nothing changes (the seeds' token buffer).",
            features: 0, provides: SECONDARY | REPLAYABLE | KEEPS_FRAME_SLOTS, needs: 0,
        },
        submission Submit<GROUPS, DIRECT, REPLAY> {
            name: "groups-replay",
            description: "Material groups recorded once and replayed while nothing changes.",
            features: 0, provides: SECONDARY | REPLAYABLE | KEEPS_FRAME_SLOTS, needs: 0,
        },
        submission Submit<GROUPS, INDIRECT, REPLAY> {
            name: "groups-mdi-replay",
            description: "Material-group multi-draw-indirect recorded once and replayed; changes rewrite only the indirect buffer's contents.",
            features: MDI_FEATURES, provides: SECONDARY | REPLAYABLE | KEEPS_FRAME_SLOTS, needs: GPU_DRAWS,
        },
        submission Submit<INDIVIDUAL, DIRECT, THREADS> {
            name: "individual-threads",
            description: "One draw per part, recorded every frame in parallel into secondary command buffers on worker threads.",
            features: 0, provides: SECONDARY | REPLAYABLE, needs: 0,
        },
        submission Submit<GROUPS, DIRECT, THREADS> {
            name: "groups-threads",
            description: "Material groups recorded every frame in parallel on worker threads.",
            features: 0, provides: SECONDARY | REPLAYABLE, needs: 0,
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pass(pipeline: u64) -> abi::CadrPass {
        abi::CadrPass {
            pipeline,
            kind: abi::CADR_PASS_TRIANGLES,
        }
    }

    fn stream(offset: u64, stride: u32) -> abi::CadrGpuDraws {
        abi::CadrGpuDraws {
            commands: 7,
            commands_offset: offset,
            count_buffer: 8,
            count_offset: offset / 100,
            max_draws: 100,
            stride,
        }
    }

    #[test]
    fn two_passes_with_one_stream_of_named_commands_are_one_execution() {
        let passes = [pass(1), pass(2), pass(3)];
        // The split's two passes share a stream; the third (edges) has its own.
        let draws = [stream(0, 24), stream(0, 24), stream(2400, 24)];
        let executions = gpu_executions(&passes, &draws, None);
        assert_eq!(executions.len(), 2);
        assert_eq!(
            (executions[0].pass, executions[0].next_pass_pipeline),
            (0, Some(vk::Pipeline::from_raw(2)))
        );
        assert_eq!(
            (executions[1].pass, executions[1].next_pass_pipeline),
            (2, None)
        );
    }

    #[test]
    fn a_shared_stream_of_parameter_blocks_needs_room_for_the_name_the_block_and_the_draw() {
        let passes = [pass(1), pass(2)];
        let layout = Some(vk::PipelineLayout::from_raw(9));
        // 4 + 96 + 20 bytes: one execution of both passes, pushing blocks.
        let shared = gpu_executions(&passes, &[stream(0, 120), stream(0, 120)], layout);
        assert_eq!(shared.len(), 1);
        assert_eq!(shared[0].parameter_blocks, layout);
        assert_eq!(
            shared[0].next_pass_pipeline,
            Some(vk::Pipeline::from_raw(2))
        );
        // Named commands without room for the block: each pass draws the stream alone.
        let short = gpu_executions(&passes, &[stream(0, 24), stream(0, 24)], layout);
        assert_eq!(short.len(), 2);
        assert_eq!(generated::sequence_bytes(false, true), 116);
        assert_eq!(generated::sequence_bytes(true, false), 24);
    }

    #[test]
    fn passes_with_streams_of_their_own_or_without_room_for_names_stay_apart() {
        let passes = [pass(1), pass(2)];
        // Two streams: as a culler of ABI 1.18 writes the split.
        let apart = gpu_executions(&passes, &[stream(0, 20), stream(2000, 20)], None);
        assert_eq!(apart.len(), 2);
        assert!(apart.iter().all(|e| e.next_pass_pipeline.is_none()));
        // One 20-byte stream given to both: no word to name a pass, so each pass draws it.
        let same = gpu_executions(&passes, &[stream(0, 20), stream(0, 20)], None);
        assert_eq!(same.len(), 2);
        // A pass without commands runs nothing.
        let mut empty = stream(0, 24);
        empty.commands = 0;
        assert_eq!(
            gpu_executions(&passes, &[empty, stream(2400, 24)], None).len(),
            1
        );
    }
}
