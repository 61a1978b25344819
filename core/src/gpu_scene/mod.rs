//! The one GPU scene, fed by the scene tree, that every technique, the pick pass and every
//! product path draws from ([`abi::CadrSceneView`] is how plugins see it): geometry in shared
//! arenas (`geometry.rs`), per-instance entries, records and part boxes, matrices (f64 on the CPU for
//! culling; on the GPU with translations split into f32 high and low parts) and materials.
//!
//! World matrices of moved subtrees are computed where the active techniques need them
//! ([`Transforms`]): on the host, or on the GPU by the transform hierarchy (`hierarchy.rs`),
//! in which case a moved node uploads its local matrix only.
//!
//! It reads the tree as one of its readers ([`SceneTree::subscribe`]): each sync applies what
//! changed since this scene's own last sync, with work and uploads in proportion to the change
//! (changed slots gathered and scattered on the GPU by `upload.rs`; a replaced geometry written
//! in place when it fits; only the touched instances' entries refreshed). Two scenes of one
//! tree each see every change.
//!
//! Several views (renderers of one scene) may draw one GPU scene: each keeps only its own
//! culling, drawn set and the slots changed since its last frame (`view_state.rs`,
//! [`ViewState`]), and catches up with the scene before each frame ([`GpuScene::catch_up`]).

mod bounds;
mod clusters;
mod compute;
mod edge_levels;
mod geometry;
mod hierarchy;
mod stand_ins;
mod streaming;
mod textures;
mod upload;
mod view_state;

pub use hierarchy::{
    gpu_local, HierarchyMethod, HierarchyPlan, Transforms, LOCAL_BYTES, LOCAL_WORDS,
};
pub use streaming::StreamingReport;
pub use textures::{
    gpu_material_texture, TextureBindings, ARRAY_BUDGET_BYTES, MATERIAL_TEXTURE_BYTES,
    MAX_LAYER_SIZE, MAX_TABLE_SIDE, TABLE_BUDGET_BYTES,
};
pub use upload::UploadStats;
pub use view_state::ViewState;

use std::sync::Arc;

use crate::commands_key::mix;
use crate::error::RenderResult;
use crate::vk::raw as vk;
use crate::vk::raw::Handle;
use cadr_plugin_abi as abi;
use glam::DMat4;

use crate::graph::SceneGraph;
use crate::render::split_f64;
use crate::scene::{AlphaMode, Vertex};
use crate::tree::{ChangeReader, InstanceRef, SceneTree, TreeChanges};
use crate::vk::{Device, OneShot};
pub use compute::{HierarchyParameters, HierarchyStage, ScatterParameters, ScenePipelines};
use geometry::GeometryArenas;
use hierarchy::TransformHierarchy;
use textures::SceneTextures;
use upload::{GpuArray, SparseUploader};
use view_state::{bit, set_bit, Followers, SceneFacts, Unseen};

/// Bytes of one matrix on the GPU ([`abi::CadrMatrix`]).
pub const MATRIX_BYTES: usize = 64;
/// Bytes of one material on the GPU ([`abi::CadrMaterial`]).
pub const MATERIAL_BYTES: usize = 32;
/// Bytes of one instance record on the GPU ([`abi::CadrInstanceRecord`]).
pub const RECORD_BYTES: usize = 16;
/// Bytes of one cull entry on the GPU ([`abi::CadrCullEntry`]).
pub const CULL_ENTRY_BYTES: usize = 48;
/// Bytes of one part box ([`abi::CadrBox`]) in the part box array, by instance id.
const PART_BOX_BYTES: usize = 32;

/// A world matrix as the GPU holds it: rotation and scale in f32, the translation's high part
/// in column 3 and its low part in the w of columns 0–2.
pub fn gpu_matrix(world: &DMat4) -> abi::CadrMatrix {
    let (high, low) = split_f64(world.w_axis.truncate());
    let mut columns = world.as_mat4().to_cols_array_2d();
    for axis in 0..3 {
        columns[axis][3] = low[axis];
    }
    columns[3] = [high[0], high[1], high[2], 1.0];
    abi::CadrMatrix { columns }
}

/// A material as the GPU holds it.
pub fn gpu_material(graph: &SceneGraph, slot: u32) -> abi::CadrMaterial {
    graph
        .material_at(slot)
        .map(|m| abi::CadrMaterial {
            base_color: m.base_color,
            surface: [m.metallic, m.roughness, 0.0, 0.0],
        })
        .unwrap_or_default()
}

/// The flags of parts drawn with material slot `slot` that say what can be seen through them:
/// [`abi::CADR_INSTANCE_TRANSLUCENT`] when they are translucent, with
/// [`abi::CADR_INSTANCE_TRANSLUCENT_BY_TEXTURE`] when only their texture makes them so (the
/// vertex shader decides the same from the base colour's alpha and the material's texture
/// description), and [`abi::CADR_INSTANCE_CUTOUT`] when their texture cuts holes.
fn translucency(graph: &SceneGraph, slot: u32) -> abi::CadrInstanceFlags {
    let Some(material) = graph.material_at(slot) else {
        return 0;
    };
    let cutout = if matches!(material.alpha_mode, AlphaMode::Mask { .. })
        && material.base_color_texture.is_some()
    {
        abi::CADR_INSTANCE_CUTOUT
    } else {
        0
    };
    let translucent = if material.is_translucent_without_textures() {
        abi::CADR_INSTANCE_TRANSLUCENT
    } else if graph.is_translucent(material) {
        abi::CADR_INSTANCE_TRANSLUCENT | abi::CADR_INSTANCE_TRANSLUCENT_BY_TEXTURE
    } else {
        0
    };
    translucent | cutout
}

/// What the frame set's scene bindings name (see [`GpuScene::frame_resources`]).
pub struct FrameResources<'a> {
    /// Instance records (binding 2).
    pub records: vk::Buffer,
    /// Material slots' texture descriptions (binding 3).
    pub material_textures: vk::Buffer,
    /// Vertex attributes (binding 4).
    pub vertex_attributes: vk::Buffer,
    /// The textures (the array at bindings 5 and 6, or the bindless table at binding 9).
    pub textures: TextureBindings<'a>,
    /// Trilinear sampler (binding 5).
    pub linear_sampler: vk::Sampler,
    /// Nearest-magnification sampler (binding 6).
    pub nearest_sampler: vk::Sampler,
    /// Cull entries, whose bounding spheres the section caps' pass reads (binding 8).
    pub cull_entries: vk::Buffer,
    /// Changes whenever one of them is replaced.
    pub generation: u64,
}

/// The first generation of the next GPU scene (each scene counts within its own 2^32).
static NEXT_GENERATIONS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

/// The GPU scene.
pub struct GpuScene {
    device: Arc<Device>,
    reader: ChangeReader,
    arenas: GeometryArenas,
    instances: Vec<abi::CadrInstance>,
    /// Per instance id, one bit: a candidate for drawing (alive, visible, with triangles).
    candidate: Vec<u64>,
    matrices: Vec<abi::CadrMatrix>,
    materials: Vec<abi::CadrMaterial>,
    material_info: MaterialInfo,
    /// The textures, rebuilt when the graph's change.
    textures: SceneTextures,
    moves: TransformState,
    /// The arrays' GPU copies, their sparse uploader and its pipelines.
    gpu: GpuCopies,
    /// The views drawing this scene, each with the changes it has not seen.
    followers: Followers,
    generations: Generations,
    counts: SceneCounts,
    /// What techniques see of the buffers and clusters, which the view points into.
    seen: SeenByTechniques,
}

/// What techniques see of the scene's buffers and clusters, kept with the scene so that the
/// view's pointers stay valid as long as it does.
struct SeenByTechniques {
    /// The buffers (with device addresses), refreshed when replaced.
    buffer_refs: [abi::CadrBufferRef; 11],
    /// The clusters, their boxes and the parts' boxes, chained on the view.
    clusters_extension: ClustersExtension,
}

