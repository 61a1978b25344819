//! `VK_EXT_device_generated_commands` (extension 573): the GPU writes a stream of command
//! sequences (pipeline switches, push constants, draws) and the command buffer executes it,
//! with the number of sequences read from GPU memory.
//!
//! Bound, as the `dgc` submission uses them: the feature struct, an indirect commands layout
//! of indexed-draw tokens, with an execution-set token, a push-constant token, both or
//! neither before them, execution sets of pipelines (made, updated, destroyed; their
//! pipelines made indirect-bindable), the memory-requirements query and the execute command
//! (preprocessing implicit). The other tokens (vertex and index buffers, sequence index, push
//! data), explicit preprocessing and shader objects are not bound: bind them with the
//! technique that uses them.

use std::ffi::{c_void, CStr};
use std::marker::PhantomData;

use ash::vk;

/// The extension's name.
pub const NAME: &CStr = c"VK_EXT_device_generated_commands";

/// `VK_STRUCTURE_TYPE_*` values: 1000000000 + (573 − 1) × 1000 + offset.
const fn structure_type(offset: i32) -> vk::StructureType {
    vk::StructureType::from_raw(1_000_572_000 + offset)
}

/// `VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DEVICE_GENERATED_COMMANDS_FEATURES_EXT`.
pub const STRUCTURE_TYPE_FEATURES: vk::StructureType = structure_type(0);
/// `VK_STRUCTURE_TYPE_GENERATED_COMMANDS_MEMORY_REQUIREMENTS_INFO_EXT`.
pub const STRUCTURE_TYPE_MEMORY_REQUIREMENTS_INFO: vk::StructureType = structure_type(2);
/// `VK_STRUCTURE_TYPE_INDIRECT_EXECUTION_SET_CREATE_INFO_EXT`.
pub const STRUCTURE_TYPE_EXECUTION_SET_CREATE_INFO: vk::StructureType = structure_type(3);
/// `VK_STRUCTURE_TYPE_GENERATED_COMMANDS_INFO_EXT`.
pub const STRUCTURE_TYPE_GENERATED_COMMANDS_INFO: vk::StructureType = structure_type(4);
/// `VK_STRUCTURE_TYPE_INDIRECT_COMMANDS_LAYOUT_CREATE_INFO_EXT`.
pub const STRUCTURE_TYPE_LAYOUT_CREATE_INFO: vk::StructureType = structure_type(6);
/// `VK_STRUCTURE_TYPE_INDIRECT_COMMANDS_LAYOUT_TOKEN_EXT`.
pub const STRUCTURE_TYPE_LAYOUT_TOKEN: vk::StructureType = structure_type(7);
/// `VK_STRUCTURE_TYPE_WRITE_INDIRECT_EXECUTION_SET_PIPELINE_EXT`.
pub const STRUCTURE_TYPE_WRITE_EXECUTION_SET_PIPELINE: vk::StructureType = structure_type(8);
/// `VK_STRUCTURE_TYPE_INDIRECT_EXECUTION_SET_PIPELINE_INFO_EXT`.
pub const STRUCTURE_TYPE_EXECUTION_SET_PIPELINE_INFO: vk::StructureType = structure_type(10);
/// `VK_STRUCTURE_TYPE_GENERATED_COMMANDS_PIPELINE_INFO_EXT`.
pub const STRUCTURE_TYPE_GENERATED_COMMANDS_PIPELINE_INFO: vk::StructureType = structure_type(13);

/// `VK_BUFFER_USAGE_2_PREPROCESS_BUFFER_BIT_EXT` (a `VkBufferUsageFlags2` bit, given through
/// `VkBufferUsageFlags2CreateInfoKHR` of `VK_KHR_maintenance5`).
pub const BUFFER_USAGE_2_PREPROCESS_BUFFER: vk::BufferUsageFlags2KHR =
    vk::BufferUsageFlags2KHR::from_raw(1 << 31);
/// `VK_PIPELINE_CREATE_2_INDIRECT_BINDABLE_BIT_EXT` (a `VkPipelineCreateFlags2` bit, given
/// through `VkPipelineCreateFlags2CreateInfoKHR` of `VK_KHR_maintenance5`): the pipeline may
/// be put into an execution set.
pub const PIPELINE_CREATE_2_INDIRECT_BINDABLE: vk::PipelineCreateFlags2KHR =
    vk::PipelineCreateFlags2KHR::from_raw(1 << 38);
