//! `gen:fine`: machined parts with real triangle counts, for level-of-detail benchmarks. Each
//! unit is a flange with a bore and fillets, a gear with smooth tooth flanks, a stepped shaft,
//! and eight bolts (threaded shanks, filleted heads) with washers on the flange's bolt circle,
//! the fasteners instanced. Curved faces have shared normals, faces meet at creases (split
//! vertices), as CAD tessellations do; `detail` scales the tessellation (about 10³ triangles
//! per part at 1, 10⁵ at 10).

use std::f64::consts::{PI, TAU};

use glam::{DMat4, DVec3};

use super::grid::hue_to_rgb;
use crate::scene::{
    Geometry, GeometrySink, KeepInScene, Material, MeshRef, Node, Part, Scene, Vertex,
};

/// Variants of each unique part (sizes and tooth counts), so units differ.
const VARIANTS: u32 = 4;
/// Bolts (and washers) per unit, on the flange's bolt circle.
const BOLTS: u32 = 8;
/// Distance between unit centres.
const PITCH: f64 = 5.0;

/// Positions are rounded to multiples of 1 / SNAP.
const SNAP: f64 = (1u64 << 20) as f64;

/// A point of a surface and its normal.
type Sample = (DVec3, DVec3);

/// One smooth face: a grid of `columns` × `rows` quads over a surface, `wraps` when its last
/// column meets its first. Normals come from the surface's own partial derivatives, so a face
/// is smooth inside; faces meet at creases, where vertices are split.
fn face(
    geometry: &mut Geometry,
    (columns, rows): (u32, u32),
    wraps: bool,
    surface: &dyn Fn(f64, f64) -> DVec3,
) {
    let base = geometry.vertices.len() as u32;
    let eps = 1e-4;
    let sample = |u: f64, v: f64| -> Sample {
        let p = surface(u, v);
        // Measured a little inside the face, so that a pole (a disc's centre, where the
        // circle has no length) still has the face's normal.
        let w = v.clamp(1e-3, 1.0 - 1e-3);
        let du = surface(u + eps, w) - surface(u - eps, w);
        let dv = surface(u, w + eps) - surface(u, w - eps);
        (p, du.cross(dv).normalize_or_zero())
    };
    let width = if wraps { columns } else { columns + 1 };
    for row in 0..=rows {
        for column in 0..width {
            let (p, n) = sample(
                f64::from(column) / f64::from(columns),
                f64::from(row) / f64::from(rows),
            );
            // Snapped to a grid of 2^-20 units, so that the faces' shared rims (computed by
            // different formulas) meet exactly and the part is watertight.
            let p = (p * SNAP).round() / SNAP;
            geometry.vertices.push(Vertex {
                position: p.as_vec3().to_array(),
                normal: n.as_vec3().to_array(),
            });
        }
    }
    for row in 0..rows {
        for column in 0..columns {
            let next = if wraps {
                (column + 1) % columns
            } else {
                column + 1
            };
            let a = base + row * width + column;
            let b = base + row * width + next;
            let c = a + width;
            let d = b + width;
            // Wound counter-clockwise seen from where the normals point.
            geometry.indices.extend([a, b, d, a, d, c]);
        }
    }
}

/// A surface of revolution around +Y: `profile(v)` gives (radius, height). Every profile runs
/// counter-clockwise around the solid's cross-section (up the outside, inward along a top,
/// down a bore, outward along a bottom), so that the normals point out of the solid.
fn lathe(geometry: &mut Geometry, segments: u32, rows: u32, profile: &dyn Fn(f64) -> (f64, f64)) {
    face(geometry, (segments, rows), true, &|u, v| {
        let (r, y) = profile(v);
        let angle = -u * TAU;
        DVec3::new(r * angle.cos(), y, r * angle.sin())
    });
}

/// A point at `v` along the arc of `radius` around `center` (radius, height) from angle `from`
/// to `to`: a fillet or a rounded edge of a profile.
fn arc(v: f64, center: (f64, f64), radius: f64, (from, to): (f64, f64)) -> (f64, f64) {
    let angle = from + (to - from) * v;
    (
        center.0 + radius * angle.cos(),
        center.1 + radius * angle.sin(),
    )
}

/// A straight profile segment from `a` to `b`.
fn line(v: f64, a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    (a.0 + (b.0 - a.0) * v, a.1 + (b.1 - a.1) * v)
}

/// Closes a geometry's triangles into one part.
fn one_part(mut geometry: Geometry) -> Geometry {
    // Made by pushing: the arrays keep no room beyond what they hold.
    geometry.vertices.shrink_to_fit();
    geometry.indices.shrink_to_fit();
    geometry.parts = vec![Part {
        first_index: 0,
        index_count: geometry.indices.len() as u32,
        first_wire_index: 0,
        wire_index_count: 0,
    }];
    geometry
}

