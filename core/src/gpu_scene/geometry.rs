//! The GPU scene's geometry: every geometry's vertices, triangle indices and edge indices in
//! three shared arenas (usable as vertex, index and storage buffers), with its clusters and
//! groups in two more (and the clusters' boxes beside them, laid out like the clusters), and
//! each geometry's place and room there. Geometries come and go
//! without the arenas being laid out again: a replaced geometry that fits its room is written
//! in place (only its bytes are uploaded and only its users' instance entries change); a new
//! one takes the room a destroyed one left, or the room at the arenas' end; a destroyed one
//! leaves its room free. Only when no room is left are the arenas laid out again, then with
//! room to spare. Texture coordinates and colours go in a sixth arena laid out like the
//! vertices (the same index finds a vertex's attributes), made only when some geometry has
//! them.

use std::sync::Arc;

use crate::error::RenderResult;
use crate::vk::raw as vk;

use super::bounds;
use super::clusters::{self, GeometryClusters};
use super::streaming::{
    coarse_share, CoarseForm, FullDetail, LoadRetry, PartBounds, PrepareFailure, Preparer,
    Streaming, StreamingPlan, UPLOAD_BYTES_PER_FRAME,
};
use crate::graph::{GeometryHandle, GeometrySource, GraphError, SceneGraph};
use crate::scene::closure::{closure_welded, Closure};
use crate::scene::edges::{feature_edges_welded, DEFAULT_CREASE_DEGREES};
use crate::scene::weld::first_at_position;
use crate::scene::{Geometry, Part, Vertex, VertexAttributes};
use crate::vk::{Buffer, Device};
use cadr_plugin_abi as abi;

/// Elements of each arena, in the order vertices, indices (the coarser clusters' too), wire
/// indices, clusters, groups.
type Extent = [u32; 5];

/// Where one geometry lies in the arenas and how much room it has there.
#[derive(Clone, Debug)]
pub(super) struct GeometryPlace {
    /// The geometry placed there: a slot reused by another geometry is placed again.
    handle: GeometryHandle,
    pub(super) vertex_base: u32,
    pub(super) first_index: u32,
    pub(super) first_wire_index: u32,
    pub(super) first_cluster: u32,
    pub(super) first_group: u32,
    /// What the place can hold (the size of the geometry it was made for).
    room: Extent,
    /// Per part: its ranges, bounds and shape.
    pub(super) parts: Vec<PartEntry>,
    /// Per part: its first cluster (relative to `first_cluster`), how many it has, and how
    /// many its coarsest cut has.
    pub(super) part_clusters: Vec<[u32; 3]>,
    /// Where the scene streams and this place holds the full detail: the coarse form's place,
    /// kept in the arenas (the coarse forms stay resident), so that going back to it builds and
    /// uploads nothing.
    coarse: Option<Box<GeometryPlace>>,
}

impl GeometryPlace {
    /// Where the place starts in each arena.
    fn starts(&self) -> Extent {
        [
            self.vertex_base,
            self.first_index,
            self.first_wire_index,
            self.first_cluster,
            self.first_group,
        ]
    }

    /// Part `part`'s first cluster in the cluster arena, how many it has, and how many its
    /// coarsest cut has.
    pub(super) fn clusters_of(&self, part: u32) -> Option<[u32; 3]> {
        let [first, count, coarsest] = *self.part_clusters.get(part as usize)?;
        Some([self.first_cluster + first, count, coarsest])
    }
}

/// A geometry's data as the arenas hold it: edge indices derived by crease angle when the
/// geometry has none of its own, and the parts' clusters (whose order the triangle indices
/// take).
struct ArenaData<'g> {
    vertices: &'g [Vertex],
    /// Its vertices welded by position (`weld::first_at_position`), which feature edges and
    /// the parts' closure both use.
    welded: Vec<u32>,
    wire: std::borrow::Cow<'g, [u32]>,
    parts: std::borrow::Cow<'g, [Part]>,
    clusters: GeometryClusters,
}

fn arena_data(geometry: &Geometry) -> ArenaData<'_> {
    let welded = first_at_position(&geometry.vertices);
    if geometry.wire_indices.is_empty() {
        let (wire, parts) = feature_edges_welded(geometry, &welded, DEFAULT_CREASE_DEGREES);
        arena_data_with_edges(geometry, welded, (wire.into(), parts.into()))
    } else {
        let edges = (&geometry.wire_indices).into();
        arena_data_with_edges(geometry, welded, (edges, (&geometry.parts).into()))
    }
}

/// [`arena_data`] of `geometry` welded as `welded`, with the edges `wire` (a line list) and
/// the parts with their ranges in it.
fn arena_data_with_edges<'g>(
    geometry: &'g Geometry,
    welded: Vec<u32>,
    (wire, parts): (std::borrow::Cow<'g, [u32]>, std::borrow::Cow<'g, [Part]>),
) -> ArenaData<'g> {
    let clusters = clusters::build_cached(&geometry.vertices, &geometry.indices, &wire, &parts);
    ArenaData {
        vertices: &geometry.vertices,
        welded,
        wire,
        parts,
        clusters,
    }
}

/// A geometry's full detail prepared for the arenas off the frame's thread (streaming): the
/// geometry, its edge indices and parts, and its clusters.
pub(super) struct PreparedGeometry {
    geometry: Geometry,
    welded: Vec<u32>,
    wire: Vec<u32>,
    parts: Vec<Part>,
    clusters: GeometryClusters,
}

/// Reads `source` (from the scene graph's page file where it is there) and prepares it for the
/// arenas (see [`arena_data`]), owning what it needs; fails where it cannot be read.
fn prepare_geometry(source: GeometrySource) -> Result<PreparedGeometry, String> {
    let geometry = source.load()?;
    let ArenaData {
        welded,
        wire,
        parts,
        clusters,
        ..
    } = arena_data(&geometry);
    let (wire, parts) = (wire.into_owned(), parts.into_owned());
    Ok(PreparedGeometry {
        geometry,
        welded,
        wire,
        parts,
        clusters,
    })
}

/// Device bytes of a geometry of `sizes` elements (with texture coordinates and colours per
/// vertex where `attributes`).
fn bytes_of(sizes: Extent, attributes: bool) -> u64 {
    let [vertices, indices, wire, clusters, groups] = sizes.map(u64::from);
    let vertex_bytes = std::mem::size_of::<Vertex>() as u64
        + if attributes {
            std::mem::size_of::<VertexAttributes>() as u64
        } else {
            0
        };
    vertices * vertex_bytes
        + (indices + wire) * 4
        + clusters * (CLUSTER_BYTES + CLUSTER_BOX_BYTES) as u64
        + groups * GROUP_BYTES as u64
}

