//! The GLSL sources in `shaders/`, embedded so that the library needs no files at run time, and
//! their compiler: GLSL → SPIR-V at run time with shaderc (linked to the system libshaderc).
//!
//! Run-time compilation is deliberate: technique plugins contribute GLSL snippets (parameter
//! accessors, vertex fetch) that are assembled into complete shaders when a combination is
//! chosen, so a build-time compiler could not know every permutation.

use std::sync::Arc;

use crate::disk_cache::DiskCache;
use crate::error::{RenderResult, ShaderCompileError};
use crate::timings::{self, Phase};
use crate::vk::{Device, ShaderModule, ShaderStage};

fn shaderc_kind(stage: ShaderStage) -> shaderc::ShaderKind {
    match stage {
        ShaderStage::Vertex => shaderc::ShaderKind::Vertex,
        ShaderStage::Geometry => shaderc::ShaderKind::Geometry,
        ShaderStage::Fragment => shaderc::ShaderKind::Fragment,
        ShaderStage::Compute => shaderc::ShaderKind::Compute,
        ShaderStage::Task => shaderc::ShaderKind::Task,
        ShaderStage::Mesh => shaderc::ShaderKind::Mesh,
    }
}

/// A virtual file that `#include "name"` resolves to.
pub type IncludeFile = (&'static str, &'static str);

/// The cache kind of compiled shaders.
const SPIRV_CACHE: &str = "spirv";
/// The first word of every SPIR-V module.
const SPIRV_MAGIC: u32 = 0x0723_0203;

/// Compiles GLSL `source` (named `name` in messages) for Vulkan 1.3, resolving `#include`
/// against `includes`. Returns the SPIR-V words. A module compiled before from the same
/// source, stage and includes by the same cadr and compiler comes from the user's disk cache
/// ([`crate::disk_cache`]); what is compiled goes there. Timed as
/// [`Phase::ShaderCompile`].
pub fn compile_glsl(
    name: &str,
    source: &str,
    stage: ShaderStage,
    includes: &[IncludeFile],
) -> Result<Vec<u32>, ShaderCompileError> {
    timings::time(Phase::ShaderCompile, || {
        compile_cached(name, source, stage, includes)
    })
}

/// The shader module of a built-in `shader` on `device`: compiled with the shared includes
/// ([`INCLUDES`]), or taken from the disk cache.
pub fn module(device: &Arc<Device>, shader: &ShaderSource) -> RenderResult<ShaderModule> {
    let words = compile_glsl(shader.name, shader.source, shader.stage, INCLUDES)?;
    Ok(ShaderModule::from_spirv(
        device,
        shader.name,
        &words,
        shader.stage,
    )?)
}

/// `source` with `defines` (whole `#define` lines) inserted after its `#version` line.
pub fn with_defines(source: &str, defines: &str) -> String {
    source.replacen("#version 460\n", &format!("#version 460\n{defines}"), 1)
}

/// One shader for [`compile_glsl_all`].
#[derive(Clone, Copy, Debug)]
pub struct CompileRequest<'a> {
    /// Its name in messages.
    pub name: &'a str,
    /// GLSL text.
    pub source: &'a str,
    /// Pipeline stage.
    pub stage: ShaderStage,
    /// Files `#include` resolves to.
    pub includes: &'a [IncludeFile],
}

