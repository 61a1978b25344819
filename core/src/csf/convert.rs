//! Converting between CSF files and cadr scenes.
//!
//! CSF → scene keeps geometry sharing, the node tree, per-part materials, hidden parts and
//! per-part sub-transforms, and the wire indices (for the edges shade mode); it drops texture
//! coordinates, aux and per-part channels (the file keeps them). Scene → CSF unfolds shared
//! subgraphs into a tree (CSF nodes are unique), stores node and geometry names as metas, and
//! materials as their colour plus the glTF 2 material packet (metallic, roughness).

use std::borrow::Cow;

use glam::{DMat4, DVec3};

use super::read::CsfBytes;
use super::write::CsfGeometries;
use super::{
    error, CsfError, CsfFile, CsfGeometry, CsfGeometryPart, CsfMaterial, CsfMeta, CsfNode,
    CsfNodePart, FLAG_PER_PART_VERTICES, FLAG_STRIPS, FLAG_UNIQUE_NODES, GUID_MATERIAL_GLTF2,
    VERSION,
};
use crate::scene::{
    Geometry, GeometrySink, GeometryStore, KeepInScene, Material, MeshRef, Node, NodeIndex, Part,
    PartOverride, Scene, Vertex,
};

/// Size of `CSFMaterialGLTF2Meta`, the glTF 2 material packet.
const GLTF2_PACKET_SIZE: usize = 940;

/// The scene a CSF file describes; `name` names it.
pub fn scene_from_csf(file: &CsfFile, name: &str) -> Result<Scene, CsfError> {
    check_supported(file)?;
    let mut scene = Scene {
        name: name.to_owned(),
        ..Scene::default()
    };
    for (g, geometry) in file.geometries.iter().enumerate() {
        add_csf_geometry(&mut scene, file, g, geometry, &mut KeepInScene)?;
    }
    add_csf_nodes(&mut scene, file)?;
    Ok(scene)
}

/// The scene of a CSF file's (decompressed) bytes, in memory or read from the file where each
/// array lies, read and converted one geometry at a time: each is validated and handed to
/// `sink` (see [`GeometrySink`]) as soon as it is read, so that its CSF arrays and the
/// converted geometry are the only ones held beyond the sink's (and, from a file, the file is
/// never held whole).
pub fn scene_from_csf_source(
    bytes: CsfBytes<'_>,
    name: &str,
    sink: &mut dyn GeometrySink,
) -> Result<Scene, CsfError> {
    let mut scene = Scene {
        name: name.to_owned(),
        ..Scene::default()
    };
    let file = super::read::read_csf_from(bytes, &mut |file, g, geometry| {
        check_supported(file)?;
        add_csf_geometry(&mut scene, file, g, &geometry, sink)
    })?;
    check_supported(&file)?;
    add_csf_nodes(&mut scene, &file)?;
    Ok(scene)
}

/// Refuses what cadr does not read: triangle strips.
fn check_supported(file: &CsfFile) -> Result<(), CsfError> {
    if file.file_flags & FLAG_STRIPS != 0 {
        return Err(error(
            "header",
            "fileFlags",
            "triangle strips (flag 2) are not supported",
        ));
    }
    Ok(())
}

/// Converts geometry `g` of `file`, validates it and hands it to `sink` as the scene's next.
fn add_csf_geometry(
    scene: &mut Scene,
    file: &CsfFile,
    g: usize,
    geometry: &CsfGeometry,
    sink: &mut dyn GeometrySink,
) -> Result<(), CsfError> {
    let name = meta_name(&file.geometry_metas, g).unwrap_or_else(|| format!("geometry {g}"));
    let converted = geometry_from_csf(geometry, g, name, file.file_flags)?;
    scene
        .add_geometry(sink, converted)
        .map_err(|e| error(format!("geometry {g}"), "content", e.0))?;
    Ok(())
}