/// The coarse form of the geometry `data` was made from, its parts cut within `share` of their
/// triangles (see `streaming::coarse_share`), with its full-detail bytes.
fn coarse_form(
    geometry: &Geometry,
    data: &ArenaData<'_>,
    attributes: bool,
    share: f64,
) -> (u64, Option<CoarseForm>) {
    let bytes = bytes_of(data.sizes(), attributes);
    let parts = part_entries(data).into_iter().map(|p| p.extent).collect();
    let full = FullDetail {
        geometry,
        wire: &data.wire,
        parts: &data.parts,
        clusters: &data.clusters,
    };
    (bytes, CoarseForm::of(&full, parts, share))
}

/// A coarse form's data as the arenas hold it: its edges those it was given (the full
/// detail's, even where there are none), and its own DAG's errors raised, part by part, by the
/// form's error against the full detail, so that a cut of it at a threshold stays within the
/// threshold of the full detail (the cut is finer for it), not of the coarse form alone.
fn coarse_arena_data(form: &CoarseForm) -> ArenaData<'_> {
    let geometry = &form.geometry;
    let welded = first_at_position(&geometry.vertices);
    let edges = ((&geometry.wire_indices).into(), (&geometry.parts).into());
    let mut data = arena_data_with_edges(geometry, welded, edges);
    // Each group's raise: its part's error (a part's clusters and edge levels name its groups).
    let clusters = &data.clusters;
    let mut raise = vec![0.0_f32; clusters.groups.len()];
    for (part, &error) in form.errors.iter().enumerate() {
        let (own, levels) = clusters.part_records(part).unwrap_or_default();
        for cluster in own.iter().chain(levels) {
            if let Some(raise) = raise.get_mut(cluster.group as usize) {
                *raise = error;
            }
        }
    }
    for (group, raise) in data.clusters.groups.iter_mut().zip(raise) {
        if group.error < f32::MAX {
            group.error += raise;
        }
    }
    data
}

/// The entries of a coarse form's parts as placed in geometry slot `slot` (`placed`, made from
/// the coarse geometry): their ranges, with the full detail's bounds and shape, the form's
/// error and the slot's request bit.
fn coarse_part_entries(form: &CoarseForm, slot: u32, mut placed: Vec<PartEntry>) -> Vec<PartEntry> {
    let full = form.full_parts.iter().zip(&form.errors);
    for (part, (full, &error)) in placed.iter_mut().zip(full) {
        part.extent = PartBounds {
            bounds: abi::CadrBox {
                coarse_error: error.max(f32::MIN_POSITIVE),
                request_bit: slot,
                ..full.bounds
            },
            ..*full
        };
    }
    placed
}

/// The entries of a streamed geometry's parts at full detail in geometry slot `slot`
/// (`placed`): each part box carries the slot's request bit and its coarse form's error
/// negated, so that the cullers keep asking for the full detail where it is still needed (and
/// it is not put back in its coarse form).
fn full_part_entries(form: &CoarseForm, slot: u32, mut placed: Vec<PartEntry>) -> Vec<PartEntry> {
    for (part, &error) in placed.iter_mut().zip(&form.errors) {
        part.extent.bounds.coarse_error = -error.max(f32::MIN_POSITIVE);
        part.extent.bounds.request_bit = slot;
    }
    placed
}

impl ArenaData<'_> {
    /// How much of each arena the geometry takes.
    fn sizes(&self) -> Extent {
        let clusters = &self.clusters;
        [
            self.vertices.len(),
            clusters.indices.len() + clusters.lod_indices.len(),
            self.wire.len() + clusters.wire_lod.len(),
            clusters.clusters.len(),
            clusters.groups.len(),
        ]
        .map(|n| n as u32)
    }

    /// The clusters' bytes as the arena holds them: indices made absolute from the geometry's
    /// `first_index` (an edge level's from its `first_wire_index`), groups from its
    /// `first_group`.
    fn cluster_bytes(&self, first_index: u32, first_wire_index: u32, first_group: u32) -> Vec<u8> {
        let absolute = |group: u32| {
            if group == abi::CADR_CLUSTER_ORIGINAL {
                group
            } else {
                first_group + group
            }
        };
        self.clusters
            .clusters
            .iter()
            .flat_map(|c| {
                if clusters::is_edge_level(&self.clusters, c) {
                    return abi::CadrCluster {
                        first_index: first_wire_index + c.first_index,
                        group: absolute(c.group),
                        ..*c
                    }
                    .to_le_bytes();
                }
                abi::CadrCluster {
                    first_index: first_index + c.first_index,
                    group: absolute(c.group),
                    refined: absolute(c.refined),
                    ..*c
                }
                .to_le_bytes()
            })
            .collect()
    }

    /// The clusters' boxes ([`abi::CadrBox`]), in cluster order: each the smallest
    /// box along the object's axes around the vertices its indices name.
    fn cluster_box_bytes(&self) -> Vec<u8> {
        let clusters = &self.clusters;
        clusters
            .clusters
            .iter()
            .flat_map(|c| {
                let first = c.first_index as usize;
                let range = first..first + c.index_count as usize;
                let vertex = |&i: &u32| self.vertices.get(i as usize);
                if clusters::is_edge_level(clusters, c) {
                    let wire = range.filter_map(|i| self.wire_index(i));
                    return bounding_box(wire.filter_map(vertex)).to_le_bytes();
                }
                let vertices = range.filter_map(|i| clusters.index(i)).filter_map(vertex);
                bounding_box(vertices).to_le_bytes()
            })
            .collect()
    }

    /// Index `i` of the geometry's wire index range as the arena lays it out: its own edge
    /// indices, then its edge levels'.
    fn wire_index(&self, i: usize) -> Option<&u32> {
        self.clusters.wire_index(&self.wire, i)
    }

    /// The groups' bytes as the arena holds them: their clusters made absolute from the
    /// geometry's `first_cluster`.
    fn group_bytes(&self, first_cluster: u32) -> Vec<u8> {
        self.clusters
            .groups
            .iter()
            .flat_map(|g| {
                abi::CadrClusterGroup {
                    first_cluster: first_cluster + g.first_cluster,
                    ..*g
                }
                .to_le_bytes()
            })
            .collect()
    }
}

/// The smallest box along the object's axes around `vertices`, a hair larger so that rounding
/// never leaves a corner outside (an empty box at the origin for none).
fn bounding_box<'v>(vertices: impl Iterator<Item = &'v Vertex>) -> abi::CadrBox {
    let mut min = [f32::INFINITY; 3];
    let mut max = [f32::NEG_INFINITY; 3];
    for v in vertices {
        for axis in 0..3 {
            min[axis] = min[axis].min(v.position[axis]);
            max[axis] = max[axis].max(v.position[axis]);
        }
    }
    if min[0] > max[0] {
        return abi::CadrBox::default();
    }
    let center = [0, 1, 2].map(|a| 0.5 * (min[a] + max[a]));
    abi::CadrBox {
        center,
        half_extent: [0, 1, 2].map(|a| {
            let half = 0.5 * (max[a] - min[a]);
            half + (half + center[a].abs()) * 1e-6
        }),
        ..abi::CadrBox::default()
    }
}

