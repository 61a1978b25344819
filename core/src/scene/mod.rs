//! The scene model: geometries with parts, materials, and a node hierarchy in which a node may
//! be shared by several parents (a DAG). [`flatten`] turns it into one draw item per path to a
//! drawable part.

mod bounds;
pub mod closure;
pub mod edges;
mod flatten;
pub mod graph;
mod sink;
mod stats;
mod texture;
pub mod weld;

pub use bounds::Aabb;
pub use flatten::{flatten, flatten_outline, DrawItem, FlatScene, Instance};
pub use sink::{GeometrySink, GeometryStore, GeometrySummary, KeepInScene};
pub use stats::SceneStats;
pub use texture::{AlphaMode, Sampler, Texture, TextureRef, UvTransform, Wrap};

use glam::DMat4;

/// One vertex as the GPU reads it: position and normal, 24 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Vertex {
    /// Object-space position.
    pub position: [f32; 3],
    /// Object-space unit normal.
    pub normal: [f32; 3],
}

/// What a vertex carries besides its position and normal, 12 bytes on the GPU: a texture
/// coordinate and a colour. A geometry has them for every vertex or for none.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct VertexAttributes {
    /// Texture coordinate (glTF `TEXCOORD_n`; (0, 0) at the image's top left).
    pub uv: [f32; 2],
    /// Linear RGBA colour multiplying the material's base colour (glTF `COLOR_0`).
    pub color: [u8; 4],
}

impl Default for VertexAttributes {
    /// No coordinate, white: the material's colour unchanged.
    fn default() -> Self {
        Self {
            uv: [0.0, 0.0],
            color: [255; 4],
        }
    }
}

/// A sub-range of a geometry's index buffer drawn with one material (a glTF primitive, a CSF
/// geometry part), and its sub-range of edge (wire) indices.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Part {
    /// First index in the geometry's triangle index buffer.
    pub first_index: u32,
    /// Number of indices (a multiple of 3: triangle lists).
    pub index_count: u32,
    /// First index in the geometry's wire index buffer.
    pub first_wire_index: u32,
    /// Number of wire indices (a multiple of 2: line lists); 0 when the part has no edges.
    pub wire_index_count: u32,
}

impl Part {
    /// Number of triangles.
    pub fn triangle_count(&self) -> u32 {
        self.index_count / 3
    }
}

/// Vertices, 32-bit triangle-list indices and the parts they are split into.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Geometry {
    /// Name from the file or generator.
    pub name: String,
    /// Vertex data.
    pub vertices: Vec<Vertex>,
    /// Triangle-list indices into `vertices`.
    pub indices: Vec<u32>,
    /// Line-list indices into `vertices`: the edges a CAD file stores for the "solid with
    /// edges" shade mode (CSF wire indices). Empty when the source has none.
    pub wire_indices: Vec<u32>,
    /// Index ranges, each drawn with its own material.
    pub parts: Vec<Part>,
    /// Texture coordinates and colours: one per vertex, or empty (every vertex white, at
    /// (0, 0)).
    pub attributes: Vec<VertexAttributes>,
}

impl Geometry {
    /// Bounds of the vertices.
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(self.vertices.iter().map(|v| v.position))
    }

    /// Bytes of its arrays in host memory (vertices, indices, wire indices, parts,
    /// attributes).
    pub fn host_bytes(&self) -> u64 {
        (std::mem::size_of_val(&self.vertices[..])
            + std::mem::size_of_val(&self.indices[..])
            + std::mem::size_of_val(&self.wire_indices[..])
            + std::mem::size_of_val(&self.parts[..])
            + std::mem::size_of_val(&self.attributes[..])) as u64
    }

    /// Number of triangles over all parts.
    pub fn triangle_count(&self) -> u64 {
        self.parts
            .iter()
            .map(|p| u64::from(p.triangle_count()))
            .sum()
    }
}

