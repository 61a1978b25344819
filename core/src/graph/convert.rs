//! Between the scene graph and the flat [`Scene`] model of loaders and savers.

use std::collections::HashMap;

use glam::DMat4;

use super::paging::StoredGeometry;
use super::{
    GeometryHandle, GraphError, MaterialHandle, NodeHandle, NodeKind, SceneGraph, TextureHandle,
};
use crate::scene::{MeshRef, Node, PartOverride, Scene};

/// The scene the graph shows: hidden nodes and inactive Switch children are left out, a LOD
/// shows its first (most detailed) child and a Billboard does not turn (both depend on the
/// eye, which a scene does not have).
pub(super) fn graph_to_scene(graph: &SceneGraph) -> Result<Scene, GraphError> {
    let mut scene = Scene {
        name: "scene graph".into(),
        ..Scene::default()
    };
    let mut geometry_index = HashMap::new();
    for (handle, entry) in graph.geometries.iter() {
        geometry_index.insert(handle, scene.geometries.len() as u32);
        scene.geometries.push(entry.stored.load()?.into_owned());
    }
    let mut texture_index = HashMap::new();
    for (handle, entry) in graph.textures.iter() {
        texture_index.insert(handle.index(), scene.textures.len() as u32);
        scene.textures.push(entry.texture.clone());
    }
    let mut material_index = HashMap::new();
    for (handle, entry) in graph.materials.iter() {
        material_index.insert(handle, scene.materials.len() as u32);
        let mut material = entry.material.clone();
        if let Some(texture) = &mut material.base_color_texture {
            texture.texture = texture_index[&texture.texture];
        }
        scene.materials.push(material);
    }
    let mut node_index: HashMap<NodeHandle, u32> = HashMap::new();
    for (handle, _) in graph.nodes.iter() {
        node_index.insert(handle, node_index.len() as u32);
    }
    for (_, node) in graph.nodes.iter() {
        let shown = |link: &&super::ChildLink| {
            link.active && graph.nodes.get(link.node).is_some_and(|c| c.flags.visible)
        };
        let mut children: Vec<u32> = node
            .children
            .iter()
            .filter(shown)
            .map(|l| node_index[&l.node])
            .collect();
        if matches!(node.kind, NodeKind::Lod { .. }) {
            children.truncate(1);
        }
        let mesh = match &node.kind {
            NodeKind::Geo {
                geometry,
                part_materials,
                part_visible,
            } => Some(MeshRef {
                geometry: geometry_index[geometry],
                part_materials: part_materials.iter().map(|m| material_index[m]).collect(),
                part_overrides: part_visible
                    .iter()
                    .enumerate()
                    .filter(|(_, &shown)| !shown)
                    .map(|(part, _)| PartOverride {
                        part: part as u32,
                        visible: false,
                        transform_child: None,
                    })
                    .collect(),
            }),
            _ => None,
        };
        scene.nodes.push(Node {
            name: node.name.clone(),
            local: node.local_matrix(),
            children,
            mesh,
        });
    }
    if graph.node(graph.root).is_ok_and(|r| r.flags.visible) {
        scene.roots.push(node_index[&graph.root]);
    }
    Ok(scene)
}

/// What [`SceneGraph::import`] created: the Group holding the scene's roots, and every node,
/// geometry, material and texture made for it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Imported {
    /// The new Group (named after the scene) that holds the scene's roots.
    pub root: NodeHandle,
    /// Every node created, the root first.
    pub nodes: Vec<NodeHandle>,
    /// One geometry per scene geometry, in the scene's order.
    pub geometries: Vec<GeometryHandle>,
    /// One material per scene material, in the scene's order.
    pub materials: Vec<MaterialHandle>,
    /// One texture per scene texture, in the scene's order.
    pub textures: Vec<TextureHandle>,
}

/// A graph equivalent to `scene`: see [`import_scene`]; the scene's roots hang directly under
/// the graph's root. Returns the handle of each scene node. The new graph has no pending events.
pub(super) fn scene_to_graph(scene: &Scene) -> Result<(SceneGraph, Vec<NodeHandle>), GraphError> {
    scene.validate().map_err(|e| GraphError::Invalid(e.0))?;
    let mut graph = SceneGraph::new();
    let root = graph.root;
    let geometries = create_geometries(&mut graph, scene)?;
    let (handles, _) = add_scene(&mut graph, scene, geometries, root)?;
    graph.events.clear();
    Ok((graph, handles))
}

/// Adds `scene` under a new Group (named after the scene) below `parent`: each scene node
/// becomes a Transform (a Group when its matrix is the identity) with, for a mesh, a Geo node as
/// its first child (hidden parts hidden; a part placed by a child's matrix gets a Transform and
/// Geo node of its own). The scene is validated first, so a refused import changes nothing.
pub(super) fn import_scene(
    graph: &mut SceneGraph,
    scene: &Scene,
    parent: NodeHandle,
) -> Result<Imported, GraphError> {
    scene.validate().map_err(|e| GraphError::Invalid(e.0))?;
    graph.node(parent)?;
    let geometries = create_geometries(graph, scene)?;
    add_scene_under_group(graph, scene, geometries, parent)
}

