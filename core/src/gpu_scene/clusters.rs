//! Clusters and their level-of-detail DAG, per part of a geometry, built with meshoptimizer's
//! cluster LOD library (`meshopt::clod_build`, the same method as Nanite and vk_lod_clusters):
//! the part's triangles are split into clusters of at most [`MAX_CLUSTER_TRIANGLES`]
//! triangles and vertices; neighbouring clusters are grouped, each group simplified to half
//! its triangles with its outer border locked, and split again, level after level, each group
//! recording the error of its simplification (which only grows toward the coarse levels).
//!
//! A part whose coarsest simplification still has many triangles (faceted parts, whose every
//! vertex is on a crease the simplification keeps) ends its DAG in stand-ins
//! ([`abi::CADR_CLUSTER_PROXY_DEPTH`], made in `stand_ins.rs`): whole-part simplifications,
//! coarser one after the other, one of which is drawn in place of the whole part where its
//! error projects under the threshold, so that a far part costs tens of triangles instead of
//! hundreds (and never vanishes).
//!
//! The part's original clusters keep exactly its triangles: they are written back over the
//! part's own index range, cluster after cluster, so every technique that draws the part whole
//! draws the same triangles as before, in cluster order. The coarser clusters' indices go after
//! the geometry's own indices and name the same vertices (simplification only removes them).
//!
//! Building is the slow part of putting a large geometry on the GPU (seconds for millions of
//! triangles), so a geometry of [`CACHED_TRIANGLES`] or more keeps its clusters in the disk
//! cache, keyed by its content; an entry is checked through before it is used.

use meshopt::{ClodCluster, ClodGroup, ClodMesh, VertexDataAdapter};

use super::{bounds, edge_levels, stand_ins};
use crate::disk_cache::{self, DiskCache};
use crate::scene::{Part, Vertex};
use cadr_plugin_abi as abi;

/// Geometries with at least this many triangles keep their clusters in the disk cache; below,
/// building them is quicker than reading a file.
pub const CACHED_TRIANGLES: usize = 8192;

/// What a cache entry's key starts with: bump it when the clusters a geometry gets change.
const CACHE_VERSION: &[u8] =
    b"clusters 13: clod 128, normals protected, no sloppy fallback, small parts whole, spans, welded stand-ins from one source at 0.7, spatial clusters for fans, edge levels";
/// The disk cache's kind of entry.
const CACHE_KIND: &str = "clusters";

/// The most triangles (and vertices) in one cluster: within what mesh shaders emit on every
/// device cadr runs on, and small enough for culling to pay.
pub const MAX_CLUSTER_TRIANGLES: usize = 128;

/// A part's coarsest cut with more triangles than this gets stand-ins after it.
const PROXY_AFTER_TRIANGLES: usize = 32;

/// A cone cutoff no test passes: triangles that face too many ways (or a cluster whose cone
/// could not be trusted) are never culled as back-facing.
const NO_CONE: f32 = 2.0;

/// A geometry's clusters, as the arenas hold them.
#[derive(Debug, Default)]
pub(super) struct GeometryClusters {
    /// The geometry's triangle indices with each part's range reordered cluster by cluster.
    pub(super) indices: Vec<u32>,
    /// The coarser clusters' indices, which follow `indices` in the index arena.
    pub(super) lod_indices: Vec<u32>,
    /// Every part's clusters, the parts one after the other; `first_index` relative to the
    /// geometry's first index, `group` relative to the geometry's first group.
    pub(super) clusters: Vec<abi::CadrCluster>,
    /// The DAGs' groups, the parts one after the other.
    pub(super) groups: Vec<abi::CadrClusterGroup>,
    /// Per part: its first cluster in `clusters`, how many it has, and how many of them are
    /// in groups never simplified further (its coarsest cut).
    pub(super) part_ranges: Vec<[u32; 3]>,
    /// The coarser levels of the parts' feature edges (`edge_levels.rs`), a line list that
    /// follows the geometry's own edge indices in the wire index arena; empty until added
    /// (the disk cache keeps the clusters without them).
    pub(super) wire_lod: Vec<u32>,
    /// Per part (where added): how many edge levels follow its clusters.
    pub(super) edge_levels: Vec<u32>,
}

/// One part's DAG as `clod_build` hands it over, before it is laid out.
#[derive(Default)]
struct PartDag {
    /// Per cluster: its indices (into the geometry's vertices), its group and refined group.
    clusters: Vec<(Vec<u32>, u32, u32)>,
    groups: Vec<abi::CadrClusterGroup>,
}

/// [`build`] with the levels of the parts' edges (`wire`, the geometry's line list; see
/// `edge_levels.rs`), through the user's disk cache for a geometry of [`CACHED_TRIANGLES`] or
/// more.
pub(super) fn build_cached(
    vertices: &[Vertex],
    indices: &[u32],
    wire: &[u32],
    parts: &[Part],
) -> GeometryClusters {
    let build_all = || {
        let mut clusters = build(vertices, indices, parts);
        add_edge_levels(&mut clusters, vertices, wire, parts);
        clusters
    };
    let cache = (indices.len() / 3 >= CACHED_TRIANGLES)
        .then(DiskCache::user)
        .flatten();
    let Some(cache) = cache else {
        return build_all();
    };
    let part_words: Vec<u32> = parts
        .iter()
        .flat_map(|p| {
            [
                p.first_index,
                p.index_count,
                p.first_wire_index,
                p.wire_index_count,
            ]
        })
        .collect();
    let key = disk_cache::key(&[
        CACHE_VERSION,
        bytemuck::cast_slice(vertices),
        bytemuck::cast_slice(indices),
        bytemuck::cast_slice(wire),
        bytemuck::cast_slice(&part_words),
    ]);
    let sizes = [vertices.len(), indices.len(), wire.len(), parts.len()];
    if let Some(clusters) = cache
        .read(CACHE_KIND, &key)
        .and_then(|bytes| GeometryClusters::from_bytes(&bytes, sizes))
    {
        return clusters;
    }
    let clusters = build_all();
    cache.write(CACHE_KIND, &key, &clusters.to_bytes());
    clusters
}

impl GeometryClusters {
    /// Index `i` of the geometry's index range as the arenas lay it out: its own indices, then
    /// the coarser clusters' (what a cluster's `first_index` counts in).
    pub(super) fn index(&self, i: usize) -> Option<&u32> {
        match i.checked_sub(self.indices.len()) {
            None => self.indices.get(i),
            Some(lod) => self.lod_indices.get(lod),
        }
    }

    /// Index `i` of the geometry's wire index range as the arenas lay it out, the geometry's
    /// own edge indices being `wire`: those, then the levels of its parts' edges (what an edge
    /// level's `first_index` counts in).
    pub(super) fn wire_index<'w>(&'w self, wire: &'w [u32], i: usize) -> Option<&'w u32> {
        match i.checked_sub(wire.len()) {
            None => wire.get(i),
            Some(level) => self.wire_lod.get(level),
        }
    }

