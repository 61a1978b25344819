//! The scene graph: the model a CAD host edits. Nodes of several kinds (group, transform,
//! geometry, switch, LOD, billboard) with flags, shared by any number of parents (a DAG, never
//! a cycle); geometries and materials shared by nodes. Every object is reached through a
//! generation-checked [`Handle`], so a destroyed or foreign handle is an error, never undefined
//! behaviour. Every edit is recorded as a [`GraphEvent`]; the scene tree
//! ([`crate::tree::SceneTree`]) applies them incrementally.
//!
//! Local matrices are `f64`: CAD assemblies span kilometres with micrometre detail.

mod convert;
mod intake;
mod page_file;
mod paging;
mod slots;

pub use convert::Imported;
pub use intake::LoadedGeometries;
pub use page_file::Page;
pub(crate) use page_file::{page_directory, temporary_file, RemovedOnDrop};
pub use paging::{GeometryInfo, GeometryMemory, GeometrySource};
pub use slots::{Handle, Slots};

use std::borrow::Cow;
use std::collections::HashMap;

use glam::DMat4;

use crate::scene::{Aabb, Geometry, Material, Scene, Texture};

/// The most paths (scene tree nodes) one link may add: sharing multiplies paths, and a chain
/// of nodes each linked twice would otherwise expand to billions.
pub const MAX_NEW_PATHS: u64 = 1 << 27;

/// A node of the graph.
pub type NodeHandle = Handle<GraphNode>;

/// A geometry of the graph.
pub type GeometryHandle = Handle<GeometryEntry>;
/// A material of the graph.
pub type MaterialHandle = Handle<MaterialEntry>;
/// A texture of the graph. Materials name it by its slot ([`TextureHandle::index`]) in
/// [`crate::scene::TextureRef::texture`].
pub type TextureHandle = Handle<TextureEntry>;

/// What a node does.
#[derive(Clone, Debug, PartialEq)]
pub enum NodeKind {
    /// Groups its children.
    Group,
    /// Places its children with a local matrix (double precision).
    Transform {
        /// Child space to parent space.
        matrix: DMat4,
    },
    /// Draws a geometry with one material per part.
    Geo {
        /// The geometry.
        geometry: GeometryHandle,
        /// One material per part of the geometry.
        part_materials: Vec<MaterialHandle>,
        /// Whether each part is shown (a CAD host hides single faces or features).
        part_visible: Vec<bool>,
    },
    /// Shows only its active children (see [`SceneGraph::set_switch_mask`]).
    Switch,
    /// Shows one child chosen by its distance from the eye or its size on screen: child `i`
    /// while the measure lies between `thresholds[i - 1]` and `thresholds[i]` (the last child
    /// beyond the last threshold). See [`LodMetric`].
    Lod {
        /// Switch points, one fewer than the children chosen from: increasing distances, or
        /// decreasing angular sizes.
        thresholds: Vec<f64>,
        /// What the thresholds measure.
        metric: LodMetric,
    },
    /// Turns its children about their local origin to face the eye (rotation about +Y).
    Billboard,
}

impl NodeKind {
    fn name(&self) -> &'static str {
        match self {
            Self::Group => "Group",
            Self::Transform { .. } => "Transform",
            Self::Geo { .. } => "Geo",
            Self::Switch => "Switch",
            Self::Lod { .. } => "Lod",
            Self::Billboard => "Billboard",
        }
    }
}

/// What a LOD node measures to choose its child.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LodMetric {
    /// Distance from the eye to the LOD's origin (world units); thresholds increase.
    Distance,
    /// Size on screen: the angle, in radians, that a sphere of `radius` (in the LOD's own
    /// units, scaled with its world matrix) at the LOD's origin subtends at the eye; thresholds
    /// decrease, so the first (most detailed) child shows while the part looks big. Independent
    /// of the image's resolution.
    ScreenSize {
        /// Bounding radius of the LOD's content.
        radius: f64,
    },
}

/// Per-node flags a CAD host needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NodeFlags {
    /// Drawn (with its subtree) when set.
    pub visible: bool,
    /// Can be picked by selection.
    pub pickable: bool,
    /// Drawn highlighted (selection feedback).
    pub highlighted: bool,
}

impl Default for NodeFlags {
    fn default() -> Self {
        Self {
            visible: true,
            pickable: true,
            highlighted: false,
        }
    }
}

/// A link from a parent to a child; `active` is the switch mask bit (always set for other kinds).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ChildLink {
    /// The child.
    pub node: NodeHandle,
    /// Whether a Switch parent shows this child.
    pub active: bool,
}

/// A node: kind, name, flags and children. Its parents are counted for sharing.
#[derive(Clone, Debug)]
pub struct GraphNode {
    /// Name (for hosts and tools).
    pub name: String,
    /// What the node does.
    pub kind: NodeKind,
    /// Flags.
    pub flags: NodeFlags,
    children: Vec<ChildLink>,
    parents: Vec<NodeHandle>,
}

impl GraphNode {
    /// Whether part `part` of a Geo node is shown (always for other kinds).
    pub fn part_shown(&self, part: usize) -> bool {
        match &self.kind {
            NodeKind::Geo { part_visible, .. } => part_visible.get(part).copied().unwrap_or(true),
            _ => true,
        }
    }

    /// The children, in drawing order.
    pub fn children(&self) -> &[ChildLink] {
        &self.children
    }

    /// The parents (a parent appears once per link).
    pub fn parents(&self) -> &[NodeHandle] {
        &self.parents
    }

