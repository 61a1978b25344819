//! The scene kept on the GPU and updated from the scene tree's changes: world matrices (one
//! slot per tree node, translations split into high and low f32 parts) and materials live in storage
//! buffers; each frame only the changed matrices are gathered into a compact buffer and
//! scattered into place by `scatter.comp`, and only changed materials are copied. The draw
//! list is grouped by geometry and material and updated per changed instance in O(1) (never
//! re-sorted); matrix edits do not touch it.

use std::sync::Arc;

use ash::vk;
use glam::DVec3;

use super::arena::GeometryArena;
use super::draw_list::DrawBuckets;
use super::pipeline::{DescriptorSets, DrawIndices, MaterialParameters, MatrixUpdate, Pipelines};
use crate::graph::SceneGraph;
use crate::scene::Part;
use crate::tree::{SceneTree, TreeChanges};
use crate::vk::{Buffer, Device, MemoryLocation, VkResult};

/// One draw of the resident technique.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ResidentDraw {
    /// Geometry slot.
    pub geometry: u32,
    /// First index of the part.
    pub first_index: u32,
    /// Index count of the part.
    pub index_count: u32,
    /// Indices pushed with the draw.
    pub indices: DrawIndices,
}

/// What the last [`ResidentScene::sync`] will upload.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UploadStats {
    /// Matrices in the compact upload.
    pub matrices: u64,
    /// Materials copied.
    pub materials: u64,
    /// Bytes written to upload buffers (matrices with their slots, materials, geometry).
    pub bytes: u64,
    /// Draw list entries added, removed or changed (each O(1); the list is never re-sorted).
    pub draws_updated: u64,
}

/// The GPU-resident scene.
pub struct ResidentScene {
    device: Arc<Device>,
    arena: GeometryArena,
    /// The parts of each geometry slot (the draws read their index ranges).
    geometry_parts: Vec<Option<Vec<Part>>>,
    matrices: Buffer,
    translation_lows: Buffer,
    matrix_capacity: u32,
    materials: Buffer,
    material_capacity: u32,
    updates: Buffer,
    update_capacity: u32,
    material_staging: Buffer,
    sets: DescriptorSets,
    draws: DrawBuckets<ResidentDraw>,
    pending_matrices: Vec<MatrixUpdate>,
    pending_materials: Vec<(u32, MaterialParameters)>,
    last_upload: UploadStats,
}

const MATRIX_BYTES: u64 = 64;
const MATERIAL_BYTES: u64 = std::mem::size_of::<MaterialParameters>() as u64;
const UPDATE_BYTES: u64 = std::mem::size_of::<MatrixUpdate>() as u64;

fn storage(
    device: &Arc<Device>,
    name: &str,
    size: u64,
    location: MemoryLocation,
    extra: vk::BufferUsageFlags,
) -> VkResult<Buffer> {
    Buffer::new(
        device,
        name,
        size,
        vk::BufferUsageFlags::STORAGE_BUFFER | extra,
        location,
    )
}

impl ResidentScene {
    /// Puts the tree's scene on the GPU.
    pub fn new(
        device: &Arc<Device>,
        pipelines: &Pipelines,
        graph: &SceneGraph,
        tree: &mut SceneTree,
    ) -> VkResult<Self> {
        let placeholder = |name: &str| {
            storage(
                device,
                name,
                64,
                MemoryLocation::GpuOnly,
                vk::BufferUsageFlags::TRANSFER_DST,
            )
        };
        let sets = DescriptorSets::new(
            device,
            "resident scene",
            &[pipelines.resident_set_layout, pipelines.scatter_set_layout],
            &[vk::DescriptorPoolSize::default()
                .ty(vk::DescriptorType::STORAGE_BUFFER)
                .descriptor_count(6)],
        )?;
        let mut scene = Self {
            device: Arc::clone(device),
            arena: GeometryArena::upload(device, std::iter::empty())?,
            geometry_parts: Vec::new(),
            matrices: placeholder("resident matrices")?,
            translation_lows: placeholder("translation lows")?,
            matrix_capacity: 0,
            materials: placeholder("resident materials")?,
            material_capacity: 0,
            updates: placeholder("matrix updates")?,
            update_capacity: 0,
            material_staging: placeholder("material staging")?,
            sets,
            draws: DrawBuckets::default(),
            pending_matrices: Vec::new(),
            pending_materials: Vec::new(),
            last_upload: UploadStats::default(),
        };
        scene.upload_geometries(graph)?;
        tree.take_changes();
        scene.grow_matrices(tree)?;
        scene.grow_materials(graph)?;
        scene.rebuild_draws(tree);
        scene.last_upload.draws_updated = scene.draws.len() as u64;
        Ok(scene)
    }