/// `VK_INDIRECT_EXECUTION_SET_INFO_TYPE_PIPELINES_EXT`: an execution set of pipelines (the
/// only kind cadr makes; `VkIndirectExecutionSetInfoTypeEXT`).
pub const EXECUTION_SET_OF_PIPELINES: i32 = 0;

/// `VkIndirectCommandsLayoutEXT`: how one sequence of the stream is laid out.
#[repr(transparent)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct IndirectCommandsLayout(u64);

impl IndirectCommandsLayout {
    /// The null handle.
    pub const fn null() -> Self {
        Self(0)
    }
}

/// `VkIndirectExecutionSetEXT`: pipelines a sequence picks by index (null: the bound pipeline
/// draws every sequence).
#[repr(transparent)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct IndirectExecutionSet(u64);

impl IndirectExecutionSet {
    /// The null handle.
    pub const fn null() -> Self {
        Self(0)
    }
}

/// `VkIndirectCommandsTokenTypeEXT` (the kinds cadr uses).
#[repr(transparent)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TokenType(i32);

impl TokenType {
    /// `VK_INDIRECT_COMMANDS_TOKEN_TYPE_EXECUTION_SET_EXT`: a `u32`, the index in the execution
    /// set of the pipeline that draws the sequence.
    pub const EXECUTION_SET: Self = Self(0);
    /// `VK_INDIRECT_COMMANDS_TOKEN_TYPE_PUSH_CONSTANT_EXT`: the bytes of a push-constant range,
    /// pushed before the sequence's draw.
    pub const PUSH_CONSTANT: Self = Self(1);
    /// `VK_INDIRECT_COMMANDS_TOKEN_TYPE_DRAW_INDEXED_EXT`: a `VkDrawIndexedIndirectCommand`.
    pub const DRAW_INDEXED: Self = Self(5);
    /// The raw value.
    pub const fn as_raw(self) -> i32 {
        self.0
    }
}

/// `VkIndirectCommandsLayoutUsageFlagsEXT` (cadr sets none).
#[repr(transparent)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LayoutUsageFlags(u32);

/// `VkPhysicalDeviceDeviceGeneratedCommandsFeaturesEXT`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PhysicalDeviceFeatures<'a> {
    /// Set by `Default`.
    pub s_type: vk::StructureType,
    /// Chain.
    pub p_next: *mut c_void,
    /// `deviceGeneratedCommands`.
    pub device_generated_commands: vk::Bool32,
    /// `dynamicGeneratedPipelineLayout`.
    pub dynamic_generated_pipeline_layout: vk::Bool32,
    /// Ties the struct to the chain it is pushed into.
    pub _marker: PhantomData<&'a ()>,
}

impl Default for PhysicalDeviceFeatures<'_> {
    fn default() -> Self {
        Self {
            s_type: STRUCTURE_TYPE_FEATURES,
            p_next: std::ptr::null_mut(),
            device_generated_commands: vk::FALSE,
            dynamic_generated_pipeline_layout: vk::FALSE,
            _marker: PhantomData,
        }
    }
}

// SAFETY: the struct begins with sType and pNext, as every extending struct does.
unsafe impl vk::ExtendsPhysicalDeviceFeatures2 for PhysicalDeviceFeatures<'_> {}
// SAFETY: as above.
unsafe impl vk::ExtendsDeviceCreateInfo for PhysicalDeviceFeatures<'_> {}
// SAFETY: ash's chain walker reads sType and pNext only, at the offsets every Vulkan struct
// has them.
unsafe impl vk::TaggedStructure for PhysicalDeviceFeatures<'_> {
    const STRUCTURE_TYPE: vk::StructureType = STRUCTURE_TYPE_FEATURES;
}

