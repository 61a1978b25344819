//! The scene as every technique sees it ([`abi::CadrSceneView`]): geometry in shared arenas
//! (vertices, triangle indices, edge indices) usable as vertex, index and storage buffers;
//! per-instance entries and records; matrices and materials on the CPU and on the GPU. Kept in
//! step with the scene tree's changes, uploading only what changed.

use std::sync::Arc;

use ash::vk;
use ash::vk::Handle;
use cadr_plugin_abi as abi;
use glam::DMat4;

use crate::graph::SceneGraph;
use crate::render::split_f64;
use crate::scene::edges::{feature_edges, DEFAULT_CREASE_DEGREES};
use crate::scene::Vertex;
use crate::tree::SceneTree;
use crate::vk::{Buffer, Device, MemoryLocation, VkResult};

#[derive(Clone, Debug)]
struct GeometryPlace {
    vertex_base: u32,
    first_index: u32,
    first_wire_index: u32,
    /// Per part: first index, count, first wire index, wire count (relative), sphere.
    parts: Vec<([u32; 4], [f32; 4])>,
}

/// A GPU array with a CPU mirror's length.
struct GpuArray {
    buffer: Buffer,
    capacity: usize,
}

/// The technique scene.
pub struct TechniqueScene {
    device: Arc<Device>,
    vertices: Buffer,
    indices: Buffer,
    wire_indices: Buffer,
    places: Vec<Option<GeometryPlace>>,
    instances: Vec<abi::CadrInstance>,
    records: Vec<abi::CadrInstanceRecord>,
    candidate_bits: Vec<u64>,
    culled_bits: Vec<u64>,
    drawn_bits: Vec<u64>,
    matrices: Vec<abi::CadrMatrix>,
    worlds: Vec<[f64; 16]>,
    materials: Vec<abi::CadrMaterial>,
    matrix_gpu: GpuArray,
    material_gpu: GpuArray,
    record_gpu: GpuArray,
    staging: Option<Buffer>,
    pending_matrices: Vec<u32>,
    pending_materials: Vec<u32>,
    pending_records: Vec<u32>,
    frame_dirty_matrices: Vec<u32>,
    frame_dirty_materials: Vec<u32>,
    draws_generation: u64,
    parameters_generation: u64,
    buffers_generation: u64,
    triangles: u64,
    /// The buffers as techniques see them (with device addresses), refreshed when replaced.
    buffer_refs: [abi::CadrBufferRef; 6],
}

fn usage(device: &Device, base: vk::BufferUsageFlags) -> vk::BufferUsageFlags {
    let mut usage =
        base | vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
    if device.capabilities().buffer_device_address {
        usage |= vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS;
    }
    usage
}