    /// Part `part`'s records: its clusters, then the levels of its edges that follow them;
    /// `None` for a part it does not have.
    pub(super) fn part_records(
        &self,
        part: usize,
    ) -> Option<(&[abi::CadrCluster], &[abi::CadrCluster])> {
        let [first, count, _] = self.part_ranges.get(part)?.map(|n| n as usize);
        let levels = self.edge_levels.get(part).map_or(0, |&n| n as usize);
        let end = first.checked_add(count)?;
        let records = self.clusters.get(first..end.checked_add(levels)?)?;
        Some(records.split_at(count))
    }

    /// The cache entry's bytes: the seven lengths, then each array in little-endian words.
    fn to_bytes(&self) -> Vec<u8> {
        let lengths = [
            self.indices.len(),
            self.lod_indices.len(),
            self.clusters.len(),
            self.groups.len(),
            self.part_ranges.len(),
            self.wire_lod.len(),
            self.edge_levels.len(),
        ];
        let mut bytes: Vec<u8> = lengths
            .iter()
            .flat_map(|&n| (n as u64).to_le_bytes())
            .collect();
        for word in self.indices.iter().chain(&self.lod_indices) {
            bytes.extend_from_slice(&word.to_le_bytes());
        }
        for cluster in &self.clusters {
            bytes.extend_from_slice(&cluster.to_le_bytes());
        }
        for group in &self.groups {
            bytes.extend_from_slice(&group.to_le_bytes());
        }
        let words = self.part_ranges.iter().flatten();
        for word in words.chain(&self.wire_lod).chain(&self.edge_levels) {
            bytes.extend_from_slice(&word.to_le_bytes());
        }
        bytes
    }

    /// Reads a cache entry back for a geometry of `[vertices, indices, wire indices, parts]`
    /// (their counts); `None` unless everything in it is in range.
    fn from_bytes(bytes: &[u8], sizes: [usize; 4]) -> Option<Self> {
        let [vertex_count, index_count, wire_count, part_count] = sizes;
        let mut words = bytes
            .chunks_exact(4)
            .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]));
        let mut length = || -> Option<usize> {
            let low = words.next()?;
            let high = words.next()?;
            usize::try_from(u64::from(low) | u64::from(high) << 32).ok()
        };
        let mut lengths = [0_usize; 7];
        for n in &mut lengths {
            *n = length()?;
        }
        let [indices, lod, clusters, groups, parts, wire_lod, edge_levels] = lengths;
        let expected = 56
            + 4 * (indices + lod)
            + 64 * clusters
            + 32 * groups
            + 12 * parts
            + 4 * (wire_lod + edge_levels);
        let counts_fit = indices == index_count
            && parts == part_count
            && (edge_levels == 0 || edge_levels == parts);
        if bytes.len() != expected || !counts_fit {
            return None;
        }
        let mut take = |n: usize| -> Vec<u32> { words.by_ref().take(n).collect() };
        let all_indices = take(indices + lod);
        let cluster_words = take(16 * clusters);
        let group_words = take(8 * groups);
        let range_words = take(3 * parts);
        let wire_lod = take(wire_lod);
        let edge_levels = take(edge_levels);
        let float = f32::from_bits;
        let out = Self {
            indices: all_indices[..indices].to_vec(),
            lod_indices: all_indices[indices..].to_vec(),
            clusters: cluster_words
                .chunks_exact(16)
                .map(|w| abi::CadrCluster {
                    sphere: [float(w[0]), float(w[1]), float(w[2]), float(w[3])],
                    cone_apex: [float(w[4]), float(w[5]), float(w[6])],
                    cone_cutoff: float(w[7]),
                    cone_axis: [float(w[8]), float(w[9]), float(w[10])],
                    first_index: w[11],
                    index_count: w[12],
                    group: w[13],
                    refined: w[14],
                    part_clusters: w[15],
                })
                .collect(),
            groups: group_words
                .chunks_exact(8)
                .map(|w| abi::CadrClusterGroup {
                    sphere: [float(w[0]), float(w[1]), float(w[2]), float(w[3])],
                    error: float(w[4]),
                    depth: w[5],
                    first_cluster: w[6],
                    cluster_count: w[7],
                })
                .collect(),
            part_ranges: range_words
                .chunks_exact(3)
                .map(|w| [w[0], w[1], w[2]])
                .collect(),
            wire_lod,
            edge_levels,
        };
        out.is_consistent(vertex_count, wire_count).then_some(out)
    }

    /// Whether every index names a vertex, every cluster's indices and groups exist (an edge
    /// level's in the `wire_count` wire indices and its levels), and every part's clusters are
    /// in range: what the GPU may trust of an entry read from disk.
    fn is_consistent(&self, vertex_count: usize, wire_count: usize) -> bool {
        let total = self.indices.len() + self.lod_indices.len();
        let wire_total = wire_count + self.wire_lod.len();
        let groups = self.groups.len();
        let group_ok = |g: u32| (g as usize) < groups;
        let in_range = |c: &abi::CadrCluster, total: usize| {
            (c.first_index as usize).saturating_add(c.index_count as usize) <= total
        };
        self.indices
            .iter()
            .chain(&self.lod_indices)
            .chain(&self.wire_lod)
            .all(|&i| (i as usize) < vertex_count)
            && self.clusters.iter().all(|c| {
                if !group_ok(c.group) {
                    return false;
                }
                if is_edge_level(self, c) {
                    return in_range(c, wire_total) && c.index_count % 2 == 0;
                }
                in_range(c, total)
                    && c.index_count % 3 == 0
                    && (c.refined == abi::CADR_CLUSTER_ORIGINAL || group_ok(c.refined))
            })
            && self.groups.iter().all(|g| {
                (g.first_cluster as usize).saturating_add(g.cluster_count as usize)
                    <= self.clusters.len()
                    && self.clusters[g.first_cluster as usize..][..g.cluster_count as usize]
                        .iter()
                        .all(|c| self.groups.get(c.group as usize) == Some(g))
            })
            && self
                .part_ranges
                .iter()
                .enumerate()
                .all(|(part, &[_, count, coarsest])| {
                    // A part's edge levels, right after its clusters, each saying how many there are.
                    let Some((own, levels)) = self.part_records(part) else {
                        return false;
                    };
                    coarsest <= count
                        && own
                            .iter()
                            .all(|c| c.part_clusters == count && !is_edge_level(self, c))
                        && levels
                            .iter()
                            .all(|c| is_edge_level(self, c) && c.refined as usize == levels.len())
                })
    }
}

