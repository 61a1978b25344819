//! A scene on the GPU: every geometry's vertices and indices in two arenas, plus the flattened
//! draw items, world matrices and material parameters the techniques read.

use std::sync::Arc;

use ash::vk;
use glam::DMat4;

use crate::scene::{flatten, DrawItem, FlatScene, Scene, SceneError, SceneStats, Vertex};
use crate::vk::{Buffer, Device, VkError};

/// Where one geometry lies in the arenas.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GeometryRange {
    /// Byte offset of its first vertex in the vertex arena.
    pub vertex_offset_bytes: u64,
    /// Byte offset of its first index in the index arena.
    pub index_offset_bytes: u64,
}

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

/// The GPU copy of a scene.
pub struct GpuScene {
    /// All vertices of all geometries.
    pub vertex_arena: Buffer,
    /// All indices of all geometries.
    pub index_arena: Buffer,
    /// Per geometry, its place in the arenas.
    pub geometry_ranges: Vec<GeometryRange>,
    /// Draw items in traversal order.
    pub draws: Vec<DrawItem>,
    /// World matrix of each instance (double precision).
    pub instance_worlds: Vec<DMat4>,
    /// Per material: base colour and (metallic, roughness, 0, 0).
    pub material_parameters: Vec<[[f32; 4]; 2]>,
    /// Statistics of the scene.
    pub stats: SceneStats,
}

impl GpuScene {
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
        let vertex_bytes: usize = scene
            .geometries
            .iter()
            .map(|g| g.vertices.len() * std::mem::size_of::<Vertex>())
            .sum();
        let index_bytes: usize = scene.geometries.iter().map(|g| g.indices.len() * 4).sum();
        let mut vertices = Vec::with_capacity(vertex_bytes);
        let mut indices = Vec::with_capacity(index_bytes);
        let mut geometry_ranges = Vec::with_capacity(scene.geometries.len());
        for geometry in &scene.geometries {
            geometry_ranges.push(GeometryRange {
                vertex_offset_bytes: vertices.len() as u64,
                index_offset_bytes: indices.len() as u64,
            });
            vertices.extend_from_slice(bytemuck::cast_slice(&geometry.vertices));
            indices.extend_from_slice(bytemuck::cast_slice(&geometry.indices));
        }
        let vertex_arena = Buffer::with_data(
            device,
            "vertex arena",
            &vertices,
            vk::BufferUsageFlags::VERTEX_BUFFER,
        )?;
        let index_arena = Buffer::with_data(
            device,
            "index arena",
            &indices,
            vk::BufferUsageFlags::INDEX_BUFFER,
        )?;
        let material_parameters = scene
            .materials
            .iter()
            .map(|m| [m.base_color, [m.metallic, m.roughness, 0.0, 0.0]])
            .collect();
        let stats = SceneStats::new(scene, &flat);
        Ok(Self {
            vertex_arena,
            index_arena,
            geometry_ranges,
            instance_worlds: flat.instances.iter().map(|i| i.world).collect(),
            draws: flat.draws,
            material_parameters,
            stats,
        })
    }
}
