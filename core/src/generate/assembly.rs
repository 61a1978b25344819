//! Laying out an assembly: modules on a floor grid, rows inside modules, objects in rows, each
//! object an instance of a shared component with per-part materials in runs (so that grouping
//! parts by material merges them the way the seeds' "material groups" do).

use glam::{DMat4, DVec3};

use super::component::component;
use super::rng::Rng;
use super::shapes::GeometryBuilder;
use crate::scene::{Geometry, Material, MeshRef, Node, Scene};

/// What an assembly generator produces.
#[derive(Clone, Debug, PartialEq)]
pub struct AssemblySpec {
    /// Scene name.
    pub name: String,
    /// Objects (nodes with a geometry).
    pub objects: usize,
    /// Distinct geometries shared by the objects.
    pub geometries: usize,
    /// Materials.
    pub materials: usize,
    /// Average parts per geometry.
    pub parts_per_geometry: f64,
    /// Average triangles per part.
    pub triangles_per_part: f64,
    /// Objects per module (a module is a group of rows with its own transform).
    pub objects_per_module: usize,
    /// Random seed.
    pub seed: u64,
}

/// A material palette of CAD colours: steels, aluminium, brass, painted and plastic parts.
fn palette(count: usize, rng: &mut Rng) -> Vec<Material> {
    const BASES: [([f32; 3], f32, f32, &str); 10] = [
        ([0.62, 0.64, 0.67], 0.9, 0.35, "steel"),
        ([0.80, 0.81, 0.83], 0.9, 0.25, "aluminium"),
        ([0.36, 0.37, 0.40], 0.8, 0.5, "dark steel"),
        ([0.78, 0.62, 0.30], 0.9, 0.3, "brass"),
        ([0.70, 0.16, 0.12], 0.0, 0.4, "red paint"),
        ([0.16, 0.32, 0.66], 0.0, 0.4, "blue paint"),
        ([0.20, 0.50, 0.28], 0.0, 0.5, "green plastic"),
        ([0.90, 0.68, 0.12], 0.0, 0.45, "yellow paint"),
        ([0.12, 0.12, 0.13], 0.0, 0.6, "black plastic"),
        ([0.88, 0.44, 0.12], 0.0, 0.45, "orange paint"),
    ];
    (0..count)
        .map(|i| {
            let (color, metallic, roughness, name) = BASES[i % BASES.len()];
            // Later rounds of the palette vary the shade a little.
            let shade = if i < BASES.len() {
                1.0
            } else {
                rng.range(0.8, 1.15) as f32
            };
            Material {
                name: format!("{name} {i}"),
                base_color: [
                    (color[0] * shade).min(1.0),
                    (color[1] * shade).min(1.0),
                    (color[2] * shade).min(1.0),
                    1.0,
                ],
                metallic,
                roughness,
                ..Material::default()
            }
        })
        .collect()
}

/// The assembly's geometries: geometry 0 is the machine bed every module stands on, the others
/// are components whose part counts vary between half and one and a half times the average.
fn geometries(spec: &AssemblySpec, rng: &mut Rng) -> Vec<Geometry> {
    let mut bed = GeometryBuilder::new("machine bed");
    bed.cuboid(
        DVec3::new(0.0, -0.12, 0.0),
        DVec3::new(1.0, 0.0, 1.0),
        DMat4::IDENTITY,
    );
    let mut geometries = vec![bed.finish()];
    let geometry_count = spec.geometries.clamp(2, spec.objects.max(1) + 1);
    for g in 1..geometry_count {
        let parts = (spec.parts_per_geometry * rng.range(0.5, 1.5))
            .round()
            .max(1.0) as usize;
        geometries.push(component(
            format!("component {g}"),
            parts,
            spec.triangles_per_part,
            rng,
        ));
    }
    geometries
}

