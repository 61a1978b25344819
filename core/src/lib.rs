//! cadr core: the scene model, its loaders and generators, and the Vulkan renderer.
//!
//! One road from the files to the GPU: a [`scene::Scene`] (loaded by [`load`] or [`csf`], made
//! by [`generate`]) becomes a [`graph::SceneGraph`] (what hosts edit), flattened incrementally
//! into a [`tree::SceneTree`]; each [`view::View`] keeps a [`gpu_scene::GpuScene`] in step with
//! the tree and draws it, and its pick pass, with the active [`technique`] combination (the
//! built-in one or plugins) into a [`frame::Renderer`]'s target, with the pieces of
//! [`render`]. [`vk`] is the thin Vulkan layer under all of it, the only code that calls ash;
//! [`error::RenderError`] is what the layers above it report. The modules form layers, each
//! using only those below it (ARCHITECTURE.md; `core/tests/module_layers.rs` checks it).

mod commands_key;
pub mod csf;
pub mod disk_cache;
pub mod error;
pub mod frame;
pub mod freed_memory;
pub mod generate;
pub mod gpu_scene;
pub mod graph;
pub mod host_heap;
pub mod load;
pub mod memory_budget;
pub mod panic_boundary;
pub mod parallel;
pub mod render;
pub mod save;
pub mod scene;
pub mod shaders;
pub mod technique;
pub mod timings;
pub mod tree;
pub mod view;
pub mod vk;
