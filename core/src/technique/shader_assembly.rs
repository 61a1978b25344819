//! The shaders of a technique combination: the vertex shader assembled from the vertex and
//! parameter paths' snippets (the seeds' effect system: each path generates its own layouts and
//! accessors), the fragment shaders each pass set draws with, and the transparency method's,
//! compiled once per (vertex path, parameter path) and kept ([`ShaderCache`]).

use std::collections::HashMap;
use std::sync::Arc;

use crate::error::RenderResult;
use crate::render::TransparencyMethod;
use crate::shaders;
use crate::vk::{Capabilities, ShaderStage};

use super::surface_passes::{PassSet, ShadeMode, SurfaceInputs};

/// The SPIR-V of a transparency method: its translucent fragment shader, and the merge's
/// vertex and fragment shaders.
#[derive(Clone)]
pub(super) struct MethodShaders {
    pub(super) translucent: Arc<Vec<u32>>,
    pub(super) merge_vertex: Arc<Vec<u32>>,
    pub(super) merge: Arc<Vec<u32>>,
}

/// Assembles the technique vertex shader from the two snippets. Lines of a snippet starting
/// with `#extension` are moved to the top, where GLSL wants them.
pub fn assemble_vertex_shader(vertex_snippet: &str, parameter_snippet: &str) -> String {
    assemble(&shaders::TECHNIQUE_VERT, vertex_snippet, parameter_snippet)
}

/// Assembles the technique mesh shader (`technique.mesh`) from the two snippets of paths that
/// announce mesh shading: as [`assemble_vertex_shader`], with the snippets' `gl_VertexIndex`
/// and `gl_InstanceIndex` (which a mesh shader lacks) read from the corner being computed.
pub fn assemble_mesh_shader(vertex_snippet: &str, parameter_snippet: &str) -> String {
    let in_mesh = |snippet: &str| {
        snippet
            .replace("gl_VertexIndex", "cadr_mesh_vertex_index")
            .replace("gl_InstanceIndex", "cadr_mesh_instance_index")
    };
    assemble(
        &shaders::TECHNIQUE_MESH,
        &in_mesh(vertex_snippet),
        &in_mesh(parameter_snippet),
    )
}

/// `template` with the vertex and parameter snippets at its two markers, their `#extension`
/// lines moved to the top.
fn assemble(
    template: &shaders::ShaderSource,
    vertex_snippet: &str,
    parameter_snippet: &str,
) -> String {
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
    let (version, body) = template
        .source
        .split_once("#version 460\n")
        .map_or(("", template.source), |(before, after)| (before, after));
    let body = body
        .replace("//@VERTEX_PATH@", &vertex)
        .replace("//@PARAMETER_PATH@", &parameters);
    format!("#version 460\n{}\n{version}{body}", extensions.join("\n"))
}

/// The shaders of the passes after the shared vertex shader: fragment shaders, and the
/// geometry shader of the hidden silhouettes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) enum PassShader {
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

    /// Whether the shader reads [`SurfaceInputs`] (the surface and pick shaders): it has a
    /// variant for each.
    fn reads_surface_inputs(self) -> bool {
        matches!(self, Self::Solid | Self::Pick)
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

/// How the technique shaders of a (vertex path, parameter path) pair are assembled, when the
/// cache lacks them: the vertex shader, and the mesh shader where a mesh-shading submission
/// draws the triangle passes.
pub struct TechniqueShaderSources<'a> {
    /// Assembles `technique.vert`.
    pub vertex: &'a dyn Fn() -> String,
    /// Assembles `technique.mesh`, or `None` without mesh shading.
    pub mesh: Option<&'a dyn Fn() -> String>,
}

/// The task and mesh shaders of a mesh-shading pass set.
#[derive(Clone)]
pub struct MeshShaders {
    /// `technique.task`, the same for every pair of paths.
    pub task: Arc<Vec<u32>>,
    /// `technique.mesh` assembled from the paths' snippets.
    pub mesh: Arc<Vec<u32>>,
}

