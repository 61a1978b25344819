//! Pipelines of a technique combination: the vertex shader is assembled from the vertex and
//! parameter paths' snippets (the seeds' effect system: each path generates its own layouts and
//! accessors), compiled once per (vertex path, parameter path) and validated like every shader;
//! the pipeline layout joins the host's frame set with the paths' sets.

use std::collections::HashMap;
use std::sync::Arc;

use crate::error::RenderResult;
use crate::vk::raw as vk;
use cadr_plugin_abi as abi;

use crate::render::{TransparencyMethod, PICK_FORMAT};
use crate::shaders;
use crate::vk::{
    Blend, Capabilities, ColorTarget, DepthUse, DescriptorSetLayout, Device, GraphicsPipelineDesc,
    Pipeline, PipelineLayout, ShaderModule, ShaderStage, VertexLayout, COLOR_FORMAT,
};

/// The display modes: how surfaces and edges are drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum ShadeMode {
    /// Shaded triangles.
    #[default]
    Solid,
    /// Shaded triangles (pushed back by a depth bias) with edge lines over them.
    Edges,
    /// Edge lines only, those hidden behind opaque surfaces removed: the opaque surfaces fill
    /// the depth buffer (pushed back by a depth bias) but not the picture; translucent ones
    /// hide no lines. Section caps are filled, over the lines behind them.
    HiddenLine,
    /// Every triangle's edges, hidden ones included (no surface is filled).
    Wireframe,
    /// Every part translucent with its edges, except highlighted parts, which stay opaque: what
    /// is inside an assembly shows through its housing.
    XRay,
}

impl ShadeMode {
    /// Every mode.
    pub const ALL: [ShadeMode; 5] = [
        ShadeMode::Solid,
        ShadeMode::Edges,
        ShadeMode::HiddenLine,
        ShadeMode::Wireframe,
        ShadeMode::XRay,
    ];

    /// Its name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ShadeMode::Solid => "solid",
            ShadeMode::Edges => "edges",
            ShadeMode::HiddenLine => "hidden-line",
            ShadeMode::Wireframe => "wireframe",
            ShadeMode::XRay => "xray",
        }
    }

    /// Whether translucent surfaces are drawn as such in this mode (in the line modes no
    /// surface is drawn: in hidden-line the opaque ones hide lines, the translucent ones do
    /// not). X-ray always draws some.
    pub fn shows_translucency(self) -> bool {
        matches!(self, ShadeMode::Solid | ShadeMode::Edges | ShadeMode::XRay)
    }

    /// Whether this mode draws feature edges, which silhouette edges join when they are on
    /// (`Renderer::set_silhouettes`): edges, hidden-line and X-ray. Wireframe draws every
    /// triangle's edges, which need none.
    pub fn draws_silhouettes(self) -> bool {
        matches!(
            self,
            ShadeMode::Edges | ShadeMode::HiddenLine | ShadeMode::XRay
        )
    }

    /// Parses a command-line name.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// The passes a set of pipelines draws: the shaded frame in a shade mode, or the pick pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PassSet {
    /// Shaded triangles (and edges in the edge modes) into the colour target; with
    /// `translucent`, opaque surfaces first, then the translucent ones with the transparency
    /// method (its targets join the rendering) and its merge after the rendering.
    Shaded {
        /// The display mode.
        mode: ShadeMode,
        /// Whether the frame draws translucent surfaces.
        translucent: bool,
        /// Samples per pixel (1, or the MSAA level the renderer draws with).
        samples: u32,
        /// In the hidden-line mode, whether hidden edges are drawn too, dashed and lighter
        /// (always false in the other modes).
        dashed_hidden: bool,
        /// In the hidden-line mode, whether the scene has translucent surfaces, which then
        /// hide no lines: what is behind glass shows through it (always false in the other
        /// modes, which draw translucency as such).
        lines_through_translucent: bool,
        /// In the edges and hidden-line modes, whether section caps can show (caps are on and
        /// the eye is on the cut side of a plane): the lines then write no depth, and after
        /// them a caps pass (`shaders/caps.frag`, depth EQUAL on the surfaces' depth) paints
        /// the visible caps again over the lines of the far faces they are painted on (always
        /// false in the other modes).
        caps_over_lines: bool,
        /// With `dashed_hidden`, whether the silhouettes of hidden curved surfaces are dashed
        /// too: a pass over the triangles whose geometry shader
        /// (`shaders/silhouette_lines.geom`) turns each into the segment where its surface
        /// turns away from the eye, drawn only behind the surfaces (silhouettes on, and the
        /// device has geometry shaders; always false otherwise).
        hidden_silhouettes: bool,
    },
    /// Triangles of pickable instances, their ids into the pick target.
    Pick {
        /// Whether translucent parts let the click through to what is behind them.
        through_translucent: bool,
    },
}

impl PassSet {
    /// Samples per pixel of the pass's attachments (the pick pass is always exact: one).
    pub fn samples(self) -> u32 {
        match self {
            PassSet::Shaded { samples, .. } => samples,
            PassSet::Pick { .. } => 1,
        }
    }
}