    /// The draws, grouped by geometry and material.
    pub fn draws(&self) -> impl Iterator<Item = &ResidentDraw> {
        self.draws.iter()
    }

    /// Number of draws.
    pub fn draw_count(&self) -> usize {
        self.draws.len()
    }

    /// What the last sync prepared for upload.
    pub fn last_upload(&self) -> UploadStats {
        self.last_upload
    }

    fn upload_geometries(&mut self, graph: &SceneGraph) -> VkResult<()> {
        let (_, geometry_slots, _) = graph.capacities();
        let slots = || (0..geometry_slots as u32).map(|slot| graph.geometry_at(slot));
        self.arena = GeometryArena::upload(&self.device, slots())?;
        self.geometry_parts = slots().map(|g| g.map(|g| g.parts.clone())).collect();
        self.last_upload.bytes += self.arena.bytes();
        Ok(())
    }

    /// Writes a replaced geometry into its own place in the arenas when it fits; returns
    /// `false` when it does not (or the slot is new), so the arenas must be laid out again.
    fn replace_geometry_in_place(&mut self, graph: &SceneGraph, slot: u32) -> VkResult<bool> {
        let Some(geometry) = graph.geometry_at(slot) else {
            return Ok(false);
        };
        let Some(written) = self.arena.write_in_place(slot, geometry)? else {
            return Ok(false);
        };
        if let Some(parts) = self.geometry_parts.get_mut(slot as usize) {
            *parts = Some(geometry.parts.clone());
        }
        self.last_upload.bytes += written;
        Ok(true)
    }

    /// Queues the matrix of slot `t`: rotation and scale in f32, the translation split into an
    /// f32 high part and the f32 remainder (see `split_f64`).
    fn queue_matrix(&mut self, tree: &SceneTree, t: u32) {
        let world = tree.world(t);
        let (high, low) = split_f64(world.w_axis.truncate());
        let mut matrix = world.as_mat4().to_cols_array_2d();
        matrix[3] = [high[0], high[1], high[2], 1.0];
        self.pending_matrices.push(MatrixUpdate {
            slot: t,
            padding: [0; 3],
            matrix,
            translation_low: [low[0], low[1], low[2], 0.0],
        });
    }

    /// Makes room for every matrix slot of the tree; after growing, every matrix is uploaded.
    fn grow_matrices(&mut self, tree: &SceneTree) -> VkResult<bool> {
        let needed = tree.node_capacity().max(1) as u32;
        if needed <= self.matrix_capacity {
            return Ok(false);
        }
        self.matrix_capacity = needed.next_power_of_two().max(64);
        self.matrices = storage(
            &self.device,
            "resident matrices",
            u64::from(self.matrix_capacity) * MATRIX_BYTES,
            MemoryLocation::GpuOnly,
            vk::BufferUsageFlags::TRANSFER_DST,
        )?;
        self.translation_lows = storage(
            &self.device,
            "translation lows",
            u64::from(self.matrix_capacity) * 16,
            MemoryLocation::GpuOnly,
            vk::BufferUsageFlags::TRANSFER_DST,
        )?;
        self.write_sets();
        self.pending_matrices.clear();
        let slots: Vec<u32> = tree
            .instances()
            .filter_map(|i| tree.instance(i))
            .map(|i| i.tree_node)
            .collect();
        let mut queued = crate::tree::BitSet::default();
        for t in slots {
            if !queued.contains(t) {
                queued.insert(t);
                self.queue_matrix(tree, t);
            }
        }
        Ok(true)
    }

    fn grow_materials(&mut self, graph: &SceneGraph) -> VkResult<bool> {
        let (_, _, material_slots) = graph.capacities();
        let needed = material_slots.max(1) as u32;
        if needed <= self.material_capacity {
            return Ok(false);
        }
        self.material_capacity = needed.next_power_of_two().max(16);
        self.materials = storage(
            &self.device,
            "resident materials",
            u64::from(self.material_capacity) * MATERIAL_BYTES,
            MemoryLocation::GpuOnly,
            vk::BufferUsageFlags::TRANSFER_DST,
        )?;
        self.write_sets();
        self.pending_materials = (0..material_slots as u32)
            .filter_map(|slot| Some((slot, material_parameters(graph, slot)?)))
            .collect();
        Ok(true)
    }

    fn write_sets(&self) {
        let ssbo = vk::DescriptorType::STORAGE_BUFFER;
        let whole = vk::WHOLE_SIZE;
        for (binding, buffer) in [&self.matrices, &self.materials, &self.translation_lows]
            .into_iter()
            .enumerate()
        {
            self.sets
                .write_buffer(0, binding as u32, ssbo, buffer.raw(), whole);
        }
        for (binding, buffer) in [&self.updates, &self.matrices, &self.translation_lows]
            .into_iter()
            .enumerate()
        {
            self.sets
                .write_buffer(1, binding as u32, ssbo, buffer.raw(), whole);
        }
    }