/// The scene view's extensions, kept with the scene they describe: the clusters
/// ([`abi::CadrSceneClusters`]), whose header's `next` names their boxes
/// ([`abi::CadrSceneClusterBoxes`]), whose `next` names the parts' boxes
/// ([`abi::CadrScenePartBoxes`]), the end of the chain.
struct ClusterExtensions {
    clusters: abi::CadrSceneClusters,
    boxes: abi::CadrSceneClusterBoxes,
    part_boxes: abi::CadrScenePartBoxes,
    /// Chained after the parts' boxes only where the scene streams.
    streaming: abi::CadrSceneStreaming,
}

/// [`ClusterExtensions`] on the heap, where the pointer from the first to the second stays
/// valid however the scene moves.
struct ClustersExtension(Box<ClusterExtensions>);

impl ClustersExtension {
    fn new() -> Self {
        let mut extensions = Box::new(ClusterExtensions {
            clusters: abi::CadrSceneClusters {
                header: abi::CadrExtension {
                    size: std::mem::size_of::<abi::CadrSceneClusters>() as u32,
                    kind: abi::CADR_EXTENSION_SCENE_CLUSTERS,
                    next: std::ptr::null(),
                },
                cluster_buffer: abi::CadrBufferRef::default(),
                cluster_count: 0,
                group_count: 0,
                group_buffer: abi::CadrBufferRef::default(),
                candidate_clusters: 0,
                candidate_coarsest_clusters: 0,
            },
            boxes: abi::CadrSceneClusterBoxes {
                header: abi::CadrExtension {
                    size: std::mem::size_of::<abi::CadrSceneClusterBoxes>() as u32,
                    kind: abi::CADR_EXTENSION_SCENE_CLUSTER_BOXES,
                    next: std::ptr::null(),
                },
                box_buffer: abi::CadrBufferRef::default(),
            },
            part_boxes: abi::CadrScenePartBoxes {
                header: abi::CadrExtension {
                    size: std::mem::size_of::<abi::CadrScenePartBoxes>() as u32,
                    kind: abi::CADR_EXTENSION_SCENE_PART_BOXES,
                    next: std::ptr::null(),
                },
                box_buffer: abi::CadrBufferRef::default(),
            },
            streaming: abi::CadrSceneStreaming {
                header: abi::CadrExtension {
                    size: std::mem::size_of::<abi::CadrSceneStreaming>() as u32,
                    kind: abi::CADR_EXTENSION_SCENE_STREAMING,
                    next: std::ptr::null(),
                },
                request_buffer: abi::CadrBufferRef::default(),
                request_word_count: 0,
                reserved: 0,
            },
        });
        extensions.clusters.header.next = &extensions.boxes.header;
        extensions.boxes.header.next = &extensions.part_boxes.header;
        Self(extensions)
    }
}

// SAFETY: the structs' pointers are their headers' `next`, each naming the next struct in the
// same heap allocation (moving the scene moves only the box), the last null; so the chain may
// move to and be read from any thread like the plain values it holds.
unsafe impl Send for ClustersExtension {}
// SAFETY: as above; it is only written through `&mut GpuScene`.
unsafe impl Sync for ClustersExtension {}

/// What the scene knows of each material slot besides its values.
struct MaterialInfo {
    /// Per material slot: its texture description (`textures::gpu_material_texture`).
    textures: Vec<[u32; 12]>,
    /// Per material slot: the translucency flags of its parts (see [`translucency`]).
    translucency: Vec<abi::CadrInstanceFlags>,
    /// Material slots whose parts are translucent: with textures off (`[0]`) and on (`[1]`).
    translucent: [usize; 2],
    /// Material slots whose texture description is not the default (a texture, or an alpha
    /// mode other than BLEND): while there are none, the vertex shader skips reading them.
    described: usize,
}

/// How moved subtrees get their world matrices, and what the last move left to upload.
struct TransformState {
    /// Where moved subtrees' world matrices are computed.
    transforms: Transforms,
    /// World matrices in f64 per matrix slot, for techniques that read them on the host; empty
    /// while the transform hierarchy is on the GPU ([`Transforms::Gpu`]), where none does.
    worlds: Vec<[f64; 16]>,
    /// Local matrices per tree node (with [`Transforms::Gpu`] only).
    locals: Vec<[f32; LOCAL_WORDS]>,
    /// Tree nodes moved since the last upload (with [`Transforms::Gpu`]).
    frame_moved: Vec<u32>,
    hierarchy: TransformHierarchy,
    /// What the last upload's hierarchy pass did.
    last_hierarchy: Option<HierarchyPlan>,
}

/// The GPU copies of the scene's arrays, the uploader that gathers their changed items and the
/// compute pipelines that scatter them and run the transform hierarchy.
struct GpuCopies {
    matrices: GpuArray,
    materials: GpuArray,
    material_textures: GpuArray,
    records: GpuArray,
    cull_entries: GpuArray,
    /// [`abi::CadrBox`] of each instance's part, by instance id, beside its cull entry.
    part_boxes: GpuArray,
    locals: GpuArray,
    uploader: SparseUploader,
    pipelines: ScenePipelines,
}

/// Generations that tell techniques what changed (see the plugin ABI's `CadrSceneView`; a
/// view's draws generation also moves with its culling, see [`ViewState`]).
struct Generations {
    /// The scene's identity: its first generation.
    identity: u64,
    draws: u64,
    parameters: u64,
    buffers: u64,
}

/// What the scene counts for statistics.
struct SceneCounts {
    /// Triangles of the candidates.
    candidate_triangles: u64,
    /// Live instances flagged highlighted.
    highlighted: usize,
    /// What the last sync and upload wrote.
    last_upload: UploadStats,
    /// Instance entries refreshed by the last sync.
    last_touched: u64,
    /// Whether an instance changed since the clusters of the candidates' parts were summed
    /// (into the view's [`abi::CadrSceneClusters`]).
    clusters_stale: bool,
    /// Bytes of the textures as last built.
    texture_bytes: u64,
}

impl GpuScene {
    /// Puts the tree's scene on the GPU, with world matrices kept where `transforms` says, and
    /// subscribes to the tree's changes.
    pub fn new(
        device: &Arc<Device>,
        graph: &SceneGraph,
        tree: &mut SceneTree,
        transforms: Transforms,
    ) -> RenderResult<Self> {
        // Generations are unique across scenes: techniques that cached a previous scene's
        // buffers or commands see that this one differs.
        let first_generation =
            NEXT_GENERATIONS.fetch_add(1 << 32, std::sync::atomic::Ordering::Relaxed);
        let reader = tree.subscribe();
        let (arenas, geometry_bytes) = GeometryArenas::upload(device, graph, false, None)?;
        crate::freed_memory::after_sync(geometry_bytes, 0);
        let (textures, texture_bytes) = SceneTextures::new(device, graph)?;
        let mut scene = Self {
            device: Arc::clone(device),
            reader,
            arenas,
            instances: Vec::new(),
            candidate: Vec::new(),
            matrices: Vec::new(),
            materials: Vec::new(),
            material_info: MaterialInfo {
                textures: Vec::new(),
                translucency: Vec::new(),
                translucent: [0; 2],
                described: 0,
            },
            textures,
            moves: TransformState {
                transforms,
                worlds: Vec::new(),
                locals: Vec::new(),
                frame_moved: Vec::new(),
                hierarchy: TransformHierarchy::new(device),
                last_hierarchy: None,
            },
            gpu: GpuCopies {
                matrices: GpuArray::new(device, "scene matrices", MATRIX_BYTES)?,
                materials: GpuArray::new(device, "scene materials", MATERIAL_BYTES)?,
                material_textures: GpuArray::new(
                    device,
                    "scene material textures",
                    MATERIAL_TEXTURE_BYTES,
                )?,
                records: GpuArray::new(device, "scene instance records", RECORD_BYTES)?,
                cull_entries: GpuArray::new(device, "scene cull entries", CULL_ENTRY_BYTES)?,
                part_boxes: GpuArray::new(device, "scene part boxes", PART_BOX_BYTES)?,
                locals: GpuArray::new(device, "scene local matrices", LOCAL_BYTES)?,
                uploader: SparseUploader::default(),
                pipelines: ScenePipelines::new(device)?,
            },
            followers: Followers::default(),
            generations: Generations {
                identity: first_generation,
                draws: first_generation,
                parameters: first_generation,
                buffers: first_generation,
            },
            counts: SceneCounts {
                candidate_triangles: 0,
                highlighted: 0,
                last_upload: UploadStats {
                    geometry_bytes,
                    texture_bytes,
                    bytes: geometry_bytes + texture_bytes,
                    ..UploadStats::default()
                },
                last_touched: 0,
                clusters_stale: true,
                texture_bytes,
            },
            seen: SeenByTechniques {
                buffer_refs: Default::default(),
                clusters_extension: ClustersExtension::new(),
            },
        };
        scene.refresh_all(graph, tree)?;
        Ok(scene)
    }