/// The sphere of the part `indices` names among `vertices` ([`bounds::sphere_of`]), with
/// rounding slack.
fn part_sphere(vertices: &[Vertex], indices: &[u32]) -> [f32; 4] {
    let positions = (indices.iter()).filter_map(|&i| Some(vertices.get(i as usize)?.position));
    let [x, y, z, radius] = bounds::sphere_of(positions);
    [x, y, z, radius * (1.0 + 1e-5)]
}

/// The instance flags of a part's shape: its closure, and whether it is curved. `welded` are
/// `vertices` welded by position (`weld::first_at_position`).
fn shape_flags(vertices: &[Vertex], welded: &[u32], indices: &[u32]) -> u32 {
    let closure = match closure_welded(vertices, welded, indices) {
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

/// What the instances of a part are made from.
#[derive(Clone, Copy, Debug)]
pub(super) struct PartEntry {
    /// First index, count, first wire index, wire count (relative to the geometry's).
    pub(super) ranges: [u32; 4],
    /// Its bounding sphere, box and shape.
    pub(super) extent: PartBounds,
    /// Whether coarser levels of its edges follow its clusters (`edge_levels.rs`).
    pub(super) edge_levels: bool,
}

fn part_entries(data: &ArenaData<'_>) -> Vec<PartEntry> {
    let indices = &data.clusters.indices;
    let edge_levels = &data.clusters.edge_levels;
    let welded = &data.welded;
    data.parts
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let start = (p.first_index as usize).min(indices.len());
            let end = (start + p.index_count as usize).min(indices.len());
            let own = &indices[start..end];
            PartEntry {
                ranges: [
                    p.first_index,
                    p.index_count,
                    p.first_wire_index,
                    p.wire_index_count,
                ],
                extent: PartBounds {
                    sphere: part_sphere(data.vertices, own),
                    bounds: bounding_box(own.iter().filter_map(|&i| data.vertices.get(i as usize))),
                    shape: shape_flags(data.vertices, welded, own),
                },
                edge_levels: edge_levels.get(k).is_some_and(|&n| n > 0),
            }
        })
        .collect()
}

/// Bytes of one cluster in the cluster arena ([`abi::CadrCluster`]).
const CLUSTER_BYTES: usize = 64;
/// Bytes of one cluster's box in the box arena ([`abi::CadrBox`]).
const CLUSTER_BOX_BYTES: usize = 32;
/// Bytes of one group in the group arena ([`abi::CadrClusterGroup`]).
const GROUP_BYTES: usize = 32;

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
    /// [`abi::CadrCluster`] per cluster of every part.
    pub(super) clusters: Buffer,
    /// [`abi::CadrBox`] per cluster, at the cluster's index.
    pub(super) cluster_boxes: Buffer,
    /// [`abi::CadrClusterGroup`] per group of every part's level-of-detail DAG.
    pub(super) groups: Buffer,
    /// Where the arenas' unused end starts, and how much each holds.
    tails: Extent,
    capacity: Extent,
    /// The rooms destroyed geometries left: (starts, room).
    free: Vec<(Extent, Extent)>,
    /// The graph's geometries generation the places follow.
    generation: u64,
    /// One [`VertexAttributes`] per vertex when `has_attributes`, else 16 unused bytes.
    pub(super) attributes: Buffer,
    /// Whether some geometry has texture coordinates or colours.
    pub(super) has_attributes: bool,
    pub(super) places: Vec<Option<GeometryPlace>>,
    /// Where the scene streams its geometry: which geometries are at full detail.
    pub(super) streaming: Option<Streaming>,
    /// The thread that prepares full detail for streaming, made on first use.
    preparer: Option<Preparer<PreparedGeometry>>,
}

/// Every geometry of a graph one after the other, in slot order: the arenas' contents and
/// the places (each geometry in its coarse form where the scene streams and its full detail
/// is not on the GPU).
struct Layout {
    vertices: Vec<Vertex>,
    indices: Vec<u32>,
    wire: Vec<u32>,
    clusters: Vec<u8>,
    cluster_boxes: Vec<u8>,
    groups: Vec<u8>,
    /// Texture coordinates and colours laid out like `vertices`, where some geometry has them.
    attributes: Option<Vec<VertexAttributes>>,
    places: Vec<Option<GeometryPlace>>,
    /// Elements every geometry's full detail would take, summed, and the most one takes.
    full_sizes: Extent,
    largest: Extent,
}

/// The error of a geometry that cannot be read back (from the scene graph's page file).
fn unreadable(error: GraphError) -> crate::error::RenderError {
    crate::error::RenderError::SceneData(error.to_string())
}

/// The most full-detail geometry bytes `device` holds before the scene streams:
/// `CADR_MEMORY_BUDGET` (else the machine's memory), and at most half the device's video
/// memory (its largest device-local heap), which also holds the coarse forms, the instances,
/// textures and the frames' targets.
fn streaming_budget(device: &Device) -> u64 {
    let budget = crate::memory_budget::budget().unwrap_or(u64::MAX);
    match device.adapter().video_memory {
        0 => budget,
        video_memory => budget.min(video_memory / 2),
    }
}

/// Slots laid out at once: their coarse forms' arena data is made in parallel.
const LAYOUT_CHUNK: usize = 32;

/// One geometry slot as the layout measured it.
enum Measured<'g> {
    /// A geometry the graph keeps in memory, with its full detail's data.
    Resident(GeometryHandle, &'g Geometry, ArenaData<'g>),
    /// A geometry read from the graph's page file and let go again (a scene that pages its
    /// geometry holds no more of it at once than a thread per core reads): its full detail's
    /// sizes, and its bytes and coarse form in case the scene streams.
    Paged(GeometryHandle, Extent, Option<(u64, Option<CoarseForm>)>),
}

impl Measured<'_> {
    fn handle(&self) -> GeometryHandle {
        match self {
            Self::Resident(handle, ..) | Self::Paged(handle, ..) => *handle,
        }
    }

    fn sizes(&self) -> Extent {
        match self {
            Self::Resident(_, _, data) => data.sizes(),
            Self::Paged(_, sizes, _) => *sizes,
        }
    }
}

/// Measures slot `slot` of `graph` (see [`Measured`]); a paged geometry's coarse form is cut
/// within `share` of its parts' triangles.
fn measure(
    graph: &SceneGraph,
    slot: u32,
    (has_attributes, share): (bool, f64),
) -> RenderResult<Option<Measured<'_>>> {
    let Some(handle) = graph.geometry_handle_at(slot) else {
        return Ok(None);
    };
    Ok(Some(match graph.geometry(handle).map_err(unreadable)? {
        std::borrow::Cow::Borrowed(geometry) => {
            Measured::Resident(handle, geometry, arena_data(geometry))
        }
        std::borrow::Cow::Owned(geometry) => {
            let data = arena_data(&geometry);
            let coarse = coarse_form(&geometry, &data, has_attributes, share);
            Measured::Paged(handle, data.sizes(), Some(coarse))
        }
    }))
}