/// Which surfaces a technique pipeline draws (the vertex shader's `CADR_DRAW_ROLE`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum DrawRole {
    /// Every surface (frames without translucency, lines, picking).
    All = 0,
    /// Opaque surfaces only.
    Opaque = 1,
    /// Translucent surfaces only.
    Translucent = 2,
}

/// What a pass lets through: its vertex shader's draw role, whether it is the section caps'
/// pass (`CADR_CAPS_PASS`, closed parts a plane cuts only), and whether it is the hidden
/// silhouettes' pass (whose geometry shader yields nothing for a part that is not curved).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct PassScope {
    role: DrawRole,
    caps: bool,
    silhouettes: bool,
}

impl PassScope {
    /// The instances the pass needs, as the plugin ABI's filter and exclusion on their flags:
    /// the others its vertex shader clips away whole, so submissions and GPU cullers may skip
    /// them. `xray`: the X-ray mode, where every part not highlighted is translucent.
    /// `textures`: whether textures are drawn; without them a part translucent only by its
    /// texture ([`abi::CADR_INSTANCE_TRANSLUCENT_BY_TEXTURE`]) is opaque.
    fn filter(self, xray: bool, textures: bool) -> (abi::CadrPassFilter, abi::CadrPassExclusion) {
        const HIGHLIGHTED: u32 = abi::CADR_INSTANCE_HIGHLIGHTED;
        const TRANSLUCENT: u32 = abi::CADR_INSTANCE_TRANSLUCENT;
        const BY_TEXTURE: u32 = abi::CADR_INSTANCE_TRANSLUCENT_BY_TEXTURE;
        const ANY: (u32, u32) = (0, 0);
        // Translucent by material: with textures, the flag; without, the flag but not by texture.
        let (material_mask, material_translucent) = if textures {
            (TRANSLUCENT, TRANSLUCENT)
        } else {
            (TRANSLUCENT | BY_TEXTURE, TRANSLUCENT)
        };
        let ((mut mask, mut value), exclusion) = match (self.role, xray) {
            (DrawRole::All, _) => (ANY, ANY),
            // Opaque: not translucent by material (without textures, an exclusion says it).
            (DrawRole::Opaque, false) if textures => ((TRANSLUCENT, 0), ANY),
            (DrawRole::Opaque, false) => (ANY, (material_mask, material_translucent)),
            // Opaque in X-ray: highlighted, and not translucent by material.
            (DrawRole::Opaque, true) if textures => ((HIGHLIGHTED | TRANSLUCENT, HIGHLIGHTED), ANY),
            (DrawRole::Opaque, true) => (
                (HIGHLIGHTED, HIGHLIGHTED),
                (material_mask, material_translucent),
            ),
            (DrawRole::Translucent, false) => ((material_mask, material_translucent), ANY),
            // Translucent in X-ray: not highlighted, or translucent by material: every part
            // but the highlighted opaque ones. Without textures one exclusion cannot also
            // name those translucent by texture only: they are drawn, and clipped.
            (DrawRole::Translucent, true) => (ANY, (HIGHLIGHTED | TRANSLUCENT, HIGHLIGHTED)),
        };
        if self.caps {
            mask |= abi::CADR_INSTANCE_CLOSED;
            value |= abi::CADR_INSTANCE_CLOSED;
        }
        if self.silhouettes {
            mask |= abi::CADR_INSTANCE_CURVED;
            value |= abi::CADR_INSTANCE_CURVED;
        }
        let filter = abi::CadrPassFilter {
            mask,
            value,
            // The caps pass: only parts a plane cuts can show a cap.
            section_cut: u32::from(self.caps),
        };
        let (mask, value) = exclusion;
        (filter, abi::CadrPassExclusion { mask, value })
    }
}

/// The instances each pass of a frame needs, one filter and one exclusion per pass, in the
/// order of `TechniquePipelines::passes` (see `PassScope::filter`).
#[derive(Clone, Debug, Default)]
pub struct PassFilters {
    /// What each pass keeps.
    pub filters: Vec<abi::CadrPassFilter>,
    /// Of those, what each pass does not need.
    pub exclusions: Vec<abi::CadrPassExclusion>,
}

/// The SPIR-V of a transparency method: its translucent fragment shader, and the merge's
/// vertex and fragment shaders.
#[derive(Clone)]
struct MethodShaders {
    translucent: Arc<Vec<u32>>,
    merge_vertex: Arc<Vec<u32>>,
    merge: Arc<Vec<u32>>,
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

/// The shaders of the passes after the shared vertex shader: fragment shaders, and the
/// geometry shader of the hidden silhouettes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum PassShader {
    /// Shaded triangles.
    Solid,
    /// Edge lines.
    Edges,
    /// Hidden edge lines, dashed.
    HiddenEdges,
    /// The silhouette lines of curved surfaces (a geometry shader over their triangles).
    SilhouetteLines,
    /// Section caps painted again over the lines.
    Caps,
    /// Instance ids and depths for picking.
    Pick,
}

