//! GPU culling (plugin ABI 1.3; seeds 002 and 004): the frame's draws are decided by compute
//! shaders on the GPU scene's own buffers, so a moving camera costs the CPU what a still one
//! does.
//!
//! - `gpu-frustum`: per instance, the bounding sphere placed by its GPU matrix (relative to
//!   the eye, so precision holds far from the origin) against the frustum; the survivors'
//!   indirect commands are appended and counted per pass (`shaders/gpu_cull.comp`).
//! - `gpu-occlusion`: the seeds' temporal two-phase occlusion. Phase 0 draws what was visible
//!   at the end of the last frame (and is in the frustum); between the phases a depth pyramid
//!   is built from that depth (`shaders/hiz.comp`); phase 1 tests every instance against it,
//!   draws what became visible, and keeps the visibility for the next frame. A part that
//!   comes into view is drawn in the frame it does.
//! - `gpu-clusters` (ABI 1.14, the scene's clusters): `gpu-occlusion` per part, then per
//!   cluster. A part that passes draws, in the triangle passes, the clusters of its
//!   level-of-detail cut (the coarsest whose simplification error projects at or under the
//!   host's threshold, `lod_error` pixels; 0 draws the original clusters, exactly the part's
//!   triangles), each tested against the frustum, the section planes, the depth pyramid (in
//!   phase 1) and, in passes that hide back faces, its normal cone (closed opaque parts that
//!   no plane cuts, under transforms that keep angles). Clusters that follow each other in the
//!   index buffer are drawn by one command, so a part in full view costs what it did. Edge
//!   passes draw parts whole, at full detail: edges are the features a CAD user measures.
//! - All cull parts smaller than the host's sub-pixel threshold (ABI 1.5, off by default):
//!   a part whose bounding sphere projects under `min_pixels` across is drawn in no pass.
//! - All route each part by its back faces where the host splits the opaque surfaces (ABI
//!   1.18, `CadrBackFacePasses`): closed parts whose back faces cannot show go to the pass
//!   whose rasterizer culls them, the rest to the pass that draws both faces. Where the host
//!   asks for shared streams (ABI 1.19, for a submission that picks pipelines per command:
//!   `dgc`), both passes write one stream in one slot, each command after a word naming its
//!   pass (0 culled, 1 kept).
//! - All write each command after its instance's parameter block where the host asks (ABI
//!   1.22, `CadrParameterBlocks`, for the `push` parameter path under `dgc`): the world matrix
//!   from the scene's matrices, the material values, flags and instance id from its records.
//!
//! The submission draws the commands with `vkCmdDrawIndexedIndirectCount` (a submission
//! providing `CADR_TRAIT_DRAWS_GPU_COMMANDS`), or, where it draws them by their capacity
//! without the count (ABI 1.24, `CadrEmptyCommandTails`: `individual-mdi`, for devices without
//! drawIndirectCount such as SwiftShader), with `vkCmdDrawIndexedIndirect` over commands this
//! culler leaves empty past the count; commands use absolute ranges and `firstInstance`
//! = instance id, so the vertex path must bind the whole scene once and the parameter path
//! find parameters from the instance index.

use std::sync::Arc;

use cadr_plugin_sdk::abi;
use cadr_plugin_sdk::vk::{self, Handle};
use cadr_plugin_sdk::vulkan_failure;
use cadr_plugin_sdk::{
    buffer, grown_capacity, Gpu, GpuCull, GpuCulling, HostBuffer, PassFilter, Technique,
};

/// Words of the counts buffer: commands per (phase, pass) slot, then commands in all,
/// triangles drawn and clusters drawn, then per slot the cluster commands asked for.
const COUNT_WORDS: usize = 19;
const TOTAL_COMMANDS: usize = 8;
const TOTAL_TRIANGLES: usize = 9;
const TOTAL_CLUSTERS: usize = 10;
/// Passes per phase the counts have room for.
const PASSES_PER_PHASE: usize = 4;
/// How the commands and counts are read: as indirect buffers, and by device address where the
/// submission runs them as generated commands (the host drops that usage on a device without
/// buffer device addresses).
const DRAWN_FROM: vk::BufferUsageFlags = vk::BufferUsageFlags::from_raw(
    vk::BufferUsageFlags::INDIRECT_BUFFER.as_raw()
        | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS.as_raw(),
);
/// What the cull shader takes a pass of `kind` for: a mesh pipeline's pass (plugin ABI 1.23)
/// draws what the vertex pipeline's would.
fn drawn_as(kind: abi::CadrPassKind) -> abi::CadrPassKind {
    match kind {
        abi::CADR_PASS_MESH_TRIANGLES => abi::CADR_PASS_TRIANGLES,
        abi::CADR_PASS_MESH_PICK => abi::CADR_PASS_PICK,
        other => other,
    }
}

/// Words of one `VkDrawIndexedIndirectCommand`.
const COMMAND_WORDS: u32 = 5;
/// Words of the word naming a command's pass, in a frame whose split surface passes share
/// streams (`CadrSharedFaceStreams`).
const PASS_NAME_WORDS: u32 = crate::NAMED_COMMAND_BYTES / 4 - COMMAND_WORDS;
/// Words of a parameter block before each command, where the host asks for them
/// (`CadrParameterBlocks`, a `CadrParameterBlock`).
const PARAMETER_BLOCK_WORDS: u32 = (std::mem::size_of::<abi::CadrParameterBlock>() / 4) as u32;

/// The visibility buffers: last frame's (read) and this frame's (written).
const LAST: usize = 0;
const NOW: usize = 1;
/// The binding of the host's view uniform (`CadrGpuCullView`) in the cull set.
const VIEW_BINDING: usize = 4;

const MODE_FRUSTUM: u32 = 0;
const MODE_LAST_VISIBLE: u32 = 1;
const MODE_NEWLY_VISIBLE: u32 = 2;
/// What a phase 1 dispatch records (`writes_visibility`, as `gpu_cull.comp`'s `RECORDS_*`):
/// every part's visibility, and the clusters' of the parts its pass takes.
const RECORDS_PARTS: u32 = 1;
const RECORDS_CLUSTERS: u32 = 2;

/// What a frame slot's cull set was last written with: the host's buffers' handles, the ids of
/// ours, the scene's buffers generation and the view's offset.
type CullSetKey = ([u64; 18], [u64; 9], u64, u64);

