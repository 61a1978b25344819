//! A faceted part's stand-ins: whole-part replacements for when the part is far.
//!
//! The cluster DAG's simplification keeps every crease and seam, so a faceted part (a prism of
//! a hundred sides, every vertex on a crease) stops simplifying at once. Its stand-ins are
//! simplified another way:
//!
//! - **Welded levels**: the part's vertices welded by position, so that its seams are no longer
//!   borders, then simplified whole to at most one cluster's triangles, and to [`LEVEL_SHARE`]
//!   as many again, level after level, each from the part (or, for a large part, from one
//!   simplification of it). A welded level is watertight wherever the part was, and has no
//!   neighbour to crack against. Each corner of a simplified triangle names the part's own
//!   vertex at that position whose normal best matches the triangle's: the facets keep their
//!   own normals, and no vertex is added.
//! - **The octahedron** through the part's extreme vertices along each axis, last, where it
//!   has fewer triangles than the last welded level. Its error is at least half the diagonal
//!   of the part's box.
//!
//! Each stand-in's error (in the part's units) is twice the farthest any of the part's
//! positions is from it (the outline loses that much on each side), at least the
//! simplification's own estimate, and no less than the errors before it; all are measured
//! from one sphere around every group of the part. So a culler that draws the coarsest
//! stand-in whose error projects under its threshold picks one level, seen from anywhere.

use std::borrow::Cow;

use meshopt::{SimplifyOptions, VertexDataAdapter};

use super::bounds::half_box_diagonal;
use crate::scene::Vertex;

/// A welded level is kept only when it has at most this share of the triangles of the level
/// before it: a level that barely simplifies is not worth a test per frame.
const SHRINK: f64 = 0.75;

/// Each welded level aims at this share of the triangles of the level before it. A culler draws
/// the coarsest level within its threshold, so a part draws up to 1/`LEVEL_SHARE` times the
/// triangles it needs. Halving (0.5) drew 12 % more triangles at 1 px on gen:grid's 100 000
/// prisms; this costs about half as many stand-in indices again (a 400-triangle prism: 390
/// against 254).
const LEVEL_SHARE: f64 = 0.7;

/// One stand-in of a part.
#[derive(Debug)]
pub(super) struct StandIn {
    /// Its triangles, as indices into the part's own vertices.
    pub(super) indices: Vec<u32>,
    /// Its error in the part's units: how far it strays from the part (at least the errors
    /// before it and `floor`).
    pub(super) error: f32,
}

/// The stand-ins of a part whose coarsest cut has `coarsest` triangles (`indices` into its
/// own `vertices`), each of at most `most_triangles`, with errors from `floor` up, from the
/// finest to the coarsest. Empty when nothing simplifies.
pub(super) fn stand_ins(
    vertices: &[Vertex],
    indices: &[u32],
    (coarsest, most_triangles): (usize, usize),
    floor: f32,
) -> Vec<StandIn> {
    let bytes: &[u8] = bytemuck::cast_slice(vertices);
    let Ok(adapter) = VertexDataAdapter::new(bytes, std::mem::size_of::<Vertex>(), 0) else {
        return Vec::new();
    };
    let mut levels = Vec::new();
    let mut error_floor = floor;
    let mut triangles_before = coarsest;
    for (level, error) in welded_levels(vertices, &adapter, indices, (coarsest, most_triangles)) {
        let triangles = level.len() / 3;
        if triangles as f64 > triangles_before as f64 * SHRINK {
            continue;
        }
        error_floor = error_floor.max(error);
        triangles_before = triangles;
        levels.push(StandIn {
            indices: level,
            error: error_floor,
        });
    }
    if let Some(octahedron) = extreme_octahedron(vertices) {
        if octahedron.len() / 3 < triangles_before {
            let positions: Vec<[f32; 3]> = vertices.iter().map(|v| v.position).collect();
            let strayed = farthest_from(&positions, &octahedron);
            levels.push(StandIn {
                error: error_floor
                    .max(half_box_diagonal(vertices.iter().map(|v| v.position)))
                    .max(2.0 * strayed),
                indices: octahedron,
            });
        }
    }
    levels
}

/// The share of `triangles` a level after them aims at.
fn next_target(triangles: usize) -> usize {
    (triangles as f64 * LEVEL_SHARE) as usize
}