    fn refresh_buffer_refs(&mut self) {
        let with_address = self.device.capabilities().buffer_device_address;
        self.seen.buffer_refs = [
            &self.arenas.vertices,
            &self.arenas.indices,
            &self.arenas.wire_indices,
            &self.gpu.matrices.buffer,
            &self.gpu.materials.buffer,
            &self.gpu.records.buffer,
            &self.gpu.cull_entries.buffer,
            &self.arenas.clusters,
            &self.arenas.groups,
            &self.arenas.cluster_boxes,
            &self.gpu.part_boxes.buffer,
        ]
        .map(|buffer| abi::CadrBufferRef {
            buffer: buffer.raw().as_raw(),
            size_bytes: buffer.size(),
            address: if with_address {
                buffer.device_address()
            } else {
                0
            },
        });
        let [.., clusters, groups, boxes, part_boxes] = self.seen.buffer_refs;
        let extensions = &mut *self.seen.clusters_extension.0;
        extensions.boxes.box_buffer = boxes;
        extensions.part_boxes.box_buffer = part_boxes;
        extensions.part_boxes.header.next = std::ptr::null();
        if let Some(streaming) = &self.arenas.streaming {
            let (requests, words) = streaming.requests();
            extensions.streaming.request_buffer = abi::CadrBufferRef {
                buffer: requests.raw().as_raw(),
                size_bytes: requests.size(),
                address: 0,
            };
            extensions.streaming.request_word_count = words;
            extensions.part_boxes.header.next = &extensions.streaming.header;
        }
        let extension = &mut extensions.clusters;
        extension.cluster_buffer = clusters;
        extension.group_buffer = groups;
        [extension.cluster_count, extension.group_count] = self.arenas.cluster_counts();
    }

    /// Sums the clusters of the candidates' parts again when an instance changed since the
    /// last time: a scan of every instance, for edits (moves never change them).
    fn count_candidate_clusters(&mut self) {
        if !self.counts.clusters_stale {
            return;
        }
        let arenas = &self.arenas;
        let [all, coarsest] = self
            .instances
            .iter()
            .enumerate()
            .filter(|&(id, _)| bit(&self.candidate, id as u32))
            .filter_map(|(_, instance)| {
                let place = arenas.places.get(instance.geometry as usize)?.as_ref()?;
                place.clusters_of(instance.part)
            })
            .fold([0u64; 2], |[all, coarsest], [_, count, coarse]| {
                [all + u64::from(count), coarsest + u64::from(coarse)]
            });
        let extension = &mut self.seen.clusters_extension.0.clusters;
        extension.candidate_clusters = all;
        extension.candidate_coarsest_clusters = coarsest;
        self.counts.clusters_stale = false;
    }

    /// Rebuilds every entry from the tree and graph and queues every array for upload.
    fn refresh_all(&mut self, graph: &SceneGraph, tree: &mut SceneTree) -> RenderResult<()> {
        tree.refresh_worlds();
        let nodes = tree.node_capacity();
        let on_gpu = self.moves.transforms == Transforms::Gpu;
        self.moves.frame_moved.clear();
        self.moves.hierarchy.cancel();
        // Each array is made on a thread per core, every item written once (see
        // `parallel::collect_indexed`); slots that keep no matrix stay zero.
        let kept = |t: u32| self.keeps_matrix(tree, t);
        let matrices = per_kept_node(nodes, &kept, |t| gpu_matrix(&tree.world(t)));
        let worlds = if on_gpu {
            Vec::new()
        } else {
            per_kept_node(nodes, &kept, |t| tree.world(t).to_cols_array())
        };
        let locals = if on_gpu {
            per_kept_node(nodes, &kept, |t| gpu_local(&tree.local(t)))
        } else {
            Vec::new()
        };
        (self.matrices, self.moves.worlds, self.moves.locals) = (matrices, worlds, locals);
        let (_, _, material_slots) = graph.capacities();
        self.materials = (0..material_slots as u32)
            .map(|slot| gpu_material(graph, slot))
            .collect();
        self.material_info.textures = (0..material_slots as u32)
            .map(|slot| gpu_material_texture(graph, slot))
            .collect();
        self.material_info.translucency = (0..material_slots as u32)
            .map(|slot| translucency(graph, slot))
            .collect();
        self.material_info.translucent = self
            .material_info
            .translucency
            .iter()
            .map(|&flags| translucent_with_and_without_textures(flags))
            .fold([0; 2], |[a, b], [c, d]| [a + c, b + d]);
        self.material_info.described = self
            .material_info
            .textures
            .iter()
            .filter(|words| textures::is_described(words))
            .count();
        let count = tree.instance_capacity();
        let (instances, tallies) =
            make_instances(&self.arenas, &self.material_info.translucency, tree, count);
        self.instances = instances;
        self.candidate = tallies
            .iter()
            .flat_map(|tally| tally.candidate_bits.iter().copied())
            .collect();
        self.counts.candidate_triangles = tallies.iter().map(|tally| tally.triangles).sum();
        self.counts.highlighted = tallies.iter().map(|tally| tally.highlighted).sum();
        let device = Arc::clone(&self.device);
        self.gpu.matrices.reserve(&device, nodes.max(1))?;
        self.gpu.materials.reserve(&device, material_slots.max(1))?;
        self.gpu
            .material_textures
            .reserve(&device, material_slots.max(1))?;
        self.gpu.records.reserve(&device, count.max(1))?;
        self.gpu.cull_entries.reserve(&device, count.max(1))?;
        self.gpu.part_boxes.reserve(&device, count.max(1))?;
        self.gpu
            .locals
            .reserve(&device, self.moves.locals.len().max(1))?;
        for array in [
            &mut self.gpu.matrices,
            &mut self.gpu.materials,
            &mut self.gpu.material_textures,
            &mut self.gpu.records,
            &mut self.gpu.cull_entries,
            &mut self.gpu.part_boxes,
            &mut self.gpu.locals,
        ] {
            array.queue_all();
        }
        // Every view starts over: its culling, drawn set and uniform copies.
        self.followers.changes = Unseen {
            all: true,
            ..Unseen::default()
        };
        self.counts.last_touched = count as u64;
        self.generations.buffers += 1;
        self.generations.draws += 1;
        self.generations.parameters += 1;
        self.refresh_buffer_refs();
        self.counts.clusters_stale = true;
        self.count_candidate_clusters();
        Ok(())
    }