/// Compiles several shaders at once, each on a thread of its own (as [`compile_glsl`] does
/// one): what a combination needs is ready in the time of its slowest shader. Results in the
/// order of `requests`.
pub fn compile_glsl_all(
    requests: &[CompileRequest<'_>],
) -> Vec<Result<Vec<u32>, ShaderCompileError>> {
    timings::time(Phase::ShaderCompile, || match requests {
        [] => Vec::new(),
        [one] => vec![compile_cached(
            one.name,
            one.source,
            one.stage,
            one.includes,
        )],
        many => std::thread::scope(|scope| {
            let workers: Vec<_> = many
                .iter()
                .map(|r| scope.spawn(move || compile_cached(r.name, r.source, r.stage, r.includes)))
                .collect();
            workers
                .into_iter()
                .zip(many)
                .map(|(worker, request)| {
                    worker.join().unwrap_or_else(|_| {
                        Err(ShaderCompileError {
                            name: request.name.to_owned(),
                            log: "the compiler's thread panicked".into(),
                        })
                    })
                })
                .collect()
        }),
    })
}

fn compile_cached(
    name: &str,
    source: &str,
    stage: ShaderStage,
    includes: &[IncludeFile],
) -> Result<Vec<u32>, ShaderCompileError> {
    let Some(cache) = DiskCache::user() else {
        return compile_uncached(name, source, stage, includes);
    };
    let (spirv_major, spirv_minor) = shaderc::get_spirv_version();
    let versions = format!(
        "cadr {} shaderc spirv {spirv_major}.{spirv_minor} vulkan1.3 performance",
        env!("CARGO_PKG_VERSION")
    );
    let stage_name = format!("{stage:?}");
    let mut parts: Vec<&[u8]> = vec![
        versions.as_bytes(),
        stage_name.as_bytes(),
        name.as_bytes(),
        source.as_bytes(),
    ];
    for (file, content) in includes {
        parts.extend([file.as_bytes(), content.as_bytes()]);
    }
    let entry = format!("{}.spv", crate::disk_cache::key(&parts));
    if let Some(words) = cache
        .read(SPIRV_CACHE, &entry)
        .and_then(|b| spirv_words(&b))
    {
        return Ok(words);
    }
    let words = compile_uncached(name, source, stage, includes)?;
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    cache.write(SPIRV_CACHE, &entry, &bytes);
    Ok(words)
}

/// SPIR-V words from cached bytes, if they look like a module (whole words, the magic first).
fn spirv_words(bytes: &[u8]) -> Option<Vec<u32>> {
    if bytes.len() % 4 != 0 || bytes.len() < 20 {
        return None;
    }
    let words: Vec<u32> = bytes
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    (words[0] == SPIRV_MAGIC).then_some(words)
}

fn compile_uncached(
    name: &str,
    source: &str,
    stage: ShaderStage,
    includes: &[IncludeFile],
) -> Result<Vec<u32>, ShaderCompileError> {
    let failure = |log: String| ShaderCompileError {
        name: name.to_owned(),
        log,
    };
    let compiler = shaderc::Compiler::new().map_err(|e| failure(format!("shaderc: {e}")))?;
    let mut options =
        shaderc::CompileOptions::new().map_err(|e| failure(format!("shaderc: {e}")))?;
    options.set_target_env(
        shaderc::TargetEnv::Vulkan,
        shaderc::EnvVersion::Vulkan1_3 as u32,
    );
    options.set_optimization_level(shaderc::OptimizationLevel::Performance);
    options.set_warnings_as_errors();
    let includes: Vec<IncludeFile> = includes.to_vec();
    options.set_include_callback(move |requested, _type, requester, _depth| {
        includes
            .iter()
            .find(|(file, _)| *file == requested)
            .map(|(file, content)| shaderc::ResolvedInclude {
                resolved_name: (*file).to_owned(),
                content: (*content).to_owned(),
            })
            .ok_or_else(|| format!("{requester}: no include file named '{requested}'"))
    });
    let artifact = compiler
        .compile_into_spirv(source, shaderc_kind(stage), name, "main", Some(&options))
        .map_err(|e| failure(e.to_string()))?;
    Ok(artifact.as_binary().to_vec())
}

/// Files that `#include` resolves to.
pub const INCLUDES: &[IncludeFile] = &[
    ("frame.glsl", include_str!("../../shaders/frame.glsl")),
    ("shading.glsl", include_str!("../../shaders/shading.glsl")),
    ("section.glsl", include_str!("../../shaders/section.glsl")),
    (
        "texturing.glsl",
        include_str!("../../shaders/texturing.glsl"),
    ),
    (
        "pixel_keys.glsl",
        include_str!("../../shaders/pixel_keys.glsl"),
    ),
    (
        "transparency.glsl",
        include_str!("../../shaders/transparency.glsl"),
    ),
    (
        "technique_inputs.glsl",
        include_str!("../../shaders/technique_inputs.glsl"),
    ),
    (
        "technique_vertex.glsl",
        include_str!("../../shaders/technique_vertex.glsl"),
    ),
    (
        "mesh_tasks.glsl",
        include_str!("../../shaders/mesh_tasks.glsl"),
    ),
];

/// A complete shader: name (file name), stage and source.
#[derive(Clone, Copy, Debug)]
pub struct ShaderSource {
    /// File name in `shaders/`.
    pub name: &'static str,
    /// Pipeline stage.
    pub stage: ShaderStage,
    /// GLSL text.
    pub source: &'static str,
}

/// Shaded triangles of every technique combination.
pub const SHADED_FRAG: ShaderSource = ShaderSource {
    name: "shaded.frag",
    stage: ShaderStage::Fragment,
    source: include_str!("../../shaders/shaded.frag"),
};
/// The pick pass's fragment shader.
pub const PICK_FRAG: ShaderSource = ShaderSource {
    name: "pick.frag",
    stage: ShaderStage::Fragment,
    source: include_str!("../../shaders/pick.frag"),
};
/// The GPU scene's sparse upload: compact updates scattered into place.
pub const SCATTER_COMP: ShaderSource = ShaderSource {
    name: "scatter.comp",
    stage: ShaderStage::Compute,
    source: include_str!("../../shaders/scatter.comp"),
};
/// The GPU transform hierarchy: world matrices of moved subtrees from their local matrices.
pub const TRANSFORMS_COMP: ShaderSource = ShaderSource {
    name: "transforms.comp",
    stage: ShaderStage::Compute,
    source: include_str!("../../shaders/transforms.comp"),
};

/// The technique vertex shader's frame: the host pastes the vertex and parameter paths'
/// snippets in (see `technique::pipeline`), so it is not complete by itself.
pub const TECHNIQUE_VERT: ShaderSource = ShaderSource {
    name: "technique.vert",
    stage: ShaderStage::Vertex,
    source: include_str!("../../shaders/technique.vert"),
};

/// The task shader of mesh-shading submissions: launches the mesh workgroups of a pass's
/// GPU-written commands.
pub const TECHNIQUE_TASK: ShaderSource = ShaderSource {
    name: "technique.task",
    stage: ShaderStage::Task,
    source: include_str!("../../shaders/technique.task"),
};

/// The mesh shader of mesh-shading submissions, a template as [`TECHNIQUE_VERT`] is: the
/// vertex of `technique.vert` computed per triangle corner of a command's chunk.
pub const TECHNIQUE_MESH: ShaderSource = ShaderSource {
    name: "technique.mesh",
    stage: ShaderStage::Mesh,
    source: include_str!("../../shaders/technique.mesh"),
};

/// Edge lines of the "solid with edges" shade mode.
pub const EDGES_FRAG: ShaderSource = ShaderSource {
    name: "edges.frag",
    stage: ShaderStage::Fragment,
    source: include_str!("../../shaders/edges.frag"),
};
/// Screen-space ambient occlusion over the opaque picture (an option).
pub const SSAO_FRAG: ShaderSource = ShaderSource {
    name: "ssao.frag",
    stage: ShaderStage::Fragment,
    source: include_str!("../../shaders/ssao.frag"),
};
/// Silhouette edges over the picture of the edge display modes, found where the depth breaks.
pub const SILHOUETTES_FRAG: ShaderSource = ShaderSource {
    name: "silhouettes.frag",
    stage: ShaderStage::Fragment,
    source: include_str!("../../shaders/silhouettes.frag"),
};
/// The outline highlight style's band around highlighted parts.
pub const OUTLINE_FRAG: ShaderSource = ShaderSource {
    name: "outline.frag",
    stage: ShaderStage::Fragment,
    source: include_str!("../../shaders/outline.frag"),
};
/// Section caps painted again over the edge lines (the edge modes with caps on).
pub const CAPS_FRAG: ShaderSource = ShaderSource {
    name: "caps.frag",
    stage: ShaderStage::Fragment,
    source: include_str!("../../shaders/caps.frag"),
};
/// Section caps where the face a cap is found on ties with another part's surface.
pub const CAP_TIES_FRAG: ShaderSource = ShaderSource {
    name: "cap_ties.frag",
    stage: ShaderStage::Fragment,
    source: include_str!("../../shaders/cap_ties.frag"),
};
/// Hidden edge lines, dashed (the hidden-line mode's option).
pub const HIDDEN_EDGES_FRAG: ShaderSource = ShaderSource {
    name: "hidden_edges.frag",
    stage: ShaderStage::Fragment,
    source: include_str!("../../shaders/hidden_edges.frag"),
};

/// Silhouette lines of curved surfaces, found per triangle from its vertex normals: the
/// hidden-line mode's dashed hidden silhouettes.
pub const SILHOUETTE_LINES_GEOM: ShaderSource = ShaderSource {
    name: "silhouette_lines.geom",
    stage: ShaderStage::Geometry,
    source: include_str!("../../shaders/silhouette_lines.geom"),
};

/// Translucent surfaces: the transparency method's fragment snippet completes it (see
/// `technique::pipeline`).
pub const TRANSLUCENT_FRAG: ShaderSource = ShaderSource {
    name: "translucent.frag",
    stage: ShaderStage::Fragment,
    source: include_str!("../../shaders/translucent.frag"),
};
/// The transparency merge: the method's merge snippet completes it.
pub const MERGE_FRAG: ShaderSource = ShaderSource {
    name: "merge.frag",
    stage: ShaderStage::Fragment,
    source: include_str!("../../shaders/merge.frag"),
};
/// One triangle covering the target (full-screen passes).
pub const MERGE_VERT: ShaderSource = ShaderSource {
    name: "merge.vert",
    stage: ShaderStage::Vertex,
    source: include_str!("../../shaders/merge.vert"),
};

/// The background under what a frame drew.
pub const BACKGROUND_FRAG: ShaderSource = ShaderSource {
    name: "background.frag",
    stage: ShaderStage::Fragment,
    source: include_str!("../../shaders/background.frag"),
};

/// The marker a transparency method's snippet replaces in [`TRANSLUCENT_FRAG`] and
/// [`MERGE_FRAG`].
pub const TRANSPARENCY_MARKER: &str = "//@TRANSPARENCY@";

/// Shaders that are templates: plugins' snippets complete them (see `technique::pipeline`).
pub const TEMPLATES: &[ShaderSource] =
    &[TECHNIQUE_VERT, TECHNIQUE_MESH, TRANSLUCENT_FRAG, MERGE_FRAG];

/// Every complete shader, for validation.
pub const ALL: &[ShaderSource] = &[
    SHADED_FRAG,
    PICK_FRAG,
    SCATTER_COMP,
    TRANSFORMS_COMP,
    EDGES_FRAG,
    HIDDEN_EDGES_FRAG,
    SILHOUETTE_LINES_GEOM,
    CAPS_FRAG,
    SSAO_FRAG,
    SILHOUETTES_FRAG,
    OUTLINE_FRAG,
    CAP_TIES_FRAG,
    MERGE_VERT,
    BACKGROUND_FRAG,
    TECHNIQUE_TASK,
];
