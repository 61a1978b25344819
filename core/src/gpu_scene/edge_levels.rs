//! Coarser levels of a part's feature edges, for the level-of-detail cut (plugin ABI 1.25,
//! `CADR_CLUSTER_EDGE_DEPTH`): a far part's surfaces are drawn from a few triangles, and its
//! edges would otherwise still be drawn whole, every segment of every fillet and bore (a part
//! eight pixels across drew its 300 edge segments where a few dozen show the same).
//!
//! The edges are joined by position into chains between junctions (where other than two
//! segments meet) and closed loops; each chain is simplified on its own by Douglas–Peucker, its
//! ends kept, so the simplified edges stay connected wherever the edges were, use only the
//! part's own edge vertices, and never draw an edge the part lacks. Where every edge ends at a
//! junction (a faceted part's side, a gear's teeth), nothing is left to simplify that way: a
//! level then first merges the edge vertices that share a cell of a grid (so edges nearer
//! than the cell become one, and a loop within a cell a dot), then simplifies the chains that
//! remain. A level's error is the farthest any of the part's edges lies from it.

use std::rc::Rc;

use rustc_hash::FxHashMap;

use super::bounds;
use crate::scene::weld::{edge_key, position_key};
use crate::scene::Vertex;

/// A part whose edges have fewer segments gets no coarser level.
const MIN_SEGMENTS: usize = 16;
/// Each level keeps at most this share of the segments of the level before.
const LEVEL_SHARE: f32 = 0.6;
/// The most coarser levels a part gets.
const MAX_LEVELS: usize = 8;
/// The finest tolerance tried, as a share of the edges' radius; each next is √2 times the
/// last.
const FIRST_TOLERANCE: f32 = 1.0 / 4096.0;

/// One coarser level of a part's edges.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct EdgeLevel {
    /// A line list naming the part's vertices (the same ones its edges name).
    pub(super) lines: Vec<u32>,
    /// The farthest the part's edges lie from these lines (object space), never less than a
    /// finer level's.
    pub(super) error: f32,
}

/// The coarser levels of the edges `lines` (a line list into `vertices`), finest first, and
/// the sphere holding the edges (centre, radius); none where simplifying saves too little.
pub(super) fn edge_levels(vertices: &[Vertex], lines: &[u32]) -> (Vec<EdgeLevel>, [f32; 4]) {
    let Some(graph) = EdgeGraph::of(vertices, lines) else {
        return (Vec::new(), [0.0; 4]);
    };
    let sphere = bounds::sphere_of(graph.node_position.iter().copied());
    let mut levels: Vec<EdgeLevel> = Vec::new();
    if graph.segments.len() < MIN_SEGMENTS || sphere[3] <= 0.0 {
        return (levels, sphere);
    }
    let mut last_segments = graph.segments.len();
    let chains = graph.chains();
    let chains_bend = chains.nodes.len() > 2 * chains.ends.len();
    let shortest = graph.shortest_segment();
    let mut tolerance = sphere[3] * FIRST_TOLERANCE;
    // Past twice the radius every chain is its two ends: nothing coarser can come.
    while levels.len() < MAX_LEVELS && tolerance <= 2.0 * sphere[3] {
        // The chains simplified within the tolerance; or, where that leaves fewer, the nodes
        // of each cell merged first (no node moves farther than the cell's diagonal, half the
        // tolerance: edges closer than that become one, as the facets of a faceted part's
        // side do, whose every edge ends where three meet) and the chains that remain
        // simplified within what the merging left of the tolerance. (A chain of one segment
        // has nothing to simplify; a cell whose diagonal is under half the shortest segment
        // merges next to nothing.)
        let center = [sphere[0], sphere[1], sphere[2]];
        let merged = (tolerance >= shortest)
            .then(|| graph.clustered(0.5 * tolerance / 3.0_f32.sqrt(), center))
            .filter(|&(_, moved)| moved > 0.0)
            .map(|(merged, moved)| {
                let (lines, strayed) = simplified(&merged, &merged.chains(), tolerance - moved);
                (lines, moved + strayed)
            });
        let (lines, strayed) = (chains_bend.then(|| simplified(&graph, &chains, tolerance)))
            .into_iter()
            .chain(merged)
            .min_by_key(|(lines, _)| lines.len())
            .unwrap_or_else(|| (graph.line_list(), 0.0));
        let count = lines.len() / 2;
        if (count as f32) <= LEVEL_SHARE * last_segments as f32 {
            let floor = levels.last().map_or(0.0, |l| l.error);
            levels.push(EdgeLevel {
                lines,
                error: strayed.max(floor),
            });
            last_segments = count;
        }
        tolerance *= std::f32::consts::SQRT_2;
    }
    (levels, sphere)
}