fn part_sphere(vertices: &[Vertex], indices: &[u32]) -> [f32; 4] {
    let mut min = [f32::INFINITY; 3];
    let mut max = [f32::NEG_INFINITY; 3];
    for &i in indices {
        if let Some(v) = vertices.get(i as usize) {
            for axis in 0..3 {
                min[axis] = min[axis].min(v.position[axis]);
                max[axis] = max[axis].max(v.position[axis]);
            }
        }
    }
    if min[0] > max[0] {
        return [0.0; 4];
    }
    let center = [0, 1, 2].map(|a| 0.5 * (min[a] + max[a]));
    let radius = indices
        .iter()
        .filter_map(|&i| vertices.get(i as usize))
        .map(|v| {
            let d = [0, 1, 2].map(|a| v.position[a] - center[a]);
            (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
        })
        .fold(0.0_f32, f32::max);
    [center[0], center[1], center[2], radius * (1.0 + 1e-5)]
}

fn matrix_of(world: &DMat4) -> abi::CadrMatrix {
    let (high, low) = split_f64(world.w_axis.truncate());
    let mut columns = world.as_mat4().to_cols_array_2d();
    for axis in 0..3 {
        columns[axis][3] = low[axis];
    }
    columns[3] = [high[0], high[1], high[2], 1.0];
    abi::CadrMatrix { columns }
}

/// The first generation of the next technique scene (each scene counts within its own 2^32).
static NEXT_GENERATIONS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

impl TechniqueScene {
    /// Puts the tree's scene on the GPU.
    pub fn new(device: &Arc<Device>, graph: &SceneGraph, tree: &mut SceneTree) -> VkResult<Self> {
        // Generations are unique across scenes: techniques that cached a previous scene's
        // buffers or commands see that this one differs.
        let first_generation =
            NEXT_GENERATIONS.fetch_add(1 << 32, std::sync::atomic::Ordering::Relaxed);
        let empty = |name: &str| {
            Buffer::new(
                device,
                name,
                64,
                usage(device, vk::BufferUsageFlags::empty()),
                MemoryLocation::GpuOnly,
            )
        };
        let mut scene = Self {
            device: Arc::clone(device),
            vertices: empty("technique vertices")?,
            indices: empty("technique indices")?,
            wire_indices: empty("technique wire indices")?,
            places: Vec::new(),
            instances: Vec::new(),
            records: Vec::new(),
            candidate_bits: Vec::new(),
            culled_bits: Vec::new(),
            drawn_bits: Vec::new(),
            matrices: Vec::new(),
            worlds: Vec::new(),
            materials: Vec::new(),
            matrix_gpu: GpuArray {
                buffer: empty("technique matrices")?,
                capacity: 0,
            },
            material_gpu: GpuArray {
                buffer: empty("technique materials")?,
                capacity: 0,
            },
            record_gpu: GpuArray {
                buffer: empty("technique instance records")?,
                capacity: 0,
            },
            staging: None,
            pending_matrices: Vec::new(),
            pending_materials: Vec::new(),
            pending_records: Vec::new(),
            frame_dirty_matrices: Vec::new(),
            frame_dirty_materials: Vec::new(),
            draws_generation: first_generation,
            parameters_generation: first_generation,
            buffers_generation: first_generation,
            triangles: 0,
            buffer_refs: Default::default(),
        };
        tree.take_changes();
        scene.upload_geometries(graph)?;
        scene.refresh_all(graph, tree)?;
        Ok(scene)
    }

    fn upload_geometries(&mut self, graph: &SceneGraph) -> VkResult<()> {
        let (_, geometry_slots, _) = graph.capacities();
        let mut vertices: Vec<Vertex> = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        let mut wire: Vec<u32> = Vec::new();
        self.places = (0..geometry_slots as u32)
            .map(|slot| {
                let geometry = graph.geometry_at(slot)?;
                let derived;
                let (wire_indices, parts) = if geometry.wire_indices.is_empty() {
                    derived = feature_edges(geometry, DEFAULT_CREASE_DEGREES);
                    (&derived.0, &derived.1)
                } else {
                    (&geometry.wire_indices, &geometry.parts)
                };
                let place = GeometryPlace {
                    vertex_base: vertices.len() as u32,
                    first_index: indices.len() as u32,
                    first_wire_index: wire.len() as u32,
                    parts: parts
                        .iter()
                        .map(|p| {
                            let start = (p.first_index as usize).min(geometry.indices.len());
                            let end = (start + p.index_count as usize).min(geometry.indices.len());
                            (
                                [
                                    p.first_index,
                                    p.index_count,
                                    p.first_wire_index,
                                    p.wire_index_count,
                                ],
                                part_sphere(&geometry.vertices, &geometry.indices[start..end]),
                            )
                        })
                        .collect(),
                };
                vertices.extend_from_slice(&geometry.vertices);
                indices.extend_from_slice(&geometry.indices);
                wire.extend_from_slice(wire_indices);
                Some(place)
            })
            .collect();
        let device = &self.device;
        let upload = |name: &str, data: &[u8], base: vk::BufferUsageFlags| {
            let bytes: &[u8] = if data.is_empty() { &[0; 16] } else { data };
            Buffer::with_data(device, name, bytes, usage(device, base))
        };
        self.vertices = upload(
            "technique vertices",
            bytemuck::cast_slice(&vertices),
            vk::BufferUsageFlags::VERTEX_BUFFER,
        )?;
        self.indices = upload(
            "technique indices",
            bytemuck::cast_slice(&indices),
            vk::BufferUsageFlags::INDEX_BUFFER,
        )?;
        self.wire_indices = upload(
            "technique wire indices",
            bytemuck::cast_slice(&wire),
            vk::BufferUsageFlags::INDEX_BUFFER,
        )?;
        self.buffers_generation += 1;
        self.refresh_buffer_refs();
        Ok(())
    }

    fn refresh_buffer_refs(&mut self) {
        let with_address = self.device.capabilities().buffer_device_address;
        self.buffer_refs = [
            &self.vertices,
            &self.indices,
            &self.wire_indices,
            &self.matrix_gpu.buffer,
            &self.material_gpu.buffer,
            &self.record_gpu.buffer,
        ]
        .map(|buffer| abi::CadrBufferRef {
            buffer: buffer.raw().as_raw(),
            size_bytes: buffer.size(),
            address: if with_address {
                buffer.device_address()
            } else {
                0
            },
        });
    }

    /// Grows a GPU array to hold `count` items of `item` bytes; true when it was replaced.
    fn ensure(
        device: &Arc<Device>,
        array: &mut GpuArray,
        count: usize,
        item: usize,
        name: &str,
    ) -> VkResult<bool> {
        if count <= array.capacity && array.capacity > 0 {
            return Ok(false);
        }
        let capacity = count.next_power_of_two().max(64);
        array.buffer = Buffer::new(
            device,
            name,
            (capacity * item) as u64,
            usage(device, vk::BufferUsageFlags::empty()),
            MemoryLocation::GpuOnly,
        )?;
        array.capacity = capacity;
        Ok(true)
    }

    /// Rebuilds every entry from the tree and graph and queues everything for upload.
    fn refresh_all(&mut self, graph: &SceneGraph, tree: &SceneTree) -> VkResult<()> {
        let nodes = tree.node_capacity();
        self.worlds = vec![[0.0; 16]; nodes];
        self.matrices = vec![abi::CadrMatrix::default(); nodes];
        for t in 0..nodes as u32 {
            if tree.has_instances(t) {
                self.set_matrix(tree, t);
            }
        }
        let (_, _, material_slots) = graph.capacities();
        self.materials = (0..material_slots as u32)
            .map(|slot| material_of(graph, slot))
            .collect();
        let count = tree.instance_capacity();
        self.instances = vec![abi::CadrInstance::default(); count];
        self.records = vec![abi::CadrInstanceRecord::default(); count];
        let words = count.div_ceil(64);
        self.candidate_bits = vec![0; words];
        self.drawn_bits = vec![0; words];
        self.culled_bits = vec![u64::MAX; words];
        self.triangles = 0;
        for id in 0..count as u32 {
            self.refresh_instance(tree, id);
        }
        let device = Arc::clone(&self.device);
        Self::ensure(
            &device,
            &mut self.matrix_gpu,
            nodes.max(1),
            64,
            "technique matrices",
        )?;
        Self::ensure(
            &device,
            &mut self.material_gpu,
            material_slots.max(1),
            32,
            "technique materials",
        )?;
        Self::ensure(
            &device,
            &mut self.record_gpu,
            count.max(1),
            16,
            "technique instance records",
        )?;
        self.pending_matrices = (0..nodes as u32)
            .filter(|&t| tree.has_instances(t))
            .collect();
        self.pending_materials = (0..material_slots as u32).collect();
        self.pending_records = (0..count as u32).collect();
        self.frame_dirty_matrices = self.pending_matrices.clone();
        self.frame_dirty_materials = self.pending_materials.clone();
        self.buffers_generation += 1;
        self.draws_generation += 1;
        self.parameters_generation += 1;
        self.refresh_buffer_refs();
        Ok(())
    }

    fn is_drawn(&self, id: u32) -> bool {
        self.drawn_bits[id as usize / 64] >> (id % 64) & 1 == 1
    }

    /// Sets instance `id`'s drawn bit, keeping the drawn triangle count in step.
    fn set_drawn(&mut self, id: u32, drawn: bool) {
        if self.is_drawn(id) != drawn {
            let triangles = u64::from(self.instances[id as usize].index_count / 3);
            if drawn {
                self.triangles += triangles;
            } else {
                self.triangles -= triangles;
            }
            Self::set_bit(&mut self.drawn_bits, id, drawn);
        }
    }

    fn set_matrix(&mut self, tree: &SceneTree, t: u32) {
        let world = tree.world(t);
        self.worlds[t as usize] = world.to_cols_array();
        self.matrices[t as usize] = matrix_of(&world);
    }

    fn set_bit(bits: &mut [u64], id: u32, on: bool) {
        let (word, bit) = (id as usize / 64, id % 64);
        if on {
            bits[word] |= 1 << bit;
        } else {
            bits[word] &= !(1 << bit);
        }
    }

    fn refresh_instance(&mut self, tree: &SceneTree, id: u32) {
        let found = tree.instance(id).and_then(|instance| {
            let place = self.places.get(instance.geometry as usize)?.as_ref()?;
            let ([first, count, first_wire, wire_count], sphere) =
                *place.parts.get(instance.part as usize)?;
            Some((
                instance, place, first, count, first_wire, wire_count, sphere,
            ))
        });
        let (entry, candidate) = match found {
            Some((instance, place, first, count, first_wire, wire_count, sphere)) => {
                let flags = abi::CADR_INSTANCE_ALIVE
                    | if instance.highlighted {
                        abi::CADR_INSTANCE_HIGHLIGHTED
                    } else {
                        0
                    }
                    | if instance.pickable {
                        abi::CADR_INSTANCE_PICKABLE
                    } else {
                        0
                    };
                (
                    abi::CadrInstance {
                        matrix: instance.tree_node,
                        material: instance.material,
                        geometry: instance.geometry,
                        part: instance.part,
                        flags,
                        vertex_base: place.vertex_base,
                        geometry_first_index: place.first_index,
                        geometry_first_wire_index: place.first_wire_index,
                        first_index: place.first_index + first,
                        index_count: count,
                        first_wire_index: place.first_wire_index + first_wire,
                        wire_index_count: wire_count,
                        sphere,
                    },
                    instance.visible && count > 0,
                )
            }
            None => (abi::CadrInstance::default(), false),
        };
        let i = id as usize;
        // Out of the drawn set with its old entry, back in with the new one.
        self.set_drawn(id, false);
        self.instances[i] = entry;
        self.records[i] = abi::CadrInstanceRecord {
            matrix: entry.matrix,
            material: entry.material,
            flags: entry.flags,
            instance: id,
        };
        Self::set_bit(&mut self.candidate_bits, id, candidate);
        let culled_in = self.culled_bits[i / 64] >> (i % 64) & 1 == 1;
        self.set_drawn(id, candidate && culled_in);
    }

    /// Applies the tree's changes since the last sync.
    pub fn sync(&mut self, graph: &SceneGraph, tree: &mut SceneTree) -> VkResult<()> {
        let changes = tree.take_changes();
        self.frame_dirty_matrices.clear();
        self.frame_dirty_materials.clear();
        if changes.is_empty() {
            return Ok(());
        }
        let grown = tree.node_capacity() > self.matrices.len()
            || tree.instance_capacity() > self.instances.len()
            || graph.capacities().2 > self.materials.len();
        if !changes.dirty_geometries.is_empty() || grown {
            if !changes.dirty_geometries.is_empty() {
                self.upload_geometries(graph)?;
            }
            return self.refresh_all(graph, tree);
        }
        for &t in &changes.dirty_matrices {
            if tree.has_instances(t) {
                self.set_matrix(tree, t);
                self.pending_matrices.push(t);
                self.frame_dirty_matrices.push(t);
            }
        }
        for &slot in &changes.dirty_materials {
            if (slot as usize) < self.materials.len() {
                self.materials[slot as usize] = material_of(graph, slot);
                self.pending_materials.push(slot);
                self.frame_dirty_materials.push(slot);
            }
        }
        if !changes.dirty_matrices.is_empty() || !changes.dirty_materials.is_empty() {
            self.parameters_generation += 1;
        }
        let touched: Vec<u32> = changes
            .removed
            .iter()
            .chain(&changes.added)
            .chain(&changes.changed)
            .chain(&changes.visibility_changed)
            .copied()
            .collect();
        for &id in &touched {
            self.refresh_instance(tree, id);
            self.pending_records.push(id);
        }
        if !touched.is_empty() {
            self.draws_generation += 1;
        }
        Ok(())
    }

    /// Applies culling's result: `visible` bits and the bits that `changed` since last frame;
    /// only changed ids are touched.
    pub(crate) fn apply_culling(&mut self, visible: &[u64], changed: &[u64]) {
        let mut any = false;
        for (word, &bits) in changed.iter().enumerate() {
            let mut bits = bits;
            while bits != 0 {
                let bit = bits.trailing_zeros();
                bits &= bits - 1;
                let id = word as u32 * 64 + bit;
                if id as usize >= self.instances.len() {
                    continue;
                }
                let on = visible.get(word).is_some_and(|w| w >> bit & 1 == 1);
                Self::set_bit(&mut self.culled_bits, id, on);
                let candidate = self.candidate_bits[word] >> bit & 1 == 1;
                self.set_drawn(id, candidate && on);
                any = true;
            }
        }
        if any {
            self.draws_generation += 1;
        }
    }

    /// Records the pending uploads (before the pass) and clears them.
    pub(crate) fn record_uploads(&mut self, command_buffer: vk::CommandBuffer) -> VkResult<u64> {
        let mut data: Vec<u8> = Vec::new();
        let mut copies: Vec<(vk::Buffer, vk::BufferCopy)> = Vec::new();
        let mut queue = |data: &mut Vec<u8>, target: vk::Buffer, offset: u64, bytes: &[u8]| {
            copies.push((
                target,
                vk::BufferCopy {
                    src_offset: data.len() as u64,
                    dst_offset: offset,
                    size: bytes.len() as u64,
                },
            ));
            data.extend_from_slice(bytes);
        };
        for &t in &self.pending_matrices {
            let bytes = self.matrices[t as usize].to_le_bytes();
            queue(
                &mut data,
                self.matrix_gpu.buffer.raw(),
                u64::from(t) * 64,
                &bytes,
            );
        }
        for &m in &self.pending_materials {
            let bytes = self.materials[m as usize].to_le_bytes();
            queue(
                &mut data,
                self.material_gpu.buffer.raw(),
                u64::from(m) * 32,
                &bytes,
            );
        }
        for &id in &self.pending_records {
            let bytes = self.records[id as usize].to_le_bytes();
            queue(
                &mut data,
                self.record_gpu.buffer.raw(),
                u64::from(id) * 16,
                &bytes,
            );
        }
        self.pending_matrices.clear();
        self.pending_materials.clear();
        self.pending_records.clear();
        if data.is_empty() {
            return Ok(0);
        }
        let needed = data.len() as u64;
        if self.staging.as_ref().is_none_or(|s| s.size() < needed) {
            self.staging = Some(Buffer::new(
                &self.device,
                "technique staging",
                needed.next_power_of_two(),
                vk::BufferUsageFlags::TRANSFER_SRC,
                MemoryLocation::CpuToGpu,
            )?);
        }
        let Some(staging) = self.staging.as_mut() else {
            return Ok(0);
        };
        staging.write(0, &data)?;
        let raw = self.device.raw();
        copies.sort_by_key(|(target, _)| target.as_raw());
        for chunk in copies.chunk_by(|a, b| a.0 == b.0) {
            let regions: Vec<vk::BufferCopy> = chunk.iter().map(|(_, c)| *c).collect();
            // SAFETY: the staging and target buffers outlive the frame (waited for); every
            // region lies inside both (slots are below the arrays' capacities).
            unsafe { raw.cmd_copy_buffer(command_buffer, staging.raw(), chunk[0].0, &regions) };
        }
        Ok(needed)
    }

    /// The view techniques read this frame. Valid while `self` is not changed.
    pub(crate) fn view(&self) -> abi::CadrSceneView {
        let [vertex_buffer, index_buffer, wire_index_buffer, matrix_buffer, material_buffer, instance_buffer] =
            self.buffer_refs;
        abi::CadrSceneView {
            size: std::mem::size_of::<abi::CadrSceneView>() as u32,
            instance_count: self.instances.len() as u32,
            instances: self.instances.as_ptr(),
            drawn_bits: self.drawn_bits.as_ptr(),
            draws_generation: self.draws_generation,
            parameters_generation: self.parameters_generation,
            matrix_count: self.matrices.len() as u32,
            matrices: self.matrices.as_ptr(),
            material_count: self.materials.len() as u32,
            materials: self.materials.as_ptr(),
            dirty_matrices: self.frame_dirty_matrices.as_ptr(),
            dirty_matrix_count: self.frame_dirty_matrices.len() as u32,
            dirty_materials: self.frame_dirty_materials.as_ptr(),
            dirty_material_count: self.frame_dirty_materials.len() as u32,
            buffers_generation: self.buffers_generation,
            vertex_buffer,
            vertex_stride: std::mem::size_of::<Vertex>() as u32,
            index_buffer,
            wire_index_buffer,
            matrix_buffer,
            material_buffer,
            instance_buffer,
        }
    }

    /// Culling's bits as last applied.
    pub(crate) fn culled_bits(&self) -> &[u64] {
        &self.culled_bits
    }

    /// Candidate bits (alive, visible, with triangles) for culling.
    pub(crate) fn candidate_bits(&self) -> &[u64] {
        &self.candidate_bits
    }

    /// World matrices (f64) per matrix slot.
    pub(crate) fn worlds(&self) -> &[[f64; 16]] {
        &self.worlds
    }

    /// Instances drawn this frame.
    pub fn drawn_count(&self) -> usize {
        self.drawn_bits
            .iter()
            .map(|w| w.count_ones() as usize)
            .sum()
    }

    /// Triangles of the drawn instances.
    pub fn drawn_triangles(&self) -> u64 {
        self.triangles
    }

    /// Instance ids in use are below this.
    pub fn instance_capacity(&self) -> usize {
        self.instances.len()
    }
}

fn material_of(graph: &SceneGraph, slot: u32) -> abi::CadrMaterial {
    graph
        .material_at(slot)
        .map(|m| abi::CadrMaterial {
            base_color: m.base_color,
            surface: [m.metallic, m.roughness, 0.0, 0.0],
        })
        .unwrap_or_default()
}
