//! Every geometry's vertices and indices in two device-local buffers (the arenas), with each
//! geometry's place in them. Both the baseline and the resident scene draw from one; a geometry
//! is bound by offsetting the arenas, so drawing needs no per-geometry buffers.

use std::sync::Arc;

use ash::vk;

use crate::scene::Geometry;
use crate::vk::{Buffer, Device, VkResult};

/// Where one geometry lies in the arenas, and how much room it has there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GeometryRange {
    /// Byte offset of its first vertex in the vertex arena.
    pub vertex_offset_bytes: u64,
    /// Byte offset of its first index in the index arena.
    pub index_offset_bytes: u64,
    /// Bytes of vertices it may occupy (its size when the arenas were laid out).
    pub vertex_capacity_bytes: u64,
    /// Bytes of indices it may occupy.
    pub index_capacity_bytes: u64,
}

/// The vertex and index arenas and the place of each geometry slot in them.
pub struct GeometryArena {
    vertices: Buffer,
    indices: Buffer,
    ranges: Vec<Option<GeometryRange>>,
    bytes: u64,
}

impl GeometryArena {
    /// Lays out and uploads `geometries`, one per slot (`None` for an empty slot).
    pub fn upload<'g>(
        device: &Arc<Device>,
        geometries: impl IntoIterator<Item = Option<&'g Geometry>>,
    ) -> VkResult<Self> {
        let mut vertices: Vec<u8> = Vec::new();
        let mut indices: Vec<u8> = Vec::new();
        let ranges = geometries
            .into_iter()
            .map(|slot| {
                slot.map(|g| {
                    let vertex_bytes: &[u8] = bytemuck::cast_slice(&g.vertices);
                    let index_bytes: &[u8] = bytemuck::cast_slice(&g.indices);
                    let range = GeometryRange {
                        vertex_offset_bytes: vertices.len() as u64,
                        index_offset_bytes: indices.len() as u64,
                        vertex_capacity_bytes: vertex_bytes.len() as u64,
                        index_capacity_bytes: index_bytes.len() as u64,
                    };
                    vertices.extend_from_slice(vertex_bytes);
                    indices.extend_from_slice(index_bytes);
                    range
                })
            })
            .collect();
        let bytes = (vertices.len() + indices.len()) as u64;
        Ok(Self {
            vertices: Buffer::with_data(
                device,
                "vertex arena",
                &vertices,
                vk::BufferUsageFlags::VERTEX_BUFFER,
            )?,
            indices: Buffer::with_data(
                device,
                "index arena",
                &indices,
                vk::BufferUsageFlags::INDEX_BUFFER,
            )?,
            ranges,
            bytes,
        })
    }

    /// Bytes uploaded when the arenas were laid out.
    pub fn bytes(&self) -> u64 {
        self.bytes
    }

    /// The place of geometry slot `slot`, if it holds one.
    pub fn range(&self, slot: u32) -> Option<GeometryRange> {
        self.ranges.get(slot as usize).copied().flatten()
    }

    /// Writes `geometry` over slot `slot` when it fits in the room the slot has; returns the
    /// bytes written, or `None` when it does not fit (the arenas must be laid out again). The
    /// caller makes sure the GPU is not drawing from the arenas meanwhile.
    pub fn write_in_place(&self, slot: u32, geometry: &Geometry) -> VkResult<Option<u64>> {
        let Some(range) = self.range(slot) else {
            return Ok(None);
        };
        let vertices: &[u8] = bytemuck::cast_slice(&geometry.vertices);
        let indices: &[u8] = bytemuck::cast_slice(&geometry.indices);
        if vertices.len() as u64 > range.vertex_capacity_bytes
            || indices.len() as u64 > range.index_capacity_bytes
        {
            return Ok(None);
        }
        self.vertices
            .upload_at(range.vertex_offset_bytes, vertices)?;
        self.indices.upload_at(range.index_offset_bytes, indices)?;
        Ok(Some((vertices.len() + indices.len()) as u64))
    }

    /// Binds geometry slot `slot`'s vertices and indices; `false` (and nothing bound) for an
    /// empty slot.
    pub(crate) fn bind(
        &self,
        device: &Device,
        command_buffer: vk::CommandBuffer,
        slot: u32,
    ) -> bool {
        let Some(range) = self.range(slot) else {
            return false;
        };
        // SAFETY: command_buffer is recording; the arenas outlive its submission (their owners
        // wait for frames before dropping them); the offsets lie within the arenas.
        unsafe {
            device.raw().cmd_bind_vertex_buffers(
                command_buffer,
                0,
                &[self.vertices.raw()],
                &[range.vertex_offset_bytes],
            );
            device.raw().cmd_bind_index_buffer(
                command_buffer,
                self.indices.raw(),
                range.index_offset_bytes,
                vk::IndexType::UINT32,
            );
        }
        true
    }
}
