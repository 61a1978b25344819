//! Whether a part's triangles enclose a volume, which section caps need: a cut through a closed
//! surface shows its inside, a cut through an open one shows nothing to fill.
//!
//! Vertices are welded by position first (CAD meshes split vertices along hard edges to give
//! them several normals). The surface is closed when every edge between two welded positions
//! belongs to exactly two triangles that run along it in opposite directions (a consistently
//! wound, watertight surface); its signed volume then says whether the triangles wind
//! counter-clockwise seen from outside (as glTF wants) or are inside out. Degenerate triangles
//! are ignored.

use rustc_hash::FxHashMap;

use super::sink::{GeometrySink, GeometrySummary};
use super::weld::{edge_key, first_at_position};
use super::Vertex;

/// How a part's triangles close.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Closure {
    /// Not watertight or not consistently wound (or enclosing no volume).
    Open,
    /// Closed, counter-clockwise seen from outside.
    Closed,
    /// Closed, clockwise seen from outside.
    InsideOut,
}

/// The closure of the triangles `indices` over `vertices` (indices out of range make it open).
pub fn closure(vertices: &[Vertex], indices: &[u32]) -> Closure {
    closure_welded(vertices, &first_at_position(vertices), indices)
}

/// [`closure`], with `welded` the vertices welded by position
/// ([`super::weld::first_at_position`] of `vertices`): a geometry's parts weld its vertices
/// once.
pub fn closure_welded(vertices: &[Vertex], welded: &[u32], indices: &[u32]) -> Closure {
    // Per undirected edge: how many triangles use it, and the sum of their directions (sized
    // for a closed surface: one and a half edges per triangle).
    let mut edges: FxHashMap<u64, (u32, i32)> =
        FxHashMap::with_capacity_and_hasher(indices.len() / 2, Default::default());
    let mut volume = 0.0_f64;
    for triangle in indices.chunks_exact(3) {
        let weld = |corner: usize| welded.get(triangle[corner] as usize).copied();
        let (Some(a), Some(b), Some(c)) = (weld(0), weld(1), weld(2)) else {
            return Closure::Open;
        };
        if a == b || b == c || c == a {
            continue;
        }
        for (from, to) in [(a, b), (b, c), (c, a)] {
            let edge = edges.entry(edge_key(from, to)).or_insert((0, 0));
            edge.0 += 1;
            edge.1 += if from < to { 1 } else { -1 };
        }
        let [p, q, r] = [0, 1, 2].map(|i| {
            let position = vertices[triangle[i] as usize].position;
            glam::DVec3::new(
                f64::from(position[0]),
                f64::from(position[1]),
                f64::from(position[2]),
            )
        });
        volume += p.dot(q.cross(r));
    }
    let watertight = !edges.is_empty() && edges.values().all(|&(uses, sum)| uses == 2 && sum == 0);
    match (watertight, volume) {
        (true, v) if v > 0.0 => Closure::Closed,
        (true, v) if v < 0.0 => Closure::InsideOut,
        _ => Closure::Open,
    }
}

/// How the parts of `scene`'s geometries close. Parts whose index range lies outside their
/// geometry count as open.
pub fn count_closed_parts(scene: &super::Scene) -> ClosedPartCounts {
    let mut counts = ClosedPartCounts::default();
    for geometry in &scene.geometries {
        counts.add(geometry);
    }
    counts
}

/// How many parts close, counted geometry by geometry.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ClosedPartCounts {
    /// Parts closed, counter-clockwise seen from outside.
    pub closed: usize,
    /// Parts closed but inside out.
    pub inside_out: usize,
    /// Parts in all.
    pub parts: usize,
}

impl ClosedPartCounts {
    /// Counts the parts of `geometry` (a part whose index range lies outside it is open).
    fn add(&mut self, geometry: &super::Geometry) {
        let welded = first_at_position(&geometry.vertices);
        for part in &geometry.parts {
            let start = part.first_index as usize;
            let indices = geometry
                .indices
                .get(start..start.saturating_add(part.index_count as usize))
                .unwrap_or(&[]);
            match closure_welded(&geometry.vertices, &welded, indices) {
                Closure::Closed => self.closed += 1,
                Closure::InsideOut => self.inside_out += 1,
                Closure::Open => {}
            }
            self.parts += 1;
        }
    }
}