/// The scene's materials, nodes and roots from `file`'s.
fn add_csf_nodes(scene: &mut Scene, file: &CsfFile) -> Result<(), CsfError> {
    scene.materials = file.materials.iter().map(material_from_csf).collect();
    for (n, node) in file.nodes.iter().enumerate() {
        let name = meta_name(&file.node_metas, n).unwrap_or_else(|| format!("node {n}"));
        let local = DMat4::from_cols_array(&node.object_tm.map(f64::from));
        if !local.to_cols_array().iter().all(|c| c.is_finite()) {
            return Err(error(
                format!("node {n}"),
                "objectTM",
                "has a non-finite value",
            ));
        }
        let mesh = (node.geometry >= 0).then(|| MeshRef {
            geometry: node.geometry as u32,
            part_materials: node.parts.iter().map(|p| p.material as u32).collect(),
            part_overrides: node
                .parts
                .iter()
                .enumerate()
                .filter(|(_, p)| p.active == 0 || p.node >= 0)
                .map(|(i, p)| PartOverride {
                    part: i as u32,
                    visible: p.active != 0,
                    transform_child: (p.node >= 0).then_some(p.node as NodeIndex),
                })
                .collect(),
        });
        let children: Vec<NodeIndex> = node.children.iter().map(|&c| c as NodeIndex).collect();
        if let Some(p) = node
            .parts
            .iter()
            .position(|p| p.node >= 0 && !children.contains(&(p.node as NodeIndex)))
        {
            return Err(error(
                format!("node {n} part {p}"),
                "nodeIDX",
                format!("{} is not a child of node {n}", node.parts[p].node),
            ));
        }
        scene.nodes.push(Node {
            name,
            local,
            children,
            mesh,
        });
    }
    scene.roots = if file.root >= 0 {
        vec![file.root as NodeIndex]
    } else {
        (0..file.nodes.len() as NodeIndex).collect()
    };
    Ok(())
}

fn meta_name(metas: &[CsfMeta], index: usize) -> Option<String> {
    metas
        .get(index)
        .map(|m| m.name.clone())
        .filter(|n| !n.is_empty())
}

fn geometry_from_csf(
    csf: &CsfGeometry,
    g: usize,
    name: String,
    file_flags: u32,
) -> Result<Geometry, CsfError> {
    let s = format!("geometry {g}");
    let vertex_count = csf.vertex_count();
    let positions: Vec<[f32; 3]> = csf
        .vertices
        .chunks_exact(3)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    if let Some(i) = positions
        .iter()
        .position(|p| !p.iter().all(|c| c.is_finite()))
    {
        return Err(error(
            &s,
            "vertexOFFSET",
            format!("vertex {i} is not finite"),
        ));
    }
    // Indices of parts that own vertex ranges are relative to the range's first vertex.
    let bases: Vec<u32> = if file_flags & FLAG_PER_PART_VERTICES != 0 {
        csf.part_vertex_ranges()
            .map(|r| r.into_iter().map(|(begin, _)| begin).collect())
            .unwrap_or_default()
    } else {
        Vec::new()
    };
    let mut geometry = Geometry {
        name,
        ..Geometry::default()
    };
    let (mut solid, mut wire) = (0_usize, 0_usize);
    for (p, part) in csf.parts.iter().enumerate() {
        let (solid_count, wire_count) =
            (part.num_index_solid as usize, part.num_index_wire as usize);
        if solid_count % 3 != 0 {
            return Err(error(
                format!("{s} part {p}"),
                "numIndexSolid",
                format!("{solid_count} is not a multiple of 3 (triangle lists)"),
            ));
        }
        if wire_count % 2 != 0 {
            return Err(error(
                format!("{s} part {p}"),
                "numIndexWire",
                format!("{wire_count} is not a multiple of 2 (line lists)"),
            ));
        }
        let base = bases.get(p).copied().unwrap_or(0);
        geometry.parts.push(Part {
            first_index: geometry.indices.len() as u32,
            index_count: solid_count as u32,
            first_wire_index: geometry.wire_indices.len() as u32,
            wire_index_count: wire_count as u32,
        });
        geometry.indices.extend(
            csf.index_solid[solid..solid + solid_count]
                .iter()
                .map(|&i| i + base),
        );
        geometry.wire_indices.extend(
            csf.index_wire[wire..wire + wire_count]
                .iter()
                .map(|&i| i + base),
        );
        solid += solid_count;
        wire += wire_count;
    }
    let normals: Vec<[f32; 3]> = if csf.normal_channels > 0 && csf.normals.len() >= 3 * vertex_count
    {
        csf.normals[..3 * vertex_count]
            .chunks_exact(3)
            .map(|n| [n[0], n[1], n[2]])
            .collect()
    } else {
        smooth_normals(&positions, &geometry.indices)
    };
    if let Some(i) = normals
        .iter()
        .position(|n| !n.iter().all(|c| c.is_finite()))
    {
        return Err(error(
            &s,
            "normalOFFSET",
            format!("normal {i} is not finite"),
        ));
    }
    geometry.vertices = positions
        .into_iter()
        .zip(normals)
        .map(|(position, normal)| Vertex { position, normal })
        .collect();
    Ok(geometry)
}