impl Layout {
    /// Lays `graph` out; starts streaming (`streaming`) where its full detail needs more than
    /// the memory budget.
    fn of(
        device: &Arc<Device>,
        graph: &SceneGraph,
        streaming: &mut Option<Streaming>,
    ) -> RenderResult<Self> {
        let (_, geometry_slots, _) = graph.capacities();
        let has_attributes = (0..geometry_slots as u32)
            .filter_map(|slot| graph.geometry_info_at(slot))
            .any(|info| info.has_attributes);
        // How coarse the coarse forms are, where the scene streams: set from its bytes in host
        // memory (in memory and in the page file), which the graph counts, before any geometry
        // is read.
        let budget = streaming_budget(device);
        let share = match streaming {
            Some(streaming) => streaming.coarse_share(),
            None => {
                let memory = graph.geometry_memory();
                coarse_share(budget, memory.resident_bytes + memory.paged_bytes)
            }
        };
        // The clusters are built on a thread per core, the geometries laid out in slot order.
        let slots: Vec<u32> = (0..geometry_slots as u32).collect();
        let measured = crate::parallel::map(&slots, |&slot| {
            measure(graph, slot, (has_attributes, share))
        })
        .into_iter()
        .collect::<RenderResult<Vec<_>>>()?;
        let mut full_sizes: Extent = [0; 5];
        let mut largest: Extent = [0; 5];
        for sizes in measured.iter().flatten().map(Measured::sizes) {
            for ((total, most), n) in full_sizes.iter_mut().zip(&mut largest).zip(sizes) {
                *total = total.saturating_add(n);
                *most = (*most).max(n);
            }
        }
        if streaming.is_none() && bytes_of(full_sizes, has_attributes) > budget {
            *streaming = Some(Streaming::new(device, budget, share)?);
        }
        let mut layout = Self {
            vertices: Vec::new(),
            indices: Vec::new(),
            wire: Vec::new(),
            clusters: Vec::new(),
            cluster_boxes: Vec::new(),
            groups: Vec::new(),
            attributes: has_attributes.then(Vec::new),
            places: Vec::with_capacity(measured.len()),
            full_sizes,
            largest,
        };
        // A chunk of slots at a time: the coarse forms' arena data is made on a thread per
        // core, appended, and let go (streaming keeps the forms without their arrays), so that
        // the layout holds each coarse form once, not as a form, its data and its place.
        let mut measured = measured.into_iter();
        for chunk in slots.chunks(LAYOUT_CHUNK) {
            let entries: Vec<Option<Measured<'_>>> = measured.by_ref().take(chunk.len()).collect();
            layout.add_chunk(graph, chunk, entries, streaming, has_attributes)?;
        }
        Ok(layout)
    }

    /// Lays out the geometries `entries` of slots `chunk`: in their coarse form where the
    /// scene streams and streaming says so, else at full detail.
    fn add_chunk(
        &mut self,
        graph: &SceneGraph,
        chunk: &[u32],
        mut entries: Vec<Option<Measured<'_>>>,
        streaming: &mut Option<Streaming>,
        has_attributes: bool,
    ) -> RenderResult<()> {
        let share = streaming.as_ref().map_or(0.0, Streaming::coarse_share);
        let forms: Vec<Option<Arc<CoarseForm>>> = match streaming.as_mut() {
            None => vec![None; chunk.len()],
            Some(streaming) => (chunk.iter().zip(&mut entries))
                .map(|(&slot, entry)| {
                    let entry = entry.as_mut()?;
                    let handle = entry.handle();
                    streaming.form_to_place(slot, handle, || match entry {
                        Measured::Resident(_, geometry, data) => {
                            coarse_form(geometry, data, has_attributes, share)
                        }
                        Measured::Paged(_, _, form) => form.take().unwrap_or_default(),
                    })
                })
                .collect(),
        };
        let coarse_data = crate::parallel::map(chunk, |&slot| {
            let at = (slot - chunk[0]) as usize;
            forms[at].as_deref().map(coarse_arena_data)
        });
        for ((&slot, entry), (form, data)) in
            chunk.iter().zip(entries).zip(forms.iter().zip(coarse_data))
        {
            let Some(entry) = entry else {
                self.places.push(None);
                continue;
            };
            let place = match (form, data) {
                (Some(form), Some(data)) => {
                    let mut place = self.push(entry.handle(), &data, &form.geometry);
                    place.parts = coarse_part_entries(form, slot, place.parts);
                    place
                }
                _ => self.push_full(graph, slot, entry, streaming.as_ref())?,
            };
            self.places.push(Some(place));
            // The coarse form is laid out: streaming keeps it without its arrays.
            if let (Some(streaming), Some(_)) = (streaming.as_mut(), form) {
                streaming.placed(slot);
            }
        }
        Ok(())
    }

    /// Adds slot `slot`'s full detail (read again from the page file where it was paged);
    /// its part entries say so where the scene streams it.
    fn push_full(
        &mut self,
        graph: &SceneGraph,
        slot: u32,
        measured: Measured<'_>,
        streaming: Option<&Streaming>,
    ) -> RenderResult<GeometryPlace> {
        let mut place = match measured {
            Measured::Resident(handle, geometry, data) => self.push(handle, &data, geometry),
            Measured::Paged(handle, ..) => {
                let geometry = graph.geometry(handle).map_err(unreadable)?;
                self.push(handle, &arena_data(&geometry), &geometry)
            }
        };
        if let Some(form) = streaming.and_then(|s| s.coarse_form_of(slot)) {
            place.parts = full_part_entries(&form, slot, place.parts);
        }
        Ok(place)
    }

    /// Where each arena's used part ends.
    fn tails(&self) -> Extent {
        [
            self.vertices.len(),
            self.indices.len(),
            self.wire.len(),
            self.clusters.len() / CLUSTER_BYTES,
            self.groups.len() / GROUP_BYTES,
        ]
        .map(|n| n as u32)
    }

    /// The elements each arena is made for: what the layout uses, with room to spare where
    /// `spare` (a layout made because the room ran out), and room for the full detail the
    /// budget allows where the scene `streaming`.
    fn capacity(&self, spare: bool, streaming: Option<&Streaming>) -> Extent {
        let tails = self.tails();
        let capacity = if spare {
            tails.map(with_spare_room)
        } else {
            tails
        };
        match streaming {
            Some(streaming) => {
                let full_bytes = bytes_of(self.full_sizes, self.attributes.is_some());
                with_streaming_room(
                    capacity,
                    (streaming.budget(), full_bytes),
                    (self.full_sizes, self.largest),
                )
            }
            None => capacity,
        }
    }