/// Push constants of one cull dispatch.
#[derive(Clone, Copy)]
struct CullDispatch {
    instance_count: u32,
    pass_kind: u32,
    pass_slot: u32,
    first_command: u32,
    mode: u32,
    writes_visibility: u32,
    pyramid_levels: u32,
    /// The pass's filter and exclusion: only the instances it keeps get a command.
    filter: PassFilter,
    /// Level-of-detail threshold in pixels (cluster culling).
    lod_error: f32,
    /// Whether the pass hides the back faces of closed opaque parts (cluster culling).
    back_faces_hidden: bool,
    /// Commands a pass slot holds, words of each, and whether each carries its parameter block:
    /// [`COMMAND_WORDS`], [`PASS_NAME_WORDS`] more where each command starts with the word
    /// naming its pass (1 for a [`abi::CADR_FACES_KEPT`] pass, else 0), and
    /// [`PARAMETER_BLOCK_WORDS`] more where a block comes before its draw.
    commands: (u32, u32, bool),
    /// Of those, how many the cuts at `lod_error` may take (cluster culling); past that, parts
    /// are drawn at their coarsest, which the rest always holds.
    cluster_budget: u32,
    /// Bits of the cluster visibility table, less one (a power of two less one).
    cluster_bit_mask: u32,
    /// Which parts the pass takes by whether their back faces are culled (`CADR_FACES_*`).
    face_route: abi::CadrFaceRoute,
    /// Words of the scene's streaming requests ([`abi::CadrSceneStreaming`]); 0 where the scene
    /// does not stream.
    request_words: u32,
}

impl CullDispatch {
    /// The push constants, in the order `gpu_cull.comp` declares them.
    fn constants(&self) -> Vec<u8> {
        words(&[
            self.instance_count,
            self.pass_kind,
            self.pass_slot,
            self.first_command,
            self.mode,
            self.writes_visibility,
            self.pyramid_levels,
            self.filter.keep.mask,
            self.filter.keep.value,
            self.filter.keep.section_cut,
            self.filter.exclude.mask,
            self.filter.exclude.value,
            self.lod_error.to_bits(),
            u32::from(self.back_faces_hidden),
            self.commands.0,
            self.cluster_budget,
            self.cluster_bit_mask,
            self.face_route,
            self.commands.1,
            self.request_words,
            u32::from(self.commands.2),
        ])
    }
}

/// Bytes of [`CullDispatch`] as pushed.
const CULL_PUSH_BYTES: u32 = 84;
/// The most bits of the cluster visibility table (32 MiB a copy): past it, clusters share
/// bits, which only makes phase 0 draw a few hidden clusters.
const MAX_CLUSTER_BITS: u64 = 1 << 28;
/// The most cluster commands a pass slot gives the cuts at the host's threshold, unless
/// [`CLUSTER_BUDGET_VARIABLE`] says otherwise: 262 144 (5 MiB a slot), some hundred times what a
/// 4K view's cut needs at 1 px. Full detail of a scene of billions of triangles needs more:
/// past it, parts are drawn at their coarsest instead.
const CLUSTER_COMMAND_BUDGET: u64 = 1 << 18;
/// The environment variable that sets the cluster command budget (a count, at least 1): more
/// memory for full detail of larger scenes, or less.
const CLUSTER_BUDGET_VARIABLE: &str = "CADR_CLUSTER_COMMAND_BUDGET";

/// The cluster command budget: [`CLUSTER_BUDGET_VARIABLE`] when it holds a count of at least
/// 1, else [`CLUSTER_COMMAND_BUDGET`].
fn cluster_command_budget() -> u64 {
    std::env::var(CLUSTER_BUDGET_VARIABLE)
        .ok()
        .and_then(|text| text.trim().parse::<u64>().ok())
        .filter(|&n| n >= 1)
        .unwrap_or(CLUSTER_COMMAND_BUDGET)
}
/// Storage buffers of the cull set besides the view uniform: the scene's cull entries and
/// matrices, the commands and counts, both visibility buffers, the pyramid, and with clusters
/// the scene's clusters and groups, both cluster visibility tables and the parts phase 0 skipped,
/// the clusters' and the parts' boxes, the streaming requests, and the scene's instance records
/// and materials (for parameter blocks).
const CULL_STORAGE_BUFFERS: u32 = 17;
/// The frame slots a host may have ([`abi::CadrFrameSlot::slot_count`] is at most 3).
const FRAME_SLOTS: usize = 3;

/// Push constants of one pyramid level.
#[derive(Clone, Copy)]
struct PyramidLevel {
    source_size: [u32; 2],
    size: [u32; 2],
    source_offset: u32,
    offset: u32,
    from_depth: u32,
}

