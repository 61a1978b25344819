//! The GPU scene's geometry: every geometry's vertices, triangle indices and edge indices in
//! three shared arenas (usable as vertex, index and storage buffers), with each geometry's place
//! and room there. A replaced geometry that fits its room is written in place: only its bytes
//! are uploaded and only its users' instance entries change. Texture coordinates and colours
//! go in a fourth arena laid out like the vertices (the same index finds a vertex's
//! attributes), made only when some geometry has them.

use std::sync::Arc;

use crate::error::RenderResult;
use crate::vk::raw as vk;

use crate::graph::SceneGraph;
use crate::scene::closure::{closure, Closure};
use crate::scene::edges::{feature_edges, DEFAULT_CREASE_DEGREES};
use crate::scene::{Geometry, Part, Vertex, VertexAttributes};
use crate::vk::{Buffer, Device};
use cadr_plugin_abi as abi;

/// Where one geometry lies in the arenas and how much room it has there.
#[derive(Clone, Debug)]
pub(super) struct GeometryPlace {
    pub(super) vertex_base: u32,
    pub(super) first_index: u32,
    pub(super) first_wire_index: u32,
    /// Vertices, indices and wire indices the place can hold (its size when laid out).
    room: [u32; 3],
    /// Per part: first index, count, first wire index, wire count (relative), bounding sphere,
    /// and its shape as instance flags (`CADR_INSTANCE_CLOSED`, `CADR_INSTANCE_INSIDE_OUT`,
    /// `CADR_INSTANCE_CURVED`).
    pub(super) parts: Vec<([u32; 4], [f32; 4], u32)>,
}

/// A geometry's data as the arenas hold it: edge indices derived by crease angle when the
/// geometry has none of its own.
struct ArenaData<'g> {
    vertices: &'g [Vertex],
    indices: &'g [u32],
    wire: std::borrow::Cow<'g, [u32]>,
    parts: std::borrow::Cow<'g, [Part]>,
}

fn arena_data(geometry: &Geometry) -> ArenaData<'_> {
    if geometry.wire_indices.is_empty() {
        let (wire, parts) = feature_edges(geometry, DEFAULT_CREASE_DEGREES);
        ArenaData {
            vertices: &geometry.vertices,
            indices: &geometry.indices,
            wire: wire.into(),
            parts: parts.into(),
        }
    } else {
        ArenaData {
            vertices: &geometry.vertices,
            indices: &geometry.indices,
            wire: geometry.wire_indices.as_slice().into(),
            parts: geometry.parts.as_slice().into(),
        }
    }
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

/// The instance flags of a part's shape: its closure, and whether it is curved.
fn shape_flags(vertices: &[Vertex], indices: &[u32]) -> u32 {
    let closure = match closure(vertices, indices) {
        Closure::Open => 0,
        Closure::Closed => abi::CADR_INSTANCE_CLOSED,
        Closure::InsideOut => abi::CADR_INSTANCE_CLOSED | abi::CADR_INSTANCE_INSIDE_OUT,
    };
    let curved = if is_curved(vertices, indices) {
        abi::CADR_INSTANCE_CURVED
    } else {
        0
    };
    closure | curved
}

/// Whether some triangle of `indices` has vertex normals that differ (bit for bit: the hidden
/// silhouettes' geometry shader skips a triangle whose three normals are the same).
fn is_curved(vertices: &[Vertex], indices: &[u32]) -> bool {
    let normal = |i: u32| vertices.get(i as usize).map(|v| v.normal.map(f32::to_bits));
    indices.chunks_exact(3).any(|triangle| {
        let first = normal(triangle[0]);
        triangle[1..].iter().any(|&i| normal(i) != first)
    })
}

fn part_entries(data: &ArenaData<'_>) -> Vec<([u32; 4], [f32; 4], u32)> {
    data.parts
        .iter()
        .map(|p| {
            let start = (p.first_index as usize).min(data.indices.len());
            let end = (start + p.index_count as usize).min(data.indices.len());
            (
                [
                    p.first_index,
                    p.index_count,
                    p.first_wire_index,
                    p.wire_index_count,
                ],
                part_sphere(data.vertices, &data.indices[start..end]),
                shape_flags(data.vertices, &data.indices[start..end]),
            )
        })
        .collect()
}