    /// Appends `data`, made from `geometry`, and returns its place.
    fn push(
        &mut self,
        handle: GeometryHandle,
        data: &ArenaData<'_>,
        geometry: &Geometry,
    ) -> GeometryPlace {
        let first_group = (self.groups.len() / GROUP_BYTES) as u32;
        let first_index = self.indices.len() as u32;
        let place = GeometryPlace {
            handle,
            vertex_base: self.vertices.len() as u32,
            first_index,
            first_wire_index: self.wire.len() as u32,
            first_cluster: (self.clusters.len() / CLUSTER_BYTES) as u32,
            first_group,
            room: data.sizes(),
            parts: part_entries(data),
            part_clusters: data.clusters.part_ranges.clone(),
            coarse: None,
        };
        self.vertices.extend_from_slice(data.vertices);
        self.indices.extend_from_slice(&data.clusters.indices);
        self.indices.extend_from_slice(&data.clusters.lod_indices);
        self.wire.extend_from_slice(&data.wire);
        self.wire.extend_from_slice(&data.clusters.wire_lod);
        self.groups.extend(data.group_bytes(place.first_cluster));
        self.clusters
            .extend(data.cluster_bytes(first_index, place.first_wire_index, first_group));
        self.cluster_boxes.extend(data.cluster_box_bytes());
        if let Some(attributes) = &mut self.attributes {
            extend_attributes(attributes, geometry);
        }
        place
    }
}

impl GeometryArenas {
    /// Device bytes of the coarse forms' places (see `GpuScene::coarse_form_bytes`).
    pub(super) fn coarse_form_bytes(&self) -> u64 {
        let Some(streaming) = &self.streaming else {
            return 0;
        };
        (self.places.iter().enumerate())
            .filter_map(|(slot, place)| {
                let place = place.as_ref()?;
                match &place.coarse {
                    Some(coarse) => Some(coarse.room),
                    None => streaming.is_coarse(slot as u32).then_some(place.room),
                }
            })
            .map(|room| bytes_of(room, self.has_attributes))
            .sum()
    }

    /// Lays out and uploads every geometry of `graph`, with room to spare at the end of each
    /// arena when `spare` (a layout made because the room ran out); returns the arenas and
    /// the bytes uploaded.
    pub(super) fn upload(
        device: &Arc<Device>,
        graph: &SceneGraph,
        spare: bool,
        streaming: Option<Streaming>,
    ) -> RenderResult<(Self, u64)> {
        let mut streaming = streaming;
        let layout = Layout::of(device, graph, &mut streaming)?;
        let tails = layout.tails();
        let capacity = layout.capacity(spare, streaming.as_ref());
        let Layout {
            vertices,
            indices,
            wire,
            clusters,
            cluster_boxes,
            groups,
            attributes,
            places,
            ..
        } = layout;
        let has_attributes = attributes.is_some();
        let attributes = attributes.unwrap_or_default();
        let bytes = (std::mem::size_of_val(vertices.as_slice())
            + std::mem::size_of_val(indices.as_slice())
            + std::mem::size_of_val(wire.as_slice())
            + std::mem::size_of_val(attributes.as_slice())
            + clusters.len()
            + cluster_boxes.len()
            + groups.len()) as u64;
        // Each arena holds `capacity` elements of its size (16 bytes at least).
        let arena = |name: &str, data: &[u8], elements: u32, size: usize, base| {
            let room = (u64::from(elements) * size as u64)
                .max(data.len() as u64)
                .max(16);
            let mut buffer = Buffer::new(
                device,
                name,
                room,
                usage(device, base),
                crate::vk::MemoryLocation::GpuOnly,
            )?;
            buffer.upload_at(0, data)?;
            RenderResult::Ok(buffer)
        };
        let index = vk::BufferUsageFlags::INDEX_BUFFER;
        let none = vk::BufferUsageFlags::empty();
        let attribute_elements = if has_attributes { capacity[0] } else { 0 };
        let arenas = Self {
            vertices: arena(
                "scene vertices",
                bytemuck::cast_slice(&vertices),
                capacity[0],
                std::mem::size_of::<Vertex>(),
                vk::BufferUsageFlags::VERTEX_BUFFER,
            )?,
            indices: arena(
                "scene indices",
                bytemuck::cast_slice(&indices),
                capacity[1],
                4,
                index,
            )?,
            wire_indices: arena(
                "scene wire indices",
                bytemuck::cast_slice(&wire),
                capacity[2],
                4,
                index,
            )?,
            attributes: arena(
                "scene vertex attributes",
                bytemuck::cast_slice(&attributes),
                attribute_elements,
                std::mem::size_of::<VertexAttributes>(),
                none,
            )?,
            clusters: arena(
                "scene clusters",
                &clusters,
                capacity[3],
                CLUSTER_BYTES,
                none,
            )?,
            cluster_boxes: arena(
                "scene cluster boxes",
                &cluster_boxes,
                capacity[3],
                CLUSTER_BOX_BYTES,
                none,
            )?,
            groups: arena(
                "scene cluster groups",
                &groups,
                capacity[4],
                GROUP_BYTES,
                none,
            )?,
            tails,
            capacity,
            free: Vec::new(),
            generation: graph.geometries_generation(),
            has_attributes,
            places,
            streaming,
            preparer: None,
        };
        Ok((arenas, bytes))
    }

    /// Brings the places up to date with the geometries `graph` created and destroyed since
    /// the last time: a destroyed geometry's room is freed, a new one placed and written.
    /// Returns the bytes uploaded, or `None` when some new geometry found no room (the arenas
    /// must be laid out again).
    pub(super) fn follow_created_and_destroyed(
        &mut self,
        graph: &SceneGraph,
    ) -> RenderResult<Option<u64>> {
        if graph.geometries_generation() == self.generation {
            return Ok(Some(0));
        }
        let (_, geometry_slots, _) = graph.capacities();
        let slots = geometry_slots.max(self.places.len()) as u32;
        let stale = |places: &[Option<GeometryPlace>], slot: u32| {
            let placed = places
                .get(slot as usize)
                .and_then(|p| p.as_ref().map(|p| p.handle));
            placed != graph.geometry_handle_at(slot)
        };
        // Free first, so that new geometries can take the rooms.
        for slot in 0..slots {
            if stale(&self.places, slot) {
                self.release(slot);
                if let Some(streaming) = &mut self.streaming {
                    streaming.forget(slot);
                }
            }
        }
        let mut uploaded = 0;
        for slot in 0..slots {
            if stale(&self.places, slot) {
                match self.place(graph, slot)? {
                    Some(bytes) => uploaded += bytes,
                    None => return Ok(None),
                }
            }
        }
        self.generation = graph.geometries_generation();
        Ok(Some(uploaded))
    }