fn named(name: String) -> Geometry {
    Geometry {
        name,
        ..Geometry::default()
    }
}

/// A bolt along +Y: a round head with a rounded top edge, a fillet into a threaded shank, a
/// chamfered tip.
fn bolt(detail: u32) -> Geometry {
    let mut g = named("fine bolt".into());
    let segments = 24 * detail;
    let (head_r, head_h, shank_r, length) = (0.28, 0.18, 0.14, 1.2);
    let round = 0.2 * head_r;
    let neck = (shank_r * 1.3, -0.3 * shank_r);
    let (pitch, thread, chamfer) = (0.06, 0.012, 0.03);
    let tip = -length;
    lathe(&mut g, segments, 2 * detail, &|v| {
        line(v, (head_r - round, head_h), (0.0, head_h))
    });
    lathe(&mut g, segments, 4 * detail, &|v| {
        arc(v, (head_r - round, head_h - round), round, (0.0, PI * 0.5))
    });
    lathe(&mut g, segments, 2 * detail, &|v| {
        line(v, (head_r, 0.0), (head_r, head_h - round))
    });
    lathe(&mut g, segments, detail, &|v| {
        line(v, (neck.0, 0.0), (head_r, 0.0))
    });
    lathe(&mut g, segments, 3 * detail, &|v| {
        arc(v, neck, neck.0 - shank_r, (PI, PI * 0.5))
    });
    // The threaded shank: a helix cut into the radius, fading out at both ends so that it
    // meets the fillet and the chamfer.
    let rows = (length / pitch * 4.0 * f64::from(detail)).ceil() as u32;
    face(&mut g, (segments, rows), true, &|u, v| {
        let y = tip + v * (neck.1 - tip);
        let fade = (v * (1.0 - v) * 40.0).min(1.0);
        let turn = (y / pitch + u) * TAU;
        let r = shank_r - thread * fade * (0.5 + 0.5 * turn.sin());
        let angle = -u * TAU;
        DVec3::new(r * angle.cos(), y, r * angle.sin())
    });
    lathe(&mut g, segments, detail, &|v| {
        line(v, (shank_r - chamfer, tip - chamfer), (shank_r, tip))
    });
    lathe(&mut g, segments, detail, &|v| {
        line(v, (0.0, tip - chamfer), (shank_r - chamfer, tip - chamfer))
    });
    one_part(g)
}

/// A washer: a flat ring with a rounded outer edge around a hole.
fn washer(detail: u32) -> Geometry {
    let mut g = named("fine washer".into());
    let segments = 48 * detail;
    let (inner, outer, h) = (0.16, 0.34, 0.05);
    lathe(&mut g, segments, detail, &|v| {
        line(v, (outer, h), (inner, h))
    });
    lathe(&mut g, segments, detail, &|v| {
        line(v, (inner, h), (inner, 0.0))
    });
    lathe(&mut g, segments, detail, &|v| {
        line(v, (inner, 0.0), (outer, 0.0))
    });
    lathe(&mut g, segments, 3 * detail, &|v| {
        arc(v, (outer, h * 0.5), h * 0.5, (-PI * 0.5, PI * 0.5))
    });
    one_part(g)
}

/// A flange: a hub with a bore, a fillet down to a disc with a rounded rim.
fn flange(detail: u32, variant: u32) -> Geometry {
    let mut g = named(format!("fine flange {variant}"));
    let segments = 48 * detail;
    let scale = 1.0 + 0.15 * f64::from(variant);
    let (bore, hub, disc, hub_h, disc_h) = (0.35 * scale, 0.6 * scale, 1.5 * scale, 0.8, 0.25);
    let f = 0.15;
    lathe(&mut g, segments, detail, &|v| {
        line(v, (hub, hub_h), (bore, hub_h))
    });
    lathe(&mut g, segments, 2 * detail, &|v| {
        line(v, (bore, hub_h), (bore, 0.0))
    });
    lathe(&mut g, segments, 2 * detail, &|v| {
        line(v, (bore, 0.0), (disc, 0.0))
    });
    lathe(&mut g, segments, 4 * detail, &|v| {
        arc(v, (disc, disc_h * 0.5), disc_h * 0.5, (-PI * 0.5, PI * 0.5))
    });
    lathe(&mut g, segments, 2 * detail, &|v| {
        line(v, (disc, disc_h), (hub + f, disc_h))
    });
    lathe(&mut g, segments, 4 * detail, &|v| {
        arc(v, (hub + f, disc_h + f), f, (PI * 1.5, PI))
    });
    lathe(&mut g, segments, 2 * detail, &|v| {
        line(v, (hub, disc_h + f), (hub, hub_h))
    });
    one_part(g)
}