/// Buffer usage of the arenas and of every GPU scene array.
pub(super) fn usage(device: &Device, base: vk::BufferUsageFlags) -> vk::BufferUsageFlags {
    let mut usage = base
        | vk::BufferUsageFlags::STORAGE_BUFFER
        | vk::BufferUsageFlags::TRANSFER_DST
        | vk::BufferUsageFlags::TRANSFER_SRC;
    if device.capabilities().buffer_device_address {
        usage |= vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS;
    }
    usage
}

/// The arenas and the place of every geometry slot in them.
pub(super) struct GeometryArenas {
    pub(super) vertices: Buffer,
    pub(super) indices: Buffer,
    pub(super) wire_indices: Buffer,
    /// One [`VertexAttributes`] per vertex when `has_attributes`, else 16 unused bytes.
    pub(super) attributes: Buffer,
    /// Whether some geometry has texture coordinates or colours.
    pub(super) has_attributes: bool,
    pub(super) places: Vec<Option<GeometryPlace>>,
}

impl GeometryArenas {
    /// Lays out and uploads every geometry of `graph`; returns the arenas and the bytes uploaded.
    pub(super) fn upload(device: &Arc<Device>, graph: &SceneGraph) -> RenderResult<(Self, u64)> {
        let (_, geometry_slots, _) = graph.capacities();
        let mut vertices: Vec<Vertex> = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        let mut wire: Vec<u32> = Vec::new();
        let places = (0..geometry_slots as u32)
            .map(|slot| {
                let data = arena_data(graph.geometry_at(slot)?);
                let place = GeometryPlace {
                    vertex_base: vertices.len() as u32,
                    first_index: indices.len() as u32,
                    first_wire_index: wire.len() as u32,
                    room: [
                        data.vertices.len() as u32,
                        data.indices.len() as u32,
                        data.wire.len() as u32,
                    ],
                    parts: part_entries(&data),
                };
                vertices.extend_from_slice(data.vertices);
                indices.extend_from_slice(data.indices);
                wire.extend_from_slice(&data.wire);
                Some(place)
            })
            .collect();
        let upload = |name: &str, data: &[u8], base: vk::BufferUsageFlags| {
            let bytes: &[u8] = if data.is_empty() { &[0; 16] } else { data };
            Buffer::with_data(device, name, bytes, usage(device, base))
        };
        let has_attributes = (0..geometry_slots as u32)
            .filter_map(|slot| graph.geometry_at(slot))
            .any(|g| !g.attributes.is_empty());
        let mut attributes: Vec<VertexAttributes> = Vec::new();
        if has_attributes {
            attributes.reserve(vertices.len());
            for slot in 0..geometry_slots as u32 {
                if let Some(geometry) = graph.geometry_at(slot) {
                    extend_attributes(&mut attributes, geometry);
                }
            }
        }
        let bytes = (std::mem::size_of_val(vertices.as_slice())
            + std::mem::size_of_val(indices.as_slice())
            + std::mem::size_of_val(wire.as_slice())
            + std::mem::size_of_val(attributes.as_slice())) as u64;
        let arenas = Self {
            vertices: upload(
                "scene vertices",
                bytemuck::cast_slice(&vertices),
                vk::BufferUsageFlags::VERTEX_BUFFER,
            )?,
            indices: upload(
                "scene indices",
                bytemuck::cast_slice(&indices),
                vk::BufferUsageFlags::INDEX_BUFFER,
            )?,
            wire_indices: upload(
                "scene wire indices",
                bytemuck::cast_slice(&wire),
                vk::BufferUsageFlags::INDEX_BUFFER,
            )?,
            attributes: upload(
                "scene vertex attributes",
                bytemuck::cast_slice(&attributes),
                vk::BufferUsageFlags::empty(),
            )?,
            has_attributes,
            places,
        };
        Ok((arenas, bytes))
    }

