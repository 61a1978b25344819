//! Pipelines of a technique combination: the vertex shader is assembled from the vertex and
//! parameter paths' snippets (the seeds' effect system: each path generates its own layouts and
//! accessors), compiled once per (vertex path, parameter path) and validated like every shader;
//! the pipeline layout joins the host's frame set with the paths' sets.

use std::collections::HashMap;
use std::sync::Arc;

use ash::vk;
use cadr_plugin_abi as abi;

use crate::shaders;
use crate::vk::{
    compile_glsl, Device, ShaderStage, VkError, VkResult, VkResultExt, COLOR_FORMAT, DEPTH_FORMAT,
};

/// The shade modes of the seeds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum ShadeMode {
    /// Shaded triangles.
    #[default]
    Solid,
    /// Shaded triangles (pushed back by a depth bias) with edge lines over them.
    Edges,
}

impl ShadeMode {
    /// Both modes.
    pub const ALL: [ShadeMode; 2] = [ShadeMode::Solid, ShadeMode::Edges];

    /// Its name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ShadeMode::Solid => "solid",
            ShadeMode::Edges => "edges",
        }
    }

    /// Parses a command-line name.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// Assembles the technique vertex shader from the two snippets. Lines of a snippet starting
/// with `#extension` are moved to the top, where GLSL wants them.
pub fn assemble_vertex_shader(vertex_snippet: &str, parameter_snippet: &str) -> String {
    let mut extensions = Vec::new();
    let mut strip = |snippet: &str| -> String {
        snippet
            .lines()
            .filter(|line| {
                let is_extension = line.trim_start().starts_with("#extension");
                if is_extension && !extensions.contains(&line.trim().to_owned()) {
                    extensions.push(line.trim().to_owned());
                }
                !is_extension
            })
            .collect::<Vec<_>>()
            .join("\n")
    };
    let vertex = strip(vertex_snippet);
    let parameters = strip(parameter_snippet);
    let body = shaders::TECHNIQUE_VERT
        .source
        .replace("//@VERTEX_PATH@", &vertex)
        .replace("//@PARAMETER_PATH@", &parameters);
    format!("#version 460\n{}\n{body}", extensions.join("\n"))
}

/// SPIR-V of the fragment shaders: shaded triangles and edge lines.
#[derive(Clone)]
struct FragmentShaders {
    solid: Arc<Vec<u32>>,
    edges: Arc<Vec<u32>>,
}

/// SPIR-V of assembled shaders, by (vertex path, parameter path) name.
#[derive(Default)]
pub struct ShaderCache {
    vertex: HashMap<(String, String), Arc<Vec<u32>>>,
    fragments: Option<FragmentShaders>,
}

impl ShaderCache {
    /// The vertex shader of a combination, compiled on first use.
    pub fn vertex(
        &mut self,
        key: (String, String),
        source: impl FnOnce() -> String,
    ) -> VkResult<Arc<Vec<u32>>> {
        if let Some(words) = self.vertex.get(&key) {
            return Ok(Arc::clone(words));
        }
        let name = format!("technique.vert [{} + {}]", key.0, key.1);
        let words = Arc::new(compile_glsl(
            &name,
            &source(),
            ShaderStage::Vertex,
            shaders::INCLUDES,
        )?);
        self.vertex.insert(key, Arc::clone(&words));
        Ok(words)
    }

    fn fragments(&mut self) -> VkResult<FragmentShaders> {
        if let Some(shaders) = &self.fragments {
            return Ok(shaders.clone());
        }
        let compile = |shader: &shaders::ShaderSource| {
            compile_glsl(shader.name, shader.source, shader.stage, shaders::INCLUDES).map(Arc::new)
        };
        let shaders = FragmentShaders {
            solid: compile(&shaders::RESIDENT_FRAG)?,
            edges: compile(&shaders::EDGES_FRAG)?,
        };
        self.fragments = Some(shaders.clone());
        Ok(shaders)
    }
}

/// The pipelines and layout of one combination and shade mode; destroyed together.
pub struct TechniquePipelines {
    device: Arc<Device>,
    /// The shared layout.
    pub layout: vk::PipelineLayout,
    empty_set_layout: vk::DescriptorSetLayout,
    /// The passes, in order.
    pub passes: Vec<abi::CadrPass>,
    pipelines: Vec<vk::Pipeline>,
}

impl Drop for TechniquePipelines {
    fn drop(&mut self) {
        let raw = self.device.raw();
        // SAFETY: dropped after the GPU finished the frames using them (the owner waits).
        unsafe {
            for &pipeline in &self.pipelines {
                raw.destroy_pipeline(pipeline, None);
            }
            raw.destroy_pipeline_layout(self.layout, None);
            raw.destroy_descriptor_set_layout(self.empty_set_layout, None);
        }
    }
}

/// What a combination's pipelines are built from.
pub struct PipelineInputs<'a> {
    /// The host's set 0 layout.
    pub frame_set_layout: vk::DescriptorSetLayout,
    /// Set layouts 1 and 2 (parameter path) and 3 (vertex path); null for none.
    pub path_set_layouts: [vk::DescriptorSetLayout; 3],
    /// The vertex path's input.
    pub vertex_input: abi::CadrVertexInput,
    /// Assembled vertex shader.
    pub vertex_spirv: &'a [u32],
    /// Shade mode.
    pub mode: ShadeMode,
}