/// `VkIndirectCommandsTokenDataEXT`: what a token needs besides its kind, by kind; every
/// member is a pointer, and draw tokens need none.
#[repr(C)]
#[derive(Clone, Copy)]
pub union TokenData<'a> {
    /// For draw tokens, which need nothing.
    pub none: *const c_void,
    /// `pExecutionSet`, for [`TokenType::EXECUTION_SET`].
    pub execution_set: *const ExecutionSetToken,
    /// `pPushConstant`, for [`TokenType::PUSH_CONSTANT`].
    pub push_constant: *const PushConstantToken,
    _marker: PhantomData<&'a ()>,
}

impl std::fmt::Debug for TokenData<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("TokenData")
    }
}

/// `VkIndirectCommandsLayoutTokenEXT`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct LayoutToken<'a> {
    /// Set by the constructors.
    pub s_type: vk::StructureType,
    /// Chain.
    pub p_next: *const c_void,
    /// `type`.
    pub ty: TokenType,
    /// `data`, as `ty` says.
    pub data: TokenData<'a>,
    /// `offset`: bytes from the sequence's start.
    pub offset: u32,
}

impl<'a> LayoutToken<'a> {
    fn new(ty: TokenType, data: TokenData<'a>, offset: u32) -> Self {
        Self {
            s_type: STRUCTURE_TYPE_LAYOUT_TOKEN,
            p_next: std::ptr::null(),
            ty,
            data,
            offset,
        }
    }

    /// A `VkDrawIndexedIndirectCommand` at `offset`.
    pub fn draw_indexed(offset: u32) -> Self {
        Self::new(
            TokenType::DRAW_INDEXED,
            TokenData {
                none: std::ptr::null(),
            },
            offset,
        )
    }
}

impl<'a> LayoutToken<'a> {
    /// A `u32` at `offset` that picks the sequence's pipeline from the execution set: `token`
    /// says which stages the set's pipelines have.
    pub fn execution_set(token: &'a ExecutionSetToken, offset: u32) -> Self {
        Self::new(
            TokenType::EXECUTION_SET,
            TokenData {
                execution_set: token,
            },
            offset,
        )
    }
}

impl<'a> LayoutToken<'a> {
    /// The bytes at `offset` pushed as the push-constant range `token` names (its size, from its
    /// offset in the pipeline layout's push constants).
    pub fn push_constant(token: &'a PushConstantToken, offset: u32) -> Self {
        Self::new(
            TokenType::PUSH_CONSTANT,
            TokenData {
                push_constant: token,
            },
            offset,
        )
    }
}

/// `VkIndirectCommandsPushConstantTokenEXT`: which push constants a push-constant token sets.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PushConstantToken {
    /// `updateRange`: stages, offset and size, within a range of the layout's pipeline layout.
    pub update_range: vk::PushConstantRange,
}

/// `VkIndirectCommandsExecutionSetTokenEXT`: what an execution-set token switches.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct ExecutionSetToken {
    /// `type`: [`EXECUTION_SET_OF_PIPELINES`].
    pub ty: i32,
    /// `shaderStages`: the stages the set's pipelines have.
    pub shader_stages: vk::ShaderStageFlags,
}

/// `VkIndirectExecutionSetPipelineInfoEXT`: a set of pipelines like `initial_pipeline`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct ExecutionSetPipelineInfo<'a> {
    /// Set by `new`.
    pub s_type: vk::StructureType,
    /// Chain.
    pub p_next: *const c_void,
    /// `initialPipeline`: index 0 of the set, and what every pipeline put in it must match.
    pub initial_pipeline: vk::Pipeline,
    /// `maxPipelineCount`.
    pub max_pipeline_count: u32,
    /// Lifetime of the chain.
    pub _marker: PhantomData<&'a ()>,
}

impl ExecutionSetPipelineInfo<'_> {
    /// A set of at most `max_pipelines`, `initial` at index 0.
    pub fn new(initial: vk::Pipeline, max_pipelines: u32) -> Self {
        Self {
            s_type: STRUCTURE_TYPE_EXECUTION_SET_PIPELINE_INFO,
            p_next: std::ptr::null(),
            initial_pipeline: initial,
            max_pipeline_count: max_pipelines,
            _marker: PhantomData,
        }
    }
}