/// Surface parameters of a material (metallic-roughness, as glTF; Blinn-Phong hosts map onto it).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name from the file or generator.
    pub name: String,
    /// Linear RGBA base color.
    pub base_color: [f32; 4],
    /// 0 = dielectric, 1 = metal.
    pub metallic: f32,
    /// 0 = mirror, 1 = fully rough.
    pub roughness: f32,
    /// The base colour's texture, multiplying `base_color` (and the vertex colours).
    pub base_color_texture: Option<TextureRef>,
    /// How texture and vertex alpha are used.
    pub alpha_mode: AlphaMode,
}

impl Material {
    /// Whether parts drawn with it are translucent: in the BLEND mode, an opacity under 1 or a
    /// texture with translucent texels (`texture_is_translucent` says whether the texture it
    /// names has any).
    pub fn is_translucent(&self, texture_is_translucent: impl Fn(u32) -> bool) -> bool {
        self.is_translucent_without_textures()
            || (self.alpha_mode == AlphaMode::Blend
                && self
                    .base_color_texture
                    .is_some_and(|t| texture_is_translucent(t.texture)))
    }

    /// Whether parts drawn with it are translucent while textures are turned off: in the
    /// BLEND mode, an opacity under 1.
    pub fn is_translucent_without_textures(&self) -> bool {
        self.alpha_mode == AlphaMode::Blend && self.base_color[3] < 1.0
    }
}

impl Default for Material {
    fn default() -> Self {
        Self {
            name: "default".into(),
            base_color: [0.8, 0.8, 0.8, 1.0],
            metallic: 0.0,
            roughness: 0.5,
            base_color_texture: None,
            alpha_mode: AlphaMode::Blend,
        }
    }
}

/// Index of a node in [`Scene::nodes`].
pub type NodeIndex = u32;

/// A geometry drawn by a node, with one material per part.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshRef {
    /// Index in [`Scene::geometries`].
    pub geometry: u32,
    /// Material index for each part of the geometry (same length as its parts).
    pub part_materials: Vec<u32>,
    /// Parts drawn differently from the rest (rare; CSF files have them): hidden parts and
    /// parts placed by a child node's matrix. Empty for most meshes.
    pub part_overrides: Vec<PartOverride>,
}

impl MeshRef {
    /// A mesh of `geometry` with these part materials and no overrides.
    pub fn new(geometry: u32, part_materials: Vec<u32>) -> Self {
        Self {
            geometry,
            part_materials,
            part_overrides: Vec::new(),
        }
    }

    /// The override of `part`, if any.
    pub fn part_override(&self, part: u32) -> Option<&PartOverride> {
        self.part_overrides.iter().find(|o| o.part == part)
    }
}

/// How one part of a [`MeshRef`] differs from the others.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PartOverride {
    /// The part's index in its geometry.
    pub part: u32,
    /// `false` hides the part.
    pub visible: bool,
    /// A child of the owning node whose local matrix places this part (CSF `nodeIDX`).
    pub transform_child: Option<NodeIndex>,
}

/// A node: a local transform (double precision), children, and optionally a mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    /// Name from the file or generator.
    pub name: String,
    /// Transform from this node's space to its parent's.
    pub local: DMat4,
    /// Child node indices (a child may have several parents).
    pub children: Vec<NodeIndex>,
    /// What the node draws, if anything.
    pub mesh: Option<MeshRef>,
}

impl Node {
    /// A node with an identity transform and nothing attached.
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            local: DMat4::IDENTITY,
            children: Vec::new(),
            mesh: None,
        }
    }
}

/// A whole scene.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scene {
    /// Name (file name or generator).
    pub name: String,
    /// Shared geometries.
    pub geometries: Vec<Geometry>,
    /// Materials.
    pub materials: Vec<Material>,
    /// Textures the materials name.
    pub textures: Vec<Texture>,
    /// All nodes.
    pub nodes: Vec<Node>,
    /// The nodes drawn at the top level.
    pub roots: Vec<NodeIndex>,
}

/// A scene that breaks the model's rules; the message names the item and field.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("invalid scene: {0}")]
pub struct SceneError(pub String);