impl PassShader {
    fn source(self) -> &'static shaders::ShaderSource {
        match self {
            Self::Solid => &shaders::SHADED_FRAG,
            Self::Edges => &shaders::EDGES_FRAG,
            Self::HiddenEdges => &shaders::HIDDEN_EDGES_FRAG,
            Self::SilhouetteLines => &shaders::SILHOUETTE_LINES_GEOM,
            Self::Caps => &shaders::CAPS_FRAG,
            Self::Pick => &shaders::PICK_FRAG,
        }
    }

    /// Those `passes` draw with.
    fn needed_by(passes: PassSet) -> Vec<PassShader> {
        let mut shaders = Self::needed_without_silhouette_lines(passes).to_vec();
        if let PassSet::Shaded {
            hidden_silhouettes: true,
            ..
        } = passes
        {
            shaders.push(Self::SilhouetteLines);
        }
        shaders
    }

    /// Those `passes` draw with, leaving out the hidden silhouettes' geometry shader.
    fn needed_without_silhouette_lines(passes: PassSet) -> &'static [PassShader] {
        match passes {
            PassSet::Shaded {
                mode: ShadeMode::HiddenLine,
                dashed_hidden: true,
                caps_over_lines: true,
                ..
            } => &[Self::Solid, Self::HiddenEdges, Self::Edges, Self::Caps],
            PassSet::Shaded {
                mode: ShadeMode::HiddenLine,
                dashed_hidden: true,
                ..
            } => &[Self::Solid, Self::HiddenEdges, Self::Edges],
            PassSet::Shaded {
                caps_over_lines: true,
                ..
            } => &[Self::Solid, Self::Edges, Self::Caps],
            PassSet::Shaded { mode, .. } => match mode {
                ShadeMode::Solid => &[Self::Solid],
                ShadeMode::Edges | ShadeMode::HiddenLine | ShadeMode::XRay => {
                    &[Self::Solid, Self::Edges]
                }
                ShadeMode::Wireframe => &[Self::Edges],
            },
            PassSet::Pick { .. } => &[Self::Pick],
        }
    }
}

/// The `#define` (and `#extension`) lines every fragment shader is compiled with on a device
/// with `capabilities`.
pub fn fragment_defines(capabilities: Capabilities) -> String {
    let mut defines = String::new();
    if capabilities.bindless_textures > 0 {
        defines.push_str(
            "#extension GL_EXT_nonuniform_qualifier : require\n#define CADR_BINDLESS_TEXTURES\n",
        );
    }
    if capabilities.fragment_stores_and_atomics {
        defines.push_str("#define CADR_PIXEL_KEYS_WRITTEN\n");
    }
    defines
}

/// SPIR-V of assembled vertex shaders, by (vertex path, parameter path) name, and of the
/// passes' other shaders, each compiled when a pass first needs it.
#[derive(Default)]
pub struct ShaderCache {
    vertex: HashMap<(String, String), Arc<Vec<u32>>>,
    pass_shaders: HashMap<PassShader, Arc<Vec<u32>>>,
    methods: HashMap<String, MethodShaders>,
    /// `#define` lines every fragment (and geometry) shader is compiled with: what the device
    /// allows.
    fragment_defines: String,
}

/// The SPIR-V one pass set is built from.
pub struct PassShaders {
    /// The assembled vertex shader.
    pub vertex: Arc<Vec<u32>>,
    pass_shaders: Vec<(PassShader, Arc<Vec<u32>>)>,
    /// The transparency method's, for a frame with translucent surfaces.
    method: Option<MethodShaders>,
}

impl PassShaders {
    fn shader(&self, shader: PassShader) -> RenderResult<&[u32]> {
        self.pass_shaders
            .iter()
            .find(|(kind, _)| *kind == shader)
            .map(|(_, words)| words.as_slice())
            .ok_or_else(|| {
                crate::error::RenderError::InvalidUse(format!(
                    "the {shader:?} shader was not prepared"
                ))
            })
    }
}

impl ShaderCache {
    /// An empty cache for a device with `capabilities`: with `fragmentStoresAndAtomics`, the
    /// surface shaders record the per-pixel keys, the highlight outline style's and the
    /// silhouettes' nearest surfaces (`CADR_PIXEL_KEYS_WRITTEN`, `shaders/pixel_keys.glsl`);
    /// with bindless textures, they index the table of textures
    /// (`CADR_BINDLESS_TEXTURES`, `shaders/texturing.glsl`).
    pub fn new(capabilities: Capabilities) -> Self {
        Self {
            fragment_defines: fragment_defines(capabilities),
            ..Self::default()
        }
    }