    /// Whether matrix slot `t` holds a world matrix: a Geo path's, or with the GPU transform
    /// hierarchy any live path's (the hierarchy starts from the parents of moved nodes).
    fn keeps_matrix(&self, tree: &SceneTree, t: u32) -> bool {
        match self.moves.transforms {
            Transforms::Host => tree.has_instances(t),
            Transforms::Gpu => tree.is_node_alive(t),
        }
    }

    fn set_matrix(&mut self, tree: &SceneTree, t: u32) {
        let world = tree.world(t);
        if let Some(kept) = self.moves.worlds.get_mut(t as usize) {
            *kept = world.to_cols_array();
        }
        self.matrices[t as usize] = gpu_matrix(&world);
        if let Some(local) = self.moves.locals.get_mut(t as usize) {
            *local = gpu_local(&tree.local(t));
        }
    }

    /// The entry of a live instance whose geometry and part are in the arenas.
    fn entry_of(&self, instance: &InstanceRef) -> Option<(abi::CadrInstance, bool)> {
        entry_in(&self.arenas, &self.material_info.translucency, instance)
    }

    /// Sets or clears the translucency flags ([`translucency`]) on the instances of the material
    /// slots whose translucency changed (`flipped`), queues their records and cull entries,
    /// and says whether any changed. A scan of every instance, for an edit that is rare.
    fn reflag_translucency(&mut self, flipped: &[u32]) -> bool {
        if flipped.is_empty() {
            return false;
        }
        let mut any = false;
        for id in 0..self.instances.len() {
            let entry = &mut self.instances[id];
            if entry.flags & abi::CADR_INSTANCE_ALIVE == 0 || !flipped.contains(&entry.material) {
                continue;
            }
            entry.flags = with_translucency(
                entry.flags,
                self.material_info.translucency[entry.material as usize],
            );
            self.gpu.records.queue(id as u32);
            self.gpu.cull_entries.queue(id as u32);
            self.gpu.part_boxes.queue(id as u32);
            any = true;
        }
        any
    }

    /// Refreshes the entries of instances `ids` and queues their records, cull entries and
    /// part boxes for upload.
    fn refresh_instances(&mut self, tree: &SceneTree, ids: &[u32]) {
        for &id in ids {
            self.refresh_instance(tree, id);
            self.gpu.records.queue(id);
            self.gpu.cull_entries.queue(id);
            self.gpu.part_boxes.queue(id);
        }
    }

    fn refresh_instance(&mut self, tree: &SceneTree, id: u32) {
        let (entry, candidate) = tree
            .instance(id)
            .and_then(|instance| self.entry_of(&instance))
            .unwrap_or((abi::CadrInstance::default(), false));
        let i = id as usize;
        let old = &self.instances[i];
        let old_triangles = old.index_count / 3;
        // Each view takes the instance out of its drawn set with the old entry's triangles
        // and back in with the new one's.
        self.followers.changes.touched.push((id, old_triangles));
        if bit(&self.candidate, id) {
            self.counts.candidate_triangles -= u64::from(old_triangles);
        }
        if candidate {
            self.counts.candidate_triangles += u64::from(entry.index_count / 3);
        }
        self.counts.highlighted -= usize::from(is_highlighted(old));
        self.counts.highlighted += usize::from(is_highlighted(&entry));
        self.instances[i] = entry;
        set_bit(&mut self.candidate, id, candidate);
        self.counts.clusters_stale = true;
    }

    /// Applies the tree's changes since this scene's last sync, with world matrices kept where
    /// `transforms` says (a change of place uploads every matrix again). The tree must be up
    /// to date with the graph (`SceneTree::update`).
    pub fn sync(
        &mut self,
        graph: &SceneGraph,
        tree: &mut SceneTree,
        transforms: Transforms,
    ) -> RenderResult<()> {
        self.sync_after(graph, tree, transforms, &mut || Ok(()))
    }

    /// [`GpuScene::sync`], calling `settle` first when there is anything to change: a
    /// renderer with a frame in flight waits for it there, as changes may replace buffers it
    /// reads or copy into them. With nothing changed (a moving camera), nothing waits.
    pub fn sync_after(
        &mut self,
        graph: &SceneGraph,
        tree: &mut SceneTree,
        transforms: Transforms,
        settle: &mut dyn FnMut() -> RenderResult<()>,
    ) -> RenderResult<()> {
        self.followers.changes = Unseen::default();
        let result = self
            .apply_tree_changes(graph, tree, transforms, settle)
            .and_then(|()| self.stream(graph, tree, settle));
        if result.is_err() {
            // Half applied: every view starts over from what the scene holds.
            self.followers.changes.all = true;
        }
        // A load or an unload frees its transient buffers by now.
        crate::freed_memory::after_sync(
            self.counts.last_upload.geometry_bytes,
            self.counts.last_touched,
        );
        let slots = self.instances.len() + self.matrices.len() + self.materials.len();
        self.followers.deliver(slots.max(1024));
        result
    }

    /// Where the scene streams its geometry: reads the last frames' requests and brings the
    /// geometries asked for to full detail (others back to their coarse form to make room),
    /// then refreshes the entries of their instances.
    fn stream(
        &mut self,
        graph: &SceneGraph,
        tree: &mut SceneTree,
        settle: &mut dyn FnMut() -> RenderResult<()>,
    ) -> RenderResult<()> {
        let Some(streaming) = &mut self.arenas.streaming else {
            return Ok(());
        };
        if streaming.reserve_requests(&self.device, self.arenas.places.len())? {
            self.refresh_buffer_refs();
            self.generations.buffers += 1;
        }
        let (changed, bytes) = self.arenas.stream(graph, settle)?;
        if changed.is_empty() {
            return Ok(());
        }
        self.counts.last_upload.geometry_bytes += bytes;
        self.counts.last_upload.bytes += bytes;
        let extension = &mut self.seen.clusters_extension.0.clusters;
        [extension.cluster_count, extension.group_count] = self.arenas.cluster_counts();
        let mut swapped = vec![false; self.arenas.places.len()];
        for &slot in &changed {
            if let Some(flag) = swapped.get_mut(slot as usize) {
                *flag = true;
            }
        }
        let users: Vec<u32> = (0..self.instances.len() as u32)
            .filter(|&id| {
                geometry_of_entry(&self.instances[id as usize])
                    .is_some_and(|g| swapped.get(g as usize) == Some(&true))
            })
            .collect();
        self.refresh_instances(tree, &users);
        self.counts.last_touched += users.len() as u64;
        self.generations.draws += 1;
        self.count_candidate_clusters();
        Ok(())
    }

    /// Where the scene streams its geometry: asks for the full detail of the geometries of the
    /// instances a CPU culler leaves visible (`visible`, one bit per instance id), from the next
    /// frame until asked again. A scan of the visible instances, made when culling ran.
    pub(crate) fn ask_for_visible(&mut self, visible: &[u64]) {
        let Some(streaming) = &mut self.arenas.streaming else {
            return;
        };
        let mut asked = vec![false; self.arenas.places.len()];
        for (word_index, (visible, candidate)) in visible.iter().zip(&self.candidate).enumerate() {
            let mut word = visible & candidate;
            while word != 0 {
                let id = word_index * 64 + word.trailing_zeros() as usize;
                word &= word - 1;
                let slot = self.instances.get(id).and_then(geometry_of_entry);
                if let Some(seen) = slot.and_then(|slot| asked.get_mut(slot as usize)) {
                    *seen = true;
                }
            }
        }
        let slots = (asked.iter().enumerate())
            .filter(|(_, &asked)| asked)
            .map(|(slot, _)| slot as u32)
            .collect();
        streaming.ask_for(slots);
    }