    /// The local matrix (identity for every kind but Transform).
    pub fn local_matrix(&self) -> DMat4 {
        match self.kind {
            NodeKind::Transform { matrix } => matrix,
            _ => DMat4::IDENTITY,
        }
    }
}

/// A geometry (in memory or in the page file) and the Geo nodes that use it.
#[derive(Clone, Debug)]
pub struct GeometryEntry {
    stored: paging::StoredGeometry,
    users: Vec<NodeHandle>,
}

/// A material and how many Geo node parts use it.
#[derive(Clone, Debug)]
pub struct MaterialEntry {
    /// The parameters.
    pub material: Material,
    users: u32,
}

/// A texture and whether any of its texels is translucent.
#[derive(Clone, Debug)]
pub struct TextureEntry {
    /// The image and its sampling.
    pub texture: Texture,
    /// Whether any texel's alpha is under 1 (a BLEND material using it is translucent).
    pub translucent: bool,
}

/// An edit, as the scene tree consumes it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GraphEvent {
    /// `child` was inserted into `parent`'s children at `position`.
    ChildInserted {
        /// The parent.
        parent: NodeHandle,
        /// Where.
        position: u32,
        /// The child.
        child: NodeHandle,
    },
    /// The child at `position` of `parent` was removed.
    ChildRemoved {
        /// The parent.
        parent: NodeHandle,
        /// Where it was.
        position: u32,
    },
    /// A Transform's matrix changed.
    MatrixChanged(NodeHandle),
    /// A node's flags changed.
    FlagsChanged(NodeHandle),
    /// A Switch's mask or a LOD's distances changed.
    SelectionChanged(NodeHandle),
    /// A Geo node's part material changed.
    PartMaterialChanged {
        /// The Geo node.
        node: NodeHandle,
        /// The part.
        part: u32,
    },
    /// A Geo node's part was shown or hidden.
    PartVisibilityChanged {
        /// The Geo node.
        node: NodeHandle,
        /// The part.
        part: u32,
    },
    /// A geometry's data was replaced.
    GeometryReplaced(GeometryHandle),
    /// A material's parameters changed.
    MaterialChanged(MaterialHandle),
}

/// Why an edit was refused. Nothing is changed by a refused edit.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GraphError {
    /// The node handle is destroyed or from another graph.
    #[error("node handle {index}:{generation} is destroyed or belongs to another graph")]
    StaleNode {
        /// Slot.
        index: u32,
        /// Generation.
        generation: u32,
    },
    /// The geometry handle is destroyed or from another graph.
    #[error("geometry handle {index}:{generation} is destroyed or belongs to another graph")]
    StaleGeometry {
        /// Slot.
        index: u32,
        /// Generation.
        generation: u32,
    },
    /// The material handle is destroyed or from another graph.
    #[error("material handle {index}:{generation} is destroyed or belongs to another graph")]
    StaleMaterial {
        /// Slot.
        index: u32,
        /// Generation.
        generation: u32,
    },
    /// The texture handle is destroyed or from another graph.
    #[error("texture handle {index}:{generation} is destroyed or belongs to another graph")]
    StaleTexture {
        /// Slot.
        index: u32,
        /// Generation.
        generation: u32,
    },
    /// The edit needs another kind of node.
    #[error("node '{name}' is a {actual}; {operation} needs a {expected}")]
    WrongKind {
        /// The node's name.
        name: String,
        /// Its kind.
        actual: &'static str,
        /// The kind the operation needs.
        expected: &'static str,
        /// The operation.
        operation: &'static str,
    },
    /// Adding the child would make the node its own ancestor.
    #[error("adding '{child}' under '{parent}' would create a cycle")]
    Cycle {
        /// The parent's name.
        parent: String,
        /// The child's name.
        child: String,
    },
    /// An index is out of range.
    #[error("{what} {index} is out of range (0..{len})")]
    OutOfRange {
        /// What was indexed.
        what: &'static str,
        /// The index.
        index: usize,
        /// The number of items.
        len: usize,
    },
    /// The object is still used.
    #[error("{what} is still used by {users} node(s)")]
    InUse {
        /// What.
        what: String,
        /// How many users.
        users: u32,
    },
    /// Other invalid input (bad geometry data, the root, wrong counts).
    #[error("{0}")]
    Invalid(String),
    /// A geometry kept in the page file could not be read back (the message names the
    /// geometry and the file).
    #[error("{0}")]
    PageRead(String),
}

/// The scene graph. It has one root Group, created with it.
pub struct SceneGraph {
    nodes: Slots<GraphNode>,
    geometries: Slots<GeometryEntry>,
    materials: Slots<MaterialEntry>,
    textures: Slots<TextureEntry>,
    /// Changes whenever a texture is created or destroyed.
    textures_generation: u64,
    /// Changes whenever a geometry is created or destroyed.
    geometries_generation: u64,
    root: NodeHandle,
    events: Vec<GraphEvent>,
    /// Which geometries stay in memory and which go to the page file.
    paging: paging::Paging,
}

impl Default for SceneGraph {
    fn default() -> Self {
        Self::new()
    }
}

fn stale_node(h: NodeHandle) -> GraphError {
    GraphError::StaleNode {
        index: h.index(),
        generation: h.generation(),
    }
}

fn stale_geometry(h: GeometryHandle) -> GraphError {
    GraphError::StaleGeometry {
        index: h.index(),
        generation: h.generation(),
    }
}