impl Geometry {
    /// Checks that indices refer to vertices, parts lie within the index buffers (whole
    /// triangles and lines), and values are finite; `g` numbers the geometry in messages.
    pub fn validate(&self, g: usize) -> Result<(), SceneError> {
        let geometry = self;
        let fail = |text: String| Err(SceneError(text));
        let vertex_count = geometry.vertices.len();
        if let Some((i, v)) = geometry
            .vertices
            .iter()
            .enumerate()
            .find(|(_, v)| !v.position.iter().chain(&v.normal).all(|c| c.is_finite()))
        {
            return fail(format!(
                "geometry {g} ('{}') vertex {i} is not finite: {v:?}",
                geometry.name
            ));
        }
        if !geometry.attributes.is_empty() && geometry.attributes.len() != vertex_count {
            return fail(format!(
                "geometry {g} ('{}') has {} vertex attributes for {vertex_count} vertices (one per vertex, or none)",
                geometry.name,
                geometry.attributes.len()
            ));
        }
        if let Some((i, a)) = geometry
            .attributes
            .iter()
            .enumerate()
            .find(|(_, a)| !a.uv.iter().all(|c| c.is_finite()))
        {
            return fail(format!(
                "geometry {g} ('{}') texture coordinate {i} is not finite: {:?}",
                geometry.name, a.uv
            ));
        }
        if let Some((i, index)) = geometry
            .indices
            .iter()
            .enumerate()
            .find(|(_, &x)| x as usize >= vertex_count)
        {
            return fail(format!(
                "geometry {g} ('{}') index {i} is {index}, but there are {vertex_count} vertices",
                geometry.name
            ));
        }
        if let Some((i, index)) = geometry
            .wire_indices
            .iter()
            .enumerate()
            .find(|(_, &x)| x as usize >= vertex_count)
        {
            return fail(format!(
                "geometry {g} ('{}') wire index {i} is {index}, but there are {vertex_count} vertices",
                geometry.name
            ));
        }
        for (p, part) in geometry.parts.iter().enumerate() {
            let end = u64::from(part.first_index) + u64::from(part.index_count);
            if end > geometry.indices.len() as u64 || part.index_count % 3 != 0 {
                return fail(format!(
                    "geometry {g} ('{}') part {p} covers indices {}..{end} (a multiple of 3 within {} indices is required)",
                    geometry.name,
                    part.first_index,
                    geometry.indices.len()
                ));
            }
            let wire_end = u64::from(part.first_wire_index) + u64::from(part.wire_index_count);
            if wire_end > geometry.wire_indices.len() as u64 || part.wire_index_count % 2 != 0 {
                return fail(format!(
                    "geometry {g} ('{}') part {p} covers wire indices {}..{wire_end} (a multiple of 2 within {} wire indices is required)",
                    geometry.name,
                    part.first_wire_index,
                    geometry.wire_indices.len()
                ));
            }
        }
        Ok(())
    }
}

impl Scene {
    /// Checks every reference and range: indices within vertices, parts within indices, node,
    /// geometry and material references in range, finite values, no cycles in the node graph,
    /// and an expansion (paths × parts) within `MAX_DRAW_ITEMS` and the memory budget.
    /// Everything downstream (flattening, rendering) relies on a validated scene.
    pub fn validate(&self) -> Result<(), SceneError> {
        self.validate_references()?;
        flatten::check_expansion(self).map(|_| ())
    }

    /// [`Scene::validate`] without the expansion check.
    pub(super) fn validate_references(&self) -> Result<(), SceneError> {
        for (g, geometry) in self.geometries.iter().enumerate() {
            geometry.validate(g)?;
        }
        self.validate_outline_references()
    }

    /// [`Scene::validate`] for a scene whose geometries were validated as they were made
    /// ([`Scene::add_geometry`]), so that it may hold stand-ins: everything but the
    /// geometries' arrays.
    pub fn validate_outline(&self) -> Result<(), SceneError> {
        self.validate_outline_references()?;
        flatten::check_expansion(self).map(|_| ())
    }

