//! Pipelines of a technique combination: the vertex shader is assembled from the vertex and
//! parameter paths' snippets (the seeds' effect system: each path generates its own layouts and
//! accessors), compiled once per (vertex path, parameter path) and validated like every shader;
//! the pipeline layout joins the host's frame set with the paths' sets.

use std::collections::HashMap;
use std::sync::Arc;

use crate::error::RenderResult;
use crate::vk::raw as vk;
use cadr_plugin_abi as abi;

use crate::render::PICK_FORMAT;
use crate::shaders;
use crate::vk::{
    DescriptorSetLayout, Device, GraphicsPipelineDesc, Pipeline, PipelineLayout, ShaderModule,
    ShaderStage, VertexLayout, COLOR_FORMAT,
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

/// The passes a set of pipelines draws: the shaded frame in a shade mode, or the pick pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PassSet {
    /// Shaded triangles (and edges in [`ShadeMode::Edges`]) into the colour target.
    Shaded(ShadeMode),
    /// Triangles of pickable instances, their ids into the pick target.
    Pick,
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

/// SPIR-V of the fragment shaders: shaded triangles, edge lines and instance ids.
#[derive(Clone)]
struct FragmentShaders {
    solid: Arc<Vec<u32>>,
    edges: Arc<Vec<u32>>,
    pick: Arc<Vec<u32>>,
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
    ) -> RenderResult<Arc<Vec<u32>>> {
        if let Some(words) = self.vertex.get(&key) {
            return Ok(Arc::clone(words));
        }
        let name = format!("technique.vert [{} + {}]", key.0, key.1);
        let words = Arc::new(shaders::compile_glsl(
            &name,
            &source(),
            ShaderStage::Vertex,
            shaders::INCLUDES,
        )?);
        self.vertex.insert(key, Arc::clone(&words));
        Ok(words)
    }

    fn fragments(&mut self) -> RenderResult<FragmentShaders> {
        if let Some(shaders) = &self.fragments {
            return Ok(shaders.clone());
        }
        let compile = |shader: &shaders::ShaderSource| {
            shaders::compile_glsl(shader.name, shader.source, shader.stage, shaders::INCLUDES)
                .map(Arc::new)
        };
        let shaders = FragmentShaders {
            solid: compile(&shaders::SHADED_FRAG)?,
            edges: compile(&shaders::EDGES_FRAG)?,
            pick: compile(&shaders::PICK_FRAG)?,
        };
        self.fragments = Some(shaders.clone());
        Ok(shaders)
    }
}

/// The pipelines and layout of one combination and shade mode; destroyed together.
pub struct TechniquePipelines {
    device: Arc<Device>,
    // Dropped in this order: the pipelines, then the layouts they were made with.
    pipelines: Vec<Pipeline>,
    /// The shared layout.
    pub layout: PipelineLayout,
    /// Stands in for the sets a path does not use below one it does.
    _empty_set_layout: DescriptorSetLayout,
    /// The passes, in order.
    pub passes: Vec<abi::CadrPass>,
    /// The colour attachment's format (the pick pass draws ids).
    pub color_format: vk::Format,
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
    /// The passes to build.
    pub passes: PassSet,
    /// The kind the pick pass is given: [`abi::CADR_PASS_PICK`] when every active technique
    /// knows it (ABI 1.2 or later), else [`abi::CADR_PASS_TRIANGLES`].
    pub pick_kind: abi::CadrPassKind,
}

impl TechniquePipelines {
    /// Creates the layout and the passes' pipelines.
    pub fn new(
        device: &Arc<Device>,
        cache: &mut ShaderCache,
        inputs: &PipelineInputs<'_>,
    ) -> RenderResult<Self> {
        let empty_set_layout = DescriptorSetLayout::new(device, "empty set layout", &[])?;
        let used = inputs
            .path_set_layouts
            .iter()
            .rposition(|l| *l != vk::DescriptorSetLayout::null())
            .map_or(1, |i| i + 2);
        let mut sets = vec![inputs.frame_set_layout];
        sets.extend(inputs.path_set_layouts.iter().map(|&l| {
            if l == vk::DescriptorSetLayout::null() {
                empty_set_layout.raw()
            } else {
                l
            }
        }));
        sets.truncate(used);
        let layout = PipelineLayout::new(
            device,
            "technique layout",
            &sets,
            128,
            vk::ShaderStageFlags::VERTEX,
        )?;
        let mut this = Self {
            device: Arc::clone(device),
            pipelines: Vec::new(),
            layout,
            _empty_set_layout: empty_set_layout,
            passes: Vec::new(),
            color_format: match inputs.passes {
                PassSet::Pick => PICK_FORMAT,
                PassSet::Shaded(_) => COLOR_FORMAT,
            },
        };
        let fragments = cache.fragments()?;
        let triangles = vk::PrimitiveTopology::TRIANGLE_LIST;
        match inputs.passes {
            PassSet::Shaded(ShadeMode::Solid) => {
                let pipeline = this.pipeline(inputs, &fragments.solid, triangles, false)?;
                this.add(pipeline, abi::CADR_PASS_TRIANGLES);
            }
            PassSet::Shaded(ShadeMode::Edges) => {
                let pipeline = this.pipeline(inputs, &fragments.solid, triangles, true)?;
                this.add(pipeline, abi::CADR_PASS_TRIANGLES);
                let lines = vk::PrimitiveTopology::LINE_LIST;
                let pipeline = this.pipeline(inputs, &fragments.edges, lines, false)?;
                this.add(pipeline, abi::CADR_PASS_EDGES);
            }
            PassSet::Pick => {
                let pipeline = this.pipeline(inputs, &fragments.pick, triangles, false)?;
                this.add(pipeline, inputs.pick_kind);
            }
        }
        Ok(this)
    }

    fn add(&mut self, pipeline: Pipeline, kind: abi::CadrPassKind) {
        use crate::vk::raw::Handle;
        self.passes.push(abi::CadrPass {
            pipeline: pipeline.raw().as_raw(),
            kind,
        });
        self.pipelines.push(pipeline);
    }

    fn pipeline(
        &self,
        inputs: &PipelineInputs<'_>,
        fragment: &[u32],
        topology: vk::PrimitiveTopology,
        depth_bias: bool,
    ) -> RenderResult<Pipeline> {
        let vertex = ShaderModule::from_spirv(
            &self.device,
            "technique.vert",
            inputs.vertex_spirv,
            ShaderStage::Vertex,
        )?;
        let fragment = ShaderModule::from_spirv(
            &self.device,
            "technique fragment",
            fragment,
            ShaderStage::Fragment,
        )?;
        let input = inputs.vertex_input;
        let count = (input.attribute_count as usize).min(input.formats.len());
        let attributes: Vec<(vk::Format, u32)> = (0..count)
            .map(|i| (vk::Format::from_raw(input.formats[i]), input.offsets[i]))
            .collect();
        Ok(Pipeline::graphics(
            &self.device,
            &GraphicsPipelineDesc {
                layout: &self.layout,
                vertex: &vertex,
                fragment: &fragment,
                vertex_layout: (input.stride != 0).then_some(VertexLayout {
                    stride: input.stride,
                    attributes: &attributes,
                }),
                topology,
                depth_bias,
                color_format: self.color_format,
                name: "technique pipeline",
            },
        )?)
    }
}
