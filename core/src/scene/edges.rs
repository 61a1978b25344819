//! Feature edges for the "solid with edges" shade mode when a file stores none: an edge is
//! drawn where only one triangle uses it (a border) or where the two faces meeting at it bend
//! by more than the crease angle. Vertices are matched by position, so meshes whose vertices are
//! split at creases (per-face normals) find their edges too.

use std::collections::hash_map::Entry;

use rustc_hash::FxHashMap;

use super::weld::{edge_key, first_at_position};
use super::{Geometry, Part};

/// The default crease angle in degrees: CAD tessellations bend less than this between
/// neighbouring facets of a smooth surface.
pub const DEFAULT_CREASE_DEGREES: f32 = 30.0;

/// The faces that meet at an edge, by their normals: one (a border), two (a fold or a flat
/// seam, by their angle), or more (non-manifold: always a visible edge).
enum Faces {
    One([f32; 3]),
    Two([f32; 3], [f32; 3]),
    More,
}

impl Faces {
    /// These faces and one more, of `normal`.
    fn and(self, normal: [f32; 3]) -> Self {
        match self {
            Self::One(first) => Self::Two(first, normal),
            Self::Two(..) | Self::More => Self::More,
        }
    }
}

/// Per edge (between welded vertices, see `weld.rs`): its first vertex pair and its faces.
type EdgeFaces = FxHashMap<u64, ((u32, u32), Faces)>;

fn face_normal(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> [f32; 3] {
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    let length = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if length > 0.0 {
        n.map(|c| c / length)
    } else {
        [0.0; 3]
    }
}

/// Derives feature edges per part. Returns the line-list indices and the parts with their
/// wire ranges set; parts keep their triangle ranges.
pub fn feature_edges(geometry: &Geometry, crease_degrees: f32) -> (Vec<u32>, Vec<Part>) {
    feature_edges_welded(
        geometry,
        &first_at_position(&geometry.vertices),
        crease_degrees,
    )
}

/// [`feature_edges`], with `welded` the geometry's vertices welded by position
/// ([`super::weld::first_at_position`]), for a caller that needs them too.
pub fn feature_edges_welded(
    geometry: &Geometry,
    welded: &[u32],
    crease_degrees: f32,
) -> (Vec<u32>, Vec<Part>) {
    let cos_crease = crease_degrees.to_radians().cos();
    let mut wire = Vec::new();
    let mut parts = Vec::with_capacity(geometry.parts.len());
    let position = |i: u32| {
        geometry
            .vertices
            .get(i as usize)
            .map_or([0.0; 3], |v| v.position)
    };
    // A vertex past the geometry's is a point of its own.
    let weld = |i: u32| welded.get(i as usize).copied().unwrap_or(i);
    for part in &geometry.parts {
        let first_wire_index = wire.len() as u32;
        let start = part.first_index as usize;
        let end = (start + part.index_count as usize).min(geometry.indices.len());
        // A closed surface has about one and a half edges per triangle.
        let capacity = end.saturating_sub(start) / 2;
        let mut edges: EdgeFaces =
            FxHashMap::with_capacity_and_hasher(capacity, Default::default());
        for triangle in geometry.indices[start.min(end)..end].chunks_exact(3) {
            let normal = face_normal(
                position(triangle[0]),
                position(triangle[1]),
                position(triangle[2]),
            );
            if normal == [0.0; 3] {
                continue; // degenerate: no face to bend
            }
            for (a, b) in [
                (triangle[0], triangle[1]),
                (triangle[1], triangle[2]),
                (triangle[2], triangle[0]),
            ] {
                let (wa, wb) = (weld(a), weld(b));
                if wa == wb {
                    continue;
                }
                match edges.entry(edge_key(wa, wb)) {
                    Entry::Occupied(mut entry) => {
                        let faces = &mut entry.get_mut().1;
                        *faces = std::mem::replace(faces, Faces::More).and(normal);
                    }
                    Entry::Vacant(entry) => {
                        entry.insert(((a, b), Faces::One(normal)));
                    }
                }
            }
        }
        let mut found: Vec<(u32, u32)> = edges
            .into_values()
            .filter(|(_, faces)| match faces {
                Faces::One(_) | Faces::More => true,
                Faces::Two(n, m) => n[0] * m[0] + n[1] * m[1] + n[2] * m[2] < cos_crease,
            })
            .map(|(pair, _)| pair)
            .collect();
        found.sort_unstable(); // deterministic output
        for (a, b) in found {
            wire.extend([a, b]);
        }
        parts.push(Part {
            first_wire_index,
            wire_index_count: wire.len() as u32 - first_wire_index,
            ..*part
        });
    }
    (wire, parts)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Vertex;

    fn vertex(position: [f32; 3]) -> Vertex {
        Vertex {
            position,
            normal: [0.0, 0.0, 1.0],
        }
    }

    #[test]
    fn a_flat_quad_has_its_border_and_a_folded_one_its_fold() {
        // Two triangles sharing the diagonal 0-2.
        let mut quad = Geometry {
            vertices: [
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ]
            .map(vertex)
            .to_vec(),
            indices: vec![0, 1, 2, 0, 2, 3],
            parts: vec![Part {
                first_index: 0,
                index_count: 6,
                first_wire_index: 0,
                wire_index_count: 0,
            }],
            ..Geometry::default()
        };
        let (wire, parts) = feature_edges(&quad, DEFAULT_CREASE_DEGREES);
        assert_eq!(wire.len(), 8, "four border edges, not the flat diagonal");
        assert_eq!(parts[0].wire_index_count, 8);
        // Fold vertex 3 up by 90 degrees: the diagonal becomes a crease.
        quad.vertices[3].position = [0.0, 0.0, 1.0];
        let (wire, _) = feature_edges(&quad, DEFAULT_CREASE_DEGREES);
        assert_eq!(wire.len(), 10);
    }
}