/// SPIR-V of assembled vertex (and mesh) shaders, by (vertex path, parameter path) name, and
/// of the passes' other shaders, each compiled when a pass first needs it.
#[derive(Default)]
pub struct ShaderCache {
    vertex: HashMap<(String, String), Arc<Vec<u32>>>,
    /// The assembled mesh shaders, by the same key.
    mesh: HashMap<(String, String), Arc<Vec<u32>>>,
    /// `technique.task`, once a mesh-shading pass set needed it.
    task: Option<Arc<Vec<u32>>>,
    /// By shader and the inputs it interpolates (always the default for the shaders that do
    /// not read [`SurfaceInputs`]).
    pass_shaders: HashMap<(PassShader, SurfaceInputs), Arc<Vec<u32>>>,
    /// By method name and whether the translucent shader interpolates the vertex colours and
    /// texture coordinates ([`SurfaceInputs::attributes`]; it never draws caps).
    methods: HashMap<(String, bool), MethodShaders>,
    /// `#define` lines every fragment (and geometry) shader is compiled with: what the device
    /// allows.
    fragment_defines: String,
}

/// The SPIR-V one pass set is built from.
pub struct PassShaders {
    /// The assembled vertex shader.
    pub vertex: Arc<Vec<u32>>,
    /// The task and mesh shaders the triangle passes draw with, where a mesh-shading
    /// submission draws them.
    pub mesh: Option<MeshShaders>,
    pass_shaders: Vec<(PassShader, Arc<Vec<u32>>)>,
    /// The transparency method's, for a frame with translucent surfaces.
    pub(super) method: Option<MethodShaders>,
}