/// `VkIndirectExecutionSetInfoEXT`: what a set holds, by its type.
#[repr(C)]
#[derive(Clone, Copy)]
pub union ExecutionSetInfo<'a> {
    /// `pPipelineInfo`, for [`EXECUTION_SET_OF_PIPELINES`].
    pub pipeline_info: *const ExecutionSetPipelineInfo<'a>,
}

impl std::fmt::Debug for ExecutionSetInfo<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("ExecutionSetInfo")
    }
}

/// `VkIndirectExecutionSetCreateInfoEXT`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct ExecutionSetCreateInfo<'a> {
    /// Set by `pipelines`.
    pub s_type: vk::StructureType,
    /// Chain.
    pub p_next: *const c_void,
    /// `type`: [`EXECUTION_SET_OF_PIPELINES`].
    pub ty: i32,
    /// `info`, as `ty` says.
    pub info: ExecutionSetInfo<'a>,
}

impl<'a> ExecutionSetCreateInfo<'a> {
    /// A set of pipelines as `info` says.
    pub fn pipelines(info: &'a ExecutionSetPipelineInfo<'a>) -> Self {
        Self {
            s_type: STRUCTURE_TYPE_EXECUTION_SET_CREATE_INFO,
            p_next: std::ptr::null(),
            ty: EXECUTION_SET_OF_PIPELINES,
            info: ExecutionSetInfo {
                pipeline_info: info,
            },
        }
    }
}

/// `VkWriteIndirectExecutionSetPipelineEXT`: puts `pipeline` at `index` of a set.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct WriteExecutionSetPipeline<'a> {
    /// Set by `new`.
    pub s_type: vk::StructureType,
    /// Chain.
    pub p_next: *const c_void,
    /// `index`.
    pub index: u32,
    /// `pipeline` (made indirect-bindable, like the set's initial pipeline).
    pub pipeline: vk::Pipeline,
    /// Lifetime of the chain.
    pub _marker: PhantomData<&'a ()>,
}

impl WriteExecutionSetPipeline<'_> {
    /// Puts `pipeline` at `index`.
    pub fn new(index: u32, pipeline: vk::Pipeline) -> Self {
        Self {
            s_type: STRUCTURE_TYPE_WRITE_EXECUTION_SET_PIPELINE,
            p_next: std::ptr::null(),
            index,
            pipeline,
            _marker: PhantomData,
        }
    }
}

/// `VkIndirectCommandsLayoutCreateInfoEXT`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct LayoutCreateInfo<'a> {
    /// Set by `new`.
    pub s_type: vk::StructureType,
    /// Chain.
    pub p_next: *const c_void,
    /// `flags`.
    pub flags: LayoutUsageFlags,
    /// `shaderStages`: the stages the sequences' state reaches.
    pub shader_stages: vk::ShaderStageFlags,
    /// `indirectStride`: bytes from one sequence to the next.
    pub indirect_stride: u32,
    /// `pipelineLayout` (for push constant tokens).
    pub pipeline_layout: vk::PipelineLayout,
    /// `tokenCount`.
    pub token_count: u32,
    /// `pTokens`.
    pub p_tokens: *const LayoutToken<'a>,
    /// Ties the struct to `tokens`.
    pub _marker: PhantomData<&'a ()>,
}

impl<'a> LayoutCreateInfo<'a> {
    /// A layout of `tokens`, one sequence every `stride` bytes, for `stages`.
    pub fn new(
        flags: LayoutUsageFlags,
        stages: vk::ShaderStageFlags,
        stride: u32,
        pipeline_layout: vk::PipelineLayout,
        tokens: &'a [LayoutToken<'a>],
    ) -> Self {
        Self {
            s_type: STRUCTURE_TYPE_LAYOUT_CREATE_INFO,
            p_next: std::ptr::null(),
            flags,
            shader_stages: stages,
            indirect_stride: stride,
            pipeline_layout,
            token_count: tokens.len() as u32,
            p_tokens: tokens.as_ptr(),
            _marker: PhantomData,
        }
    }
}

/// `VkGeneratedCommandsPipelineInfoEXT`: the pipeline of a stream that has no execution set.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct GeneratedCommandsPipelineInfo<'a> {
    /// Set by `new`.
    pub s_type: vk::StructureType,
    /// Chain.
    pub p_next: *mut c_void,
    /// `pipeline`.
    pub pipeline: vk::Pipeline,
    /// Lifetime of the chain.
    pub _marker: PhantomData<&'a ()>,
}