fn stale_texture(h: TextureHandle) -> GraphError {
    GraphError::StaleTexture {
        index: h.index(),
        generation: h.generation(),
    }
}

fn stale_material(h: MaterialHandle) -> GraphError {
    GraphError::StaleMaterial {
        index: h.index(),
        generation: h.generation(),
    }
}

impl SceneGraph {
    /// An empty graph: just the root Group.
    pub fn new() -> Self {
        let mut nodes = Slots::default();
        let root = nodes.insert(GraphNode {
            name: "root".into(),
            kind: NodeKind::Group,
            flags: NodeFlags::default(),
            children: Vec::new(),
            parents: Vec::new(),
        });
        Self {
            nodes,
            geometries: Slots::default(),
            materials: Slots::default(),
            textures: Slots::default(),
            textures_generation: 0,
            geometries_generation: 0,
            root,
            events: Vec::new(),
            paging: paging::Paging::new(),
        }
    }

    /// The root Group.
    pub fn root(&self) -> NodeHandle {
        self.root
    }

    /// The node, or an error for a stale handle.
    pub fn node(&self, node: NodeHandle) -> Result<&GraphNode, GraphError> {
        self.nodes.get(node).ok_or_else(|| stale_node(node))
    }

    /// The node in slot `index` (for the scene tree, which stores slot indices).
    pub fn node_at(&self, index: u32) -> Option<&GraphNode> {
        self.nodes.get_by_index(index)
    }

    /// The current handle of the node in slot `index`.
    pub fn node_handle_at(&self, index: u32) -> Option<NodeHandle> {
        self.nodes.handle_at(index)
    }