/// A part's edges joined by position: a node per position (its first vertex, its position)
/// and the segments between nodes, each once.
#[derive(Clone)]
struct EdgeGraph {
    node_vertex: Rc<[u32]>,
    node_position: Rc<[[f32; 3]]>,
    segments: Vec<(u32, u32)>,
}

impl EdgeGraph {
    /// The graph of `lines` (`None` where a line names a vertex that does not exist).
    fn of(vertices: &[Vertex], lines: &[u32]) -> Option<Self> {
        let mut node_of: FxHashMap<[u32; 3], u32> =
            FxHashMap::with_capacity_and_hasher(lines.len() / 2, Default::default());
        let mut node_vertex = Vec::new();
        let mut node_position = Vec::new();
        let mut node = |vertex: u32| -> Option<u32> {
            let position = vertices.get(vertex as usize)?.position;
            Some(*node_of.entry(position_key(position)).or_insert_with(|| {
                node_vertex.push(vertex);
                node_position.push(position);
                node_vertex.len() as u32 - 1
            }))
        };
        let mut segments = Vec::with_capacity(lines.len() / 2);
        for pair in lines.chunks_exact(2) {
            segments.push((node(pair[0])?, node(pair[1])?));
        }
        Some(Self {
            node_vertex: node_vertex.into(),
            node_position: node_position.into(),
            segments: distinct_segments(segments),
        })
    }

    /// The graph with the nodes of each cube of side `cell` (on a grid through `origin`)
    /// merged into the cell's node nearest its centre, and how far a node moved at most. A cell whose
    /// segments all fall within it keeps one of them, so that a small loop (a bore seen from
    /// far) still shows as a dot rather than vanishing.
    fn clustered(&self, cell: f32, origin: [f32; 3]) -> (Self, f32) {
        let cell_of = |p: [f32; 3]| [0, 1, 2].map(|a| ((p[a] - origin[a]) / cell).floor() as i32);
        let centre_of = |c: [i32; 3]| [0, 1, 2].map(|a| origin[a] + (c[a] as f32 + 0.5) * cell);
        let distance = |p: [f32; 3], q: [f32; 3]| distance_to_segment(p, q, q);
        // Each cell's node nearest its centre (the nodes sorted by cell: no hashing, no
        // allocation per cell).
        // A cell's coordinates packed in one word, 21 bits each (the finest cell is about a
        // 14 000th of the edges' radius: far within).
        let packed = |c: [i32; 3]| {
            c.iter().fold(0_u64, |key, &x| {
                key << 21 | (i64::from(x) + (1 << 20)).clamp(0, (1 << 21) - 1) as u64
            })
        };
        let cells: Vec<[i32; 3]> = self.node_position.iter().map(|&p| cell_of(p)).collect();
        let mut order: Vec<(u64, u32)> = (cells.iter().enumerate())
            .map(|(n, &c)| (packed(c), n as u32))
            .collect();
        order.sort_unstable();
        let mut merged_into = vec![0_u32; cells.len()];
        let mut moved = 0.0_f32;
        for run in order.chunk_by(|a, b| a.0 == b.0) {
            let centre = centre_of(cells[run[0].1 as usize]);
            let from_centre = |n: u32| distance(self.node_position[n as usize], centre);
            let kept = (run.iter().map(|&(_, n)| n))
                .min_by(|&a, &b| from_centre(a).total_cmp(&from_centre(b)))
                .unwrap_or(run[0].1);
            for &(_, n) in run {
                merged_into[n as usize] = kept;
                let p = self.node_position[n as usize];
                moved = moved.max(distance(p, self.node_position[kept as usize]));
            }
        }
        let mut segments = Vec::with_capacity(self.segments.len());
        let mut drawn = vec![false; self.node_vertex.len()];
        let mut collapsed = Vec::new();
        for &(a, b) in &self.segments {
            let (ma, mb) = (merged_into[a as usize], merged_into[b as usize]);
            if ma == mb {
                collapsed.push((a, b));
            } else {
                segments.push((ma, mb));
                drawn[ma as usize] = true;
                drawn[mb as usize] = true;
            }
        }
        for (a, b) in collapsed {
            let cell_node = merged_into[a as usize] as usize;
            if !drawn[cell_node] {
                drawn[cell_node] = true;
                segments.push((a, b));
            }
        }
        let merged = Self {
            segments: distinct_segments(segments),
            ..self.clone()
        };
        (merged, moved)
    }