    /// Where the scene streams: reads the frames' requests, asks the preparing thread for the
    /// full detail of the geometries they want, and writes what it has prepared, putting others
    /// back in their coarse form to make room (see `streaming.rs`), after `settle` (frames in
    /// flight must finish before their geometry moves). Returns the slots whose form changed
    /// and the bytes uploaded.
    pub(super) fn stream(
        &mut self,
        graph: &SceneGraph,
        settle: &mut dyn FnMut() -> RenderResult<()>,
    ) -> RenderResult<(Vec<u32>, u64)> {
        let Some(streaming) = &mut self.streaming else {
            return Ok((Vec::new(), 0));
        };
        let StreamingPlan { load, unload } = streaming.take_requests()?;
        let preparer = self
            .preparer
            .get_or_insert_with(|| Preparer::new(prepare_geometry));
        for slot in load {
            if graph.geometry_info_at(slot).is_none() {
                continue;
            }
            let Some(ticket) = streaming.start_loading(slot) else {
                continue;
            };
            let asked = (graph.geometry_source_at(slot))
                .is_some_and(|source| preparer.ask(slot, ticket, source));
            if !asked {
                streaming.load_failed(slot, LoadRetry::Never);
            }
        }
        // At most a frame's worth of bytes is written (at least one geometry); the rest waits
        // for the next frames, so that preparations finishing together make no long frame.
        let mut ready = preparer.finished();
        let mut writing = 0;
        let mut taken = 0;
        for (slot, _, _) in &ready {
            let bytes = streaming.full_bytes_of(*slot);
            if taken > 0 && writing + bytes > UPLOAD_BYTES_PER_FRAME {
                break;
            }
            writing += bytes;
            taken += 1;
        }
        preparer.put_back(ready.split_off(taken));
        if unload.is_empty() && ready.is_empty() {
            return Ok((Vec::new(), 0));
        }
        settle()?;
        let mut changed = Vec::new();
        let mut uploaded = 0;
        for slot in unload {
            if let Some(streaming) = &mut self.streaming {
                streaming.set_coarse(slot);
            }
            if !self.restore_coarse(slot) {
                // Released first, so that the coarse form does not keep the full detail's room.
                self.release(slot);
                uploaded += self.place(graph, slot)?.unwrap_or(0);
            }
            changed.push(slot);
        }
        for (slot, ticket, prepared) in ready {
            if let Some(bytes) = self.place_prepared(graph, slot, ticket, prepared)? {
                uploaded += bytes;
                changed.push(slot);
            }
        }
        Ok((changed, uploaded))
    }

    /// Writes slot `slot`'s full detail as the preparing thread made it (`None`: it failed),
    /// where the slot still waits for the preparation of `ticket`; a full detail that finds no
    /// room leaves the coarse form in place (tried again later). Returns the bytes uploaded, or
    /// `None` where nothing changed.
    fn place_prepared(
        &mut self,
        graph: &SceneGraph,
        slot: u32,
        ticket: u64,
        prepared: Result<PreparedGeometry, PrepareFailure>,
    ) -> RenderResult<Option<u64>> {
        let Some(streaming) = &mut self.streaming else {
            return Ok(None);
        };
        let Some(handle) = graph.geometry_handle_at(slot) else {
            return Ok(None);
        };
        if !streaming.is_loading(slot, ticket) {
            return Ok(None);
        }
        let PreparedGeometry {
            geometry,
            welded,
            wire,
            parts,
            clusters,
        } = match prepared {
            Ok(prepared) => prepared,
            Err(PrepareFailure::Panicked) => {
                streaming.load_failed(slot, LoadRetry::Never);
                return Ok(None);
            }
            Err(PrepareFailure::Unreadable(message)) => {
                streaming.read_failed(slot, &message);
                return Ok(None);
            }
        };
        let data = ArenaData {
            vertices: &geometry.vertices,
            welded,
            wire: wire.into(),
            parts: parts.into(),
            clusters,
        };
        // Marked loaded first: the place's part entries then say it is at full detail.
        streaming.loaded(slot);
        // The coarse form's place is kept aside (in the arenas) while the full detail gets one.
        let coarse = self.places.get_mut(slot as usize).and_then(Option::take);
        if let Some(bytes) = self.write_place(slot, handle, data, &geometry, None)? {
            if let Some(place) = self.places[slot as usize].as_mut() {
                place.coarse = coarse.map(Box::new);
            }
            if let Some(streaming) = &mut self.streaming {
                streaming.count_streamed(bytes);
            }
            return Ok(Some(bytes));
        }
        // No room: the coarse form stays where it is, and the full detail is tried later.
        if let Some(streaming) = &mut self.streaming {
            streaming.set_coarse(slot);
            streaming.load_failed(slot, LoadRetry::Later);
        }
        match coarse {
            Some(coarse) => {
                self.places[slot as usize] = Some(coarse);
                Ok(None)
            }
            None => self.place(graph, slot),
        }
    }

    /// Clusters and groups in use (up to the end of the last place).
    pub(super) fn cluster_counts(&self) -> [u32; 2] {
        [self.tails[3], self.tails[4]]
    }

    /// Frees the room of slot `slot`'s place (and of the coarse form's place it keeps), if it
    /// has one.
    fn release(&mut self, slot: u32) {
        if let Some(mut place) = self.places.get_mut(slot as usize).and_then(Option::take) {
            self.free_kept_coarse(&mut place);
            self.free.push((place.starts(), place.room));
        }
    }

    /// Frees the room of the coarse form's place `place` keeps, if it keeps one.
    fn free_kept_coarse(&mut self, place: &mut GeometryPlace) {
        if let Some(coarse) = place.coarse.take() {
            self.free.push((coarse.starts(), coarse.room));
        }
    }

    /// Puts slot `slot` back in the coarse form its place kept while at full detail (the full
    /// detail's room freed); false where it kept none (the arenas were laid out while it was
    /// at full detail), so that the coarse form must be placed anew.
    fn restore_coarse(&mut self, slot: u32) -> bool {
        let Some(place) = self.places.get_mut(slot as usize) else {
            return false;
        };
        let Some(coarse) = place.as_mut().and_then(|p| p.coarse.take()) else {
            return false;
        };
        if let Some(full) = place.replace(*coarse) {
            self.free.push((full.starts(), full.room));
        }
        true
    }

    /// Where a geometry of `sizes` can go: the smallest free room that holds it (taken
    /// whole: a file loaded again finds the rooms its geometries left), or the arenas' unused
    /// end. Returns the starts and the room.
    fn allocate(&mut self, sizes: Extent) -> Option<(Extent, Extent)> {
        let fits = |room: &Extent| room.iter().zip(sizes).all(|(&room, n)| n <= room);
        let waste = |room: &Extent| -> u64 {
            room.iter()
                .zip(sizes)
                .map(|(&room, n)| u64::from(room - n))
                .sum()
        };
        let best = (self.free.iter().enumerate())
            .filter(|(_, (_, room))| fits(room))
            .min_by_key(|(_, (_, room))| waste(room))
            .map(|(i, _)| i);
        if let Some(i) = best {
            return Some(self.free.swap_remove(i));
        }
        let ends: Extent = std::array::from_fn(|i| self.tails[i].saturating_add(sizes[i]));
        if ends
            .iter()
            .zip(self.capacity)
            .any(|(&end, capacity)| end > capacity)
        {
            return None;
        }
        let starts = self.tails;
        self.tails = ends;
        Some((starts, sizes))
    }

