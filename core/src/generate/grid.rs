//! `gen:grid`: exactly N parts in a cube of objects, for scaling benchmarks up to millions.

use glam::{DMat4, DVec3};

use super::component::component;
use super::rng::Rng;
use crate::scene::{Material, MeshRef, Node, Scene};

/// Parts of each object in the grid.
pub const PARTS_PER_OBJECT: u64 = 10;
const COMPONENTS: usize = 16;
const MATERIALS: usize = 24;

/// A grid with exactly `parts` parts of about `triangles_per_part` triangles.
pub fn grid(parts: u64, triangles_per_part: f64) -> Scene {
    let mut rng = Rng::new(0x6772_6964);
    let mut scene = Scene {
        name: format!("grid:parts={parts}"),
        ..Scene::default()
    };
    scene.materials = (0..MATERIALS)
        .map(|i| {
            let hue = i as f32 / MATERIALS as f32;
            Material {
                name: format!("grid material {i}"),
                base_color: hue_to_rgb(hue),
                metallic: if i % 3 == 0 { 0.9 } else { 0.0 },
                roughness: 0.4,
                ..Material::default()
            }
        })
        .collect();
    for g in 0..COMPONENTS {
        scene.geometries.push(component(
            format!("grid component {g}"),
            PARTS_PER_OBJECT as usize,
            triangles_per_part,
            &mut rng,
        ));
    }
    let full_objects = parts / PARTS_PER_OBJECT;
    let remainder = (parts % PARTS_PER_OBJECT) as usize;
    if remainder > 0 {
        scene.geometries.push(component(
            "grid remainder".into(),
            remainder,
            triangles_per_part,
            &mut rng,
        ));
    }
    let objects = full_objects + u64::from(remainder > 0);
    let side = (objects as f64).cbrt().ceil().max(1.0) as u64;
    let pitch = 1.6;
    scene.nodes.push(Node::new(scene.name.clone()));
    scene.roots.push(0);
    let mut placed = 0_u64;
    'layers: for y in 0..side {
        let layer = scene.nodes.len() as u32;
        let layer_local = DMat4::from_translation(DVec3::new(0.0, y as f64 * pitch, 0.0));
        scene.nodes.push(Node {
            local: layer_local,
            ..Node::new(format!("layer {y}"))
        });
        scene.nodes[0].children.push(layer);
        for z in 0..side {
            let row = scene.nodes.len() as u32;
            let row_local = DMat4::from_translation(DVec3::new(0.0, 0.0, z as f64 * pitch));
            scene.nodes.push(Node {
                local: row_local,
                ..Node::new(format!("layer {y} row {z}"))
            });
            scene.nodes[layer as usize].children.push(row);
            for x in 0..side {
                if placed == objects {
                    break 'layers;
                }
                let geometry = if placed == full_objects {
                    COMPONENTS
                } else {
                    rng.below(COMPONENTS)
                };
                let part_count = scene.geometries[geometry].parts.len();
                let first_material = rng.below(MATERIALS);
                let part_materials = (0..part_count)
                    .map(|p| ((first_material + p / 4) % MATERIALS) as u32)
                    .collect();
                let local = DMat4::from_translation(DVec3::new(x as f64 * pitch, 0.0, 0.0))
                    * DMat4::from_rotation_y(rng.below(4) as f64 * std::f64::consts::FRAC_PI_2);
                let object = scene.nodes.len() as u32;
                scene.nodes.push(Node {
                    local,
                    mesh: Some(MeshRef::new(geometry as u32, part_materials)),
                    ..Node::new(format!("object {placed}"))
                });
                scene.nodes[row as usize].children.push(object);
                placed += 1;
            }
        }
    }
    scene
}

pub(super) fn hue_to_rgb(hue: f32) -> [f32; 4] {
    let channel = |offset: f32| {
        let t = (hue + offset).fract() * 6.0;
        let value = (t - 3.0).abs() - 1.0;
        0.25 + 0.6 * value.clamp(0.0, 1.0)
    };
    [channel(0.0), channel(2.0 / 3.0), channel(1.0 / 3.0), 1.0]
}