/// A spur gear around +Y: smooth tooth flanks, flat faces, a bore.
fn gear(detail: u32, variant: u32) -> Geometry {
    let mut g = named(format!("fine gear {variant}"));
    let teeth = 24 + 8 * variant;
    let (root, height, bore, width) = (1.0, 0.08, 0.3, 0.3);
    let segments = teeth * 8 * detail;
    // One smooth bump per tooth.
    let radius = move |u: f64| root + height * (0.5 - 0.5 * (u * f64::from(teeth) * TAU).cos());
    let at = |r: f64, u: f64, y: f64| {
        let angle = -u * TAU;
        DVec3::new(r * angle.cos(), y, r * angle.sin())
    };
    let rows = 2 * detail;
    face(&mut g, (segments, rows), true, &|u, v| {
        at(radius(u), u, width * v)
    });
    face(&mut g, (segments, rows), true, &|u, v| {
        at(radius(u) + (bore - radius(u)) * v, u, width)
    });
    face(&mut g, (segments, rows), true, &|u, v| {
        at(bore + (radius(u) - bore) * v, u, 0.0)
    });
    lathe(&mut g, segments, detail, &|v| {
        line(v, (bore, width), (bore, 0.0))
    });
    one_part(g)
}

/// A stepped shaft along +Y with a fillet at the step.
fn shaft(detail: u32, variant: u32) -> Geometry {
    let mut g = named(format!("fine shaft {variant}"));
    let segments = 32 * detail;
    let (big, small, length) = (0.3, 0.22, 2.4 + 0.3 * f64::from(variant));
    let step = length * 0.55;
    let f = 0.05;
    lathe(&mut g, segments, detail, &|v| {
        line(v, (0.0, 0.0), (big, 0.0))
    });
    lathe(&mut g, segments, 6 * detail, &|v| {
        line(v, (big, 0.0), (big, step))
    });
    lathe(&mut g, segments, detail, &|v| {
        line(v, (big, step), (small + f, step))
    });
    lathe(&mut g, segments, 3 * detail, &|v| {
        arc(v, (small + f, step + f), f, (PI * 1.5, PI))
    });
    lathe(&mut g, segments, 6 * detail, &|v| {
        line(v, (small, step + f), (small, length))
    });
    lathe(&mut g, segments, detail, &|v| {
        line(v, (small, length), (0.0, length))
    });
    one_part(g)
}

/// `units` units of a flange, gear, shaft and eight bolts with washers, at `detail`; where
/// `unique`, every unit with geometries of its own (copies of its variant's).
pub fn fine(units: u32, detail: u32, unique: bool) -> Scene {
    fine_through(units, detail, unique, &mut KeepInScene)
}