    /// Writes geometry slot `slot` of `graph` (new, or replaced) into the arenas: over its
    /// place when it fits the room there, else into a free room or the arenas' end (its old
    /// room freed). Returns the bytes uploaded, or `None` when no room holds it (or it is the
    /// first geometry with attributes), so the arenas must be laid out again. A slot whose
    /// geometry is gone has its room freed. The GPU must not be drawing from the arenas
    /// meanwhile (frames are waited for before the next one syncs).
    pub(super) fn place(&mut self, graph: &SceneGraph, slot: u32) -> RenderResult<Option<u64>> {
        let (Some(handle), Some(info)) =
            (graph.geometry_handle_at(slot), graph.geometry_info_at(slot))
        else {
            self.release(slot);
            if let Some(streaming) = &mut self.streaming {
                streaming.forget(slot);
            }
            return Ok(Some(0));
        };
        if info.has_attributes && !self.has_attributes {
            // The first geometry with attributes: the attribute arena is made by a new layout.
            return Ok(None);
        }
        // A known geometry going back to its coarse form is not read again.
        let known = (self.streaming.as_ref()).and_then(|s| s.known_form(slot, handle));
        if let Some(Some(form)) = known {
            let data = coarse_arena_data(&form);
            let written = self.write_place(slot, handle, data, &form.geometry, Some(&form))?;
            return Ok(self.coarse_placed(slot, written));
        }
        let geometry = graph.geometry(handle).map_err(unreadable)?;
        let geometry = &*geometry;
        let has_attributes = self.has_attributes;
        let mut full_data = None;
        let coarse = self.streaming.as_mut().and_then(|streaming| {
            let share = streaming.coarse_share();
            streaming.form_to_place(slot, handle, || {
                let data = arena_data(geometry);
                let form = coarse_form(geometry, &data, has_attributes, share);
                full_data = Some(data);
                form
            })
        });
        let (data, geometry) = match &coarse {
            Some(form) => (coarse_arena_data(form), &form.geometry),
            None => (full_data.unwrap_or_else(|| arena_data(geometry)), geometry),
        };
        let written = self.write_place(slot, handle, data, geometry, coarse.as_deref())?;
        Ok(match coarse {
            Some(_) => self.coarse_placed(slot, written),
            None => written,
        })
    }

    /// Where slot `slot`'s coarse form was `written` to the GPU, streaming lets go of its
    /// arrays; returns `written`.
    fn coarse_placed(&mut self, slot: u32, written: Option<u64>) -> Option<u64> {
        if let (Some(_), Some(streaming)) = (written, &mut self.streaming) {
            streaming.placed(slot);
        }
        written
    }

    /// Writes `data` (made from `geometry`, the coarse form `coarse` of slot `slot`'s geometry
    /// where that is what goes on the GPU) over slot `slot`'s place where it fits the room
    /// there, else into a free room or the arenas' end. Returns the bytes uploaded, or `None`
    /// when no room holds it.
    fn write_place(
        &mut self,
        slot: u32,
        handle: GeometryHandle,
        data: ArenaData<'_>,
        geometry: &Geometry,
        coarse: Option<&CoarseForm>,
    ) -> RenderResult<Option<u64>> {
        let sizes = data.sizes();
        if self.places.len() <= slot as usize {
            self.places.resize(slot as usize + 1, None);
        }
        // A coarse form kept for other data is no longer the geometry's.
        if let Some(mut place) = self.places[slot as usize].take() {
            self.free_kept_coarse(&mut place);
            self.places[slot as usize] = Some(place);
        }
        let fits = |place: &GeometryPlace| place.room.iter().zip(sizes).all(|(&r, n)| n <= r);
        if !self.places[slot as usize].as_ref().is_some_and(fits) {
            self.release(slot);
            let Some((starts, room)) = self.allocate(sizes) else {
                return Ok(None);
            };
            let [vertex_base, first_index, first_wire_index, first_cluster, first_group] = starts;
            self.places[slot as usize] = Some(GeometryPlace {
                handle,
                vertex_base,
                first_index,
                first_wire_index,
                first_cluster,
                first_group,
                room,
                parts: Vec::new(),
                part_clusters: Vec::new(),
                coarse: None,
            });
        }
        let Some(place) = self.places[slot as usize].as_mut() else {
            return Ok(None);
        };
        place.handle = handle;
        let vertex_bytes: &[u8] = bytemuck::cast_slice(data.vertices);
        let index_bytes: Vec<u8> = data
            .clusters
            .indices
            .iter()
            .chain(&data.clusters.lod_indices)
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let wire_bytes: Vec<u8> = data
            .wire
            .iter()
            .chain(&data.clusters.wire_lod)
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let cluster_bytes =
            data.cluster_bytes(place.first_index, place.first_wire_index, place.first_group);
        let box_bytes = data.cluster_box_bytes();
        let group_bytes = data.group_bytes(place.first_cluster);
        let vertex_size = std::mem::size_of::<Vertex>() as u64;
        self.vertices
            .upload_at(u64::from(place.vertex_base) * vertex_size, vertex_bytes)?;
        self.indices
            .upload_at(u64::from(place.first_index) * 4, &index_bytes)?;
        self.wire_indices
            .upload_at(u64::from(place.first_wire_index) * 4, &wire_bytes)?;
        self.clusters.upload_at(
            u64::from(place.first_cluster) * CLUSTER_BYTES as u64,
            &cluster_bytes,
        )?;
        self.cluster_boxes.upload_at(
            u64::from(place.first_cluster) * CLUSTER_BOX_BYTES as u64,
            &box_bytes,
        )?;
        self.groups.upload_at(
            u64::from(place.first_group) * GROUP_BYTES as u64,
            &group_bytes,
        )?;
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
        let streamed = self.streaming.as_ref().and_then(|s| s.coarse_form_of(slot));
        place.parts = match (coarse, streamed) {
            (Some(form), _) => coarse_part_entries(form, slot, part_entries(&data)),
            (None, Some(form)) => full_part_entries(&form, slot, part_entries(&data)),
            (None, None) => part_entries(&data),
        };
        place.part_clusters = data.clusters.part_ranges;
        Ok(Some(
            (vertex_bytes.len()
                + index_bytes.len()
                + wire_bytes.len()
                + attribute_bytes
                + cluster_bytes.len()
                + box_bytes.len()
                + group_bytes.len()) as u64,
        ))
    }
}

/// The arenas' `capacity` with room for the full detail a streaming budget allows (`budget`
/// bytes, of a scene whose full detail takes `full_bytes`, `full` elements in all and
/// `largest` for its largest geometry): each arena's share of the budget, a quarter more
/// (geometries differ in how they fill each arena), and the largest geometry.
fn with_streaming_room(
    capacity: Extent,
    (budget, full_bytes): (u64, u64),
    (full, largest): (Extent, Extent),
) -> Extent {
    let share = (1.25 * budget as f64 / full_bytes.max(1) as f64).min(1.0);
    std::array::from_fn(|i| {
        let extra = (f64::from(full[i]) * share).ceil() as u32;
        capacity[i]
            .saturating_add(extra)
            .saturating_add(largest[i])
            .saturating_add(4096)
    })
}

/// The elements an arena laid out again holds for `used`: a quarter more, and at least a few
/// thousand, so that the geometries loaded next fit without another layout.
fn with_spare_room(used: u32) -> u32 {
    used.saturating_add(used / 4).saturating_add(4096)
}

