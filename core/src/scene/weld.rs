//! Vertices welded by position: CAD meshes split a vertex wherever its faces need different
//! normals (creases, seams), so what is one point of the surface may be several vertices.
//! Closure and feature edges ask which vertices are one point.

use rustc_hash::FxHashMap;

use super::Vertex;

/// For each of `vertices`, the first of them at its position (+0.0 and -0.0 are one position):
/// two vertices are one point of the surface where these are equal.
pub fn first_at_position(vertices: &[Vertex]) -> Vec<u32> {
    let mut first: FxHashMap<[u32; 3], u32> =
        FxHashMap::with_capacity_and_hasher(vertices.len(), Default::default());
    (vertices.iter().zip(0u32..))
        .map(|(vertex, index)| *first.entry(position_key(vertex.position)).or_insert(index))
        .collect()
}

/// The bits of `position`, +0.0 and -0.0 made one.
pub fn position_key(position: [f32; 3]) -> [u32; 3] {
    position.map(|c| (c + 0.0).to_bits())
}

/// The key of the undirected edge between welded vertices `a` and `b` (the same either way).
pub fn edge_key(a: u32, b: u32) -> u64 {
    (u64::from(a.min(b)) << 32) | u64::from(a.max(b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vertices_at_one_position_weld_to_the_first_of_them() {
        let at = |position: [f32; 3], normal: [f32; 3]| Vertex { position, normal };
        let vertices = [
            at([0.0, 1.0, 2.0], [1.0, 0.0, 0.0]),
            at([1.0, 1.0, 2.0], [1.0, 0.0, 0.0]),
            at([0.0, 1.0, 2.0], [0.0, 1.0, 0.0]),
            at([-0.0, 1.0, 2.0], [0.0, 0.0, 1.0]),
            at([1.0, 1.0, 2.0], [0.0, 1.0, 0.0]),
        ];
        assert_eq!(first_at_position(&vertices), vec![0, 1, 0, 0, 1]);
        assert_eq!(edge_key(3, 7), edge_key(7, 3));
        assert_ne!(edge_key(3, 7), edge_key(3, 8));
    }
}