/// Area-weighted vertex normals, for geometries stored without normals.
fn smooth_normals(positions: &[[f32; 3]], indices: &[u32]) -> Vec<[f32; 3]> {
    let mut sums = vec![DVec3::ZERO; positions.len()];
    let point = |i: u32| DVec3::from(positions[i as usize].map(f64::from));
    for triangle in indices.chunks_exact(3) {
        let face = (point(triangle[1]) - point(triangle[0]))
            .cross(point(triangle[2]) - point(triangle[0]));
        for &i in triangle {
            sums[i as usize] += face;
        }
    }
    sums.into_iter()
        .map(|n| n.normalize_or(DVec3::Y).as_vec3().to_array())
        .collect()
}

fn material_from_csf(csf: &CsfMaterial) -> Material {
    let mut material = Material {
        name: csf.name.clone(),
        base_color: csf.color,
        metallic: 0.0,
        roughness: 0.5,
        ..Material::default()
    };
    if let Some(packet) = gltf2_packet(&csf.bytes) {
        let f32_at = |at: usize| {
            f32::from_le_bytes([packet[at], packet[at + 1], packet[at + 2], packet[at + 3]])
        };
        let shading_model = i32::from_le_bytes([packet[20], packet[21], packet[22], packet[23]]);
        material.base_color = std::array::from_fn(|i| f32_at(48 + 4 * i));
        if shading_model == 0 {
            material.metallic = f32_at(64);
            material.roughness = f32_at(68);
        }
    }
    if !material
        .base_color
        .iter()
        .chain([&material.metallic, &material.roughness])
        .all(|c| c.is_finite())
    {
        material.base_color = csf.color.map(|c| if c.is_finite() { c } else { 0.8 });
        material.metallic = 0.0;
        material.roughness = 0.5;
    }
    material
}

/// The glTF 2 material packet in a material payload, if there is a complete one.
fn gltf2_packet(bytes: &[u8]) -> Option<&[u8]> {
    let mut at = 0;
    while bytes.len().saturating_sub(at) >= 20 {
        let word = |i: usize| {
            u32::from_le_bytes([
                bytes[at + i],
                bytes[at + i + 1],
                bytes[at + i + 2],
                bytes[at + i + 3],
            ])
        };
        let guid = [word(0), word(4), word(8), word(12)];
        let size = word(16) as usize;
        if size < 20 || at + size > bytes.len() {
            return None;
        }
        if guid == GUID_MATERIAL_GLTF2 && size >= 72 {
            return Some(&bytes[at..at + size]);
        }
        at += size;
    }
    None
}

fn gltf2_packet_for(material: &Material) -> Vec<u8> {
    let mut packet = vec![0_u8; GLTF2_PACKET_SIZE];
    let mut put = |at: usize, bytes: [u8; 4]| packet[at..at + 4].copy_from_slice(&bytes);
    for (i, word) in GUID_MATERIAL_GLTF2.iter().enumerate() {
        put(4 * i, word.to_le_bytes());
    }
    put(16, (GLTF2_PACKET_SIZE as u32).to_le_bytes());
    put(20, 0_i32.to_le_bytes()); // metallic-roughness
    put(24, 1_i32.to_le_bytes()); // double-sided, as CAD surfaces are
    for (i, c) in material.base_color.iter().enumerate() {
        put(48 + 4 * i, c.to_le_bytes());
    }
    put(64, material.metallic.to_le_bytes());
    put(68, material.roughness.to_le_bytes());
    packet
}

/// A version 6 CSF file for `scene` (validated). Shared subgraphs are unfolded into a tree.
pub fn csf_from_scene(scene: &Scene) -> Result<CsfFile, crate::scene::SceneError> {
    scene.validate()?;
    let mut file = csf_outline_from_scene(scene);
    file.geometries = scene.geometries.iter().map(geometry_to_csf).collect();
    Ok(file)
}

/// What [`csf_from_scene`] makes of `scene`, but for the geometries' arrays: `geometries` is
/// left empty, the geometries' names are kept as metas. The scene may be an outline (its
/// geometries stand-ins, see [`crate::scene::GeometrySink`]), validated as it was loaded: the
/// file's geometries are then converted one at a time as they are written
/// ([`CsfGeometriesOf`]).
pub fn csf_outline_from_scene(scene: &Scene) -> CsfFile {
    let mut file = CsfFile {
        version: VERSION,
        file_flags: FLAG_UNIQUE_NODES,
        root: 0,
        ..CsfFile::default()
    };
    for geometry in &scene.geometries {
        file.geometry_metas.push(CsfMeta {
            name: geometry.name.clone(),
            ..CsfMeta::default()
        });
    }
    file.materials = scene
        .materials
        .iter()
        .map(|m| CsfMaterial {
            name: m.name.clone(),
            color: m.base_color,
            kind: 0,
            bytes: gltf2_packet_for(m),
        })
        .collect();
    // One root: the scene's only root, or a new group above several.
    if let [only] = scene.roots[..] {
        add_tree(scene, only, DMat4::IDENTITY, &mut file);
    } else {
        let root = push_node(&mut file, "scene root", DMat4::IDENTITY, DMat4::IDENTITY);
        for &r in &scene.roots {
            let child = add_tree(scene, r, DMat4::IDENTITY, &mut file);
            file.nodes[root].children.push(child as i32);
        }
    }
    file
}

