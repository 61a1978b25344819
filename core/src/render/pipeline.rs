//! The baseline graphics pipeline: vertex buffers, per-frame uniforms in set 0, per-draw matrix
//! and material in push constants.

use std::sync::Arc;

use ash::vk;

use crate::scene::Vertex;
use crate::shaders;
use crate::vk::{Device, ShaderModule, VkResult, VkResultExt, COLOR_FORMAT, DEPTH_FORMAT};

/// Per-frame uniform data; mirrors `FrameUniforms` in `shaders/frame.glsl` (std140).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FrameUniforms {
    /// View to clip space.
    pub projection: [[f32; 4]; 4],
    /// Ambient, diffuse and specular strength of the head light.
    pub light: [f32; 4],
}

/// Per-draw push constants; mirrors `DrawParameters` in `shaders/baseline.vert`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct DrawParameters {
    /// Object to view space.
    pub model_view: [[f32; 4]; 4],
    /// Linear RGBA.
    pub base_color: [f32; 4],
    /// x: metallic, y: roughness.
    pub surface: [f32; 4],
}

/// Pipeline, layouts and the descriptor set of the per-frame uniforms.
pub struct BaselinePipeline {
    device: Arc<Device>,
    set_layout: vk::DescriptorSetLayout,
    descriptor_pool: vk::DescriptorPool,
    /// The set holding the frame uniform buffer.
    pub frame_set: vk::DescriptorSet,
    /// The pipeline layout.
    pub layout: vk::PipelineLayout,
    /// The graphics pipeline.
    pub pipeline: vk::Pipeline,
}

impl BaselinePipeline {
    /// Compiles the shaders and creates the pipeline; `frame_buffer` is the uniform buffer
    /// bound in set 0.
    pub fn new(device: &Arc<Device>, frame_buffer: vk::Buffer) -> VkResult<Self> {
        let raw = device.raw();
        let mut this = Self {
            device: Arc::clone(device),
            set_layout: vk::DescriptorSetLayout::null(),
            descriptor_pool: vk::DescriptorPool::null(),
            frame_set: vk::DescriptorSet::null(),
            layout: vk::PipelineLayout::null(),
            pipeline: vk::Pipeline::null(),
        };
        let bindings = [vk::DescriptorSetLayoutBinding::default()
            .binding(0)
            .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
            .descriptor_count(1)
            .stage_flags(vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT)];
        let set_layout_info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
        // SAFETY: the info is valid and lives for the call; Drop destroys what is created.
        this.set_layout = unsafe { raw.create_descriptor_set_layout(&set_layout_info, None) }
            .or_vk("vkCreateDescriptorSetLayout")?;
        device.set_name(this.set_layout, "baseline frame set layout");
        let pool_sizes = [vk::DescriptorPoolSize::default()
            .ty(vk::DescriptorType::UNIFORM_BUFFER)
            .descriptor_count(1)];
        let pool_info = vk::DescriptorPoolCreateInfo::default()
            .max_sets(1)
            .pool_sizes(&pool_sizes);
        // SAFETY: as above.
        this.descriptor_pool = unsafe { raw.create_descriptor_pool(&pool_info, None) }
            .or_vk("vkCreateDescriptorPool")?;
        device.set_name(this.descriptor_pool, "baseline descriptor pool");
        let set_layouts = [this.set_layout];
        let alloc_info = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(this.descriptor_pool)
            .set_layouts(&set_layouts);
        // SAFETY: the pool has room for exactly this set.
        this.frame_set = unsafe { raw.allocate_descriptor_sets(&alloc_info) }
            .or_vk("vkAllocateDescriptorSets")?[0];
        device.set_name(this.frame_set, "baseline frame set");
        let buffer_info = [vk::DescriptorBufferInfo::default()
            .buffer(frame_buffer)
            .range(std::mem::size_of::<FrameUniforms>() as u64)];
        let write = [vk::WriteDescriptorSet::default()
            .dst_set(this.frame_set)
            .dst_binding(0)
            .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
            .buffer_info(&buffer_info)];
        // SAFETY: the set is not in use by any command buffer yet.
        unsafe { raw.update_descriptor_sets(&write, &[]) };

        let push_ranges = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT)
            .size(std::mem::size_of::<DrawParameters>() as u32)];
        let layout_info = vk::PipelineLayoutCreateInfo::default()
            .set_layouts(&set_layouts)
            .push_constant_ranges(&push_ranges);
        // SAFETY: as above.
        this.layout = unsafe { raw.create_pipeline_layout(&layout_info, None) }
            .or_vk("vkCreatePipelineLayout")?;
        device.set_name(this.layout, "baseline pipeline layout");
        this.pipeline = create_pipeline(device, this.layout)?;
        Ok(this)
    }
}

fn create_pipeline(device: &Arc<Device>, layout: vk::PipelineLayout) -> VkResult<vk::Pipeline> {
    let vertex = ShaderModule::from_glsl(
        device,
        shaders::BASELINE_VERT.name,
        shaders::BASELINE_VERT.source,
        shaders::BASELINE_VERT.stage,
        shaders::INCLUDES,
    )?;
    let fragment = ShaderModule::from_glsl(
        device,
        shaders::BASELINE_FRAG.name,
        shaders::BASELINE_FRAG.source,
        shaders::BASELINE_FRAG.stage,
        shaders::INCLUDES,
    )?;
    let stages = [
        vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::VERTEX)
            .module(vertex.raw())
            .name(c"main"),
        vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::FRAGMENT)
            .module(fragment.raw())
            .name(c"main"),
    ];
    let vertex_bindings = [vk::VertexInputBindingDescription::default()
        .binding(0)
        .stride(std::mem::size_of::<Vertex>() as u32)
        .input_rate(vk::VertexInputRate::VERTEX)];
    let vertex_attributes = [
        vk::VertexInputAttributeDescription::default()
            .location(0)
            .binding(0)
            .format(vk::Format::R32G32B32_SFLOAT)
            .offset(0),
        vk::VertexInputAttributeDescription::default()
            .location(1)
            .binding(0)
            .format(vk::Format::R32G32B32_SFLOAT)
            .offset(12),
    ];
    let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
        .vertex_binding_descriptions(&vertex_bindings)
        .vertex_attribute_descriptions(&vertex_attributes);
    let input_assembly = vk::PipelineInputAssemblyStateCreateInfo::default()
        .topology(vk::PrimitiveTopology::TRIANGLE_LIST);
    let viewport = vk::PipelineViewportStateCreateInfo::default()
        .viewport_count(1)
        .scissor_count(1);
    let rasterization = vk::PipelineRasterizationStateCreateInfo::default()
        .polygon_mode(vk::PolygonMode::FILL)
        .cull_mode(vk::CullModeFlags::NONE)
        .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
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
    let color_formats = [COLOR_FORMAT];
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
        .layout(layout)
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
    device.set_name(pipelines[0], "baseline pipeline");
    Ok(pipelines[0])
}

impl Drop for BaselinePipeline {
    fn drop(&mut self) {
        let raw = self.device.raw();
        // SAFETY: the renderer waits for its last frame before dropping the pipeline; null
        // handles (from a failed constructor) are ignored by Vulkan.
        unsafe {
            raw.destroy_pipeline(self.pipeline, None);
            raw.destroy_pipeline_layout(self.layout, None);
            raw.destroy_descriptor_pool(self.descriptor_pool, None);
            raw.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}