    /// The segments as a line list of the nodes' vertices.
    fn line_list(&self) -> Vec<u32> {
        (self.segments.iter())
            .flat_map(|&(a, b)| [self.node_vertex[a as usize], self.node_vertex[b as usize]])
            .collect()
    }

    /// The length of the shortest segment.
    fn shortest_segment(&self) -> f32 {
        (self.segments.iter())
            .map(|&(a, b)| {
                let (p, q) = (
                    self.node_position[a as usize],
                    self.node_position[b as usize],
                );
                distance_to_segment(p, q, q)
            })
            .fold(f32::INFINITY, f32::min)
    }

    /// The segments joined into chains: from each junction (where other than two segments
    /// meet) along each of its segments to the next junction, then the closed loops that
    /// remain, each from its first node back to it.
    fn chains(&self) -> Chains {
        let node_count = self.node_vertex.len();
        // Each node's segments, by the segments' places.
        let mut first = vec![0_u32; node_count + 1];
        for &(a, b) in &self.segments {
            first[a as usize + 1] += 1;
            first[b as usize + 1] += 1;
        }
        for n in 0..node_count {
            first[n + 1] += first[n];
        }
        let mut fill = first.clone();
        let mut around = vec![0_u32; self.segments.len() * 2];
        for (s, &(a, b)) in self.segments.iter().enumerate() {
            for end in [a, b] {
                around[fill[end as usize] as usize] = s as u32;
                fill[end as usize] += 1;
            }
        }
        let degree = |n: u32| first[n as usize + 1] - first[n as usize];
        let mut taken = vec![false; self.segments.len()];
        let mut chains = Chains::default();
        let junctions = (0..node_count as u32).filter(|&n| degree(n) != 2 && degree(n) != 0);
        let loop_starts = (0..node_count as u32).filter(|&n| degree(n) == 2);
        for start in junctions.chain(loop_starts) {
            for k in first[start as usize]..first[start as usize + 1] {
                let mut segment = around[k as usize];
                if taken[segment as usize] {
                    continue;
                }
                chains.nodes.push(start);
                let mut at = start;
                loop {
                    taken[segment as usize] = true;
                    let (a, b) = self.segments[segment as usize];
                    at = if a == at { b } else { a };
                    chains.nodes.push(at);
                    if degree(at) != 2 {
                        break;
                    }
                    let range = first[at as usize] as usize..first[at as usize + 1] as usize;
                    match around[range].iter().find(|&&s| !taken[s as usize]) {
                        Some(&next) => segment = next,
                        None => break,
                    }
                }
                chains.ends.push(chains.nodes.len() as u32);
            }
        }
        chains
    }
}