/// A scene's geometries as a CSF file's, each converted from its store as it is written
/// (see [`csf_outline_from_scene`]).
pub struct CsfGeometriesOf<'a, S: GeometryStore + ?Sized> {
    store: &'a S,
    /// Of the geometries converted so far, those with texture coordinates or vertex colours,
    /// which the CSF geometry does not keep.
    pub attributed: usize,
}

impl<'a, S: GeometryStore + ?Sized> CsfGeometriesOf<'a, S> {
    /// The geometries of `store`, none converted yet.
    pub fn new(store: &'a S) -> Self {
        Self {
            store,
            attributed: 0,
        }
    }
}

impl<S: GeometryStore + ?Sized> CsfGeometries for CsfGeometriesOf<'_, S> {
    type Error = String;

    fn count(&self) -> usize {
        self.store.geometry_count()
    }

    fn geometry(&mut self, index: usize) -> Result<Cow<'_, CsfGeometry>, String> {
        let geometry = self.store.geometry(index)?;
        self.attributed += usize::from(!geometry.attributes.is_empty());
        Ok(Cow::Owned(geometry_to_csf(&geometry)))
    }
}

fn push_node(file: &mut CsfFile, name: &str, local: DMat4, world: DMat4) -> usize {
    file.nodes.push(CsfNode {
        object_tm: local.as_mat4().to_cols_array(),
        world_tm: world.as_mat4().to_cols_array(),
        geometry: -1,
        ..CsfNode::default()
    });
    file.node_metas.push(CsfMeta {
        name: name.to_owned(),
        ..CsfMeta::default()
    });
    file.nodes.len() - 1
}

/// Adds the subtree of `node` (depth-first, parents before children) and returns its index.
fn add_tree(scene: &Scene, node: NodeIndex, parent_world: DMat4, file: &mut CsfFile) -> usize {
    let source = &scene.nodes[node as usize];
    let world = parent_world * source.local;
    let index = push_node(file, &source.name, source.local, world);
    let mut child_indices = Vec::with_capacity(source.children.len());
    for &child in &source.children {
        child_indices.push((child, add_tree(scene, child, world, file)));
    }
    let csf_node = &mut file.nodes[index];
    csf_node.children = child_indices.iter().map(|&(_, c)| c as i32).collect();
    if let Some(mesh) = &source.mesh {
        csf_node.geometry = mesh.geometry as i32;
        csf_node.parts = mesh
            .part_materials
            .iter()
            .enumerate()
            .map(|(p, &material)| {
                let part_override = mesh.part_override(p as u32);
                let node = part_override
                    .and_then(|o| o.transform_child)
                    .and_then(|c| {
                        child_indices
                            .iter()
                            .find(|&&(scene_child, _)| scene_child == c)
                    })
                    .map_or(-1, |&(_, csf_child)| csf_child as i32);
                CsfNodePart {
                    active: i32::from(part_override.is_none_or(|o| o.visible)),
                    material: material as i32,
                    node,
                }
            })
            .collect();
    }
    index
}

fn geometry_to_csf(geometry: &Geometry) -> CsfGeometry {
    let mut csf = CsfGeometry {
        vertices: geometry.vertices.iter().flat_map(|v| v.position).collect(),
        normals: geometry.vertices.iter().flat_map(|v| v.normal).collect(),
        normal_channels: 1,
        ..CsfGeometry::default()
    };
    // CSF parts are consecutive ranges: write each part's indices in part order.
    for part in &geometry.parts {
        let solid = &geometry.indices
            [part.first_index as usize..(part.first_index + part.index_count) as usize];
        let wire = &geometry.wire_indices[part.first_wire_index as usize
            ..(part.first_wire_index + part.wire_index_count) as usize];
        csf.index_solid.extend_from_slice(solid);
        csf.index_wire.extend_from_slice(wire);
        csf.parts.push(CsfGeometryPart {
            deprecated: 0,
            num_index_solid: part.index_count as i32,
            num_index_wire: part.wire_index_count as i32,
        });
    }
    csf
}
