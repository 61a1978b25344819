//! Scenes: the scene graph a host edits and the scene tree that flattens it incrementally for
//! renderers; the handles of scenes, nodes, geometries, materials and textures. Nodes are made
//! and edited in `nodes.rs`, files loaded in `load.rs`, bounds and statistics in `bounds.rs`,
//! geometry and materials in `geometry.rs`, textures and vertex attributes in `textures.rs`.

use cadr_core::graph::{
    GeometryHandle, GraphError, MaterialHandle, NodeHandle, SceneGraph, TextureHandle,
};
use cadr_core::tree::SceneTree;
use cadr_core::view::{SharedScenes, View};

use crate::args::deliver;
use crate::error::{guard, CadrResult, Failure};
use crate::handles::{lock, Registry};

/// Opaque type behind [`CadrScene`].
pub struct CadrSceneObject {
    _private: (),
}

/// A scene: a scene graph with one root Group, and the scene tree flattened from it.
/// Created by `cadr_scene_create`, released by `cadr_scene_destroy`. A scene needs no context:
/// any renderer can draw it.
pub type CadrScene = *mut CadrSceneObject;

/// A node of a scene (0 is never a valid node). Generation-checked: a destroyed node's handle
/// gives `CADR_RESULT_DESTROYED_HANDLE`.
pub type CadrNode = u64;

/// A geometry of a scene (0 is never valid).
pub type CadrGeometry = u64;

/// A material of a scene (0 is never valid).
pub type CadrMaterial = u64;

/// A texture of a scene (0 is never valid; where a texture is optional, 0 means none).
pub type CadrTexture = u64;

/// Node flag: the node and its subtree are drawn.
pub const CADR_NODE_VISIBLE: u32 = 1;
/// Node flag: the node's parts can be picked.
pub const CADR_NODE_PICKABLE: u32 = 2;
/// Node flag: the node's parts are drawn highlighted.
pub const CADR_NODE_HIGHLIGHTED: u32 = 4;

/// What a scene holds.
pub(crate) struct SceneState {
    pub(crate) graph: SceneGraph,
    /// The scene tree, whose changes the GPU scenes read.
    pub(crate) tree: SceneTree,
    /// The scene on the GPU, one per context (and place of world matrices), shared by the
    /// renderers drawing it: each keeps only its target, culling and uniforms.
    pub(crate) gpu_scenes: SharedScenes,
}

impl SceneState {
    /// Brings the tree up to date with the graph's edits.
    pub(crate) fn update(&mut self) {
        self.tree.update(&mut self.graph);
    }

    /// Brings the tree and `view`'s GPU scene (the one the scene's renderers share) up to date
    /// with the graph's edits.
    pub(crate) fn sync(&mut self, view: &mut View) -> Result<(), Failure> {
        self.update();
        view.sync_shared(&self.graph, &mut self.tree, &mut self.gpu_scenes)?;
        Ok(())
    }
}

pub(crate) static SCENES: Registry<SceneState> = Registry::new(0xC2, "scene");

const NODE_TAG: u64 = 0x4E;
const GEOMETRY_TAG: u64 = 0x47;
const MATERIAL_TAG: u64 = 0x4D;
const TEXTURE_TAG: u64 = 0x54;
const GENERATION_MASK: u32 = 0xff_ffff;

fn encode(tag: u64, index: u32, generation: u32) -> u64 {
    tag << 56 | u64::from(generation & GENERATION_MASK) << 32 | u64::from(index)
}

/// Decodes an item handle: checks its tag, finds the live handle in its slot and compares
/// generations.
fn decode<T>(
    value: u64,
    tag: u64,
    what: &str,
    type_name: &str,
    capacity: usize,
    handle_at: impl Fn(u32) -> Option<cadr_core::graph::Handle<T>>,
) -> Result<cadr_core::graph::Handle<T>, Failure> {
    if value == 0 {
        return Err(Failure::new(
            CadrResult::NullArgument,
            format!("{what} is 0"),
        ));
    }
    let index = value as u32;
    let generation = (value >> 32) as u32 & GENERATION_MASK;
    let foreign = || {
        Failure::new(
            CadrResult::ForeignHandle,
            format!("{what} ({value:#x}) is not a {type_name} of this scene"),
        )
    };
    if value >> 56 != tag || index as usize >= capacity {
        return Err(foreign());
    }
    match handle_at(index) {
        Some(handle) if handle.generation() & GENERATION_MASK == generation => Ok(handle),
        _ => Err(Failure::new(
            CadrResult::DestroyedHandle,
            format!("{what} ({value:#x}) is a destroyed {type_name}"),
        )),
    }
}