/// Adds the coarser levels of every part's edges to `clusters` (the clusters of the geometry
/// of `vertices` and `parts`, whose edges are `wire`): per level a record right after the
/// part's clusters and a group of depth [`abi::CADR_CLUSTER_EDGE_DEPTH`] after the geometry's
/// groups, and its lines in [`GeometryClusters::wire_lod`]. The parts' clusters move down to
/// make room (their groups' spans with them); nothing else changes.
pub(super) fn add_edge_levels(
    clusters: &mut GeometryClusters,
    vertices: &[Vertex],
    wire: &[u32],
    parts: &[Part],
) {
    let levels_of = |part: &Part| {
        let start = part.first_wire_index as usize;
        let end = start.saturating_add(part.wire_index_count as usize);
        // A part without triangles has no clusters to follow.
        match wire.get(start..end) {
            Some(lines) if part.index_count >= 3 => edge_levels::edge_levels(vertices, lines),
            _ => (Vec::new(), [0.0; 4]),
        }
    };
    let levels: Vec<_> = parts.iter().map(levels_of).collect();
    if parts.len() != clusters.part_ranges.len() || levels.iter().all(|(l, _)| l.is_empty()) {
        clusters.edge_levels = vec![0; clusters.part_ranges.len()];
        return;
    }
    let old = std::mem::take(&mut clusters.clusters);
    clusters.edge_levels.clear();
    for (range, (part_levels, sphere)) in clusters.part_ranges.iter_mut().zip(levels) {
        let [first, count, _] = *range;
        range[0] = clusters.clusters.len() as u32;
        let own = old
            .get(first as usize..(first + count) as usize)
            .unwrap_or(&[]);
        clusters.clusters.extend_from_slice(own);
        clusters.edge_levels.push(part_levels.len() as u32);
        for level in &part_levels {
            let group = clusters.groups.len() as u32;
            clusters.groups.push(abi::CadrClusterGroup {
                sphere,
                error: level.error,
                depth: abi::CADR_CLUSTER_EDGE_DEPTH,
                first_cluster: 0,
                cluster_count: 0,
            });
            clusters.clusters.push(abi::CadrCluster {
                sphere,
                cone_cutoff: NO_CONE,
                first_index: (wire.len() + clusters.wire_lod.len()) as u32,
                index_count: level.lines.len() as u32,
                group,
                refined: part_levels.len() as u32,
                part_clusters: count,
                ..abi::CadrCluster::default()
            });
            clusters.wire_lod.extend_from_slice(&level.lines);
        }
    }
    for group in &mut clusters.groups {
        group.cluster_count = 0;
    }
    set_group_spans(clusters, 0);
}

/// Whether `cluster` of `clusters` is a level of its part's edges rather than triangles.
pub(super) fn is_edge_level(clusters: &GeometryClusters, cluster: &abi::CadrCluster) -> bool {
    clusters
        .groups
        .get(cluster.group as usize)
        .is_some_and(|g| g.depth == abi::CADR_CLUSTER_EDGE_DEPTH)
}

/// Builds the clusters of every part of a geometry. Parts whose ranges overlap another's, or
/// that lie outside the indices, keep their order and are cut into consecutive runs of
/// triangles without coarser levels (a scene that passed validation has neither).
pub(super) fn build(vertices: &[Vertex], indices: &[u32], parts: &[Part]) -> GeometryClusters {
    let mut out = GeometryClusters {
        indices: indices.to_vec(),
        ..GeometryClusters::default()
    };
    let bytes: &[u8] = bytemuck::cast_slice(vertices);
    let adapter = VertexDataAdapter::new(bytes, std::mem::size_of::<Vertex>(), 0).ok();
    let disjoint = parts_are_disjoint(parts, indices.len());
    let own_indices = |part: &Part| {
        let start = part.first_index as usize;
        indices
            .get(start..start + part.index_count as usize)
            .unwrap_or(&[])
    };
    // A part that fits one cluster has no coarser level to build (and most CAD parts are that
    // small): it is its own cluster, in its own order.
    let dag_of = |part: &Part| {
        let own = own_indices(part);
        let wanted = adapter.is_some() && disjoint && own.len() % 3 == 0 && !fits_one_cluster(own);
        wanted.then(|| part_dag(vertices, own)).flatten()
    };
    // A large geometry builds its parts' DAGs on every core, a part per core at a time (one
    // exported as a single mesh of many primitives would otherwise take one core for all of
    // it, and no more DAGs are held at once than cores); a small one one after the other.
    let at_once = if indices.len() / 3 >= PARALLEL_PARTS_TRIANGLES {
        std::thread::available_parallelism().map_or(1, usize::from)
    } else {
        1
    };
    let dags = parts.chunks(at_once).flat_map(|chunk| match chunk {
        [part] => vec![dag_of(part)],
        _ => crate::parallel::map(chunk, dag_of),
    });
    for (part, dag) in parts.iter().zip(dags) {
        let own = own_indices(part);
        let first_cluster = out.clusters.len() as u32;
        match (dag, &adapter) {
            (Some(dag), Some(adapter)) => lay_out(&mut out, adapter, dag, part.first_index),
            (_, adapter) => runs_of_triangles(&mut out, adapter.as_ref(), own, part.first_index),
        }
        let count = out.clusters.len() as u32 - first_cluster;
        for cluster in &mut out.clusters[first_cluster as usize..] {
            cluster.part_clusters = count;
        }
        set_group_spans(&mut out, first_cluster);
        let coarsest = out.clusters[first_cluster as usize..]
            .iter()
            .filter(|c| {
                out.groups
                    .get(c.group as usize)
                    .is_some_and(|g| g.error == f32::MAX)
            })
            .count() as u32;
        out.part_ranges.push([first_cluster, count, coarsest]);
    }
    out
}

/// The triangles of a geometry from which its parts' DAGs are built in parallel.
const PARALLEL_PARTS_TRIANGLES: usize = 1 << 16;

/// Sets the first cluster and the cluster count of the groups of the part whose clusters start
/// at `first_cluster` (each group's clusters are contiguous: see `lay_out`).
fn set_group_spans(out: &mut GeometryClusters, first_cluster: u32) {
    for k in first_cluster as usize..out.clusters.len() {
        let group = out.clusters[k].group as usize;
        if let Some(group) = out.groups.get_mut(group) {
            if group.cluster_count == 0 {
                group.first_cluster = k as u32;
            }
            group.cluster_count += 1;
        }
    }
}

/// Whether the parts' index ranges lie within `index_count` and share no index.
fn parts_are_disjoint(parts: &[Part], index_count: usize) -> bool {
    let mut ranges: Vec<(usize, usize)> = parts
        .iter()
        .map(|p| {
            let start = p.first_index as usize;
            (start, start + p.index_count as usize)
        })
        .collect();
    ranges.sort_unstable();
    ranges.iter().all(|&(_, end)| end <= index_count)
        && ranges.windows(2).all(|pair| pair[0].1 <= pair[1].0)
}