fn words(values: &[u32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// The sizes of the pyramid's levels for a `width` × `height` depth image: the image's own,
/// then halved (rounding up) down to 1 × 1.
fn pyramid_levels(width: u32, height: u32) -> Vec<[u32; 2]> {
    let mut size = [width.max(1), height.max(1)];
    let mut levels = vec![size];
    while size != [1, 1] {
        size = [size[0].div_ceil(2).max(1), size[1].div_ceil(2).max(1)];
        levels.push(size);
    }
    levels
}

/// The Vulkan objects a culler owns, destroyed on drop (null ones skipped), so that a
/// creation failing half-way leaks nothing.
struct Objects {
    gpu: Arc<Gpu>,
    cull_set_layout: vk::DescriptorSetLayout,
    cull_layout: vk::PipelineLayout,
    cull_pipeline: vk::Pipeline,
    pyramid_set_layout: vk::DescriptorSetLayout,
    pyramid_layout: vk::PipelineLayout,
    pyramid_pipeline: vk::Pipeline,
    sampler: vk::Sampler,
    pool: vk::DescriptorPool,
    /// One cull set per frame slot: a slot's set names its part of the host's view buffer, and
    /// a frame recorded for one slot never sees another's rewritten while it runs.
    cull_sets: [vk::DescriptorSet; FRAME_SLOTS],
    pyramid_set: vk::DescriptorSet,
}

impl Drop for Objects {
    fn drop(&mut self) {
        let (device, allocator) = (&self.gpu.device, self.gpu.allocator());
        // SAFETY: the host destroys instances after the GPU is done with them; each object
        // was created on this device with these callbacks and is destroyed once.
        unsafe {
            device.destroy_pipeline(self.cull_pipeline, allocator);
            device.destroy_pipeline(self.pyramid_pipeline, allocator);
            device.destroy_pipeline_layout(self.cull_layout, allocator);
            device.destroy_pipeline_layout(self.pyramid_layout, allocator);
            device.destroy_descriptor_set_layout(self.cull_set_layout, allocator);
            device.destroy_descriptor_set_layout(self.pyramid_set_layout, allocator);
            device.destroy_descriptor_pool(self.pool, allocator);
            device.destroy_sampler(self.sampler, allocator);
        }
    }
}

impl Objects {
    fn set_layout(
        &self,
        bindings: &[(vk::DescriptorType, u32)],
    ) -> Result<vk::DescriptorSetLayout, String> {
        let bindings: Vec<_> = bindings
            .iter()
            .enumerate()
            .map(|(i, &(ty, _))| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(i as u32)
                    .descriptor_type(ty)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
        // SAFETY: the info lives for the call.
        unsafe {
            self.gpu
                .device
                .create_descriptor_set_layout(&info, self.gpu.allocator())
        }
        .map_err(vulkan_failure("vkCreateDescriptorSetLayout"))
    }

    /// A compute pipeline from GLSL `source` with one set and `push_bytes` of push constants.
    fn pipeline(
        &self,
        name: &str,
        source: &str,
        set_layout: vk::DescriptorSetLayout,
        push_bytes: u32,
    ) -> Result<(vk::PipelineLayout, vk::Pipeline), String> {
        let (device, allocator) = (&self.gpu.device, self.gpu.allocator());
        let set_layouts = [set_layout];
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::COMPUTE)
            .size(push_bytes)];
        let info = vk::PipelineLayoutCreateInfo::default()
            .set_layouts(&set_layouts)
            .push_constant_ranges(&ranges);
        // SAFETY: the info lives for the call.
        let layout = unsafe { device.create_pipeline_layout(&info, allocator) }
            .map_err(vulkan_failure("vkCreatePipelineLayout"))?;
        let module =
            match self
                .gpu
                .create_shader_module(name, vk::ShaderStageFlags::COMPUTE, source)
            {
                Ok(module) => module,
                Err(e) => {
                    // SAFETY: created above, unused.
                    unsafe { device.destroy_pipeline_layout(layout, allocator) };
                    return Err(e);
                }
            };
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module)
            .name(c"main");
        let info = [vk::ComputePipelineCreateInfo::default()
            .stage(stage)
            .layout(layout)];
        // SAFETY: the module and layout are live; the info lives for the call.
        let created =
            unsafe { device.create_compute_pipelines(self.gpu.pipeline_cache, &info, allocator) };
        // SAFETY: the pipeline keeps what it needs of the module.
        unsafe { device.destroy_shader_module(module, allocator) };
        match created {
            Ok(pipelines) => Ok((layout, pipelines[0])),
            Err((_, e)) => {
                // SAFETY: created above, unused.
                unsafe { device.destroy_pipeline_layout(layout, allocator) };
                Err(format!(
                    "{name}: {}",
                    vulkan_failure("vkCreateComputePipelines")(e)
                ))
            }
        }
    }

    fn new(gpu: &Arc<Gpu>, occlusion: bool, clusters: bool) -> Result<Self, String> {
        let mut objects = Self {
            gpu: Arc::clone(gpu),
            cull_set_layout: vk::DescriptorSetLayout::null(),
            cull_layout: vk::PipelineLayout::null(),
            cull_pipeline: vk::Pipeline::null(),
            pyramid_set_layout: vk::DescriptorSetLayout::null(),
            pyramid_layout: vk::PipelineLayout::null(),
            pyramid_pipeline: vk::Pipeline::null(),
            sampler: vk::Sampler::null(),
            pool: vk::DescriptorPool::null(),
            cull_sets: [vk::DescriptorSet::null(); FRAME_SLOTS],
            pyramid_set: vk::DescriptorSet::null(),
        };
        let storage = vk::DescriptorType::STORAGE_BUFFER;
        let mut cull_bindings = vec![
            (storage, 0),
            (storage, 1),
            (storage, 2),
            (storage, 3),
            (vk::DescriptorType::UNIFORM_BUFFER, 4),
            (storage, 5),
            (storage, 6),
            (storage, 7),
        ];
        let source = include_str!("../shaders/gpu_cull.comp");
        let source = if clusters {
            cull_bindings.extend([
                (storage, 8),
                (storage, 9),
                (storage, 10),
                (storage, 11),
                (storage, 12),
                (storage, 13),
                (storage, 14),
                (storage, 15),
                (storage, 16),
                (storage, 17),
            ]);
            source.replacen("#version 460\n", "#version 460\n#define CLUSTERS 1\n", 1)
        } else {
            cull_bindings.extend([(storage, 8), (storage, 9), (storage, 10), (storage, 11)]);
            source.to_owned()
        };
        objects.cull_set_layout = objects.set_layout(&cull_bindings)?;
        (objects.cull_layout, objects.cull_pipeline) = objects.pipeline(
            "gpu_cull.comp",
            &source,
            objects.cull_set_layout,
            CULL_PUSH_BYTES,
        )?;
        let (device, allocator) = (&gpu.device, gpu.allocator());
        if occlusion {
            objects.pyramid_set_layout = objects.set_layout(&[
                (vk::DescriptorType::COMBINED_IMAGE_SAMPLER, 0),
                (storage, 1),
            ])?;
            (objects.pyramid_layout, objects.pyramid_pipeline) = objects.pipeline(
                "hiz.comp",
                include_str!("../shaders/hiz.comp"),
                objects.pyramid_set_layout,
                28,
            )?;
            let info = vk::SamplerCreateInfo::default()
                .mag_filter(vk::Filter::NEAREST)
                .min_filter(vk::Filter::NEAREST)
                .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
                .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE);
            // SAFETY: the info lives for the call.
            objects.sampler = unsafe { device.create_sampler(&info, allocator) }
                .map_err(vulkan_failure("vkCreateSampler"))?;
        }
        let sizes = [
            vk::DescriptorPoolSize::default()
                .ty(storage)
                .descriptor_count(CULL_STORAGE_BUFFERS * FRAME_SLOTS as u32 + 1),
            vk::DescriptorPoolSize::default()
                .ty(vk::DescriptorType::UNIFORM_BUFFER)
                .descriptor_count(FRAME_SLOTS as u32),
            vk::DescriptorPoolSize::default()
                .ty(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                .descriptor_count(1),
        ];
        let info = vk::DescriptorPoolCreateInfo::default()
            .max_sets(FRAME_SLOTS as u32 + 1)
            .pool_sizes(&sizes);
        // SAFETY: the info lives for the call.
        objects.pool = unsafe { device.create_descriptor_pool(&info, allocator) }
            .map_err(vulkan_failure("vkCreateDescriptorPool"))?;
        let mut layouts = vec![objects.cull_set_layout; FRAME_SLOTS];
        if occlusion {
            layouts.push(objects.pyramid_set_layout);
        }
        let info = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(objects.pool)
            .set_layouts(&layouts);
        // SAFETY: the pool has room for these sets.
        let sets = unsafe { device.allocate_descriptor_sets(&info) }
            .map_err(vulkan_failure("vkAllocateDescriptorSets"))?;
        objects.cull_sets.copy_from_slice(&sets[..FRAME_SLOTS]);
        objects.pyramid_set = sets.get(FRAME_SLOTS).copied().unwrap_or_default();
        Ok(objects)
    }
}