/// The welded simplifications of the part (`indices` into `vertices`), each with its error in
/// the part's units: [`LEVEL_SHARE`] of `coarsest` triangles but at most `most_triangles`, then
/// that share of the level before each time, down to 8.
fn welded_levels(
    vertices: &[Vertex],
    adapter: &VertexDataAdapter<'_>,
    indices: &[u32],
    (coarsest, most_triangles): (usize, usize),
) -> Vec<(Vec<u32>, f32)> {
    // One vertex per position (the library would keep split vertices as seams), named by the
    // first of the part's vertices there.
    let first_at = meshopt::generate_position_remap(adapter);
    let mut positions: Vec<u32> = first_at.clone();
    positions.sort_unstable();
    positions.dedup();
    let welded_of = |vertex: u32| {
        let first = first_at.get(vertex as usize).copied().unwrap_or(vertex);
        positions.binary_search(&first).unwrap_or(0) as u32
    };
    let welded: Vec<u32> = indices.iter().map(|&i| welded_of(i)).collect();
    let welded_positions: Vec<[f32; 3]> = positions
        .iter()
        .map(|&v| vertices[v as usize].position)
        .collect();
    // The part's vertices at each welded position.
    let mut at_position: Vec<Vec<u32>> = vec![Vec::new(); positions.len()];
    for vertex in 0..vertices.len() as u32 {
        at_position[welded_of(vertex) as usize].push(vertex);
    }
    let Ok(welded_adapter) = VertexDataAdapter::new(
        bytemuck::cast_slice(&welded_positions),
        std::mem::size_of::<[f32; 3]>(),
        0,
    ) else {
        return Vec::new();
    };
    let scale = meshopt::simplify_scale(&welded_adapter);
    let mut target = next_target(coarsest).min(most_triangles);
    let mut levels = Vec::new();
    // Each level is simplified from one source, not from the level before: a chain of
    // simplifications drifts, and its coarser levels strayed two to three times as far for
    // their triangles (gen:grid's prisms drew 12 % more triangles at 1 px). The source is the
    // part, or for a large part its simplification to [`SOURCE_TRIANGLES`]: the part itself
    // costs one simplification, not one per level. Each error is measured against the part.
    let (source, source_error) = level_source(&welded, &welded_adapter, scale);
    while target >= 8 {
        let (simplified, library_error) = simplified_to(&source, &welded_adapter, target, scale);
        if simplified.is_empty() || simplified.len() > target * 3 {
            break;
        }
        let level = with_facet_normals(vertices, &at_position, &welded_positions, &simplified);
        let reached = level.len() / 3;
        // The library's error measures how far the kept vertices moved from the planes of
        // their triangles, not how far the part's surface is from the level's: a round prism
        // cut down to a few sides is off by its sagitta, which only the part's own vertices
        // show. A level made of the part's own vertices lies within its outline, which then
        // loses that distance on each side: the error counts it twice.
        let strayed = farthest_from(&welded_positions, &simplified);
        let simplification_error = source_error + library_error;
        levels.push((level, simplification_error.max(2.0 * strayed)));
        target = next_target(target.min(reached));
    }
    levels
}

/// The most triangles of the source the welded levels are simplified from.
const SOURCE_TRIANGLES: usize = 1024;

/// What the welded levels are simplified from, and its error in the part's units: the welded
/// part, or its simplification to at most [`SOURCE_TRIANGLES`] where it has more.
fn level_source<'a>(
    welded: &'a [u32],
    welded_adapter: &VertexDataAdapter<'_>,
    scale: f32,
) -> (Cow<'a, [u32]>, f32) {
    if welded.len() / 3 > SOURCE_TRIANGLES {
        let (simplified, error) = simplified_to(welded, welded_adapter, SOURCE_TRIANGLES, scale);
        if !simplified.is_empty() {
            return (Cow::Owned(simplified), error);
        }
    }
    (Cow::Borrowed(welded), 0.0)
}

/// `indices` simplified towards `triangles` triangles (the library may stop short of them), and
/// the library's error in the part's units (`scale` is the library's for the part).
fn simplified_to(
    indices: &[u32],
    welded_adapter: &VertexDataAdapter<'_>,
    triangles: usize,
    scale: f32,
) -> (Vec<u32>, f32) {
    let mut relative_error = 0.0;
    let simplified = meshopt::simplify(
        indices,
        welded_adapter,
        triangles * 3,
        1.0,
        SimplifyOptions::None,
        Some(&mut relative_error),
    );
    (simplified, relative_error * scale)
}

/// The most part positions whose distance to a level is measured: past it, evenly spaced ones
/// (large parts cost a distance per position and triangle).
const MEASURED_POSITIONS: usize = 2048;