/// Whether the triangles `indices` fit one cluster: at most [`MAX_CLUSTER_TRIANGLES`]
/// triangles and as many distinct vertices.
fn fits_one_cluster(indices: &[u32]) -> bool {
    if indices.len() > MAX_CLUSTER_TRIANGLES * 3 {
        return false;
    }
    let mut distinct = indices.to_vec();
    distinct.sort_unstable();
    distinct.dedup();
    distinct.len() <= MAX_CLUSTER_TRIANGLES
}

/// The DAG of one part (`indices` into `vertices`, a multiple of 3), or `None` when its
/// original clusters do not hold exactly its triangles. The library is given the part's own
/// vertices only (its work per call grows with the vertices it is given: a geometry of many
/// parts would otherwise cost parts × vertices).
fn part_dag(vertices: &[Vertex], indices: &[u32]) -> Option<PartDag> {
    let mut used = indices.to_vec();
    used.sort_unstable();
    used.dedup();
    let local_of = |global: u32| used.binary_search(&global).ok().map(|i| i as u32);
    let local_indices: Vec<u32> = indices
        .iter()
        .map(|&i| local_of(i))
        .collect::<Option<_>>()?;
    let local: Vec<Vertex> = used
        .iter()
        .map(|&i| vertices.get(i as usize).copied())
        .collect::<Option<_>>()?;
    let normals: Vec<f32> = local.iter().flat_map(|v| v.normal).collect();
    let bytes: &[u8] = bytemuck::cast_slice(&local);
    let adapter = VertexDataAdapter::new(bytes, std::mem::size_of::<Vertex>(), 0).ok()?;
    let mut mesh = ClodMesh::new(&local_indices, &adapter);
    // Normals steer the simplification (a crease stays a crease) and their discontinuities
    // (split vertices along hard edges) are kept as seams.
    mesh.vertex_attributes = &normals;
    mesh.vertex_attributes_stride = 3 * std::mem::size_of::<f32>();
    mesh.attribute_weights = &[0.5, 0.5, 0.5];
    mesh.attribute_protect_mask = 0b111;
    let mut config = meshopt::clod_default_config(MAX_CLUSTER_TRIANGLES);
    config.cluster_spatial = fan_work(&local_indices, local.len()) > FLEX_FAN_WORK_LIMIT;
    // Where the careful simplification is stuck, the library may fall back to a sloppy one
    // that ignores normals and seams: faceted CAD features (prisms, fins) came out as smooth
    // blobs within the error bound. Stuck groups stay as they are instead.
    config.simplify_fallback_sloppy = false;
    let mut dag = PartDag::default();
    meshopt::clod_build(
        config,
        &mesh,
        |group: ClodGroup, clusters: &[ClodCluster<'_>]| {
            let id = dag.groups.len() as u32;
            let bounds = group.simplified;
            dag.groups.push(abi::CadrClusterGroup {
                sphere: [
                    bounds.center[0],
                    bounds.center[1],
                    bounds.center[2],
                    bounds.radius,
                ],
                error: if bounds.error.is_finite() {
                    bounds.error.max(0.0)
                } else {
                    f32::MAX
                },
                depth: group.depth.max(0) as u32,
                first_cluster: 0,
                cluster_count: 0,
            });
            for cluster in clusters {
                let refined = u32::try_from(cluster.refined).unwrap_or(abi::CADR_CLUSTER_ORIGINAL);
                let global = cluster
                    .indices
                    .iter()
                    .map(|&i| used.get(i as usize).copied().unwrap_or(0))
                    .collect();
                dag.clusters.push((global, id, refined));
            }
            id as i32
        },
    );
    let original: usize = dag
        .clusters
        .iter()
        .filter(|(_, _, refined)| *refined == abi::CADR_CLUSTER_ORIGINAL)
        .map(|(cluster, _, _)| cluster.len())
        .sum();
    if original != indices.len() {
        return None;
    }
    add_stand_ins(&mut dag, &local, &local_indices, &used);
    Some(dag)
}

/// Above this [`fan_work`], a part's clusters are made by meshoptimizer's spatial
/// clusterizer instead of its flexible one: about 70 ms of the flexible one's time.
const FLEX_FAN_WORK_LIMIT: u64 = 1 << 25;

/// The work meshoptimizer's flexible clusterizer (`meshopt_buildMeshletsFlex`, which grows
/// clusters through shared vertices) spends on the part's fans: for every triangle it adds,
/// it scans the live triangles around each vertex of the cluster, so a vertex shared by `v`
/// triangles costs about `v²` (a prism of 25 000 triangles, each cap a fan of 6 250 around
/// one vertex as CAD tessellators make of planar faces, took 163 ms, one of 10 000 27 ms; a
/// part of a million such triangles would take minutes). Counted over
/// the vertices shared by more than 64 triangles (a smooth or faceted surface's vertices are
/// shared by about 6, whatever its size, and cost it nothing of the kind). The spatial
/// clusterizer splits the triangles by position, at a cost that grows as `n log n`, for clusters
/// about as full on such parts (on smooth ones it makes about 40 % more, so it is kept for
/// fans).
fn fan_work(local_indices: &[u32], vertex_count: usize) -> u64 {
    let mut shared_by = vec![0_u32; vertex_count];
    for &vertex in local_indices {
        if let Some(count) = shared_by.get_mut(vertex as usize) {
            *count += 1;
        }
    }
    shared_by
        .iter()
        .filter(|&&count| count > 64)
        .map(|&count| u64::from(count) * u64::from(count))
        .sum()
}