/// Visibility bits at the end of the last frame ([`LAST`], read) and of this one ([`NOW`],
/// written, then copied over the first at the end of the frame, so that every frame records
/// the same commands).
struct VisibilityBits {
    /// Last frame's and this one's.
    buffers: [HostBuffer; 2],
    /// Words in each.
    words: u32,
}

/// The indirect commands: one region of `capacity` per (phase, pass) slot, each command at most
/// `words` long.
struct CommandRegions {
    buffer: Option<HostBuffer>,
    capacity: u32,
    words: u32,
    /// Whether this frame's commands start with the word naming their pass, and whether they
    /// carry parameter blocks.
    frame_shape: (bool, bool),
}

impl CommandRegions {
    /// Words of each command this frame (see [`CullDispatch::commands`]).
    fn frame_words(&self) -> u32 {
        let (named, blocks) = self.frame_shape;
        COMMAND_WORDS
            + u32::from(named) * PASS_NAME_WORDS
            + u32::from(blocks) * PARAMETER_BLOCK_WORDS
    }
}

/// A GPU culler: `gpu-frustum` without occlusion, `gpu-occlusion` with it, `gpu-clusters`
/// with occlusion and clusters.
pub struct GpuCuller<const OCCLUSION: bool, const CLUSTERS: bool> {
    gpu: Arc<Gpu>,
    objects: Objects,
    /// Commands per (phase, pass) slot and the totals; host-visible for the frame's counts.
    counts: HostBuffer,
    /// The commands' regions.
    commands: CommandRegions,
    /// Visibility bits of instances; 4 bytes each for `gpu-frustum`, which reads none.
    visibility: VisibilityBits,
    /// The same for clusters (gpu-clusters): a table of bits that an instance's cluster finds
    /// by hashing the pair; 4 bytes each for other cullers.
    cluster_visibility: VisibilityBits,
    /// One bit per instance id, cleared every frame: the parts whose cut phase 0 found no room
    /// for, which phase 1 then draws whole (gpu-clusters; as big as the visibility buffers).
    phase0_skipped: HostBuffer,
    /// Bound in place of the clusters' and the parts' boxes where the host has none (ABI 1.19 or
    /// older).
    no_boxes: HostBuffer,
    /// The cluster commands a slot gives the cuts at the host's threshold (this frame's), and
    /// the most it may give (see [`CLUSTER_COMMAND_BUDGET`]).
    cluster_budget: u32,
    max_cluster_budget: u64,
    /// The depth pyramid (occlusion) and the depth size it was made for.
    pyramid: HostBuffer,
    pyramid_size: (u32, u32),
    /// Levels of the pyramid of the current target size (a push constant of the culls).
    pyramid_levels: u32,
    /// What the descriptor sets were last written with.
    cull_written: [Option<CullSetKey>; FRAME_SLOTS],
    pyramid_written: Option<(u64, u64)>,
}

impl<const OCCLUSION: bool, const CLUSTERS: bool> Technique for GpuCuller<OCCLUSION, CLUSTERS> {
    fn create(gpu: Arc<Gpu>) -> Result<Self, String> {
        let objects = Objects::new(&gpu, OCCLUSION, CLUSTERS)?;
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
        let counts = gpu.create_buffer(
            "gpu cull counts",
            (COUNT_WORDS * 4) as u64,
            storage | DRAWN_FROM,
            abi::CADR_MEMORY_CPU_TO_GPU,
        )?;
        let visibility_usage = storage | vk::BufferUsageFlags::TRANSFER_SRC;
        let tiny = |name| gpu.create_buffer(name, 4, visibility_usage, abi::CADR_MEMORY_GPU_ONLY);
        Ok(Self {
            visibility: VisibilityBits {
                buffers: [tiny("gpu cull visibility")?, tiny("gpu cull visibility")?],
                words: 0,
            },
            cluster_visibility: VisibilityBits {
                buffers: [
                    tiny("gpu cull cluster visibility")?,
                    tiny("gpu cull cluster visibility")?,
                ],
                words: 1,
            },
            phase0_skipped: tiny("gpu cull phase 0 skipped")?,
            no_boxes: tiny("gpu cull no boxes")?,
            pyramid: tiny("gpu cull pyramid")?,
            gpu,
            objects,
            counts,
            commands: CommandRegions {
                buffer: None,
                capacity: 0,
                words: COMMAND_WORDS,
                frame_shape: (false, false),
            },
            cluster_budget: 0,
            max_cluster_budget: cluster_command_budget(),
            pyramid_size: (0, 0),
            pyramid_levels: 1,
            cull_written: [None; FRAME_SLOTS],
            pyramid_written: None,
        })
    }
}

/// Records filling `buffer` with zeros (outside rendering; the buffer allows transfer writes).
fn clear(gpu: &Gpu, command_buffer: vk::CommandBuffer, buffer: &HostBuffer) {
    // SAFETY: recording outside rendering; every buffer cleared here has transfer-dst usage.
    unsafe {
        gpu.device
            .cmd_fill_buffer(command_buffer, buffer.raw(), 0, vk::WHOLE_SIZE, 0)
    };
}

/// A barrier from `src` to `dst` (stages and accesses) on all memory.
fn barrier(
    gpu: &Gpu,
    command_buffer: vk::CommandBuffer,
    src: (vk::PipelineStageFlags2, vk::AccessFlags2),
    dst: (vk::PipelineStageFlags2, vk::AccessFlags2),
) {
    let barriers = [vk::MemoryBarrier2::default()
        .src_stage_mask(src.0)
        .src_access_mask(src.1)
        .dst_stage_mask(dst.0)
        .dst_access_mask(dst.1)];
    let info = vk::DependencyInfo::default().memory_barriers(&barriers);
    // SAFETY: recording outside rendering.
    unsafe { gpu.device.cmd_pipeline_barrier2(command_buffer, &info) };
}

impl<const OCCLUSION: bool, const CLUSTERS: bool> GpuCuller<OCCLUSION, CLUSTERS> {
    fn phases(&self) -> u32 {
        if OCCLUSION {
            2
        } else {
            1
        }
    }