    /// The vertex shader of the (vertex path, parameter path) `key` (assembled by `source`)
    /// and the other shaders `passes` draw with. Those not compiled before are compiled
    /// now, together, on a thread each (a combination is ready in the time of its slowest
    /// shader); passes not drawn compile nothing.
    pub fn prepare(
        &mut self,
        key: (String, String),
        source: impl FnOnce() -> String,
        passes: PassSet,
        method: Option<&TransparencyMethod>,
    ) -> RenderResult<PassShaders> {
        let wanted = PassShader::needed_by(passes);
        let missing: Vec<PassShader> = wanted
            .iter()
            .copied()
            .filter(|f| !self.pass_shaders.contains_key(f))
            .collect();
        let vertex_name = format!("technique.vert [{} + {}]", key.0, key.1);
        let vertex_source = (!self.vertex.contains_key(&key)).then(source);
        let pass_sources: Vec<String> = missing
            .iter()
            .map(|f| shaders::with_defines(f.source().source, &self.fragment_defines))
            .collect();
        let mut requests: Vec<shaders::CompileRequest<'_>> = missing
            .iter()
            .zip(&pass_sources)
            .map(|(f, source)| {
                let shader = f.source();
                shaders::CompileRequest {
                    name: shader.name,
                    source,
                    stage: shader.stage,
                    includes: shaders::INCLUDES,
                }
            })
            .collect();
        if let Some(source) = &vertex_source {
            requests.push(shaders::CompileRequest {
                name: &vertex_name,
                source,
                stage: ShaderStage::Vertex,
                includes: shaders::INCLUDES,
            });
        }
        let mut compiled = shaders::compile_glsl_all(&requests).into_iter();
        for shader in &missing {
            if let Some(words) = compiled.next() {
                self.pass_shaders.insert(*shader, Arc::new(words?));
            }
        }
        if vertex_source.is_some() {
            if let Some(words) = compiled.next() {
                self.vertex.insert(key.clone(), Arc::new(words?));
            }
        }
        let not_compiled =
            || crate::error::RenderError::InvalidUse("a technique shader was not compiled".into());
        let method = match (passes, method) {
            (
                PassSet::Shaded {
                    translucent: true, ..
                },
                Some(method),
            ) => Some(self.method_shaders(method)?),
            _ => None,
        };
        Ok(PassShaders {
            method,
            vertex: Arc::clone(self.vertex.get(&key).ok_or_else(not_compiled)?),
            pass_shaders: wanted
                .iter()
                .map(|f| {
                    Ok((
                        *f,
                        Arc::clone(self.pass_shaders.get(f).ok_or_else(not_compiled)?),
                    ))
                })
                .collect::<RenderResult<_>>()?,
        })
    }
}

impl ShaderCache {
    /// The shaders of `method`, compiled together the first time.
    fn method_shaders(&mut self, method: &TransparencyMethod) -> RenderResult<MethodShaders> {
        if let Some(shaders) = self.methods.get(&method.name) {
            return Ok(shaders.clone());
        }
        let defines = &self.fragment_defines;
        let translucent = method.assemble(
            &shaders::TRANSLUCENT_FRAG,
            &method.fragment_snippet,
            defines,
        );
        let merge = method.assemble(&shaders::MERGE_FRAG, &method.merge_snippet, defines);
        let translucent_name = format!("translucent.frag [{}]", method.name);
        let merge_name = format!("merge.frag [{}]", method.name);
        let request = |name, source, stage| shaders::CompileRequest {
            name,
            source,
            stage,
            includes: shaders::INCLUDES,
        };
        let mut compiled = shaders::compile_glsl_all(&[
            request(&translucent_name, &translucent, ShaderStage::Fragment),
            request(
                shaders::MERGE_VERT.name,
                shaders::MERGE_VERT.source,
                ShaderStage::Vertex,
            ),
            request(&merge_name, &merge, ShaderStage::Fragment),
        ])
        .into_iter();
        let mut next = || -> RenderResult<Arc<Vec<u32>>> {
            let words = compiled.next().ok_or_else(|| {
                crate::error::RenderError::InvalidUse(
                    "a transparency shader was not compiled".into(),
                )
            })??;
            Ok(Arc::new(words))
        };
        let shaders = MethodShaders {
            translucent: next()?,
            merge_vertex: next()?,
            merge: next()?,
        };
        self.methods.insert(method.name.clone(), shaders.clone());
        Ok(shaders)
    }
}

/// How a pass rasterizes, beyond its shaders and topology.
#[derive(Clone, Copy, Debug, Default)]
struct Raster {
    /// Translucent surfaces, blended into the method's targets (depth tested, not written).
    translucent: bool,
    /// Pushed back so that edge lines win the depth test.
    depth_bias: bool,
    /// Triangles drawn as their edges.
    triangle_outlines: bool,
    /// Depth only, no colour.
    depth_only: bool,
    /// Drawn only behind the surfaces (depth GREATER, not written): hidden lines.
    behind: bool,
    /// Drawn only on the surface each pixel shows (depth EQUAL, not written): the caps pass,
    /// whose vertex shader (`CADR_CAPS_PASS`) also clips away every part that cannot show a
    /// cap (open, or crossed by no plane).
    on_surfaces: bool,
    /// Depth tested, not written: the lines under the caps pass, which must find the
    /// surfaces' depth where lines were drawn.
    keeps_depth: bool,
    /// Triangles turned into their silhouette segments by the geometry shader
    /// (`shaders/silhouette_lines.geom`): lines, not surfaces.
    silhouette_lines: bool,
}

/// The pipelines and layout of one combination and pass set; destroyed together.
pub struct TechniquePipelines {
    device: Arc<Device>,
    // Dropped in this order: the pipelines, then the layouts they were made with.
    pipelines: Vec<Pipeline>,
    /// The transparency merge, for a pass set with translucent surfaces.
    pub merge: Option<Pipeline>,
    /// The shared layout.
    pub layout: PipelineLayout,
    /// The merge's layout: the frame set, then the method's targets.
    pub merge_layout: Option<PipelineLayout>,
    /// Stands in for the sets a path does not use below one it does.
    _empty_set_layout: DescriptorSetLayout,
    /// What they draw.
    pub pass_set: PassSet,
    /// The passes, in order.
    pub passes: Vec<abi::CadrPass>,
    /// The instances each pass needs, in the same order (see [`PassScope::filter`]): with
    /// textures off (`[0]`) and on (`[1]`). Made with the passes, so a frame only picks one.
    filters: [PassFilters; 2],
    /// The colour attachment's format (the pick pass draws ids).
    pub color_format: vk::Format,
    /// The formats of the colour attachments after the first (the transparency method's
    /// targets, while translucent surfaces are drawn).
    pub extra_color_formats: Vec<vk::Format>,
    /// The transparency method's targets (empty without translucent surfaces).
    targets: Vec<abi::CadrTransparencyTarget>,
}

