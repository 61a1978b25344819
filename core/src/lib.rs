//! cadr core: the scene model, its loaders and generators, and the Vulkan renderer.
//!
//! Data flows from a [`scene::Scene`] (loaded by [`load`] or made by [`generate`]) through
//! [`scene::flatten`] into draw items, which a [`render::Renderer`] draws with one of its
//! techniques into an offscreen target via the thin Vulkan layer in [`vk`].

pub mod csf;
pub mod error;
pub mod generate;
pub mod gpu_scene;
pub mod graph;
pub mod load;
pub mod render;
pub mod save;
pub mod scene;
pub mod shaders;
pub mod technique;
pub mod tree;
pub mod view;
pub mod vk;