pub(crate) fn node_of(
    graph: &SceneGraph,
    value: CadrNode,
    what: &str,
) -> Result<NodeHandle, Failure> {
    let capacity = graph.capacities().0;
    decode(value, NODE_TAG, what, "node", capacity, |i| {
        graph.node_handle_at(i)
    })
}

pub(crate) fn geometry_of(
    graph: &SceneGraph,
    value: CadrGeometry,
    what: &str,
) -> Result<GeometryHandle, Failure> {
    let capacity = graph.capacities().1;
    decode(value, GEOMETRY_TAG, what, "geometry", capacity, |i| {
        graph.geometry_handle_at(i)
    })
}

pub(crate) fn material_of(
    graph: &SceneGraph,
    value: CadrMaterial,
    what: &str,
) -> Result<MaterialHandle, Failure> {
    let capacity = graph.capacities().2;
    decode(value, MATERIAL_TAG, what, "material", capacity, |i| {
        graph.material_handle_at(i)
    })
}

pub(crate) fn texture_of(
    graph: &SceneGraph,
    value: CadrTexture,
    what: &str,
) -> Result<TextureHandle, Failure> {
    let capacity = graph.texture_capacity();
    decode(value, TEXTURE_TAG, what, "texture", capacity, |i| {
        graph.texture_handle_at(i)
    })
}

pub(crate) fn node_value(handle: NodeHandle) -> CadrNode {
    encode(NODE_TAG, handle.index(), handle.generation())
}

pub(crate) fn geometry_value(handle: GeometryHandle) -> CadrGeometry {
    encode(GEOMETRY_TAG, handle.index(), handle.generation())
}

pub(crate) fn material_value(handle: MaterialHandle) -> CadrMaterial {
    encode(MATERIAL_TAG, handle.index(), handle.generation())
}

pub(crate) fn texture_value(handle: TextureHandle) -> CadrTexture {
    encode(TEXTURE_TAG, handle.index(), handle.generation())
}

/// A graph error as a result code and message.
pub(crate) fn graph_failure(error: GraphError) -> Failure {
    let code = match error {
        GraphError::StaleNode { .. }
        | GraphError::StaleGeometry { .. }
        | GraphError::StaleMaterial { .. }
        | GraphError::StaleTexture { .. } => CadrResult::DestroyedHandle,
        GraphError::InUse { .. } => CadrResult::InUse,
        GraphError::PageRead(_) => CadrResult::Io,
        _ => CadrResult::InvalidArgument,
    };
    Failure::new(code, error.to_string())
}

/// Runs `edit` on a scene's state.
pub(crate) fn with_scene<R>(
    scene: CadrScene,
    edit: impl FnOnce(&mut SceneState) -> Result<R, Failure>,
) -> Result<R, Failure> {
    let object = SCENES.get(scene as u64, "scene")?;
    let mut state = lock(&object);
    edit(&mut state)
}

/// Creates an empty scene (a root Group only).
///
/// Returns `CADR_RESULT_OK` and writes `*scene`, or `CADR_RESULT_NULL_ARGUMENT`.
/// Ownership: the scene is the caller's until `cadr_scene_destroy`. Thread-safety: callable
/// from any thread; a scene may be used from several threads, one call at a time (an internal
/// lock serialises them).
///
/// # Safety
/// `scene` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_create(scene: *mut CadrScene) -> CadrResult {
    guard(|| {
        let mut graph = SceneGraph::new();
        let tree = SceneTree::build(&mut graph);
        let state = SceneState {
            graph,
            tree,
            gpu_scenes: SharedScenes::default(),
        };
        let handle = SCENES.insert(state)?;
        // SAFETY: scene is null or writable (the caller's contract).
        unsafe { deliver(scene, "scene", handle as CadrScene) }
    })
}

/// Destroys a scene and everything in it; its node, geometry and material handles become
/// invalid. NULL is a no-op.
///
/// Returns `CADR_RESULT_OK` or a handle error.
/// Ownership: the handle (or item) is given back to cadr and invalid afterwards.
/// Thread-safety: not while another thread uses the scene.
#[no_mangle]
pub extern "C" fn cadr_scene_destroy(scene: CadrScene) -> CadrResult {
    guard(|| {
        let removed = SCENES.remove(scene as u64, "scene")?;
        drop(removed);
        Ok(())
    })
}

/// Writes the scene's root Group.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the outputs are the caller's; cadr keeps no pointer to them.
/// Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// `root` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_root(scene: CadrScene, root: *mut CadrNode) -> CadrResult {
    guard(|| {
        let value = with_scene(scene, |s| Ok(node_value(s.graph.root())))?;
        // SAFETY: root is null or writable (the caller's contract).
        unsafe { deliver(root, "root", value) }
    })
}