/// Generates the assembly.
pub fn assembly(spec: &AssemblySpec) -> Scene {
    let mut rng = Rng::new(spec.seed);
    let mut scene = Scene {
        name: spec.name.clone(),
        ..Scene::default()
    };
    scene.materials = palette(spec.materials.max(1), &mut rng);
    scene.geometries = geometries(spec, &mut rng);
    let geometry_count = scene.geometries.len();

    let root = push_node(&mut scene, Node::new(spec.name.clone()));
    scene.roots.push(root);
    let per_module = spec.objects_per_module.max(1);
    let modules = spec.objects.div_ceil(per_module);
    let modules_per_side = (modules as f64).sqrt().ceil().max(1.0) as usize;
    let per_row = (per_module as f64).sqrt().ceil().max(1.0) as usize;
    let pitch = 1.5;
    let module_size = per_row as f64 * pitch + 1.5;
    let mut placed = 0;
    let mut placed_parts = 0;
    for m in 0..modules {
        let (mx, mz) = (m % modules_per_side, m / modules_per_side);
        let quarter_turns = rng.below(4) as f64;
        let center = module_size * 0.5;
        let local = DMat4::from_translation(DVec3::new(
            mx as f64 * module_size,
            0.0,
            mz as f64 * module_size,
        )) * DMat4::from_translation(DVec3::new(center, 0.0, center))
            * DMat4::from_rotation_y(quarter_turns * std::f64::consts::FRAC_PI_2)
            * DMat4::from_translation(DVec3::new(-center, 0.0, -center));
        let module = push_node(
            &mut scene,
            Node {
                local,
                ..Node::new(format!("module {m}"))
            },
        );
        scene.nodes[root as usize].children.push(module);
        let bed_material = rng.below(3) as u32 % scene.materials.len() as u32;
        let bed = push_node(
            &mut scene,
            Node {
                local: DMat4::from_translation(DVec3::new(0.15, 0.0, 0.15))
                    * DMat4::from_scale(DVec3::new(module_size - 0.3, 1.0, module_size - 0.3)),
                mesh: Some(MeshRef::new(0, vec![bed_material])),
                ..Node::new(format!("module {m} bed"))
            },
        );
        scene.nodes[module as usize].children.push(bed);
        // Each module uses a handful of components and two or three materials per object.
        let theme: Vec<usize> = (0..6).map(|_| 1 + rng.below(geometry_count - 1)).collect();
        let in_module = per_module.min(spec.objects - placed);
        for r in 0..in_module.div_ceil(per_row) {
            let row_local = DMat4::from_translation(DVec3::new(0.75, 0.0, 0.75 + r as f64 * pitch));
            let row = push_node(
                &mut scene,
                Node {
                    local: row_local,
                    ..Node::new(format!("module {m} row {r}"))
                },
            );
            scene.nodes[module as usize].children.push(row);
            for c in 0..per_row.min(in_module - r * per_row) {
                // Of two candidates from the theme, take the one that keeps the running part
                // count closest to the target, so totals match the requested statistics.
                let target = (placed + 1) as f64 * spec.parts_per_geometry;
                let geometry = [theme[rng.below(theme.len())], theme[rng.below(theme.len())]]
                    .into_iter()
                    .min_by_key(|&g| {
                        let total = (placed_parts + scene.geometries[g].parts.len()) as f64;
                        ((total - target).abs() * 1000.0) as u64
                    })
                    .unwrap_or(theme[0]);
                placed_parts += scene.geometries[geometry].parts.len();
                let scale = rng.range(0.75, 1.25);
                let lift = if rng.unit() < 0.15 {
                    rng.range(0.3, 0.8)
                } else {
                    0.0
                };
                // As in CAD files: a placement node per object, its shape node beneath.
                let placement = push_node(
                    &mut scene,
                    Node {
                        local: DMat4::from_translation(DVec3::new(c as f64 * pitch, lift, 0.0)),
                        ..Node::new(format!("object {placed}"))
                    },
                );
                scene.nodes[row as usize].children.push(placement);
                let part_materials = material_runs(
                    scene.geometries[geometry].parts.len(),
                    scene.materials.len(),
                    &mut rng,
                );
                let shape = push_node(
                    &mut scene,
                    Node {
                        local: DMat4::from_rotation_y(
                            rng.below(4) as f64 * std::f64::consts::FRAC_PI_2,
                        ) * DMat4::from_scale(DVec3::splat(scale)),
                        mesh: Some(MeshRef::new(geometry as u32, part_materials)),
                        ..Node::new(format!("object {placed} shape"))
                    },
                );
                scene.nodes[placement as usize].children.push(shape);
                placed += 1;
            }
        }
    }
    scene
}

/// Materials for `parts` parts: the first part (the body) has its own, the features follow in
/// runs of about eight parts that alternate between two materials (which gives the seeds'
/// proportion of material-group ranges to parts on the Graphicscard statistics).
fn material_runs(parts: usize, materials: usize, rng: &mut Rng) -> Vec<u32> {
    let choices: Vec<u32> = (0..3).map(|_| rng.below(materials) as u32).collect();
    let mut out = Vec::with_capacity(parts);
    let mut run = 0;
    let mut current = 0;
    for p in 0..parts {
        if p == 0 {
            out.push(choices[0]);
            continue;
        }
        if run == 0 {
            current = 1 + (current % 2);
            run = 6 + rng.below(5);
        }
        out.push(choices[current]);
        run -= 1;
    }
    out
}

fn push_node(scene: &mut Scene, node: Node) -> u32 {
    scene.nodes.push(node);
    scene.nodes.len() as u32 - 1
}