    /// Writes geometry slot `slot` of `graph` over its place when it fits the room there;
    /// returns the bytes uploaded, or `None` when it does not fit (or the slot is new), so the
    /// arenas must be laid out again. The GPU must not be drawing from the arenas meanwhile
    /// (frames are waited for before the next one syncs).
    pub(super) fn replace_in_place(
        &mut self,
        graph: &SceneGraph,
        slot: u32,
    ) -> RenderResult<Option<u64>> {
        let Some(geometry) = graph.geometry_at(slot) else {
            return Ok(None);
        };
        if !geometry.attributes.is_empty() && !self.has_attributes {
            // The first geometry with attributes: the attribute arena is made by a new layout.
            return Ok(None);
        }
        let Some(Some(place)) = self.places.get_mut(slot as usize) else {
            return Ok(None);
        };
        let data = arena_data(geometry);
        let sizes = [data.vertices.len(), data.indices.len(), data.wire.len()];
        if sizes
            .iter()
            .zip(place.room)
            .any(|(&n, room)| n > room as usize)
        {
            return Ok(None);
        }
        let vertex_bytes: &[u8] = bytemuck::cast_slice(data.vertices);
        let index_bytes: &[u8] = bytemuck::cast_slice(data.indices);
        let wire_bytes: &[u8] = bytemuck::cast_slice(&data.wire);
        let vertex_size = std::mem::size_of::<Vertex>() as u64;
        self.vertices
            .upload_at(u64::from(place.vertex_base) * vertex_size, vertex_bytes)?;
        self.indices
            .upload_at(u64::from(place.first_index) * 4, index_bytes)?;
        self.wire_indices
            .upload_at(u64::from(place.first_wire_index) * 4, wire_bytes)?;
        let mut attribute_bytes = 0;
        if self.has_attributes {
            let mut attributes = Vec::with_capacity(data.vertices.len());
            extend_attributes(&mut attributes, geometry);
            let bytes: &[u8] = bytemuck::cast_slice(&attributes);
            let size = std::mem::size_of::<VertexAttributes>() as u64;
            self.attributes
                .upload_at(u64::from(place.vertex_base) * size, bytes)?;
            attribute_bytes = bytes.len();
        }
        place.parts = part_entries(&data);
        Ok(Some(
            (vertex_bytes.len() + index_bytes.len() + wire_bytes.len() + attribute_bytes) as u64,
        ))
    }
}

/// Appends the geometry's attributes, or white at (0, 0) for each vertex when it has none.
fn extend_attributes(attributes: &mut Vec<VertexAttributes>, geometry: &Geometry) {
    if geometry.attributes.len() == geometry.vertices.len() {
        attributes.extend_from_slice(&geometry.attributes);
    } else {
        attributes.resize(
            attributes.len() + geometry.vertices.len(),
            VertexAttributes::default(),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate::GeometryBuilder;
    use glam::DMat4;

    #[test]
    fn a_part_is_curved_where_a_triangle_has_normals_that_differ() {
        let mut builder = GeometryBuilder::new("prism");
        builder.prism(48, DMat4::IDENTITY);
        let faceted = builder.finish();
        assert_eq!(
            shape_flags(&faceted.vertices, &faceted.indices) & abi::CADR_INSTANCE_CURVED,
            0,
            "a normal per facet"
        );
        let vertex = |position: [f32; 3], normal: [f32; 3]| Vertex { position, normal };
        let shared = [
            vertex([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
            vertex([1.0, 0.0, 0.0], [0.6, 0.0, 0.8]),
            vertex([0.0, 1.0, 0.0], [0.0, 0.0, 1.0]),
        ];
        assert!(is_curved(&shared, &[0, 1, 2]));
        assert!(!is_curved(&shared, &[0, 2, 0]), "one normal");
        assert!(!is_curved(&shared, &[]));
    }
}