/// Chains of nodes, one after the other: each ends before its entry of `ends`.
#[derive(Default)]
struct Chains {
    nodes: Vec<u32>,
    ends: Vec<u32>,
}

impl Chains {
    fn iter(&self) -> impl Iterator<Item = &[u32]> {
        let starts = std::iter::once(0).chain(self.ends.iter().copied());
        starts
            .zip(&self.ends)
            .map(|(start, &end)| &self.nodes[start as usize..end as usize])
    }
}

/// `segments` each once, its lower node first, with none from a node to itself.
fn distinct_segments(segments: Vec<(u32, u32)>) -> Vec<(u32, u32)> {
    let mut keys: Vec<u64> = (segments.into_iter())
        .filter(|&(a, b)| a != b)
        .map(|(a, b)| edge_key(a, b))
        .collect();
    keys.sort_unstable();
    keys.dedup();
    keys.into_iter()
        .map(|key| ((key >> 32) as u32, key as u32))
        .collect()
}

/// Every chain simplified within `tolerance`: the line list and the farthest a left-out point
/// lies from its simplified segment.
fn simplified(graph: &EdgeGraph, chains: &Chains, tolerance: f32) -> (Vec<u32>, f32) {
    let mut lines = Vec::new();
    let mut error = 0.0_f32;
    let mut kept = Vec::new();
    let mut stack = Vec::new();
    for chain in chains.iter() {
        let position = |i: usize| graph.node_position[chain[i] as usize];
        kept.clear();
        kept.resize(chain.len(), false);
        kept[0] = true;
        kept[chain.len() - 1] = true;
        stack.push((0, chain.len() - 1));
        while let Some((from, to)) = stack.pop() {
            if to <= from + 1 {
                continue;
            }
            let (far, distance) = (from + 1..to)
                .map(|i| {
                    (
                        i,
                        distance_to_segment(position(i), position(from), position(to)),
                    )
                })
                .fold(
                    (from + 1, -1.0),
                    |best, d| if d.1 > best.1 { d } else { best },
                );
            // A closed loop's two ends are one point: its farthest point is always kept, so
            // that it is never drawn as nothing.
            let closed_loop = from == 0 && to == chain.len() - 1 && chain[from] == chain[to];
            if distance > tolerance || closed_loop {
                kept[far] = true;
                stack.push((from, far));
                stack.push((far, to));
            } else {
                error = error.max(distance);
            }
        }
        let mut last = chain[0];
        for (i, &node) in chain.iter().enumerate().skip(1) {
            if kept[i] {
                lines.push(graph.node_vertex[last as usize]);
                lines.push(graph.node_vertex[node as usize]);
                last = node;
            }
        }
    }
    (lines, error)
}