    /// What the scene's geometry streaming holds and has done, where the scene streams (its
    /// full detail needs more than the memory budget; see `streaming.rs`).
    pub fn streaming(&self) -> Option<StreamingReport> {
        self.arenas.streaming.as_ref().map(|s| s.report())
    }

    /// Device bytes the coarse forms of a streaming scene take in the geometry arenas (their
    /// places' rooms: vertices, indices, clusters and groups): what it holds beyond its full
    /// detail's budget, besides the arenas' spare room and the instances; 0 where the scene
    /// does not stream. Counts every geometry: for tools and tests, not for every frame.
    pub fn coarse_form_bytes(&self) -> u64 {
        self.arenas.coarse_form_bytes()
    }

    /// Applies what `view` has not seen of this scene yet (everything, for a view that drew
    /// another scene or none): before each of its frames.
    pub fn catch_up(&mut self, view: &mut ViewState) {
        let facts = SceneFacts {
            identity: self.generations.identity,
            draws: self.generations.draws,
            candidate: &self.candidate,
            candidate_triangles: self.counts.candidate_triangles,
            instances: &self.instances,
            slots: (self.matrices.len(), self.materials.len()),
        };
        view.catch_up(&mut self.followers, &facts);
    }

    /// The body of [`GpuScene::sync_after`], which hands what it changed to the views.
    fn apply_tree_changes(
        &mut self,
        graph: &SceneGraph,
        tree: &mut SceneTree,
        transforms: Transforms,
        settle: &mut dyn FnMut() -> RenderResult<()>,
    ) -> RenderResult<()> {
        self.counts.last_upload = UploadStats::default();
        self.counts.last_touched = 0;
        let Some(changes) = tree.changes_for(&self.reader) else {
            // A tree this scene does not read: start over from it.
            settle()?;
            self.reader = tree.subscribe();
            self.moves.transforms = transforms;
            return self.relayout(graph, tree);
        };
        if transforms != self.moves.transforms {
            settle()?;
            self.moves.transforms = transforms;
            if !self.place_geometries(graph, &changes.dirty_geometries)? {
                return self.relayout(graph, tree);
            }
            return self.refresh_all(graph, tree);
        }
        if changes.is_empty() {
            return Ok(());
        }
        settle()?;
        // Materials name textures by slot: with new textures their descriptions are made
        // again with every array, and the frame set names the new image.
        let textures_changed = graph.textures_generation() != self.textures.generation;
        if textures_changed {
            self.rebuild_textures(graph)?;
        }
        let grown = tree.node_capacity() > self.matrices.len()
            || tree.instance_capacity() > self.instances.len()
            || graph.capacities().2 > self.materials.len();
        if !self.place_geometries(graph, &changes.dirty_geometries)? {
            return self.relayout(graph, tree);
        }
        if grown || textures_changed {
            return self.refresh_all(graph, tree);
        }
        self.apply(graph, tree, &changes);
        self.count_candidate_clusters();
        if self.moves.transforms == Transforms::Gpu && !self.gpu.locals.is_whole() {
            self.moves.frame_moved.sort_unstable();
            self.moves.frame_moved.dedup();
            self.moves.hierarchy.plan(tree, &self.moves.frame_moved)?;
        }
        Ok(())
    }

    /// Bytes the scene keeps on the GPU: the geometry arenas (clusters included), the
    /// instance, matrix and material arrays with their spare room, and the textures.
    pub fn resident_bytes(&self) -> u64 {
        let arenas = &self.arenas;
        let gpu = &self.gpu;
        [
            &arenas.vertices,
            &arenas.indices,
            &arenas.wire_indices,
            &arenas.attributes,
            &arenas.clusters,
            &arenas.cluster_boxes,
            &arenas.groups,
            &gpu.matrices.buffer,
            &gpu.materials.buffer,
            &gpu.material_textures.buffer,
            &gpu.records.buffer,
            &gpu.cull_entries.buffer,
            &gpu.part_boxes.buffer,
            &gpu.locals.buffer,
        ]
        .iter()
        .map(|buffer| buffer.size())
        .sum::<u64>()
            + self.counts.texture_bytes
    }

    /// The device the scene lives on.
    pub fn device(&self) -> &Arc<Device> {
        &self.device
    }

    /// Where world matrices of moved subtrees are computed now.
    pub fn transforms(&self) -> Transforms {
        self.moves.transforms
    }

    /// Makes the transform hierarchy use `method` whatever the shape of the moved subtrees
    /// (`None`: chosen from it, the default). For comparing the methods.
    pub fn force_hierarchy_method(&mut self, method: Option<HierarchyMethod>) {
        self.moves.hierarchy.forced = method;
    }

    /// What the last upload's transform hierarchy pass did (none when nothing moved, or with
    /// [`Transforms::Host`]).
    pub fn last_hierarchy(&self) -> Option<HierarchyPlan> {
        self.moves.last_hierarchy
    }

    /// Builds the textures again from the graph's (see [`SceneTextures::rebuild`]).
    fn rebuild_textures(&mut self, graph: &SceneGraph) -> RenderResult<()> {
        let bytes = self.textures.rebuild(&self.device, graph)?;
        self.counts.texture_bytes = bytes;
        self.counts.last_upload.texture_bytes += bytes;
        self.counts.last_upload.bytes += bytes;
        Ok(())
    }

    /// Gives the geometries created, destroyed and replaced (`replaced` slots) since the last
    /// sync their places, and frees those left; false where the room ran out, so that the
    /// arenas must be laid out again.
    fn place_geometries(&mut self, graph: &SceneGraph, replaced: &[u32]) -> RenderResult<bool> {
        let mut placed = self.arenas.follow_created_and_destroyed(graph)?;
        for &slot in replaced {
            // New data under the same handle: streaming makes its coarse form again.
            if let Some(streaming) = &mut self.arenas.streaming {
                streaming.forget(slot);
            }
            placed = match (placed, self.arenas.place(graph, slot)?) {
                (Some(before), Some(bytes)) => Some(before + bytes),
                _ => None,
            };
        }
        let Some(bytes) = placed else {
            return Ok(false);
        };
        self.counts.last_upload.geometry_bytes += bytes;
        self.counts.last_upload.bytes += bytes;
        // A geometry placed at the arenas' end adds clusters the extension must count.
        let extension = &mut self.seen.clusters_extension.0.clusters;
        [extension.cluster_count, extension.group_count] = self.arenas.cluster_counts();
        Ok(true)
    }

    /// Lays the arenas out again and rebuilds every entry.
    fn relayout(&mut self, graph: &SceneGraph, tree: &mut SceneTree) -> RenderResult<()> {
        let mut streaming = self.arenas.streaming.take();
        if let Some(streaming) = &mut streaming {
            // The preparing thread goes with the old arenas.
            streaming.cancel_loading();
        }
        let (arenas, bytes) = GeometryArenas::upload(&self.device, graph, true, streaming)?;
        self.arenas = arenas;
        self.counts.last_upload.geometry_bytes += bytes;
        self.counts.last_upload.bytes += bytes;
        if graph.textures_generation() != self.textures.generation {
            self.rebuild_textures(graph)?;
        }
        self.refresh_all(graph, tree)
    }