    /// Makes the commands (a region per phase and pass slot, each room for `commands`) and
    /// visibility buffers big enough for `instances`; new visibility buffers are cleared in
    /// `command_buffer`.
    fn reserve(
        &mut self,
        (instances, commands, clusters): (u32, u32, u64),
        command_buffer: vk::CommandBuffer,
    ) -> Result<(), String> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
        let needed = commands.max(instances).max(1);
        let words = self.commands.frame_words();
        if self.commands.buffer.is_none()
            || needed > self.commands.capacity
            || words > self.commands.words
        {
            // Longer commands alone (a submission that shares streams) keep the capacity.
            let capacity = if needed > self.commands.capacity {
                u32::try_from(grown_capacity(
                    u64::from(self.commands.capacity),
                    u64::from(needed),
                ))
                .unwrap_or(u32::MAX)
            } else {
                self.commands.capacity
            };
            let slots = (self.phases() as usize * PASSES_PER_PHASE) as u64;
            self.commands.buffer = Some(self.gpu.create_buffer(
                "gpu cull commands",
                u64::from(capacity) * u64::from(words) * 4 * slots,
                storage | DRAWN_FROM,
                abi::CADR_MEMORY_GPU_ONLY,
            )?);
            self.commands.capacity = capacity;
            self.commands.words = words;
        }
        let needed = instances.max(1);
        if OCCLUSION && needed.div_ceil(32) > self.visibility.words {
            let words = needed.div_ceil(32).next_power_of_two();
            self.visibility = VisibilityBits {
                buffers: [
                    self.zeroed_bits("gpu cull visibility", words, command_buffer)?,
                    self.zeroed_bits("gpu cull visibility", words, command_buffer)?,
                ],
                words,
            };
            if CLUSTERS {
                self.phase0_skipped =
                    self.zeroed_bits("gpu cull phase 0 skipped", words, command_buffer)?;
            }
        }
        let bits = clusters.clamp(32, MAX_CLUSTER_BITS).next_power_of_two();
        if CLUSTERS && bits / 32 > u64::from(self.cluster_visibility.words) {
            let words = (bits / 32) as u32;
            self.cluster_visibility = VisibilityBits {
                buffers: [
                    self.zeroed_bits("gpu cull cluster visibility", words, command_buffer)?,
                    self.zeroed_bits("gpu cull cluster visibility", words, command_buffer)?,
                ],
                words,
            };
        }
        Ok(())
    }

    /// A GPU buffer of `words` words of bits (storage, copied from and to), cleared in
    /// `command_buffer` before anything reads it.
    fn zeroed_bits(
        &self,
        name: &str,
        words: u32,
        command_buffer: vk::CommandBuffer,
    ) -> Result<HostBuffer, String> {
        let buffer = self.gpu.create_buffer(
            name,
            u64::from(words) * 4,
            vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::TRANSFER_DST
                | vk::BufferUsageFlags::TRANSFER_SRC,
            abi::CADR_MEMORY_GPU_ONLY,
        )?;
        clear(&self.gpu, command_buffer, &buffer);
        Ok(buffer)
    }

    /// Makes the pyramid buffer fit a `width` × `height` depth image (before the frame's
    /// first use of the cull set, which points at it).
    fn reserve_pyramid(&mut self, width: u32, height: u32) -> Result<(), String> {
        if self.pyramid_size == (width, height) {
            return Ok(());
        }
        let texels: u64 = pyramid_levels(width, height)
            .iter()
            .map(|[w, h]| u64::from(w * h))
            .sum();
        self.pyramid = self.gpu.create_buffer(
            "gpu cull pyramid",
            texels * 4,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            abi::CADR_MEMORY_GPU_ONLY,
        )?;
        self.pyramid_size = (width, height);
        Ok(())
    }

    /// Points the cull set of frame `slot` at the scene's buffers, the host's view and ours
    /// (when any changed).
    fn write_cull_set(
        &mut self,
        slot: usize,
        scene: &abi::CadrSceneView,
        clusters: Option<&abi::CadrSceneClusters>,
        (boxes, part_boxes, streaming): (
            Option<&abi::CadrSceneClusterBoxes>,
            Option<&abi::CadrScenePartBoxes>,
            Option<&abi::CadrSceneStreaming>,
        ),
        (view, view_offset): (vk::Buffer, u64),
    ) {
        let Some(commands) = &self.commands.buffer else {
            return;
        };
        let mut buffers = vec![
            buffer(&scene.cull_buffer),
            buffer(&scene.matrix_buffer),
            commands.raw(),
            self.counts.raw(),
            view,
            self.visibility.buffers[LAST].raw(),
            self.visibility.buffers[NOW].raw(),
            self.pyramid.raw(),
        ];
        if let Some(clusters) = clusters {
            buffers.extend([
                buffer(&clusters.cluster_buffer),
                buffer(&clusters.group_buffer),
                self.cluster_visibility.buffers[LAST].raw(),
                self.cluster_visibility.buffers[NOW].raw(),
                self.phase0_skipped.raw(),
                // From an older host, 4 bytes: fewer boxes than clusters tells the shader to
                // test the clusters' spheres.
                boxes.map_or(self.no_boxes.raw(), |b| buffer(&b.box_buffer)),
            ]);
        }
        // The parts' boxes, after the clusters' bindings (binding 14, or 8 without clusters);
        // from an older host 4 bytes, which the shader tells from a box per entry.
        buffers.push(part_boxes.map_or(self.no_boxes.raw(), |b| buffer(&b.box_buffer)));
        // The streaming requests after them; where the scene does not stream, 4 bytes the
        // shader never writes (it is told no words).
        buffers.push(streaming.map_or(self.no_boxes.raw(), |s| buffer(&s.request_buffer)));
        // What parameter blocks are made of, last.
        buffers.push(buffer(&scene.instance_buffer));
        buffers.push(buffer(&scene.material_buffer));
        // Keyed on what cannot come back: the host's scene buffers by handle and generation
        // (it bumps the generation when it replaces one), ours by id. A destroyed buffer's
        // handle may be given to the next one made (lavapipe's are addresses), and a set still
        // pointing at the old one's memory then reads and writes what lives there now.
        let own = [
            self.visibility.buffers[LAST].id(),
            self.visibility.buffers[NOW].id(),
            self.pyramid.id(),
            self.cluster_visibility.buffers[LAST].id(),
            self.cluster_visibility.buffers[NOW].id(),
            self.phase0_skipped.id(),
            self.no_boxes.id(),
            commands.id(),
            self.counts.id(),
        ];
        let mut raw = [0u64; 18];
        for (slot, b) in raw.iter_mut().zip(&buffers) {
            *slot = b.as_raw();
        }
        let key = (raw, own, scene.buffers_generation, view_offset);
        if self.cull_written[slot] == Some(key) {
            return;
        }
        let infos: Vec<[vk::DescriptorBufferInfo; 1]> = buffers
            .iter()
            .enumerate()
            .map(|(binding, &b)| {
                let info = vk::DescriptorBufferInfo::default().buffer(b);
                [if binding == VIEW_BINDING {
                    info.offset(view_offset)
                        .range(std::mem::size_of::<abi::CadrGpuCullView>() as u64)
                } else {
                    info.range(vk::WHOLE_SIZE)
                }]
            })
            .collect();
        let writes: Vec<vk::WriteDescriptorSet> = infos
            .iter()
            .enumerate()
            .map(|(binding, info)| {
                let ty = if binding == VIEW_BINDING {
                    vk::DescriptorType::UNIFORM_BUFFER
                } else {
                    vk::DescriptorType::STORAGE_BUFFER
                };
                vk::WriteDescriptorSet::default()
                    .dst_set(self.objects.cull_sets[slot])
                    .dst_binding(binding as u32)
                    .descriptor_type(ty)
                    .buffer_info(info)
            })
            .collect();
        // SAFETY: the set is not in use: frames of other slots use their own sets, and the
        // host waited for this slot's last frame before recording it; the buffers are live.
        unsafe { self.gpu.device.update_descriptor_sets(&writes, &[]) };
        self.cull_written[slot] = Some(key);
    }

    /// Records the cull dispatches of `phase` for every pass, in `mode`, with the cull set of
    /// frame `slot`.
    fn dispatch_cull(&self, cull: &GpuCull<'_>, slot: usize, instances: u32, mode: u32) {
        let back_faces_hidden = cull.back_faces_hidden();
        // A culler without clusters draws full detail: its threshold (which streaming asks
        // for full detail by) is 0.
        let lod_error = cull.cluster_cull().filter(|_| CLUSTERS).map_or(0.0, |c| {
            if c.lod_error.is_finite() {
                c.lod_error.max(0.0)
            } else {
                0.0
            }
        });
        let request_words = (cull.scene())
            .and_then(|scene| scene.streaming())
            .map_or(0, |streaming| streaming.request_word_count);
        let device = &self.gpu.device;
        let command_buffer = cull.command_buffer();
        // SAFETY: recording outside rendering; the pipeline, layout and set are live.
        unsafe {
            device.cmd_bind_pipeline(
                command_buffer,
                vk::PipelineBindPoint::COMPUTE,
                self.objects.cull_pipeline,
            );
            device.cmd_bind_descriptor_sets(
                command_buffer,
                vk::PipelineBindPoint::COMPUTE,
                self.objects.cull_layout,
                0,
                &[self.objects.cull_sets[slot]],
                &[],
            );
        }
        let filters = cull.pass_filters();
        let face_routes = cull.face_routes();
        let command_words = self.commands.frame_words();
        let (shares, parameter_blocks) = self.commands.frame_shape;
        for (index, (pass, filter)) in cull
            .passes()
            .iter()
            .zip(filters)
            .enumerate()
            .take(PASSES_PER_PHASE)
        {
            let route = face_routes
                .get(index)
                .copied()
                .unwrap_or(abi::CADR_FACES_ANY);
            // A kept pass shares the stream (slot) of the culled pass before it.
            let shares_previous = shares
                && route == abi::CADR_FACES_KEPT
                && index > 0
                && face_routes.get(index - 1) == Some(&abi::CADR_FACES_CULLED);
            let slot =
                cull.phase() as usize * PASSES_PER_PHASE + index - usize::from(shares_previous);
            let dispatch = CullDispatch {
                instance_count: instances,
                pass_kind: drawn_as(pass.kind),
                pass_slot: slot as u32,
                first_command: slot as u32 * self.commands.capacity,
                mode,
                // The first pass records every part's visibility (the others test the pyramid
                // only for the parts they take); the clusters' is recorded by the pass that
                // draws them: the first, and where the surfaces are split, the other parts'.
                writes_visibility: if index == 0 {
                    RECORDS_PARTS | RECORDS_CLUSTERS
                } else if route == abi::CADR_FACES_KEPT {
                    RECORDS_CLUSTERS
                } else {
                    0
                },
                pyramid_levels: self.pyramid_levels,
                filter,
                lod_error,
                back_faces_hidden: back_faces_hidden.get(index).copied().unwrap_or(false),
                commands: (self.commands.capacity, command_words, parameter_blocks),
                cluster_budget: self.cluster_budget,
                cluster_bit_mask: self.cluster_visibility.words * 32 - 1,
                face_route: route,
                request_words,
            };
            let constants = dispatch.constants();
            // SAFETY: recording; the constants fit the layout's 84 bytes.
            unsafe {
                device.cmd_push_constants(
                    command_buffer,
                    self.objects.cull_layout,
                    vk::ShaderStageFlags::COMPUTE,
                    0,
                    &constants,
                );
                device.cmd_dispatch(command_buffer, instances.div_ceil(64), 1, 1);
            }
            if let Some(draws) = self.draws(slot, route) {
                cull.set_draws(index, draws);
            }
        }
    }

    /// Where the commands of pass slot `slot` (a pass of `route`) lie this frame. In a frame
    /// of named commands a shared stream starts at its first command's word, any other stream
    /// at its first command itself.
    fn draws(&self, slot: usize, route: abi::CadrFaceRoute) -> Option<abi::CadrGpuDraws> {
        let commands = self.commands.buffer.as_ref()?;
        let words = self.commands.frame_words();
        let region_start = slot as u64 * u64::from(self.commands.capacity) * u64::from(words) * 4;
        let shared = matches!(route, abi::CADR_FACES_CULLED | abi::CADR_FACES_KEPT);
        let word_skipped = self.commands.frame_shape.0 && !shared;
        Some(abi::CadrGpuDraws {
            commands: commands.raw().as_raw(),
            commands_offset: region_start + u64::from(word_skipped) * 4,
            count_buffer: self.counts.raw().as_raw(),
            count_offset: slot as u64 * 4,
            max_draws: self.commands.capacity,
            stride: words * 4,
        })
    }

    /// Copies this frame's visibility over the last frame's, for the next frame to read: the
    /// buffers keep their roles, so every frame records the same commands.
    fn keep_visibility(&self, command_buffer: vk::CommandBuffer) {
        barrier(
            &self.gpu,
            command_buffer,
            (
                vk::PipelineStageFlags2::COMPUTE_SHADER,
                vk::AccessFlags2::SHADER_READ | vk::AccessFlags2::SHADER_WRITE,
            ),
            (
                vk::PipelineStageFlags2::ALL_TRANSFER,
                vk::AccessFlags2::TRANSFER_READ | vk::AccessFlags2::TRANSFER_WRITE,
            ),
        );
        let region = [vk::BufferCopy::default().size(u64::from(self.visibility.words) * 4)];
        // SAFETY: recording outside rendering; both buffers hold `visibility.words` words and
        // allow the transfer; the barrier above ordered the culls' accesses before it.
        unsafe {
            self.gpu.device.cmd_copy_buffer(
                command_buffer,
                self.visibility.buffers[NOW].raw(),
                self.visibility.buffers[LAST].raw(),
                &region,
            )
        };
        if CLUSTERS {
            let region =
                [vk::BufferCopy::default().size(u64::from(self.cluster_visibility.words) * 4)];
            // SAFETY: as above, for the cluster tables of `cluster_visibility.words` words.
            unsafe {
                self.gpu.device.cmd_copy_buffer(
                    command_buffer,
                    self.cluster_visibility.buffers[NOW].raw(),
                    self.cluster_visibility.buffers[LAST].raw(),
                    &region,
                )
            };
        }
    }

    /// Builds the depth pyramid from the depth drawn in phase 0.
    fn build_pyramid(&mut self, cull: &GpuCull<'_>) -> Result<(), String> {
        let raw = cull.raw();
        let (width, height) = (raw.width.max(1), raw.height.max(1));
        let levels = pyramid_levels(width, height);
        if self.pyramid_size != (width, height) {
            return Err("the target changed size between the phases of a frame".into());
        }
        let depth_view = vk::ImageView::from_raw(raw.depth_view);
        if depth_view == vk::ImageView::null() {
            return Err("the host passed no depth for phase 1".into());
        }
        // The host's depth view by handle (it changes with the target), our pyramid by id (see
        // `write_cull_set`).
        let key = (raw.depth_view, self.pyramid.id());
        let device = &self.gpu.device;
        if self.pyramid_written != Some(key) {
            let image = [vk::DescriptorImageInfo::default()
                .sampler(self.objects.sampler)
                .image_view(depth_view)
                .image_layout(vk::ImageLayout::from_raw(raw.depth_layout))];
            let pyramid = [vk::DescriptorBufferInfo::default()
                .buffer(self.pyramid.raw())
                .range(vk::WHOLE_SIZE)];
            let writes = [
                vk::WriteDescriptorSet::default()
                    .dst_set(self.objects.pyramid_set)
                    .dst_binding(0)
                    .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                    .image_info(&image),
                vk::WriteDescriptorSet::default()
                    .dst_set(self.objects.pyramid_set)
                    .dst_binding(1)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .buffer_info(&pyramid),
            ];
            // SAFETY: the set is not in use (see `write_cull_set`).
            unsafe { device.update_descriptor_sets(&writes, &[]) };
            self.pyramid_written = Some(key);
        }
        let command_buffer = cull.command_buffer();
        // SAFETY: recording outside rendering; pipeline, layout and set are live.
        unsafe {
            device.cmd_bind_pipeline(
                command_buffer,
                vk::PipelineBindPoint::COMPUTE,
                self.objects.pyramid_pipeline,
            );
            device.cmd_bind_descriptor_sets(
                command_buffer,
                vk::PipelineBindPoint::COMPUTE,
                self.objects.pyramid_layout,
                0,
                &[self.objects.pyramid_set],
                &[],
            );
        }
        let mut source = ([width, height], 0u32);
        let mut offset = 0u32;
        for (index, &size) in levels.iter().enumerate() {
            let level = PyramidLevel {
                source_size: source.0,
                size,
                source_offset: source.1,
                offset,
                from_depth: u32::from(index == 0),
            };
            let constants = words(&[
                level.source_size[0],
                level.source_size[1],
                level.size[0],
                level.size[1],
                level.source_offset,
                level.offset,
                level.from_depth,
            ]);
            // SAFETY: recording; the constants fit the layout's 28 bytes.
            unsafe {
                device.cmd_push_constants(
                    command_buffer,
                    self.objects.pyramid_layout,
                    vk::ShaderStageFlags::COMPUTE,
                    0,
                    &constants,
                );
                device.cmd_dispatch(command_buffer, size[0].div_ceil(8), size[1].div_ceil(8), 1);
            }
            barrier(
                &self.gpu,
                command_buffer,
                (
                    vk::PipelineStageFlags2::COMPUTE_SHADER,
                    vk::AccessFlags2::SHADER_WRITE,
                ),
                (
                    vk::PipelineStageFlags2::COMPUTE_SHADER,
                    vk::AccessFlags2::SHADER_READ,
                ),
            );
            source = (size, offset);
            offset += size[0] * size[1];
        }
        Ok(())
    }
}

