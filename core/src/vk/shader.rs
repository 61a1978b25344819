//! Shader modules from SPIR-V, and the stages they are written for (GLSL is compiled by
//! `crate::shaders`).

use super::host_memory::core_callbacks as host_callbacks;
use std::sync::Arc;

use ash::vk;

use super::device::Device;
use super::error::{VkResult, VkResultExt};

/// The pipeline stage a GLSL source is written for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShaderStage {
    /// Vertex shader.
    Vertex,
    /// Geometry shader (needs the device's `geometryShader`: [`super::Capabilities::geometry_shader`]).
    Geometry,
    /// Fragment shader.
    Fragment,
    /// Compute shader.
    Compute,
    /// Task shader, launching mesh shader workgroups (needs [`super::Capabilities::mesh_shader`]).
    Task,
    /// Mesh shader, writing vertices and primitives (needs [`super::Capabilities::mesh_shader`]).
    Mesh,
}

impl ShaderStage {
    /// The stage for a file name ending in `.vert`, `.geom`, `.frag`, `.comp`, `.task` or
    /// `.mesh`.
    pub fn from_file_name(name: &str) -> Option<Self> {
        match name.rsplit('.').next()? {
            "vert" => Some(Self::Vertex),
            "geom" => Some(Self::Geometry),
            "frag" => Some(Self::Fragment),
            "comp" => Some(Self::Compute),
            "task" => Some(Self::Task),
            "mesh" => Some(Self::Mesh),
            _ => None,
        }
    }

    /// The Vulkan stage flag.
    pub fn flag(self) -> vk::ShaderStageFlags {
        match self {
            Self::Vertex => vk::ShaderStageFlags::VERTEX,
            Self::Geometry => vk::ShaderStageFlags::GEOMETRY,
            Self::Fragment => vk::ShaderStageFlags::FRAGMENT,
            Self::Compute => vk::ShaderStageFlags::COMPUTE,
            Self::Task => vk::ShaderStageFlags::TASK_EXT,
            Self::Mesh => vk::ShaderStageFlags::MESH_EXT,
        }
    }
}

/// Creates a shader module from SPIR-V `words` that the caller owns (a plugin, which destroys
/// it with the same allocation callbacks).
pub fn create_unowned_shader_module(
    device: &Device,
    name: &str,
    words: &[u32],
    callbacks: &vk::AllocationCallbacks<'_>,
) -> VkResult<vk::ShaderModule> {
    let info = vk::ShaderModuleCreateInfo::default().code(words);
    // SAFETY: words is SPIR-V from shaderc; info and callbacks live until the call returns.
    let raw = unsafe { device.raw.create_shader_module(&info, Some(callbacks)) }
        .or_vk("vkCreateShaderModule")?;
    device.set_name(raw, name);
    Ok(raw)
}

/// A compiled shader module; destroyed on drop.
pub struct ShaderModule {
    device: Arc<Device>,
    raw: vk::ShaderModule,
    stage: ShaderStage,
}

impl ShaderModule {
    /// Creates a module from SPIR-V `words` (from `shaders::compile_glsl`).
    pub fn from_spirv(
        device: &Arc<Device>,
        name: &str,
        words: &[u32],
        stage: ShaderStage,
    ) -> VkResult<Self> {
        let info = vk::ShaderModuleCreateInfo::default().code(words);
        // SAFETY: words is SPIR-V from shaderc; info lives until the call returns.
        let raw = unsafe { device.raw.create_shader_module(&info, host_callbacks()) }
            .or_vk("vkCreateShaderModule")?;
        device.set_name(raw, name);
        Ok(Self {
            device: Arc::clone(device),
            raw,
            stage,
        })
    }

    /// The Vulkan handle.
    pub fn raw(&self) -> vk::ShaderModule {
        self.raw
    }

    /// The stage it was compiled for.
    pub fn stage(&self) -> ShaderStage {
        self.stage
    }
}

impl Drop for ShaderModule {
    fn drop(&mut self) {
        // SAFETY: pipelines built from the module keep their own copy; destroyed once.
        unsafe {
            self.device
                .raw
                .destroy_shader_module(self.raw, host_callbacks())
        };
    }
}