    /// Applies changes that fit the current arrays.
    fn apply(&mut self, graph: &SceneGraph, tree: &mut SceneTree, changes: &TreeChanges) {
        for &t in &changes.dirty_matrices {
            if self.keeps_matrix(tree, t) {
                self.set_matrix(tree, t);
                self.gpu.matrices.queue(t);
                if self.moves.transforms == Transforms::Gpu {
                    self.gpu.locals.queue(t);
                }
                self.followers.changes.matrices.push(t);
            }
        }
        self.apply_moves(tree, &changes.moved);
        let mut flipped = Vec::new();
        for &slot in &changes.dirty_materials {
            if (slot as usize) < self.materials.len() {
                let flags = translucency(graph, slot);
                let was =
                    std::mem::replace(&mut self.material_info.translucency[slot as usize], flags);
                if was != flags {
                    flipped.push(slot);
                }
                let (now, was) = (
                    translucent_with_and_without_textures(flags),
                    translucent_with_and_without_textures(was),
                );
                for ((count, now), was) in
                    self.material_info.translucent.iter_mut().zip(now).zip(was)
                {
                    *count = *count + now - was;
                }
                self.materials[slot as usize] = gpu_material(graph, slot);
                let description = gpu_material_texture(graph, slot);
                let was =
                    std::mem::replace(&mut self.material_info.textures[slot as usize], description);
                self.material_info.described = self.material_info.described
                    + usize::from(textures::is_described(&description))
                    - usize::from(textures::is_described(&was));
                self.gpu.materials.queue(slot);
                self.gpu.material_textures.queue(slot);
                self.followers.changes.materials.push(slot);
            }
        }
        if !changes.dirty_matrices.is_empty()
            || !changes.moved.is_empty()
            || !changes.dirty_materials.is_empty()
        {
            self.generations.parameters += 1;
        }
        if self.reflag_translucency(&flipped) {
            self.generations.draws += 1;
        }
        let touched: Vec<u32> = changes
            .removed
            .iter()
            .chain(&changes.added)
            .chain(&changes.changed)
            .chain(&changes.visibility_changed)
            .copied()
            .collect();
        self.refresh_instances(tree, &touched);
        self.counts.last_touched = touched.len() as u64;
        if !touched.is_empty() {
            self.generations.draws += 1;
        }
    }

    /// Applies moved paths: on the GPU, their local matrices go up marked as moved roots;
    /// on the host, the world matrices of their subtrees are brought up to date and uploaded.
    fn apply_moves(&mut self, tree: &mut SceneTree, moved: &[u32]) {
        match self.moves.transforms {
            Transforms::Gpu => {
                for &t in moved {
                    self.moves.locals[t as usize] = gpu_local(&tree.local(t));
                    self.gpu.locals.queue_marked(t);
                    self.moves.frame_moved.push(t);
                }
            }
            Transforms::Host => {
                if moved.is_empty() {
                    return;
                }
                tree.refresh_worlds();
                let mut stack: Vec<u32> = moved.to_vec();
                while let Some(t) = stack.pop() {
                    if tree.has_instances(t) {
                        self.set_matrix(tree, t);
                        self.gpu.matrices.queue(t);
                        self.followers.changes.matrices.push(t);
                    }
                    stack.extend_from_slice(tree.children(t));
                }
            }
        }
    }

    /// Applies culling's result to `view`: `visible` bits and the bits that `changed` since
    /// its last frame; only changed ids are touched.
    pub(crate) fn apply_culling(&self, view: &mut ViewState, visible: &[u64], changed: &[u64]) {
        view.apply_culling((&self.candidate, &self.instances), visible, changed);
    }

    /// Whether the next frame uploads anything (a changed slot or a whole array).
    pub(crate) fn has_pending_uploads(&self) -> bool {
        [
            &self.gpu.matrices,
            &self.gpu.materials,
            &self.gpu.material_textures,
            &self.gpu.records,
            &self.gpu.cull_entries,
            &self.gpu.part_boxes,
            &self.gpu.locals,
        ]
        .iter()
        .any(|array| array.has_pending())
    }

    /// Gathers the pending uploads on the host and clears them, making their commands ready
    /// for [`GpuScene::record_uploads`]; returns the bytes sent and what those commands
    /// depend on (equal keys record equal commands, whatever the items moved).
    pub(crate) fn prepare_uploads(&mut self) -> RenderResult<(u64, u64)> {
        let matrices = &self.matrices;
        let materials = &self.materials;
        let matrix_bytes = |slot: u32, out: &mut [u8]| {
            let item = matrices.get(slot as usize).copied().unwrap_or_default();
            out.copy_from_slice(&item.to_le_bytes());
        };
        let material_bytes = |slot: u32, out: &mut [u8]| {
            let item = materials.get(slot as usize).copied().unwrap_or_default();
            out.copy_from_slice(&item.to_le_bytes());
        };
        let material_textures = &self.material_info.textures;
        let material_texture_bytes = |slot: u32, out: &mut [u8]| {
            let item = material_textures
                .get(slot as usize)
                .copied()
                .unwrap_or_default();
            out.copy_from_slice(bytemuck::cast_slice(&item));
        };
        let (instances, candidates, arenas) = (&self.instances, &self.candidate, &self.arenas);
        let record_bytes = |slot: u32, out: &mut [u8]| {
            let item = instances
                .get(slot as usize)
                .map_or_else(Default::default, |entry| record_of(entry, slot));
            out.copy_from_slice(&item.to_le_bytes());
        };
        let cull_entry_bytes = |slot: u32, out: &mut [u8]| {
            let item = cull_entry(arenas, instances, candidates, slot);
            out.copy_from_slice(&item.to_le_bytes());
        };
        let part_box_bytes = |slot: u32, out: &mut [u8]| {
            out.copy_from_slice(&part_box(arenas, instances, slot).to_le_bytes());
        };
        let locals = &self.moves.locals;
        let local_bytes = |slot: u32, out: &mut [u8]| {
            let item = locals.get(slot as usize).copied().unwrap_or_default();
            out.copy_from_slice(bytemuck::cast_slice(&item));
        };
        let last_slots = self.gpu.uploader.commands_key();
        let (
            [matrix_count, material_count, _, record_count, _, _, local_count],
            first_words,
            bytes,
        ) = self.gpu.uploader.gather(
            &self.device,
            &self.gpu.pipelines,
            [
                (&mut self.gpu.matrices, &matrix_bytes),
                (&mut self.gpu.materials, &material_bytes),
                (&mut self.gpu.material_textures, &material_texture_bytes),
                (&mut self.gpu.records, &record_bytes),
                (&mut self.gpu.cull_entries, &cull_entry_bytes),
                (&mut self.gpu.part_boxes, &part_box_bytes),
                (&mut self.gpu.locals, &local_bytes),
            ],
        )?;
        self.moves.frame_moved.clear();
        self.moves.last_hierarchy = match self.gpu.uploader.updates() {
            Some(updates) if self.moves.transforms == Transforms::Gpu => {
                self.moves.hierarchy.prepare(
                    &self.gpu.pipelines,
                    updates,
                    (first_words[6], local_count as u32),
                    (&self.gpu.locals.buffer, &self.gpu.matrices.buffer),
                    self.gpu.uploader.commands_key() == last_slots,
                )?
            }
            _ => {
                self.moves.hierarchy.cancel();
                None
            }
        };
        self.counts.last_upload.matrices += matrix_count;
        self.counts.last_upload.materials += material_count;
        self.counts.last_upload.records += record_count;
        self.counts.last_upload.bytes += bytes;
        // The buffers generation is unique across scenes: a prologue recorded for another
        // scene (its sets gone with it) never matches.
        let mut key = mix(self.generations.buffers, self.gpu.uploader.commands_key());
        key = mix(key, self.moves.hierarchy.commands_key());
        key = mix(key, u64::from(self.moves.last_hierarchy.is_some()));
        Ok((bytes, key))
    }

    /// Records the commands of the uploads [`GpuScene::prepare_uploads`] gathered: the scatter
    /// and the transform hierarchy's pass (before the frame's pass, whose first barrier makes
    /// their writes visible).
    pub(crate) fn record_uploads(&self, command_buffer: vk::CommandBuffer) -> RenderResult<()> {
        self.gpu
            .uploader
            .record(&self.device, &self.gpu.pipelines, command_buffer)?;
        if self.moves.last_hierarchy.is_some() {
            self.moves
                .hierarchy
                .record(&self.gpu.pipelines, command_buffer)?;
        }
        Ok(())
    }

