//! Pipelines and their layouts: the per-frame descriptor set shared by every technique and the
//! GPU scene's scatter compute pipeline.

use std::sync::{Arc, OnceLock};

use ash::vk;

use crate::shaders::{self, ShaderSource};
use crate::vk::{Device, ShaderModule, VkError, VkResult, VkResultExt, DEPTH_FORMAT};

/// Format of the pick target: one instance id (+1) per pixel.
pub const PICK_FORMAT: vk::Format = vk::Format::R32_UINT;

/// Per-frame uniform data; mirrors `FrameUniforms` in `shaders/frame.glsl` (std140).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FrameUniforms {
    /// View to clip space.
    pub projection: [[f32; 4]; 4],
    /// World to view space without the translation (the eye at the origin).
    pub view_rotation: [[f32; 4]; 4],
    /// The eye's world position, f32 high part (xyz).
    pub eye_high: [f32; 4],
    /// The eye's world position, f32 remainder (xyz).
    pub eye_low: [f32; 4],
    /// Ambient, diffuse and specular strength of the head light.
    pub light: [f32; 4],
}

/// Push constants of `scatter.comp`: one dispatch scatters the items of one array.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ScatterParameters {
    /// Items in the dispatch.
    pub item_count: u32,
    /// 32-bit words per item, without its slot.
    pub item_words: u32,
    /// The index of the dispatch's first word in the update buffer.
    pub first_word: u32,
}

fn set_layout(
    device: &Device,
    name: &str,
    bindings: &[(vk::DescriptorType, vk::ShaderStageFlags)],
) -> VkResult<vk::DescriptorSetLayout> {
    let bindings: Vec<vk::DescriptorSetLayoutBinding<'_>> = bindings
        .iter()
        .enumerate()
        .map(|(i, &(ty, stages))| {
            vk::DescriptorSetLayoutBinding::default()
                .binding(i as u32)
                .descriptor_type(ty)
                .descriptor_count(1)
                .stage_flags(stages)
        })
        .collect();
    let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
    // SAFETY: the info lives for the call.
    let layout = unsafe { device.raw().create_descriptor_set_layout(&info, None) }
        .or_vk("vkCreateDescriptorSetLayout")?;
    device.set_name(layout, name);
    Ok(layout)
}

fn pipeline_layout(
    device: &Device,
    name: &str,
    sets: &[vk::DescriptorSetLayout],
    push_size: u32,
    push_stages: vk::ShaderStageFlags,
) -> VkResult<vk::PipelineLayout> {
    let push = [vk::PushConstantRange::default()
        .stage_flags(push_stages)
        .size(push_size)];
    let info = vk::PipelineLayoutCreateInfo::default()
        .set_layouts(sets)
        .push_constant_ranges(&push);
    // SAFETY: the info lives for the call.
    let layout = unsafe { device.raw().create_pipeline_layout(&info, None) }
        .or_vk("vkCreatePipelineLayout")?;
    device.set_name(layout, name);
    Ok(layout)
}

/// A descriptor pool, its sets and the layouts it was made for; destroyed together.
pub struct DescriptorSets {
    device: Arc<Device>,
    pool: vk::DescriptorPool,
    /// The sets, one per layout given.
    pub sets: Vec<vk::DescriptorSet>,
}

impl DescriptorSets {
    /// Allocates one set per layout from a pool sized for them.
    pub fn new(
        device: &Arc<Device>,
        name: &str,
        layouts: &[vk::DescriptorSetLayout],
        sizes: &[vk::DescriptorPoolSize],
    ) -> VkResult<Self> {
        let info = vk::DescriptorPoolCreateInfo::default()
            .max_sets(layouts.len() as u32)
            .pool_sizes(sizes);
        // SAFETY: the info lives for the call.
        let pool = unsafe { device.raw().create_descriptor_pool(&info, None) }
            .or_vk("vkCreateDescriptorPool")?;
        device.set_name(pool, name);
        let mut this = Self {
            device: Arc::clone(device),
            pool,
            sets: Vec::new(),
        };
        let alloc = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(pool)
            .set_layouts(layouts);
        // SAFETY: the pool was sized for exactly these sets.
        this.sets = unsafe { device.raw().allocate_descriptor_sets(&alloc) }
            .or_vk("vkAllocateDescriptorSets")?;
        for (i, &set) in this.sets.iter().enumerate() {
            device.set_name(set, &format!("{name} set {i}"));
        }
        Ok(this)
    }

    /// Points `binding` of set `set` at `buffer` (whole range).
    pub fn write_buffer(
        &self,
        set: usize,
        binding: u32,
        ty: vk::DescriptorType,
        buffer: vk::Buffer,
        range: u64,
    ) {
        let info = [vk::DescriptorBufferInfo::default()
            .buffer(buffer)
            .range(range)];
        let write = [vk::WriteDescriptorSet::default()
            .dst_set(self.sets[set])
            .dst_binding(binding)
            .descriptor_type(ty)
            .buffer_info(&info)];
        // SAFETY: callers update sets only while no submitted command buffer uses them (frames
        // are waited for before the next is recorded).
        unsafe { self.device.raw().update_descriptor_sets(&write, &[]) };
    }
}

