//! Technique plugins on the host side: finding and loading them ([`PluginRegistry`]), the
//! active combination with its pipelines ([`Techniques`]) and the frame that drives them over
//! the one [`crate::gpu_scene::GpuScene`] (`Renderer::render_techniques`,
//! `Renderer::pick_techniques`).

mod frame;
mod gpu_cull;
mod host_api;
mod pipeline;
mod registry;
mod set;

pub use frame::frustum_planes;
pub use host_api::AllocationCounts;
pub use pipeline::{
    assemble_vertex_shader, fragment_defines, PassSet, ShadeMode, TransparencyMethod,
};
pub use registry::{
    default_plugin_dirs, feature_bits, feature_names, PluginRegistry, Refusal, TechniqueEntry,
    TechniqueKind, BUILT_IN_LIBRARY, PLUGIN_PATH_VARIABLE,
};
pub use set::{check_combination, Combination, Techniques, Transforms, DEFAULT_TRANSPARENCY};