    /// Uploads what is pending now, outside a frame (one submission, waited for); returns the
    /// bytes sent. Frames upload by themselves; this serves measurements and tests.
    pub fn flush_uploads(&mut self) -> RenderResult<u64> {
        let mut one_shot = OneShot::begin(&self.device, "scene upload")?;
        let (bytes, _) = self.prepare_uploads()?;
        self.record_uploads(one_shot.command_buffer())?;
        one_shot.submit_and_wait()?;
        Ok(bytes)
    }

    /// What the last sync and the frame after it uploaded.
    pub fn last_upload(&self) -> UploadStats {
        self.counts.last_upload
    }

    /// Instance entries the last sync refreshed.
    pub fn last_touched(&self) -> u64 {
        self.counts.last_touched
    }

    /// The scene as techniques see it in a frame of `view` (caught up first). Valid while
    /// neither is changed.
    pub(crate) fn view(&self, view: &ViewState) -> abi::CadrSceneView {
        let (dirty_matrices, dirty_materials) = view.dirty_slots();
        let [vertex_buffer, index_buffer, wire_index_buffer, matrix_buffer, material_buffer, instance_buffer, cull_buffer, _, _, _, _] =
            self.seen.buffer_refs;
        abi::CadrSceneView {
            size: std::mem::size_of::<abi::CadrSceneView>() as u32,
            instance_count: self.instances.len() as u32,
            instances: self.instances.as_ptr(),
            drawn_bits: view.drawn_bits().as_ptr(),
            draws_generation: view.draws_generation(),
            parameters_generation: self.generations.parameters,
            matrix_count: self.matrices.len() as u32,
            matrices: self.matrices.as_ptr(),
            material_count: self.materials.len() as u32,
            materials: self.materials.as_ptr(),
            dirty_matrices: dirty_matrices.as_ptr(),
            dirty_matrix_count: dirty_matrices.len() as u32,
            dirty_materials: dirty_materials.as_ptr(),
            dirty_material_count: dirty_materials.len() as u32,
            buffers_generation: self.generations.buffers,
            vertex_buffer,
            vertex_stride: std::mem::size_of::<Vertex>() as u32,
            index_buffer,
            wire_index_buffer,
            matrix_buffer,
            material_buffer,
            instance_buffer,
            cull_buffer,
            extensions: &self.seen.clusters_extension.0.clusters.header,
        }
    }

    /// Candidate bits (alive, visible, with triangles) for culling.
    pub(crate) fn candidate_bits(&self) -> &[u64] {
        &self.candidate
    }

    /// World matrices (f64) per matrix slot.
    pub(crate) fn worlds(&self) -> &[[f64; 16]] {
        &self.moves.worlds
    }

    /// Whether some material is translucent (opacity under 1, or, with `textures` drawn, a
    /// BLEND texture with translucent texels): frames then draw translucent surfaces with the
    /// transparency method.
    pub fn has_translucency(&self, textures: bool) -> bool {
        self.material_info.translucent[usize::from(textures)] > 0
    }

    /// Whether some live instance is highlighted (the silhouettes of the edge display modes
    /// then take the highlight's line colour where they outline one).
    pub fn has_highlighted(&self) -> bool {
        self.counts.highlighted > 0
    }

    /// Whether some geometry has texture coordinates or colours (the vertex shader reads them
    /// only then).
    pub fn has_vertex_attributes(&self) -> bool {
        self.arenas.has_attributes
    }

    /// Whether the scene has textures.
    pub fn has_textures(&self) -> bool {
        self.textures.any
    }

    /// Whether some material slot has a texture or an alpha mode other than BLEND (the
    /// vertex shader reads the descriptions only then).
    pub fn has_material_descriptions(&self) -> bool {
        self.material_info.described > 0
    }

    /// The buffers, image and samplers the frame set names for the shared shaders.
    pub fn frame_resources(&self) -> FrameResources<'_> {
        FrameResources {
            records: self.gpu.records.buffer.raw(),
            material_textures: self.gpu.material_textures.buffer.raw(),
            vertex_attributes: self.arenas.attributes.raw(),
            textures: self.textures.bindings(),
            linear_sampler: self.textures.linear.raw(),
            nearest_sampler: self.textures.nearest.raw(),
            cull_entries: self.gpu.cull_entries.buffer.raw(),
            generation: self.generations.buffers,
        }
    }

    /// Triangles of the candidates (what a view draws before culling).
    pub fn candidate_triangles(&self) -> u64 {
        self.counts.candidate_triangles
    }

    /// Instance ids in use are below this.
    pub fn instance_capacity(&self) -> usize {
        self.instances.len()
    }

    /// The CPU copy of the GPU-side content: instance entries (the GPU's instance records and
    /// cull entries are made from them), matrices and materials (for comparing an
    /// incrementally synced scene with a fresh one).
    pub fn content(&self) -> SceneContent<'_> {
        SceneContent {
            instances: &self.instances,
            matrices: &self.matrices,
            materials: &self.materials,
            candidate_bits: &self.candidate,
        }
    }

    /// Reads back the vertex and index arenas (for tests: geometries placed one by one must
    /// draw what a fresh layout draws). Waits for the device.
    pub fn read_back_geometry(&self) -> RenderResult<[Vec<u8>; 2]> {
        let read = |buffer: &crate::vk::Buffer| buffer.download(0, buffer.size());
        Ok([read(&self.arenas.vertices)?, read(&self.arenas.indices)?])
    }

    /// Reads back the GPU's matrix, material, record and cull-entry arrays (for tests: the
    /// sparse uploads must leave them equal to the CPU copy). Waits for the device.
    pub fn read_back_arrays(&self) -> RenderResult<[Vec<u8>; 5]> {
        let read = |array: &GpuArray, bytes: usize| array.buffer.download(0, bytes as u64);
        Ok([
            read(&self.gpu.matrices, self.matrices.len() * MATRIX_BYTES)?,
            read(&self.gpu.materials, self.materials.len() * MATERIAL_BYTES)?,
            read(&self.gpu.records, self.instances.len() * RECORD_BYTES)?,
            read(
                &self.gpu.cull_entries,
                self.instances.len() * CULL_ENTRY_BYTES,
            )?,
            read(&self.gpu.part_boxes, self.instances.len() * PART_BOX_BYTES)?,
        ])
    }
}

/// A GPU scene as one view draws it: the scene (perhaps shared with other views) and what the
/// view keeps of its own, caught up ([`GpuScene::catch_up`]) before the frame.
pub struct ViewedScene<'a> {
    /// The scene.
    pub scene: &'a mut GpuScene,
    /// The view's own culling, drawn set and changed slots.
    pub own: &'a mut ViewState,
}

impl ViewedScene<'_> {
    /// The scene as techniques see it in this view's frame.
    pub(crate) fn view(&self) -> abi::CadrSceneView {
        self.scene.view(self.own)
    }

    /// Applies culling's result (see [`GpuScene::apply_culling`]).
    pub(crate) fn apply_culling(&mut self, visible: &[u64], changed: &[u64]) {
        self.scene.apply_culling(self.own, visible, changed);
    }

    /// Where the scene streams its geometry, asks for the full detail of what this view's CPU
    /// culling leaves visible (see [`GpuScene::ask_for_visible`]).
    pub(crate) fn ask_for_visible(&mut self) {
        self.scene.ask_for_visible(self.own.culled_bits());
    }
}

/// The CPU copy of a GPU scene's content (see [`GpuScene::content`]).
#[derive(Debug)]
pub struct SceneContent<'a> {
    /// Instance entries by instance id.
    pub instances: &'a [abi::CadrInstance],
    /// Matrices by tree node.
    pub matrices: &'a [abi::CadrMatrix],
    /// Materials by slot.
    pub materials: &'a [abi::CadrMaterial],
    /// Candidate bits (alive, visible, with triangles) by instance id.
    pub candidate_bits: &'a [u64],
}