impl<const OCCLUSION: bool, const CLUSTERS: bool> GpuCuller<OCCLUSION, CLUSTERS> {
    /// Room for the indirect commands of `instances` parts: one each drawn whole; with
    /// clusters, the cuts get a budget and every part room for its coarsest cut. Returns the
    /// room and the budget.
    fn command_room(
        &self,
        instances: u32,
        clusters: Option<&abi::CadrSceneClusters>,
    ) -> (u32, u32) {
        clusters.map_or((instances, 0), |c| {
            let budget = c.candidate_clusters.min(self.max_cluster_budget);
            let room = budget.saturating_add(c.candidate_coarsest_clusters);
            (
                u32::try_from(room).unwrap_or(u32::MAX),
                u32::try_from(budget).unwrap_or(u32::MAX),
            )
        })
    }

    /// The first phase's preparation: buffers of `sizes` (instances, commands, cluster
    /// visibility bits) and the depth pyramid made or grown, this frame's counts and
    /// visibility cleared after the last frame's reads, and the clears made visible to the
    /// culling shader.
    fn prepare_buffers(
        &mut self,
        cull: &GpuCull<'_>,
        sizes: (u32, u32, u64),
    ) -> Result<(), String> {
        let raw = cull.raw();
        let command_buffer = cull.command_buffer();
        if cull.passes().len() > PASSES_PER_PHASE {
            return Err(format!(
                "{} passes; GPU culling handles at most {PASSES_PER_PHASE}",
                cull.passes().len()
            ));
        }
        // New buffers are cleared first (nothing else uses them yet).
        self.reserve(sizes, command_buffer)?;
        // The previous frame's reads of our buffers (indirect draws, culls, the visibility
        // copy) and those clears come before this frame's clears.
        barrier(
            &self.gpu,
            command_buffer,
            (
                vk::PipelineStageFlags2::DRAW_INDIRECT
                    | vk::PipelineStageFlags2::COMPUTE_SHADER
                    | vk::PipelineStageFlags2::ALL_TRANSFER,
                vk::AccessFlags2::INDIRECT_COMMAND_READ
                    | vk::AccessFlags2::SHADER_READ
                    | vk::AccessFlags2::TRANSFER_READ
                    | vk::AccessFlags2::TRANSFER_WRITE,
            ),
            (
                vk::PipelineStageFlags2::ALL_TRANSFER,
                vk::AccessFlags2::TRANSFER_WRITE,
            ),
        );
        let (width, height) = (raw.width.max(1), raw.height.max(1));
        self.pyramid_levels = pyramid_levels(width, height).len() as u32;
        if OCCLUSION {
            self.reserve_pyramid(width, height)?;
            // This frame reads what the last one found visible and writes afresh.
            clear(&self.gpu, command_buffer, &self.visibility.buffers[NOW]);
            if CLUSTERS {
                clear(
                    &self.gpu,
                    command_buffer,
                    &self.cluster_visibility.buffers[NOW],
                );
                clear(&self.gpu, command_buffer, &self.phase0_skipped);
            }
        }
        clear(&self.gpu, command_buffer, &self.counts);
        // Where the submission draws commands past the count (`individual-mdi` draws every
        // command of the capacity, on devices without drawIndirectCount; `dgc` runs a pass in
        // chunks, each reading the pass's count), what lies there must draw nothing: commands
        // of zero instances. Only then: the room is large (gen:grid's 100 000 parts, 55 MB),
        // and filling it cost Mesa 25's lavapipe 10 ms a frame.
        if cull.empties_command_tails() {
            if let Some(commands) = &self.commands.buffer {
                clear(&self.gpu, command_buffer, commands);
            }
        }
        barrier(
            &self.gpu,
            command_buffer,
            (
                vk::PipelineStageFlags2::ALL_TRANSFER,
                vk::AccessFlags2::TRANSFER_WRITE,
            ),
            (
                vk::PipelineStageFlags2::COMPUTE_SHADER,
                vk::AccessFlags2::SHADER_READ
                    | vk::AccessFlags2::SHADER_WRITE
                    | vk::AccessFlags2::UNIFORM_READ,
            ),
        );
        Ok(())
    }
}

