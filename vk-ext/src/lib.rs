//! Bindings for Vulkan extensions newer than the ash release cadr builds on (ash 0.38 follows
//! Vulkan 1.3.281), written in ash's own pattern: `#[repr(C)]` structs with an `s_type` set
//! by `Default`, and a `Device` function table loaded through `vkGetDeviceProcAddr`.
//!
//! Only what cadr uses is bound. Each struct's layout is checked against the Vulkan registry's
//! definition (`vk.xml`) by `tests/tests/vk_ext_layouts.rs`. Both the core library's Vulkan
//! layer (`cadr_core::vk::dgc`) and the technique plugins (which load Vulkan themselves, through
//! `cadr-plugin-sdk`) use this crate, so the definitions exist once.

pub mod device_generated_commands;