/// The geometry slot of a live instance's entry.
fn geometry_of_entry(entry: &abi::CadrInstance) -> Option<u32> {
    (entry.flags & abi::CADR_INSTANCE_ALIVE != 0).then_some(entry.geometry)
}

/// The box of instance `slot`'s part (zero for an id not in use: a dead instance's entry names
/// geometry 0, whose box would go stale when that geometry changes).
fn part_box(arenas: &GeometryArenas, instances: &[abi::CadrInstance], slot: u32) -> abi::CadrBox {
    instances
        .get(slot as usize)
        .filter(|instance| instance.flags & abi::CADR_INSTANCE_ALIVE != 0)
        .and_then(|instance| {
            let place = arenas.places.get(instance.geometry as usize)?.as_ref()?;
            Some(place.parts.get(instance.part as usize)?.extent.bounds)
        })
        .unwrap_or_default()
}

/// The cull entry of instance `slot`: its sphere, ranges and first cluster, flagged as a
/// candidate when it is drawn unless culled.
fn cull_entry(
    arenas: &GeometryArenas,
    instances: &[abi::CadrInstance],
    candidates: &[u64],
    slot: u32,
) -> abi::CadrCullEntry {
    let Some(instance) = instances.get(slot as usize) else {
        return abi::CadrCullEntry::default();
    };
    let candidate = bit(candidates, slot);
    abi::CadrCullEntry {
        sphere: instance.sphere,
        first_index: instance.first_index,
        index_count: instance.index_count,
        first_wire_index: instance.first_wire_index,
        wire_index_count: instance.wire_index_count,
        vertex_base: instance.vertex_base,
        matrix: instance.matrix,
        flags: instance.flags
            | if candidate {
                abi::CADR_INSTANCE_CANDIDATE
            } else {
                0
            },
        first_cluster: arenas
            .places
            .get(instance.geometry as usize)
            .and_then(Option::as_ref)
            .and_then(|place| place.clusters_of(instance.part))
            .map_or(0, |[first, _, _]| first),
    }
}

/// The entry of a live instance whose geometry and part are in `arenas`, and whether it is a
/// candidate for drawing (shown, with triangles).
/// `translucency` gives per material slot its parts' translucency flags.
fn entry_in(
    arenas: &GeometryArenas,
    translucency: &[abi::CadrInstanceFlags],
    instance: &InstanceRef,
) -> Option<(abi::CadrInstance, bool)> {
    let place = arenas.places.get(instance.geometry as usize)?.as_ref()?;
    let part = *place.parts.get(instance.part as usize)?;
    let ([first, count, first_wire, wire_count], sphere, shape) =
        (part.ranges, part.extent.sphere, part.extent.shape);
    let translucency = translucency
        .get(instance.material as usize)
        .copied()
        .unwrap_or(0);
    let flags = with_translucency(abi::CADR_INSTANCE_ALIVE, translucency)
        | shape
        | if part.edge_levels {
            abi::CADR_INSTANCE_EDGE_LEVELS
        } else {
            0
        }
        | if instance.highlighted {
            abi::CADR_INSTANCE_HIGHLIGHTED
        } else {
            0
        }
        | if instance.pickable {
            abi::CADR_INSTANCE_PICKABLE
        } else {
            0
        };
    let entry = abi::CadrInstance {
        matrix: instance.tree_node,
        material: instance.material,
        geometry: instance.geometry,
        part: instance.part,
        flags,
        vertex_base: place.vertex_base,
        geometry_first_index: place.first_index,
        geometry_first_wire_index: place.first_wire_index,
        first_index: place.first_index + first,
        index_count: count,
        first_wire_index: place.first_wire_index + first_wire,
        wire_index_count: wire_count,
        sphere,
    };
    Some((entry, instance.visible && count > 0))
}

/// Whether a material slot of `translucency` flags counts as translucent with textures off
/// (`[0]`) and on (`[1]`), as 0 or 1.
fn translucent_with_and_without_textures(translucency: abi::CadrInstanceFlags) -> [usize; 2] {
    let translucency = translucency & !abi::CADR_INSTANCE_CUTOUT;
    [
        usize::from(translucency == abi::CADR_INSTANCE_TRANSLUCENT),
        usize::from(translucency != 0),
    ]
}

/// `flags` with their translucency flags replaced by `translucency` (see [`translucency`]).
fn with_translucency(
    flags: abi::CadrInstanceFlags,
    translucency: abi::CadrInstanceFlags,
) -> abi::CadrInstanceFlags {
    const BITS: u32 = abi::CADR_INSTANCE_TRANSLUCENT
        | abi::CADR_INSTANCE_TRANSLUCENT_BY_TEXTURE
        | abi::CADR_INSTANCE_CUTOUT;
    flags & !BITS | translucency
}

/// Fewer instances than this per thread are made on the calling thread.
const PARALLEL_FILL_INSTANCES: usize = 1 << 15;
/// Fewer tree nodes than this per thread have their matrices made on the calling thread.
const PARALLEL_FILL_NODES: usize = 1 << 15;

/// An array with an item per tree node: `make(t)` for the nodes that keep a matrix, zero
/// for the others; made on a thread per core.
fn per_kept_node<T: Default + Send>(
    nodes: usize,
    kept: &(impl Fn(u32) -> bool + Sync),
    make: impl Fn(u32) -> T + Sync,
) -> Vec<T> {
    crate::parallel::collect_indexed(nodes, (1, PARALLEL_FILL_NODES), |t, _: &mut ()| {
        let t = t as u32;
        if kept(t) {
            make(t)
        } else {
            T::default()
        }
    })
    .0
}

/// The record of instance `id` (what the drawing shaders read of it).
fn record_of(entry: &abi::CadrInstance, id: u32) -> abi::CadrInstanceRecord {
    abi::CadrInstanceRecord {
        matrix: entry.matrix,
        material: entry.material,
        flags: entry.flags,
        instance: id,
    }
}

/// What one thread counted of the instances it made: the candidate bits of its chunk (which
/// starts at a multiple of 64) and their triangles.
#[derive(Default)]
struct InstanceTally {
    candidate_bits: Vec<u64>,
    triangles: u64,
    /// Live instances flagged highlighted.
    highlighted: usize,
}

/// The entries of instances `0..count` of `tree` (dead ones default; `translucency` per
/// material slot), on a thread per core.
fn make_instances(
    arenas: &GeometryArenas,
    translucency: &[abi::CadrInstanceFlags],
    tree: &SceneTree,
    count: usize,
) -> (Vec<abi::CadrInstance>, Vec<InstanceTally>) {
    crate::parallel::collect_indexed(
        count,
        (64, PARALLEL_FILL_INSTANCES),
        |id, tally: &mut InstanceTally| {
            if id % 64 == 0 {
                tally.candidate_bits.push(0);
            }
            let (entry, candidate) = tree
                .instance(id as u32)
                .and_then(|instance| entry_in(arenas, translucency, &instance))
                .unwrap_or((abi::CadrInstance::default(), false));
            if candidate {
                if let Some(word) = tally.candidate_bits.last_mut() {
                    *word |= 1 << (id % 64);
                }
                tally.triangles += u64::from(entry.index_count / 3);
            }
            tally.highlighted += usize::from(is_highlighted(&entry));
            entry
        },
    )
}

/// Whether `entry` is a live instance flagged highlighted.
fn is_highlighted(entry: &abi::CadrInstance) -> bool {
    const BITS: u32 = abi::CADR_INSTANCE_ALIVE | abi::CADR_INSTANCE_HIGHLIGHTED;
    entry.flags & BITS == BITS
}
