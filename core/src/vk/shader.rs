//! GLSL → SPIR-V at run time with shaderc (linked to the system libshaderc), and shader modules.
//!
//! Run-time compilation is deliberate: technique plugins contribute GLSL snippets (parameter
//! accessors, vertex fetch) that are assembled into complete shaders when a combination is
//! chosen, so a build-time compiler could not know every permutation.

use std::sync::Arc;

use ash::vk;

use super::device::Device;
use super::error::{VkError, VkResult, VkResultExt};

/// The pipeline stage a GLSL source is written for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShaderStage {
    /// Vertex shader.
    Vertex,
    /// Fragment shader.
    Fragment,
    /// Compute shader.
    Compute,
}

impl ShaderStage {
    /// The stage for a file name ending in `.vert`, `.frag` or `.comp`.
    pub fn from_file_name(name: &str) -> Option<Self> {
        match name.rsplit('.').next()? {
            "vert" => Some(Self::Vertex),
            "frag" => Some(Self::Fragment),
            "comp" => Some(Self::Compute),
            _ => None,
        }
    }

    fn kind(self) -> shaderc::ShaderKind {
        match self {
            Self::Vertex => shaderc::ShaderKind::Vertex,
            Self::Fragment => shaderc::ShaderKind::Fragment,
            Self::Compute => shaderc::ShaderKind::Compute,
        }
    }

    /// The Vulkan stage flag.
    pub fn flag(self) -> vk::ShaderStageFlags {
        match self {
            Self::Vertex => vk::ShaderStageFlags::VERTEX,
            Self::Fragment => vk::ShaderStageFlags::FRAGMENT,
            Self::Compute => vk::ShaderStageFlags::COMPUTE,
        }
    }
}

/// A virtual file that `#include "name"` resolves to.
pub type IncludeFile = (&'static str, &'static str);

/// Compiles GLSL `source` (named `name` in messages) for Vulkan 1.3, resolving `#include`
/// against `includes`. Returns the SPIR-V words.
pub fn compile_glsl(
    name: &str,
    source: &str,
    stage: ShaderStage,
    includes: &[IncludeFile],
) -> VkResult<Vec<u32>> {
    let failure = |log: String| VkError::ShaderCompile {
        name: name.to_owned(),
        log,
    };
    let compiler = shaderc::Compiler::new().map_err(|e| failure(format!("shaderc: {e}")))?;
    let mut options =
        shaderc::CompileOptions::new().map_err(|e| failure(format!("shaderc: {e}")))?;
    options.set_target_env(
        shaderc::TargetEnv::Vulkan,
        shaderc::EnvVersion::Vulkan1_3 as u32,
    );
    options.set_optimization_level(shaderc::OptimizationLevel::Performance);
    options.set_warnings_as_errors();
    let includes: Vec<IncludeFile> = includes.to_vec();
    options.set_include_callback(move |requested, _type, requester, _depth| {
        includes
            .iter()
            .find(|(file, _)| *file == requested)
            .map(|(file, content)| shaderc::ResolvedInclude {
                resolved_name: (*file).to_owned(),
                content: (*content).to_owned(),
            })
            .ok_or_else(|| format!("{requester}: no include file named '{requested}'"))
    });
    let artifact = compiler
        .compile_into_spirv(source, stage.kind(), name, "main", Some(&options))
        .map_err(|e| failure(e.to_string()))?;
    Ok(artifact.as_binary().to_vec())
}

/// A compiled shader module; destroyed on drop.
pub struct ShaderModule {
    device: Arc<Device>,
    raw: vk::ShaderModule,
    stage: ShaderStage,
}

impl ShaderModule {
    /// Compiles `source` and creates the module.
    pub fn from_glsl(
        device: &Arc<Device>,
        name: &str,
        source: &str,
        stage: ShaderStage,
        includes: &[IncludeFile],
    ) -> VkResult<Self> {
        let words = compile_glsl(name, source, stage, includes)?;
        Self::from_spirv(device, name, &words, stage)
    }

    /// Creates a module from SPIR-V `words` (from [`compile_glsl`]).
    pub fn from_spirv(
        device: &Arc<Device>,
        name: &str,
        words: &[u32],
        stage: ShaderStage,
    ) -> VkResult<Self> {
        let info = vk::ShaderModuleCreateInfo::default().code(words);
        // SAFETY: words is SPIR-V from shaderc; info lives until the call returns.
        let raw = unsafe { device.raw.create_shader_module(&info, None) }
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
        unsafe { self.device.raw.destroy_shader_module(self.raw, None) };
    }
}
