//! The GLSL sources in `shaders/`, embedded so that the library needs no files at run time.

use crate::vk::{IncludeFile, ShaderStage};

/// Files that `#include` resolves to.
pub const INCLUDES: &[IncludeFile] = &[
    ("frame.glsl", include_str!("../../shaders/frame.glsl")),
    ("shading.glsl", include_str!("../../shaders/shading.glsl")),
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

/// The technique vertex shader's frame: the host pastes the vertex and parameter paths'
/// snippets in (see `technique::pipeline`), so it is not complete by itself.
pub const TECHNIQUE_VERT: ShaderSource = ShaderSource {
    name: "technique.vert",
    stage: ShaderStage::Vertex,
    source: include_str!("../../shaders/technique.vert"),
};
/// Edge lines of the "solid with edges" shade mode.
pub const EDGES_FRAG: ShaderSource = ShaderSource {
    name: "edges.frag",
    stage: ShaderStage::Fragment,
    source: include_str!("../../shaders/edges.frag"),
};

/// Shaders that are templates: plugins' snippets complete them (see `technique::pipeline`).
pub const TEMPLATES: &[ShaderSource] = &[TECHNIQUE_VERT];

/// Every complete shader, for validation.
pub const ALL: &[ShaderSource] = &[SHADED_FRAG, PICK_FRAG, SCATTER_COMP, EDGES_FRAG];
