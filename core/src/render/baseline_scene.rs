//! The flat scene of the built-in baseline: every geometry's vertices and indices in two
//! arenas, plus the flattened draw items, world matrices and material parameters it pushes per
//! draw. It reads a [`Scene`] directly (not the scene tree), so it also serves the tests as an
//! independent oracle for the one GPU scene's techniques.

use std::sync::Arc;

use glam::DMat4;

use super::arena::GeometryArena;
use crate::scene::{flatten, DrawItem, FlatScene, Scene, SceneError, SceneStats};
use crate::vk::{Device, VkError};

/// Why a scene could not be put on the GPU.
#[derive(Debug, thiserror::Error)]
pub enum UploadError {
    /// The scene breaks the model's rules.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// Vulkan failed (usually out of memory).
    #[error(transparent)]
    Vulkan(#[from] VkError),
}

/// The baseline's copy of a scene.
pub struct BaselineScene {
    /// Every geometry's vertices and indices, in scene order.
    pub arena: GeometryArena,
    /// Draw items in traversal order.
    pub draws: Vec<DrawItem>,
    /// World matrix of each instance (double precision).
    pub instance_worlds: Vec<DMat4>,
    /// Per material: base colour and (metallic, roughness, 0, 0).
    pub material_parameters: Vec<[[f32; 4]; 2]>,
    /// Statistics of the scene.
    pub stats: SceneStats,
}

impl BaselineScene {
    /// Validates, flattens and uploads `scene`.
    pub fn upload(device: &Arc<Device>, scene: &Scene) -> Result<Self, UploadError> {
        let flat = flatten(scene)?;
        Self::upload_flat(device, scene, flat)
    }

    /// Uploads an already flattened scene.
    pub fn upload_flat(
        device: &Arc<Device>,
        scene: &Scene,
        flat: FlatScene,
    ) -> Result<Self, UploadError> {
        let arena = GeometryArena::upload(device, scene.geometries.iter().map(Some))?;
        let material_parameters = scene
            .materials
            .iter()
            .map(|m| [m.base_color, [m.metallic, m.roughness, 0.0, 0.0]])
            .collect();
        let stats = SceneStats::new(scene, &flat);
        Ok(Self {
            arena,
            instance_worlds: flat.instances.iter().map(|i| i.world).collect(),
            draws: flat.draws,
            material_parameters,
            stats,
        })
    }
}