    /// The geometry, or an error for a stale handle. A geometry in the page file is read
    /// back (an error where that fails); [`SceneGraph::geometry_info_at`] says what a geometry
    /// is without reading it.
    pub fn geometry(&self, geometry: GeometryHandle) -> Result<Cow<'_, Geometry>, GraphError> {
        self.geometries
            .get(geometry)
            .ok_or_else(|| stale_geometry(geometry))?
            .stored
            .load()
    }

    /// The bounds of a geometry's vertices (known without reading a paged geometry), or an
    /// error for a stale handle.
    pub fn geometry_bounds(&self, geometry: GeometryHandle) -> Result<Aabb, GraphError> {
        (self.geometries.get(geometry))
            .map(|e| e.stored.bounds())
            .ok_or_else(|| stale_geometry(geometry))
    }

    /// The bounds of the vertices of the geometry in slot `index`.
    pub fn geometry_bounds_at(&self, index: u32) -> Option<Aabb> {
        self.geometries
            .get_by_index(index)
            .map(|e| e.stored.bounds())
    }

    /// The Geo nodes that draw `geometry`.
    pub fn geometry_users(&self, geometry: GeometryHandle) -> Result<&[NodeHandle], GraphError> {
        self.geometries
            .get(geometry)
            .map(|e| &e.users[..])
            .ok_or_else(|| stale_geometry(geometry))
    }

    /// The geometry in slot `index` (`None`: the slot is empty), read back where it is in the
    /// page file.
    pub fn geometry_at(&self, index: u32) -> Result<Option<Cow<'_, Geometry>>, GraphError> {
        (self.geometries.get_by_index(index))
            .map(|e| e.stored.load())
            .transpose()
    }

    /// What the geometry in slot `index` is (name, parts, attributes, where it is kept),
    /// without reading it.
    pub fn geometry_info_at(&self, index: u32) -> Option<GeometryInfo<'_>> {
        self.geometries.get_by_index(index).map(|e| e.stored.info())
    }

    /// The geometry in slot `index` as another thread can read it: a copy where it is in
    /// memory, its page where it is in the page file (read there, off this thread).
    pub fn geometry_source_at(&self, index: u32) -> Option<GeometrySource> {
        self.geometries
            .get_by_index(index)
            .map(|e| e.stored.source())
    }

    /// Where the geometries are kept: bytes in memory, bytes in the page file, and the file.
    pub fn geometry_memory(&self) -> GeometryMemory {
        self.paging.memory()
    }

    /// Sets how many bytes of geometry the graph keeps in memory; geometries created or
    /// replaced beyond it go to the page file. The default is half the memory budget
    /// (`CADR_MEMORY_BUDGET`, else the machine's memory). Geometries already made stay where
    /// they are.
    pub fn set_geometry_memory_limit(&mut self, bytes: u64) {
        self.paging.set_limit(bytes);
    }

    /// The material, or an error for a stale handle.
    pub fn material(&self, material: MaterialHandle) -> Result<&Material, GraphError> {
        self.materials
            .get(material)
            .map(|e| &e.material)
            .ok_or_else(|| stale_material(material))
    }

    /// The material in slot `index`.
    pub fn material_at(&self, index: u32) -> Option<&Material> {
        self.materials.get_by_index(index).map(|e| &e.material)
    }

    /// The texture, or an error for a stale handle.
    pub fn texture(&self, texture: TextureHandle) -> Result<&Texture, GraphError> {
        self.textures
            .get(texture)
            .map(|e| &e.texture)
            .ok_or_else(|| stale_texture(texture))
    }

    /// The texture in slot `index`, with whether it has translucent texels.
    pub fn texture_at(&self, index: u32) -> Option<&TextureEntry> {
        self.textures.get_by_index(index)
    }

    /// Bound of texture slot indices.
    pub fn texture_capacity(&self) -> usize {
        self.textures.capacity()
    }

    /// Changes whenever a texture is created or destroyed (the GPU scene rebuilds its textures
    /// then).
    pub fn textures_generation(&self) -> u64 {
        self.textures_generation
    }

    /// Changes whenever a geometry is created or destroyed (the GPU scene places new
    /// geometries and frees the room of destroyed ones then).
    pub fn geometries_generation(&self) -> u64 {
        self.geometries_generation
    }

    /// Whether a material drawn with `material` is translucent (see
    /// [`Material::is_translucent`]).
    pub fn is_translucent(&self, material: &Material) -> bool {
        material.is_translucent(|t| self.texture_at(t).is_some_and(|e| e.translucent))
    }

    /// Bounds of node, geometry and material slot indices.
    pub fn capacities(&self) -> (usize, usize, usize) {
        (
            self.nodes.capacity(),
            self.geometries.capacity(),
            self.materials.capacity(),
        )
    }

    /// Live counts of nodes, geometries and materials.
    pub fn counts(&self) -> (usize, usize, usize) {
        (
            self.nodes.len(),
            self.geometries.len(),
            self.materials.len(),
        )
    }

    /// Hands the events recorded since the last call over in `events` (what it held is
    /// dropped) and keeps `events`' old storage to record the next ones: a reader calling it
    /// every frame with the same vector allocates nothing once both are large enough.
    pub fn take_events(&mut self, events: &mut Vec<GraphEvent>) {
        events.clear();
        std::mem::swap(events, &mut self.events);
    }

    /// Number of events waiting.
    pub fn pending_events(&self) -> usize {
        self.events.len()
    }

    // ---- creation and destruction -------------------------------------------------------

    fn create(&mut self, name: &str, kind: NodeKind) -> NodeHandle {
        self.nodes.insert(GraphNode {
            name: name.to_owned(),
            kind,
            flags: NodeFlags::default(),
            children: Vec::new(),
            parents: Vec::new(),
        })
    }

    /// A new Group (not attached anywhere yet).
    pub fn create_group(&mut self, name: &str) -> NodeHandle {
        self.create(name, NodeKind::Group)
    }

    /// A new Transform with `matrix`; non-finite matrices are refused.
    pub fn create_transform(
        &mut self,
        name: &str,
        matrix: DMat4,
    ) -> Result<NodeHandle, GraphError> {
        check_matrix(name, &matrix)?;
        Ok(self.create(name, NodeKind::Transform { matrix }))
    }

    /// A new Geo node drawing `geometry` with one material per part.
    pub fn create_geo(
        &mut self,
        name: &str,
        geometry: GeometryHandle,
        part_materials: &[MaterialHandle],
    ) -> Result<NodeHandle, GraphError> {
        let parts = (self.geometries.get(geometry))
            .ok_or_else(|| stale_geometry(geometry))?
            .stored
            .info()
            .parts
            .len();
        if part_materials.len() != parts {
            return Err(GraphError::Invalid(format!(
                "Geo node '{name}': {} part materials for a geometry with {parts} parts",
                part_materials.len()
            )));
        }
        for &m in part_materials {
            self.material(m)?;
        }
        for &m in part_materials {
            if let Some(entry) = self.materials.get_mut(m) {
                entry.users += 1;
            }
        }
        let node = self.create(
            name,
            NodeKind::Geo {
                geometry,
                part_materials: part_materials.to_vec(),
                part_visible: vec![true; parts],
            },
        );
        if let Some(entry) = self.geometries.get_mut(geometry) {
            entry.users.push(node);
        }
        Ok(node)
    }

    /// A new Switch (children active until a mask says otherwise).
    pub fn create_switch(&mut self, name: &str) -> NodeHandle {
        self.create(name, NodeKind::Switch)
    }

    /// A new LOD choosing by distance, with increasing, finite, positive switch `distances`.
    pub fn create_lod(&mut self, name: &str, distances: &[f64]) -> Result<NodeHandle, GraphError> {
        check_thresholds(name, distances, LodMetric::Distance)?;
        Ok(self.create(
            name,
            NodeKind::Lod {
                thresholds: distances.to_vec(),
                metric: LodMetric::Distance,
            },
        ))
    }

    /// A new LOD choosing by size on screen: content of bounding `radius`, switching at the
    /// decreasing angular `sizes` (radians, each below pi).
    pub fn create_lod_by_screen_size(
        &mut self,
        name: &str,
        radius: f64,
        sizes: &[f64],
    ) -> Result<NodeHandle, GraphError> {
        let metric = LodMetric::ScreenSize { radius };
        check_thresholds(name, sizes, metric)?;
        Ok(self.create(
            name,
            NodeKind::Lod {
                thresholds: sizes.to_vec(),
                metric,
            },
        ))
    }

    /// A new Billboard.
    pub fn create_billboard(&mut self, name: &str) -> NodeHandle {
        self.create(name, NodeKind::Billboard)
    }

    /// Destroys `node`: it is removed from every parent; its children stay (they may have
    /// other parents, or be attached again). The root cannot be destroyed.
    pub fn destroy_node(&mut self, node: NodeHandle) -> Result<(), GraphError> {
        if node == self.root {
            return Err(GraphError::Invalid("the root cannot be destroyed".into()));
        }
        let parents: Vec<NodeHandle> = self.node(node)?.parents.clone();
        let mut unique_parents = parents;
        unique_parents.sort_by_key(|p| p.index());
        unique_parents.dedup();
        for parent in unique_parents {
            while let Some(position) = self
                .node(parent)?
                .children
                .iter()
                .rposition(|c| c.node == node)
            {
                self.remove_child_at(parent, position)?;
            }
        }
        let removed = self.nodes.remove(node).ok_or_else(|| stale_node(node))?;
        for link in &removed.children {
            if let Some(child) = self.nodes.get_mut(link.node) {
                if let Some(i) = child.parents.iter().position(|&p| p == node) {
                    child.parents.swap_remove(i);
                }
            }
        }
        if let NodeKind::Geo {
            geometry,
            part_materials,
            ..
        } = removed.kind
        {
            if let Some(entry) = self.geometries.get_mut(geometry) {
                if let Some(i) = entry.users.iter().position(|&u| u == node) {
                    entry.users.swap_remove(i);
                }
            }
            for m in part_materials {
                if let Some(entry) = self.materials.get_mut(m) {
                    entry.users -= 1;
                }
            }
        }
        Ok(())
    }

    /// A new geometry; its data is validated (indices, parts, finite values).
    pub fn create_geometry(&mut self, geometry: Geometry) -> Result<GeometryHandle, GraphError> {
        check_geometry(&geometry)?;
        let stored = self.paging.store(geometry);
        Ok(self.adopt_geometry(stored))
    }

    /// Gives the graph a geometry its paging has already stored (by [`SceneGraph::create_geometry`],
    /// or by a load for the graph, see [`intake`]).
    fn adopt_geometry(&mut self, stored: paging::StoredGeometry) -> GeometryHandle {
        self.geometries_generation += 1;
        self.geometries.insert(GeometryEntry {
            stored,
            users: Vec::new(),
        })
    }

    /// Destroys a geometry no Geo node uses.
    pub fn destroy_geometry(&mut self, geometry: GeometryHandle) -> Result<(), GraphError> {
        let entry = self
            .geometries
            .get(geometry)
            .ok_or_else(|| stale_geometry(geometry))?;
        if !entry.users.is_empty() {
            return Err(GraphError::InUse {
                what: format!("geometry '{}'", entry.stored.info().name),
                users: entry.users.len() as u32,
            });
        }
        if let Some(entry) = self.geometries.remove(geometry) {
            self.paging.release(&entry.stored);
        }
        self.geometries_generation += 1;
        Ok(())
    }

    /// Replaces a geometry's data. While Geo nodes use it, the part count must stay the same.
    pub fn replace_geometry(
        &mut self,
        geometry: GeometryHandle,
        data: Geometry,
    ) -> Result<(), GraphError> {
        check_geometry(&data)?;
        let entry = self
            .geometries
            .get_mut(geometry)
            .ok_or_else(|| stale_geometry(geometry))?;
        let info = entry.stored.info();
        if !entry.users.is_empty() && info.parts.len() != data.parts.len() {
            return Err(GraphError::Invalid(format!(
                "geometry '{}' has {} parts and is in use; its replacement has {}",
                info.name,
                info.parts.len(),
                data.parts.len()
            )));
        }
        self.paging.release(&entry.stored);
        entry.stored = self.paging.store(data);
        self.events.push(GraphEvent::GeometryReplaced(geometry));
        Ok(())
    }

    /// A new texture; its texel count must match its size.
    pub fn create_texture(&mut self, texture: Texture) -> Result<TextureHandle, GraphError> {
        texture
            .validate(self.textures.capacity())
            .map_err(|e| GraphError::Invalid(e.0))?;
        let translucent = texture.has_translucent_texels();
        self.textures_generation += 1;
        Ok(self.textures.insert(TextureEntry {
            texture,
            translucent,
        }))
    }

    /// Destroys a texture no material uses.
    pub fn destroy_texture(&mut self, texture: TextureHandle) -> Result<(), GraphError> {
        let entry = self
            .textures
            .get(texture)
            .ok_or_else(|| stale_texture(texture))?;
        let users = self
            .materials
            .iter()
            .filter(|(_, m)| {
                m.material
                    .base_color_texture
                    .is_some_and(|t| t.texture == texture.index())
            })
            .count();
        if users > 0 {
            return Err(GraphError::InUse {
                what: format!("texture '{}' (by materials, not nodes)", entry.texture.name),
                users: users as u32,
            });
        }
        self.textures.remove(texture);
        self.textures_generation += 1;
        Ok(())
    }

    /// Checks a material's values and that the texture it names is alive.
    fn check_material(&self, material: &Material) -> Result<(), GraphError> {
        check_material(material)?;
        if let Some(t) = material.base_color_texture {
            if self.textures.get_by_index(t.texture).is_none() {
                return Err(GraphError::Invalid(format!(
                    "material '{}' uses texture slot {}, which holds no texture",
                    material.name, t.texture
                )));
            }
        }
        Ok(())
    }

    /// A new material; its values must be finite and its texture alive.
    pub fn create_material(&mut self, material: Material) -> Result<MaterialHandle, GraphError> {
        self.check_material(&material)?;
        Ok(self.materials.insert(MaterialEntry { material, users: 0 }))
    }

    /// Changes a material's parameters.
    pub fn set_material(
        &mut self,
        handle: MaterialHandle,
        material: Material,
    ) -> Result<(), GraphError> {
        self.check_material(&material)?;
        let entry = self
            .materials
            .get_mut(handle)
            .ok_or_else(|| stale_material(handle))?;
        entry.material = material;
        self.events.push(GraphEvent::MaterialChanged(handle));
        Ok(())
    }

    /// Destroys a material no part uses.
    pub fn destroy_material(&mut self, material: MaterialHandle) -> Result<(), GraphError> {
        let entry = self
            .materials
            .get(material)
            .ok_or_else(|| stale_material(material))?;
        if entry.users > 0 {
            return Err(GraphError::InUse {
                what: format!("material '{}'", entry.material.name),
                users: entry.users,
            });
        }
        self.materials.remove(material);
        Ok(())
    }

    // ---- structure ------------------------------------------------------------------------

    /// Appends `child` to `parent`'s children.
    pub fn add_child(&mut self, parent: NodeHandle, child: NodeHandle) -> Result<(), GraphError> {
        let position = self.node(parent)?.children.len();
        self.insert_child(parent, position, child)
    }

    /// Inserts `child` at `position` of `parent`'s children. A node may have many parents, and
    /// the same child may appear twice; a cycle is refused.
    pub fn insert_child(
        &mut self,
        parent: NodeHandle,
        position: usize,
        child: NodeHandle,
    ) -> Result<(), GraphError> {
        let len = self.node(parent)?.children.len();
        self.node(child)?;
        if position > len {
            return Err(GraphError::OutOfRange {
                what: "child position",
                index: position,
                len: len + 1,
            });
        }
        if self.is_ancestor_or_self(child, parent) {
            return Err(GraphError::Cycle {
                parent: self.node(parent)?.name.clone(),
                child: self.node(child)?.name.clone(),
            });
        }
        // Sharing multiplies paths: a link adds (paths to the parent) × (nodes the child expands
        // to) paths to the scene tree. Refuse links that would add more than MAX_NEW_PATHS.
        let new_paths = self
            .paths_from_root(parent)
            .saturating_mul(self.expanded_size(child));
        if new_paths > MAX_NEW_PATHS {
            return Err(GraphError::Invalid(format!(
                "adding '{}' under '{}' would add {new_paths} paths to the scene (shared subgraphs multiply paths; at most {MAX_NEW_PATHS} per edit)",
                self.node(child)?.name,
                self.node(parent)?.name
            )));
        }
        if let Some(p) = self.nodes.get_mut(parent) {
            p.children.insert(
                position,
                ChildLink {
                    node: child,
                    active: true,
                },
            );
        }
        if let Some(c) = self.nodes.get_mut(child) {
            c.parents.push(parent);
        }
        self.events.push(GraphEvent::ChildInserted {
            parent,
            position: position as u32,
            child,
        });
        Ok(())
    }

    /// Removes the first link from `parent` to `child`.
    pub fn remove_child(
        &mut self,
        parent: NodeHandle,
        child: NodeHandle,
    ) -> Result<(), GraphError> {
        let position = self
            .node(parent)?
            .children
            .iter()
            .position(|c| c.node == child)
            .ok_or_else(|| {
                GraphError::Invalid(format!(
                    "'{}' is not a child of '{}'",
                    self.nodes
                        .get(child)
                        .map_or("(destroyed node)", |n| n.name.as_str()),
                    self.nodes.get(parent).map_or("", |n| n.name.as_str())
                ))
            })?;
        self.remove_child_at(parent, position)
    }

    /// Removes the child at `position` of `parent`.
    pub fn remove_child_at(
        &mut self,
        parent: NodeHandle,
        position: usize,
    ) -> Result<(), GraphError> {
        let len = self.node(parent)?.children.len();
        if position >= len {
            return Err(GraphError::OutOfRange {
                what: "child position",
                index: position,
                len,
            });
        }
        let link = self
            .nodes
            .get_mut(parent)
            .map(|p| p.children.remove(position));
        if let Some(link) = link {
            if let Some(c) = self.nodes.get_mut(link.node) {
                if let Some(i) = c.parents.iter().position(|&p| p == parent) {
                    c.parents.swap_remove(i);
                }
            }
        }
        self.events.push(GraphEvent::ChildRemoved {
            parent,
            position: position as u32,
        });
        Ok(())
    }

    /// Number of paths from the root to `node` (0 for a node not attached to the root);
    /// walks up through the ancestors, counting each once. Saturates.
    fn paths_from_root(&self, node: NodeHandle) -> u64 {
        let root = self.root;
        self.dag_sum(node, |n| n.parents.clone(), |h| u64::from(h == root))
    }

    /// Number of tree nodes one path to `node` expands to (itself and everything below, each
    /// shared subgraph counted once per link); each distinct node is visited once. Saturates.
    fn expanded_size(&self, node: NodeHandle) -> u64 {
        self.dag_sum(node, |n| n.children.iter().map(|l| l.node).collect(), |_| 1)
    }

    /// `value(start)` where `value(n) = base(n) + Σ value(m)` over the nodes `next(n)` lists
    /// (with repeats): a memoised, iterative walk that visits each distinct node once.
    fn dag_sum(
        &self,
        start: NodeHandle,
        next: impl Fn(&GraphNode) -> Vec<NodeHandle>,
        base: impl Fn(NodeHandle) -> u64,
    ) -> u64 {
        let mut memo: HashMap<NodeHandle, u64> = HashMap::new();
        let mut stack = vec![start];
        while let Some(&n) = stack.last() {
            if memo.contains_key(&n) {
                stack.pop();
                continue;
            }
            let neighbours = self.nodes.get(n).map(&next).unwrap_or_default();
            let pending: Vec<NodeHandle> = neighbours
                .iter()
                .copied()
                .filter(|m| !memo.contains_key(m))
                .collect();
            if pending.is_empty() {
                let value = neighbours
                    .iter()
                    .fold(base(n), |sum, m| sum.saturating_add(memo[m]));
                memo.insert(n, value);
                stack.pop();
            } else {
                stack.extend(pending);
            }
        }
        memo[&start]
    }

    /// Whether `ancestor` is `node` or lies above it (walks up through every parent).
    fn is_ancestor_or_self(&self, ancestor: NodeHandle, node: NodeHandle) -> bool {
        let mut stack = vec![node];
        let mut seen = std::collections::HashSet::new();
        while let Some(n) = stack.pop() {
            if n == ancestor {
                return true;
            }
            if seen.insert(n) {
                if let Some(node) = self.nodes.get(n) {
                    stack.extend(node.parents.iter().copied());
                }
            }
        }
        false
    }

    // ---- properties ---------------------------------------------------------------------

    fn node_mut(&mut self, node: NodeHandle) -> Result<&mut GraphNode, GraphError> {
        self.nodes.get_mut(node).ok_or_else(|| stale_node(node))
    }

    fn wrong_kind(node: &GraphNode, expected: &'static str, operation: &'static str) -> GraphError {
        GraphError::WrongKind {
            name: node.name.clone(),
            actual: node.kind.name(),
            expected,
            operation,
        }
    }

    /// Sets a Transform's matrix.
    pub fn set_matrix(&mut self, node: NodeHandle, matrix: DMat4) -> Result<(), GraphError> {
        let n = self.node_mut(node)?;
        check_matrix(&n.name, &matrix)?;
        match &mut n.kind {
            NodeKind::Transform { matrix: m } => *m = matrix,
            _ => return Err(Self::wrong_kind(n, "Transform", "set_matrix")),
        }
        self.events.push(GraphEvent::MatrixChanged(node));
        Ok(())
    }

    /// Sets which children of a Switch are shown: one flag per child, in order.
    pub fn set_switch_mask(&mut self, node: NodeHandle, mask: &[bool]) -> Result<(), GraphError> {
        let n = self.node_mut(node)?;
        if !matches!(n.kind, NodeKind::Switch) {
            return Err(Self::wrong_kind(n, "Switch", "set_switch_mask"));
        }
        if mask.len() != n.children.len() {
            return Err(GraphError::Invalid(format!(
                "Switch '{}' has {} children; the mask has {} flags",
                n.name,
                n.children.len(),
                mask.len()
            )));
        }
        for (link, &active) in n.children.iter_mut().zip(mask) {
            link.active = active;
        }
        self.events.push(GraphEvent::SelectionChanged(node));
        Ok(())
    }

    /// Sets a LOD's switch points (distances or angular sizes, as its metric says).
    pub fn set_lod_thresholds(
        &mut self,
        node: NodeHandle,
        thresholds: &[f64],
    ) -> Result<(), GraphError> {
        let n = self.node_mut(node)?;
        let name = n.name.clone();
        match &mut n.kind {
            NodeKind::Lod {
                thresholds: t,
                metric,
            } => {
                check_thresholds(&name, thresholds, *metric)?;
                *t = thresholds.to_vec();
            }
            _ => return Err(Self::wrong_kind(n, "Lod", "set_lod_thresholds")),
        }
        self.events.push(GraphEvent::SelectionChanged(node));
        Ok(())
    }

    /// Sets a node's flags.
    pub fn set_flags(&mut self, node: NodeHandle, flags: NodeFlags) -> Result<(), GraphError> {
        let n = self.node_mut(node)?;
        if n.flags != flags {
            n.flags = flags;
            self.events.push(GraphEvent::FlagsChanged(node));
        }
        Ok(())
    }

    /// Shows or hides one part of a Geo node.
    pub fn set_part_visible(
        &mut self,
        node: NodeHandle,
        part: usize,
        visible: bool,
    ) -> Result<(), GraphError> {
        let n = self.node_mut(node)?;
        match &mut n.kind {
            NodeKind::Geo { part_visible, .. } => {
                let len = part_visible.len();
                let slot = part_visible.get_mut(part).ok_or(GraphError::OutOfRange {
                    what: "part",
                    index: part,
                    len,
                })?;
                if *slot == visible {
                    return Ok(());
                }
                *slot = visible;
            }
            _ => return Err(Self::wrong_kind(n, "Geo", "set_part_visible")),
        }
        self.events.push(GraphEvent::PartVisibilityChanged {
            node,
            part: part as u32,
        });
        Ok(())
    }

    /// Sets the material of one part of a Geo node.
    pub fn set_part_material(
        &mut self,
        node: NodeHandle,
        part: usize,
        material: MaterialHandle,
    ) -> Result<(), GraphError> {
        self.material(material)?;
        let n = self.nodes.get_mut(node).ok_or_else(|| stale_node(node))?;
        let old = match &mut n.kind {
            NodeKind::Geo { part_materials, .. } => {
                let len = part_materials.len();
                let slot = part_materials.get_mut(part).ok_or(GraphError::OutOfRange {
                    what: "part",
                    index: part,
                    len,
                })?;
                std::mem::replace(slot, material)
            }
            _ => return Err(Self::wrong_kind(n, "Geo", "set_part_material")),
        };
        if let Some(e) = self.materials.get_mut(old) {
            e.users -= 1;
        }
        if let Some(e) = self.materials.get_mut(material) {
            e.users += 1;
        }
        self.events.push(GraphEvent::PartMaterialChanged {
            node,
            part: part as u32,
        });
        Ok(())
    }

    /// The scene this graph describes, with dense indices (for savers, statistics and
    /// comparisons). Handles map to indices in slot order. Fails where a geometry in the page
    /// file cannot be read back.
    pub fn to_scene(&self) -> Result<Scene, GraphError> {
        convert::graph_to_scene(self)
    }

    /// Builds a graph from a scene; returns it with the handles of the scene's nodes.
    pub fn from_scene(scene: &Scene) -> Result<(Self, Vec<NodeHandle>), GraphError> {
        crate::timings::time(crate::timings::Phase::SceneBuild, || {
            convert::scene_to_graph(scene)
        })
    }

    /// Adds `scene` (from a loader or generator) below `parent` under a new Group named after
    /// it, and returns everything created. The scene is checked first: a refused import
    /// changes nothing.
    pub fn import(&mut self, scene: &Scene, parent: NodeHandle) -> Result<Imported, GraphError> {
        convert::import_scene(self, scene, parent)
    }

    /// Adds a scene loaded for the graph (`crate::load::SceneSource::load_for_graph`): its
    /// outline, whose geometries are stand-ins, and the geometries themselves, which the graph
    /// adopts where they are (in memory or in their page file, which the graph then keeps). As
    /// [`SceneGraph::import`] does, the scene goes below `parent` under a new Group named
    /// after it, and `parent` and the outline are checked first: a refused import changes
    /// nothing (the geometries go, with their page file).
    pub fn import_loaded(
        &mut self,
        outline: &Scene,
        geometries: LoadedGeometries,
        parent: NodeHandle,
    ) -> Result<Imported, GraphError> {
        self.node(parent)?;
        outline
            .validate_outline()
            .map_err(|e| GraphError::Invalid(e.0))?;
        if geometries.len() != outline.geometries.len() {
            return Err(GraphError::Invalid(format!(
                "the scene '{}' has {} geometries, but {} were loaded for it",
                outline.name,
                outline.geometries.len(),
                geometries.len()
            )));
        }
        crate::timings::time(crate::timings::Phase::SceneBuild, || {
            let LoadedGeometries { paging, taken, .. } = geometries;
            self.paging.absorb(paging);
            convert::import_outline(self, outline, taken, parent)
        })
    }

    /// Bytes of geometry the graph can still keep in memory: its memory limit
    /// ([`SceneGraph::set_geometry_memory_limit`]) less what it keeps there. A load for the
    /// graph keeps this much in memory and pages the rest.
    pub fn geometry_memory_left(&self) -> u64 {
        self.paging.memory_left()
    }

    /// The live geometry in slot `index`, if any.
    pub fn geometry_handle_at(&self, index: u32) -> Option<GeometryHandle> {
        self.geometries.handle_at(index)
    }

    /// The live material in slot `index`, if any.
    pub fn material_handle_at(&self, index: u32) -> Option<MaterialHandle> {
        self.materials.handle_at(index)
    }

    /// The live texture in slot `index`, if any.
    pub fn texture_handle_at(&self, index: u32) -> Option<TextureHandle> {
        self.textures.handle_at(index)
    }

    /// Live nodes with handles.
    pub fn nodes(&self) -> impl Iterator<Item = (NodeHandle, &GraphNode)> {
        self.nodes.iter()
    }
}