/// [`fine`], handing each geometry to `sink` as soon as it is made (see [`GeometrySink`]): with
/// `unique`, a unit's copies go as the unit is made, so that a sink that pages them never holds
/// more than one unit's.
pub fn fine_through(units: u32, detail: u32, unique: bool, sink: &mut dyn GeometrySink) -> Scene {
    let detail = detail.max(1);
    let mut scene = Scene {
        name: if unique {
            format!("fine:units={units},detail={detail},unique=1")
        } else {
            format!("fine:units={units},detail={detail}")
        },
        ..Scene::default()
    };
    scene.materials = (0..6)
        .map(|i| Material {
            name: format!("fine material {i}"),
            base_color: hue_to_rgb(i as f32 / 6.0),
            metallic: if i % 2 == 0 { 0.8 } else { 0.1 },
            roughness: 0.35,
            ..Material::default()
        })
        .collect();
    // Geometry slots: bolt, washer, then per variant a flange, a gear and a shaft. With
    // `unique`, they are templates each unit copies.
    let mut templates = vec![bolt(detail), washer(detail)];
    for variant in 0..VARIANTS {
        templates.extend([
            flange(detail, variant),
            gear(detail, variant),
            shaft(detail, variant),
        ]);
    }
    // Made valid (the tests check it), so they go to the sink unchecked.
    let mut keep = |scene: &mut Scene, geometry: Geometry| {
        let index = scene.geometries.len() as u32;
        let kept = sink.take(index, geometry);
        scene.geometries.push(kept);
    };
    if !unique {
        for template in std::mem::take(&mut templates) {
            keep(&mut scene, template);
        }
    }
    let mesh = |geometry: u32, material: u32| {
        Some(MeshRef {
            geometry,
            part_materials: vec![material],
            part_overrides: Vec::new(),
        })
    };
    scene.nodes.push(Node::new(scene.name.clone()));
    scene.roots.push(0);
    let side = f64::from(units).sqrt().ceil().max(1.0) as u32;
    for unit in 0..units {
        let variant = unit % VARIANTS;
        let scale = 1.0 + 0.15 * f64::from(variant);
        let place = DVec3::new(
            f64::from(unit % side) * PITCH,
            0.0,
            f64::from(unit / side) * PITCH,
        );
        // Bolt, washer, flange, gear, shaft: the shared ones, or copies of its own.
        let [bolt, washer, first] = if unique {
            let own = scene.geometries.len() as u32;
            for shared in [0, 1, 2 + 3 * variant, 3 + 3 * variant, 4 + 3 * variant] {
                keep(&mut scene, templates[shared as usize].clone());
            }
            [own, own + 1, own + 2]
        } else {
            [0, 1, 2 + 3 * variant]
        };
        let unit_node = scene.nodes.len() as u32;
        scene.nodes[0].children.push(unit_node);
        scene.nodes.push(Node {
            local: DMat4::from_translation(place),
            ..Node::new(format!("unit {unit}"))
        });
        let mut add = |name: String, local: DMat4, mesh_ref: Option<MeshRef>| {
            let index = scene.nodes.len() as u32;
            scene.nodes[unit_node as usize].children.push(index);
            scene.nodes.push(Node {
                name,
                local,
                children: Vec::new(),
                mesh: mesh_ref,
            });
        };
        add("flange".into(), DMat4::IDENTITY, mesh(first, 0));
        add(
            "shaft".into(),
            DMat4::from_translation(DVec3::new(0.0, -0.5, 0.0)),
            mesh(first + 2, 1),
        );
        add(
            "gear".into(),
            DMat4::from_translation(DVec3::new(0.0, 1.2, 0.0)),
            mesh(first + 1, 2),
        );
        let circle = 1.1 * scale;
        for b in 0..BOLTS {
            let angle = f64::from(b) / f64::from(BOLTS) * TAU;
            let at = DVec3::new(circle * angle.cos(), 0.25, circle * angle.sin());
            add(
                format!("washer {b}"),
                DMat4::from_translation(at),
                mesh(washer, 3),
            );
            add(
                format!("bolt {b}"),
                DMat4::from_translation(at + DVec3::Y * 0.05),
                mesh(bolt, 4 + b % 2),
            );
        }
    }
    scene
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parts_have_the_triangles_the_detail_asks_for_and_normals_that_are_unit() {
        for detail in [1, 4] {
            let scene = fine(2, detail, false);
            scene.validate().expect("generated geometry is valid");
            for geometry in &scene.geometries {
                let triangles = geometry.indices.len() / 3;
                let low = 500 * (detail * detail) as usize;
                assert!(
                    (low..low * 40).contains(&triangles),
                    "{} at detail {detail}: {triangles} triangles",
                    geometry.name
                );
                for v in &geometry.vertices {
                    let length = v.normal.iter().map(|c| c * c).sum::<f32>().sqrt();
                    assert!((length - 1.0).abs() < 1e-3, "{}: {:?}", geometry.name, v);
                }
            }
        }
        assert_eq!(fine(3, 2, false), fine(3, 2, false), "deterministic");
        // Unique units: five geometries each (bolt, washer, flange, gear, shaft), each used by
        // one unit only, the same shapes as the shared ones.
        let (shared, unique) = (fine(6, 1, false), fine(6, 1, true));
        assert_eq!(unique.geometries.len(), 30);
        let mut users = vec![std::collections::BTreeSet::new(); 30];
        for (unit, &node) in unique.nodes[0].children.iter().enumerate() {
            for &child in &unique.nodes[node as usize].children {
                if let Some(mesh) = &unique.nodes[child as usize].mesh {
                    users[mesh.geometry as usize].insert(unit);
                }
            }
        }
        assert!(users.iter().all(|u| u.len() == 1), "{users:?}");
        let triangles = |s: &Scene| s.geometries.iter().map(|g| g.indices.len()).sum::<usize>();
        assert!(triangles(&unique) > 2 * triangles(&shared));
        // Watertight and wound outward: cones and section caps apply.
        for geometry in &fine(1, 1, false).geometries {
            assert_eq!(
                crate::scene::closure::closure(&geometry.vertices, &geometry.indices),
                crate::scene::closure::Closure::Closed,
                "{}",
                geometry.name
            );
        }
    }
}