/// Appends `geometry`'s texture coordinates and colours (white at (0, 0) where it has none).
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
    fn each_clusters_box_holds_its_vertices_and_touches_them_on_every_side() {
        let mut builder = GeometryBuilder::new("prisms");
        builder.prism(200, DMat4::from_scale(glam::DVec3::new(4.0, 0.5, 1.0)));
        let geometry = builder.finish();
        let data = arena_data(&geometry);
        let bytes = data.cluster_box_bytes();
        let clusters = &data.clusters;
        assert_eq!(bytes.len(), clusters.clusters.len() * CLUSTER_BOX_BYTES);
        assert!(clusters.clusters.len() > 1, "a part of several clusters");
        let all: Vec<u32> = clusters
            .indices
            .iter()
            .chain(&clusters.lod_indices)
            .copied()
            .collect();
        for (cluster, bytes) in clusters.clusters.iter().zip(bytes.chunks_exact(32)) {
            let word = |i: usize| {
                f32::from_le_bytes([
                    bytes[4 * i],
                    bytes[4 * i + 1],
                    bytes[4 * i + 2],
                    bytes[4 * i + 3],
                ])
            };
            let (center, half) = ([word(0), word(1), word(2)], [word(4), word(5), word(6)]);
            let first = cluster.first_index as usize;
            let mut reached = [[false; 2]; 3];
            // A level of the part's edges names wire indices (the geometry's, then the
            // levels').
            let indices: Vec<u32> = (first..first + cluster.index_count as usize)
                .map(|i| {
                    if clusters::is_edge_level(clusters, cluster) {
                        *data.wire_index(i).expect("the level names wire indices")
                    } else {
                        all[i]
                    }
                })
                .collect();
            for &i in &indices {
                let p = geometry.vertices[i as usize].position;
                for axis in 0..3 {
                    let offset = p[axis] - center[axis];
                    assert!(
                        offset.abs() <= half[axis],
                        "vertex {i} outside on axis {axis}"
                    );
                    let slack = 1e-5 * (1.0 + half[axis]);
                    reached[axis][0] |= offset <= -half[axis] + slack;
                    reached[axis][1] |= offset >= half[axis] - slack;
                }
            }
            assert_eq!(reached, [[true; 2]; 3], "the box is the smallest");
        }
    }

    /// The positions of the line ends of `wire` among `vertices`.
    fn line_ends(vertices: &[Vertex], wire: &[u32]) -> Vec<[u32; 3]> {
        let mut ends: Vec<[u32; 3]> = (wire.iter())
            .map(|&i| vertices[i as usize].position.map(f32::to_bits))
            .collect();
        ends.sort_unstable();
        ends.dedup();
        ends
    }

    #[test]
    fn a_faceted_parts_coarse_form_is_a_stand_in_drawn_with_the_parts_own_edges() {
        let mut builder = GeometryBuilder::new("prism");
        builder.prism(100, DMat4::IDENTITY);
        let geometry = builder.finish();
        let data = arena_data(&geometry);
        let triangles = geometry.indices.len() / 3;
        let (_, form) = coarse_form(&geometry, &data, false, 0.125);
        // The DAG keeps every crease of a faceted prism: its coarsest cut is the part.
        let form = form.expect("a coarse form from the part's stand-ins");
        let coarse = &form.geometry;
        assert!(
            coarse.indices.len() / 3 <= triangles / 8 + 1,
            "{} of {triangles} triangles",
            coarse.indices.len() / 3
        );
        assert!(form.errors[0] > 0.0, "{:?}", form.errors);
        // Its edges are the part's, at a level within the form's error: ends at the part's
        // edge vertices, fewer lines than the 300 the prism has.
        let full_ends = line_ends(&geometry.vertices, &data.wire);
        let ends = line_ends(&coarse.vertices, &coarse.wire_indices);
        assert!(!ends.is_empty() && ends.iter().all(|e| full_ends.binary_search(e).is_ok()));
        let lines = coarse.wire_indices.len() / 2;
        assert!(lines < data.wire.len() / 2, "{lines} lines");
        // Laid out with those edges, not edges found again on the stand-in's triangles.
        let laid_out = coarse_arena_data(&form);
        assert_eq!(laid_out.wire.as_ref(), coarse.wire_indices.as_slice());
    }

    #[test]
    fn a_smooth_parts_coarse_form_draws_no_edge_where_the_part_has_none() {
        // A sphere: no crease anywhere, but a coarse form of a few dozen triangles has folds
        // steeper than the crease angle.
        let (rings, segments) = (24u32, 48u32);
        let vertex = |p: [f32; 3]| Vertex {
            position: p,
            normal: p,
        };
        // The poles, then the rings between them: closed, without seams.
        let mut vertices = vec![vertex([0.0, 1.0, 0.0]), vertex([0.0, -1.0, 0.0])];
        for ring in 1..rings {
            let polar = std::f32::consts::PI * ring as f32 / rings as f32;
            for segment in 0..segments {
                let azimuth = std::f32::consts::TAU * segment as f32 / segments as f32;
                let (x, z) = (polar.sin() * azimuth.cos(), polar.sin() * azimuth.sin());
                vertices.push(vertex([x, polar.cos(), z]));
            }
        }
        let at = |ring: u32, segment: u32| 2 + (ring - 1) * segments + segment % segments;
        let mut indices = Vec::new();
        for segment in 0..segments {
            indices.extend_from_slice(&[0, at(1, segment + 1), at(1, segment)]);
            let last = rings - 1;
            indices.extend_from_slice(&[1, at(last, segment), at(last, segment + 1)]);
            for ring in 1..last {
                let (a, b) = (at(ring, segment), at(ring + 1, segment));
                let (c, d) = (at(ring, segment + 1), at(ring + 1, segment + 1));
                indices.extend_from_slice(&[a, c, b, c, d, b]);
            }
        }
        let part = Part {
            first_index: 0,
            index_count: indices.len() as u32,
            first_wire_index: 0,
            wire_index_count: 0,
        };
        let geometry = Geometry {
            name: "sphere".into(),
            vertices,
            indices,
            parts: vec![part],
            ..Geometry::default()
        };
        let data = arena_data(&geometry);
        assert!(data.wire.is_empty(), "a sphere has no feature edge");
        let (_, form) = coarse_form(&geometry, &data, false, 0.02);
        let form = form.expect("a coarse form");
        let refound = crate::scene::edges::feature_edges(&form.geometry, DEFAULT_CREASE_DEGREES).0;
        assert!(
            !refound.is_empty(),
            "its coarse triangles fold past the crease angle"
        );
        assert!(coarse_arena_data(&form).wire.is_empty());
    }

    #[test]
    fn a_part_is_curved_where_a_triangle_has_normals_that_differ() {
        let mut builder = GeometryBuilder::new("prism");
        builder.prism(48, DMat4::IDENTITY);
        let faceted = builder.finish();
        assert_eq!(
            shape_flags(
                &faceted.vertices,
                &first_at_position(&faceted.vertices),
                &faceted.indices
            ) & abi::CADR_INSTANCE_CURVED,
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