impl GeneratedCommandsPipelineInfo<'_> {
    /// For streams drawn with `pipeline` bound.
    pub fn new(pipeline: vk::Pipeline) -> Self {
        Self {
            s_type: STRUCTURE_TYPE_GENERATED_COMMANDS_PIPELINE_INFO,
            p_next: std::ptr::null_mut(),
            pipeline,
            _marker: PhantomData,
        }
    }
}

/// `VkGeneratedCommandsMemoryRequirementsInfoEXT`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct MemoryRequirementsInfo<'a> {
    /// Set by `new`.
    pub s_type: vk::StructureType,
    /// Chain (a [`GeneratedCommandsPipelineInfo`] where there is no execution set).
    pub p_next: *const c_void,
    /// `indirectExecutionSet`.
    pub indirect_execution_set: IndirectExecutionSet,
    /// `indirectCommandsLayout`.
    pub indirect_commands_layout: IndirectCommandsLayout,
    /// `maxSequenceCount`.
    pub max_sequence_count: u32,
    /// `maxDrawCount`.
    pub max_draw_count: u32,
    /// Lifetime of the chain.
    pub _marker: PhantomData<&'a ()>,
}

impl<'a> MemoryRequirementsInfo<'a> {
    /// The preprocess memory `max_sequences` sequences of `layout` need, with `set` (or the
    /// pipeline of `pipeline_info` where `set` is null).
    pub fn new(
        layout: IndirectCommandsLayout,
        set: IndirectExecutionSet,
        pipeline_info: Option<&'a GeneratedCommandsPipelineInfo<'a>>,
        max_sequences: u32,
    ) -> Self {
        Self {
            s_type: STRUCTURE_TYPE_MEMORY_REQUIREMENTS_INFO,
            p_next: pipeline_info.map_or(std::ptr::null(), |info| {
                (info as *const GeneratedCommandsPipelineInfo<'_>).cast()
            }),
            indirect_execution_set: set,
            indirect_commands_layout: layout,
            max_sequence_count: max_sequences,
            max_draw_count: 0,
            _marker: PhantomData,
        }
    }
}

/// `VkGeneratedCommandsInfoEXT`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct GeneratedCommandsInfo<'a> {
    /// Set by `Default`.
    pub s_type: vk::StructureType,
    /// Chain (a [`GeneratedCommandsPipelineInfo`] where there is no execution set).
    pub p_next: *const c_void,
    /// `shaderStages`.
    pub shader_stages: vk::ShaderStageFlags,
    /// `indirectExecutionSet` (null: the bound pipeline draws every sequence).
    pub indirect_execution_set: IndirectExecutionSet,
    /// `indirectCommandsLayout`.
    pub indirect_commands_layout: IndirectCommandsLayout,
    /// `indirectAddress`: the first sequence.
    pub indirect_address: vk::DeviceAddress,
    /// `indirectAddressSize`: bytes of sequences.
    pub indirect_address_size: vk::DeviceSize,
    /// `preprocessAddress`.
    pub preprocess_address: vk::DeviceAddress,
    /// `preprocessSize`.
    pub preprocess_size: vk::DeviceSize,
    /// `maxSequenceCount`.
    pub max_sequence_count: u32,
    /// `sequenceCountAddress`: a `u32` the GPU reads (0: run `max_sequence_count`).
    pub sequence_count_address: vk::DeviceAddress,
    /// `maxDrawCount`.
    pub max_draw_count: u32,
    /// Lifetime of the chain.
    pub _marker: PhantomData<&'a ()>,
}

impl Default for GeneratedCommandsInfo<'_> {
    fn default() -> Self {
        Self {
            s_type: STRUCTURE_TYPE_GENERATED_COMMANDS_INFO,
            p_next: std::ptr::null(),
            shader_stages: vk::ShaderStageFlags::empty(),
            indirect_execution_set: IndirectExecutionSet::null(),
            indirect_commands_layout: IndirectCommandsLayout::null(),
            indirect_address: 0,
            indirect_address_size: 0,
            preprocess_address: 0,
            preprocess_size: 0,
            max_sequence_count: 0,
            sequence_count_address: 0,
            max_draw_count: 0,
            _marker: PhantomData,
        }
    }
}