impl Drop for DescriptorSets {
    fn drop(&mut self) {
        // SAFETY: owners drop their sets after the GPU is done with them; sets go with the pool.
        unsafe { self.device.raw().destroy_descriptor_pool(self.pool, None) };
    }
}

/// Every pipeline and layout the renderer uses.
pub struct Pipelines {
    device: Arc<Device>,
    /// Set 0: the frame uniform buffer.
    pub frame_set_layout: vk::DescriptorSetLayout,
    /// The scatter pipeline's set: the compact updates and the array they go into.
    pub scatter_set_layout: vk::DescriptorSetLayout,
    /// Scatter layout.
    pub scatter_layout: vk::PipelineLayout,
    /// Scatter compute pipeline.
    scatter: OnceLock<vk::Pipeline>,
}

impl Pipelines {
    /// Compiles every shader and creates the pipelines.
    pub fn new(device: &Arc<Device>) -> VkResult<Self> {
        let graphics = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT;
        let mut this = Self {
            device: Arc::clone(device),
            frame_set_layout: vk::DescriptorSetLayout::null(),
            scatter_set_layout: vk::DescriptorSetLayout::null(),
            scatter_layout: vk::PipelineLayout::null(),
            scatter: OnceLock::new(),
        };
        this.frame_set_layout = set_layout(
            device,
            "frame set layout",
            &[(vk::DescriptorType::UNIFORM_BUFFER, graphics)],
        )?;
        let compute = vk::ShaderStageFlags::COMPUTE;
        let compute_storage = (vk::DescriptorType::STORAGE_BUFFER, compute);
        this.scatter_set_layout = set_layout(device, "scatter set layout", &[compute_storage; 2])?;
        this.scatter_layout = pipeline_layout(
            device,
            "scatter layout",
            &[this.scatter_set_layout],
            std::mem::size_of::<ScatterParameters>() as u32,
            compute,
        )?;
        Ok(this)
    }

    /// `cell`'s pipeline, created by `make` on first use (each pipeline costs a shader compile
    /// and, on lavapipe, a JIT compile of 60–150 ms, so only what a renderer draws with is made).
    fn lazy(
        &self,
        cell: &OnceLock<vk::Pipeline>,
        make: impl FnOnce() -> VkResult<vk::Pipeline>,
    ) -> VkResult<vk::Pipeline> {
        if let Some(&pipeline) = cell.get() {
            return Ok(pipeline);
        }
        let pipeline = make()?;
        if let Err(unused) = cell.set(pipeline) {
            // SAFETY: made just now and never used.
            unsafe { self.device.raw().destroy_pipeline(unused, None) };
        }
        cell.get()
            .copied()
            .ok_or_else(|| VkError::InvalidUse("pipeline cell empty".into()))
    }

    /// The scatter compute pipeline.
    pub fn scatter(&self) -> VkResult<vk::Pipeline> {
        self.lazy(&self.scatter, || {
            compute_pipeline(
                &self.device,
                self.scatter_layout,
                &shaders::SCATTER_COMP,
                "scatter pipeline",
            )
        })
    }
}

impl Drop for Pipelines {
    fn drop(&mut self) {
        let raw = self.device.raw();
        // SAFETY: the renderer waits for its last frame before dropping the pipelines; null
        // handles (from a failed constructor) are ignored by Vulkan.
        unsafe {
            if let Some(&pipeline) = self.scatter.get() {
                raw.destroy_pipeline(pipeline, None);
            }
            raw.destroy_pipeline_layout(self.scatter_layout, None);
            for layout in [self.frame_set_layout, self.scatter_set_layout] {
                raw.destroy_descriptor_set_layout(layout, None);
            }
        }
    }
}

fn module(device: &Arc<Device>, shader: &ShaderSource) -> VkResult<ShaderModule> {
    ShaderModule::from_glsl(
        device,
        shader.name,
        shader.source,
        shader.stage,
        shaders::INCLUDES,
    )
}

fn compute_pipeline(
    device: &Arc<Device>,
    layout: vk::PipelineLayout,
    shader: &ShaderSource,
    name: &str,
) -> VkResult<vk::Pipeline> {
    let module = module(device, shader)?;
    let stage = vk::PipelineShaderStageCreateInfo::default()
        .stage(vk::ShaderStageFlags::COMPUTE)
        .module(module.raw())
        .name(c"main");
    let info = [vk::ComputePipelineCreateInfo::default()
        .stage(stage)
        .layout(layout)];
    // SAFETY: the info and the module live for the call.
    let pipelines = unsafe {
        device
            .raw()
            .create_compute_pipelines(vk::PipelineCache::null(), &info, None)
    }
    .map_err(|(_, result)| result)
    .or_vk("vkCreateComputePipelines")?;
    device.set_name(pipelines[0], name);
    Ok(pipelines[0])
}

