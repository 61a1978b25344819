//! What can go wrong while rendering: Vulkan failing, a shader failing to compile, a technique
//! failing or being refused, a renderer being used against its contract, or the scene's data
//! failing to be read back. Only the first is a Vulkan error.

use crate::vk::VkError;

/// An error of the renderer, its techniques or the Vulkan layer below them.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// Vulkan failed (out of memory, device lost, a failed call…).
    #[error(transparent)]
    Vulkan(#[from] VkError),
    /// A shader (an assembled technique shader included) failed to compile.
    #[error(transparent)]
    ShaderCompile(#[from] ShaderCompileError),
    /// A technique plugin failed, or a technique (combination) cannot be used.
    #[error("technique {technique}: {message}")]
    Technique {
        /// `kind name` of the technique, or the combination.
        technique: String,
        /// What went wrong.
        message: String,
    },
    /// The renderer was used against its contract (a caller's bug, reported instead of
    /// panicking).
    #[error("invalid use: {0}")]
    InvalidUse(String),
    /// The scene's data could not be read: a geometry in the scene graph's page file (the
    /// message names the geometry and the file).
    #[error("{0}")]
    SceneData(String),
}

/// A shader that failed to compile: a renderer error (a broken source or snippet), not a
/// Vulkan one.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("shader '{name}' failed to compile:\n{log}")]
pub struct ShaderCompileError {
    /// The shader's name.
    pub name: String,
    /// The compiler's messages.
    pub log: String,
}

/// Result of the renderer and its techniques.
pub type RenderResult<T> = Result<T, RenderError>;