/// What a combination's pipelines are built from.
pub struct PipelineInputs<'a> {
    /// The host's set 0 layout.
    pub frame_set_layout: vk::DescriptorSetLayout,
    /// The merge's set 1 layout: the transparency targets as sampled images.
    pub merge_set_layout: vk::DescriptorSetLayout,
    /// Set layouts 1 and 2 (parameter path) and 3 (vertex path); null for none.
    pub path_set_layouts: [vk::DescriptorSetLayout; 3],
    /// The vertex path's input.
    pub vertex_input: abi::CadrVertexInput,
    /// The vertex and fragment shaders of the passes.
    pub shaders: &'a PassShaders,
    /// The passes to build.
    pub passes: PassSet,
    /// The kind the pick pass is given: [`abi::CADR_PASS_PICK`] when every active technique
    /// knows it (ABI 1.2 or later), else [`abi::CADR_PASS_TRIANGLES`].
    pub pick_kind: abi::CadrPassKind,
    /// The active transparency method.
    pub method: Option<&'a TransparencyMethod>,
}

impl TechniquePipelines {
    /// Creates the layout and the passes' pipelines.
    pub fn new(device: &Arc<Device>, inputs: &PipelineInputs<'_>) -> RenderResult<Self> {
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
        let translucent_method = match (inputs.passes, inputs.method) {
            (
                PassSet::Shaded {
                    translucent: true, ..
                },
                Some(method),
            ) => Some(method),
            _ => None,
        };
        let mut this = Self {
            device: Arc::clone(device),
            pipelines: Vec::new(),
            merge: None,
            layout,
            merge_layout: None,
            _empty_set_layout: empty_set_layout,
            pass_set: inputs.passes,
            passes: Vec::new(),
            filters: Default::default(),
            color_format: match inputs.passes {
                PassSet::Pick { .. } => PICK_FORMAT,
                PassSet::Shaded { .. } => COLOR_FORMAT,
            },
            extra_color_formats: translucent_method.map_or_else(Vec::new, |m| m.target_formats()),
            targets: translucent_method.map_or_else(Vec::new, |m| m.targets.clone()),
        };
        let fragment = |shader: PassShader| inputs.shaders.shader(shader);
        let triangles = vk::PrimitiveTopology::TRIANGLE_LIST;
        let lines = vk::PrimitiveTopology::LINE_LIST;
        let plain = Raster::default();
        let under_lines = Raster {
            depth_bias: true,
            ..plain
        };
        match inputs.passes {
            PassSet::Shaded {
                mode: ShadeMode::Solid,
                ..
            } => {
                let solid = fragment(PassShader::Solid)?;
                let pipeline = this.pipeline(inputs, solid, triangles, plain)?;
                this.add(pipeline, abi::CADR_PASS_TRIANGLES);
            }
            PassSet::Shaded {
                mode: mode @ (ShadeMode::Edges | ShadeMode::HiddenLine | ShadeMode::XRay),
                ..
            } => {
                let surfaces = Raster {
                    depth_only: mode == ShadeMode::HiddenLine,
                    ..under_lines
                };
                let solid = fragment(PassShader::Solid)?;
                let pipeline = this.pipeline(inputs, solid, triangles, surfaces)?;
                this.add(pipeline, abi::CADR_PASS_TRIANGLES);
                if let PassSet::Shaded {
                    dashed_hidden: true,
                    ..
                } = inputs.passes
                {
                    // Before the visible lines, which win where the two cross.
                    let hidden = Raster {
                        behind: true,
                        ..plain
                    };
                    let dashed = fragment(PassShader::HiddenEdges)?;
                    let pipeline = this.pipeline(inputs, dashed, lines, hidden)?;
                    this.add(pipeline, abi::CADR_PASS_EDGES);
                    if let PassSet::Shaded {
                        hidden_silhouettes: true,
                        ..
                    } = inputs.passes
                    {
                        // The triangles, each turned into its silhouette segment, if any.
                        let silhouettes = Raster {
                            silhouette_lines: true,
                            ..hidden
                        };
                        let pipeline = this.pipeline(inputs, dashed, triangles, silhouettes)?;
                        this.add(pipeline, abi::CADR_PASS_TRIANGLES);
                    }
                }
                let caps_over_lines = matches!(
                    inputs.passes,
                    PassSet::Shaded {
                        caps_over_lines: true,
                        ..
                    }
                );
                let visible_lines = Raster {
                    keeps_depth: caps_over_lines,
                    ..plain
                };
                let edges = fragment(PassShader::Edges)?;
                let pipeline = this.pipeline(inputs, edges, lines, visible_lines)?;
                this.add(pipeline, abi::CADR_PASS_EDGES);
                if caps_over_lines {
                    // The surfaces' own vertex shader, role and depth bias: depth EQUAL finds
                    // the surface each pixel shows.
                    let caps = Raster {
                        on_surfaces: true,
                        ..under_lines
                    };
                    let caps_fragment = fragment(PassShader::Caps)?;
                    let pipeline = this.pipeline(inputs, caps_fragment, triangles, caps)?;
                    this.add(pipeline, abi::CADR_PASS_TRIANGLES);
                }
            }
            PassSet::Shaded {
                mode: ShadeMode::Wireframe,
                ..
            } => {
                let outlines = Raster {
                    triangle_outlines: true,
                    ..plain
                };
                let edges = fragment(PassShader::Edges)?;
                let pipeline = this.pipeline(inputs, edges, triangles, outlines)?;
                this.add(pipeline, abi::CADR_PASS_TRIANGLES);
            }
            PassSet::Pick { .. } => {
                let pick = fragment(PassShader::Pick)?;
                let pipeline = this.pipeline(inputs, pick, triangles, plain)?;
                this.add(pipeline, inputs.pick_kind);
            }
        }
        if let (Some(shaders), Some(_)) = (inputs.shaders.method.as_ref(), translucent_method) {
            let translucent = Raster {
                translucent: true,
                ..plain
            };
            let pipeline = this.pipeline(inputs, &shaders.translucent, triangles, translucent)?;
            this.add(pipeline, abi::CADR_PASS_TRIANGLES);
            this.add_merge(inputs, shaders)?;
        }
        Ok(this)
    }

