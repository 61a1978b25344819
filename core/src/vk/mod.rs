//! The Vulkan layer: a thin, named, unsafe-contained layer over `ash`.
//!
//! Nothing above this module calls ash directly. Every object here holds an `Arc<Device>` so
//! the device (and its instance) outlives all children; owners of GPU resources wait for the
//! GPU before dropping them. Errors are [`VkError`]s naming the failing call; out-of-memory and
//! device loss are reported as such, everything else means the configuration is unsupported.
//! With validation on, the debug messenger records every message in a [`ValidationLog`]; tests
//! fail when it holds an error.

mod adapter;
mod buffer;
mod command;
mod device;
mod error;
pub mod fault;
mod frame_blit;
mod frame_export;
pub mod host_memory;
pub mod host_vulkan;
mod image;
mod instance;
mod mesh;
mod offscreen;
mod pipeline;
mod pipeline_cache;
mod rendering;
mod sampler;
mod shader;
mod sharing;
mod swapchain;
mod timer;

pub use adapter::{
    enumerate as enumerate_adapters, Adapter, DeviceChoice, DEVICE_ENV, MAX_BINDLESS_TEXTURES,
    TEXTURE_ARRAY_ENV,
};
pub use buffer::{Buffer, MemoryLocation};
pub use command::{record_dispatch, record_fullscreen, resubmit_times_us, CommandContext, OneShot};
pub use device::{Capabilities, Device, DeviceMemoryUsage, DeviceOptions, RawHandles};
pub use error::{map_result, VkError, VkResult, VkResultExt};
pub use frame_blit::{BlitTarget, HostImage, ImageOutput};
pub use frame_export::FrameExport;
pub use image::{
    memory_barrier, read_image, record_image_copy, subresource_range, transition, transition_range,
    Image, ImageShape, TexelImage, COLOR_FORMAT, DEPTH_FORMAT,
};
pub use instance::{Instance, InstanceOptions, ValidationLog, ValidationMessage};
pub use mesh::{
    draw_mesh_tasks, draw_mesh_tasks_indirect_count, MeshPipelineDesc,
    DRAW_MESH_TASKS_COMMAND_BYTES,
};
pub use offscreen::{DepthSharing, MultisampledTarget, OffscreenTarget};
pub use pipeline::{
    Blend, ColorTarget, DepthUse, DescriptorSetLayout, DescriptorSets, GraphicsPipelineDesc,
    LayoutBinding, Pipeline, PipelineLayout, VertexLayout,
};
pub use rendering::{
    begin_overlay, begin_rendering, end_overlay, end_rendering, suspend_rendering, Multisampled,
    RenderingTarget, SUSPENDED_DEPTH_LAYOUT,
};
pub use sampler::Sampler;
pub use shader::{create_unowned_shader_module, ShaderModule, ShaderStage};
pub use sharing::Shared;
pub use swapchain::{PresentMode, PresentOutcome, Swapchain};
pub use timer::{GpuTimer, MOST_TIMESTAMPS};

pub use ash::vk as raw;
pub use cadr_vk_ext::device_generated_commands as dgc;
