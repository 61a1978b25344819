//! Building geometries out of faceted prisms, each prism one part, the way machined CAD parts
//! are made of features (plates, bosses, fins, shaft sections).

use glam::{DMat3, DMat4, DVec3};

use crate::scene::{Geometry, Part, Vertex};

/// Triangles of a prism with `sides` faces and both caps.
pub fn prism_triangles(sides: u32) -> u32 {
    4 * sides - 4
}

/// Appends parts to a geometry.
pub struct GeometryBuilder {
    geometry: Geometry,
}

impl GeometryBuilder {
    /// An empty geometry named `name`.
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            geometry: Geometry {
                name: name.into(),
                ..Geometry::default()
            },
        }
    }

    /// Number of parts so far.
    pub fn part_count(&self) -> usize {
        self.geometry.parts.len()
    }

    /// Adds one part: a prism with `sides` flat faces around the Y axis (circumradius 1,
    /// y from -0.5 to 0.5, one face centred on +X) with both caps, placed by `transform`.
    pub fn prism(&mut self, sides: u32, transform: DMat4) {
        let sides = sides.max(3);
        let normal_matrix = DMat3::from_mat4(transform).inverse().transpose();
        let first_index = self.geometry.indices.len() as u32;
        let first_wire_index = self.geometry.wire_indices.len() as u32;
        let corner = |k: u32, y: f64| {
            let angle = std::f64::consts::TAU * (f64::from(k) + 0.5) / f64::from(sides);
            DVec3::new(angle.cos(), y, angle.sin())
        };
        let push = |geometry: &mut Geometry, position: DVec3, normal: DVec3| {
            let position = transform.transform_point3(position).as_vec3().to_array();
            let normal = (normal_matrix * normal)
                .normalize_or_zero()
                .as_vec3()
                .to_array();
            geometry.vertices.push(Vertex { position, normal });
            geometry.vertices.len() as u32 - 1
        };
        let geometry = &mut self.geometry;
        for k in 0..sides {
            let mid = std::f64::consts::TAU * f64::from(k + 1) / f64::from(sides);
            let normal = DVec3::new(mid.cos(), 0.0, mid.sin());
            let a = push(geometry, corner(k, -0.5), normal);
            let b = push(geometry, corner(k + 1, -0.5), normal);
            let c = push(geometry, corner(k + 1, 0.5), normal);
            let d = push(geometry, corner(k, 0.5), normal);
            geometry.indices.extend([a, c, b, a, d, c]);
            // Feature edges: bottom, top and the vertical edge where two faces meet.
            geometry.wire_indices.extend([a, b, d, c, a, d]);
        }
        for (y, normal) in [(0.5, DVec3::Y), (-0.5, DVec3::NEG_Y)] {
            let ring: Vec<u32> = (0..sides)
                .map(|k| push(geometry, corner(k, y), normal))
                .collect();
            for k in 1..sides as usize - 1 {
                if y > 0.0 {
                    geometry.indices.extend([ring[0], ring[k + 1], ring[k]]);
                } else {
                    geometry.indices.extend([ring[0], ring[k], ring[k + 1]]);
                }
            }
        }
        let index_count = geometry.indices.len() as u32 - first_index;
        let wire_index_count = geometry.wire_indices.len() as u32 - first_wire_index;
        geometry.parts.push(Part {
            first_index,
            index_count,
            first_wire_index,
            wire_index_count,
        });
    }

    /// Adds a box part from `min` to `max`, axis-aligned after `transform`.
    pub fn cuboid(&mut self, min: DVec3, max: DVec3, transform: DMat4) {
        let size = max - min;
        let center = (min + max) * 0.5;
        // A 4-sided prism of circumradius 1 has axis-aligned faces at distance 1/sqrt(2).
        let scale = DVec3::new(
            size.x / std::f64::consts::SQRT_2,
            size.y,
            size.z / std::f64::consts::SQRT_2,
        );
        self.prism(
            4,
            transform * DMat4::from_translation(center) * DMat4::from_scale(scale),
        );
    }

    /// The finished geometry.
    pub fn finish(self) -> Geometry {
        self.geometry
    }
}