/// Ends the part's DAG with its stand-ins (`stand_ins.rs`) where its coarsest cut has more
/// than [`PROXY_AFTER_TRIANGLES`]: each in a group of its own
/// ([`abi::CADR_CLUSTER_PROXY_DEPTH`]), from the finest to the coarsest, with errors no less
/// than any error below them, measured from one sphere around the part's box and every
/// group's. A stand-in's `refined` names a terminal group, so that a culler that does not know
/// stand-ins never draws it. `local` are the part's own vertices, `local_indices` its
/// triangles among them, `used` their indices in the geometry.
fn add_stand_ins(dag: &mut PartDag, local: &[Vertex], local_indices: &[u32], used: &[u32]) {
    let terminal = |group: u32| dag.groups[group as usize].error == f32::MAX;
    let coarsest: usize = dag
        .clusters
        .iter()
        .filter(|(_, group, _)| terminal(*group))
        .map(|(indices, _, _)| indices.len() / 3)
        .sum();
    let Some(&(_, stands_for, _)) = dag.clusters.iter().find(|(_, group, _)| terminal(*group))
    else {
        return;
    };
    if coarsest <= PROXY_AFTER_TRIANGLES {
        return;
    }
    let below = dag
        .groups
        .iter()
        .map(|g| g.error)
        .filter(|&e| e < f32::MAX)
        .fold(0.0f32, f32::max);
    let levels = stand_ins::stand_ins(
        local,
        local_indices,
        (coarsest, MAX_CLUSTER_TRIANGLES),
        below,
    );
    // The box's sphere, grown over every group's: a stand-in's error then projects at least as
    // large as any group's, seen from anywhere.
    let positions = local.iter().map(|v| v.position);
    let (min, max) = bounds::box_of(positions.clone());
    let centre = glam::Vec3::from(std::array::from_fn(|a| 0.5 * (min[a] + max[a])));
    let radius = dag
        .groups
        .iter()
        .fold(bounds::half_box_diagonal(positions), |radius, g| {
            let [x, y, z, r] = g.sphere;
            radius.max(centre.distance(glam::Vec3::new(x, y, z)) + r)
        });
    for level in levels {
        let group = dag.groups.len() as u32;
        dag.groups.push(abi::CadrClusterGroup {
            // Rounding slack, as the clusters' spheres have.
            sphere: [centre.x, centre.y, centre.z, radius * (1.0 + 1e-5)],
            error: level.error,
            depth: abi::CADR_CLUSTER_PROXY_DEPTH,
            first_cluster: 0,
            cluster_count: 0,
        });
        let global = level.indices.iter().map(|&i| used[i as usize]).collect();
        dag.clusters.push((global, group, stands_for));
    }
}

/// The culling bounds and normal cone of the triangles `indices` (at most
/// [`MAX_CLUSTER_TRIANGLES`]).
fn cluster_bounds(adapter: Option<&VertexDataAdapter<'_>>, indices: &[u32]) -> abi::CadrCluster {
    let Some(adapter) = adapter else {
        return abi::CadrCluster {
            cone_cutoff: NO_CONE,
            ..abi::CadrCluster::default()
        };
    };
    let bounds = meshopt::compute_cluster_bounds(indices, adapter);
    let finite = bounds.cone_axis.iter().all(|a| a.is_finite()) && bounds.cone_cutoff.is_finite();
    abi::CadrCluster {
        // Rounding slack, as the parts' spheres have.
        sphere: [
            bounds.center[0],
            bounds.center[1],
            bounds.center[2],
            bounds.radius * (1.0 + 1e-5),
        ],
        cone_apex: bounds.cone_apex,
        cone_cutoff: if finite { bounds.cone_cutoff } else { NO_CONE },
        cone_axis: bounds.cone_axis,
        index_count: indices.len() as u32,
        ..abi::CadrCluster::default()
    }
}

/// Writes a part's DAG into `out`: its original clusters over the part's range (starting at
/// `part_first`), the coarser ones after the geometry's indices.
fn lay_out(
    out: &mut GeometryClusters,
    adapter: &VertexDataAdapter<'_>,
    dag: PartDag,
    part_first: u32,
) {
    let first_group = out.groups.len() as u32;
    out.groups.extend(dag.groups);
    // Each group's clusters together (the library hands them over so; the sort keeps that
    // order), the original ones first.
    let mut clusters = dag.clusters;
    clusters.sort_by_key(|&(_, group, _)| group);
    let (original, coarser): (Vec<_>, Vec<_>) = clusters
        .into_iter()
        .partition(|(_, _, refined)| *refined == abi::CADR_CLUSTER_ORIGINAL);
    let mut next = part_first as usize;
    for (indices, group, _) in original {
        out.indices[next..next + indices.len()].copy_from_slice(&indices);
        out.clusters.push(abi::CadrCluster {
            first_index: next as u32,
            group: first_group + group,
            refined: abi::CADR_CLUSTER_ORIGINAL,
            ..cluster_bounds(Some(adapter), &indices)
        });
        next += indices.len();
    }
    for (indices, group, refined) in coarser {
        let first = (out.indices.len() + out.lod_indices.len()) as u32;
        out.clusters.push(abi::CadrCluster {
            first_index: first,
            group: first_group + group,
            refined: first_group + refined,
            ..cluster_bounds(Some(adapter), &indices)
        });
        out.lod_indices.extend_from_slice(&indices);
    }
}

