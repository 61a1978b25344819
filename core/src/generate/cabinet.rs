//! `gen:cabinet`: machines inside closed housings, cabinets in racks. Seen from outside, the
//! housings hide almost every part: the scene that occlusion culling is for.

use glam::{DMat4, DVec3};

use super::component::component;
use super::grid::hue_to_rgb;
use super::rng::Rng;
use super::shapes::GeometryBuilder;
use crate::scene::{Material, MeshRef, Node, Scene};

/// Machines per cabinet: 3 wide, 4 high, 3 deep.
const MACHINES: [u32; 3] = [3, 4, 3];
/// Parts per machine.
const MACHINE_PARTS: usize = 10;
/// Distance between machine centres.
const PITCH: f64 = 1.6;
/// Different machine geometries.
const MACHINE_KINDS: usize = 12;
/// Cabinets per rack (one row).
const CABINETS_PER_RACK: u32 = 6;
const MATERIALS: usize = 12;

/// The closed housing of a cabinet of `inner` size: six panels (floor, roof, back, sides and
/// the door at +Z), each one part, meeting at the edges so that no gap shows the inside.
fn housing(inner: DVec3, wall: f64) -> crate::scene::Geometry {
    let mut builder = GeometryBuilder::new("cabinet housing");
    let (lo, hi) = (-inner * 0.5, inner * 0.5);
    let w = DVec3::splat(wall);
    let (outer_lo, outer_hi) = (lo - w, hi + w);
    let panels = [
        (outer_lo, DVec3::new(outer_hi.x, lo.y, outer_hi.z)),
        (DVec3::new(outer_lo.x, hi.y, outer_lo.z), outer_hi),
        (
            DVec3::new(outer_lo.x, lo.y, outer_lo.z),
            DVec3::new(lo.x, hi.y, outer_hi.z),
        ),
        (
            DVec3::new(hi.x, lo.y, outer_lo.z),
            DVec3::new(outer_hi.x, hi.y, outer_hi.z),
        ),
        (
            DVec3::new(lo.x, lo.y, outer_lo.z),
            DVec3::new(hi.x, hi.y, lo.z),
        ),
        (
            DVec3::new(lo.x, lo.y, hi.z),
            DVec3::new(hi.x, hi.y, outer_hi.z),
        ),
    ];
    for (min, max) in panels {
        builder.cuboid(min, max, DMat4::IDENTITY);
    }
    builder.finish()
}

/// `cabinets` cabinets, in racks of six along X, racks one behind the other along Z.
pub fn cabinet(cabinets: u32) -> Scene {
    let mut rng = Rng::new(0x6361_6269);
    let mut scene = Scene {
        name: format!("cabinet:cabinets={cabinets}"),
        ..Scene::default()
    };
    scene.materials = (0..MATERIALS)
        .map(|i| Material {
            name: format!("cabinet material {i}"),
            base_color: if i == 0 {
                [0.55, 0.58, 0.62, 1.0]
            } else {
                hue_to_rgb(i as f32 / MATERIALS as f32)
            },
            metallic: if i % 4 == 1 { 0.8 } else { 0.0 },
            roughness: 0.5,
            ..Material::default()
        })
        .collect();
    for kind in 0..MACHINE_KINDS {
        scene.geometries.push(component(
            format!("machine {kind}"),
            MACHINE_PARTS,
            12.0,
            &mut rng,
        ));
    }
    let inner = DVec3::new(
        f64::from(MACHINES[0]),
        f64::from(MACHINES[1]),
        f64::from(MACHINES[2]),
    ) * PITCH;
    let wall = 0.1;
    let housing_geometry = scene.geometries.len() as u32;
    scene.geometries.push(housing(inner, wall));
    let spacing = inner + DVec3::new(0.8, 0.0, 3.0);
    scene.nodes.push(Node::new(scene.name.clone()));
    scene.roots.push(0);
    for index in 0..cabinets {
        let (rack, slot) = (index / CABINETS_PER_RACK, index % CABINETS_PER_RACK);
        if slot == 0 {
            let node = scene.nodes.len() as u32;
            scene.nodes.push(Node {
                local: DMat4::from_translation(DVec3::new(0.0, 0.0, -f64::from(rack) * spacing.z)),
                ..Node::new(format!("rack {rack}"))
            });
            scene.nodes[0].children.push(node);
        }
        let rack_node = scene.nodes[0].children[rack as usize] as usize;
        let cabinet_node = scene.nodes.len() as u32;
        scene.nodes.push(Node {
            local: DMat4::from_translation(DVec3::new(
                f64::from(slot) * spacing.x,
                inner.y * 0.5 + wall,
                0.0,
            )),
            ..Node::new(format!("cabinet {index}"))
        });
        scene.nodes[rack_node].children.push(cabinet_node);
        let housing_node = scene.nodes.len() as u32;
        scene.nodes.push(Node {
            mesh: Some(MeshRef::new(housing_geometry, vec![0; 6])),
            ..Node::new(format!("cabinet {index} housing"))
        });
        scene.nodes[cabinet_node as usize]
            .children
            .push(housing_node);
        for x in 0..MACHINES[0] {
            for y in 0..MACHINES[1] {
                for z in 0..MACHINES[2] {
                    let centre = (DVec3::new(f64::from(x), f64::from(y), f64::from(z)) + 0.5)
                        * PITCH
                        - inner * 0.5;
                    let geometry = rng.below(MACHINE_KINDS);
                    let first_material = 1 + rng.below(MATERIALS - 1);
                    let materials = (0..MACHINE_PARTS)
                        .map(|p| (1 + (first_material + p / 3) % (MATERIALS - 1)) as u32)
                        .collect();
                    let node = scene.nodes.len() as u32;
                    scene.nodes.push(Node {
                        local: DMat4::from_translation(centre)
                            * DMat4::from_scale(DVec3::splat(0.9)),
                        mesh: Some(MeshRef::new(geometry as u32, materials)),
                        ..Node::new(format!("cabinet {index} machine {x}.{y}.{z}"))
                    });
                    scene.nodes[cabinet_node as usize].children.push(node);
                }
            }
        }
    }
    scene
}