/// Binding 0's stride and its attributes (format, offset) at locations 0, 1, ….
#[derive(Clone, Copy, Debug)]
pub(crate) struct VertexLayout<'a> {
    pub stride: u32,
    pub attributes: &'a [(vk::Format, u32)],
}

/// What cadr's graphics pipelines differ in. The rest is shared: dynamic viewport and scissor,
/// no face culling, depth test and write with LESS_OR_EQUAL, one colour target, dynamic
/// rendering with [`DEPTH_FORMAT`].
pub(crate) struct GraphicsPipelineDesc<'a> {
    pub layout: vk::PipelineLayout,
    pub vertex: &'a ShaderModule,
    pub fragment: &'a ShaderModule,
    /// `None` for no vertex input (vertex pulling).
    pub vertex_layout: Option<VertexLayout<'a>>,
    pub topology: vk::PrimitiveTopology,
    /// Pushes triangles back (constant and slope factor 1) so that edge lines win the depth test.
    pub depth_bias: bool,
    pub color_format: vk::Format,
    pub name: &'a str,
}

/// Creates a graphics pipeline.
pub(crate) fn create_graphics_pipeline(
    device: &Arc<Device>,
    desc: &GraphicsPipelineDesc<'_>,
) -> VkResult<vk::Pipeline> {
    let stages = [
        vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::VERTEX)
            .module(desc.vertex.raw())
            .name(c"main"),
        vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::FRAGMENT)
            .module(desc.fragment.raw())
            .name(c"main"),
    ];
    let layout = desc.vertex_layout.unwrap_or(VertexLayout {
        stride: 0,
        attributes: &[],
    });
    let vertex_bindings = [vk::VertexInputBindingDescription::default()
        .binding(0)
        .stride(layout.stride)
        .input_rate(vk::VertexInputRate::VERTEX)];
    let vertex_attributes: Vec<vk::VertexInputAttributeDescription> = layout
        .attributes
        .iter()
        .enumerate()
        .map(|(location, &(format, offset))| {
            vk::VertexInputAttributeDescription::default()
                .location(location as u32)
                .binding(0)
                .format(format)
                .offset(offset)
        })
        .collect();
    let vertex_input = match desc.vertex_layout {
        Some(_) => vk::PipelineVertexInputStateCreateInfo::default()
            .vertex_binding_descriptions(&vertex_bindings)
            .vertex_attribute_descriptions(&vertex_attributes),
        None => vk::PipelineVertexInputStateCreateInfo::default(),
    };
    let input_assembly =
        vk::PipelineInputAssemblyStateCreateInfo::default().topology(desc.topology);
    let viewport = vk::PipelineViewportStateCreateInfo::default()
        .viewport_count(1)
        .scissor_count(1);
    let rasterization = vk::PipelineRasterizationStateCreateInfo::default()
        .polygon_mode(vk::PolygonMode::FILL)
        .cull_mode(vk::CullModeFlags::NONE)
        .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
        .depth_bias_enable(desc.depth_bias)
        .depth_bias_constant_factor(1.0)
        .depth_bias_slope_factor(1.0)
        .line_width(1.0);
    let multisample = vk::PipelineMultisampleStateCreateInfo::default()
        .rasterization_samples(vk::SampleCountFlags::TYPE_1);
    let depth = vk::PipelineDepthStencilStateCreateInfo::default()
        .depth_test_enable(true)
        .depth_write_enable(true)
        .depth_compare_op(vk::CompareOp::LESS_OR_EQUAL);
    let blend_attachments = [vk::PipelineColorBlendAttachmentState::default()
        .color_write_mask(vk::ColorComponentFlags::RGBA)];
    let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend_attachments);
    let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
    let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
    let color_formats = [desc.color_format];
    let mut rendering = vk::PipelineRenderingCreateInfo::default()
        .color_attachment_formats(&color_formats)
        .depth_attachment_format(DEPTH_FORMAT);
    let info = [vk::GraphicsPipelineCreateInfo::default()
        .stages(&stages)
        .vertex_input_state(&vertex_input)
        .input_assembly_state(&input_assembly)
        .viewport_state(&viewport)
        .rasterization_state(&rasterization)
        .multisample_state(&multisample)
        .depth_stencil_state(&depth)
        .color_blend_state(&blend)
        .dynamic_state(&dynamic)
        .layout(desc.layout)
        .push_next(&mut rendering)];
    // SAFETY: every struct the info points to lives until the call returns; the modules are
    // alive during the call (pipelines do not keep them).
    let pipelines = unsafe {
        device
            .raw()
            .create_graphics_pipelines(vk::PipelineCache::null(), &info, None)
    }
    .map_err(|(_, result)| result)
    .or_vk("vkCreateGraphicsPipelines")?;
    device.set_name(pipelines[0], desc.name);
    Ok(pipelines[0])
}