/// A part kept in its order: consecutive runs of [`MAX_CLUSTER_TRIANGLES`] triangles, each its
/// own coarsest cluster (one terminal group for the part).
fn runs_of_triangles(
    out: &mut GeometryClusters,
    adapter: Option<&VertexDataAdapter<'_>>,
    indices: &[u32],
    part_first: u32,
) {
    let group = out.groups.len() as u32;
    out.groups.push(abi::CadrClusterGroup {
        error: f32::MAX,
        ..abi::CadrClusterGroup::default()
    });
    let whole = indices.len() - indices.len() % 3;
    for (k, run) in indices[..whole]
        .chunks(MAX_CLUSTER_TRIANGLES * 3)
        .enumerate()
    {
        let in_range = adapter.filter(|a| run.iter().all(|&i| (i as usize) < a.vertex_count));
        out.clusters.push(abi::CadrCluster {
            first_index: part_first + (k * MAX_CLUSTER_TRIANGLES * 3) as u32,
            group,
            refined: abi::CADR_CLUSTER_ORIGINAL,
            ..cluster_bounds(in_range, run)
        });
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

    use super::*;

    fn sorted_triangles(indices: &[u32]) -> Vec<[u32; 3]> {
        let mut triangles: Vec<[u32; 3]> = indices
            .chunks_exact(3)
            .map(|t| {
                // The same triangle, whichever vertex it starts from.
                let k = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
                [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
            })
            .collect();
        triangles.sort_unstable();
        triangles
    }

    /// A smooth UV sphere of radius 1 at `center` (shared vertices and normals), appended to
    /// `geometry` as one part.
    fn add_sphere(geometry: &mut crate::scene::Geometry, segments: u32, center: [f32; 3]) {
        let rings = segments / 2;
        let base = geometry.vertices.len() as u32;
        for r in 0..=rings {
            let polar = std::f32::consts::PI * r as f32 / rings as f32;
            for s in 0..=segments {
                let azimuth = std::f32::consts::TAU * s as f32 / segments as f32;
                let normal = [
                    polar.sin() * azimuth.cos(),
                    polar.cos(),
                    polar.sin() * azimuth.sin(),
                ];
                let position = [0, 1, 2].map(|a| center[a] + normal[a]);
                geometry.vertices.push(Vertex { position, normal });
            }
        }
        let first_index = geometry.indices.len() as u32;
        let row = segments + 1;
        for r in 0..rings {
            for s in 0..segments {
                let a = base + r * row + s;
                let (b, c, d) = (a + 1, a + row, a + row + 1);
                geometry.indices.extend([a, b, c, b, d, c]);
            }
        }
        geometry.parts.push(Part {
            first_index,
            index_count: geometry.indices.len() as u32 - first_index,
            ..Part::default()
        });
    }

    /// Two smooth spheres of thousands of triangles, one part each.
    fn fine_geometry() -> crate::scene::Geometry {
        let mut geometry = crate::scene::Geometry::default();
        add_sphere(&mut geometry, 64, [0.0; 3]);
        add_sphere(&mut geometry, 48, [4.0, 0.0, 0.0]);
        geometry
    }

    #[test]
    fn original_clusters_tile_each_part_with_its_own_triangles() {
        let geometry = fine_geometry();
        let built = build(&geometry.vertices, &geometry.indices, &geometry.parts);
        assert_eq!(built.part_ranges.len(), geometry.parts.len());
        for (part, &[first, count, _]) in geometry.parts.iter().zip(&built.part_ranges) {
            let range = part.first_index as usize..(part.first_index + part.index_count) as usize;
            assert_eq!(
                sorted_triangles(&built.indices[range.clone()]),
                sorted_triangles(&geometry.indices[range.clone()]),
                "the same triangles, reordered"
            );
            let clusters = &built.clusters[first as usize..(first + count) as usize];
            let mut next = part.first_index;
            for cluster in clusters
                .iter()
                .filter(|c| c.refined == abi::CADR_CLUSTER_ORIGINAL)
            {
                assert_eq!(cluster.first_index, next, "original clusters tile the part");
                assert!(cluster.index_count as usize <= MAX_CLUSTER_TRIANGLES * 3);
                next += cluster.index_count;
            }
            assert_eq!(next, part.first_index + part.index_count);
            assert!(clusters.iter().all(|c| c.part_clusters == count));
            assert!(
                clusters
                    .iter()
                    .any(|c| c.refined != abi::CADR_CLUSTER_ORIGINAL),
                "a part of thousands of triangles has coarser levels"
            );
        }
    }

    #[test]
    fn errors_grow_toward_the_coarse_levels_and_every_part_ends_in_a_terminal_group() {
        let geometry = fine_geometry();
        let built = build(&geometry.vertices, &geometry.indices, &geometry.parts);
        for &[first, count, coarsest] in &built.part_ranges {
            let clusters = &built.clusters[first as usize..(first + count) as usize];
            for cluster in clusters {
                let own_group = &built.groups[cluster.group as usize];
                if cluster.refined != abi::CADR_CLUSTER_ORIGINAL
                    && own_group.depth != abi::CADR_CLUSTER_PROXY_DEPTH
                {
                    let refined = &built.groups[cluster.refined as usize];
                    assert!(refined.error <= own_group.error, "errors are monotonic");
                    assert!(refined.depth < own_group.depth || own_group.error == f32::MAX);
                    // The coarse cluster's indices name the part's vertices.
                    let start = cluster.first_index as usize - built.indices.len();
                    let lod = &built.lod_indices[start..start + cluster.index_count as usize];
                    assert!(lod.iter().all(|&i| (i as usize) < geometry.vertices.len()));
                }
            }
            let terminal = clusters
                .iter()
                .filter(|c| built.groups[c.group as usize].error == f32::MAX)
                .count();
            assert!(
                terminal > 0,
                "a part never vanishes: its coarsest clusters are always over any threshold"
            );
            assert_eq!(terminal as u32, coarsest, "the coarsest cut's size");
            assert!(coarsest * 4 < count, "the coarsest cut is a few clusters");
        }
    }

    #[test]
    fn faceted_parts_end_in_stand_ins_coarser_one_after_the_other() {
        // gen:grid's parts: faceted prisms of 400 triangles, every vertex on a crease.
        let scene = crate::generate::generate(
            &crate::generate::GeneratorSpec::parse("grid:parts=1,tris=400").unwrap(),
        );
        let geometry = &scene.geometries[0];
        let built = build(&geometry.vertices, &geometry.indices, &geometry.parts);
        let &[first, count, coarsest] = built.part_ranges.first().unwrap();
        let clusters = &built.clusters[first as usize..(first + count) as usize];
        let is_stand_in = |c: &abi::CadrCluster| {
            built.groups[c.group as usize].depth == abi::CADR_CLUSTER_PROXY_DEPTH
        };
        let stand_ins: Vec<&abi::CadrCluster> =
            clusters.iter().skip_while(|c| !is_stand_in(c)).collect();
        assert!(
            stand_ins.len() >= 3,
            "levels between the part and its coarsest"
        );
        assert!(
            stand_ins.iter().all(|c| is_stand_in(c)),
            "the part's last clusters"
        );
        let triangles: Vec<u32> = stand_ins.iter().map(|c| c.index_count / 3).collect();
        assert!(
            triangles[0] <= MAX_CLUSTER_TRIANGLES as u32,
            "{triangles:?}"
        );
        assert!(*triangles.last().unwrap() <= 8, "{triangles:?}");
        assert!(triangles.windows(2).all(|t| t[1] < t[0]), "{triangles:?}");
        let first_sphere = built.groups[stand_ins[0].group as usize].sphere;
        let mut error_before = 0.0;
        for stand_in in &stand_ins {
            let group = &built.groups[stand_in.group as usize];
            assert_eq!(group.cluster_count, 1);
            assert_eq!(group.sphere, first_sphere, "one sphere for every stand-in");
            assert!(group.error >= error_before && group.error < f32::MAX);
            error_before = group.error;
            // It stands for a terminal group, which a culler that knows no stand-in never
            // leaves.
            assert_eq!(built.groups[stand_in.refined as usize].error, f32::MAX);
            // Made of the part's own vertices.
            let start = stand_in.first_index as usize - built.indices.len();
            let lod = &built.lod_indices[start..start + stand_in.index_count as usize];
            let own = &geometry.indices[geometry.parts[0].first_index as usize..]
                [..geometry.parts[0].index_count as usize];
            assert!(lod.iter().all(|i| own.contains(i)));
        }
        let terminal = clusters
            .iter()
            .filter(|c| built.groups[c.group as usize].error == f32::MAX)
            .count();
        assert_eq!(
            coarsest as usize, terminal,
            "the stand-ins are not the coarsest cut"
        );
        assert!(terminal > 0);
        // Errors: each at least twice the farthest the part's vertices are from it (the part's
        // prism is round: its few-sided levels are off by their sagitta), and no error below
        // them larger, from a sphere around every group's.
        let part = &geometry.parts[0];
        let own = &geometry.indices[part.first_index as usize..][..part.index_count as usize];
        let positions: Vec<[f32; 3]> = geometry.vertices.iter().map(|v| v.position).collect();
        for stand_in in &stand_ins {
            let start = stand_in.first_index as usize - built.indices.len();
            let lod = &built.lod_indices[start..start + stand_in.index_count as usize];
            let farthest = own
                .iter()
                .map(|&i| {
                    let p = glam::Vec3::from(positions[i as usize]);
                    lod.chunks_exact(3)
                        .map(|t| {
                            let [a, b, c] =
                                [t[0], t[1], t[2]].map(|k| glam::Vec3::from(positions[k as usize]));
                            p.distance(stand_ins::closest_on_triangle(p, a, b, c))
                        })
                        .fold(f32::MAX, f32::min)
                })
                .fold(0.0, f32::max);
            let error = built.groups[stand_in.group as usize].error;
            assert!(
                error >= 2.0 * farthest * 0.999,
                "{error} against {farthest}"
            );
        }
        let centre = glam::Vec3::new(first_sphere[0], first_sphere[1], first_sphere[2]);
        for c in clusters.iter().filter(|c| !is_stand_in(c)) {
            let other = &built.groups[c.group as usize];
            let finest = built.groups[stand_ins[0].group as usize].error;
            assert!(other.error == f32::MAX || other.error <= finest);
            let [x, y, z, r] = other.sphere;
            assert!(centre.distance(glam::Vec3::new(x, y, z)) + r <= first_sphere[3] * 1.0001);
        }
        // A part whose coarsest cut is already a few triangles gets none.
        let smooth = fine_geometry();
        let built = build(&smooth.vertices, &smooth.indices, &smooth.parts);
        for &[first, count, _] in &built.part_ranges {
            let clusters = &built.clusters[first as usize..(first + count) as usize];
            let has_stand_ins = clusters
                .iter()
                .any(|c| built.groups[c.group as usize].depth == abi::CADR_CLUSTER_PROXY_DEPTH);
            let coarsest: usize = clusters
                .iter()
                .filter(|c| built.groups[c.group as usize].error == f32::MAX)
                .map(|c| c.index_count as usize / 3)
                .sum();
            assert_eq!(has_stand_ins, coarsest > PROXY_AFTER_TRIANGLES);
        }
    }

    #[test]
    fn the_cones_cull_the_far_side_of_a_sphere_only() {
        let mut geometry = crate::scene::Geometry::default();
        add_sphere(&mut geometry, 64, [0.0; 3]);
        let built = build(&geometry.vertices, &geometry.indices, &geometry.parts);
        let original: Vec<_> = built
            .clusters
            .iter()
            .filter(|c| c.refined == abi::CADR_CLUSTER_ORIGINAL)
            .collect();
        assert!(!original.is_empty());
        // An eye far along +Z sees the +Z face and none of the faces pointing away.
        let eye = [0.0f32, 0.0, 10.0];
        let facing_away = |c: &abi::CadrCluster| {
            let to_apex: Vec<f32> = (0..3).map(|a| c.cone_apex[a] - eye[a]).collect();
            let length = to_apex.iter().map(|d| d * d).sum::<f32>().sqrt();
            let dot: f32 = (0..3).map(|a| to_apex[a] / length * c.cone_axis[a]).sum();
            dot >= c.cone_cutoff
        };
        let culled = original.iter().filter(|c| facing_away(c)).count();
        assert!(
            culled * 5 > original.len(),
            "{culled} of {} clusters face away",
            original.len()
        );
        assert!(
            culled * 5 < original.len() * 3,
            "{culled} of {} clusters face away",
            original.len()
        );
        for cluster in original.iter().filter(|c| facing_away(c)) {
            assert!(
                cluster.sphere[2] < 0.5,
                "a culled cluster lies on the far side"
            );
        }
    }

    #[test]
    fn clusters_come_back_from_the_cache_as_they_were_built_and_damage_is_refused() {
        let geometry = fine_geometry();
        let (wire, parts) = crate::scene::edges::feature_edges(&geometry, 30.0);
        let mut built = build(&geometry.vertices, &geometry.indices, &parts);
        add_edge_levels(&mut built, &geometry.vertices, &wire, &parts);
        assert!(
            built.edge_levels.iter().any(|&n| n > 0),
            "edge levels to keep"
        );
        let bytes = built.to_bytes();
        let (v, i, w, p) = (
            geometry.vertices.len(),
            geometry.indices.len(),
            wire.len(),
            geometry.parts.len(),
        );
        let back = GeometryClusters::from_bytes(&bytes, [v, i, w, p]).unwrap();
        assert_eq!(back.indices, built.indices);
        assert_eq!(back.lod_indices, built.lod_indices);
        assert_eq!(back.clusters, built.clusters);
        assert_eq!(back.groups, built.groups);
        assert_eq!(back.part_ranges, built.part_ranges);
        assert_eq!(back.wire_lod, built.wire_lod);
        assert_eq!(back.edge_levels, built.edge_levels);
        assert!(GeometryClusters::from_bytes(&bytes[..bytes.len() - 4], [v, i, w, p]).is_none());
        assert!(
            GeometryClusters::from_bytes(&bytes, [v, i + 3, w, p]).is_none(),
            "another geometry"
        );
        // An index past the vertices (a checksum would catch it first; this is the last line).
        let mut damaged = bytes.clone();
        damaged[56..60].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(GeometryClusters::from_bytes(&damaged, [v, i, w, p]).is_none());
        // A cluster naming a group that is not there.
        let cluster_at = 56 + 4 * (built.indices.len() + built.lod_indices.len());
        let mut damaged = bytes.clone();
        damaged[cluster_at + 52..cluster_at + 56].copy_from_slice(&9_999_999u32.to_le_bytes());
        assert!(GeometryClusters::from_bytes(&damaged, [v, i, w, p]).is_none());
        // An edge level whose lines run past the wire indices (those of a geometry with fewer
        // edges).
        assert!(GeometryClusters::from_bytes(&bytes, [v, i, w / 2, p]).is_none());
        // A part saying it has more edge levels than follow its clusters.
        let mut damaged = bytes;
        let levels_at = damaged.len() - 4 * built.edge_levels.len();
        let part = built.edge_levels.iter().position(|&n| n > 0).unwrap();
        let more = built.edge_levels[part] + 1;
        damaged[levels_at + 4 * part..][..4].copy_from_slice(&more.to_le_bytes());
        assert!(GeometryClusters::from_bytes(&damaged, [v, i, w, p]).is_none());
    }

    #[test]
    fn overlapping_parts_keep_their_order_in_runs() {
        let geometry = fine_geometry();
        let all = geometry.indices.len() as u32;
        let parts = [
            Part {
                first_index: 0,
                index_count: all,
                ..Part::default()
            },
            Part {
                first_index: 0,
                index_count: 3 * 200,
                ..Part::default()
            },
        ];
        let built = build(&geometry.vertices, &geometry.indices, &parts);
        assert_eq!(built.indices, geometry.indices, "nothing reordered");
        assert!(built.lod_indices.is_empty());
        let [_, second, coarsest] = built.part_ranges[1];
        assert_eq!(second, 2, "200 triangles in runs of 128");
        assert_eq!(coarsest, 2, "runs are their part's coarsest");
    }

    /// A disc capped by one fan (a prism of 5 000 sides: each cap's first vertex is shared by
    /// 4 998 triangles) would cost the flexible clusterizer the square of that: the part is
    /// clustered spatially, and its clusters still hold exactly its triangles, each cluster
    /// within the limits. A smooth sphere's vertices cost nothing of the kind.
    #[test]
    fn a_part_capped_by_a_large_fan_is_clustered_by_position_and_keeps_its_triangles() {
        let mut builder = crate::generate::shapes::GeometryBuilder::new("disc");
        builder.prism(5000, glam::DMat4::IDENTITY);
        let disc = builder.finish();
        assert!(fan_work(&disc.indices, disc.vertices.len()) > FLEX_FAN_WORK_LIMIT);
        let dag = part_dag(&disc.vertices, &disc.indices).unwrap();
        let original: Vec<u32> = dag
            .clusters
            .iter()
            .filter(|(_, _, refined)| *refined == abi::CADR_CLUSTER_ORIGINAL)
            .flat_map(|(indices, _, _)| indices.iter().copied())
            .collect();
        assert_eq!(sorted_triangles(&original), sorted_triangles(&disc.indices));
        for (indices, group, _) in &dag.clusters {
            let mut vertices = indices.clone();
            vertices.sort_unstable();
            vertices.dedup();
            let stand_in = dag.groups[*group as usize].depth == abi::CADR_CLUSTER_PROXY_DEPTH;
            assert!(
                indices.len() / 3 <= MAX_CLUSTER_TRIANGLES,
                "{}",
                indices.len() / 3
            );
            assert!(stand_in || vertices.len() <= 128, "{}", vertices.len());
        }

        let mut sphere = crate::scene::Geometry::default();
        add_sphere(&mut sphere, 256, [0.0; 3]);
        assert!(fan_work(&sphere.indices, sphere.vertices.len()) < FLEX_FAN_WORK_LIMIT / 100);
    }

    /// A geometry large enough to build its parts' DAGs on every core gives each part the
    /// clusters and groups it gets when built alone, in the parts' order.
    #[test]
    fn a_large_geometrys_parts_built_together_get_the_dags_they_get_alone() {
        let mut together = crate::scene::Geometry::default();
        for (k, segments) in [160, 150, 170].into_iter().enumerate() {
            add_sphere(&mut together, segments, [3.0 * k as f32, 0.0, 0.0]);
        }
        assert!(together.indices.len() / 3 >= PARALLEL_PARTS_TRIANGLES);
        let built = build(&together.vertices, &together.indices, &together.parts);
        for (part, &[first_cluster, count, coarsest]) in
            together.parts.iter().zip(&built.part_ranges)
        {
            let start = part.first_index as usize;
            let own = &together.indices[start..start + part.index_count as usize];
            let alone_part = Part {
                first_index: 0,
                index_count: part.index_count,
                ..*part
            };
            let alone = build(&together.vertices, own, &[alone_part]);
            assert_eq!([count, coarsest], alone.part_ranges[0][1..]);
            let clusters =
                &built.clusters[first_cluster as usize..(first_cluster + count) as usize];
            let triangles = |clusters: &[abi::CadrCluster]| -> Vec<u32> {
                clusters.iter().map(|c| c.index_count).collect()
            };
            assert_eq!(triangles(clusters), triangles(&alone.clusters));
        }
    }

    #[test]
    fn each_parts_levels_follow_its_clusters_unchanged() {
        // Two flat discs of 64 rim points: each part's edges are its rim.
        let vertex = |position: [f32; 3]| Vertex {
            position,
            normal: [0.0, 1.0, 0.0],
        };
        let mut geometry = crate::scene::Geometry::default();
        for center in [[0.0_f32, 0.0, 0.0], [3.0, 0.0, 0.0]] {
            let first_vertex = geometry.vertices.len() as u32;
            let first_index = geometry.indices.len() as u32;
            geometry.vertices.push(vertex(center));
            geometry.vertices.extend((0..64).map(|k| {
                let angle = std::f32::consts::TAU * k as f32 / 64.0;
                vertex([center[0] + angle.cos(), center[1], center[2] + angle.sin()])
            }));
            for k in 0..64 {
                geometry.indices.extend([
                    first_vertex,
                    first_vertex + 1 + (k + 1) % 64,
                    first_vertex + 1 + k,
                ]);
            }
            geometry.parts.push(Part {
                first_index,
                index_count: geometry.indices.len() as u32 - first_index,
                ..Part::default()
            });
        }
        let (wire, parts) = crate::scene::edges::feature_edges(&geometry, 30.0);
        let built = build(&geometry.vertices, &geometry.indices, &parts);
        let mut clusters = build(&geometry.vertices, &geometry.indices, &parts);
        add_edge_levels(&mut clusters, &geometry.vertices, &wire, &parts);
        assert_eq!(clusters.edge_levels.len(), 2);
        for (part, (&[first, count, coarsest], &[old_first, old_count, old_coarsest])) in clusters
            .part_ranges
            .iter()
            .zip(&built.part_ranges)
            .enumerate()
        {
            assert_eq!((count, coarsest), (old_count, old_coarsest));
            let own = |c: &GeometryClusters, first: u32| {
                c.clusters[first as usize..(first + count) as usize].to_vec()
            };
            assert_eq!(own(&clusters, first), own(&built, old_first));
            let levels = clusters.edge_levels[part];
            assert!(levels >= 2, "part {part}: {levels} levels");
            let records = &clusters.clusters[(first + count) as usize..][..levels as usize];
            let mut error = 0.0;
            for record in records {
                assert!(is_edge_level(&clusters, record));
                assert_eq!((record.refined, record.part_clusters), (levels, count));
                let group = clusters.groups[record.group as usize];
                assert!(group.error >= error);
                error = group.error;
                let start = record.first_index as usize - wire.len();
                let lines = &clusters.wire_lod[start..start + record.index_count as usize];
                assert!(lines.len() % 2 == 0 && !lines.is_empty());
            }
        }
        // Every group's span holds its clusters and only them.
        for (g, group) in clusters.groups.iter().enumerate() {
            let span =
                &clusters.clusters[group.first_cluster as usize..][..group.cluster_count as usize];
            assert!(span.iter().all(|c| c.group as usize == g));
            let all = clusters
                .clusters
                .iter()
                .filter(|c| c.group as usize == g)
                .count();
            assert_eq!(all, group.cluster_count as usize);
        }
    }
}