    fn add(&mut self, (pipeline, scope): (Pipeline, PassScope), kind: abi::CadrPassKind) {
        use crate::vk::raw::Handle;
        self.passes.push(abi::CadrPass {
            pipeline: pipeline.raw().as_raw(),
            kind,
        });
        let xray = matches!(
            self.pass_set,
            PassSet::Shaded {
                mode: ShadeMode::XRay,
                ..
            }
        );
        for (filters, textures) in self.filters.iter_mut().zip([false, true]) {
            let (filter, exclusion) = scope.filter(xray, textures);
            filters.filters.push(filter);
            filters.exclusions.push(exclusion);
        }
        self.pipelines.push(pipeline);
    }

    /// The instances each pass needs (see [`PassScope::filter`]), in the order of
    /// [`TechniquePipelines::passes`].
    pub fn pass_filters(&self, textures: bool) -> &PassFilters {
        &self.filters[usize::from(textures)]
    }

    /// The merge: a full-screen triangle blending the method's result over the picture.
    fn add_merge(
        &mut self,
        inputs: &PipelineInputs<'_>,
        shaders: &MethodShaders,
    ) -> RenderResult<()> {
        let layout = PipelineLayout::new(
            &self.device,
            "transparency merge layout",
            &[inputs.frame_set_layout, inputs.merge_set_layout],
            0,
            vk::ShaderStageFlags::FRAGMENT,
        )?;
        let vertex = ShaderModule::from_spirv(
            &self.device,
            "merge.vert",
            &shaders.merge_vertex,
            ShaderStage::Vertex,
        )?;
        let fragment = ShaderModule::from_spirv(
            &self.device,
            "merge.frag",
            &shaders.merge,
            ShaderStage::Fragment,
        )?;
        self.merge = Some(Pipeline::fullscreen(
            &self.device,
            &layout,
            (&vertex, &fragment),
            Blend::PREMULTIPLIED_OVER,
            "transparency merge",
        )?);
        self.merge_layout = Some(layout);
        Ok(())
    }

    /// The colour attachments of a pipeline drawing `raster`: the picture, then the method's
    /// targets, each written only by the pipelines that draw into it.
    fn colors(&self, raster: Raster) -> Vec<ColorTarget> {
        let picture = if raster.translucent || raster.depth_only {
            ColorTarget::untouched(self.color_format)
        } else {
            ColorTarget::replaced(self.color_format)
        };
        std::iter::once(picture)
            .chain(self.targets.iter().map(|target| {
                if raster.translucent {
                    ColorTarget {
                        format: vk::Format::from_raw(target.format),
                        writes: true,
                        blend: Some(blend_of(&target.blend)),
                    }
                } else {
                    ColorTarget::untouched(vk::Format::from_raw(target.format))
                }
            }))
            .collect()
    }