/// The sink that counts how the parts of each geometry close and keeps only its summary,
/// leaving a stand-in (see [`GeometrySink`]): a scene's statistics and closed parts, read one
/// geometry at a time, so that a model larger than memory can be described (`cadr info`).
#[derive(Clone, Debug, Default)]
pub struct ClosedPartCounter {
    /// The parts counted so far.
    pub counts: ClosedPartCounts,
    /// Each geometry's summary, in the scene's order.
    pub summaries: Vec<GeometrySummary>,
}

impl GeometrySink for ClosedPartCounter {
    fn take(&mut self, index: u32, geometry: super::Geometry) -> super::Geometry {
        debug_assert_eq!(
            index as usize,
            self.summaries.len(),
            "geometries come in order"
        );
        self.counts.add(&geometry);
        self.summaries.push(geometry.summary());
        geometry.stand_in()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vertex(x: f32, y: f32, z: f32) -> Vertex {
        Vertex {
            position: [x, y, z],
            normal: [0.0, 0.0, 1.0],
        }
    }

    /// A unit tetrahedron, counter-clockwise from outside.
    fn tetrahedron() -> (Vec<Vertex>, Vec<u32>) {
        let vertices = vec![
            vertex(0.0, 0.0, 0.0),
            vertex(1.0, 0.0, 0.0),
            vertex(0.0, 1.0, 0.0),
            vertex(0.0, 0.0, 1.0),
        ];
        let indices = vec![0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3];
        (vertices, indices)
    }

    #[test]
    fn a_tetrahedron_is_closed_and_inside_out_when_flipped() {
        let (vertices, indices) = tetrahedron();
        assert_eq!(closure(&vertices, &indices), Closure::Closed);
        let flipped: Vec<u32> = indices.chunks(3).flat_map(|t| [t[0], t[2], t[1]]).collect();
        assert_eq!(closure(&vertices, &flipped), Closure::InsideOut);
    }

    #[test]
    fn split_vertices_are_welded_by_position() {
        // Each face with vertices of its own, as a mesh with hard-edge normals has them.
        let (vertices, indices) = tetrahedron();
        let split: Vec<Vertex> = indices.iter().map(|&i| vertices[i as usize]).collect();
        let own: Vec<u32> = (0..split.len() as u32).collect();
        assert_eq!(closure(&split, &own), Closure::Closed);
    }

    #[test]
    fn a_missing_face_a_doubled_face_or_a_flipped_face_is_open() {
        let (vertices, indices) = tetrahedron();
        assert_eq!(closure(&vertices, &indices[..9]), Closure::Open);
        let mut doubled = indices.clone();
        doubled.extend_from_slice(&indices[..3]);
        assert_eq!(closure(&vertices, &doubled), Closure::Open);
        let mut one_flipped = indices.clone();
        one_flipped.swap(0, 1);
        assert_eq!(closure(&vertices, &one_flipped), Closure::Open);
        assert_eq!(closure(&vertices, &[]), Closure::Open);
        assert_eq!(closure(&vertices, &[0, 1, 9]), Closure::Open);
    }

    #[test]
    fn a_scene_counts_its_closed_inside_out_and_open_parts() {
        let (vertices, closed) = tetrahedron();
        let flipped: Vec<u32> = closed.iter().rev().copied().collect();
        let indices: Vec<u32> = [&closed[..], &flipped[..], &closed[..9]].concat();
        let part = |first_index: u32, index_count: u32| super::super::Part {
            first_index,
            index_count,
            first_wire_index: 0,
            wire_index_count: 0,
        };
        let geometry = super::super::Geometry {
            name: "tetrahedra".into(),
            vertices,
            indices,
            wire_indices: Vec::new(),
            // Closed, inside out, open, and a range past the indices (open).
            parts: vec![part(0, 12), part(12, 12), part(24, 9), part(30, 12)],
            attributes: Vec::new(),
        };
        let scene = super::super::Scene {
            geometries: vec![geometry],
            ..super::super::Scene::default()
        };
        assert_eq!(
            count_closed_parts(&scene),
            ClosedPartCounts {
                closed: 1,
                inside_out: 1,
                parts: 4
            }
        );
    }
}