type GetMemoryRequirements = unsafe extern "system" fn(
    vk::Device,
    *const MemoryRequirementsInfo<'_>,
    *mut vk::MemoryRequirements2<'_>,
);
type CmdExecute =
    unsafe extern "system" fn(vk::CommandBuffer, vk::Bool32, *const GeneratedCommandsInfo<'_>);
type CreateLayout = unsafe extern "system" fn(
    vk::Device,
    *const LayoutCreateInfo<'_>,
    *const vk::AllocationCallbacks<'_>,
    *mut IndirectCommandsLayout,
) -> vk::Result;
type DestroyLayout = unsafe extern "system" fn(
    vk::Device,
    IndirectCommandsLayout,
    *const vk::AllocationCallbacks<'_>,
);

type CreateExecutionSet = unsafe extern "system" fn(
    vk::Device,
    *const ExecutionSetCreateInfo<'_>,
    *const vk::AllocationCallbacks<'_>,
    *mut IndirectExecutionSet,
) -> vk::Result;
type DestroyExecutionSet =
    unsafe extern "system" fn(vk::Device, IndirectExecutionSet, *const vk::AllocationCallbacks<'_>);
type UpdateExecutionSetPipeline = unsafe extern "system" fn(
    vk::Device,
    IndirectExecutionSet,
    u32,
    *const WriteExecutionSetPipeline<'_>,
);

/// The extension's device-level functions, loaded for one device.
#[derive(Clone)]
pub struct Device {
    handle: vk::Device,
    get_memory_requirements: GetMemoryRequirements,
    cmd_execute: CmdExecute,
    create_layout: CreateLayout,
    destroy_layout: DestroyLayout,
    create_execution_set: CreateExecutionSet,
    destroy_execution_set: DestroyExecutionSet,
    update_execution_set_pipeline: UpdateExecutionSetPipeline,
}

impl std::fmt::Debug for Device {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("device_generated_commands::Device")
            .field("handle", &self.handle)
            .finish()
    }
}

impl Device {
    /// Loads the functions for `device`; `None` where one is missing (the extension was not
    /// enabled on it).
    pub fn new(instance: &ash::Instance, device: &ash::Device) -> Option<Self> {
        let handle = device.handle();
        let load = |name: &CStr| {
            // SAFETY: the device belongs to the instance; the name is NUL-terminated.
            unsafe { instance.get_device_proc_addr(handle, name.as_ptr()) }
        };
        macro_rules! function {
            ($name:literal, $ty:ty) => {{
                let pointer = load($name)?;
                // SAFETY: the loader returned the named command, whose signature is `$ty`
                // as the registry defines it.
                unsafe { std::mem::transmute::<unsafe extern "system" fn(), $ty>(pointer) }
            }};
        }
        Some(Self {
            handle,
            get_memory_requirements: function!(
                c"vkGetGeneratedCommandsMemoryRequirementsEXT",
                GetMemoryRequirements
            ),
            cmd_execute: function!(c"vkCmdExecuteGeneratedCommandsEXT", CmdExecute),
            create_layout: function!(c"vkCreateIndirectCommandsLayoutEXT", CreateLayout),
            destroy_layout: function!(c"vkDestroyIndirectCommandsLayoutEXT", DestroyLayout),
            create_execution_set: function!(c"vkCreateIndirectExecutionSetEXT", CreateExecutionSet),
            destroy_execution_set: function!(
                c"vkDestroyIndirectExecutionSetEXT",
                DestroyExecutionSet
            ),
            update_execution_set_pipeline: function!(
                c"vkUpdateIndirectExecutionSetPipelineEXT",
                UpdateExecutionSetPipeline
            ),
        })
    }

    /// `vkGetGeneratedCommandsMemoryRequirementsEXT`: the preprocess buffer's size, alignment
    /// and memory types.
    ///
    /// # Safety
    /// `info`'s handles belong to this device and are alive.
    pub unsafe fn memory_requirements(
        &self,
        info: &MemoryRequirementsInfo<'_>,
    ) -> vk::MemoryRequirements {
        let mut requirements = vk::MemoryRequirements2::default();
        // SAFETY: the caller's contract; the output struct lives on this frame.
        unsafe { (self.get_memory_requirements)(self.handle, info, &mut requirements) };
        requirements.memory_requirements
    }

    /// `vkCmdExecuteGeneratedCommandsEXT`.
    ///
    /// # Safety
    /// As the command's valid usage requires: recording inside rendering with the layout's
    /// state bound; the stream, count and preprocess memory alive until the GPU ran it.
    pub unsafe fn cmd_execute(
        &self,
        command_buffer: vk::CommandBuffer,
        preprocessed: bool,
        info: &GeneratedCommandsInfo<'_>,
    ) {
        // SAFETY: the caller's contract.
        unsafe { (self.cmd_execute)(command_buffer, vk::Bool32::from(preprocessed), info) };
    }

    /// `vkCreateIndirectCommandsLayoutEXT`.
    ///
    /// # Safety
    /// `info` and what it points to are valid; `allocator` as for any Vulkan object.
    pub unsafe fn create_layout(
        &self,
        info: &LayoutCreateInfo<'_>,
        allocator: Option<&vk::AllocationCallbacks<'_>>,
    ) -> Result<IndirectCommandsLayout, vk::Result> {
        let mut layout = IndirectCommandsLayout::null();
        // SAFETY: the caller's contract; the output lives on this frame.
        let result =
            unsafe { (self.create_layout)(self.handle, info, as_ptr(allocator), &mut layout) };
        result.result_with_success(layout)
    }

    /// `vkDestroyIndirectCommandsLayoutEXT`.
    ///
    /// # Safety
    /// No pending command uses `layout`; `allocator` as at creation.
    pub unsafe fn destroy_layout(
        &self,
        layout: IndirectCommandsLayout,
        allocator: Option<&vk::AllocationCallbacks<'_>>,
    ) {
        // SAFETY: the caller's contract.
        unsafe { (self.destroy_layout)(self.handle, layout, as_ptr(allocator)) };
    }
}

impl Device {
    /// `vkCreateIndirectExecutionSetEXT`.
    ///
    /// # Safety
    /// `info` and what it points to are valid (its initial pipeline made indirect-bindable);
    /// `allocator` as for any Vulkan object.
    pub unsafe fn create_execution_set(
        &self,
        info: &ExecutionSetCreateInfo<'_>,
        allocator: Option<&vk::AllocationCallbacks<'_>>,
    ) -> Result<IndirectExecutionSet, vk::Result> {
        let mut set = IndirectExecutionSet::null();
        // SAFETY: the caller's contract; the output lives on this frame.
        let result =
            unsafe { (self.create_execution_set)(self.handle, info, as_ptr(allocator), &mut set) };
        result.result_with_success(set)
    }

    /// `vkUpdateIndirectExecutionSetPipelineEXT`.
    ///
    /// # Safety
    /// The set is alive and no pending command uses the indices written; each pipeline is
    /// indirect-bindable and matches the set's initial pipeline.
    pub unsafe fn update_execution_set_pipelines(
        &self,
        set: IndirectExecutionSet,
        writes: &[WriteExecutionSetPipeline<'_>],
    ) {
        // SAFETY: the caller's contract; `writes` lives for the call.
        unsafe {
            (self.update_execution_set_pipeline)(
                self.handle,
                set,
                writes.len() as u32,
                writes.as_ptr(),
            )
        };
    }

    /// `vkDestroyIndirectExecutionSetEXT`.
    ///
    /// # Safety
    /// No pending command uses `set`; `allocator` as at creation.
    pub unsafe fn destroy_execution_set(
        &self,
        set: IndirectExecutionSet,
        allocator: Option<&vk::AllocationCallbacks<'_>>,
    ) {
        // SAFETY: the caller's contract.
        unsafe { (self.destroy_execution_set)(self.handle, set, as_ptr(allocator)) };
    }
}

fn as_ptr<'a>(
    allocator: Option<&vk::AllocationCallbacks<'a>>,
) -> *const vk::AllocationCallbacks<'a> {
    allocator.map_or(std::ptr::null(), |a| a as *const _)
}
