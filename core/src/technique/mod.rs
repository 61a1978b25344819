//! Technique plugins on the host side: finding and loading them ([`PluginRegistry`]), the
//! active combination with its pipelines ([`Techniques`]), what a frame's surfaces draw
//! (`surface_passes.rs`), the shaders and pipelines of each pass set (`shader_assembly.rs`,
//! `pass_pipelines.rs`; shared by the renderers of one device, `shared_pipelines.rs`) and what plugins may call back (`host_api.rs`). [`crate::frame`] drives them over the GPU
//! scene each frame.

mod host_api;
mod pass_pipelines;
mod registry;
mod set;
mod shader_assembly;
mod shared_pipelines;
mod surface_passes;

pub use host_api::AllocationCounts;
pub use pass_pipelines::PassFilters;
pub(crate) use pass_pipelines::TechniquePipelines;
pub(crate) use registry::announces;
pub use registry::{
    default_plugin_dirs, feature_bits, feature_names, PluginRegistry, Refusal, TechniqueEntry,
    TechniqueKind, BUILT_IN_LIBRARY, PLUGIN_PATH_VARIABLE,
};
pub use set::{
    check_combination, Combination, Techniques, DEFAULT_LOD_ERROR, DEFAULT_TRANSPARENCY,
};
pub(crate) use set::{status, Active, Message};
pub use shader_assembly::{assemble_vertex_shader, fragment_defines};
pub use surface_passes::{PassSet, ShadeMode, SurfaceInputs};