    fn pipeline(
        &self,
        inputs: &PipelineInputs<'_>,
        fragment: &[u32],
        topology: vk::PrimitiveTopology,
        raster: Raster,
    ) -> RenderResult<(Pipeline, PassScope)> {
        let vertex = ShaderModule::from_spirv(
            &self.device,
            "technique.vert",
            &inputs.shaders.vertex,
            ShaderStage::Vertex,
        )?;
        let fragment = ShaderModule::from_spirv(
            &self.device,
            "technique fragment",
            fragment,
            ShaderStage::Fragment,
        )?;
        let geometry = if raster.silhouette_lines {
            Some(ShaderModule::from_spirv(
                &self.device,
                "silhouette_lines.geom",
                inputs.shaders.shader(PassShader::SilhouetteLines)?,
                ShaderStage::Geometry,
            )?)
        } else {
            None
        };
        let input = inputs.vertex_input;
        let count = (input.attribute_count as usize).min(input.formats.len());
        let attributes: Vec<(vk::Format, u32)> = (0..count)
            .map(|i| (vk::Format::from_raw(input.formats[i]), input.offsets[i]))
            .collect();
        let surfaces = topology == vk::PrimitiveTopology::TRIANGLE_LIST
            && !raster.triangle_outlines
            && !raster.silhouette_lines;
        let translucent_frame = matches!(
            self.pass_set,
            PassSet::Shaded {
                translucent: true,
                ..
            }
        );
        let through_translucent = matches!(
            self.pass_set,
            PassSet::Pick {
                through_translucent: true
            }
        );
        let lines_through_translucent = matches!(
            self.pass_set,
            PassSet::Shaded {
                lines_through_translucent: true,
                ..
            }
        );
        let role = match (translucent_frame, raster.translucent, surfaces) {
            (false, _, _) if through_translucent => DrawRole::Opaque,
            (false, _, true) if lines_through_translucent => DrawRole::Opaque,
            (false, _, _) => DrawRole::All,
            (true, true, _) => DrawRole::Translucent,
            (true, false, true) => DrawRole::Opaque,
            (true, false, false) => DrawRole::All,
        };
        let colors = self.colors(raster);
        let scope = PassScope {
            role,
            caps: raster.on_surfaces,
            silhouettes: raster.silhouette_lines,
        };
        let pipeline = Pipeline::graphics(
            &self.device,
            &GraphicsPipelineDesc {
                layout: &self.layout,
                vertex: &vertex,
                geometry: geometry.as_ref(),
                fragment: &fragment,
                vertex_layout: (input.stride != 0).then_some(VertexLayout {
                    stride: input.stride,
                    attributes: &attributes,
                }),
                topology,
                depth_bias: raster.depth_bias,
                triangle_outlines: raster.triangle_outlines,
                colors: &colors,
                depth: if raster.behind {
                    DepthUse::TestBehind
                } else if raster.on_surfaces {
                    DepthUse::TestEqual
                } else if raster.translucent || raster.keeps_depth {
                    DepthUse::Test
                } else {
                    DepthUse::TestAndWrite
                },
                vertex_constants: &[role as u32, u32::from(raster.on_surfaces)],
                samples: self.pass_set.samples(),
                name: if raster.translucent {
                    "translucent technique pipeline"
                } else {
                    "technique pipeline"
                },
            },
        )?;
        Ok((pipeline, scope))
    }
}