/// The distance from `p` to the segment from `a` to `b`.
fn distance_to_segment(p: [f32; 3], a: [f32; 3], b: [f32; 3]) -> f32 {
    let ab = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let ap = [p[0] - a[0], p[1] - a[1], p[2] - a[2]];
    let length2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
    let t = if length2 > 0.0 {
        ((ap[0] * ab[0] + ap[1] * ab[1] + ap[2] * ab[2]) / length2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let d = [ap[0] - t * ab[0], ap[1] - t * ab[1], ap[2] - t * ab[2]];
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

    use std::collections::HashMap;

    use super::*;

    fn vertex(position: [f32; 3]) -> Vertex {
        Vertex {
            position,
            normal: [0.0, 1.0, 0.0],
        }
    }

    /// A circle of `segments` in the XZ plane, each point twice (as split vertices are), and
    /// its line list (alternating between the copies).
    fn circle(segments: u32, center: [f32; 3]) -> (Vec<Vertex>, Vec<u32>) {
        let mut vertices = Vec::new();
        for k in 0..segments {
            let angle = std::f32::consts::TAU * k as f32 / segments as f32;
            let p = [center[0] + angle.cos(), center[1], center[2] + angle.sin()];
            vertices.extend([vertex(p), vertex(p)]);
        }
        let lines = (0..segments)
            .flat_map(|k| [2 * k, 2 * ((k + 1) % segments) + 1])
            .collect();
        (vertices, lines)
    }

    fn position(vertices: &[Vertex], i: u32) -> [f32; 3] {
        vertices[i as usize].position
    }

    /// The farthest any point of `lines` lies from `level`.
    fn farthest_from(vertices: &[Vertex], lines: &[u32], level: &[u32]) -> f32 {
        let near = |p: [f32; 3]| {
            level
                .chunks_exact(2)
                .map(|s| distance_to_segment(p, position(vertices, s[0]), position(vertices, s[1])))
                .fold(f32::INFINITY, f32::min)
        };
        lines
            .chunks_exact(2)
            .flat_map(|s| {
                let (a, b) = (position(vertices, s[0]), position(vertices, s[1]));
                (0..=8).map(move |t| {
                    let t = t as f32 / 8.0;
                    [0, 1, 2].map(|c| a[c] + t * (b[c] - a[c]))
                })
            })
            .map(near)
            .fold(0.0, f32::max)
    }

    /// How many segments of `lines` meet at each position.
    fn degrees(vertices: &[Vertex], lines: &[u32]) -> HashMap<[u32; 3], u32> {
        let mut degrees = HashMap::new();
        for &i in lines {
            *degrees
                .entry(position(vertices, i).map(f32::to_bits))
                .or_insert(0) += 1;
        }
        degrees
    }

    #[test]
    fn a_circles_levels_hold_ever_fewer_segments_within_their_errors() {
        let (vertices, lines) = circle(256, [0.0; 3]);
        let (levels, sphere) = edge_levels(&vertices, &lines);
        assert!((sphere[3] - 1.0).abs() < 1e-3, "{sphere:?}");
        assert!(levels.len() >= 3, "{} levels", levels.len());
        let mut segments = lines.len() / 2;
        let mut error = 0.0;
        for level in &levels {
            let count = level.lines.len() / 2;
            assert!(
                count as f32 <= LEVEL_SHARE * segments as f32,
                "{count} after {segments}"
            );
            assert!(level.error >= error);
            // Every point of the circle lies within the level's error of it, and the level
            // is made of the circle's own vertices, each where two of its segments meet.
            let farthest = farthest_from(&vertices, &lines, &level.lines);
            assert!(
                farthest <= level.error + 1e-5,
                "{farthest} > {}",
                level.error
            );
            assert!(level.lines.iter().all(|&i| lines.contains(&i)));
            assert!(degrees(&vertices, &level.lines).values().all(|&d| d == 2));
            segments = count;
            error = level.error;
        }
        // The coarsest level still spans the circle: it is never a point.
        let last = levels.last().unwrap();
        assert!(last.lines.len() >= 4, "{:?}", last.lines);
    }

    #[test]
    fn a_faceted_prisms_edges_get_coarser_levels() {
        // Every vertical edge of a 100-sided prism ends where three edges meet: no chain to
        // simplify, but edges a few hundredths of the radius apart, which merge.
        let mut builder = crate::generate::shapes::GeometryBuilder::new("prism");
        builder.prism(100, glam::DMat4::IDENTITY);
        let geometry = builder.finish();
        let lines = &geometry.wire_indices;
        assert_eq!(lines.len() / 2, 300);
        let (levels, _) = edge_levels(&geometry.vertices, lines);
        let summary: Vec<_> = levels
            .iter()
            .map(|l| (l.lines.len() / 2, l.error))
            .collect();
        assert!(levels.len() >= 4, "{summary:?}");
        for level in &levels {
            let farthest = farthest_from(&geometry.vertices, lines, &level.lines);
            assert!(
                farthest <= level.error + 1e-5,
                "{farthest} > {}",
                level.error
            );
        }
        // Within 0.15 of the radius (the sides' edges are 0.063 apart), at most 120 of the 300
        // segments.
        let within = levels.iter().rev().find(|l| l.error <= 0.15).unwrap();
        assert!(within.lines.len() / 2 <= 120, "{summary:?}");
    }

    #[test]
    fn straight_edges_between_corners_get_no_level() {
        let corners: Vec<Vertex> = (0..8)
            .map(|k| vertex([(k & 1) as f32, (k >> 1 & 1) as f32, (k >> 2) as f32]))
            .collect();
        let mut lines = Vec::new();
        for a in 0..8_u32 {
            for bit in [1, 2, 4] {
                if a & bit == 0 {
                    lines.extend([a, a | bit]);
                }
            }
        }
        assert_eq!(lines.len(), 24);
        assert!(edge_levels(&corners, &lines).0.is_empty());
    }

    /// How many pieces `lines` fall into, joined where they share a position.
    fn pieces(vertices: &[Vertex], lines: &[u32]) -> usize {
        let key = |i: u32| position(vertices, i).map(f32::to_bits);
        let mut parent: HashMap<[u32; 3], [u32; 3]> = HashMap::new();
        fn root(parent: &mut HashMap<[u32; 3], [u32; 3]>, k: [u32; 3]) -> [u32; 3] {
            let up = *parent.entry(k).or_insert(k);
            if up == k {
                k
            } else {
                let top = root(parent, up);
                parent.insert(k, top);
                top
            }
        }
        for s in lines.chunks_exact(2) {
            let (a, b) = (root(&mut parent, key(s[0])), root(&mut parent, key(s[1])));
            parent.insert(a, b);
        }
        let keys: Vec<_> = parent.keys().copied().collect();
        let mut roots: Vec<_> = keys.into_iter().map(|k| root(&mut parent, k)).collect();
        roots.sort_unstable();
        roots.dedup();
        roots.len()
    }

    #[test]
    fn edges_that_meet_still_meet_at_every_level() {
        // A circle with a diameter across it (three edges meet at each of its ends), and a
        // small circle beside it: two pieces at every level, each within the level's error.
        let (mut vertices, mut lines) = circle(128, [0.0; 3]);
        let (ends, steps) = ([0_u32, 128], 40_u32);
        let (a, b) = (position(&vertices, ends[0]), position(&vertices, ends[1]));
        let mut last = ends[0];
        for k in 1..steps {
            let t = k as f32 / steps as f32;
            vertices.push(vertex([0, 1, 2].map(|c| a[c] + t * (b[c] - a[c]))));
            lines.extend([last, vertices.len() as u32 - 1]);
            last = vertices.len() as u32 - 1;
        }
        lines.extend([last, ends[1]]);
        let (small, small_lines) = circle(32, [3.0, 0.0, 0.0]);
        let offset = vertices.len() as u32;
        vertices.extend(small.iter().map(|v| {
            let [x, y, z] = v.position;
            vertex([3.0 + 0.05 * (x - 3.0), y, 0.05 * z])
        }));
        lines.extend(small_lines.iter().map(|i| i + offset));
        assert_eq!(pieces(&vertices, &lines), 2);
        let (levels, _) = edge_levels(&vertices, &lines);
        assert!(levels.len() >= 2, "{} levels", levels.len());
        for level in &levels {
            assert_eq!(pieces(&vertices, &level.lines), 2, "{level:?}");
            let farthest = farthest_from(&vertices, &lines, &level.lines);
            assert!(
                farthest <= level.error + 1e-5,
                "{farthest} > {}",
                level.error
            );
            // The other way round the error is not a bound (a chord may pass a little
            // farther from a winding chain than the chain from it), but it stays near it.
            let back = farthest_from(&vertices, &level.lines, &lines);
            assert!(
                back <= 1.5 * level.error + 1e-5,
                "{back} > 1.5 × {}",
                level.error
            );
        }
    }
}