impl TechniquePipelines {
    /// Creates the layout and the passes' pipelines.
    pub fn new(
        device: &Arc<Device>,
        cache: &mut ShaderCache,
        inputs: &PipelineInputs<'_>,
    ) -> VkResult<Self> {
        let raw = device.raw();
        let info = vk::DescriptorSetLayoutCreateInfo::default();
        // SAFETY: the info lives for the call.
        let empty_set_layout = unsafe { raw.create_descriptor_set_layout(&info, None) }
            .or_vk("vkCreateDescriptorSetLayout")?;
        let mut this = Self {
            device: Arc::clone(device),
            layout: vk::PipelineLayout::null(),
            empty_set_layout,
            passes: Vec::new(),
            pipelines: Vec::new(),
        };
        let used = inputs
            .path_set_layouts
            .iter()
            .rposition(|l| *l != vk::DescriptorSetLayout::null())
            .map_or(1, |i| i + 2);
        let mut sets = vec![inputs.frame_set_layout];
        sets.extend(inputs.path_set_layouts.iter().map(|&l| {
            if l == vk::DescriptorSetLayout::null() {
                empty_set_layout
            } else {
                l
            }
        }));
        sets.truncate(used);
        let push = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::VERTEX)
            .size(128)];
        let layout_info = vk::PipelineLayoutCreateInfo::default()
            .set_layouts(&sets)
            .push_constant_ranges(&push);
        // SAFETY: the info lives for the call.
        this.layout = unsafe { raw.create_pipeline_layout(&layout_info, None) }
            .or_vk("vkCreatePipelineLayout")?;
        let fragments = cache.fragments()?;
        match inputs.mode {
            ShadeMode::Solid => {
                let pipeline = this.pipeline(
                    inputs,
                    &fragments.solid,
                    vk::PrimitiveTopology::TRIANGLE_LIST,
                    false,
                )?;
                this.add(pipeline, abi::CADR_PASS_TRIANGLES);
            }
            ShadeMode::Edges => {
                let triangles = this.pipeline(
                    inputs,
                    &fragments.solid,
                    vk::PrimitiveTopology::TRIANGLE_LIST,
                    true,
                )?;
                this.add(triangles, abi::CADR_PASS_TRIANGLES);
                let lines = this.pipeline(
                    inputs,
                    &fragments.edges,
                    vk::PrimitiveTopology::LINE_LIST,
                    false,
                )?;
                this.add(lines, abi::CADR_PASS_EDGES);
            }
        }
        Ok(this)
    }

    fn add(&mut self, pipeline: vk::Pipeline, kind: abi::CadrPassKind) {
        use ash::vk::Handle;
        self.pipelines.push(pipeline);
        self.passes.push(abi::CadrPass {
            pipeline: pipeline.as_raw(),
            kind,
        });
    }

    fn pipeline(
        &self,
        inputs: &PipelineInputs<'_>,
        fragment: &[u32],
        topology: vk::PrimitiveTopology,
        depth_bias: bool,
    ) -> VkResult<vk::Pipeline> {
        let raw = self.device.raw();
        let module = |words: &[u32]| {
            let info = vk::ShaderModuleCreateInfo::default().code(words);
            // SAFETY: SPIR-V from shaderc; the info lives for the call.
            unsafe { raw.create_shader_module(&info, None) }.or_vk("vkCreateShaderModule")
        };
        let vertex_module = module(inputs.vertex_spirv)?;
        let fragment_module = match module(fragment) {
            Ok(m) => m,
            Err(e) => {
                // SAFETY: created above, unused.
                unsafe { raw.destroy_shader_module(vertex_module, None) };
                return Err(e);
            }
        };
        let stages = [
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::VERTEX)
                .module(vertex_module)
                .name(c"main"),
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::FRAGMENT)
                .module(fragment_module)
                .name(c"main"),
        ];
        let input = inputs.vertex_input;
        let bindings = [vk::VertexInputBindingDescription::default()
            .binding(0)
            .stride(input.stride)
            .input_rate(vk::VertexInputRate::VERTEX)];
        let attribute_count = (input.attribute_count as usize).min(4);
        let attributes: Vec<vk::VertexInputAttributeDescription> = (0..attribute_count)
            .map(|i| {
                vk::VertexInputAttributeDescription::default()
                    .location(i as u32)
                    .binding(0)
                    .format(vk::Format::from_raw(input.formats[i]))
                    .offset(input.offsets[i])
            })
            .collect();
        let vertex_input = if input.stride == 0 {
            vk::PipelineVertexInputStateCreateInfo::default()
        } else {
            vk::PipelineVertexInputStateCreateInfo::default()
                .vertex_binding_descriptions(&bindings)
                .vertex_attribute_descriptions(&attributes)
        };
        let input_assembly = vk::PipelineInputAssemblyStateCreateInfo::default().topology(topology);
        let viewport = vk::PipelineViewportStateCreateInfo::default()
            .viewport_count(1)
            .scissor_count(1);
        let rasterization = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(vk::CullModeFlags::NONE)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .depth_bias_enable(depth_bias)
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
        let blend =
            vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend_attachments);
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
            .layout(self.layout)
            .push_next(&mut rendering)];
        // SAFETY: every struct the info points to lives until the call returns.
        let created =
            unsafe { raw.create_graphics_pipelines(vk::PipelineCache::null(), &info, None) };
        // SAFETY: pipelines keep their own copy of the code.
        unsafe {
            raw.destroy_shader_module(vertex_module, None);
            raw.destroy_shader_module(fragment_module, None);
        }
        let pipelines = created
            .map_err(|(_, result)| result)
            .or_vk("vkCreateGraphicsPipelines")?;
        pipelines
            .first()
            .copied()
            .ok_or_else(|| VkError::InvalidUse("no pipeline created".into()))
    }
}
