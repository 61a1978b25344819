//! Technique plugins on the host side: finding and loading them ([`PluginRegistry`]), the
//! scene they all read ([`TechniqueScene`]), the active combination with its pipelines
//! ([`Techniques`]) and the frame that drives them (`Renderer::render_techniques`).

mod frame;
mod host_api;
mod pipeline;
mod registry;
mod scene;
mod set;

pub use frame::frustum_planes;
pub use host_api::AllocationCounts;
pub use pipeline::{assemble_vertex_shader, ShadeMode};
pub use registry::{
    default_plugin_dirs, feature_bits, feature_names, PluginRegistry, Refusal, TechniqueEntry,
    TechniqueKind, PLUGIN_PATH_VARIABLE,
};
pub use scene::TechniqueScene;
pub use set::{check_combination, Combination, Techniques};