/// How far the farthest of `positions` (up to [`MEASURED_POSITIONS`] of them, evenly spaced) is
/// from the triangles `indices` (into `positions`).
fn farthest_from(positions: &[[f32; 3]], indices: &[u32]) -> f32 {
    let triangles: Vec<[glam::Vec3; 3]> = indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]].map(|i| glam::Vec3::from(positions[i as usize])))
        .collect();
    let step = positions.len().div_ceil(MEASURED_POSITIONS).max(1);
    let mut farthest = 0.0f32;
    for &p in positions.iter().step_by(step) {
        let p = glam::Vec3::from(p);
        // A position within `farthest` of some triangle cannot raise it: the first such
        // triangle ends its search (most positions lie on the level, at a distance of 0).
        let mut nearest = f32::MAX;
        for &[a, b, c] in &triangles {
            nearest = nearest.min(p.distance(closest_on_triangle(p, a, b, c)));
            if nearest <= farthest {
                break;
            }
        }
        farthest = farthest.max(nearest);
    }
    farthest
}

/// The point of the triangle `a b c` closest to `p` (by the triangle's regions: each corner,
/// each edge, the inside).
pub(super) fn closest_on_triangle(
    p: glam::Vec3,
    a: glam::Vec3,
    b: glam::Vec3,
    c: glam::Vec3,
) -> glam::Vec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denominator = va + vb + vc;
    if denominator == 0.0 || !denominator.is_finite() {
        return a;
    }
    a + ab * (vb / denominator) + ac * (vc / denominator)
}

/// The welded triangles `simplified` with each corner moved to the part's vertex at that
/// position whose normal best matches the triangle's; triangles without area are left out.
fn with_facet_normals(
    vertices: &[Vertex],
    at_position: &[Vec<u32>],
    welded_positions: &[[f32; 3]],
    simplified: &[u32],
) -> Vec<u32> {
    let position = |i: u32| glam::Vec3::from(welded_positions[i as usize]);
    let mut out = Vec::with_capacity(simplified.len());
    for triangle in simplified.chunks_exact(3) {
        let [a, b, c] = [triangle[0], triangle[1], triangle[2]];
        let facing = (position(b) - position(a)).cross(position(c) - position(a));
        if facing.length_squared() == 0.0 || !facing.is_finite() {
            continue;
        }
        let facing = facing.normalize();
        let along = |i: &u32| glam::Vec3::from(vertices[*i as usize].normal).dot(facing);
        let corners = [a, b, c].map(|corner| {
            at_position
                .get(corner as usize)?
                .iter()
                .max_by(|p, q| along(p).total_cmp(&along(q)))
                .copied()
        });
        if let [Some(a), Some(b), Some(c)] = corners {
            out.extend([a, b, c]);
        }
    }
    out
}