    /// The draw of an instance, if it is visible and its part has triangles.
    fn draw_for(&self, tree: &SceneTree, id: u32) -> Option<ResidentDraw> {
        let instance = tree.instance(id).filter(|i| i.visible)?;
        let part = self
            .geometry_parts
            .get(instance.geometry as usize)?
            .as_ref()?
            .get(instance.part as usize)?;
        (part.index_count > 0).then_some(ResidentDraw {
            geometry: instance.geometry,
            first_index: part.first_index,
            index_count: part.index_count,
            indices: DrawIndices {
                matrix: instance.tree_node,
                material: instance.material,
                flags: if instance.highlighted {
                    DrawIndices::HIGHLIGHTED
                } else {
                    0
                } | if instance.pickable {
                    DrawIndices::PICKABLE
                } else {
                    0
                },
                instance: id,
            },
        })
    }

    /// Sets (or removes) the draw of instance `id` from the tree's current state.
    fn refresh_draw(&mut self, tree: &SceneTree, id: u32) {
        match self.draw_for(tree, id) {
            Some(draw) => self
                .draws
                .insert(id, (draw.geometry, draw.indices.material), draw),
            None => self.draws.remove(id),
        }
    }

    fn rebuild_draws(&mut self, tree: &SceneTree) {
        self.draws.clear();
        for id in tree.instances() {
            self.refresh_draw(tree, id);
        }
    }

    /// Applies the tree's changes since the last sync: queues the changed matrices and
    /// materials for upload and rebuilds the draw list if instances changed.
    pub fn sync(&mut self, graph: &SceneGraph, tree: &mut SceneTree) -> VkResult<()> {
        let changes = tree.take_changes();
        self.last_upload = UploadStats::default();
        let mut arenas_rebuilt = false;
        for &slot in &changes.dirty_geometries {
            if !self.replace_geometry_in_place(graph, slot)? {
                // Grown past its room (or new): lay the arenas out again.
                self.upload_geometries(graph)?;
                arenas_rebuilt = true;
                break;
            }
        }
        if !self.grow_matrices(tree)? {
            for t in uploaded_matrix_slots(tree, &changes) {
                self.queue_matrix(tree, t);
            }
        }
        if !self.grow_materials(graph)? {
            for &slot in &changes.dirty_materials {
                if let Some(parameters) = material_parameters(graph, slot) {
                    self.pending_materials.push((slot, parameters));
                }
            }
        }
        if arenas_rebuilt {
            self.rebuild_draws(tree);
            self.last_upload.draws_updated = self.draws.len() as u64;
        } else {
            // Removed ids first: an id may be reused by an added instance.
            for &id in &changes.removed {
                self.draws.remove(id);
            }
            let touched = changes
                .added
                .iter()
                .chain(&changes.changed)
                .chain(&changes.visibility_changed);
            for &id in touched {
                self.refresh_draw(tree, id);
            }
            self.last_upload.draws_updated = (changes.removed.len()
                + changes.added.len()
                + changes.changed.len()
                + changes.visibility_changed.len())
                as u64;
        }
        Ok(())
    }