/// [`import_scene`] for the outline a loader made through the graph's
/// [`super::intake::GeometryIntake`]: `taken` are its geometries, which the graph now owns (the
/// outline's are stand-ins). The outline and `parent` are checked first.
pub(super) fn import_outline(
    graph: &mut SceneGraph,
    outline: &Scene,
    taken: Vec<StoredGeometry>,
    parent: NodeHandle,
) -> Result<Imported, GraphError> {
    let geometries = taken
        .into_iter()
        .map(|stored| graph.adopt_geometry(stored))
        .collect();
    add_scene_under_group(graph, outline, geometries, parent)
}

/// A copy of each of the scene's geometries in the graph.
fn create_geometries(
    graph: &mut SceneGraph,
    scene: &Scene,
) -> Result<Vec<GeometryHandle>, GraphError> {
    (scene.geometries.iter())
        .map(|g| graph.create_geometry(g.clone()))
        .collect()
}

/// Adds the scene (its geometries already in the graph as `geometries`) below `parent` under a
/// new Group named after it.
fn add_scene_under_group(
    graph: &mut SceneGraph,
    scene: &Scene,
    geometries: Vec<GeometryHandle>,
    parent: NodeHandle,
) -> Result<Imported, GraphError> {
    let root = graph.create_group(&scene.name);
    let (_, created) = add_scene(graph, scene, geometries, root)?;
    graph.add_child(parent, root)?;
    Ok(Imported {
        root,
        nodes: std::iter::once(root).chain(created.nodes).collect(),
        geometries: created.geometries,
        materials: created.materials,
        textures: created.textures,
    })
}

/// Creates the scene's objects (its geometries are in the graph already: `geometries`) and
/// hangs its roots under `parent`; returns the handle of each scene node and everything
/// created.
fn add_scene(
    graph: &mut SceneGraph,
    scene: &Scene,
    geometries: Vec<GeometryHandle>,
    parent: NodeHandle,
) -> Result<(Vec<NodeHandle>, Imported), GraphError> {
    let mut created = Imported {
        root: parent,
        nodes: Vec::new(),
        geometries: Vec::new(),
        materials: Vec::new(),
        textures: Vec::new(),
    };
    let textures = scene
        .textures
        .iter()
        .map(|t| graph.create_texture(t.clone()))
        .collect::<Result<Vec<_>, _>>()?;
    let materials = scene
        .materials
        .iter()
        .map(|m| {
            let mut material = m.clone();
            if let Some(texture) = &mut material.base_color_texture {
                let handle = textures.get(texture.texture as usize).ok_or_else(|| {
                    GraphError::Invalid(format!(
                        "material '{}' uses texture {}, but the scene has {}",
                        m.name,
                        texture.texture,
                        textures.len()
                    ))
                })?;
                texture.texture = handle.index();
            }
            graph.create_material(material)
        })
        .collect::<Result<Vec<_>, _>>()?;
    created.geometries.clone_from(&geometries);
    created.materials.clone_from(&materials);
    created.textures.clone_from(&textures);
    let mut handles = Vec::with_capacity(scene.nodes.len());
    for node in &scene.nodes {
        let handle = if node.local == DMat4::IDENTITY {
            graph.create_group(&node.name)
        } else {
            graph.create_transform(&node.name, node.local)?
        };
        created.nodes.push(handle);
        if let Some(mesh) = &node.mesh {
            let part_materials: Vec<_> = mesh
                .part_materials
                .iter()
                .map(|&m| materials[m as usize])
                .collect();
            let geometry = geometries[mesh.geometry as usize];
            let geo = graph.create_geo(
                &format!("{} geometry", node.name),
                geometry,
                &part_materials,
            )?;
            created.nodes.push(geo);
            graph.add_child(handle, geo)?;
            for o in &mesh.part_overrides {
                // Hidden here: either hidden outright, or drawn below by a node of its own.
                graph.set_part_visible(geo, o.part as usize, false)?;
                let (true, Some(child)) = (o.visible, o.transform_child) else {
                    continue;
                };
                // A part placed by a child's matrix: a Transform with that matrix holding a
                // Geo node that shows only this part.
                let placed = graph.create_transform(
                    &format!("{} part {}", node.name, o.part),
                    scene.nodes[child as usize].local,
                )?;
                let part_geo = graph.create_geo(
                    &format!("{} part {} geometry", node.name, o.part),
                    geometry,
                    &part_materials,
                )?;
                for p in (0..part_materials.len()).filter(|&p| p != o.part as usize) {
                    graph.set_part_visible(part_geo, p, false)?;
                }
                created.nodes.extend([placed, part_geo]);
                graph.add_child(placed, part_geo)?;
                graph.add_child(handle, placed)?;
            }
        }
        handles.push(handle);
    }
    for (node, &handle) in scene.nodes.iter().zip(&handles) {
        for &child in &node.children {
            graph.add_child(handle, handles[child as usize])?;
        }
    }
    for &root in &scene.roots {
        graph.add_child(parent, handles[root as usize])?;
    }
    Ok((handles, created))
}
