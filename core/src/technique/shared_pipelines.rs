//! Pipelines shared by the renderers of one device: a CAD tool's four viewports of one scene
//! draw with one set of pipelines per pass set instead of building, and holding, four.
//!
//! A pass set's pipelines are made from the paths' snippets, vertex input and set layouts, the
//! transparency method and the host's own layouts (the frame set's and the merge's, which
//! depend on the device alone). Set layouts are per technique instance, so pipelines built
//! with one renderer's layouts may be drawn by another only where the layouts are *identically
//! defined* (Vulkan then calls them compatible). Both paths must promise it
//! (`CADR_TRAIT_SHARES_PIPELINES`); without the promise each renderer builds its own, as before.
//!
//! The registry holds the pipelines weakly: they live as long as a renderer keeps them among its
//! kept pass sets, and whichever renderer drops them last destroys them (each waits for the
//! device to be idle before it lets a pass set go, so no frame still draws with them).

use std::path::PathBuf;
use std::sync::Arc;

use crate::error::RenderResult;
use crate::render::TransparencyMethod;
use crate::vk::{Device, Shared};
use cadr_plugin_abi as abi;

use super::pass_pipelines::TechniquePipelines;
use super::registry::TechniqueEntry;
use super::surface_passes::PassSet;

/// A technique as pipelines know it: where it comes from and its name.
#[derive(Clone, Debug, PartialEq, Eq)]
struct TechniqueId {
    library: PathBuf,
    name: String,
}

impl TechniqueId {
    fn of(entry: &TechniqueEntry) -> Self {
        Self {
            library: entry.library.clone(),
            name: entry.name.clone(),
        }
    }
}

/// Everything a pass set's pipelines are built from, beside the device: two renderers whose
/// keys are equal build the same pipelines.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct PipelineKey {
    vertex: TechniqueId,
    parameters: TechniqueId,
    vertex_snippet: String,
    parameter_snippet: String,
    /// The vertex input's stride, attribute count, formats and offsets.
    vertex_input: [i64; 10],
    passes: PassSet,
    pick_kind: abi::CadrPassKind,
    method: Option<TransparencyMethod>,
    mesh_shading: bool,
}

/// What [`PipelineKey::new`] is made from.
pub(crate) struct KeyInputs<'a> {
    /// The vertex and parameter paths' entries.
    pub paths: (&'a TechniqueEntry, &'a TechniqueEntry),
    /// Their snippets, in the same order.
    pub snippets: (&'a str, &'a str),
    /// The vertex path's input.
    pub vertex_input: &'a abi::CadrVertexInput,
    /// The pass set.
    pub passes: PassSet,
    /// The pick pass's kind.
    pub pick_kind: abi::CadrPassKind,
    /// The transparency method.
    pub method: Option<&'a TransparencyMethod>,
    /// Whether the triangle passes are mesh pipelines (a mesh-shading submission).
    pub mesh_shading: bool,
}

impl PipelineKey {
    /// The key of pipelines built from `inputs`, or `None` where a path does not promise the
    /// same layouts in every instance (`CADR_TRAIT_SHARES_PIPELINES`, ABI 1.20 or later): then
    /// nobody else may draw with them.
    pub(crate) fn new(inputs: &KeyInputs<'_>) -> Option<Self> {
        let (vertex, parameters) = inputs.paths;
        let promised = [vertex, parameters]
            .iter()
            .all(|entry| entry.announces(abi::CADR_TRAIT_SHARES_PIPELINES, 20));
        if !promised {
            return None;
        }
        let input = inputs.vertex_input;
        let mut vertex_input = [0i64; 10];
        vertex_input[0] = input.stride.into();
        vertex_input[1] = input.attribute_count.into();
        for i in 0..4 {
            vertex_input[2 + i] = input.formats[i].into();
            vertex_input[6 + i] = input.offsets[i].into();
        }
        Some(Self {
            vertex: TechniqueId::of(vertex),
            parameters: TechniqueId::of(parameters),
            vertex_snippet: inputs.snippets.0.to_owned(),
            parameter_snippet: inputs.snippets.1.to_owned(),
            vertex_input,
            passes: inputs.passes,
            pick_kind: inputs.pick_kind,
            method: inputs.method.cloned(),
            mesh_shading: inputs.mesh_shading,
        })
    }
}

/// A pass set's pipelines as a renderer keeps them, with the key others may find them by.
pub(crate) struct KeptPipelines {
    key: Option<PipelineKey>,
    pipelines: TechniquePipelines,
}

impl std::ops::Deref for KeptPipelines {
    type Target = TechniquePipelines;

    fn deref(&self) -> &TechniquePipelines {
        &self.pipelines
    }
}

/// The pipelines the renderers of every device share, by device and key.
static SHARED_PIPELINES: Shared<KeptPipelines> = Shared::new();

/// The pipelines of `key` on `device`: those another renderer built, or the ones `build` makes
/// (kept for the next renderer when `key` is some).
pub(crate) fn shared_or_built(
    device: &Arc<Device>,
    key: Option<PipelineKey>,
    build: impl FnOnce() -> RenderResult<TechniquePipelines>,
) -> RenderResult<Arc<KeptPipelines>> {
    let Some(key) = key else {
        return Ok(Arc::new(KeptPipelines {
            key: None,
            pipelines: build()?,
        }));
    };
    let fits = |kept: &KeptPipelines| {
        Arc::ptr_eq(kept.pipelines.device(), device) && kept.key.as_ref() == Some(&key)
    };
    SHARED_PIPELINES.get_or_make(fits, || {
        Ok(KeptPipelines {
            pipelines: build()?,
            key: Some(key.clone()),
        })
    })
}