/// The triangles (indices into `vertices`, wound counter-clockwise seen from outside) of the
/// octahedron through the vertices at the least and the most of each axis, leaving out those
/// that collapse; `None` when fewer than four remain.
fn extreme_octahedron(vertices: &[Vertex]) -> Option<Vec<u32>> {
    let extreme = |axis: usize, most: bool| -> Option<u32> {
        let key = |v: &&Vertex| v.position[axis];
        let found = if most {
            vertices
                .iter()
                .enumerate()
                .max_by(|a, b| key(&a.1).total_cmp(&key(&b.1)))
        } else {
            vertices
                .iter()
                .enumerate()
                .min_by(|a, b| key(&a.1).total_cmp(&key(&b.1)))
        };
        found.map(|(i, _)| i as u32)
    };
    let ends: Vec<[u32; 2]> = (0..3)
        .map(|axis| Some([extreme(axis, false)?, extreme(axis, true)?]))
        .collect::<Option<_>>()?;
    let position = |i: u32| glam::Vec3::from(vertices[i as usize].position);
    let mut triangles = Vec::new();
    for corner in 0..8usize {
        let side = |axis: usize| (corner >> axis) & 1;
        let [a, b, c] = [ends[0][side(0)], ends[1][side(1)], ends[2][side(2)]];
        let normal = (position(b) - position(a)).cross(position(c) - position(a));
        if a == b || b == c || a == c || normal.length_squared() == 0.0 {
            continue;
        }
        // Outward: toward the corner's side on every axis.
        let outward = glam::Vec3::from(std::array::from_fn(|axis| {
            if side(axis) == 1 {
                1.0
            } else {
                -1.0
            }
        }));
        triangles.extend(if normal.dot(outward) >= 0.0 {
            [a, b, c]
        } else {
            [a, c, b]
        });
    }
    (triangles.len() >= 12).then_some(triangles)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

    use glam::Vec3;

    use super::*;

    #[test]
    fn the_closest_point_of_a_triangle_is_no_farther_than_any_point_of_it() {
        let [a, b, c] = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.5, 1.5, 0.3),
        ];
        let samples: Vec<Vec3> = (0..=40)
            .flat_map(|i| (0..=40 - i).map(move |j| (i as f32 / 40.0, j as f32 / 40.0)))
            .map(|(u, v)| a + (b - a) * u + (c - a) * v)
            .collect();
        // Points in every region: beyond each corner and edge, above the inside.
        for p in [
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(3.0, -0.5, 0.2),
            Vec3::new(0.4, 3.0, 0.0),
            Vec3::new(1.0, -2.0, 1.0),
            Vec3::new(1.6, 1.2, -0.4),
            Vec3::new(-0.8, 0.7, 0.5),
            Vec3::new(0.7, 0.4, 2.0),
        ] {
            let closest = closest_on_triangle(p, a, b, c);
            let nearest_sample = samples
                .iter()
                .map(|s| p.distance(*s))
                .fold(f32::MAX, f32::min);
            assert!(p.distance(closest) <= nearest_sample + 1e-5, "{p}");
            assert!(
                p.distance(closest) >= nearest_sample - 0.06,
                "{p}: on the triangle"
            );
        }
    }

    /// A faceted prism of `sides` sides (every facet its own vertices and normal), radius 1.
    fn faceted_prism(sides: u32) -> (Vec<Vertex>, Vec<u32>) {
        let corner = |k: u32, y: f32| {
            let angle = std::f32::consts::TAU * k as f32 / sides as f32;
            [angle.cos(), y, angle.sin()]
        };
        let mut vertices = Vec::new();
        let mut indices = Vec::new();
        let mut facet = |corners: &[[f32; 3]]| {
            let [a, b, c] = [0, 1, 2].map(|i| Vec3::from(corners[i]));
            let normal = (b - a).cross(c - a).normalize().to_array();
            let base = vertices.len() as u32;
            vertices.extend(corners.iter().map(|&position| Vertex { position, normal }));
            for k in 1..corners.len() as u32 - 1 {
                indices.extend([base, base + k, base + k + 1]);
            }
        };
        for k in 0..sides {
            facet(&[
                corner(k, 0.0),
                corner(k, 1.0),
                corner(k + 1, 1.0),
                corner(k + 1, 0.0),
            ]);
        }
        let top: Vec<_> = (0..sides).rev().map(|k| corner(k, 1.0)).collect();
        let bottom: Vec<_> = (0..sides).map(|k| corner(k, 0.0)).collect();
        facet(&top);
        facet(&bottom);
        (vertices, indices)
    }

    #[test]
    fn welded_levels_of_a_faceted_prism_shrink_and_keep_their_facets_normals() {
        let (vertices, indices) = faceted_prism(64);
        let triangles = indices.len() / 3;
        let levels = stand_ins(&vertices, &indices, (triangles, 128), 0.0);
        let counts: Vec<usize> = levels.iter().map(|l| l.indices.len() / 3).collect();
        assert!(counts.len() >= 4, "{counts:?}");
        assert!(
            counts[0] <= 128 && counts.windows(2).all(|c| c[1] < c[0]),
            "{counts:?}"
        );
        let errors: Vec<f32> = levels.iter().map(|l| l.error).collect();
        assert!(errors.windows(2).all(|e| e[1] >= e[0]), "{errors:?}");
        // The coarsest has few sides: its sagitta on a circle of radius 1 is large.
        assert!(*errors.last().unwrap() > 0.2, "{errors:?}");
        // Corners take the part's normals nearest the triangle's own: within a few degrees
        // where the level still has many sides, within about 70 while it has 16 triangles or
        // more (past that, a triangle may cross the prism where no facet faces its way).
        for level in levels.iter().filter(|l| l.indices.len() / 3 >= 16) {
            let least = if level.indices.len() / 3 >= 100 {
                0.95
            } else {
                0.3
            };
            for t in level.indices.chunks_exact(3) {
                let [a, b, c] =
                    [t[0], t[1], t[2]].map(|i| Vec3::from(vertices[i as usize].position));
                let facing = (b - a).cross(c - a).normalize();
                for &corner in t {
                    let along = Vec3::from(vertices[corner as usize].normal).dot(facing);
                    assert!(
                        along > least,
                        "{along} at {} triangles",
                        level.indices.len() / 3
                    );
                }
            }
        }
    }

    #[test]
    fn a_part_that_does_not_simplify_gets_only_what_has_fewer_triangles() {
        // A box of 12 triangles: nothing simplifies it, and its octahedron (8 triangles) is
        // kept only because it has fewer.
        let (vertices, indices) = faceted_prism(4);
        let levels = stand_ins(&vertices, &indices, (indices.len() / 3, 128), 0.5);
        assert!(levels
            .iter()
            .all(|l| l.indices.len() / 3 < indices.len() / 3));
        assert!(
            levels.iter().all(|l| l.error >= 0.5),
            "no error under the floor"
        );
    }
}