    /// [`Scene::validate_references`] without the geometries' arrays.
    pub(crate) fn validate_outline_references(&self) -> Result<(), SceneError> {
        let fail = |text: String| Err(SceneError(text));
        for (m, material) in self.materials.iter().enumerate() {
            let values = material
                .base_color
                .iter()
                .chain([&material.metallic, &material.roughness]);
            if !values.into_iter().all(|c| c.is_finite()) {
                return fail(format!(
                    "material {m} ('{}') has a non-finite value",
                    material.name
                ));
            }
            material.validate_texture(m, self.textures.len())?;
        }
        for (t, texture) in self.textures.iter().enumerate() {
            texture.validate(t)?;
        }
        for (n, node) in self.nodes.iter().enumerate() {
            if !node.local.to_cols_array().iter().all(|c| c.is_finite()) {
                return fail(format!(
                    "node {n} ('{}') has a non-finite matrix",
                    node.name
                ));
            }
            if let Some(&child) = node
                .children
                .iter()
                .find(|&&c| c as usize >= self.nodes.len())
            {
                return fail(format!(
                    "node {n} ('{}') has child {child}, but there are {} nodes",
                    node.name,
                    self.nodes.len()
                ));
            }
            if let Some(mesh) = &node.mesh {
                let Some(geometry) = self.geometries.get(mesh.geometry as usize) else {
                    return fail(format!(
                        "node {n} ('{}') uses geometry {}, but there are {}",
                        node.name,
                        mesh.geometry,
                        self.geometries.len()
                    ));
                };
                if mesh.part_materials.len() != geometry.parts.len() {
                    return fail(format!(
                        "node {n} ('{}') gives {} part materials for geometry {} with {} parts",
                        node.name,
                        mesh.part_materials.len(),
                        mesh.geometry,
                        geometry.parts.len()
                    ));
                }
                for o in &mesh.part_overrides {
                    if o.part as usize >= geometry.parts.len() {
                        return fail(format!(
                            "node {n} ('{}') overrides part {}, but geometry {} has {} parts",
                            node.name,
                            o.part,
                            mesh.geometry,
                            geometry.parts.len()
                        ));
                    }
                    if let Some(child) = o.transform_child.filter(|c| !node.children.contains(c)) {
                        return fail(format!(
                            "node {n} ('{}') part {} is placed by node {child}, which is not its child",
                            node.name, o.part
                        ));
                    }
                }
                if let Some(&m) = mesh
                    .part_materials
                    .iter()
                    .find(|&&m| m as usize >= self.materials.len())
                {
                    return fail(format!(
                        "node {n} ('{}') uses material {m}, but there are {}",
                        node.name,
                        self.materials.len()
                    ));
                }
            }
        }
        if let Some(&root) = self.roots.iter().find(|&&r| r as usize >= self.nodes.len()) {
            return fail(format!(
                "root {root} is not a node (there are {})",
                self.nodes.len()
            ));
        }
        if let Some(node) = self.find_cycle() {
            return fail(format!(
                "the node graph has a cycle through node {node} ('{}')",
                self.nodes[node as usize].name
            ));
        }
        Ok(())
    }

    /// A node on a cycle of the child graph, if there is one.
    fn find_cycle(&self) -> Option<NodeIndex> {
        graph::first_cycle(self.nodes.len(), |node, i| {
            self.nodes[node].children.get(i).map(|&c| c as usize)
        })
        .map(|(_, child)| child as NodeIndex)
    }
}

impl Material {
    /// Checks its texture reference against `texture_count` textures and its transform and
    /// cutoff for finite values; `m` numbers the material in messages.
    pub fn validate_texture(&self, m: usize, texture_count: usize) -> Result<(), SceneError> {
        if let Some(texture) = &self.base_color_texture {
            if texture.texture as usize >= texture_count {
                return Err(SceneError(format!(
                    "material {m} ('{}') uses texture {}, but there are {texture_count}",
                    self.name, texture.texture
                )));
            }
            if !texture.transform.is_finite() {
                return Err(SceneError(format!(
                    "material {m} ('{}') has a non-finite texture transform",
                    self.name
                )));
            }
        }
        if let AlphaMode::Mask { cutoff } = self.alpha_mode {
            if !cutoff.is_finite() {
                return Err(SceneError(format!(
                    "material {m} ('{}') has a non-finite alpha cutoff",
                    self.name
                )));
            }
        }
        Ok(())
    }
}
