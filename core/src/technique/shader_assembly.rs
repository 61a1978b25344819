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

/// SPIR-V of assembled vertex shaders, by (vertex path, parameter path) name, and of the
/// passes' other shaders, each compiled when a pass first needs it.
#[derive(Default)]
pub struct ShaderCache {
    vertex: HashMap<(String, String), Arc<Vec<u32>>>,
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
        let vertex_name = format!("technique.vert [{} + {}]", key.0, key.1);
        let vertex_source = (!self.vertex.contains_key(&key)).then(source);
        let pass_sources: Vec<String> = missing
            .iter()
            .map(|(f, inputs)| {
                let defines = format!("{}{}", self.fragment_defines, inputs.defines());
                shaders::with_defines(f.source().source, &defines)
            })
            .collect();
        let mut requests: Vec<shaders::CompileRequest<'_>> = missing
            .iter()
            .zip(&pass_sources)
            .map(|((f, _), source)| {
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
            ) => Some(self.method_shaders(method, inputs.attributes)?),
            _ => None,
        };
        Ok(PassShaders {
            method,
            vertex: Arc::clone(self.vertex.get(&key).ok_or_else(not_compiled)?),
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
            assembled, 1,
            "the vertex shader is assembled and compiled once"
        );
        assert_eq!(cache.vertex.len(), 1);
    }
}