impl<const OCCLUSION: bool, const CLUSTERS: bool> GpuCulling for GpuCuller<OCCLUSION, CLUSTERS> {
    const REQUIRED_EXTENSIONS: &'static [abi::CadrExtensionKind] = if CLUSTERS {
        &[
            abi::CADR_EXTENSION_SCENE_CLUSTERS,
            abi::CADR_EXTENSION_CLUSTER_CULL,
        ]
    } else {
        &[]
    };

    fn phase_count(&self) -> u32 {
        self.phases()
    }

    fn record(&mut self, cull: &GpuCull<'_>) -> Result<(), String> {
        let scene = cull.scene().ok_or("no scene")?;
        let instances = scene.raw().instance_count;
        let clusters = if CLUSTERS {
            Some(
                scene
                    .clusters()
                    .ok_or("the host passed no clusters (a host of ABI 1.14 or later does)")?,
            )
        } else {
            None
        };
        let boxes = (
            scene.cluster_boxes().filter(|_| CLUSTERS),
            scene.part_boxes(),
            scene.streaming(),
        );
        let slot = scene.frame_slot().map_or(0, |frame| frame.slot as usize);
        if slot >= FRAME_SLOTS {
            return Err(format!(
                "frame slot {slot}: this culler keeps sets for {FRAME_SLOTS} frames in flight"
            ));
        }
        let (commands, cluster_budget) = self.command_room(instances, clusters);
        self.cluster_budget = cluster_budget;
        self.commands.frame_shape = (cull.shares_face_streams(), scene.parameter_blocks());
        let command_buffer = cull.command_buffer();
        let view = cull
            .view_buffer()
            .ok_or("the host passed no view buffer (a host of ABI 1.5 or later does)")?;
        if cull.phase() == 0 {
            let cluster_bits = clusters.map_or(0, |c| c.candidate_clusters);
            self.prepare_buffers(cull, (instances, commands, cluster_bits))?;
            self.write_cull_set(slot, scene.raw(), clusters, boxes, view);
            let mode = if OCCLUSION {
                MODE_LAST_VISIBLE
            } else {
                MODE_FRUSTUM
            };
            self.dispatch_cull(cull, slot, instances, mode);
        } else {
            self.build_pyramid(cull)?;
            self.write_cull_set(slot, scene.raw(), clusters, boxes, view);
            self.dispatch_cull(cull, slot, instances, MODE_NEWLY_VISIBLE);
            if cull.phase() + 1 == self.phases() {
                self.keep_visibility(command_buffer);
            }
        }
        // The commands and counts are read by the draws; the counts by the host at the end.
        barrier(
            &self.gpu,
            command_buffer,
            (
                vk::PipelineStageFlags2::COMPUTE_SHADER,
                vk::AccessFlags2::SHADER_WRITE,
            ),
            (
                vk::PipelineStageFlags2::DRAW_INDIRECT
                    | vk::PipelineStageFlags2::VERTEX_SHADER
                    | vk::PipelineStageFlags2::COMPUTE_SHADER
                    | vk::PipelineStageFlags2::HOST,
                vk::AccessFlags2::INDIRECT_COMMAND_READ
                    | vk::AccessFlags2::SHADER_READ
                    | vk::AccessFlags2::HOST_READ,
            ),
        );
        Ok(())
    }

    fn counts(&self) -> abi::CadrStats {
        let read = |word: usize| {
            self.counts
                .read(word as u64 * 4, 4)
                .ok()
                .and_then(|b| b.try_into().ok())
                .map_or(0, u32::from_le_bytes)
        };
        abi::CadrStats {
            // A cluster culler's ranges are its clusters (and the parts its edge passes draw
            // whole, one command each, which the cluster count leaves out).
            draws: u64::from(read(if CLUSTERS {
                TOTAL_CLUSTERS
            } else {
                TOTAL_COMMANDS
            })),
            primitives: u64::from(read(TOTAL_TRIANGLES)),
            ..abi::CadrStats::default()
        }
    }
}

/// `gpu-frustum`.
pub type GpuFrustum = GpuCuller<false, false>;
/// `gpu-occlusion`.
pub type GpuOcclusion = GpuCuller<true, false>;
/// `gpu-clusters`.
pub type GpuClusters = GpuCuller<true, true>;