impl PassShaders {
    pub(super) fn shader(&self, shader: PassShader) -> RenderResult<&[u32]> {
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

    /// The vertex shader of the (vertex path, parameter path) `key` (assembled by `sources`),
    /// its mesh shader and the task shader where `sources` has a mesh shader, and the other
    /// shaders `passes` draw with. Those not compiled before are compiled now, together, on a
    /// thread each (a combination is ready in the time of its slowest shader); passes not drawn
    /// compile nothing.
    pub fn prepare(
        &mut self,
        key: (String, String),
        sources: TechniqueShaderSources<'_>,
        passes: PassSet,
        method: Option<&TransparencyMethod>,
    ) -> RenderResult<PassShaders> {
        let inputs = passes.surface_inputs();
        let variant = |shader: PassShader| {
            let read = shader.reads_surface_inputs();
            (
                shader,
                if read {
                    inputs
                } else {
                    SurfaceInputs::default()
                },
            )
        };
        let wanted: Vec<(PassShader, SurfaceInputs)> = PassShader::needed_by(passes)
            .into_iter()
            .map(variant)
            .collect();
        let missing: Vec<(PassShader, SurfaceInputs)> = wanted
            .iter()
            .copied()
            .filter(|f| !self.pass_shaders.contains_key(f))
            .collect();
        let pair = format!("[{} + {}]", key.0, key.1);
        let vertex_name = format!("technique.vert {pair}");
        let mesh_name = format!("technique.mesh {pair}");
        let vertex_source = (!self.vertex.contains_key(&key)).then(sources.vertex);
        let mesh_source = sources
            .mesh
            .filter(|_| !self.mesh.contains_key(&key))
            .map(|assemble| assemble());
        let task_needed = sources.mesh.is_some() && self.task.is_none();
        let pass_sources: Vec<String> = missing
            .iter()
            .map(|(f, inputs)| {
                let defines = format!("{}{}", self.fragment_defines, inputs.defines());
                shaders::with_defines(f.source().source, &defines)
            })
            .collect();
        let request = |name, source, stage| shaders::CompileRequest {
            name,
            source,
            stage,
            includes: shaders::INCLUDES,
        };
        let mut requests: Vec<shaders::CompileRequest<'_>> = missing
            .iter()
            .zip(&pass_sources)
            .map(|((f, _), source)| {
                let shader = f.source();
                request(shader.name, source, shader.stage)
            })
            .collect();
        requests.extend(
            vertex_source
                .as_ref()
                .map(|source| request(&vertex_name, source, ShaderStage::Vertex)),
        );
        requests.extend(
            mesh_source
                .as_ref()
                .map(|source| request(&mesh_name, source, ShaderStage::Mesh)),
        );
        let task = &shaders::TECHNIQUE_TASK;
        if task_needed {
            requests.push(request(task.name, task.source, task.stage));
        }
        let mut compiled = shaders::compile_glsl_all(&requests).into_iter();
        for shader in &missing {
            if let Some(words) = compiled.next() {
                self.pass_shaders.insert(*shader, Arc::new(words?));
            }
        }
        // In the order requested; only what was requested has a result.
        for (requested, cache) in [
            (vertex_source.is_some(), &mut self.vertex),
            (mesh_source.is_some(), &mut self.mesh),
        ] {
            if requested {
                if let Some(words) = compiled.next() {
                    cache.insert(key.clone(), Arc::new(words?));
                }
            }
        }
        if task_needed {
            if let Some(words) = compiled.next() {
                self.task = Some(Arc::new(words?));
            }
        }
        let method = match (passes, method) {
            (
                PassSet::Shaded {
                    translucent: true, ..
                },
                Some(method),
            ) => Some(self.method_shaders(method, inputs.attributes)?),
            _ => None,
        };
        self.compiled(&key, sources.mesh.is_some(), &wanted, method)
    }

    /// The pass set's shaders, compiled before: the pair `key`'s vertex shader (and mesh
    /// shader with the task shader, where `mesh`), the `wanted` pass shaders, and `method`'s.
    fn compiled(
        &self,
        key: &(String, String),
        mesh: bool,
        wanted: &[(PassShader, SurfaceInputs)],
        method: Option<MethodShaders>,
    ) -> RenderResult<PassShaders> {
        let not_compiled =
            || crate::error::RenderError::InvalidUse("a technique shader was not compiled".into());
        let mesh = if mesh {
            Some(MeshShaders {
                task: Arc::clone(self.task.as_ref().ok_or_else(not_compiled)?),
                mesh: Arc::clone(self.mesh.get(key).ok_or_else(not_compiled)?),
            })
        } else {
            None
        };
        Ok(PassShaders {
            method,
            vertex: Arc::clone(self.vertex.get(key).ok_or_else(not_compiled)?),
            mesh,
            pass_shaders: wanted
                .iter()
                .map(|f| {
                    Ok((
                        f.0,
                        Arc::clone(self.pass_shaders.get(f).ok_or_else(not_compiled)?),
                    ))
                })
                .collect::<RenderResult<_>>()?,
        })
    }
}

impl ShaderCache {
    /// The shaders of `method`, its translucent shader interpolating the vertex colours and
    /// texture coordinates where `attributes`, compiled together the first time.
    fn method_shaders(
        &mut self,
        method: &TransparencyMethod,
        attributes: bool,
    ) -> RenderResult<MethodShaders> {
        let key = (method.name.clone(), attributes);
        if let Some(shaders) = self.methods.get(&key) {
            return Ok(shaders.clone());
        }
        let defines = &self.fragment_defines;
        let inputs = SurfaceInputs {
            attributes,
            caps: false,
        };
        let translucent = method.assemble(
            &shaders::TRANSLUCENT_FRAG,
            &method.fragment_snippet,
            &format!("{defines}{}", inputs.defines()),
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
        self.methods.insert(key, shaders.clone());
        Ok(shaders)
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

    #[test]
    fn only_the_shaders_a_pass_set_draws_with_are_compiled_each_once() {
        let mut cache = ShaderCache::default();
        let key = || ("per-geometry".to_owned(), "push".to_owned());
        let assembled = std::cell::Cell::new(0);
        let assemble = || {
            assembled.set(assembled.get() + 1);
            vertex_source()
        };
        let prepare = |cache: &mut ShaderCache, passes| {
            let sources = TechniqueShaderSources {
                vertex: &assemble,
                mesh: None,
            };
            cache.prepare(key(), sources, passes, None)
        };
        let solid = || PassSet::plain(ShadeMode::Solid);
        prepare(&mut cache, solid()).expect("solid");
        assert_eq!(
            cache.pass_shaders.len(),
            1,
            "solid needs one fragment shader"
        );
        let mut multisampled_edges = PassSet::plain(ShadeMode::Edges);
        if let PassSet::Shaded { samples, .. } = &mut multisampled_edges {
            *samples = 4;
        }
        prepare(&mut cache, multisampled_edges).expect("edges");
        assert_eq!(
            cache.pass_shaders.len(),
            2,
            "the sample count changes pipelines, not shaders"
        );
        prepare(
            &mut cache,
            PassSet::Pick {
                through_translucent: false,
                inputs: SurfaceInputs::default(),
            },
        )
        .expect("pick");
        assert_eq!(cache.pass_shaders.len(), 3);
        let dashed = |silhouettes| {
            let mut passes = PassSet::plain(ShadeMode::HiddenLine);
            if let PassSet::Shaded {
                dashed_hidden,
                hidden_silhouettes,
                ..
            } = &mut passes
            {
                *dashed_hidden = true;
                *hidden_silhouettes = silhouettes;
            }
            passes
        };
        prepare(&mut cache, dashed(false)).expect("dashed");
        assert_eq!(cache.pass_shaders.len(), 4, "the dashes' fragment shader");
        let silhouette_lines = (PassShader::SilhouetteLines, SurfaceInputs::default());
        assert!(!cache.pass_shaders.contains_key(&silhouette_lines));
        prepare(&mut cache, dashed(true)).expect("dashed silhouettes");
        assert!(
            cache.pass_shaders.contains_key(&silhouette_lines),
            "the hidden silhouettes' geometry shader"
        );
        assert_eq!(cache.pass_shaders.len(), 5);

        // Vertex colours, textures or caps shown: the surface shader again, with those inputs;
        // every other shader, and the vertex shader, as they were.
        let capped = |attributes, caps| {
            let mut passes = PassSet::plain(ShadeMode::Edges);
            if let PassSet::Shaded { inputs, .. } = &mut passes {
                *inputs = SurfaceInputs { attributes, caps };
            }
            passes
        };
        prepare(&mut cache, capped(false, true)).expect("caps");
        assert_eq!(
            cache.pass_shaders.len(),
            6,
            "the surface shader reading the eye offset"
        );
        prepare(&mut cache, capped(true, true)).expect("caps and textures");
        assert_eq!(cache.pass_shaders.len(), 7);
        assert!(cache.pass_shaders.contains_key(&(
            PassShader::Solid,
            SurfaceInputs {
                attributes: true,
                caps: true
            }
        )));

        prepare(&mut cache, solid()).expect("again");
        assert_eq!(
            assembled.get(),
            1,
            "the vertex shader is assembled and compiled once"
        );
        assert_eq!(cache.vertex.len(), 1);
    }

    /// The mesh shader assembled from paths that pull their vertex and index their instance
    /// (as `pulling` and `ssbo-index` do) compiles, and reads neither built-in it lacks.
    #[test]
    fn the_mesh_shader_assembles_from_pulling_paths_and_compiles() {
        let vertex = "layout(set = 3, binding = 0, std430) readonly buffer V { float v[]; };\n\
             vec3 cadr_vertex_position() { uint b = uint(gl_VertexIndex) * 6u; return vec3(v[b], v[b + 1u], v[b + 2u]); }\n\
             vec3 cadr_vertex_normal() { return vec3(0.0, 0.0, 1.0); }\n\
             #define CADR_VERTEX_INDEX\n\
             uint cadr_vertex_index() { return uint(gl_VertexIndex); }";
        let parameters = "#extension GL_EXT_scalar_block_layout : enable\n\
             layout(set = 1, binding = 1, std430) readonly buffer M { mat4 m[]; };\n\
             CadrObject cadr_object() {\n\
                 return CadrObject(m[gl_InstanceIndex], vec4(1.0), vec2(0.0), 0u, uint(gl_InstanceIndex));\n\
             }";
        let source = assemble_mesh_shader(vertex, parameters);
        // A mesh shader that read gl_VertexIndex or gl_InstanceIndex would not compile.
        let words = shaders::compile_glsl(
            "technique.mesh",
            &source,
            ShaderStage::Mesh,
            shaders::INCLUDES,
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(words.first(), Some(&0x0723_0203));
        let vertex_source = assemble_vertex_shader(vertex, parameters);
        shaders::compile_glsl(
            "technique.vert",
            &vertex_source,
            ShaderStage::Vertex,
            shaders::INCLUDES,
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let task = &shaders::TECHNIQUE_TASK;
        shaders::compile_glsl(task.name, task.source, task.stage, shaders::INCLUDES)
            .unwrap_or_else(|e| panic!("{e}"));
    }
}