/// A method's blend state as the Vulkan layer takes it.
fn blend_of(blend: &abi::CadrBlend) -> Blend {
    Blend {
        src_color: vk::BlendFactor::from_raw(blend.src_color),
        dst_color: vk::BlendFactor::from_raw(blend.dst_color),
        color_op: vk::BlendOp::from_raw(blend.color_op),
        src_alpha: vk::BlendFactor::from_raw(blend.src_alpha),
        dst_alpha: vk::BlendFactor::from_raw(blend.dst_alpha),
        alpha_op: vk::BlendOp::from_raw(blend.alpha_op),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A vertex shader assembled from two small paths: positions and normals from vertex
    /// inputs, the object from push constants.
    fn vertex_source() -> String {
        assemble_vertex_shader(
            "layout(location = 0) in vec3 in_position;\n\
             layout(location = 1) in vec3 in_normal;\n\
             vec3 cadr_vertex_position() { return in_position; }\n\
             vec3 cadr_vertex_normal() { return in_normal; }",
            "CadrObject cadr_object() {\n\
                 return CadrObject(cadr_push.matrix, cadr_push.vectors[0], cadr_push.vectors[1].xy,\n\
                                   cadr_push.words[0].x, cadr_push.words[0].y);\n\
             }",
        )
    }

    /// Whether a pass of `scope` draws anything of a part with `flags`: technique.vert's
    /// translucency test, role and caps clipping, as the shader decides them, and for the
    /// hidden silhouettes' pass whether its geometry shader can yield a segment.
    fn pass_draws(scope: PassScope, xray: bool, textures: bool, flags: u32) -> bool {
        let set = |bit: u32| flags & bit != 0;
        let by_material = set(abi::CADR_INSTANCE_TRANSLUCENT)
            && (textures || !set(abi::CADR_INSTANCE_TRANSLUCENT_BY_TEXTURE));
        let translucent = by_material || (xray && !set(abi::CADR_INSTANCE_HIGHLIGHTED));
        let drawn = match scope.role {
            DrawRole::All => true,
            DrawRole::Opaque => !translucent,
            DrawRole::Translucent => translucent,
        };
        drawn
            && (!scope.caps || set(abi::CADR_INSTANCE_CLOSED))
            && (!scope.silhouettes || set(abi::CADR_INSTANCE_CURVED))
    }

    #[test]
    fn a_pass_filter_leaves_out_only_what_its_pass_cannot_draw() {
        use abi::CADR_INSTANCE_CURVED as CURVED;
        use abi::CADR_INSTANCE_TRANSLUCENT as TRANSLUCENT;
        use abi::CADR_INSTANCE_TRANSLUCENT_BY_TEXTURE as BY_TEXTURE;
        use abi::{CADR_INSTANCE_CLOSED as CLOSED, CADR_INSTANCE_HIGHLIGHTED as HIGHLIGHTED};
        let mut every_flags = Vec::new();
        for highlighted in [0, HIGHLIGHTED] {
            for translucency in [0, TRANSLUCENT, TRANSLUCENT | BY_TEXTURE] {
                for closed in [0, CLOSED] {
                    for curved in [0, CURVED] {
                        every_flags.push(highlighted | translucency | closed | curved);
                    }
                }
            }
        }
        let mut kept_needlessly = Vec::new();
        for role in [DrawRole::All, DrawRole::Opaque, DrawRole::Translucent] {
            for (caps, silhouettes) in [(false, false), (true, false), (false, true)] {
                let scope = PassScope {
                    role,
                    caps,
                    silhouettes,
                };
                for (xray, textures) in [(false, false), (false, true), (true, false), (true, true)]
                {
                    let (filter, exclusion) = scope.filter(xray, textures);
                    let keeps = |flags| filter.keeps(flags) && !exclusion.excludes(flags);
                    for &flags in &every_flags {
                        let drawn = pass_draws(scope, xray, textures, flags);
                        assert!(
                            keeps(flags) || !drawn,
                            "{scope:?} xray {xray} textures {textures}: flags {flags:#x} drawn \
                             but filtered out"
                        );
                        if keeps(flags) && !drawn {
                            let shapeless = flags & !(CLOSED | CURVED);
                            kept_needlessly.push((scope, xray, textures, shapeless));
                        }
                    }
                }
            }
        }
        // Every filter is exact but one: X-ray's translucent pass without textures keeps the
        // highlighted parts translucent by texture only, which one exclusion cannot also name.
        kept_needlessly.dedup();
        let textured_highlighted = HIGHLIGHTED | TRANSLUCENT | BY_TEXTURE;
        assert_eq!(
            kept_needlessly,
            [(false, false), (true, false), (false, true)].map(|(caps, silhouettes)| (
                PassScope {
                    role: DrawRole::Translucent,
                    caps,
                    silhouettes
                },
                true,
                false,
                textured_highlighted
            ))
        );
        // The caps pass: only those a plane cuts (for cullers that can tell).
        let caps = PassScope {
            role: DrawRole::All,
            caps: true,
            silhouettes: false,
        };
        let opaque = PassScope {
            role: DrawRole::Opaque,
            caps: false,
            silhouettes: false,
        };
        assert_eq!(caps.filter(false, true).0.section_cut, 1);
        assert_eq!(opaque.filter(false, true).0.section_cut, 0);
    }

    #[test]
    fn only_the_shaders_a_pass_set_draws_with_are_compiled_each_once() {
        let mut cache = ShaderCache::default();
        let key = || ("per-geometry".to_owned(), "push".to_owned());
        let mut assembled = 0;
        let mut prepare = |cache: &mut ShaderCache, passes| {
            cache.prepare(
                key(),
                || {
                    assembled += 1;
                    vertex_source()
                },
                passes,
                None,
            )
        };
        let solid = || PassSet::Shaded {
            mode: ShadeMode::Solid,
            translucent: false,
            samples: 1,
            dashed_hidden: false,
            lines_through_translucent: false,
            caps_over_lines: false,
            hidden_silhouettes: false,
        };
        prepare(&mut cache, solid()).expect("solid");
        assert_eq!(
            cache.pass_shaders.len(),
            1,
            "solid needs one fragment shader"
        );
        prepare(
            &mut cache,
            PassSet::Shaded {
                mode: ShadeMode::Edges,
                translucent: false,
                samples: 4,
                dashed_hidden: false,
                lines_through_translucent: false,
                caps_over_lines: false,
                hidden_silhouettes: false,
            },
        )
        .expect("edges");
        assert_eq!(
            cache.pass_shaders.len(),
            2,
            "the sample count changes pipelines, not shaders"
        );
        prepare(
            &mut cache,
            PassSet::Pick {
                through_translucent: false,
            },
        )
        .expect("pick");
        assert_eq!(cache.pass_shaders.len(), 3);
        let dashed = |hidden_silhouettes| PassSet::Shaded {
            mode: ShadeMode::HiddenLine,
            translucent: false,
            samples: 1,
            dashed_hidden: true,
            lines_through_translucent: false,
            caps_over_lines: false,
            hidden_silhouettes,
        };
        prepare(&mut cache, dashed(false)).expect("dashed");
        assert_eq!(cache.pass_shaders.len(), 4, "the dashes' fragment shader");
        assert!(!cache
            .pass_shaders
            .contains_key(&PassShader::SilhouetteLines));
        prepare(&mut cache, dashed(true)).expect("dashed silhouettes");
        assert!(
            cache
                .pass_shaders
                .contains_key(&PassShader::SilhouetteLines),
            "the hidden silhouettes' geometry shader"
        );
        assert_eq!(cache.pass_shaders.len(), 5);
        prepare(&mut cache, solid()).expect("again");
        assert_eq!(
            assembled, 1,
            "the vertex shader is assembled and compiled once"
        );
        assert_eq!(cache.vertex.len(), 1);
    }
}