fn check_matrix(name: &str, matrix: &DMat4) -> Result<(), GraphError> {
    if matrix.to_cols_array().iter().all(|c| c.is_finite()) {
        Ok(())
    } else {
        Err(GraphError::Invalid(format!(
            "the matrix of '{name}' has a non-finite value"
        )))
    }
}

fn check_thresholds(name: &str, thresholds: &[f64], metric: LodMetric) -> Result<(), GraphError> {
    let positive = thresholds.iter().all(|t| t.is_finite() && *t > 0.0);
    let ordered = match metric {
        LodMetric::Distance => thresholds.windows(2).all(|w| w[0] < w[1]),
        LodMetric::ScreenSize { radius } => {
            radius.is_finite()
                && radius > 0.0
                && thresholds.windows(2).all(|w| w[0] > w[1])
                && thresholds.iter().all(|&t| t < std::f64::consts::PI)
        }
    };
    if positive && ordered {
        Ok(())
    } else {
        let rule = match metric {
            LodMetric::Distance => "distances must be finite, positive and increasing".to_owned(),
            LodMetric::ScreenSize { radius } => {
                format!("angular sizes must be positive, below pi and decreasing, and the radius ({radius}) positive")
            }
        };
        Err(GraphError::Invalid(format!(
            "LOD '{name}': {rule}: {thresholds:?}"
        )))
    }
}

fn check_geometry(geometry: &Geometry) -> Result<(), GraphError> {
    geometry.validate(0).map_err(|e| GraphError::Invalid(e.0))
}

fn check_material(material: &Material) -> Result<(), GraphError> {
    let values = material
        .base_color
        .iter()
        .chain([&material.metallic, &material.roughness]);
    if !values.into_iter().all(|v| v.is_finite()) {
        return Err(GraphError::Invalid(format!(
            "material '{}' has a non-finite value",
            material.name
        )));
    }
    // The texture's existence is checked by the graph; here only the values.
    material
        .validate_texture(0, usize::MAX)
        .map_err(|e| GraphError::Invalid(e.0.replacen("material 0 ", "material ", 1)))
}