    /// Records the pending uploads (before the render pass) and clears them. Returns the bytes
    /// uploaded.
    pub fn record_uploads(
        &mut self,
        pipelines: &Pipelines,
        command_buffer: vk::CommandBuffer,
    ) -> VkResult<u64> {
        let device = Arc::clone(&self.device);
        let raw = device.raw();
        let mut bytes = 0;
        let mut barriers = Vec::new();
        if !self.pending_materials.is_empty() {
            let parameters: Vec<MaterialParameters> =
                self.pending_materials.iter().map(|&(_, p)| p).collect();
            let data: &[u8] = bytemuck::cast_slice(&parameters);
            if self.material_staging.size() < data.len() as u64 {
                self.material_staging = Buffer::new(
                    &self.device,
                    "material staging",
                    (data.len() as u64).next_power_of_two(),
                    vk::BufferUsageFlags::TRANSFER_SRC,
                    MemoryLocation::CpuToGpu,
                )?;
            }
            self.material_staging.write(0, data)?;
            let regions: Vec<vk::BufferCopy> = self
                .pending_materials
                .iter()
                .enumerate()
                .map(|(i, &(slot, _))| {
                    vk::BufferCopy::default()
                        .src_offset(i as u64 * MATERIAL_BYTES)
                        .dst_offset(u64::from(slot) * MATERIAL_BYTES)
                        .size(MATERIAL_BYTES)
                })
                .collect();
            // SAFETY: both buffers outlive the frame, which is waited for before the next one;
            // regions lie within both (slots < capacity).
            unsafe {
                raw.cmd_copy_buffer(
                    command_buffer,
                    self.material_staging.raw(),
                    self.materials.raw(),
                    &regions,
                )
            };
            bytes += data.len() as u64;
            self.last_upload.materials += self.pending_materials.len() as u64;
            self.pending_materials.clear();
            barriers.push((
                vk::PipelineStageFlags2::COPY,
                vk::AccessFlags2::TRANSFER_WRITE,
            ));
        }
        if !self.pending_matrices.is_empty() {
            let count = self.pending_matrices.len() as u32;
            if count > self.update_capacity {
                self.update_capacity = count.next_power_of_two().max(64);
                self.updates = storage(
                    &self.device,
                    "matrix updates",
                    u64::from(self.update_capacity) * UPDATE_BYTES,
                    MemoryLocation::CpuToGpu,
                    vk::BufferUsageFlags::empty(),
                )?;
                self.write_sets();
            }
            let data: &[u8] = bytemuck::cast_slice(&self.pending_matrices);
            self.updates.write(0, data)?;
            let scatter = pipelines.scatter()?;
            // SAFETY: the set points at live buffers; the dispatch covers `count` updates.
            unsafe {
                raw.cmd_bind_pipeline(command_buffer, vk::PipelineBindPoint::COMPUTE, scatter);
                raw.cmd_bind_descriptor_sets(
                    command_buffer,
                    vk::PipelineBindPoint::COMPUTE,
                    pipelines.scatter_layout,
                    0,
                    &[self.sets.sets[1]],
                    &[],
                );
                raw.cmd_push_constants(
                    command_buffer,
                    pipelines.scatter_layout,
                    vk::ShaderStageFlags::COMPUTE,
                    0,
                    &count.to_le_bytes(),
                );
                raw.cmd_dispatch(command_buffer, count.div_ceil(64), 1, 1);
            }
            bytes += data.len() as u64;
            self.last_upload.matrices += u64::from(count);
            self.pending_matrices.clear();
            barriers.push((
                vk::PipelineStageFlags2::COMPUTE_SHADER,
                vk::AccessFlags2::SHADER_STORAGE_WRITE,
            ));
        }
        if !barriers.is_empty() {
            let memory: Vec<vk::MemoryBarrier2> = barriers
                .iter()
                .map(|&(stage, access)| {
                    vk::MemoryBarrier2::default()
                        .src_stage_mask(stage)
                        .src_access_mask(access)
                        .dst_stage_mask(vk::PipelineStageFlags2::VERTEX_SHADER)
                        .dst_access_mask(vk::AccessFlags2::SHADER_STORAGE_READ)
                })
                .collect();
            let dependency = vk::DependencyInfo::default().memory_barriers(&memory);
            // SAFETY: recording, outside a render pass.
            unsafe { raw.cmd_pipeline_barrier2(command_buffer, &dependency) };
        }
        self.last_upload.bytes += bytes;
        Ok(bytes)
    }

    /// The set with the matrix and material buffers (set 1 of the resident pipeline).
    pub fn parameter_set(&self) -> vk::DescriptorSet {
        self.sets.sets[0]
    }

    /// The geometry arena the draws read.
    pub fn arena(&self) -> &GeometryArena {
        &self.arena
    }
}

/// The matrix slots a resident scene uploads for `changes`: dirty paths that carry instances
/// (only those have a matrix on the GPU).
pub fn uploaded_matrix_slots<'a>(
    tree: &'a SceneTree,
    changes: &'a TreeChanges,
) -> impl Iterator<Item = u32> + 'a {
    changes
        .dirty_matrices
        .iter()
        .copied()
        .filter(|&t| tree.has_instances(t))
}

/// Bytes one uploaded matrix costs (slot, padding, matrix, low translation).
pub const MATRIX_UPLOAD_BYTES: u64 = UPDATE_BYTES;

/// Bytes one uploaded material costs.
pub const MATERIAL_UPLOAD_BYTES: u64 = MATERIAL_BYTES;

/// Splits f64 coordinates into an f32 high part and the f32 remainder: `high + low` equals the
/// input to about 2^-48 of its size, and the shader subtracts the eye's parts separately so
/// that positions relative to the eye keep that precision on the GPU.
pub fn split_f64(v: DVec3) -> ([f32; 3], [f32; 3]) {
    let high = v.as_vec3();
    let low = (v - high.as_dvec3()).as_vec3();
    (high.to_array(), low.to_array())
}

fn material_parameters(graph: &SceneGraph, slot: u32) -> Option<MaterialParameters> {
    graph.material_at(slot).map(|m| MaterialParameters {
        base_color: m.base_color,
        surface: [m.metallic, m.roughness, 0.0, 0.0],
    })
}
