//! Technique plugins on the host side: finding and loading them ([`PluginRegistry`]), the
//! active combination with its pipelines ([`Techniques`]), the pipelines of each pass set
//! (`pipeline.rs`) and what plugins may call back (`host_api.rs`). [`crate::frame`] drives
//! them over the GPU scene each frame.

mod host_api;
mod pipeline;
mod registry;
mod set;

pub use host_api::AllocationCounts;
pub use pipeline::{assemble_vertex_shader, fragment_defines, PassFilters, PassSet, ShadeMode};
pub(crate) use registry::announces;
pub use registry::{
    default_plugin_dirs, feature_bits, feature_names, PluginRegistry, Refusal, TechniqueEntry,
    TechniqueKind, BUILT_IN_LIBRARY, PLUGIN_PATH_VARIABLE,
};
pub use set::{check_combination, Combination, Techniques, DEFAULT_TRANSPARENCY};
pub(crate) use set::{status, Active, Message};
